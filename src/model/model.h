/* model.h -- bodies, joints, validation at finalize, welding of fixed joints. */
#ifndef AQS_MODEL_H
#define AQS_MODEL_H

#include "linkage.h"

/* Validate body values (mass, inertia). Returns AQS_OK or AQS_EINVAL with a
 * message naming fn. */
aqs_status model_check_body(aqs_linkage *L, const char *fn, double mass, const double com[3],
                            const double inertia[9]);
/* Validate the topology and build L->m (composites, effective joints).
 * Returns AQS_OK, AQS_EMODEL or AQS_ENOMEM; on failure L->m is empty. */
aqs_status model_build(aqs_linkage *L);
void model_free(aqs_linkage *L);
/* The composites' inverse inertias (comp_inverse), allocated and computed
 * when first needed: the inverse-inertia form (dca_enable), welded bodies
 * (finalize) and the world measures (worldbound_enable).
 * AQS_OK or AQS_ENOMEM (nothing changed). */
aqs_status model_inverse_alloc(aqs_linkage *L);
/* a = I_c^-1 f for composite c: from comp_inverse when it is held (welded
 * bodies, the inverse-inertia form, a world measure), else computed as
 * model_inverse_alloc would compute it (the same bits; the square-root form
 * needs it only when a leaf's centre-of-mass factor fails). */
void model_inverse_apply(const aqs_linkage *L, int32_t c, const double f[6], double a[6]);
/* Release comp_inertia and eff_place after finalize: the articulated-body
 * solver keeps both in its own order (kin_comp_inertia, kin_eff_place). */
void model_drop_inertia(aqs_linkage *L);
/* Spatial inertia of a body about its own origin, body frame. */
void model_body_inertia(const aqs_linkage *L, int32_t body, double I[36]);
/* Mass properties mp (13 doubles: mass, centre of mass, rotational inertia
 * about it, 3x3 row-major) combined by the two-body parallel-axis rule, only
 * sums of positive terms: acc += (m2, c2, I2), acc += mp posed by P in acc's
 * frame, and a composite's from its bodies (in its root body's frame). */
void model_mass_add(double *acc, double m2, const double c2[3], const double I2[9]);
void model_mass_add_posed(double *acc, const pose *P, const double *mp);
void model_comp_mass(const aqs_linkage *L, int32_t comp, double *mp);

#endif
