// Contacts with friction, joint limits and joint dry friction (dynamics/contact.hpp), on the host
// and the emulated MCU: a sphere bounces to the height its restitution gives; a box on a 20-degree
// slope stays with mu = 0.5 and slides with g (sin - mu cos) with mu = 0.2; a pendulum comes to rest
// on its limit with the limit carrying gravity's torque; a joint's dry friction holds below its
// breakaway torque and lets the excess accelerate above it; a floating tree spawned in the ground
// under random torques stays finite; refusals leave the state alone; no heap.
#include <cmath>

#include "kestrel/dynamics/contact.hpp"
#include "kestrel/kernel/rng.hpp"
#include "ktest.hpp"
#include "test_scratch.hpp"

using namespace kestrel;
namespace dy = kestrel::dynamics;

namespace {

constexpr real kG = 9.81_r;

dy::SpatialInertia solid(real mass, const Vec3& diag) {
  dy::SpatialInertia b;
  b.mass = mass;
  b.com = Vec3::Zero();
  b.inertia_com = diag.asDiagonal();
  return b;
}

// One free body (a floating base with no children).
void free_body(dy::MultibodyModel<1>& m, const dy::SpatialInertia& b) {
  m.num_bodies = 1;
  m.parent[0] = -1;
  m.joint[0] = dy::JointType::free;
  m.body[0] = b;
  KASSERT_EQ(dy::finish_model(m), Status::ok);
}

using FreeData = dy::ConstraintData<1, 8>;

// A test's model, its dynamics scratch and the solver's data, taken together from the shared test
// scratch (test_scratch.hpp): up to 14 KiB each (a five-body tree with 8 contacts), too big for an
// MCU test's stack and, as statics of every test, 46 KiB of the core test image's RAM.
template <int kBodies, int kContacts>
struct World {
  dy::MultibodyModel<kBodies> m;
  dy::MultibodyData<kBodies> d;
  dy::ConstraintData<kBodies, kContacts> cd;
};

// A floating base with two legs of two links each (bodies 1-2 and 3-4), joint axes along y; the
// joint kinds, axes and offsets vary per test through `leg`.
template <class Leg>
void two_legged_tree(dy::MultibodyModel<5>& m, Leg leg) {
  m.num_bodies = 5;
  m.parent[0] = -1;
  m.joint[0] = dy::JointType::free;
  m.body[0] = solid(5, Vec3(0.05_r, 0.1_r, 0.1_r));
  const int parents[5] = {-1, 0, 1, 0, 3};
  for (int i = 1; i < 5; ++i) {
    m.parent[i] = parents[i];
    m.joint[i] = dy::JointType::revolute;
    m.axis[i] = Vec3(0, 1, 0);
    leg(i);
  }
}

// Steps a free body with one shape over a half-space; returns the status of the last step.
Status step_free(const dy::MultibodyModel<1>& m, dy::MultibodyData<1>& d, FreeData& cd, const dy::CollisionShape& shape,
                 const dy::HalfSpace& ground, real* q, real* qd, real dt) {
  dy::ContactPoint contacts[8];
  dy::forward_kinematics(m, d, q, cd.X_world);
  const int found = dy::collide_halfspace(&shape, 1, cd.X_world, ground, real(0.05), contacts, 8);
  const real tau[6] = {};
  return dy::step_constrained(m, d, cd, q, qd, tau, dt, contacts, found);
}

}  // namespace

KTEST(Contact, SphereBouncesToTheHeightItsRestitutionGives) {
  auto& w = ktest::scratch<World<1, 8>>();
  auto& m = w.m;
  auto& d = w.d;
  auto& cd = w.cd;
  const real r = 0.1_r;
  free_body(m, solid(1, Vec3::Constant(real(0.4) * r * r)));
  dy::CollisionShape ball;
  ball.body = 0;
  ball.size = Vec3(r, 0, 0);
  for (real e : {real(0.5), real(0)}) {
    ball.restitution = e;
    dy::HalfSpace ground;
    ground.restitution = e;  // combined: the mean, e
    real q[7] = {0, 0, 1 + r, 0, 0, 0, 1}, qd[6] = {};
    bool landed = false;
    real apex = 0;
    for (int k = 0; k < 2000; ++k) {  // 2 s at 1 ms: falls 1 m in 0.45 s, rises again
      KASSERT_EQ(step_free(m, d, cd, ball, ground, q, qd, 1e-3_r), Status::ok);
      if (!landed && qd[2] > 0) landed = true;
      if (landed) apex = std::max(apex, q[2] - r);
      KEXPECT_GE(q[2] - r, -real(2e-3));  // never sinks
    }
    KEXPECT_TRUE(landed || e == 0);
    // Newton's law: the rebound speed e v, the height e^2 h (1 m dropped).
    KEXPECT_CLOSE(apex, e * e, 0.01, 0, "apex above the ground (m)");
  }
}

KTEST(Contact, BoxOnASlopeStaysOrSlidesByCoulomb) {
  auto& w = ktest::scratch<World<1, 8>>();
  auto& m = w.m;
  auto& d = w.d;
  auto& cd = w.cd;
  const real h = 0.1_r, mass = 2;
  free_body(m, solid(mass, Vec3::Constant(mass * (h * h + h * h) * 4 / 12)));
  const real theta = 20 * kPi / 180;
  dy::HalfSpace slope;  // z = x tan(theta): rising toward +x
  slope.normal_w = Vec3(-std::sin(theta), 0, std::cos(theta));
  const Vec3 downhill(-std::cos(theta), 0, -std::sin(theta));
  dy::CollisionShape box;
  box.body = 0;
  box.type = dy::ShapeType::box;
  box.size = Vec3(h, h, h);
  for (real mu : {real(0.5), real(0.2)}) {
    box.friction = slope.friction = mu;
    // The box's z along the slope's normal (a turn of -theta about y), its bottom face on the slope.
    const Vec3 c = h * slope.normal_w;
    real q[7] = {c[0], c[1], c[2], 0, std::sin(-theta / 2), 0, std::cos(-theta / 2)}, qd[6] = {};
    const real dt = 0.005_r;  // legged_gym's physics step
    Vec3 force_sum = Vec3::Zero();
    for (int k = 0; k < 200; ++k) {  // 1 s
      KASSERT_EQ(step_free(m, d, cd, box, slope, q, qd, dt), Status::ok);
      if (k == 199)
        for (int i = 0; i < 4; ++i) force_sum += cd.contact_force_w[i];
    }
    const Vec3 moved = Vec3(q[0], q[1], q[2]) - c;
    // The base's linear velocity is in its own frame: turned to the world's.
    const Vec3 v_w = rotate(quat_from_xyzw(q + 3), Vec3(qd[0], qd[1], qd[2]));
    if (mu > std::tan(theta)) {
      KEXPECT_LT(moved.norm(), real(1e-3));  // static friction holds (tan 20 deg = 0.36 < 0.5)
      // The four corners together carry the weight.
      KEXPECT_CLOSE(force_sum[2], mass * kG, 0, 0.01, "vertical contact force (N)");
      KEXPECT_CLOSE(force_sum[0], 0, 0.01 * mass * kG, 0, "horizontal contact force (N)");
    } else {
      const real a = kG * (std::sin(theta) - mu * std::cos(theta));  // 1.512 m/s^2
      KEXPECT_CLOSE(v_w.dot(downhill), a * 1, 0, 0.02, "speed down the slope after 1 s (m/s)");
      KEXPECT_CLOSE(moved.dot(downhill), a / 2, 0, 0.03, "distance down the slope after 1 s (m)");
      KEXPECT_LT(std::fabs(moved.dot(slope.normal_w)), real(2e-3));  // slides on its face, does not tip
      KEXPECT_LT(std::fabs(v_w[1]), real(1e-3));
    }
  }
}

KTEST(Contact, PendulumComesToRestOnItsLimit) {
  auto& w = ktest::scratch<World<1, 1>>();
  auto& m = w.m;
  auto& d = w.d;
  auto& cd = w.cd;
  const real mass = 1, l = 0.5_r;
  m.num_bodies = 1;
  m.parent[0] = -1;
  m.joint[0] = dy::JointType::revolute;
  m.axis[0] = Vec3(0, 1, 0);
  m.body[0] = solid(mass, Vec3::Constant(real(0.01)));
  m.body[0].com = Vec3(l, 0, 0);  // gravity turns it toward +q
  m.has_limit[0] = true;
  m.q_min[0] = -0.5_r;
  m.q_max[0] = 0.5_r;
  m.damping[0] = 0.05_r;
  KASSERT_EQ(dy::finish_model(m), Status::ok);
  real q[1] = {0}, qd[1] = {0};
  const real tau[1] = {0};
  real deepest = 0;
  for (int k = 0; k < 600; ++k) {  // 3 s at 5 ms
    KASSERT_EQ(dy::step_constrained(m, d, cd, q, qd, tau, 0.005_r, nullptr, 0), Status::ok);
    deepest = std::max(deepest, q[0] - m.q_max[0]);
  }
  KEXPECT_LT(deepest, real(2e-3));  // hits the stop without passing it
  KEXPECT_CLOSE(q[0], m.q_max[0], 1e-3, 0, "rest angle (rad)");
  KEXPECT_LT(std::fabs(qd[0]), real(1e-3));
  // At rest the limit carries gravity's torque about the axis, m g l cos(q).
  KEXPECT_CLOSE(cd.joint_constraint_force[0], -mass * kG * l * std::cos(q[0]), 0, 0.01, "limit torque (N m)");
}

KTEST(Contact, JointDryFrictionHoldsBelowBreakawayAndSlipsAbove) {
  auto& w = ktest::scratch<World<1, 1>>();
  auto& m = w.m;
  auto& d = w.d;
  auto& cd = w.cd;
  m.num_bodies = 1;
  m.parent[0] = -1;
  m.joint[0] = dy::JointType::revolute;
  m.axis[0] = Vec3(0, 0, 1);  // vertical: gravity does no work
  m.body[0] = solid(2, Vec3(0.1_r, 0.1_r, 0.2_r));
  m.friction_loss[0] = 1;  // N m
  KASSERT_EQ(dy::finish_model(m), Status::ok);
  for (real torque : {real(0.8), real(1.5), real(-1.5)}) {
    real q[1] = {0}, qd[1] = {0};
    const real tau[1] = {torque};
    for (int k = 0; k < 200; ++k)  // 1 s
      KASSERT_EQ(dy::step_constrained(m, d, cd, q, qd, tau, 0.005_r, nullptr, 0), Status::ok);
    if (std::fabs(torque) < 1) {
      KEXPECT_LT(std::fabs(qd[0]), real(1e-5));
      KEXPECT_LT(std::fabs(q[0]), real(1e-5));
      KEXPECT_CLOSE(cd.joint_constraint_force[0], -torque, 0, 1e-3, "friction torque at rest (N m)");
    } else {
      const real excess = torque - std::copysign(real(1), torque);
      KEXPECT_CLOSE(qd[0], excess / real(0.2), 0, 0.01, "speed after 1 s (rad/s)");  // (tau - F) / I t
    }
  }
}

KTEST(Contact, FloatingTreeSpawnedInTheGroundStaysFinite) {
  // A base with two legs of two links each, spheres on every link, spawned up to 20 cm deep in the
  // ground, under random joint torques of up to 50 N m with limits and dry friction.
  auto& w = ktest::scratch<World<5, 8>>();
  auto& m = w.m;
  auto& d = w.d;
  auto& cd = w.cd;
  two_legged_tree(m, [&m](int i) {
    m.X_tree[i].r = m.parent[i] == 0 ? Vec3(i == 1 ? 0.2_r : -0.2_r, 0, 0) : Vec3(0, 0, -0.2_r);
    m.body[i] = solid(0.5_r, Vec3::Constant(real(2e-3)));
    m.body[i].com = Vec3(0, 0, -0.1_r);
    m.has_limit[i] = true;
    m.q_min[i] = -1.5_r;
    m.q_max[i] = 1.5_r;
    m.friction_loss[i] = 0.2_r;
    m.damping[i] = 0.1_r;
  });
  KASSERT_EQ(dy::finish_model(m), Status::ok);
  dy::CollisionShape shapes[5];
  for (int i = 0; i < 5; ++i) {
    shapes[i].body = i;
    shapes[i].type = i == 0 ? dy::ShapeType::box : dy::ShapeType::sphere;
    shapes[i].size = i == 0 ? Vec3(0.25_r, 0.1_r, 0.05_r) : Vec3(0.03_r, 0, 0);
    shapes[i].p_b = i == 0 ? Vec3::Zero() : Vec3(0, 0, -0.2_r);
  }
  RngStream rng(2026, 7, 3);
  for (int trial = 0; trial < 4; ++trial) {
    real q[11] = {0, 0, rng.uniform(-0.2_r, 0.3_r), 0, 0, 0, 1}, qd[10] = {};
    for (int k = 0; k < 300; ++k) {
      real tau[10] = {};
      for (int j = 6; j < 10; ++j) tau[j] = rng.uniform(-50, 50);
      dy::ContactPoint contacts[8];
      dy::forward_kinematics(m, d, q, cd.X_world);
      const int found = dy::collide_halfspace(shapes, 5, cd.X_world, dy::HalfSpace(), real(0.02), contacts, 8);
      KASSERT_EQ(dy::step_constrained(m, d, cd, q, qd, tau, 0.005_r, contacts, std::min(found, 8)), Status::ok);
      KEXPECT_TRUE(all_finite(q, 11) && all_finite(qd, 10));
    }
    KEXPECT_GT(q[2], real(-0.05));  // pushed out of the ground, not fallen through it
  }
}

KTEST(Contact, RefusalsLeaveTheStateAlone) {
  auto& w = ktest::scratch<World<1, 8>>();
  auto& m = w.m;
  auto& d = w.d;
  auto& cd = w.cd;
  free_body(m, solid(1, Vec3::Constant(real(0.01))));
  real q[7] = {0, 0, 0.05_r, 0, 0, 0, 1}, qd[6] = {0, 0, -1, 0, 0, 0};
  const real q0[7] = {0, 0, 0.05_r, 0, 0, 0, 1};
  real tau[6] = {};
  dy::ContactPoint c;
  c.body = 0;
  c.separation_m = -0.01_r;
  auto unchanged = [&] {
    for (int k = 0; k < 7; ++k) KEXPECT_EQ(q[k], q0[k]);
    KEXPECT_EQ(qd[2], real(-1));
  };
  KEXPECT_EQ(dy::step_constrained(m, d, cd, q, qd, tau, 0, &c, 1), Status::invalid_argument);
  KEXPECT_EQ(dy::step_constrained(m, d, cd, q, qd, tau, 0.005_r, &c, 9), Status::invalid_argument);  // > capacity
  KEXPECT_EQ(dy::step_constrained(m, d, cd, q, qd, tau, 0.005_r, nullptr, 1), Status::invalid_argument);
  dy::ContactPoint bad = c;
  bad.normal_w = Vec3(0, 0, 2);
  KEXPECT_EQ(dy::step_constrained(m, d, cd, q, qd, tau, 0.005_r, &bad, 1), Status::invalid_argument);
  bad = c;
  bad.friction = -1;
  KEXPECT_EQ(dy::step_constrained(m, d, cd, q, qd, tau, 0.005_r, &bad, 1), Status::invalid_argument);
  bad = c;
  bad.restitution = 1.5_r;
  KEXPECT_EQ(dy::step_constrained(m, d, cd, q, qd, tau, 0.005_r, &bad, 1), Status::invalid_argument);
  bad = c;
  bad.body = 1;
  KEXPECT_EQ(dy::step_constrained(m, d, cd, q, qd, tau, 0.005_r, &bad, 1), Status::invalid_argument);
  bad = c;
  bad.separation_m = std::numeric_limits<real>::quiet_NaN();
  KEXPECT_EQ(dy::step_constrained(m, d, cd, q, qd, tau, 0.005_r, &bad, 1), Status::invalid_argument);
  tau[2] = std::numeric_limits<real>::infinity();
  KEXPECT_EQ(dy::step_constrained(m, d, cd, q, qd, tau, 0.005_r, &c, 1), Status::non_finite_input);
  unchanged();
  tau[2] = 0;
  // And the same step accepted pushes the body out: the normal impulse stops the fall.
  KEXPECT_NO_HEAP(KEXPECT_EQ(dy::step_constrained(m, d, cd, q, qd, tau, 0.005_r, &c, 1), Status::ok));
  KEXPECT_GE(qd[2], real(0));
  KEXPECT_GT(cd.contact_force_w[0][2], real(0));
}

KTEST(Contact, WithoutConstraintsItIsTheSemiImplicitStep) {
  // The mass-matrix path (CRBA and the branch-sparse L^T D L solve) against ABA's: a floating base
  // with two two-link legs, damped joints, random states and torques, one step each.
  auto& w = ktest::scratch<World<5, 1>>();
  auto& m = w.m;
  auto& d = w.d;
  auto& cd = w.cd;
  two_legged_tree(m, [&m](int i) {
    m.joint[i] = i % 2 ? dy::JointType::revolute : dy::JointType::prismatic;
    m.axis[i] = i < 3 ? Vec3(0, 1, 0) : Vec3(0.6_r, 0, 0.8_r);
    m.X_tree[i].r = Vec3(0.1_r * i, -0.05_r, -0.2_r);
    m.body[i] = solid(0.5_r + 0.1_r * i, Vec3(2e-3_r, 3e-3_r, 1e-3_r));
    m.body[i].com = Vec3(0.01_r, 0, -0.1_r);
    m.damping[i] = 0.3_r;
    m.armature[i] = 0.01_r;
  });
  KASSERT_EQ(dy::finish_model(m), Status::ok);
  RngStream rng(2026, 11, 5);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec4 quat = Vec4(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)).normalized();
    real q[11] = {rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1), quat[0], quat[1], quat[2], quat[3]};
    real qd[10], tau[10];
    for (int k = 7; k < 11; ++k) q[k] = rng.uniform(-1, 1);
    for (int k = 0; k < 10; ++k) {
      qd[k] = rng.uniform(-2, 2);
      tau[k] = rng.uniform(-5, 5);
    }
    real q2[11], qd2[10], qd0[10];
    for (int k = 0; k < 11; ++k) q2[k] = q[k];
    for (int k = 0; k < 10; ++k) qd2[k] = qd0[k] = qd[k];
    real qdd[10];
    KASSERT_EQ(dy::step_semi_implicit(m, d, q, qd, tau, 0.005_r, qdd), Status::ok);
    KASSERT_EQ(dy::step_constrained(m, d, cd, q2, qd2, tau, 0.005_r, nullptr, 0), Status::ok);
    const double tol = sizeof(real) == 4 ? 2e-4 : 1e-10;
    for (int k = 0; k < 10; ++k) {
      KEXPECT_CLOSE(qd2[k], qd[k], tol, tol, "velocity after one step");
      // The accelerations themselves (the velocity change over dt): float rounding of qd (~2) / dt.
      KEXPECT_CLOSE((qd2[k] - qd0[k]) / 0.005_r, qdd[k], sizeof(real) == 4 ? 2e-3 : 1e-8, 1e-4, "acceleration");
    }
    for (int k = 0; k < 11; ++k) KEXPECT_CLOSE(q2[k], q[k], tol, tol, "position after one step");
  }
}

KTEST(Contact, ARowNothingCanMoveGetsNoImpulse) {
  // A welded base (no degrees of freedom) in the ground with an arm on a hinge above it: the
  // base's contact rows are all zero and must neither divide by zero nor stop the arm's step.
  auto& w = ktest::scratch<World<2, 2>>();
  auto& m = w.m;
  auto& d = w.d;
  auto& cd = w.cd;
  m.num_bodies = 2;
  m.parent[0] = -1;
  m.joint[0] = dy::JointType::fixed;
  m.body[0] = solid(3, Vec3::Constant(real(0.05)));
  m.parent[1] = 0;
  m.joint[1] = dy::JointType::revolute;
  m.axis[1] = Vec3(0, 1, 0);
  m.X_tree[1].r = Vec3(0, 0, 0.5_r);
  m.body[1] = solid(1, Vec3::Constant(real(0.01)));
  m.body[1].com = Vec3(0.3_r, 0, 0);
  KASSERT_EQ(dy::finish_model(m), Status::ok);
  dy::ContactPoint c[2];
  c[0].body = 0;
  c[0].separation_m = -0.01_r;
  c[1] = c[0];
  c[1].point_w = Vec3(0.1_r, 0, 0);
  real q[1] = {0}, qd[1] = {0};
  const real tau[1] = {0};
  KASSERT_EQ(dy::step_constrained(m, d, cd, q, qd, tau, 0.005_r, c, 2), Status::ok);
  KEXPECT_TRUE(all_finite(q, 1) && all_finite(qd, 1));
  KEXPECT_GT(qd[0], real(0));  // the arm falls (gravity turns it toward +q about y)
  KEXPECT_EQ(cd.contact_force_w[0][2], real(0));
}

KTEST(Contact, ImplicitDriveGainsKeepALightJointStable) {
  // A light link (I = 0.003 kg m^2 about a vertical axis) under PD kp = 40 N m/rad, kd = 2 N m s/rad
  // at h = 5 ms: kd h / I = 3.3 > 2, so the explicit PD diverges; taken implicitly it settles.
  auto& w = ktest::scratch<World<1, 1>>();
  auto& m = w.m;
  auto& d = w.d;
  auto& cd = w.cd;
  m.num_bodies = 1;
  m.parent[0] = -1;
  m.joint[0] = dy::JointType::revolute;
  m.axis[0] = Vec3(0, 0, 1);
  m.body[0] = solid(0.2_r, Vec3(0.003_r, 0.003_r, 0.003_r));
  KASSERT_EQ(dy::finish_model(m), Status::ok);
  const real kp[1] = {40}, kd[1] = {2}, target = 0.5_r;
  for (int implicit = 0; implicit < 2; ++implicit) {
    real q[1] = {0}, qd[1] = {0};
    real largest = 0;
    for (int k = 0; k < 200; ++k) {
      const real tau[1] = {kp[0] * (target - q[0]) - kd[0] * qd[0]};
      const Status st = implicit ? dy::step_constrained(m, d, cd, q, qd, tau, 0.005_r, nullptr, 0, dy::ConstraintParams(), kp, kd)
                                 : dy::step_constrained(m, d, cd, q, qd, tau, 0.005_r, nullptr, 0);
      if (st != Status::ok) break;
      largest = std::max(largest, std::fabs(q[0]));
    }
    if (implicit) {
      KEXPECT_CLOSE(q[0], target, 1e-4, 0, "settled angle (rad)");
      KEXPECT_LT(largest, target * real(1.05));  // overdamped: no real overshoot
    } else {
      KEXPECT_GT(largest, real(10));  // the explicit PD's divergence the implicit gains remove
    }
  }
  real q[1] = {0}, qd[1] = {0};
  const real tau[1] = {0}, bad_kp[1] = {-1};
  KEXPECT_EQ(dy::step_constrained(m, d, cd, q, qd, tau, 0.005_r, nullptr, 0, dy::ConstraintParams(), bad_kp, kd),
             Status::invalid_argument);
}

namespace {

// A gripper and a cube as one model, a forest: a carriage on a vertical slide from the world (body
// 0) with two fingers on horizontal slides (bodies 1, 2; a box pad each), and a free 2.5 cm cube
// (body 3, its own root), resting on the ground between the open pads.
struct Gripper {
  static constexpr int kBodies = 4;
  dy::MultibodyModel<kBodies> m;
  dy::MultibodyData<kBodies> d;
  dy::ConstraintData<kBodies, 16> cd;
  dy::WarmStart<60> warm;
  dy::CollisionShape pad[2], cube;
  dy::HalfSpace ground;
  static constexpr real kCubeHalf = 0.0125_r, kCubeMass = 0.03_r;  // 3-D printed PLA, 25 mm: ~30 g
  real q[10] = {}, qd[9] = {};
  real kp[9] = {}, kd[9] = {}, target[3] = {};

  void build(real friction) {
    m.num_bodies = kBodies;
    m.parent[0] = -1;
    m.joint[0] = dy::JointType::prismatic;
    m.axis[0] = Vec3(0, 0, 1);
    m.X_tree[0].r = Vec3(0, 0, kCubeHalf);  // the carriage's origin at the cube's centre height
    m.body[0] = solid(0.5_r, Vec3(1e-3_r, 1e-3_r, 1e-3_r));
    for (int f = 0; f < 2; ++f) {
      m.parent[1 + f] = 0;
      m.joint[1 + f] = dy::JointType::prismatic;
      m.axis[1 + f] = Vec3(0, f == 0 ? real(1) : real(-1), 0);  // each opens outward
      m.body[1 + f] = solid(0.02_r, Vec3(2e-6_r, 2e-6_r, 2e-6_r));
      pad[f].body = 1 + f;
      pad[f].type = dy::ShapeType::box;
      pad[f].size = Vec3(0.008_r, 0.002_r, 0.008_r);  // 16 x 16 mm face, 4 mm thick
      pad[f].friction = friction;
    }
    m.parent[3] = -1;
    m.joint[3] = dy::JointType::free;
    m.body[3] = solid(kCubeMass, Vec3::Constant(kCubeMass * 8 * kCubeHalf * kCubeHalf / 12));
    KASSERT_EQ(dy::finish_model(m), Status::ok);
    KASSERT_EQ(m.num_dofs, 9);  // 1 + 2 + 6: capacity 4 + 5 holds one free joint besides three sliders
    cube.body = 3;
    cube.type = dy::ShapeType::box;
    cube.size = Vec3::Constant(kCubeHalf);
    cube.friction = friction;
    ground.friction = friction;
    for (real& x : q) x = 0;
    for (real& x : qd) x = 0;
    q[0] = 0;                       // carriage at the cube's centre height
    q[1] = q[2] = 0.025_r;          // pads open: inner faces 25 - 2 = 23 mm from the centre
    q[3] = 0, q[4] = 0, q[5] = kCubeHalf, q[9] = 1;  // the cube on the ground (free joint: q[3..9])
    kp[0] = 2000, kd[0] = 100;      // a stiff lift
    kp[1] = kp[2] = 100, kd[1] = kd[2] = 5;
    target[0] = 0, target[1] = target[2] = 0.025_r;
    warm.count = 0;
  }

  // One 5 ms step with the pads' and cube's contacts; the drives' PD torques, taken implicitly.
  Status step() {
    static constexpr real kDt = 0.005_r;
    dy::forward_kinematics(m, d, q, cd.X_world);
    dy::ContactPoint contacts[16];
    int n = 0;
    for (int f = 0; f < 2; ++f)
      n += dy::collide_shapes(pad[f], cd.X_world[pad[f].body], cube, cd.X_world[3], 0.002_r, contacts + n, 16 - n, 16 * f);
    n += dy::collide_halfspace(&cube, 1, cd.X_world, ground, 0.002_r, contacts + n, 16 - n, 4);
    if (n > 16) return Status::invalid_argument;
    real tau[9] = {};
    for (int k = 0; k < 3; ++k) tau[k] = kp[k] * (target[k] - q[k]) - kd[k] * qd[k];
    tau[0] += (m.body[0].mass + m.body[1].mass + m.body[2].mass) * kG;  // the gripper's own weight, fed forward
    dy::ConstraintParams p;
    return dy::step_constrained(m, d, cd, q, qd, tau, kDt, contacts, n, p, kp, kd, &warm);
  }
};

}  // namespace

// The grasp of the arm issue, held by contact forces and friction alone: the pads close on the cube
// with a squeeze of kp x (their overlap target), the carriage lifts by 5 cm, and the cube rises with
// it and stays in the pads while held; with too little friction for the squeeze (2 mu F < m g) the
// same motions leave it on the ground.
KTEST(Contact, AFrictionGraspLiftsTheCubeAndHoldsIt) {
  Gripper& g = ktest::scratch<Gripper>();  // 24 KiB: the largest of these tests
  for (int variant = 0; variant < 2; ++variant) {
    const real mu = variant == 0 ? real(1) : real(0.1);
    g.build(mu);
    int k = 0;
    auto run = [&](int steps) {
      for (int i = 0; i < steps; ++i, ++k) KASSERT_EQ(g.step(), Status::ok);
    };
    run(40);  // settle on the ground
    KEXPECT_CLOSE(g.q[5], Gripper::kCubeHalf, 1e-3, 0, "cube resting height (m)");
    // Close: each pad's target 5 mm inside the cube's face, a squeeze of 100 x 0.0055 + the
    // remaining gap ~ 0.6 N per pad.
    g.target[1] = g.target[2] = Gripper::kCubeHalf + 0.002_r - 0.0055_r;
    run(100);
    const real squeeze_N = g.kp[1] * (g.q[1] - g.target[1]);
    KEXPECT_GT(squeeze_N, real(0.4));
    for (int i = 1; i <= 100; ++i) {  // lift 5 cm in 0.5 s, smoothly (peak 1.2 m/s^2)
      const real u = real(i) / 100;
      g.target[0] = 0.05_r * u * u * (3 - 2 * u);
      run(1);
    }
    run(100);
    const real lifted = g.q[5] - Gripper::kCubeHalf;
    const real held_z = g.q[5];
    run(200);  // hold 1 s
    const real slip = held_z - g.q[5];
    if (mu == 1) {
      // 2 mu F = 1.1 N against m g = 0.29 N: held.
      KEXPECT_CLOSE(g.q[0], 0.05, 2e-3, 0, "carriage height (m)");
      KEXPECT_CLOSE(lifted, g.q[0], 2e-3, 0, "cube lifted with the carriage (m)");
      KEXPECT_LT(std::fabs(slip), real(5e-4));  // no slip while held
      KEXPECT_LT(std::fabs(g.qd[6]) + std::fabs(g.qd[7]) + std::fabs(g.qd[8]), real(0.05));  // no spin
    } else {
      // 2 mu F ~ 0.11 N < m g: the cube slides out and stays on the ground.
      KEXPECT_LT(g.q[5], Gripper::kCubeHalf + 2e-3_r);
    }
  }
}

// Two-body contacts between shapes: a sphere resting on a box on a body, a box's corner in another
// box, segments' closest points; the normals push `body` out of `body_b`.
KTEST(Contact, ShapePairsGiveTheirContacts) {
  dy::CollisionShape box, ball, cap;
  box.body = 1;
  box.type = dy::ShapeType::box;
  box.size = Vec3(0.1_r, 0.2_r, 0.05_r);
  ball.body = 0;
  ball.size = Vec3(0.02_r, 0, 0);
  dy::Transform X_box, X_ball;  // identity: the box at the origin
  X_ball.r = Vec3(0.03_r, -0.01_r, 0.05_r + 0.015_r);  // 5 mm into the box's top face
  dy::ContactPoint c[16];
  KASSERT_EQ(dy::collide_shapes(ball, X_ball, box, X_box, 0, c, 16, 32), 1);
  KEXPECT_EQ(c[0].body, 0);
  KEXPECT_EQ(c[0].body_b, 1);
  KEXPECT_CLOSE(c[0].separation_m, -0.005, 1e-6, 0, "sphere in box (m)");
  KEXPECT_CLOSE(c[0].normal_w[2], 1, 1e-6, 0, "normal up");
  KEXPECT_CLOSE(c[0].point_w[2], 0.045, 1e-6, 0, "the sphere's deepest point");
  KEXPECT_EQ(c[0].key, 32);
  // The same pair the other way round: the box is pushed down.
  KASSERT_EQ(dy::collide_shapes(box, X_box, ball, X_ball, 0, c, 16), 1);
  KEXPECT_CLOSE(c[0].normal_w[2], -1, 1e-6, 0, "normal down");
  // Beside the box, beyond the margin: nothing; within it: a speculative contact.
  X_ball.r = Vec3(0.13_r, 0, 0);
  KEXPECT_EQ(dy::collide_shapes(ball, X_ball, box, X_box, 0.005_r, c, 16), 0);
  KASSERT_EQ(dy::collide_shapes(ball, X_ball, box, X_box, 0.02_r, c, 16), 1);
  KEXPECT_CLOSE(c[0].separation_m, 0.01, 1e-6, 0, "gap (m)");
  KEXPECT_CLOSE(c[0].normal_w[0], 1, 1e-6, 0, "normal out of the +x face");
  // A 2 cm cube on the box's top face, 1 mm in: its four bottom corners, nothing of the box's.
  dy::CollisionShape cube = box;
  cube.body = 0;
  cube.size = Vec3::Constant(0.01_r);
  dy::Transform X_cube;
  X_cube.r = Vec3(0, 0, 0.05_r + 0.009_r);
  const int n = dy::collide_shapes(cube, X_cube, box, X_box, 0, c, 16);
  KASSERT_EQ(n, 4);
  for (int i = 0; i < n; ++i) {
    KEXPECT_CLOSE(c[i].separation_m, -0.001, 1e-6, 0, "corner depth (m)");
    KEXPECT_CLOSE(c[i].normal_w[2], 1, 1e-6, 0, "corner normal");
    KEXPECT_LT(c[i].key, 8);
  }
  // Two capsules crossing at right angles (x and y), 4 mm apart at their cores with radii 5 mm:
  // 6 mm deep.
  cap.body = 0;
  cap.type = dy::ShapeType::capsule;
  cap.size = Vec3(0.005_r, 0.1_r, 0);
  dy::CollisionShape cap2 = cap;
  cap2.body = -1;
  cap.R_b << 0, 0, 1, 0, 1, 0, -1, 0, 0;    // its z along the world's x
  cap2.R_b << 1, 0, 0, 0, 0, -1, 0, 1, 0;  // its z along the world's y
  dy::Transform X_cap;
  X_cap.r = Vec3(0.02_r, 0, 0.004_r);
  KASSERT_EQ(dy::collide_shapes(cap, X_cap, cap2, dy::Transform(), 0, c, 16), 1);
  KEXPECT_EQ(c[0].body_b, -1);
  KEXPECT_CLOSE(c[0].separation_m, -0.006, 1e-6, 0, "capsule overlap (m)");
  KEXPECT_CLOSE(c[0].normal_w[2], 1, 1e-6, 0, "capsule normal");
  KEXPECT_CLOSE(c[0].point_w[0], 0, 1e-6, 0, "at the crossing");
  KEXPECT_CLOSE(c[0].point_w[2], 0.005, 1e-6, 0, "on b's surface");
}

// A convex shape (a collision mesh's hull points) against a half-space: the vertices below the
// margin, at most kMaxConvexContacts of them, the deepest; a cube's 8 corners resting on the
// plane give its 4 bottom corners, and a 12-point shape tilted into the ground gives its 8
// deepest. The points are where a box of the same size has its corners.
KTEST(Contact, ConvexPointsCollideWithAHalfSpaceThroughTheirDeepestVertices) {
  Vec3 corners[8];
  for (int k = 0; k < 8; ++k) corners[k] = Vec3((k & 1) ? 0.1_r : -0.1_r, (k & 2) ? 0.1_r : -0.1_r, (k & 4) ? 0.1_r : -0.1_r);
  dy::CollisionShape cube;
  cube.body = 0;
  cube.type = dy::ShapeType::convex;
  cube.points = corners;
  cube.num_points = 8;
  dy::Transform X[1];
  X[0].E = Mat3::Identity();
  X[0].r = Vec3(0, 0, 0.1_r - 0.001_r);  // 1 mm into the ground
  dy::ContactPoint c[16];
  KASSERT_EQ(dy::collide_halfspace(&cube, 1, X, dy::HalfSpace(), 0.005_r, c, 16), 4);
  for (int i = 0; i < 4; ++i) {
    KEXPECT_NEAR(c[i].separation_m, -0.001_r, 1e-6_r);
    KEXPECT_NEAR(c[i].point_w[2], -0.001_r, 1e-6_r);
    KEXPECT_EQ(c[i].body, 0);
    KEXPECT_EQ(c[i].body_b, -1);
  }
  // The same as the box primitive's corners, in the same order.
  dy::CollisionShape box = cube;
  box.type = dy::ShapeType::box;
  box.size = Vec3(0.1_r, 0.1_r, 0.1_r);
  dy::ContactPoint cb[16];
  KASSERT_EQ(dy::collide_halfspace(&box, 1, X, dy::HalfSpace(), 0.005_r, cb, 16), 4);
  for (int i = 0; i < 4; ++i) KEXPECT_NEAR((c[i].point_w - cb[i].point_w).norm(), 0, 1e-6_r);
  // 12 points, all below the plane at different depths: the 8 deepest, in vertex order.
  Vec3 line[12];
  for (int k = 0; k < 12; ++k) line[k] = Vec3(0.01_r * k, 0, -0.001_r * static_cast<real>((k * 5) % 12));
  dy::CollisionShape stick = cube;
  stick.points = line;
  stick.num_points = 12;
  X[0].r = Vec3::Zero();
  KASSERT_EQ(dy::collide_halfspace(&stick, 1, X, dy::HalfSpace(), 0.0005_r, c, 16), 8);
  real shallowest = -1;
  for (int i = 0; i < 8; ++i) shallowest = c[i].separation_m > shallowest ? c[i].separation_m : shallowest;
  KEXPECT_NEAR(shallowest, -0.004_r, 1e-6_r);  // depths 0..11 mm: the deepest 8 are 4..11 mm
  for (int i = 1; i < 8; ++i) KEXPECT_TRUE(c[i].point_w[0] > c[i - 1].point_w[0]);  // vertex order kept
  // Convex shapes give no contact with other shapes (collide_shapes: half-spaces only).
  dy::CollisionShape ball;
  ball.body = 0;
  ball.size = Vec3(0.5_r, 0, 0);
  KEXPECT_EQ(dy::collide_shapes(cube, X[0], ball, X[0], 0.01_r, c, 16), 0);
}

// A heavy base (a 50 kg box, ANYmal's order) lying on the ground with two two-link legs stretched
// out sideways to spheres that rest on it too, the joints with dry friction: a resting tree with
// contact, cone and joint rows coupled through the base. Warm-started, once settled each step's
// PGS stops within a sweep or two (it converged: a sweep that starts converged changes nothing),
// far below its cap (a solver whose residuals drift by rounding keeps changing at the tolerance
// and runs to the cap every step); and the step given the caller's kinematics
// (ConstraintParams::poses_current) is bit for bit the step that computes them.
KTEST(Contact, ARestingTreeConvergesInASweepOrTwoAndReusedPosesChangeNothing) {
  auto& w = ktest::scratch<World<5, 8>>();
  auto& m = w.m;
  auto& d = w.d;
  auto& cd = w.cd;
  two_legged_tree(m, [&m](int i) {
    const real side = i <= 2 ? real(1) : real(-1);
    m.X_tree[i].r = Vec3(side * 0.25_r, 0, 0);  // the base's side, then the next link's end
    m.body[i] = solid(1, Vec3::Constant(real(5e-3)));
    m.body[i].com = Vec3(side * 0.125_r, 0, 0);
    m.friction_loss[i] = 0.5_r;
  });
  m.body[0] = solid(50, Vec3(0.5_r, 1.0_r, 1.2_r));
  KASSERT_EQ(dy::finish_model(m), Status::ok);
  dy::CollisionShape shapes[5];
  for (int i = 0; i < 5; ++i) {
    shapes[i].body = i;
    shapes[i].type = i == 0 ? dy::ShapeType::box : dy::ShapeType::sphere;
    shapes[i].size = i == 0 ? Vec3(0.25_r, 0.15_r, 0.05_r) : Vec3(0.05_r, 0, 0);
    shapes[i].p_b = i == 0 ? Vec3::Zero() : Vec3((i <= 2 ? real(1) : real(-1)) * 0.25_r, 0, 0);
    shapes[i].friction = 0.8_r;
  }
  static dy::WarmStart<32> warm;
  warm.count = 0;
  real q[11] = {0, 0, 0.05_r, 0, 0, 0, 1}, qd[10] = {};
  const real tau[10] = {};
  auto step = [&](real* qs, real* qds, dy::WarmStart<32>& ws, bool poses_current) {
    dy::ContactPoint contacts[8];
    dy::forward_kinematics(m, d, qs, cd.X_world);
    const int found = dy::collide_halfspace(shapes, 5, cd.X_world, dy::HalfSpace(), real(0.01), contacts, 8);
    dy::ConstraintParams p;
    p.poses_current = poses_current;
    return dy::step_constrained(m, d, cd, qs, qds, tau, 0.005_r, contacts, std::min(found, 8), p, nullptr, nullptr, &ws);
  };
  for (int k = 0; k < 200; ++k) KASSERT_EQ(step(q, qd, warm, false), Status::ok);  // 1 s to settle
  int sweeps = 0, rows = 0;
  for (int k = 0; k < 40; ++k) {
    KASSERT_EQ(step(q, qd, warm, false), Status::ok);
    sweeps += cd.iterations_used;
    rows = cd.num_rows;
  }
  KEXPECT_GE(rows, 16);  // 4 box corners and 4 feet: 8 contacts x 3 rows, and 4 dry-friction rows
  KEXPECT_LE(sweeps, 40 * 2);  // 1 per step here; residuals kept only incrementally took 217
  KEXPECT_LT(std::fabs(q[2] - 0.05_r), real(2e-3));  // the base rests where it lay
  // The same step from the same state, with and without the reused kinematics.
  real q2[11], qd2[10];
  for (int k = 0; k < 11; ++k) q2[k] = q[k];
  for (int k = 0; k < 10; ++k) qd2[k] = qd[k];
  static dy::WarmStart<32> warm2;
  warm2 = warm;
  KASSERT_EQ(step(q, qd, warm, false), Status::ok);
  KASSERT_EQ(step(q2, qd2, warm2, true), Status::ok);
  for (int k = 0; k < 11; ++k) KEXPECT_EQ(q2[k], q[k]);
  for (int k = 0; k < 10; ++k) KEXPECT_EQ(qd2[k], qd[k]);
}

// collide_halfspace skips a capsule or a box whose bounding sphere clears the plane by the margin
// and 0.1 mm: random poses around that threshold, tilted planes, against the points computed by
// hand (every capsule end and box corner, the same expressions): the same contacts, keys and gaps.
KTEST(Contact, HalfSpaceCullLosesNoContact) {
  RngStream rng(5, 0, 0);
  int checked = 0, touching = 0;
  for (int trial = 0; trial < 400; ++trial) {
    dy::CollisionShape s;
    s.body = 0;
    const bool box = trial % 2 == 0;
    s.type = box ? dy::ShapeType::box : dy::ShapeType::capsule;
    s.size = box ? Vec3(rng.uniform(0.01_r, 0.2_r), rng.uniform(0.01_r, 0.2_r), rng.uniform(0.01_r, 0.2_r))
                 : Vec3(rng.uniform(0.005_r, 0.05_r), rng.uniform(0.01_r, 0.2_r), 0);
    s.p_b = Vec3(rng.uniform(-0.05_r, 0.05_r), rng.uniform(-0.05_r, 0.05_r), rng.uniform(-0.05_r, 0.05_r));
    const Vec3 axis_b = Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)).normalized();
    s.R_b = Eigen::AngleAxis<real>(rng.uniform(-3, 3), axis_b).toRotationMatrix();
    dy::HalfSpace g;
    g.normal_w = Vec3(rng.uniform(-0.3_r, 0.3_r), rng.uniform(-0.3_r, 0.3_r), 1).normalized();
    g.offset_m = rng.uniform(-0.1_r, 0.1_r);
    dy::Transform X[1];
    const Vec3 axis = Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)).normalized();
    X[0].E = Eigen::AngleAxis<real>(rng.uniform(-3, 3), axis).toRotationMatrix();
    // The centre at the cull's threshold height above the plane, give or take 2 mm, or anywhere
    // within the shape's reach.
    const real margin = 0.01_r;
    const real reach = box ? s.size.norm() : s.size[0] + s.size[1];
    const real height = trial % 4 < 2 ? reach + margin + rng.uniform(-0.002_r, 0.002_r) : rng.uniform(-reach, reach + margin);
    const Vec3 centre_w = g.normal_w * (g.offset_m + height);
    X[0].r = centre_w - X[0].E.transpose() * s.p_b;
    dy::ContactPoint c[16];
    const int found = dy::collide_halfspace(&s, 1, X, g, margin, c, 16, 3);
    // By hand: every point, no cull.
    const Mat3 R_w = X[0].E.transpose() * s.R_b;
    const Vec3 c_w = X[0].r + X[0].E.transpose() * s.p_b;
    int want = 0;
    for (int k = 0; k < (box ? 8 : 2); ++k) {
      Vec3 p;
      real gap;
      if (box) {
        p = c_w + R_w * Vec3((k & 1) ? s.size[0] : -s.size[0], (k & 2) ? s.size[1] : -s.size[1], (k & 4) ? s.size[2] : -s.size[2]);
        gap = g.normal_w.dot(p) - g.offset_m;
      } else {
        const Vec3 end = c_w + R_w * Vec3(0, 0, real(2 * k - 1) * s.size[1]);
        p = end - s.size[0] * g.normal_w;
        gap = g.normal_w.dot(end) - g.offset_m - s.size[0];
      }
      if (!(gap < margin)) continue;
      KASSERT_TRUE(want < found);
      KEXPECT_EQ(c[want].key, 3 * 8 + k);
      KEXPECT_EQ(c[want].separation_m, gap);
      KEXPECT_EQ((c[want].point_w - p).norm(), real(0));
      ++want;
    }
    KEXPECT_EQ(found, want);
    ++checked;
    touching += want > 0 ? 1 : 0;
  }
  KEXPECT_EQ(checked, 400);
  KEXPECT_GT(touching, 100);  // the poses probe both sides of the threshold
}
