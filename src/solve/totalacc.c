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
 * the stacked matrix. Rows are stored packed: row r holds its columns
 * trowpos[r] .. 6nh, right after row r - 1 (at most (6nh+1)(6nh+2)/2
 * doubles per node instead of (6nh+1)^2). */
#include "totalacc.h"

#include <math.h>
#include <string.h>

#include "dca.h"
#include "dense.h"
#include "invariant.h"
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

/* Room for T's rows: T_C's rows come from the children's (each child row
 * placed or reflected, no more rows out of the reflections than into them)
 * and K's kd, so they are at most the counted dofs of the subassembly, and
 * at most its columns (upper triangular). Row r starts at column r or later,
 * so R rows take at most R cols - R (R - 1) / 2 doubles packed. The counts go
 * through tf[].tcap, children first. */
static void factor_room(const aqs_linkage *L, tfactor *tf, int64_t *size, int64_t *npos)
{
    const tree *t = &L->t;
    int32_t n;
    *size = *npos = 0;
    for (n = 0; n < t->nnodes; n++) {
        const node *nd = &t->nodes[n];
        int64_t cols = 6 * (int64_t)nd->nh + 1, dofs, R;
        tf[n].tcap = 0;
        if (nd->joint < 0) continue;
        dofs = (int64_t)tf[nd->a].tcap + tf[nd->b].tcap +
               (L->joints[L->m.eff_joint[nd->joint]].type != AQS_JOINT_FREE ? nd->d : 0);
        R = dofs < cols ? dofs : cols;
        tf[n].tcap = (int32_t)R;
        tf[n].T = *size;
        tf[n].tpos = *npos;
        *size += R * cols - R * (R - 1) / 2;
        *npos += R;
    }
}

aqs_status totalacc_enable(aqs_linkage *L, const char *fn)
{
    tree *t = &L->t;
    int64_t size = 0, npos = 0, cmax = 6 * (int64_t)t->max_handles + 1;
    int32_t n;
    double *tdata, *scratch;
    int32_t *perm, *iscratch, *rowpos;
    tfactor *tf;
    aqs_status st;
    if ((st = dca_enable(L, fn)) != AQS_OK) return st;
    tf = lk_calloc_in(L, LK_MEM_FACTORS, (size_t)t->nnodes + 1, sizeof *tf);
    if (tf) factor_room(L, tf, &size, &npos);
    tdata = lk_calloc_in(L, LK_MEM_FACTORS, (size_t)size + 1, sizeof(double));
    /* the reflected rows (column-major, at most 6 + 6 + 6), the node's
     * factor unpacked (cmax x cmax) and one row of M W (cmax) */
    scratch = lk_calloc_in(L, LK_MEM_FACTORS, (size_t)(cmax + 19) * (size_t)cmax, sizeof(double));
    perm = lk_calloc_in(L, LK_MEM_FACTORS, (size_t)t->nhandles + 1, sizeof(int32_t));
    /* posC, mapA, mapB (nh each) and the present rows (cols) */
    iscratch = lk_calloc_in(L, LK_MEM_FACTORS, 3 * (size_t)t->max_handles + (size_t)cmax + 3, sizeof(int32_t));
    rowpos = lk_calloc_in(L, LK_MEM_FACTORS, (size_t)npos + 1, sizeof(int32_t));
    if (!tf || !tdata || !scratch || !perm || !iscratch || !rowpos) {
        lk_free(L, tf);
        lk_free(L, tdata);
        lk_free(L, scratch);
        lk_free(L, perm);
        lk_free(L, iscratch);
        lk_free(L, rowpos);
        return lk_fail(L, AQS_ENOMEM, "%s: out of memory for %lld total-acceleration coefficients",
                       fn, (long long)size);
    }
    t->tdata = tdata;
    t->tf = tf;
    t->tscratch = scratch;
    t->tperm = perm;
    t->tiscratch = iscratch;
    t->trowpos = rowpos;
    for (n = 0; n < t->nnodes; n++) {
        t->tf[n].trows = 0;
        order_handles(t, n);
    }
    return AQS_OK;
}

void totalacc_free(aqs_linkage *L)
{
    lk_free(L, L->t.tdata);
    lk_free(L, L->t.tf);
    L->t.tf = NULL;
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
 * M_c W g (dca_mw_apply, from the node update's products), the constant
 * g . gamma. */
static void add_gF(const aqs_linkage *L, int32_t n, const double *g, const double *gamma,
                   const int32_t *pos, int32_t nh, double *D, int64_t ld, int32_t r, double *mw)
{
    int32_t c, i;
    double s = 0.0;
    dca_mw_apply(L, n, g, mw);
    for (c = 0; c < nh; c++) {
        double *col = D + (int64_t)6 * pos[c] * ld + r;
        for (i = 0; i < 6; i++) col[i * ld] += mw[6 * c + i];
    }
    for (i = 0; i < 6; i++) s += g[i] * gamma[i];
    D[(int64_t)6 * nh * ld + r] += s;
}

/* Copy a packed row of a child's factor (its columns q .. 6 nh_x, in the
 * child's order), without its joined first block, to C's columns: block
 * p >= 1 goes to block map[p], the constant to C's last column. dst + col *
 * stride is C's column col (stride 1 for a row of R, ld for a row of D),
 * zero beforehand where the row is zero. */
static void copy_child_row(const double *tr, int32_t q, int32_t nh_x, const int32_t *map, int32_t cols,
                           double *dst, int64_t stride)
{
    int32_t p, i;
    for (p = q / 6 > 1 ? q / 6 : 1, i = p == q / 6 ? q % 6 : 0; p < nh_x; p++, i = 0) {
        double *d = dst + (int64_t)6 * map[p] * stride;
        for (; i < 6; i++) d[i * stride] = tr[6 * p + i - q];
    }
    dst[(int64_t)(cols - 1) * stride] += tr[6 * nh_x - q];
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
    return t->trowpos + t->tf[n].tpos;
}

/* Rows of child x's factor starting in its first block (the joined handle):
 * they are reflected; the others are placed. */
static int32_t reflected_rows(const tree *t, int32_t x)
{
    const int32_t *pos = row_starts(t, x);
    int32_t r = 0;
    while (r < t->tf[x].trows && pos[r] < 6) r++;
    return r;
}

/* Place the rows of child x's factor from row `from` (at packed offset off)
 * on in R (C's cols x cols rows, row j starting at column j): a row starting
 * at the child's column q goes to C's row for q (map). The constant-only rows
 * of the two children (q = 6 nh_x) share C's last row. */
static void place_rows(const tree *t, int32_t x, int32_t from, int64_t off, const int32_t *map,
                       int32_t cols, double *R, int32_t *present)
{
    const node *X = &t->nodes[x];
    const int32_t *pos = row_starts(t, x);
    int32_t r, cx = 6 * X->nh + 1;
    for (r = from; r < t->tf[X - t->nodes].trows; r++) {
        const double *tr = t->tdata + t->tf[X - t->nodes].T + off;
        int32_t q = pos[r], j = q < 6 * X->nh ? 6 * map[q / 6] + q % 6 : cols - 1;
        double *last = R + (int64_t)cols * cols - 1;
        if (j == cols - 1 && present[j]) {
            *last = hypot(*last, tr[cx - 1 - q]);
        } else {
            copy_child_row(tr, q, X->nh, map, cols, R + (int64_t)j * cols, 1);
            present[j] = 1;
        }
        off += cx - q;
    }
}

/* The joined block (the first 6 columns) of a packed child row starting at
 * column q < 6. */
static void joined_block(const double *tr, int32_t q, double k[6])
{
    int32_t i;
    for (i = 0; i < 6; i++) k[i] = i < q ? 0.0 : tr[i - q];
}

void totalacc_node_update(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    node *C = &t->nodes[n];
    const node *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const joint_def *jd = &L->joints[L->m.eff_joint[C->joint]];
    const double *rho = t->data + nd_rho(C), *gamma = t->data + nd_gamma(C);
    const pose *J = t->poses + nd_J(C);
    const int32_t *permC = t->tperm + C->handles;
    int counted = jd->type != AQS_JOINT_FREE;
    int32_t nh = C->nh, cols = 6 * nh + 1, nAo = A->nh - 1, r, i, c, j;
    int32_t kd = counted ? C->d : 0, da = reflected_rows(t, C->a), db = reflected_rows(t, C->b);
    int32_t p = da + db + kd, row = 0;
    int32_t *posC = t->tiscratch, *mapA = posC + nh, *mapB = mapA + A->nh, *present = mapB + B->nh;
    int32_t *rowpos = t->trowpos + t->tf[C - t->nodes].tpos;
    double *D = t->tscratch; /* the reflected rows, column-major, leading dimension p */
    const int64_t cmax = 6 * (int64_t)t->max_handles + 1;
    double *R = D + 18 * cmax; /* C's factor, unpacked */
    double *mw = R + cmax * cmax; /* M W g, or a row of U M^T (dca.c) */
    double *T = t->tdata + t->tf[C - t->nodes].T;
    const int32_t *posA = row_starts(t, C->a), *posB = row_starts(t, C->b);
    int64_t offA = 0, offB = 0, off;

    /* the factor's shape: its rows fit the scratch (at most 6 + 6 + 6 reflected) */
    AQS_ASSERT(p <= 18 && cols <= cmax && t->tf[A - t->nodes].trows <= 6 * A->nh + 1 && t->tf[B - t->nodes].trows <= 6 * B->nh + 1);
    t->tf[C - t->nodes].trows = 0;
    if (t->tf[A - t->nodes].trows + t->tf[B - t->nodes].trows + kd == 0) return;
    for (c = 0; c < nh; c++) posC[permC[c]] = c;
    child_map(t, A, C->ka, 0, posC, mapA);
    child_map(t, B, C->kb, nAo, posC, mapB);
    memset(D, 0, sizeof(double) * (size_t)p * (size_t)cols);
    memset(R, 0, sizeof(double) * (size_t)cols * (size_t)cols);
    memset(present, 0, sizeof(int32_t) * (size_t)cols);

    /* T_A E_A: -(T_A)_k X^T F added to the rows starting in block k (the row
     * g^T = (T_A)_k X^T is X applied to (T_A)_k); the others are copied. */
    for (r = 0; r < da; r++, row++) {
        const double *tr = t->tdata + t->tf[A - t->nodes].T + offA;
        double g[6], k[6];
        copy_child_row(tr, posA[r], A->nh, mapA, cols, D + row, p);
        joined_block(tr, posA[r], k);
        offA += 6 * A->nh + 1 - posA[r];
        spatial_xform_motion(J, k, g);
        for (i = 0; i < 6; i++) g[i] = -g[i];
        add_gF(L, n, g, gamma, posC, nh, D, p, row, mw);
    }
    /* T_B E_B */
    for (r = 0; r < db; r++, row++) {
        const double *tr = t->tdata + t->tf[B - t->nodes].T + offB;
        double k[6];
        copy_child_row(tr, posB[r], B->nh, mapB, cols, D + row, p);
        joined_block(tr, posB[r], k);
        offB += 6 * B->nh + 1 - posB[r];
        add_gF(L, n, k, gamma, posC, nh, D, p, row, mw);
    }
    /* K = [-U M^T, rho] */
    for (r = 0; r < kd; r++, row++) {
        dca_um_row(L, n, r, mw);
        for (c = 0; c < nh; c++) {
            double *col = D + (int64_t)6 * posC[c] * p + row;
            for (i = 0; i < 6; i++) col[i * p] = -mw[6 * c + i];
        }
        D[(int64_t)(cols - 1) * p + row] = rho[r];
    }
    place_rows(t, C->a, da, offA, mapA, cols, R, present);
    place_rows(t, C->b, db, offB, mapB, cols, R, present);
    (void)dense_qr_append_simd(R, cols, present, D, p, t->avx);
    /* keep the present rows, in order, packed */
    for (j = 0, r = 0, off = 0; j < cols; j++) {
        if (!present[j]) continue;
        memcpy(T + off, R + (int64_t)j * cols + j, sizeof(double) * (size_t)(cols - j));
        off += cols - j;
        rowpos[r++] = j;
    }
    /* packed triangle, within the room factor_room gave it */
    AQS_ASSERT(r <= t->tf[n].tcap && off <= (int64_t)r * cols - (int64_t)r * (r - 1) / 2);
    t->tf[C - t->nodes].trows = r;
}

double totalacc_eval(const aqs_linkage *L, int32_t n)
{
    const tree *t = &L->t;
    const node *nd = &t->nodes[n];
    const double *T = t->tdata + t->tf[nd - t->nodes].T, *x = t->data + nd_xf(nd);
    const int32_t *perm = t->tperm + nd->handles, *pos = row_starts(t, n);
    int32_t cols = 6 * nd->nh + 1, r, p, i, c;
    double sum = 0.0, xs[6 * 8 + 1];
    if (nd->nh <= 8) {
        /* x in the factor's column order, 1 last: each row is one dot product */
        for (p = 0; p < nd->nh; p++)
            for (i = 0; i < 6; i++) xs[6 * p + i] = x[6 * perm[p] + i];
        xs[cols - 1] = 1.0;
        for (r = 0; r < t->tf[nd - t->nodes].trows; r++) {
            const int32_t c0 = pos[r], len = cols - c0;
            const double *z = xs + c0;
            double s = 0.0;
            for (c = 0; c < len; c++) s += T[c] * z[c];
            T += len;
            sum += s * s;
        }
        return sum;
    }
    for (r = 0; r < t->tf[nd - t->nodes].trows; r++) {
        /* the packed row holds columns pos[r] .. cols - 1: column c at T[c - pos[r]] */
        int32_t c0 = pos[r];
        double s = T[cols - 1 - c0];
        for (p = c0 / 6, i = c0 % 6; p < nd->nh; p++, i = 0) {
            const double *xp = x + 6 * perm[p];
            for (; i < 6; i++) s += T[6 * p + i - c0] * xp[i];
        }
        T += cols - c0;
        sum += s * s;
    }
    return sum;
}
