/* urdf.c -- loading URDF models (docs/urdf.md) with expat, an optional build
 * feature (AQS_HAVE_EXPAT). Without it the entry points exist and return
 * AQS_ESTATE with a message saying so.
 *
 * Two passes: expat streams the document into a small element tree (tags,
 * attributes, line numbers; character data is not needed by URDF), then the
 * tree is checked and turned into bodies, joints, names, limits and shapes
 * through the public building functions, so the library's own argument
 * checks apply. Any failure empties the linkage again. */
#include <errno.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "aqs.h"
#include "collide.h"
#include "linkage.h"
#include "model.h"

AQS_API void aqs_urdf_options_init(aqs_urdf_options *options)
{
    if (!options) return;
    memset(options, 0, sizeof *options);
    options->size = (uint32_t)sizeof *options;
    options->root = AQS_URDF_ROOT_FIXED;
    options->collision = 0;
    options->finalize = 1;
    options->physical_inertia = 0;
}

#ifndef AQS_HAVE_EXPAT

AQS_API int32_t aqs_urdf_supported(void) { return 0; }

static aqs_status unsupported(aqs_linkage *L, const char *fn)
{
    if (!L) return AQS_EINVAL;
    return lk_fail(L, AQS_ESTATE,
                   "%s: this libaqs was built without URDF support (expat was not found at "
                   "build time, or AQS_URDF=0); rebuild with libexpat1-dev installed",
                   fn);
}

AQS_API aqs_status aqs_linkage_load_urdf(aqs_linkage *L, const char *path,
                                         const aqs_urdf_options *options)
{
    (void)path;
    (void)options;
    return unsupported(L, "aqs_linkage_load_urdf");
}

AQS_API aqs_status aqs_linkage_load_urdf_buffer(aqs_linkage *L, const char *data, size_t size,
                                                const char *name, const aqs_urdf_options *options)
{
    (void)data;
    (void)size;
    (void)name;
    (void)options;
    return unsupported(L, "aqs_linkage_load_urdf_buffer");
}

#else /* AQS_HAVE_EXPAT */

#include <expat.h>

AQS_API int32_t aqs_urdf_supported(void) { return 1; }

/* ------------------------------------------------------------ the document */

typedef struct {
    size_t tag;                /* offset in text */
    int32_t attr, nattr;       /* pairs (name, value) of offsets in attrs */
    int32_t parent, first, last, next;
    int32_t line;
} element;

/* Warning categories: what is read but not modelled. */
enum { W_INERTIA, W_MIMIC, W_TRANSMISSION, W_GAZEBO, W_DYNAMICS, W_SAFETY, W_CALIBRATION, W_MESH,
       W_GEOMETRY, W_OTHER, W_COUNT };
static const char *const warning_text[W_COUNT] = {
    "inertias no real body has (not positive semi-definite, or violating the triangle "
    "inequality) are loaded as given, only their rigid groups are checked: links",
    "<mimic> is not modelled (the joints move independently): joints",
    "<transmission> is not modelled:",
    "<gazebo> (simulator settings) is not modelled: references",
    "<dynamics> (damping, friction) is not modelled (quasi-statics has no velocity): joints",
    "<safety_controller> is not modelled: joints",
    "<calibration> is not modelled: joints",
    "<collision> meshes are not loaded (aqs loads box, sphere, cylinder, capsule): links",
    "<collision> without a geometry aqs reads is skipped: links",
    "unknown elements under <robot> are not modelled:",
};
#define WARN_NAMES 5

typedef struct {
    aqs_linkage *L;
    const char *fn, *source;
    aqs_status status; /* first failure */
    element *els;
    int32_t nels, capels;
    char *text;
    size_t ntext, captext;
    size_t *attrs;
    int32_t nattrs, capattrs;
    int32_t current; /* open element, -1 at the top */
    XML_Parser parser;
    int32_t wcount[W_COUNT];
    char wnames[W_COUNT][WARN_NAMES][64];
} doc;

static aqs_status fail(doc *d, aqs_status status, const char *fmt, ...)
#ifdef __GNUC__
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static aqs_status fail(doc *d, aqs_status status, const char *fmt, ...)
{
    char what[sizeof d->L->error];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    d->status = status;
    return lk_fail(d->L, status, "%s: %s: %s", d->fn, d->source, what);
}

static aqs_status oom(doc *d) { return fail(d, AQS_ENOMEM, "out of memory"); }

/* Grow *p (cap elements of elem bytes) to hold need; 0 on failure. */
static int grow(doc *d, void **p, size_t *cap, size_t need, size_t elem)
{
    size_t ncap;
    void *q;
    if (need <= *cap) return 1;
    ncap = *cap ? *cap : 64;
    while (ncap < need) {
        if (ncap > ((size_t)-1 / 2) / elem) return 0;
        ncap *= 2;
    }
    q = lk_alloc(d->L, ncap * elem);
    if (!q) return 0;
    if (*p) {
        memcpy(q, *p, *cap * elem);
        lk_free(d->L, *p);
    }
    *p = q;
    *cap = ncap;
    return 1;
}

static size_t add_text(doc *d, const char *s)
{
    size_t n = strlen(s) + 1, at = d->ntext;
    if (!grow(d, (void **)&d->text, &d->captext, d->ntext + n, 1)) return (size_t)-1;
    memcpy(d->text + at, s, n);
    d->ntext += n;
    return at;
}

static void XMLCALL on_start(void *user, const XML_Char *tag, const XML_Char **atts)
{
    doc *d = user;
    element *e;
    size_t cap, acap;
    int32_t n = 0, i;
    if (d->status != AQS_OK) return;
    while (atts[2 * n]) n++;
    cap = (size_t)d->capels;
    acap = (size_t)d->capattrs;
    if (d->nels == INT32_MAX - 1 || d->nattrs > INT32_MAX - 2 * n - 1 ||
        !grow(d, (void **)&d->els, &cap, (size_t)d->nels + 1, sizeof *d->els) ||
        !grow(d, (void **)&d->attrs, &acap, (size_t)d->nattrs + 2 * (size_t)n, sizeof(size_t))) {
        d->capels = (int32_t)(cap > INT32_MAX ? INT32_MAX : cap);
        d->capattrs = (int32_t)(acap > INT32_MAX ? INT32_MAX : acap);
        oom(d);
        XML_StopParser(d->parser, XML_FALSE);
        return;
    }
    d->capels = (int32_t)cap;
    d->capattrs = (int32_t)acap;
    e = &d->els[d->nels];
    e->tag = add_text(d, tag);
    e->attr = d->nattrs;
    e->nattr = n;
    e->parent = d->current;
    e->first = e->last = e->next = -1;
    e->line = (int32_t)XML_GetCurrentLineNumber(d->parser);
    for (i = 0; i < 2 * n; i++) {
        size_t at = add_text(d, atts[i]);
        if (at == (size_t)-1 || e->tag == (size_t)-1) {
            oom(d);
            XML_StopParser(d->parser, XML_FALSE);
            return;
        }
        d->attrs[d->nattrs++] = at;
    }
    if (e->tag == (size_t)-1) {
        oom(d);
        XML_StopParser(d->parser, XML_FALSE);
        return;
    }
    if (d->current >= 0) {
        element *p = &d->els[d->current];
        if (p->last >= 0) d->els[p->last].next = d->nels;
        else p->first = d->nels;
        p->last = d->nels;
    }
    d->current = d->nels++;
}

static void XMLCALL on_end(void *user, const XML_Char *tag)
{
    doc *d = user;
    (void)tag;
    if (d->status != AQS_OK || d->current < 0) return;
    d->current = d->els[d->current].parent;
}

static const char *tag_of(const doc *d, int32_t e) { return d->text + d->els[e].tag; }

static const char *attr(const doc *d, int32_t e, const char *name)
{
    int32_t i;
    if (e < 0) return NULL;
    for (i = 0; i < d->els[e].nattr; i++)
        if (strcmp(d->text + d->attrs[d->els[e].attr + 2 * i], name) == 0)
            return d->text + d->attrs[d->els[e].attr + 2 * i + 1];
    return NULL;
}

static int32_t child(const doc *d, int32_t e, const char *tag)
{
    int32_t c;
    if (e < 0) return -1;
    for (c = d->els[e].first; c >= 0; c = d->els[c].next)
        if (strcmp(tag_of(d, c), tag) == 0) return c;
    return -1;
}

static void warn(doc *d, int what, const char *name)
{
    int32_t k = d->wcount[what]++;
    if (k < WARN_NAMES && name) snprintf(d->wnames[what][k], sizeof d->wnames[what][k], "%s", name);
}

/* The warnings as one string through the allocator (NULL when none). */
static aqs_status store_warnings(doc *d)
{
    size_t need = 1, at = 0;
    int w, k;
    char *s;
    for (w = 0; w < W_COUNT; w++)
        if (d->wcount[w]) need += strlen(warning_text[w]) + 48 + WARN_NAMES * 70;
    lk_free(d->L, d->L->load_warnings);
    d->L->load_warnings = NULL;
    if (need == 1) return AQS_OK;
    s = lk_alloc(d->L, need);
    if (!s) return oom(d);
    for (w = 0; w < W_COUNT; w++) {
        if (!d->wcount[w]) continue;
        if (at) s[at++] = '\n';
        at += (size_t)snprintf(s + at, need - at, "%s: %s", d->source, warning_text[w]);
        for (k = 0; k < d->wcount[w] && k < WARN_NAMES; k++)
            at += (size_t)snprintf(s + at, need - at, "%s '%s'", k ? "," : "", d->wnames[w][k]);
        if (d->wcount[w] > WARN_NAMES)
            at += (size_t)snprintf(s + at, need - at, " and %d more",
                                   (int)(d->wcount[w] - WARN_NAMES));
        at += (size_t)snprintf(s + at, need - at, " (%d)", (int)d->wcount[w]);
    }
    d->L->load_warnings = s;
    return AQS_OK;
}

/* ----------------------------------------------------------------- numbers */

/* Parse count numbers of element e's attribute into out, default def when
 * the attribute (or the element) is missing; def NULL: it is required. The C
 * locale's '.' is the decimal point whatever the caller's locale. */
static aqs_status numbers(doc *d, int32_t e, const char *name, int count, const double *def,
                          const char *where, double *out)
{
    const char *text = attr(d, e, name), *p;
    char dot = localeconv()->decimal_point[0];
    int n = 0, i;
    if (!text) {
        if (!def) return fail(d, AQS_EINVAL, "%s: missing attribute %s", where, name);
        for (i = 0; i < count; i++) out[i] = def[i];
        return AQS_OK;
    }
    p = text;
    for (;;) {
        char token[128], *end;
        size_t len = 0;
        double v;
        while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r') p++;
        if (!*p) break;
        while (p[len] && p[len] != ' ' && p[len] != '\t' && p[len] != '\n' && p[len] != '\r') len++;
        if (len >= sizeof token) return fail(d, AQS_EINVAL, "%s: %s = '%.60s...' is not %d numbers", where, name, text, count);
        memcpy(token, p, len);
        token[len] = 0;
        if (dot != '.')
            for (i = 0; i < (int)len; i++)
                if (token[i] == '.') token[i] = dot;
        v = strtod(token, &end);
        if (end == token || *end || strpbrk(token, "xX"))
            return fail(d, AQS_EINVAL, "%s: %s = '%s' is not %d number%s", where, name, text,
                        count, count > 1 ? "s" : "");
        if (n < count) out[n] = v;
        n++;
        p += len;
    }
    if (n != count)
        return fail(d, AQS_EINVAL, "%s: %s = '%s' has %d numbers, expected %d", where, name, text,
                    n, count);
    for (i = 0; i < count; i++)
        if (!isfinite(out[i]))
            return fail(d, AQS_EINVAL, "%s: %s = '%s' is not finite", where, name, text);
    return AQS_OK;
}

/* The shortest of 15, 16, 17 significant digits that reads back as v (as
 * Python's repr does). */
typedef struct {
    char s[32];
} numtext;

static numtext num(double v)
{
    numtext t;
    int p;
    for (p = 15; p <= 17; p++) {
        snprintf(t.s, sizeof t.s, "%.*g", p, v);
        if (strtod(t.s, NULL) == v) break;
    }
    return t;
}

static aqs_status origin(doc *d, int32_t e, const char *where, double xyz[3], double rpy[3])
{
    static const double zero[3] = {0, 0, 0};
    char w[200];
    int32_t o = child(d, e, "origin");
    aqs_status st;
    snprintf(w, sizeof w, "%s <origin>", where);
    if ((st = numbers(d, o, "xyz", 3, zero, w, xyz)) != AQS_OK) return st;
    return numbers(d, o, "rpy", 3, zero, w, rpy);
}

/* Quaternion (w, x, y, z) of R = Rz(yaw) Ry(pitch) Rx(roll). */
static void rpy_quat(const double rpy[3], double q[4])
{
    double cr = cos(0.5 * rpy[0]), sr = sin(0.5 * rpy[0]);
    double cp = cos(0.5 * rpy[1]), sp = sin(0.5 * rpy[1]);
    double cy = cos(0.5 * rpy[2]), sy = sin(0.5 * rpy[2]);
    q[0] = cr * cp * cy + sr * sp * sy;
    q[1] = sr * cp * cy - cr * sp * sy;
    q[2] = cr * sp * cy + sr * cp * sy;
    q[3] = cr * cp * sy - sr * sp * cy;
}

static void rpy_matrix(const double rpy[3], double R[9])
{
    double cr = cos(rpy[0]), sr = sin(rpy[0]), cp = cos(rpy[1]), sp = sin(rpy[1]);
    double cy = cos(rpy[2]), sy = sin(rpy[2]);
    R[0] = cy * cp; R[1] = cy * sp * sr - sy * cr; R[2] = cy * sp * cr + sy * sr;
    R[3] = sy * cp; R[4] = sy * sp * sr + cy * cr; R[5] = sy * sp * cr - cy * sr;
    R[6] = -sp;     R[7] = cp * sr;                R[8] = cp * cr;
}

/* ------------------------------------------------------------------- model */

enum { U_REVOLUTE, U_CONTINUOUS, U_PRISMATIC, U_FIXED, U_FLOATING, U_PLANAR, U_TYPES };
static const char *const urdf_types[U_TYPES] = {"revolute", "continuous", "prismatic",
                                                "fixed", "floating", "planar"};
static const int32_t aqs_types[U_TYPES] = {AQS_JOINT_REVOLUTE, AQS_JOINT_REVOLUTE,
                                           AQS_JOINT_PRISMATIC, AQS_JOINT_FIXED,
                                           AQS_JOINT_FREE, AQS_JOINT_PLANAR};

typedef struct {
    const char *name;
    int32_t type, parent, child; /* U_*, link indices */
    double xyz[3], rpy[3], axis[3], limits[4];
} ujoint;

typedef struct {
    const char *name;
    int32_t el;
    double mass, com[3], inertia[9];
    int has_inertial;
} ulink;

typedef struct {
    doc d;
    ulink *links;
    ujoint *joints;
    int32_t nlinks, njoints;
    int32_t *hash; /* open addressing over link names: link index or -1 */
    int32_t *jhash; /* the same over joint names */
    size_t hcap, jcap;
    int32_t *parent_joint, *group, *body_of;
} model_in;

static uint64_t name_hash(const char *s)
{
    uint64_t h = 1469598103934665603ULL;
    while (*s) h = (h ^ (unsigned char)*s++) * 1099511628211ULL;
    return h;
}

/* The link named name, or -1; with insert >= 0, insert it (returns -2 if
 * the name is taken). */
static int32_t link_lookup(model_in *m, const char *name, int32_t insert)
{
    size_t i = (size_t)name_hash(name) & (m->hcap - 1);
    while (m->hash[i] >= 0) {
        if (strcmp(m->links[m->hash[i]].name, name) == 0) return insert >= 0 ? -2 : m->hash[i];
        i = (i + 1) & (m->hcap - 1);
    }
    if (insert >= 0) m->hash[i] = insert;
    return insert >= 0 ? insert : -1;
}

/* Insert joint index under its name; 0 if the name is taken. */
static int joint_insert(model_in *m, int32_t index)
{
    const char *name = m->joints[index].name;
    size_t i = (size_t)name_hash(name) & (m->jcap - 1);
    while (m->jhash[i] >= 0) {
        if (strcmp(m->joints[m->jhash[i]].name, name) == 0) return 0;
        i = (i + 1) & (m->jcap - 1);
    }
    m->jhash[i] = index;
    return 1;
}

static int32_t find_group(int32_t *group, int32_t a)
{
    while (group[a] != a) {
        group[a] = group[group[a]];
        a = group[a];
    }
    return a;
}

/* "'a' <- 'c' <- 'b' <- 'a'": the parent chain from start, from the first
 * link that repeats (the cycle it runs into). Uses group and body_of as
 * scratch (nothing else needs them yet). */
static void cycle_text(const model_in *m, int32_t start, char *out, size_t n)
{
    int32_t *path = m->group, *pos = m->body_of, count = 0, k, at = start, from;
    size_t len = 0;
    for (k = 0; k < m->nlinks; k++) pos[k] = -1;
    while (m->parent_joint[at] >= 0 && pos[at] < 0) {
        pos[at] = count;
        path[count++] = at;
        at = m->joints[m->parent_joint[at]].parent;
    }
    from = pos[at] >= 0 ? pos[at] : 0;
    out[0] = 0;
    for (k = from; k < count && len < n; k++)
        len += (size_t)snprintf(out + len, n - len, "%s'%s'", len ? " <- " : "",
                                m->links[path[k]].name);
    if (len < n) snprintf(out + len, n - len, "%s'%s'", len ? " <- " : "", m->links[at].name);
}

static aqs_status read_inertial(model_in *m, ulink *lk)
{
    doc *d = &m->d;
    int32_t e = child(d, lk->el, "inertial"), me, ie;
    char where[200];
    double xyz[3], rpy[3], I[9], R[9], t[9];
    static const char *const keys[6] = {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"};
    double v[6];
    int i, j, k;
    aqs_status st;
    lk->mass = 0.0;
    memset(lk->com, 0, sizeof lk->com);
    memset(lk->inertia, 0, sizeof lk->inertia);
    lk->has_inertial = e >= 0;
    if (e < 0) return AQS_OK;
    snprintf(where, sizeof where, "link '%.150s' <inertial>", lk->name);
    if ((st = origin(d, e, where, xyz, rpy)) != AQS_OK) return st;
    me = child(d, e, "mass");
    snprintf(where, sizeof where, "link '%.150s'", lk->name);
    if (me < 0) return fail(d, AQS_EINVAL, "%s: <inertial> has no <mass>", where);
    snprintf(where, sizeof where, "link '%.150s' <mass>", lk->name);
    if ((st = numbers(d, me, "value", 1, NULL, where, &lk->mass)) != AQS_OK) return st;
    if (lk->mass < 0.0)
        return fail(d, AQS_EINVAL, "link '%s': mass = %s is negative", lk->name, num(lk->mass).s);
    memcpy(lk->com, xyz, sizeof xyz);
    ie = child(d, e, "inertia");
    if (ie < 0) {
        if (lk->mass > 0.0)
            return fail(d, AQS_EINVAL, "link '%s': <inertial> has mass %s but no <inertia>",
                        lk->name, num(lk->mass).s);
        return AQS_OK;
    }
    snprintf(where, sizeof where, "link '%.150s' <inertia>", lk->name);
    for (i = 0; i < 6; i++)
        if ((st = numbers(d, ie, keys[i], 1, NULL, where, &v[i])) != AQS_OK) return st;
    I[0] = v[0]; I[1] = v[1]; I[2] = v[2];
    I[3] = v[1]; I[4] = v[3]; I[5] = v[4];
    I[6] = v[2]; I[7] = v[4]; I[8] = v[5];
    /* Into the link frame: R I R^T with R the inertial frame's orientation. */
    rpy_matrix(rpy, R);
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            double s = 0.0;
            for (k = 0; k < 3; k++) s += R[3 * i + k] * I[3 * k + j];
            t[3 * i + j] = s;
        }
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            double s = 0.0;
            for (k = 0; k < 3; k++) s += t[3 * i + k] * R[3 * j + k];
            lk->inertia[3 * i + j] = s;
        }
    for (i = 0; i < 3; i++)
        for (j = i + 1; j < 3; j++)
            lk->inertia[3 * i + j] = lk->inertia[3 * j + i] =
                0.5 * (lk->inertia[3 * i + j] + lk->inertia[3 * j + i]);
    return AQS_OK;
}

static aqs_status read_joint(model_in *m, int32_t e, ujoint *j)
{
    doc *d = &m->d;
    static const double xaxis[3] = {1, 0, 0};
    char where[200];
    const char *type = attr(d, e, "type");
    int32_t ends[2], k, le, c;
    aqs_status st;
    snprintf(where, sizeof where, "joint '%.150s'", j->name);
    for (k = 0; k < U_TYPES; k++)
        if (type && strcmp(type, urdf_types[k]) == 0) break;
    if (k == U_TYPES) {
        if (!type) return fail(d, AQS_EINVAL, "%s: has no type (aqs loads continuous, fixed, floating, planar, prismatic, revolute)", where);
        return fail(d, AQS_EINVAL,
                    "%s: type = '%s' is not supported (aqs loads continuous, fixed, floating, "
                    "planar, prismatic, revolute)",
                    where, type);
    }
    j->type = k;
    for (k = 0; k < 2; k++) {
        static const char *const tags[2] = {"parent", "child"};
        const char *link = attr(d, child(d, e, tags[k]), "link");
        if (!link || !*link) return fail(d, AQS_EINVAL, "%s: missing <%s link=...>", where, tags[k]);
        ends[k] = link_lookup(m, link, -1);
        if (ends[k] < 0)
            return fail(d, AQS_EINVAL, "%s: %s link '%s' is not defined", where, tags[k], link);
    }
    j->parent = ends[0];
    j->child = ends[1];
    if (j->parent == j->child)
        return fail(d, AQS_EINVAL, "%s: parent and child are the same link '%s'", where,
                    m->links[j->parent].name);
    if (m->parent_joint[j->child] >= 0)
        return fail(d, AQS_EINVAL, "link '%s' is the child of two joints ('%s' and '%s')",
                    m->links[j->child].name, m->joints[m->parent_joint[j->child]].name, j->name);
    m->parent_joint[j->child] = (int32_t)(j - m->joints);
    if ((st = origin(d, e, where, j->xyz, j->rpy)) != AQS_OK) return st;
    j->axis[0] = 1.0;
    j->axis[1] = j->axis[2] = 0.0;
    if (j->type != U_FIXED && j->type != U_FLOATING) {
        char w[220];
        snprintf(w, sizeof w, "%s <axis>", where);
        if ((st = numbers(d, child(d, e, "axis"), "xyz", 3, xaxis, w, j->axis)) != AQS_OK) return st;
        if (!(j->axis[0] * j->axis[0] + j->axis[1] * j->axis[1] + j->axis[2] * j->axis[2] > 0.0))
            return fail(d, AQS_EINVAL, "%s: <axis xyz> is zero", where);
    }
    /* <limit>: kept; URDF's defaults (lower = upper = 0) for revolute and
     * prismatic joints, none for the others; effort and velocity: none when
     * absent. */
    j->limits[0] = -HUGE_VAL;
    j->limits[1] = j->limits[2] = j->limits[3] = HUGE_VAL;
    le = child(d, e, "limit");
    if (le >= 0) {
        static const double zero = 0.0, inf = HUGE_VAL;
        char w[220];
        int positional = j->type == U_REVOLUTE || j->type == U_PRISMATIC;
        snprintf(w, sizeof w, "%s <limit>", where);
        if (positional) {
            if ((st = numbers(d, le, "lower", 1, &zero, w, &j->limits[0])) != AQS_OK ||
                (st = numbers(d, le, "upper", 1, &zero, w, &j->limits[1])) != AQS_OK)
                return st;
            if (j->limits[0] > j->limits[1])
                return fail(d, AQS_EINVAL, "%s: lower = %s is above upper = %s", w,
                            num(j->limits[0]).s, num(j->limits[1]).s);
        }
        if ((st = numbers(d, le, "effort", 1, &inf, w, &j->limits[2])) != AQS_OK ||
            (st = numbers(d, le, "velocity", 1, &inf, w, &j->limits[3])) != AQS_OK)
            return st;
        if (attr(d, le, "effort") && j->limits[2] < 0.0)
            return fail(d, AQS_EINVAL, "%s: effort = %s is negative", w, num(j->limits[2]).s);
        if (attr(d, le, "velocity") && j->limits[3] < 0.0)
            return fail(d, AQS_EINVAL, "%s: velocity = %s is negative", w, num(j->limits[3]).s);
    }
    for (c = d->els[e].first; c >= 0; c = d->els[c].next) {
        const char *t = tag_of(d, c);
        if (strcmp(t, "mimic") == 0) warn(d, W_MIMIC, j->name);
        else if (strcmp(t, "dynamics") == 0) warn(d, W_DYNAMICS, j->name);
        else if (strcmp(t, "safety_controller") == 0) warn(d, W_SAFETY, j->name);
        else if (strcmp(t, "calibration") == 0) warn(d, W_CALIBRATION, j->name);
    }
    return AQS_OK;
}

/* Shapes of link lk's <collision> elements on body (or AQS_WORLD). */
static aqs_status add_collision(model_in *m, const ulink *lk, int32_t body)
{
    doc *d = &m->d;
    int32_t c;
    for (c = d->els[lk->el].first; c >= 0; c = d->els[c].next) {
        int32_t g, s;
        double xyz[3], rpy[3], q[4], size[3] = {0, 0, 0}, v[3];
        int32_t type = -1;
        char where[200];
        aqs_status st;
        if (strcmp(tag_of(d, c), "collision") != 0) continue;
        snprintf(where, sizeof where, "link '%.150s' <collision>", lk->name);
        if ((st = origin(d, c, where, xyz, rpy)) != AQS_OK) return st;
        g = child(d, c, "geometry");
        s = g >= 0 ? d->els[g].first : -1;
        if (s < 0) {
            warn(d, W_GEOMETRY, lk->name);
            continue;
        }
        snprintf(where, sizeof where, "link '%.150s' <collision> <%.20s>", lk->name, tag_of(d, s));
        if (strcmp(tag_of(d, s), "sphere") == 0) {
            if ((st = numbers(d, s, "radius", 1, NULL, where, v)) != AQS_OK) return st;
            type = AQS_SHAPE_SPHERE;
            size[0] = v[0];
        } else if (strcmp(tag_of(d, s), "box") == 0) {
            if ((st = numbers(d, s, "size", 3, NULL, where, v)) != AQS_OK) return st;
            type = AQS_SHAPE_BOX;
            size[0] = 0.5 * v[0];
            size[1] = 0.5 * v[1];
            size[2] = 0.5 * v[2];
        } else if (strcmp(tag_of(d, s), "cylinder") == 0 || strcmp(tag_of(d, s), "capsule") == 0) {
            if ((st = numbers(d, s, "radius", 1, NULL, where, v)) != AQS_OK ||
                (st = numbers(d, s, "length", 1, NULL, where, v + 1)) != AQS_OK)
                return st;
            type = tag_of(d, s)[1] == 'y' ? AQS_SHAPE_CYLINDER : AQS_SHAPE_CAPSULE;
            size[0] = v[0];
            size[1] = 0.5 * v[1];
        } else if (strcmp(tag_of(d, s), "mesh") == 0) {
            warn(d, W_MESH, lk->name);
            continue;
        } else {
            warn(d, W_GEOMETRY, lk->name);
            continue;
        }
        rpy_quat(rpy, q);
        if ((st = aqs_shape_add(m->d.L, body, type, size, xyz, q, NULL)) != AQS_OK) {
            char msg[sizeof m->d.L->error];
            snprintf(msg, sizeof msg, "%s", m->d.L->error);
            return fail(d, st, "%s: %s", where, msg);
        }
    }
    return AQS_OK;
}

static int32_t count_of(const doc *d, int32_t e, const char *tag)
{
    int32_t c, n = 0;
    for (c = d->els[e].first; c >= 0; c = d->els[c].next) n += strcmp(tag_of(d, c), tag) == 0;
    return n;
}

static aqs_status build(model_in *m, const aqs_urdf_options *o)
{
    doc *d = &m->d;
    aqs_linkage *L = d->L;
    int32_t robot = 0, c, i, root = -1, nroots = 0, world_group = -1;
    int root_is_world, root_free = o->root == AQS_URDF_ROOT_FREE;
    aqs_status st;
    char text[400];

    if (d->nels == 0 || strcmp(tag_of(d, robot), "robot") != 0)
        return fail(d, AQS_EINVAL, "the root element is <%s>, not <robot>",
                    d->nels ? tag_of(d, robot) : "");
    m->nlinks = count_of(d, robot, "link");
    m->njoints = count_of(d, robot, "joint");
    if (m->nlinks == 0) return fail(d, AQS_EINVAL, "no <link>");
    m->links = lk_calloc(L, (size_t)m->nlinks, sizeof *m->links);
    m->joints = lk_calloc(L, (size_t)m->njoints + 1, sizeof *m->joints);
    for (m->hcap = 16; m->hcap < 2 * (size_t)m->nlinks;) m->hcap *= 2;
    m->hash = lk_alloc(L, m->hcap * sizeof *m->hash);
    for (m->jcap = 16; m->jcap < 2 * (size_t)m->njoints;) m->jcap *= 2;
    m->jhash = lk_alloc(L, m->jcap * sizeof *m->jhash);
    m->parent_joint = lk_alloc(L, (size_t)m->nlinks * sizeof(int32_t));
    m->group = lk_alloc(L, (size_t)m->nlinks * sizeof(int32_t));
    m->body_of = lk_alloc(L, (size_t)m->nlinks * sizeof(int32_t));
    if (!m->links || !m->joints || !m->hash || !m->jhash || !m->parent_joint || !m->group ||
        !m->body_of)
        return oom(d);
    for (i = 0; i < (int32_t)m->hcap; i++) m->hash[i] = -1;
    for (i = 0; i < (int32_t)m->jcap; i++) m->jhash[i] = -1;
    for (i = 0; i < m->nlinks; i++) m->parent_joint[i] = -1;

    /* Links, joints, and what is not modelled, in document order. */
    m->nlinks = m->njoints = 0;
    for (c = d->els[robot].first; c >= 0; c = d->els[c].next) {
        const char *t = tag_of(d, c), *name = attr(d, c, "name");
        if (strcmp(t, "link") == 0) {
            if (!name || !*name) return fail(d, AQS_EINVAL, "a <link> has no name");
            m->links[m->nlinks].name = name;
            m->links[m->nlinks].el = c;
            if (link_lookup(m, name, m->nlinks) == -2)
                return fail(d, AQS_EINVAL, "link '%s' is defined twice", name);
            m->nlinks++;
        } else if (strcmp(t, "transmission") == 0) {
            warn(d, W_TRANSMISSION, name ? name : "(unnamed)");
        } else if (strcmp(t, "gazebo") == 0) {
            const char *ref = attr(d, c, "reference");
            warn(d, W_GAZEBO, ref ? ref : "(robot)");
        } else if (strcmp(t, "joint") != 0 && strcmp(t, "material") != 0) {
            char tag[64];
            snprintf(tag, sizeof tag, "<%.60s>", t);
            warn(d, W_OTHER, tag);
        }
    }
    for (c = d->els[robot].first; c >= 0; c = d->els[c].next) {
        ujoint *j;
        const char *name;
        if (strcmp(tag_of(d, c), "joint") != 0) continue;
        name = attr(d, c, "name");
        if (!name || !*name) return fail(d, AQS_EINVAL, "a <joint> has no name");
        j = &m->joints[m->njoints];
        j->name = name;
        if (!joint_insert(m, m->njoints)) return fail(d, AQS_EINVAL, "joint '%s' is defined twice", name);
        m->njoints++;
        if ((st = read_joint(m, c, j)) != AQS_OK) return st;
    }

    /* One root; everything reachable from it. */
    for (i = 0; i < m->nlinks; i++)
        if (m->parent_joint[i] < 0) {
            if (nroots++ == 0) root = i;
        }
    if (nroots == 0) {
        cycle_text(m, 0, text, sizeof text);
        return fail(d, AQS_EINVAL, "the joints form a cycle: every link has a parent (%s)", text);
    }
    if (nroots > 1) {
        size_t len = 0;
        int shown = 0;
        text[0] = 0;
        for (i = 0; i < m->nlinks && len < sizeof text; i++)
            if (m->parent_joint[i] < 0 && shown++ < 8)
                len += (size_t)snprintf(text + len, sizeof text - len, "%s'%s'", len ? ", " : "",
                                        m->links[i].name);
        return fail(d, AQS_EINVAL,
                    "several root links (links that are no joint's child): %s%s; a URDF tree "
                    "has exactly one",
                    text, shown > 8 ? ", ..." : "");
    }
    /* Every link reaches the root: walk up to the root or to a link known to
     * reach it, then mark the walk (state in body_of: 1 reaches the root). */
    for (i = 0; i < m->nlinks; i++) m->body_of[i] = i == root;
    for (i = 0; i < m->nlinks; i++) {
        int32_t k = i, steps = 0, n;
        while (!m->body_of[k] && m->parent_joint[k] >= 0 && steps < m->nlinks) {
            m->group[steps++] = k;
            k = m->joints[m->parent_joint[k]].parent;
        }
        if (!m->body_of[k]) {
            cycle_text(m, i, text, sizeof text);
            return fail(d, AQS_EINVAL,
                        "the joints form a cycle not connected to the root link '%s' (%s)",
                        m->links[root].name, text);
        }
        for (n = 0; n < steps; n++) m->body_of[m->group[n]] = 1;
    }
    for (i = 0; i < m->nlinks; i++)
        if ((st = read_inertial(m, &m->links[i])) != AQS_OK) return st;

    /* Rigid groups: links welded by fixed joints. */
    for (i = 0; i < m->nlinks; i++) m->group[i] = i;
    for (i = 0; i < m->njoints; i++)
        if (m->joints[i].type == U_FIXED)
            m->group[find_group(m->group, m->joints[i].child)] = find_group(m->group, m->joints[i].parent);
    root_is_world = m->links[root].mass == 0.0;
    if (root_is_world && root_free) {
        /* Float the root's rigid group when it has mass; a root already
         * carrying only floating joints floats as it is; anything else has
         * nothing to float: refuse rather than return a fixed base. */
        double gm = 0.0;
        int only_floating = 1, any = 0;
        for (i = 0; i < m->nlinks; i++)
            if (find_group(m->group, i) == find_group(m->group, root)) gm += m->links[i].mass;
        for (i = 0; i < m->njoints; i++)
            if (m->joints[i].parent == root) {
                any = 1;
                if (m->joints[i].type != U_FLOATING) only_floating = 0;
            }
        if (gm > 0.0) root_is_world = 0;
        else if (!(any && only_floating))
            return fail(d, AQS_EINVAL,
                        "root = free, but the root link '%s' has no mass and no link with mass "
                        "is welded to it by fixed joints: there is no rigid body to float (aqs "
                        "will not silently fix it to the world); load with root = fixed, or "
                        "give the root link an <inertial>",
                        m->links[root].name);
    }
    if (root_is_world || !root_free) world_group = find_group(m->group, root);
    {
        double *gmass = lk_calloc(L, (size_t)m->nlinks, sizeof(double));
        if (!gmass) return oom(d);
        for (i = 0; i < m->nlinks; i++) gmass[find_group(m->group, i)] += m->links[i].mass;
        for (i = 0; i < m->nlinks; i++) {
            int32_t g = find_group(m->group, i), k;
            size_t len = 0;
            if (g == world_group || gmass[g] > 0.0) continue;
            text[0] = 0;
            for (k = 0; k < m->nlinks && len < sizeof text - 8; k++)
                if (find_group(m->group, k) == g)
                    len += (size_t)snprintf(text + len, sizeof text - len, "%s'%s'",
                                            len ? ", " : "", m->links[k].name);
            lk_free(L, gmass);
            return fail(d, AQS_EINVAL,
                        "link '%s' has no mass (%s) and is not welded by fixed joints to a link "
                        "with mass or to the world (its rigid group: %s); aqs needs mass on "
                        "every moving part",
                        m->links[i].name, m->links[i].has_inertial ? "mass 0" : "no <inertial>",
                        text);
        }
        lk_free(L, gmass);
    }
    for (i = 0; i < m->njoints; i++)
        if (m->joints[i].type == U_FLOATING && !(root_is_world && m->joints[i].parent == root))
            return fail(d, AQS_EINVAL,
                        "joint '%s': a floating joint must hang from the massless root link (the "
                        "world); its parent is '%s'",
                        m->joints[i].name, m->links[m->joints[i].parent].name);

    /* Build through the public functions. */
    {
        int32_t nb = 0;
        for (i = 0; i < m->nlinks; i++) {
            const ulink *lk = &m->links[i];
            if (root_is_world && i == root) {
                m->body_of[i] = AQS_WORLD;
                continue;
            }
            if (!o->physical_inertia) {
                /* Accepted (the solvers need positive semi-definite per link,
                 * definite per rigid group, checked at finalize); reported, as
                 * no real body has it. */
                L->lax_inertia = 0;
                if (model_check_body(L, "aqs_body_add", lk->mass, lk->com, lk->inertia) != AQS_OK) {
                    L->lax_inertia = 1;
                    if (model_check_body(L, "aqs_body_add", lk->mass, lk->com, lk->inertia) == AQS_OK)
                        warn(d, W_INERTIA, lk->name);
                }
                L->lax_inertia = 1;
            }
            if ((st = aqs_body_add(L, lk->mass, lk->com, lk->inertia, &m->body_of[i])) != AQS_OK ||
                (st = aqs_body_set_name(L, m->body_of[i], lk->name)) != AQS_OK) {
                char msg[sizeof L->error];
                snprintf(msg, sizeof msg, "%s", L->error);
                return fail(d, st, "link '%s': %s", lk->name, msg);
            }
            nb++;
        }
        (void)nb;
    }
    if (!root_is_world) {
        static const double zero[3] = {0, 0, 0}, unit[4] = {1, 0, 0, 0};
        char name[256];
        int32_t jj;
        snprintf(name, sizeof name, "world_to_%.240s", m->links[root].name);
        if ((st = aqs_joint_add(L, root_free ? AQS_JOINT_FREE : AQS_JOINT_FIXED, AQS_WORLD,
                                m->body_of[root], zero, unit, NULL, &jj)) != AQS_OK ||
            (st = aqs_joint_set_name(L, jj, name)) != AQS_OK)
            return fail(d, st, "%s", L->error);
    }
    for (i = 0; i < m->njoints; i++) {
        const ujoint *j = &m->joints[i];
        double q[4];
        int32_t jj;
        rpy_quat(j->rpy, q);
        if ((st = aqs_joint_add(L, aqs_types[j->type], m->body_of[j->parent], m->body_of[j->child],
                                j->xyz, q, j->axis, &jj)) != AQS_OK ||
            (st = aqs_joint_set_name(L, jj, j->name)) != AQS_OK ||
            (st = aqs_joint_set_limits(L, jj, j->limits[0], j->limits[1], j->limits[2],
                                       j->limits[3])) != AQS_OK) {
            char msg[sizeof L->error];
            snprintf(msg, sizeof msg, "%s", L->error);
            return fail(d, st, "joint '%s': %s", j->name, msg);
        }
    }
    if (o->collision)
        for (i = 0; i < m->nlinks; i++)
            if ((st = add_collision(m, &m->links[i], m->body_of[i])) != AQS_OK) return st;
    if ((st = store_warnings(d)) != AQS_OK) return st;
    if (o->finalize && (st = aqs_linkage_finalize(L)) != AQS_OK) {
        char msg[sizeof L->error];
        snprintf(msg, sizeof msg, "%s", L->error);
        return fail(d, st, "%s", msg);
    }
    return AQS_OK;
}

/* ------------------------------------------------------------ entry points */

/* Return the linkage to empty after a failed load (it was empty before). */
static void empty_linkage(aqs_linkage *L)
{
    char saved[sizeof L->error];
    if (L->finalized) return; /* finalize is the last step and leaves it building on failure */
    memcpy(saved, L->error, sizeof saved);
    collide_free(L);
    lk_names_free(L);
    L->nbodies = L->njoints = L->nq = L->nv = L->nloaded = 0;
    memcpy(L->error, saved, sizeof saved);
}

static void free_doc(model_in *m)
{
    aqs_linkage *L = m->d.L;
    lk_free(L, m->d.els);
    lk_free(L, m->d.text);
    lk_free(L, m->d.attrs);
    lk_free(L, m->links);
    lk_free(L, m->joints);
    lk_free(L, m->hash);
    lk_free(L, m->jhash);
    lk_free(L, m->parent_joint);
    lk_free(L, m->group);
    lk_free(L, m->body_of);
}

static aqs_status check_call(aqs_linkage *L, const char *fn, const aqs_urdf_options *options,
                             aqs_urdf_options *o)
{
    aqs_urdf_options_init(o);
    if (options) {
        if (options->size < sizeof(uint32_t) || options->size > 4096)
            return lk_fail(L, AQS_EINVAL, "%s: options->size = %u is not a size this library "
                           "knows (set it with aqs_urdf_options_init)", fn, (unsigned)options->size);
        memcpy(o, options, options->size < sizeof *o ? options->size : sizeof *o);
        o->size = (uint32_t)sizeof *o;
    }
    if (o->root != AQS_URDF_ROOT_FIXED && o->root != AQS_URDF_ROOT_FREE)
        return lk_fail(L, AQS_EINVAL, "%s: options->root = %d is not an AQS_URDF_ROOT_* value", fn,
                       (int)o->root);
    if (o->collision != 0 && o->collision != 1)
        return lk_fail(L, AQS_EINVAL, "%s: options->collision = %d must be 0 or 1", fn,
                       (int)o->collision);
    if (o->physical_inertia != 0 && o->physical_inertia != 1)
        return lk_fail(L, AQS_EINVAL, "%s: options->physical_inertia = %d must be 0 or 1", fn,
                       (int)o->physical_inertia);
    if (o->finalize != 0 && o->finalize != 1)
        return lk_fail(L, AQS_EINVAL, "%s: options->finalize = %d must be 0 or 1", fn,
                       (int)o->finalize);
    if (L->finalized || L->nbodies || L->njoints || collide_has_shapes(L))
        return lk_fail(L, AQS_ESTATE,
                       "%s: the linkage must be empty (it has %d bodies, %d joints%s%s); load "
                       "into a new one",
                       fn, (int)L->nbodies, (int)L->njoints, collide_has_shapes(L) ? ", shapes" : "",
                       L->finalized ? ", finalized" : "");
    return AQS_OK;
}

/* feed(user, parser) pushes the whole document through XML_Parse. */
typedef aqs_status (*feed_fn)(doc *d, const void *user);

static aqs_status load(aqs_linkage *L, const char *fn, const char *source, feed_fn feed,
                       const void *user, const aqs_urdf_options *options)
{
    model_in m;
    aqs_urdf_options o;
    aqs_status st;
    if ((st = check_call(L, fn, options, &o)) != AQS_OK) return st;
    memset(&m, 0, sizeof m);
    m.d.L = L;
    m.d.fn = fn;
    m.d.source = source;
    m.d.current = -1;
    m.d.parser = XML_ParserCreate(NULL);
    if (!m.d.parser) return lk_fail(L, AQS_ENOMEM, "%s: out of memory", fn);
    XML_SetUserData(m.d.parser, &m.d);
    XML_SetElementHandler(m.d.parser, on_start, on_end);
    lk_free(L, L->load_warnings);
    L->load_warnings = NULL;
    st = feed(&m.d, user);
    XML_ParserFree(m.d.parser);
    m.d.parser = NULL;
    if (st == AQS_OK) {
        int lax = L->lax_inertia;
        L->lax_inertia = !o.physical_inertia;
        st = build(&m, &o);
        L->lax_inertia = lax;
    }
    if (st != AQS_OK) empty_linkage(L);
    free_doc(&m);
    return st;
}

static aqs_status parse_chunk(doc *d, const char *data, size_t n, int last)
{
    while (n > 0 || last) {
        int chunk = n > (size_t)1 << 30 ? 1 << 30 : (int)n;
        int final = last && (size_t)chunk == n;
        if (XML_Parse(d->parser, data, chunk, final) == XML_STATUS_ERROR) {
            if (d->status != AQS_OK) return d->status;
            return fail(d, AQS_EINVAL, "not well-formed XML (%s) at line %lu, column %lu",
                        XML_ErrorString(XML_GetErrorCode(d->parser)),
                        (unsigned long)XML_GetCurrentLineNumber(d->parser),
                        (unsigned long)XML_GetCurrentColumnNumber(d->parser) + 1);
        }
        if (d->status != AQS_OK) return d->status;
        data += chunk;
        n -= (size_t)chunk;
        if (final) break;
    }
    return AQS_OK;
}

typedef struct {
    const char *data;
    size_t size;
} buffer;

static aqs_status feed_buffer(doc *d, const void *user)
{
    const buffer *b = user;
    return parse_chunk(d, b->data, b->size, 1);
}

static aqs_status feed_file(doc *d, const void *user)
{
    FILE *f = fopen((const char *)user, "rb");
    char block[1 << 14];
    aqs_status st = AQS_OK;
    if (!f) return fail(d, AQS_EINVAL, "cannot read (%s)", strerror(errno));
    for (;;) {
        size_t n = fread(block, 1, sizeof block, f);
        if (ferror(f)) {
            st = fail(d, AQS_EINVAL, "cannot read (%s)", strerror(errno));
            break;
        }
        if ((st = parse_chunk(d, block, n, feof(f) ? 1 : 0)) != AQS_OK || feof(f)) break;
    }
    fclose(f);
    return st;
}

AQS_API aqs_status aqs_linkage_load_urdf(aqs_linkage *L, const char *path,
                                         const aqs_urdf_options *options)
{
    static const char fn[] = "aqs_linkage_load_urdf";
    if (!L) return AQS_EINVAL;
    if (!path) return lk_fail(L, AQS_EINVAL, "%s: path is NULL", fn);
    return load(L, fn, path, feed_file, path, options);
}

AQS_API aqs_status aqs_linkage_load_urdf_buffer(aqs_linkage *L, const char *data, size_t size,
                                                const char *name, const aqs_urdf_options *options)
{
    static const char fn[] = "aqs_linkage_load_urdf_buffer";
    buffer b;
    if (!L) return AQS_EINVAL;
    if (!data && size) return lk_fail(L, AQS_EINVAL, "%s: data is NULL with size = %zu", fn, size);
    b.data = data ? data : "";
    b.size = size;
    return load(L, fn, name ? name : "<buffer>", feed_buffer, &b, options);
}

#endif /* AQS_HAVE_EXPAT */
