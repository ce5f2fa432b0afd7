// hard_reference.hpp -- O(n) extended-precision reference for the quasi-statics of a tree
// (tests and benchmarks only; issue 12).
//
// Featherstone's articulated-body algorithm at zero velocity, templated on the scalar type:
// long double (x87, 64-bit mantissa, unit roundoff 5.4e-20) and __float128 (libquadmath,
// 113-bit mantissa, unit roundoff 9.6e-35). The model is read back through the public C API
// only (aqs_linkage_get_sizes, aqs_body_get_inertial, aqs_joint_get_definition,
// aqs_linkage_get_positions), never from the library's internals, and the loads (which the
// C API cannot read back) are given by the caller, exactly the doubles it handed to the
// library. So the reference solves the same problem as the library, given as doubles,
// in more precise arithmetic: it is "the truth" for those doubles up to its own rounding,
// which the hardcases program measures by comparing the two scalar types (and
// dense_reference.hpp's dense long-double solve on small cases; closed forms for a
// pendulum).
//
// Written from include/aqs.h's conventions and dense_reference.hpp's kinematics
// (same joint motions, motion subspaces in the child frame, angular part first), not from
// the library's code:
//   load_i  = f_i^ext + I_i [0; R_i^T g]            (body frame, about the body origin)
//   inward:  IA_i = I_i + sum_c X*_c Ia_c X*_c^T, pA_i = -load_i + sum_c X*_c pa_c,
//            U = IA S, D = S^T U, u = tau - S^T pA,
//            Ia = IA - U D^-1 U^T, pa = pA + U D^-1 u
//   outward: a_i = X_down a_parent, qdd = D^-1 (u - U^T a_i), a_i += S qdd
// The joint-space gravity/load torque (inverse dynamics at qdd = 0, for the near-equilibrium
// family): tau0_j = -S_j^T sum_{i in subtree(j)} load_i, so qdd = 0 exactly when tau = tau0.
#ifndef AQS_TESTS_HARD_REFERENCE_HPP
#define AQS_TESTS_HARD_REFERENCE_HPP

#include <aqs.h>

#include <quadmath.h>

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace hardref {

typedef __float128 quad;

template <class T> struct M;
template <> struct M<double> {
    static double sqrt(double x) { return std::sqrt(x); }
    static double sin(double x) { return std::sin(x); }
    static double cos(double x) { return std::cos(x); }
    static double fabs(double x) { return std::fabs(x); }
};
template <> struct M<long double> {
    static long double sqrt(long double x) { return sqrtl(x); }
    static long double sin(long double x) { return sinl(x); }
    static long double cos(long double x) { return cosl(x); }
    static long double fabs(long double x) { return fabsl(x); }
};
template <> struct M<quad> {
    static quad sqrt(quad x) { return sqrtq(x); }
    static quad sin(quad x) { return sinq(x); }
    static quad cos(quad x) { return cosq(x); }
    static quad fabs(quad x) { return fabsq(x); }
};

// ---------------------------------------------------------------------------------------
// The model as read back through the C API (doubles), and the loads (doubles).
// ---------------------------------------------------------------------------------------
struct BodyData {
    double mass;
    double com[3];
    double inertia[9];
};
struct JointData {
    int32_t type, parent, child;
    double pos[3], quat[4], axis[3];
    int32_t q_off, nq, v_off, nv;
};
struct ModelData {
    std::vector<BodyData> bodies;
    std::vector<JointData> joints;
    std::vector<double> q;
    int32_t nq = 0, nv = 0;
};
struct BodyLoad {
    int32_t body;
    double force[3];   // world frame
    double point[3];   // body frame
    double torque[3];  // world frame
};
struct Loads {
    double gravity[3] = {0, 0, 0};
    std::vector<BodyLoad> body;  // at most one per body (aqs_body_set_force replaces)
    std::vector<double> tau;     // nv values, or empty for none
};

inline void check(aqs_status s, const aqs_linkage *l, const char *what) {
    if (s != AQS_OK)
        throw std::runtime_error(std::string(what) + ": " + aqs_linkage_last_error(l));
}

inline ModelData read_model(const aqs_linkage *l) {
    ModelData m;
    int32_t nb = 0, nj = 0;
    check(aqs_linkage_get_sizes(l, &nb, &nj, &m.nq, &m.nv), l, "get_sizes");
    m.bodies.resize(nb);
    for (int32_t b = 0; b < nb; ++b)
        check(aqs_body_get_inertial(l, b, &m.bodies[b].mass, m.bodies[b].com,
                                    m.bodies[b].inertia),
              l, "body_get_inertial");
    m.joints.resize(nj);
    for (int32_t j = 0; j < nj; ++j) {
        JointData &J = m.joints[j];
        check(aqs_joint_get_definition(l, j, &J.type, &J.parent, &J.child, J.pos, J.quat,
                                       J.axis),
              l, "joint_get_definition");
        check(aqs_joint_get_layout(l, j, &J.q_off, &J.nq, &J.v_off, &J.nv), l,
              "joint_get_layout");
    }
    m.q.resize(m.nq);
    if (m.nq > 0) check(aqs_linkage_get_positions(l, m.q.data(), m.q.size()), l, "positions");
    return m;
}

// ---------------------------------------------------------------------------------------
// Small fixed-size algebra in T
// ---------------------------------------------------------------------------------------
template <class T> struct V3 {
    T v[3];
    T &operator[](int i) { return v[i]; }
    const T &operator[](int i) const { return v[i]; }
};
template <class T> struct M3 {
    T a[3][3];
};
template <class T> V3<T> mul(const M3<T> &R, const V3<T> &x) {
    V3<T> y;
    for (int i = 0; i < 3; ++i) y[i] = R.a[i][0] * x[0] + R.a[i][1] * x[1] + R.a[i][2] * x[2];
    return y;
}
template <class T> V3<T> mulT(const M3<T> &R, const V3<T> &x) {
    V3<T> y;
    for (int i = 0; i < 3; ++i) y[i] = R.a[0][i] * x[0] + R.a[1][i] * x[1] + R.a[2][i] * x[2];
    return y;
}
template <class T> M3<T> mul(const M3<T> &A, const M3<T> &B) {
    M3<T> C;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            C.a[i][j] = A.a[i][0] * B.a[0][j] + A.a[i][1] * B.a[1][j] + A.a[i][2] * B.a[2][j];
    return C;
}
template <class T> M3<T> ident() {
    M3<T> I;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) I.a[i][j] = i == j ? T(1) : T(0);
    return I;
}
template <class T> V3<T> cross(const V3<T> &a, const V3<T> &b) {
    V3<T> c;
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
    return c;
}
template <class T> V3<T> v3(const double *x) {
    V3<T> y;
    for (int i = 0; i < 3; ++i) y[i] = T(x[i]);
    return y;
}

template <class T> M3<T> quat_matrix(T w, T x, T y, T z) {
    const T n = M<T>::sqrt(w * w + x * x + y * y + z * z);
    w /= n;
    x /= n;
    y /= n;
    z /= n;
    M3<T> R;
    R.a[0][0] = 1 - 2 * (y * y + z * z);
    R.a[0][1] = 2 * (x * y - w * z);
    R.a[0][2] = 2 * (x * z + w * y);
    R.a[1][0] = 2 * (x * y + w * z);
    R.a[1][1] = 1 - 2 * (x * x + z * z);
    R.a[1][2] = 2 * (y * z - w * x);
    R.a[2][0] = 2 * (x * z - w * y);
    R.a[2][1] = 2 * (y * z + w * x);
    R.a[2][2] = 1 - 2 * (x * x + y * y);
    return R;
}

// Rodrigues: c I + s [a]x + (1 - c) a a^T.
template <class T> M3<T> axis_rotation(const V3<T> &a, T angle) {
    const T c = M<T>::cos(angle), s = M<T>::sin(angle), t = 1 - c;
    M3<T> R;
    R.a[0][0] = c + t * a[0] * a[0];
    R.a[0][1] = t * a[0] * a[1] - s * a[2];
    R.a[0][2] = t * a[0] * a[2] + s * a[1];
    R.a[1][0] = t * a[1] * a[0] + s * a[2];
    R.a[1][1] = c + t * a[1] * a[1];
    R.a[1][2] = t * a[1] * a[2] - s * a[0];
    R.a[2][0] = t * a[2] * a[0] - s * a[1];
    R.a[2][1] = t * a[2] * a[1] + s * a[0];
    R.a[2][2] = c + t * a[2] * a[2];
    return R;
}

template <class T> struct Axes {
    V3<T> a, u, v;
};
// a = unit axis; e = coordinate axis of the smallest |a_i| (first on ties);
// u = normalize(e - (e.a) a); v = a x u  (include/aqs.h, aqs_joint_add).
template <class T> Axes<T> joint_axes(const double *axis) {
    Axes<T> ax;
    V3<T> a = v3<T>(axis);
    const T n = M<T>::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    for (int i = 0; i < 3; ++i) a[i] /= n;
    int e = 0;
    for (int i = 1; i < 3; ++i)
        if (std::fabs(axis[i]) < std::fabs(axis[e])) e = i;
    V3<T> u;
    for (int i = 0; i < 3; ++i) u[i] = (i == e ? T(1) : T(0)) - a[e] * a[i];
    const T un = M<T>::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int i = 0; i < 3; ++i) u[i] /= un;
    ax.a = a;
    ax.u = u;
    ax.v = cross(a, u);
    return ax;
}

// 6-vectors [angular; linear] and 6x6 matrices, row-major.
template <class T> struct V6 {
    T v[6];
};
template <class T> struct M6 {
    T a[6][6];
};

// Per joint: child frame in the parent frame (R, p), and S (6 x nv, child frame).
template <class T> struct JointKin {
    M3<T> R;
    V3<T> p;
    T S[6][6];
    int nv;
};

template <class T> JointKin<T> joint_kin(const JointData &J, const double *q) {
    JointKin<T> k;
    const M3<T> RJ = quat_matrix<T>(T(J.quat[0]), T(J.quat[1]), T(J.quat[2]), T(J.quat[3]));
    M3<T> Rm = ident<T>();
    V3<T> pm = {{T(0), T(0), T(0)}};
    for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 6; ++c) k.S[r][c] = 0;
    k.nv = J.nv;
    switch (J.type) {
    case AQS_JOINT_REVOLUTE: {
        const Axes<T> ax = joint_axes<T>(J.axis);
        Rm = axis_rotation(ax.a, T(q[0]));
        for (int i = 0; i < 3; ++i) k.S[i][0] = ax.a[i];
        break;
    }
    case AQS_JOINT_PRISMATIC: {
        const Axes<T> ax = joint_axes<T>(J.axis);
        for (int i = 0; i < 3; ++i) {
            pm[i] = T(q[0]) * ax.a[i];
            k.S[3 + i][0] = ax.a[i];
        }
        break;
    }
    case AQS_JOINT_SPHERICAL:
        Rm = quat_matrix<T>(T(q[0]), T(q[1]), T(q[2]), T(q[3]));
        for (int i = 0; i < 3; ++i) k.S[i][i] = 1;
        break;
    case AQS_JOINT_FREE:
        Rm = quat_matrix<T>(T(q[3]), T(q[4]), T(q[5]), T(q[6]));
        pm = v3<T>(q);
        for (int i = 0; i < 6; ++i) k.S[i][i] = 1;
        break;
    case AQS_JOINT_FIXED:
        break;
    case AQS_JOINT_UNIVERSAL: {
        const Axes<T> ax = joint_axes<T>(J.axis);
        const M3<T> R2 = axis_rotation(ax.u, T(q[1]));
        Rm = mul(axis_rotation(ax.a, T(q[0])), R2);
        const V3<T> s0 = mulT(R2, ax.a);
        for (int i = 0; i < 3; ++i) {
            k.S[i][0] = s0[i];
            k.S[i][1] = ax.u[i];
        }
        break;
    }
    case AQS_JOINT_CYLINDRICAL: {
        const Axes<T> ax = joint_axes<T>(J.axis);
        Rm = axis_rotation(ax.a, T(q[0]));
        for (int i = 0; i < 3; ++i) {
            pm[i] = T(q[1]) * ax.a[i];
            k.S[i][0] = ax.a[i];
            k.S[3 + i][1] = ax.a[i];
        }
        break;
    }
    case AQS_JOINT_PLANAR: {
        const Axes<T> ax = joint_axes<T>(J.axis);
        Rm = axis_rotation(ax.a, T(q[2]));
        const V3<T> su = mulT(Rm, ax.u), sv = mulT(Rm, ax.v);
        for (int i = 0; i < 3; ++i) {
            pm[i] = T(q[0]) * ax.u[i] + T(q[1]) * ax.v[i];
            k.S[3 + i][0] = su[i];
            k.S[3 + i][1] = sv[i];
            k.S[i][2] = ax.a[i];
        }
        break;
    }
    default:
        throw std::invalid_argument("hardref: bad joint type");
    }
    k.R = mul(RJ, Rm);
    const V3<T> rp = mul(RJ, pm);
    for (int i = 0; i < 3; ++i) k.p[i] = T(J.pos[i]) + rp[i];
    return k;
}

// Force from the child frame to the parent frame: f_p = X* f_c with
// X* = [R, [p]x R; 0, R]: n_p = R n + p x (R f), f_p = R f.
template <class T> V6<T> force_up(const JointKin<T> &k, const V6<T> &f) {
    V6<T> o;
    const V3<T> n = mul(k.R, V3<T>{{f.v[0], f.v[1], f.v[2]}});
    const V3<T> F = mul(k.R, V3<T>{{f.v[3], f.v[4], f.v[5]}});
    const V3<T> pf = cross(k.p, F);
    for (int i = 0; i < 3; ++i) {
        o.v[i] = n[i] + pf[i];
        o.v[3 + i] = F[i];
    }
    return o;
}
// Motion from the parent frame to the child frame: w_c = R^T w, v_c = R^T (v - p x w).
template <class T> V6<T> motion_down(const JointKin<T> &k, const V6<T> &m) {
    V6<T> o;
    const V3<T> w = {{m.v[0], m.v[1], m.v[2]}};
    const V3<T> pw = cross(k.p, w);
    const V3<T> v = {{m.v[3] - pw[0], m.v[4] - pw[1], m.v[5] - pw[2]}};
    const V3<T> wc = mulT(k.R, w), vc = mulT(k.R, v);
    for (int i = 0; i < 3; ++i) {
        o.v[i] = wc[i];
        o.v[3 + i] = vc[i];
    }
    return o;
}
// X* A X*^T for a symmetric 6x6 A in the child frame: the columns are forces.
template <class T> M6<T> inertia_up(const JointKin<T> &k, const M6<T> &A) {
    M6<T> B, C;
    for (int c = 0; c < 6; ++c) {  // B = X* A (column by column)
        V6<T> col;
        for (int r = 0; r < 6; ++r) col.v[r] = A.a[r][c];
        const V6<T> o = force_up(k, col);
        for (int r = 0; r < 6; ++r) B.a[r][c] = o.v[r];
    }
    for (int r = 0; r < 6; ++r) {  // C = B X*^T = (X* B^T)^T
        V6<T> row;
        for (int c = 0; c < 6; ++c) row.v[c] = B.a[r][c];
        const V6<T> o = force_up(k, row);
        for (int c = 0; c < 6; ++c) C.a[r][c] = o.v[c];
    }
    return C;
}

// Spatial inertia about the body origin in body axes (MATH.md 1.3).
template <class T> M6<T> body_inertia(const BodyData &b) {
    M6<T> I;
    const T m = T(b.mass);
    const V3<T> c = v3<T>(b.com);
    T C[3][3] = {{0, -c[2], c[1]}, {c[2], 0, -c[0]}, {-c[1], c[0], 0}};
    for (int r = 0; r < 3; ++r)
        for (int s = 0; s < 3; ++s) {
            T ccT = 0;  // (C C^T)_rs
            for (int t = 0; t < 3; ++t) ccT += C[r][t] * C[s][t];
            I.a[r][s] = T(b.inertia[3 * r + s]) + m * ccT;
            I.a[r][3 + s] = m * C[r][s];
            I.a[3 + r][s] = m * C[s][r];
            I.a[3 + r][3 + s] = r == s ? m : T(0);
        }
    return I;
}

// Solve D x = b for a small symmetric positive definite D (n <= 6) by Gaussian elimination
// with partial pivoting; returns false when a pivot is zero.
template <class T> bool small_solve(int n, T D[6][6], T *x) {
    T A[6][7];
    for (int r = 0; r < n; ++r) {
        for (int c = 0; c < n; ++c) A[r][c] = D[r][c];
        A[r][n] = x[r];
    }
    for (int c = 0; c < n; ++c) {
        int p = c;
        for (int r = c + 1; r < n; ++r)
            if (M<T>::fabs(A[r][c]) > M<T>::fabs(A[p][c])) p = r;
        if (A[p][c] == T(0)) return false;
        if (p != c)
            for (int k = 0; k <= n; ++k) std::swap(A[p][k], A[c][k]);
        for (int r = c + 1; r < n; ++r) {
            const T f = A[r][c] / A[c][c];
            for (int k = c; k <= n; ++k) A[r][k] -= f * A[c][k];
        }
    }
    for (int r = n - 1; r >= 0; --r) {
        T s = A[r][n];
        for (int k = r + 1; k < n; ++k) s -= A[r][k] * x[k];
        x[r] = s / A[r][r];
    }
    return true;
}

// Order of the joints, parents before children (breadth-first from the world), and each
// body's world rotation (for the world-frame loads and gravity).
struct Order {
    std::vector<int32_t> order;
    std::vector<int32_t> joint_of_body;
};
inline Order make_order(const ModelData &m) {
    Order o;
    const int32_t nb = (int32_t)m.bodies.size(), nj = (int32_t)m.joints.size();
    o.joint_of_body.assign(nb, -1);
    std::vector<std::vector<int32_t>> kids(nb + 1);
    for (int32_t j = 0; j < nj; ++j) {
        o.joint_of_body[m.joints[j].child] = j;
        kids[m.joints[j].parent + 1].push_back(j);
    }
    o.order = kids[0];
    for (size_t h = 0; h < o.order.size(); ++h)
        for (int32_t k : kids[m.joints[o.order[h]].child + 1]) o.order.push_back(k);
    if ((int32_t)o.order.size() != nj) throw std::invalid_argument("hardref: not a tree");
    return o;
}

template <class T> struct Result {
    std::vector<T> qdd;   // nv
    std::vector<T> tau0;  // the generalized force that makes qdd = 0 (if asked)
    // Per joint, the spatial force it exerts on its child, in the child's body frame about its
    // origin, torque first (aqs_linkage_get_constraint_forces' convention): Newton-Euler on the
    // child's subtree, f_j = sum over the subtree of (I_i a_i - load_i), from the solve's own
    // accelerations in T.
    std::vector<V6<T>> force;
};

// The solve. With want_tau0, also tau0_j = -S_j^T sum_{subtree} load (qdd = 0 for tau = tau0).
template <class T>
Result<T> solve(const ModelData &m, const Loads &L, bool want_tau0 = false) {
    const int32_t nb = (int32_t)m.bodies.size(), nj = (int32_t)m.joints.size();
    const Order ord = make_order(m);
    std::vector<JointKin<T>> kin(nj);
    for (int32_t j = 0; j < nj; ++j) kin[j] = joint_kin<T>(m.joints[j], m.q.data() + m.joints[j].q_off);
    // World rotation of every body.
    std::vector<M3<T>> Rw(nb);
    for (int32_t j : ord.order) {
        const JointData &J = m.joints[j];
        Rw[J.child] = J.parent >= 0 ? mul(Rw[J.parent], kin[j].R) : kin[j].R;
    }
    std::vector<M6<T>> IA(nb);
    std::vector<V6<T>> pA(nb);  // bias force = -load
    const V3<T> g = v3<T>(L.gravity);
    for (int32_t b = 0; b < nb; ++b) {
        IA[b] = body_inertia<T>(m.bodies[b]);
        const V3<T> gb = mulT(Rw[b], g);
        for (int r = 0; r < 6; ++r) {
            T s = 0;
            for (int c = 0; c < 3; ++c) s += IA[b].a[r][3 + c] * gb[c];
            pA[b].v[r] = -s;
        }
    }
    for (const BodyLoad &f : L.body) {
        const V3<T> F = mulT(Rw[f.body], v3<T>(f.force));
        const V3<T> n = cross(v3<T>(f.point), F);
        const V3<T> tq = mulT(Rw[f.body], v3<T>(f.torque));
        for (int i = 0; i < 3; ++i) {
            pA[f.body].v[i] -= n[i] + tq[i];
            pA[f.body].v[3 + i] -= F[i];
        }
    }
    // The bodies' own inertias and loads (-pA), kept for the constraint forces: the inward pass
    // below accumulates the subtrees into IA and pA.
    const std::vector<M6<T>> I0 = IA;
    const std::vector<V6<T>> p0 = pA;
    Result<T> res;
    res.qdd.assign(m.nv, T(0));
    if (want_tau0) {
        // Subtree sums of the loads (-pA), in each subtree root's frame.
        std::vector<V6<T>> Lc(nb);
        for (int32_t b = 0; b < nb; ++b)
            for (int r = 0; r < 6; ++r) Lc[b].v[r] = -pA[b].v[r];
        for (int32_t k = nj - 1; k >= 0; --k) {
            const int32_t j = ord.order[k];
            const JointData &J = m.joints[j];
            if (J.parent < 0) continue;
            const V6<T> up = force_up(kin[j], Lc[J.child]);
            for (int r = 0; r < 6; ++r) Lc[J.parent].v[r] += up.v[r];
        }
        res.tau0.assign(m.nv, T(0));
        for (int32_t j = 0; j < nj; ++j) {
            const JointData &J = m.joints[j];
            for (int c = 0; c < J.nv; ++c) {
                T s = 0;
                for (int r = 0; r < 6; ++r) s += kin[j].S[r][c] * Lc[J.child].v[r];
                res.tau0[J.v_off + c] = -s;
            }
        }
    }
    // Inward pass.
    std::vector<T> U(6 * 6 * (size_t)nj), u(6 * (size_t)nj);
    std::vector<std::array<std::array<T, 6>, 6>> Dm(nj);
    for (int32_t k = nj - 1; k >= 0; --k) {
        const int32_t j = ord.order[k];
        const JointData &J = m.joints[j];
        const JointKin<T> &K = kin[j];
        const int32_t b = J.child, n = K.nv;
        M6<T> Ia = IA[b];
        V6<T> pa = pA[b];
        if (n > 0) {
            T *Uj = &U[36 * (size_t)j];  // U = IA S, 6 x n, column-major per joint
            for (int c = 0; c < n; ++c)
                for (int r = 0; r < 6; ++r) {
                    T s = 0;
                    for (int t = 0; t < 6; ++t) s += IA[b].a[r][t] * K.S[t][c];
                    Uj[6 * c + r] = s;
                }
            T D[6][6];
            for (int r = 0; r < n; ++r)
                for (int c = 0; c < n; ++c) {
                    T s = 0;
                    for (int t = 0; t < 6; ++t) s += K.S[t][r] * Uj[6 * c + t];
                    D[r][c] = s;
                }
            for (int r = 0; r < n; ++r)
                for (int c = 0; c < n; ++c) Dm[j][r][c] = D[r][c];
            T uj[6];
            for (int c = 0; c < n; ++c) {
                T s = L.tau.empty() ? T(0) : T(L.tau[J.v_off + c]);
                for (int t = 0; t < 6; ++t) s -= K.S[t][c] * pA[b].v[t];
                uj[c] = s;
                u[6 * (size_t)j + c] = s;
            }
            if (J.parent >= 0) {
                // W = D^-1 U^T (n x 6), column by column; Ia -= U W; pa += U D^-1 u.
                T W[6][6];
                for (int r = 0; r < 6; ++r) {
                    T x[6], Dc[6][6];
                    for (int c = 0; c < n; ++c) x[c] = Uj[6 * c + r];
                    for (int a = 0; a < n; ++a)
                        for (int c = 0; c < n; ++c) Dc[a][c] = D[a][c];
                    if (!small_solve<T>(n, Dc, x))
                        throw std::runtime_error("hardref: singular D at joint " + std::to_string(j));
                    for (int c = 0; c < n; ++c) W[c][r] = x[c];
                }
                T x[6], Dc[6][6];
                for (int c = 0; c < n; ++c) x[c] = uj[c];
                for (int a = 0; a < n; ++a)
                    for (int c = 0; c < n; ++c) Dc[a][c] = D[a][c];
                small_solve<T>(n, Dc, x);
                for (int r = 0; r < 6; ++r) {
                    for (int c = 0; c < 6; ++c) {
                        T s = 0;
                        for (int t = 0; t < n; ++t) s += Uj[6 * t + r] * W[t][c];
                        Ia.a[r][c] -= s;
                    }
                    T s = 0;
                    for (int t = 0; t < n; ++t) s += Uj[6 * t + r] * x[t];
                    pa.v[r] += s;
                }
            }
        }
        if (J.parent >= 0) {
            // Exact symmetry before carrying up.
            for (int r = 0; r < 6; ++r)
                for (int c = r + 1; c < 6; ++c) Ia.a[r][c] = Ia.a[c][r] = (Ia.a[r][c] + Ia.a[c][r]) / 2;
            const M6<T> up = inertia_up(K, Ia);
            const V6<T> fp = force_up(K, pa);
            for (int r = 0; r < 6; ++r) {
                for (int c = 0; c < 6; ++c) IA[J.parent].a[r][c] += up.a[r][c];
                pA[J.parent].v[r] += fp.v[r];
            }
        }
    }
    // Outward pass.
    std::vector<V6<T>> acc(nb);
    for (int32_t j : ord.order) {
        const JointData &J = m.joints[j];
        const JointKin<T> &K = kin[j];
        V6<T> a;
        if (J.parent >= 0)
            a = motion_down(K, acc[J.parent]);
        else
            for (int r = 0; r < 6; ++r) a.v[r] = 0;
        const int n = K.nv;
        if (n > 0) {
            const T *Uj = &U[36 * (size_t)j];
            T x[6], D[6][6];
            for (int c = 0; c < n; ++c) {
                T s = u[6 * (size_t)j + c];
                for (int t = 0; t < 6; ++t) s -= Uj[6 * c + t] * a.v[t];
                x[c] = s;
            }
            for (int r = 0; r < n; ++r)
                for (int c = 0; c < n; ++c) D[r][c] = Dm[j][r][c];
            if (!small_solve<T>(n, D, x))
                throw std::runtime_error("hardref: singular D at joint " + std::to_string(j));
            for (int c = 0; c < n; ++c) {
                res.qdd[J.v_off + c] = x[c];
                for (int r = 0; r < 6; ++r) a.v[r] += K.S[r][c] * x[c];
            }
        }
        acc[J.child] = a;
    }
    // Constraint forces: net[b] = I_b a_b - load_b, the children's subtree sums carried up.
    std::vector<V6<T>> net(nb);
    for (int32_t b = 0; b < nb; ++b)
        for (int r = 0; r < 6; ++r) {
            T s = p0[b].v[r];
            for (int c = 0; c < 6; ++c) s += I0[b].a[r][c] * acc[b].v[c];
            net[b].v[r] = s;
        }
    for (int32_t k = nj - 1; k >= 0; --k) {
        const JointData &J = m.joints[ord.order[k]];
        if (J.parent < 0) continue;
        const V6<T> up = force_up(kin[ord.order[k]], net[J.child]);
        for (int r = 0; r < 6; ++r) net[J.parent].v[r] += up.v[r];
    }
    res.force.resize(nj);
    for (int32_t j = 0; j < nj; ++j) res.force[j] = net[m.joints[j].child];
    return res;
}

template <class T> std::vector<double> to_double(const std::vector<T> &x) {
    std::vector<double> y(x.size());
    for (size_t i = 0; i < x.size(); ++i) y[i] = (double)x[i];
    return y;
}

}  // namespace hardref

#endif  // AQS_TESTS_HARD_REFERENCE_HPP
