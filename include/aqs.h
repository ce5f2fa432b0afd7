/*
 * aqs.h -- adaptive quasi-statics of large articulated linkages.
 *
 * The whole public C ABI of libaqs. C99 and C++ compatible.
 *
 * Conventions used throughout (see docs/api.md for the long form):
 *  - Units are the caller's, consistent (SI suggested: kg, m, s, N, N m).
 *  - Spatial vectors are 6-vectors, angular part first: a motion vector is
 *    [omega; v_O], a force vector is [n_O; f] (moment about the frame origin O).
 *  - Quaternions are (w, x, y, z), scalar first, unit length.
 *  - Bodies and joints are named by int32_t indices, in the order they were
 *    added, starting at 0. AQS_WORLD (-1) names the fixed world.
 *  - Every fallible function returns an aqs_status: AQS_OK (0) or a negative
 *    code. A failed call leaves the linkage as it was (model, positions,
 *    loads, settings), and aqs_linkage_last_error() then names the argument
 *    and value that were wrong. The one exception is a numerical failure
 *    (AQS_ENUMERIC) of solve, step or refine: positions are restored but the
 *    results of the failed solve are not readable until the next successful
 *    one. Nothing aborts, exits or prints.
 *  - Non-finite inputs (NaN, +-Inf) are rejected with AQS_EINVAL.
 *  - A linkage is used by one thread at a time; different linkages are
 *    independent. There is no global mutable state.
 */
#ifndef AQS_H
#define AQS_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(AQS_BUILDING_LIBRARY) && defined(__GNUC__)
#define AQS_API __attribute__((visibility("default")))
#else
#define AQS_API
#endif

/* ------------------------------------------------------------------------
 * Version
 * ---------------------------------------------------------------------- */

#define AQS_VERSION_MAJOR 0
#define AQS_VERSION_MINOR 1
#define AQS_VERSION_PATCH 0
/** The version as one number: MAJOR * 10000 + MINOR * 100 + PATCH. */
#define AQS_VERSION_NUMBER \
    (AQS_VERSION_MAJOR * 10000 + AQS_VERSION_MINOR * 100 + AQS_VERSION_PATCH)

/** Version of the library actually linked, as AQS_VERSION_NUMBER. Compare it
 *  with the header's AQS_VERSION_NUMBER to detect a mismatched build. */
AQS_API int32_t aqs_version(void);

/** Version of the linked library as a fixed string "MAJOR.MINOR.PATCH". */
AQS_API const char *aqs_version_string(void);

/* ------------------------------------------------------------------------
 * Status codes (fixed values; never renumbered)
 * ---------------------------------------------------------------------- */

typedef int32_t aqs_status;

#define AQS_OK 0        /**< success */
#define AQS_EINVAL (-1) /**< an argument is invalid (NULL, non-finite, out of its domain) */
#define AQS_ERANGE (-2) /**< a body or joint index is out of range */
#define AQS_ESTATE (-3) /**< wrong phase: e.g. adding after finalize, solving before */
#define AQS_ENOMEM (-4) /**< an allocation failed; the linkage is unchanged (a solve's hand-over to the exact DCA also discards the previous results: AQS_EXACT_ABA) */
#define AQS_EMODEL (-5) /**< finalize found the linkage invalid (topology, mass) */
#define AQS_ENUMERIC (-6) /**< a numerical failure (singular articulated inertia) */
#define AQS_ESIZE (-7)  /**< a caller's array is too small, or not the exact size asked; nothing was written */

/** A fixed, static text for a status code ("unknown status" for others). */
AQS_API const char *aqs_status_string(aqs_status status);

/* ------------------------------------------------------------------------
 * Creation, allocation, errors
 * ---------------------------------------------------------------------- */

/** Opaque linkage handle. */
typedef struct aqs_linkage aqs_linkage;

/** Allocation callback: return size bytes aligned for any C type
 *  (max_align_t), or NULL on failure. */
typedef void *(*aqs_alloc_fn)(void *user, size_t size);
/** Release callback for memory returned by the matching aqs_alloc_fn.
 *  Never called with NULL. */
typedef void (*aqs_free_fn)(void *user, void *ptr);

/** Create an empty linkage using malloc/free.
 *  out: receives the handle (non-NULL). Returns AQS_OK, AQS_EINVAL, AQS_ENOMEM. */
AQS_API aqs_status aqs_linkage_create(aqs_linkage **out);

/** Create an empty linkage whose memory all comes from alloc/free (both
 *  non-NULL), called with user as their first argument. Returns AQS_OK,
 *  AQS_EINVAL, AQS_ENOMEM. */
AQS_API aqs_status aqs_linkage_create_with_allocator(aqs_alloc_fn alloc, aqs_free_fn free_fn,
                                                     void *user, aqs_linkage **out);

/** Destroy a linkage and release all its memory. NULL is accepted. */
AQS_API void aqs_linkage_destroy(aqs_linkage *linkage);

/** The message of the last failed call on this linkage ("" if none): names
 *  the function, the argument and the offending value. Valid until the next
 *  call on the linkage. Never NULL (a NULL linkage gives a fixed text). */
AQS_API const char *aqs_linkage_last_error(const aqs_linkage *linkage);

/* ------------------------------------------------------------------------
 * Building (only before aqs_linkage_finalize; AQS_ESTATE afterwards)
 * ---------------------------------------------------------------------- */

#define AQS_WORLD (-1) /**< the fixed world, as a joint's parent */

/** Joint types (fixed values). Degrees of freedom (nq position values,
 *  nv acceleration values) in parentheses. "u" and "v" are the joint frame
 *  directions completing the axis a (see aqs_joint_add). */
#define AQS_JOINT_REVOLUTE 0    /**< rotation by q about a (nq 1, nv 1) */
#define AQS_JOINT_PRISMATIC 1   /**< translation by q along a (1, 1) */
#define AQS_JOINT_SPHERICAL 2   /**< rotation by a unit quaternion (4, 3) */
#define AQS_JOINT_FREE 3        /**< 6-dof floating base, world parent only (7, 6) */
#define AQS_JOINT_FIXED 4       /**< welded: no motion (0, 0) */
#define AQS_JOINT_UNIVERSAL 5   /**< rotation q1 about a, then q2 about the moved u (2, 2) */
#define AQS_JOINT_CYLINDRICAL 6 /**< rotation q1 about a and translation q2 along a (2, 2) */
#define AQS_JOINT_PLANAR 7      /**< translation q1 u + q2 v, then rotation q3 about a (3, 3) */

/** Whether aqs_body_add requires physically realizable inertias: positive
 *  semi-definite, principal moments obeying the triangle inequality
 *  (I1 + I2 >= I3), which every real mass distribution has. physical: 1 (the
 *  default) or 0 (accept any symmetric inertia, e.g. for synthetic test
 *  models or the per-link data of CAD exports; finalize still requires every
 *  moving rigid group to have mass and a positive definite inertia).
 *  Building phase only. Returns AQS_OK, AQS_EINVAL, AQS_ESTATE. */
AQS_API aqs_status aqs_linkage_set_inertia_check(aqs_linkage *linkage, int32_t physical);

/** Add a rigid body.
 *  mass: kg, finite, >= 0.
 *  com: (3) centre of mass in the body frame, m.
 *  inertia: (3 x 3, row-major) rotational inertia about the centre of mass in
 *        the body frame, kg m^2: symmetric (relative 1e-9); positive
 *        semi-definite (relative 1e-9) with principal moments obeying the
 *        triangle inequality (relative 1e-9) unless
 *        aqs_linkage_set_inertia_check(0).
 *  One rule for every mass: (0, zeros) and (0.01, zeros) are both accepted
 *  here. What the solvers need -- mass > 0 and a positive definite inertia --
 *  is checked at finalize on each rigid group (bodies welded by fixed joints;
 *  groups welded to the world are exempt), so a massless or point-mass body
 *  welded to a massive one is fine, and one that moves alone is AQS_EMODEL.
 *  out_body: receives the new body index (may be NULL).
 *  Returns AQS_OK, AQS_EINVAL, AQS_ESTATE, AQS_ENOMEM. */
AQS_API aqs_status aqs_body_add(aqs_linkage *linkage, double mass, const double com[3],
                                const double inertia[9], int32_t *out_body);

/** Add a joint from parent (a body index or AQS_WORLD) to child (a body index).
 *  type: one of AQS_JOINT_*.
 *  pos: (3) origin of the joint frame in the parent body frame (world frame for
 *       AQS_WORLD), m. quat: (4, w x y z) orientation of the joint frame in the
 *       parent frame; unit within 1e-6, then normalized.
 *  axis: (3) direction a in the joint frame, non-zero, normalized on input.
 *       Ignored (may be NULL) for spherical, free and fixed joints.
 *  The child body frame coincides with the joint frame at q = 0 and is moved
 *  from it by the joint position (URDF convention).
 *  Second directions: with e the coordinate axis along which |a| has its
 *  smallest component (the first such), u = normalize(e - (e.a) a) and
 *  v = a x u, so (u, v, a) is right-handed; for a = z this is (x, y, z).
 *  out_joint: receives the new joint index (may be NULL).
 *  A free joint whose parent is not AQS_WORLD is rejected here (AQS_EINVAL).
 *  Topology (one parent joint per body, no cycles, connected) is checked at
 *  finalize.
 *  Returns AQS_OK, AQS_EINVAL, AQS_ERANGE, AQS_ESTATE, AQS_ENOMEM. */
AQS_API aqs_status aqs_joint_add(aqs_linkage *linkage, int32_t type, int32_t parent,
                                 int32_t child, const double pos[3], const double quat[4],
                                 const double axis[3], int32_t *out_joint);

/** How finalize builds the assembly tree (MATH.md §10).
 *  AQS_TREE_CONTRACTION (default): tree contraction by rake and compress
 *  rounds: height O(log N), a node never has more handles than the largest
 *  body degree. AQS_TREE_BISECTION: recursive bisection at the most
 *  balancing joint: balanced, but more handles per node on branched trees
 *  (kept to compare tree shapes). Building phase only.
 *  Returns AQS_OK, AQS_EINVAL, AQS_ESTATE. */
#define AQS_TREE_CONTRACTION 0
#define AQS_TREE_BISECTION 1
AQS_API aqs_status aqs_linkage_set_tree_builder(aqs_linkage *linkage, int32_t builder);

/** Validate the linkage and build the assembly tree (topology and frames)
 *  and the exact solver's memory. The DCA coefficients of the tree (O(N)
 *  memory) are allocated and computed only when first needed: at finalize
 *  when the exact solver is AQS_EXACT_DCA, otherwise by the first
 *  aqs_linkage_set_tolerance / set_max_computed / set_exact_solver(DCA).
 *  Checks, reporting the first problem by body/joint index (AQS_EMODEL):
 *  at least one body; each body the child of exactly one joint; every body
 *  connected to the world (no cycles); every
 *  rigid group formed by fixed joints with positive mass and a positive
 *  definite inertia (unless welded to the world).
 *  Returns AQS_OK, AQS_EMODEL, AQS_ESTATE (already finalized), AQS_ENOMEM,
 *  AQS_ENUMERIC (with the DCA as exact solver; the articulated-body solver
 *  reports a singular articulated inertia at its first solve). On failure the
 *  linkage stays unfinalized and editable. */
AQS_API aqs_status aqs_linkage_finalize(aqs_linkage *linkage);

/** Sizes. Any phase. Each out pointer may be NULL.
 *  bodies, joints: counts as added; nq: position values; nv: acceleration
 *  values (sums over all joints of the per-type sizes above).
 *  Returns AQS_OK, AQS_EINVAL (NULL linkage). */
AQS_API aqs_status aqs_linkage_get_sizes(const aqs_linkage *linkage, int32_t *bodies,
                                         int32_t *joints, int32_t *nq, int32_t *nv);

/** Offsets of joint j in the bulk position and acceleration arrays and its
 *  sizes. Any phase. Each out pointer may be NULL.
 *  Returns AQS_OK, AQS_EINVAL, AQS_ERANGE. */
AQS_API aqs_status aqs_joint_get_layout(const aqs_linkage *linkage, int32_t joint,
                                        int32_t *q_offset, int32_t *nq, int32_t *v_offset,
                                        int32_t *nv);

/** Assembly tree statistics (after finalize). Each out pointer may be NULL.
 *  nodes: tree nodes (leaves and internal); height: edges on the longest
 *  root-to-leaf path; mean_handles, max_handles: over all nodes.
 *  Returns AQS_OK, AQS_EINVAL, AQS_ESTATE. */
AQS_API aqs_status aqs_linkage_get_tree_stats(const aqs_linkage *linkage, int32_t *nodes,
                                              int32_t *height, double *mean_handles,
                                              int32_t *max_handles);

/** Memory held by a linkage, counted by the library at every allocation and
 *  release through the linkage's allocator (docs/api.md, "Memory"): the
 *  caller sets size = sizeof(aqs_memory_stats); the library fills only the
 *  fields that size covers (as for aqs_solve_stats). Bytes are those asked
 *  of the allocator (aqs_linkage_create_with_allocator's alloc sees the same
 *  sizes), each block's header (16 bytes on common platforms) and the handle included; the
 *  categories add up to bytes. */
typedef struct aqs_memory_stats {
    uint32_t size;      /**< set by the caller: sizeof(aqs_memory_stats) */
    uint32_t blocks;    /**< blocks held, the handle included */
    uint64_t bytes;     /**< held now */
    uint64_t peak;      /**< the largest bytes held at any time since creation */
    uint64_t model;     /**< what was built: the handle, bodies, joints, loads, names, positions,
                             results, rigid groups (finalize's scratch while it runs) */
    uint64_t tree;      /**< the assembly tree: nodes, handle lists, poses, lazy-update sets,
                             the adaptive solver's lists */
    uint64_t exact;     /**< the articulated-body solver (exact solves) */
    uint64_t dca;       /**< the tree's DCA coefficients, inverse inertias, rounding estimate and
                             the adaptive solver's per-node arrays: allocated by the first
                             tolerance, cap or AQS_EXACT_DCA (0 before) */
    uint64_t factors;   /**< the total-acceleration factors (a tolerance or a cap; 0 before) */
    uint64_t world;     /**< the world measures' per-node data (0 until one is set) */
    uint64_t collision; /**< shapes, bounding volumes, certificates (0 without shapes; a few
                             hundred bytes once a filter or setting is stored) */
} aqs_memory_stats;

/** Fill stats (stats->size set by the caller, >= 8). Any phase. Returns
 *  AQS_OK, AQS_EINVAL (NULL linkage or stats, size too small). */
AQS_API aqs_status aqs_linkage_get_memory(const aqs_linkage *linkage, aqs_memory_stats *stats);

/* ------------------------------------------------------------------------
 * Reading the model back (any phase; what was added, for exporters)
 * ---------------------------------------------------------------------- */

/** Mass properties of a body as added. Any phase. Each out pointer may be NULL.
 *  mass: kg. com: (3) centre of mass, body frame, m. inertia: (3 x 3,
 *  row-major) about the centre of mass, body frame, kg m^2: the symmetric
 *  part (I + I^T) / 2 of what aqs_body_add was given (the part it stores).
 *  Returns AQS_OK, AQS_EINVAL (NULL linkage), AQS_ERANGE. */
AQS_API aqs_status aqs_body_get_inertial(const aqs_linkage *linkage, int32_t body,
                                         double *mass, double com[3], double inertia[9]);

/** Definition of a joint as added. Any phase. Each out pointer may be NULL.
 *  type: AQS_JOINT_*. parent: a body index or AQS_WORLD. child: a body index.
 *  pos: (3) joint frame origin in the parent frame, m, as given. quat: (4,
 *  w x y z) joint frame orientation, the given one divided by its norm.
 *  axis: (3) the given axis divided by its norm; (0, 0, 1) for the types that
 *  ignore it (spherical, free, fixed).
 *  Returns AQS_OK, AQS_EINVAL (NULL linkage), AQS_ERANGE. */
AQS_API aqs_status aqs_joint_get_definition(const aqs_linkage *linkage, int32_t joint,
                                            int32_t *type, int32_t *parent, int32_t *child,
                                            double pos[3], double quat[4], double axis[3]);

/* ------------------------------------------------------------------------
 * Names and joint limits (any phase; what model files carry besides the
 * mechanics; none of it changes a solve)
 * ---------------------------------------------------------------------- */

/** Name a body: name is copied (non-NULL, 1..4096 bytes, any bytes but NUL;
 *  UTF-8 suggested). Renaming replaces the old name. Names need not be
 *  unique (aqs_body_find returns the lowest index). Any phase.
 *  Returns AQS_OK, AQS_EINVAL (NULL or empty name), AQS_ERANGE, AQS_ENOMEM. */
AQS_API aqs_status aqs_body_set_name(aqs_linkage *linkage, int32_t body, const char *name);

/** Name a joint, as aqs_body_set_name. */
AQS_API aqs_status aqs_joint_set_name(aqs_linkage *linkage, int32_t joint, const char *name);

/** The name of a body into *name (non-NULL): the linkage's own copy, "" when
 *  unnamed, valid until the body is renamed or the linkage destroyed.
 *  Returns AQS_OK, AQS_EINVAL, AQS_ERANGE. */
AQS_API aqs_status aqs_body_get_name(const aqs_linkage *linkage, int32_t body, const char **name);

/** The name of a joint, as aqs_body_get_name. */
AQS_API aqs_status aqs_joint_get_name(const aqs_linkage *linkage, int32_t joint,
                                      const char **name);

/** The lowest-numbered body named name (exact bytes) into *out_body
 *  (non-NULL; -1 when none). A linear scan, O(bodies): look names up once,
 *  keep the indices. Returns AQS_OK, AQS_EINVAL (NULL name or out_body),
 *  AQS_ERANGE (no body has that name). */
AQS_API aqs_status aqs_body_find(const aqs_linkage *linkage, const char *name, int32_t *out_body);

/** The lowest-numbered joint named name, as aqs_body_find. */
AQS_API aqs_status aqs_joint_find(const aqs_linkage *linkage, const char *name,
                                  int32_t *out_joint);

/** Keep a joint's limits (URDF <limit>), for the caller to read back: the
 *  solvers do NOT enforce them (quasi-statics integrates past them; clamp
 *  positions yourself if you need to). lower <= upper: position limits, m or
 *  rad (-INFINITY / INFINITY: none); effort (N or N m) and velocity (m/s or
 *  rad/s): >= 0, INFINITY for none. Infinities are allowed here, NaN is not.
 *  A new joint has (-inf, inf, inf, inf). Any phase.
 *  Returns AQS_OK, AQS_EINVAL, AQS_ERANGE. */
AQS_API aqs_status aqs_joint_set_limits(aqs_linkage *linkage, int32_t joint, double lower,
                                        double upper, double effort, double velocity);

/** A joint's limits (see aqs_joint_set_limits). Each out pointer may be NULL.
 *  Returns AQS_OK, AQS_EINVAL (NULL linkage), AQS_ERANGE. */
AQS_API aqs_status aqs_joint_get_limits(const aqs_linkage *linkage, int32_t joint, double *lower,
                                        double *upper, double *effort, double *velocity);

/* ------------------------------------------------------------------------
 * Loading URDF models (an optional build feature: needs expat)
 * ---------------------------------------------------------------------- */

/** Root link with mass: what joins it to the world (aqs_urdf_options.root). */
#define AQS_URDF_ROOT_FIXED 0 /**< welded to the world (Pinocchio's and MuJoCo's default) */
#define AQS_URDF_ROOT_FREE 1  /**< a free joint: the robot floats (see docs/urdf.md) */

/** Options of aqs_linkage_load_urdf. Fill with aqs_urdf_options_init, then
 *  change fields; the library reads only the fields that size covers. */
typedef struct aqs_urdf_options {
    uint32_t size;     /**< sizeof(aqs_urdf_options), set by aqs_urdf_options_init */
    int32_t root;      /**< AQS_URDF_ROOT_* (default AQS_URDF_ROOT_FIXED) */
    int32_t collision; /**< 1: <collision> spheres, boxes, cylinders, capsules become
                            shapes (aqs_shape_add); 0 (default): collision ignored */
    int32_t finalize;  /**< 1 (default): finalize after loading; 0: leave it building */
    int32_t physical_inertia; /**< 0 (default): a link inertia no real body has (not
                                   positive semi-definite, or violating the triangle
                                   inequality: common in CAD exports) is loaded as given and
                                   listed in the warnings, and only its rigid group is
                                   checked (at finalize); 1: it is an error, as
                                   aqs_linkage_set_inertia_check(1) makes it for aqs_body_add */
} aqs_urdf_options;

/** Fill options with the defaults and options->size. options non-NULL. */
AQS_API void aqs_urdf_options_init(aqs_urdf_options *options);

/** Whether this library was built with URDF loading (1) or without (0: the
 *  load functions then return AQS_ESTATE saying so). */
AQS_API int32_t aqs_urdf_supported(void);

/** Load a URDF file into linkage, which must be empty (no body, no joint,
 *  not finalized: create it with aqs_linkage_create or with an allocator;
 *  the linkage's memory, the loader's element tree included, comes from its
 *  allocator; expat's own parser state, freed before return, from malloc).
 *  Bodies are the links in document order (a massless root link is the
 *  world, not a body), joints the URDF joints in document order, preceded by
 *  joint 0 "world_to_<root>" when the root link has mass; bodies and joints
 *  are named after their links and joints, <limit> is kept
 *  (aqs_joint_get_limits). Rules and mapping: docs/urdf.md.
 *  path: a file (non-NULL). options: NULL for the defaults.
 *  On failure the linkage is left empty and aqs_linkage_last_error() gives
 *  "aqs_linkage_load_urdf: <path>: <what, naming the link or joint and the
 *  value>". On success, what the loader read but does not model (mimic,
 *  transmissions, gazebo tags, meshes, dynamics...) is listed by
 *  aqs_linkage_load_warnings().
 *  Returns AQS_OK, AQS_EINVAL (NULL argument, bad options, a file aqs cannot
 *  load: not XML, not URDF, an unknown encoding, bad values, topology),
 *  AQS_ESTATE (linkage not empty; or built without URDF support),
 *  AQS_EMODEL (finalize refused the model: a rigid group without mass or
 *  with a singular inertia), AQS_ENOMEM; a file that cannot be read is
 *  AQS_EINVAL. */
AQS_API aqs_status aqs_linkage_load_urdf(aqs_linkage *linkage, const char *path,
                                         const aqs_urdf_options *options);

/** Load a URDF document from memory: data (size bytes; need not be
 *  NUL-terminated), name used in messages in place of the path (NULL:
 *  "<buffer>"). Otherwise as aqs_linkage_load_urdf. */
AQS_API aqs_status aqs_linkage_load_urdf_buffer(aqs_linkage *linkage, const char *data,
                                                size_t size, const char *name,
                                                const aqs_urdf_options *options);

/** What the last successful URDF load into this linkage read but does not
 *  model: one warning per line ("\n"-separated, no trailing newline), each
 *  naming the elements, links or joints concerned; "" when nothing.
 *  Valid until the next load or aqs_linkage_destroy. Never NULL. */
AQS_API const char *aqs_linkage_load_warnings(const aqs_linkage *linkage);

/* ------------------------------------------------------------------------
 * Loads (any phase; persistent until changed or cleared)
 * ---------------------------------------------------------------------- */

/** Gravitational acceleration, world frame, m/s^2 (default 0,0,0).
 *  gravity: (3), finite. Returns AQS_OK, AQS_EINVAL (NULL linkage or
 *  gravity, a non-finite value). */
AQS_API aqs_status aqs_linkage_set_gravity(aqs_linkage *linkage, const double gravity[3]);

/** Set the external load on a body, replacing any earlier one.
 *  force: (3) world frame, N, applied at point: (3) body frame, m (NULL = the
 *  body origin). torque: (3) pure torque, world frame, N m (NULL = zero).
 *  Returns AQS_OK, AQS_EINVAL, AQS_ERANGE. */
AQS_API aqs_status aqs_body_set_force(aqs_linkage *linkage, int32_t body, const double force[3],
                                      const double point[3], const double torque[3]);

/** Remove the external load of one body. Returns AQS_OK, AQS_EINVAL, AQS_ERANGE. */
AQS_API aqs_status aqs_body_clear_force(aqs_linkage *linkage, int32_t body);

/** Remove every body load and every joint force (gravity and the contact
 *  stiffness are kept). Returns AQS_OK, AQS_EINVAL (NULL linkage). */
AQS_API aqs_status aqs_linkage_clear_forces(aqs_linkage *linkage);

/** Active joint force Q, one value per dof (N for translations, N m for
 *  rotations), in the same layout and frame as the joint's acceleration.
 *  tau: (n), n must equal the joint's nv (n = 0 and tau = NULL for fixed
 *  joints). Returns AQS_OK, AQS_EINVAL (NULL, non-finite), AQS_ERANGE,
 *  AQS_ESIZE (n mismatch; nothing set). */
AQS_API aqs_status aqs_joint_set_force(aqs_linkage *linkage, int32_t joint, const double *tau,
                                       int32_t n);

/* ------------------------------------------------------------------------
 * Solving and stepping (after finalize)
 * ---------------------------------------------------------------------- */

/** Solve the quasi-statics at the current positions and loads. Exact by
 *  default: every joint acceleration, the floating bases' accelerations and
 *  every joint's constraint force. With a tolerance (aqs_linkage_set_tolerance)
 *  only the joints that matter are computed; the others read 0 (acceleration)
 *  and NaN (constraint force). Only the assembly-tree nodes made stale by
 *  changed positions or loads are recomputed first (aqs_solve_stats).
 *  Returns AQS_OK, AQS_EINVAL, AQS_ESTATE, AQS_ENUMERIC. */
AQS_API aqs_status aqs_linkage_solve(aqs_linkage *linkage);

/** Solve, then move every computed joint by q <- q (+) dt^2 * qdd (on the rotation
 *  group for spherical and free joints: the increment is a rotation vector in
 *  the child frame; a free joint's translation moves by its body-frame
 *  increment rotated into the joint frame), then update the coefficients.
 *  The accelerations and forces read afterwards are those of the solve at the
 *  start of the step. dt: s, finite, > 0.
 *  Returns AQS_OK, AQS_EINVAL, AQS_ESTATE, AQS_ENUMERIC. */
AQS_API aqs_status aqs_linkage_step(aqs_linkage *linkage, double dt);

/** Which algorithm computes an exact solve (eps = 0 and no cap).
 *  AQS_EXACT_ABA (default): Featherstone's articulated-body algorithm over
 *  the joints, O(N) with a small constant; it leaves the assembly tree's
 *  coefficients stale (an adaptive solve recomputes them first, once), so an
 *  exact step reports nodes_updated = 0. Where its refinement cannot reach
 *  the rounding level (its factors lost the digits: planar, universal,
 *  spherical joints between bodies 1e9 apart), or its backward pass finds an
 *  articulated inertia singular on a linkage where some joint's child is
 *  more than 1e2 times heavier than its parent, the solve is answered by the exact DCA (refined) and the stats report
 *  path AQS_PATH_EXACT_DCA (so are the next 16 exact solves, directly);
 *  the first such solve allocates the DCA's coefficients (AQS_ENOMEM if
 *  that fails, and then, as after AQS_ENUMERIC, the previous results are
 *  no longer readable: the attempt overwrote them; docs/math.md 5b, "Where
 *  the articulated-body solve cannot refine"). AQS_EXACT_DCA: the full
 *  divide-and-conquer back-substitution over the assembly tree, recomputing
 *  the tree after every step (the paper's exact solver; its per-node time is
 *  the benchmarks' reference for the adaptive solve). Both give the same
 *  accelerations and constraint forces up to rounding. Any phase; the
 *  choice takes effect at the next solve. Choosing the DCA after finalize
 *  allocates the tree's DCA coefficients if no tolerance did (O(N) memory).
 *  Returns AQS_OK, AQS_EINVAL, AQS_ENOMEM (nothing changed). */
#define AQS_EXACT_ABA 0
#define AQS_EXACT_DCA 1
AQS_API aqs_status aqs_linkage_set_exact_solver(aqs_linkage *linkage, int32_t solver);
/** The current AQS_EXACT_* choice into *solver. Returns AQS_OK, AQS_EINVAL (NULL). */
AQS_API aqs_status aqs_linkage_get_exact_solver(const aqs_linkage *linkage, int32_t *solver);

/** How the divide-and-conquer solver (the exact DCA and every adaptive
 *  solve) keeps a subassembly's articulated inverse inertia Phi.
 *  AQS_DCA_FORM_SQRT (default): Phi = G I^-1 G^T + Lambda Lambda^T, the
 *  composite inertia I kept as mass, centre of mass and rotational inertia
 *  and the mobility of the internal joints as a square-root factor Lambda,
 *  joined by Householder reflections (docs/math.md, "Accurate Phi"): no
 *  mobility is subtracted from another, so long straight chains (10^5 links
 *  and more), near point masses, light parts and large mass ratios keep
 *  their digits. AQS_DCA_FORM_PHI: Phi as an explicit matrix, joined by
 *  Phi_C = Phi_oo - M W M^T (the form of aqs up to 0.1.0): about 1.9x fewer
 *  instructions per tree node, but the subtraction loses digits as the
 *  subassemblies grow (a straight chain of 13,000 links fails with
 *  AQS_ENUMERIC) and with small or badly scaled inertias (docs/api.md,
 *  "Accuracy"). Only while building (before aqs_linkage_finalize).
 *  Returns AQS_OK, AQS_EINVAL (not an AQS_DCA_FORM_* value, message
 *  naming form), AQS_ESTATE (finalized). */
#define AQS_DCA_FORM_SQRT 0
#define AQS_DCA_FORM_PHI 1
AQS_API aqs_status aqs_linkage_set_dca_form(aqs_linkage *linkage, int32_t form);
/** The current AQS_DCA_FORM_* choice into *form. Returns AQS_OK, AQS_EINVAL (NULL). */
AQS_API aqs_status aqs_linkage_get_dca_form(const aqs_linkage *linkage, int32_t *form);

/* ------------------------------------------------------------------------
 * Error-bounded adaptive solving (Redon & Lin; MATH.md §4-6)
 * ---------------------------------------------------------------------- */

/** Error measures (the paper's Definition 2), over the joints that are not
 *  computed (their acceleration is reported as 0). A joint's error is the
 *  2-norm of its acceleration vector. Free joints (floating bases) are not
 *  part of the measure: they are always computed exactly. */
#define AQS_METRIC_ABS_LINKAGE 0 /**< sqrt(sum of ||qdd_j||^2 over uncomputed j) */
#define AQS_METRIC_REL_LINKAGE 1 /**< the above / sqrt(sum over all joints) */
#define AQS_METRIC_ABS_JOINT 2   /**< max ||qdd_j|| over uncomputed j */
#define AQS_METRIC_REL_JOINT 3   /**< the above / max ||qdd_j|| over all joints */
/** World-space measures (docs/math.md §10b): the error, caused by the
 *  uncomputed joints, in what the bodies do. For body b with centre of mass
 *  acceleration a_b and angular acceleration alpha_b, e_b = |delta a_b| +
 *  ell_b |delta alpha_b|, ell_b = sqrt(tr(I_b) / (2 m_b)) the root mean square
 *  distance of its mass from its centre of mass (0 for a point mass): a
 *  bound on the linear acceleration error of its points at that distance.
 *  The certified bound sums, over the queued subassemblies, sqrt(A(C)) times
 *  their joints' lever arms (from bounding spheres of the bodies). */
#define AQS_METRIC_ABS_WORLD 4   /**< max_b e_b (m/s^2) */
#define AQS_METRIC_REL_WORLD 5   /**< the above / max_b (|a_b| + ell_b |alpha_b|) over all bodies */

/** Set the error measure and its bound eps (finite, >= 0; 0, the default,
 *  means exact: every joint is computed). With eps > 0 a solve computes only
 *  the joints that matter, in decreasing order of their subassemblies' total
 *  acceleration, until the certified bound is <= eps. The first eps > 0
 *  allocates the DCA coefficients (unless the DCA solver did) and the
 *  total-acceleration factors (O(N) memory) and schedules their computation
 *  at the next solve. Any phase after finalize.
 *  Returns AQS_OK, AQS_EINVAL, AQS_ESTATE, AQS_ENOMEM. */
AQS_API aqs_status aqs_linkage_set_tolerance(aqs_linkage *linkage, int32_t metric, double eps);

/** Anytime control: stop a solve once max_joints joint accelerations are
 *  computed (0, the default, means no cap), reporting the bound reached.
 *  Joints on the path to a floating base may exceed the cap. A cap with
 *  eps = 0 also uses the adaptive solver (allocating the total-acceleration
 *  factors like aqs_linkage_set_tolerance). Returns AQS_OK, AQS_EINVAL,
 *  AQS_ESTATE, AQS_ENOMEM. */
AQS_API aqs_status aqs_linkage_set_max_computed(aqs_linkage *linkage, int32_t max_joints);

/** Which bound the joint-wise measures (AQS_METRIC_ABS_JOINT, _REL_JOINT)
 *  stop on: AQS_JOINT_BOUND_HEAP_TOP (default), the tighter
 *  sqrt(max_{queued} A(C)) of MATH.md §6.1, or AQS_JOINT_BOUND_SUM, the
 *  paper's sqrt(sum_{queued} A(C)). Both are certified; the heap top computes
 *  fewer joints for the same eps. Returns AQS_OK, AQS_EINVAL, AQS_ESTATE. */
#define AQS_JOINT_BOUND_HEAP_TOP 0
#define AQS_JOINT_BOUND_SUM 1
AQS_API aqs_status aqs_linkage_set_joint_bound(aqs_linkage *linkage, int32_t kind);

/** Exact fallback: when an adaptive solve computes more than fraction of
 *  the counted joints (those of aqs_solve_stats.counted_joints), computing
 *  almost everything adaptively costs more than an exact solve, so the next
 *  AQS_FALLBACK_RUN solves are exact, by the articulated-body algorithm
 *  (whatever aqs_linkage_set_exact_solver says), and the one after is
 *  adaptive again to see whether the loads still need that many joints.
 *  Exact solves report error_bound 0, every joint computed and
 *  aqs_solve_stats.fallback = 1. fraction in [0, 1]; 0, the default, turns
 *  it off. Inactive with a cap (aqs_linkage_set_max_computed) or eps = 0.
 *  Setting it, a tolerance or a cap starts over with an adaptive solve.
 *  Any phase. Returns AQS_OK, AQS_EINVAL (fraction not finite or outside
 *  [0, 1]; nothing changed). */
#define AQS_FALLBACK_RUN 15
AQS_API aqs_status aqs_linkage_set_exact_fallback(aqs_linkage *linkage, double fraction);
/** The fraction of aqs_linkage_set_exact_fallback into *fraction. Returns
 *  AQS_OK, AQS_EINVAL (NULL). */
AQS_API aqs_status aqs_linkage_get_exact_fallback(const aqs_linkage *linkage, double *fraction);

/** Rounding fallback (on by default): an adaptive solve that skips joints
 *  estimates what the DCA's rounding adds to its measure
 *  (aqs_solve_stats.rounding_bound, docs/math.md §10a). When that estimate,
 *  relative to the solution's size in the measure, exceeds level (or cannot
 *  be given: a near-singular pivot), its computed joints and its bound are
 *  not as accurate as an exact solve would be (large mass ratios, light
 *  parts behind heavy ones, states near equilibrium), so the solve is done
 *  again exactly, by the articulated-body algorithm, and so are the next
 *  AQS_FALLBACK_RUN solves; the one after is adaptive again. Those solves
 *  report error_bound 0, every joint computed, path AQS_PATH_EXACT_ABA and
 *  aqs_solve_stats.rounding_fallback = 1. The relative size is the
 *  estimate itself for the relative measures, and over the DCA's 2-norm of
 *  the joint accelerations (abs_linkage) or its largest computed joint
 *  acceleration (abs_joint). Default AQS_ROUNDING_FALLBACK_LEVEL (1e-8:
 *  above every benign case of the hard-case suite by 270x and the
 *  benchmark scenes by 400x, below every case whose adaptive solve was less
 *  accurate than the ABA's error allows by 5.7x, docs/math.md §10a); 0
 *  turns it off. Only in the square-root DCA form (the
 *  other has no estimate) and under the four joint measures (the world
 *  measures' estimate is 1e4 .. 2e7 times the truth, too loose to decide
 *  by); inactive with a cap or eps = 0; the exact fallback
 *  takes precedence. Setting it, a tolerance or a cap starts over with an
 *  adaptive solve. Any phase. Returns AQS_OK, AQS_EINVAL (level not finite
 *  or < 0; nothing changed). */
#define AQS_ROUNDING_FALLBACK_LEVEL 1e-8
AQS_API aqs_status aqs_linkage_set_rounding_fallback(aqs_linkage *linkage, double level);
/** The level of aqs_linkage_set_rounding_fallback into *level. Returns
 *  AQS_OK, AQS_EINVAL (NULL). */
AQS_API aqs_status aqs_linkage_get_rounding_fallback(const aqs_linkage *linkage, double *level);

/** Refinement of adaptive solves (on by default): an adaptive solve whose
 *  rounding estimate, relative as for the rounding fallback above, exceeds
 *  level (light parts behind heavy ones, tiny floating bases), or whose
 *  estimated error of its computed joints' constraint forces exceeds level
 *  times the largest of them, has its
 *  computed joints refined before it returns: corrections by the DCA on the
 *  nodes it back-substituted, with the residual of the linkage reduced to
 *  those joints (the skipped subtrees held by their coefficients) as their
 *  only load, each kept only when it lowers that residual, at most
 *  aqs_linkage_set_exact_refinement's count (0 turns both off; docs/math.md
 *  §13c). It repairs the rounding of the computed joints' own assembly and
 *  back-substitution, not that of a skipped subtree's coefficients; skipped
 *  subtrees whose coefficients the estimate calls lossy, or whose handle
 *  accelerations cancel (above level, or above the default level when level
 *  is lower), are computed first, so a refined solve may compute more
 *  joints than its bound needs. Only in
 *  the square-root DCA form and under the four joint measures; not when the
 *  rounding fallback answers the solve (it still sees the unrefined
 *  estimate).
 *  The first refined solve allocates 344 bytes per node of the tree (a
 *  revolute joint's; more for joints with more freedoms) and from then on
 *  each node update keeps its load factors. Default
 *  AQS_ADAPTIVE_REFINEMENT_LEVEL (1e-10: above the benchmark scenes' estimates
 *  at 2^-19, 3.7e-11 at most, where a refinement would cost 30-40 % of a
 *  step and gain a few u); 0 turns it off. On a linkage where some joint's
 *  child composite is more than 1e3 times heavier than its parent composite
 *  the trigger uses level / 1e3 (light links between heavy ones: computed
 *  joints up to 5e3x the ABA's error under 1e-10; docs/math.md §13c).
 *  Any phase. Returns AQS_OK,
 *  AQS_EINVAL (level not finite or < 0; nothing changed). */
#define AQS_ADAPTIVE_REFINEMENT_LEVEL 1e-10
AQS_API aqs_status aqs_linkage_set_adaptive_refinement(aqs_linkage *linkage, double level);
/** The level of aqs_linkage_set_adaptive_refinement into *level. Returns
 *  AQS_OK, AQS_EINVAL (NULL). */
AQS_API aqs_status aqs_linkage_get_adaptive_refinement(const aqs_linkage *linkage, double *level);

/** Prediction: a joint whose node's total acceleration A(C) exceeded
 *  margin x the stopping level of the last adaptive solve (the largest A a
 *  queued node may have when it stops: eps^2, (eps L)^2 for
 *  AQS_METRIC_REL_JOINT with L its lower bound on the largest joint
 *  acceleration, eps^2 A(root) for AQS_METRIC_REL_LINKAGE) is certain to be
 *  needed again after a step (A moves little), so the next
 *  solve computes those joints (a set closed towards the root) without
 *  evaluating their A, and the update after the step skips their
 *  total-acceleration factors (aqs_solve_stats.nodes_predicted,
 *  factors_updated). The bound stays certified: every node left queued is
 *  evaluated exactly, and a wrong prediction (loads changed a lot) only
 *  computes more joints than needed for one solve. margin = 0 turns it off;
 *  default AQS_PREDICTION_MARGIN (2^10: accelerations 32x the stopping
 *  level). Unused with eps = 0 or a cap. Setting it, a tolerance or a joint
 *  bound empties the predicted set. After finalize. Returns AQS_OK,
 *  AQS_EINVAL (margin not finite, or in (0, 1); nothing changed),
 *  AQS_ESTATE. */
#define AQS_PREDICTION_MARGIN 1024.0
AQS_API aqs_status aqs_linkage_set_prediction(aqs_linkage *linkage, double margin);
/** The margin of aqs_linkage_set_prediction into *margin. Returns AQS_OK,
 *  AQS_EINVAL (NULL), AQS_ESTATE. */
AQS_API aqs_status aqs_linkage_get_prediction(const aqs_linkage *linkage, double *margin);

/** Automatic path (on by default): with a tolerance (eps > 0, no cap),
 *  each solve or step runs the cheaper of the adaptive solver and the
 *  exact articulated-body solve, as a cost model counted in instructions
 *  predicts it from the last solves' counts (nodes processed, predicted and
 *  stale; estimated from the accelerations after an exact solve; the exact
 *  path at what the last exact solve counted, its refinement or its
 *  hand-over to the exact DCA included: docs/api.md). After
 *  exact solves every node of the assembly tree is stale, and a return to
 *  the adaptive solver recomputes them all: it happens once the exact
 *  solves have lost as much as that costs. The first solve after a
 *  tolerance, cap, prediction margin or this mode is set is adaptive.
 *  Exact solves report error_bound 0 and every joint computed;
 *  aqs_solve_stats.path says which path ran, auto_chosen whether this model
 *  chose it, cost_adaptive / cost_exact its predicted costs. The choice
 *  depends on counts only: reproducible. The exact fallback, when set,
 *  takes precedence. enabled: 1 (on) or 0 (off: always the adaptive
 *  solver, as before). Any phase. Returns AQS_OK, AQS_EINVAL (enabled not
 *  0 or 1; nothing changed). */
#define AQS_PATH_ADAPTIVE 0  /**< the adaptive solver (a tolerance or a cap) */
#define AQS_PATH_EXACT_ABA 1 /**< exact, the articulated-body algorithm */
#define AQS_PATH_EXACT_DCA 2 /**< exact, the full DCA back-substitution (AQS_EXACT_DCA, eps = 0) */
AQS_API aqs_status aqs_linkage_set_auto(aqs_linkage *linkage, int32_t enabled);
/** Whether the automatic path is on (1) or off (0) into *enabled. Returns
 *  AQS_OK, AQS_EINVAL (NULL). */
AQS_API aqs_status aqs_linkage_get_auto(const aqs_linkage *linkage, int32_t *enabled);

/** Refine the last solve down to a smaller eps (same measure) by continuing
 *  its priority queue instead of starting over. Valid only right after a
 *  solve or refine, before anything changes positions or loads; otherwise
 *  AQS_ESTATE. eps >= the bound already reached does nothing. The cap of
 *  aqs_linkage_set_max_computed still applies. Returns AQS_OK, AQS_EINVAL,
 *  AQS_ESTATE, AQS_ENUMERIC (a result came out non-finite: the results are
 *  then unreadable, as after a failed solve). */
AQS_API aqs_status aqs_linkage_refine(aqs_linkage *linkage, double eps);

/** Statistics of the last solve. The caller sets size = sizeof(aqs_solve_stats);
 *  the library fills only the fields that size covers (so callers built
 *  against an older header keep working). */
typedef struct aqs_solve_stats {
    uint32_t size;           /**< set by the caller: sizeof(aqs_solve_stats) */
    int32_t metric;          /**< AQS_METRIC_* in force */
    double eps;              /**< the bound asked for (0 = exact) */
    double error_bound;      /**< certified bound on the measure achieved (0 when exact) */
    int32_t computed_joints; /**< N_E: joint accelerations computed (free joints excluded) */
    int32_t counted_joints;  /**< joints that count for the measures (all but free and fixed) */
    int32_t nodes_updated;   /**< assembly-tree nodes recomputed by the last solve, or by the last step (before its solve and after its move) */
    int32_t nodes_processed; /**< internal nodes back-substituted by the last solve */
    int32_t capped;          /**< 1 if the last solve stopped at the max_computed cap */
    int32_t fallback;        /**< 1 if the last solve was exact because of aqs_linkage_set_exact_fallback */
    int32_t nodes_predicted; /**< internal nodes the last solve processed without evaluating their total acceleration (aqs_linkage_set_prediction) */
    int32_t factors_updated; /**< total-acceleration factors recomputed, counted as nodes_updated */
    int32_t path;            /**< AQS_PATH_*: the path the last solve ran */
    int32_t auto_chosen;     /**< 1 if the automatic path (aqs_linkage_set_auto) chose it */
    double cost_adaptive;    /**< the automatic path's predicted cost of the adaptive path, instructions (0 when it did not choose) */
    double cost_exact;       /**< the same for the exact path */
    double rounding_bound;   /**< estimate with margin of what the DCA's rounding adds to the measure:
                                  against the true solution, measure <= error_bound + rounding_bound
                                  when certified (+inf when no bound can be given) */
    int32_t certified;       /**< 1: error_bound + rounding_bound is a bound (an estimate with a
                                  safety factor, docs/math.md) and rounding_bound <= eps (eps > 0);
                                  0: no honest bound (rounding above eps, a near-singular pivot, the
                                  inverse-inertia form, a world measure whose estimate is unusable
                                  (docs/api.md), or an exact solve by the ABA, which does not
                                  estimate its rounding) */
    int32_t rounding_fallback; /**< 1 if the last solve was exact because of the rounding fallback
                                    (aqs_linkage_set_rounding_fallback) */
} aqs_solve_stats;

/** Fill stats (stats->size set by the caller, >= 8). Returns AQS_OK,
 *  AQS_EINVAL, AQS_ESTATE (no solve yet). */
AQS_API aqs_status aqs_linkage_get_stats(const aqs_linkage *linkage, aqs_solve_stats *stats);

/** Whether the last solve computed joint j: *computed = 1 or 0. An
 *  uncomputed joint reads acceleration 0 and constraint force NaN (a fixed
 *  joint's force is available when its rigid group was reached).
 *  Returns AQS_OK, AQS_EINVAL, AQS_ERANGE, AQS_ESTATE. */
AQS_API aqs_status aqs_joint_get_computed(const aqs_linkage *linkage, int32_t joint,
                                          int32_t *computed);

/* ------------------------------------------------------------------------
 * Reading back and setting state
 *
 * An array argument whose required length is 0 (nq = 0 or nv = 0: only
 * fixed joints) may be NULL.
 * ---------------------------------------------------------------------- */

/** All joint positions in joint order. q: (n >= nq). Any phase.
 *  Returns AQS_OK, AQS_EINVAL, AQS_ESIZE. */
AQS_API aqs_status aqs_linkage_get_positions(const aqs_linkage *linkage, double *q, size_t n);

/** Set all joint positions. q: (n == nq), finite; quaternions unit within
 *  1e-6 (normalized on input). Any phase. Returns AQS_OK, AQS_EINVAL, AQS_ESIZE. */
AQS_API aqs_status aqs_linkage_set_positions(aqs_linkage *linkage, const double *q, size_t n);

/** Position of one joint. q: (n == the joint's nq; may be NULL when nq is 0).
 *  Any phase. Returns AQS_OK, AQS_EINVAL (NULL linkage or q), AQS_ERANGE,
 *  AQS_ESIZE (n != nq; nothing written). */
AQS_API aqs_status aqs_joint_get_position(const aqs_linkage *linkage, int32_t joint, double *q,
                                          int32_t n);
/** Set the position of one joint. q: (n == the joint's nq; may be NULL when
 *  nq is 0), as above: finite, quaternions unit within 1e-6 (normalized on
 *  input). Any phase. Returns AQS_OK, AQS_EINVAL (NULL linkage or q, a
 *  non-finite value, a quaternion not unit), AQS_ERANGE, AQS_ESIZE
 *  (n != nq). */
AQS_API aqs_status aqs_joint_set_position(aqs_linkage *linkage, int32_t joint, const double *q,
                                          int32_t n);

/** All joint accelerations of the last solve, in joint order. qdd: (n >= nv).
 *  Units m/s^2 or rad/s^2. Spherical: angular acceleration of the child
 *  relative to the parent side, child frame. Free: the child's spatial
 *  acceleration in its own body frame [dw; dv], gravity included.
 *  Returns AQS_OK, AQS_EINVAL, AQS_ESTATE (no solve yet), AQS_ESIZE. */
AQS_API aqs_status aqs_linkage_get_accelerations(const aqs_linkage *linkage, double *qdd,
                                                 size_t n);

/** Acceleration of one joint of the last solve. qdd: (n == the joint's nv;
 *  may be NULL when nv is 0), as above. Returns AQS_OK, AQS_EINVAL (NULL
 *  linkage or qdd), AQS_ERANGE, AQS_ESTATE (not finalized, nothing solved
 *  yet, or the last solve failed), AQS_ESIZE (n != nv; nothing written). */
AQS_API aqs_status aqs_joint_get_acceleration(const aqs_linkage *linkage, int32_t joint,
                                              double *qdd, int32_t n);

/** Constraint forces of the last solve: (joints x 6), row j the spatial force
 *  joint j exerts on its child, in the child body frame about its origin,
 *  torque first, [n; f] in N m and N; NaN rows for joints the last
 *  (adaptive) solve did not compute. n >= 6 * joints.
 *  Returns AQS_OK, AQS_EINVAL, AQS_ESTATE, AQS_ESIZE. */
AQS_API aqs_status aqs_linkage_get_constraint_forces(const aqs_linkage *linkage, double *f,
                                                     size_t n);

/** Constraint force of one joint: f (6), as above. Returns AQS_OK,
 *  AQS_EINVAL (NULL linkage or f), AQS_ERANGE, AQS_ESTATE (not finalized,
 *  nothing solved yet, or the last solve failed). */
AQS_API aqs_status aqs_joint_get_constraint_force(const aqs_linkage *linkage, int32_t joint,
                                                  double f[6]);

/** World pose of one body at the current positions (after finalize), found
 *  through the assembly tree's hierarchical frames in O(log N) (after one
 *  O(N) refresh when positions moved since they were last needed), or up the
 *  kinematic tree in O(depth) when the tree holds no frames (docs/api.md).
 *  pos: (3) origin of the body frame, world frame. quat: (4, w x y z)
 *  orientation. Returns AQS_OK, AQS_EINVAL, AQS_ERANGE, AQS_ESTATE. */
AQS_API aqs_status aqs_body_get_pose_world(const aqs_linkage *linkage, int32_t body,
                                           double pos[3], double quat[4]);

/** World poses of all bodies in one O(N) pass. poses: (bodies x 7), row i =
 *  x y z w qx qy qz of body i. n >= 7 * bodies.
 *  Returns AQS_OK, AQS_EINVAL, AQS_ESTATE, AQS_ESIZE. */
AQS_API aqs_status aqs_linkage_get_body_poses_world(const aqs_linkage *linkage, double *poses,
                                                    size_t n);

/* ------------------------------------------------------------------------
 * Collision: convex shapes on bodies, obstacles, contact queries (libccd)
 *
 * Shapes are attached to bodies (moving with them) or to AQS_WORLD (static
 * obstacles), in any phase; queries run after finalize. A linkage without
 * shapes allocates nothing for collision and pays nothing per step. Bodies
 * welded together by fixed joints (one rigid group) never collide with each
 * other, nor do bodies welded to the world with obstacles. See
 * docs/collision.md for the model and its limits.
 * ---------------------------------------------------------------------- */

/** Shape types (fixed values). size[] per type, all finite and > 0: */
#define AQS_SHAPE_SPHERE 0   /**< size[0] radius */
#define AQS_SHAPE_CAPSULE 1  /**< size[0] radius, size[1] half-length of the segment along z */
#define AQS_SHAPE_BOX 2      /**< size[0..2] half-extents along x, y, z */
#define AQS_SHAPE_CYLINDER 3 /**< size[0] radius, size[1] half-height along z */
#define AQS_SHAPE_HULL 4     /**< convex hull of points (aqs_shape_add_hull only) */

/** Attach a shape to body (a body index, or AQS_WORLD for a static
 *  obstacle). type: AQS_SHAPE_SPHERE..AQS_SHAPE_CYLINDER. size: (3), the
 *  entries the type uses in [1e-150, 1e150] (the scale collision geometry is
 *  computed at), the others ignored (may be anything finite). pos: (3) origin of
 *  the shape frame in the body frame (world frame for AQS_WORLD), m, each
 *  entry within 1e150. quat:
 *  (4, w x y z) its orientation, unit within 1e-6, then normalized.
 *  out_shape: receives the shape index (shapes of all bodies and obstacles
 *  are numbered together from 0, in the order added; may be NULL).
 *  Any phase. Returns AQS_OK, AQS_EINVAL, AQS_ERANGE, AQS_ENOMEM. */
AQS_API aqs_status aqs_shape_add(aqs_linkage *linkage, int32_t body, int32_t type,
                                 const double size[3], const double pos[3], const double quat[4],
                                 int32_t *out_shape);

/** Attach the convex hull of npoints points (npoints x 3, row-major, in the
 *  shape frame; each coordinate within 1e150; at least 4 not all coplanar,
 *  relative to their extent: 1e-9, and not all within 1e-150 of each other) to body, placed by pos and quat as in aqs_shape_add. The
 *  points are copied. Returns AQS_OK, AQS_EINVAL, AQS_ERANGE, AQS_ENOMEM. */
AQS_API aqs_status aqs_shape_add_hull(aqs_linkage *linkage, int32_t body, const double *points,
                                      int32_t npoints, const double pos[3], const double quat[4],
                                      int32_t *out_shape);

/** Number of shapes (obstacles included) into *count (non-NULL). Any phase.
 *  Returns AQS_OK, AQS_EINVAL (NULL linkage or count). */
AQS_API aqs_status aqs_linkage_get_shape_count(const aqs_linkage *linkage, int32_t *count);

/** Collision filter of a body (or of all obstacles with AQS_WORLD): two
 *  shapes may touch only if (group_a & mask_b) and (group_b & mask_a) are
 *  both non-zero. Default group 1, mask 0xFFFFFFFF. Any phase.
 *  Returns AQS_OK, AQS_EINVAL, AQS_ERANGE, AQS_ENOMEM. */
AQS_API aqs_status aqs_body_set_collision_filter(aqs_linkage *linkage, int32_t body,
                                                 uint32_t group, uint32_t mask);

/** Never report contacts between body_a and body_b (either may be AQS_WORLD:
 *  the obstacles; not both). Idempotent. Any phase.
 *  Returns AQS_OK, AQS_EINVAL, AQS_ERANGE, AQS_ENOMEM. */
AQS_API aqs_status aqs_collision_exclude_pair(aqs_linkage *linkage, int32_t body_a,
                                              int32_t body_b);

/** Whether two bodies joined by a joint (parent and child) may collide:
 *  0 (the default: they never do) or 1. Obstacles are never "joined".
 *  Any phase. Returns AQS_OK, AQS_EINVAL. */
AQS_API aqs_status aqs_linkage_set_collide_joined(aqs_linkage *linkage, int32_t enabled);

/** One contact between two shapes. body_b = AQS_WORLD for an obstacle;
 *  a's shape has the lower shape index when both are on bodies, and b is the
 *  obstacle otherwise. depth >= 0: moving b by depth along the normal
 *  (nx, ny, nz: unit, world frame, pointing from a towards b) separates them.
 *  (px, py, pz): contact point, world frame. */
typedef struct aqs_contact {
    int32_t body_a;
    int32_t body_b;
    int32_t shape_a;
    int32_t shape_b;
    double depth;
    double nx;
    double ny;
    double nz;
    double px;
    double py;
    double pz;
} aqs_contact;

/** How aqs_linkage_collide searches (all return the same contacts):
 *  LAZY (default) traverses the assembly tree, refitting only the nodes
 *  whose joints moved and skipping subassemblies that were free of internal
 *  contact at the last query and did not move since; FULL refits every node
 *  and forgets what earlier queries learned; BRUTE tests all pairs of shapes
 *  (reference and benchmark). */
#define AQS_COLLIDE_LAZY 0
#define AQS_COLLIDE_FULL 1
#define AQS_COLLIDE_BRUTE 2

/** All contacts at the current positions: self-collision and contacts with
 *  obstacles. contacts: (capacity) filled with min(total, capacity)
 *  contacts (may be NULL when capacity is 0). count: receives the total
 *  number found (non-NULL). Returns AQS_OK; AQS_ESIZE when total > capacity
 *  (the first capacity contacts are written and *count holds the total, so
 *  the caller can size the array and call again); AQS_EINVAL, AQS_ESTATE
 *  (not finalized), AQS_ENOMEM (first query: the per-node bounding volumes
 *  are allocated). Order of contacts: unspecified. */
AQS_API aqs_status aqs_linkage_collide(aqs_linkage *linkage, int32_t mode, aqs_contact *contacts,
                                       size_t capacity, size_t *count);

/** Whether any two shapes touch: *hit = 1 or 0. Stops at the first contact.
 *  Returns AQS_OK, AQS_EINVAL, AQS_ESTATE, AQS_ENOMEM (as above). */
AQS_API aqs_status aqs_linkage_any_contact(aqs_linkage *linkage, int32_t *hit);

/** Work of the last collide / any-contact query (each pointer may be NULL):
 *  nodes_refit: bounding volumes recomputed; volume_tests: pairs of bounding
 *  spheres tested; narrow_tests: pairs of shapes given to libccd (after a
 *  shape-level sphere test); nodes_skipped: subassemblies skipped because
 *  they were still free of internal contact. Returns AQS_OK, AQS_EINVAL. */
AQS_API aqs_status aqs_linkage_get_collision_stats(const aqs_linkage *linkage,
                                                   int32_t *nodes_refit, int32_t *volume_tests,
                                                   int32_t *narrow_tests, int32_t *nodes_skipped);

/** Work of the last collision query (aqs_linkage_collide, aqs_linkage_any_contact,
 *  or the penalty contact of a solve), all of it: the caller sets
 *  size = sizeof(aqs_collision_stats); the library fills only the fields that
 *  size covers (as for aqs_solve_stats). Zero before any query. The certificate
 *  counters are those of docs/collision.md, "Certificates". */
typedef struct aqs_collision_stats {
    uint32_t size;         /**< set by the caller: sizeof(aqs_collision_stats) */
    int32_t nodes_refit;   /**< bounding volumes recomputed */
    int32_t volume_tests;  /**< pairs of bounding spheres tested */
    int32_t narrow_tests;  /**< pairs of shapes given to libccd (after a shape-level sphere test) */
    int32_t nodes_skipped; /**< subassemblies skipped: still free of internal contact */
    int32_t certs_reused;  /**< cross pairs whose separation certificate still held */
    int32_t certs_made;    /**< cross pairs certified anew (a near list built) */
    int32_t near_tests;    /**< shape pairs retested from near lists */
} aqs_collision_stats;

/** Fill stats (stats->size set by the caller, >= 8). Any phase. Returns
 *  AQS_OK, AQS_EINVAL (NULL linkage or stats, size too small). */
AQS_API aqs_status aqs_linkage_get_query_stats(const aqs_linkage *linkage, aqs_collision_stats *stats);

/** Penalty contact (docs/collision.md): with stiffness k > 0 (force per
 *  unit depth, N/m), every solve and step first finds all contacts (a lazy
 *  query) and applies, for each, the force k * depth along its normal at the
 *  contact point: +k depth n on body b, -k depth n on body a (obstacles and
 *  bodies welded to the world take nothing), on top of the loads set by the
 *  caller, through the same load path. The forces do not depend on
 *  accelerations. k = 0 (the default) turns it off. stiffness: finite,
 *  >= 0. After finalize; builds the collision data (AQS_ENOMEM possible) so
 *  that solving and stepping still allocate nothing. The statistics of
 *  aqs_linkage_get_query_stats then describe the last query of either
 *  kind. Returns AQS_OK, AQS_EINVAL, AQS_ESTATE, AQS_ENOMEM. */
AQS_API aqs_status aqs_linkage_set_contact_stiffness(aqs_linkage *linkage, double stiffness);

/** Iterative refinement of the exact solves.
 *
 *  The articulated-body solve (docs/math.md 5b): its forward pass also
 *  checks each body's balance of forces (the body's inertial force and load
 *  against its joint forces, 0 in exact arithmetic) and each joint's own
 *  equation S^T f = Q (about 185 instructions a joint, +12 %); where the largest imbalance is above 16 u of the largest
 *  term or 256 u of the largest joint force (when the joint forces are not
 *  below 2^-10 of the terms, as a free fall's are) (it lost digits:
 *  spherical and planar joints between very different masses, up to 1.4e-9
 *  off; a long planar chain held in an oblique frame, 4e-9 at 2,000 links;
 *  a floating tree whose joint forces are small beside its weights, forces
 *  1.4e-11 off), or where some joint's |Q - S^T f| is above 1,024 u of the
 *  largest joint force (floating trees of very different masses under
 *  tilted gravity, forces up to 3.6e-10 off while every body balanced), at
 *  most max_corrections corrections
 *  qdd += ABA^-1(Q - ID(qdd)) by the solve's own factors, the residual
 *  Q - ID(qdd) in double-double arithmetic (about 106 bits), each kept
 *  while the corrections shrink by half or more (2e-16 .. 4e-15 there);
 *  then the bodies' accelerations are refined on their own against that
 *  residual, and the solve takes the inverse dynamics' constraint forces of
 *  them. On a linkage where some joint's child composite is more than 1e2
 *  times heavier than its parent composite, every solve takes that residual
 *  and a correction (the balance, formed with the solve's own forces,
 *  misses a heavy body held by light links: up to 1.5e-7 off, 2.5e-10 with
 *  a residual in double; 5e-16 refined); a correction at the rounding
 *  level there leaves the answer as it is. A refining solve costs about
 *  3 .. 7x an unrefined one on an x86-64 processor with fma, 5 .. 12x
 *  without (docs/math.md 5b, "The residual in double-double"). Elsewhere the answer is bit for bit the unrefined one.
 *  Its arrays (4 doubles per dof and 60 per joint) are allocated at the
 *  first solve that refines; if that fails, the solve succeeds unrefined.
 *  max_corrections 0 turns the check off too.
 *
 *  The exact DCA solve (docs/math.md 13a): after a
 *  solve that computes every joint through the DCA's back-substitution
 *  (AQS_EXACT_DCA, eps = 0 without a cap, or an adaptive solve that ended
 *  up computing every joint: error_bound 0), at most max_corrections
 *  GMRES cycles on M dq = Q - ID(qdd) preconditioned by the DCA itself,
 *  each kept only when its answer is finite and lowers the inverse-dynamics
 *  residual (or converged and both residuals are at its rounding floor). The
 *  constraint forces and accelerations are refined first by the DCA's own
 *  residual (across each joint, the bodies' relative acceleration against
 *  S qdd, and Q - S^T f: docs/math.md 13a, "The joint forces of a refined
 *  solve"); the forces are then that refinement's (when it converged), or
 *  the inverse dynamics' of the refined accelerations where their estimated
 *  error is at the rounding level or below the unrefined forces'; where the
 *  back-substitution's forces do not balance the bodies, those of the
 *  bodies' accelerations refined as the state (corrections by the DCA, as
 *  the articulated-body refinement does; docs/math.md 13a). A cycle's
 *  first step is the plain correction
 *  qdd += DCA^-1(Q - ID(qdd)), about one more pass over the tree's nodes,
 *  and where it is resolved (the usual case) the cycle ends there; otherwise
 *  up to 128 steps of one such pass each (a further cycle when the last one's
 *  true residual ended far above GMRES's estimate). On a linkage with a heavy
 *  child (as above) the answer is then corrected by the articulated-body
 *  factors (their pass at the same positions, their refinement started from
 *  the DCA's answer): corrected accelerations kept where the corrections
 *  contract to the rounding level and leave the residual at most the DCA's
 *  or at its rounding floor; else, the refined forces where the factors'
 *  own answer agrees with the DCA's to 64 u; not in a hand-over (docs/math.md
 *  13a, "Corrections by the articulated-body factors"). max_corrections: 0 (off: the DCA's
 *  back-substitution as it is, the paper's exact solver) to
 *  AQS_REFINEMENT_MAX; default AQS_REFINEMENT_MAX. Any phase; takes effect
 *  at the next solve. The refinement's arrays (~2,300 B per joint with the
 *  nodes' load factors, which node updates keep from then on, and 328 B
 *  for the Krylov basis when GMRES needs it, 2,056 B when a cycle needs more
 *  than 20 steps) are allocated at the first
 *  solve that refines: the only allocation a solve makes; if it fails, that
 *  solve succeeds unrefined.
 *  Returns AQS_OK, AQS_EINVAL (nothing changed). */
#define AQS_REFINEMENT_MAX 3
AQS_API aqs_status aqs_linkage_set_exact_refinement(aqs_linkage *linkage, int32_t max_corrections);
/** The current maximum into *max_corrections. Returns AQS_OK, AQS_EINVAL (NULL). */
AQS_API aqs_status aqs_linkage_get_exact_refinement(const aqs_linkage *linkage, int32_t *max_corrections);

#ifdef __cplusplus
}
#endif

#endif /* AQS_H */
