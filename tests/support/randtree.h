/* randtree.h -- random linkages for the tests of the adaptive solver and its
 * bounds (test_adaptive.c, test_worldbound.c). */
#ifndef AQS_TEST_RANDTREE_H
#define AQS_TEST_RANDTREE_H

#include "testutil.h"

typedef struct {
    int32_t nbodies;
    int floating;       /* the first joint is free (else revolute) */
    int gravity;        /* a random gravity (else none) */
    int nforces;        /* random loads on random bodies */
    int revolute_only;  /* every other joint revolute (else of random type) */
    double mass_spread; /* masses in [1/s, s] (log-uniform) */
    int chain;          /* every body hangs from the one before: a pure chain */
    double reach;       /* joint placements in [-reach, reach]^3; 0: 0.8 */
    int some_prismatic; /* with revolute_only: joints i % 5 == 2 prismatic */
    int uniform_quat;   /* quaternions by test_random_quat (uniform) rather than
                           normalized samples of the cube */
} test_tree_spec;

/* A random tree: body i hangs from a random earlier body (chains when the
 * drawn branchiness is small), the exact solver set to AQS_EXACT_DCA (the
 * twin reference of these tests back-substitutes the same coefficients as
 * the adaptive solve, so a difference is truncation alone), finalized, at
 * random positions, with the gravity and loads the spec asks for. */
aqs_linkage *test_random_tree(uint64_t *rng, const test_tree_spec *sp);

/* test_random_tree with joints of every type, gravity, nforces loads, masses
 * over mass_spread, a floating base when floating is set. */
aqs_linkage *test_mixed_tree(uint64_t *rng, int32_t nbodies, int floating, int nforces, double mass_spread);

#endif
