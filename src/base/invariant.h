/* invariant.h -- AQS_ASSERT(cond): an internal invariant (never a check of
 * user input: that returns a status). Compiled in debug and sanitizer builds
 * (AQS_DEBUG: make SANITIZE=1 or DEBUG=1, and the fuzz target), where a
 * violation prints the condition and aborts; compiled out of release builds,
 * where cond is not evaluated (only type-checked) and nothing prints. */
#ifndef AQS_INVARIANT_H
#define AQS_INVARIANT_H

#ifdef AQS_DEBUG
#include <stdio.h>
#include <stdlib.h>
#define AQS_ASSERT(cond)                                                                       \
    do {                                                                                       \
        if (!(cond)) {                                                                         \
            fprintf(stderr, "%s:%d: aqs internal invariant violated: %s\n", __FILE__, __LINE__, \
                    #cond);                                                                    \
            abort();                                                                           \
        }                                                                                      \
    } while (0)
#else
#define AQS_ASSERT(cond) ((void)sizeof(!(cond)))
#endif

#endif
