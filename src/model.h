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
/* Spatial inertia of a body about its own origin, body frame. */
void model_body_inertia(const aqs_linkage *L, int32_t body, double I[36]);

#endif
