/*
 * pinpeer_main.cpp -- Pinocchio's articulated-body algorithm against aqs's
 * exact pass (set_positions + solve) on the same model and state, timed
 * interleaved in one process (make bench-peer; docs/bench.md, issue 14).
 *
 *   pinpeer_main [--cases LIST] [--rounds R] [--reps K] [--only aqs|pin]
 *
 * LIST: comma-separated SCENE:JOINTS (default
 * chain30:30,chain:1000,molecule:5000,molecule:50000,millipede:13000).
 *
 * The one C++ file of the project (a benchmark program, not the library):
 * compiled with -O3 -march=native against the headers of the `libpinocchio`
 * 4.1.0 wheel from PyPI (header-only use: no Pinocchio library is linked).
 *
 * What runs on the Pinocchio side. Pinocchio's stock DataTpl allocates dense
 * nv x nv members (and the nv x nv x 6 kinematic Hessians), and its ModelTpl
 * keeps every joint's support path and subtree (O(N * depth)): neither fits
 * a 50,000-joint molecule. So the three passes of Pinocchio 4.1's
 * world-convention ABA (impl::AbaWorldConventionForwardStep1,
 * ...BackwardStep, ...ForwardStep2 of src/algorithm/aba.hxx, the overload
 * with external forces) are copied below verbatim except that Model and Data
 * are the lean structs LeanModel and LeanData, which hold exactly the
 * members those passes read and write (same types, same names, same
 * allocation as DataTpl's). The joints are Pinocchio's generic JointModel /
 * JointData variants (boost::variant dispatch per joint, as in a stock
 * Pinocchio model): revolute about an aligned axis -> JointModelRX/RY/RZ,
 * otherwise JointModelRevoluteUnaligned (q = the angle, as aqs's), free ->
 * JointModelFreeFlyer (q = x y z qx qy qz qw; acceleration [v; w] against
 * aqs's [w; v], swapped when compared).
 *
 * The model is read from the aqs linkage through the read-back API (as
 * bench/urdf.c writes it as URDF): joint frame in the parent body frame,
 * axis, mass, centre of mass, inertia about the centre of mass. The state:
 * zero velocity, zero joint torques, gravity off, one 1 N force on a seeded
 * body at its centre of mass (as exact_main.c: the same body, direction and
 * point), and the same positions per pass: q0 + 1e-3 sin(i + 0.7 k) on the
 * revolute angles. The world force is expressed in the loaded joint's local
 * frame at q0 (Pinocchio's fext convention) and kept for every pass (the
 * work per pass does not depend on its value). Before timing, both sides'
 * accelerations at q0 are compared: max |qdd_pin - qdd_aqs| / max |qdd_aqs|
 * is printed and must be below 1e-6 (else the program fails).
 *
 * Timing: in each round, for each case in turn, K passes of aqs then K passes
 * of Pinocchio at the same positions; per side the median pass of the round,
 * then the median over rounds. Instruction counts: run under
 *   valgrind --tool=callgrind --toggle-collect=bench_exact_pass \
 *       --toggle-collect=peer_pin_aba build/bench/pinpeer_main --cases ... \
 *       --rounds 1 --reps 3
 * and read each function's inclusive count (callgrind_annotate --inclusive=yes)
 * divided by rounds x reps x joints (tools/bench_peer.sh does it; the checks
 * before the timing call the same passes outside these two functions).
 */
#include <pinocchio/math.hpp>
#include <pinocchio/multibody.hpp>
#include <pinocchio/spatial.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

extern "C" {
#include "aqs.h"
#include "scenes.h"
#include "timing.h"
}

namespace lean
{
  using namespace pinocchio;
  typedef double Scalar;
  enum
  {
    Options = 0
  };
  typedef JointCollectionDefaultTpl<Scalar, Options> JointCollection;
  typedef JointModelTpl<Scalar, Options, JointCollectionDefaultTpl> JointModel;
  typedef JointDataTpl<Scalar, Options, JointCollectionDefaultTpl> JointData;
  typedef Eigen::Matrix<Scalar, Eigen::Dynamic, 1, Options> VectorXs;

  /* The members of ModelTpl that the world-convention ABA reads. */
  struct LeanModel
  {
    typedef std::size_t JointIndex;
    int njoints = 1, nq = 0, nv = 0;
    std::vector<JointModel> joints;
    std::vector<JointIndex> parents;
    PINOCCHIO_ALIGNED_STD_VECTOR(SE3) jointPlacements;
    std::vector<Inertia> inertias;
    VectorXs armature;
    Motion gravity;
  };

  /* The members of DataTpl that the world-convention ABA reads and writes. */
  struct LeanData
  {
    typedef pinocchio::Motion Motion;
    typedef pinocchio::Force Force;
    typedef pinocchio::Inertia Inertia;
    typedef Eigen::Matrix<Scalar, 6, Eigen::Dynamic, Options> Matrix6x;
    typedef Inertia::Matrix6 Matrix6;
    std::vector<JointData> joints;
    PINOCCHIO_ALIGNED_STD_VECTOR(SE3) liMi, oMi;
    std::vector<Motion> ov, oa_gf, oa;
    std::vector<Force> oh, of;
    std::vector<Inertia> oinertias, oYcrb;
    PINOCCHIO_ALIGNED_STD_VECTOR(Matrix6) oYaba;
    Matrix6x J;
    VectorXs u, ddq;

    explicit LeanData(const LeanModel & model)
    : liMi((std::size_t)model.njoints, SE3::Identity())
    , oMi((std::size_t)model.njoints, SE3::Identity())
    , ov((std::size_t)model.njoints, Motion::Zero())
    , oa_gf((std::size_t)model.njoints, Motion::Zero())
    , oa((std::size_t)model.njoints, Motion::Zero())
    , oh((std::size_t)model.njoints, Force::Zero())
    , of((std::size_t)model.njoints, Force::Zero())
    , oinertias((std::size_t)model.njoints, Inertia::Zero())
    , oYcrb((std::size_t)model.njoints, Inertia::Zero())
    , oYaba((std::size_t)model.njoints, Matrix6::Zero())
    , J(Matrix6x::Zero(6, model.nv))
    , u(VectorXs::Zero(model.nv))
    , ddq(VectorXs::Zero(model.nv))
    {
      joints.reserve((std::size_t)model.njoints);
      for (int i = 0; i < model.njoints; i++)
        joints.push_back(model.joints[(std::size_t)i].createData());
    }
  };

  typedef LeanModel Model;
  typedef LeanData Data;

  /* ---- copied from pinocchio 4.1.0 src/algorithm/aba.hxx (world convention),
   * Model/Data typedefs replaced by the lean ones ---- */
  template<typename ConfigVectorType, typename TangentVectorType>
  struct AbaWorldConventionForwardStep1
  : public fusion::JointUnaryVisitorBase<
      AbaWorldConventionForwardStep1<ConfigVectorType, TangentVectorType>>
  {
    typedef boost::fusion::
      vector<const Model &, Data &, const ConfigVectorType &, const TangentVectorType &>
        ArgsType;

    template<typename JointModel>
    static void algo(
      const pinocchio::JointModelBase<JointModel> & jmodel,
      pinocchio::JointDataBase<typename JointModel::JointDataDerived> & jdata,
      const Model & model,
      Data & data,
      const Eigen::MatrixBase<ConfigVectorType> & q,
      const Eigen::MatrixBase<TangentVectorType> & v)
    {
      typedef typename Model::JointIndex JointIndex;
      typedef typename Data::Motion Motion;

      const JointIndex i = jmodel.id();
      Motion & ov = data.ov[i];
      jmodel.calc(jdata.derived(), q.derived(), v.derived());

      const JointIndex & parent = model.parents[i];
      data.liMi[i] = model.jointPlacements[i] * jdata.M();
      if (parent > 0)
        data.oMi[i] = data.oMi[parent] * data.liMi[i];
      else
        data.oMi[i] = data.liMi[i];

      jmodel.jointCols(data.J) = data.oMi[i].act(jdata.S());

      ov = data.oMi[i].act(jdata.v());
      if (parent > 0)
        ov += data.ov[parent];

      data.oa_gf[i] = data.oMi[i].act(jdata.c());
      if (parent > 0)
        data.oa_gf[i] += (data.ov[parent] ^ ov);

      data.oinertias[i] = data.oYcrb[i] = data.oMi[i].act(model.inertias[i]);
      data.oYaba[i] = data.oYcrb[i].matrix();

      data.oh[i] = data.oYcrb[i] * ov; // necessary for ABA derivatives
      data.of[i] = ov.cross(data.oh[i]);
    }
  };

  struct AbaWorldConventionBackwardStep
  : public fusion::JointUnaryVisitorBase<AbaWorldConventionBackwardStep>
  {
    typedef boost::fusion::vector<const Model &, Data &> ArgsType;

    template<typename JointModel>
    static void algo(
      const JointModelBase<JointModel> & jmodel,
      JointDataBase<typename JointModel::JointDataDerived> & jdata,
      const Model & model,
      Data & data)
    {
      typedef typename Model::JointIndex JointIndex;
      typedef typename Data::Inertia Inertia;
      typedef typename Data::Force Force;
      typedef typename Data::Matrix6x Matrix6x;

      const JointIndex i = jmodel.id();
      const JointIndex parent = model.parents[i];
      typename Inertia::Matrix6 & Ia = data.oYaba[i];

      typedef typename SizeDepType<JointModel::NV>::template ColsReturn<Matrix6x>::Type ColBlock;
      ColBlock Jcols = jmodel.jointCols(data.J);

      Force & fi = data.of[i];

      jmodel.jointVelocitySelector(data.u).noalias() -= Jcols.transpose() * fi.toVector();

      jdata.U().noalias() = Ia * Jcols;
      jdata.StU().noalias() = Jcols.transpose() * jdata.U();

      // Account for the rotor inertia contribution
      jdata.StU().diagonal() += jmodel.jointVelocitySelector(model.armature);

      ::pinocchio::internal::matrix_inversion(jdata.StU(), jdata.Dinv());
      jdata.UDinv().noalias() = jdata.U() * jdata.Dinv();

      if (parent > 0)
      {
        Ia.noalias() -= jdata.UDinv() * jdata.U().transpose();

        fi.toVector().noalias() +=
          Ia * data.oa_gf[i].toVector() + jdata.UDinv() * jmodel.jointVelocitySelector(data.u);
        data.oYaba[parent] += Ia;
        data.of[parent] += fi;
      }
    }
  };

  struct AbaWorldConventionForwardStep2
  : public fusion::JointUnaryVisitorBase<AbaWorldConventionForwardStep2>
  {
    typedef boost::fusion::vector<const Model &, Data &> ArgsType;

    template<typename JointModel>
    static void algo(
      const pinocchio::JointModelBase<JointModel> & jmodel,
      pinocchio::JointDataBase<typename JointModel::JointDataDerived> & jdata,
      const Model & model,
      Data & data)
    {
      typedef typename Model::JointIndex JointIndex;
      typedef typename Data::Matrix6x Matrix6x;

      typedef typename SizeDepType<JointModel::NV>::template ColsReturn<Matrix6x>::Type ColBlock;
      ColBlock J_cols = jmodel.jointCols(data.J);

      const JointIndex i = jmodel.id();
      const JointIndex parent = model.parents[i];

      data.oa_gf[i] += data.oa_gf[parent]; // does take into account the gravity field
      jmodel.jointVelocitySelector(data.ddq).noalias() =
        jdata.Dinv() * jmodel.jointVelocitySelector(data.u)
        - jdata.UDinv().transpose() * data.oa_gf[i].toVector();
      data.oa_gf[i].toVector().noalias() += J_cols * jmodel.jointVelocitySelector(data.ddq);

      // Handle consistent output
      data.oa[i] = data.oa_gf[i] + model.gravity;
      data.of[i] = data.oinertias[i] * data.oa_gf[i] + data.ov[i].cross(data.oh[i]);
    }
  };

  /* abaWorldConvention(model, data, q, v, tau, fext) of aba.hxx. */
  template<typename ConfigVectorType, typename TangentVectorType1, typename TangentVectorType2>
  const VectorXs & abaWorldConvention(
    const Model & model,
    Data & data,
    const Eigen::MatrixBase<ConfigVectorType> & q,
    const Eigen::MatrixBase<TangentVectorType1> & v,
    const Eigen::MatrixBase<TangentVectorType2> & tau,
    const std::vector<Force> & fext)
  {
    typedef Model::JointIndex JointIndex;
    data.oa_gf[0] = -model.gravity;
    data.u = tau;

    typedef AbaWorldConventionForwardStep1<ConfigVectorType, TangentVectorType1> Pass1;
    for (JointIndex i = 1; i < (JointIndex)model.njoints; ++i)
    {
      Pass1::run(
        model.joints[i], data.joints[i],
        typename Pass1::ArgsType(model, data, q.derived(), v.derived()));
      data.of[i] -= data.oMi[i].act(fext[i]);
    }

    typedef AbaWorldConventionBackwardStep Pass2;
    for (JointIndex i = (JointIndex)model.njoints - 1; i > 0; --i)
    {
      Pass2::run(model.joints[i], data.joints[i], typename Pass2::ArgsType(model, data));
    }

    typedef AbaWorldConventionForwardStep2 Pass3;
    for (JointIndex i = 1; i < (JointIndex)model.njoints; ++i)
    {
      Pass3::run(model.joints[i], data.joints[i], typename Pass3::ArgsType(model, data));
    }

    return data.ddq;
  }
  /* ---- end of the copy ---- */
} // namespace lean

struct peer_case
{
  std::string scene_name;
  int scene = 0;
  int32_t size = 0, bodies = 0, joints = 0, nq = 0, nv = 0;
  aqs_linkage * L = nullptr;
  std::vector<double> q0, q;         // aqs layout
  std::vector<int32_t> type, q_of;   // per aqs joint
  lean::LeanModel * model = nullptr; // Pinocchio side
  lean::LeanData * data = nullptr;
  lean::VectorXs pq, pv, ptau;
  std::vector<pinocchio::Force> fext;
  std::vector<double> aqs_ns, pin_ns; // per round
};

extern "C" int bench_exact_pass(aqs_linkage * L, const double * q, size_t nq);
extern "C" int peer_pin_aba(peer_case * c);

/* As exact_main.c: not inlined, so that callgrind can toggle on them. */
static int exact_pass(aqs_linkage * L, const double * q, size_t nq)
{
  if (aqs_linkage_set_positions(L, q, nq) != AQS_OK)
    return 1;
  return aqs_linkage_solve(L) != AQS_OK;
}

static int pin_aba(peer_case * c)
{
  lean::abaWorldConvention(*c->model, *c->data, c->pq, c->pv, c->ptau, c->fext);
  return 0;
}

/* The timed passes only (setup calls exact_pass and pin_aba directly, so
 * that callgrind's --toggle-collect on these counts rounds x reps passes). */
extern "C" __attribute__((noinline)) int bench_exact_pass(aqs_linkage * L, const double * q, size_t nq)
{
  return exact_pass(L, q, nq);
}

extern "C" __attribute__((noinline)) int peer_pin_aba(peer_case * c) { return pin_aba(c); }

static int fail(aqs_linkage * L, const char * what)
{
  std::fprintf(stderr, "pinpeer_main: %s failed: %s\n", what, L ? aqs_linkage_last_error(L) : "");
  return 1;
}

/* aqs positions -> Pinocchio's (revolute: the angle; free: x y z, then
 * qx qy qz qw from aqs's w x y z). Joint j of aqs is Pinocchio joint j + 1. */
static void to_pin(peer_case & c)
{
  for (int32_t j = 0; j < c.joints; j++)
  {
    const auto & jm = c.model->joints[(std::size_t)j + 1];
    const double * a = &c.q[(std::size_t)c.q_of[(std::size_t)j]];
    if (c.type[(std::size_t)j] == AQS_JOINT_FREE)
    {
      c.pq.segment<7>(jm.idx_q()) << a[0], a[1], a[2], a[4], a[5], a[6], a[3];
    }
    else
      c.pq[jm.idx_q()] = a[0];
  }
}

static void positions(peer_case & c, int k)
{
  int32_t i, lo = c.scene == BENCH_SCENE_MILLIPEDE ? 7 : 0;
  c.q = c.q0;
  for (i = lo; i < c.nq; i++)
    c.q[(std::size_t)i] += 1e-3 * std::sin((double)i + 0.7 * k);
  to_pin(c);
}

static int setup(peer_case & c)
{
  using namespace pinocchio;
  const double zero[3] = {0, 0, 0};
  double f[3], p[3];
  int32_t body;
  bench_rng rng;
  if (aqs_linkage_create(&c.L) != AQS_OK)
    return fail(nullptr, "create");
  if (bench_build_scene(c.L, (bench_scene_kind)c.scene, c.size) != AQS_OK)
    return fail(c.L, "build");
  if (aqs_linkage_finalize(c.L) != AQS_OK)
    return fail(c.L, "finalize");
  if (aqs_linkage_get_sizes(c.L, &c.bodies, &c.joints, &c.nq, &c.nv) != AQS_OK)
    return fail(c.L, "sizes");
  c.q0.resize((std::size_t)c.nq);
  if (aqs_linkage_get_positions(c.L, c.q0.data(), (size_t)c.nq) != AQS_OK)
    return fail(c.L, "positions");
  if (aqs_linkage_set_gravity(c.L, zero) != AQS_OK)
    return fail(c.L, "gravity");
  bench_rng_seed(&rng, 1);
  body = c.scene == BENCH_SCENE_MILLIPEDE
           ? BENCH_MILLIPEDE_SPINE
               + (int32_t)bench_rng_below(&rng, (uint64_t)(c.bodies - BENCH_MILLIPEDE_SPINE))
           : (int32_t)bench_rng_below(&rng, (uint64_t)c.bodies);
  bench_rng_unit_vector(&rng, f);
  bench_scene_body_com((bench_scene_kind)c.scene, body, p);
  if (aqs_body_set_force(c.L, body, f, p, nullptr) != AQS_OK)
    return fail(c.L, "force");

  /* The Pinocchio model from the read-back API. */
  c.model = new lean::LeanModel();
  lean::LeanModel & m = *c.model;
  m.joints.push_back(lean::JointModel(JointModelRX())); // the universe (unused)
  m.parents.push_back(0);
  m.jointPlacements.push_back(SE3::Identity());
  m.inertias.push_back(Inertia::Zero());
  c.type.resize((std::size_t)c.joints);
  c.q_of.resize((std::size_t)c.joints);
  int32_t qoff = 0;
  for (int32_t j = 0; j < c.joints; j++)
  {
    double pos[3], quat[4], axis[3], mass, com[3], I[9];
    int32_t type, parent, child;
    if (aqs_joint_get_definition(c.L, j, &type, &parent, &child, pos, quat, axis) != AQS_OK)
      return fail(c.L, "joint definition");
    if (child != j)
      return std::fprintf(stderr, "pinpeer_main: joint %d has child %d\n", j, child), 1;
    if (aqs_body_get_inertial(c.L, child, &mass, com, I) != AQS_OK)
      return fail(c.L, "inertial");
    c.type[(std::size_t)j] = type;
    c.q_of[(std::size_t)j] = qoff;
    lean::JointModel jm;
    if (type == AQS_JOINT_REVOLUTE)
    {
      if (axis[0] == 1 && axis[1] == 0 && axis[2] == 0)
        jm = JointModelRX();
      else if (axis[0] == 0 && axis[1] == 1 && axis[2] == 0)
        jm = JointModelRY();
      else if (axis[0] == 0 && axis[1] == 0 && axis[2] == 1)
        jm = JointModelRZ();
      else
        jm = JointModelRevoluteUnaligned(axis[0], axis[1], axis[2]);
      qoff += 1;
    }
    else if (type == AQS_JOINT_FREE)
    {
      jm = JointModelFreeFlyer();
      qoff += 7;
    }
    else
      return std::fprintf(stderr, "pinpeer_main: joint %d: type %d not handled\n", j, type), 1;
    jm.setIndexes((JointIndex)(j + 1), m.nq, m.nv);
    m.nq += jm.nq();
    m.nv += jm.nv();
    m.joints.push_back(jm);
    m.parents.push_back(parent == AQS_WORLD ? 0 : (std::size_t)parent + 1);
    const Eigen::Quaterniond qu(quat[0], quat[1], quat[2], quat[3]);
    m.jointPlacements.push_back(SE3(qu.toRotationMatrix(), Eigen::Vector3d(pos[0], pos[1], pos[2])));
    Eigen::Matrix3d In;
    In << I[0], I[1], I[2], I[3], I[4], I[5], I[6], I[7], I[8];
    m.inertias.push_back(Inertia(mass, Eigen::Vector3d(com[0], com[1], com[2]), In));
    if (parent != AQS_WORLD && parent >= j)
      return std::fprintf(stderr, "pinpeer_main: joint %d: parent %d after it\n", j, parent), 1;
  }
  m.njoints = c.joints + 1;
  m.armature = lean::VectorXs::Zero(m.nv);
  m.gravity = Motion::Zero();
  c.data = new lean::LeanData(m);
  c.pq = lean::VectorXs::Zero(m.nq);
  c.pv = lean::VectorXs::Zero(m.nv);
  c.ptau = lean::VectorXs::Zero(m.nv);
  c.fext.assign((std::size_t)m.njoints, Force::Zero());

  /* State q0 on both sides; the force in the joint's local frame at q0. */
  c.q = c.q0;
  to_pin(c);
  pin_aba(&c);
  {
    const SE3 & oMi = c.data->oMi[(std::size_t)body + 1];
    const Eigen::Vector3d fl = oMi.rotation().transpose() * Eigen::Vector3d(f[0], f[1], f[2]);
    const Eigen::Vector3d pl(p[0], p[1], p[2]);
    c.fext[(std::size_t)body + 1] = Force(fl, pl.cross(fl));
  }
  pin_aba(&c);
  if (exact_pass(c.L, c.q.data(), (size_t)c.nq))
    return fail(c.L, "first pass");
  std::vector<double> qdd((std::size_t)c.nv);
  if (aqs_linkage_get_accelerations(c.L, qdd.data(), (size_t)c.nv) != AQS_OK)
    return fail(c.L, "accelerations");
  double scale = 0.0, diff = 0.0;
  int32_t voff = 0;
  for (int32_t j = 0; j < c.joints; j++)
  {
    const auto & jm = m.joints[(std::size_t)j + 1];
    const int nvj = jm.nv();
    for (int k = 0; k < nvj; k++)
    {
      const int kp = c.type[(std::size_t)j] == AQS_JOINT_FREE ? (k + 3) % 6 : k;
      const double a = qdd[(std::size_t)(voff + k)], b = c.data->ddq[jm.idx_v() + kp];
      scale = std::max(scale, std::fabs(a));
      diff = std::max(diff, std::fabs(a - b));
    }
    voff += nvj;
  }
  const double rel = diff / scale;
  std::printf("%s %d: %d joints, nv %d; max |qdd_pin - qdd_aqs| / max |qdd_aqs| = %.2e\n",
              c.scene_name.c_str(), (int)c.size, (int)c.joints, (int)c.nv, rel);
  if (!(rel < 1e-6))
    return std::fprintf(stderr, "pinpeer_main: the accelerations differ (%.3e)\n", rel), 1;
  return 0;
}

int main(int argc, char ** argv)
{
  std::string cases = "chain30:30,chain:1000,molecule:5000,molecule:50000,millipede:13000";
  std::string only;
  int rounds = 9, reps = 5;
  for (int a = 1; a < argc; a++)
  {
    if (!std::strcmp(argv[a], "--cases") && a + 1 < argc)
      cases = argv[++a];
    else if (!std::strcmp(argv[a], "--rounds") && a + 1 < argc)
      rounds = std::atoi(argv[++a]);
    else if (!std::strcmp(argv[a], "--reps") && a + 1 < argc)
      reps = std::atoi(argv[++a]);
    else if (!std::strcmp(argv[a], "--only") && a + 1 < argc)
      only = argv[++a];
    else
    {
      std::fprintf(
        stderr, "usage: pinpeer_main [--cases SCENE:N,...] [--rounds R] [--reps K] [--only aqs|pin]\n");
      return 2;
    }
  }
  if (rounds < 1 || reps < 1)
    return 2;
  std::vector<peer_case> cs;
  {
    std::size_t start = 0;
    while (start < cases.size())
    {
      std::size_t end = cases.find(',', start);
      if (end == std::string::npos)
        end = cases.size();
      const std::string item = cases.substr(start, end - start);
      const std::size_t colon = item.find(':');
      peer_case c;
      c.scene_name = item.substr(0, colon);
      c.scene = bench_scene_from_name(c.scene_name.c_str());
      if (c.scene < 0)
        return std::fprintf(stderr, "pinpeer_main: unknown scene %s\n", c.scene_name.c_str()), 2;
      c.size = colon == std::string::npos ? 0 : (int32_t)std::atol(item.c_str() + colon + 1);
      cs.push_back(c);
      start = end + 1;
    }
  }
  for (auto & c : cs)
    if (setup(c))
      return 1;
  std::vector<double> ta((std::size_t)reps), tp((std::size_t)reps);
  for (int r = 0; r < rounds; r++)
    for (auto & c : cs)
    {
      for (int k = 0; k < reps; k++)
      {
        positions(c, r * reps + k + 1);
        if (only != "pin")
        {
          const double t0 = bench_now();
          if (bench_exact_pass(c.L, c.q.data(), (size_t)c.nq))
            return fail(c.L, "pass");
          ta[(std::size_t)k] = 1e9 * (bench_now() - t0);
        }
        if (only != "aqs")
        {
          const double t0 = bench_now();
          peer_pin_aba(&c);
          tp[(std::size_t)k] = 1e9 * (bench_now() - t0);
        }
      }
      c.aqs_ns.push_back(bench_median(ta.data(), (size_t)reps));
      c.pin_ns.push_back(bench_median(tp.data(), (size_t)reps));
    }
  std::printf("%d rounds x %d passes, interleaved (aqs set_positions + solve; Pinocchio 4.1 ABA, world convention)\n",
              rounds, reps);
  std::printf("%-10s %8s %12s %12s %10s %10s %8s %14s\n", "scene", "joints", "pin ms", "aqs ms",
              "pin ns/j", "aqs ns/j", "aqs/pin", "ratio range");
  for (auto & c : cs)
  {
    std::vector<double> ratio;
    for (std::size_t r = 0; r < c.aqs_ns.size(); r++)
      ratio.push_back(c.aqs_ns[r] / c.pin_ns[r]);
    const double a = bench_median(c.aqs_ns.data(), c.aqs_ns.size()),
                 p = bench_median(c.pin_ns.data(), c.pin_ns.size());
    std::printf("%-10s %8d %12.4f %12.4f %10.1f %10.1f %8.2f %6.2f-%-6.2f\n", c.scene_name.c_str(),
                (int)c.joints, p * 1e-6, a * 1e-6, p / c.joints, a / c.joints, a / p,
                *std::min_element(ratio.begin(), ratio.end()),
                *std::max_element(ratio.begin(), ratio.end()));
  }
  for (auto & c : cs)
  {
    aqs_linkage_destroy(c.L);
    delete c.data;
    delete c.model;
  }
  return 0;
}
