// test_vectors.cpp -- the exact test vectors ($AQS_VECTORS/exact/*.json; make check points
// AQS_VECTORS at tests/vectors) against the library (through the C API) and against the dense reference of dense_reference.hpp.
//
// For every vector:
//   * library vs expected: relative 2-norm error over the whole vector <= 1e-8 for the
//     accelerations and for the constraint forces (the contract of tests/vectors/README.md);
//   * reference vs expected: the same bound (validates dense_reference.hpp itself; the
//     measured agreement is ~1e-14);
//   * library world poses vs the reference's forward kinematics (1e-12, scaled).
// The library-vs-reference errors are printed for information (the expected values are
// themselves rounded: 09-chain-60-floating carries ~1e-11).
// Prints one line per vector, then "N passed, M failed"; exits non-zero on any failure.
#include <aqs.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <dirent.h>
#include <fstream>
#include <string>
#include <vector>

#include "dense_reference.hpp"

using aqsref::Model;
using aqsref::Real;

namespace {

const double kTolVector = 1e-8;  // vectors/README.md
const double kTolPose = 1e-12;

int joint_type_from_name(const std::string &s) {
    for (int t = 0; t < 8; ++t)
        if (s == aqsref::joint_type_name(t)) return t;
    throw std::runtime_error("unknown joint type '" + s + "'");
}

template <size_t N> std::array<double, N> arr(const nlohmann::json &j) {
    if (!j.is_array() || j.size() != N) throw std::runtime_error("bad array size");
    std::array<double, N> a{};
    for (size_t i = 0; i < N; ++i) a[i] = j[i].get<double>();
    return a;
}

struct Vector {
    Model model;
    std::vector<double> acc;  // expected accelerations
    std::vector<double> cf;   // expected constraint forces, joints x 6
};

Vector load_vector(const std::string &path) {
    std::ifstream in(path);
    if (!in) throw std::runtime_error("cannot open " + path);
    const nlohmann::json d = nlohmann::json::parse(in);
    Vector v;
    Model &m = v.model;
    for (const auto &b : d.at("bodies")) {
        aqsref::Body body;
        body.mass = b.at("mass").get<double>();
        body.com = arr<3>(b.at("com"));
        const auto &I = b.at("inertia");
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) body.inertia[3 * r + c] = I.at(r).at(c).get<double>();
        m.bodies.push_back(body);
    }
    for (const auto &j : d.at("joints")) {
        aqsref::Joint jt;
        jt.type = joint_type_from_name(j.at("type").get<std::string>());
        jt.parent = j.at("parent").get<int>();
        jt.child = j.at("child").get<int>();
        jt.pos = arr<3>(j.at("pos"));
        jt.quat = arr<4>(j.at("quat"));
        if (j.contains("axis")) jt.axis = arr<3>(j.at("axis"));
        m.joints.push_back(jt);
    }
    for (const auto &q : d.at("positions")) m.positions.push_back(q.get<double>());
    m.gravity = arr<3>(d.at("gravity"));
    for (const auto &f : d.at("body_forces")) {
        aqsref::BodyForce bf;
        bf.body = f.at("body").get<int>();
        bf.force = arr<3>(f.at("force"));
        bf.point = arr<3>(f.at("point"));
        bf.torque = arr<3>(f.at("torque"));
        m.body_forces.push_back(bf);
    }
    for (const auto &f : d.at("joint_forces")) {
        aqsref::JointForce jf;
        jf.joint = f.at("joint").get<int>();
        for (const auto &x : f.at("tau")) jf.tau.push_back(x.get<double>());
        m.joint_forces.push_back(jf);
    }
    const auto &e = d.at("expected");
    for (const auto &x : e.at("accelerations")) v.acc.push_back(x.get<double>());
    for (const auto &row : e.at("constraint_forces")) {
        if (row.size() != 6) throw std::runtime_error("constraint force row size != 6");
        for (const auto &x : row) v.cf.push_back(x.get<double>());
    }
    return v;
}

// ||got - want||_2 / ||want||_2 (absolute when want is 0).
double rel_err(const std::vector<double> &got, const std::vector<double> &want) {
    if (got.size() != want.size()) return INFINITY;
    long double num = 0, den = 0;
    for (size_t i = 0; i < got.size(); ++i) {
        const long double d = (long double)got[i] - want[i];
        num += d * d;
        den += (long double)want[i] * want[i];
    }
    if (!std::isfinite((double)num)) return INFINITY;
    return (double)std::sqrt(den > 0 ? num / den : num);
}

// Library results, or an error message.
struct LibResult {
    std::string error;
    std::vector<double> acc, cf, poses;
};

#define LIB_CALL(expr)                                                                       \
    do {                                                                                     \
        const aqs_status st_ = (expr);                                                       \
        if (st_ != AQS_OK) {                                                                 \
            r.error = std::string(#expr) + " -> " + aqs_status_string(st_) + ": " +          \
                      aqs_linkage_last_error(L);                                             \
            aqs_linkage_destroy(L);                                                          \
            return r;                                                                        \
        }                                                                                    \
    } while (0)

LibResult run_library(const Model &m) {
    LibResult r;
    aqs_linkage *L = nullptr;
    if (aqs_linkage_create(&L) != AQS_OK || !L) {
        r.error = "aqs_linkage_create failed";
        return r;
    }
    // The vectors' inertias are synthetic (random SPD matrices, some violating the triangle
    // inequality of real mass distributions): accept any SPD inertia.
    LIB_CALL(aqs_linkage_set_inertia_check(L, 0));
    for (const auto &b : m.bodies) {
        int32_t id = -1;
        LIB_CALL(aqs_body_add(L, b.mass, b.com.data(), b.inertia.data(), &id));
    }
    for (const auto &j : m.joints) {
        int32_t id = -1;
        LIB_CALL(aqs_joint_add(L, j.type, j.parent, j.child, j.pos.data(), j.quat.data(),
                               j.axis.data(), &id));
    }
    LIB_CALL(aqs_linkage_finalize(L));
    int32_t nb = 0, nj = 0, nq = 0, nv = 0;
    LIB_CALL(aqs_linkage_get_sizes(L, &nb, &nj, &nq, &nv));
    if (nb != (int32_t)m.bodies.size() || nj != (int32_t)m.joints.size() ||
        nq != (int32_t)m.positions.size()) {
        r.error = "aqs_linkage_get_sizes: unexpected sizes";
        aqs_linkage_destroy(L);
        return r;
    }
    LIB_CALL(aqs_linkage_set_gravity(L, m.gravity.data()));
    for (const auto &f : m.body_forces)
        LIB_CALL(aqs_body_set_force(L, f.body, f.force.data(), f.point.data(), f.torque.data()));
    for (const auto &f : m.joint_forces)
        LIB_CALL(aqs_joint_set_force(L, f.joint, f.tau.empty() ? nullptr : f.tau.data(),
                                     (int32_t)f.tau.size()));
    LIB_CALL(aqs_linkage_set_positions(L, m.positions.data(), m.positions.size()));
    LIB_CALL(aqs_linkage_solve(L));
    r.acc.assign((size_t)nv, 0.0);
    r.cf.assign(6 * (size_t)nj, 0.0);
    r.poses.assign(7 * (size_t)nb, 0.0);
    LIB_CALL(aqs_linkage_get_accelerations(L, r.acc.data(), r.acc.size()));
    LIB_CALL(aqs_linkage_get_constraint_forces(L, r.cf.data(), r.cf.size()));
    LIB_CALL(aqs_linkage_get_body_poses_world(L, r.poses.data(), r.poses.size()));
    aqs_linkage_destroy(L);
    return r;
}

// Worst scaled pose error: position error / max(1, |p|), rotation-matrix error (Frobenius).
double pose_err(const std::vector<double> &poses, const std::vector<aqsref::Pose> &ref) {
    double worst = 0;
    for (size_t b = 0; b < ref.size(); ++b) {
        const double *P = poses.data() + 7 * b;
        const aqsref::Vec3 p(P[0], P[1], P[2]);
        const aqsref::Mat3 R = aqsref::quat_to_matrix(P[3], P[4], P[5], P[6]);
        const double qn = std::sqrt(P[3] * P[3] + P[4] * P[4] + P[5] * P[5] + P[6] * P[6]);
        const double ep = (double)((p - ref[b].p).norm() / std::max<Real>(1, ref[b].p.norm()));
        const double eR = (double)(R - ref[b].R).norm();
        const double en = std::fabs(qn - 1);
        const double e = std::max({ep, eR, en});
        if (!(e <= worst)) worst = e;  // NaN-propagating max
    }
    return worst;
}

}  // namespace

int main() {
    const char *root = std::getenv("AQS_VECTORS");
    if (!root || !*root) {
        std::printf("AQS_VECTORS is not set\n0 passed, 1 failed\n");
        return 1;
    }
    const std::string dir = std::string(root) + "/exact";
    std::vector<std::string> files;
    if (DIR *d = opendir(dir.c_str())) {
        while (const dirent *e = readdir(d)) {
            const std::string n = e->d_name;
            if (n.size() > 5 && n.compare(n.size() - 5, 5, ".json") == 0)
                files.push_back(dir + "/" + n);
        }
        closedir(d);
    }
    std::sort(files.begin(), files.end());
    int passed = 0, failed = 0;
    if (files.empty()) {
        std::printf("no vectors found in %s\n", dir.c_str());
        ++failed;
    }
    double worst_ref_acc = 0, worst_ref_cf = 0, worst_lib_acc = 0, worst_lib_cf = 0,
           worst_pose = 0;
    for (const std::string &path : files) {
        const std::string name = path.substr(path.rfind('/') + 1);
        std::string why;
        try {
            const Vector v = load_vector(path);
            // Reference vs expected.
            const aqsref::Solution s = aqsref::solve(v.model);
            std::vector<double> racc((size_t)s.nv), rcf;
            for (int i = 0; i < s.nv; ++i) racc[i] = (double)s.qdd(i);
            for (const auto &f : s.constraint)
                for (int k = 0; k < 6; ++k) rcf.push_back((double)f(k));
            const double ra = rel_err(racc, v.acc), rc = rel_err(rcf, v.cf);
            worst_ref_acc = std::max(worst_ref_acc, ra);
            worst_ref_cf = std::max(worst_ref_cf, rc);
            if (!(ra <= kTolVector && rc <= kTolVector))
                why += " reference disagrees with expected (acc " + std::to_string(ra) +
                       ", cf " + std::to_string(rc) + ")";
            // Library vs expected.
            const LibResult lr = run_library(v.model);
            double la = NAN, lc = NAN, pe = NAN, xa = NAN, xc = NAN;
            if (!lr.error.empty()) {
                why += " library error: " + lr.error;
            } else {
                la = rel_err(lr.acc, v.acc);
                lc = rel_err(lr.cf, v.cf);
                pe = pose_err(lr.poses, s.pose);
                xa = rel_err(lr.acc, racc);  // library vs reference (information only)
                xc = rel_err(lr.cf, rcf);
                worst_lib_acc = std::max(worst_lib_acc, la);
                worst_lib_cf = std::max(worst_lib_cf, lc);
                worst_pose = std::max(worst_pose, pe);
                if (!(la <= kTolVector)) why += " accelerations rel err " + std::to_string(la);
                if (!(lc <= kTolVector)) why += " constraint forces rel err " + std::to_string(lc);
                if (!(pe <= kTolPose)) why += " world poses err " + std::to_string(pe);
            }
            std::printf("%-26s ref: acc %.1e cf %.1e | lib: acc %.1e cf %.1e pose %.1e | "
                        "lib-ref: acc %.1e cf %.1e  %s\n",
                        name.c_str(), ra, rc, la, lc, pe, xa, xc, why.empty() ? "ok" : "FAIL");
        } catch (const std::exception &ex) {
            why += std::string(" exception: ") + ex.what();
            std::printf("%-28s FAIL\n", name.c_str());
        }
        if (why.empty()) {
            ++passed;
        } else {
            ++failed;
            std::printf("  FAILED %s:%s\n", name.c_str(), why.c_str());
        }
    }
    std::printf("worst: reference acc %.2e cf %.2e; library acc %.2e cf %.2e pose %.2e "
                "(tolerance %.0e, poses %.0e)\n",
                worst_ref_acc, worst_ref_cf, worst_lib_acc, worst_lib_cf, worst_pose, kTolVector,
                kTolPose);
    std::printf("%d passed, %d failed\n", passed, failed);
    return failed == 0 ? 0 : 1;
}
