/* names.c -- body and joint names (set, get, find) and joint limits: what a
 * model file carries besides the mechanics. Names cost nothing until the
 * first one is set; limits are kept and read back, never enforced. */
#include <math.h>
#include <string.h>

#include "aqs.h"
#include "linkage.h"

#define NAME_MAX_BYTES 4096

void lk_names_free(aqs_linkage *L)
{
    int32_t i;
    for (i = 0; L->body_name && i < L->body_name_cap; i++) lk_free(L, L->body_name[i]);
    for (i = 0; L->joint_name && i < L->joint_name_cap; i++) lk_free(L, L->joint_name[i]);
    lk_free(L, L->body_name);
    lk_free(L, L->joint_name);
    lk_free(L, L->load_warnings);
    L->body_name = L->joint_name = NULL;
    L->body_name_cap = L->joint_name_cap = 0;
    L->load_warnings = NULL;
}

/* Store a copy of name at index in *table (grown to at least count entries,
 * count > index). A failure changes nothing. */
static aqs_status set_name(aqs_linkage *L, const char *fn, const char *what, char ***table,
                           int32_t *cap, int32_t count, int32_t index, const char *name)
{
    size_t len;
    char *copy;
    if (!name) return lk_fail(L, AQS_EINVAL, "%s: name is NULL", fn);
    len = strlen(name);
    if (len == 0) return lk_fail(L, AQS_EINVAL, "%s: name is empty (%s %d)", fn, what, (int)index);
    if (len > NAME_MAX_BYTES)
        return lk_fail(L, AQS_EINVAL, "%s: name has %zu bytes, more than %d (%s %d)", fn, len,
                       NAME_MAX_BYTES, what, (int)index);
    copy = lk_alloc(L, len + 1);
    if (!copy) return lk_fail(L, AQS_ENOMEM, "%s: out of memory", fn);
    memcpy(copy, name, len + 1);
    if (*cap < count) {
        int32_t newcap = count < 16 ? 16 : count, i;
        char **grown;
        if (newcap < INT32_MAX / 2 && newcap < 2 * *cap) newcap = 2 * *cap;
        grown = lk_alloc(L, (size_t)newcap * sizeof *grown);
        if (!grown) {
            lk_free(L, copy);
            return lk_fail(L, AQS_ENOMEM, "%s: out of memory", fn);
        }
        for (i = 0; i < newcap; i++) grown[i] = i < *cap ? (*table)[i] : NULL;
        lk_free(L, *table);
        *table = grown;
        *cap = newcap;
    }
    lk_free(L, (*table)[index]);
    (*table)[index] = copy;
    return AQS_OK;
}

AQS_API aqs_status aqs_body_set_name(aqs_linkage *L, int32_t body, const char *name)
{
    static const char fn[] = "aqs_body_set_name";
    if (!L) return AQS_EINVAL;
    if (body < 0 || body >= L->nbodies)
        return lk_fail(L, AQS_ERANGE, "%s: body = %d is out of range [0, %d)", fn, (int)body,
                       (int)L->nbodies);
    return set_name(L, fn, "body", &L->body_name, &L->body_name_cap, L->nbodies, body, name);
}

AQS_API aqs_status aqs_joint_set_name(aqs_linkage *L, int32_t joint, const char *name)
{
    static const char fn[] = "aqs_joint_set_name";
    if (!L) return AQS_EINVAL;
    if (joint < 0 || joint >= L->njoints)
        return lk_fail(L, AQS_ERANGE, "%s: joint = %d is out of range [0, %d)", fn, (int)joint,
                       (int)L->njoints);
    return set_name(L, fn, "joint", &L->joint_name, &L->joint_name_cap, L->njoints, joint, name);
}

AQS_API aqs_status aqs_body_get_name(const aqs_linkage *cL, int32_t body, const char **name)
{
    static const char fn[] = "aqs_body_get_name";
    aqs_linkage *L = (aqs_linkage *)cL; /* only the error message is written */
    const char *n;
    if (!L) return AQS_EINVAL;
    if (!name) return lk_fail(L, AQS_EINVAL, "%s: name is NULL", fn);
    if (body < 0 || body >= L->nbodies)
        return lk_fail(L, AQS_ERANGE, "%s: body = %d is out of range [0, %d)", fn, (int)body,
                       (int)L->nbodies);
    n = lk_body_name(L, body);
    *name = n ? n : "";
    return AQS_OK;
}

AQS_API aqs_status aqs_joint_get_name(const aqs_linkage *cL, int32_t joint, const char **name)
{
    static const char fn[] = "aqs_joint_get_name";
    aqs_linkage *L = (aqs_linkage *)cL;
    const char *n;
    if (!L) return AQS_EINVAL;
    if (!name) return lk_fail(L, AQS_EINVAL, "%s: name is NULL", fn);
    if (joint < 0 || joint >= L->njoints)
        return lk_fail(L, AQS_ERANGE, "%s: joint = %d is out of range [0, %d)", fn, (int)joint,
                       (int)L->njoints);
    n = lk_joint_name(L, joint);
    *name = n ? n : "";
    return AQS_OK;
}

/* The first index in [0, count) named name, or -1. */
static int32_t find_name(char **table, int32_t cap, int32_t count, const char *name)
{
    int32_t i, n = cap < count ? cap : count;
    for (i = 0; table && i < n; i++)
        if (table[i] && strcmp(table[i], name) == 0) return i;
    return -1;
}

static aqs_status find(aqs_linkage *L, const char *fn, const char *what, char **table,
                       int32_t cap, int32_t count, const char *name, int32_t *out)
{
    int32_t i;
    if (!out) return lk_fail(L, AQS_EINVAL, "%s: out is NULL", fn);
    *out = -1;
    if (!name) return lk_fail(L, AQS_EINVAL, "%s: name is NULL", fn);
    i = find_name(table, cap, count, name);
    if (i < 0) {
        int shown = 0;
        while (shown < 200 && name[shown]) shown++;
        return lk_fail(L, AQS_ERANGE, "%s: no %s is named '%.*s'%s", fn, what, shown, name,
                       name[shown] ? "..." : "");
    }
    *out = i;
    return AQS_OK;
}

AQS_API aqs_status aqs_body_find(const aqs_linkage *cL, const char *name, int32_t *out_body)
{
    aqs_linkage *L = (aqs_linkage *)cL;
    if (!L) return AQS_EINVAL;
    return find(L, "aqs_body_find", "body", L->body_name, L->body_name_cap, L->nbodies, name,
                out_body);
}

AQS_API aqs_status aqs_joint_find(const aqs_linkage *cL, const char *name, int32_t *out_joint)
{
    aqs_linkage *L = (aqs_linkage *)cL;
    if (!L) return AQS_EINVAL;
    return find(L, "aqs_joint_find", "joint", L->joint_name, L->joint_name_cap, L->njoints, name,
                out_joint);
}

/* ------------------------------------------------------------------ limits */

AQS_API aqs_status aqs_joint_set_limits(aqs_linkage *L, int32_t joint, double lower, double upper,
                                        double effort, double velocity)
{
    static const char fn[] = "aqs_joint_set_limits";
    double *lim;
    if (!L) return AQS_EINVAL;
    if (joint < 0 || joint >= L->njoints)
        return lk_fail(L, AQS_ERANGE, "%s: joint = %d is out of range [0, %d)", fn, (int)joint,
                       (int)L->njoints);
    if (isnan(lower) || isnan(upper) || !(lower <= upper) || lower == HUGE_VAL ||
        upper == -HUGE_VAL)
        return lk_fail(L, AQS_EINVAL,
                       "%s: lower = %g, upper = %g must be numbers with lower <= upper "
                       "(-inf and +inf for none)", fn, lower, upper);
    if (!(effort >= 0.0))
        return lk_fail(L, AQS_EINVAL, "%s: effort = %g must be >= 0 (+inf for none)", fn, effort);
    if (!(velocity >= 0.0))
        return lk_fail(L, AQS_EINVAL, "%s: velocity = %g must be >= 0 (+inf for none)", fn,
                       velocity);
    lim = L->joints[joint].limits;
    lim[0] = lower;
    lim[1] = upper;
    lim[2] = effort;
    lim[3] = velocity;
    return AQS_OK;
}

AQS_API aqs_status aqs_joint_get_limits(const aqs_linkage *cL, int32_t joint, double *lower,
                                        double *upper, double *effort, double *velocity)
{
    aqs_linkage *L = (aqs_linkage *)cL;
    const double *lim;
    if (!L) return AQS_EINVAL;
    if (joint < 0 || joint >= L->njoints)
        return lk_fail(L, AQS_ERANGE, "aqs_joint_get_limits: joint = %d is out of range [0, %d)",
                       (int)joint, (int)L->njoints);
    lim = L->joints[joint].limits;
    if (lower) *lower = lim[0];
    if (upper) *upper = lim[1];
    if (effort) *effort = lim[2];
    if (velocity) *velocity = lim[3];
    return AQS_OK;
}

AQS_API const char *aqs_linkage_load_warnings(const aqs_linkage *L)
{
    if (!L) return "aqs_linkage_load_warnings: linkage is NULL";
    return L->load_warnings ? L->load_warnings : "";
}
