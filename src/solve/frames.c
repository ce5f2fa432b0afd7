/* frames.c -- hierarchical frames (MATH.md §9.2): the handle poses of the
 * assembly tree's nodes, world poses on request, and a body load re-expressed
 * in its composite's frame. Split out of update.c so that dca.c, which needs
 * the world poses, and update.c, which calls dca.c, call downward. */
#include "frames.h"

#include "collide.h"
#include "invariant.h"

void frames_leaf(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    const node *nd = &t->nodes[n];
    pose *P = t->poses + nd->poses;
    int32_t i;
    for (i = 0; i < nd->nh; i++) {
        int32_t e = t->handles[nd->handles + i];
        if (L->m.eff_child[e] == nd->comp) pose_identity(&P[i]); /* hangs from e: own frame */
        else P[i] = L->m.eff_place[e];                             /* holds e up: joint frame */
    }
}

/* Pose of B's frame (the child frame of k) in C's frame, from the stored
 * J(q_k) (refreshed by frames_node whenever q_k changes). */
static void child_frame_in_node(const aqs_linkage *L, const node *C, pose *out)
{
    const tree *t = &L->t;
    const pose *PA = t->poses + t->nodes[C->a].poses;
    pose_compose(&PA[C->ka], t->poses + C->J, out);
}

void frames_node(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    const node *C = &t->nodes[n], *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const pose *PA = t->poses + A->poses, *PB = t->poses + B->poses;
    const joint_def *jd = &L->joints[L->m.eff_joint[C->joint]];
    pose *P = t->poses + C->poses, Pk;
    int32_t i, ci = 0;
    joint_child_pose(jd, L->q + jd->qoff, t->poses + C->J); /* J(q_k), used by dca.c too */
    child_frame_in_node(L, C, &Pk);
    for (i = 0; i < A->nh; i++)
        if (i != C->ka) P[ci++] = PA[i];
    for (i = 0; i < B->nh; i++)
        if (i != C->kb) pose_compose(&Pk, &PB[i], &P[ci++]);
    AQS_ASSERT(ci == C->nh && C->nh == A->nh + B->nh - 2); /* the joined handles drop out */
    if (L->col) broadphase_node_moved(L, n); /* collision: refit its bounding sphere */
}

void frames_all(aqs_linkage *L)
{
    int32_t n;
    for (n = 0; n < L->t.nnodes; n++)
        if (L->t.nodes[n].joint >= 0) frames_node(L, n);
}

void frames_from_joint(aqs_linkage *L, int32_t e)
{
    int32_t n = L->t.node_of_eff[e];
    for (; n >= 0; n = L->t.nodes[n].parent) frames_node(L, n);
}

void frames_comp_world(const aqs_linkage *L, int32_t comp, pose *P)
{
    const tree *t = &L->t;
    int32_t n, parent;
    pose_identity(P);
    if (comp == L->m.ncomp || t->nnodes == 0) return;
    /* Walk up: a B child's frame is its parent's frame times A's handle k
     * times J(q_k); an A child shares its parent's frame. */
    for (n = t->leaf_of_comp[comp]; (parent = t->nodes[n].parent) >= 0; n = parent) {
        const node *C = &t->nodes[parent];
        if (C->b == n) {
            pose Pk, tmp;
            child_frame_in_node(L, C, &Pk);
            pose_compose(&Pk, P, &tmp);
            *P = tmp;
        }
    }
}

void frames_body_world(const aqs_linkage *L, int32_t body, pose *P)
{
    pose C;
    frames_comp_world(L, L->m.comp_of_body[body], &C);
    pose_compose(&C, &L->m.body_in_comp[body], P);
}

void frames_all_bodies_world(const aqs_linkage *L, pose *out)
{
    int32_t k;
    for (k = 0; k < L->nbodies; k++) {
        int32_t b = L->m.order[k];
        const joint_def *jd = &L->joints[L->m.parent_joint[b]];
        pose place, J, jp;
        pose_from_quat(jd->pos, jd->quat, &place);
        joint_child_pose(jd, L->q + jd->qoff, &J);
        pose_compose(&place, &J, &jp);
        if (jd->parent == AQS_WORLD) out[b] = jp;
        else pose_compose(&out[jd->parent], &jp, &out[b]);
    }
}

void frames_load_in_comp(const aqs_linkage *L, int32_t body, const pose *comp_world,
                         double f[6])
{
    const body_load *ld = &L->loads[body];
    const pose *bc = &L->m.body_in_comp[body];
    double r[3], n[3];
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
