// Velocity + steering-angle controller for car-like ground vehicles (Ackermann steering), over the
// kinematic bicycle model.
//
// Model (rear-axle reference point, no slip): R. Rajamani, "Vehicle Dynamics and Control", 2nd ed.,
// Springer 2012, section 2.2 (kinematic model of lateral vehicle motion), with the slip angle
// beta = 0 at the rear axle; also J. Kong, M. Pfeiffer, G. Schildbach, F. Borrelli, "Kinematic and
// dynamic vehicle models for autonomous driving control design", IEEE IV 2015, eq. (1):
//     x' = v cos(psi),  y' = v sin(psi),  psi' = v tan(delta) / L,
// so with a constant steering angle delta the rear axle drives a circle of radius L / tan(delta).
// The front wheels' Ackermann geometry collapses onto one virtual wheel at the axle midpoint
// (the "bicycle"), which is what delta is.
//
// The controller tracks a command [speed_m_s, steering_rad]:
//  - speed: proportional-integral loop on the measured speed along the heading, giving a
//    longitudinal acceleration clipped to [-max_decel, max_accel] (anti-windup: the integrator
//    does not grow while the output is clipped);
//  - steering: the steering actuator moves toward the commanded angle at most max_steering_rate,
//    inside +-max_steering.
// The outputs are the acceleration (and the force m a), the steering angle actually set, and the
// bicycle-model yaw rate v tan(delta) / L at the next speed, so a simulator (sim/src/planar*.cpp)
// or a firmware drive loop can apply them directly.
//
// Core rules: no heap, no exceptions, float by default; a non-finite command or measurement is
// rejected (the last safe output is held, a fault is raised, nothing else changes); out-of-range
// commands are clipped and flagged.
#pragma once

#include <cstddef>
#include <cstdint>

#include "kestrel/kernel/status.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel {

/// Action layout: [speed_m_s, steering_rad].
constexpr std::size_t kVelocitySteeringActionDim = 2;

struct VelocitySteeringParams {
  real wheelbase_m = 0.33_r;          // L: rear to front axle (1/10-scale car, F1TENTH class)
  real mass_kg = 3.5_r;               // for the force output only
  real max_speed_m_s = 3;             // forward speed command limit
  real max_reverse_speed_m_s = 1;     // reverse speed command limit (>= 0)
  real max_accel_m_s2 = 4;            // acceleration limit
  real max_decel_m_s2 = 6;            // braking limit (>= 0, applied as -max_decel)
  real max_steering_rad = 0.4_r;      // |delta| limit (about 23 deg)
  real max_steering_rate_rad_s = 3;   // steering actuator slew rate
  // Speed loop v' = k_speed e + k_speed_i integral(e): characteristic s^2 + k_speed s + k_speed_i,
  // critically damped at (s + 2)^2 with these defaults (0.5 s time constant).
  real k_speed = 4;                   // (m/s^2) per m/s of speed error
  real k_speed_i = 4;                 // (m/s^2) per m of integrated speed error
};

/// Positive finite wheelbase, mass and limits; non-negative finite gains.
[[nodiscard]] Status validate_velocity_steering_params(const VelocitySteeringParams& params);

struct VelocitySteeringState {
  real steering_rad = 0;          // steering angle now set (the actuator's state)
  real speed_error_integral_m = 0;
  real gain_scale = 1;            // multiplies k_speed and k_speed_i (domain randomisation)
  real last_accel_m_s2 = 0;       // last safe output (held on rejected input)
  FaultFlags faults;              // latched until reset
  std::uint32_t step_faults = 0;  // raised by the most recent update only
};

struct VelocitySteeringOutput {
  real accel_m_s2 = 0;      // longitudinal acceleration along the heading
  real force_N = 0;         // mass_kg * accel_m_s2
  real steering_rad = 0;    // steering angle set after the slew limit
  real speed_m_s = 0;       // speed after dt at this acceleration (the bicycle model's v)
  real yaw_rate_radps = 0;  // speed_m_s * tan(steering_rad) / wheelbase_m
};

/// Zero steering, zero integral, faults cleared; keeps nothing from before.
void velocity_steering_reset(VelocitySteeringState& state, real gain_scale = 1);

/// One update over dt_s: `measured_speed_m_s` is the speed along the heading (negative in reverse),
/// `action` holds kVelocitySteeringActionDim values. Returns Status::non_finite_input when the
/// command, the measurement or dt was rejected (output = held acceleration and the current
/// steering), Status::invalid_argument for dt <= 0, else Status::ok.
[[nodiscard]] Status update_velocity_steering(const VelocitySteeringParams& params, VelocitySteeringState& state,
                                              real measured_speed_m_s, const real* action, real dt_s,
                                              VelocitySteeringOutput& out);

/// Kinematic bicycle yaw rate v tan(delta) / L (rad/s).
real bicycle_yaw_rate(real speed_m_s, real steering_rad, real wheelbase_m);
/// Turning radius of the rear axle L / tan(delta) (m); +inf-free: 0 steering returns 0 (straight).
real bicycle_turn_radius(real steering_rad, real wheelbase_m);

}  // namespace kestrel
