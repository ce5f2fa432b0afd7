/* worldbound.c -- the bound of the world-space error measures (docs/math.md
 * §10b). For body b (centre of mass p_b, length scale ell_b) the measure is
 * e_b = |delta a_lin(b)| + ell_b |delta alpha(b)|, the error caused by the
 * joints a solve did not compute. Joint j (motion subspace S_j at its child
 * frame origin o_j) moves b's centre of mass by S_lin qdd + S_ang qdd x
 * (p_b - o_j), so for a queued node n (all its joints uncomputed)
 *   contribution_n(b) <= sum_{j in n} |qdd_j| (sigma_lin_j + sigma_ang_j rho_n)
 *                     <= sqrt(A(n)) (sqrt(SL_n) + rho_n sqrt(SA_n)) = E_n
 * (Cauchy-Schwarz, then Minkowski), with rho_n >= |p_b - o_j| + ell_b over
 * the bodies b the joints of n move: from n's sphere when they all lie in n,
 * else from n's and the root's spheres. max_b e_b <= sum_{queued} E_n. */
#include "worldbound.h"

#include <math.h>
#include <string.h>

#include "dense.h"

int worldbound_active(const aqs_linkage *L)
{
    return L->wb != NULL && (L->s.metric == AQS_METRIC_ABS_WORLD || L->s.metric == AQS_METRIC_REL_WORLD);
}

void worldbound_free(aqs_linkage *L)
{
    struct worldbound *w = L->wb;
    if (!w) return;
    lk_free(L, w->sph);
    lk_free(L, w->sl2);
    lk_free(L, w->sa2);
    lk_free(L, w->lmax);
    lk_free(L, w->holds);
    lk_free(L, w->wpose);
    lk_free(L, w->ell);
    lk_free(L, w);
    L->wb = NULL;
}


/* Largest singular value of rows [r0, r0 + 3) of S (6 x d), bounded by
 * Gershgorin on the d x d Gram matrix (exact for orthogonal columns). */
static double sigma_rows(const double *S, int d, int r0)
{
    double best = 0.0;
    int i, j, r;
    for (i = 0; i < d; i++) {
        double row = 0.0;
        for (j = 0; j < d; j++) {
            double g = 0.0;
            for (r = r0; r < r0 + 3; r++) g += S[r * d + i] * S[r * d + j];
            row += fabs(g);
        }
        if (row > best) best = row;
    }
    return sqrt(best) * (1.0 + 1e-15);
}

/* A leaf's sphere in its composite's frame: the frame origin (the origin of
 * the composite's parent joint) and the members' centres of mass. */
static void leaf_sphere(const aqs_linkage *L, int32_t c, double *s, double *lmax)
{
    const model *m = &L->m;
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0}, r = 0.0;
    int32_t k, i;
    *lmax = 0.0;
    if (c == m->ncomp) { /* the world: nothing moves */
        s[0] = s[1] = s[2] = 0.0;
        s[3] = -1.0;
        return;
    }
    for (k = m->member_start[c]; k < m->member_start[c + 1]; k++) {
        int32_t b = m->members[k];
        double p[3];
        mat3_vec(model_body_in_comp(m, b)->R, L->bodies[b].com, p);
        for (i = 0; i < 3; i++) {
            p[i] += model_body_in_comp(m, b)->p[i];
            if (p[i] < lo[i]) lo[i] = p[i];
            if (p[i] > hi[i]) hi[i] = p[i];
        }
        if (L->wb->ell[b] > *lmax) *lmax = L->wb->ell[b];
    }
    for (i = 0; i < 3; i++) s[i] = 0.5 * (lo[i] + hi[i]);
    r = sqrt(vec3_dot(s, s));
    for (k = m->member_start[c]; k < m->member_start[c + 1]; k++) {
        int32_t b = m->members[k];
        double p[3], d;
        mat3_vec(model_body_in_comp(m, b)->R, L->bodies[b].com, p);
        for (i = 0; i < 3; i++) p[i] += model_body_in_comp(m, b)->p[i];
        d = vec3_dist(p, s);
        if (d > r) r = d;
    }
    s[3] = r * (1.0 + 1e-12);
}

aqs_status worldbound_enable(aqs_linkage *L, const char *fn)
{
    tree *t = &L->t;
    struct worldbound *w;
    size_t nn = (size_t)t->nnodes + 1;
    int32_t *size, n, b, h;
    if (L->wb) return AQS_OK;
    w = lk_calloc(L, 1, sizeof *w);
    if (!w) return lk_fail(L, AQS_ENOMEM, "%s: out of memory (world-space bound)", fn);
    L->wb = w;
    w->sph = lk_calloc(L, 4 * nn, sizeof(double));
    w->sl2 = lk_calloc(L, nn, sizeof(double));
    w->sa2 = lk_calloc(L, nn, sizeof(double));
    w->lmax = lk_calloc(L, nn, sizeof(double));
    w->holds = lk_calloc(L, nn, 1);
    w->wpose = lk_calloc(L, nn, sizeof(pose));
    w->ell = lk_calloc(L, (size_t)L->nbodies + 1, sizeof(double));
    size = lk_calloc(L, nn, sizeof(int32_t));
    if (!w->sph || !w->sl2 || !w->sa2 || !w->lmax || !w->holds || !w->wpose || !w->ell || !size) {
        lk_free(L, size);
        worldbound_free(L);
        return lk_fail(L, AQS_ENOMEM, "%s: out of memory (world-space bound)", fn);
    }
    for (b = 0; b < L->nbodies; b++) {
        const body_def *bd = &L->bodies[b];
        double tr = bd->inertia[0] + bd->inertia[4] + bd->inertia[8];
        w->ell[b] = bd->mass > 0.0 && tr > 0.0 ? sqrt(tr / (2.0 * bd->mass)) : 0.0;
    }
    /* Children first (post-order: a child's index is below its parent's). */
    for (n = 0; n < t->nnodes; n++) {
        const node *nd = &t->nodes[n];
        size[n] = 1;
        if (nd->joint < 0) {
            leaf_sphere(L, nd->comp, w->sph + 4 * n, &w->lmax[n]);
            continue;
        }
        size[n] += size[nd->a] + size[nd->b];
        w->sph[4 * n + 3] = -1.0; /* computed by the update (the caller marks every node) */
        w->lmax[n] = fmax(w->lmax[nd->a], w->lmax[nd->b]);
        w->sl2[n] = w->sl2[nd->a] + w->sl2[nd->b];
        w->sa2[n] = w->sa2[nd->a] + w->sa2[nd->b];
        {
            const joint_def *jd = &L->joints[L->m.eff_joint[nd->joint]];
            if (jd->type != AQS_JOINT_FREE) {
                double S[36] = {0}, sl, sa;
                int d = joint_nv(jd->type);
                joint_subspace(jd, L->q + jd->qoff, S);
                sa = sigma_rows(S, d, 0);
                sl = sigma_rows(S, d, 3);
                w->sl2[n] += sl * sl;
                w->sa2[n] += sa * sa;
            }
        }
    }
    /* holds[n]: a handle e of n whose child composite lies outside n's
     * subtree, i.e. n holds e up and what hangs beyond it moves with n's
     * joints. n's subtree is the index range (n - size[n], n]. */
    for (n = 0; n < t->nnodes; n++) {
        const node *nd = &t->nodes[n];
        for (h = 0; h < nd->nh; h++) {
            int32_t e = t->handles[nd->handles + h];
            int32_t leaf = t->leaf_of_comp[L->m.eff_child[e]];
            if (leaf <= n - size[n] || leaf > n) w->holds[n] = 1;
        }
    }
    lk_free(L, size);
    return AQS_OK;
}

/* Pose of B's frame in C's frame (as src/solve/frames.c). */
static void child_frame(const aqs_linkage *L, const node *C, pose *Pk)
{
    const tree *t = &L->t;
    pose_compose(&t->poses[t->nodes[C->a].poses + C->ka], t->poses + nd_J(C), Pk);
}

void worldbound_node_update(aqs_linkage *L, int32_t n)
{
    struct worldbound *w = L->wb;
    const node *C = &L->t.nodes[n];
    const double *sb = w->sph + 4 * C->b;
    double tb[4];
    pose Pk;
    child_frame(L, C, &Pk);
    mat3_vec(Pk.R, sb, tb);
    tb[0] += Pk.p[0];
    tb[1] += Pk.p[1];
    tb[2] += Pk.p[2];
    tb[3] = sb[3];
    sphere_merge(w->sph + 4 * C->a, tb, w->sph + 4 * n);
}

void worldbound_begin(aqs_linkage *L)
{
    struct worldbound *w = L->wb;
    if (L->t.nnodes > 0) pose_identity(&w->wpose[L->t.root]);
    w->lower = 0.0;
}

/* Composite c's exact spatial acceleration minus g (its frame) from its
 * leaf's handle forces: Newton's law, as dca.c's comp_acceleration. */
static void comp_accel(const aqs_linkage *L, int32_t leaf, double a[6])
{
    const tree *t = &L->t;
    const node *nd = &t->nodes[leaf];
    const pose *P = t->poses + nd->poses;
    const double *x = t->data + nd_xf(nd);
    double f[6], tmp[6];
    int32_t h, i;
    memcpy(f, L->m.comp_force + 6 * nd->comp, sizeof f);
    for (h = 0; h < nd->nh; h++) {
        spatial_xform_force_back(&P[h], x + 6 * h, tmp);
        for (i = 0; i < 6; i++) f[i] += tmp[i];
    }
    dense_matvec(L->m.comp_inverse + 36 * nd->comp, f, a, 6, 6);
}

/* The reached leaf's bodies: their accelerations are exact (the leaf's
 * handle forces are), so max_b e(a_b) over them is a lower bound on the
 * largest over all bodies. a = (a - g) + R^T g: the true acceleration. */
static void leaf_lower(aqs_linkage *L, int32_t leaf)
{
    struct worldbound *w = L->wb;
    const model *m = &L->m;
    int32_t c = L->t.nodes[leaf].comp, k;
    double a[6], g[3];
    if (c == m->ncomp) return;
    comp_accel(L, leaf, a);
    mat3_tvec(w->wpose[leaf].R, L->gravity, g);
    a[3] += g[0];
    a[4] += g[1];
    a[5] += g[2];
    for (k = m->member_start[c]; k < m->member_start[c + 1]; k++) {
        int32_t b = m->members[k];
        double r[3], al[3], e;
        mat3_vec(model_body_in_comp(m, b)->R, L->bodies[b].com, r);
        r[0] += model_body_in_comp(m, b)->p[0];
        r[1] += model_body_in_comp(m, b)->p[1];
        r[2] += model_body_in_comp(m, b)->p[2];
        vec3_cross(a, r, al);
        al[0] += a[3];
        al[1] += a[4];
        al[2] += a[5];
        e = sqrt(vec3_dot(al, al)) + w->ell[b] * sqrt(vec3_dot(a, a));
        e *= 1.0 - 1e-12; /* the rounding of these few operations */
        if (e > w->lower) w->lower = e;
    }
}

void worldbound_processed(aqs_linkage *L, int32_t n)
{
    struct worldbound *w = L->wb;
    const node *C = &L->t.nodes[n];
    pose Pk;
    child_frame(L, C, &Pk);
    w->wpose[C->a] = w->wpose[n];
    pose_compose(&w->wpose[n], &Pk, &w->wpose[C->b]);
    if (L->s.metric != AQS_METRIC_REL_WORLD) return; /* only the relative form needs L_w */
    if (L->t.nodes[C->a].joint < 0) leaf_lower(L, C->a);
    if (L->t.nodes[C->b].joint < 0) leaf_lower(L, C->b);
}

double worldbound_key(const aqs_linkage *L, int32_t n, double a)
{
    const struct worldbound *w = L->wb;
    const double *s = w->sph + 4 * n;
    double R = s[3] > 0.0 ? s[3] : 0.0, rho = 2.0 * R + w->lmax[n];
    if (a <= 0.0) return 0.0;
    if (w->holds[n]) {
        /* bodies beyond n's held handles: anywhere in the root's sphere */
        const double *s0 = w->sph + 4 * L->t.root;
        const pose *P = &w->wpose[n];
        double c[3], far;
        mat3_vec(P->R, s, c);
        c[0] += P->p[0];
        c[1] += P->p[1];
        c[2] += P->p[2];
        far = R + vec3_dist(c, s0) + (s0[3] > 0.0 ? s0[3] : 0.0) + w->lmax[L->t.root];
        if (far > rho) rho = far;
    }
    return sqrt(a) * (sqrt(w->sl2[n]) + rho * sqrt(w->sa2[n])) * (1.0 + 1e-12);
}
