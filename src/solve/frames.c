/* frames.c -- hierarchical frames (MATH.md §9.2): the handle poses of the
 * assembly tree's nodes, world poses on request, and a body load re-expressed
 * in its composite's frame. Split out of update.c so that dca.c, which needs
 * the world poses, and update.c, which calls dca.c, call downward. */
#include "frames.h"

#include "collide.h"
#include "check.h"
#include "invariant.h"
#include "kintree.h"
#include "stale.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

/* out = a b, the operations of pose_compose (src/base/spatial.c) in its
 * order: R's columns 0 and 1 two at a time under SSE2 (each lane the scalar
 * sum a_i0 b_0j + a_i1 b_1j + a_i2 b_2j), the rest scalar. out must not be
 * a or b. */
static void compose(const pose *a, const pose *b, pose *out)
{
    const double *A = a->R, *B = b->R;
    int i;
#if defined(__SSE2__)
    const __m128d b0 = _mm_loadu_pd(B), b1 = _mm_loadu_pd(B + 3), b2 = _mm_loadu_pd(B + 6);
    for (i = 0; i < 3; i++) {
        const double a0 = A[3 * i], a1 = A[3 * i + 1], a2 = A[3 * i + 2];
        _mm_storeu_pd(out->R + 3 * i, _mm_add_pd(_mm_add_pd(_mm_mul_pd(_mm_set1_pd(a0), b0), _mm_mul_pd(_mm_set1_pd(a1), b1)),
                                                 _mm_mul_pd(_mm_set1_pd(a2), b2)));
        out->R[3 * i + 2] = a0 * B[2] + a1 * B[5] + a2 * B[8];
    }
#else
    for (i = 0; i < 3; i++) {
        int j;
        for (j = 0; j < 3; j++) out->R[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
    }
#endif
    for (i = 0; i < 3; i++) out->p[i] = a->p[i] + (A[3 * i] * b->p[0] + A[3 * i + 1] * b->p[1] + A[3 * i + 2] * b->p[2]);
}

void frames_world_frame(const aqs_linkage *L, pose *W)
{
    const tree *t = &L->t;
    const node *nd;
    pose_identity(W);
    if (t->nnodes == 0) return;
    nd = &t->nodes[t->leaf_of_comp[L->m.ncomp]];
    /* its orientation only: the world's origin stays the origin, so that
     * other roots near it keep their small coordinates however far the
     * first one is */
    if (nd->nh > 0) memcpy(W->R, kin_eff_place(L, t->handles[nd->handles])->R, sizeof W->R);
}

/* Handle-frame poses of a leaf in its composite's frame (constant); the
 * world leaf's in world_frame, its first handle's. */
static void frames_leaf(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    const node *nd = &t->nodes[n];
    pose *P = t->poses + nd->poses, Wi;
    int32_t i;
    const int world = nd->comp == L->m.ncomp;
    if (world) pose_inverse(&t->world_frame, &Wi); /* set at finalize */
    for (i = 0; i < nd->nh; i++) {
        int32_t e = t->handles[nd->handles + i];
        if (L->m.eff_child[e] == nd->comp) pose_identity(&P[i]); /* hangs from e: own frame */
        else if (!world) P[i] = *kin_eff_place(L, e);              /* holds e up: joint frame */
        else if (i > 0) pose_compose(&Wi, kin_eff_place(L, e), &P[i]); /* in world_frame */
        else { /* the first: turned as world_frame, exactly */
            pose_identity(&P[0]);
            mat3_tvec(t->world_frame.R, kin_eff_place(L, e)->p, P[0].p);
        }
    }
}

void frames_leaf_handle(const aqs_linkage *L, int32_t leaf, int32_t h, pose *P)
{
    const tree *t = &L->t;
    const node *nd = &t->nodes[leaf];
    if (nd->comp == L->m.ncomp) pose_compose(&t->world_frame, &t->poses[nd->poses + h], P);
    else *P = t->poses[nd->poses + h];
}

/* Pose of B's frame (the child frame of k) in C's frame, from the stored
 * J(q_k) (refreshed by frames_node whenever q_k changes). */
static void child_frame_in_node(const aqs_linkage *L, const node *C, pose *out)
{
    const tree *t = &L->t;
    const pose *PA = t->poses + t->nodes[C->a].poses;
    compose(&PA[C->ka], t->poses + nd_J(C), out);
}

void frames_node(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    const node *C = &t->nodes[n], *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const pose *PA = t->poses + A->poses, *PB = t->poses + B->poses;
    const joint_def *jd = &L->joints[L->m.eff_joint[C->joint]];
    pose *P = t->poses + C->poses, Pk;
    int32_t i, ci = 0;
    joint_child_pose_aligned(jd, L->q + jd->qoff, t->poses + nd_J(C)); /* J(q_k) in the aligned frames, used by dca.c too */
    child_frame_in_node(L, C, &Pk);
    for (i = 0; i < A->nh; i++)
        if (i != C->ka) P[ci++] = PA[i];
    for (i = 0; i < B->nh; i++)
        if (i != C->kb) compose(&Pk, &PB[i], &P[ci++]);
    AQS_ASSERT(ci == C->nh && C->nh == A->nh + B->nh - 2); /* the joined handles drop out */
    if (collide_has_shapes(L)) broadphase_node_moved(L, n); /* collision: refit its bounding sphere */
}

/* All internal nodes' cross poses, children first. O(N). */
static void frames_all(aqs_linkage *L)
{
    int32_t n;
    for (n = 0; n < L->t.nnodes; n++)
        if (L->t.nodes[n].joint >= 0) frames_node(L, n);
}

void frames_from_joint(aqs_linkage *L, int32_t e)
{
    int32_t n = L->t.node_of_eff[e];
    if (L->t.poses_stale) return; /* recomputed in full when read */
    for (; n >= 0; n = L->t.nodes[n].parent) frames_node(L, n);
}

void frames_positions_moved(aqs_linkage *L)
{
    if (collide_has_shapes(L)) frames_all(L); /* shapes follow every move */
    else stale_poses(L);
    stale_positions(L, -1);
}

aqs_status frames_poses_alloc(aqs_linkage *L)
{
    tree *t = &L->t;
    int32_t n;
    if (t->poses) return AQS_OK;
    t->poses = lk_calloc_in(L, LK_MEM_TREE, (size_t)t->nposes + 1, sizeof(pose));
    if (!t->poses)
        return lk_fail(L, AQS_ENOMEM, "out of memory for the assembly tree's %lld poses", (long long)t->nposes);
    for (n = 0; n < t->nnodes; n++)
        if (t->nodes[n].joint < 0) frames_leaf(L, n);
    stale_poses(L);
    return AQS_OK;
}

aqs_status frames_poses(aqs_linkage *L)
{
    aqs_status st;
    if (!L->t.poses_stale) return AQS_OK;
    if ((st = frames_poses_alloc(L)) != AQS_OK) return st;
    frames_all(L);
    stale_poses_fresh(L);
    return AQS_OK;
}

void frames_comp_world(aqs_linkage *L, int32_t comp, pose *P)
{
    const tree *t = &L->t;
    int32_t n, parent;
    if (t->poses_stale && (!t->poses || L->aba.x_valid)) {
        /* no tree poses (never needed so far), or inside an exact solve:
         * up the kinematic tree from the positions, O(depth) */
        kin_comp_world_walk(L, comp, P);
        return;
    }
    pose_identity(P);
    if (comp == L->m.ncomp || t->nnodes == 0) return;
    (void)frames_poses(L); /* allocated: only recomputes (no failure) */
    /* Walk up: a B child's frame is its parent's frame times A's handle k
     * times J(q_k); an A child shares its parent's frame; the root's is the
     * world leaf's, world_frame. */
    for (n = t->leaf_of_comp[comp]; (parent = t->nodes[n].parent) >= 0; n = parent) {
        const node *C = &t->nodes[parent];
        if (C->b == n) {
            pose Pk, tmp;
            child_frame_in_node(L, C, &Pk);
            pose_compose(&Pk, P, &tmp);
            *P = tmp;
        }
    }
    {
        pose tmp;
        pose_compose(&t->world_frame, P, &tmp);
        *P = tmp;
    }
}

void frames_body_world(aqs_linkage *L, int32_t body, pose *P)
{
    pose C, B;
    frames_comp_world(L, L->m.comp_of_body[body], &C);
    kin_body_in_comp(L, body, &B);
    pose_compose(&C, &B, P);
}

void frames_load_in_comp(const aqs_linkage *L, int32_t body, const pose *comp_world,
                              double f[6])
{
    const body_load *ld = &L->loads[body];
    pose B;
    const pose *bc = &B;
    double r[3], n[3];
    kin_body_in_comp(L, body, &B);
    mat3_tvec(comp_world->R, ld->force, f + 3);
    mat3_tvec(comp_world->R, ld->torque, f);
    mat3_vec(bc->R, ld->point, r);
    r[0] += bc->p[0];
    r[1] += bc->p[1];
    r[2] += bc->p[2];
    vec3_cross(r, f + 3, n);
    f[0] += n[0];
    f[1] += n[1];
    f[2] += n[2];
}
