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
    for (n = 0; n < t->nnodes; n++) {
        node *nd = &t->nodes[n];
        int64_t cols = 6 * (int64_t)nd->nh + 1;
        nd->T = size;
        if (nd->joint >= 0) size += cols * cols;
    }
    tdata = lk_calloc(L, (size_t)size + 1, sizeof(double));
    /* the stacked matrix, row-major, then its column-major copy */
    scratch = lk_calloc(L, 2 * (size_t)(2 * (6 * maxh + 1) + 6) * (size_t)(6 * maxh + 1), sizeof(double));
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

/* row (length 6nh+1) += g^T F for F = [W M^T, gamma]: block c gets
 * M_c (W g), the last entry g . gamma. */
static void add_gF(const double *W, const double *g, const double *M, const double *gamma,
                   int32_t nh, double *row)
{
    double w[6], tmp[6];
    int32_t c, i;
    double s = 0.0;
    dense_matvec6(W, g, w);
    for (c = 0; c < nh; c++) {
        dense_matvec6(M + 36 * c, w, tmp);
        for (i = 0; i < 6; i++) row[6 * c + i] += tmp[i];
    }
    for (i = 0; i < 6; i++) s += g[i] * gamma[i];
    row[6 * nh] += s;
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
    int32_t nh = C->nh, cols = 6 * nh + 1, nAo = A->nh - 1, rows = 0, r, i, c, kept;
    double *S = t->tscratch, *Sc = t->tscratch + (int64_t)(2 * (6 * t->max_handles + 1) + 6) * (6 * t->max_handles + 1);
    double W[36];
    int counted = jd->type != AQS_JOINT_FREE;

    dca_form_W(L, n, W); /* once for all the rows: each row needs W g */

    /* T_A E_A */
    {
        const double *TA = t->tdata + A->T;
        int32_t ca = 6 * A->nh + 1;
        for (r = 0; r < A->trows; r++, rows++) {
            double *row = S + (int64_t)rows * cols, g[6];
            const double *tr = TA + (int64_t)r * ca;
            memset(row, 0, sizeof(double) * (size_t)cols);
            for (i = 0, c = 0; i < A->nh; i++) {
                if (i == C->ka) continue;
                memcpy(row + 6 * c, tr + 6 * i, 6 * sizeof(double));
                c++;
            }
            row[cols - 1] += tr[ca - 1];
            /* -(T_A)_k X^T F: the row g^T = (T_A)_k X^T is X applied to (T_A)_k. */
            spatial_xform_motion(J, tr + 6 * C->ka, g);
            for (i = 0; i < 6; i++) g[i] = -g[i];
            add_gF(W, g, M, gamma, nh, row);
        }
    }
    /* T_B E_B */
    {
        const double *TB = t->tdata + B->T;
        int32_t cb = 6 * B->nh + 1;
        for (r = 0; r < B->trows; r++, rows++) {
            double *row = S + (int64_t)rows * cols;
            const double *tr = TB + (int64_t)r * cb;
            memset(row, 0, sizeof(double) * (size_t)cols);
            for (i = 0, c = nAo; i < B->nh; i++) {
                if (i == C->kb) continue;
                memcpy(row + 6 * c, tr + 6 * i, 6 * sizeof(double));
                c++;
            }
            row[cols - 1] += tr[cb - 1];
            add_gF(W, tr + 6 * C->kb, M, gamma, nh, row);
        }
    }
    /* K = [-U M^T, rho] */
    if (counted) {
        for (r = 0; r < C->d; r++, rows++) {
            double *row = S + (int64_t)rows * cols, tmp[6];
            for (c = 0; c < nh; c++) {
                dense_matvec6(M + 36 * c, U + 6 * r, tmp);
                for (i = 0; i < 6; i++) row[6 * c + i] = -tmp[i];
            }
            row[cols - 1] = rho[r];
        }
    }
    /* QR in column-major order (contiguous reflections), R back row-major */
    kept = 0;
    if (rows > 0) {
        double *T = t->tdata + C->T;
        for (r = 0; r < rows; r++)
            for (c = 0; c < cols; c++) Sc[(int64_t)c * rows + r] = S[(int64_t)r * cols + c];
        kept = dense_qr_r_colmajor(Sc, rows, cols);
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
