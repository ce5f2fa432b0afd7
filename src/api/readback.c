/* readback.c -- reading the model back as it was added: a body's mass
 * properties and a joint's definition (what an exporter such as URDF needs).
 * Valid in any phase; only the error message of the linkage is written. */
#include <string.h>

#include "aqs.h"
#include "joint.h"
#include "linkage.h"

AQS_API aqs_status aqs_body_get_inertial(const aqs_linkage *cL, int32_t body, double *mass,
                                         double com[3], double inertia[9])
{
    aqs_linkage *L = (aqs_linkage *)cL; /* only the error message is written */
    const body_def *b;
    if (!L) return AQS_EINVAL;
    if (body < 0 || body >= L->nbodies)
        return lk_fail(L, AQS_ERANGE, "aqs_body_get_inertial: body = %d is out of range [0, %d)",
                       (int)body, (int)L->nbodies);
    b = &L->bodies[body];
    if (mass) *mass = b->mass;
    if (com) memcpy(com, b->com, sizeof b->com);
    if (inertia) memcpy(inertia, b->inertia, sizeof b->inertia);
    return AQS_OK;
}

AQS_API aqs_status aqs_joint_get_definition(const aqs_linkage *cL, int32_t joint, int32_t *type,
                                            int32_t *parent, int32_t *child, double pos[3],
                                            double quat[4], double axis[3])
{
    aqs_linkage *L = (aqs_linkage *)cL;
    const joint_def *j;
    if (!L) return AQS_EINVAL;
    if (joint < 0 || joint >= L->njoints)
        return lk_fail(L, AQS_ERANGE,
                       "aqs_joint_get_definition: joint = %d is out of range [0, %d)", (int)joint,
                       (int)L->njoints);
    j = &L->joints[joint];
    if (type) *type = j->type;
    if (parent) *parent = j->parent;
    if (child) *child = j->child;
    if (pos) memcpy(pos, j->pos, sizeof j->pos);
    if (quat) { /* w >= 0 (docs/api.md, Conventions): q and -q are the same rotation */
        const double sgn = j->quat[0] < 0.0 ? -1.0 : 1.0;
        int i;
        for (i = 0; i < 4; i++) quat[i] = sgn * j->quat[i];
    }
    if (axis) memcpy(axis, j->axis, sizeof j->axis);
    return AQS_OK;
}
