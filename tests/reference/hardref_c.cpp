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
#include <aqs.h>

#include <cstdio>
#include <cstring>
#include <exception>

#include "hard_reference.hpp"

extern "C" __attribute__((visibility("default"))) int hardref_solve(
    const aqs_linkage *l, const double gravity[3], const double *tau, int32_t ntau,
    int32_t precision, double *qdd, int32_t nqdd, char *err, int32_t nerr) {
    try {
        const hardref::ModelData m = hardref::read_model(l);
        if (nqdd != m.nv) throw std::invalid_argument("nqdd != nv");
        if (ntau != 0 && ntau != m.nv) throw std::invalid_argument("ntau != nv");
        hardref::Loads L;
        for (int i = 0; i < 3; ++i) L.gravity[i] = gravity[i];
        if (ntau) L.tau.assign(tau, tau + ntau);
        if (precision == 1) {
            const auto r = hardref::solve<hardref::quad>(m, L);
            for (int i = 0; i < m.nv; ++i) qdd[i] = (double)r.qdd[i];
        } else {
            const auto r = hardref::solve<long double>(m, L);
            for (int i = 0; i < m.nv; ++i) qdd[i] = (double)r.qdd[i];
        }
        return 0;
    } catch (const std::exception &e) {
        if (err && nerr > 0) std::snprintf(err, (size_t)nerr, "%s", e.what());
        return -1;
    }
}
