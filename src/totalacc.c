/* totalacc.c -- the square-root form of the total acceleration (MATH.md §5).
 *
 * For node C = A + B through joint k, with z = [x_C; 1]:
 *   f_k = F z,          F = [W M^T, gamma]            (M as in dca.c)
 *   x_A = E_A z: A's outer handles copy x_C, A's handle k is -X^T f_k
 *   x_B = E_B z: B's handle k is f_k, B's outer handles copy x_C
 *   qdd_k = K z,        K = [-U M^T, rho]
 * and T_C is the R factor of the QR of [T_A E_A; T_B E_B; K] (K only if k
 * is counted), so ||T_C z|| = sqrt(A_C) exactly in exact arithmetic and
 * never negative in floating point. */
#include "totalacc.h"

#include <math.h>
#include <string.h>

#include "dca.h"
#include "dense.h"
#include "pool.h"

aqs_status totalacc_enable(aqs_linkage *L, const char *fn)
{
    tree *t = &L->t;
    int64_t size = 0;
    int32_t n, maxh = t->max_handles;
    double *tdata, *scratch;
    aqs_status st;
    if ((st = dca_enable(L, fn)) != AQS_OK) return st;
    for (n = 0; n < t->nnodes; n++) {
        node *nd = &t->nodes[n];
        int64_t cols = 6 * (int64_t)nd->nh + 1;
        nd->T = size;
        if (nd->joint >= 0) size += cols * cols;
    }
    tdata = lk_calloc(L, (size_t)size + 1, sizeof(double));
    /* the stacked matrix, column-major: up to 2 (6 maxh + 1) + 6 rows */
    scratch = lk_calloc(L, (size_t)(2 * (6 * maxh + 1) + 6) * (size_t)(6 * maxh + 1), sizeof(double));
    if (!tdata || !scratch) {
        lk_free(L, tdata);
        lk_free(L, scratch);
        return lk_fail(L, AQS_ENOMEM, "%s: out of memory for %lld total-acceleration coefficients",
                       fn, (long long)size);
    }
    t->tdata = tdata;
    t->tscratch = scratch;
    for (n = 0; n < t->nnodes; n++) t->nodes[n].trows = 0;
    return AQS_OK;
}

void totalacc_free(aqs_linkage *L)
{
    lk_free(L, L->t.tdata);
    lk_free(L, L->t.tscratch);
    L->t.tdata = NULL;
    L->t.tscratch = NULL;
}

/* Row r of the column-major stacked matrix (rows x (6nh+1), leading
 * dimension ld) += g^T F for F = [W M^T, gamma]: block c gets M_c (W g),
 * the last entry g . gamma. */
static void add_gF(const double *W, const double *g, const double *M, const double *gamma,
                   int32_t nh, double *Sc, int64_t ld, int32_t r)
{
    double w[6], tmp[6];
    int32_t c, i;
    double s = 0.0;
    dense_matvec6(W, g, w);
    for (c = 0; c < nh; c++) {
        dense_matvec6(M + 36 * c, w, tmp);
        for (i = 0; i < 6; i++) Sc[(6 * c + i) * ld + r] += tmp[i];
    }
    for (i = 0; i < 6; i++) s += g[i] * gamma[i];
    Sc[6 * nh * ld + r] += s;
}

/* Copy row tr of a child's factor (its nh_child handle blocks and the
 * constant) into row r of the stacked matrix, skipping the joined handle
 * k, its outer blocks going to block columns first, first+1, ... */
static void copy_child_row(const double *tr, int32_t nh_child, int32_t k, int32_t first, int32_t cols,
                           double *Sc, int64_t ld, int32_t r)
{
    int32_t i, j, c = first;
    for (i = 0; i < nh_child; i++) {
        if (i == k) continue;
        for (j = 0; j < 6; j++) Sc[(6 * c + j) * ld + r] = tr[6 * i + j];
        c++;
    }
    Sc[(cols - 1) * ld + r] += tr[6 * nh_child];
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
    int counted = jd->type != AQS_JOINT_FREE;
    int32_t nh = C->nh, cols = 6 * nh + 1, nAo = A->nh - 1, r, i, c, kept;
    int32_t rows = A->trows + B->trows + (counted ? C->d : 0), row = 0;
    double *Sc = t->tscratch; /* the stacked matrix, column-major, leading dimension rows */
    double W[36];

    C->trows = 0;
    if (rows == 0) return;
    memset(Sc, 0, sizeof(double) * (size_t)rows * (size_t)cols);
    dca_form_W(L, n, W); /* once for all the rows: each row needs W g */

    /* T_A E_A; -(T_A)_k X^T F: the row g^T = (T_A)_k X^T is X applied to (T_A)_k. */
    for (r = 0; r < A->trows; r++, row++) {
        const double *tr = t->tdata + A->T + (int64_t)r * (6 * A->nh + 1);
        double g[6];
        copy_child_row(tr, A->nh, C->ka, 0, cols, Sc, rows, row);
        spatial_xform_motion(J, tr + 6 * C->ka, g);
        for (i = 0; i < 6; i++) g[i] = -g[i];
        add_gF(W, g, M, gamma, nh, Sc, rows, row);
    }
    /* T_B E_B */
    for (r = 0; r < B->trows; r++, row++) {
        const double *tr = t->tdata + B->T + (int64_t)r * (6 * B->nh + 1);
        copy_child_row(tr, B->nh, C->kb, nAo, cols, Sc, rows, row);
        add_gF(W, tr + 6 * C->kb, M, gamma, nh, Sc, rows, row);
    }
    /* K = [-U M^T, rho] */
    if (counted) {
        for (r = 0; r < C->d; r++, row++) {
            double tmp[6];
            for (c = 0; c < nh; c++) {
                dense_matvec6(M + 36 * c, U + 6 * r, tmp);
                for (i = 0; i < 6; i++) Sc[(int64_t)(6 * c + i) * rows + row] = -tmp[i];
            }
            Sc[(int64_t)(cols - 1) * rows + row] = rho[r];
        }
    }
    /* QR in column-major order (contiguous reflections), R back row-major */
    kept = dense_qr_r_colmajor(Sc, rows, cols);
    {
        double *T = t->tdata + C->T;
        for (r = 0; r < kept; r++)
            for (c = 0; c < cols; c++) T[(int64_t)r * cols + c] = c < r ? 0.0 : Sc[(int64_t)c * rows + r];
    }
    C->trows = kept;
}

double totalacc_eval(const aqs_linkage *L, int32_t n)
{
    const tree *t = &L->t;
    const node *nd = &t->nodes[n];
    const double *T = t->tdata + nd->T, *x = t->data + nd->xf;
    int32_t cols = 6 * nd->nh + 1, r, j;
    double sum = 0.0;
    for (r = 0; r < nd->trows; r++) {
        const double *row = T + (int64_t)r * cols;
        double s = row[cols - 1];
        for (j = r; j < cols - 1; j++) s += row[j] * x[j];
        sum += s * s;
    }
    return sum;
}
