// Motor model: see motor_model.hpp for the equations and their source.
#include "kestrel/allocation/motor_model.hpp"

#include <cmath>

#include "kestrel/kernel/math.hpp"

namespace kestrel::allocation {

namespace {

bool range_ok(real lo, real hi) { return is_finite(lo) && is_finite(hi) && lo <= hi; }

/// One stage of the rate function: the clamp is applied inside every RK4 stage (as the reference).
inline real motor_rate(real gain, real target, real x, real max_rate) {
  return clamp(gain * (target - x), -max_rate, max_rate);
}

void apply_failure(MotorModelState& state, int i, real scale) {
  state.health_scale[i] = scale;
  if (scale < 1) state.faults.raise(kFaultMotorFailure);
  if (scale == 0) state.thrust_N[i] = 0;  // dead: no spin-down, the thrust is gone from this step on
}

}  // namespace

Status validate(const MotorModelConfig& cfg) {
  if (cfg.num_motors < 1 || cfg.num_motors > kMaxRotors) return Status::invalid_argument;
  if (!range_ok(cfg.thrust_min_N, cfg.thrust_max_N)) return Status::invalid_argument;
  if (!range_ok(cfg.time_constant_increasing_min_s, cfg.time_constant_increasing_max_s) ||
      !(cfg.time_constant_increasing_min_s > 0)) {
    return Status::invalid_argument;
  }
  if (!range_ok(cfg.time_constant_decreasing_min_s, cfg.time_constant_decreasing_max_s) ||
      !(cfg.time_constant_decreasing_min_s > 0)) {
    return Status::invalid_argument;
  }
  if (!is_finite(cfg.max_rate) || !(cfg.max_rate > 0) || !is_finite(cfg.thrust_to_torque_m)) {
    return Status::invalid_argument;
  }
  if (cfg.integrator != MotorIntegrator::euler && cfg.integrator != MotorIntegrator::rk4)
    return Status::invalid_argument;
  if (cfg.use_rps) {
    if (!range_ok(cfg.thrust_constant_min, cfg.thrust_constant_max) || !(cfg.thrust_constant_min > 0)) {
      return Status::invalid_argument;
    }
    // Quirk 9: sqrt(f / c) of a negative thrust. Rejected rather than patched (see the header).
    if (cfg.thrust_min_N < 0) return Status::invalid_argument;
  }
  return Status::ok;
}

Status motor_model_reset(const MotorModelConfig& cfg, MotorModelState& state, RngStream& rng,
                         const real* initial_thrust_N) {
  const Status st = validate(cfg);
  if (st != Status::ok) return st;
  if (initial_thrust_N != nullptr && !all_finite(initial_thrust_N, cfg.num_motors)) return Status::invalid_argument;
  MotorModelState s;
  s.num_motors = cfg.num_motors;
  for (int i = 0; i < cfg.num_motors; ++i) {
    s.time_constant_increasing_s[i] =
        rng.uniform(cfg.time_constant_increasing_min_s, cfg.time_constant_increasing_max_s);
    s.time_constant_decreasing_s[i] =
        rng.uniform(cfg.time_constant_decreasing_min_s, cfg.time_constant_decreasing_max_s);
    s.thrust_constant[i] = rng.uniform(cfg.thrust_constant_min, cfg.thrust_constant_max);
  }
  for (int i = 0; i < cfg.num_motors; ++i) {
    const real f0 = initial_thrust_N != nullptr ? clamp(initial_thrust_N[i], cfg.thrust_min_N, cfg.thrust_max_N)
                                                : rng.uniform(cfg.thrust_min_N, cfg.thrust_max_N);
    s.thrust_N[i] = f0;
    s.last_reference_N[i] = f0;
    s.health_scale[i] = 1;
    s.axial_torque_Nm[i] = -static_cast<real>(cfg.direction[i]) * cfg.thrust_to_torque_m * f0;
  }
  state = s;
  return Status::ok;
}

namespace {

/// The per-motor loop of motor_model_step, with the rotor-speed choice fixed at compile time: RK4
/// or explicit Euler on the thrust or on the rotor speed sqrt(f / c); gain and target fixed in
/// the step. (A quadrotor-unrolled copy was measured: more instructions on the Cortex-M4F, the
/// unrolled body spills; so one rolled loop.)
template <bool kRps>
Status step_motors(const MotorModelConfig& cfg, MotorModelState& state, const real* reference_thrust_N, real dt_s) {
  const bool rk4 = cfg.integrator != MotorIntegrator::euler;
  const int n = state.num_motors;
  Status status = Status::ok;
  // Configuration in locals: the stores into `state` below could alias `cfg` as far as the
  // compiler knows, which would reload every field for every motor.
  const bool discrete = cfg.use_discrete_approximation;
  const real thrust_min = cfg.thrust_min_N, thrust_max = cfg.thrust_max_N;
  const real max_rate = cfg.max_rate;
  const real half_max_rate = 0.5_r * max_rate;
  const real ratio = cfg.thrust_to_torque_m;
  const real half_dt = 0.5_r * dt_s;
  const real dt_6 = dt_s / 6.0_r;
  const std::uint16_t pending = state.pending_mask;
  for (int i = 0; i < n; ++i) {
    if (pending != 0 && (state.pending_mask & (1u << i)) != 0 && state.elapsed_s + half_dt >= state.failure_time_s[i]) {
      state.pending_mask = static_cast<std::uint16_t>(state.pending_mask & ~(1u << i));
      apply_failure(state, i, state.pending_scale[i]);
    }

    real ref = reference_thrust_N[i];
    if (is_finite(ref)) {
      state.last_reference_N[i] = ref;
    } else {
      ref = state.last_reference_N[i];
      state.faults.raise(kFaultNonFiniteCommand);
      status = Status::non_finite_input;
    }

    const real scale = state.health_scale[i];
    if (scale == 0) {
      state.thrust_N[i] = 0;
      state.axial_torque_Nm[i] = 0;
      continue;
    }
    // A weak motor: both limits scaled (for a unidirectional rotor that is the max only).
    const real lo = scale * thrust_min;
    const real hi = scale * thrust_max;
    const real r = clamp(ref, lo, hi);
    const real f = state.thrust_N[i];
    // sign0(f) * sign0(r - f) < 0: f and r - f of opposite signs, neither zero (nor NaN).
    const real e = r - f;
    const bool decreasing = (f > 0 && e < 0) || (f < 0 && e > 0);
    const real tau = decreasing ? state.time_constant_decreasing_s[i] : state.time_constant_increasing_s[i];
    const real gain = discrete ? 1.0_r / (dt_s + tau) : 1.0_r / tau;

    real c = 0, target = r, x = f;
    if constexpr (kRps) {
      c = state.thrust_constant[i];
      target = std::sqrt(r / c);
      x = std::sqrt(f / c);
    }
    // The clamp is applied inside every RK4 stage (as the reference).
    const real s1_raw = gain * (target - x);
    real x_new;
    if (rk4 && discrete && std::fabs(s1_raw) <= half_max_rate) {
      // Unclamped fast path, bit-identical to the clamped stages below: with the discrete
      // approximation dt k = dt / (dt + tau) < 1, so each later stage's error target - x_j is
      // e (1 - c dt k) with 0 <= c dt k <= 1 (to round-off): |s_j| <= |s1| (1 + a few ulp), and
      // with |s1| <= max_rate / 2 no clamp can bind (a clamp that does not bind returns its
      // argument unchanged). Saves the 4 two-sided clamps (~28 Cortex-M4F instructions) per motor
      // in the common case; NaN fails the test and takes the clamped path.
      const real s2 = gain * (target - (x + half_dt * s1_raw));
      const real s3 = gain * (target - (x + half_dt * s2));
      const real s4 = gain * (target - (x + dt_s * s3));
      x_new = x + dt_6 * (s1_raw + 2.0_r * s2 + 2.0_r * s3 + s4);
    } else if (rk4) {
      const real s1 = clamp(s1_raw, -max_rate, max_rate);
      const real s2 = motor_rate(gain, target, x + half_dt * s1, max_rate);
      const real s3 = motor_rate(gain, target, x + half_dt * s2, max_rate);
      const real s4 = motor_rate(gain, target, x + dt_s * s3, max_rate);
      x_new = x + dt_6 * (s1 + 2.0_r * s2 + 2.0_r * s3 + s4);
    } else {
      x_new = x + dt_s * clamp(s1_raw, -max_rate, max_rate);
    }
    real f_new = x_new;
    if constexpr (kRps) f_new = c * x_new * x_new;
    if (!is_finite(f_new)) {
      // Cannot happen with a validated config, finite state and a sane dt; kept as the last line of
      // defence so the state never holds NaN. A huge dt (e.g. 1e18 s) does get here: reported as a
      // status too, not only as a latched fault, so a caller checking the status sees the fallback.
      f_new = clamp(f, lo, hi);
      state.faults.raise(kFaultNonFiniteOutput);
      if (status == Status::ok) status = Status::non_finite_output;
    }
    state.thrust_N[i] = f_new;
    state.axial_torque_Nm[i] = -static_cast<real>(cfg.direction[i]) * ratio * f_new;
  }
  state.elapsed_s += dt_s;
  return status;
}

}  // namespace

Status motor_model_step(const MotorModelConfig& cfg, MotorModelState& state, const real* reference_thrust_N,
                        real dt_s) {
  const int n = state.num_motors;
  if (n != cfg.num_motors || n < 1 || !is_finite(dt_s) || !(dt_s > 0) || reference_thrust_N == nullptr) {
    return Status::invalid_argument;
  }
  return cfg.use_rps ? step_motors<true>(cfg, state, reference_thrust_N, dt_s)
                     : step_motors<false>(cfg, state, reference_thrust_N, dt_s);
}

Status schedule_motor_failure(MotorModelState& state, int motor, real thrust_scale, real at_time_s) {
  if (motor < 0 || motor >= state.num_motors || !is_finite(thrust_scale) || thrust_scale < 0 || thrust_scale > 1 ||
      !is_finite(at_time_s)) {
    return Status::invalid_argument;
  }
  state.pending_scale[motor] = thrust_scale;
  state.failure_time_s[motor] = at_time_s;
  state.pending_mask = static_cast<std::uint16_t>(state.pending_mask | (1u << motor));
  return Status::ok;
}

Status inject_motor_failure(MotorModelState& state, int motor, real thrust_scale) {
  const Status st = schedule_motor_failure(state, motor, thrust_scale, state.elapsed_s);
  if (st != Status::ok) return st;
  state.pending_mask = static_cast<std::uint16_t>(state.pending_mask & ~(1u << motor));
  apply_failure(state, motor, thrust_scale);
  if (thrust_scale == 0) state.axial_torque_Nm[motor] = 0;
  return Status::ok;
}

}  // namespace kestrel::allocation
