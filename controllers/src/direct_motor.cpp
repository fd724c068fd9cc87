// Direct motor commands (see direct_motor.hpp).
#include "kestrel/controllers/direct_motor.hpp"

#include "kestrel/kernel/assert.hpp"
#include "kestrel/kernel/math.hpp"

namespace kestrel {

Status validate_direct_motor_params(const DirectMotorParams& p) {
  if (p.num_motors < 1 || p.num_motors > kMaxMotors) return Status::invalid_argument;
  for (std::size_t i = 0; i < p.num_motors; ++i) {
    if (!is_finite(p.min_thrust_N[i]) || !is_finite(p.max_thrust_N[i])) return Status::invalid_argument;
    if (!(p.min_thrust_N[i] <= p.max_thrust_N[i])) return Status::invalid_argument;
  }
  return Status::ok;
}

DirectMotorParams direct_motor_params(std::size_t num_motors, real min_thrust_N, real max_thrust_N) {
  DirectMotorParams p;
  p.num_motors = num_motors < kMaxMotors ? num_motors : kMaxMotors;
  for (std::size_t i = 0; i < p.num_motors; ++i) {
    p.min_thrust_N[i] = min_thrust_N;
    p.max_thrust_N[i] = max_thrust_N;
  }
  return p;
}

void direct_motor_reset(const DirectMotorParams& p, DirectMotorState& s) {
  s = DirectMotorState();
  for (std::size_t i = 0; i < p.num_motors && i < kMaxMotors; ++i) {
    s.last_safe_thrust_N[i] = clamp(0, p.min_thrust_N[i], p.max_thrust_N[i]);
  }
}

void update_direct_motor(const DirectMotorParams& p, DirectMotorState& s, const real* cmd, real* out) {
  KESTREL_ASSERT(cmd != nullptr && out != nullptr && p.num_motors <= kMaxMotors);
  const std::size_t n = p.num_motors;
  std::uint32_t faults = 0;
  if (!all_finite(cmd, static_cast<int>(n))) {
    faults = kFaultNonFiniteCommand;
  } else {
    for (std::size_t i = 0; i < n; ++i) {
      const real v = clamp(cmd[i], p.min_thrust_N[i], p.max_thrust_N[i]);
      if (v != cmd[i]) faults |= kFaultSaturated;
      s.last_safe_thrust_N[i] = v;
    }
  }
  for (std::size_t i = 0; i < n; ++i) out[i] = s.last_safe_thrust_N[i];
  s.step_faults = faults;
  s.faults.raise(faults);
}

}  // namespace kestrel
