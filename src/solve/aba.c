/* aba.c -- the exact quasi-static solve by Featherstone's articulated-body
 * algorithm (ABA) over the kinematic tree of composites, all velocities
 * zero. It gives the same accelerations and constraint forces as a full DCA
 * back-substitution (MATH.md §3, checked by tests/reference against the
 * dense solver for both), in O(N) with a small constant. It neither reads
 * nor writes the assembly tree (its coefficients nor its poses), so the
 * tree's stale marks simply accumulate until an adaptive solve needs it.
 *
 * For composite c hanging from effective joint e (parent composite p, S the
 * motion subspace in c's frame, Q the active force, f_c the external load):
 *   backward:  IA_c = I_c + sum_children X^T Ia X,  pA_c = -f_c + sum X^T pa
 *              U = IA_c S,  D = S^T U,  u = Q - S^T pA_c
 *              Ia = IA_c - U D^-1 U^T,  pa = pA_c + U D^-1 u
 *   forward:   a' = X a_p,  qdd = D^-1 (u - U^T a'),  a_c = a' + S qdd
 *              f_e = IA_c a_c + pA_c  (the force of e on c, c's frame)
 * with X the motion transform from p's frame to c's, and the world moving
 * with a_0 = -g (the root trick, MATH.md §3.7).
 *
 * Layout (docs/math.md §5a): one array of per-joint constants (aba_joint)
 * and one of per-solve values (aba_node), both in the ABA order, parents
 * before children, depth first; the passes stream them forward (poses,
 * accelerations) and backward (inertias). Revolute and prismatic joints take
 * a specialized path: U is one column, D a scalar, the articulated-inertia
 * update a rank-one downdate, and the inertias are kept packed (21 values)
 * and moved to the parent frame blockwise using their symmetry. Other joints
 * take the general path on the unpacked 6x6 inertia. */
#include "aba.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "abarefine.h"
#include "adaptive.h"
#include "cost.h"
#include "dca.h"
#include "dense.h"
#include "kintree.h"
#include "invariant.h"
#include "rounding.h"
#include "update.h"

#ifdef __GNUC__
#define ABA_INLINE static inline __attribute__((always_inline))
#else
#define ABA_INLINE static
#endif

/* Build the ABA order (depth first from the world, children by effective
 * index) and the per-joint constants. */
aqs_status aba_alloc(aqs_linkage *L)
{
    const model *m = &L->m;
    aba_state *a = &L->aba;
    int32_t *head, *next, *stack, e, n = 0, top = 0, i;
    int multi = 0;
    a->joint = lk_calloc_in(L, LK_MEM_EXACT, (size_t)m->ne + 1, sizeof(aba_joint));
    a->node = lk_calloc_in(L, LK_MEM_EXACT, (size_t)m->ne + 1, sizeof(aba_node));
    a->pos_of_comp = lk_calloc_in(L, LK_MEM_EXACT, (size_t)m->ncomp + 1, sizeof(int32_t));
    a->x = lk_calloc_in(L, LK_MEM_EXACT, 6 * (size_t)L->t.max_handles + 1, sizeof(double));
    a->need = lk_calloc_in(L, LK_MEM_EXACT, (size_t)m->ne + 1, 1);
    a->kin = lk_calloc_in(L, LK_MEM_EXACT, (size_t)m->ne + 1, 1);
    a->path = lk_calloc_in(L, LK_MEM_EXACT, (size_t)m->ne + 1, sizeof(int32_t));
    head = lk_calloc_in(L, LK_MEM_EXACT, (size_t)m->ncomp + 2, sizeof(int32_t));
    next = lk_calloc_in(L, LK_MEM_EXACT, (size_t)m->ne + 1, sizeof(int32_t));
    stack = lk_calloc_in(L, LK_MEM_EXACT, (size_t)m->ne + 1, sizeof(int32_t));
    if (!a->joint || !a->node || !a->pos_of_comp || !a->x || !a->need || !a->kin || !a->path || !head || !next ||
        !stack) {
        lk_free(L, head);
        lk_free(L, next);
        lk_free(L, stack);
        return AQS_ENOMEM;
    }
    /* Children lists, descending: popped from the stack ascending. */
    for (i = 0; i <= m->ncomp; i++) head[i] = -1;
    for (e = 0; e < m->ne; e++) {
        int32_t p = m->eff_parent[e];
        next[e] = head[p];
        head[p] = e;
    }
    for (e = head[m->ncomp]; e >= 0; e = next[e]) stack[top++] = e;
    while (top > 0) {
        int32_t c;
        e = stack[--top];
        c = m->eff_child[e];
        a->pos_of_comp[c] = n;
        for (i = head[c]; i >= 0; i = next[i]) stack[top++] = i;
        {
            aba_joint *jt = &a->joint[n];
            const joint_def *jd = &L->joints[m->eff_joint[e]];
            int32_t p = m->eff_parent[e];
            jt->place = m->eff_place[e]; /* the aligned frames, as the model keeps them */
            kin_pack_inertia(m->comp_inertia + 36 * (size_t)c, jt->I);
            jt->parent = p == m->ncomp ? -1 : a->pos_of_comp[p]; /* p came first */
            jt->type = jd->type;
            jt->qoff = jd->qoff;
            jt->voff = jd->voff;
            jt->joint = m->eff_joint[e];
            jt->comp = c;
            if (joint_nv(jd->type) > 1) multi = 1;
        }
        n++;
    }
    /* the leaves and each position's parent's last child (next[]: the last
     * child of each position, -1: none) */
    for (i = 0; i < n; i++) next[i] = -1;
    for (i = 0; i < n; i++)
        if (a->joint[i].parent >= 0) next[a->joint[i].parent] = i;
    for (i = 0; i < n; i++)
        a->kin[i] = (unsigned char)((next[i] < 0 ? ABA_LEAF : 0) |
                                    (a->joint[i].parent >= 0 && next[a->joint[i].parent] == i ? ABA_LAST : 0));
    lk_free(L, head);
    lk_free(L, next);
    lk_free(L, stack);
    if (n != m->ne) return lk_fail(L, AQS_EINVAL, "internal: the articulated-body order holds %d of %d joints",
                                   (int)n, (int)m->ne);
    if (multi) { /* U and u of the multi-dof joints only, at moff of their position */
        size_t nm = 0;
        a->moff = lk_calloc_in(L, LK_MEM_EXACT, (size_t)m->ne + 1, sizeof(int32_t));
        if (!a->moff) return AQS_ENOMEM;
        for (i = 0; i < m->ne; i++) {
            int d = joint_nv(a->joint[i].type);
            if (d > 1) {
                a->moff[i] = (int32_t)nm;
                nm += (size_t)d;
            }
        }
        a->Um = lk_calloc_in(L, LK_MEM_EXACT, 6 * nm + 1, sizeof(double));
        a->um = lk_calloc_in(L, LK_MEM_EXACT, nm + 1, sizeof(double));
        if (!a->Um || !a->um) return AQS_ENOMEM;
    }
    a->dirty = 1; /* IA and pA set by the first solve */
    return AQS_OK;
}

void aba_free(aqs_linkage *L)
{
    aba_state *a = &L->aba;
    aba_refine_free(L);
    lk_free(L, a->joint);
    lk_free(L, a->node);
    lk_free(L, a->pos_of_comp);
    lk_free(L, a->Um);
    lk_free(L, a->um);
    lk_free(L, a->moff);
    lk_free(L, a->x);
    lk_free(L, a->need);
    lk_free(L, a->kin);
    lk_free(L, a->path);
    memset(a, 0, sizeof *a);
}

/* Software prefetch of position k's constants and values, ABA_AHEAD
 * positions ahead of the pass (behind it, going backward): every line of the
 * values, and of the constants those the pass reads (the backward pass all
 * but I; the forward pass resets IA from I). With the hardware prefetchers
 * alone the passes at 50,000 and 10^6 joints took 1.2-1.3x as long
 * (docs/bench.md, "Time per joint flat in N"). A hint: no effect on the
 * results. */
#if defined(__GNUC__) || defined(__clang__)
#define ABA_PREFETCH(p) __builtin_prefetch((p), 0, 3)
#else
#define ABA_PREFETCH(p) ((void)(p))
#endif
enum { ABA_AHEAD = 4, ABA_LINE = 64 };

/* How far ahead to prefetch: ABA_AHEAD, or ne (never) when the arrays fit in
 * 4 MiB (up to ~5,700 joints), where they stay in the caches from one pass
 * to the next and the prefetches would only cost their instructions (~3 %
 * of the 2,000-joint time, measured). */
static int32_t prefetch_ahead(int32_t ne)
{
    return (size_t)ne * (sizeof(aba_joint) + sizeof(aba_node)) < ((size_t)4 << 20) ? ne : ABA_AHEAD;
}

ABA_INLINE void prefetch_position(const aba_state *a, int32_t k, int joint_bytes)
{
    const char *j = (const char *)&a->joint[k], *n = (const char *)&a->node[k];
    int l;
    /* a line from each 64 bytes: the line holding a struct's last bytes is
     * the next one's first, prefetched with it */
    for (l = 0; l < joint_bytes; l += ABA_LINE) ABA_PREFETCH(j + l);
    for (l = 0; l < (int)sizeof(aba_node); l += ABA_LINE) ABA_PREFETCH(n + l);
}

/* out = a b, written out (pose_compose). */
ABA_INLINE void compose(const pose *a, const pose *b, pose *out)
{
    const double *A = a->R, *B = b->R;
    int i;
    for (i = 0; i < 3; i++) {
        const double r0 = A[3 * i], r1 = A[3 * i + 1], r2 = A[3 * i + 2];
        out->R[3 * i] = r0 * B[0] + r1 * B[3] + r2 * B[6];
        out->R[3 * i + 1] = r0 * B[1] + r1 * B[4] + r2 * B[7];
        out->R[3 * i + 2] = r0 * B[2] + r1 * B[5] + r2 * B[8];
        out->p[i] = a->p[i] + r0 * b->p[0] + r1 * b->p[1] + r2 * b->p[2];
    }
}

/* The world poses the loads need, top-down along the path from each loaded
 * composite up to the first position already done (or the world), into
 * node[].v.world, with their X; need[] marks them (the backward pass clears
 * the marks and does not compose those X again). */
static void world_for_loads(aqs_linkage *L)
{
    aba_state *a = &L->aba;
    const model *m = &L->m;
    int32_t i, n = 0;
    for (i = 0; i < L->nloaded; i++) {
        int32_t c = m->comp_of_body[L->loaded_bodies[i]], k, start = n, j;
        if (c == m->ncomp) continue;
        for (k = a->pos_of_comp[c]; k >= 0 && !a->need[k]; k = a->joint[k].parent) {
            a->need[k] = 1;
            a->path[n++] = k;
        }
        for (j = n - 1; j >= start; j--) { /* parents first */
            const aba_joint *jt = &a->joint[a->path[j]];
            aba_node *nd = &a->node[a->path[j]];
            kin_joint_pose(L, jt, &nd->X); /* kept: the backward pass skips it */
            if (jt->parent < 0) nd->v.world = nd->X;
            else compose(&a->node[jt->parent].v.world, &nd->X, &nd->v.world);
        }
    }
}

/* IA <- I, pA <- 0 and no marks everywhere (after a failed solve, and
 * before the first). */
static void reset_nodes(aqs_linkage *L)
{
    aba_state *a = &L->aba;
    int32_t k;
    memset(a->need, 0, (size_t)L->m.ne);
    for (k = 0; k < L->m.ne; k++) {
        memcpy(a->node[k].IA, a->joint[k].I, sizeof a->node[k].IA);
        memset(a->node[k].pA, 0, sizeof a->node[k].pA);
    }
    a->dirty = 0;
}

/* out += R S R^T for packed symmetric 3x3 S (xx xy xz yy yz zz), R row-major. */
ABA_INLINE void rot_sym(const double *R, const double *S, double *o)
{
    /* T = S R^T (3x3): T_ij = sum_k S_ik R_jk */
    const double s00 = S[0], s01 = S[1], s02 = S[2], s11 = S[3], s12 = S[4], s22 = S[5];
    double T[9];
    int j;
    for (j = 0; j < 3; j++) {
        const double r0 = R[3 * j], r1 = R[3 * j + 1], r2 = R[3 * j + 2];
        T[j] = s00 * r0 + s01 * r1 + s02 * r2;
        T[3 + j] = s01 * r0 + s11 * r1 + s12 * r2;
        T[6 + j] = s02 * r0 + s12 * r1 + s22 * r2;
    }
    o[0] = R[0] * T[0] + R[1] * T[3] + R[2] * T[6];
    o[1] = R[0] * T[1] + R[1] * T[4] + R[2] * T[7];
    o[2] = R[0] * T[2] + R[1] * T[5] + R[2] * T[8];
    o[3] = R[3] * T[1] + R[4] * T[4] + R[5] * T[7];
    o[4] = R[3] * T[2] + R[4] * T[5] + R[5] * T[8];
    o[5] = R[6] * T[2] + R[7] * T[5] + R[8] * T[8];
}

/* o = R B R^T for a full 3x3 B. */
ABA_INLINE void rot_full(const double *R, const double *B, double *o)
{
    double T[9];
    int i, j;
    for (i = 0; i < 3; i++) /* T = B R^T */
        for (j = 0; j < 3; j++) T[3 * i + j] = B[3 * i] * R[3 * j] + B[3 * i + 1] * R[3 * j + 1] + B[3 * i + 2] * R[3 * j + 2];
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) o[3 * i + j] = R[3 * i] * T[j] + R[3 * i + 1] * T[3 + j] + R[3 * i + 2] * T[6 + j];
}

ABA_INLINE void cross(const double *a, double b0, double b1, double b2, double *o)
{
    o[0] = a[1] * b2 - a[2] * b1;
    o[1] = a[2] * b0 - a[0] * b2;
    o[2] = a[0] * b1 - a[1] * b0;
}

/* IG += X* IF X*^T for the frame with pose P in G, packed; the same
 * arithmetic as spatial_inertia_to_parent: rotate the blocks (A' = R A R^T,
 * B' = R B R^T, C' = R C R^T), then with M = p~ C' and K = p~ B'^T:
 * A'' = A' + K + K^T - M p~,  B'' = B' + M,  C'' = C'. */
static void inertia_to_parent_add(const pose *P, const double *IF, double *IG)
{
    const double *p = P->p;
    double A[6], B[9], C[6], Cf[9], M[9], K[9], N[9];
    int i, j;
    rot_sym(P->R, IF + KIN_PA, A);
    rot_full(P->R, IF + KIN_PB, B);
    rot_sym(P->R, IF + KIN_PC, C);
    Cf[0] = C[0], Cf[1] = Cf[3] = C[1], Cf[2] = Cf[6] = C[2];
    Cf[4] = C[3], Cf[5] = Cf[7] = C[4], Cf[8] = C[5];
    for (j = 0; j < 3; j++) { /* column j of M = p x (column j of C'); row j of K^T... */
        double c[3];
        cross(p, Cf[j], Cf[3 + j], Cf[6 + j], c);
        M[j] = c[0], M[3 + j] = c[1], M[6 + j] = c[2];
        cross(p, B[3 * j], B[3 * j + 1], B[3 * j + 2], c); /* K column j = p x (row j of B') */
        K[j] = c[0], K[3 + j] = c[1], K[6 + j] = c[2];
    }
    for (i = 0; i < 3; i++) /* row i of M p~ = -(p x row i of M) */
        cross(p, M[3 * i], M[3 * i + 1], M[3 * i + 2], N + 3 * i);
    IG[KIN_PA + 0] += A[0] + 2.0 * K[0] + N[0];
    IG[KIN_PA + 1] += A[1] + K[1] + K[3] + N[1];
    IG[KIN_PA + 2] += A[2] + K[2] + K[6] + N[2];
    IG[KIN_PA + 3] += A[3] + 2.0 * K[4] + N[4];
    IG[KIN_PA + 4] += A[4] + K[5] + K[7] + N[5];
    IG[KIN_PA + 5] += A[5] + 2.0 * K[8] + N[8];
    for (i = 0; i < 9; i++) IG[KIN_PB + i] += B[i] + M[i];
    for (i = 0; i < 6; i++) IG[KIN_PC + i] += C[i];
}

/* pG += X^T f: [R n + p x (R f); R f]. */
ABA_INLINE void force_to_parent_add(const pose *P, const double *f, double *g)
{
    const double *R = P->R, *p = P->p;
    double l0 = R[0] * f[3] + R[1] * f[4] + R[2] * f[5];
    double l1 = R[3] * f[3] + R[4] * f[4] + R[5] * f[5];
    double l2 = R[6] * f[3] + R[7] * f[4] + R[8] * f[5];
    g[0] += R[0] * f[0] + R[1] * f[1] + R[2] * f[2] + (p[1] * l2 - p[2] * l1);
    g[1] += R[3] * f[0] + R[4] * f[1] + R[5] * f[2] + (p[2] * l0 - p[0] * l2);
    g[2] += R[6] * f[0] + R[7] * f[1] + R[8] * f[2] + (p[0] * l1 - p[1] * l0);
    g[3] += l0;
    g[4] += l1;
    g[5] += l2;
}

/* o = X v, v in the parent's frame: [R^T w; R^T (v - p x w)]. */
ABA_INLINE void motion_from_parent(const pose *P, const double *v, double *o)
{
    const double *R = P->R, *p = P->p;
    const double t0 = v[3] - (p[1] * v[2] - p[2] * v[1]);
    const double t1 = v[4] - (p[2] * v[0] - p[0] * v[2]);
    const double t2 = v[5] - (p[0] * v[1] - p[1] * v[0]);
    o[0] = R[0] * v[0] + R[3] * v[1] + R[6] * v[2];
    o[1] = R[1] * v[0] + R[4] * v[1] + R[7] * v[2];
    o[2] = R[2] * v[0] + R[5] * v[1] + R[8] * v[2];
    o[3] = R[0] * t0 + R[3] * t1 + R[6] * t2;
    o[4] = R[1] * t0 + R[4] * t1 + R[7] * t2;
    o[5] = R[2] * t0 + R[5] * t1 + R[8] * t2;
}

static aqs_status singular(aqs_linkage *L, const aba_joint *jt)
{
    return lk_fail(L, AQS_ENUMERIC, "articulated inertia across joint %d is numerically singular", (int)jt->joint);
}

/* The general joint: on the unpacked inertia; Ia (packed) and pa out. */
static aqs_status backward_general(aqs_linkage *L, const aba_joint *jt, aba_node *nd, double *Ia, double *pa)
{
    const aba_state *a = &L->aba;
    const double *Q = L->tau + jt->voff;
    double IA[36], S[36], Dinv[36], w[6], F[36], DU[36];
    const int32_t mo = a->moff[jt - a->joint];
    double *U = a->Um + 6 * mo, *u = a->um + mo;
    int d = joint_nv(jt->type), i, j, r;
    kin_unpack_inertia(nd->IA, IA);
    joint_subspace_aligned(&L->joints[jt->joint], L->q + jt->qoff, S);
    for (j = 0; j < d; j++) {
        double s = 0.0;
        for (r = 0; r < 6; r++) {
            double v = 0.0;
            for (i = 0; i < 6; i++) v += IA[6 * r + i] * S[i * d + j];
            U[6 * j + r] = v;
            s += S[r * d + j] * nd->pA[r];
        }
        u[j] = Q[j] - s;
    }
    if (dense_joint_space_inverse(S, U, d, Dinv) != 0) return singular(L, jt);
    /* w = D^-1 u; Ia = IA - U^T D^-1 U (U stored as d rows), pa = pA + U^T w */
    for (j = 0; j < d; j++) {
        double v = 0.0;
        for (i = 0; i < d; i++) v += Dinv[d * j + i] * u[i];
        w[j] = v;
    }
    for (r = 0; r < 6; r++) {
        double v = nd->pA[r];
        for (j = 0; j < d; j++) v += U[6 * j + r] * w[j];
        pa[r] = v;
    }
    for (j = 0; j < d; j++)
        for (r = 0; r < 6; r++) {
            double v = 0.0;
            for (i = 0; i < d; i++) v += Dinv[d * j + i] * U[6 * i + r];
            DU[6 * j + r] = v;
        }
    for (r = 0; r < 6; r++)
        for (i = r; i < 6; i++) {
            double v = IA[6 * r + i];
            for (j = 0; j < d; j++) v -= U[6 * j + r] * DU[6 * j + i];
            F[6 * r + i] = F[6 * i + r] = v;
        }
    kin_pack_inertia(F, Ia);
    return AQS_OK;
}

static aqs_status backward(aqs_linkage *L)
{
    const model *m = &L->m;
    aba_state *a = &L->aba;
    int32_t k, i;
    aqs_status st;
    const int32_t ahead = prefetch_ahead(m->ne);
    for (i = 0; i < m->nloaded_comps; i++) { /* pA starts at minus the loads */
        int32_t c = m->loaded_comps[i];
        double *pA = a->node[a->pos_of_comp[c]].pA;
        for (k = 0; k < 6; k++) pA[k] -= m->comp_force[6 * c + k];
    }
    for (k = m->ne - 1; k >= 0; k--) {
        const aba_joint *jt = &a->joint[k];
        aba_node *nd = &a->node[k];
        const double *IA = nd->IA, *pA = nd->pA;
        double Ia[21], pa[6], *U = nd->v.s.U;
        if (k >= ahead) prefetch_position(a, k - ABA_AHEAD, (int)offsetof(aba_joint, I));
        if (a->need[k]) a->need[k] = 0; /* X composed for the loads already */
        else kin_joint_pose(L, jt, &nd->X); /* composed once: the forward pass reads it */
        if (jt->type == AQS_JOINT_REVOLUTE || jt->type == AQS_JOINT_PRISMATIC) {
            double D, Dinv, u, w;
            /* the aligned frame (kintree.h): the axis is z */
            if (jt->type == AQS_JOINT_REVOLUTE) { /* S = [e_z; 0]: U = [A e_z; B^T e_z] */
                const double *A = IA + KIN_PA, *B = IA + KIN_PB;
                U[0] = A[2], U[1] = A[4], U[2] = A[5];
                U[3] = B[6], U[4] = B[7], U[5] = B[8];
                D = U[2];
                u = L->tau[jt->voff] - pA[2];
            } else { /* S = [0; e_z]: U = [B e_z; C e_z] */
                const double *B = IA + KIN_PB, *C = IA + KIN_PC;
                U[0] = B[2], U[1] = B[5], U[2] = B[8];
                U[3] = C[2], U[4] = C[4], U[5] = C[5];
                D = U[5];
                u = L->tau[jt->voff] - pA[5];
            }
            if (!(D > 0.0) || !isfinite(D)) return singular(L, jt);
            Dinv = 1.0 / D;
            nd->Dinv = Dinv;
            nd->u = u;
            if (jt->parent < 0) continue; /* the world takes nothing back */
            w = u * Dinv;
            {
                /* rank-one downdate Ia = IA - U U^T / D, packed */
                const double v0 = U[0] * Dinv, v1 = U[1] * Dinv, v2 = U[2] * Dinv;
                const double v3 = U[3] * Dinv, v4 = U[4] * Dinv, v5 = U[5] * Dinv;
                Ia[KIN_PA + 0] = IA[KIN_PA + 0] - v0 * U[0];
                Ia[KIN_PA + 1] = IA[KIN_PA + 1] - v0 * U[1];
                Ia[KIN_PA + 2] = IA[KIN_PA + 2] - v0 * U[2];
                Ia[KIN_PA + 3] = IA[KIN_PA + 3] - v1 * U[1];
                Ia[KIN_PA + 4] = IA[KIN_PA + 4] - v1 * U[2];
                Ia[KIN_PA + 5] = IA[KIN_PA + 5] - v2 * U[2];
                Ia[KIN_PB + 0] = IA[KIN_PB + 0] - v0 * U[3];
                Ia[KIN_PB + 1] = IA[KIN_PB + 1] - v0 * U[4];
                Ia[KIN_PB + 2] = IA[KIN_PB + 2] - v0 * U[5];
                Ia[KIN_PB + 3] = IA[KIN_PB + 3] - v1 * U[3];
                Ia[KIN_PB + 4] = IA[KIN_PB + 4] - v1 * U[4];
                Ia[KIN_PB + 5] = IA[KIN_PB + 5] - v1 * U[5];
                Ia[KIN_PB + 6] = IA[KIN_PB + 6] - v2 * U[3];
                Ia[KIN_PB + 7] = IA[KIN_PB + 7] - v2 * U[4];
                Ia[KIN_PB + 8] = IA[KIN_PB + 8] - v2 * U[5];
                Ia[KIN_PC + 0] = IA[KIN_PC + 0] - v3 * U[3];
                Ia[KIN_PC + 1] = IA[KIN_PC + 1] - v3 * U[4];
                Ia[KIN_PC + 2] = IA[KIN_PC + 2] - v3 * U[5];
                Ia[KIN_PC + 3] = IA[KIN_PC + 3] - v4 * U[4];
                Ia[KIN_PC + 4] = IA[KIN_PC + 4] - v4 * U[5];
                Ia[KIN_PC + 5] = IA[KIN_PC + 5] - v5 * U[5];
            }
            for (i = 0; i < 6; i++) pa[i] = pA[i] + U[i] * w;
        } else {
            if ((st = backward_general(L, jt, nd, Ia, pa)) != AQS_OK) return st;
            if (jt->parent < 0) continue;
        }
        {
            aba_node *pn = &a->node[jt->parent];
            inertia_to_parent_add(&nd->X, Ia, pn->IA);
            force_to_parent_add(&nd->X, pa, pn->pA);
        }
    }
    return AQS_OK;
}

static void forward_general(aqs_linkage *L, const aba_joint *jt, aba_node *nd, double *ac)
{
    const aba_state *a = &L->aba;
    const int32_t mo = a->moff[jt - a->joint];
    const double *U = a->Um + 6 * mo, *u = a->um + mo;
    double S[36], Dinv[36];
    const int d = joint_nv(jt->type);
    joint_subspace_aligned(&L->joints[jt->joint], L->q + jt->qoff, S);
    (void)dense_joint_space_inverse(S, U, d, Dinv); /* succeeded in the backward pass */
    if (jt->type == AQS_JOINT_FREE) dense_free_accel(Dinv, u, ac, L->qdd + jt->voff);
    else dense_joint_accel(S, U, Dinv, d, u, ac, L->qdd + jt->voff);
}

/* The forward pass. With check, it also returns the bodies' balance of
 * forces relative to their terms (docs/math.md §5b): with the solve's joint
 * forces f (f_e = IA a + pA, the force of e on its child c), each body's
 *   b_c = I_c a_c - f_ext,c - f_e + sum_children X^T f_child
 * is 0 in exact arithmetic; its linear rows (three of six, at a third of
 * the cost) show what the rounding of the articulated inertias left
 * unbalanced. Returned: max_c |b_c|_1 over max_c (|(I_c a_c)_lin|_1 +
 * m_c |g| + |f_e,lin|_1) (a free fall's forces are 0: its weights are the
 * scale), or over ABA_FORCE_SCALE max_e |f_e,lin|_1 where that is smaller
 * and the joint forces are not below 2^-10 of that scale (a floating tree
 * whose joint forces are small beside its weights loses digits in its
 * forces that the terms' scale hides: docs/math.md §5b). b_c is summed in
 * pA (the backward pass's, read at c's turn before) and read and zeroed
 * where it is complete: at c's turn for a leaf, else at its last child's
 * (aba_state.kin). Also each joint's own equation: S^T f_e = Q_e holds in
 * exact arithmetic (the forward pass's qdd makes it so), and where f_e is a
 * small difference of large I^A a and p^A its rounding shows there while
 * every body still balances (floating trees of very different masses under
 * tilted gravity). Returned as well: max_e |Q_e - S^T f_e| over
 * ABA_PROJ_SCALE max_e |f_e| (torques weighed by 1/l), unless the joint
 * forces are below 2^-20 of the terms; the larger of the two measures.
 * Without check, 0 (pA zeroed as well). */
static double forward(aqs_linkage *L, int check)
{
    const model *m = &L->m;
    aba_state *a = &L->aba;
    double g[6], tsum = 0.0, bmax = 0.0, flmax = 0.0, emax = 0.0, f6max = 0.0, gn, bal;
    int32_t k, i;
    int bad = 0;
    const int32_t ahead = prefetch_ahead(m->ne);
    const double il = m->length > 0.0 ? 1.0 / m->length : 1.0;
    for (i = 0; i < 3; i++) {
        g[i] = 0.0;
        g[3 + i] = -L->gravity[i];
    }
    gn = sqrt(L->gravity[0] * L->gravity[0] + L->gravity[1] * L->gravity[1] + L->gravity[2] * L->gravity[2]);
    if (check) /* the loaded composites, for their turns (need[] is 0 after the backward pass) */
        for (i = 0; i < m->nloaded_comps; i++) a->need[a->pos_of_comp[m->loaded_comps[i]]] = 1;
    for (k = 0; k < m->ne; k++) {
        const aba_joint *jt = &a->joint[k];
        aba_node *nd = &a->node[k];
        const double *ap = jt->parent < 0 ? g : a->node[jt->parent].v.s.acc;
        double *ac = nd->v.s.acc, *f = L->cforce + 6 * (size_t)jt->joint, *b = nd->pA;
        if (k + ahead < m->ne) prefetch_position(a, k + ABA_AHEAD, (int)sizeof(aba_joint));
        motion_from_parent(&nd->X, ap, ac); /* a' = X a_p */
        if (jt->type == AQS_JOINT_REVOLUTE || jt->type == AQS_JOINT_PRISMATIC) {
            const double *U = nd->v.s.U;
            double qdd = (nd->u - (U[0] * ac[0] + U[1] * ac[1] + U[2] * ac[2] + U[3] * ac[3] + U[4] * ac[4] +
                                   U[5] * ac[5])) * nd->Dinv;
            L->qdd[jt->voff] = qdd;
            ac[jt->type == AQS_JOINT_REVOLUTE ? 2 : 5] += qdd; /* S = e_z, aligned */
        } else {
            forward_general(L, jt, nd, ac);
        }
        if (jt->type == AQS_JOINT_FREE) { /* S = 1: the joint force is Q, exactly */
            memcpy(f, L->tau + jt->voff, 6 * sizeof(double));
        } else {
            kin_inertia_mul(nd->IA, ac, f);
            for (i = 0; i < 6; i++) f[i] += nd->pA[i];
        }
        /* the balance of forces (the linear rows): this body's terms, its
         * children's forces added at their turns */
        if (check) {
            const double *B = jt->I + KIN_PB, *C = jt->I + KIN_PC;
            const double t3 = B[0] * ac[0] + B[3] * ac[1] + B[6] * ac[2] + C[0] * ac[3] + C[1] * ac[4] + C[2] * ac[5];
            const double t4 = B[1] * ac[0] + B[4] * ac[1] + B[7] * ac[2] + C[1] * ac[3] + C[3] * ac[4] + C[4] * ac[5];
            const double t5 = B[2] * ac[0] + B[5] * ac[1] + B[8] * ac[2] + C[2] * ac[3] + C[4] * ac[4] + C[5] * ac[5];
            const double fl = fabs(f[3]) + fabs(f[4]) + fabs(f[5]);
            const double sc = fabs(t3) + fabs(t4) + fabs(t5) + C[0] * gn + fl;
            const double f6 = (fabs(f[0]) + fabs(f[1]) + fabs(f[2])) * il + fl;
            const unsigned char kin = a->kin[k];
            const double e = kin_joint_residual(L, jt, f, il, NULL); /* Q - S^T f, torques by 1/l */
            if (sc > tsum) tsum = sc;
            if (fl > flmax) flmax = fl;
            if (f6 > f6max) f6max = f6;
            if (!(e <= emax)) emax = e; /* NaN too */
            b[0] = t3 - f[3];
            b[1] = t4 - f[4];
            b[2] = t5 - f[5];
            if (a->need[k]) {
                const double *fe = m->comp_force + 6 * (size_t)jt->comp;
                a->need[k] = 0;
                for (i = 0; i < 3; i++) b[i] -= fe[3 + i];
            }
            if (kin & ABA_LEAF) { /* complete: no child adds to it */
                const double v = fabs(b[0]) + fabs(b[1]) + fabs(b[2]);
                if (v > bmax) bmax = v;
                bad |= v != v;
                memset(b, 0, sizeof nd->pA); /* ready for the next backward pass */
            }
            if (jt->parent >= 0) {
                const double *R = nd->X.R;
                double *bp = a->node[jt->parent].pA;
                bp[0] += R[0] * f[3] + R[1] * f[4] + R[2] * f[5];
                bp[1] += R[3] * f[3] + R[4] * f[4] + R[5] * f[5];
                bp[2] += R[6] * f[3] + R[7] * f[4] + R[8] * f[5];
                if (kin & ABA_LAST) { /* the parent's balance is complete */
                    const double v = fabs(bp[0]) + fabs(bp[1]) + fabs(bp[2]);
                    if (v > bmax) bmax = v;
                    bad |= v != v;
                    memset(bp, 0, sizeof nd->pA);
                }
            }
        } else {
            memset(b, 0, sizeof nd->pA); /* ready for the next backward pass */
        }
        memcpy(nd->IA, jt->I, sizeof nd->IA); /* ready for the next backward pass */
    }
    if (!check) return 0.0;
    if (bad || emax != emax) return NAN;
    /* the projection, against the largest joint force, unless the joint
     * forces are below 2^-20 of the terms (a free fall's are rounding noise) */
    bal = flmax >= 0x1p-20 * tsum && f6max > 0.0 ? emax / (ABA_PROJ_SCALE * f6max) : 0.0;
    /* the balance's scale: the largest term, or 16x the largest joint force
     * where that is smaller, unless the joint forces are below 2^-10 of the
     * terms */
    if (flmax >= 0x1p-10 * tsum && ABA_FORCE_SCALE * flmax < tsum) tsum = ABA_FORCE_SCALE * flmax;
    if (tsum > 0.0) bal = fmax(bal, bmax / tsum);
    else if (bmax > 0.0) bal = INFINITY;
    return bal;
}

/* Fixed joints: dca_welded_forces_comp takes a composite's leaf handle
 * forces, so form them (in L->aba.x, not in the tree, whose coefficients may
 * not even be allocated) from the joint forces just computed: the force on
 * the composite through handle h, in the handle's frame (its own frame for
 * its parent joint, the joint frame for a joint it holds up). */
void aba_welded_forces(aqs_linkage *L)
{
    const model *m = &L->m;
    const tree *t = &L->t;
    int32_t c, h, i;
    if (m->nwelded == 0) return;
    AQS_ASSERT(t->poses != NULL); /* the leaves' handle poses: allocated at finalize */
    for (c = 0; c <= m->ncomp; c++) {
        const node *leaf;
        double *x;
        if (!m->comp_welded[c]) continue;
        leaf = &t->nodes[t->leaf_of_comp[c]];
        x = L->aba.x;
        for (h = 0; h < leaf->nh; h++) {
            int32_t e = t->handles[leaf->handles + h];
            const double *f = L->cforce + 6 * (size_t)m->eff_joint[e];
            if (m->eff_child[e] == c) {
                memcpy(x + 6 * h, f, 6 * sizeof(double));
            } else {
                const joint_def *jd = &L->joints[m->eff_joint[e]];
                double fj[6];
                pose J;
                joint_child_pose_aligned(jd, L->q + jd->qoff, &J); /* handle frames: the aligned ones */
                spatial_xform_force_back(&J, f, fj);
                for (i = 0; i < 6; i++) x[6 * h + i] = -fj[i];
            }
        }
        dca_welded_forces_comp(L, c, x);
    }
}

/* The loads into the composites' frames and the backward pass (the factors
 * IA, U, D and the bias forces), counted by the work meter. */
static aqs_status factor(aqs_linkage *L)
{
    aqs_status st;
    /* World poses for the loads: from the sweep when the tree's are stale
     * (the tree's take O(log N) per loaded body when current). */
    int world = L->loads_dirty && L->nloaded > 0 && L->t.poses_stale;
    if (L->aba.dirty) reset_nodes(L);
    if (world) world_for_loads(L);
    L->aba.world_valid = world;
    update_loads(L); /* the composites' loads in their frames */
    L->aba.world_valid = 0;
    cost_count_joints(L, COST_ABA_JOINT);
    if ((st = backward(L)) != AQS_OK) L->aba.dirty = 1; /* IA / pA partly accumulated, marks left in need[] */
    return st;
}

int32_t aba_polish(aqs_linkage *L, const double *start, double level)
{
    const size_t nvb = sizeof(double) * (size_t)L->nv;
    char saved[sizeof L->error];
    double d = 0.0, m = 0.0;
    int32_t kept = 0, i;
    memcpy(saved, L->error, sizeof saved);
    if (factor(L) != AQS_OK) {
        memcpy(L->error, saved, sizeof saved); /* a singular articulated inertia: not the solve's failure */
        return -1;
    }
    (void)forward(L, 0); /* the factors' own answer, pA cleared for the corrections */
    for (i = 0; i < L->nv; i++) {
        d = fmax(d, fabs(L->qdd[i] - start[i]));
        m = fmax(m, fabs(start[i]));
    }
    memcpy(L->qdd, start, nvb);
    /* as an unbalanced solve's refinement (its forces refined too) */
    kept = aba_refine(L, 1.0, 1);
    if (L->aba.lost) return -1;
    if (kept > 0 && !(aba_refine_residual(L) <= level)) return -1; /* the DCA's accelerations were better */
    /* the accelerations as the DCA gave them: the forces of factors whose
     * own answer agrees with them, where they corrected something */
    if (kept == 0 && (L->aba.fkept == 0 || !(d <= ABA_POLISH_AGREE * RND_U * m))) return -1;
    L->aba.x_valid = 1;
    aba_welded_forces(L);
    L->aba.x_valid = 0;
    return kept;
}

aqs_status aba_solve(aqs_linkage *L)
{
    aqs_status st;
    if ((st = factor(L)) != AQS_OK) return st;
    {
        double bal = forward(L, L->refine_max > 0);
        /* a heavy child on a light parent: the balance, formed with the
         * solve's own forces, can miss the light links' mode (docs/math.md
         * 5b, "Where it loses digits its check does not see"): such a solve
         * is always refined */
        L->s.refined = aba_refine(L, bal, L->m.heavy_ratio > AQS_HEAVY_CHILD_ABA);
    }
    L->aba.x_valid = 1;
    aba_welded_forces(L);
    L->aba.x_valid = 0;
    adaptive_mark_exact(L);
    L->t.nodes_updated = 0;
    L->t.factors_updated = 0;
    return AQS_OK;
}
