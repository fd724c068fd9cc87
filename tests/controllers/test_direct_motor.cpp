// Direct motor commands: pass-through with clamping and a held output on non-finite input.
#include <limits>

#include "kestrel/controllers/direct_motor.hpp"
#include "ktest.hpp"

using namespace kestrel;

KTEST(DirectMotor, ParamsValidate) {
  KEXPECT_TRUE(validate_direct_motor_params(direct_motor_params(4, 0, 2)) == Status::ok);
  KEXPECT_TRUE(validate_direct_motor_params(direct_motor_params(8, -6.25_r, 6.25_r)) == Status::ok);
  KEXPECT_TRUE(validate_direct_motor_params(direct_motor_params(0, 0, 2)) == Status::invalid_argument);
  KEXPECT_TRUE(validate_direct_motor_params(direct_motor_params(4, 2, 0)) == Status::invalid_argument);
  DirectMotorParams p = direct_motor_params(4, 0, 2);
  p.num_motors = kMaxMotors + 1;
  KEXPECT_TRUE(validate_direct_motor_params(p) == Status::invalid_argument);
}

KTEST(DirectMotor, PassesThroughAndClampsToMotorLimits) {
  const DirectMotorParams p = direct_motor_params(4, 0, 2);
  DirectMotorState s;
  KEXPECT_NO_HEAP(direct_motor_reset(p, s));
  const real in_range[4] = {0, 0.5_r, 1.25_r, 2};
  real out[4];
  KEXPECT_NO_HEAP(update_direct_motor(p, s, in_range, out));
  for (int i = 0; i < 4; ++i) KEXPECT_EQ(out[i], in_range[i]);
  KEXPECT_EQ(s.step_faults, 0u);
  const real outside[4] = {-1, 3, 1, 2.0001_r};
  KEXPECT_NO_HEAP(update_direct_motor(p, s, outside, out));
  KEXPECT_EQ(out[0], 0);
  KEXPECT_EQ(out[1], 2);
  KEXPECT_EQ(out[2], 1);
  KEXPECT_EQ(out[3], 2);
  KEXPECT_EQ(s.step_faults, static_cast<std::uint32_t>(kFaultSaturated));
  // Bidirectional limits and in-place use (output aliasing the command).
  const DirectMotorParams pb = direct_motor_params(8, -6.25_r, 6.25_r);
  DirectMotorState sb;
  direct_motor_reset(pb, sb);
  real buf[8] = {-7, -6.25_r, -1, 0, 1, 6.25_r, 7, 3};
  update_direct_motor(pb, sb, buf, buf);
  KEXPECT_EQ(buf[0], -6.25_r);
  KEXPECT_EQ(buf[2], -1);
  KEXPECT_EQ(buf[6], 6.25_r);
  KEXPECT_EQ(buf[7], 3);
}

KTEST(DirectMotor, NonFiniteCommandHoldsAllMotors) {
  DirectMotorParams p = direct_motor_params(4, 0.1_r, 2);  // idle thrust above zero
  DirectMotorState s;
  direct_motor_reset(p, s);
  const real nan = std::numeric_limits<real>::quiet_NaN();
  const real bad[4] = {1, nan, 1, 1};
  real out[4];
  // Before any good command: 0 N clamped into each motor's range.
  KEXPECT_NO_HEAP(update_direct_motor(p, s, bad, out));
  for (int i = 0; i < 4; ++i) KEXPECT_EQ(out[i], 0.1_r);
  KEXPECT_EQ(s.step_faults, static_cast<std::uint32_t>(kFaultNonFiniteCommand));
  const real good[4] = {0.5_r, 0.6_r, 0.7_r, 0.8_r};
  update_direct_motor(p, s, good, out);
  const real inf_cmd[4] = {1, 1, std::numeric_limits<real>::infinity(), 1};
  update_direct_motor(p, s, inf_cmd, out);
  for (int i = 0; i < 4; ++i) KEXPECT_EQ(out[i], good[i]);  // whole vector held, not mixed
  KEXPECT_TRUE(s.faults.has(kFaultNonFiniteCommand));
  direct_motor_reset(p, s);
  KEXPECT_FALSE(s.faults.any());
}
