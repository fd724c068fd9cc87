// The Lee geometric controller family, as Aerial Gym runs it.
//
// T. Lee, M. Leok, N. H. McClamroch, "Geometric tracking control of a quadrotor UAV on SE(3)",
// IEEE CDC 2010. The attitude error is e_R = 1/2 vee(R_d^T R - R^T R_d) and the rate error
// e_w = w - R^T R_d w_d (eqs. 10-11 there), the torque tau = -k_R e_R - k_w e_w + w x J w
// (eq. 16 without the feed-forward acceleration terms, exactly as Aerial Gym drops them).
//
// Every controller here reproduces Aerial Gym (ntnu-arl/aerial_gym_simulator, commit f0d0f05)
// within the float32 tolerances of tests/golden/reference/controllers.json, quirks included, except
// where a comment says otherwise (lee_rates, whose reference crashes; in-place edits of the
// caller's action, which we never do).
//
// Shape: LeeParams (read-only, built once per vehicle type), LeeState (per instance: active gains,
// last safe output, latched faults, intermediates), one update function per controller taking the
// vehicle state and a fixed-length action array, returning the body wrench.
//
// Input handling, common to every update function:
//  - a non-finite action component -> the update is rejected: the last safe wrench is returned,
//    kFaultNonFiniteCommand is raised, nothing else in the state changes;
//  - a non-finite vehicle state -> same, with kFaultNonFiniteState;
//  - an action component outside [action_min, action_max] -> clipped (as Aerial Gym's robot does
//    before calling its controller) and kFaultCommandOutOfRange raised; the update goes on;
//  - a degenerate desired attitude (zero collective force, heading parallel to the thrust axis,
//    zero command quaternion) -> a fallback attitude (documented at each controller in lee.cpp)
//    and kFaultSingular;
//  - a non-finite result (e.g. absurd parameters) -> rejected like a non-finite input, with
//    kFaultNonFiniteOutput. NaN never reaches the state or the output.
// The last safe wrench starts at zero (see LeeState::last_safe_wrench_b for why not hover).
#pragma once

#include <cstddef>
#include <cstdint>

#include "kestrel/kernel/rng.hpp"
#include "kestrel/kernel/status.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel {

/// Per-axis gains of the Lee controllers (element-wise products, as Aerial Gym's tensors).
struct LeeGains {
  // Plain arrays (PlainVec3, kernel/types.hpp) so that LeeParams can be constant-initialised.
  PlainVec3 k_pos = {};     // (m/s^2) per m of position error
  PlainVec3 k_vel = {};     // (m/s^2) per m/s of velocity error
  PlainVec3 k_rot = {};     // N m per unit of attitude error e_R
  PlainVec3 k_angvel = {};  // N m per rad/s of rate error
};

/// Inclusive ranges of each gain component. Aerial Gym starts every instance at the midpoint and,
/// when its config asks for it, redraws the gains uniformly in [min, max] at every reset.
struct LeeGainRanges {
  LeeGains min;
  LeeGains max;
};

struct LeeParams {
  real mass_kg = 0;
  PlainMat3 inertia_b = {};  // kg m^2, about the centre of mass, body axes
  PlainVec3 gravity_w = {0, 0, -kStandardGravity};  // m/s^2
  real max_yaw_rate_radps = 0;  // clamp on the body-z component of the desired body rate
  LeeGainRanges gain_ranges;    // nominal gains = midpoints; min = max fixes a gain
  bool randomize_gains = false; // lee_reset(..., rng) draws gains only when set
  real action_min = -10;        // every action component is clipped to [action_min, action_max]
  real action_max = 10;
};

/// Upper bounds validate_lee_params() enforces. Why: the controller multiplies gains by state errors
/// (and mass by accelerations); with these bounds and any physically meaningful state the products
/// stay many orders of magnitude below the float limit (3.4e38), whereas e.g. k_angvel = 1e37 at
/// 10 rad/s overflows the allocation on every step. Generous: the presets use gains of 0.1 to ~15,
/// masses of 0.25 to 2.4 kg.
constexpr real kLeeMaxGain = 1e6_r;          // |every gain component|
constexpr real kLeeMaxMassKg = 1e6_r;        // mass in (0, 1e6] kg
constexpr real kLeeMaxInertiaKgm2 = 1e6_r;   // |every inertia entry|
constexpr real kLeeMaxGravityMps2 = 1e3_r;   // |every gravity component|

/// Checks a LeeParams once, when it is built: finite mass in (0, kLeeMaxMassKg], finite inertia
/// entries and gravity components within kLeeMaxInertiaKgm2 / kLeeMaxGravityMps2, non-negative
/// yaw-rate limit, finite gain ranges with min <= max and |gain| <= kLeeMaxGain,
/// action_min < action_max.
[[nodiscard]] Status validate_lee_params(const LeeParams& params);

/// Midpoints of the ranges: the gains every instance holds before any randomisation.
LeeGains lee_nominal_gains(const LeeGainRanges& ranges);

/// Gains drawn uniformly in [min, max] per component (12 draws in the order k_pos xyz, k_vel xyz,
/// k_rot xyz, k_angvel xyz), so a stream keyed by (seed, instance, kPurposeGains) reproduces them.
LeeGains randomize_lee_gains(const LeeGainRanges& ranges, RngStream& rng);

/// Aerial Gym's default Lee config ranges (lee_controller_config.py).
LeeGainRanges lee_gain_ranges_default();
/// Aerial Gym's ROV fully actuated config ranges (fully_actuated_controller_rov.py).
LeeGainRanges lee_gain_ranges_rov();

/// Presets with the float32 values listed in golden/controllers.json params.
LeeParams lee_params_base_quadrotor();  // 0.25 kg, diag(8.45e-4, 8.45e-4, 1.69e-3), default ranges
LeeParams lee_params_rov();             // 1.1 kg, 0.096 I, ROV ranges, randomize_gains = true

struct LeeState {
  LeeGains gains;  // active gains of this instance (set by lee_reset)
  /// Returned while input is rejected. Starts at zero, not at hover: before the first accepted
  /// update the vehicle is on the ground or in an unknown attitude, and a hover thrust with an
  /// unknown attitude would push it in an unknown direction; zero is the "motors idle" state a
  /// supervisor expects. After an accepted update it is that update's wrench.
  Wrench last_safe_wrench_b;
  FaultFlags faults;              // latched until cleared (lee_reset clears them)
  std::uint32_t step_faults = 0;  // fault bits raised by the most recent update only
  // Intermediates of the last accepted update (telemetry and golden checks):
  Vec3 accel_command_w = Vec3::Zero();             // m/s^2, before gravity compensation
  Vec4 desired_quat_xyzw = Vec4(0, 0, 0, 1);        // R_d as a quaternion (sign: w >= 0, except
                                                    // the ROV, which keeps the command's sign)
  Vec3 desired_angvel_b = Vec3::Zero();             // rad/s, after the body-z clamp
  /// Set by lee_reset when params.inertia_b has zero off-diagonal entries (every preset, the
  /// C API and the simulator build it as diag(...)): the gyroscopic term w x (J w) then needs 3
  /// products instead of 9, with the same bits. False (the default) takes the general path, so a
  /// state that never saw lee_reset is still correct. Call lee_reset again after changing
  /// params.inertia_b (LeeParams are read-only after construction anyway).
  bool inertia_diagonal = false;
};

/// Start an instance: nominal gains, zero outputs and intermediates, faults cleared.
void lee_reset(const LeeParams& params, LeeState& state);
/// As above, then draws the gains from `rng` if params.randomize_gains (Aerial Gym's reset).
void lee_reset(const LeeParams& params, LeeState& state, RngStream& rng);

/// Action lengths.
constexpr std::size_t kLeeActionDim = 4;
constexpr std::size_t kPoseActionDim = 7;

/// lee_position_control, action [x_w, y_w, z_w, yaw] (m, m, m, rad).
Wrench update_lee_position(const LeeParams& params, LeeState& state, const RigidBodyState& body,
                           const real* action);
/// lee_velocity_control, action [vx_v, vy_v, vz_v, yaw_rate] (m/s in the vehicle frame, Euler
/// yaw rate in rad/s). The heading is the current yaw; yaw moves through the rate term only.
Wrench update_lee_velocity(const LeeParams& params, LeeState& state, const RigidBodyState& body,
                           const real* action);
/// lee_acceleration_control, action [ax_w, ay_w, az_w, yaw_rate] (m/s^2, rad/s).
Wrench update_lee_acceleration(const LeeParams& params, LeeState& state, const RigidBodyState& body,
                               const real* action);
/// lee_attitude_control, action [thrust, roll, pitch, yaw_rate]: fz = (thrust + 1) m |g|
/// (not tilt-compensated), desired attitude Rz(current yaw) Ry(pitch) Rx(roll).
Wrench update_lee_attitude(const LeeParams& params, LeeState& state, const RigidBodyState& body,
                           const real* action);
/// lee_rates_control, action [thrust, p, q, r] (body rates, rad/s). fz = (thrust + 1) m |g| as
/// the attitude controller (the reference's own thrust line crashes), torques as the reference's
/// torque routine with R_d = R (r clamped to +-max_yaw_rate on a copy).
Wrench update_lee_rates(const LeeParams& params, LeeState& state, const RigidBodyState& body,
                        const real* action);
/// Aerial Gym's LeeVelocitySteeringAngleController, action [vx_v, vy_v, vz_v, yaw] (m/s, rad):
/// velocity control with an absolute heading and no rate feed-forward.
Wrench update_lee_velocity_steering_angle(const LeeParams& params, LeeState& state, const RigidBodyState& body,
                                          const real* action);
/// rov_fully_actuated_control, action [x_w, y_w, z_w, qx, qy, qz, qw]: full 3-D body force and
/// torque toward a pose. The command quaternion is normalised on a copy (never in the caller's
/// array); a (near-)zero quaternion gives the identity attitude, as the reference's eps-clamped
/// normalisation does, and raises kFaultSingular.
Wrench update_rov_fully_actuated(const LeeParams& params, LeeState& state, const RigidBodyState& body,
                                 const real* action);

/// What the controllers derive from the state quaternion, computed once per update: the rotation
/// matrix (of the quaternion as given: like the reference, it is not re-normalised) and the cosine
/// and sine of the Euler yaw (R = Rz(yaw) Ry(pitch) Rx(roll)) without calling any trig function:
/// (cos yaw, sin yaw) = (R00, R10) / |(R00, R10)|, the same two numbers whose atan2 is the yaw.
/// At pitch +-90 deg, where yaw is undefined, it is 0 (cos 1, sin 0).
struct AttitudeFrame {
  Mat3 r_wb;
  real cos_yaw = 1;
  real sin_yaw = 0;
};
AttitudeFrame attitude_frame(const Quat& q_wb);

}  // namespace kestrel
