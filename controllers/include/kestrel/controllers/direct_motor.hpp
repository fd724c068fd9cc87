// Direct motor commands: the action is the per-motor thrust reference itself (Aerial Gym's
// "no_control" path, where the policy outputs motor thrusts and the motor model tracks them).
//
// Per update: a non-finite command component rejects the whole command (all motors keep the last
// safe thrusts, kFaultNonFiniteCommand): a vector with one NaN comes from a broken source, and a
// consistent set from one earlier step is safer than a mix of old and new values. Otherwise each
// thrust is clamped to its motor's [min, max] (kFaultSaturated when any clamp acted).
#pragma once

#include <cstddef>
#include <cstdint>

#include "kestrel/kernel/status.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel {

/// Capacity of the direct-motor path (Aerial Gym's largest airframes, octarotor/ROV, have 8).
constexpr std::size_t kMaxMotors = 8;

struct DirectMotorParams {
  std::size_t num_motors = 0;
  real min_thrust_N[kMaxMotors] = {};
  real max_thrust_N[kMaxMotors] = {};
};

/// num_motors in [1, kMaxMotors], finite limits with min <= max.
[[nodiscard]] Status validate_direct_motor_params(const DirectMotorParams& params);

/// Uniform limits for the first n motors (e.g. quad [0, 2] N, octarotor [-6.25, 6.25] N).
DirectMotorParams direct_motor_params(std::size_t num_motors, real min_thrust_N, real max_thrust_N);

struct DirectMotorState {
  /// Output held while a command is rejected. Starts at 0 N clamped into each motor's range
  /// (idle: a vehicle must not spin up on a bad first command).
  real last_safe_thrust_N[kMaxMotors] = {};
  FaultFlags faults;              // latched until cleared (direct_motor_reset clears them)
  std::uint32_t step_faults = 0;  // fault bits raised by the most recent update only
};

void direct_motor_reset(const DirectMotorParams& params, DirectMotorState& state);

/// Reads params.num_motors thrust commands (N) and writes as many motor thrust references (N).
/// `thrust_out_N` may alias `thrust_cmd_N`.
void update_direct_motor(const DirectMotorParams& params, DirectMotorState& state, const real* thrust_cmd_N,
                         real* thrust_out_N);

}  // namespace kestrel
