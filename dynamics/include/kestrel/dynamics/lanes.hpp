// Lanes of one scalar type for the batched dynamics (multibody.hpp's aba_batch): L robots of one
// model computed side by side, one per lane, as the multirotor's batched step does for its robots
// (sim/batch_step.hpp). A lane value is a GCC vector (`vector_size`): + - * / act lane by lane as
// IEEE operations, so every lane computes with the same operations in the same order as the scalar
// code and gets the same bits (-ffp-contract=off: no fused multiply-add on either side). Where the
// target has SIMD registers of that width (SSE2: 4 floats) the compiler uses them; on an MCU it
// lowers them to scalar code. sqrt and sin_cos call the scalar function once per lane: the
// function the scalar path calls, hence the same bits.
//
// Core rules: no heap, no exceptions; float or double (kernel/types.hpp's real).
#pragma once

#include <cmath>
#include <type_traits>

#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/types.hpp"

// Lanes wider than the target's registers (4 doubles without AVX) are passed in memory: GCC notes
// that this differs from an AVX build's ABI (-Wpsabi). These functions are inline templates, never
// an interface between separately compiled code, so the note does not apply.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

namespace kestrel::dynamics {

namespace detail {
// A dependent vector_size in an alias template is ignored by GCC: one specialisation per width.
template <int L>
struct LaneType;
template <>
struct LaneType<2> {
  typedef real type __attribute__((vector_size(2 * sizeof(real))));
};
template <>
struct LaneType<4> {
  typedef real type __attribute__((vector_size(4 * sizeof(real))));
};
template <>
struct LaneType<8> {
  typedef real type __attribute__((vector_size(8 * sizeof(real))));
};
}  // namespace detail

/// L lanes of `real` (L = 2, 4 or 8; 4 is the batched path the tests and the bench run).
template <int L>
using Lanes = typename detail::LaneType<L>::type;

namespace lanes {

template <class T>
constexpr int count() {
  if constexpr (std::is_same_v<T, real>) {
    return 1;
  } else {
    return static_cast<int>(sizeof(T) / sizeof(real));
  }
}

/// The value x in every lane (x itself for a scalar).
template <class T>
inline T splat(real x) {
  if constexpr (std::is_same_v<T, real>) {
    return x;
  } else {
    T v = {};
    for (int l = 0; l < count<T>(); ++l) v[l] = x;
    return v;
  }
}

/// The scalar function f of each lane.
template <class T, class F>
inline T map(const T& x, F f) {
  if constexpr (std::is_same_v<T, real>) {
    return f(x);
  } else {
    T y = x;
    for (int l = 0; l < count<T>(); ++l) y[l] = f(x[l]);
    return y;
  }
}
template <class T>
inline T sqrt(const T& x) {
  return map(x, [](real v) { return std::sqrt(v); });
}
/// Sine and cosine of each lane by the kernel's sin_cos (kernel/math.hpp: in float its own
/// polynomial, the same bits on the host and every MCU and no libm; in double the library's).
template <class T>
inline void sin_cos(const T& x, T& s, T& c) {
  if constexpr (std::is_same_v<T, real>) {
    kestrel::sin_cos(x, s, c);
  } else {
    s = x;
    c = x;
    for (int l = 0; l < count<T>(); ++l) {
      real sl = 0, cl = 0;
      kestrel::sin_cos(x[l], sl, cl);
      s[l] = sl;
      c[l] = cl;
    }
  }
}

/// Bit l set where lane l fails `pred` (a predicate on one real).
template <class T, class P>
inline unsigned failing(const T& x, P pred) {
  if constexpr (std::is_same_v<T, real>) {
    return pred(x) ? 0u : 1u;
  } else {
    unsigned bits = 0;
    for (int l = 0; l < count<T>(); ++l) bits |= (pred(x[l]) ? 0u : 1u) << l;
    return bits;
  }
}
/// Bit l set where lane l is not positive (NaN included): `!(x > 0)`.
template <class T>
inline unsigned not_positive(const T& x) {
  return failing(x, [](real v) { return v > 0; });
}
/// Bit l set where lane l is not finite.
template <class T>
inline unsigned not_finite(const T& x) {
  return failing(x, [](real v) { return std::isfinite(v); });
}

}  // namespace lanes
}  // namespace kestrel::dynamics

#pragma GCC diagnostic pop
