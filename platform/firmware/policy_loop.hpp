// The trained position policy flying the firmware example's vehicle: the same 500 Hz closed loop as
// flight_loop.hpp (core chain robots::multirotor_* -> rigid-body plant, all on the target), with
// the command coming from the policy network instead of a position setpoint:
//
//   observation (policy/observations.hpp: the training task's builder, error in the vehicle frame
//   as Kestrel-PositionSetpoint-v0's vehicle_frame_obs)
//     -> policy::mlp_forward (the exported actor, position_policy.hpp, weights in flash)
//     -> the task's action clip (+-10) -> Lee velocity control [vx, vy, vz, yaw rate]
//     -> allocation -> motor model -> plant.
//
// The vehicle starts hovering at the first waypoint and flies the same second waypoint as the Lee
// example, so the report prints both tracking errors side by side.
#pragma once

#include <cstdint>

#include "flight_loop.hpp"

namespace kestrel::firmware {

struct PolicyFlightReport {
  int steps = 0;
  real hold_rms_error_m = 0;    // RMS position error over the hold window of the second waypoint
  real final_error_m = 0;
  real lee_hold_rms_error_m = 0;  // the Lee position controller over the same window (same start)
  real lee_final_error_m = 0;
  int rejected_inferences = 0;  // non-finite observations or outputs (the last action is held)
  std::uint32_t faults = 0;
  std::uint64_t policy_cost_total = 0;   // clock units summed over inferences (observation + MLP)
  std::uint64_t control_cost_total = 0;  // clock units of the chain after the policy
  // FNV-1a (64-bit) over the bits of the plant state (position, orientation xyzw, linear and
  // angular velocity) after every step of each flight: the host build and the MCU image print
  // it, and the ctest kestrel_firmware_policy.host_parity requires the same values, so the desktop
  // harness is shown to reproduce the firmware's trajectory bit for bit, not within a tolerance.
  std::uint64_t policy_trajectory_hash = 0;
  std::uint64_t lee_trajectory_hash = 0;
  bool finite = true;
};

/// Flies the policy, then the Lee position controller over the same course; fills the report.
[[nodiscard]] Status fly_policy(const FlightConfig& c, FlightStack& s, Plant& p, ClockFn clock, WaitFn wait,
                                PolicyFlightReport& r);
/// The pass criterion: finite, no rejected inference, final error within the task's success radius.
bool policy_flight_pass(const PolicyFlightReport& r);
void print_policy_report(const PolicyFlightReport& r, const char* target, const char* cost_unit, double cost_scale);

}  // namespace kestrel::firmware
