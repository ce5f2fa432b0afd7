/* factor.c -- reading the packed total-acceleration factors (factor.h). */
#include "factor.h"

#include <string.h>

void test_unpack_factor(const aqs_linkage *L, int32_t n, double *full)
{
    const tree *t = &L->t;
    const node *nd = &t->nodes[n];
    const int32_t *pos = t->trowpos + t->tf[n].tpos;
    int32_t cols = 6 * nd->nh + 1, r;
    int64_t off = 0;
    for (r = 0; r < t->tf[n].trows; r++) {
        double *row = full + (int64_t)r * cols;
        int32_t len = cols - pos[r];
        memset(row, 0, sizeof(double) * (size_t)pos[r]);
        memcpy(row + pos[r], t->tdata + t->tf[n].T + off, sizeof(double) * (size_t)len);
        off += len;
    }
}
