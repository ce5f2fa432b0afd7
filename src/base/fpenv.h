/* fpenv.h -- the floating-point environment of a solve (docs/math.md §11).
 *
 * Results that would be subnormal (below DBL_MIN = 2.2e-308 in magnitude)
 * are flushed to zero while the library solves: on x86 a subnormal result
 * costs about a hundred times a normal one, and a linkage loaded at one end
 * has accelerations decaying through the tree into that range (42 % of the
 * 50,000-joint molecule's under one 1 N force). The caller's environment is
 * restored on return, on every path; inputs are read as they are (no
 * denormals-are-zero). Where the
 * target has no flush-to-zero control these are no-ops. */
#ifndef AQS_FPENV_H
#define AQS_FPENV_H

typedef struct {
    int changed;        /* whether fpenv_leave must restore it */
} fpenv;

/* Turn flush-to-zero on (if `on`) and remember the caller's setting. */
void fpenv_enter(fpenv *e, int on);
/* Restore the caller's setting (the flush-to-zero bit only: the exception
 * flags raised meanwhile stay, as they would without it). */
void fpenv_leave(const fpenv *e);

#endif
