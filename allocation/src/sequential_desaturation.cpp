// Sequential desaturation; see sequential_desaturation.hpp for the method and its sources.
#include "kestrel/allocation/sequential_desaturation.hpp"

#include <cmath>

#include "kestrel/kernel/math.hpp"

namespace kestrel::allocation {

namespace {

enum Axis : int { kFx = 0, kFy = 1, kFz = 2, kTx = 3, kTy = 4, kTz = 5 };

enum class GainSign : std::uint8_t { any, non_positive };

/// One desaturation direction: a column of A+ (motor thrust per unit of one wrench axis; the
/// matrix is column-major, so the column is contiguous).
struct Direction {
  const real* d;
  real d_min;  // |d_i| <= d_min: motor i cannot be moved along this axis
};

Direction direction(const AllocationModel& model, int axis) {
  // PX4 skips |d| < FLT_EPSILON on its normalised matrix; A+ is in physical units here, so the
  // threshold is relative to the column's largest entry (precomputed with the model).
  return Direction{&model.pinv(0, axis), 1e-6_r * model.pinv_col_abs_max[axis]};
}

struct Work {
  int n;
  const real* lo;
  const real* hi;
  real* f;  // the thrusts being desaturated (the result's array)
};

/// Gain k along `dir` that removes the worst violation of [lo, hi]: the smallest negative and the
/// largest positive k that bring each violating motor back to its bound, summed (one of them is
/// zero unless motors violate both ways, then the sum balances them).
real desaturation_gain(const Work& w, const Direction& dir, const real* hi) {
  real k_min = 0, k_max = 0;
  for (int i = 0; i < w.n; ++i) {
    const real f = w.f[i];
    real k;
    if (f < w.lo[i]) {
      k = w.lo[i] - f;
    } else if (f > hi[i]) {
      k = hi[i] - f;
    } else {
      continue;
    }
    const real d = dir.d[i];
    if (!(std::fabs(d) > dir.d_min)) continue;
    k /= d;
    k_min = k < k_min ? k : k_min;
    k_max = k > k_max ? k : k_max;
  }
  return k_min + k_max;
}

void shift(Work& w, const Direction& dir, real gain) {
  for (int i = 0; i < w.n; ++i) w.f[i] += gain * dir.d[i];
}

/// Two passes: remove the worst violation, then half of what remains (PX4 desaturateActuators).
/// `hi` replaces the upper limits (yaw headroom).
void desaturate(Work& w, const Direction& dir, GainSign sign, const real* hi) {
  real gain = desaturation_gain(w, dir, hi);
  if (sign == GainSign::non_positive && gain > 0) return;
  if (gain == 0) return;  // nothing violated: the second pass would find nothing either
  shift(w, dir, gain);
  gain = 0.5_r * desaturation_gain(w, dir, hi);
  if (sign == GainSign::non_positive && gain > 0) return;
  shift(w, dir, gain);
}
void desaturate(Work& w, const Direction& dir, GainSign sign) { desaturate(w, dir, sign, w.hi); }

/// f = A+ w (written out: see apply_pinv).
void mix(Work& w, const PinvMatrix& p, const Vec6& wrench) {
  const real w0 = wrench(kFx), w1 = wrench(kFy), w2 = wrench(kFz), w3 = wrench(kTx), w4 = wrench(kTy);
  const real w5 = wrench(kTz);
  for (int i = 0; i < w.n; ++i) {
    real f = p(i, kFx) * w0;
    f += p(i, kFy) * w1;
    f += p(i, kFz) * w2;
    f += p(i, kTx) * w3;
    f += p(i, kTy) * w4;
    f += p(i, kTz) * w5;
    w.f[i] = f;
  }
}

/// Adds yaw, fits it with headroom, then removes the headroom by reducing thrust only.
void mix_yaw(Work& w, const Direction& yaw, const Direction& thrust, real yaw_cmd, real headroom) {
  shift(w, yaw, yaw_cmd);
  real hi[kMaxRotors];
  for (int i = 0; i < w.n; ++i) hi[i] = w.hi[i] + headroom * (w.hi[i] - w.lo[i]);
  desaturate(w, yaw, GainSign::any, hi);
  desaturate(w, thrust, GainSign::non_positive);
}

}  // namespace

Status allocate_sequential_desaturation(const AllocationModel& model, const SequentialDesaturationParams& params,
                                        AllocatorState& state, const Vec6& wrench_cmd, AllocationResult& out) {
  const int n = model.num_rotors;
  if (n < 1 || n > kMaxRotors) return Status::invalid_argument;
  if (!all_finite(wrench_cmd)) return detail::hold_allocation(model, state, out);

  Work w;
  w.n = n;
  w.lo = model.thrust_min_N;
  w.hi = model.thrust_max_N;
  w.f = out.thrust_N;

  // Fast path: the full pseudo-inverse solution is within limits, so the command is feasible as
  // is and no axis has to give anything up (the common case in flight). PX4 mixes roll/pitch
  // first even then, which differs only when adding yaw would bring an out-of-range motor back in
  // range; the exact answer is kept here.
  mix(w, model.pinv, wrench_cmd);
  bool feasible = true;
  for (int i = 0; i < n; ++i) feasible = feasible && w.f[i] >= w.lo[i] && w.f[i] <= w.hi[i];

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

  std::uint16_t low = 0, high = 0;
  for (int i = 0; i < n; ++i) {
    const real lo = w.lo[i], hi = w.hi[i];
    if (!(hi > lo)) continue;  // dead motor: reported through the model, not as saturated
    const real tol = 1e-5_r * (hi - lo);
    if (w.f[i] <= lo + tol) low = static_cast<std::uint16_t>(low | (1u << i));
    if (w.f[i] >= hi - tol) high = static_cast<std::uint16_t>(high | (1u << i));
  }
  out.saturated_low_mask = low;
  out.saturated_high_mask = high;
  out.iterations = 0;
  detail::finish_allocation(model, state, wrench_cmd, out);
  return Status::ok;
}

}  // namespace kestrel::allocation
