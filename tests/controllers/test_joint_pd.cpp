// Joint PD controller (legged_gym's _compute_torques) with gain scales and an action-delay line.
#include <cmath>
#include <limits>

#include "kestrel/controllers/joint_pd.hpp"
#include "ktest.hpp"

using namespace kestrel;

namespace {

using Params = JointPdParams<12, 4>;
using State = JointPdState<12, 4>;

Params make(JointControlMode mode, std::size_t n = 3) {
  Params p;
  p.num_joints = n;
  p.mode = mode;
  for (std::size_t i = 0; i < n; ++i) {
    p.kp[i] = 20 + static_cast<real>(i);
    p.kd[i] = 0.5_r + 0.25_r * static_cast<real>(i);
    p.default_pos_rad[i] = 0.1_r * static_cast<real>(i) - 0.1_r;
    p.torque_limit_Nm[i] = 30;
  }
  p.action_scale = 0.25_r;
  p.dt_s = 0.005_r;
  return p;
}

}  // namespace

KTEST(JointPd, ParamsValidate) {
  Params p = make(JointControlMode::position);
  KEXPECT_TRUE(validate_joint_pd_params(p) == Status::ok);
  p.num_joints = 13;
  KEXPECT_TRUE(validate_joint_pd_params(p) == Status::invalid_argument);
  p = make(JointControlMode::position);
  p.delay_steps = 5;  // capacity is 4
  KEXPECT_TRUE(validate_joint_pd_params(p) == Status::invalid_argument);
  p = make(JointControlMode::velocity);
  p.dt_s = 0;
  KEXPECT_TRUE(validate_joint_pd_params(p) == Status::invalid_argument);
  p = make(JointControlMode::position);
  p.torque_limit_Nm[1] = -1;
  KEXPECT_TRUE(validate_joint_pd_params(p) == Status::invalid_argument);
  p = make(JointControlMode::position);
  p.gain_scale_ranges.kp_scale_min = 2;  // > max
  KEXPECT_TRUE(validate_joint_pd_params(p) == Status::invalid_argument);
}

KTEST(JointPd, PositionModeMatchesLeggedGym) {
  const Params p = make(JointControlMode::position);
  State s;
  joint_pd_reset(p, s);
  const real q[3] = {0.2_r, -0.1_r, 0.05_r};
  const real qd[3] = {1.0_r, -2.0_r, 0.5_r};
  const real act[3] = {0.4_r, -0.8_r, 2.0_r};
  real tau[3];
  Status st = Status::invalid_argument;
  KEXPECT_NO_HEAP(st = update_joint_pd(p, s, q, qd, act, tau));
  KEXPECT_TRUE(st == Status::ok);
  for (int i = 0; i < 3; ++i) {
    const double expect = static_cast<double>(p.kp[i]) * (0.25 * act[i] + p.default_pos_rad[i] - q[i]) -
                          static_cast<double>(p.kd[i]) * qd[i];
    KEXPECT_NEAR(tau[i], expect, 1e-5);
  }
  KEXPECT_EQ(s.step_faults, 0u);
}

KTEST(JointPd, VelocityModeUsesRateDifference) {
  const Params p = make(JointControlMode::velocity);
  State s;
  joint_pd_reset(p, s);
  const real q[3] = {0, 0, 0};
  const real qd0[3] = {0.5_r, -0.5_r, 0.1_r};
  const real qd1[3] = {0.6_r, -0.4_r, 0.1_r};
  const real act[3] = {1, 2, -1};
  real tau[3];
  KEXPECT_NO_HEAP((void)update_joint_pd(p, s, q, qd0, act, tau));
  // First update: last qd is 0 after reset.
  for (int i = 0; i < 3; ++i) {
    const double expect = static_cast<double>(p.kp[i]) * (0.25 * act[i] - qd0[i]) -
                          static_cast<double>(p.kd[i]) * (qd0[i] - 0.0) / 0.005;
    KEXPECT_NEAR(tau[i], expect > 30 ? 30 : (expect < -30 ? -30 : expect), 1e-3);
  }
  KEXPECT_NO_HEAP((void)update_joint_pd(p, s, q, qd1, act, tau));
  for (int i = 0; i < 3; ++i) {
    const double expect = static_cast<double>(p.kp[i]) * (0.25 * act[i] - qd1[i]) -
                          static_cast<double>(p.kd[i]) * (static_cast<double>(qd1[i]) - qd0[i]) / 0.005;
    KEXPECT_NEAR(tau[i], expect > 30 ? 30 : (expect < -30 ? -30 : expect), 1e-3);
  }
}

KTEST(JointPd, TorqueModeAndTorqueLimits) {
  Params p = make(JointControlMode::torque);
  p.torque_limit_Nm[0] = 0.2_r;
  State s;
  joint_pd_reset(p, s);
  const real q[3] = {0, 0, 0}, qd[3] = {0, 0, 0};
  const real act[3] = {2, -1, 0.4_r};  // scaled: 0.5, -0.25, 0.1
  real tau[3];
  KEXPECT_NO_HEAP((void)update_joint_pd(p, s, q, qd, act, tau));
  KEXPECT_NEAR(tau[0], 0.2, 1e-7);  // clipped to the limit
  KEXPECT_NEAR(tau[1], -0.25, 1e-7);
  KEXPECT_NEAR(tau[2], 0.1, 1e-7);
  KEXPECT_TRUE(s.step_faults & kFaultSaturated);
  // Limits are symmetric.
  const real neg[3] = {-2, 0, 0};
  (void)update_joint_pd(p, s, q, qd, neg, tau);
  KEXPECT_NEAR(tau[0], -0.2, 1e-7);
  // A large PD torque is clipped too.
  Params pp = make(JointControlMode::position);
  State ps;
  joint_pd_reset(pp, ps);
  const real far[3] = {10, -10, 0};
  real qfar[3] = {-3, 3, 0};
  (void)update_joint_pd(pp, ps, qfar, qd, far, tau);
  KEXPECT_EQ(tau[0], 30);
  KEXPECT_EQ(tau[1], -30);
}

KTEST(JointPd, ActionClipAndNonFiniteHold) {
  Params p = make(JointControlMode::torque);
  p.action_clip = 1;
  p.action_scale = 1;
  State s;
  joint_pd_reset(p, s);
  const real q[3] = {0, 0, 0}, qd[3] = {0, 0, 0};
  const real act[3] = {5, -0.5_r, 0.25_r};
  real tau[3];
  KEXPECT_TRUE(update_joint_pd(p, s, q, qd, act, tau) == Status::ok);
  KEXPECT_EQ(tau[0], 1);
  KEXPECT_TRUE(s.step_faults & kFaultCommandOutOfRange);
  const real nan = std::numeric_limits<real>::quiet_NaN();
  const real bad[3] = {0, nan, 0};
  Status st = Status::ok;
  KEXPECT_NO_HEAP(st = update_joint_pd(p, s, q, qd, bad, tau));
  KEXPECT_TRUE(st == Status::non_finite_input);
  KEXPECT_EQ(s.step_faults, static_cast<std::uint32_t>(kFaultNonFiniteCommand));
  KEXPECT_EQ(tau[0], 1);  // held
  KEXPECT_EQ(tau[1], -0.5_r);
  KEXPECT_EQ(tau[2], 0.25_r);
  const real bad_q[3] = {0, 0, std::numeric_limits<real>::infinity()};
  KEXPECT_TRUE(update_joint_pd(p, s, bad_q, qd, act, tau) == Status::non_finite_input);
  KEXPECT_EQ(s.step_faults, static_cast<std::uint32_t>(kFaultNonFiniteState));
  KEXPECT_EQ(tau[1], -0.5_r);
  for (int i = 0; i < 3; ++i) KEXPECT_TRUE(std::isfinite(s.last_safe_torque_Nm[i]) && std::isfinite(s.last_qd_radps[i]));
  KEXPECT_TRUE(s.faults.has(kFaultNonFiniteCommand | kFaultNonFiniteState | kFaultCommandOutOfRange));
}

KTEST(JointPd, DelayLineDelaysByExactlyKSteps) {
  for (std::size_t k = 0; k <= 4; ++k) {
    Params p = make(JointControlMode::torque, 2);
    p.action_scale = 1;
    p.delay_steps = k;
    State s;
    joint_pd_reset(p, s);
    KEXPECT_EQ(s.delay_line.size(), k);
    const real q[2] = {0, 0}, qd[2] = {0, 0};
    for (int t = 0; t < 12; ++t) {
      const real act[2] = {static_cast<real>(t + 1), -static_cast<real>(t + 1)};
      real tau[2];
      KEXPECT_NO_HEAP((void)update_joint_pd(p, s, q, qd, act, tau));
      // Action t+1 given at update t is applied at update t + k; before that: zero (reset fill).
      const real expect = t >= static_cast<int>(k) ? static_cast<real>(t + 1 - static_cast<int>(k)) : real(0);
      KEXPECT_EQ(tau[0], expect);
      KEXPECT_EQ(tau[1], -expect);
    }
    KEXPECT_EQ(s.delay_line.size(), k);
  }
}

KTEST(JointPd, RejectedUpdateDoesNotAdvanceDelayLine) {
  Params p = make(JointControlMode::torque, 1);
  p.action_scale = 1;
  p.delay_steps = 2;
  State s;
  joint_pd_reset(p, s);
  const real q[1] = {0}, qd[1] = {0};
  real tau[1];
  const real a1[1] = {1}, a2[1] = {2}, a3[1] = {3};
  const real nan[1] = {std::numeric_limits<real>::quiet_NaN()};
  (void)update_joint_pd(p, s, q, qd, a1, tau);  // applies 0
  (void)update_joint_pd(p, s, q, qd, nan, tau);  // rejected: holds 0, line unchanged
  KEXPECT_EQ(tau[0], 0);
  (void)update_joint_pd(p, s, q, qd, a2, tau);  // applies 0 (second reset zero)
  KEXPECT_EQ(tau[0], 0);
  (void)update_joint_pd(p, s, q, qd, a3, tau);  // applies a1
  KEXPECT_EQ(tau[0], 1);
}

KTEST(JointPd, PositionModeZeroActionHoldsDefaultPoseDuringDelay) {
  Params p = make(JointControlMode::position);
  p.delay_steps = 3;
  State s;
  joint_pd_reset(p, s);
  const real qd[3] = {0, 0, 0};
  const real act[3] = {4, 4, 4};
  real tau[3];
  for (int t = 0; t < 3; ++t) {
    (void)update_joint_pd(p, s, p.default_pos_rad, qd, act, tau);
    for (int i = 0; i < 3; ++i) KEXPECT_EQ(tau[i], 0);  // zero action = default position
  }
  (void)update_joint_pd(p, s, p.default_pos_rad, qd, act, tau);
  KEXPECT_NEAR(tau[0], static_cast<double>(p.kp[0]), 1e-5);  // kp * 0.25 * 4
}

KTEST(JointPd, GainScalesRandomisedPerInstance) {
  Params p = make(JointControlMode::position);
  p.gain_scale_ranges.kp_scale_min = 0.8_r;
  p.gain_scale_ranges.kp_scale_max = 1.2_r;
  p.gain_scale_ranges.kd_scale_min = 0.5_r;
  p.gain_scale_ranges.kd_scale_max = 1.5_r;
  p.randomize_gain_scales = true;
  KEXPECT_TRUE(validate_joint_pd_params(p) == Status::ok);
  State a, b, c;
  RngStream ra(42, 0, kPurposeGains), rb(42, 0, kPurposeGains), rc(42, 1, kPurposeGains);
  KEXPECT_NO_HEAP(joint_pd_reset(p, a, ra));
  joint_pd_reset(p, b, rb);
  joint_pd_reset(p, c, rc);
  KEXPECT_EQ(a.scales.kp_scale, b.scales.kp_scale);
  KEXPECT_EQ(a.scales.kd_scale, b.scales.kd_scale);
  KEXPECT_NE(a.scales.kp_scale, c.scales.kp_scale);
  for (std::uint32_t inst = 0; inst < 100; ++inst) {
    RngStream r(7, inst, kPurposeGains);
    const JointGainScales g = randomize_joint_gain_scales(p.gain_scale_ranges, r);
    KEXPECT_GE(g.kp_scale, 0.8_r);
    KEXPECT_LE(g.kp_scale, 1.2_r);
    KEXPECT_GE(g.kd_scale, 0.5_r);
    KEXPECT_LE(g.kd_scale, 1.5_r);
  }
  // The scales multiply kp and kd.
  const real q[3] = {0, 0, 0}, qd[3] = {1, 1, 1}, act[3] = {0, 0, 0};
  real tau[3];
  (void)update_joint_pd(p, a, q, qd, act, tau);
  const double expect = static_cast<double>(p.kp[0] * a.scales.kp_scale) * (0 + p.default_pos_rad[0] - 0) -
                        static_cast<double>(p.kd[0] * a.scales.kd_scale) * 1.0;
  KEXPECT_NEAR(tau[0], expect, 1e-5);
  // Without randomisation the scales are the midpoints.
  p.randomize_gain_scales = false;
  RngStream rd(42, 2, kPurposeGains);
  joint_pd_reset(p, a, rd);
  KEXPECT_NEAR(a.scales.kp_scale, 1.0, 1e-7);
  KEXPECT_NEAR(a.scales.kd_scale, 1.0, 1e-7);
}
