// Behaviour shared by all allocators: the allocation model and motor health, the plain
// pseudo-inverse allocator, limits, and the non-finite-command hold.
#include <cmath>
#include <limits>

#include "alloc_test_util.hpp"
#include "kestrel/allocation/cls_allocator.hpp"
#include "kestrel/allocation/sequential_desaturation.hpp"
#include "kestrel/kernel/rng.hpp"
#include "ktest.hpp"

using namespace alloc_test;

namespace {

Airframe g_airframe;
AllocationModel g_model;

enum class Which { pinv, desat, cls };

Status run(Which which, const AllocationModel& m, AllocatorState& s, const Vec6& w, AllocationResult& out) {
  Status st = Status::invalid_argument;
  switch (which) {
    case Which::pinv:
      KEXPECT_NO_HEAP(st = allocate_pinv(m, s, w, out));
      break;
    case Which::desat:
      KEXPECT_NO_HEAP(st = allocate_sequential_desaturation(m, SequentialDesaturationParams(), s, w, out));
      break;
    case Which::cls:
      KEXPECT_NO_HEAP(st = allocate_cls(m, ClsParams(), s, w, out));
      break;
  }
  return st;
}

}  // namespace

KTEST(Alloc, PinvHoverIsExactAndUnsaturated) {
  KASSERT_EQ(static_cast<int>(build_preset(kBaseQuadrotor, g_airframe, g_model)), static_cast<int>(Status::singular));
  AllocatorState s;
  AllocationResult out;
  const Vec6 w = hover_wrench(kBaseQuadrotor);
  KEXPECT_EQ(static_cast<int>(run(Which::pinv, g_model, s, w, out)), static_cast<int>(Status::ok));
  for (int i = 0; i < 4; ++i) KEXPECT_NEAR(out.thrust_N[i], 0.25 * 0.25 * 9.81, 1e-6);
  KEXPECT_FALSE(out.any_saturated());
  for (int k = 0; k < 6; ++k) KEXPECT_NEAR(out.wrench_unallocated(k), 0.0, 2e-6);
  KEXPECT_FALSE(s.faults.any());
}

KTEST(Alloc, PinvClampsAndFlagsBothSides) {
  KASSERT_EQ(static_cast<int>(build_preset(kBaseQuadrotor, g_airframe, g_model)), static_cast<int>(Status::singular));
  AllocatorState s;
  AllocationResult out;
  // 10 N collective on a 4 x 2 N quad: all motors high.
  KEXPECT_EQ(static_cast<int>(run(Which::pinv, g_model, s, wrench(0, 0, 10, 0, 0, 0), out)),
             static_cast<int>(Status::ok));
  KEXPECT_EQ(out.saturated_high_mask, 0xFu);
  KEXPECT_EQ(out.saturated_low_mask, 0u);
  for (int i = 0; i < 4; ++i) KEXPECT_EQ(out.thrust_N[i], real(2));
  KEXPECT_NEAR(out.wrench_realized(2), 8.0, 1e-6);
  KEXPECT_NEAR(out.wrench_unallocated(2), 2.0, 1e-6);
  KEXPECT_TRUE(s.faults.has(kFaultSaturated));
  // A large roll torque at low thrust: the right motors (0, 1: y < 0) would need negative thrust.
  KEXPECT_EQ(static_cast<int>(run(Which::pinv, g_model, s, wrench(0, 0, 1, 0.3_r, 0, 0), out)),
             static_cast<int>(Status::ok));
  KEXPECT_EQ(out.saturated_low_mask, 0x3u);
  KEXPECT_EQ(out.saturated_high_mask, 0u);
  KEXPECT_EQ(out.thrust_N[0], real(0));
  // ... and at high thrust the left motors (2, 3) would exceed 2 N.
  KEXPECT_EQ(static_cast<int>(run(Which::pinv, g_model, s, wrench(0, 0, 6, 0.3_r, 0, 0), out)),
             static_cast<int>(Status::ok));
  KEXPECT_EQ(out.saturated_low_mask, 0u);
  KEXPECT_EQ(out.saturated_high_mask, 0xCu);
}

KTEST(Alloc, MotorHealthScalesLimitsAndRemovesDeadColumns) {
  Airframe a;
  KASSERT_EQ(static_cast<int>(no_heap([&] { return make_airframe(kHexarotor, a); })), static_cast<int>(Status::ok));
  MotorHealth h;
  h.thrust_scale[2] = 0.5_r;
  h.thrust_scale[4] = 0;
  Status st = Status::invalid_argument;
  KEXPECT_NO_HEAP(st = build_allocation_model(a, h, g_model));
  KEXPECT_EQ(static_cast<int>(st), static_cast<int>(Status::singular));
  KEXPECT_EQ(g_model.thrust_max_N[2], real(4));
  KEXPECT_EQ(g_model.thrust_max_N[4], real(0));
  KEXPECT_EQ(g_model.thrust_min_N[4], real(0));
  KEXPECT_EQ(g_model.weak_mask, 1u << 2);
  KEXPECT_EQ(g_model.dead_mask, 1u << 4);
  for (int r = 0; r < 6; ++r) KEXPECT_EQ(g_model.effectiveness(r, 4), real(0));
  KEXPECT_TRUE(g_model.faults.has(kFaultMotorFailure));
  // Out-of-range health values are rejected and leave an empty model.
  h.thrust_scale[1] = 1.5_r;
  KEXPECT_EQ(static_cast<int>(no_heap([&] { return build_allocation_model(a, h, g_model); })),
             static_cast<int>(Status::invalid_argument));
  KEXPECT_EQ(g_model.num_rotors, 0);
  h.thrust_scale[1] = std::numeric_limits<real>::quiet_NaN();
  KEXPECT_EQ(static_cast<int>(no_heap([&] { return build_allocation_model(a, h, g_model); })),
             static_cast<int>(Status::invalid_argument));
  // Every allocator refuses an empty model.
  AllocatorState s;
  AllocationResult out;
  KEXPECT_EQ(static_cast<int>(run(Which::pinv, g_model, s, wrench(0, 0, 1, 0, 0, 0), out)),
             static_cast<int>(Status::invalid_argument));
  KEXPECT_EQ(static_cast<int>(run(Which::desat, g_model, s, wrench(0, 0, 1, 0, 0, 0), out)),
             static_cast<int>(Status::invalid_argument));
  KEXPECT_EQ(static_cast<int>(run(Which::cls, g_model, s, wrench(0, 0, 1, 0, 0, 0), out)),
             static_cast<int>(Status::invalid_argument));
}

KTEST(Alloc, NonFiniteCommandHoldsLastOutputWithoutNaN) {
  KASSERT_EQ(static_cast<int>(build_preset(kX500, g_airframe, g_model)), static_cast<int>(Status::singular));
  const Which all[3] = {Which::pinv, Which::desat, Which::cls};
  const real bad[3] = {std::numeric_limits<real>::quiet_NaN(), std::numeric_limits<real>::infinity(),
                       -std::numeric_limits<real>::infinity()};
  for (Which which : all) {
    AllocatorState s;
    AllocationResult out;
    // Before any good command the hold is zero thrust.
    Vec6 w = hover_wrench(kX500);
    w(3) = bad[0];
    KEXPECT_EQ(static_cast<int>(run(which, g_model, s, w, out)), static_cast<int>(Status::non_finite_input));
    for (int i = 0; i < 4; ++i) KEXPECT_EQ(out.thrust_N[i], real(0));
    const Vec6 good = wrench(0, 0, 20, 0.4_r, -0.2_r, 0.05_r);
    KEXPECT_EQ(static_cast<int>(run(which, g_model, s, good, out)), static_cast<int>(Status::ok));
    real last[4];
    for (int i = 0; i < 4; ++i) last[i] = out.thrust_N[i];
    for (real b : bad) {
      for (int k = 0; k < 6; ++k) {
        Vec6 wb = good;
        wb(k) = b;
        KEXPECT_EQ(static_cast<int>(run(which, g_model, s, wb, out)), static_cast<int>(Status::non_finite_input));
        for (int i = 0; i < 4; ++i) KEXPECT_EQ(out.thrust_N[i], last[i]);
        KEXPECT_TRUE(all_finite(out.wrench_realized));
        KEXPECT_TRUE(all_finite(out.wrench_unallocated));
      }
    }
    KEXPECT_TRUE(s.faults.has(kFaultNonFiniteCommand));
    // And recovers on the next finite command.
    KEXPECT_EQ(static_cast<int>(run(which, g_model, s, good, out)), static_cast<int>(Status::ok));
  }
}

// Fuzz finding F1: a finite command near the float limit (what the Lee controller makes of a
// 3.4e38 rad/s body rate, or of a 1e37 gain) overflowed A+ w to +-inf, the desaturation turned
// inf - inf into NaN and clamp() let it through: NaN thrusts with Status::ok, and NaN stored as the
// held output. Now: never NaN; an overflowed solution holds the last finite thrust with
// Status::non_finite_output and kFaultNonFiniteOutput, and the next sane command recovers.
KTEST(Alloc, OverflowingFiniteCommandHoldsLastFiniteOutput) {
  const AirframeSpec* specs[2] = {&kBaseQuadrotor, &kHexarotor};  // unrolled 4-rotor path and run-time count
  const Which all[3] = {Which::pinv, Which::desat, Which::cls};
  const real big[4] = {3.4e38_r, -3.4e38_r, 1e38_r, -5e37_r};
  for (const AirframeSpec* spec : specs) {
    const Status bst = build_preset(*spec, g_airframe, g_model);
    KASSERT_TRUE(bst == Status::ok || bst == Status::singular);
    const int n = spec->num_rotors;
    for (Which which : all) {
      int held = 0;
      for (int mode = 0; mode < 3; ++mode) {
        if (which != Which::desat && mode > 0) continue;
        SequentialDesaturationParams dp;
        dp.airmode = static_cast<Airmode>(mode);
        auto alloc = [&](AllocatorState& s, const Vec6& w, AllocationResult& out) {
          if (which != Which::desat) return run(which, g_model, s, w, out);
          Status st = Status::invalid_argument;
          KEXPECT_NO_HEAP(st = allocate_sequential_desaturation(g_model, dp, s, w, out));
          return st;
        };
        AllocatorState s;
        AllocationResult out;
        const Vec6 good = hover_wrench(*spec);
        KEXPECT_EQ(static_cast<int>(alloc(s, good, out)), static_cast<int>(Status::ok));
        real last[kMaxRotors];
        for (int i = 0; i < n; ++i) last[i] = out.thrust_N[i];
        for (int k = 2; k < 6; ++k) {
          for (real b : big) {
            Vec6 w = good;
            w(k) = b;
            if (k != 5) w(5) = -b;  // yaw against the other axis: inf - inf in the desaturation
            const Status st = alloc(s, w, out);
            KEXPECT_TRUE(st == Status::ok || st == Status::non_finite_output);
            for (int i = 0; i < n; ++i) {
              KEXPECT_TRUE(std::isfinite(out.thrust_N[i]));
              KEXPECT_TRUE(std::isfinite(s.last_thrust_N[i]));
              KEXPECT_GE(out.thrust_N[i], g_model.thrust_min_N[i]);
              KEXPECT_LE(out.thrust_N[i], g_model.thrust_max_N[i]);
            }
            KEXPECT_TRUE(all_finite(out.wrench_realized));
            if (st == Status::non_finite_output) {
              ++held;
              KEXPECT_TRUE(s.faults.has(kFaultNonFiniteOutput));
              for (int i = 0; i < n; ++i) KEXPECT_EQ(out.thrust_N[i], last[i]);
            } else {
              for (int i = 0; i < n; ++i) last[i] = out.thrust_N[i];
            }
          }
        }
        // Recovers on the next sane command.
        KEXPECT_EQ(static_cast<int>(alloc(s, good, out)), static_cast<int>(Status::ok));
        for (int i = 0; i < n; ++i) KEXPECT_TRUE(std::isfinite(out.thrust_N[i]));
      }
      // The sequential desaturation reaches NaN for these commands on both frames (the F1 case).
      if (which == Which::desat) {
        KEXPECT_GT(held, 0);
      }
    }
  }
}

KTEST(Alloc, RandomCommandsStayWithinLimitsForEveryPresetAndAllocator) {
  RngStream rng(2024, 0, kPurposeUser);
  int calls = 0;
  for (int p = 0; p < kNumAirframePresets; ++p) {
    const AirframeSpec& spec = airframe_spec(static_cast<AirframePreset>(p));
    const Status bst = build_preset(spec, g_airframe, g_model);
    KASSERT_TRUE(bst == Status::ok || bst == Status::singular);
    const real fz_hover = spec.mass_kg * kStandardGravity;
    for (Which which : {Which::pinv, Which::desat, Which::cls}) {
      AllocatorState s;
      for (int t = 0; t < 40; ++t) {
        Vec6 w;
        for (int k = 0; k < 3; ++k) w(k) = rng.uniform(-1, 1) * fz_hover * (k == 2 ? 1.5_r : 0.3_r);
        for (int k = 3; k < 6; ++k) w(k) = rng.uniform(-1, 1) * fz_hover * (k == 5 ? 0.01_r : 0.1_r);
        AllocationResult out;
        const Status st = run(which, g_model, s, w, out);
        KEXPECT_TRUE(st == Status::ok);
        ++calls;
        for (int i = 0; i < spec.num_rotors; ++i) {
          KEXPECT_GE(out.thrust_N[i], g_model.thrust_min_N[i]);
          KEXPECT_LE(out.thrust_N[i], g_model.thrust_max_N[i]);
        }
        const Vec6 realized =
            no_heap([&] { return wrench_from_thrusts(EffectivenessMatrix(g_model.effectiveness.map()), spec.num_rotors, out.thrust_N); });
        for (int k = 0; k < 6; ++k) {
          KEXPECT_EQ(out.wrench_realized(k), realized(k));
          KEXPECT_NEAR(out.wrench_unallocated(k) + out.wrench_realized(k), w(k), 1e-5 * (1 + std::fabs(w(k))));
        }
      }
    }
  }
  KEXPECT_EQ(calls, kNumAirframePresets * 3 * 40);
}
