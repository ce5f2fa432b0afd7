/* fpenv.c -- flush-to-zero for the duration of a solve (src/base/fpenv.h). */
#include "fpenv.h"

#if defined(__SSE2__) || defined(_M_X64) || (defined(_M_IX86_FP) && _M_IX86_FP >= 2)
#include <xmmintrin.h>
#define FPENV_SSE 1
#endif

void fpenv_enter(fpenv *e, int on)
{
    e->changed = 0;
#ifdef FPENV_SSE
    if (on) {
        const unsigned int c = _mm_getcsr();
        if (!(c & _MM_FLUSH_ZERO_ON)) { /* FTZ only: subnormal inputs keep their values */
            e->changed = 1;
            _mm_setcsr(c | _MM_FLUSH_ZERO_ON);
        }
    }
#else
    (void)on;
#endif
}

void fpenv_leave(const fpenv *e)
{
#ifdef FPENV_SSE
    /* only the bit set: the exception flags the solve raised stay raised,
     * as they would without it */
    if (e->changed) _mm_setcsr(_mm_getcsr() & ~(unsigned int)_MM_FLUSH_ZERO_ON);
#else
    (void)e;
#endif
}
