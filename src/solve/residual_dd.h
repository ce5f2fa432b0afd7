/* residual_dd.h -- the body of the double-double residual passes
 * (residual.h, residual_dd_*), included twice by residual.c: with the exact
 * product by Dekker's splitting, and on x86-64 with the fma instruction
 * (compiled for the "fma" target, run where the processor has it). Both
 * products are exact, so both give the same results bit for bit (make
 * check-hard compares them: AQS_SIMD=sse2 takes the first). Before each
 * inclusion: DD_FN(name) (the functions' names), DD_TARGET (their target
 * attribute, or nothing), DD_ADD_MUL and DD_ADD_PROD (src/base/ddouble.h's
 * dd_add_mul and dd_add_prod, or their _fma forms). Not a header of its own:
 * no include guard. */

/* Double-double forms of aba.c's transforms: o = X v (v a motion in the
 * parent's frame), g += X^T f, o = I v (I packed). */
static DD_TARGET void DD_FN(dd_motion_from_parent)(const pose *P, const ddouble *v, ddouble *o)
{
    const double *R = P->R, *p = P->p;
    ddouble t[3];
    int i;
    t[0] = DD_ADD_MUL(DD_ADD_MUL(v[3], -p[1], v[2]), p[2], v[1]);
    t[1] = DD_ADD_MUL(DD_ADD_MUL(v[4], -p[2], v[0]), p[0], v[2]);
    t[2] = DD_ADD_MUL(DD_ADD_MUL(v[5], -p[0], v[1]), p[1], v[0]);
    for (i = 0; i < 3; i++) {
        o[i] = DD_ADD_MUL(DD_ADD_MUL(DD_ADD_MUL(dd_from(0.0), R[i], v[0]), R[3 + i], v[1]), R[6 + i], v[2]);
        o[3 + i] = DD_ADD_MUL(DD_ADD_MUL(DD_ADD_MUL(dd_from(0.0), R[i], t[0]), R[3 + i], t[1]), R[6 + i], t[2]);
    }
}

static DD_TARGET void DD_FN(dd_force_to_parent_add)(const pose *P, const ddouble *f, ddouble *g)
{
    const double *R = P->R, *p = P->p;
    ddouble l[3], n[3];
    int i;
    for (i = 0; i < 3; i++) {
        l[i] = DD_ADD_MUL(DD_ADD_MUL(DD_ADD_MUL(dd_from(0.0), R[3 * i], f[3]), R[3 * i + 1], f[4]), R[3 * i + 2], f[5]);
        n[i] = DD_ADD_MUL(DD_ADD_MUL(DD_ADD_MUL(dd_from(0.0), R[3 * i], f[0]), R[3 * i + 1], f[1]), R[3 * i + 2], f[2]);
    }
    g[0] = dd_add(g[0], DD_ADD_MUL(DD_ADD_MUL(n[0], p[1], l[2]), -p[2], l[1]));
    g[1] = dd_add(g[1], DD_ADD_MUL(DD_ADD_MUL(n[1], p[2], l[0]), -p[0], l[2]));
    g[2] = dd_add(g[2], DD_ADD_MUL(DD_ADD_MUL(n[2], p[0], l[1]), -p[1], l[0]));
    for (i = 0; i < 3; i++) g[3 + i] = dd_add(g[3 + i], l[i]);
}

static DD_TARGET void DD_FN(dd_inertia_mul)(const double *I, const ddouble *v, ddouble *o)
{
    double F[36];
    int i, j;
    kin_unpack_inertia(I, F);
    for (i = 0; i < 6; i++) {
        ddouble s = dd_from(0.0);
        for (j = 0; j < 6; j++) s = DD_ADD_MUL(s, F[6 * i + j], v[j]);
        o[i] = s;
    }
}

static DD_TARGET void DD_FN(dd_accelerations)(const aqs_linkage *L, const double *qdd, ddouble *acc)
{
    const model *m = &L->m;
    const aba_state *a = &L->aba;
    double S[36];
    ddouble g[6];
    int32_t k, i, j;
    for (i = 0; i < 3; i++) {
        g[i] = dd_from(0.0);
        g[3 + i] = dd_from(-L->gravity[i]);
    }
    for (k = 0; k < m->ne; k++) {
        const aba_joint *jt = &a->joint[k];
        const double *q = qdd + jt->voff;
        ddouble *ac = acc + 6 * (size_t)k;
        DD_FN(dd_motion_from_parent)(&a->node[k].X, jt->parent < 0 ? g : acc + 6 * (size_t)jt->parent, ac);
        if (jt->type == AQS_JOINT_REVOLUTE) {
            ac[2] = dd_add(ac[2], dd_from(q[0])); /* S = e_z, aligned */
        } else if (jt->type == AQS_JOINT_PRISMATIC) {
            ac[5] = dd_add(ac[5], dd_from(q[0]));
        } else if (jt->type != AQS_JOINT_FIXED) {
            const int d = joint_nv(jt->type);
            joint_subspace_aligned(&L->joints[jt->joint], L->q + jt->qoff, S);
            for (i = 0; i < 6; i++)
                for (j = 0; j < d; j++) ac[i] = DD_ADD_PROD(ac[i], S[i * d + j], q[j]);
        }
    }
}

static DD_TARGET double DD_FN(dd_eval)(const aqs_linkage *L, const ddouble *acc, ddouble *fw, double *r, double *forces)
{
    const model *m = &L->m;
    const aba_state *a = &L->aba;
    const double il = m->length > 0.0 ? 1.0 / m->length : 1.0;
    const double gn = sqrt(L->gravity[0] * L->gravity[0] + L->gravity[1] * L->gravity[1] + L->gravity[2] * L->gravity[2]);
    double rmax = 0.0, smax = 0.0, tsum = 0.0, S[36];
    int32_t k, i, j, bad = 0;
    memset(fw, 0, 6 * (size_t)m->ne * sizeof(ddouble));
    for (i = 0; i < m->nloaded_comps; i++) {
        const int32_t c = m->loaded_comps[i];
        ddouble *f = fw + 6 * (size_t)a->pos_of_comp[c];
        for (j = 0; j < 6; j++) f[j] = dd_from(-m->comp_force[6 * c + j]);
    }
    for (k = m->ne - 1; k >= 0; k--) {
        const aba_joint *jt = &a->joint[k];
        ddouble *f = fw + 6 * (size_t)k, t[6];
        double e = 0.0, fl[6];
        DD_FN(dd_inertia_mul)(jt->I, acc + 6 * (size_t)k, t);
        /* the bodies' terms, their norms summed: I (a - g) and the weight m |g| (in
         * a free fall both are 0 and m |g|, and so are the joint forces) */
        tsum += (fabs(t[0].hi) + fabs(t[1].hi) + fabs(t[2].hi)) * il + fabs(t[3].hi) + fabs(t[4].hi) +
                fabs(t[5].hi) + jt->I[KIN_PC] * gn;
        for (i = 0; i < 6; i++) {
            f[i] = dd_add(f[i], t[i]);
            fl[i] = dd_to_double(f[i]);
        }
        if (jt->type == AQS_JOINT_REVOLUTE || jt->type == AQS_JOINT_PRISMATIC) {
            const int rev = jt->type == AQS_JOINT_REVOLUTE;
            const double v = dd_to_double(dd_add(dd_from(L->tau[jt->voff]), dd_neg(f[rev ? 2 : 5])));
            if (r) r[jt->voff] = v;
            e = fabs(v) * (rev ? il : 1.0);
        } else if (jt->type != AQS_JOINT_FIXED) {
            const int d = joint_nv(jt->type);
            joint_subspace_aligned(&L->joints[jt->joint], L->q + jt->qoff, S);
            for (j = 0; j < d; j++) {
                ddouble s = dd_from(L->tau[jt->voff + j]);
                double v;
                for (i = 0; i < 6; i++) s = DD_ADD_MUL(s, -S[i * d + j], f[i]);
                v = dd_to_double(s);
                if (r) r[jt->voff + j] = v;
                v = fabs(v);
                if (S[0 * d + j] != 0.0 || S[1 * d + j] != 0.0 || S[2 * d + j] != 0.0) v *= il; /* a torque */
                if (!(v <= e)) e = v; /* NaN too */
            }
        }
        rmax = max_of(rmax, e);
        bad |= !(e == e); /* max_of drops a NaN */
        smax = max_of(smax, (fabs(fl[0]) + fabs(fl[1]) + fabs(fl[2])) * il + fabs(fl[3]) + fabs(fl[4]) + fabs(fl[5]));
        if (forces) memcpy(forces + 6 * (size_t)k, fl, sizeof fl);
        if (jt->parent >= 0) DD_FN(dd_force_to_parent_add)(&a->node[k].X, f, fw + 6 * (size_t)jt->parent);
    }
    smax = max_of(smax, tsum);
    if (bad || !isfinite(smax)) return NAN;
    return smax > 0.0 ? rmax / smax : (rmax > 0.0 ? INFINITY : 0.0);
}
