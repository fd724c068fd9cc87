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
