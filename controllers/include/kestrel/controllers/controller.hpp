// One entry point over every multirotor/ROV controller, in the manner of Crazyflie's controller.c
// (an enum, a constant table of {name, update function}, no virtual calls): the simulator and the C
// API select a controller by kind or by Aerial Gym's registry name and call update_controller()
// with a uniform action array.
#pragma once

#include <cstddef>
#include <cstdint>

#include "kestrel/controllers/direct_motor.hpp"
#include "kestrel/controllers/lee.hpp"
#include "kestrel/kernel/rng.hpp"
#include "kestrel/kernel/status.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel {

/// Kinds, in Aerial Gym's registry order; names from controller_name().
enum class ControllerKind : std::uint8_t {
  lee_position = 0,             // "lee_position_control"                 [x, y, z, yaw]
  lee_velocity = 1,             // "lee_velocity_control"                 [vx, vy, vz, yaw_rate]
  lee_acceleration = 2,         // "lee_acceleration_control"             [ax, ay, az, yaw_rate]
  lee_attitude = 3,             // "lee_attitude_control"                 [thrust, roll, pitch, yaw_rate]
  lee_rates = 4,                // "lee_rates_control"                    [thrust, p, q, r]
  lee_velocity_steering_angle = 5,  // "lee_velocity_steering_angle_control" [vx, vy, vz, yaw]
  rov_fully_actuated = 6,       // "rov_fully_actuated_control"           [x, y, z, qx, qy, qz, qw]
  direct_motor = 7,             // "direct_motor_control"                 [f_0 .. f_{n-1}] (N)
};
constexpr std::size_t kNumControllerKinds = 8;

/// Width of the uniform action array: 7 for the pose command; direct motor commands take one
/// value per motor, up to kMaxMotors (8 for the octarotor/ROV airframes).
constexpr std::size_t kMaxActionDim = kMaxMotors > kPoseActionDim ? kMaxMotors : kPoseActionDim;

struct ControllerParams {
  LeeParams lee;              // every kind but direct_motor
  DirectMotorParams motors;   // direct_motor
};

struct ControllerState {
  LeeState lee;
  DirectMotorState motors;
};

struct ControllerOutput {
  bool is_wrench = true;       // true: wrench_b is the output; false: motor_thrust_N
  Wrench wrench_b;
  std::size_t num_motors = 0;
  real motor_thrust_N[kMaxMotors] = {};
};

/// Registry name of a kind ("unknown" outside the enum).
const char* controller_name(ControllerKind kind);
/// Kind of a registry name; false (kind untouched) if the name is not one of them.
[[nodiscard]] bool controller_kind_from_name(const char* name, ControllerKind& kind);
/// Number of action values the kind reads: 4, 7, or params.motors.num_motors (0 for an unknown kind).
std::size_t controller_action_dim(ControllerKind kind, const ControllerParams& params);
/// Whether the kind outputs a body wrench (all but direct_motor).
bool controller_outputs_wrench(ControllerKind kind);

/// Resets the part of `state` the kind uses (lee_reset / direct_motor_reset).
void controller_reset(ControllerKind kind, const ControllerParams& params, ControllerState& state);
/// As above, drawing randomised gains from `rng` where the params ask for it.
void controller_reset(ControllerKind kind, const ControllerParams& params, ControllerState& state, RngStream& rng);

/// One update of the selected controller. `action` holds at least controller_action_dim() values
/// (a wider uniform array is fine; the rest is ignored). Returns:
///  - Status::invalid_argument (nothing written) for an unknown kind or a too-short action;
///  - Status::non_finite_input when the controller rejected the input and held its last safe
///    output (see the fault bits in the kind's state);
///  - Status::ok otherwise (clipping/saturation/singular fallbacks show up as fault bits only).
[[nodiscard]] Status update_controller(ControllerKind kind, const ControllerParams& params, ControllerState& state,
                                       const RigidBodyState& body, const real* action, std::size_t action_len,
                                       ControllerOutput& out);

}  // namespace kestrel
