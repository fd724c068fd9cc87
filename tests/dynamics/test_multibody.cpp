// Articulated-body dynamics of the core (dynamics/multibody.hpp), on the host and the emulated
// MCU: a pendulum against its closed form; random trees of revolute, prismatic and fixed joints
// (half with armature and joint damping) where ABA inverts RNEA, CRBA's mass matrix is symmetric
// positive definite and reproduces RNEA's torques (H qdd + bias = tau); the kinetic energy; point
// Jacobians against the twists of RNEA's forward pass; the same on floating-base trees, and a free
// body against Newton-Euler; refusals; no heap.
#include <cmath>
#include <cstring>
#include <limits>

#include "kestrel/dynamics/multibody.hpp"
#include "kestrel/kernel/rng.hpp"
#include "ktest.hpp"

using namespace kestrel;
namespace dy = kestrel::dynamics;

namespace {

// Relative tolerances: float32 builds (the MCU default) and double builds.
constexpr double kTol = sizeof(real) == 4 ? 2e-3 : 1e-9;

dy::SpatialInertia body(real m, const Vec3& com, const Vec3& diag) {
  dy::SpatialInertia b;
  b.mass = m;
  b.com = com;
  b.inertia_com = diag.asDiagonal();
  return b;
}

// A random unit vector / rotation / tree from a counter-based stream (the same on every target).
Vec3 unit(RngStream& r) {
  Vec3 v(r.uniform(-1, 1), r.uniform(-1, 1), r.uniform(-1, 1));
  if (v.norm() < real(0.1)) v = Vec3(0, 0, 1);
  return v / v.norm();
}

template <int N>
void random_tree(dy::MultibodyModel<N>& m, int bodies, std::uint32_t stream, bool floating = false) {
  RngStream r(2026, stream, 1);
  m.num_bodies = bodies;
  for (int i = 0; i < bodies; ++i) {
    m.parent[i] = i == 0 ? -1 : static_cast<int>(r.uniform(0, static_cast<real>(i) - real(0.001)));
    const real kind = r.uniform(0, 1);
    m.joint[i] = kind < real(0.6) ? dy::JointType::revolute : kind < real(0.85) ? dy::JointType::prismatic : dy::JointType::fixed;
    if (i == 0 && m.joint[i] == dy::JointType::fixed) m.joint[i] = dy::JointType::revolute;
    m.axis[i] = unit(r);
    const Vec3 a = unit(r);
    const real angle = r.uniform(-3, 3);
    m.X_tree[i].E = Eigen::AngleAxis<real>(angle, a).toRotationMatrix();
    m.X_tree[i].r = Vec3(r.uniform(-0.3_r, 0.3_r), r.uniform(-0.3_r, 0.3_r), r.uniform(-0.3_r, 0.3_r));
    // A principal inertia turned by a random rotation: symmetric positive definite.
    const Mat3 R = Eigen::AngleAxis<real>(r.uniform(-3, 3), unit(r)).toRotationMatrix();
    const Vec3 p(r.uniform(0.01_r, 0.1_r), r.uniform(0.01_r, 0.1_r), r.uniform(0.01_r, 0.1_r));
    m.body[i] = body(r.uniform(0.2_r, 3), Vec3(r.uniform(-0.1_r, 0.1_r), r.uniform(-0.1_r, 0.1_r), r.uniform(-0.1_r, 0.1_r)), p);
    m.body[i].inertia_com = R * p.asDiagonal() * R.transpose();
    m.body[i].inertia_com = real(0.5) * (m.body[i].inertia_com + m.body[i].inertia_com.transpose());
    m.armature[i] = stream % 2 == 0 ? r.uniform(0, 0.05_r) : 0;  // half the trees with rotor inertia and damping
    m.damping[i] = stream % 2 == 0 ? r.uniform(0, 0.5_r) : 0;
    // In a third of the trees, every other revolute joint turns about +x, +y or +z of an unrotated
    // joint frame, as in most robot files: aba's elementary-axis path (finish_model finds them).
    if (stream % 3 == 1 && i % 2 == 0 && m.joint[i] == dy::JointType::revolute) {
      m.axis[i] = Vec3::Unit(static_cast<int>(r.uniform(0, 2.999_r)));
      m.X_tree[i].E = Mat3::Identity();
    }
    // And every other prismatic joint slides along +x, +y or +z: crba's and rnea's unit-subspace
    // path (finish_model's unit_subspace 3..5), whatever X_tree.
    if (stream % 3 == 1 && i % 2 == 0 && m.joint[i] == dy::JointType::prismatic)
      m.axis[i] = Vec3::Unit(static_cast<int>(r.uniform(0, 2.999_r)));
  }
  if (floating) {
    m.joint[0] = dy::JointType::free;
    m.armature[0] = m.damping[0] = 0;
  }
}

template <int N>
int elementary_joints(const dy::MultibodyModel<N>& m) {
  int n = 0;
  for (int i = 0; i < m.num_bodies; ++i) n += m.elementary_axis[i] >= 0 ? 1 : 0;
  return n;
}

// Joints (not the free one) whose motion subspace finish_model marked a unit vector, linear ones
// (prismatic along +x, +y, +z) counted in `linear`.
template <int N>
int unit_subspace_joints(const dy::MultibodyModel<N>& m, int& linear) {
  int n = 0;
  for (int i = 0; i < m.num_bodies; ++i) {
    n += m.unit_subspace[i] >= 0 ? 1 : 0;
    linear += m.unit_subspace[i] >= 3 ? 1 : 0;
  }
  return n;
}

// A random configuration (unit base quaternion for a floating tree) and velocities.
template <int N>
void random_state(const dy::MultibodyModel<N>& m, RngStream& r, real* q, real* qd) {
  for (int k = 0; k < m.num_q; ++k) q[k] = r.uniform(-2, 2);
  for (int k = 0; k < m.num_dofs; ++k) qd[k] = r.uniform(-2, 2);
  if (m.joint[0] == dy::JointType::free) {
    real* quat = q + m.q_index[0] + 3;
    const Vec3 a = unit(r);
    const Quat Q(Eigen::AngleAxis<real>(r.uniform(-3, 3), a));
    quat[0] = Q.x();
    quat[1] = Q.y();
    quat[2] = Q.z();
    quat[3] = Q.w();
  }
}

constexpr int kMax = 8;
dy::MultibodyModel<kMax> g_model;
dy::MultibodyData<kMax> g_data;

// The Jacobian of a random point on each body, times qd, against the point's velocity from the
// body twists that the last rnea(q, qd, ...) left in g_data.v (carried to the world).
void check_point_jacobians(const dy::MultibodyModel<kMax>& m, const real* q, const real* qd, RngStream& r) {
  constexpr int kDofs = dy::max_dofs<kMax>();
  static dy::Transform X_world[kMax];
  static dy::MultibodyData<kMax> d2;
  static real J[6 * kDofs];
  dy::forward_kinematics(m, d2, q, X_world);
  for (int b = 0; b < m.num_bodies; ++b) {
    const Vec3 p_b(r.uniform(-0.2_r, 0.2_r), r.uniform(-0.2_r, 0.2_r), r.uniform(-0.2_r, 0.2_r));
    dy::point_jacobian(m, X_world, b, p_b, J, kDofs);
    const Mat3 Et = X_world[b].E.transpose();
    const Vec3 w_b = dy::ang(g_data.v[b]), v_b = dy::lin(g_data.v[b]);
    const Vec3 want_v = Et * (v_b + w_b.cross(p_b)), want_w = Et * w_b;
    for (int a = 0; a < 3; ++a) {
      real jv = 0, jw = 0;
      for (int k = 0; k < m.num_dofs; ++k) {
        jv += J[kDofs * a + k] * qd[k];
        jw += J[kDofs * (3 + a) + k] * qd[k];
      }
      KEXPECT_NEAR(jv, want_v[a], kTol * 20 * (1 + want_v.norm()));
      KEXPECT_NEAR(jw, want_w[a], kTol * 20 * (1 + want_w.norm()));
    }
  }
}

// On one tree at a random state: ABA inverts RNEA; CRBA's mass matrix is symmetric positive
// definite with H qdd + bias = tau and 1/2 qd^T H qd the bodies' (and rotors') kinetic energy; a
// floating base's block carries the whole tree's mass; point Jacobians give the point velocities.
void check_consistency(const dy::MultibodyModel<kMax>& m, RngStream& r) {
  constexpr int kDofs = dy::max_dofs<kMax>();
  const int n = m.num_dofs;
  real q[kDofs + 1] = {}, qd[kDofs] = {}, qdd[kDofs] = {}, tau[kDofs] = {}, bias[kDofs] = {}, zero[kDofs] = {}, back[kDofs] = {};
  random_state(m, r, q, qd);
  for (int k = 0; k < n; ++k) qdd[k] = r.uniform(-3, 3);
  dy::rnea(m, g_data, q, qd, qdd, tau);
  Status st = Status::invalid_argument;
  KEXPECT_NO_HEAP(st = dy::aba(m, g_data, q, qd, tau, back));
  KEXPECT_TRUE(st == Status::ok);
  for (int k = 0; k < n; ++k) KEXPECT_NEAR(back[k], qdd[k], kTol * 50 * (1 + std::fabs(qdd[k])));
  dy::rnea(m, g_data, q, qd, zero, bias);
  static real H[kDofs * kDofs];
  for (real& h : H) h = std::numeric_limits<real>::quiet_NaN();
  dy::crba(m, g_data, q, H, kDofs);
  Eigen::Matrix<real, kDofs, kDofs> Hm = Eigen::Matrix<real, kDofs, kDofs>::Identity();
  real scale = 0;
  for (int k = 0; k < n; ++k) scale = std::max(scale, std::fabs(tau[k]));
  for (int i = 0; i < n; ++i) {
    real s = bias[i];
    for (int j = 0; j < n; ++j) {
      Hm(i, j) = H[kDofs * i + j];
      s += H[kDofs * i + j] * qdd[j];
      KEXPECT_NEAR(H[kDofs * i + j], H[kDofs * j + i], kTol * 10);
    }
    KEXPECT_NEAR(s, tau[i], kTol * 10 * (1 + scale));
  }
  Eigen::LLT<Eigen::Matrix<real, kDofs, kDofs>> llt(Hm);
  KEXPECT_TRUE(llt.info() == Eigen::Success);
  if (m.joint[0] == dy::JointType::free) {  // the base block is the whole tree's inertia
    real total_mass = 0;
    for (int b = 0; b < m.num_bodies; ++b) total_mass += m.body[b].mass;
    for (int a = 0; a < 3; ++a) KEXPECT_NEAR(H[kDofs * a + a], total_mass, kTol * 10 * total_mass);
  }
  real ke_joint = 0, ke_bodies = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) ke_joint += real(0.5) * qd[i] * H[kDofs * i + j] * qd[j];
  dy::rnea(m, g_data, q, qd, zero, bias);  // body twists in g_data.v
  for (int b = 0; b < m.num_bodies; ++b) {
    ke_bodies += real(0.5) * g_data.v[b].dot(dy::inertia_times(m.body[b], g_data.v[b]));
    const int k = m.dof_index[b];
    if (k >= 0 && m.joint[b] != dy::JointType::free) ke_bodies += real(0.5) * m.armature[b] * qd[k] * qd[k];
  }
  KEXPECT_NEAR(ke_joint, ke_bodies, kTol * 10 * (1 + ke_bodies));
  check_point_jacobians(m, q, qd, r);  // g_data.v holds the twists of the last rnea
}

}  // namespace

KTEST(Multibody, PendulumMatchesItsClosedForm) {
  // A rod of mass m, centre of mass L below a revolute joint about y: (Iyy + m L^2) qdd = -m g L sin q.
  dy::MultibodyModel<2> p;
  p.num_bodies = 1;
  p.parent[0] = -1;
  p.joint[0] = dy::JointType::revolute;
  p.axis[0] = Vec3(0, 1, 0);
  const real mass = 1.5_r, L = 0.4_r, Iyy = 0.02_r;
  p.body[0] = body(mass, Vec3(0, 0, -L), Vec3(0.02_r, Iyy, 0.01_r));
  KASSERT_TRUE(dy::finish_model(p) == Status::ok);
  KEXPECT_EQ(p.num_dofs, 1);
  dy::MultibodyData<2> d;
  const real g = 9.81_r;
  for (real q : {0.0_r, 0.3_r, 1.2_r, -2.5_r}) {
    const real qd = 0.7_r, tau = 0.1_r;
    real qdd = 0;
    KEXPECT_TRUE(dy::aba(p, d, &q, &qd, &tau, &qdd) == Status::ok);
    const real want = (tau - mass * g * L * std::sin(q)) / (Iyy + mass * L * L);
    KEXPECT_NEAR(qdd, want, kTol * 10);
    real back = 0;
    dy::rnea(p, d, &q, &qd, &qdd, &back);
    KEXPECT_NEAR(back, tau, kTol * 10);
    real H = 0;
    dy::crba(p, d, &q, &H, 1);
    KEXPECT_NEAR(H, Iyy + mass * L * L, kTol);
  }
}

// Random fixed-base trees (half with armature and damping, a third with elementary-axis joints,
// whose ABA path RNEA and CRBA do not share): check_consistency, Jacobians included.
KTEST(Multibody, AbaInvertsRneaAndCrbaAgreesOnRandomTrees) {
  int elementary = 0, unit = 0, unit_linear = 0;
  for (std::uint32_t tree = 0; tree < 20; ++tree) {
    dy::MultibodyModel<kMax>& m = g_model;
    m = dy::MultibodyModel<kMax>();
    random_tree(m, 3 + static_cast<int>(tree % 6), tree);
    KASSERT_TRUE(dy::finish_model(m) == Status::ok);
    KEXPECT_EQ(m.num_q, m.num_dofs);
    elementary += elementary_joints(m);
    unit += unit_subspace_joints(m, unit_linear);
    RngStream r(7, tree, 2);
    check_consistency(m, r);
  }
  KEXPECT_GT(elementary, 5);
  KEXPECT_GT(unit, elementary - 1);  // every elementary joint has a unit subspace
  KEXPECT_GT(unit_linear, 0);
}

// The elementary-axis products of update_kinematics, rnea and crba (rotate_down, rotate_up,
// inertia_up) against Eigen's general 3 x 3 products on the same trees: with elementary_axis
// cleared after finish_model every joint takes the general path. Equal values entry by entry
// (the two may differ only in the sign of an exact zero), on fixed and floating trees.
KTEST(Multibody, ElementaryAxisProductsGiveTheGeneralOnesBitForBit) {
  constexpr int kDofs = dy::max_dofs<kMax>();
  static dy::MultibodyModel<kMax> general;
  static dy::MultibodyData<kMax> d2;
  int elementary = 0, compared = 0;
  for (std::uint32_t tree = 1; tree < 40; tree += 3) {  // the streams with elementary joints
    dy::MultibodyModel<kMax>& m = g_model;
    m = dy::MultibodyModel<kMax>();
    random_tree(m, 3 + static_cast<int>(tree % 6), tree, tree % 2 == 0);
    KASSERT_TRUE(dy::finish_model(m) == Status::ok);
    elementary += elementary_joints(m);
    general = m;
    for (int i = 0; i < general.num_bodies; ++i) general.elementary_axis[i] = -1;
    RngStream r(11, tree, 3);
    for (int s = 0; s < 10; ++s) {
      real q[kDofs + 1], qd[kDofs], qdd[kDofs], tau[kDofs], tau2[kDofs];
      random_state(m, r, q, qd);
      for (int k = 0; k < m.num_dofs; ++k) qdd[k] = r.uniform(-3, 3);
      static real H[kDofs * kDofs], H2[kDofs * kDofs];
      dy::crba(m, g_data, q, H, kDofs);
      dy::crba(general, d2, q, H2, kDofs);
      for (int i = 0; i < m.num_bodies; ++i)
        for (int a = 0; a < 3; ++a) {
          KEXPECT_EQ(g_data.Xup[i].r[a], d2.Xup[i].r[a]);
          for (int b = 0; b < 3; ++b) KEXPECT_EQ(g_data.Xup[i].E(a, b), d2.Xup[i].E(a, b));
        }
      for (int k = 0; k < m.num_dofs * kDofs; ++k) KEXPECT_EQ(H[k], H2[k]);
      dy::rnea(m, g_data, q, qd, qdd, tau);
      dy::rnea(general, d2, q, qd, qdd, tau2);
      for (int k = 0; k < m.num_dofs; ++k) KEXPECT_EQ(tau[k], tau2[k]);
      ++compared;
    }
  }
  KEXPECT_GT(elementary, 10);
  KEXPECT_EQ(compared, 130);
}

KTEST(Multibody, RefusesBadModelsAndInputs) {
  dy::MultibodyModel<2> m;
  m.num_bodies = 2;
  m.parent[0] = -1;
  m.parent[1] = 0;
  m.joint[0] = m.joint[1] = dy::JointType::revolute;
  m.axis[0] = m.axis[1] = Vec3(0, 0, 1);
  m.body[0] = m.body[1] = body(1, Vec3::Zero(), Vec3(0.1_r, 0.1_r, 0.1_r));
  KEXPECT_TRUE(dy::finish_model(m) == Status::ok);
  KEXPECT_EQ(m.num_dofs, 2);
  dy::MultibodyModel<2> bad = m;
  bad.parent[1] = 1;  // its own parent
  KEXPECT_TRUE(dy::finish_model(bad) == Status::invalid_argument);
  bad = m;
  bad.axis[1] = Vec3(0, 0, 2);
  KEXPECT_TRUE(dy::finish_model(bad) == Status::invalid_argument);
  bad = m;
  bad.body[0].mass = 0;
  KEXPECT_TRUE(dy::finish_model(bad) == Status::invalid_argument);
  bad = m;
  bad.body[1].inertia_com(0, 1) = 1;  // not symmetric
  KEXPECT_TRUE(dy::finish_model(bad) == Status::invalid_argument);
  bad = m;
  bad.damping[1] = -1;
  KEXPECT_TRUE(dy::finish_model(bad) == Status::invalid_argument);
  bad = m;
  bad.num_bodies = 3;  // over the capacity
  KEXPECT_TRUE(dy::finish_model(bad) == Status::invalid_argument);
  dy::MultibodyData<2> d;
  const real q[2] = {0.1_r, 0.2_r}, qd[2] = {0, 0};
  const real nan_tau[2] = {0, std::numeric_limits<real>::quiet_NaN()};
  real qdd[2] = {42, 42};
  KEXPECT_TRUE(dy::aba(m, d, q, qd, nan_tau, qdd) == Status::non_finite_input);
  KEXPECT_EQ(qdd[0], 42);  // untouched
  KEXPECT_EQ(qdd[1], 42);
}

// One free body (the floating base alone) against the Newton-Euler equations in its frame, with
// the centre of mass at its origin: f = m (dv/dt + w x v) - m R^T g, n = I dw/dt + w x I w.
KTEST(Multibody, FreeBodyFollowsNewtonEuler) {
  dy::MultibodyModel<1> m;
  m.num_bodies = 1;
  m.parent[0] = -1;
  m.joint[0] = dy::JointType::free;
  const real mass = 2.0_r;
  const Vec3 Idiag(0.02_r, 0.03_r, 0.05_r);
  m.body[0] = body(mass, Vec3::Zero(), Idiag);
  KASSERT_TRUE(dy::finish_model(m) == Status::ok);
  KEXPECT_EQ(m.num_dofs, 6);
  KEXPECT_EQ(m.num_q, 7);
  dy::MultibodyData<1> d;
  const Quat Q(Eigen::AngleAxis<real>(0.8_r, Vec3(1, 2, 3).normalized()));
  const real q[7] = {0.5_r, -1, 2, Q.x(), Q.y(), Q.z(), Q.w()};
  const Vec3 v(0.3_r, -0.2_r, 0.1_r), w(1.0_r, -0.5_r, 2.0_r), f(1, 2, -3), n(0.01_r, -0.02_r, 0.03_r);
  const real qd[6] = {v[0], v[1], v[2], w[0], w[1], w[2]};
  const real tau[6] = {f[0], f[1], f[2], n[0], n[1], n[2]};
  real qdd[6] = {};
  Status st = Status::invalid_argument;
  KEXPECT_NO_HEAP(st = dy::aba(m, d, q, qd, tau, qdd));
  KASSERT_TRUE(st == Status::ok);
  const Mat3 I = Idiag.asDiagonal();
  const Vec3 g_b = Q.toRotationMatrix().transpose() * m.gravity_w;
  const Vec3 dw = I.inverse() * (n - w.cross(I * w));
  const Vec3 dv = f / mass - w.cross(v) + g_b;
  for (int a = 0; a < 3; ++a) {
    KEXPECT_NEAR(qdd[a], dv[a], kTol * 10);
    KEXPECT_NEAR(qdd[3 + a], dw[a], kTol * 10 * (1 + dw.norm()));
  }
  real back[6];
  dy::rnea(m, d, q, qd, qdd, back);
  for (int k = 0; k < 6; ++k) KEXPECT_NEAR(back[k], tau[k], kTol * 20);
  // At rest with no wrench: it falls, gravity in its own frame, and does not turn.
  const real zero[6] = {};
  KEXPECT_TRUE(dy::aba(m, d, q, zero, zero, qdd) == Status::ok);
  for (int a = 0; a < 3; ++a) {
    KEXPECT_NEAR(qdd[a], g_b[a], kTol * 10);
    KEXPECT_NEAR(qdd[3 + a], 0, kTol);
  }
  // A quaternion far from unit length is refused; qdd untouched.
  real q_bad[7] = {0, 0, 0, 0, 0, 0, 0.5_r};
  qdd[0] = 42;
  KEXPECT_TRUE(dy::aba(m, d, q_bad, zero, zero, qdd) == Status::non_finite_input);
  KEXPECT_EQ(qdd[0], 42);
  // A free joint anywhere but on body 0 from the world, or with armature, is refused.
  dy::MultibodyModel<2> two;
  two.num_bodies = 2;
  two.parent[0] = -1;
  two.parent[1] = 0;
  two.joint[0] = dy::JointType::revolute;
  two.axis[0] = Vec3(0, 0, 1);
  two.joint[1] = dy::JointType::free;
  two.body[0] = two.body[1] = body(1, Vec3::Zero(), Vec3(0.1_r, 0.1_r, 0.1_r));
  KEXPECT_TRUE(dy::finish_model(two) == Status::invalid_argument);
  m.armature[0] = 0.1_r;
  KEXPECT_TRUE(dy::finish_model(m) == Status::invalid_argument);
}

// Floating-base trees (a free joint at the root, the rest random): ABA inverts RNEA, CRBA's
// (6 + n)-square mass matrix is symmetric positive definite with H qdd + bias = tau and the
// kinetic energy 1/2 qd^T H qd, and point Jacobians give the point velocities.
KTEST(Multibody, FloatingBaseTreesAreConsistent) {
  int elementary = 0;
  for (std::uint32_t tree = 0; tree < 12; ++tree) {
    dy::MultibodyModel<kMax>& m = g_model;
    m = dy::MultibodyModel<kMax>();
    random_tree(m, 2 + static_cast<int>(tree % 7), 300 + tree, true);
    KASSERT_TRUE(dy::finish_model(m) == Status::ok);
    const int n = m.num_dofs;
    KEXPECT_EQ(m.num_q, n + 1);
    elementary += elementary_joints(m);
    RngStream r(11, tree, 4);
    check_consistency(m, r);
  }
  KEXPECT_GT(elementary, 2);
}

// step_semi_implicit at legged_gym's dt = 0.005 s: implicit damping keeps a stiffly damped joint
// stable where explicit Euler diverges; a conservative pendulum's energy stays bounded; a free body
// keeps a unit quaternion and its angular momentum, and falls as the scheme's closed form says.
KTEST(Multibody, SemiImplicitEulerIsStableAndKeepsEnergy) {
  const real dt = 0.005_r, g = 9.81_r;
  dy::MultibodyModel<2> p;
  p.num_bodies = 1;
  p.parent[0] = -1;
  p.joint[0] = dy::JointType::revolute;
  p.axis[0] = Vec3(0, 1, 0);
  // A short heavy pendulum with strong damping: I = 4.1e-4 kg m^2, so explicit Euler needs
  // dt < 2 I / D = 1.6 ms; overdamped, it creeps down with a time constant D / (m g L) = 2.5 s.
  const real mass = 1, L = 0.02_r, Iyy = 1e-5_r;
  p.body[0] = body(mass, Vec3(0, 0, -L), Vec3(1e-5_r, Iyy, 1e-5_r));
  p.damping[0] = 0.5_r;
  KASSERT_TRUE(dy::finish_model(p) == Status::ok);
  dy::MultibodyData<2> d;
  const real tau = 0;
  {
    real q = 1, qd = 0;
    bool finite = true;
    for (int k = 0; k < 2000; ++k) finite = finite && dy::step_semi_implicit(p, d, &q, &qd, &tau, dt) == Status::ok;
    KEXPECT_TRUE(finite);
    // 10 s = 4 time constants: from 1 rad to about e^-4 (a little more: sin q < q on the way).
    KEXPECT_TRUE(q > 0 && q < 0.05_r);  // overdamped: no overshoot through 0
    KEXPECT_TRUE(qd < 0 && qd > -0.02_r);
    // The same accelerations taken explicitly (damping at the start of the step) blow up.
    real qe = 1, qde = 0, qdd = 0;
    int blew_up_at = -1;
    for (int k = 0; k < 2000 && blew_up_at < 0; ++k) {
      if (dy::aba(p, d, &qe, &qde, &tau, &qdd) != Status::ok || !(std::fabs(qde) < 1e3)) {
        blew_up_at = k;
        break;
      }
      qde += dt * qdd;
      qe += dt * qde;
    }
    KEXPECT_TRUE(blew_up_at > 0 && blew_up_at < 200);
  }
  {
    // Undamped: energy I qd^2 / 2 + m g L (1 - cos q) oscillates by O(dt), with no drift.
    p.damping[0] = 0;
    const real I = Iyy + mass * L * L;
    real q = 1, qd = 0;
    const real E0 = mass * g * L * (1 - std::cos(q));
    real worst = 0, early = 0, late = 0;
    for (int k = 0; k < 2000; ++k) {
      KASSERT_TRUE(dy::step_semi_implicit(p, d, &q, &qd, &tau, dt) == Status::ok);
      const real E = 0.5_r * I * qd * qd + mass * g * L * (1 - std::cos(q));
      const real rel = std::fabs(E - E0) / E0;
      worst = rel > worst ? rel : worst;
      if (k < 200) early += E / 200;
      if (k >= 1800) late += E / 200;
    }
    // The oscillation is O(w dt) with w = sqrt(m g L / I) = 22 rad/s here (w dt = 0.11): 5.4 %
    // measured; the mean energy of the last second equals the first's (explicit Euler's grows).
    KEXPECT_LT(worst, 0.08);
    KEXPECT_LT(std::fabs(late - early) / E0, 0.01);
  }
  {
    // A free body: torque-free spin about a non-principal axis in zero gravity, then a free fall.
    dy::MultibodyModel<1> m;
    m.num_bodies = 1;
    m.parent[0] = -1;
    m.joint[0] = dy::JointType::free;
    const Vec3 Idiag(0.02_r, 0.03_r, 0.05_r);
    m.body[0] = body(2, Vec3::Zero(), Idiag);
    m.gravity_w = Vec3::Zero();
    KASSERT_TRUE(dy::finish_model(m) == Status::ok);
    dy::MultibodyData<1> fd;
    real q[7] = {0, 0, 1, 0, 0, 0, 1}, qd[6] = {0.5_r, 0, 0, 1.0_r, 0.5_r, 2.0_r};
    const real zero[6] = {};
    auto L_w = [&] {
      const Quat Q = quat_from_xyzw(q + 3);
      return Vec3(rotate(Q, Vec3(Idiag.cwiseProduct(Vec3(qd[3], qd[4], qd[5])))));
    };
    const Vec3 L0 = L_w();
    for (int k = 0; k < 200; ++k) KASSERT_TRUE(dy::step_semi_implicit(m, fd, q, qd, zero, dt) == Status::ok);
    KEXPECT_NEAR(std::sqrt(q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]), 1, 1e-5);
    KEXPECT_LT((L_w() - L0).norm() / L0.norm(), 0.02);
    // It moved 1 s at 0.5 m/s along its body x axis, which turned: the world path length is 0.5 m.
    KEXPECT_LT(std::fabs(Vec3(q[0], q[1], q[2] - 1).norm() - 0.5_r), 0.05);
    // Free fall from rest: z_n = z_0 - g dt^2 n (n + 1) / 2, the scheme's exact discrete solution.
    m.gravity_w = Vec3(0, 0, -g);
    real fq[7] = {0, 0, 10, 0, 0, 0, 1}, fqd[6] = {};
    for (int k = 0; k < 200; ++k) KASSERT_TRUE(dy::step_semi_implicit(m, fd, fq, fqd, zero, dt) == Status::ok);
    KEXPECT_NEAR(fq[2], 10 - g * dt * dt * 200 * 201 / 2, 1e-3);
    KEXPECT_NEAR(fqd[2], -g * 1.0_r, 1e-3);
    // Refusals leave q and qd as they were.
    const real nan_tau[6] = {std::numeric_limits<real>::quiet_NaN(), 0, 0, 0, 0, 0};
    const real z_before = fq[2], v_before = fqd[2];
    KEXPECT_TRUE(dy::step_semi_implicit(m, fd, fq, fqd, nan_tau, dt) == Status::non_finite_input);
    KEXPECT_TRUE(dy::step_semi_implicit(m, fd, fq, fqd, zero, real(0)) == Status::invalid_argument);
    KEXPECT_TRUE(fq[2] == z_before && fqd[2] == v_before);
    KEXPECT_NO_HEAP((void)dy::step_semi_implicit(m, fd, fq, fqd, zero, dt));
  }
}

namespace {
// The bits of a real, for comparisons that must be exact (NaN or -0 included).
std::uint64_t bits_of(real v) {
  std::uint64_t b = 0;
  std::memcpy(&b, &v, sizeof(real));
  return b;
}
dy::MultibodyBatchData<kMax, 4> g_batch;
}  // namespace

// The batched ABA (4 lanes) gives every lane the bits the scalar aba gives that robot alone: on
// random fixed and floating trees with armature, damping, implicit damping and external forces,
// and lanes it refuses (a NaN torque, an off-unit quaternion) keep their outputs while the others
// are computed. The scalar path is the same kernel, so this also pins that the kernel's lane code
// (vector operations, per-lane sin/cos/sqrt) computes what its scalar instantiation does.
KTEST(Multibody, BatchedAbaIsBitIdenticalToTheScalarOne) {
  constexpr int L = 4, kDofs = dy::max_dofs<kMax>();
  using T = dy::Lanes<L>;
  int compared = 0, refused_seen = 0, elementary = 0;
  for (std::uint32_t tree = 0; tree < 24; ++tree) {
    dy::MultibodyModel<kMax>& m = g_model;
    m = dy::MultibodyModel<kMax>();
    const bool floating = tree % 2 == 1;
    random_tree(m, (floating ? 2 : 3) + static_cast<int>(tree % 6), tree, floating);
    KASSERT_TRUE(dy::finish_model(m) == Status::ok);
    elementary += elementary_joints(m);
    RngStream r(11, tree, 3);
    real q[L][kDofs + 1] = {}, qd[L][kDofs] = {}, tau[L][kDofs] = {};
    T qb[kDofs + 1] = {}, qdb[kDofs] = {}, taub[kDofs] = {}, qddb[kDofs] = {};
    dy::detail::LaneVec6<T> fb[kMax] = {};
    Vec6 f[L][kMax];
    const bool with_f = tree % 3 == 0;
    const real h = tree % 4 == 0 ? 0.005_r : 0;
    for (int l = 0; l < L; ++l) {
      random_state(m, r, q[l], qd[l]);
      for (int k = 0; k < m.num_dofs; ++k) tau[l][k] = r.uniform(-5, 5);
      for (int b = 0; b < m.num_bodies; ++b)
        for (int a = 0; a < 6; ++a) f[l][b][a] = with_f ? r.uniform(-2, 2) : 0;
    }
    // Lane 2 of every third tree gets a NaN torque, lane 3 of floating ones an off-unit quaternion.
    const bool nan_lane = tree % 3 == 1;
    if (nan_lane) tau[2][m.num_dofs - 1] = std::numeric_limits<real>::quiet_NaN();
    const bool bad_quat = floating && tree % 4 == 1;
    if (bad_quat)
      for (int a = 3; a < 7; ++a) q[3][m.q_index[0] + a] *= 1.01_r;
    for (int l = 0; l < L; ++l) {
      for (int k = 0; k < m.num_q; ++k) qb[k][l] = q[l][k];
      for (int k = 0; k < m.num_dofs; ++k) {
        qdb[k][l] = qd[l][k];
        taub[k][l] = tau[l][k];
        qddb[k][l] = real(-7);  // kept where a lane is refused
      }
      for (int b = 0; b < m.num_bodies; ++b)
        for (int a = 0; a < 6; ++a) fb[b][a][l] = f[l][b][a];
    }
    unsigned refused = 0;
    KEXPECT_NO_HEAP(refused = dy::aba_batch(m, g_batch, qb, qdb, taub, qddb, with_f ? fb : nullptr, h));
    for (int l = 0; l < L; ++l) {
      real want[kDofs] = {};
      const Status st = dy::aba(m, g_data, q[l], qd[l], tau[l], want, with_f ? f[l] : nullptr, h);
      KEXPECT_EQ(((refused >> l) & 1u) != 0, st != Status::ok);
      if (st != Status::ok) {
        ++refused_seen;
        for (int k = 0; k < m.num_dofs; ++k) KEXPECT_EQ(qddb[k][l], real(-7));
        continue;
      }
      for (int k = 0; k < m.num_dofs; ++k) {
        KEXPECT_EQ(bits_of(qddb[k][l]), bits_of(want[k]));
        ++compared;
      }
    }
    if (nan_lane) {
      KEXPECT_TRUE(((refused >> 2) & 1u) != 0);
    }
    if (bad_quat) {
      KEXPECT_TRUE(((refused >> 3) & 1u) != 0);
    }
  }
  KEXPECT_GT(compared, 500);
  KEXPECT_GT(refused_seen, 8);
  KEXPECT_GT(elementary, 5);
}
