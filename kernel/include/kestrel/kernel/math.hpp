// Scalar helpers: finite checks, clamps, angle wrapping, sine/cosine. Deterministic (no fast-math
// tricks).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

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

template <int Rows, int Cols>
inline bool all_finite(const PlainMat<Rows, Cols>& m) {
  return all_finite(m.map());
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

namespace detail {

/// Single-precision sine and cosine of one argument, after Cephes sinf.c / cosf.c (S. L. Moshier,
/// Cephes Math Library 2.2, 1992; also the basis of many embedded libms):
///  - range reduction: j = trunc(|x| * 4/pi) rounded up to even, so |x| = j pi/4 + r with
///    |r| <= pi/4; r is computed Cody-Waite style with pi/4 split into three floats DP1 + DP2 + DP3
///    (DP1, DP2 have few significant bits, so j * DP1 and j * DP2 are exact for the j used here);
///  - minimax polynomials on [-pi/4, pi/4]: sin r = r + r^3 P(r^2), cos r = 1 - r^2/2 + r^4 Q(r^2)
///    with Cephes' coefficients (peak relative error ~1.2e-7 on +-4096 per Cephes' documentation;
///    tests/kernel/test_math.cpp measures it against double on both targets).
/// Why not std::sin / std::cos: newlib's sinf + cosf pull ~2.9 KB of Payne-Hanek reduction
/// (__kernel_rem_pio2f and its 2/pi table) into the firmware, cost ~160 instructions per angle on
/// a Cortex-M4F, and give different bits than glibc on the host. This uses only float +, -, *,
/// so under -ffp-contract=off it gives the same bits on every IEEE target.
/// Domain: full accuracy for |x| <= 8192 (Cephes' lossth); from there to 2^24 the reduction is a
/// single-constant one (absolute error ~ulp(|x|), e.g. ~1e-3 at 8192 rad); beyond 2^24 (where
/// consecutive floats are more than a radian apart and the angle is meaningless) it returns
/// sin 0, cos 1 as Cephes does; NaN / inf give NaN. The controllers' angles are clipped to the
/// action range (default +-10 rad).
/// The reduced path of sincos_f32 (|x| >= ~pi/4, NaN, inf), out of line: see sincos_f32.
__attribute__((noinline)) inline void sincos_f32_reduced(float x, float& s, float& c) {
  constexpr float kFourOverPi = 1.27323954473516f;
  constexpr float kDP1 = 0.78515625f;
  constexpr float kDP2 = 2.4187564849853515625e-4f;
  constexpr float kDP3 = 3.77489497744594108e-8f;
  constexpr float kLossTh = 8192.0f;
  constexpr float kT24M1 = 16777215.0f;
  const bool neg = x < 0;
  float ax = neg ? -x : x;
  if (!(ax <= kT24M1)) {
    // NaN or inf: NaN out (x - x); huge finite: Cephes' answer for sin, cos = 1.
    const float v = (ax - ax);  // 0 for finite, NaN for inf/NaN
    s = v;
    c = 1 + v;
    return;
  }
  const float q = kFourOverPi * ax;
  int j = static_cast<int>(q);
  float y = static_cast<float>(j);
  if (j & 1) {  // map zeros to the origin: round the octant up to even
    j += 1;
    y += 1;
  }
  if (ax <= kLossTh) {
    ax = ((ax - y * kDP1) - y * kDP2) - y * kDP3;
  } else {
    ax = ax - y * 0.7853981633974483096f;
  }
  const float z = ax * ax;
  const float ps = ((-1.9515295891e-4f * z + 8.3321608736e-3f) * z - 1.6666654611e-1f) * z * ax + ax;
  const float pc = ((2.443315711809948e-5f * z - 1.388731625493765e-3f) * z + 4.166664568298827e-2f) * z * z -
                   0.5f * z + 1.0f;
  // |x| = k pi/2 + r with k = j/2: (sin, cos)(|x|) = (ps, pc), (pc, -ps), (-ps, -pc), (-pc, ps).
  const int k = (j >> 1) & 3;
  float sv, cv;
  if (k & 1) {
    sv = pc;
    cv = ps;
  } else {
    sv = ps;
    cv = pc;
  }
  if (k >= 2) sv = -sv;
  if (k == 1 || k == 2) cv = -cv;
  s = neg ? -sv : sv;  // sine is odd, cosine even
  c = cv;
}

/// Octant 0 (|x| < ~pi/4, the common case for commanded attitudes: no reduction) is forced inline
/// into the caller (~20 instructions on a Cortex-M4F, against ~35 for the call alone, whose
/// results come back through memory); everything else goes to sincos_f32_reduced. Same bits as
/// the general path, where j = 0 makes every reduction term exactly zero. NaN fails q < 1.
__attribute__((always_inline)) inline void sincos_f32(float x, float& s, float& c) {
  constexpr float kFourOverPi = 1.27323954473516f;
  const bool neg = x < 0;
  const float ax = neg ? -x : x;
  const float q = kFourOverPi * ax;
  if (q < 1) {
    const float z = ax * ax;
    const float ps = ((-1.9515295891e-4f * z + 8.3321608736e-3f) * z - 1.6666654611e-1f) * z * ax + ax;
    s = neg ? -ps : ps;
    c = ((2.443315711809948e-5f * z - 1.388731625493765e-3f) * z + 4.166664568298827e-2f) * z * z - 0.5f * z + 1.0f;
    return;
  }
  sincos_f32_reduced(x, s, c);
}

}  // namespace detail

/// Sine and cosine of one angle (named sin_cos: glibc declares ::sincos). Float builds use
/// detail::sincos_f32 (deterministic, identical bits on the host and the MCU, no libm); double
/// builds (host only) use the library's double functions.
inline void sin_cos(real x, real& s, real& c) {
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  s = std::sin(x);
  c = std::cos(x);
#else
  detail::sincos_f32(x, s, c);
#endif
}

/// e^x and tanh(x) with identical bits on the host and every MCU (no libm: libm's expf/tanhf
/// differ between glibc and newlib in the last bit), for the policy network's activations.
/// Float algorithms after S. L. Moshier's Cephes expf and tanhf (range reduction by ln 2 split
/// into an exact and a small part, degree-5 minimax polynomial; tanh by a degree-5 odd polynomial
/// below 0.625 and 1 - 2 / (e^2x + 1) above): about 1 ulp of float. Double builds (host only) use
/// the library.
namespace detail {
/// 2^e as a float, for e in [-126, 127] (exact: the exponent field alone).
__attribute__((always_inline)) inline float exp2i_f32(int e) {
  const std::uint32_t u = static_cast<std::uint32_t>(e + 127) << 23;
  float f;
  std::memcpy(&f, &u, sizeof f);
  return f;
}
/// exp_f32's main path, for x in [-103.97..., 88.72...] (no NaN): callers that know their range
/// (tanh_f32's large branch, the ELU's negative side) skip the checks, with the same bits.
/// kNormalOnly: x in [-87.3, 88.7], where the result is a normal float and the scaling by 2^n
/// needs one step: the same bits without the two range branches (the ELU's side above -17.5).
template <bool kNormalOnly = false>
__attribute__((always_inline)) inline float exp_f32_reduced(float x) {
  constexpr float kLog2e = 1.44269504088896341f;
  const float zf = kLog2e * x + 0.5f;
  // n = floor(zf): truncation, then one down where that rounded up (zf < 0, not an integer; for
  // zf >= 0 the truncation is never above zf, so the test needs no sign check).
  int n = static_cast<int>(zf);
  float fn = static_cast<float>(n);
  if (fn > zf) {
    --n;
    fn = static_cast<float>(n);
  }
  float r = x - fn * 0.693359375f;
  r = r - fn * -2.12194440e-4f;
  const float z = r * r;
  float y = ((((1.9875691500e-4f * r + 1.3981999507e-3f) * r + 8.3334519073e-3f) * r + 4.1665795894e-2f) * r +
             1.6666665459e-1f) * r + 5.0000001201e-1f;
  y = y * z + r + 1.0f;
  // y * 2^n in two exact power-of-two steps (n may reach -150 on the way to a subnormal).
  if (!kNormalOnly) {
    if (n > 127) return y * exp2i_f32(127) * exp2i_f32(n - 127);
    if (n < -126) return y * exp2i_f32(-126) * exp2i_f32(n + 126 < -126 ? -126 : n + 126);
  }
  return y * exp2i_f32(n);
}
inline float exp_f32(float x) {
  if (!(x == x)) return x;                    // NaN
  if (x > 88.72283905206835f) return std::numeric_limits<float>::infinity();
  if (x < -103.972077083991796f) return 0.0f;
  return exp_f32_reduced(x);
}
/// e^x for x <= 0 or NaN (the ELU's negative side): exp_f32 without its overflow test, which no
/// such x passes; the same bits.
__attribute__((always_inline)) inline float exp_f32_nonpositive(float x) {
  if (x >= -103.972077083991796f) return exp_f32_reduced(x);  // false for NaN
  return x == x ? 0.0f : x;
}
/// tanh for |x| > 0.625 or NaN: 1 - 2 / (e^2|x| + 1) with the sign of x, +-1 beyond 9.01.
inline float tanh_f32_large(float x) {
  const bool neg = x < 0;
  const float ax = neg ? -x : x;
  if (!(ax == ax)) return x;                        // NaN
  if (ax > 9.01091334f) return neg ? -1.0f : 1.0f;  // tanh rounds to 1 in float
  const float e = exp_f32_reduced(2 * ax);          // 2|x| in (1.25, 18.03]: no range checks
  const float t = 1.0f - 2.0f / (e + 1.0f);
  return neg ? -t : t;
}
/// tanh_f32's polynomial branch: its bound and coefficients, as values so that a loop can hold
/// them in registers (policy/mlp.hpp does; the arithmetic is the same with literals).
struct TanhSmall {
  float max_abs, c5, c4, c3, c2, c1;
};
inline constexpr TanhSmall kTanhSmall{0.625f, -5.70498872745e-3f, 2.06390887954e-2f, 5.37397155531e-2f,
                                      1.33314422036e-1f, 3.33332819422e-1f};
/// |x| <= 0.625: the odd polynomial, evaluated on x itself. z = x * x and the polynomial in z are
/// the same for -x, and the last two steps ((p z) x, then + x) see every operand negated, which
/// round-to-nearest maps to exactly the negated result: tanh(-x) = -tanh(x) bit for bit, the bits
/// of evaluating on |x| and negating (the form this had before), without its sign tests. -0 gives
/// +0 both ways: (p(0) 0) (-0) + (-0) = (-0)(-0) + (-0) = +0 + -0 = +0. Everything else (|x| >
/// 0.625, NaN) goes to tanh_f32_large.
__attribute__((always_inline)) inline float tanh_f32(float x, const TanhSmall& c = kTanhSmall) {
  if (std::fabs(x) <= c.max_abs) {  // false for NaN
    const float z = x * x;
    return ((((c.c5 * z + c.c4) * z - c.c3) * z + c.c2) * z - c.c1) * z * x + x;
  }
  return tanh_f32_large(x);
}
}  // namespace detail

inline real exp_det(real x) {
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  return std::exp(x);
#else
  return detail::exp_f32(x);
#endif
}
inline real tanh_det(real x) {
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  return std::tanh(x);
#else
  return detail::tanh_f32(x);
#endif
}

}  // namespace kestrel
