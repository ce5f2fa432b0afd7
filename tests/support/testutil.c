/* testutil.c -- shared helpers of the C unit tests. */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

/* ---- Added for the per-concept unit tests. ---- */


double test_max_abs_diff(const double *a, const double *b, size_t n)
{
    double m = 0;
    size_t i;
    for (i = 0; i < n; i++) {
        double d = fabs(a[i] - b[i]);
        if (!(d <= m)) m = d; /* NaN propagates as the maximum */
    }
    return m;
}

void test_rodrigues(const double axis[3], double angle, double R[9])
{
    double n = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    double x = axis[0] / n, y = axis[1] / n, z = axis[2] / n;
    double K[9] = {0, -z, y, z, 0, -x, -y, x, 0}, K2[9];
    double s = sin(angle), c1 = 1.0 - cos(angle);
    int i;
    test_mat3_mul(K, K, K2);
    for (i = 0; i < 9; i++) R[i] = (i % 4 == 0 ? 1.0 : 0.0) + s * K[i] + c1 * K2[i];
}

void test_quat_matrix(const double q[4], double R[9])
{
    double w = q[0], v[3] = {q[1], q[2], q[3]};
    double d = w * w - (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    double S[9] = {0, -v[2], v[1], v[2], 0, -v[0], -v[1], v[0], 0};
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            R[3 * i + j] = (i == j ? d : 0.0) + 2.0 * v[i] * v[j] + 2.0 * w * S[3 * i + j];
}

void test_mat3_mul(const double A[9], const double B[9], double C[9])
{
    int i, j, k;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            double s = 0;
            for (k = 0; k < 3; k++) s += A[3 * i + k] * B[3 * k + j];
            C[3 * i + j] = s;
        }
}

void test_random_quat(uint64_t *state, double q[4])
{
    const double two_pi = 6.283185307179586;
    double u1 = test_uniform(state, 0, 1), u2 = test_uniform(state, 0, 1);
    double u3 = test_uniform(state, 0, 1), a = sqrt(1 - u1), b = sqrt(u1);
    q[0] = a * sin(two_pi * u2);
    q[1] = a * cos(two_pi * u2);
    q[2] = b * sin(two_pi * u3);
    q[3] = b * cos(two_pi * u3);
    if (q[0] < 0) {
        q[0] = -q[0];
        q[1] = -q[1];
        q[2] = -q[2];
        q[3] = -q[3];
    }
}

void test_assert_contains(const char *text, const char *needle)
{
    if (!text || !strstr(text, needle)) {
        print_error("expected \"%s\" in the message \"%s\"\n", needle, text ? text : "(null)");
        fail();
    }
}

aqs_linkage *test_new_linkage(void)
{
    aqs_linkage *L = NULL;
    assert_int_equal(aqs_linkage_create(&L), AQS_OK);
    assert_non_null(L);
    return L;
}

aqs_linkage *test_new_linkage_in(counting_state *cs)
{
    aqs_linkage *L = NULL;
    if (cs)
        assert_int_equal(aqs_linkage_create_with_allocator(counting_alloc, counting_free, cs, &L), AQS_OK);
    else
        assert_int_equal(aqs_linkage_create(&L), AQS_OK);
    return L;
}
