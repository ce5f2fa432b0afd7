/* certificate.c -- pair pools and motion bounds for the lazy collision query
 * (certificate.h; the scheme is in docs/collision.md, "Certificates"). */
#include "certificate.h"

#include <math.h>
#include <string.h>

int pair_pool_push(pair_pool *p, int32_t i, int32_t j)
{
    if (p->used >= p->cap) return 0;
    p->buf[p->cur][2 * p->used] = i;
    p->buf[p->cur][2 * p->used + 1] = j;
    p->used++;
    return 1;
}

int pair_pool_compact(pair_pool *p, int32_t nnodes, unsigned char *live, int32_t *off,
                      const int32_t *cnt, int partial)
{
    int32_t n, used = 0, *src = p->buf[p->cur], *dst = p->buf[1 - p->cur];
    if (!partial) {
        for (n = 0; n < nnodes; n++)
            if (live[n]) used += cnt[n];
        if (used > p->cap / 2) return 0;
    }
    for (n = 0; n < nnodes; n++) {
        if (!live[n] || cnt[n] == 0) continue;
        if (used + cnt[n] > p->cap / 2) { /* partial: this list is dropped */
            live[n] = 0;
            continue;
        }
        memcpy(dst + 2 * used, src + 2 * off[n], 2 * sizeof(int32_t) * (size_t)cnt[n]);
        off[n] = used;
        used += cnt[n];
    }
    p->cur = 1 - p->cur;
    p->used = used;
    return 1;
}

double bound_up(double x)
{
    return nextafter(x, HUGE_VAL);
}

double placement_motion(const pose *old_pk, const pose *new_pk, const double s[4], double grow)
{
    double dR[9], fro = 0.0, d[3], scale = 0.0, r = s[3] + grow;
    int k;
    if (s[3] < 0.0 || memcmp(old_pk, new_pk, sizeof *old_pk) == 0) return 0.0;
    for (k = 0; k < 9; k++) {
        dR[k] = new_pk->R[k] - old_pk->R[k];
        fro += dR[k] * dR[k];
    }
    mat3_vec(dR, s, d);
    for (k = 0; k < 3; k++) {
        d[k] += new_pk->p[k] - old_pk->p[k];
        scale += fabs(s[k]) + fabs(new_pk->p[k]) + fabs(old_pk->p[k]);
    }
    /* relative 1e-12 for the rounding of these few operations, and 1e-12 of
     * the coordinates for that of the poses themselves */
    return (sqrt(vec3_dot(d, d)) + sqrt(fro) * r) * (1.0 + 1e-12) + 1e-12 * (scale + r);
}
