/* worldbound.c -- the bound of the world-space error measures (docs/math.md
 * §10b). For body b (centre of mass p_b, length scale ell_b) the measure is
 * e_b = |delta a_lin(b)| + ell_b |delta alpha(b)|, the error caused by the
 * joints a solve did not compute. Per queued node n (all its joints
 * uncomputed) a body is inside n, beyond exactly one handle n holds up, or
 * not moved by n's joints, so n's part is at most E_n = max(E_in, E_h):
 *   inside:  sum_{j on b's path in n} |qdd_j| (sigma_lin_j + rho_n sigma_ang_j)
 *            <= sqrt(A(n)) (sqrt(PL_n) + rho_n sqrt(PA_n))   (Cauchy-Schwarz on
 *            the path, Minkowski; PL, PA: the largest path sums of sigma^2,
 *            rho_n from n's sphere);
 *   beyond held handle h: the rigid motion D_h = a_h - a_entry, exact from
 *            n's coefficients at its handle forces, at the root sphere's
 *            radius: |D_lin(c_0)| + |D_ang| (R_0 + ellmax).
 * max_b e_b <= min(sum_{queued} E_n, max_{queued} E_n + sum_{queued} E_h) (a
 * body lies inside at most one queued node). The rounding estimate carries
 * every joint's estimated error to the bodies (worldbound_rounding), and
 * rel_world's lower bound less its own estimated error is lower_r. */
#include "worldbound.h"

#include <math.h>
#include <string.h>

#include "dense.h"
#include "kintree.h"
#include "model.h"
#include "rounding.h"

/* handles of a node for which the bound beyond held handles is evaluated
 * (larger nodes fall back to the spheres) */
#define AQS_WB_MAXH 64

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
    lk_free(L, w->hl2);
    lk_free(L, w->ha2);
    lk_free(L, w->holds);
    lk_free(L, w->size);
    lk_free(L, w->wpose);
    lk_free(L, w->ell);
    lk_free(L, w->beyond);
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
        pose B;
        kin_body_in_comp(L, b, &B);
        mat3_vec(B.R, L->bodies[b].com, p);
        for (i = 0; i < 3; i++) {
            p[i] += B.p[i];
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
        pose B;
        kin_body_in_comp(L, b, &B);
        mat3_vec(B.R, L->bodies[b].com, p);
        for (i = 0; i < 3; i++) p[i] += B.p[i];
        d = vec3_dist(p, s);
        if (d > r) r = d;
    }
    s[3] = r * (1.0 + 1e-12);
}

/* pl_all, pa_all: the largest sums of sigma_lin^2, sigma_ang^2 over the
 * non-fixed joints on one composite's path to the world, free ones left
 * out (at most one per path, its first: worldbound_rounding adds it
 * apart), in body order (parents first): the lever sums of the rounding
 * estimate (worldbound_rounding). */
static aqs_status all_paths(aqs_linkage *L, const char *fn)
{
    struct worldbound *w = L->wb;
    const model *m = &L->m;
    double *pl = lk_calloc_in(L, LK_MEM_WORLD, 2 * ((size_t)m->ncomp + 1), sizeof(double)), *pa;
    int32_t i;
    if (!pl) {
        worldbound_free(L);
        return lk_fail(L, AQS_ENOMEM, "%s: out of memory (world-space bound)", fn);
    }
    pa = pl + m->ncomp + 1;
    w->pl_all = w->pa_all = 0.0;
    for (i = 0; i < L->nbodies; i++) {
        const int32_t e = m->eff_of_joint[m->parent_joint[m->order[i]]];
        const joint_def *jd;
        double S[36] = {0};
        int32_t c, p, d;
        if (e < 0) continue; /* welded to its parent: the same composite */
        jd = &L->joints[m->eff_joint[e]];
        c = m->eff_child[e];
        p = m->eff_parent[e];
        if (jd->type == AQS_JOINT_FREE) { /* its parent is the world */
            pl[c] = pa[c] = 0.0;
            continue;
        }
        d = joint_nv(jd->type);
        joint_subspace_aligned(jd, L->q + jd->qoff, S);
        pl[c] = pl[p] + sigma_rows(S, d, 3) * sigma_rows(S, d, 3);
        pa[c] = pa[p] + sigma_rows(S, d, 0) * sigma_rows(S, d, 0);
        w->pl_all = fmax(w->pl_all, pl[c]);
        w->pa_all = fmax(w->pa_all, pa[c]);
    }
    lk_free(L, pl);
    return AQS_OK;
}

aqs_status worldbound_enable(aqs_linkage *L, const char *fn)
{
    tree *t = &L->t;
    struct worldbound *w;
    size_t nn = (size_t)t->nnodes + 1;
    int32_t *size, n, b, h;
    if (L->wb) return AQS_OK;
    w = lk_calloc_in(L, LK_MEM_WORLD, 1, sizeof *w);
    if (!w) return lk_fail(L, AQS_ENOMEM, "%s: out of memory (world-space bound)", fn);
    L->wb = w;
    w->sph = lk_calloc_in(L, LK_MEM_WORLD, 4 * nn, sizeof(double));
    w->sl2 = lk_calloc_in(L, LK_MEM_WORLD, nn, sizeof(double));
    w->sa2 = lk_calloc_in(L, LK_MEM_WORLD, nn, sizeof(double));
    w->lmax = lk_calloc_in(L, LK_MEM_WORLD, nn, sizeof(double));
    w->hl2 = lk_calloc_in(L, LK_MEM_WORLD, (size_t)t->nhandles + 1, sizeof(double));
    w->ha2 = lk_calloc_in(L, LK_MEM_WORLD, (size_t)t->nhandles + 1, sizeof(double));
    w->holds = lk_calloc_in(L, LK_MEM_WORLD, nn, 1);
    w->wpose = lk_calloc_in(L, LK_MEM_WORLD, nn, sizeof(pose));
    w->ell = lk_calloc_in(L, LK_MEM_WORLD, (size_t)L->nbodies + 1, sizeof(double));
    w->beyond = lk_calloc_in(L, LK_MEM_WORLD, nn, sizeof(double));
    size = w->size = lk_calloc_in(L, LK_MEM_WORLD, nn, sizeof(int32_t));
    if (!w->sph || !w->sl2 || !w->sa2 || !w->lmax || !w->hl2 || !w->ha2 || !w->holds || !w->wpose || !w->ell || !w->beyond || !size ||
        model_inverse_alloc(L) != AQS_OK) { /* comp_accel reads the inverse inertias */
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
        {
            const joint_def *jd = &L->joints[L->m.eff_joint[nd->joint]];
            double sl = 0.0, sa = 0.0;
            /* P: the side holding k (it holds n's entry or the world), Q: the side hanging from k */
            int32_t kleaf = t->leaf_of_comp[L->m.eff_child[nd->joint]];
            int32_t inA = kleaf > nd->a - size[nd->a] && kleaf <= nd->a;
            int32_t P = inA ? nd->b : nd->a, Q = inA ? nd->a : nd->b, kP = inA ? nd->kb : nd->ka;
            int32_t ci = 0, side;
            double bl, ba;
            if (jd->type != AQS_JOINT_FREE) {
                double S[36] = {0};
                int d = joint_nv(jd->type);
                joint_subspace_aligned(jd, L->q + jd->qoff, S);
                sa = sigma_rows(S, d, 0);
                sl = sigma_rows(S, d, 3);
            }
            /* the paths into Q: P's path to k, k, then Q's paths */
            bl = w->hl2[t->nodes[P].handles + kP] + sl * sl;
            ba = w->ha2[t->nodes[P].handles + kP] + sa * sa;
            w->sl2[n] = fmax(w->sl2[P], bl + w->sl2[Q]);
            w->sa2[n] = fmax(w->sa2[P], ba + w->sa2[Q]);
            /* n's handles, in the order [A-outer; B-outer] */
            for (side = 0; side < 2; side++) {
                int32_t c = side == 0 ? nd->a : nd->b, kc = side == 0 ? nd->ka : nd->kb;
                const node *cn = &t->nodes[c];
                for (h = 0; h < cn->nh; h++) {
                    if (h == kc) continue;
                    w->hl2[nd->handles + ci] = w->hl2[cn->handles + h] + (c == Q ? bl : 0.0);
                    w->ha2[nd->handles + ci] = w->ha2[cn->handles + h] + (c == Q ? ba : 0.0);
                    ci++;
                }
            }
        }
    }
    if (all_paths(L, fn) != AQS_OK) return AQS_ENOMEM;
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
    if (L->t.nnodes > 0) w->wpose[L->t.root] = L->t.world_frame; /* the root's frame: frames.h */
    w->lower = w->lower_r = 0.0;
}

/* The linkage's length scale l (model.length, docs/math.md §10a "The unit
 * of length"): the rounding terms below weigh the angular and linear parts
 * of spatial vectors by it, as rounding.c does, so that each scales by one
 * factor under a change of the unit of length (docs/math.md §10b, "The unit
 * of length"). */
static double length_of(const aqs_linkage *L) { return L->m.length > 0.0 ? L->m.length : 1.0; }
/* A force [n; f] as |(n/l, f)| (il = 1/l; N), as rounding.c's n6f. */
static double n6f(const double *v, double il)
{
    const double x = v[0] * il, y = v[1] * il, z = v[2] * il;
    return sqrt(x * x + y * y + z * z + v[3] * v[3] + v[4] * v[4] + v[5] * v[5]);
}

/* Composite c's exact spatial acceleration minus g (its frame) from its
 * leaf's handle forces: Newton's law, as dca.c's comp_acceleration. *err:
 * the estimated error of a = [alpha; a_lin] as |(alpha, a_lin / l)| (so
 * |delta alpha| <= err, |delta a_lin| <= l err), from the handle forces'
 * estimated errors (tree.rnd_x, as |(n/l, f)|: rounding.c's n6f), carried
 * by X_h^T (|X_h^T v| <= (1 + |p_h| / l) |v| in that norm) and the
 * products' rounding, through the inverse inertia in the same norms (the
 * Frobenius norm of diag(1, 1/l) I^-1 diag(l, 1): every entry in
 * 1/(kg m)); the inverse inertia is data, as for the leaf coefficients
 * (docs/math.md §10a). +inf without the estimate's storage. */
static void comp_accel(const aqs_linkage *L, int32_t leaf, double a[6], double *err)
{
    const tree *t = &L->t;
    const node *nd = &t->nodes[leaf];
    const pose *P = t->poses + nd->poses;
    const double *x = t->data + nd_xf(nd), *Ii = L->m.comp_inverse + 36 * nd->comp;
    const double l = length_of(L), il = 1.0 / l;
    double f[6], tmp[6], ef = 0.0, mag, ni = 0.0;
    int32_t h, i;
    memcpy(f, L->m.comp_force + 6 * nd->comp, sizeof f);
    mag = n6f(f, il);
    for (h = 0; h < nd->nh; h++) {
        spatial_xform_force_back(&P[h], x + 6 * h, tmp);
        for (i = 0; i < 6; i++) f[i] += tmp[i];
        mag += n6f(tmp, il);
        if (t->rnd_x) ef += (1.0 + sqrt(vec3_dot(P[h].p, P[h].p)) * il) * t->rnd_x[nd->handles + h];
    }
    dense_matvec(Ii, f, a, 6, 6);
    { /* the blocks: angular rows (1) by torque columns (l), the off-diagonal ones (1), linear rows (1/l) by force columns (1) */
        double saa = 0.0, sx = 0.0, sll = 0.0;
        for (h = 0; h < 3; h++)
            for (i = 0; i < 3; i++) {
                const double aa = Ii[6 * h + i], al = Ii[6 * h + 3 + i], la = Ii[6 * (h + 3) + i], ll = Ii[6 * (h + 3) + 3 + i];
                saa += aa * aa;
                sx += al * al + la * la;
                sll += ll * ll;
            }
        ni = l * l * saa + sx + il * il * sll;
    }
    *err = t->rnd_x ? sqrt(ni) * (ef + RND_SAFETY * RND_U * 16.0 * mag) : INFINITY;
}

/* The reached leaf's bodies: their accelerations are exact (the leaf's
 * handle forces are), so max_b e(a_b) over them is a lower bound on the
 * largest over all bodies. a = (a - g) + R^T g: the true acceleration. */
static void leaf_lower(aqs_linkage *L, int32_t leaf)
{
    struct worldbound *w = L->wb;
    const model *m = &L->m;
    int32_t c = L->t.nodes[leaf].comp, k;
    const double l = length_of(L);
    double a[6], g[3], ea;
    if (c == m->ncomp) return;
    comp_accel(L, leaf, a, &ea);
    mat3_tvec(w->wpose[leaf].R, L->gravity, g);
    a[3] += g[0];
    a[4] += g[1];
    a[5] += g[2];
    for (k = m->member_start[c]; k < m->member_start[c + 1]; k++) {
        int32_t b = m->members[k];
        double r[3], al[3], e;
        pose B;
        kin_body_in_comp(L, b, &B);
        mat3_vec(B.R, L->bodies[b].com, r);
        r[0] += B.p[0];
        r[1] += B.p[1];
        r[2] += B.p[2];
        vec3_cross(a, r, al);
        al[0] += a[3];
        al[1] += a[4];
        al[2] += a[5];
        e = sqrt(vec3_dot(al, al)) + w->ell[b] * sqrt(vec3_dot(a, a));
        e *= 1.0 - 1e-12; /* the rounding of these few operations */
        if (e > w->lower) w->lower = e;
        /* |delta a_lin + delta alpha x r| + ell |delta alpha| <= ea (l + |r| + ell) */
        e -= ea * (l + sqrt(vec3_dot(r, r)) + w->ell[b]);
        if (e > w->lower_r) w->lower_r = e;
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

/* Handle i's acceleration (minus g, in the handle's frame) less the
 * subassembly's common rigid motion G_i I^-1 G^T x, which is the same rigid
 * motion at every handle and cancels from the relative accelerations
 * (square-root form: Lambda_i (Lambda^T x) + b_i; the inverse-inertia form
 * keeps it: Phi_i x + b_i). mag: a sum of absolute values of the terms (a
 * scale for the rounding), the linear rows' divided by l (il = 1/l: all in
 * 1/s^2, as rounding.c's n6m). lw, lwa: Lambda^T x and |Lambda|^T |x|. */
static void handle_acc(const aqs_linkage *L, int32_t n, const double *lw, const double *lwa, int32_t i,
                       double il, double out[6], double *mag)
{
    const tree *t = &L->t;
    const node *nd = &t->nodes[n];
    const double *b = t->data + nd->bv + 6 * i, *x = t->data + nd_xf(nd);
    int32_t r, k;
    for (r = 0; r < 6; r++) {
        double s = b[r], m = fabs(b[r]);
        if (L->dca_form == AQS_DCA_FORM_PHI) {
            int32_t j;
            for (j = 0; j < nd->nh; j++) {
                const double *blk = t->data + nd_lam(nd) + 36 * ((int64_t)nd->nh * i + j) + 6 * r;
                for (k = 0; k < 6; k++) {
                    s += blk[k] * x[6 * j + k];
                    m += fabs(blk[k] * x[6 * j + k]);
                }
            }
        } else {
            const double *lr = t->data + nd_lam(nd) + (int64_t)(6 * i + r) * nd->lld;
            for (k = 0; k < nd->rank; k++) {
                s += lr[k] * lw[k];
                m += fabs(lr[k]) * lwa[k];
            }
        }
        out[r] = s;
        *mag += r < 3 ? m : m * il;
    }
}

/* Handle i's acceleration (as handle_acc) in the world: angular, and the
 * linear one of the point c (world). */
/* The root's sphere in the world: stored, like every node's, in the node's
 * frame, which for the root is the world leaf's (tree.world_frame). */
static void root_sphere_world(const aqs_linkage *L, double s0[4])
{
    const double *s = L->wb->sph + 4 * L->t.root;
    const pose *W = &L->t.world_frame;
    int i;
    mat3_vec(W->R, s, s0);
    for (i = 0; i < 3; i++) s0[i] += W->p[i];
    s0[3] = s[3];
}

static void handle_world(const aqs_linkage *L, int32_t n, const double a[6], int32_t i, const double c[3],
                         double al[3], double lin[3])
{
    const pose *P = L->t.poses + L->t.nodes[n].poses + i, *Wn = &L->wb->wpose[n];
    pose H;
    double l[3], d[3], cr[3];
    pose_compose(Wn, P, &H);
    mat3_vec(H.R, a, al);
    mat3_vec(H.R, a + 3, l);
    d[0] = c[0] - H.p[0];
    d[1] = c[1] - H.p[1];
    d[2] = c[2] - H.p[2];
    vec3_cross(al, d, cr);
    lin[0] = l[0] + cr[0];
    lin[1] = l[1] + cr[1];
    lin[2] = l[2] + cr[2];
}

/* The bound on the error node n's joints cause in the bodies beyond its
 * held handles (docs/math.md §10b, "Beyond a held handle"): for held
 * handle h, those joints move everything beyond h rigidly with
 * D_h = a_h - a_e, h's acceleration relative to the composite n hangs from
 * (entry handle e; the world for a grounded node), both exact at n's handle
 * forces. For b beyond h: |D_lin(p_b)| + ell_b |D_ang| <= |D_lin(c_0)| +
 * |D_ang| (R_0 + ellmax), c_0, R_0 the root's sphere. -1 if n has no entry
 * (the caller falls back to the spheres). */
static double beyond_bound(const aqs_linkage *L, int32_t n)
{
    const struct worldbound *w = L->wb;
    const tree *t = &L->t;
    const node *nd = &t->nodes[n];
    const double *x = t->data + nd_xf(nd);
    const int32_t rows = 6 * nd->nh;
    double lw[6 * AQS_WB_MAXH], lwa[6 * AQS_WB_MAXH], s0[4];
    const double l = length_of(L), il = 1.0 / l;
    double ae[6], ale[3], line[3], mag = 0.0, best = 0.0, R0;
    int32_t i, k, r, entry = -1;
    root_sphere_world(L, s0);
    R0 = (s0[3] > 0.0 ? s0[3] : 0.0) + w->lmax[t->root];
    if (nd->nh > AQS_WB_MAXH) return -1.0;
    for (i = 0; i < nd->nh; i++) {
        int32_t e = t->handles[nd->handles + i];
        int32_t leaf = t->leaf_of_comp[L->m.eff_child[e]];
        if (leaf > n - w->size[n] && leaf <= n) entry = i;
    }
    if (entry < 0 && !nd->grounded) return -1.0;
    if (L->dca_form != AQS_DCA_FORM_PHI) {
        for (k = 0; k < nd->rank; k++) lw[k] = lwa[k] = 0.0;
        for (r = 0; r < rows; r++) {
            const double *lr = t->data + nd_lam(nd) + (int64_t)r * nd->lld;
            for (k = 0; k < nd->rank; k++) {
                lw[k] += lr[k] * x[r];
                lwa[k] += fabs(lr[k] * x[r]);
            }
        }
    }
    if (entry >= 0) {
        handle_acc(L, n, lw, lwa, entry, il, ae, &mag);
        handle_world(L, n, ae, entry, s0, ale, line);
    } else { /* the world: -g everywhere (root trick), no rotation */
        ale[0] = ale[1] = ale[2] = 0.0;
        for (k = 0; k < 3; k++) line[k] = -L->gravity[k];
        mag += sqrt(vec3_dot(line, line)) * il;
    }
    for (i = 0; i < nd->nh; i++) {
        double ah[6], al[3], lin[3], m = mag, v;
        if (i == entry) continue;
        handle_acc(L, n, lw, lwa, i, il, ah, &m);
        handle_world(L, n, ah, i, s0, al, lin);
        for (k = 0; k < 3; k++) {
            al[k] -= ale[k];
            lin[k] -= line[k];
        }
        /* rounding: the DCA's relative accuracy (1e-12) times the terms'
         * scale m (in 1/s^2: the angular terms, and the linear ones over l)
         * times (l + 2 R0): at least the first-order propagation 1e-12
         * (m_lin + 2 R0 m_ang) (the angular error at the lever arm R0, and
         * again through D_lin(c_0) = lin + al x (c_0 - handle)), and at
         * least the former 1e-12 (m_ang + m_lin)(1 + R0) where l = 1 m
         * (docs/math.md §10b, "The unit of length") */
        v = sqrt(vec3_dot(lin, lin)) + sqrt(vec3_dot(al, al)) * R0 + 1e-12 * m * (l + 2.0 * R0);
        if (v > best) best = v;
    }
    return best;
}

double worldbound_key(const aqs_linkage *L, int32_t n, double a, double *beyond)
{
    const struct worldbound *w = L->wb;
    const double *s = w->sph + 4 * n;
    double R = s[3] > 0.0 ? s[3] : 0.0, rho = 2.0 * R + w->lmax[n], e;
    *beyond = 0.0;
    if (a <= 0.0) return 0.0;
    /* the bodies inside n: lever arms within n's sphere */
    e = sqrt(a) * (sqrt(w->sl2[n]) + rho * sqrt(w->sa2[n]));
    if (w->holds[n]) {
        double far = beyond_bound(L, n);
        if (far < 0.0) {
            /* bodies beyond n's held handles: anywhere in the root's sphere */
            const pose *P = &w->wpose[n];
            double c[3], s0[4];
            root_sphere_world(L, s0);
            mat3_vec(P->R, s, c);
            c[0] += P->p[0];
            c[1] += P->p[1];
            c[2] += P->p[2];
            rho = R + vec3_dist(c, s0) + (s0[3] > 0.0 ? s0[3] : 0.0) + w->lmax[L->t.root];
            far = sqrt(a) * (sqrt(w->sl2[n]) + rho * sqrt(w->sa2[n]));
        }
        *beyond = far * (1.0 + 1e-12);
        if (far > e) e = far;
    }
    return e * (1.0 + 1e-12);
}

double worldbound_rounding(const aqs_linkage *L, double r2, double rfree)
{
    /* Body b's part: sum over the joints j on its path of e_j (sigma_lin_j +
     * sigma_ang_j (|p_b - o_j| + ell_b)), and p_b, o_j lie in the root's
     * sphere; Cauchy-Schwarz on the path, Minkowski, and the path's e_j^2
     * summed at most to r2^2 (docs/math.md §10b, "Rounding"). A free joint
     * is at most one per path (the first): its error rfree is |(delta
     * alpha, delta a / l)|, so it adds at most rfree (l + lever). */
    const struct worldbound *w = L->wb;
    const double *s0 = w->sph + 4 * L->t.root;
    const double lever = 2.0 * (s0[3] > 0.0 ? s0[3] : 0.0) + w->lmax[L->t.root];
    return (r2 * (sqrt(w->pl_all) + lever * sqrt(w->pa_all)) + rfree * (length_of(L) + lever)) * (1.0 + 1e-12);
}
