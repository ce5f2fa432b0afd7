/* check.c -- error messages and shared argument checks (src/base/check.h). */
#include "check.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "spatial.h"

#define STR2(x) #x
#define STR(x) STR2(x)

aqs_status lk_fail(aqs_linkage *L, aqs_status status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(L->error, sizeof L->error, fmt, ap);
    va_end(ap);
    return status;
}

aqs_status lk_fail_in(aqs_linkage *L, aqs_status status, const char *fn)
{
    const size_t n = strlen(fn) + 2, cap = sizeof L->error;
    if (status == AQS_OK || strncmp(L->error, "aqs_", 4) == 0 || n >= cap) return status;
    memmove(L->error + n, L->error, cap - n); /* what no longer fits is cut */
    L->error[cap - 1] = '\0';
    memcpy(L->error, fn, n - 2);
    L->error[n - 2] = ':';
    L->error[n - 1] = ' ';
    return status;
}

int check_quat_is_unit(const double q[4], double *norm)
{
    *norm = quat_norm(q);
    return fabs(*norm - 1.0) <= UNIT_QUAT_TOLERANCE;
}

aqs_status check_vec(aqs_linkage *L, const char *fn, const char *name, const double *v, int n)
{
    int i;
    if (!v) return lk_fail(L, AQS_EINVAL, "%s: %s is NULL", fn, name);
    for (i = 0; i < n; i++)
        if (!isfinite(v[i]))
            return lk_fail(L, AQS_EINVAL, "%s: %s[%d] = %g is not finite", fn, name, i, v[i]);
    return AQS_OK;
}

aqs_status check_unit_quat(aqs_linkage *L, const char *fn, const char *name, const double q[4],
                           double *norm)
{
    if (!check_quat_is_unit(q, norm))
        return lk_fail(L, AQS_EINVAL, "%s: %s has norm %.17g, not unit (tolerance " STR(UNIT_QUAT_TOLERANCE) ")",
                       fn, name, *norm);
    return AQS_OK;
}

aqs_status check_finalized(aqs_linkage *L, const char *fn)
{
    if (!L->finalized)
        return lk_fail(L, AQS_ESTATE, "%s: the linkage is not finalized (call aqs_linkage_finalize)", fn);
    return AQS_OK;
}

aqs_status check_stats_size(aqs_linkage *L, const char *fn, const void *stats, uint32_t *size)
{
    if (!stats) return lk_fail(L, AQS_EINVAL, "%s: stats is NULL", fn);
    memcpy(size, stats, sizeof *size); /* each such struct starts with uint32_t size */
    if (*size < 8) return lk_fail(L, AQS_EINVAL, "%s: stats->size = %u is too small", fn, (unsigned)*size);
    return AQS_OK;
}
