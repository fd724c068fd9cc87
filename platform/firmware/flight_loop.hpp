// The closed-loop firmware example: the control stack a flight controller runs (Lee position
// controller -> sequential-desaturation allocation -> motor model) closing the loop with the
// core's rigid-body plant, all on the target itself. The same code runs on the host and on the
// emulated Cortex-M4F; only the clock differs (host: nanoseconds, MCU: SysTick ticks that QEMU's
// -icount shift=0 turns into exact instruction counts).
//
// Scenario: the base quadrotor (Aerial Gym's 0.25 kg quad) starts on the ground, takes off to a
// 1 m hover setpoint, then steps to a second setpoint 1.1 m away with a 0.5 rad yaw change, and
// holds it. The report gives the tracking error over each hold window and the cost of one control
// step.
#pragma once

#include <cstdint>

#include "kestrel/allocation/airframe.hpp"
#include "kestrel/allocation/allocation_model.hpp"
#include "kestrel/allocation/motor_model.hpp"
#include "kestrel/allocation/sequential_desaturation.hpp"
#include "kestrel/controllers/lee.hpp"
#include "kestrel/kernel/rigid_body.hpp"
#include "kestrel/robots/multirotor.hpp"
#include "kestrel/kernel/status.hpp"

namespace kestrel::firmware {

/// One position setpoint [x, y, z, yaw], active from t_s on.
struct Waypoint {
  real t_s;
  real position_w[3];
  real yaw_rad;
};

struct FlightConfig {
  real control_rate_hz = 500;  // control and plant rate (one motor-model and plant step per tick)
  real duration_s = 12;
  int num_waypoints = 2;
  Waypoint waypoints[4] = {{0, {0, 0, 1}, 0}, {6, {1, -0.5_r, 1.5_r}, 0.5_r}};
  real hold_window_s = 1.5_r;  // tracking error is measured over the last part of each segment
};

/// What lives on the flight controller: constant parameters and the state each stage owns.
/// The chain is the core's (robots/multirotor.hpp), the same code the simulator steps.
struct FlightStack {
  robots::MultirotorModel model;  // Lee position gains, airframe, allocation model, motor constants
  robots::MultirotorState state;  // controller, allocator and motor state
  robots::MultirotorOutput out;   // the last controller wrench and thrust setpoints
};

/// The simulated vehicle the stack flies (closed on the target itself).
struct Plant {
  RigidBodyModel body;
  RigidBodyState state;
};

/// Builds every stage from the presets. Returns the first failing status.
[[nodiscard]] Status flight_init(FlightStack& stack, Plant& plant);

/// One control step: position command [x, y, z, yaw] -> wrench -> motor thrusts -> motor model.
void control_step(FlightStack& stack, const RigidBodyState& estimate, const real* command, real dt_s);

/// One plant step with the motors' current thrusts (wrench = A f, reaction torques included);
/// the ground is a floor at z = 0 that the vehicle rests on.
void plant_step(const FlightStack& stack, Plant& plant, real dt_s);

/// Per-segment hold error and totals, accumulated by fly().
struct FlightReport {
  int steps = 0;
  real takeoff_time_s = -1;          // first time within 0.1 m of the first setpoint
  real hold_rms_error_m[4] = {};     // RMS position error over each segment's hold window
  real hold_max_error_m[4] = {};
  real hold_yaw_error_rad[4] = {};   // |yaw error| at the end of each segment
  real final_error_m = 0;
  std::uint32_t faults = 0;          // union of the stages' fault bits
  std::uint64_t control_cost_total = 0;  // clock units summed over every control step
  std::uint64_t plant_cost_total = 0;
  bool finite = true;
};

/// Clock used to time the control and plant steps (host: ns; MCU: SysTick ticks).
using ClockFn = std::uint64_t (*)();
/// Called once per tick before the step (MCU: waits for the SysTick interrupt); may be null.
using WaitFn = void (*)();

/// Flies the scenario. Returns ok, or the status of a failed initialisation.
[[nodiscard]] Status fly(const FlightConfig& config, FlightStack& stack, Plant& plant, ClockFn clock, WaitFn wait,
                         FlightReport& report);

/// The example's pass criterion: finite throughout, took off, final error under 5 cm.
bool flight_pass(const FlightReport& report);

/// Prints the report; `cost_unit` names the clock unit and `cost_scale` converts clock units to it.
void print_report(const FlightConfig& config, const FlightReport& report, const char* target, const char* cost_unit,
                  double cost_scale);

}  // namespace kestrel::firmware

namespace kestrel::firmware {
/// Clock units for `n` back-to-back control steps from a hovering state (the steady-state cost,
/// without the loop's waiting and bookkeeping), minus the cost of reading the clock.
std::uint64_t time_control_steps(FlightStack& stack, int n, ClockFn clock);
}  // namespace kestrel::firmware
