/*
 * scenes.h -- the paper's benchmark scenes, built through the public API.
 *
 * Every builder adds bodies and joints to an empty, unfinalized linkage and
 * returns the first non-OK aqs_status it meets (the linkage's
 * aqs_linkage_last_error() then says why), or AQS_EINVAL / AQS_ENOMEM for a
 * bad size or a failed scratch allocation of the builder itself. Bodies and
 * joints are added in pairs, so joint i is always the parent joint of body i.
 *
 * Randomness comes from bench_rng (xoshiro256** seeded by splitmix64): the
 * integer stream is identical on every platform; geometry derived from it
 * uses libm (sin, cos, log, sqrt), so positions agree across platforms to
 * the last few bits. Parameters of each scene: bench/README.md.
 */
#ifndef BENCH_SCENES_H
#define BENCH_SCENES_H

#include <stdint.h>

#include "aqs.h"

/* ------------------------------------------------------------------------
 * Deterministic random numbers
 * ---------------------------------------------------------------------- */

typedef struct bench_rng {
    uint64_t s[4];
} bench_rng;

/** Seed the generator (any seed, 0 included). */
void bench_rng_seed(bench_rng *rng, uint64_t seed);
/** Next 64 random bits. */
uint64_t bench_rng_next(bench_rng *rng);
/** Uniform double in [0, 1), 53 random bits. */
double bench_rng_uniform(bench_rng *rng);
/** Uniform integer in [0, n), n > 0, without modulo bias. */
uint64_t bench_rng_below(bench_rng *rng, uint64_t n);
/** Normal deviate N(mean, sd) (Box-Muller, one deviate per call). */
double bench_rng_normal(bench_rng *rng, double mean, double sd);
/** Uniform random unit vector in R^3. */
void bench_rng_unit_vector(bench_rng *rng, double out[3]);

/* ------------------------------------------------------------------------
 * chain30: the bicycle chain (paper section 6.1, Figure 1)
 * ---------------------------------------------------------------------- */

#define BENCH_CHAIN30_LINKS 30
#define BENCH_CHAIN30_LINK_LENGTH 1.0 /**< m, along each link's body x axis */

/** 30 links of length 1 along x, revolute joints about z (parallel axes),
 *  the first joint from the world at the origin: a straight planar chain
 *  along +x at q = 0. Link i is body i and the child of joint i. */
aqs_status bench_build_chain30(aqs_linkage *linkage);

/** Body index of the last link (the tip); its far end is the body-frame point
 *  (BENCH_CHAIN30_LINK_LENGTH, 0, 0). */
int32_t bench_chain30_tip_body(void);

/* ------------------------------------------------------------------------
 * chain: a long revolute chain for timing
 * ---------------------------------------------------------------------- */

#define BENCH_CHAIN_SEED UINT64_C(0x5eedc4a1)

/** n >= 1 unit links, each joint revolute about a seeded random axis, the
 *  joint frame turned by a seeded random rotation (angle <= 60 degrees) so the
 *  chain coils instead of running straight. Fixed base (joint 0 from the
 *  world). Link i is body i, the child of joint i. */
aqs_status bench_build_chain(aqs_linkage *linkage, int32_t n);

/* ------------------------------------------------------------------------
 * molecule: random molecule-like tree (paper section 6.3, Figure 6)
 * ---------------------------------------------------------------------- */

#define BENCH_MOLECULE_SEED UINT64_C(20050801)
#define BENCH_MOLECULE_BOND_MEAN 1.5      /**< bond length mean */
#define BENCH_MOLECULE_BOND_SD 0.03       /**< bond length standard deviation */
#define BENCH_MOLECULE_ANGLE_MEAN_DEG 111.0 /**< bond angle mean, degrees */
#define BENCH_MOLECULE_ANGLE_SD_DEG 4.0   /**< bond angle standard deviation */

/** A random molecule-like tree with exactly njoints (>= 1) revolute torsion
 *  joints and as many atoms (bodies): a backbone of round(0.42 njoints) atoms
 *  (body 0 is the first, child of a revolute joint about the world z axis),
 *  side chains of 1-4 atoms on about half the backbone atoms, some forked.
 *  Each body frame sits at its atom with z along the incoming bond; each
 *  joint rotates its child's subtree about that bond. */
aqs_status bench_build_molecule(aqs_linkage *linkage, int32_t njoints, uint64_t seed);

/** As bench_build_molecule; also writes parents[i] = the parent body of body
 *  i (AQS_WORLD for body 0) when parents (njoints) is non-NULL, and
 *  backbone_atoms when non-NULL. */
aqs_status bench_build_molecule_ex(aqs_linkage *linkage, int32_t njoints, uint64_t seed,
                                   int32_t *parents, int32_t *backbone_atoms);

/** Every this many-th terminal atom (the one in the middle of each run of
 *  this many) weighs bench_build_molecule_heavy's factor times its mass. */
#define BENCH_MOLECULE_HEAVY_EVERY 400

/** As bench_build_molecule (the same tree, positions and random draws), with
 *  the mass and inertia of every BENCH_MOLECULE_HEAVY_EVERY-th terminal atom
 *  multiplied by heavy (> 0, finite; else AQS_EINVAL): at heavy = 1e3 the
 *  linkage has heavy children (a child 1e3 times its parent), on which the
 *  exact articulated-body solve refines (docs/bench.md, "The automatic path
 *  on heavy linkages"). heavy = 1 builds bench_build_molecule's linkage. */
aqs_status bench_build_molecule_heavy(aqs_linkage *linkage, int32_t njoints, uint64_t seed, double heavy);

/* ------------------------------------------------------------------------
 * millipede: spine and legs (paper section 6.2, Figures 4 and 5)
 * ---------------------------------------------------------------------- */

#define BENCH_MILLIPEDE_SPINE 3000
#define BENCH_MILLIPEDE_LEGS 1000
#define BENCH_MILLIPEDE_LEG_LINKS 10
#define BENCH_MILLIPEDE_LINKS \
    (BENCH_MILLIPEDE_SPINE + BENCH_MILLIPEDE_LEGS * BENCH_MILLIPEDE_LEG_LINKS)
#define BENCH_MILLIPEDE_LEG_LINK_LENGTH 0.3 /**< m */

/** 3,000 unit spine rods (bodies 0..2999) along x; joint i (1..2999) joins
 *  rod i-1 to rod i about z for odd i, about y for even i; joint 0 is a free
 *  joint from the world to rod 0. Leg l (0..999) hangs from the middle of
 *  rod 3l, on +y for even l and -y for odd l, as 10 links of 0.3 m (bodies
 *  3000 + 10 l + k, k = 0..9), each link's body x along the leg, joint axes
 *  alternating z, y in the leg's frame (swing, lift). 13,000 bodies and
 *  13,000 joints: 1 free + 12,999 revolute. */
aqs_status bench_build_millipede(aqs_linkage *linkage);

/** Body index of link k (0 = at the spine, 9 = the foot) of leg l. */
int32_t bench_millipede_leg_body(int32_t leg, int32_t link);

/* ------------------------------------------------------------------------
 * The scenes by name (aqs-bench, and anything that takes a scene argument)
 * ---------------------------------------------------------------------- */

typedef enum bench_scene_kind {
    BENCH_SCENE_CHAIN30 = 0,
    BENCH_SCENE_CHAIN = 1,
    BENCH_SCENE_MOLECULE = 2,
    BENCH_SCENE_MILLIPEDE = 3,
    BENCH_SCENE_COUNT = 4
} bench_scene_kind;

/** "chain30", "chain", "molecule", "millipede"; NULL for an unknown kind. */
const char *bench_scene_name(bench_scene_kind kind);

/** The kind named name; -1 if there is none. */
int bench_scene_from_name(const char *name);

/** 1 if the scene's size is a parameter (chain, molecule), else 0. */
int bench_scene_has_size(bench_scene_kind kind);

/** Default size: joints of chain (50,000) and molecule (50,000); the fixed
 *  joint count of chain30 (30) and millipede (13,000). */
int32_t bench_scene_default_size(bench_scene_kind kind);

/** Build scene kind into an empty linkage; size is used by the sized scenes
 *  only; the molecule uses BENCH_MOLECULE_SEED, the chain BENCH_CHAIN_SEED. */
aqs_status bench_build_scene(aqs_linkage *linkage, bench_scene_kind kind, int32_t size);

/** Centre of mass of body (body frame) in scene kind: the middle of a rod
 *  or link, the atom itself in the molecule. */
void bench_scene_body_com(bench_scene_kind kind, int32_t body, double com[3]);

#endif /* BENCH_SCENES_H */
