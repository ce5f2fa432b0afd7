/* oblique_frames.c -- the oblique chain two ways (docs/math.md 13a, "What is left"): (a) axes (0,1,1)/sqrt2 in identity frames; (b) the same chain with
 * the first joint's frame rotated by 45 deg about x (so every body frame has z along the axis) and
 * axes z. ABA vs exact DCA, and (a) vs (b) (the same physics). */
#include <aqs.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
static aqs_linkage *build(int n, int rotated, double *qdd_aba, double *qdd_dca) {
    aqs_linkage *L; aqs_linkage_create(&L);
    const double com[3] = {0.5, 0, 0}, I[9] = {0.01, 0, 0, 0, 0.1, 0, 0, 0, 0.1}, q1[4] = {1, 0, 0, 0};
    const double ao[3] = {0, 0.70710678118654752, 0.70710678118654752}, az[3] = {0, 0, 1};
    /* rotation about x by -45 deg maps z to (0, sin45, cos45) */
    const double c = cos(-M_PI / 8), s = sin(-M_PI / 8), qr[4] = {c, s, 0, 0};
    int32_t prev = AQS_WORLD, b;
    for (int i = 0; i < n; i++) {
        const double pos[3] = {i ? 1.0 : 0.0, 0, 0};
        aqs_body_add(L, 1.0, com, I, &b);
        if (aqs_joint_add(L, AQS_JOINT_REVOLUTE, prev, b, pos, rotated && i == 0 ? qr : q1, rotated ? az : ao, NULL) != AQS_OK) { printf("%s\n", aqs_linkage_last_error(L)); exit(1); }
        prev = b;
    }
    aqs_linkage_finalize(L);
    const double g[3] = {0, -9.81, 0};
    aqs_linkage_set_gravity(L, g);
    aqs_linkage_solve(L); aqs_linkage_get_accelerations(L, qdd_aba, n);
    aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA); aqs_linkage_set_auto(L, 0);
    aqs_linkage_solve(L); aqs_linkage_get_accelerations(L, qdd_dca, n);
    return L;
}
static double rel(const double *a, const double *b, int n) { double x = 0, y = 0; for (int i = 0; i < n; i++) { x += (a[i]-b[i])*(a[i]-b[i]); y += b[i]*b[i]; } return sqrt(x/y); }
int main(int argc, char **argv) {
    int n = atoi(argv[1]);
    double *aa = malloc(8.0*n), *ad = malloc(8.0*n), *ba = malloc(8.0*n), *bd = malloc(8.0*n);
    build(n, 0, aa, ad); build(n, 1, ba, bd);
    printf("n=%d  oblique: ABA vs DCA %.2e | rotated frames: ABA vs DCA %.2e | ABA obl vs ABA rot %.2e | DCA obl vs DCA rot %.2e | DCA obl vs ABA rot %.2e  qdd0 %.4f %.4f\n",
           n, rel(aa, ad, n), rel(ba, bd, n), rel(aa, ba, n), rel(ad, bd, n), rel(ad, ba, n), aa[0], ba[0]);
    return 0;
}
