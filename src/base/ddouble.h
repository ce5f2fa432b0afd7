/* ddouble.h -- double-double arithmetic: a value held as the unevaluated sum
 * hi + lo of two doubles (|lo| <= ulp(hi) / 2), about 106 bits. For sums
 * whose terms are many orders of magnitude larger than the sum, where a
 * double loses u times the largest term (the articulated-body solve's
 * residual on a heavy body held by light links: src/solve/abarefine.c,
 * docs/math.md §5b). Built from error-free transformations: Knuth's two-sum
 * and an exact product (fma where the compiler has a fast one, else
 * Dekker's splitting, whose products of halves are exact, so that neither
 * depends on whether the compiler contracts a * b + c). Round-to-nearest
 * double arithmetic without extended intermediates (FLT_EVAL_METHOD 0, as
 * on x86-64 and AArch64) is assumed. */
#ifndef AQS_DDOUBLE_H
#define AQS_DDOUBLE_H

#include <math.h>

typedef struct {
    double hi, lo;
} ddouble;

static inline ddouble dd_from(double a)
{
    ddouble r;
    r.hi = a;
    r.lo = 0.0;
    return r;
}

/* s + e = a + b exactly (Knuth). */
static inline ddouble dd_two_sum(double a, double b)
{
    ddouble r;
    const double s = a + b, bb = s - a;
    r.hi = s;
    r.lo = (a - (s - bb)) + (b - bb);
    return r;
}

/* s + e = a + b exactly, for |a| >= |b| or a = 0 (Dekker). */
static inline ddouble dd_fast_two_sum(double a, double b)
{
    ddouble r;
    const double s = a + b;
    r.hi = s;
    r.lo = b - (s - a);
    return r;
}

/* p + e = a b exactly (no overflow assumed). */
static inline ddouble dd_two_prod(double a, double b)
{
    ddouble r;
    r.hi = a * b;
#ifdef FP_FAST_FMA
    r.lo = fma(a, b, -r.hi);
#else
    {
        const double sp = 134217729.0; /* 2^27 + 1 */
        const double ca = sp * a, cb = sp * b;
        const double ah = ca - (ca - a), al = a - ah, bh = cb - (cb - b), bl = b - bh;
        r.lo = ((ah * bh - r.hi) + ah * bl + al * bh) + al * bl;
    }
#endif
    return r;
}

/* a + b, to a relative error of a few u^2 of |a| + |b| (the "sloppy"
 * double-double sum: enough here, where the sums' terms, not their results,
 * set the scale). */
static inline ddouble dd_add(ddouble a, ddouble b)
{
    ddouble s = dd_two_sum(a.hi, b.hi);
    s.lo += a.lo + b.lo;
    return dd_fast_two_sum(s.hi, s.lo);
}

static inline ddouble dd_neg(ddouble a)
{
    a.hi = -a.hi;
    a.lo = -a.lo;
    return a;
}

/* a + b c, b and c doubles (b c formed exactly). */
static inline ddouble dd_add_prod(ddouble a, double b, double c)
{
    return dd_add(a, dd_two_prod(b, c));
}

/* a + b c, b a double. */
static inline ddouble dd_add_mul(ddouble a, double b, ddouble c)
{
    ddouble p = dd_two_prod(b, c.hi);
    p.lo += b * c.lo;
    return dd_add(a, dd_fast_two_sum(p.hi, p.lo));
}

/* The same three with the fma instruction, for code compiled for the "fma"
 * target and run only where the processor has it (src/solve/residual.c):
 * the same results bit for bit, the product being exact either way. */
#if defined(__GNUC__) && defined(__x86_64__) && defined(__SSE2__) && !defined(AQS_NO_FMA_DISPATCH)
#define DD_FMA_TARGET __attribute__((target("fma")))
static inline DD_FMA_TARGET ddouble dd_two_prod_fma(double a, double b)
{
    ddouble r;
    r.hi = a * b;
    r.lo = __builtin_fma(a, b, -r.hi);
    return r;
}

static inline DD_FMA_TARGET ddouble dd_add_prod_fma(ddouble a, double b, double c)
{
    return dd_add(a, dd_two_prod_fma(b, c));
}

static inline DD_FMA_TARGET ddouble dd_add_mul_fma(ddouble a, double b, ddouble c)
{
    ddouble p = dd_two_prod_fma(b, c.hi);
    p.lo += b * c.lo;
    return dd_add(a, dd_fast_two_sum(p.hi, p.lo));
}
#endif

/* The nearest double (up to one rounding of lo). */
static inline double dd_to_double(ddouble a)
{
    return a.hi + a.lo;
}

#endif
