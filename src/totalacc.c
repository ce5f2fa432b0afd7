/* totalacc.c -- the square-root form of the total acceleration (MATH.md §5).
 *
 * For node C = A + B through joint k, with z = [x_C; 1]:
 *   f_k = F z,          F = [W M^T, gamma]            (M as in dca.c)
 *   x_A = E_A z: A's outer handles copy x_C, A's handle k is -X^T f_k
 *   x_B = E_B z: B's handle k is f_k, B's outer handles copy x_C
 *   qdd_k = K z,        K = [-U M^T, rho]
 * and T_C is the R factor of the QR of [T_A E_A; T_B E_B; K] (K only if k
 * is counted), so ||T_C z|| = sqrt(A_C) exactly in exact arithmetic and
 * never negative in floating point.
 *
 * Column order. T's column blocks are the node's handles in the order the
 * ancestors will join them: the handle joined by the parent first, then by
 * the grandparent, ... (tree.tperm; the constant column last). T is upper
 * triangular with rows missing: row r starts at column trowpos[r] (zeros
 * left of it), strictly increasing. A child's joined handle k is its first
 * block, so its rows starting at column 6 or later are zero there: E_A and
 * E_B only copy them, into columns that keep their relative order in C (the
 * same ancestors order both), so they stay rows of an upper-triangular
 * matrix. Only the child rows starting in block k (at most 6 per child) and
 * K (d rows) are reflected (dense_qr_append), instead of all the rows of
 * the stacked matrix. */
#include "totalacc.h"

#include <math.h>
#include <string.h>

#include "dca.h"
#include "dense.h"
#include "pool.h"

/* Height of the node whose principal joint is handle h of node n: an
 * ancestor of n, the lower the sooner it joins h. */
static int32_t join_height(const tree *t, int32_t n, int32_t h)
{
    return t->nodes[t->node_of_eff[t->handles[t->nodes[n].handles + h]]].height;
}

/* tperm of node n: its handles sorted by join height (insertion sort: nh is
 * the degree of a body at most; distinct ancestors have distinct heights). */
static void order_handles(tree *t, int32_t n)
{
    const node *nd = &t->nodes[n];
    int32_t *perm = t->tperm + nd->handles, h, k;
    for (h = 0; h < nd->nh; h++) {
        int32_t key = join_height(t, n, h);
        for (k = h; k > 0 && join_height(t, n, perm[k - 1]) > key; k--) perm[k] = perm[k - 1];
        perm[k] = h;
    }
}

aqs_status totalacc_enable(aqs_linkage *L, const char *fn)
{
    tree *t = &L->t;
    int64_t size = 0, npos = 0, cmax = 6 * (int64_t)t->max_handles + 1;
    int32_t n;
    double *tdata, *scratch;
    int32_t *perm, *iscratch, *rowpos;
    aqs_status st;
    if ((st = dca_enable(L, fn)) != AQS_OK) return st;
    for (n = 0; n < t->nnodes; n++) {
        node *nd = &t->nodes[n];
        int64_t cols = 6 * (int64_t)nd->nh + 1;
        nd->T = size;
        nd->tpos = npos;
        if (nd->joint >= 0) {
            size += cols * cols;
            npos += cols;
        }
    }
    tdata = lk_calloc(L, (size_t)size + 1, sizeof(double));
    /* the stacked matrix, column-major: up to 2 cmax + 6 rows */
    scratch = lk_calloc(L, (size_t)(2 * cmax + 6) * (size_t)cmax, sizeof(double));
    perm = lk_calloc(L, (size_t)t->nhandles + 1, sizeof(int32_t));
    /* posC, mapA, mapB (nh each) and the present rows (cols) */
    iscratch = lk_calloc(L, 3 * (size_t)t->max_handles + (size_t)cmax + 3, sizeof(int32_t));
    rowpos = lk_calloc(L, (size_t)npos + 1, sizeof(int32_t));
    if (!tdata || !scratch || !perm || !iscratch || !rowpos) {
        lk_free(L, tdata);
        lk_free(L, scratch);
        lk_free(L, perm);
        lk_free(L, iscratch);
        lk_free(L, rowpos);
        return lk_fail(L, AQS_ENOMEM, "%s: out of memory for %lld total-acceleration coefficients",
                       fn, (long long)size);
    }
    t->tdata = tdata;
    t->tscratch = scratch;
    t->tperm = perm;
    t->tiscratch = iscratch;
    t->trowpos = rowpos;
    for (n = 0; n < t->nnodes; n++) {
        t->nodes[n].trows = 0;
        order_handles(t, n);
    }
    return AQS_OK;
}

void totalacc_free(aqs_linkage *L)
{
    lk_free(L, L->t.tdata);
    lk_free(L, L->t.tscratch);
    lk_free(L, L->t.tperm);
    lk_free(L, L->t.tiscratch);
    lk_free(L, L->t.trowpos);
    L->t.trowpos = NULL;
    L->t.tdata = NULL;
    L->t.tscratch = NULL;
    L->t.tperm = NULL;
    L->t.tiscratch = NULL;
}

/* Row r of the column-major D (leading dimension ld) += g^T F for
 * F = [W M^T, gamma]: C's handle c (block pos[c] of T's order) gets
 * M_c (W g), the constant g . gamma. */
static void add_gF(const double *W, const double *g, const double *M, const double *gamma,
                   const int32_t *pos, int32_t nh, double *D, int64_t ld, int32_t r)
{
    double w[6], tmp[6];
    int32_t c, i;
    double s = 0.0;
    dense_matvec6(W, g, w);
    for (c = 0; c < nh; c++) {
        double *col = D + (int64_t)6 * pos[c] * ld + r;
        dense_matvec6(M + 36 * c, w, tmp);
        for (i = 0; i < 6; i++) col[i * ld] += tmp[i];
    }
    for (i = 0; i < 6; i++) s += g[i] * gamma[i];
    D[(int64_t)6 * nh * ld + r] += s;
}

/* Copy row tr of a child's factor (cols_x columns in the child's order),
 * without its joined first block, to C's columns: block p >= 1 goes to
 * block map[p], the constant to C's last column. dst + col * stride is
 * C's column col: stride 1 for a row of T_C, ld for a row of D. */
static void copy_child_row(const double *tr, int32_t nh_x, const int32_t *map, int32_t cols,
                           double *dst, int64_t stride)
{
    int32_t p, i;
    for (p = 1; p < nh_x; p++) {
        double *d = dst + (int64_t)6 * map[p] * stride;
        for (i = 0; i < 6; i++) d[i * stride] = tr[6 * p + i];
    }
    dst[(int64_t)(cols - 1) * stride] += tr[6 * nh_x];
}

/* map[p] for the blocks of child x (handle k joined; its outer handles are
 * C's handles off, off + 1, ... in x's order): C's T block. */
static void child_map(const tree *t, const node *X, int32_t k, int32_t off, const int32_t *posC,
                      int32_t *map)
{
    const int32_t *perm = t->tperm + X->handles;
    int32_t p;
    for (p = 1; p < X->nh; p++) map[p] = posC[off + perm[p] - (perm[p] > k)];
    map[0] = -1;
}

static const int32_t *row_starts(const tree *t, int32_t n)
{
    return t->trowpos + t->nodes[n].tpos;
}

/* Rows of child x's factor starting in its first block (the joined handle):
 * they are reflected; the others are placed. */
static int32_t reflected_rows(const tree *t, int32_t x)
{
    const int32_t *pos = row_starts(t, x);
    int32_t r = 0;
    while (r < t->nodes[x].trows && pos[r] < 6) r++;
    return r;
}

/* Place the rows of child x's factor from row `from` on in T (C's cols x
 * cols rows, row j starting at column j): a row starting at the child's
 * column q goes to C's row for q (map). The constant-only rows of the two
 * children (q = 6 nh_x) share C's last row. */
static void place_rows(const tree *t, int32_t x, int32_t from, const int32_t *map, int32_t cols,
                       double *T, int32_t *present)
{
    const node *X = &t->nodes[x];
    const int32_t *pos = row_starts(t, x);
    int32_t r, cx = 6 * X->nh + 1;
    for (r = from; r < X->trows; r++) {
        const double *tr = t->tdata + X->T + (int64_t)r * cx;
        int32_t q = pos[r], j = q < 6 * X->nh ? 6 * map[q / 6] + q % 6 : cols - 1;
        double *last = T + (int64_t)cols * cols - 1;
        if (j == cols - 1 && present[j]) {
            *last = hypot(*last, tr[cx - 1]);
        } else {
            copy_child_row(tr, X->nh, map, cols, T + (int64_t)j * cols, 1);
            present[j] = 1;
        }
    }
}

void totalacc_node_update(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    node *C = &t->nodes[n];
    const node *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const joint_def *jd = &L->joints[L->m.eff_joint[C->joint]];
    /* M of this node, left in the scratch by dca_node_update just before */
    const double *U = t->data + C->U, *M = t->mscratch;
    const double *rho = t->data + C->rho, *gamma = t->data + C->gamma;
    const pose *J = t->poses + C->J;
    const int32_t *permC = t->tperm + C->handles;
    int counted = jd->type != AQS_JOINT_FREE;
    int32_t nh = C->nh, cols = 6 * nh + 1, nAo = A->nh - 1, r, i, c, j;
    int32_t kd = counted ? C->d : 0, da = reflected_rows(t, C->a), db = reflected_rows(t, C->b);
    int32_t p = da + db + kd, row = 0;
    int32_t *posC = t->tiscratch, *mapA = posC + nh, *mapB = mapA + A->nh, *present = mapB + B->nh;
    int32_t *rowpos = t->trowpos + C->tpos;
    double *D = t->tscratch; /* the reflected rows, column-major, leading dimension p */
    double *T = t->tdata + C->T;
    double W[36];

    C->trows = 0;
    if (A->trows + B->trows + kd == 0) return;
    for (c = 0; c < nh; c++) posC[permC[c]] = c;
    child_map(t, A, C->ka, 0, posC, mapA);
    child_map(t, B, C->kb, nAo, posC, mapB);
    memset(D, 0, sizeof(double) * (size_t)p * (size_t)cols);
    memset(T, 0, sizeof(double) * (size_t)cols * (size_t)cols);
    memset(present, 0, sizeof(int32_t) * (size_t)cols);
    if (da + db > 0) dca_form_W(L, n, W); /* once for all the rows: each row needs W g */

    /* T_A E_A: -(T_A)_k X^T F added to the rows starting in block k (the row
     * g^T = (T_A)_k X^T is X applied to (T_A)_k); the others are copied. */
    for (r = 0; r < da; r++, row++) {
        const double *tr = t->tdata + A->T + (int64_t)r * (6 * A->nh + 1);
        double g[6];
        copy_child_row(tr, A->nh, mapA, cols, D + row, p);
        spatial_xform_motion(J, tr, g);
        for (i = 0; i < 6; i++) g[i] = -g[i];
        add_gF(W, g, M, gamma, posC, nh, D, p, row);
    }
    /* T_B E_B */
    for (r = 0; r < db; r++, row++) {
        const double *tr = t->tdata + B->T + (int64_t)r * (6 * B->nh + 1);
        copy_child_row(tr, B->nh, mapB, cols, D + row, p);
        add_gF(W, tr, M, gamma, posC, nh, D, p, row);
    }
    /* K = [-U M^T, rho] */
    for (r = 0; r < kd; r++, row++) {
        double tmp[6];
        for (c = 0; c < nh; c++) {
            double *col = D + (int64_t)6 * posC[c] * p + row;
            dense_matvec6(M + 36 * c, U + 6 * r, tmp);
            for (i = 0; i < 6; i++) col[i * p] = -tmp[i];
        }
        D[(int64_t)(cols - 1) * p + row] = rho[r];
    }
    place_rows(t, C->a, da, mapA, cols, T, present);
    place_rows(t, C->b, db, mapB, cols, T, present);
    (void)dense_qr_append(T, cols, present, D, p);
    /* keep the present rows, in order (row j moves up to r <= j) */
    for (j = 0, r = 0; j < cols; j++) {
        if (!present[j]) continue;
        if (r != j) memcpy(T + (int64_t)r * cols, T + (int64_t)j * cols, sizeof(double) * (size_t)cols);
        rowpos[r++] = j;
    }
    C->trows = r;
}

double totalacc_eval(const aqs_linkage *L, int32_t n)
{
    const tree *t = &L->t;
    const node *nd = &t->nodes[n];
    const double *T = t->tdata + nd->T, *x = t->data + nd->xf;
    const int32_t *perm = t->tperm + nd->handles, *pos = row_starts(t, n);
    int32_t cols = 6 * nd->nh + 1, r, p, i;
    double sum = 0.0;
    for (r = 0; r < nd->trows; r++) {
        const double *row = T + (int64_t)r * cols;
        double s = row[cols - 1];
        for (p = pos[r] / 6; p < nd->nh; p++) {
            const double *xp = x + 6 * perm[p], *rp = row + 6 * p;
            for (i = 0; i < 6; i++) s += rp[i] * xp[i];
        }
        sum += s * s;
    }
    return sum;
}
