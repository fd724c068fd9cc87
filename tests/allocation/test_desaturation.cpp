// Sequential desaturation (airmode): priorities roll/pitch > collective thrust > yaw, limits kept.
#include <cmath>

#include "alloc_test_util.hpp"
#include "kestrel/allocation/sequential_desaturation.hpp"
#include "ktest.hpp"

using namespace alloc_test;

namespace {

Airframe g_airframe;
AllocationModel g_model;

Status desat(const Vec6& w, AllocationResult& out, Airmode mode = Airmode::roll_pitch) {
  AllocatorState s;
  SequentialDesaturationParams p;
  p.airmode = mode;
  Status st = Status::invalid_argument;
  KEXPECT_NO_HEAP(st = allocate_sequential_desaturation(g_model, p, s, w, out));
  return st;
}

void expect_within_limits(const AllocationResult& out) {
  for (int i = 0; i < g_model.num_rotors; ++i) {
    KEXPECT_GE(out.thrust_N[i], g_model.thrust_min_N[i]);
    KEXPECT_LE(out.thrust_N[i], g_model.thrust_max_N[i]);
  }
}

}  // namespace

KTEST(Desat, UnsaturatedCommandEqualsPseudoInverse) {
  const AirframeSpec* specs[] = {&kBaseQuadrotor, &kHexarotor, &kX500};
  for (const AirframeSpec* spec : specs) {
    KASSERT_EQ(static_cast<int>(build_preset(*spec, g_airframe, g_model)), static_cast<int>(Status::singular));
    const real hover = spec->mass_kg * kStandardGravity;
    const Vec6 w = wrench(0, 0, hover, 0.02_r * hover * 0.1_r, -0.01_r * hover * 0.1_r, 0.001_r * hover);
    AllocationResult out;
    KEXPECT_EQ(static_cast<int>(desat(w, out)), static_cast<int>(Status::ok));
    real f[kMaxRotors];
    no_heap([&] { return apply_pinv(g_model, w, f); });
    for (int i = 0; i < spec->num_rotors; ++i) KEXPECT_NEAR(out.thrust_N[i], f[i], 1e-6 * hover);
    KEXPECT_FALSE(out.any_saturated());
    for (int k = 2; k < 6; ++k) KEXPECT_NEAR(out.wrench_unallocated(k), 0.0, 1e-5);
  }
}

KTEST(Desat, KeepsRollPitchExactlyWhenThrustIsReduced) {
  KASSERT_EQ(static_cast<int>(build_preset(kBaseQuadrotor, g_airframe, g_model)), static_cast<int>(Status::singular));
  // 7.5 N of 8 N collective with a roll and pitch command the motors cannot add on top.
  const Vec6 w = wrench(0, 0, 7.5_r, 0.1_r, -0.06_r, 0);
  AllocationResult out;
  KEXPECT_EQ(static_cast<int>(desat(w, out)), static_cast<int>(Status::ok));
  expect_within_limits(out);
  KEXPECT_NEAR(out.wrench_realized(3), 0.1, 1e-6);
  KEXPECT_NEAR(out.wrench_realized(4), -0.06, 1e-6);
  KEXPECT_NEAR(out.wrench_realized(5), 0.0, 1e-6);
  KEXPECT_LT(out.wrench_realized(2), 7.5 - 0.1);  // thrust was given up
  KEXPECT_GT(out.wrench_unallocated(2), 0.1);
  KEXPECT_NE(out.saturated_high_mask, 0u);  // some motor sits at its max
  // The same command through the plain pseudo-inverse + clamp loses roll/pitch instead.
  AllocatorState s;
  AllocationResult clipped;
  KEXPECT_NO_HEAP((void)allocate_pinv(g_model, s, w, clipped));
  KEXPECT_GT(std::fabs(clipped.wrench_unallocated(3)) + std::fabs(clipped.wrench_unallocated(4)), 0.01);
}

KTEST(Desat, AirmodeRaisesThrustToKeepRollPitchAtLowCollective) {
  KASSERT_EQ(static_cast<int>(build_preset(kBaseQuadrotor, g_airframe, g_model)), static_cast<int>(Status::singular));
  const Vec6 w = wrench(0, 0, 0.3_r, 0.1_r, 0.05_r, 0);
  AllocationResult out;
  KEXPECT_EQ(static_cast<int>(desat(w, out)), static_cast<int>(Status::ok));
  expect_within_limits(out);
  KEXPECT_NEAR(out.wrench_realized(3), 0.1, 1e-6);
  KEXPECT_NEAR(out.wrench_realized(4), 0.05, 1e-6);
  KEXPECT_GT(out.wrench_realized(2), 0.3);  // collective raised (airmode)
  KEXPECT_NE(out.saturated_low_mask, 0u);
  // Airmode disabled never raises thrust: it gives up roll/pitch instead.
  AllocationResult off;
  KEXPECT_EQ(static_cast<int>(desat(w, off, Airmode::disabled)), static_cast<int>(Status::ok));
  expect_within_limits(off);
  KEXPECT_LE(off.wrench_realized(2), 0.3 + 1e-6);
  KEXPECT_LT(std::fabs(off.wrench_realized(3)), 0.1 - 1e-3);
}

KTEST(Desat, YawIsGivenUpBeforeRollPitch) {
  KASSERT_EQ(static_cast<int>(build_preset(kBaseQuadrotor, g_airframe, g_model)), static_cast<int>(Status::singular));
  // Mid collective, strong roll and an unreachable yaw command.
  const Vec6 w = wrench(0, 0, 4, 0.2_r, 0, 0.05_r);
  AllocationResult out;
  KEXPECT_EQ(static_cast<int>(desat(w, out)), static_cast<int>(Status::ok));
  expect_within_limits(out);
  KEXPECT_NEAR(out.wrench_realized(3), 0.2, 1e-6);
  KEXPECT_NEAR(out.wrench_realized(4), 0.0, 1e-6);
  KEXPECT_GT(out.wrench_realized(5), 0.0);      // some yaw remains ...
  KEXPECT_GT(out.wrench_unallocated(5), 1e-3);  // ... but not all of it
  // roll_pitch_yaw mode: yaw gets the full thrust shift first, then is reduced; roll still kept.
  AllocationResult rpy;
  KEXPECT_EQ(static_cast<int>(desat(w, rpy, Airmode::roll_pitch_yaw)), static_cast<int>(Status::ok));
  expect_within_limits(rpy);
  KEXPECT_NEAR(rpy.wrench_realized(3), 0.2, 1e-6);
}

KTEST(Desat, HexarotorAtFullThrustKeepsAttitudeAuthority) {
  KASSERT_EQ(static_cast<int>(build_preset(kHexarotor, g_airframe, g_model)), static_cast<int>(Status::singular));
  const Vec6 w = wrench(0, 0, 47, -0.8_r, 1.2_r, 0.1_r);  // 47 N of 48 N
  AllocationResult out;
  KEXPECT_EQ(static_cast<int>(desat(w, out)), static_cast<int>(Status::ok));
  expect_within_limits(out);
  KEXPECT_NEAR(out.wrench_realized(3), -0.8, 2e-6);
  KEXPECT_NEAR(out.wrench_realized(4), 1.2, 2e-6);
  KEXPECT_LT(out.wrench_realized(2), 47.0);
  KEXPECT_TRUE(out.any_saturated());
}

KTEST(Desat, DeadMotorPseudoInverseStillHovers) {
  MotorHealth h;
  h.thrust_scale[0] = 0;
  KASSERT_EQ(static_cast<int>(build_preset(kHexarotor, g_airframe, g_model, h)), static_cast<int>(Status::singular));
  const Vec6 w = hover_wrench(kHexarotor);
  AllocationResult out;
  KEXPECT_EQ(static_cast<int>(desat(w, out)), static_cast<int>(Status::ok));
  expect_within_limits(out);
  KEXPECT_EQ(out.thrust_N[0], real(0));
  for (int k = 2; k < 6; ++k) KEXPECT_NEAR(out.wrench_unallocated(k), 0.0, 2e-5);
  KEXPECT_FALSE(out.saturated(0));  // a dead motor is reported through the model, not as saturated
}

// ---- Exact desaturation results on hand-analysed commands (tests/MUTANTS.md: mutants a, c, d).
// The quadrotor's A+ has equal thrust-column entries (1/4 per motor) and yaw-column entries of
// equal magnitude and alternating sign, so each pass below can be followed by hand.

namespace {
/// Thrusts of A+ (A f0): for the rank-4 quadrotor A+ A = I on the 4 rotors, so the allocator
/// starts from f0 itself (to rounding); the command has no fx, fy.
Vec6 wrench_of(const real* f0) {
  Vec6 w = Vec6::Zero();
  for (int i = 0; i < 4; ++i) w += g_model.effectiveness.map().col(i) * f0[i];
  return w;
}
}  // namespace

// Yaw headroom is a fraction of each motor's thrust RANGE (hi - lo), PX4's definition; with lo = 0
// (every preset) hi + lo would read the same, so the motors here idle at lo = 0.4 N.
// Command: collective 6 N (1.5 N per motor) and a yaw torque worth +-0.9 N per motor. roll_pitch:
// yaw is fitted with upper limit hi + 0.15 (2 - 0.4) = 2.24 N (the +0.9 motors go to 2.24, the
// others to 0.76), then collective is given up until the max is 2 N: 2.0 / 0.52 N. With a
// headroom of 0.15 (hi + lo) the result would be 2.0 / 0.4 N.
KTEST(Desat, YawHeadroomIsAFractionOfTheThrustRange) {
  AirframeSpec spec = kBaseQuadrotor;
  spec.thrust_min_N = 0.4_r;
  KASSERT_EQ(static_cast<int>(build_preset(spec, g_airframe, g_model)), static_cast<int>(Status::singular));
  KASSERT_TRUE(g_model.thrust_min_N[0] == 0.4_r && g_model.thrust_max_N[0] == 2);
  const real k = std::fabs(g_model.pinv(0, 5));
  for (int i = 0; i < 4; ++i) {
    KASSERT_TRUE(std::fabs(g_model.pinv(i, 2) - 0.25_r) < 1e-6_r);
    KASSERT_TRUE(std::fabs(std::fabs(g_model.pinv(i, 5)) - k) < 1e-6_r * k);
  }
  const Vec6 w = wrench(0, 0, 6, 0, 0, 0.9_r / k);
  AllocationResult out;
  KEXPECT_EQ(static_cast<int>(desat(w, out)), static_cast<int>(Status::ok));
  for (int i = 0; i < 4; ++i) {
    const bool up = g_model.pinv(i, 5) > 0;
    KEXPECT_NEAR(out.thrust_N[i], up ? 2.0 : 0.52, 2e-5);
  }
  KEXPECT_NEAR(out.wrench_realized(2), 5.04, 1e-4);  // 6 - 4 * 0.15 * (2 - 0.4)
}

// The second pass of a desaturation removes HALF of what the first left (PX4
// desaturateActuators). Motors from A+ A f0 with f0 = {2.7, 0.7, -0.3, 1.7} N (limits [0, 2]; the
// max and the min, rotors 0 and 2, spin the same way), airmode roll_pitch_yaw: collective pass 1
// moves all by -0.4 (worst above -0.7, worst below +0.3: summed), pass 2 by 0.5 x 0.4 = +0.2
// -> {2.5, 0.5, -0.5, 1.5}; the yaw pass then sees -0.5 above on rotor 0 and +0.5 below on rotor 2
// with the same yaw sign: gain 0. Clamped: {2, 0.5, 0, 1.5}. (A 0.75 second pass gives
// {2, 0.7, 0, 1.7}.)
KTEST(Desat, SecondPassRemovesHalfOfTheRemainingViolation) {
  KASSERT_EQ(static_cast<int>(build_preset(kBaseQuadrotor, g_airframe, g_model)), static_cast<int>(Status::singular));
  KASSERT_TRUE(g_model.pinv(0, 5) * g_model.pinv(2, 5) > 0);  // rotors 0 and 2 share a yaw sign
  const real f0[4] = {2.7_r, 0.7_r, -0.3_r, 1.7_r};
  AllocationResult out;
  KEXPECT_EQ(static_cast<int>(desat(wrench_of(f0), out, Airmode::roll_pitch_yaw)), static_cast<int>(Status::ok));
  const double expected[4] = {2.0, 0.5, 0.0, 1.5};
  for (int i = 0; i < 4; ++i) KEXPECT_NEAR(out.thrust_N[i], expected[i], 2e-5);
  KEXPECT_EQ(out.saturated_high_mask, 1u);
  KEXPECT_EQ(out.saturated_low_mask, 4u);
}

// Saturation flags: a motor counts as saturated within 1e-5 of its range from a limit, no further
// (the flags feed kFaultSaturated and the sim's saturation statistics). A feasible command puts
// rotor 0 at 0.1 % of the range below the max and rotor 1 at 0.1 % above the min: not saturated;
// rotors 2 and 3 within 1e-7 of the range: saturated.
KTEST(Desat, SaturationFlagToleranceIsOneHundredThousandthOfTheRange) {
  KASSERT_EQ(static_cast<int>(build_preset(kBaseQuadrotor, g_airframe, g_model)), static_cast<int>(Status::singular));
  const real range = g_model.thrust_max_N[0] - g_model.thrust_min_N[0];
  const real near[4] = {g_model.thrust_max_N[0] - 1e-3_r * range, g_model.thrust_min_N[1] + 1e-3_r * range, 1.0_r, 1.0_r};
  AllocationResult out;
  for (Airmode mode : {Airmode::disabled, Airmode::roll_pitch, Airmode::roll_pitch_yaw}) {
    KEXPECT_EQ(static_cast<int>(desat(wrench_of(near), out, mode)), static_cast<int>(Status::ok));
    KEXPECT_NEAR(out.thrust_N[0], near[0], 1e-5);
    KEXPECT_EQ(out.saturated_high_mask, 0u);
    KEXPECT_EQ(out.saturated_low_mask, 0u);
  }
  const real at[4] = {1.0_r, 1.0_r, g_model.thrust_max_N[2] - 1e-7_r * range, g_model.thrust_min_N[3] + 1e-7_r * range};
  KEXPECT_EQ(static_cast<int>(desat(wrench_of(at), out)), static_cast<int>(Status::ok));
  KEXPECT_EQ(out.saturated_high_mask, 4u);
  KEXPECT_EQ(out.saturated_low_mask, 8u);
}
