/* linkage.h -- the private layout of aqs_linkage, shared by the src/ files.
 * Never installed. */
#ifndef AQS_LINKAGE_H
#define AQS_LINKAGE_H

/* model.heavy_ratio, the largest mass of a joint's child composite over its
 * parent composite's (docs/math.md 5b), above which the articulated-body
 * solve always refines (AQS_HEAVY_CHILD_ABA) and the adaptive refinement's
 * level is lowered (AQS_HEAVY_CHILD, docs/math.md 13c) */
#define AQS_HEAVY_CHILD 1e3
#define AQS_HEAVY_CHILD_ABA 1e2
/* After an articulated-body solve handed over to the exact DCA, this many exact
 * solves go to the DCA directly (src/api/api.c, exact_solve) */
#define AQS_HANDOVER_RUN 16

#include <stddef.h>
#include <stdint.h>

#include "aqs.h"
#include "joint.h"
#include "spatial.h"

typedef struct {
    double mass, com[3], inertia[9];
} body_def;

/* A persistent external load: force (world) at point (body frame) + torque (world). */
typedef struct {
    double force[3], point[3], torque[3];
} body_load;

/* One node of the assembly tree (MATH.md §3.2, §10). Offsets index the
 * pooled arrays of the tree. */
typedef struct {
    int64_t handles;      /* nh effective joint indices, in tree.handles */
    int64_t poses;        /* nh handle-frame poses in the node's frame, in tree.poses; then
                             (internal nodes) nd_J */
    int64_t bv;           /* b (6nh), in tree.data; then, laid out after it (the offsets are
                             computed by the nd_ functions below, not stored): nd_xf, nd_ic,
                             nd_lam, and for internal nodes nd_W, nd_U, nd_rho, nd_gamma, nd_S */
    int32_t a, b, parent; /* children (-1 for leaves), parent (-1 for the root) */
    int32_t joint;        /* principal joint (effective index); -1 for leaves */
    int32_t comp;         /* leaves: rigid group (model.ncomp = world); -1 otherwise */
    int32_t nh;           /* number of handles */
    int32_t ka, kb;       /* position of the principal joint among A's / B's handles */
    int32_t height;       /* leaves 0 */
    int32_t rank;         /* columns of Lambda (0 for leaves) */
    int32_t ncount;       /* counted joints inside the node (every one but free joints) */
    int32_t jw;           /* the 6 rows of Lambda of the handle the parent joins use only its
                             first jw columns (<= rank; 6 when compressed and that handle is
                             the first) */
    int32_t lld;          /* Lambda's row stride and column capacity (src/model/assembly.c's
                             layout): the structural rank min(6nh, d + lld_A + lld_B) in the
                             square-root form (0 for leaves; rank never exceeds it), 6nh in
                             the inverse-inertia form (Phi, 6nh x 6nh) */
    unsigned char d;      /* dofs of the principal joint (<= 6) */
    unsigned char grounded; /* holds the world leaf: I^-1 = 0 */
    unsigned char forced; /* the node or a descendant holds a free joint: always computed */
    /* The total-acceleration factor's offsets are in tree.tf, the rounding estimate's
     * per-node levels in tree.rnd_node (both allocated with the DCA coefficients or the
     * factors, not held by a linkage solved only exactly). */
} node;

/* A node's pooled arrays after its b (tree.data) and after its handle poses (tree.poses),
 * in the order src/model/assembly.c's layout takes them:
 *   xf     handle forces x (6nh)
 *   ic     mass properties of the subassembly: mass, centre of mass, inertia about it
 *          (13 doubles, node frame; zero when grounded)
 *   lam    Lambda (6nh x rank, row-major with row stride lld, capacity 6nh x lld):
 *          Phi = G I^-1 G^T + Lambda Lambda^T (src/solve/dca.c, docs/math.md
 *          "Accurate Phi"); in the inverse-inertia form Phi itself (lld = 6nh)
 *   W      FX = W M^T (6 x 6nh): the joint force is f = FX x + gamma
 *   U, rho, gamma, S: QX = U M^T (d x 6nh): qdd = rho - QX x; rho (d), gamma (6),
 *          S (6 x d); x: the node's handle forces
 *   J      in tree.poses: k's child frame in its joint frame (X = spatial_from_parent(J))
 * (W .. S and J exist for internal nodes only.) */
static inline int64_t nd_xf(const node *n) { return n->bv + 6 * (int64_t)n->nh; }
static inline int64_t nd_ic(const node *n) { return n->bv + 12 * (int64_t)n->nh; }
static inline int64_t nd_lam(const node *n) { return nd_ic(n) + 13; }
static inline int64_t nd_W(const node *n) { return nd_lam(n) + 6 * (int64_t)n->nh * n->lld; }
static inline int64_t nd_U(const node *n) { return nd_W(n) + 36 * (int64_t)n->nh; }
static inline int64_t nd_rho(const node *n) { return nd_U(n) + 6 * (int64_t)n->d * n->nh; }
static inline int64_t nd_gamma(const node *n) { return nd_rho(n) + n->d; }
static inline int64_t nd_S(const node *n) { return nd_gamma(n) + 6; }
static inline int64_t nd_J(const node *n) { return n->poses + n->nh; }

/* A node's square-root total-acceleration factor (§5, src/solve/totalacc.c). */
typedef struct {
    int64_t T;            /* the factor, in tree.tdata */
    int64_t tpos;         /* the first column of each row of T, in tree.trowpos (tcap entries) */
    int32_t trows;        /* rows of T (<= tcap); 0 for leaves */
    int32_t tcap;         /* rows T has room for: min(6nh + 1, the counted dofs of the
                             subassembly), which bounds them (src/solve/totalacc.c) */
} tfactor;

typedef struct {
    int32_t nnodes, root;
    node *nodes;
    int32_t *handles;
    int64_t nhandles;
    pose *poses;
    int64_t nposes;
    double *data;
    int64_t ndata;
    int32_t *node_of_eff;  /* ne: the node whose principal joint it is */
    int32_t *leaf_of_comp; /* ncomp + 1 */
    int32_t height, max_handles;
    int32_t avx; /* dca_enable: the AVX kernels of src/solve/dca.c (reflect_row) run (docs/math.md §4a) */
    double mean_handles;
    double *scratch;  /* 84 * (max_handles + 2) doubles */
    double *hscratch; /* (6 max_handles + 13) x (12 max_handles + 6): the stacked factor of
                         dca_node_update, its reflection vector and relative rows */
    double *mscratch; /* 36 * (max_handles + 1): M = [Phi^A_ok X^T; -Phi^B_ok] of the node
                         being updated (6nh x 6), not stored per node */
    /* Total-acceleration factors, allocated when adaptive solving is first used. */
    double *tdata;
    tfactor *tf;      /* nnodes, with tdata */
    double *tscratch; /* the stacked matrix of one node */
    int32_t *tperm;   /* per node (at its handles offset): T's column blocks as handle
                         indices, in the order the ancestors join them (src/solve/totalacc.c) */
    int32_t *trowpos; /* per node (at its tpos, 6nh + 1 entries): the first column of each row of T */
    int32_t *tiscratch; /* 9 max_handles + 4 */
    /* Lazy update: nodes whose coefficients are stale (top-closed set). */
    uint32_t *stamp;
    uint32_t epoch;
    int32_t *dirty;
    int32_t *dirty_tmp; /* scratch of the dirty-set sort, nnodes entries */
    int32_t ndirty;
    int all_dirty;
    int32_t nodes_updated; /* by the last update */
    int32_t factors_updated; /* total-acceleration factors recomputed by the last update */
    double *rnd_x;     /* nhandles, at each node's handles offset: the estimated absolute error
                          of its handle forces (src/solve/rounding.c), set by the back-substitution;
                          then 6 + 7 max_handles for the back-substitution's sums by handle
                          (rounding_backsub_products); allocated by dca_enable */
    double *rnd_node;  /* RND_NODE_LEVELS (6) per node, allocated by dca_enable (src/solve/rounding.c,
                          docs/math.md "The rounding term"): relative error levels in units of u,
                          RND_K of the node's reduced factors (U, E, QX, FX), RND_KB of its b;
                          absolute errors (2-norms) RND_RHO of rho and RND_GAM of gamma; RND_SUB
                          the largest rho error in the subtree; RND_TQ its joint acceleration's
                          error from the rounding of its parent's force transform, set by the
                          parent's back-substitution */
    double *lf;         /* the load factors (src/solve/dca.c dca_loads_enable), at lfoff per
                           internal node, valid where lfok; NULL unless an adaptive solve
                           was refined (src/solve/arefine.c) */
    int64_t *lfoff;
    unsigned char *lfok;
    pose world_frame; /* the world leaf's frame in the world: at the world's origin, turned as
                         the (aligned) joint frame of its first handle (frames_world_frame,
                         docs/math.md §13b), so that the
                         grounded nodes, whose frame it is, share the plane of a planar
                         linkage that the world holds; set at finalize */
    int poses_stale; /* the internal nodes' poses (and J) do not follow q: frames_poses
                        recomputes them when the DCA, the adaptive solver, collision or a
                        world-pose query needs them (src/model/stale.c decides) */
} tree;

/* What finalize derives from the user's bodies and joints: rigid groups
 * (bodies welded by fixed joints, "composites") and the effective joints. */
typedef struct {
    int32_t ncomp;          /* composites; index ncomp is the world */
    int32_t *comp_of_body;  /* nbodies */
    pose *body_in_comp;     /* nbodies: body frame in its composite's (aligned) frame; NULL after
                               finalize when no body is welded (every body a root, at
                               (C^T, 0)): read it with kin_body_in_comp */
    int32_t *comp_root;     /* ncomp: the body whose frame is the composite's */
    double *comp_inertia;   /* ncomp x 36: spatial inertia, composite frame; NULL after
                               finalize (kin_comp_inertia has it, packed) */
    double *comp_inverse;   /* ncomp x 36; NULL until model_inverse_alloc (read through
                               model_inverse_apply, which computes it when not held) */
    double *comp_force;     /* (ncomp + 1) x 6: external load, composite frame */
    unsigned char *comp_loaded; /* ncomp + 1 */
    int32_t *loaded_comps;  /* comps whose comp_force is non-zero */
    int32_t nloaded_comps;
    int32_t ne;             /* effective (non-fixed) joints */
    int32_t *eff_joint;     /* ne: user joint index */
    int32_t *eff_of_joint;  /* njoints: effective index or -1 for fixed joints */
    int32_t *eff_parent;    /* ne: parent composite (ncomp = world) */
    int32_t *eff_child;     /* ne: child composite */
    pose *eff_place;        /* ne: joint frame in the parent composite's frame; NULL after
                               finalize (kin_eff_place has it) */
    int32_t *parent_joint;  /* nbodies: the joint whose child the body is */
    int32_t *order;         /* nbodies: parents before children */
    int32_t nwelded;        /* bodies that are not the root of their composite */
    int32_t *members;       /* nbodies: bodies grouped by composite, parents first */
    int32_t *member_start;  /* ncomp + 2: composite c's members at [start[c], start[c+1]) */
    unsigned char *comp_welded; /* ncomp + 1: holds bodies welded by fixed joints */
    int32_t nquat;          /* joints with a quaternion (spherical, free) */
    double heavy_ratio;     /* the largest mass of a joint's child composite over its parent
                               composite's, the world excluded (model_build; 0 without such a
                               joint): above AQS_HEAVY_CHILD_ABA (1e2) the articulated-body solve
                               always refines (src/solve/aba.c, docs/math.md 5b), above
                               AQS_HEAVY_CHILD (1e3) the adaptive refinement's level is lower */
    double length;          /* the linkage's length scale, m (model_build: the geometric mean
                               of the joints' non-zero offsets in their parents' composites,
                               else of the composites' radii of gyration, else 1): weighs
                               linear against angular parts where the rounding estimate takes
                               norms of spatial vectors, so that it does not depend on the
                               unit of length (src/solve/rounding.c) */
} model;

/* State of the last solve (adaptive back-substitution, MATH.md §6). */
typedef struct {
    int32_t metric;       /* AQS_METRIC_* */
    double eps;           /* 0 = exact */
    int32_t max_computed; /* 0 = no cap */
    int32_t joint_bound;  /* AQS_JOINT_BOUND_* */
    int enabled;          /* total-acceleration factors are maintained */
    /* results */
    int all;              /* the last solve computed every joint (exact path) */
    int valid;            /* heap and queue still match positions and loads (refine allowed) */
    int tracked;          /* the processed/reached lists describe the current outputs */
    int32_t *processed;   /* internal nodes processed, in order */
    int32_t nprocessed;
    int32_t *reached;     /* composites with welded bodies whose leaf got its forces */
    int32_t nreached;
    double *heap_key;
    int32_t *heap_item;
    int32_t heap_size;
    double sum;           /* running sum of the queued A values (eps_c^2) */
    double sum_h;         /* world measures: running sum of the queued nodes' E_h */
    double a_root;        /* A(root) */
    double lower;         /* L: lower bound on max_j ||qdd_j|| */
    int32_t computed;     /* counted joints computed: N_E */
    int32_t counted;      /* counted joints in the linkage */
    double bound;         /* certified bound of the last solve */
    int capped;           /* stopped by max_computed */
    /* Prediction (adaptive.c): nodes the next solve processes without
     * evaluating A, so the updates before it skip their factors T. */
    double margin;          /* aqs_linkage_set_prediction; 0 = off */
    unsigned char *pred;    /* nnodes: in the predicted set (top-closed) */
    unsigned char *tstale;  /* nnodes: T not recomputed since the node moved (only in pred) */
    double *aval;           /* nnodes: A of the node at its last push, or summed (forced) */
    int32_t *plist;         /* the npred members of pred */
    int32_t npred;
    int32_t npredicted;     /* nodes the last solve processed because they were predicted */
    double comp_sq;         /* sum of ||qdd_j||^2 over the computed joints */
    /* Rounding estimate of the last solve (src/solve/rounding.c) */
    double rc_sq, rc_max;   /* sum of squares / largest estimated error of the computed joints */
    double rf_max;          /* the largest estimated error of the computed free joints, as
                               |(dw, dv / l)| (the world measures, src/solve/worldbound.c) */
    double rk_max;          /* largest relative error level met (units of u) */
    double rfe_max, rfn_max; /* the computed joints' largest estimated constraint-force error and
                               largest constraint force, |(n / l, f)| (the adaptive refinement's
                               trigger, src/solve/adaptive.c) */
    int rnd_ok;             /* the estimate's storage exists (tree.rnd_x) */
    double rounding;        /* aqs_solve_stats.rounding_bound */
    double rounding_rel;    /* rounding relative to the solution's size in the measure (+inf: none) */
    int certified;          /* aqs_solve_stats.certified */
    int32_t arefined;       /* corrections of the computed joints the last adaptive solve kept (src/solve/arefine.c) */
    int32_t refined;        /* correction solves the last exact DCA solve kept (src/solve/refine.c): the joint
                               forces' first refinement's and GMRES steps */
} solve_state;

/* The exact solve by the articulated-body algorithm (src/solve/aba.c). Its data
 * live in one order, the "ABA order" (composites depth first, parents
 * before children, children by effective joint index: for a linkage added
 * depth first it is the user's order), streamed forward and backward.
 * Position k is composite aba_joint[k].comp hanging from its effective
 * parent joint. Spatial inertias are packed symmetric [A B; B^T C]:
 * A and C upper triangles (xx xy xz yy yz zz), B row-major 3x3. */
typedef struct {
    int32_t parent;   /* ABA position of the parent composite; -1: the world */
    int32_t type;     /* AQS_JOINT_* */
    int32_t qoff, voff;
    int32_t joint;    /* user joint index */
    int32_t comp;     /* the child composite */
    pose place;       /* the (aligned) joint frame in the parent composite's frame */
    double I[21];     /* the composite's spatial inertia, its frame, packed */
} aba_joint;

/* Rewritten by every solve, same order. IA and pA are left at I and 0 by
 * the forward pass for the next solve's backward pass (children add into
 * their parent before the parent's turn). */
typedef struct {
    pose X;           /* the composite's frame in its parent's at the current q */
    double IA[21];    /* articulated inertia of the subtree, its frame, packed */
    double pA[6];     /* bias force of the subtree (minus the loads), its frame */
    union {
        struct {
            double U[6];   /* IA S (1-dof joints) */
            double acc[6]; /* acceleration minus g (root trick) */
        } s;
        pose world;   /* before the backward pass: the frame's world pose (loads) */
    } v;
    double u, Dinv;   /* Q - S^T pA and 1 / (S^T U) (1-dof joints) */
} aba_node;

enum { ABA_LEAF = 1, ABA_LAST = 2 }; /* aba_state.kin */

typedef struct {
    aba_joint *joint; /* ne, ABA order */
    aba_node *node;   /* ne, ABA order */
    int32_t *pos_of_comp; /* ncomp: ABA position of each composite */
    double *Um;       /* multi-dof joints' U (row j = IA S_j), 6 per dof, at 6 moff[k]; NULL without */
    double *um;       /* multi-dof joints' u, at moff[k]; NULL without */
    int32_t *moff;    /* ne: ABA position k's offset in um (multi-dof joints; NULL without) */
    double *x;        /* 6 x max handles: a welded composite's leaf handle forces */
    unsigned char *need; /* ne: the position's world pose was computed for the loads */
    unsigned char *kin;  /* ne: ABA_LEAF (no child), ABA_LAST (its parent's last child in ABA
                            order): where the forward pass's balance of forces is complete */
    int32_t *path;    /* ne: the positions marked in need, for the loads' world poses */
    int dirty;        /* a failed solve left IA / pA accumulated: reset them first */
    int world_valid;  /* node[].v.world holds the world poses (update_loads reads them) */
    int x_valid;      /* inside aba_solve after its pose sweep: world poses by walking up
                         (kin_comp_world_walk) rather than refreshing stale tree poses */
    int lost;         /* the last solve's refinement stopped short of the rounding level: its
                         factors do not hold the digits (abarefine.c) */
    int32_t fkept;    /* corrections the last refinement of the forces kept (abarefine.c) */
} aba_state;

/* The automatic choice between the adaptive and the exact path (src/solve/autopath.c). */
typedef struct {
    int on;            /* aqs_linkage_set_auto (default 1) */
    int known;         /* proc and pred describe a solve since the model was reset */
    double proc;       /* internal nodes an adaptive solve processes: the last adaptive
                          solve's count, or the estimate from the last exact solve */
    double pred;       /* of which predicted (their factors skipped after a move) */
    int refines;       /* the last adaptive solve refined its computed joints (src/solve/arefine.c):
                          the next one is counted as refining too */
    double regret;     /* what adaptive steps would have saved over the exact solves the
                          model chose since the last adaptive one (instructions) */
    int32_t since;     /* exact solves since the last estimate from accelerations */
    int own_stale;     /* the whole tree is stale because of an exact step's move (the
                          switch cost), not because of the caller (set_positions) */
    int32_t path;      /* AQS_PATH_* of the last solve */
    int chose;         /* the model chose the last solve's path */
    double cost_adaptive, cost_exact; /* the model's costs for the last solve (0: not asked) */
    double work;       /* the work meter (src/solve/cost.h): instructions counted by the passes
                          since the last exact solve began */
    double exact;      /* what the last exact solve counted (0: none yet, or the exact
                          refinement's setting changed since) */
} autopath_state;

/* Memory through the linkage's allocator (src/base/pool.c). Every block
 * carries a header with its size and what it is for, so that the linkage
 * counts what it holds by category (aqs_linkage_get_memory). lk_alloc and
 * lk_calloc count as LK_MEM_MODEL; the _in forms name the category
 * (functions below, after the struct). */
enum {
    LK_MEM_MODEL,     /* what was built: bodies, joints, loads, names, results, rigid groups */
    LK_MEM_TREE,      /* the assembly tree: nodes, handle lists, poses, lazy-update sets */
    LK_MEM_EXACT,     /* the articulated-body solver */
    LK_MEM_DCA,       /* DCA coefficients, inverse inertias, rounding estimate, adaptive arrays */
    LK_MEM_FACTORS,   /* total-acceleration factors */
    LK_MEM_WORLD,     /* the world measures' per-node data */
    LK_MEM_COLLISION, /* shapes, bounding volumes, certificates */
    LK_MEM_COUNT
};

struct aqs_linkage {
    aqs_alloc_fn alloc;
    aqs_free_fn free_fn;
    void *user;
    size_t mem[LK_MEM_COUNT]; /* bytes held by category, headers included (the handle in MODEL) */
    size_t mem_now, mem_peak; /* their sum, and its largest value so far */
    size_t mem_blocks;        /* blocks held, the handle included */
    char error[640];
    int finalized;
    int solved;
    int loads_dirty;  /* body loads changed, or positions moved (world-frame loads) */
    int gravity_dirty; /* gravity changed since the world leaf was computed */
    int lax_inertia;  /* accept inertias violating the triangle inequality */
    int32_t tree_builder; /* AQS_TREE_* */

    int32_t nbodies, body_cap;
    body_def *bodies;
    body_load *loads;
    int32_t *load_slot; /* nbodies: position in loaded_bodies or -1 */
    int32_t *loaded_bodies;
    int32_t nloaded;

    int32_t njoints, joint_cap;
    joint_def *joints;
    int32_t nq, nv, q_cap, v_cap;
    double *q;   /* nq positions */
    double *tau; /* nv active joint forces */
    double gravity[3];

    model m;
    tree t;
    double *qdd;      /* nv */
    double *cforce;   /* 6 njoints */
    double *q_saved;  /* nq: positions before a step, to undo a failed one */
    double *welded_acc; /* scratch for fixed-joint forces */
    solve_state s;
    int32_t exact_solver; /* AQS_EXACT_* */
    int32_t refine_max;   /* corrections of an exact DCA solve (aqs_linkage_set_exact_refinement) */
    int32_t refine_forces; /* 1 (set at create): the exact refinement refines the joint forces first
                              (src/solve/refine.c, FORCES); 0 only in tests, for GMRES alone */
    int32_t dca_form;     /* AQS_DCA_FORM_* (set before finalize) */
    int exact_by_aba;     /* the last solve was exact by the articulated-body algorithm */
    int32_t aba_skip;     /* exact solves left that go to the DCA without trying the articulated-body
                             solve, after one handed over (src/api/api.c, exact_solve; set to
                             AQS_HANDOVER_RUN) */
    int handover;         /* the exact DCA solve running answers for the articulated-body solve
                             (exact_solve): its factors lost the digits, no polish by them
                             (src/solve/refine.c) */
    double fallback;      /* aqs_linkage_set_exact_fallback's fraction (0: off) */
    int32_t fb_left;      /* exact solves left before the adaptive solver is tried again */
    int fb_last;          /* the last solve was such an exact solve */
    double rfb_level;     /* aqs_linkage_set_rounding_fallback's level (0: off) */
    double arf_level;     /* aqs_linkage_set_adaptive_refinement's level (0: off) */
    int32_t rfb_left;     /* exact solves left in a rounding fallback's run */
    int rfb_last;         /* the last solve was exact because of the rounding fallback */
    int32_t rfb_processed; /* the nodes the adaptive solve it replaced processed (stats; 0 otherwise) */
    aba_state aba;
    struct collision *col; /* shapes and their queries (src/collide/collide.h); NULL without shapes */
    struct worldbound *wb; /* the world-space measures' per-node data (src/solve/worldbound.h); NULL until one is set */
    struct arefine *arf;   /* the adaptive solve's refinement arrays (src/solve/arefine.c); NULL
                              until an adaptive solve refines */
    struct aba_refine *abarf; /* the articulated-body solve's refinement arrays (src/solve/abarefine.c);
                                 NULL until an articulated-body solve refines */
    struct refine *rf;     /* the exact DCA solve's refinement arrays (src/solve/refine.c); NULL until
                              an exact DCA solve refines */
    int dd_fma;            /* the double-double passes take the fma product (src/solve/residual.c,
                              residual_dd_select) */
    char **body_name;     /* body_name_cap entries (NULL = unnamed); NULL until a name is set */
    char **joint_name;
    int32_t body_name_cap, joint_name_cap;
    char *load_warnings;  /* what the last URDF load did not model (src/api/urdf.c); NULL = none */
    autopath_state ap;    /* the automatic path (src/solve/autopath.c) */
};

/* The name of a body / joint, or NULL (set by src/api/names.c; model.c's messages read
 * them, so they are here, below the public face). */
static inline const char *lk_body_name(const aqs_linkage *L, int32_t body)
{
    if (!L->body_name || body < 0 || body >= L->body_name_cap) return NULL;
    return L->body_name[body];
}
static inline const char *lk_joint_name(const aqs_linkage *L, int32_t joint)
{
    if (!L->joint_name || joint < 0 || joint >= L->joint_name_cap) return NULL;
    return L->joint_name[joint];
}
/* Release the names and the load warnings (aqs_linkage_destroy; src/api/names.c). */
void lk_names_free(aqs_linkage *L);

void *lk_alloc(aqs_linkage *L, size_t bytes);
void *lk_calloc(aqs_linkage *L, size_t count, size_t size);
void *lk_alloc_in(aqs_linkage *L, int category, size_t bytes);
void *lk_calloc_in(aqs_linkage *L, int category, size_t count, size_t size);
void lk_free(aqs_linkage *L, void *p);
/* Bytes (headers included) requested from the allocator for one block of
 * `bytes` (the handle is counted as allocated, without a header). */
size_t lk_block_bytes(size_t bytes);
/* Record an error message (printf-style) and return status. */
aqs_status lk_fail(aqs_linkage *L, aqs_status status, const char *fmt, ...)
#ifdef __GNUC__
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* Prefix the recorded message with "fn: " unless it names a function of the
 * API already (it starts with "aqs_"): the solvers' own messages do not know
 * which call reached them. Returns status. */
aqs_status lk_fail_in(aqs_linkage *L, aqs_status status, const char *fn);

#endif
