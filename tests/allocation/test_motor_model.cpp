// Motor model behaviour beyond the golden traces: randomisation, faults, non-finite input,
// validation (quirk 9), the time-constant switch (quirk 8), rate limit and reaction torque.
#include <cmath>
#include <limits>

#include "alloc_test_util.hpp"
#include "kestrel/allocation/motor_model.hpp"
#include "kestrel/kernel/rng.hpp"
#include "ktest.hpp"

using namespace alloc_test;

namespace {

Status step(const MotorModelConfig& cfg, MotorModelState& s, const real* ref, real dt) {
  Status st = Status::invalid_argument;
  KEXPECT_NO_HEAP(st = motor_model_step(cfg, s, ref, dt));
  return st;
}

Status reset(const MotorModelConfig& cfg, MotorModelState& s, std::uint64_t seed, const real* init = nullptr) {
  RngStream rng(seed, 0, kPurposeMotors);
  Status st = Status::invalid_argument;
  KEXPECT_NO_HEAP(st = motor_model_reset(cfg, s, rng, init));
  return st;
}

MotorModelConfig force_config() {
  MotorModelConfig c = kBaseOctarotorMotors;  // force state, bidirectional, random constants
  c.num_motors = 4;
  return c;
}

}  // namespace

KTEST(Motor, ConvergesToTheClampedReference) {
  for (const MotorModelConfig& cfg : {kBaseQuadrotorMotors, kX500Motors, force_config()}) {
    MotorModelState s;
    KASSERT_EQ(static_cast<int>(reset(cfg, s, 7)), static_cast<int>(Status::ok));
    const real span = cfg.thrust_max_N - cfg.thrust_min_N;
    const real ref[4] = {cfg.thrust_min_N + 0.3_r * span, cfg.thrust_max_N + 5, cfg.thrust_min_N - 5,
                         cfg.thrust_min_N + 0.9_r * span};
    for (int k = 0; k < 400; ++k)
      KEXPECT_EQ(static_cast<int>(step(cfg, s, ref, 0.005_r)), static_cast<int>(Status::ok));
    KEXPECT_NEAR(s.thrust_N[0], ref[0], 1e-4 * span);
    KEXPECT_NEAR(s.thrust_N[1], cfg.thrust_max_N, 1e-4 * span);
    KEXPECT_NEAR(s.thrust_N[2], cfg.thrust_min_N, 1e-4 * span);
    KEXPECT_NEAR(s.thrust_N[3], ref[3], 1e-4 * span);
    for (int i = 0; i < 4; ++i) {
      KEXPECT_EQ(s.axial_torque_Nm[i], -static_cast<real>(cfg.direction[i]) * cfg.thrust_to_torque_m * s.thrust_N[i]);
    }
    KEXPECT_NEAR(s.elapsed_s, 2.0, 1e-4);
  }
}

KTEST(Motor, TimeConstantSwitchFollowsTorchSign) {
  // Euler, force state, continuous mixing: one step is f + dt (r - f) / tau exactly.
  MotorModelConfig cfg = force_config();
  cfg.integrator = MotorIntegrator::euler;
  cfg.use_discrete_approximation = false;
  cfg.time_constant_increasing_min_s = cfg.time_constant_increasing_max_s = 0.05_r;
  cfg.time_constant_decreasing_min_s = cfg.time_constant_decreasing_max_s = 0.01_r;
  const real init[4] = {0, 2, 2, -2};
  const real ref[4] = {1, 1, 3, -1};
  MotorModelState s;
  KASSERT_EQ(static_cast<int>(reset(cfg, s, 1, init)), static_cast<int>(Status::ok));
  KEXPECT_EQ(static_cast<int>(step(cfg, s, ref, 0.001_r)), static_cast<int>(Status::ok));
  // f = 0: sign0(0) = 0 -> increasing constant (quirk 8).
  KEXPECT_NEAR(s.thrust_N[0], 0 + 0.001 * (1 - 0) / 0.05, 1e-6);
  // 2 -> 1: |f| decreasing -> decreasing constant.
  KEXPECT_NEAR(s.thrust_N[1], 2 + 0.001 * (1 - 2) / 0.01, 1e-6);
  // 2 -> 3: increasing.
  KEXPECT_NEAR(s.thrust_N[2], 2 + 0.001 * (3 - 2) / 0.05, 1e-6);
  // -2 -> -1: |f| decreasing on the negative side -> decreasing constant.
  KEXPECT_NEAR(s.thrust_N[3], -2 + 0.001 * (-1 + 2) / 0.01, 1e-6);
}

KTEST(Motor, RateLimitBoundsEveryStep) {
  MotorModelConfig cfg = force_config();
  cfg.max_rate = 20;  // N/s
  MotorModelState s;
  const real init[4] = {0, 0, 0, 0};
  KASSERT_EQ(static_cast<int>(reset(cfg, s, 3, init)), static_cast<int>(Status::ok));
  const real ref[4] = {6, -6, 1, 0.01_r};
  real prev[4] = {0, 0, 0, 0};
  for (int k = 0; k < 50; ++k) {
    KEXPECT_EQ(static_cast<int>(step(cfg, s, ref, 0.01_r)), static_cast<int>(Status::ok));
    for (int i = 0; i < 4; ++i) {
      KEXPECT_LE(std::fabs(s.thrust_N[i] - prev[i]), 20 * 0.01 + 1e-6);
      prev[i] = s.thrust_N[i];
    }
    if (k == 9) {
      // Far from the reference every RK4 stage is clamped: exactly 20 N/s.
      KEXPECT_NEAR(s.thrust_N[0], 2.0, 1e-5);
      KEXPECT_NEAR(s.thrust_N[1], -2.0, 1e-5);
    }
  }
  // Close to the reference the first-order response takes over and converges.
  KEXPECT_NEAR(s.thrust_N[0], 6.0, 1e-3);
  KEXPECT_NEAR(s.thrust_N[2], 1.0, 1e-3);
}

KTEST(Motor, RandomisationIsReproduciblePerSeedAndWithinRange) {
  const MotorModelConfig cfg = kBaseQuadrotorMotors;  // thrust constant in [9.26e-6, 1.83e-5]
  MotorModelConfig thr = force_config();              // tau_increasing in [0.01, 0.03]
  thr.num_motors = 8;
  MotorModelState a, b, c;
  KASSERT_EQ(static_cast<int>(reset(thr, a, 42)), static_cast<int>(Status::ok));
  KASSERT_EQ(static_cast<int>(reset(thr, b, 42)), static_cast<int>(Status::ok));
  KASSERT_EQ(static_cast<int>(reset(thr, c, 43)), static_cast<int>(Status::ok));
  int differ = 0;
  for (int i = 0; i < 8; ++i) {
    KEXPECT_EQ(a.time_constant_increasing_s[i], b.time_constant_increasing_s[i]);
    KEXPECT_EQ(a.time_constant_decreasing_s[i], b.time_constant_decreasing_s[i]);
    KEXPECT_EQ(a.thrust_N[i], b.thrust_N[i]);
    differ += a.time_constant_increasing_s[i] != c.time_constant_increasing_s[i];
    KEXPECT_GE(a.time_constant_increasing_s[i], thr.time_constant_increasing_min_s);
    KEXPECT_LE(a.time_constant_increasing_s[i], thr.time_constant_increasing_max_s);
    KEXPECT_EQ(a.time_constant_decreasing_s[i], thr.time_constant_decreasing_min_s);  // min == max
    KEXPECT_GE(a.thrust_N[i], thr.thrust_min_N);
    KEXPECT_LE(a.thrust_N[i], thr.thrust_max_N);
  }
  KEXPECT_GE(differ, 7);
  // Per-motor values differ from each other (not one draw broadcast).
  KEXPECT_NE(a.time_constant_increasing_s[0], a.time_constant_increasing_s[1]);
  MotorModelState q;
  KASSERT_EQ(static_cast<int>(reset(cfg, q, 5)), static_cast<int>(Status::ok));
  for (int i = 0; i < 4; ++i) {
    KEXPECT_GE(q.thrust_constant[i], cfg.thrust_constant_min);
    KEXPECT_LE(q.thrust_constant[i], cfg.thrust_constant_max);
  }
  // Identical seeds give bit-identical trajectories.
  const real ref[8] = {1, -1, 2, -2, 3, -3, 0.5_r, -0.5_r};
  for (int k = 0; k < 20; ++k) {
    KEXPECT_EQ(static_cast<int>(step(thr, a, ref, 0.01_r)), static_cast<int>(Status::ok));
    KEXPECT_EQ(static_cast<int>(step(thr, b, ref, 0.01_r)), static_cast<int>(Status::ok));
  }
  for (int i = 0; i < 8; ++i) KEXPECT_EQ(a.thrust_N[i], b.thrust_N[i]);
}

KTEST(Motor, DeadMotorIsZeroFromTheInjectionTime) {
  const MotorModelConfig cfg = kBaseQuadrotorMotors;
  MotorModelState s;
  const real init[4] = {1, 1, 1, 1};
  KASSERT_EQ(static_cast<int>(reset(cfg, s, 9, init)), static_cast<int>(Status::ok));
  KEXPECT_EQ(static_cast<int>(no_heap([&] { return schedule_motor_failure(s, 2, 0, 0.05_r); })),
             static_cast<int>(Status::ok));
  const real ref[4] = {1.2_r, 1.2_r, 1.2_r, 1.2_r};
  for (int k = 0; k < 10; ++k) {
    KEXPECT_EQ(static_cast<int>(step(cfg, s, ref, 0.01_r)), static_cast<int>(Status::ok));
    if (k < 5) {
      KEXPECT_GT(s.thrust_N[2], 1.0);  // steps starting at t < 0.05 s
      KEXPECT_FALSE(s.faults.has(kFaultMotorFailure));
    } else {
      KEXPECT_EQ(s.thrust_N[2], real(0));  // the step starting at 0.05 s and after
      KEXPECT_EQ(s.axial_torque_Nm[2], real(0));
      KEXPECT_TRUE(s.faults.has(kFaultMotorFailure));
    }
    KEXPECT_GT(s.thrust_N[1], 1.0);
  }
  // Immediate injection.
  KEXPECT_EQ(static_cast<int>(no_heap([&] { return inject_motor_failure(s, 0, 0); })), static_cast<int>(Status::ok));
  KEXPECT_EQ(s.thrust_N[0], real(0));
  KEXPECT_EQ(static_cast<int>(no_heap([&] { return inject_motor_failure(s, 4, 0); })),
             static_cast<int>(Status::invalid_argument));
  KEXPECT_EQ(static_cast<int>(no_heap([&] { return inject_motor_failure(s, 1, 1.5_r); })),
             static_cast<int>(Status::invalid_argument));
  // Reset restores health.
  KASSERT_EQ(static_cast<int>(reset(cfg, s, 9, init)), static_cast<int>(Status::ok));
  KEXPECT_EQ(s.health_scale[2], real(1));
  KEXPECT_FALSE(s.faults.any());
}

KTEST(Motor, WeakMotorMaxIsScaled) {
  const MotorModelConfig cfg = kX500Motors;
  MotorModelState s;
  KASSERT_EQ(static_cast<int>(reset(cfg, s, 11)), static_cast<int>(Status::ok));
  KEXPECT_EQ(static_cast<int>(no_heap([&] { return inject_motor_failure(s, 3, 0.6_r); })),
             static_cast<int>(Status::ok));
  const real ref[4] = {10, 10, 10, 10};
  for (int k = 0; k < 300; ++k) KEXPECT_EQ(static_cast<int>(step(cfg, s, ref, 0.005_r)), static_cast<int>(Status::ok));
  KEXPECT_NEAR(s.thrust_N[0], 10.0, 1e-3);
  KEXPECT_NEAR(s.thrust_N[3], 6.0, 1e-3);
  KEXPECT_TRUE(s.faults.has(kFaultMotorFailure));
}

KTEST(Motor, NonFiniteReferenceHoldsTheLastOne) {
  for (const MotorModelConfig& cfg : {kBaseQuadrotorMotors, force_config()}) {
    MotorModelState s;
    const real init[4] = {0.5_r, 0.5_r, 0.5_r, 0.5_r};
    KASSERT_EQ(static_cast<int>(reset(cfg, s, 13, init)), static_cast<int>(Status::ok));
    const real good[4] = {1.5_r, 1.5_r, 1.5_r, 1.5_r};
    KEXPECT_EQ(static_cast<int>(step(cfg, s, good, 0.01_r)), static_cast<int>(Status::ok));
    const real nan = std::numeric_limits<real>::quiet_NaN();
    const real inf = std::numeric_limits<real>::infinity();
    const real bad[4] = {nan, inf, -inf, 1.5_r};
    for (int k = 0; k < 200; ++k) {
      KEXPECT_EQ(static_cast<int>(step(cfg, s, bad, 0.01_r)), static_cast<int>(Status::non_finite_input));
      KEXPECT_TRUE(all_finite(s.thrust_N, 4));
      KEXPECT_TRUE(all_finite(s.axial_torque_Nm, 4));
    }
    // All four motors kept tracking the last finite reference (1.5 N) as if nothing happened.
    for (int i = 0; i < 4; ++i) KEXPECT_NEAR(s.thrust_N[i], 1.5, 1e-4);
    KEXPECT_TRUE(s.faults.has(kFaultNonFiniteCommand));
  }
  // A NaN before any finite reference holds the initial thrust.
  MotorModelState s;
  const real init[4] = {0.7_r, 0.7_r, 0.7_r, 0.7_r};
  KASSERT_EQ(static_cast<int>(reset(kBaseQuadrotorMotors, s, 1, init)), static_cast<int>(Status::ok));
  const real nan4[4] = {std::numeric_limits<real>::quiet_NaN(), std::numeric_limits<real>::quiet_NaN(),
                        std::numeric_limits<real>::quiet_NaN(), std::numeric_limits<real>::quiet_NaN()};
  KEXPECT_EQ(static_cast<int>(step(kBaseQuadrotorMotors, s, nan4, 0.01_r)), static_cast<int>(Status::non_finite_input));
  for (int i = 0; i < 4; ++i) KEXPECT_NEAR(s.thrust_N[i], 0.7, 1e-6);
}

// Fuzz finding F6: from dt ~ 1e18 s the step overflows; the guard held the thrust and latched
// kFaultNonFiniteOutput but the step returned ok. The status now says so (non_finite_output).
KTEST(Motor, OverflowGuardIsReportedAsStatus) {
  int fired = 0;
  for (const MotorModelConfig& cfg : {kHexarotorMotors, kBaseQuadrotorMotors}) {
    const real dts[5] = {1e16_r, 1e18_r, 1e20_r, 1e30_r, 3e38_r};
    for (real dt : dts) {
      MotorModelState s;
      const real init[kMaxRotors] = {};
      KASSERT_EQ(static_cast<int>(reset(cfg, s, 7, init)), static_cast<int>(Status::ok));
      real ref[kMaxRotors] = {};
      for (int i = 0; i < cfg.num_motors; ++i) ref[i] = 0.5_r * cfg.thrust_max_N;
      const Status st = step(cfg, s, ref, dt);
      KEXPECT_TRUE(all_finite(s.thrust_N, cfg.num_motors));
      KEXPECT_TRUE(all_finite(s.axial_torque_Nm, cfg.num_motors));
      if (s.faults.has(kFaultNonFiniteOutput)) {
        ++fired;
        KEXPECT_EQ(static_cast<int>(st), static_cast<int>(Status::non_finite_output));
      } else {
        KEXPECT_EQ(static_cast<int>(st), static_cast<int>(Status::ok));
      }
    }
  }
  KEXPECT_GT(fired, 0);  // the guard is reached (the hexarotor's at 1e18 s, as in the fuzz report)
}

KTEST(Motor, ValidationRejectsBadConfigurations) {
  MotorModelState s;
  // Quirk 9: rotor-speed state with negative thrust would take sqrt of a negative number.
  MotorModelConfig cfg = kBaseQuadrotorMotors;
  cfg.thrust_min_N = -1;
  KEXPECT_EQ(static_cast<int>(validate(cfg)), static_cast<int>(Status::invalid_argument));
  KEXPECT_EQ(static_cast<int>(reset(cfg, s, 1)), static_cast<int>(Status::invalid_argument));
  cfg.use_rps = false;  // the same limits are fine in force state
  KEXPECT_EQ(static_cast<int>(validate(cfg)), static_cast<int>(Status::ok));
  cfg = kBaseQuadrotorMotors;
  cfg.thrust_constant_min = 0;
  KEXPECT_EQ(static_cast<int>(validate(cfg)), static_cast<int>(Status::invalid_argument));
  cfg = kBaseQuadrotorMotors;
  cfg.time_constant_increasing_min_s = 0;
  KEXPECT_EQ(static_cast<int>(validate(cfg)), static_cast<int>(Status::invalid_argument));
  cfg = kBaseQuadrotorMotors;
  cfg.time_constant_decreasing_min_s = 0.5_r;  // min > max
  KEXPECT_EQ(static_cast<int>(validate(cfg)), static_cast<int>(Status::invalid_argument));
  cfg = kBaseQuadrotorMotors;
  cfg.num_motors = kMaxRotors + 1;
  KEXPECT_EQ(static_cast<int>(validate(cfg)), static_cast<int>(Status::invalid_argument));
  cfg = kBaseQuadrotorMotors;
  cfg.max_rate = 0;
  KEXPECT_EQ(static_cast<int>(validate(cfg)), static_cast<int>(Status::invalid_argument));
  // A bad time step or an unreset state changes nothing.
  cfg = kBaseQuadrotorMotors;
  KASSERT_EQ(static_cast<int>(reset(cfg, s, 1)), static_cast<int>(Status::ok));
  const real before = s.thrust_N[0];
  const real ref[4] = {1, 1, 1, 1};
  KEXPECT_EQ(static_cast<int>(step(cfg, s, ref, 0)), static_cast<int>(Status::invalid_argument));
  KEXPECT_EQ(static_cast<int>(step(cfg, s, ref, std::numeric_limits<real>::quiet_NaN())),
             static_cast<int>(Status::invalid_argument));
  KEXPECT_EQ(s.thrust_N[0], before);
  MotorModelState fresh;
  KEXPECT_EQ(static_cast<int>(step(cfg, fresh, ref, 0.01_r)), static_cast<int>(Status::invalid_argument));
  const real bad_init[4] = {1, std::numeric_limits<real>::quiet_NaN(), 1, 1};
  KEXPECT_EQ(static_cast<int>(reset(cfg, s, 1, bad_init)), static_cast<int>(Status::invalid_argument));
}
