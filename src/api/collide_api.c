/* collide_api.c -- the public collision entry points: shapes, filters and
 * queries (argument checks, status codes, messages). The geometry is in
 * shape.c and narrowphase.c, the tree traversal in broadphase.c. */
#include <math.h>
#include <string.h>

#include "aqs.h"
#include "check.h"
#include "collide.h"
#include "linkage.h"
#include "stale.h"
#include "frames.h"

/* Get (creating on first use) the collision state. NULL on allocation failure. */
static collision *collide_state(aqs_linkage *L)
{
    if (!L->col) {
        L->col = lk_calloc_in(L, LK_MEM_COLLISION, 1, sizeof(collision));
        if (!L->col) return NULL;
        L->col->world_group = 1u;
        L->col->world_mask = 0xFFFFFFFFu;
    }
    return L->col;
}

/* Contacts may have changed: penalty forces must be recomputed. */
static void contacts_changed(aqs_linkage *L)
{
    broadphase_forget(L);
    if (L->col && L->col->stiffness > 0.0) stale_loads(L); /* penalty forces */
}

void collide_free(aqs_linkage *L)
{
    collision *c = L->col;
    int32_t i;
    if (!c) return;
    broadphase_reset(L);
    for (i = 0; i < c->nshapes; i++) lk_free(L, c->shapes[i].pts);
    lk_free(L, c->shapes);
    lk_free(L, c->group);
    lk_free(L, c->mask);
    lk_free(L, c->excl);
    lk_free(L, c);
    L->col = NULL;
}

static aqs_status oom(aqs_linkage *L, const char *fn)
{
    return lk_fail(L, AQS_ENOMEM, "%s: out of memory", fn);
}

static aqs_status check_owner(aqs_linkage *L, const char *fn, const char *name, int32_t body)
{
    if (body != AQS_WORLD && (body < 0 || body >= L->nbodies))
        return lk_fail(L, AQS_ERANGE, "%s: %s = %d is neither AQS_WORLD nor a body in [0, %d)", fn,
                       name, (int)body, (int)L->nbodies);
    return AQS_OK;
}

static aqs_status check_placement(aqs_linkage *L, const char *fn, const double pos[3],
                                  const double quat[4], pose *P)
{
    int i;
    double q[4], len;
    aqs_status st;
    if ((st = check_vec(L, fn, "pos", pos, 3)) != AQS_OK || (st = check_vec(L, fn, "quat", quat, 4)) != AQS_OK ||
        (st = check_unit_quat(L, fn, "quat", quat, &len)) != AQS_OK)
        return st;
    for (i = 0; i < 3; i++)
        if (!(fabs(pos[i]) <= SHAPE_MAX))
            return lk_fail(L, AQS_EINVAL, "%s: pos[%d] = %g is beyond 1e150 (collision geometry there overflows)",
                           fn, i, pos[i]);
    for (i = 0; i < 4; i++) q[i] = quat[i] / len;
    pose_from_quat(pos, q, P);
    return AQS_OK;
}

/* A failed first shape leaves the tree's poses as they were: refreshed or
 * allocated by it, they would change the path later solves take to the
 * bodies' world poses (frames_comp_world walks the kinematic tree while the
 * tree's poses are stale or absent), and so their last bits. */
static aqs_status first_shape_failed(aqs_linkage *L, int had_poses, int was_stale, aqs_status st)
{
    if (!had_poses && L->t.poses) {
        lk_free(L, L->t.poses);
        L->t.poses = NULL;
    }
    if (was_stale) stale_poses(L);
    return st;
}

/* Append a validated shape (pts already copied, owned on success). */
static aqs_status push_shape(aqs_linkage *L, const char *fn, const shape_def *s, int32_t *out)
{
    collision *c = collide_state(L);
    const int had_poses = L->t.poses != NULL, was_stale = L->t.poses_stale;
    int first;
    if (!c) return oom(L, fn);
    first = c->nshapes == 0;
    /* the first shape: from now on the tree's poses follow every move (a
     * linkage with filters and no shape holds no poses for them) */
    if (first && frames_poses(L) != AQS_OK) return first_shape_failed(L, had_poses, was_stale, oom(L, fn));
    if (c->nshapes == c->shape_cap) {
        int32_t cap = c->shape_cap ? 2 * c->shape_cap : 8;
        shape_def *grown = lk_alloc_in(L, LK_MEM_COLLISION, (size_t)cap * sizeof(shape_def));
        if (!grown) return first ? first_shape_failed(L, had_poses, was_stale, oom(L, fn)) : oom(L, fn);
        if (c->nshapes) memcpy(grown, c->shapes, (size_t)c->nshapes * sizeof(shape_def));
        lk_free(L, c->shapes);
        c->shapes = grown;
        c->shape_cap = cap;
    }
    c->shapes[c->nshapes] = *s;
    shape_bound(&c->shapes[c->nshapes]);
    if (L->finalized && c->stiffness > 0.0) {
        /* penalty contact: build now, so that solving never allocates; a
           failure keeps the former shapes' data, which solving needs */
        aqs_status st = broadphase_rebuild(L, c->nshapes + 1, fn);
        if (st != AQS_OK) return first ? first_shape_failed(L, had_poses, was_stale, st) : st;
        stale_loads(L);
    } else {
        c->nshapes++;
        broadphase_reset(L); /* rebuilt at the next query */
    }
    if (out) *out = c->nshapes - 1;
    return AQS_OK;
}

AQS_API aqs_status aqs_shape_add(aqs_linkage *L, int32_t body, int32_t type, const double size[3],
                                 const double pos[3], const double quat[4], int32_t *out_shape)
{
    static const char fn[] = "aqs_shape_add";
    shape_def s;
    aqs_status st;
    int r;
    if (!L) return AQS_EINVAL;
    if ((st = check_owner(L, fn, "body", body)) != AQS_OK) return st;
    if (type < AQS_SHAPE_SPHERE || type > AQS_SHAPE_CYLINDER)
        return lk_fail(L, AQS_EINVAL,
                       "%s: type = %d is not AQS_SHAPE_SPHERE, _CAPSULE, _BOX or _CYLINDER "
                       "(hulls: aqs_shape_add_hull)", fn, (int)type);
    if (!size) return lk_fail(L, AQS_EINVAL, "%s: size is NULL", fn);
    if ((r = shape_check_size(type, size)) != 0)
        return lk_fail(L, AQS_EINVAL, "%s: size[%d] = %g must be finite%s", fn, r - 1, size[r - 1],
                       isfinite(size[r - 1]) ? " and in [1e-150, 1e150] (collision geometry beyond over- or underflows)"
                                             : "");
    memset(&s, 0, sizeof s);
    if ((st = check_placement(L, fn, pos, quat, &s.local)) != AQS_OK) return st;
    s.type = type;
    s.body = body;
    memcpy(s.size, size, sizeof s.size);
    return push_shape(L, fn, &s, out_shape);
}

AQS_API aqs_status aqs_shape_add_hull(aqs_linkage *L, int32_t body, const double *points,
                                      int32_t npoints, const double pos[3], const double quat[4],
                                      int32_t *out_shape)
{
    static const char fn[] = "aqs_shape_add_hull";
    shape_def s;
    aqs_status st;
    int r;
    if (!L) return AQS_EINVAL;
    if ((st = check_owner(L, fn, "body", body)) != AQS_OK) return st;
    if (npoints < 4)
        return lk_fail(L, AQS_EINVAL, "%s: npoints = %d; a hull needs at least 4 points", fn,
                       (int)npoints);
    if (!points) return lk_fail(L, AQS_EINVAL, "%s: points is NULL", fn);
    r = shape_check_hull(points, npoints);
    if (r > 0)
        return lk_fail(L, AQS_EINVAL, "%s: points[%d] (point %d) = %g is not finite%s", fn, r - 1,
                       (r - 1) / 3, points[r - 1],
                       isfinite(points[r - 1]) ? " or beyond 1e150 (collision geometry there overflows)" : "");
    if (r == -3)
        return lk_fail(L, AQS_EINVAL,
                       "%s: the %d points lie within 1e-150 of each other (collision geometry at that "
                       "scale underflows)", fn, (int)npoints);
    if (r < 0)
        return lk_fail(L, AQS_EINVAL,
                       "%s: the %d points are coplanar (relative 1e-9); a hull needs volume", fn,
                       (int)npoints);
    memset(&s, 0, sizeof s);
    if ((st = check_placement(L, fn, pos, quat, &s.local)) != AQS_OK) return st;
    s.type = AQS_SHAPE_HULL;
    s.body = body;
    s.npts = npoints;
    s.pts = lk_alloc_in(L, LK_MEM_COLLISION, (size_t)npoints * 3 * sizeof(double));
    if (!s.pts) return oom(L, fn);
    memcpy(s.pts, points, (size_t)npoints * 3 * sizeof(double));
    if ((st = push_shape(L, fn, &s, out_shape)) != AQS_OK) lk_free(L, s.pts);
    return st;
}

AQS_API aqs_status aqs_linkage_get_shape_count(const aqs_linkage *L, int32_t *count)
{
    if (!L) return AQS_EINVAL;
    if (!count) return lk_fail((aqs_linkage *)L, AQS_EINVAL, "aqs_linkage_get_shape_count: count is NULL");
    *count = L->col ? L->col->nshapes : 0;
    return AQS_OK;
}

AQS_API aqs_status aqs_body_set_collision_filter(aqs_linkage *L, int32_t body, uint32_t group,
                                                 uint32_t mask)
{
    static const char fn[] = "aqs_body_set_collision_filter";
    collision *c;
    aqs_status st;
    if (!L) return AQS_EINVAL;
    if ((st = check_owner(L, fn, "body", body)) != AQS_OK) return st;
    if (!(c = collide_state(L))) return oom(L, fn);
    if (body == AQS_WORLD) {
        c->world_group = group;
        c->world_mask = mask;
    } else {
        if (body >= c->nfilter) {
            int32_t n = L->nbodies, i;
            uint32_t *g = lk_alloc_in(L, LK_MEM_COLLISION, (size_t)n * sizeof(uint32_t));
            uint32_t *m = lk_alloc_in(L, LK_MEM_COLLISION, (size_t)n * sizeof(uint32_t));
            if (!g || !m) {
                lk_free(L, g);
                lk_free(L, m);
                return oom(L, fn);
            }
            for (i = 0; i < n; i++) {
                g[i] = i < c->nfilter ? c->group[i] : 1u;
                m[i] = i < c->nfilter ? c->mask[i] : 0xFFFFFFFFu;
            }
            lk_free(L, c->group);
            lk_free(L, c->mask);
            c->group = g;
            c->mask = m;
            c->nfilter = n;
        }
        c->group[body] = group;
        c->mask[body] = mask;
    }
    contacts_changed(L);
    return AQS_OK;
}

AQS_API aqs_status aqs_collision_exclude_pair(aqs_linkage *L, int32_t a, int32_t b)
{
    static const char fn[] = "aqs_collision_exclude_pair";
    collision *c;
    aqs_status st;
    uint64_t key;
    int32_t pos;
    if (!L) return AQS_EINVAL;
    if ((st = check_owner(L, fn, "body_a", a)) != AQS_OK) return st;
    if ((st = check_owner(L, fn, "body_b", b)) != AQS_OK) return st;
    if (a == b)
        return lk_fail(L, AQS_EINVAL, "%s: body_a = body_b = %d; a pair needs two bodies", fn, (int)a);
    if (a > b) { int32_t t = a; a = b; b = t; }
    key = ((uint64_t)(uint32_t)(a + 1) << 32) | (uint32_t)(b + 1);
    if (!(c = collide_state(L))) return oom(L, fn);
    for (pos = 0; pos < c->nexcl && c->excl[pos] < key; pos++) {}
    if (pos < c->nexcl && c->excl[pos] == key) return AQS_OK;
    if (c->nexcl == c->excl_cap) {
        int32_t cap = c->excl_cap ? 2 * c->excl_cap : 8;
        uint64_t *grown = lk_alloc_in(L, LK_MEM_COLLISION, (size_t)cap * sizeof(uint64_t));
        if (!grown) return oom(L, fn);
        if (c->nexcl) memcpy(grown, c->excl, (size_t)c->nexcl * sizeof(uint64_t));
        lk_free(L, c->excl);
        c->excl = grown;
        c->excl_cap = cap;
    }
    memmove(c->excl + pos + 1, c->excl + pos, (size_t)(c->nexcl - pos) * sizeof(uint64_t));
    c->excl[pos] = key;
    c->nexcl++;
    contacts_changed(L);
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_set_collide_joined(aqs_linkage *L, int32_t enabled)
{
    static const char fn[] = "aqs_linkage_set_collide_joined";
    collision *c;
    if (!L) return AQS_EINVAL;
    if (enabled != 0 && enabled != 1)
        return lk_fail(L, AQS_EINVAL, "%s: enabled = %d must be 0 or 1", fn, (int)enabled);
    if (!L->col && !enabled) return AQS_OK; /* the default: nothing to store */
    if (!(c = collide_state(L))) return oom(L, fn);
    c->joined = enabled;
    contacts_changed(L);
    return AQS_OK;
}

static aqs_status prepare(aqs_linkage *L, const char *fn)
{
    aqs_status st;
    if ((st = check_finalized(L, fn)) != AQS_OK) return st;
    if (!L->col || L->col->nshapes == 0) return AQS_OK;
    return broadphase_build(L, fn);
}

AQS_API aqs_status aqs_linkage_collide(aqs_linkage *L, int32_t mode, aqs_contact *contacts,
                                       size_t capacity, size_t *count)
{
    static const char fn[] = "aqs_linkage_collide";
    aqs_status st;
    size_t total;
    if (!L) return AQS_EINVAL;
    if (mode < AQS_COLLIDE_LAZY || mode > AQS_COLLIDE_BRUTE)
        return lk_fail(L, AQS_EINVAL, "%s: mode = %d is not an AQS_COLLIDE_* value", fn, (int)mode);
    if (!count) return lk_fail(L, AQS_EINVAL, "%s: count is NULL", fn);
    if (capacity > 0 && !contacts)
        return lk_fail(L, AQS_EINVAL, "%s: contacts is NULL but capacity = %zu", fn, capacity);
    if ((st = prepare(L, fn)) != AQS_OK) return st;
    if (!L->col || L->col->nshapes == 0) {
        *count = 0;
        return AQS_OK;
    }
    total = broadphase_query(L, mode, contacts, capacity, 0);
    *count = total;
    if (total > capacity)
        return lk_fail(L, AQS_ESIZE, "%s: capacity = %zu but %zu contacts were found (the first %zu written)",
                       fn, capacity, total, capacity);
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_any_contact(aqs_linkage *L, int32_t *hit)
{
    static const char fn[] = "aqs_linkage_any_contact";
    aqs_status st;
    if (!L) return AQS_EINVAL;
    if (!hit) return lk_fail(L, AQS_EINVAL, "%s: hit is NULL", fn);
    if ((st = prepare(L, fn)) != AQS_OK) return st;
    *hit = collide_has_shapes(L) && broadphase_query(L, AQS_COLLIDE_LAZY, NULL, 0, 1) > 0;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_get_collision_stats(const aqs_linkage *L, int32_t *nodes_refit,
                                                   int32_t *volume_tests, int32_t *narrow_tests,
                                                   int32_t *nodes_skipped)
{
    const collision *c;
    if (!L) return AQS_EINVAL;
    c = L->col;
    if (nodes_refit) *nodes_refit = c ? c->nodes_refit : 0;
    if (volume_tests) *volume_tests = c ? c->volume_tests : 0;
    if (narrow_tests) *narrow_tests = c ? c->narrow_tests : 0;
    if (nodes_skipped) *nodes_skipped = c ? c->nodes_skipped : 0;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_get_query_stats(const aqs_linkage *cL, aqs_collision_stats *stats)
{
    static const char fn[] = "aqs_linkage_get_query_stats";
    aqs_linkage *L = (aqs_linkage *)cL; /* only the error message is written */
    const collision *c;
    aqs_collision_stats full;
    aqs_status st;
    uint32_t size;
    if (!L) return AQS_EINVAL;
    if ((st = check_stats_size(L, fn, stats, &size)) != AQS_OK) return st;
    memset(&full, 0, sizeof full);
    full.size = size;
    if ((c = L->col) != NULL) {
        full.nodes_refit = c->nodes_refit;
        full.volume_tests = c->volume_tests;
        full.narrow_tests = c->narrow_tests;
        full.nodes_skipped = c->nodes_skipped;
        full.certs_reused = c->certs_reused;
        full.certs_made = c->certs_made;
        full.near_tests = c->near_tests;
    }
    memcpy(stats, &full, size < sizeof full ? size : sizeof full);
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_set_contact_stiffness(aqs_linkage *L, double stiffness)
{
    static const char fn[] = "aqs_linkage_set_contact_stiffness";
    collision *c;
    aqs_status st;
    if (!L) return AQS_EINVAL;
    if ((st = check_finalized(L, fn)) != AQS_OK) return st;
    if (!isfinite(stiffness) || stiffness < 0.0)
        return lk_fail(L, AQS_EINVAL, "%s: stiffness = %g must be finite and >= 0", fn, stiffness);
    if (!L->col && stiffness == 0.0) return AQS_OK; /* the default: nothing to store */
    if (!(c = collide_state(L))) return oom(L, fn);
    if (c->nshapes > 0 && (st = broadphase_build(L, fn)) != AQS_OK) return st;
    if (c->stiffness != stiffness) {
        c->stiffness = stiffness;
        stale_loads(L);
    }
    return AQS_OK;
}
