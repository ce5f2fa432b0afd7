/* worldbound.h -- the world-space error measures (AQS_METRIC_ABS_WORLD,
 * AQS_METRIC_REL_WORLD; docs/math.md §10b): per assembly-tree node, a
 * bounding sphere of its bodies' centres of mass and joint origins (kept in
 * the node's frame, recomputed by the lazy update with the node's other
 * coefficients) and the static sums of its joints' motion-subspace norms;
 * per solve, the world pose of every node reached and a lower bound on the
 * largest body acceleration. */
#ifndef AQS_WORLDBOUND_H
#define AQS_WORLDBOUND_H

#include "linkage.h"

struct worldbound {
    double *sph;          /* 4 per node: centre (node frame), radius (< 0: no point) */
    double *sl2, *sa2;    /* per node: the largest sum of sigma_lin^2 (sigma_ang^2) over the joints
                             of n on the path from n's entry (or the world) to one of its composites */
    double *hl2, *ha2;    /* per handle (tree.handles offsets): the same sums on the path to the
                             handle's composite on n's side (0 for the entry) */
    double *lmax;         /* per node: largest length scale ell_b of a body inside (static) */
    unsigned char *holds; /* per node: it holds up a joint whose child side is outside it */
    int32_t *size;        /* per node: nodes in its subtree, itself included (the subtree
                             is the index range (n - size, n]) */
    pose *wpose;          /* per node: world pose of its frame (root: identity), set when
                             its parent is processed (valid for processed and queued nodes) */
    double *ell;          /* per body: ell_b = sqrt(tr(I_com) / (2 m)) (0 if m <= 0) */
    double *beyond;       /* per node: its E_h when it was last queued (0: holds nothing) */
    double lower;         /* lower bound on max_b e(a_b) from the reached leaves */
    double lower_r;       /* the same less each reached body's estimated rounding (the
                             rounding estimate's denominator, docs/math.md §10b) */
    double pl_all, pa_all; /* the largest sum of sigma_lin^2 (sigma_ang^2) over the non-fixed
                             joints, free ones left out, on one body's path to the world */
};

/* Whether the linkage's metric is a world one (and the data exist). */
int worldbound_active(const aqs_linkage *L);
/* Allocate and set up the static data (first world metric). The caller
 * marks the whole tree stale so that every node's sphere is computed.
 * AQS_OK or AQS_ENOMEM (message naming fn; nothing changed). */
aqs_status worldbound_enable(aqs_linkage *L, const char *fn);
void worldbound_free(aqs_linkage *L);
/* Internal node n's sphere from its children's (after its frames moved). */
void worldbound_node_update(aqs_linkage *L, int32_t n);
/* A solve starts: the root's world pose, lower bound 0. */
void worldbound_begin(aqs_linkage *L);
/* Node n was back-substituted: its children's world poses, and the exact
 * accelerations of its leaf children raise the lower bound. */
void worldbound_processed(aqs_linkage *L, int32_t n);
/* The bound E_n = max(E_in, E_h) on node n's contribution to max_b
 * e(delta a_b), from its total acceleration A(n) (the node's world pose must
 * be set). *beyond: E_h, the part for the bodies beyond the handles n holds
 * up (0 when it holds none): the solve's bound is also at most the largest
 * queued E_n plus the sum of the queued E_h (docs/math.md §10b). */
double worldbound_key(const aqs_linkage *L, int32_t n, double a, double *beyond);

/* What the DCA's rounding adds to abs_world, from r2, the 2-norm of the
 * estimated errors of every non-free joint's acceleration (computed and
 * uncomputed ones), and rfree, the largest free joint's as |(dw, dv / l)|:
 * r2 (sqrt(pl_all) + lever sqrt(pa_all)) + rfree (l + lever), lever =
 * 2 R_0 + ellmax, l the linkage's length scale. */
double worldbound_rounding(const aqs_linkage *L, double r2, double rfree);

#endif
