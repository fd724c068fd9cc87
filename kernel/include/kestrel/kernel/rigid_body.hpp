// Rigid-body dynamics of one body: Newton-Euler equations with a unit-quaternion attitude.
//
//   m dv_w/dt = R f_b + m g_w + f_drag
//   J dw_b/dt = tau_b - w_b x (J w_b) + tau_drag
//   dp_w/dt = v_w,   dq/dt = 1/2 q (x) (0, w_b)
//
// Two integrators: semi-implicit (symplectic) Euler with the exact exponential-map attitude
// update, and classical RK4 on the whole state. Both renormalise the quaternion every step.
// The wrench is held constant over the step (zero-order hold, as the controller applies it).
// Plain math, no heap: the firmware example closes the loop with it on the MCU, and the
// simulation harness steps every environment's bodies with it.
#pragma once

#include "kestrel/kernel/status.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel {

enum class Integrator : std::uint8_t { semi_implicit_euler, rk4 };

struct RigidBodyParams {
  real mass_kg = 0.25_r;
  Mat3 inertia_b = (Mat3() << 8.45e-4_r, 0, 0, 0, 8.45e-4_r, 0, 0, 0, 1.69e-3_r).finished();  // kg m^2
  Vec3 gravity_w = Vec3(0, 0, -kStandardGravity);  // m/s^2
  // Body-frame drag as in Aerial Gym's robot config: f = -(k_lin * v_b + k_quad * |v_b| * v_b),
  // tau = -(k_lin_rot * w_b + k_quad_rot * |w_b| * w_b), element-wise per body axis.
  Vec3 linear_drag_b = Vec3::Zero();       // N s/m
  Vec3 quadratic_drag_b = Vec3::Zero();    // N s^2/m^2
  Vec3 angular_drag_b = Vec3::Zero();      // N m s/rad
  Vec3 quadratic_angular_drag_b = Vec3::Zero();  // N m s^2/rad^2
  Integrator integrator = Integrator::rk4;
};

/// Precomputed quantities of RigidBodyParams (inverse inertia). Rebuild when params change.
struct RigidBodyModel {
  RigidBodyParams params;
  Mat3 inv_inertia_b = Mat3::Identity();
  real inv_mass = 4;
};

/// Validate params and precompute. Returns invalid_argument for non-positive mass or a
/// non-positive-definite inertia, leaving `out` untouched.
[[nodiscard]] Status make_rigid_body_model(const RigidBodyParams& params, RigidBodyModel& out);

/// State derivative at (state, wrench): linear and angular accelerations (world / body frame).
struct RigidBodyAccel {
  Vec3 linacc_w;
  Vec3 angacc_b;
};
RigidBodyAccel rigid_body_accel(const RigidBodyModel& model, const RigidBodyState& state, const Wrench& wrench);

/// Advance `state` by dt seconds under a constant body wrench (plus optional extra world-frame
/// force, e.g. a disturbance or contact force applied at the centre of mass).
/// Non-finite inputs leave the state unchanged and return Status::non_finite_input.
[[nodiscard]] Status step_rigid_body(const RigidBodyModel& model, RigidBodyState& state, const Wrench& wrench_b,
                                     real dt_s, const Vec3& extra_force_w = Vec3::Zero());

}  // namespace kestrel
