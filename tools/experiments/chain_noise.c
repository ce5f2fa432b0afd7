/* chain_noise.c -- where the exact DCA's error on the straight chain under gravity
 * sits (docs/math.md 13a, "Where that error sat"): the hardcases chain (1 kg, 1 m links,
 * revolute about z, gravity -y), the ABA against the unrefined and the refined exact DCA,
 * the error by tenths of the chain. Build against the library:
 *   gcc -O2 -Iinclude tools/experiments/chain_noise.c -Lbuild -Wl,-rpath,$PWD/build -laqs -lm
 *   ./a.out 1000000   (about 30 s and 5 GB) */
#include <aqs.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
static double rel(const double *a, const double *b, int n, int *imax) {
    double num = 0, den = 0, m = 0; *imax = -1;
    for (int i = 0; i < n; i++) { double d = a[i] - b[i]; num += d * d; den += b[i] * b[i]; if (fabs(d) > m) { m = fabs(d); *imax = i; } }
    return sqrt(num / den);
}
int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: %s LINKS\n", argv[0]); return 2; }
    int n = atoi(argv[1]);
    aqs_linkage *L; aqs_linkage_create(&L);
    const double com[3] = {0.5, 0, 0}, I[9] = {0.01, 0, 0, 0, 0.1, 0, 0, 0, 0.1}, quat[4] = {1, 0, 0, 0}, az[3] = {0, 0, 1};
    int32_t prev = AQS_WORLD, b;
    for (int i = 0; i < n; i++) {
        const double pos[3] = {i ? 1.0 : 0.0, 0, 0};
        aqs_body_add(L, 1.0, com, I, &b);
        if (aqs_joint_add(L, AQS_JOINT_REVOLUTE, prev, b, pos, quat, az, NULL) != AQS_OK) { printf("%s\n", aqs_linkage_last_error(L)); return 1; }
        prev = b;
    }
    if (aqs_linkage_finalize(L) != AQS_OK) { printf("%s\n", aqs_linkage_last_error(L)); return 1; }
    const double g[3] = {0, -9.81, 0};
    aqs_linkage_set_gravity(L, g);
    double *qa = malloc(8.0 * n), *qu = malloc(8.0 * n), *qr = malloc(8.0 * n);
    aqs_linkage_solve(L); aqs_linkage_get_accelerations(L, qa, n);
    aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA); aqs_linkage_set_auto(L, 0);
    aqs_linkage_set_exact_refinement(L, 0);
    if (aqs_linkage_solve(L) != AQS_OK) { printf("%s\n", aqs_linkage_last_error(L)); return 1; }
    aqs_linkage_get_accelerations(L, qu, n);
    aqs_linkage_set_exact_refinement(L, 3);
    aqs_linkage_solve(L); aqs_linkage_get_accelerations(L, qr, n);
    int iu, ir;
    double eu = rel(qu, qa, n, &iu), er = rel(qr, qa, n, &ir);
    printf("n=%d unrefined %.2e (max at %d: %.3e vs %.3e) refined %.2e (max at %d)  qdd[0]=%.3e qdd[n-1]=%.3e\n", n, eu, iu, qu[iu], qa[iu], er, ir, qa[0], qa[n-1]);
    /* where the error sits: the error profile in deciles */
    for (int k = 0; k < 10; k++) { double m = 0, s = 0; for (int i = k * n / 10; i < (k + 1) * n / 10; i++) { m = fmax(m, fabs(qu[i] - qa[i])); s = fmax(s, fabs(qa[i])); } printf("  decile %d: max err %.2e max |qdd| %.2e\n", k, m, s); }
    return 0;
}
