/*
 * scenes.c -- seeded builders of the benchmark scenes (see scenes.h and
 * bench/README.md for the parameters).
 */
#include "scenes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define BENCH_PI 3.14159265358979323846

static const double identity_quat[4] = {1.0, 0.0, 0.0, 0.0};
static const double axis_y[3] = {0.0, 1.0, 0.0};
static const double axis_z[3] = {0.0, 0.0, 1.0};
static const double origin[3] = {0.0, 0.0, 0.0};

/* ------------------------------------------------------------------------
 * Random numbers: splitmix64 to seed, xoshiro256** to draw.
 * ---------------------------------------------------------------------- */

static uint64_t splitmix64(uint64_t *x)
{
    uint64_t z = (*x += UINT64_C(0x9e3779b97f4a7c15));
    z = (z ^ (z >> 30)) * UINT64_C(0xbf58476d1ce4e5b9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94d049bb133111eb);
    return z ^ (z >> 31);
}

static uint64_t rotl64(uint64_t x, int k)
{
    return (x << k) | (x >> (64 - k));
}

void bench_rng_seed(bench_rng *rng, uint64_t seed)
{
    uint64_t x = seed;
    int i;
    for (i = 0; i < 4; ++i) {
        rng->s[i] = splitmix64(&x);
    }
}

uint64_t bench_rng_next(bench_rng *rng)
{
    uint64_t *s = rng->s;
    const uint64_t result = rotl64(s[1] * 5, 7) * 9;
    const uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = rotl64(s[3], 45);
    return result;
}

double bench_rng_uniform(bench_rng *rng)
{
    return (double)(bench_rng_next(rng) >> 11) * (1.0 / 9007199254740992.0);
}

uint64_t bench_rng_below(bench_rng *rng, uint64_t n)
{
    /* Reject the top partial block so every residue is equally likely. */
    const uint64_t limit = UINT64_MAX - UINT64_MAX % n;
    uint64_t x;
    do {
        x = bench_rng_next(rng);
    } while (x >= limit);
    return x % n;
}

double bench_rng_normal(bench_rng *rng, double mean, double sd)
{
    /* Box-Muller; 1 - u is in (0, 1], so the logarithm is finite. */
    const double u1 = 1.0 - bench_rng_uniform(rng);
    const double u2 = bench_rng_uniform(rng);
    return mean + sd * sqrt(-2.0 * log(u1)) * cos(2.0 * BENCH_PI * u2);
}

void bench_rng_unit_vector(bench_rng *rng, double out[3])
{
    const double z = 2.0 * bench_rng_uniform(rng) - 1.0;
    const double phi = 2.0 * BENCH_PI * bench_rng_uniform(rng);
    const double r = sqrt(1.0 - z * z);
    out[0] = r * cos(phi);
    out[1] = r * sin(phi);
    out[2] = z;
}

/* ------------------------------------------------------------------------
 * Shared pieces
 * ---------------------------------------------------------------------- */

/* Rotational inertia about the centre of a uniform box of mass m and side
 * lengths (lx, ly, lz), row-major 3 x 3. */
static void box_inertia(double m, double lx, double ly, double lz, double inertia[9])
{
    int i;
    for (i = 0; i < 9; ++i) {
        inertia[i] = 0.0;
    }
    inertia[0] = m * (ly * ly + lz * lz) / 12.0;
    inertia[4] = m * (lx * lx + lz * lz) / 12.0;
    inertia[8] = m * (lx * lx + ly * ly) / 12.0;
}

/* Add one body and its parent joint; the joint gets the body's index. */
static aqs_status add_link(aqs_linkage *linkage, double mass, const double com[3],
                           const double inertia[9], int32_t type, int32_t parent,
                           const double pos[3], const double quat[4], const double axis[3],
                           int32_t *out_body)
{
    int32_t body = -1;
    aqs_status st = aqs_body_add(linkage, mass, com, inertia, &body);
    if (st != AQS_OK) {
        return st;
    }
    st = aqs_joint_add(linkage, type, parent, body, pos, quat, axis, NULL);
    if (st != AQS_OK) {
        return st;
    }
    if (out_body != NULL) {
        *out_body = body;
    }
    return AQS_OK;
}

/* Quaternion (w, x, y, z) of a rotation by angle about a unit axis. */
static void axis_angle_quat(const double axis[3], double angle, double q[4])
{
    const double s = sin(0.5 * angle);
    q[0] = cos(0.5 * angle);
    q[1] = s * axis[0];
    q[2] = s * axis[1];
    q[3] = s * axis[2];
}

/* ------------------------------------------------------------------------
 * chain30 and chain
 * ---------------------------------------------------------------------- */

aqs_status bench_build_chain30(aqs_linkage *linkage)
{
    const double length = BENCH_CHAIN30_LINK_LENGTH;
    const double com[3] = {0.5 * BENCH_CHAIN30_LINK_LENGTH, 0.0, 0.0};
    const double joint_pos[3] = {BENCH_CHAIN30_LINK_LENGTH, 0.0, 0.0};
    double inertia[9];
    int32_t parent = AQS_WORLD;
    int32_t i;
    box_inertia(1.0, length, 0.1, 0.1, inertia);
    for (i = 0; i < BENCH_CHAIN30_LINKS; ++i) {
        int32_t body;
        aqs_status st = add_link(linkage, 1.0, com, inertia, AQS_JOINT_REVOLUTE, parent,
                                 i == 0 ? origin : joint_pos, identity_quat, axis_z, &body);
        if (st != AQS_OK) {
            return st;
        }
        parent = body;
    }
    return AQS_OK;
}

int32_t bench_chain30_tip_body(void)
{
    return BENCH_CHAIN30_LINKS - 1;
}

aqs_status bench_build_chain(aqs_linkage *linkage, int32_t n)
{
    const double com[3] = {0.5, 0.0, 0.0};
    const double joint_pos[3] = {1.0, 0.0, 0.0};
    double inertia[9];
    bench_rng rng;
    int32_t parent = AQS_WORLD;
    int32_t i;
    if (n < 1) {
        return AQS_EINVAL;
    }
    bench_rng_seed(&rng, BENCH_CHAIN_SEED);
    box_inertia(1.0, 1.0, 0.1, 0.1, inertia);
    for (i = 0; i < n; ++i) {
        double turn_axis[3], axis[3], quat[4];
        int32_t body;
        aqs_status st;
        bench_rng_unit_vector(&rng, turn_axis);
        axis_angle_quat(turn_axis, (BENCH_PI / 3.0) * bench_rng_uniform(&rng), quat);
        bench_rng_unit_vector(&rng, axis);
        st = add_link(linkage, 1.0, com, inertia, AQS_JOINT_REVOLUTE, parent,
                      i == 0 ? origin : joint_pos, i == 0 ? identity_quat : quat, axis, &body);
        if (st != AQS_OK) {
            return st;
        }
        parent = body;
    }
    return AQS_OK;
}

/* ------------------------------------------------------------------------
 * molecule
 *
 * Plan first (which backbone atom carries which side chain, so the atom count
 * is exact), then add the atoms depth-first: backbone atom k, its side chain,
 * backbone atom k + 1, ...
 *
 * Internal coordinates: the body frame of an atom c sits at c with z along
 * its incoming bond p -> c and x in the plane of (parent's incoming bond,
 * bond p -> c). In the parent's frame, c is at b (sin a cos phi, sin a sin phi,
 * cos a), a = pi - theta, theta the bond angle g-p-c, phi the dihedral; the
 * child frame is Rz(phi) Ry(a). The joint frame is the child frame at q = 0
 * and its axis is z: a torsion about the bond.
 * ---------------------------------------------------------------------- */

/* A side chain plan, packed in one byte: main length 0..4 (bits 0-2), the
 * chain atom the fork leaves from 0..3 (bits 3-4), fork length 0..2 (5-6). */
#define CHAIN_LEN(code) ((int)((code)&7u))
#define CHAIN_FORK_AT(code) ((int)(((code) >> 3) & 3u))
#define CHAIN_FORK_LEN(code) ((int)(((code) >> 5) & 3u))
#define CHAIN_SIZE(code) (CHAIN_LEN(code) + CHAIN_FORK_LEN(code))

static unsigned char chain_pack(int len, int fork_at, int fork_len)
{
    if (fork_len == 0) {
        fork_at = 0;
    }
    if (len == 0) {
        return 0;
    }
    return (unsigned char)(len | (fork_at << 3) | (fork_len << 5));
}

static unsigned char chain_random(bench_rng *rng)
{
    const double u = bench_rng_uniform(rng);
    const int len = u < 0.20 ? 1 : u < 0.45 ? 2 : u < 0.75 ? 3 : 4;
    int fork_at = 0, fork_len = 0;
    if (len >= 2 && bench_rng_uniform(rng) < 0.15) {
        fork_at = (int)bench_rng_below(rng, (uint64_t)(len - 1));
        fork_len = 1 + (int)bench_rng_below(rng, 2);
    }
    return chain_pack(len, fork_at, fork_len);
}

/* The plan with its size reduced by d (0 <= d <= size): the fork goes first. */
static unsigned char chain_shrink(unsigned char code, int d)
{
    int len = CHAIN_LEN(code), fork_at = CHAIN_FORK_AT(code), fork_len = CHAIN_FORK_LEN(code);
    const int from_fork = d < fork_len ? d : fork_len;
    fork_len -= from_fork;
    len -= d - from_fork;
    return chain_pack(len, fork_at, fork_len);
}

/* Side-chain plans for hosts 0..*backbone-1 with sizes summing to exactly
 * natoms - *backbone; the backbone grows if the hosts cannot hold enough. */
static void molecule_plan(bench_rng *rng, int32_t natoms, int32_t *backbone, unsigned char *plan)
{
    const int32_t hosts = *backbone;
    const int32_t target = natoms - hosts;
    int32_t total = 0, filled = 0, i;
    for (i = 0; i < natoms; ++i) {
        plan[i] = 0;
    }
    for (i = 0; i < hosts; ++i) {
        if (bench_rng_uniform(rng) < 0.5) {
            plan[i] = chain_random(rng);
            total += CHAIN_SIZE(plan[i]);
            ++filled;
        }
    }
    while (total < target && filled < hosts) {
        const int32_t k = (int32_t)bench_rng_below(rng, (uint64_t)hosts);
        if (plan[k] == 0) {
            unsigned char code = chain_random(rng);
            const int size = CHAIN_SIZE(code);
            if (size > target - total) {
                code = chain_shrink(code, size - (target - total));
            }
            plan[k] = code;
            total += CHAIN_SIZE(code);
            ++filled;
        }
    }
    while (total > target) {
        const int32_t k = (int32_t)bench_rng_below(rng, (uint64_t)hosts);
        if (plan[k] != 0) {
            const int size = CHAIN_SIZE(plan[k]);
            const int excess = total - target;
            plan[k] = chain_shrink(plan[k], size <= excess ? size : excess);
            total -= size <= excess ? size : excess;
        }
    }
    /* Every host full and still short (tiny molecules): a longer backbone. */
    *backbone = hosts + (target - total);
}

/* Mass of a group: an atom with its hydrogens (u, used as kg). */
static double atom_mass(bench_rng *rng, int terminal, int backbone)
{
    const double u = bench_rng_uniform(rng);
    if (backbone) { /* CH2, CH, NH, C, O, S */
        return u < 0.35 ? 14.0 : u < 0.60 ? 13.0 : u < 0.80 ? 15.0 : u < 0.90 ? 12.0
               : u < 0.97 ? 16.0 : 32.0;
    }
    if (terminal) { /* CH3, OH, NH2, =O, SH */
        return u < 0.55 ? 15.0 : u < 0.75 ? 17.0 : u < 0.85 ? 16.0 : u < 0.95 ? 16.0 : 33.0;
    }
    /* CH2, CH, NH, O, S */
    return u < 0.60 ? 14.0 : u < 0.75 ? 13.0 : u < 0.85 ? 15.0 : u < 0.95 ? 16.0 : 32.0;
}

typedef struct molecule_builder {
    aqs_linkage *linkage;
    bench_rng *rng;
    int32_t *parents; /* may be NULL */
    double heavy;     /* the mass factor of every BENCH_MOLECULE_HEAVY_EVERY-th terminal atom */
    int32_t terminals; /* terminal atoms added so far */
} molecule_builder;

/* Add one atom bonded to parent with dihedral phi (radians, in the parent's
 * frame), or the root atom when parent is AQS_WORLD. */
static aqs_status molecule_add_atom(molecule_builder *b, int32_t parent, double phi,
                                    int terminal, int backbone, int32_t *out_body)
{
    const double radius = 0.5; /* inertia of a ball-ish atom: 0.4 m r^2 */
    const double mass = atom_mass(b->rng, terminal, backbone) *
                        (terminal && b->terminals++ % BENCH_MOLECULE_HEAVY_EVERY == BENCH_MOLECULE_HEAVY_EVERY / 2
                             ? b->heavy
                             : 1.0);
    const double moment = 0.4 * mass * radius * radius;
    const double inertia[9] = {moment, 0.0, 0.0, 0.0, moment, 0.0, 0.0, 0.0, moment};
    double pos[3], quat[4];
    aqs_status st;
    if (parent == AQS_WORLD) {
        st = add_link(b->linkage, mass, origin, inertia, AQS_JOINT_REVOLUTE, AQS_WORLD, origin,
                      identity_quat, axis_z, out_body);
    } else {
        const double deg = BENCH_PI / 180.0;
        const double bond =
            bench_rng_normal(b->rng, BENCH_MOLECULE_BOND_MEAN, BENCH_MOLECULE_BOND_SD);
        const double theta = bench_rng_normal(b->rng, BENCH_MOLECULE_ANGLE_MEAN_DEG * deg,
                                              BENCH_MOLECULE_ANGLE_SD_DEG * deg);
        const double a = BENCH_PI - theta;
        const double ca = cos(0.5 * a), sa = sin(0.5 * a);
        const double cp = cos(0.5 * phi), sp = sin(0.5 * phi);
        pos[0] = bond * sin(a) * cos(phi);
        pos[1] = bond * sin(a) * sin(phi);
        pos[2] = bond * cos(a);
        /* Rz(phi) Ry(a) as a quaternion. */
        quat[0] = cp * ca;
        quat[1] = -sp * sa;
        quat[2] = cp * sa;
        quat[3] = sp * ca;
        st = add_link(b->linkage, mass, origin, inertia, AQS_JOINT_REVOLUTE, parent, pos, quat,
                      axis_z, out_body);
    }
    if (st == AQS_OK && b->parents != NULL) {
        b->parents[*out_body] = parent;
    }
    return st;
}

/* A random dihedral and its sibling 120 degrees to either side. */
static void sibling_dihedrals(bench_rng *rng, double *first, double *second)
{
    const double sign = (bench_rng_next(rng) >> 63) ? 1.0 : -1.0;
    *first = 2.0 * BENCH_PI * bench_rng_uniform(rng);
    *second = *first + sign * (2.0 * BENCH_PI / 3.0);
}

/* The side chain of plan code on host, its first atom at dihedral phi. */
static aqs_status molecule_add_side_chain(molecule_builder *b, int32_t host, double phi,
                                          unsigned char code)
{
    const int len = CHAIN_LEN(code), fork_at = CHAIN_FORK_AT(code);
    const int fork_len = CHAIN_FORK_LEN(code);
    int32_t atoms[4];
    double fork_phi = 0.0;
    int32_t parent = host;
    int j;
    aqs_status st;
    for (j = 0; j < len; ++j) {
        const int has_fork = fork_len > 0 && j == fork_at;
        const int terminal = j == len - 1 && !has_fork;
        double next_phi;
        st = molecule_add_atom(b, parent, phi, terminal, 0, &atoms[j]);
        if (st != AQS_OK) {
            return st;
        }
        if (has_fork) {
            sibling_dihedrals(b->rng, &next_phi, &fork_phi);
        } else {
            next_phi = 2.0 * BENCH_PI * bench_rng_uniform(b->rng);
        }
        parent = atoms[j];
        phi = next_phi;
    }
    if (fork_len > 0) {
        parent = atoms[fork_at];
        phi = fork_phi;
        for (j = 0; j < fork_len; ++j) {
            int32_t atom;
            st = molecule_add_atom(b, parent, phi, j == fork_len - 1, 0, &atom);
            if (st != AQS_OK) {
                return st;
            }
            parent = atom;
            phi = 2.0 * BENCH_PI * bench_rng_uniform(b->rng);
        }
    }
    return AQS_OK;
}

static aqs_status build_molecule(aqs_linkage *linkage, int32_t njoints, uint64_t seed, int32_t *parents,
                                 int32_t *backbone_atoms, double heavy)
{
    bench_rng rng;
    molecule_builder b;
    unsigned char *plan;
    int32_t backbone, k, previous = AQS_WORLD;
    double backbone_phi = 0.0;
    aqs_status st = AQS_OK;
    if (linkage == NULL || njoints < 1) {
        return AQS_EINVAL;
    }
    plan = (unsigned char *)malloc((size_t)njoints);
    if (plan == NULL) {
        return AQS_ENOMEM;
    }
    bench_rng_seed(&rng, seed);
    backbone = (int32_t)floor(0.42 * (double)njoints + 0.5);
    if (backbone < 1) {
        backbone = 1;
    }
    molecule_plan(&rng, njoints, &backbone, plan);
    b.linkage = linkage;
    b.rng = &rng;
    b.parents = parents;
    b.heavy = heavy;
    b.terminals = 0;
    for (k = 0; k < backbone && st == AQS_OK; ++k) {
        int32_t atom;
        double side_phi = 0.0;
        st = molecule_add_atom(&b, previous, backbone_phi, k == backbone - 1 && plan[k] == 0, 1,
                               &atom);
        if (st != AQS_OK) {
            break;
        }
        sibling_dihedrals(&rng, &backbone_phi, &side_phi);
        if (plan[k] != 0) {
            st = molecule_add_side_chain(&b, atom, side_phi, plan[k]);
        }
        previous = atom;
    }
    free(plan);
    if (st == AQS_OK && backbone_atoms != NULL) {
        *backbone_atoms = backbone;
    }
    return st;
}

aqs_status bench_build_molecule_ex(aqs_linkage *linkage, int32_t njoints, uint64_t seed,
                                   int32_t *parents, int32_t *backbone_atoms)
{
    return build_molecule(linkage, njoints, seed, parents, backbone_atoms, 1.0);
}

aqs_status bench_build_molecule(aqs_linkage *linkage, int32_t njoints, uint64_t seed)
{
    return build_molecule(linkage, njoints, seed, NULL, NULL, 1.0);
}

aqs_status bench_build_molecule_heavy(aqs_linkage *linkage, int32_t njoints, uint64_t seed, double heavy)
{
    if (!(heavy > 0.0) || !isfinite(heavy)) return AQS_EINVAL;
    return build_molecule(linkage, njoints, seed, NULL, NULL, heavy);
}

/* ------------------------------------------------------------------------
 * millipede
 * ---------------------------------------------------------------------- */

int32_t bench_millipede_leg_body(int32_t leg, int32_t link)
{
    return BENCH_MILLIPEDE_SPINE + leg * BENCH_MILLIPEDE_LEG_LINKS + link;
}

aqs_status bench_build_millipede(aqs_linkage *linkage)
{
    const double rod_com[3] = {0.5, 0.0, 0.0};
    const double rod_joint[3] = {1.0, 0.0, 0.0};
    const double leg_length = BENCH_MILLIPEDE_LEG_LINK_LENGTH;
    const double leg_com[3] = {0.5 * BENCH_MILLIPEDE_LEG_LINK_LENGTH, 0.0, 0.0};
    const double leg_joint[3] = {BENCH_MILLIPEDE_LEG_LINK_LENGTH, 0.0, 0.0};
    const double leg_mass = 0.1;
    const double rod_half_width = 0.05;
    double rod_inertia[9], leg_inertia[9];
    int32_t i, leg, k;
    aqs_status st;
    box_inertia(1.0, 1.0, 2.0 * rod_half_width, 2.0 * rod_half_width, rod_inertia);
    box_inertia(leg_mass, leg_length, 0.05, 0.05, leg_inertia);
    /* Spine: rod 0 floats; the axes alternate between z (odd joints) and y. */
    st = add_link(linkage, 1.0, rod_com, rod_inertia, AQS_JOINT_FREE, AQS_WORLD, origin,
                  identity_quat, NULL, NULL);
    for (i = 1; i < BENCH_MILLIPEDE_SPINE && st == AQS_OK; ++i) {
        st = add_link(linkage, 1.0, rod_com, rod_inertia, AQS_JOINT_REVOLUTE, i - 1, rod_joint,
                      identity_quat, (i % 2 == 1) ? axis_z : axis_y, NULL);
    }
    /* Legs: leg l on rod 3l, its frame turned +-90 degrees about z so that
     * its links run along +y (even l) or -y (odd l). */
    for (leg = 0; leg < BENCH_MILLIPEDE_LEGS && st == AQS_OK; ++leg) {
        const double side = (leg % 2 == 0) ? 1.0 : -1.0;
        const double h = sqrt(0.5);
        const double mount_quat[4] = {h, 0.0, 0.0, side * h};
        const double mount_pos[3] = {0.5, side * rod_half_width, 0.0};
        int32_t parent = 3 * leg;
        for (k = 0; k < BENCH_MILLIPEDE_LEG_LINKS && st == AQS_OK; ++k) {
            st = add_link(linkage, leg_mass, leg_com, leg_inertia, AQS_JOINT_REVOLUTE, parent,
                          k == 0 ? mount_pos : leg_joint, k == 0 ? mount_quat : identity_quat,
                          (k % 2 == 0) ? axis_z : axis_y, &parent);
        }
    }
    return st;
}

/* ------------------------------------------------------------------------
 * The scenes by name
 * ---------------------------------------------------------------------- */

static const char *const scene_names[BENCH_SCENE_COUNT] = {"chain30", "chain", "molecule",
                                                           "millipede"};

const char *bench_scene_name(bench_scene_kind kind)
{
    return ((int)kind >= 0 && kind < BENCH_SCENE_COUNT) ? scene_names[kind] : NULL;
}

int bench_scene_from_name(const char *name)
{
    int k;
    for (k = 0; k < BENCH_SCENE_COUNT && name != NULL; ++k) {
        if (strcmp(name, scene_names[k]) == 0) {
            return k;
        }
    }
    return -1;
}

int bench_scene_has_size(bench_scene_kind kind)
{
    return kind == BENCH_SCENE_CHAIN || kind == BENCH_SCENE_MOLECULE;
}

int32_t bench_scene_default_size(bench_scene_kind kind)
{
    switch (kind) {
    case BENCH_SCENE_CHAIN30:
        return BENCH_CHAIN30_LINKS;
    case BENCH_SCENE_MILLIPEDE:
        return BENCH_MILLIPEDE_LINKS;
    default:
        return 50000;
    }
}

aqs_status bench_build_scene(aqs_linkage *linkage, bench_scene_kind kind, int32_t size)
{
    switch (kind) {
    case BENCH_SCENE_CHAIN30:
        return bench_build_chain30(linkage);
    case BENCH_SCENE_CHAIN:
        return bench_build_chain(linkage, size);
    case BENCH_SCENE_MOLECULE:
        return bench_build_molecule(linkage, size, BENCH_MOLECULE_SEED);
    case BENCH_SCENE_MILLIPEDE:
        return bench_build_millipede(linkage);
    default:
        return AQS_EINVAL;
    }
}

void bench_scene_body_com(bench_scene_kind kind, int32_t body, double com[3])
{
    com[1] = com[2] = 0.0;
    switch (kind) {
    case BENCH_SCENE_MOLECULE:
        com[0] = 0.0;
        break;
    case BENCH_SCENE_MILLIPEDE:
        com[0] = body < BENCH_MILLIPEDE_SPINE ? 0.5 : 0.5 * BENCH_MILLIPEDE_LEG_LINK_LENGTH;
        break;
    default:
        com[0] = 0.5 * BENCH_CHAIN30_LINK_LENGTH; /* chain30 and chain: unit links */
        break;
    }
}
