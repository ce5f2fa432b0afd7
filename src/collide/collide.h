/* collide.h -- the collision state of a linkage (allocated by the first
 * shape or filter call; NULL otherwise) and the broad phase on the assembly
 * tree (src/collide/broadphase.c). */
#ifndef AQS_COLLIDE_H
#define AQS_COLLIDE_H

#include <stddef.h>
#include <stdint.h>

#include "certificate.h"
#include "linkage.h"
#include "narrowphase.h"
#include "shape.h"

typedef struct collision {
    shape_def *shapes;
    int32_t nshapes, shape_cap;
    uint32_t *group, *mask; /* per body, nfilter entries (later bodies: defaults) */
    int32_t nfilter;
    uint32_t world_group, world_mask; /* the obstacles' */
    uint64_t *excl;         /* excluded body pairs, sorted keys (a + 1) << 32 | (b + 1), a < b */
    int32_t nexcl, excl_cap;
    int joined;             /* bodies joined by a joint may collide */
    double stiffness;       /* penalty contact (0: off) */

    /* Built at the first query after finalize (and after shapes change). */
    int built;
    pose *shape_in;      /* nshapes: shape frame in its rigid group's frame */
    int32_t *comp_start; /* ncomp + 2: the shapes of group c at comp_shapes[start[c] .. start[c+1]) */
    int32_t *comp_shapes;
    double *sph;         /* 4 per tree node: bounding sphere (centre, radius; radius < 0: no shape)
                            in the node's upper-handle frame (MATH.md §9.2) */
    unsigned char *moved; /* a joint inside the node moved since its sphere was fitted (top-closed) */
    unsigned char *cached; /* the node's internal contacts at the last query are known (no joint
                              inside it moved since): none if ncont == 0, else the pairs below */
    int32_t *ncont;       /* per node: contacts inside its subassembly at the last query */
    int32_t *xoff, *xcnt; /* per node: its cross pairs (contacts between its children), xcnt
                             pairs from xoff in xp */
    pair_pool xp;         /* 4 pairs per shape + 1,024: live lists are compacted into the
                             other buffer when the current one is half full */
    /* Certificates (docs/collision.md, "Certificates"). */
    double *mabs;         /* per node: accumulated bound on the motion of any point of its
                             subassembly in its frame since the build (leaves: 0) */
    double *mrel;         /* per internal node: accumulated bound on the relative motion of a
                             point of A and a point of B, in its frame */
    double *mchild;       /* 2 per internal node: mabs of A and of B at its last refit */
    unsigned char *cert;  /* the node's cross pair (A, B) is certified: every allowed shape
                             pair off its near list was >= margin apart when mrel was mcert */
    double *mcert, *margin;
    int32_t *noff, *ncnt; /* per node: its near list, ncnt pairs from noff in np */
    pair_pool np;         /* 8 pairs per shape + 4,096, compacted like xp */
    int first_fit;        /* the build's refit: no motion to account for */
    pose *pk;             /* per internal node: the child frame of its principal joint in the
                             node's frame, cached at refit */
    pose *wpose;          /* per node: world pose of its frame, valid when wstamp == qstamp */
    double *wcen;         /* per node: world centre of its sphere, likewise */
    uint32_t *wstamp, qstamp;
    pose *comp_world;     /* ncomp + 1: brute-force scratch */
    placed_shape *placed; /* nshapes: brute-force scratch */
    double *centres;      /* 3 nshapes: brute-force scratch */

    /* Work of the last query. */
    int32_t nodes_refit, volume_tests, narrow_tests, nodes_skipped;
    int32_t certs_reused, certs_made, near_tests; /* internal (tests, bench) */
} collision;

/* A linkage holds shapes: from its first shape on the tree's poses follow
 * every move (a linkage with collision settings and no shape pays nothing
 * per move, and counts as empty for the URDF loader). */
static inline int collide_has_shapes(const aqs_linkage *L) { return L->col && L->col->nshapes > 0; }

void collide_free(aqs_linkage *L);
/* Forget the built data (shapes changed). */
void broadphase_reset(aqs_linkage *L);
/* Forget which subassemblies were free of contact (filters changed). */
void broadphase_forget(aqs_linkage *L);
/* The cross poses of internal node n changed (src/solve/frames.c): mark it and its
 * ancestors for refitting. O(1) amortized. */
void broadphase_node_moved(aqs_linkage *L, int32_t n);
/* Build the per-node data if needed. AQS_OK or AQS_ENOMEM (message set, nothing changed). */
aqs_status broadphase_build(aqs_linkage *L, const char *fn);
/* Build the data for the first nshapes shapes (nshapes may exceed
 * L->col->nshapes by the shapes just appended) beside the current data. On
 * AQS_ENOMEM (message set) the collision state is exactly as before, the
 * built data of the former shapes included; on AQS_OK nshapes is the count. */
aqs_status broadphase_rebuild(aqs_linkage *L, int32_t nshapes, const char *fn);
/* Run a query (after broadphase_build): mode AQS_COLLIDE_*; contacts up to
 * capacity into out; any != 0 stops at the first contact. Returns the total. */
size_t broadphase_query(aqs_linkage *L, int32_t mode, aqs_contact *out, size_t capacity, int any);
/* Penalty contact (src/solve/update.c, inside update_loads): a lazy query whose
 * contacts add k depth n at their points to the rigid groups' comp_force,
 * registering the groups as loaded. Needs the built data. */
void broadphase_penalty(aqs_linkage *L);

#endif
