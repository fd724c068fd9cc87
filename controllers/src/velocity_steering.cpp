// Velocity + steering-angle controller (see the header for the model and its sources).
#include "kestrel/controllers/velocity_steering.hpp"

#include "kestrel/kernel/math.hpp"

namespace kestrel {

namespace {
bool pos_finite(real v) { return is_finite(v) && v > 0; }
bool nonneg_finite(real v) { return is_finite(v) && v >= 0; }

// tan through the deterministic sin_cos (same bits on host and MCU); |delta| <= max_steering < pi/2
// keeps the cosine away from zero.
real tan_det(real a) {
  real s = 0, c = 1;
  sin_cos(a, s, c);
  return s / c;
}
}  // namespace

Status validate_velocity_steering_params(const VelocitySteeringParams& p) {
  const bool ok = pos_finite(p.wheelbase_m) && pos_finite(p.mass_kg) && pos_finite(p.max_speed_m_s) &&
                  nonneg_finite(p.max_reverse_speed_m_s) && pos_finite(p.max_accel_m_s2) && nonneg_finite(p.max_decel_m_s2) &&
                  pos_finite(p.max_steering_rad) && p.max_steering_rad < 1.5_r && pos_finite(p.max_steering_rate_rad_s) &&
                  nonneg_finite(p.k_speed) && nonneg_finite(p.k_speed_i);
  return ok ? Status::ok : Status::invalid_argument;
}

void velocity_steering_reset(VelocitySteeringState& s, real gain_scale) {
  s = VelocitySteeringState();
  s.gain_scale = is_finite(gain_scale) && gain_scale >= 0 ? gain_scale : 1;
}

real bicycle_yaw_rate(real speed_m_s, real steering_rad, real wheelbase_m) {
  return speed_m_s * tan_det(steering_rad) / wheelbase_m;
}

real bicycle_turn_radius(real steering_rad, real wheelbase_m) {
  if (steering_rad == 0) return 0;
  return wheelbase_m / tan_det(steering_rad);
}

Status update_velocity_steering(const VelocitySteeringParams& p, VelocitySteeringState& s, real measured_speed_m_s,
                                const real* action, real dt_s, VelocitySteeringOutput& out) {
  s.step_faults = 0;
  auto hold = [&](std::uint32_t fault) {
    s.step_faults |= fault;
    s.faults.raise(fault);
    out.accel_m_s2 = s.last_accel_m_s2;
    out.force_N = p.mass_kg * s.last_accel_m_s2;
    out.steering_rad = s.steering_rad;
    out.speed_m_s = is_finite(measured_speed_m_s) ? measured_speed_m_s : 0;
    out.yaw_rate_radps = bicycle_yaw_rate(out.speed_m_s, s.steering_rad, p.wheelbase_m);
  };
  if (!(dt_s > 0) || !is_finite(dt_s)) {
    hold(kFaultNonFiniteCommand);
    return is_finite(dt_s) ? Status::invalid_argument : Status::non_finite_input;
  }
  if (!is_finite(action[0]) || !is_finite(action[1])) {
    hold(kFaultNonFiniteCommand);
    return Status::non_finite_input;
  }
  if (!is_finite(measured_speed_m_s)) {
    hold(kFaultNonFiniteState);
    return Status::non_finite_input;
  }
  // Command limits.
  const real v_cmd = clamp(action[0], -p.max_reverse_speed_m_s, p.max_speed_m_s);
  const real d_cmd = clamp(action[1], -p.max_steering_rad, p.max_steering_rad);
  if (v_cmd != action[0] || d_cmd != action[1]) {
    s.step_faults |= kFaultCommandOutOfRange;
    s.faults.raise(kFaultCommandOutOfRange);
  }
  // Steering actuator: slew-rate limited toward the command.
  const real max_step = p.max_steering_rate_rad_s * dt_s;
  const real d_new = clamp(s.steering_rad + clamp(d_cmd - s.steering_rad, -max_step, max_step), -p.max_steering_rad,
                           p.max_steering_rad);
  // Speed loop: PI with conditional integration (the integral only grows when the output is not
  // clipped in the direction of the error), the simplest anti-windup that keeps the loop stable.
  const real err = v_cmd - measured_speed_m_s;
  const real kp = p.k_speed * s.gain_scale, ki = p.k_speed_i * s.gain_scale;
  const real integral_try = s.speed_error_integral_m + err * dt_s;
  const real a_raw = kp * err + ki * integral_try;
  const real a = clamp(a_raw, -p.max_decel_m_s2, p.max_accel_m_s2);
  if (a != a_raw) {
    s.step_faults |= kFaultSaturated;
    s.faults.raise(kFaultSaturated);
  }
  const bool windup = (a_raw > a && err > 0) || (a_raw < a && err < 0);
  if (!windup) s.speed_error_integral_m = integral_try;
  s.steering_rad = d_new;
  s.last_accel_m_s2 = a;
  out.accel_m_s2 = a;
  out.force_N = p.mass_kg * a;
  out.steering_rad = d_new;
  // Braking never reverses the direction of travel: a car moving (or standing) forwards with a
  // command >= 0 stops at zero instead of backing up (and symmetrically in reverse); at the stop
  // the brake holds and the integral is cleared, so a parked car does not creep.
  real v_next = measured_speed_m_s + a * dt_s;
  if ((measured_speed_m_s >= 0 && v_next < 0 && v_cmd >= 0) || (measured_speed_m_s <= 0 && v_next > 0 && v_cmd <= 0)) {
    v_next = 0;
    s.speed_error_integral_m = 0;
  }
  out.speed_m_s = v_next;
  out.yaw_rate_radps = bicycle_yaw_rate(v_next, d_new, p.wheelbase_m);
  return Status::ok;
}

}  // namespace kestrel
