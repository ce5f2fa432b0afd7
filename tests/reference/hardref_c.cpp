// hardref_c.cpp -- the extended-precision reference of hard_reference.hpp as a small shared
// library for the Python tests (build/tests/reference/libhardref.so; tests only, not part of
// libaqs). The model is read through the public C API from the caller's linkage handle;
// the loads, which the C API cannot read back, are passed in.
//
// int hardref_solve(const aqs_linkage *l, const double gravity[3],
//                   const double *tau, int32_t ntau,          // NULL/0: no joint forces
//                   int32_t precision,                        // 0 long double, 1 __float128
//                   double *qdd, int32_t nqdd,                // out, nv values
//                   char *err, int32_t nerr)                  // message on failure
// Returns 0 on success, -1 on failure (err filled). Body loads are not supported here (the
// Python tests use gravity and joint forces only).
//
// int hardref_solve_forces(... the same ..., double *f, int32_t nf, char *err, int32_t nerr)
// also gives every joint's constraint force (nf = 6 x joints; aqs_linkage_get_constraint_forces'
// layout: the force on the child, child frame, about its origin, torque first), from the
// reference's own accelerations (Newton-Euler on each joint's subtree).
#include <aqs.h>

#include <cstdio>
#include <cstring>
#include <exception>

#include "hard_reference.hpp"

namespace {

template <class T>
void copy_out(const hardref::Result<T> &r, int32_t nv, double *qdd, double *f) {
    for (int i = 0; i < nv; ++i) qdd[i] = (double)r.qdd[i];
    if (f)
        for (size_t j = 0; j < r.force.size(); ++j)
            for (int c = 0; c < 6; ++c) f[6 * j + c] = (double)r.force[j].v[c];
}

int solve_impl(const aqs_linkage *l, const double gravity[3], const double *tau, int32_t ntau,
               int32_t precision, double *qdd, int32_t nqdd, double *f, int32_t nf, char *err,
               int32_t nerr) {
    try {
        const hardref::ModelData m = hardref::read_model(l);
        if (nqdd != m.nv) throw std::invalid_argument("nqdd != nv");
        if (ntau != 0 && ntau != m.nv) throw std::invalid_argument("ntau != nv");
        if (f && nf != 6 * (int32_t)m.joints.size()) throw std::invalid_argument("nf != 6 x joints");
        hardref::Loads L;
        for (int i = 0; i < 3; ++i) L.gravity[i] = gravity[i];
        if (ntau) L.tau.assign(tau, tau + ntau);
        if (precision == 1)
            copy_out(hardref::solve<hardref::quad>(m, L), m.nv, qdd, f);
        else
            copy_out(hardref::solve<long double>(m, L), m.nv, qdd, f);
        return 0;
    } catch (const std::exception &e) {
        if (err && nerr > 0) std::snprintf(err, (size_t)nerr, "%s", e.what());
        return -1;
    }
}

}  // namespace

extern "C" __attribute__((visibility("default"))) int hardref_solve(
    const aqs_linkage *l, const double gravity[3], const double *tau, int32_t ntau,
    int32_t precision, double *qdd, int32_t nqdd, char *err, int32_t nerr) {
    return solve_impl(l, gravity, tau, ntau, precision, qdd, nqdd, nullptr, 0, err, nerr);
}

extern "C" __attribute__((visibility("default"))) int hardref_solve_forces(
    const aqs_linkage *l, const double gravity[3], const double *tau, int32_t ntau,
    int32_t precision, double *qdd, int32_t nqdd, double *f, int32_t nf, char *err, int32_t nerr) {
    return solve_impl(l, gravity, tau, ntau, precision, qdd, nqdd, f, nf, err, nerr);
}
