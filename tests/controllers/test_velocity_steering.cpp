// Velocity + steering-angle controller (kinematic bicycle model): speed tracking, steering slew
// and limits, the circle of radius L / tan(delta), rejected non-finite input, no heap.
#include <cmath>
#include <limits>

#include "kestrel/controllers/velocity_steering.hpp"
#include "kestrel/kernel/math.hpp"
#include "ktest.hpp"

using namespace kestrel;

KTEST(VelocitySteering, ParamsValidate) {
  VelocitySteeringParams p;
  KEXPECT_TRUE(validate_velocity_steering_params(p) == Status::ok);
  p.wheelbase_m = 0;
  KEXPECT_TRUE(validate_velocity_steering_params(p) == Status::invalid_argument);
  p = VelocitySteeringParams();
  p.max_steering_rad = 1.6_r;  // tan would blow up near pi/2
  KEXPECT_TRUE(validate_velocity_steering_params(p) == Status::invalid_argument);
  p = VelocitySteeringParams();
  p.k_speed = -1;
  KEXPECT_TRUE(validate_velocity_steering_params(p) == Status::invalid_argument);
}

KTEST(VelocitySteering, SpeedConvergesAndSteeringSlews) {
  const VelocitySteeringParams p;
  VelocitySteeringState s;
  velocity_steering_reset(s);
  const real dt = 0.01_r;
  const real cmd[2] = {2, 0.3_r};
  real v = 0;
  VelocitySteeringOutput out;
  // First step: the steering moves by at most max_steering_rate * dt, the acceleration is clipped.
  KEXPECT_NO_HEAP(KEXPECT_TRUE(update_velocity_steering(p, s, v, cmd, dt, out) == Status::ok));
  KEXPECT_NEAR(out.steering_rad, p.max_steering_rate_rad_s * dt, 1e-6);
  KEXPECT_NEAR(out.accel_m_s2, p.max_accel_m_s2, 1e-6);
  KEXPECT_TRUE((s.step_faults & kFaultSaturated) != 0);
  v = out.speed_m_s;
  for (int k = 0; k < 600; ++k) {
    (void)update_velocity_steering(p, s, v, cmd, dt, out);
    v = out.speed_m_s;
  }
  KEXPECT_NEAR(v, 2, 1e-3);
  KEXPECT_NEAR(out.steering_rad, 0.3_r, 1e-6);
  // Yaw rate of the kinematic bicycle at that speed and angle.
  KEXPECT_NEAR(out.yaw_rate_radps, v * std::tan(0.3_r) / p.wheelbase_m, 1e-4);
  KEXPECT_NEAR(out.force_N, p.mass_kg * out.accel_m_s2, 1e-5);
}

KTEST(VelocitySteering, CommandsClippedToLimits) {
  const VelocitySteeringParams p;
  VelocitySteeringState s;
  velocity_steering_reset(s);
  const real cmd[2] = {10, -1};
  VelocitySteeringOutput out;
  real v = 0;
  for (int k = 0; k < 2000; ++k) {
    (void)update_velocity_steering(p, s, v, cmd, 0.01_r, out);
    v = out.speed_m_s;
  }
  KEXPECT_NEAR(v, p.max_speed_m_s, 1e-3);
  KEXPECT_NEAR(out.steering_rad, -p.max_steering_rad, 1e-6);
  KEXPECT_TRUE(s.faults.has(kFaultCommandOutOfRange));
  // Stop command from speed: brakes at most max_decel and never overshoots into reverse.
  const real stop[2] = {0, 0};
  (void)update_velocity_steering(p, s, v, stop, 0.01_r, out);
  KEXPECT_GE(out.accel_m_s2, -p.max_decel_m_s2);
  for (int k = 0; k < 300; ++k) {
    (void)update_velocity_steering(p, s, v, stop, 0.01_r, out);
    v = out.speed_m_s;
    KEXPECT_GE(v, 0);
  }
  KEXPECT_NEAR(v, 0, 1e-3);
}

// Integrate the kinematic bicycle (rear axle) with the controller's outputs: after the speed and
// the steering settle, the rear axle stays on a circle of radius L / tan(delta).
KTEST(VelocitySteering, BicycleCircleRadius) {
  VelocitySteeringParams p;
  p.wheelbase_m = 0.5_r;
  VelocitySteeringState s;
  velocity_steering_reset(s);
  const real delta = 0.25_r;
  const real cmd[2] = {1.5_r, delta};
  const real dt = 0.001_r;
  real x = 0, y = 0, psi = 0, v = 0;
  VelocitySteeringOutput out;
  for (int k = 0; k < 3000; ++k) {  // settle: 3 s
    (void)update_velocity_steering(p, s, v, cmd, dt, out);
    v = out.speed_m_s;
    x += v * std::cos(psi) * dt;
    y += v * std::sin(psi) * dt;
    psi += out.yaw_rate_radps * dt;
  }
  const real radius = p.wheelbase_m / std::tan(delta);
  KEXPECT_NEAR(bicycle_turn_radius(delta, p.wheelbase_m), radius, 1e-5);
  KEXPECT_NEAR(bicycle_turn_radius(0, p.wheelbase_m), 0, 0);
  // Centre of the circle: radius to the left of the current heading.
  const real cx = x - radius * std::sin(psi), cy = y + radius * std::cos(psi);
  real max_dev = 0;
  for (int k = 0; k < 4000; ++k) {
    (void)update_velocity_steering(p, s, v, cmd, dt, out);
    v = out.speed_m_s;
    x += v * std::cos(psi) * dt;
    y += v * std::sin(psi) * dt;
    psi += out.yaw_rate_radps * dt;
    const real r = std::sqrt((x - cx) * (x - cx) + (y - cy) * (y - cy));
    max_dev = std::fabs(r - radius) > max_dev ? std::fabs(r - radius) : max_dev;
  }
  KEXPECT_LT(max_dev, 0.01_r * radius);  // explicit Euler drift over 4 s stays below 1 %
}

KTEST(VelocitySteering, NonFiniteInputHoldsOutput) {
  const VelocitySteeringParams p;
  VelocitySteeringState s;
  velocity_steering_reset(s);
  VelocitySteeringOutput out;
  const real good[2] = {1, 0.2_r};
  (void)update_velocity_steering(p, s, 0.5_r, good, 0.01_r, out);
  const real held_a = out.accel_m_s2, held_d = out.steering_rad, held_i = s.speed_error_integral_m;
  const real nan = std::numeric_limits<real>::quiet_NaN();
  const real bad[2] = {nan, 0.1_r};
  KEXPECT_TRUE(update_velocity_steering(p, s, 0.5_r, bad, 0.01_r, out) == Status::non_finite_input);
  KEXPECT_EQ(out.accel_m_s2, held_a);
  KEXPECT_EQ(out.steering_rad, held_d);
  KEXPECT_EQ(s.speed_error_integral_m, held_i);
  KEXPECT_TRUE(s.faults.has(kFaultNonFiniteCommand));
  KEXPECT_TRUE(update_velocity_steering(p, s, std::numeric_limits<real>::infinity(), good, 0.01_r, out) ==
               Status::non_finite_input);
  KEXPECT_TRUE(s.faults.has(kFaultNonFiniteState));
  KEXPECT_TRUE(is_finite(out.yaw_rate_radps) && is_finite(out.speed_m_s));
  KEXPECT_TRUE(update_velocity_steering(p, s, 0.5_r, good, 0, out) == Status::invalid_argument);
  // Gain scale: a halved gain gives half the proportional acceleration from rest.
  VelocitySteeringState a, b;
  velocity_steering_reset(a, 1);
  velocity_steering_reset(b, 0.5_r);
  VelocitySteeringParams pi = p;
  pi.k_speed_i = 0;
  const real small[2] = {0.2_r, 0};
  VelocitySteeringOutput oa, ob;
  (void)update_velocity_steering(pi, a, 0, small, 0.01_r, oa);
  (void)update_velocity_steering(pi, b, 0, small, 0.01_r, ob);
  KEXPECT_NEAR(ob.accel_m_s2, 0.5_r * oa.accel_m_s2, 1e-6);
}
