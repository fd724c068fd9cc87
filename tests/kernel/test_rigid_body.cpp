#include "kestrel/kernel/rigid_body.hpp"

#include <cmath>
#include <limits>

#include "kestrel/kernel/quaternion.hpp"
#include "ktest.hpp"

using namespace kestrel;

namespace {
RigidBodyModel make(Integrator integ) {
  RigidBodyParams p;
  p.integrator = integ;
  RigidBodyModel m;
  const Status s = make_rigid_body_model(p, m);
  (void)s;
  return m;
}
}  // namespace

KTEST(RigidBody, RejectsBadParams) {
  RigidBodyModel m;
  RigidBodyParams p;
  p.mass_kg = 0;
  KEXPECT_TRUE(make_rigid_body_model(p, m) == Status::invalid_argument);
  p = RigidBodyParams();
  p.inertia_b(2, 2) = -1;
  KEXPECT_TRUE(make_rigid_body_model(p, m) == Status::invalid_argument);
  p = RigidBodyParams();
  p.inertia_b(0, 1) = 1e-3_r;  // not symmetric
  KEXPECT_TRUE(make_rigid_body_model(p, m) == Status::invalid_argument);
}

KTEST(RigidBody, FreeFallIsExactUnderBothIntegrators) {
  for (Integrator integ : {Integrator::semi_implicit_euler, Integrator::rk4}) {
    const RigidBodyModel m = make(integ);
    RigidBodyState s;
    const real dt = 0.01_r;
    for (int i = 0; i < 100; ++i) KEXPECT_TRUE(step_rigid_body(m, s, Wrench(), dt) == Status::ok);
    // v = g t exactly (constant acceleration) for both.
    KEXPECT_NEAR(s.linvel_w[2], -9.81, 1e-4);
    // RK4 integrates position exactly: z = -g t^2 / 2; symplectic Euler overshoots by g dt t / 2.
    const double expect = integ == Integrator::rk4 ? -4.905 : -4.905 - 0.5 * 9.81 * 0.01;
    KEXPECT_NEAR(s.position_w[2], expect, 1e-3);
  }
}

KTEST(RigidBody, HoverThrustHoldsPosition) {
  const RigidBodyModel m = make(Integrator::rk4);
  RigidBodyState s;
  Wrench w;
  w.force_b = Vec3(0, 0, 0.25_r * 9.81_r);
  for (int i = 0; i < 500; ++i) KEXPECT_NO_HEAP((void)step_rigid_body(m, s, w, 0.002_r));
  KEXPECT_NEAR(s.position_w.norm(), 0, 1e-5);
}

KTEST(RigidBody, ConstantRateRotationMatchesAxisAngle) {
  for (Integrator integ : {Integrator::semi_implicit_euler, Integrator::rk4}) {
    RigidBodyParams p;
    p.integrator = integ;
    p.gravity_w = Vec3::Zero();
    RigidBodyModel m;
    KEXPECT_TRUE(make_rigid_body_model(p, m) == Status::ok);
    RigidBodyState s;
    s.angvel_b = Vec3(0, 0, 1);  // about a principal axis: no gyroscopic torque
    for (int i = 0; i < 100; ++i) (void)step_rigid_body(m, s, Wrench(), 0.01_r);
    const Vec3 e = euler_xyz(s.orientation_wb);
    KEXPECT_NEAR(e[2], 1.0, 1e-4);
    KEXPECT_NEAR(s.orientation_wb.norm(), 1, 1e-6);
  }
}

KTEST(RigidBody, TorqueFreeEnergyAndMomentumConserved) {
  RigidBodyParams p;
  p.gravity_w = Vec3::Zero();
  p.inertia_b = (Mat3() << 1, 0, 0, 0, 2, 0, 0, 0, 3).finished();
  RigidBodyModel m;
  KEXPECT_TRUE(make_rigid_body_model(p, m) == Status::ok);
  RigidBodyState s;
  s.angvel_b = Vec3(0.3_r, 1.0_r, 0.2_r);  // near the unstable intermediate axis
  const real e0 = 0.5_r * s.angvel_b.dot(p.inertia_b * s.angvel_b);
  const Vec3 l0 = rotate(s.orientation_wb, p.inertia_b * s.angvel_b);
  for (int i = 0; i < 1000; ++i) (void)step_rigid_body(m, s, Wrench(), 0.001_r);
  const real e1 = 0.5_r * s.angvel_b.dot(p.inertia_b * s.angvel_b);
  const Vec3 l1 = rotate(s.orientation_wb, p.inertia_b * s.angvel_b);
  KEXPECT_NEAR(e1, e0, 1e-4 * e0);
  KEXPECT_NEAR((l1 - l0).norm(), 0, 1e-4);
}

KTEST(RigidBody, NonFiniteWrenchLeavesStateUntouched) {
  const RigidBodyModel m = make(Integrator::rk4);
  RigidBodyState s;
  s.position_w = Vec3(1, 2, 3);
  Wrench w;
  w.force_b[2] = std::numeric_limits<real>::quiet_NaN();
  KEXPECT_TRUE(step_rigid_body(m, s, w, 0.01_r) == Status::non_finite_input);
  KEXPECT_EQ(s.position_w[2], 3);
  KEXPECT_TRUE(std::isfinite(s.linvel_w[2]));
}

KTEST(RigidBody, DragOpposesMotion) {
  RigidBodyParams p;
  p.gravity_w = Vec3::Zero();
  p.linear_drag_b = Vec3(0.5_r, 0.5_r, 0.5_r);
  RigidBodyModel m;
  KEXPECT_TRUE(make_rigid_body_model(p, m) == Status::ok);
  RigidBodyState s;
  s.linvel_w = Vec3(2, 0, 0);
  for (int i = 0; i < 100; ++i) (void)step_rigid_body(m, s, Wrench(), 0.01_r);
  // v(t) = v0 exp(-k t / m) = 2 exp(-2) at t = 1 s.
  KEXPECT_NEAR(s.linvel_w[0], 2 * std::exp(-2.0), 1e-4);
}
