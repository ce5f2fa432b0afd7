// dense_reference.hpp -- independent dense reference solver for the quasi-statics of
// articulated linkages (tests only).
//
// Written from MATH.md section 2 and the kinematic conventions of include/aqs.h, NOT from the
// library's code. All arithmetic is long double (x87 extended precision, unit roundoff
// ~5.4e-20, against 1.1e-16 for double), so the reference is 2-3 orders of magnitude more
// accurate than any double-precision solver it judges.
//
//   M   = sum_i J_i^T I_i J_i                       (joint-space inertia)
//   tau = Q + sum_i J_i^T (f_i^ext + I_i g)         (generalized forces, gravity g = [0; g])
//   qdd = M^{-1} tau                                (LDL^T with pivoting, Eigen, plus one
//                                                    step of iterative refinement)
//   f_j = sum_{i in subtree(j)} (I_i a_i - f_i^ext - I_i g)   (Newton-Euler on subtrees)
//
// with J_i = [S_j for j in path(i)] and a_i = J_i qdd. f_j, the spatial force joint j exerts
// on its child, is reported in the child body frame about the child origin, torque first.
//
// solve() evaluates these sums in body frames: the sums over bodies are regrouped through
// subtree ("composite") quantities carried from frame to frame up the tree, which is the same
// sum, not a different method:
//   M_jk  = S_j^T (sum_{i in subtree(j) ∩ subtree(k)} I_i) S_k
//         = S_j^T Ic_k S_k   when j is k or an ancestor of k (0 when neither is);
//   tau_j = Q_j + S_j^T sum_{i in subtree(j)} (f_i^ext + I_i g);
//   f_j   = sum over subtree(j), accumulated leaves first.
// Body frames keep every moment arm short, so no accuracy is lost when the linkage lies far
// from the world origin (MATH.md 3.6). assemble_literal() forms M and tau from the literal
// sums over bodies in world coordinates (O(N depth^2)); the tests compare the two on small
// models. world_poses() is the forward kinematics (world pose of every body).
//
// Joint kinematics (child frame = joint frame moved by the joint position; a = unit axis;
// e = coordinate axis of the smallest |a_i|, first on ties; u = normalize(e - (e.a) a);
// v = a x u). Child pose relative to the joint frame (R, p) and the motion subspace S in the
// child frame (angular rows first):
//   revolute    R = Rot(a,q)                    p = 0             S = [a; 0]
//   prismatic   R = I                           p = q a           S = [0; a]
//   spherical   R = quat(q)                     p = 0             S = [I3; 0]
//   free        R = quat(q3..6)                 p = q0..2         S = I6
//   fixed       R = I                           p = 0             S = (6x0)
//   universal   R = Rot(a,q1) Rot(u,q2)         p = 0             S = [[Rot(u,q2)^T a, u]; 0]
//   cylindrical R = Rot(a,q1)                   p = q2 a          S = [[a, 0]; [0, a]]
//   planar      R = Rot(a,q3)                   p = q1 u + q2 v   S = [[0, 0, a]; [R^T u, R^T v, 0]]
// (universal: omega = a qd1 + Rot(a,q1) u qd2 in the joint frame, so R^T omega =
//  Rot(u,q2)^T a qd1 + u qd2 in the child frame; planar: the child origin moves with
//  u qd1 + v qd2 in the joint frame, i.e. R^T (u qd1 + v qd2) in the child frame.)
#ifndef AQS_TESTS_DENSE_REFERENCE_HPP
#define AQS_TESTS_DENSE_REFERENCE_HPP

#include <Eigen/Dense>

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace aqsref {

using Real = long double;
using Vec3 = Eigen::Matrix<Real, 3, 1>;
using Mat3 = Eigen::Matrix<Real, 3, 3>;
using Vec6 = Eigen::Matrix<Real, 6, 1>;
using Mat6 = Eigen::Matrix<Real, 6, 6>;
using MatX = Eigen::Matrix<Real, Eigen::Dynamic, Eigen::Dynamic>;
using VecX = Eigen::Matrix<Real, Eigen::Dynamic, 1>;
// Per-joint quantities have at most 6 columns: fixed-capacity types, no heap.
using Mat6X = Eigen::Matrix<Real, 6, Eigen::Dynamic, 0, 6, 6>;
using MatD = Eigen::Matrix<Real, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;
using VecD = Eigen::Matrix<Real, Eigen::Dynamic, 1, 0, 6, 1>;

enum JointType {
    REVOLUTE = 0,
    PRISMATIC = 1,
    SPHERICAL = 2,
    FREE = 3,
    FIXED = 4,
    UNIVERSAL = 5,
    CYLINDRICAL = 6,
    PLANAR = 7
};

inline int joint_nq(int type) {
    static const int nq[8] = {1, 1, 4, 7, 0, 2, 2, 3};
    if (type < 0 || type > 7) throw std::invalid_argument("bad joint type");
    return nq[type];
}

inline int joint_nv(int type) {
    static const int nv[8] = {1, 1, 3, 6, 0, 2, 2, 3};
    if (type < 0 || type > 7) throw std::invalid_argument("bad joint type");
    return nv[type];
}

inline const char *joint_type_name(int type) {
    static const char *names[8] = {"revolute", "prismatic", "spherical", "free",
                                   "fixed",    "universal", "cylindrical", "planar"};
    return (type >= 0 && type <= 7) ? names[type] : "?";
}

// ---------------------------------------------------------------------------------------
// Model description (plain doubles, exactly what is handed to the C API)
// ---------------------------------------------------------------------------------------

struct Body {
    double mass = 1.0;
    std::array<double, 3> com{};      // body frame
    std::array<double, 9> inertia{};  // about the com, body frame, row-major
};

struct Joint {
    int type = REVOLUTE;
    int parent = -1;                  // body index, -1 = world
    int child = 0;
    std::array<double, 3> pos{};      // joint frame origin in the parent frame
    std::array<double, 4> quat{{1, 0, 0, 0}};  // joint frame orientation (w x y z)
    std::array<double, 3> axis{{0, 0, 1}};     // joint frame
};

struct BodyForce {
    int body = 0;
    std::array<double, 3> force{};   // world frame
    std::array<double, 3> point{};   // body frame
    std::array<double, 3> torque{};  // world frame
};

struct JointForce {
    int joint = 0;
    std::vector<double> tau;  // nv values
};

struct Model {
    std::vector<Body> bodies;
    std::vector<Joint> joints;
    std::vector<double> positions;  // all joints, joint order
    std::array<double, 3> gravity{};
    std::vector<BodyForce> body_forces;    // several on one body add up
    std::vector<JointForce> joint_forces;  // several on one joint add up
};

struct Pose {
    Mat3 R = Mat3::Identity();  // body axes in world coordinates
    Vec3 p = Vec3::Zero();      // body origin in world coordinates
};

struct Solution {
    int nq = 0, nv = 0;
    std::vector<int> q_offset, v_offset;             // per joint
    std::vector<Pose> pose;                          // per body, world
    VecX qdd;                                        // nv
    std::vector<Vec6> constraint;                    // per joint: child frame, about its origin
    std::vector<Vec6> body_acc;                      // per body, body frame: [dw; dv of origin]
    MatX M;                                          // nv x nv
    VecX tau;                                        // nv
    Real residual = 0;                               // ||M qdd - tau|| / ||tau||
    // Size of the applied loads: sqrt(sum_i ||f_i^ext + I_i g||^2 + ||Q||^2), each body's
    // load in its own frame about its origin. A scale for force errors when every constraint
    // force is (nearly) zero, e.g. a free-floating body.
    Real load_scale = 0;
};

// ---------------------------------------------------------------------------------------
// Small kinematics helpers
// ---------------------------------------------------------------------------------------

inline Mat3 skew(const Vec3 &p) {
    Mat3 s;
    s << 0, -p(2), p(1), p(2), 0, -p(0), -p(1), p(0), 0;
    return s;
}

inline Vec3 to_vec3(const double *x) { return Vec3((Real)x[0], (Real)x[1], (Real)x[2]); }
inline Vec3 to_vec3(const std::array<double, 3> &x) { return to_vec3(x.data()); }

// Rotation matrix of a quaternion (w, x, y, z); normalized here.
inline Mat3 quat_to_matrix(Real w, Real x, Real y, Real z) {
    const Real n = std::sqrt(w * w + x * x + y * y + z * z);
    if (!(n > 0)) throw std::invalid_argument("zero quaternion");
    w /= n;
    x /= n;
    y /= n;
    z /= n;
    Mat3 R;
    R << 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
        2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
        2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y);
    return R;
}

// Rotation by angle about the unit vector a (Rodrigues).
inline Mat3 axis_rotation(const Vec3 &a, Real angle) {
    const Real c = std::cos(angle), s = std::sin(angle);
    return c * Mat3::Identity() + s * skew(a) + (1 - c) * (a * a.transpose());
}

// Unit axis and completing directions u, v of a joint (see the file comment).
struct JointAxes {
    Vec3 a, u, v;
};

inline JointAxes joint_axes(const Joint &j) {
    JointAxes ax;
    const Vec3 raw = to_vec3(j.axis);
    const Real n = raw.norm();
    if (!(n > 0)) throw std::invalid_argument("zero joint axis");
    ax.a = raw / n;
    // Smallest |component| of the axis as given (normalization cannot change the order
    // except by rounding; the first index wins ties).
    int e = 0;
    for (int i = 1; i < 3; ++i)
        if (std::fabs(j.axis[i]) < std::fabs(j.axis[e])) e = i;
    Vec3 ev = Vec3::Zero();
    ev(e) = 1;
    Vec3 u = ev - ev.dot(ax.a) * ax.a;
    ax.u = u / u.norm();
    ax.v = ax.a.cross(ax.u);
    return ax;
}

// Child pose relative to the joint frame for joint positions q (joint_nq values).
inline Pose joint_motion(const Joint &j, const double *q) {
    Pose m;
    switch (j.type) {
    case REVOLUTE: {
        const JointAxes ax = joint_axes(j);
        m.R = axis_rotation(ax.a, (Real)q[0]);
        break;
    }
    case PRISMATIC: {
        const JointAxes ax = joint_axes(j);
        m.p = (Real)q[0] * ax.a;
        break;
    }
    case SPHERICAL:
        m.R = quat_to_matrix(q[0], q[1], q[2], q[3]);
        break;
    case FREE:
        m.p = to_vec3(q);
        m.R = quat_to_matrix(q[3], q[4], q[5], q[6]);
        break;
    case FIXED:
        break;
    case UNIVERSAL: {
        const JointAxes ax = joint_axes(j);
        m.R = axis_rotation(ax.a, (Real)q[0]) * axis_rotation(ax.u, (Real)q[1]);
        break;
    }
    case CYLINDRICAL: {
        const JointAxes ax = joint_axes(j);
        m.R = axis_rotation(ax.a, (Real)q[0]);
        m.p = (Real)q[1] * ax.a;
        break;
    }
    case PLANAR: {
        const JointAxes ax = joint_axes(j);
        m.R = axis_rotation(ax.a, (Real)q[2]);
        m.p = (Real)q[0] * ax.u + (Real)q[1] * ax.v;
        break;
    }
    default:
        throw std::invalid_argument("bad joint type");
    }
    return m;
}

// Motion subspace (6 x nv) in the child body frame, angular rows first.
inline Mat6X motion_subspace_child(const Joint &j, const double *q) {
    const int nv = joint_nv(j.type);
    Mat6X S = Mat6X::Zero(6, nv);
    switch (j.type) {
    case REVOLUTE:
        S.block<3, 1>(0, 0) = joint_axes(j).a;
        break;
    case PRISMATIC:
        S.block<3, 1>(3, 0) = joint_axes(j).a;
        break;
    case SPHERICAL:
        S.block<3, 3>(0, 0).setIdentity();
        break;
    case FREE:
        S.setIdentity();
        break;
    case FIXED:
        break;
    case UNIVERSAL: {
        const JointAxes ax = joint_axes(j);
        const Mat3 R2 = axis_rotation(ax.u, (Real)q[1]);
        S.block<3, 1>(0, 0) = R2.transpose() * ax.a;
        S.block<3, 1>(0, 1) = ax.u;
        break;
    }
    case CYLINDRICAL: {
        const JointAxes ax = joint_axes(j);
        S.block<3, 1>(0, 0) = ax.a;
        S.block<3, 1>(3, 1) = ax.a;
        break;
    }
    case PLANAR: {
        const JointAxes ax = joint_axes(j);
        const Mat3 R = axis_rotation(ax.a, (Real)q[2]);
        S.block<3, 1>(3, 0) = R.transpose() * ax.u;
        S.block<3, 1>(3, 1) = R.transpose() * ax.v;
        S.block<3, 1>(0, 2) = ax.a;
        break;
    }
    default:
        throw std::invalid_argument("bad joint type");
    }
    return S;
}

// Motion transform from a frame with pose (R, p) in a frame G to G: [R 0; skew(p)R R].
inline Mat6 motion_to_world(const Pose &P) {
    Mat6 X = Mat6::Zero();
    X.block<3, 3>(0, 0) = P.R;
    X.block<3, 3>(3, 0) = skew(P.p) * P.R;
    X.block<3, 3>(3, 3) = P.R;
    return X;
}

// Spatial inertia (MATH.md 1.3) of a body whose frame has pose P in some frame G, about G's
// origin in G's axes (P = identity: about the body origin in body axes).
inline Mat6 spatial_inertia(const Body &b, const Pose &P) {
    Mat3 Ic;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) Ic(r, c) = (Real)b.inertia[3 * r + c];
    const Real m = b.mass;
    const Vec3 c = P.p + P.R * to_vec3(b.com);
    const Mat3 Icw = P.R * Ic * P.R.transpose();
    const Mat3 C = skew(c);
    Mat6 I;
    I.block<3, 3>(0, 0) = Icw + m * C * C.transpose();
    I.block<3, 3>(0, 3) = m * C;
    I.block<3, 3>(3, 0) = m * C.transpose();
    I.block<3, 3>(3, 3) = m * Mat3::Identity();
    return I;
}

// ---------------------------------------------------------------------------------------
// Topology: parent joint of each body, processing order (parents before children).
// ---------------------------------------------------------------------------------------

struct Topology {
    std::vector<int> joint_of_body;   // joint whose child is the body
    std::vector<int> order;           // joints, parents before children
    std::vector<int> q_offset, v_offset;
    int nq = 0, nv = 0;
};

inline Topology make_topology(const Model &m) {
    const int nb = (int)m.bodies.size(), nj = (int)m.joints.size();
    Topology t;
    t.joint_of_body.assign(nb, -1);
    for (int j = 0; j < nj; ++j) {
        const Joint &jt = m.joints[j];
        if (jt.child < 0 || jt.child >= nb || jt.parent < -1 || jt.parent >= nb)
            throw std::invalid_argument("joint " + std::to_string(j) + ": bad body index");
        if (t.joint_of_body[jt.child] != -1)
            throw std::invalid_argument("body " + std::to_string(jt.child) + " has two parents");
        if (jt.type == FREE && jt.parent != -1)
            throw std::invalid_argument("free joint not from the world");
        t.joint_of_body[jt.child] = j;
    }
    for (int b = 0; b < nb; ++b)
        if (t.joint_of_body[b] == -1)
            throw std::invalid_argument("body " + std::to_string(b) + " has no parent joint");
    // Breadth-first from the world.
    std::vector<std::vector<int>> kids(nb + 1);  // index parent+1
    for (int j = 0; j < nj; ++j) kids[m.joints[j].parent + 1].push_back(j);
    t.order = kids[0];
    for (size_t head = 0; head < t.order.size(); ++head) {
        const int j = t.order[head];
        for (int k : kids[m.joints[j].child + 1]) t.order.push_back(k);
    }
    if ((int)t.order.size() != nj) throw std::invalid_argument("linkage not connected to world");
    t.q_offset.resize(nj);
    t.v_offset.resize(nj);
    for (int j = 0; j < nj; ++j) {
        t.q_offset[j] = t.nq;
        t.v_offset[j] = t.nv;
        t.nq += joint_nq(m.joints[j].type);
        t.nv += joint_nv(m.joints[j].type);
    }
    if ((int)m.positions.size() != t.nq) throw std::invalid_argument("positions size != nq");
    return t;
}

// World poses of all bodies (forward kinematics).
inline std::vector<Pose> world_poses(const Model &m, const Topology &t) {
    std::vector<Pose> pose(m.bodies.size());
    for (int j : t.order) {
        const Joint &jt = m.joints[j];
        Pose parent;
        if (jt.parent >= 0) parent = pose[jt.parent];
        const Mat3 RJ = quat_to_matrix(jt.quat[0], jt.quat[1], jt.quat[2], jt.quat[3]);
        const Pose mo = joint_motion(jt, m.positions.data() + t.q_offset[j]);
        Pose &c = pose[jt.child];
        c.R = parent.R * RJ * mo.R;
        c.p = parent.p + parent.R * (to_vec3(jt.pos) + RJ * mo.p);
    }
    return pose;
}

inline std::vector<Pose> world_poses(const Model &m) { return world_poses(m, make_topology(m)); }

// External spatial force on every body, world frame, about the world origin (without gravity).
inline std::vector<Vec6> external_forces_world(const Model &m, const std::vector<Pose> &pose) {
    std::vector<Vec6> f(m.bodies.size(), Vec6::Zero());
    for (const BodyForce &bf : m.body_forces) {
        if (bf.body < 0 || bf.body >= (int)m.bodies.size())
            throw std::invalid_argument("body force on a bad body");
        const Pose &P = pose[bf.body];
        const Vec3 F = to_vec3(bf.force);
        const Vec3 r = P.p + P.R * to_vec3(bf.point);
        f[bf.body].head<3>() += r.cross(F) + to_vec3(bf.torque);
        f[bf.body].tail<3>() += F;
    }
    return f;
}

inline VecX joint_forces_vector(const Model &m, const Topology &t) {
    VecX Q = VecX::Zero(t.nv);
    for (const JointForce &jf : m.joint_forces) {
        if (jf.joint < 0 || jf.joint >= (int)m.joints.size())
            throw std::invalid_argument("joint force on a bad joint");
        const int nv = joint_nv(m.joints[jf.joint].type);
        if ((int)jf.tau.size() != nv) throw std::invalid_argument("joint force size != nv");
        for (int k = 0; k < nv; ++k) Q(t.v_offset[jf.joint] + k) += (Real)jf.tau[k];
    }
    return Q;
}

// ---------------------------------------------------------------------------------------
// The solver
// ---------------------------------------------------------------------------------------

inline Solution solve(const Model &m) {
    const Topology t = make_topology(m);
    const int nb = (int)m.bodies.size(), nj = (int)m.joints.size();
    Solution s;
    s.nq = t.nq;
    s.nv = t.nv;
    s.q_offset = t.q_offset;
    s.v_offset = t.v_offset;
    s.pose = world_poses(m, t);

    // Per joint: motion transform child frame -> parent frame, motion subspace (child frame).
    std::vector<Mat6> Xup(nj);     // motion, child -> parent
    std::vector<Mat6> Xfup(nj);    // force, child -> parent (= Xup^{-T})
    std::vector<Mat6> Xdown(nj);   // motion, parent -> child (= Xup^{-1})
    std::vector<Mat6X> S(nj);
    for (int j = 0; j < nj; ++j) {
        const Joint &jt = m.joints[j];
        const double *q = m.positions.data() + t.q_offset[j];
        const Mat3 RJ = quat_to_matrix(jt.quat[0], jt.quat[1], jt.quat[2], jt.quat[3]);
        const Pose mo = joint_motion(jt, q);
        Pose rel;  // child frame in the parent frame
        rel.R = RJ * mo.R;
        rel.p = to_vec3(jt.pos) + RJ * mo.p;
        Xup[j] = motion_to_world(rel);
        Xfup[j] = Mat6::Zero();
        Xfup[j].block<3, 3>(0, 0) = rel.R;
        Xfup[j].block<3, 3>(0, 3) = skew(rel.p) * rel.R;
        Xfup[j].block<3, 3>(3, 3) = rel.R;
        Xdown[j] = Mat6::Zero();
        Xdown[j].block<3, 3>(0, 0) = rel.R.transpose();
        Xdown[j].block<3, 3>(3, 0) = -rel.R.transpose() * skew(rel.p);
        Xdown[j].block<3, 3>(3, 3) = rel.R.transpose();
        S[j] = motion_subspace_child(jt, q);
    }

    // Per body, in its own frame: spatial inertia, and load f_i^ext + I_i g (world-frame
    // forces and gravity rotated into the body frame).
    std::vector<Mat6> Ib(nb);
    std::vector<Vec6> load(nb, Vec6::Zero());
    for (const BodyForce &bf : m.body_forces) {
        if (bf.body < 0 || bf.body >= nb) throw std::invalid_argument("body force on a bad body");
        const Mat3 &R = s.pose[bf.body].R;
        const Vec3 F = R.transpose() * to_vec3(bf.force);
        load[bf.body].head<3>() += to_vec3(bf.point).cross(F) + R.transpose() * to_vec3(bf.torque);
        load[bf.body].tail<3>() += F;
    }
    for (int b = 0; b < nb; ++b) {
        Ib[b] = spatial_inertia(m.bodies[b], Pose());  // body frame
        Vec6 g = Vec6::Zero();
        g.tail<3>() = s.pose[b].R.transpose() * to_vec3(m.gravity);
        load[b] += Ib[b] * g;
    }
    const VecX Q = joint_forces_vector(m, t);
    {
        Real sum = Q.squaredNorm();
        for (int b = 0; b < nb; ++b) sum += load[b].squaredNorm();
        s.load_scale = std::sqrt(sum);
    }

    // Subtree sums of I_i and of the loads, each in the subtree root's frame (children after
    // parents in t.order, so walk it backwards).
    std::vector<Mat6> Ic(Ib);
    std::vector<Vec6> Lc(load);
    for (int k = nj - 1; k >= 0; --k) {
        const int j = t.order[k];
        const Joint &jt = m.joints[j];
        if (jt.parent >= 0) {
            Ic[jt.parent] += Xfup[j] * Ic[jt.child] * Xfup[j].transpose();
            Lc[jt.parent] += Xfup[j] * Lc[jt.child];
        }
    }

    // M and tau: M_jk = S_j^T Ic_k S_k for j = k and every ancestor j of k (F carried up
    // the path frame by frame), tau_k = Q_k + S_k^T Lc_k.
    s.M = MatX::Zero(t.nv, t.nv);
    s.tau = Q;
    for (int k = 0; k < nj; ++k) {
        const int dk = (int)S[k].cols();
        if (dk == 0) continue;
        const int ck = m.joints[k].child;
        Mat6X F = Ic[ck] * S[k];
        s.tau.segment(t.v_offset[k], dk) += S[k].transpose() * Lc[ck];
        for (int j = k;;) {
            const int dj = (int)S[j].cols();
            if (dj > 0) {
                const MatD blk = S[j].transpose() * F;
                s.M.block(t.v_offset[j], t.v_offset[k], dj, dk) = blk;
                if (j != k) s.M.block(t.v_offset[k], t.v_offset[j], dk, dj) = blk.transpose();
            }
            const int parent = m.joints[j].parent;
            if (parent < 0) break;
            F = (Xfup[j] * F).eval();  // into the parent body's frame
            j = t.joint_of_body[parent];
        }
    }
    // Exact symmetry of the diagonal blocks.
    s.M = ((s.M + s.M.transpose()) / 2).eval();

    if (t.nv > 0) {
        Eigen::LDLT<MatX> ldlt(s.M);
        if (ldlt.info() != Eigen::Success) throw std::runtime_error("LDLT failed");
        s.qdd = ldlt.solve(s.tau);
        // One step of iterative refinement (cheap, and makes the reference tighter still).
        const VecX r = s.tau - s.M * s.qdd;
        s.qdd += ldlt.solve(r);
        const Real tn = s.tau.norm();
        s.residual = (s.tau - s.M * s.qdd).norm() / (tn > 0 ? tn : 1);
    } else {
        s.qdd = VecX::Zero(0);
    }

    // Body accelerations a_i = a_parent + S_j qdd_j, each in its own body frame.
    s.body_acc.assign(nb, Vec6::Zero());
    for (int j : t.order) {
        const Joint &jt = m.joints[j];
        Vec6 a = jt.parent >= 0 ? Vec6(Xdown[j] * s.body_acc[jt.parent]) : Vec6::Zero();
        const int d = (int)S[j].cols();
        if (d > 0) a += S[j] * s.qdd.segment(t.v_offset[j], d);
        s.body_acc[jt.child] = a;
    }

    // Newton-Euler on subtrees: f_j = sum_{subtree} (I_i a_i - f_i^ext - I_i g), accumulated
    // from the leaves up, each subtree's sum in its root body's frame: that is f_j in the
    // child frame of j, about its origin.
    std::vector<Vec6> net(nb);
    for (int b = 0; b < nb; ++b) net[b] = Ib[b] * s.body_acc[b] - load[b];
    for (int k = nj - 1; k >= 0; --k) {
        const int j = t.order[k];
        const Joint &jt = m.joints[j];
        if (jt.parent >= 0) net[jt.parent] += Xfup[j] * net[jt.child];
    }
    s.constraint.assign(nj, Vec6::Zero());
    for (int j = 0; j < nj; ++j) s.constraint[j] = net[m.joints[j].child];
    return s;
}

// M and tau from the literal sums over bodies, M = sum_i J_i^T I_i J_i and
// tau = Q + sum_i J_i^T (f_i^ext + I_i g) (to check the regrouping in solve(); O(N depth^2)).
inline void assemble_literal(const Model &m, MatX &M, VecX &tau) {
    const Topology t = make_topology(m);
    const std::vector<Pose> pose = world_poses(m, t);
    const std::vector<Vec6> fext = external_forces_world(m, pose);
    Vec6 g = Vec6::Zero();
    g.tail<3>() = to_vec3(m.gravity);
    M = MatX::Zero(t.nv, t.nv);
    tau = joint_forces_vector(m, t);
    for (int b = 0; b < (int)m.bodies.size(); ++b) {
        MatX J = MatX::Zero(6, t.nv);
        for (int j = t.joint_of_body[b]; j >= 0;) {
            const Joint &jt = m.joints[j];
            const int d = joint_nv(jt.type);
            if (d > 0)
                J.block(0, t.v_offset[j], 6, d) =
                    motion_to_world(pose[jt.child]) *
                    motion_subspace_child(jt, m.positions.data() + t.q_offset[j]);
            j = jt.parent >= 0 ? t.joint_of_body[jt.parent] : -1;
        }
        const Mat6 I = spatial_inertia(m.bodies[b], pose[b]);
        M += J.transpose() * I * J;
        tau += J.transpose() * (fext[b] + I * g);
    }
}

}  // namespace aqsref

#endif  // AQS_TESTS_DENSE_REFERENCE_HPP
