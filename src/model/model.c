/* model.c -- bodies and joints as the user gave them, their validation, and
 * the welding of fixed joints into rigid groups ("composites"). */
#include "model.h"

#include "kintree.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "dense.h"

#define AQS_PI 3.14159265358979323846

/* Eigenvalues of a symmetric 3x3 matrix, ascending (trigonometric method). */
static void sym3_eigenvalues(const double A[9], double ev[3])
{
    double p1 = A[1] * A[1] + A[2] * A[2] + A[5] * A[5];
    double q = (A[0] + A[4] + A[8]) / 3.0, p2, p, B[9], r, phi, t;
    int i;
    if (p1 == 0.0) {
        ev[0] = A[0];
        ev[1] = A[4];
        ev[2] = A[8];
    } else {
        p2 = (A[0] - q) * (A[0] - q) + (A[4] - q) * (A[4] - q) + (A[8] - q) * (A[8] - q) + 2 * p1;
        p = sqrt(p2 / 6.0);
        for (i = 0; i < 9; i++) B[i] = (A[i] - (i % 4 == 0 ? q : 0.0)) / p;
        r = 0.5 * (B[0] * (B[4] * B[8] - B[5] * B[7]) - B[1] * (B[3] * B[8] - B[5] * B[6]) +
                   B[2] * (B[3] * B[7] - B[4] * B[6]));
        phi = r <= -1 ? AQS_PI / 3.0 : r >= 1 ? 0.0 : acos(r) / 3.0;
        ev[2] = q + 2 * p * cos(phi);
        ev[0] = q + 2 * p * cos(phi + 2.0 * AQS_PI / 3.0);
        ev[1] = 3 * q - ev[0] - ev[2];
    }
    /* sort ascending */
    if (ev[0] > ev[1]) { t = ev[0]; ev[0] = ev[1]; ev[1] = t; }
    if (ev[1] > ev[2]) { t = ev[1]; ev[1] = ev[2]; ev[2] = t; }
    if (ev[0] > ev[1]) { t = ev[0]; ev[0] = ev[1]; ev[1] = t; }
}

aqs_status model_check_body(aqs_linkage *L, const char *fn, double mass, const double com[3],
                            const double inertia[9])
{
    int i, j;
    double scale = 0.0, ev[3], tol;
    if (!isfinite(mass) || mass < 0.0)
        return lk_fail(L, AQS_EINVAL, "%s: mass = %g must be finite and >= 0", fn, mass);
    for (i = 0; i < 3; i++)
        if (!isfinite(com[i]))
            return lk_fail(L, AQS_EINVAL, "%s: com[%d] = %g is not finite", fn, i, com[i]);
    for (i = 0; i < 9; i++) {
        if (!isfinite(inertia[i]))
            return lk_fail(L, AQS_EINVAL, "%s: inertia[%d] = %g is not finite", fn, i, inertia[i]);
        if (fabs(inertia[i]) > scale) scale = fabs(inertia[i]);
    }
    for (i = 0; i < 3; i++)
        for (j = i + 1; j < 3; j++)
            if (fabs(inertia[3 * i + j] - inertia[3 * j + i]) > 1e-9 * scale)
                return lk_fail(L, AQS_EINVAL,
                               "%s: inertia is not symmetric: inertia[%d][%d] = %g but "
                               "inertia[%d][%d] = %g",
                               fn, i, j, inertia[3 * i + j], j, i, inertia[3 * j + i]);
    {
        double S[9];
        memcpy(S, inertia, sizeof S);
        dense_symmetrize(S, 3);
        sym3_eigenvalues(S, ev);
    }
    /* One rule for every mass, 0 included: the inertia must be positive
     * semi-definite (any symmetric one with the lax check). Positive definiteness is what the solvers need, and they
     * need it of each rigid group (bodies welded by fixed joints), so finalize
     * checks it there: a point mass welded to a massive body is fine. */
    tol = 1e-9 * (fabs(ev[0]) + fabs(ev[1]) + fabs(ev[2]));
    if (!L->lax_inertia && ev[0] < -tol)
        return lk_fail(L, AQS_EINVAL,
                       "%s: inertia is not positive semi-definite (smallest principal moment "
                       "%g; mass %g)",
                       fn, ev[0], mass);
    if (!L->lax_inertia && ev[0] + ev[1] < ev[2] - tol)
        return lk_fail(L, AQS_EINVAL,
                       "%s: principal moments %g, %g, %g violate the triangle inequality "
                       "(see aqs_linkage_set_inertia_check)", fn,
                       ev[0], ev[1], ev[2]);
    return AQS_OK;
}

/* Whether the rigid group with spatial inertia I (about its frame's origin O,
 * [I_O, m [c]x; m [c]x^T, m 1]) has a positive definite rotational inertia
 * about its centre of mass: I_c = I_O + m [c]x [c]x, with c = h / m read from
 * the off-diagonal block. Its smallest principal moment must exceed 1e-12 of
 * tr(I_O): the rounding of I_c's computation is ~1e-16 tr(I_O), so a point
 * mass alone (I_c = 0 exactly) can never pass as definite. */
/* acc += (m2, c2, I2): the two-body rule Ic = I1 + I2 + (m1 m2 / m) (|e|^2 - e e^T), e = c2 - c1. */
void model_mass_add(double *acc, double m2, const double c2[3], const double I2[9])
{
    double m1 = acc[0], m = m1 + m2, e[3], f, e2;
    int i, j;
    if (m1 == 0.0) {
        acc[0] = m2;
        memcpy(acc + 1, c2, 3 * sizeof(double));
        memcpy(acc + 4, I2, 9 * sizeof(double));
        return;
    }
    for (i = 0; i < 3; i++) e[i] = c2[i] - acc[1 + i];
    f = m1 * m2 / m;
    e2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) acc[4 + 3 * i + j] += I2[3 * i + j] + f * ((i == j ? e2 : 0.0) - e[i] * e[j]);
    for (i = 0; i < 3; i++) acc[1 + i] = (m1 * acc[1 + i] + m2 * c2[i]) / m;
    acc[0] = m;
    for (i = 0; i < 3; i++) /* exactly symmetric */
        for (j = i + 1; j < 3; j++) acc[4 + 3 * j + i] = acc[4 + 3 * i + j];
}

/* acc += mp given in a frame with pose P in acc's frame. */
void model_mass_add_posed(double *acc, const pose *P, const double *mp)
{
    double c[3], RI[9], I[9];
    int i, j, k;
    mat3_vec(P->R, mp + 1, c);
    for (i = 0; i < 3; i++) c[i] += P->p[i];
    for (i = 0; i < 3; i++) /* R Ic R^T */
        for (j = 0; j < 3; j++) {
            double s = 0.0;
            for (k = 0; k < 3; k++) s += P->R[3 * i + k] * mp[4 + 3 * k + j];
            RI[3 * i + j] = s;
        }
    for (i = 0; i < 3; i++)
        for (j = i; j < 3; j++) {
            double s = 0.0;
            for (k = 0; k < 3; k++) s += RI[3 * i + k] * P->R[3 * j + k];
            I[3 * i + j] = I[3 * j + i] = s;
        }
    model_mass_add(acc, mp[0], c, I);
}

/* The composite's mass properties in its frame (its root body's), from its bodies. */
void model_comp_mass(const aqs_linkage *L, int32_t comp, double *mp)
{
    const model *m = &L->m;
    int32_t k;
    memset(mp, 0, 13 * sizeof(double));
    for (k = m->member_start[comp]; k < m->member_start[comp + 1]; k++) {
        int32_t b = m->members[k];
        const body_def *bd = &L->bodies[b];
        double one[13];
        pose B;
        one[0] = bd->mass;
        memcpy(one + 1, bd->com, 3 * sizeof(double));
        memcpy(one + 4, bd->inertia, 9 * sizeof(double));
        kin_body_in_comp(L, b, &B);
        model_mass_add_posed(mp, &B, one);
    }
}

/* The rigid group's rotational inertia about its centre of mass, summed from
 * its bodies (model_mass_add: positive terms only, so a near point mass's
 * k I keeps its digits), is definite: its smallest eigenvalue above 64 ulps
 * of its trace (a lone body of inertia 1e-16 I passes; two welded point
 * masses have a rotational inertia of rounding size about their line and do
 * not). */
static int rotational_inertia_definite(const double *mp)
{
    double ev[3], trace;
    int r;
    for (r = 0; r < 13; r++)
        if (!isfinite(mp[r])) return 0;
    if (!(mp[0] > 0.0)) return 0;
    sym3_eigenvalues(mp + 4, ev);
    trace = mp[4] + mp[8] + mp[12];
    return isfinite(ev[0]) && ev[0] > 64 * DBL_EPSILON * trace;
}

/* Entries within 4 u of the exact zeros and ones of a joint frame whose z
 * axis is its parent composite's (or its negative) are set to them: R's
 * third row and column, and p's z when it is within 4 u |p|. Turning the
 * frames by C leaves rounding of that size where two axes are parallel; left
 * there it would couple the plane of a planar chain to its O(n^3)
 * out-of-plane inertia at every joint (docs/math.md §13b). */
static void snap_planar(pose *P)
{
    double *R = P->R, *p = P->p;
    const double tol = 4.0 * DBL_EPSILON;
    if (fabs(R[2]) > tol || fabs(R[5]) > tol || fabs(R[6]) > tol || fabs(R[7]) > tol || fabs(fabs(R[8]) - 1.0) > tol)
        return;
    R[2] = R[5] = R[6] = R[7] = 0.0;
    R[8] = R[8] > 0.0 ? 1.0 : -1.0;
    { /* and the plane's 2 x 2 block an exact turn (R[8] = 1) or reflection
       * (R[8] = -1) to the rounding: C's own rounding (C^T C = I + O(u))
       * would otherwise scale the plane by 1 + O(u) at every joint */
        const double c = R[8] > 0.0 ? 0.5 * (R[0] + R[4]) : 0.5 * (R[0] - R[4]);
        const double s = R[8] > 0.0 ? 0.5 * (R[3] - R[1]) : 0.5 * (R[1] + R[3]);
        const double h = sqrt(c * c + s * s);
        R[0] = c / h, R[3] = s / h;
        R[1] = R[8] > 0.0 ? -R[3] : R[3];
        R[4] = R[8] > 0.0 ? R[0] : -R[0];
    }
    if (fabs(p[2]) <= tol * sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2])) p[2] = 0.0;
}

void model_body_inertia(const aqs_linkage *L, int32_t body, double I[36])
{
    const body_def *b = &L->bodies[body];
    spatial_inertia(b->mass, b->com, b->inertia, I);
}

static void comp_inverse(const aqs_linkage *L, int32_t c, double out[36])
{
    const model *m = &L->m;
    double I[36];
    /* from the solver's copy whenever it exists, so that every inverse has
     * the same bits (the copy is kept in the aligned frames) */
    if (L->aba.joint) kin_comp_inertia(L, c, I);
    else memcpy(I, m->comp_inertia + 36 * (size_t)c, sizeof I);
    (void)dense_spd_inverse(I, out, 6); /* checked at finalize */
}

aqs_status model_inverse_alloc(aqs_linkage *L)
{
    model *m = &L->m;
    int32_t c;
    if (m->comp_inverse) return AQS_OK;
    m->comp_inverse = lk_calloc_in(L, LK_MEM_DCA, (size_t)m->ncomp + 1, 36 * sizeof(double));
    if (!m->comp_inverse) return AQS_ENOMEM;
    for (c = 0; c < m->ncomp; c++) comp_inverse(L, c, m->comp_inverse + 36 * (size_t)c);
    return AQS_OK;
}

void model_inverse_apply(const aqs_linkage *L, int32_t c, const double f[6], double a[6])
{
    double Ii[36];
    if (L->m.comp_inverse) {
        dense_matvec(L->m.comp_inverse + 36 * (size_t)c, f, a, 6, 6);
        return;
    }
    comp_inverse(L, c, Ii);
    dense_matvec(Ii, f, a, 6, 6);
}

void model_drop_inertia(aqs_linkage *L)
{
    lk_free(L, L->m.comp_inertia);
    lk_free(L, L->m.eff_place);
    L->m.comp_inertia = NULL;
    L->m.eff_place = NULL;
}

void model_free(aqs_linkage *L)
{
    model *m = &L->m;
    lk_free(L, m->comp_of_body);
    lk_free(L, m->body_in_comp);
    lk_free(L, m->comp_root);
    lk_free(L, m->comp_inertia);
    lk_free(L, m->comp_inverse);
    lk_free(L, m->comp_force);
    lk_free(L, m->comp_loaded);
    lk_free(L, m->loaded_comps);
    lk_free(L, m->eff_joint);
    lk_free(L, m->eff_of_joint);
    lk_free(L, m->eff_parent);
    lk_free(L, m->eff_child);
    lk_free(L, m->eff_place);
    lk_free(L, m->parent_joint);
    lk_free(L, m->order);
    lk_free(L, m->members);
    lk_free(L, m->member_start);
    lk_free(L, m->comp_welded);
    memset(m, 0, sizeof *m);
}

/* Topology: each body the child of exactly one joint, free joints from the
 * world, everything reachable from the world. Fills parent_joint and order. */
static aqs_status check_topology(aqs_linkage *L, int32_t *first_child, int32_t *next_sibling)
{
    model *m = &L->m;
    int32_t i, head = 0, tail = 0;
    if (L->nbodies == 0) return lk_fail(L, AQS_EMODEL, "aqs_linkage_finalize: the linkage has no body");
    for (i = 0; i < L->nbodies; i++) {
        m->parent_joint[i] = -1;
        first_child[i] = -1;
    }
    for (i = 0; i < L->njoints; i++) {
        const joint_def *j = &L->joints[i];
        if (m->parent_joint[j->child] >= 0)
            return lk_fail(L, AQS_EMODEL,
                           "aqs_linkage_finalize: body %d is the child of two joints (%d and %d)",
                           (int)j->child, (int)m->parent_joint[j->child], (int)i);
        m->parent_joint[j->child] = i;
    }
    for (i = 0; i < L->nbodies; i++)
        if (m->parent_joint[i] < 0)
            return lk_fail(L, AQS_EMODEL,
                           "aqs_linkage_finalize: body %d has no parent joint (every body needs "
                           "exactly one)",
                           (int)i);
    /* Children lists, in joint order; world roots traversed first. */
    for (i = L->njoints - 1; i >= 0; i--) {
        const joint_def *j = &L->joints[i];
        if (j->parent >= 0) {
            next_sibling[j->child] = first_child[j->parent];
            first_child[j->parent] = j->child;
        }
    }
    for (i = 0; i < L->njoints; i++)
        if (L->joints[i].parent == AQS_WORLD) m->order[tail++] = L->joints[i].child;
    while (head < tail) {
        int32_t b = m->order[head++], c;
        for (c = first_child[b]; c >= 0; c = next_sibling[c]) m->order[tail++] = c;
    }
    if (tail < L->nbodies) {
        /* Find the first unreachable body for the message. */
        unsigned char *seen = (unsigned char *)next_sibling; /* reuse: values no longer needed */
        memset(seen, 0, (size_t)L->nbodies);
        for (i = 0; i < tail; i++) seen[m->order[i]] = 1;
        for (i = 0; i < L->nbodies && seen[i]; i++) {
        }
        return lk_fail(L, AQS_EMODEL,
                       "aqs_linkage_finalize: body %d is not connected to the world (its "
                       "parent chain forms a cycle or never reaches a joint from AQS_WORLD)",
                       (int)i);
    }
    return AQS_OK;
}

/* The linkage's length scale (model.length): the geometric mean of the
 * effective joints' non-zero offsets in their parent composites' frames (the
 * distances between consecutive joints; a log average, so that a few far
 * joints, e.g. attached to the world far from its origin, weigh little),
 * else of the composites' non-zero radii of gyration sqrt(trace(Ic) / 2m)
 * (cmass: 13 per composite), else 1. It scales with the unit of length. */
static double length_scale(const model *m, const double *cmass)
{
    double sum = 0.0;
    int32_t e, c, n = 0;
    for (e = 0; e < m->ne; e++) {
        const double *p = m->eff_place[e].p, r = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        if (r > 0.0 && isfinite(r)) {
            sum += log(r);
            n++;
        }
    }
    if (n == 0)
        for (c = 0; c < m->ncomp; c++) {
            const double *mp = cmass + 13 * c;
            const double r2 = mp[0] > 0.0 ? (mp[4] + mp[8] + mp[12]) / (2.0 * mp[0]) : 0.0;
            if (r2 > 0.0 && isfinite(r2)) {
                sum += 0.5 * log(r2);
                n++;
            }
        }
    return n > 0 ? exp(sum / n) : 1.0;
}

aqs_status model_build(aqs_linkage *L)
{
    model *m = &L->m;
    int32_t nb = L->nbodies, nj = L->njoints, i, k;
    int32_t *first_child = NULL, *next_sibling = NULL;
    double *cmass = NULL; /* (ncomp + 1) x 13: each composite's mass properties */
    aqs_status st;
    memset(m, 0, sizeof *m);
    m->comp_of_body = lk_calloc(L, (size_t)nb + 1, sizeof(int32_t));
    m->body_in_comp = lk_calloc(L, (size_t)nb + 1, sizeof(pose));
    m->parent_joint = lk_calloc(L, (size_t)nb + 1, sizeof(int32_t));
    m->order = lk_calloc(L, (size_t)nb + 1, sizeof(int32_t));
    m->eff_of_joint = lk_calloc(L, (size_t)nj + 1, sizeof(int32_t));
    first_child = lk_calloc(L, (size_t)nb + 1, sizeof(int32_t));
    next_sibling = lk_calloc(L, (size_t)nb + 1, sizeof(int32_t));
    if (!m->comp_of_body || !m->body_in_comp || !m->parent_joint || !m->order ||
        !m->eff_of_joint || !first_child || !next_sibling) {
        st = lk_fail(L, AQS_ENOMEM, "aqs_linkage_finalize: out of memory");
        goto fail;
    }
    st = check_topology(L, first_child, next_sibling);
    if (st != AQS_OK) goto fail;

    /* Composites: walk parents before children; a fixed joint joins its
     * child to the parent's composite (the world's is -1 until numbered). */
    m->ncomp = 0;
    m->ne = 0;
    for (i = 0; i < nj; i++) m->eff_of_joint[i] = L->joints[i].type == AQS_JOINT_FIXED ? -1 : m->ne++;
    m->nquat = 0;
    for (i = 0; i < nj; i++) m->nquat += L->joints[i].type == AQS_JOINT_SPHERICAL || L->joints[i].type == AQS_JOINT_FREE;
    for (k = 0; k < nb; k++) {
        int32_t b = m->order[k];
        const joint_def *j = &L->joints[m->parent_joint[b]];
        if (j->type == AQS_JOINT_FIXED) {
            pose place;
            pose_from_quat(j->pos, j->quat, &place);
            if (j->parent == AQS_WORLD) {
                m->comp_of_body[b] = -1;
                m->body_in_comp[b] = place;
            } else {
                m->comp_of_body[b] = m->comp_of_body[j->parent];
                pose_compose(&m->body_in_comp[j->parent], &place, &m->body_in_comp[b]);
            }
            m->nwelded++;
        } else {
            m->comp_of_body[b] = m->ncomp++;
            kin_joint_turn(j, 1, &m->body_in_comp[b]); /* its pose in the aligned frame */
        }
    }
    for (i = 0; i < nb; i++)
        if (m->comp_of_body[i] < 0) m->comp_of_body[i] = m->ncomp; /* the world */

    m->comp_root = lk_calloc(L, (size_t)m->ncomp + 1, sizeof(int32_t));
    m->comp_inertia = lk_calloc(L, (size_t)m->ncomp + 1, 36 * sizeof(double));
    m->comp_inverse = NULL; /* model_inverse_alloc: the DCA and welded bodies need it */
    m->comp_force = lk_calloc(L, (size_t)m->ncomp + 1, 6 * sizeof(double));
    m->comp_loaded = lk_calloc(L, (size_t)m->ncomp + 1, 1);
    m->loaded_comps = lk_calloc(L, (size_t)m->ncomp + 1, sizeof(int32_t));
    m->eff_joint = lk_calloc(L, (size_t)m->ne + 1, sizeof(int32_t));
    m->eff_parent = lk_calloc(L, (size_t)m->ne + 1, sizeof(int32_t));
    m->eff_child = lk_calloc(L, (size_t)m->ne + 1, sizeof(int32_t));
    m->eff_place = lk_calloc(L, (size_t)m->ne + 1, sizeof(pose));
    if (!m->comp_root || !m->comp_inertia || !m->comp_force ||
        !m->comp_loaded || !m->loaded_comps || !m->eff_joint || !m->eff_parent ||
        !m->eff_child || !m->eff_place) {
        st = lk_fail(L, AQS_ENOMEM, "aqs_linkage_finalize: out of memory");
        goto fail;
    }
    /* Inertia of each composite in its root body's frame, and its mass
     * properties (for the definiteness check). */
    cmass = lk_calloc(L, (size_t)m->ncomp + 1, 13 * sizeof(double));
    if (!cmass) {
        st = lk_fail(L, AQS_ENOMEM, "aqs_linkage_finalize: out of memory");
        goto fail;
    }
    for (k = 0; k < nb; k++) {
        int32_t b = m->order[k], c = m->comp_of_body[b];
        double Ib[36], Ic[36], one[13], Cr[9];
        const body_def *bd = &L->bodies[b];
        if (c == m->ncomp) continue;
        if (L->joints[m->parent_joint[b]].type != AQS_JOINT_FIXED) m->comp_root[c] = b;
        one[0] = bd->mass;
        memcpy(one + 1, bd->com, 3 * sizeof(double));
        memcpy(one + 4, bd->inertia, 9 * sizeof(double));
        if (joint_align_rotation(&L->joints[m->parent_joint[m->comp_root[c]]], Cr)) {
            /* an aligned composite: the body's mass properties turned, then
             * its spatial inertia, whose mass block stays m I exactly (C is
             * orthogonal only to the rounding: C^T (m I) C is not m I) */
            double mp[13] = {0};
            model_mass_add_posed(mp, &m->body_in_comp[b], one);
            spatial_inertia(mp[0], mp + 1, mp + 4, Ic);
        } else {
            model_body_inertia(L, b, Ib);
            spatial_inertia_to_parent(&m->body_in_comp[b], Ib, Ic);
        }
        for (i = 0; i < 36; i++) m->comp_inertia[36 * c + i] += Ic[i];
        model_mass_add_posed(cmass + 13 * c, &m->body_in_comp[b], one);
    }
    for (i = 0; i < m->ncomp; i++) {
        double mass = m->comp_inertia[36 * i + 21]; /* the (3,3) entry is the total mass */
        double inv[36];
        const int definite = mass > 0.0 && rotational_inertia_definite(cmass + 13 * i);
        if (!definite || dense_spd_inverse(m->comp_inertia + 36 * i, inv, 6) != 0) {
            const char *name = lk_body_name(L, m->comp_root[i]);
            int32_t count = 0;
            for (k = 0; k < nb; k++) count += m->comp_of_body[k] == i;
            char group[64];
            if (count > 1) snprintf(group, sizeof group, "with %d more welded to it by fixed joints", (int)count - 1);
            else snprintf(group, sizeof group, "welded to no other body");
            if (definite) { /* the inertia is fine: its frame is too far from it */
                const double *c = cmass + 13 * i + 1;
                st = lk_fail(L, AQS_EMODEL,
                             "aqs_linkage_finalize: body %d%s%s%s (%s): its spatial inertia in its frame is "
                             "numerically singular although its inertia about its centre of mass is definite: "
                             "the centre of mass lies %g from the frame's origin, too far for its radius of "
                             "gyration (the solvers work in that frame: place the joint nearer the centre of mass)",
                             (int)m->comp_root[i], name ? " '" : "", name ? name : "", name ? "'" : "", group,
                             sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]));
                goto fail;
            }
            st = lk_fail(L, AQS_EMODEL,
                         "aqs_linkage_finalize: body %d%s%s%s (%s) has %s (total mass %g); every "
                         "rigid group that moves needs mass and a positive definite inertia: a "
                         "massless or point-mass body must be welded to a massive one",
                         (int)m->comp_root[i], name ? " '" : "", name ? name : "",
                         name ? "'" : "", group, !(mass > 0.0) ? "no mass" : "a singular inertia",
                         mass);
            goto fail;
        }
    }
    /* Effective joints. */
    for (i = 0; i < nj; i++) {
        const joint_def *j = &L->joints[i];
        int32_t e = m->eff_of_joint[i];
        pose place, P, Cj;
        if (e < 0) continue;
        m->eff_joint[e] = i;
        m->eff_child[e] = m->comp_of_body[j->child];
        pose_from_quat(j->pos, j->quat, &place);
        if (j->parent == AQS_WORLD) {
            m->eff_parent[e] = m->ncomp;
            P = place;
        } else {
            m->eff_parent[e] = m->comp_of_body[j->parent];
            pose_compose(&m->body_in_comp[j->parent], &place, &P);
        }
        kin_joint_turn(j, 0, &Cj); /* the aligned joint frame: joint frame C */
        pose_compose(&P, &Cj, &m->eff_place[e]);
        snap_planar(&m->eff_place[e]);
    }
    m->length = length_scale(m, cmass);
    /* a heavy child on a light parent (docs/math.md 5b, "Where it loses
     * digits its check does not see") */
    m->heavy_ratio = 0.0;
    for (i = 0; i < m->ne; i++) {
        const int32_t p = m->eff_parent[i], c = m->eff_child[i];
        if (p < m->ncomp && cmass[13 * c] > m->heavy_ratio * cmass[13 * p])
            m->heavy_ratio = cmass[13 * c] / cmass[13 * p]; /* masses are positive (checked at finalize) */
    }
    /* Members of each composite, parents first (for the fixed joints' forces). */
    m->members = lk_calloc(L, (size_t)nb + 1, sizeof(int32_t));
    m->member_start = lk_calloc(L, (size_t)m->ncomp + 2, sizeof(int32_t));
    m->comp_welded = lk_calloc(L, (size_t)m->ncomp + 1, 1);
    if (!m->members || !m->member_start || !m->comp_welded) {
        st = lk_fail(L, AQS_ENOMEM, "aqs_linkage_finalize: out of memory");
        goto fail;
    }
    for (i = 0; i < nb; i++) m->member_start[m->comp_of_body[i] + 1]++;
    for (i = 0; i <= m->ncomp; i++) m->member_start[i + 1] += m->member_start[i];
    {
        int32_t *cursor = next_sibling; /* nb + 1 >= ncomp + 1 entries, no longer needed */
        for (i = 0; i <= m->ncomp; i++) cursor[i] = m->member_start[i];
        for (k = 0; k < nb; k++) {
            int32_t b = m->order[k], c = m->comp_of_body[b];
            m->members[cursor[c]++] = b;
            if (L->joints[m->parent_joint[b]].type == AQS_JOINT_FIXED) m->comp_welded[c] = 1;
        }
    }
    lk_free(L, first_child);
    lk_free(L, next_sibling);
    lk_free(L, cmass);
    if (m->nwelded == 0) { /* every body is its composite's root: identity poses, not stored */
        lk_free(L, m->body_in_comp);
        m->body_in_comp = NULL;
    }
    return AQS_OK;
fail:
    lk_free(L, first_child);
    lk_free(L, next_sibling);
    lk_free(L, cmass);
    model_free(L);
    return st;
}
