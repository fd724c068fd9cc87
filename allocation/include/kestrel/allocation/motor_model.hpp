// First-order motor (rotor thrust) model with asymmetric time constants, rate limit, optional
// rotor-speed state, Euler or RK4 integration — exactly the model of the Aerial Gym Simulator's
// `MotorModel` (control/motor_model.py), checked against golden/motor_model.json.
//
// One update with time step dt, per motor (golden/README.md, "motor_model.json"):
//  1. r = clamp(reference, thrust_min, thrust_max). The thrust state itself is never clamped.
//  2. tau = decreasing constant if sign0(f) * sign0(r - f) < 0 (|f| moving toward zero), else the
//     increasing one (also for f == 0 and r == f: sign0(0) = 0, torch.sign semantics; quirk 8 —
//     the switch is discontinuous there and nothing here smooths it, for parity).
//  3. k = 1 / (dt + tau) with the discrete approximation, 1 / tau without.
//  4. rate(x) = clamp(k (target - x), -max_rate, max_rate); force mode: x = f, target = r;
//     rotor-speed mode: x = sqrt(f / c), target = sqrt(r / c), f = c x^2 after the update, with
//     the same k (chosen from the *thrust* signs) and max_rate acting on the rotor speed.
//  5. Euler x += dt rate(x); RK4 with the clamp inside every stage, k and target fixed in the step.
//
// Quirk 9 (rotor-speed mode with a negative thrust_min would take sqrt of a negative number and
// produce NaN in the reference): such a configuration is rejected with Status::invalid_argument.
// A signed square root was considered and rejected: a reversible rotor's thrust is not c w^2 on
// the negative side, so it would be a made-up model with no reference to check it against.
//
// Kestrel additions (not in the reference): per-motor faults (dead / weak, optionally scheduled),
// non-finite reference handling (the last finite reference is held, kFaultNonFiniteCommand is
// latched; the state never becomes NaN), and the per-motor reaction torque output.
#pragma once

#include <cstdint>

#include "kestrel/allocation/airframe.hpp"
#include "kestrel/kernel/rng.hpp"
#include "kestrel/kernel/status.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel::allocation {

enum class MotorIntegrator : std::uint8_t { euler, rk4 };

/// Motor model configuration (read-only in the step). Per-motor constants are drawn uniformly
/// from [min, max] at reset (min == max gives fixed constants, as in the golden configurations).
struct MotorModelConfig {
  int num_motors = 4;
  MotorIntegrator integrator = MotorIntegrator::rk4;  // Aerial Gym falls back to RK4
  bool use_rps = false;                               // rotor-speed state (thrust = c w^2)
  bool use_discrete_approximation = true;             // k = 1/(dt + tau) instead of 1/tau
  real thrust_min_N = 0;
  real thrust_max_N = 2;
  real time_constant_increasing_min_s = 0.04_r;
  real time_constant_increasing_max_s = 0.04_r;
  real time_constant_decreasing_min_s = 0.04_r;
  real time_constant_decreasing_max_s = 0.04_r;
  real thrust_constant_min = 0;  // N / (rotor speed unit)^2, rotor-speed mode only
  real thrust_constant_max = 0;
  real max_rate = 100000;                  // N/s (force mode) or rotor-speed units/s (rps mode)
  real thrust_to_torque_m = 0.01_r;        // reaction torque ratio (N m / N)
  std::int8_t direction[kMaxRotors] = {};  // +1 / -1 (see airframe.hpp); 0 gives no reaction torque
};

/// Per-motor mutable state and the per-instance constants drawn at reset.
struct MotorModelState {
  int num_motors = 0;
  real thrust_N[kMaxRotors] = {};         // output: thrust after the last update
  real axial_torque_Nm[kMaxRotors] = {};  // output: -direction * ratio * thrust
  real time_constant_increasing_s[kMaxRotors] = {};
  real time_constant_decreasing_s[kMaxRotors] = {};
  real thrust_constant[kMaxRotors] = {};   // rps mode
  real health_scale[kMaxRotors] = {};      // 1 healthy, (0, 1) weak (limits scaled), 0 dead
  real pending_scale[kMaxRotors] = {};     // scheduled failure: scale to apply ...
  real failure_time_s[kMaxRotors] = {};    // ... from this time on
  real last_reference_N[kMaxRotors] = {};  // last finite reference (held on NaN/inf input)
  std::uint16_t pending_mask = 0;          // bit i: motor i has a scheduled failure
  real elapsed_s = 0;                      // time since reset (start of the next step)
  FaultFlags faults;                       // kFaultNonFiniteCommand, kFaultMotorFailure, ...
};

/// Checks ranges: 1..kMaxRotors motors, min <= max everywhere, time constants > 0, max_rate > 0,
/// rotor-speed mode needs thrust_constant_min > 0 and thrust_min_N >= 0 (quirk 9).
[[nodiscard]] Status validate(const MotorModelConfig& cfg);

/// Draws the per-motor constants from `rng` (per motor, in order: tau_increasing,
/// tau_decreasing, thrust_constant — always all three, so the stream position does not depend on
/// the mode) and sets the initial thrust: `initial_thrust_N` (clamped to the limits) if given,
/// else uniform in [thrust_min, thrust_max] as the reference does. Clears faults and scheduled
/// failures. The last reference starts at the initial thrust (a NaN before any finite reference
/// holds the motor where it is).
[[nodiscard]] Status motor_model_reset(const MotorModelConfig& cfg, MotorModelState& state, RngStream& rng,
                                       const real* initial_thrust_N = nullptr);

/// One update of all motors with reference thrusts `reference_thrust_N` (num_motors values).
/// Returns ok, non_finite_input (some references were non-finite and held), non_finite_output (a
/// motor's new thrust overflowed, e.g. under an absurd dt: its previous thrust was kept and
/// kFaultNonFiniteOutput latched), or invalid_argument (dt not finite or <= 0, or a state that was
/// never reset; nothing changed).
[[nodiscard]] Status motor_model_step(const MotorModelConfig& cfg, MotorModelState& state,
                                      const real* reference_thrust_N, real dt_s);

/// Marks motor `motor` as failed from `at_time_s` (time since reset) on: thrust_scale 0 = dead
/// (thrust forced to 0), (0, 1) = weak (thrust limits scaled by the factor), 1 = healthy again.
/// A time <= elapsed_s applies at the next step. The failure takes effect at the first step whose
/// start time is at least at_time_s - dt/2 (so accumulated round-off in the clock does not move it
/// by a step). Latches kFaultMotorFailure when applied (unless the scale is 1).
[[nodiscard]] Status schedule_motor_failure(MotorModelState& state, int motor, real thrust_scale, real at_time_s);

/// Applies a failure immediately (same as scheduling it for the current time; the thrust of a
/// dead motor is set to 0 at once).
[[nodiscard]] Status inject_motor_failure(MotorModelState& state, int motor, real thrust_scale);

}  // namespace kestrel::allocation
