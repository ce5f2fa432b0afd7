/* chains.h -- chains of revolute links with masses alternating or falling
 * off along them, the hard-case suite's families (tests/reference/
 * hardcases.cpp: altmass, lightdistal) in the tests of the refinements
 * (test_refine.c, test_arefine.c). */
#ifndef AQS_TEST_CHAINS_H
#define AQS_TEST_CHAINS_H

#include "testutil.h"

/* n revolute links along x, 1 m apart (the first at the origin), identity
 * orientations: link i of mass m[i], centre of mass at 0.5 m, inertias
 * 0.01 m[i], 0.1 m[i], 0.1 m[i], axes alternating z and y; with weld, a
 * 0.3 kg body welded to every third link (without, link i is body i).
 * Finalized, at positions q, under gravity g. With cs, the linkage's
 * allocator is the counting one (else malloc). */
aqs_linkage *test_zy_chain(counting_state *cs, int32_t n, const double *m, int weld, const double *q,
                           const double g[3]);

/* hardcases' altmass: n links (test_zy_chain), masses alternating 1 and
 * ratio, hanging under gravity along x at random angles (uniform in
 * (-0.5, 0.5), drawn from seed). */
aqs_linkage *test_altmass_chain(counting_state *cs, int32_t n, double ratio, int weld, uint64_t seed);

#endif
