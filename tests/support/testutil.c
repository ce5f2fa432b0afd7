/* testutil.c -- shared helpers of the C unit tests. */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>

void *counting_alloc(void *user, size_t size)
{
    counting_state *s = user;
    void *p;
    s->count++;
    if (s->fail_at > 0 && s->count == s->fail_at) return NULL;
    p = malloc(size);
    if (p) {
        s->allocs++;
        s->live++;
    }
    return p;
}

void counting_free(void *user, void *ptr)
{
    counting_state *s = user;
    s->frees++;
    s->live--;
    free(ptr);
}

double test_uniform(uint64_t *state, double lo, double hi)
{
    /* splitmix64 */
    uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return lo + (hi - lo) * (double)(z >> 11) / 9007199254740992.0;
}

int32_t test_add_body(aqs_linkage *L, double m, double cx, double cy, double cz, double d)
{
    double com[3] = {cx, cy, cz}, I[9] = {d, 0, 0, 0, d, 0, 0, 0, d};
    int32_t b = -1;
    assert_int_equal(aqs_body_add(L, m, com, I, &b), AQS_OK);
    return b;
}

int32_t test_add_joint(aqs_linkage *L, int32_t type, int32_t parent, int32_t child, double px,
                       double py, double pz, double ax, double ay, double az)
{
    double pos[3] = {px, py, pz}, quat[4] = {1, 0, 0, 0}, axis[3] = {ax, ay, az};
    int32_t j = -1;
    assert_int_equal(aqs_joint_add(L, type, parent, child, pos, quat, axis, &j), AQS_OK);
    return j;
}

double test_rel_diff(const double *a, const double *b, size_t n)
{
    double num = 0, den = 0;
    size_t i;
    for (i = 0; i < n; i++) {
        num += (a[i] - b[i]) * (a[i] - b[i]);
        den += b[i] * b[i];
    }
    return den > 0 ? sqrt(num / den) : sqrt(num);
}
