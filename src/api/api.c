/* api.c -- the public entry points: argument checks, phases, status codes
 * and error messages. The numerical work is in the other files. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "aba.h"
#include "kintree.h"
#include "adaptive.h"
#include "cost.h"
#include "aqs.h"
#include "assembly.h"
#include "autopath.h"
#include "fpenv.h"
#include "check.h"
#include "collide.h"
#include "dca.h"
#include "frames.h"
#include "linkage.h"
#include "model.h"
#include "arefine.h"
#include "refine.h"
#include "stale.h"
#include "totalacc.h"
#include "worldbound.h"
#include "update.h"

#define STR2(x) #x
#define STR(x) STR2(x)

AQS_API int32_t aqs_version(void) { return AQS_VERSION_NUMBER; }

AQS_API const char *aqs_version_string(void)
{
    return STR(AQS_VERSION_MAJOR) "." STR(AQS_VERSION_MINOR) "." STR(AQS_VERSION_PATCH);
}

AQS_API const char *aqs_status_string(aqs_status status)
{
    switch (status) {
    case AQS_OK: return "success";
    case AQS_EINVAL: return "invalid argument";
    case AQS_ERANGE: return "index out of range";
    case AQS_ESTATE: return "operation not allowed in the linkage's current phase";
    case AQS_ENOMEM: return "out of memory";
    case AQS_EMODEL: return "invalid linkage";
    case AQS_ENUMERIC: return "numerical failure";
    case AQS_ESIZE: return "array of the wrong size";
    default: return "unknown status";
    }
}

/* ---------------------------------------------------------------- helpers */

static int finite_n(const double *v, int n, int *bad)
{
    int i;
    for (i = 0; i < n; i++)
        if (!isfinite(v[i])) {
            *bad = i;
            return 0;
        }
    return 1;
}

#define CHECK_LINKAGE(L)                                                                       \
    do {                                                                                       \
        if (!(L)) return AQS_EINVAL;                                                           \
    } while (0)

#define CHECK_PTR(L, fn, p)                                                                    \
    do {                                                                                       \
        if (!(p)) return lk_fail((L), AQS_EINVAL, "%s: %s is NULL", fn, #p);                   \
    } while (0)

static aqs_status check_body(aqs_linkage *L, const char *fn, int32_t body)
{
    if (body < 0 || body >= L->nbodies)
        return lk_fail(L, AQS_ERANGE, "%s: body = %d is out of range [0, %d)", fn, (int)body,
                       (int)L->nbodies);
    return AQS_OK;
}

static aqs_status check_joint(aqs_linkage *L, const char *fn, int32_t joint)
{
    if (joint < 0 || joint >= L->njoints)
        return lk_fail(L, AQS_ERANGE, "%s: joint = %d is out of range [0, %d)", fn, (int)joint,
                       (int)L->njoints);
    return AQS_OK;
}

static aqs_status need_building(aqs_linkage *L, const char *fn)
{
    if (L->finalized)
        return lk_fail(L, AQS_ESTATE, "%s: the linkage is finalized; its bodies and joints are fixed", fn);
    return AQS_OK;
}

static aqs_status need_solved(aqs_linkage *L, const char *fn)
{
    aqs_status st = check_finalized(L, fn);
    if (st == AQS_OK && !L->solved)
        return lk_fail(L, AQS_ESTATE, "%s: nothing solved yet (call aqs_linkage_solve or aqs_linkage_step)", fn);
    return st;
}

/* Grow an array to cap elements: returns the new block or NULL. */
static void *grown(aqs_linkage *L, const void *old, size_t used, size_t cap, size_t elem)
{
    void *p = lk_alloc(L, cap * elem);
    if (p && used) memcpy(p, old, used * elem);
    return p;
}

/* -------------------------------------------------------------- lifecycle */

static void *default_alloc(void *user, size_t size) { (void)user; return malloc(size); }
static void default_free(void *user, void *ptr) { (void)user; free(ptr); }

AQS_API aqs_status aqs_linkage_create_with_allocator(aqs_alloc_fn alloc, aqs_free_fn free_fn,
                                                     void *user, aqs_linkage **out)
{
    aqs_linkage *L;
    if (!alloc || !free_fn || !out) return AQS_EINVAL;
    *out = NULL;
    L = alloc(user, sizeof *L);
    if (!L) return AQS_ENOMEM;
    memset(L, 0, sizeof *L);
    L->alloc = alloc;
    L->free_fn = free_fn;
    L->user = user;
    L->mem[LK_MEM_MODEL] = L->mem_now = L->mem_peak = sizeof *L; /* aqs_linkage_get_memory */
    L->mem_blocks = 1;
    L->t.root = -1;
    autopath_init(L);
    L->refine_max = AQS_REFINEMENT_MAX;
    L->refine_forces = 1;
    L->rfb_level = AQS_ROUNDING_FALLBACK_LEVEL;
    L->arf_level = AQS_ADAPTIVE_REFINEMENT_LEVEL;
    *out = L;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_create(aqs_linkage **out)
{
    return aqs_linkage_create_with_allocator(default_alloc, default_free, NULL, out);
}

static void free_solver(aqs_linkage *L)
{
    aba_free(L);
    adaptive_free(L);
    worldbound_free(L);
    refine_free(L);
    arefine_free(L);
    totalacc_free(L);
    assembly_free(L);
    model_free(L);
    lk_free(L, L->qdd);
    lk_free(L, L->cforce);
    lk_free(L, L->q_saved);
    lk_free(L, L->welded_acc);
    L->qdd = L->cforce = L->q_saved = L->welded_acc = NULL;
}

AQS_API void aqs_linkage_destroy(aqs_linkage *L)
{
    if (!L) return;
    collide_free(L);
    lk_names_free(L);
    free_solver(L);
    lk_free(L, L->bodies);
    lk_free(L, L->loads);
    lk_free(L, L->load_slot);
    lk_free(L, L->loaded_bodies);
    lk_free(L, L->joints);
    lk_free(L, L->q);
    lk_free(L, L->tau);
    L->free_fn(L->user, L);
}

AQS_API const char *aqs_linkage_last_error(const aqs_linkage *L)
{
    if (!L) return "aqs_linkage_last_error: linkage is NULL";
    return L->error;
}

/* --------------------------------------------------------------- building */

AQS_API aqs_status aqs_linkage_set_inertia_check(aqs_linkage *L, int32_t physical)
{
    static const char fn[] = "aqs_linkage_set_inertia_check";
    aqs_status st;
    CHECK_LINKAGE(L);
    if ((st = need_building(L, fn)) != AQS_OK) return st;
    if (physical != 0 && physical != 1)
        return lk_fail(L, AQS_EINVAL, "%s: physical = %d must be 0 or 1", fn, (int)physical);
    L->lax_inertia = !physical;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_set_exact_solver(aqs_linkage *L, int32_t solver)
{
    static const char fn[] = "aqs_linkage_set_exact_solver";
    CHECK_LINKAGE(L);
    if (solver != AQS_EXACT_ABA && solver != AQS_EXACT_DCA)
        return lk_fail(L, AQS_EINVAL, "%s: solver = %d is not an AQS_EXACT_* value", fn, (int)solver);
    if (solver == AQS_EXACT_DCA && L->finalized) {
        aqs_status st = dca_enable(L, fn); /* O(N) memory, as for a tolerance */
        if (st != AQS_OK) return st;
    }
    if (solver != L->exact_solver) {
        L->exact_solver = solver;
        stale_settings(L);
    }
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_get_exact_solver(const aqs_linkage *L, int32_t *solver)
{
    static const char fn[] = "aqs_linkage_get_exact_solver";
    aqs_linkage *ml = (aqs_linkage *)L;
    CHECK_LINKAGE(ml);
    CHECK_PTR(ml, fn, solver);
    *solver = L->exact_solver;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_set_exact_refinement(aqs_linkage *L, int32_t max_corrections)
{
    static const char fn[] = "aqs_linkage_set_exact_refinement";
    CHECK_LINKAGE(L);
    if (max_corrections < 0 || max_corrections > AQS_REFINEMENT_MAX)
        return lk_fail(L, AQS_EINVAL, "%s: max_corrections = %d is not in 0 .. %d", fn, (int)max_corrections,
                       AQS_REFINEMENT_MAX);
    if (max_corrections != L->refine_max) L->ap.exact = 0.0; /* the exact path's cost changes: priced anew */
    L->refine_max = max_corrections;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_get_exact_refinement(const aqs_linkage *L, int32_t *max_corrections)
{
    static const char fn[] = "aqs_linkage_get_exact_refinement";
    aqs_linkage *ml = (aqs_linkage *)L;
    CHECK_LINKAGE(ml);
    CHECK_PTR(ml, fn, max_corrections);
    *max_corrections = L->refine_max;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_set_dca_form(aqs_linkage *L, int32_t form)
{
    static const char fn[] = "aqs_linkage_set_dca_form";
    aqs_status st;
    CHECK_LINKAGE(L);
    if ((st = need_building(L, fn)) != AQS_OK) return st;
    if (form != AQS_DCA_FORM_SQRT && form != AQS_DCA_FORM_PHI)
        return lk_fail(L, AQS_EINVAL, "%s: form = %d is not an AQS_DCA_FORM_* value", fn, (int)form);
    L->dca_form = form;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_get_dca_form(const aqs_linkage *L, int32_t *form)
{
    static const char fn[] = "aqs_linkage_get_dca_form";
    aqs_linkage *ml = (aqs_linkage *)L;
    CHECK_LINKAGE(ml);
    CHECK_PTR(ml, fn, form);
    *form = L->dca_form;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_set_tree_builder(aqs_linkage *L, int32_t builder)
{
    static const char fn[] = "aqs_linkage_set_tree_builder";
    aqs_status st;
    CHECK_LINKAGE(L);
    if ((st = need_building(L, fn)) != AQS_OK) return st;
    if (builder != AQS_TREE_CONTRACTION && builder != AQS_TREE_BISECTION)
        return lk_fail(L, AQS_EINVAL, "%s: builder = %d is not an AQS_TREE_* value", fn, (int)builder);
    L->tree_builder = builder;
    return AQS_OK;
}

AQS_API aqs_status aqs_body_add(aqs_linkage *L, double mass, const double com[3],
                                const double inertia[9], int32_t *out_body)
{
    static const char fn[] = "aqs_body_add";
    aqs_status st;
    CHECK_LINKAGE(L);
    if ((st = need_building(L, fn)) != AQS_OK) return st;
    CHECK_PTR(L, fn, com);
    CHECK_PTR(L, fn, inertia);
    if ((st = model_check_body(L, fn, mass, com, inertia)) != AQS_OK) return st;
    if (L->nbodies == INT32_MAX - 1) return lk_fail(L, AQS_ENOMEM, "%s: too many bodies", fn);
    if (L->nbodies == L->body_cap) {
        size_t cap = L->body_cap ? 2 * (size_t)L->body_cap : 16, n = (size_t)L->nbodies;
        body_def *b;
        body_load *ld;
        int32_t *slot, *list;
        if (cap > INT32_MAX) cap = INT32_MAX;
        b = grown(L, L->bodies, n, cap, sizeof *b);
        ld = grown(L, L->loads, n, cap, sizeof *ld);
        slot = grown(L, L->load_slot, n, cap, sizeof *slot);
        list = grown(L, L->loaded_bodies, (size_t)L->nloaded, cap, sizeof *list);
        if (!b || !ld || !slot || !list) {
            lk_free(L, b);
            lk_free(L, ld);
            lk_free(L, slot);
            lk_free(L, list);
            return lk_fail(L, AQS_ENOMEM, "%s: out of memory growing to %zu bodies", fn, cap);
        }
        lk_free(L, L->bodies);
        lk_free(L, L->loads);
        lk_free(L, L->load_slot);
        lk_free(L, L->loaded_bodies);
        L->bodies = b;
        L->loads = ld;
        L->load_slot = slot;
        L->loaded_bodies = list;
        L->body_cap = (int32_t)cap;
    }
    {
        body_def *b = &L->bodies[L->nbodies];
        int i, j;
        b->mass = mass;
        memcpy(b->com, com, sizeof b->com);
        for (i = 0; i < 3; i++) /* store the symmetric part */
            for (j = 0; j < 3; j++) b->inertia[3 * i + j] = 0.5 * (inertia[3 * i + j] + inertia[3 * j + i]);
        memset(&L->loads[L->nbodies], 0, sizeof(body_load));
        L->load_slot[L->nbodies] = -1;
    }
    if (out_body) *out_body = L->nbodies;
    L->nbodies++;
    return AQS_OK;
}

AQS_API aqs_status aqs_joint_add(aqs_linkage *L, int32_t type, int32_t parent, int32_t child,
                                 const double pos[3], const double quat[4], const double axis[3],
                                 int32_t *out_joint)
{
    static const char fn[] = "aqs_joint_add";
    aqs_status st;
    joint_def jd;
    int nq, nv, i;
    double qn, an = 0.0;
    CHECK_LINKAGE(L);
    if ((st = need_building(L, fn)) != AQS_OK) return st;
    if (type < 0 || type >= JOINT_TYPE_COUNT)
        return lk_fail(L, AQS_EINVAL, "%s: type = %d is not an AQS_JOINT_* value", fn, (int)type);
    if (parent != AQS_WORLD && (parent < 0 || parent >= L->nbodies))
        return lk_fail(L, AQS_ERANGE, "%s: parent = %d is neither AQS_WORLD nor a body in [0, %d)",
                       fn, (int)parent, (int)L->nbodies);
    if (child < 0 || child >= L->nbodies)
        return lk_fail(L, AQS_ERANGE, "%s: child = %d is out of range [0, %d)", fn, (int)child,
                       (int)L->nbodies);
    if (parent == child)
        return lk_fail(L, AQS_EINVAL, "%s: parent = child = %d", fn, (int)child);
    if (type == AQS_JOINT_FREE && parent != AQS_WORLD)
        return lk_fail(L, AQS_EINVAL,
                       "%s: a free joint must have parent AQS_WORLD, got parent = %d", fn, (int)parent);
    if ((st = check_vec(L, fn, "pos", pos, 3)) != AQS_OK) return st;
    if ((st = check_vec(L, fn, "quat", quat, 4)) != AQS_OK) return st;
    if ((st = check_unit_quat(L, fn, "quat", quat, &qn)) != AQS_OK) return st;
    if (joint_uses_axis(type)) {
        if ((st = check_vec(L, fn, "axis", axis, 3)) != AQS_OK) return st;
        an = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
        if (!(an > 1e-12))
            return lk_fail(L, AQS_EINVAL, "%s: axis = (%g, %g, %g) is zero", fn, axis[0], axis[1], axis[2]);
    }
    nq = joint_nq(type);
    nv = joint_nv(type);
    if (L->nq > INT32_MAX - 8 || L->njoints == INT32_MAX - 1)
        return lk_fail(L, AQS_ENOMEM, "%s: too many joints", fn);
    /* Reserve everything first so that a failure changes nothing. q and tau
     * exist from the first joint on, fixed ones included: L->q + offset is
     * then never arithmetic on NULL. */
    {
        joint_def *nj = NULL;
        double *nqa = NULL, *nta = NULL;
        size_t jcap = (size_t)L->joint_cap, qcap = (size_t)L->q_cap, vcap = (size_t)L->v_cap;
        int grow_j = L->njoints == L->joint_cap, grow_q = L->nq + nq > L->q_cap || !L->q,
            grow_v = L->nv + nv > L->v_cap || !L->tau;
        if (grow_j) {
            jcap = jcap ? 2 * jcap : 16;
            nj = grown(L, L->joints, (size_t)L->njoints, jcap, sizeof *nj);
        }
        if (grow_q) {
            qcap = qcap ? 2 * qcap + (size_t)nq : 64;
            nqa = grown(L, L->q, (size_t)L->nq, qcap, sizeof(double));
        }
        if (grow_v) {
            vcap = vcap ? 2 * vcap + (size_t)nv : 64;
            nta = grown(L, L->tau, (size_t)L->nv, vcap, sizeof(double));
        }
        if ((grow_j && !nj) || (grow_q && !nqa) || (grow_v && !nta)) {
            lk_free(L, nj);
            lk_free(L, nqa);
            lk_free(L, nta);
            return lk_fail(L, AQS_ENOMEM, "%s: out of memory", fn);
        }
        if (nj) {
            lk_free(L, L->joints);
            L->joints = nj;
            L->joint_cap = (int32_t)jcap;
        }
        if (nqa) {
            lk_free(L, L->q);
            L->q = nqa;
            L->q_cap = (int32_t)qcap;
        }
        if (nta) {
            lk_free(L, L->tau);
            L->tau = nta;
            L->v_cap = (int32_t)vcap;
        }
    }
    memset(&jd, 0, sizeof jd);
    jd.type = type;
    jd.parent = parent;
    jd.child = child;
    memcpy(jd.pos, pos, sizeof jd.pos);
    for (i = 0; i < 4; i++) jd.quat[i] = quat[i] / qn;
    if (joint_uses_axis(type)) {
        for (i = 0; i < 3; i++) jd.axis[i] = axis[i] / an;
    } else {
        jd.axis[2] = 1.0;
    }
    joint_directions(jd.axis, jd.u, jd.v);
    jd.qoff = L->nq;
    jd.voff = L->nv;
    jd.limits[0] = -HUGE_VAL; /* no limits until aqs_joint_set_limits */
    jd.limits[1] = jd.limits[2] = jd.limits[3] = HUGE_VAL;
    joint_zero_position(type, L->q + L->nq);
    for (i = 0; i < nv; i++) L->tau[L->nv + i] = 0.0;
    L->joints[L->njoints] = jd;
    L->nq += nq;
    L->nv += nv;
    if (out_joint) *out_joint = L->njoints;
    L->njoints++;
    return AQS_OK;
}

/* An array of used elements shrunk to exactly that many (the building
 * arrays grow geometrically). 0, or -1 when the copy cannot be had (the
 * array is left as it is). */
static int shrink(aqs_linkage *L, void **arr, size_t used, size_t elem, int32_t *cap)
{
    void *p;
    if (!*arr || used == 0 || used >= (size_t)*cap) return 0;
    p = lk_alloc(L, used * elem);
    if (!p) return -1;
    memcpy(p, *arr, used * elem);
    lk_free(L, *arr);
    *arr = p;
    *cap = (int32_t)used;
    return 0;
}

/* Release the unused capacity of the body, joint, position and force arrays
 * (up to half of them after geometric growth). 0, or -1 when out of memory
 * (the contents are unchanged either way). */
static int shrink_building_arrays(aqs_linkage *L)
{
    size_t nb = (size_t)L->nbodies;
    int32_t c;
    void *p;
    if (L->body_cap > L->nbodies && L->nbodies > 0) {
        body_def *b = lk_alloc(L, nb * sizeof *b);
        body_load *ld = lk_alloc(L, nb * sizeof *ld);
        int32_t *slot = lk_alloc(L, nb * sizeof *slot), *list = lk_alloc(L, nb * sizeof *list);
        if (!b || !ld || !slot || !list) {
            lk_free(L, b);
            lk_free(L, ld);
            lk_free(L, slot);
            lk_free(L, list);
            return -1;
        }
        memcpy(b, L->bodies, nb * sizeof *b);
        memcpy(ld, L->loads, nb * sizeof *ld);
        memcpy(slot, L->load_slot, nb * sizeof *slot);
        if (L->nloaded) memcpy(list, L->loaded_bodies, (size_t)L->nloaded * sizeof *list);
        lk_free(L, L->bodies);
        lk_free(L, L->loads);
        lk_free(L, L->load_slot);
        lk_free(L, L->loaded_bodies);
        L->bodies = b;
        L->loads = ld;
        L->load_slot = slot;
        L->loaded_bodies = list;
        L->body_cap = L->nbodies;
    }
    p = L->joints;
    if (shrink(L, &p, (size_t)L->njoints, sizeof *L->joints, &L->joint_cap)) return -1;
    L->joints = p;
    p = L->q, c = L->q_cap;
    if (shrink(L, &p, (size_t)L->nq, sizeof *L->q, &c)) return -1;
    L->q = p, L->q_cap = c;
    p = L->tau, c = L->v_cap;
    if (shrink(L, &p, (size_t)L->nv, sizeof *L->tau, &c)) return -1;
    L->tau = p, L->v_cap = c;
    return 0;
}

AQS_API aqs_status aqs_linkage_finalize(aqs_linkage *L)
{
    static const char fn[] = "aqs_linkage_finalize";
    aqs_status st;
    CHECK_LINKAGE(L);
    if ((st = need_building(L, fn)) != AQS_OK) return st;
    if ((st = model_build(L)) != AQS_OK) return st;
    if ((st = assembly_build(L)) != AQS_OK) {
        model_free(L);
        return st;
    }
    L->qdd = lk_calloc(L, (size_t)L->nv + 1, sizeof(double));
    L->cforce = lk_calloc(L, 6 * (size_t)L->njoints + 1, sizeof(double));
    L->q_saved = lk_calloc(L, (size_t)L->nq + 1, sizeof(double));
    /* welded bodies' forces: their accelerations, the inverse inertias */
    L->welded_acc = L->m.nwelded ? lk_calloc(L, 6 * (size_t)L->nbodies + 1, sizeof(double)) : NULL;
    if (!L->qdd || !L->cforce || !L->q_saved || (L->m.nwelded && !L->welded_acc) ||
        adaptive_alloc(L) != AQS_OK || aba_alloc(L) != AQS_OK || (L->m.nwelded && model_inverse_alloc(L) != AQS_OK)) {
        free_solver(L);
        return lk_fail(L, AQS_ENOMEM, "%s: out of memory", fn);
    }
    frames_world_frame(L, &L->t.world_frame); /* the grounded nodes' frame (frames.h) */
    /* The tree's poses when collision needs them at once, or the leaves'
     * (welded bodies' forces after an exact solve); otherwise when a setter
     * first chooses the DCA or a tolerance (dca_enable) or a shape is added. */
    if ((collide_has_shapes(L) && frames_poses(L) != AQS_OK) || (L->m.nwelded > 0 && frames_poses_alloc(L) != AQS_OK) ||
        shrink_building_arrays(L) != 0) {
        free_solver(L);
        return lk_fail(L, AQS_ENOMEM, "%s: out of memory", fn);
    }
    model_drop_inertia(L); /* the articulated-body solver has it, packed */
    stale_tree(L);
    /* The DCA coefficients only when the DCA is the exact solver, or when
     * nothing can move (no tree node: the solve takes the DCA path, and its
     * few bytes are allocated here rather than in a solve). Tolerances and
     * caps are set after finalize and allocate them then. */
    if (L->exact_solver == AQS_EXACT_DCA || L->t.nnodes == 0) {
        if ((st = dca_enable(L, fn)) != AQS_OK || (st = update_coefficients(L)) != AQS_OK) {
            free_solver(L);
            return lk_fail_in(L, st, fn);
        }
    }
    L->finalized = 1;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_get_sizes(const aqs_linkage *L, int32_t *bodies, int32_t *joints,
                                         int32_t *nq, int32_t *nv)
{
    CHECK_LINKAGE(L);
    if (bodies) *bodies = L->nbodies;
    if (joints) *joints = L->njoints;
    if (nq) *nq = L->nq;
    if (nv) *nv = L->nv;
    return AQS_OK;
}

AQS_API aqs_status aqs_joint_get_layout(const aqs_linkage *cL, int32_t joint, int32_t *q_offset,
                                        int32_t *nq, int32_t *v_offset, int32_t *nv)
{
    aqs_linkage *L = (aqs_linkage *)cL; /* only the error message is written */
    aqs_status st;
    CHECK_LINKAGE(L);
    if ((st = check_joint(L, "aqs_joint_get_layout", joint)) != AQS_OK) return st;
    if (q_offset) *q_offset = L->joints[joint].qoff;
    if (nq) *nq = joint_nq(L->joints[joint].type);
    if (v_offset) *v_offset = L->joints[joint].voff;
    if (nv) *nv = joint_nv(L->joints[joint].type);
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_get_tree_stats(const aqs_linkage *cL, int32_t *nodes,
                                              int32_t *height, double *mean_handles,
                                              int32_t *max_handles)
{
    aqs_linkage *L = (aqs_linkage *)cL;
    aqs_status st;
    CHECK_LINKAGE(L);
    if ((st = check_finalized(L, "aqs_linkage_get_tree_stats")) != AQS_OK) return st;
    if (nodes) *nodes = L->t.nnodes;
    if (height) *height = L->t.height;
    if (mean_handles) *mean_handles = L->t.mean_handles;
    if (max_handles) *max_handles = L->t.max_handles;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_get_memory(const aqs_linkage *cL, aqs_memory_stats *stats)
{
    static const char fn[] = "aqs_linkage_get_memory";
    aqs_linkage *L = (aqs_linkage *)cL; /* only the error message is written */
    aqs_memory_stats full;
    aqs_status st;
    uint32_t size;
    if (!L) return AQS_EINVAL;
    if ((st = check_stats_size(L, fn, stats, &size)) != AQS_OK) return st;
    memset(&full, 0, sizeof full);
    full.size = size;
    full.blocks = (uint32_t)L->mem_blocks;
    full.bytes = L->mem_now;
    full.peak = L->mem_peak;
    full.model = L->mem[LK_MEM_MODEL];
    full.tree = L->mem[LK_MEM_TREE];
    full.exact = L->mem[LK_MEM_EXACT];
    full.dca = L->mem[LK_MEM_DCA];
    full.factors = L->mem[LK_MEM_FACTORS];
    full.world = L->mem[LK_MEM_WORLD];
    full.collision = L->mem[LK_MEM_COLLISION];
    memcpy(stats, &full, size < sizeof full ? size : sizeof full);
    return AQS_OK;
}

/* ------------------------------------------------------------------ loads */

AQS_API aqs_status aqs_linkage_set_gravity(aqs_linkage *L, const double gravity[3])
{
    aqs_status st;
    CHECK_LINKAGE(L);
    if ((st = check_vec(L, "aqs_linkage_set_gravity", "gravity", gravity, 3)) != AQS_OK) return st;
    memcpy(L->gravity, gravity, sizeof L->gravity);
    stale_gravity(L);
    return AQS_OK;
}

AQS_API aqs_status aqs_body_set_force(aqs_linkage *L, int32_t body, const double force[3],
                                      const double point[3], const double torque[3])
{
    static const char fn[] = "aqs_body_set_force";
    static const double zero[3] = {0, 0, 0};
    aqs_status st;
    body_load *ld;
    CHECK_LINKAGE(L);
    if ((st = check_body(L, fn, body)) != AQS_OK) return st;
    if ((st = check_vec(L, fn, "force", force, 3)) != AQS_OK) return st;
    if (point && (st = check_vec(L, fn, "point", point, 3)) != AQS_OK) return st;
    if (torque && (st = check_vec(L, fn, "torque", torque, 3)) != AQS_OK) return st;
    ld = &L->loads[body];
    memcpy(ld->force, force, sizeof ld->force);
    memcpy(ld->point, point ? point : zero, sizeof ld->point);
    memcpy(ld->torque, torque ? torque : zero, sizeof ld->torque);
    if (L->load_slot[body] < 0) {
        L->load_slot[body] = L->nloaded;
        L->loaded_bodies[L->nloaded++] = body;
    }
    stale_loads(L);
    return AQS_OK;
}

static void remove_load(aqs_linkage *L, int32_t body)
{
    int32_t slot = L->load_slot[body], last;
    if (slot < 0) return;
    last = L->loaded_bodies[--L->nloaded];
    L->loaded_bodies[slot] = last;
    L->load_slot[last] = slot;
    L->load_slot[body] = -1;
    memset(&L->loads[body], 0, sizeof(body_load));
    stale_loads(L);
}

AQS_API aqs_status aqs_body_clear_force(aqs_linkage *L, int32_t body)
{
    aqs_status st;
    CHECK_LINKAGE(L);
    if ((st = check_body(L, "aqs_body_clear_force", body)) != AQS_OK) return st;
    remove_load(L, body);
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_clear_forces(aqs_linkage *L)
{
    int32_t j, k;
    CHECK_LINKAGE(L);
    /* Body loads: update_loads refreshes the formerly loaded composites. Joint
     * forces: only the nodes of actuated joints are marked (a scan of the nv
     * forces, no O(N) recomputation of the tree). */
    while (L->nloaded > 0) remove_load(L, L->loaded_bodies[L->nloaded - 1]);
    for (j = 0; j < L->njoints; j++) {
        const joint_def *jd = &L->joints[j];
        int nv = joint_nv(jd->type), actuated = 0;
        for (k = 0; k < nv; k++)
            if (L->tau[jd->voff + k] != 0.0) actuated = 1;
        if (!actuated) continue;
        memset(L->tau + jd->voff, 0, sizeof(double) * (size_t)nv);
        stale_joint_force(L, L->finalized ? L->t.node_of_eff[L->m.eff_of_joint[j]] : -1);
    }
    stale_loads(L);
    return AQS_OK;
}

AQS_API aqs_status aqs_joint_set_force(aqs_linkage *L, int32_t joint, const double *tau, int32_t n)
{
    static const char fn[] = "aqs_joint_set_force";
    aqs_status st;
    int nv;
    CHECK_LINKAGE(L);
    if ((st = check_joint(L, fn, joint)) != AQS_OK) return st;
    nv = joint_nv(L->joints[joint].type);
    if (n != nv)
        return lk_fail(L, AQS_ESIZE, "%s: n = %d but joint %d (%s) has %d dofs", fn, (int)n,
                       (int)joint, joint_type_name(L->joints[joint].type), nv);
    if (nv == 0) return AQS_OK;
    if ((st = check_vec(L, fn, "tau", tau, nv)) != AQS_OK) return st;
    memcpy(L->tau + L->joints[joint].voff, tau, sizeof(double) * (size_t)nv);
    stale_joint_force(L, L->finalized ? L->t.node_of_eff[L->m.eff_of_joint[joint]] : -1);
    return AQS_OK;
}

/* ---------------------------------------------------------------- solving */

static aqs_status check_joint_outputs(aqs_linkage *L, const char *fn, int32_t j)
{
    const joint_def *jd = &L->joints[j];
    int bad;
    if (!finite_n(L->qdd + jd->voff, joint_nv(jd->type), &bad))
        return lk_fail(L, AQS_ENUMERIC, "%s: the acceleration of joint %d came out non-finite", fn, (int)j);
    if (!finite_n(L->cforce + 6 * j, 6, &bad))
        return lk_fail(L, AQS_ENUMERIC, "%s: the constraint force of joint %d came out non-finite", fn, (int)j);
    return AQS_OK;
}

/* Whether x[0..n) are all finite: x * 0 is 0 for finite x, NaN otherwise. */
static int all_finite(const double *x, size_t n)
{
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    size_t i;
    for (i = 0; i + 4 <= n; i += 4) {
        s0 += x[i] * 0.0;
        s1 += x[i + 1] * 0.0;
        s2 += x[i + 2] * 0.0;
        s3 += x[i + 3] * 0.0;
    }
    for (; i < n; i++) s0 += x[i] * 0.0;
    return s0 + s1 + s2 + s3 == 0.0;
}

/* Whether a joint's nv accelerations and 6 constraint-force entries are all
 * finite (x * 0 is 0 for finite x, NaN otherwise), in one pass. */
static int joint_outputs_finite(const double *qdd, int nv, const double *f)
{
    double s = f[0] * 0.0 + f[1] * 0.0 + f[2] * 0.0 + f[3] * 0.0 + f[4] * 0.0 + f[5] * 0.0;
    int k;
    for (k = 0; k < nv; k++) s += qdd[k] * 0.0;
    return s == 0.0;
}

/* Non-finite numbers are never returned silently: check what was computed. */
static aqs_status check_outputs(aqs_linkage *L, const char *fn)
{
    const solve_state *s = &L->s;
    aqs_status st = AQS_OK;
    int32_t i;
    if (s->all) {
        /* one pass over both arrays; the joint loop names the first bad one */
        if (all_finite(L->qdd, (size_t)L->nv) && all_finite(L->cforce, 6 * (size_t)L->njoints)) return AQS_OK;
        for (i = 0; i < L->njoints && st == AQS_OK; i++) st = check_joint_outputs(L, fn, i);
    } else {
        /* An adaptive solve orders the joints by A (MATH.md §6): overflowed
         * values make the order and the bound meaningless (an infinite relative
         * bound over zero accelerations is a true statement, a NaN is not). */
        if (isnan(s->bound) || !isfinite(s->sum) || !isfinite(s->a_root))
            return lk_fail(L, AQS_ENUMERIC,
                           "%s: the error bound came out non-finite (bound = %g, queued sum = %g): "
                           "the loads are too large for double precision", fn, s->bound, s->sum);
        for (i = 0; i < s->nprocessed && st == AQS_OK; i++) {
            const int32_t j = L->m.eff_joint[L->t.nodes[s->processed[i]].joint];
            const joint_def *jd = &L->joints[j];
            /* the joint loop's check (and message) only where one is not finite */
            if (!joint_outputs_finite(L->qdd + jd->voff, joint_nv(jd->type), L->cforce + 6 * j))
                st = check_joint_outputs(L, fn, j);
        }
    }
    return st;
}

/* An exact solve goes through the articulated-body algorithm unless the
 * DCA was chosen; a linkage that cannot move keeps the adaptive path. */
static int exact_by_aba(const aqs_linkage *L)
{
    return L->exact_solver == AQS_EXACT_ABA && L->s.eps == 0.0 && L->s.max_computed == 0 && L->t.nnodes > 0;
}

/* The exact fallback applies to adaptive solves (eps > 0, no cap). */
static int fallback_applies(const aqs_linkage *L)
{
    return L->fallback > 0.0 && L->s.eps > 0.0 && L->s.max_computed == 0 && L->t.nnodes > 0;
}

/* The rounding fallback applies to adaptive solves (eps > 0, no cap) in the
 * square-root form, the one whose rounding is estimated, under the joint
 * measures (the world measures' estimate is 1e4 .. 2e7 times the truth:
 * too loose to decide by). */
static int rounding_fallback_applies(const aqs_linkage *L)
{
    return L->rfb_level > 0.0 && L->s.eps > 0.0 && L->s.max_computed == 0 && L->t.nnodes > 0 &&
           L->dca_form == AQS_DCA_FORM_SQRT && L->s.metric < AQS_METRIC_ABS_WORLD;
}

/* After an adaptive solve that skipped joints: its estimated rounding,
 * relative to the solution's size in the measure, is above the level, or
 * cannot be estimated (docs/math.md §10a, "The rounding fallback"). */
static int rounding_fallback_due(const aqs_linkage *L)
{
    return rounding_fallback_applies(L) && !L->s.all && !(L->s.rounding_rel <= L->rfb_level);
}

/* The exact solve by the articulated-body algorithm, answered by the exact
 * DCA (every joint through the DCA's back-substitution, then refined,
 * whatever the tolerance) where the articulated-body solve cannot give the
 * digits: its refinement stopped short of the rounding level (no
 * contraction, or max_corrections used up: its factors lost them, as on
 * planar, universal and spherical joints between bodies 1e9 apart, up to
 * 4.1 relative off, where the DCA is 2.2e-16 .. 5.6e-9), or on a
 * linkage with a heavy child its backward pass found an articulated inertia
 * numerically singular (docs/math.md 5b, "Where the articulated-body solve
 * cannot refine"). The DCA's storage is allocated at the first such solve;
 * after a hand-over the next AQS_HANDOVER_RUN exact solves go to the DCA
 * directly (the attempt cost 0.86x the DCA's solve on a 2,000-link chain),
 * then the articulated-body solve is tried again. *path says which solver
 * answered. */
static aqs_status exact_solve(aqs_linkage *L, const char *fn, int32_t *path)
{
    solve_state *s = &L->s;
    char saved[sizeof L->error];
    aqs_status st = AQS_OK;
    const int skip = L->aba_skip > 0 && L->refine_max > 0;
    memcpy(saved, L->error, sizeof saved);
    L->ap.work = 0.0; /* the work meter (cost.h): this solve's count, for the automatic path */
    if (skip) {
        L->aba_skip--;
    } else {
        st = aba_solve(L);
        *path = AQS_PATH_EXACT_ABA;
        if (!(st == AQS_OK && L->aba.lost) && !(st == AQS_ENUMERIC && L->m.heavy_ratio > AQS_HEAVY_CHILD_ABA)) {
            if (st == AQS_OK) L->ap.exact = L->ap.work;
            return st;
        }
        L->aba_skip = AQS_HANDOVER_RUN;
    }
    {
        const double eps = s->eps;
        const int32_t cap = s->max_computed;
        memcpy(L->error, saved, sizeof saved); /* the ABA's failure is not the call's */
        if ((st = dca_enable(L, fn)) != AQS_OK) return st;
        cost_count(L, autopath_update_cost(L));
        if ((st = update_coefficients(L)) != AQS_OK) return st;
        s->eps = 0.0;
        s->max_computed = 0;
        adaptive_solve(L);
        cost_count(L, COST_PROCESS * (double)s->nprocessed);
        L->handover = 1; /* no polish by the factors that lost the digits */
        refine_exact(L);
        L->handover = 0;
        s->eps = eps;
        s->max_computed = cap;
        *path = AQS_PATH_EXACT_DCA;
        L->ap.exact = L->ap.work;
    }
    return AQS_OK;
}

static aqs_status solve_body(aqs_linkage *L, const char *fn, int stepping)
{
    aqs_status st;
    int fb = fallback_applies(L) && L->fb_left > 0, chose = 0, auto_exact = 0, by_aba;
    int rfb = !fb && rounding_fallback_applies(L) && L->rfb_left > 0;
    int32_t path;
    L->exact_by_aba = 0;
    L->fb_last = 0;
    L->rfb_last = 0;
    L->rfb_processed = 0;
    L->s.refined = 0;
    fb = fb || rfb;
    if (!fb && autopath_applies(L)) {
        /* the stale marks of the loads first: the model counts them (on a
         * moved tree only the marks: the chosen path re-expresses the loads) */
        if (L->t.poses_stale) update_mark_loads(L);
        else update_loads(L);
        chose = 1;
        auto_exact = autopath_decide(L, stepping);
    }
    by_aba = exact_by_aba(L) || fb || auto_exact;
    /* the predicted set is for an adaptive solve by the heap only */
    if (by_aba || !adaptive_predict_usable(L)) adaptive_predict_clear(L);
    if (by_aba) {
        if ((st = exact_solve(L, fn, &path)) != AQS_OK) {
            stale_solve_failed(L);
            return st;
        }
        L->exact_by_aba = path == AQS_PATH_EXACT_ABA;
    } else {
        /* allocated already by finalize or by the setters that lead here */
        if ((st = dca_enable(L, fn)) != AQS_OK) return st;
        if ((st = update_coefficients(L)) != AQS_OK) {
            stale_solve_failed(L); /* the results would be the previous solve's */
            return st;
        }
        adaptive_solve(L);
        path = L->s.eps == 0.0 && L->s.max_computed == 0 ? AQS_PATH_EXACT_DCA : AQS_PATH_ADAPTIVE;
        /* every joint through the DCA's back-substitution (the exact path, or
         * an adaptive solve that computed them all): refined to the
         * articulated-body solve's accuracy (docs/math.md §13a) */
        if (path == AQS_PATH_EXACT_DCA || L->s.nprocessed == L->m.ne) refine_exact(L);
        else if (rounding_fallback_due(L)) {
            /* its computed joints and its bound carry more rounding than the
             * level allows: this solve and the next AQS_FALLBACK_RUN are exact
             * (docs/math.md §10a, "The rounding fallback") */
            const int32_t updated = L->t.nodes_updated, factors = L->t.factors_updated;
            adaptive_predict_clear(L);
            L->rfb_processed = L->s.nprocessed;
            if ((st = exact_solve(L, fn, &path)) != AQS_OK) {
                stale_solve_failed(L);
                return st;
            }
            /* the stats count the adaptive solve's work too (aba_solve zeroed them) */
            L->t.nodes_updated += updated;
            L->t.factors_updated += factors;
            L->exact_by_aba = path == AQS_PATH_EXACT_ABA;
            L->rfb_last = 1;
            L->rfb_left = AQS_FALLBACK_RUN + 1; /* this one is counted below */
            rfb = 1;
        }
    }
    if ((st = check_outputs(L, fn)) != AQS_OK) {
        stale_solve_failed(L);
        return st;
    }
    stale_solve_done(L);
    autopath_after_solve(L, path, chose);
    if (auto_exact) {
        /* the model's exact solve is not a fallback step */
    } else if (rfb) {
        L->rfb_left--;
        L->rfb_last = 1;
    } else if (fb) {
        L->fb_left--;
        L->fb_last = 1;
    } else if (fallback_applies(L) && !L->s.all && (double)L->s.computed > L->fallback * (double)L->s.counted) {
        L->fb_left = AQS_FALLBACK_RUN;
    }
    return AQS_OK;
}

/* A solve with subnormal results flushed to zero (src/base/fpenv.h). */
static aqs_status solve(aqs_linkage *L, const char *fn, int stepping)
{
    fpenv e;
    aqs_status st;
    fpenv_enter(&e, 1);
    st = solve_body(L, fn, stepping);
    fpenv_leave(&e);
    return lk_fail_in(L, st, fn); /* the solvers' messages name no function */
}

AQS_API aqs_status aqs_linkage_solve(aqs_linkage *L)
{
    static const char fn[] = "aqs_linkage_solve";
    aqs_status st;
    CHECK_LINKAGE(L);
    if ((st = check_finalized(L, fn)) != AQS_OK) return st;
    return solve(L, fn, 0);
}

/* Save (or restore) the positions a step moves: all of them after an exact
 * solve, the computed joints' after an adaptive one. */
static void copy_moved_positions(aqs_linkage *L, double *dst, const double *src)
{
    const solve_state *s = &L->s;
    int32_t i;
    if (s->all) {
        if (L->nq) memcpy(dst, src, sizeof(double) * (size_t)L->nq);
        return;
    }
    for (i = 0; i < s->nprocessed; i++) {
        const joint_def *jd = &L->joints[L->m.eff_joint[L->t.nodes[s->processed[i]].joint]];
        memcpy(dst + jd->qoff, src + jd->qoff, sizeof(double) * (size_t)joint_nq(jd->type));
    }
}

/* The positions a step moved are finite: O(N_E) after an adaptive solve. */
static aqs_status check_moved_positions(aqs_linkage *L, const char *fn)
{
    const solve_state *s = &L->s;
    int32_t i, k, n = s->all ? L->njoints : s->nprocessed;
    for (i = 0; i < n; i++) {
        int32_t j = s->all ? i : L->m.eff_joint[L->t.nodes[s->processed[i]].joint];
        const joint_def *jd = &L->joints[j];
        const int nq = joint_nq(jd->type);
        for (k = 0; k < nq; k++)
            if (!isfinite(L->q[jd->qoff + k]))
                return lk_fail(L, AQS_ENUMERIC, "%s: the position of joint %d became non-finite", fn, (int)j);
    }
    return AQS_OK;
}

static aqs_status step_body(aqs_linkage *L, double dt)
{
    static const char fn[] = "aqs_linkage_step";
    aqs_status st;
    int32_t before, before_f;
    CHECK_LINKAGE(L);
    if ((st = check_finalized(L, fn)) != AQS_OK) return st;
    if (!isfinite(dt) || !(dt > 0.0))
        return lk_fail(L, AQS_EINVAL, "%s: dt = %g must be finite and > 0", fn, dt);
    if ((st = solve(L, fn, 1)) != AQS_OK) return st;
    before = L->t.nodes_updated; /* what the solve's update recomputed (loads changed since) */
    before_f = L->t.factors_updated;
    copy_moved_positions(L, L->q_saved, L->q);
    adaptive_integrate(L, dt * dt);
    if (L->exact_by_aba) autopath_tree_moved(L, 1); /* the switch back pays for it */
    st = check_moved_positions(L, fn);
    /* After an exact solve by the articulated-body algorithm the tree's
     * coefficients are left stale (every node is marked): the next
     * articulated-body solve does not need them, an adaptive one recomputes
     * them first. */
    /* So is the update after an adaptive step's move when the automatic
     * path will take the exact one next: the nodes stay marked, and an
     * adaptive solve recomputes them first (the model counts them). */
    if (st == AQS_OK && !L->exact_by_aba && !autopath_prefers_exact(L, 1)) st = update_coefficients(L);
    else if (st == AQS_OK) L->t.nodes_updated = L->t.factors_updated = 0;
    if (st == AQS_OK) {
        L->t.nodes_updated += before;
        L->t.factors_updated += before_f;
    }
    if (st != AQS_OK) {
        /* Undo: back to the positions before the step, which solved fine. */
        char msg[sizeof L->error];
        memcpy(msg, L->error, sizeof msg);
        copy_moved_positions(L, L->q, L->q_saved);
        frames_positions_moved(L);
        if (!L->exact_by_aba) (void)update_coefficients(L);
        memcpy(L->error, msg, sizeof msg);
    }
    return lk_fail_in(L, st, fn);
}

AQS_API aqs_status aqs_linkage_step(aqs_linkage *L, double dt)
{
    fpenv e;
    aqs_status st;
    fpenv_enter(&e, 1);
    st = step_body(L, dt);
    fpenv_leave(&e);
    return st;
}

AQS_API aqs_status aqs_linkage_set_tolerance(aqs_linkage *L, int32_t metric, double eps)
{
    static const char fn[] = "aqs_linkage_set_tolerance";
    aqs_status st;
    int new_world = 0;
    CHECK_LINKAGE(L);
    if ((st = check_finalized(L, fn)) != AQS_OK) return st;
    if (metric < AQS_METRIC_ABS_LINKAGE || metric > AQS_METRIC_REL_WORLD)
        return lk_fail(L, AQS_EINVAL, "%s: metric = %d is not an AQS_METRIC_* value", fn, (int)metric);
    if (!isfinite(eps) || eps < 0.0)
        return lk_fail(L, AQS_EINVAL, "%s: eps = %g must be finite and >= 0", fn, eps);
    if (metric >= AQS_METRIC_ABS_WORLD && !L->wb && L->t.nnodes > 0) {
        /* the bodies' spheres: computed for every node by the next update
         * (marked below, once nothing can fail any more) */
        if ((st = worldbound_enable(L, fn)) != AQS_OK) return st;
        new_world = 1;
    }
    if (eps > 0.0 && !L->t.tdata && L->t.nnodes > 0) {
        if ((st = totalacc_enable(L, fn)) != AQS_OK) {
            if (new_world) worldbound_free(L); /* nothing changed */
            return st;
        }
        stale_tree(L);
    }
    if (new_world) stale_tree(L);
    L->s.metric = metric;
    L->s.eps = eps;
    stale_settings(L);
    L->fb_left = L->rfb_left = 0;
    autopath_reset(L);
    adaptive_predict_clear(L); /* made for the former measure */
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_set_max_computed(aqs_linkage *L, int32_t max_joints)
{
    static const char fn[] = "aqs_linkage_set_max_computed";
    aqs_status st;
    CHECK_LINKAGE(L);
    if ((st = check_finalized(L, fn)) != AQS_OK) return st;
    if (max_joints < 0)
        return lk_fail(L, AQS_EINVAL, "%s: max_joints = %d must be >= 0", fn, (int)max_joints);
    if (max_joints > 0 && !L->t.tdata && L->t.nnodes > 0) {
        if ((st = totalacc_enable(L, fn)) != AQS_OK) return st;
        stale_tree(L);
    }
    L->s.max_computed = max_joints;
    L->fb_left = L->rfb_left = 0;
    autopath_reset(L);
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_set_exact_fallback(aqs_linkage *L, double fraction)
{
    static const char fn[] = "aqs_linkage_set_exact_fallback";
    CHECK_LINKAGE(L);
    if (!isfinite(fraction) || fraction < 0.0 || fraction > 1.0)
        return lk_fail(L, AQS_EINVAL, "%s: fraction = %g must be finite and in [0, 1]", fn, fraction);
    L->fallback = fraction;
    L->fb_left = 0;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_get_exact_fallback(const aqs_linkage *cL, double *fraction)
{
    static const char fn[] = "aqs_linkage_get_exact_fallback";
    aqs_linkage *L = (aqs_linkage *)cL;
    CHECK_LINKAGE(L);
    CHECK_PTR(L, fn, fraction);
    *fraction = L->fallback;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_set_rounding_fallback(aqs_linkage *L, double level)
{
    static const char fn[] = "aqs_linkage_set_rounding_fallback";
    CHECK_LINKAGE(L);
    if (!isfinite(level) || level < 0.0)
        return lk_fail(L, AQS_EINVAL, "%s: level = %g must be finite and >= 0", fn, level);
    L->rfb_level = level;
    L->rfb_left = 0;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_get_rounding_fallback(const aqs_linkage *cL, double *level)
{
    static const char fn[] = "aqs_linkage_get_rounding_fallback";
    aqs_linkage *L = (aqs_linkage *)cL;
    CHECK_LINKAGE(L);
    CHECK_PTR(L, fn, level);
    *level = L->rfb_level;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_set_adaptive_refinement(aqs_linkage *L, double level)
{
    static const char fn[] = "aqs_linkage_set_adaptive_refinement";
    CHECK_LINKAGE(L);
    if (!isfinite(level) || level < 0.0)
        return lk_fail(L, AQS_EINVAL, "%s: level = %g must be finite and >= 0", fn, level);
    L->arf_level = level;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_get_adaptive_refinement(const aqs_linkage *cL, double *level)
{
    static const char fn[] = "aqs_linkage_get_adaptive_refinement";
    aqs_linkage *L = (aqs_linkage *)cL;
    CHECK_LINKAGE(L);
    CHECK_PTR(L, fn, level);
    *level = L->arf_level;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_set_prediction(aqs_linkage *L, double margin)
{
    static const char fn[] = "aqs_linkage_set_prediction";
    aqs_status st;
    CHECK_LINKAGE(L);
    if ((st = check_finalized(L, fn)) != AQS_OK) return st;
    if (!isfinite(margin) || (margin != 0.0 && margin < 1.0))
        return lk_fail(L, AQS_EINVAL, "%s: margin = %g must be 0 (off) or a finite number >= 1", fn,
                       margin);
    L->s.margin = margin;
    adaptive_predict_clear(L);
    autopath_reset(L);
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_get_prediction(const aqs_linkage *cL, double *margin)
{
    static const char fn[] = "aqs_linkage_get_prediction";
    aqs_linkage *L = (aqs_linkage *)cL;
    aqs_status st;
    CHECK_LINKAGE(L);
    if ((st = check_finalized(L, fn)) != AQS_OK) return st;
    CHECK_PTR(L, fn, margin);
    *margin = L->s.margin;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_set_auto(aqs_linkage *L, int32_t enabled)
{
    static const char fn[] = "aqs_linkage_set_auto";
    CHECK_LINKAGE(L);
    if (enabled != 0 && enabled != 1)
        return lk_fail(L, AQS_EINVAL, "%s: enabled = %d must be 0 or 1", fn, (int)enabled);
    L->ap.on = enabled;
    autopath_reset(L);
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_get_auto(const aqs_linkage *cL, int32_t *enabled)
{
    static const char fn[] = "aqs_linkage_get_auto";
    aqs_linkage *L = (aqs_linkage *)cL;
    CHECK_LINKAGE(L);
    CHECK_PTR(L, fn, enabled);
    *enabled = L->ap.on;
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_set_joint_bound(aqs_linkage *L, int32_t kind)
{
    static const char fn[] = "aqs_linkage_set_joint_bound";
    aqs_status st;
    CHECK_LINKAGE(L);
    if ((st = check_finalized(L, fn)) != AQS_OK) return st;
    if (kind != AQS_JOINT_BOUND_HEAP_TOP && kind != AQS_JOINT_BOUND_SUM)
        return lk_fail(L, AQS_EINVAL, "%s: kind = %d is not an AQS_JOINT_BOUND_* value", fn, (int)kind);
    L->s.joint_bound = kind;
    stale_settings(L);
    adaptive_predict_clear(L);
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_refine(aqs_linkage *L, double eps)
{
    static const char fn[] = "aqs_linkage_refine";
    aqs_status st;
    CHECK_LINKAGE(L);
    if ((st = need_solved(L, fn)) != AQS_OK) return st;
    if (!isfinite(eps) || eps < 0.0)
        return lk_fail(L, AQS_EINVAL, "%s: eps = %g must be finite and >= 0", fn, eps);
    if (!L->s.valid)
        return lk_fail(L, AQS_ESTATE,
                       "%s: positions, loads or the tolerance changed since the last solve; solve again", fn);
    if (L->s.all || eps >= L->s.bound) return AQS_OK;
    {
        fpenv e;
        fpenv_enter(&e, 1); /* as a solve (src/base/fpenv.h) */
        adaptive_refine(L, eps);
        fpenv_leave(&e);
    }
    L->s.eps = eps;
    if ((st = check_outputs(L, fn)) != AQS_OK) stale_solve_failed(L);
    return st;
}

AQS_API aqs_status aqs_linkage_get_stats(const aqs_linkage *cL, aqs_solve_stats *stats)
{
    static const char fn[] = "aqs_linkage_get_stats";
    aqs_linkage *L = (aqs_linkage *)cL;
    aqs_solve_stats full;
    aqs_status st;
    uint32_t size;
    CHECK_LINKAGE(L);
    if ((st = check_stats_size(L, fn, stats, &size)) != AQS_OK) return st;
    if ((st = need_solved(L, fn)) != AQS_OK) return st;
    memset(&full, 0, sizeof full);
    full.size = size;
    full.metric = L->s.metric;
    full.eps = L->s.eps;
    full.error_bound = L->s.all ? 0.0 : L->s.bound;
    full.computed_joints = L->s.all ? L->s.counted : L->s.computed;
    full.counted_joints = L->s.counted;
    full.nodes_updated = L->t.nodes_updated;
    full.nodes_processed = L->s.nprocessed + L->rfb_processed; /* the fallback's adaptive solve's */
    full.capped = L->s.capped;
    full.fallback = L->fb_last;
    full.nodes_predicted = L->s.all ? 0 : L->s.npredicted;
    full.factors_updated = L->t.factors_updated;
    full.path = L->ap.path;
    full.auto_chosen = L->ap.chose;
    full.cost_adaptive = L->ap.cost_adaptive;
    full.cost_exact = L->ap.cost_exact;
    full.rounding_bound = L->s.rounding;
    full.certified = L->s.certified;
    full.rounding_fallback = L->rfb_last;
    memcpy(stats, &full, size < sizeof full ? size : sizeof full);
    return AQS_OK;
}

AQS_API aqs_status aqs_joint_get_computed(const aqs_linkage *cL, int32_t joint, int32_t *computed)
{
    static const char fn[] = "aqs_joint_get_computed";
    aqs_linkage *L = (aqs_linkage *)cL;
    aqs_status st;
    CHECK_LINKAGE(L);
    if ((st = check_joint(L, fn, joint)) != AQS_OK) return st;
    if ((st = need_solved(L, fn)) != AQS_OK) return st;
    CHECK_PTR(L, fn, computed);
    *computed = !isnan(L->cforce[6 * (size_t)joint]);
    return AQS_OK;
}

/* ---------------------------------------------------------------- reading */

AQS_API aqs_status aqs_linkage_get_positions(const aqs_linkage *cL, double *q, size_t n)
{
    static const char fn[] = "aqs_linkage_get_positions";
    aqs_linkage *L = (aqs_linkage *)cL;
    CHECK_LINKAGE(L);
    if (L->nq == 0) return AQS_OK; /* nothing to read: q may be NULL */
    CHECK_PTR(L, fn, q);
    if (n < (size_t)L->nq)
        return lk_fail(L, AQS_ESIZE, "%s: n = %zu but the linkage has nq = %d", fn, n, (int)L->nq);
    memcpy(q, L->q, sizeof(double) * (size_t)L->nq);
    return AQS_OK;
}

/* Validate the position values of joint j (nq of them) into out. */
static aqs_status check_joint_position(aqs_linkage *L, const char *fn, int32_t j, const double *q,
                                       double *out)
{
    int r = joint_check_position(L->joints[j].type, q, out);
    if (r > 0)
        return lk_fail(L, AQS_EINVAL, "%s: position value %d of joint %d is %g, not finite", fn,
                       r - 1, (int)j, q[r - 1]);
    if (r < 0) { /* the message of every unit-quaternion check */
        char name[48];
        double norm;
        snprintf(name, sizeof name, "the quaternion of joint %d", (int)j);
        return check_unit_quat(L, fn, name, q + (L->joints[j].type == AQS_JOINT_FREE ? 3 : 0), &norm);
    }
    return AQS_OK;
}

static void positions_changed(aqs_linkage *L, int32_t joint)
{
    if (!L->finalized) return;
    if (joint < 0) {
        frames_positions_moved(L);
        autopath_tree_moved(L, 0); /* the caller's: an adaptive solve pays it too */
    } else if (L->m.eff_of_joint[joint] >= 0) {
        int32_t e = L->m.eff_of_joint[joint];
        frames_from_joint(L, e);
        stale_positions(L, L->t.node_of_eff[e]);
    } else {
        stale_loads(L); /* a fixed joint moves nothing; as for any position change */
    }
}

AQS_API aqs_status aqs_linkage_set_positions(aqs_linkage *L, const double *q, size_t n)
{
    static const char fn[] = "aqs_linkage_set_positions";
    aqs_status st;
    int32_t j;
    double tmp[8];
    CHECK_LINKAGE(L);
    if (n != (size_t)L->nq)
        return lk_fail(L, AQS_ESIZE, "%s: n = %zu but the linkage has nq = %d", fn, n, (int)L->nq);
    if (n == 0) return AQS_OK; /* nothing to set: q may be NULL */
    CHECK_PTR(L, fn, q);
    if (L->finalized && L->m.nquat == 0) {
        /* Scalar coordinates only: one pass over the values; the joint loop
         * below finds the joint of a bad value for the message. */
        int ok = 1;
        size_t i;
        for (i = 0; i < n; i++) ok &= isfinite(q[i]) != 0;
        if (ok) {
            memcpy(L->q, q, sizeof(double) * n);
            positions_changed(L, -1);
            return AQS_OK;
        }
    }
    for (j = 0; j < L->njoints; j++)
        if ((st = check_joint_position(L, fn, j, q + L->joints[j].qoff, tmp)) != AQS_OK) return st;
    for (j = 0; j < L->njoints; j++)
        check_joint_position(L, fn, j, q + L->joints[j].qoff, L->q + L->joints[j].qoff);
    positions_changed(L, -1);
    return AQS_OK;
}

AQS_API aqs_status aqs_joint_get_position(const aqs_linkage *cL, int32_t joint, double *q, int32_t n)
{
    static const char fn[] = "aqs_joint_get_position";
    aqs_linkage *L = (aqs_linkage *)cL;
    aqs_status st;
    int nq;
    CHECK_LINKAGE(L);
    if ((st = check_joint(L, fn, joint)) != AQS_OK) return st;
    nq = joint_nq(L->joints[joint].type);
    if (n != nq)
        return lk_fail(L, AQS_ESIZE, "%s: n = %d but joint %d has nq = %d", fn, (int)n, (int)joint, nq);
    if (nq == 0) return AQS_OK;
    CHECK_PTR(L, fn, q);
    memcpy(q, L->q + L->joints[joint].qoff, sizeof(double) * (size_t)nq);
    return AQS_OK;
}

AQS_API aqs_status aqs_joint_set_position(aqs_linkage *L, int32_t joint, const double *q, int32_t n)
{
    static const char fn[] = "aqs_joint_set_position";
    aqs_status st;
    int nq;
    double tmp[8];
    CHECK_LINKAGE(L);
    if ((st = check_joint(L, fn, joint)) != AQS_OK) return st;
    nq = joint_nq(L->joints[joint].type);
    if (n != nq)
        return lk_fail(L, AQS_ESIZE, "%s: n = %d but joint %d has nq = %d", fn, (int)n, (int)joint, nq);
    if (nq == 0) return AQS_OK;
    CHECK_PTR(L, fn, q);
    if ((st = check_joint_position(L, fn, joint, q, tmp)) != AQS_OK) return st;
    memcpy(L->q + L->joints[joint].qoff, tmp, sizeof(double) * (size_t)nq);
    positions_changed(L, joint);
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_get_accelerations(const aqs_linkage *cL, double *qdd, size_t n)
{
    static const char fn[] = "aqs_linkage_get_accelerations";
    aqs_linkage *L = (aqs_linkage *)cL;
    aqs_status st;
    CHECK_LINKAGE(L);
    if ((st = need_solved(L, fn)) != AQS_OK) return st;
    if (L->nv == 0) return AQS_OK; /* nothing to read: qdd may be NULL */
    CHECK_PTR(L, fn, qdd);
    if (n < (size_t)L->nv)
        return lk_fail(L, AQS_ESIZE, "%s: n = %zu but the linkage has nv = %d", fn, n, (int)L->nv);
    memcpy(qdd, L->qdd, sizeof(double) * (size_t)L->nv);
    return AQS_OK;
}

AQS_API aqs_status aqs_joint_get_acceleration(const aqs_linkage *cL, int32_t joint, double *qdd,
                                              int32_t n)
{
    static const char fn[] = "aqs_joint_get_acceleration";
    aqs_linkage *L = (aqs_linkage *)cL;
    aqs_status st;
    int nv;
    CHECK_LINKAGE(L);
    if ((st = check_joint(L, fn, joint)) != AQS_OK) return st;
    if ((st = need_solved(L, fn)) != AQS_OK) return st;
    nv = joint_nv(L->joints[joint].type);
    if (n != nv)
        return lk_fail(L, AQS_ESIZE, "%s: n = %d but joint %d has nv = %d", fn, (int)n, (int)joint, nv);
    if (nv == 0) return AQS_OK;
    CHECK_PTR(L, fn, qdd);
    memcpy(qdd, L->qdd + L->joints[joint].voff, sizeof(double) * (size_t)nv);
    return AQS_OK;
}

/* Joint j's constraint force as the user reads it: in its child body's frame.
 * The solvers keep it in the child composite's aligned frame (joint.h,
 * docs/math.md §13b), turned by C from the body's: out = C f, both halves. */
static void constraint_force_out(const aqs_linkage *L, int32_t j, double out[6])
{
    const double *f = L->cforce + 6 * (size_t)j;
    double C[9];
    if (!joint_align_rotation(&L->joints[j], C)) {
        memcpy(out, f, 6 * sizeof(double));
        return;
    }
    mat3_vec(C, f, out);
    mat3_vec(C, f + 3, out + 3);
}

AQS_API aqs_status aqs_linkage_get_constraint_forces(const aqs_linkage *cL, double *f, size_t n)
{
    static const char fn[] = "aqs_linkage_get_constraint_forces";
    aqs_linkage *L = (aqs_linkage *)cL;
    aqs_status st;
    int32_t j;
    CHECK_LINKAGE(L);
    if ((st = need_solved(L, fn)) != AQS_OK) return st;
    CHECK_PTR(L, fn, f);
    if (n < 6 * (size_t)L->njoints)
        return lk_fail(L, AQS_ESIZE, "%s: n = %zu but 6 * joints = %d", fn, n, 6 * (int)L->njoints);
    for (j = 0; j < L->njoints; j++) constraint_force_out(L, j, f + 6 * (size_t)j);
    return AQS_OK;
}

AQS_API aqs_status aqs_joint_get_constraint_force(const aqs_linkage *cL, int32_t joint, double f[6])
{
    static const char fn[] = "aqs_joint_get_constraint_force";
    aqs_linkage *L = (aqs_linkage *)cL;
    aqs_status st;
    CHECK_LINKAGE(L);
    if ((st = check_joint(L, fn, joint)) != AQS_OK) return st;
    if ((st = need_solved(L, fn)) != AQS_OK) return st;
    CHECK_PTR(L, fn, f);
    constraint_force_out(L, joint, f);
    return AQS_OK;
}

static void write_pose(const pose *P, double pos[3], double quat[4])
{
    memcpy(pos, P->p, 3 * sizeof(double));
    rot_to_quat(P->R, quat);
}

AQS_API aqs_status aqs_body_get_pose_world(const aqs_linkage *cL, int32_t body, double pos[3],
                                           double quat[4])
{
    static const char fn[] = "aqs_body_get_pose_world";
    aqs_linkage *L = (aqs_linkage *)cL;
    aqs_status st;
    pose P;
    CHECK_LINKAGE(L);
    if ((st = check_body(L, fn, body)) != AQS_OK) return st;
    if ((st = check_finalized(L, fn)) != AQS_OK) return st;
    CHECK_PTR(L, fn, pos);
    CHECK_PTR(L, fn, quat);
    frames_body_world(L, body, &P);
    write_pose(&P, pos, quat);
    return AQS_OK;
}

AQS_API aqs_status aqs_linkage_get_body_poses_world(const aqs_linkage *cL, double *poses, size_t n)
{
    static const char fn[] = "aqs_linkage_get_body_poses_world";
    aqs_linkage *L = (aqs_linkage *)cL;
    aqs_status st;
    int32_t b;
    CHECK_LINKAGE(L);
    if ((st = check_finalized(L, fn)) != AQS_OK) return st;
    CHECK_PTR(L, fn, poses);
    if (n < 7 * (size_t)L->nbodies)
        return lk_fail(L, AQS_ESIZE, "%s: n = %zu but 7 * bodies = %d", fn, n, 7 * (int)L->nbodies);
    kin_world_poses(L); /* the composites', in the exact solver's scratch */
    for (b = 0; b < L->nbodies; b++) {
        pose P;
        kin_body_world(L, b, &P);
        write_pose(&P, poses + 7 * b, poses + 7 * b + 3);
    }
    return AQS_OK;
}
