// Sequential desaturation; see sequential_desaturation.hpp for the method and its sources.
#include "kestrel/allocation/sequential_desaturation.hpp"

#include <cmath>

#include "kestrel/kernel/math.hpp"

namespace kestrel::allocation {

namespace {

enum Axis : int { kFx = 0, kFy = 1, kFz = 2, kTx = 3, kTy = 4, kTz = 5 };

enum class GainSign : std::uint8_t { any, non_positive };

// The rotor loops below run to a compile-time count for the quadrotor (the cascade's airframe):
// fully unrolled, the thrusts being desaturated stay in FPU registers across every pass and no
// loop counter is kept (on a Cortex-M4F the instruction count per call roughly halves). Other
// counts use the same code with a run-time count. The arithmetic and its order are those of the
// plain loops, so the results are bit-identical between the two.
template <int kN, typename F>
__attribute__((always_inline)) inline void for_rotors(int n, F&& body) {
  if constexpr (kN > 0) {
#pragma GCC unroll 16
    for (int i = 0; i < kN; ++i) body(i);
  } else {
#pragma GCC unroll 1
    for (int i = 0; i < n; ++i) body(i);
  }
}

/// One desaturation direction: a column of A+ (motor thrust per unit of one wrench axis; the
/// matrix is column-major, so the column is contiguous).
struct Direction {
  const real* d;
  unsigned movable;  // bit i clear: |d_i| <= d_min, motor i cannot be moved along this axis
};

Direction direction(const AllocationModel& model, int axis) {
  // PX4 skips |d| < FLT_EPSILON on its normalised matrix; A+ is in physical units here, so the
  // threshold is relative to the column's largest entry: |d_i| > 1e-6 max_j |d_j|, precomputed
  // with the model as a bit mask (pinv_col_movable_mask).
  return Direction{&model.pinv(0, axis), model.pinv_col_movable_mask[axis]};
}

/// The thrusts being desaturated (a local array: kept in registers when the count is constant).
template <int kN>
struct Work {
  static constexpr int kCount = kN > 0 ? kN : kMaxRotors;
  int n_rt;
  const real* lo;
  const real* hi;
  real f[kCount];
  int count() const { return kN > 0 ? kN : n_rt; }
};

/// Gain k along `dir` that removes the worst violation of [lo, hi]: the smallest negative and the
/// largest positive k that bring each violating motor back to its bound, summed (one of them is
/// zero unless motors violate both ways, then the sum balances them).
template <int kN>
inline real desaturation_gain(const Work<kN>& w, const Direction& dir, const real* hi) {
  real k_min = 0, k_max = 0;
  const real* const d = dir.d;  // in registers for the whole scan
  const unsigned movable = dir.movable;
  for_rotors<kN>(w.count(), [&](int i) __attribute__((always_inline)) {
    const real f = w.f[i];
    real k;
    if (f < w.lo[i]) {
      k = w.lo[i] - f;
    } else if (f > hi[i]) {
      k = hi[i] - f;
    } else {
      return;
    }
    if ((movable & (1u << i)) == 0) return;
    k /= d[i];
    k_min = k < k_min ? k : k_min;
    k_max = k > k_max ? k : k_max;
  });
  return k_min + k_max;
}

template <int kN>
inline void shift(Work<kN>& w, const Direction& dir, real gain) {
  for_rotors<kN>(w.count(), [&](int i) __attribute__((always_inline)) { w.f[i] += gain * dir.d[i]; });
}

/// Two passes: remove the worst violation, then half of what remains (PX4 desaturateActuators).
/// `hi` replaces the upper limits (yaw headroom).
/// Forced inline: GCC otherwise keeps one out-of-line copy per kN, and the thrusts go through
/// memory at every call (measured for the quadrotor cascade on the Cortex-M4F: -13 instructions
/// per call and -64 B of stack, for ~1 KB more flash).
template <int kN>
__attribute__((always_inline)) inline void desaturate(Work<kN>& w, const Direction& dir, GainSign sign,
                                                      const real* hi) {
  real gain = desaturation_gain(w, dir, hi);
  if (sign == GainSign::non_positive && gain > 0) return;
  if (gain == 0) return;  // nothing violated: the second pass would find nothing either
  shift(w, dir, gain);
  gain = 0.5_r * desaturation_gain(w, dir, hi);
  if (sign == GainSign::non_positive && gain > 0) return;
  shift(w, dir, gain);
}
template <int kN>
inline void desaturate(Work<kN>& w, const Direction& dir, GainSign sign) {
  desaturate(w, dir, sign, w.hi);
}

/// Adds yaw, fits it with headroom, then removes the headroom by reducing thrust only.
template <int kN>
inline void mix_yaw(Work<kN>& w, const Direction& yaw, const Direction& thrust, real yaw_cmd, real headroom) {
  shift(w, yaw, yaw_cmd);
  real hi[Work<kN>::kCount];
  for_rotors<kN>(w.count(), [&](int i) __attribute__((always_inline)) {
    hi[i] = w.hi[i] + headroom * (w.hi[i] - w.lo[i]);
  });
  desaturate(w, yaw, GainSign::any, hi);
  desaturate(w, thrust, GainSign::non_positive);
}

/// The output stage of allocate (see there); kNoFxFy: rows fx, fy of A are all zero. Returns false,
/// having stored nothing in `state`, when a thrust is NaN (see allocate).
template <int kN, bool kNoFxFy>
inline bool finish(const AllocationModel& model, Work<kN>& w, bool feasible, const Vec6& wrench_cmd,
                   AllocatorState& state, AllocationResult& out) {
  const int n = w.count();
  std::uint16_t low = 0, high = 0;
  real r0 = 0, r1 = 0, r2 = 0, r3 = 0, r4 = 0, r5 = 0;
  const PlainMat<6, kMaxRotors>& a = model.effectiveness;
  for_rotors<kN>(n, [&](int i) __attribute__((always_inline)) {
    const real lo = w.lo[i], hi = w.hi[i];
    real f = w.f[i];
    if (hi > lo) {  // else a dead motor: reported through the model, not as saturated
      const real tol = 1e-5_r * (hi - lo);
      if (f <= lo + tol) low = static_cast<std::uint16_t>(low | (1u << i));
      if (f >= hi - tol) high = static_cast<std::uint16_t>(high | (1u << i));
    }
    if (!feasible) f = clamp(f, lo, hi);  // feasible: already within [lo, hi]
    out.thrust_N[i] = f;
    if constexpr (!kNoFxFy) {
      r0 += a(0, i) * f;
      r1 += a(1, i) * f;
    }
    r2 += a(2, i) * f;
    r3 += a(3, i) * f;
    r4 += a(4, i) * f;
    r5 += a(5, i) * f;
  });
  // A NaN thrust (clamp() lets NaN through) makes r2 NaN: every thrust enters r2, and 0 * NaN is
  // NaN. Otherwise every thrust is within its limits and r2 is finite. One compare on the common
  // path; the held output is stored only after it, so it can never become NaN.
  if (!(r2 == r2)) return false;
  for_rotors<kN>(n, [&](int i) __attribute__((always_inline)) { state.last_thrust_N[i] = out.thrust_N[i]; });
  out.saturated_low_mask = low;
  out.saturated_high_mask = high;
  out.iterations = 0;
  state.num_rotors = n;
  out.wrench_realized << r0, r1, r2, r3, r4, r5;
  if constexpr (kNoFxFy) {
    out.wrench_unallocated(0) = wrench_cmd(kFx);
    out.wrench_unallocated(1) = wrench_cmd(kFy);
  } else {
    out.wrench_unallocated(0) = wrench_cmd(kFx) - r0;
    out.wrench_unallocated(1) = wrench_cmd(kFy) - r1;
  }
  out.wrench_unallocated(2) = wrench_cmd(kFz) - r2;
  out.wrench_unallocated(3) = wrench_cmd(kTx) - r3;
  out.wrench_unallocated(4) = wrench_cmd(kTy) - r4;
  out.wrench_unallocated(5) = wrench_cmd(kTz) - r5;
  if ((low | high) != 0) state.faults.raise(kFaultSaturated);
  return true;
}

template <int kN>
Status allocate(const AllocationModel& model, const SequentialDesaturationParams& params, AllocatorState& state,
                const Vec6& wrench_cmd, AllocationResult& out) {
  Work<kN> w;
  w.n_rt = model.num_rotors;
  w.lo = model.thrust_min_N;
  w.hi = model.thrust_max_N;
  const int n = w.count();

  // f = A+ w (written out: see apply_pinv), with the limit check of the fast path. Fast path: the
  // full pseudo-inverse solution is within limits, so the command is feasible as is and no axis
  // has to give anything up (the common case in flight). PX4 mixes roll/pitch first even then,
  // which differs only when adding yaw would bring an out-of-range motor back in range; the exact
  // answer is kept here.
  const PlainMat<kMaxRotors, 6>& p = model.pinv;
  const real w0 = wrench_cmd(kFx), w1 = wrench_cmd(kFy), w2 = wrench_cmd(kFz), w3 = wrench_cmd(kTx);
  const real w4 = wrench_cmd(kTy), w5 = wrench_cmd(kTz);
  bool feasible = true;
  for_rotors<kN>(n, [&](int i) __attribute__((always_inline)) {
    real f = p(i, kFx) * w0;
    f += p(i, kFy) * w1;
    f += p(i, kFz) * w2;
    f += p(i, kTx) * w3;
    f += p(i, kTy) * w4;
    f += p(i, kTz) * w5;
    w.f[i] = f;
    feasible = feasible && f >= w.lo[i] && f <= w.hi[i];
  });

  if (!feasible) {
    const real headroom = is_finite(params.yaw_headroom) && params.yaw_headroom > 0 ? params.yaw_headroom : real(0);
    const Direction thrust = direction(model, kFz);
    const Direction yaw = direction(model, kTz);
    switch (params.airmode) {
      case Airmode::roll_pitch_yaw:
        desaturate(w, thrust, GainSign::any);
        desaturate(w, yaw, GainSign::any);
        break;
      case Airmode::disabled:
        shift(w, yaw, -wrench_cmd(kTz));  // take the yaw term out again (cheaper than re-mixing)
        desaturate(w, thrust, GainSign::non_positive);
        desaturate(w, direction(model, kTx), GainSign::any);
        desaturate(w, direction(model, kTy), GainSign::any);
        mix_yaw(w, yaw, thrust, wrench_cmd(kTz), headroom);
        break;
      case Airmode::roll_pitch:
      default:
        shift(w, yaw, -wrench_cmd(kTz));
        desaturate(w, thrust, GainSign::any);
        mix_yaw(w, yaw, thrust, wrench_cmd(kTz), headroom);
        break;
    }
  }

  // Saturation masks (before the clamp), the clamp into the limits (detail::finish_allocation),
  // the held output and the realized wrench A f, in one pass. A multirotor whose rotors are all
  // parallel to body z (every quadrotor preset) has rows fx, fy of A all zero
  // (model.wrench_row_mask): their sums would be exactly +0 for finite thrusts and command - 0 is
  // the command, so that case is compiled without them (~30 Cortex-M4F instructions per call).
  //
  // A finite command near the float limit (a huge body rate or gain upstream) can overflow A+ w to
  // +-inf and the desaturation's differences to NaN: finish() reports that instead of storing it,
  // and the last finite output is held (kFaultNonFiniteOutput, Status::non_finite_output).
  const bool finite = (kN > 0 && (model.wrench_row_mask & 3u) == 0)
                          ? finish<kN, true>(model, w, feasible, wrench_cmd, state, out)
                          : finish<kN, false>(model, w, feasible, wrench_cmd, state, out);
  if (!finite) return detail::hold_nonfinite_result(model, state, out);
  return Status::ok;
}

}  // namespace

Status allocate_sequential_desaturation(const AllocationModel& model, const SequentialDesaturationParams& params,
                                        AllocatorState& state, const Vec6& wrench_cmd, AllocationResult& out) {
  const int n = model.num_rotors;
  if (n < 1 || n > kMaxRotors) return Status::invalid_argument;
  // A library built for quadrotors (KESTREL_MAX_ROTORS=4, what a quad's firmware links) keeps
  // only the unrolled 4-rotor path below: the run-time-count copy would be ~840 B of flash that
  // the quad never runs. Same arithmetic as the default build (kestrel_cascade_capacity_parity);
  // 1-3 rotor airframes need a larger capacity build (or allocate_pinv / CLS).
  if (kMaxRotors == 4 && n != 4) return Status::invalid_argument;
  // all_finite(wrench_cmd), branch-free: w - w is exactly +0 for a finite w and NaN for inf or
  // NaN, and a sum with a NaN term is NaN. One compare instead of six classify-and-branch steps
  // (~28 Cortex-M4F instructions per call on every path). Needs IEEE semantics (no fast-math,
  // which the project never uses).
  const real z0 = wrench_cmd(0) - wrench_cmd(0), z1 = wrench_cmd(1) - wrench_cmd(1);
  const real z2 = wrench_cmd(2) - wrench_cmd(2), z3 = wrench_cmd(3) - wrench_cmd(3);
  const real z4 = wrench_cmd(4) - wrench_cmd(4), z5 = wrench_cmd(5) - wrench_cmd(5);
  if (!((z0 + z1) + (z2 + z3) + (z4 + z5) == 0)) return detail::hold_allocation(model, state, out);
  if constexpr (kMaxRotors == 4) {
    return allocate<4>(model, params, state, wrench_cmd, out);
  } else {
    switch (n) {
      case 4:
        return allocate<4>(model, params, state, wrench_cmd, out);
      default:
        return allocate<0>(model, params, state, wrench_cmd, out);
    }
  }
}

}  // namespace kestrel::allocation
