// Scalar helpers: finite checks, clamps, angle wrapping. Deterministic (no fast-math tricks).
#pragma once

#include <cmath>

#include "kestrel/kernel/types.hpp"

namespace kestrel {

inline bool is_finite(real v) { return std::isfinite(v); }

template <typename Derived>
inline bool all_finite(const Eigen::MatrixBase<Derived>& m) {
  for (Eigen::Index i = 0; i < m.size(); ++i) {
    if (!std::isfinite(m.coeff(i))) return false;
  }
  return true;
}

inline bool all_finite(const real* v, int n) {
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(v[i])) return false;
  }
  return true;
}

constexpr real clamp(real v, real lo, real hi) { return v < lo ? lo : (v > hi ? hi : v); }

/// Sign with sign(0) = 0, as torch.sign (the motor model's time-constant switch depends on it).
constexpr real sign0(real v) { return v > 0 ? real(1) : (v < 0 ? real(-1) : real(0)); }

/// Wrap an angle to [-pi, pi) (Aerial Gym's ssa(): smallest signed angle).
inline real wrap_pi(real a) {
  // fmod keeps the operation exact for the inputs the controllers see; the second branch
  // moves +pi to -pi so the range is half-open like the reference.
  real r = std::fmod(a + kPi, kTwoPi);
  if (r < 0) r += kTwoPi;
  return r - kPi;
}

/// Wrap an angle to [0, 2 pi).
inline real wrap_two_pi(real a) {
  real r = std::fmod(a, kTwoPi);
  if (r < 0) r += kTwoPi;
  return r;
}

}  // namespace kestrel
