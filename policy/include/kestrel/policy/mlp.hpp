// A trained policy as code of the core: a fixed-size multilayer perceptron (two hidden layers,
// sizes known at compile time) with the observation normalisation and action mapping used in
// training, evaluated without heap, exceptions or libm, with identical bits on the host and every
// MCU preset (activations from kernel/math.hpp: exp_det, tanh_det).
//
// The network is what on-policy learners train for continuous control: PPO's actor (J. Schulman
// et al., "Proximal Policy Optimization Algorithms", 2017) as Stable-Baselines3 builds it (64-64,
// tanh) or rsl_rl (ELU); its deterministic action is the Gaussian's mean. Learning to Fly in
// Seconds (J. Eschmann et al., 2024) flies a 64-64 network on the Crazyflie's STM32F405 inside
// a 500 Hz loop; the MCU bench measures this one on the same chip.
//
// It is a command source upstream of the controller table, not a controller kind (code review
// P5): policy -> action -> robots::multirotor_step, so one policy drives lee_velocity on the MCU
// and in the simulator alike.
//
// On the Cortex-M4F/M7 the dense layers run as VFP assembly (detail::dense_vfp: chained VMLA, one
// rounding after the multiply and one after the add, as the portable code, so the same bits;
// tests/policy/test_mlp.cpp checks them against the plain loop), about 2.2x fewer instructions
// per inference (bench/results/cortex-m4f/control.csv, the mlp_forward rows).
//
// Weights live wherever the caller puts them: a `const MlpParams` generated into flash by
// python/kestrel/export.py (hex-float literals), or static storage filled at set-up.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/status.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel::policy {

enum class Activation : std::uint8_t {
  tanh = 0,  // Stable-Baselines3's default
  elu = 1,   // rsl_rl's default (alpha = 1)
  relu = 2,
};

/// What the output layer's mean goes through before the action clip: nothing (SB3, rsl_rl's
/// default: the learner clips), or tanh (a squashed Gaussian, into [-1, 1]).
enum class Squash : std::uint8_t { none = 0, tanh = 1 };

template <int kIn, int kOut>
struct DenseLayer {
  real weight[kOut][kIn];  // PyTorch's nn.Linear layout: weight[out][in]
  real bias[kOut];
};

/// The parts of a network besides its layers that a network may leave out, so that neither their
/// numbers nor their code reach flash (a compile-time choice: MlpParams' last argument).
enum MlpParts : unsigned {
  kMlpObsNorm = 1u,      // observation normalisation: x = clamp((obs - mean) * inv_std, -clip, clip)
  kMlpActionClamp = 2u,  // the clamp of the squashed output to [action_low, action_high]
  kMlpAllParts = 3u,
};
/// Where a part is left out, its members are of this empty type.
struct MlpAbsent {};

template <int kObs, int kH1, int kH2, int kAct, unsigned kParts = kMlpAllParts>
struct MlpParams {
  static_assert(kObs > 0 && kH1 > 0 && kH2 > 0 && kAct > 0, "layer sizes must be positive");
  static_assert((kParts & ~unsigned{kMlpAllParts}) == 0, "unknown MlpParts bit");
  static constexpr int obs_dim = kObs;
  static constexpr int action_dim = kAct;
  static constexpr bool has_obs_norm = (kParts & kMlpObsNorm) != 0;
  static constexpr bool has_action_clamp = (kParts & kMlpActionClamp) != 0;
  template <class T>
  using Part = std::conditional_t<has_obs_norm, T, MlpAbsent>;
  template <class T>
  using ClampPart = std::conditional_t<has_action_clamp, T, MlpAbsent>;
  Activation activation;
  // Observation normalisation as in training: x = clamp((obs - mean) * inv_std, -clip, clip)
  // (SB3 VecNormalize, rsl_rl EmpiricalNormalization; identity: mean 0, inv_std 1, clip large).
  // Without kMlpObsNorm the observation is the first layer's input as it is (python/kestrel/
  // export.py leaves the part out for a network trained without normalisation: 108 B of a
  // 13-input network's flash, and its loop).
  Part<real[kObs]> obs_mean;
  Part<real[kObs]> obs_inv_std;
  Part<real> obs_clip;
  DenseLayer<kObs, kH1> hidden1;
  DenseLayer<kH1, kH2> hidden2;
  DenseLayer<kH2, kAct> output;  // the Gaussian's mean (deterministic action)
  // Action mapping: action = offset + scale * clamp(squash(y), low, high) (the learner's squash or
  // clip to the action space, then the task's scaling into controller units). Without
  // kMlpActionClamp: offset + scale * squash(y) (export.py leaves the clamp out where it cannot
  // act: a tanh squash into [-1, 1] within [low, high]).
  ClampPart<real[kAct]> action_low;
  ClampPart<real[kAct]> action_high;
  real action_scale[kAct];
  real action_offset[kAct];
  Squash output_squash;  // last, so that a zero-initialised (static) network has none
};

namespace detail {
// Cortex-M4F/M7 (single-precision VFP, float core): the dense layers in VFP assembly (dense_vfp).
#if defined(__ARM_ARCH_7EM__) && defined(__ARM_FP) && (__ARM_FP & 4) && \
    !(defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE)
#define KESTREL_MLP_ARM_VFP 1
#endif

inline real activate(Activation a, real x) {
  switch (a) {
    case Activation::tanh: return tanh_det(x);
    case Activation::elu: return x > 0 ? x : exp_det(x) - 1;
    case Activation::relu: return x > 0 ? x : 0;
  }
  return x;
}
// activate() over an array, one loop per kind (the kind does not change within a layer); the same
// function of each element. Float builds call the pieces of tanh_det / exp_det that the element
// can reach (kernel/math.hpp: ELU's exp of x <= 0 skips the overflow test, which no such x passes),
// with the same bits.
//
// One out-of-line function per kind (noinline): a network's two hidden layers share one copy of
// its activation's code, and a network whose kind is a constant (a constexpr MlpParams in flash,
// mlp_forward inlined into its caller) links only that kind's. On the M4F this is what keeps the
// policy's code small beside its weights (the 22 KB flash goal of a 64-64 network).
#if !(defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE)
__attribute__((noinline)) inline void tanh_all(real* v, int n) {
  kestrel::detail::TanhSmall c = kestrel::detail::kTanhSmall;
#if defined(KESTREL_MLP_ARM_VFP)
  // Empty asm: the values are unchanged, but GCC can no longer reload them from the literal
  // pool on every iteration, so they stay in registers for the whole loop.
  __asm__("" : "+t"(c.max_abs), "+t"(c.c5), "+t"(c.c4), "+t"(c.c3), "+t"(c.c2), "+t"(c.c1));
#endif
  for (int i = 0; i < n; ++i) v[i] = kestrel::detail::tanh_f32(v[i], c);
}
// Below -17.5, e^x < 2^-25 and e^x - 1 rounds to -1 exactly, so the exp runs only on
// [-17.5, 0], where its result is normal (exp_f32_reduced<true>: no range branches): the bits of
// exp_f32_nonpositive(x) - 1 for every x, NaN included, in less code.
__attribute__((noinline)) inline void elu_all(real* v, int n) {
  for (int i = 0; i < n; ++i) {
    const real x = v[i];
    if (x > 0) continue;
    v[i] = x >= -17.5f ? kestrel::detail::exp_f32_reduced<true>(x) - 1 : (x == x ? -1.0f : x);
  }
}
__attribute__((noinline)) inline void relu_all(real* v, int n) {
  for (int i = 0; i < n; ++i)
    if (!(v[i] > 0)) v[i] = 0;
}
#endif

// tanh of the output layer (a squashed Gaussian's mean). An ELU network takes it from the ELU's
// own e^x - 1 (elu_all on -2|y| <= 0): tanh|y| = -t / (2 + t) with t = e^-2|y| - 1, so it links
// one exp and no tanh (about 0.45 KB less flash on the M4F); within 1.2e-7 of tanh (t's rounding
// near 0: absolute, not relative, for tiny y). Other kinds: tanh_det's bits (tanh_all).
__attribute__((always_inline)) inline void squash_tanh_all(Activation a, real* y, int n) {
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  (void)a;
  for (int i = 0; i < n; ++i) y[i] = tanh_det(y[i]);
#else
  if (a == Activation::elu) {
    for (int i = 0; i < n; ++i) {
      real t = -2 * std::fabs(y[i]);
      elu_all(&t, 1);
      const real u = -t / (2 + t);
      y[i] = y[i] < 0 ? -u : u;
    }
    return;
  }
  tanh_all(y, n);
#endif
}

__attribute__((always_inline)) inline void activate_all(Activation a, real* v, int n) {
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  for (int i = 0; i < n; ++i) v[i] = activate(a, v[i]);
#else
  switch (a) {
    case Activation::tanh: tanh_all(v, n); return;
    case Activation::elu: elu_all(v, n); return;
    case Activation::relu: relu_all(v, n); return;
  }
#endif
}

// y = b + W x, each output summed in input order (-ffp-contract=off: no fused multiply-add on any
// target). Four outputs at a time share each load of x[i] (a 64-64 network is ~5,200
// multiply-adds: on the Cortex-M4F the loads, not the FPU, set the cost); the sums and their order
// are those of the plain loop, so the bits are too.
__attribute__((always_inline)) inline void dense_portable(const real* w, const real* b, int in, int out,
                                                          const real* x, real* y) {
  const int groups = out / 4;
  for (int g = 0; g < groups; ++g) {
    const int o = 4 * g;
    const real* r0 = w + o * in;
    const real* r1 = r0 + in;
    const real* r2 = r1 + in;
    const real* r3 = r2 + in;
    real a0 = b[o], a1 = b[o + 1], a2 = b[o + 2], a3 = b[o + 3];
    for (int i = 0; i < in; ++i) {
      const real xi = x[i];
      a0 += r0[i] * xi;
      a1 += r1[i] * xi;
      a2 += r2[i] * xi;
      a3 += r3[i] * xi;
    }
    y[o] = a0;
    y[o + 1] = a1;
    y[o + 2] = a2;
    y[o + 3] = a3;
  }
  for (int o = 4 * groups; o < out; ++o) {
    real acc = b[o];
    const real* row = w + o * in;
    for (int i = 0; i < in; ++i) acc += row[i] * x[i];
    y[o] = acc;
  }
}

#if defined(KESTREL_MLP_ARM_VFP)
// Cortex-M4F/M7 (single-precision VFP): dense_portable's sums in hand-written VFP code, four rows
// of W at a time, each output summed in input order from its bias. Two instructions differ from
// what GCC emits, neither of them in the arithmetic:
//  - VMLA.F32 Sd, Sn, Sm is the *chained* (non-fused) multiply-accumulate: the product rounded to
//    float, then the sum rounded (Armv7-M ARM, VMLA pseudocode: S[d] = FPAdd(S[d], FPMul(S[n],
//    S[m]))); VFMA is the fused one and is never used here. So one VMLA gives exactly the bits of
//    `acc += w * x` compiled under -ffp-contract=off (a VMUL, then a VADD), in one instruction
//    instead of two. GCC emits VMLA only when contracting, hence the asm.
//  - VLDM loads several consecutive floats in one instruction, where GCC emits one VLDR each.
// Per block of 4 inputs: x in s4-s7 (one VLDM), then for each row its 4 weights in s8-s11 (one
// VLDM) and 4 VMLAs into the row's accumulator (s0-s3); then single inputs for the rest of `in`.
// 23 instructions per 16 multiply-adds, against 16 per 4 in the compiled loop. Only caller-saved
// registers (s0-s15), so nothing is pushed. Blocks of 12 inputs (s4-s15 and s16-s27) ran 55 per
// 48, 1,380 fewer instructions per 64-64 ELU inference on the M4F, but took 256 B more flash:
// the 22 KB goal of a 64-64 float32 policy (issue 11) decided for the smaller loop.
// Rows are contiguous (weight[out][in]), so a group's last row pointer ends on the next group's
// first row.
// Out of line (noinline): the three layers share one copy of it (~0.2 KB of code, against three
// inlined copies), for two extra instructions per layer.
__attribute__((noinline)) inline void dense_vfp(const real* w, const real* b, int in, int groups, const real* x,
                                                real* y) {
  const real* r1;
  const real* r2;
  const real* r3;
  int n;
  __asm__ __volatile__(
      "0:\n\t"
      "add.w %[r1], %[r0], %[in], lsl #2\n\t"
      "add.w %[r2], %[r1], %[in], lsl #2\n\t"
      "add.w %[r3], %[r2], %[in], lsl #2\n\t"
      "vldmia %[b]!, {s0-s3}\n\t"
      // n counts the inputs left minus the block size: each block loop ends on subs + branch.
      "subs %[n], %[in], #4\n\t"
      "blt 4f\n"
      "3:\n\t"
      "vldmia %[x]!, {s4-s7}\n\t"
      "vldmia %[r0]!, {s8-s11}\n\t"
      "vmla.f32 s0, s8, s4\n\t"
      "vmla.f32 s0, s9, s5\n\t"
      "vmla.f32 s0, s10, s6\n\t"
      "vmla.f32 s0, s11, s7\n\t"
      "vldmia %[r1]!, {s8-s11}\n\t"
      "vmla.f32 s1, s8, s4\n\t"
      "vmla.f32 s1, s9, s5\n\t"
      "vmla.f32 s1, s10, s6\n\t"
      "vmla.f32 s1, s11, s7\n\t"
      "vldmia %[r2]!, {s8-s11}\n\t"
      "vmla.f32 s2, s8, s4\n\t"
      "vmla.f32 s2, s9, s5\n\t"
      "vmla.f32 s2, s10, s6\n\t"
      "vmla.f32 s2, s11, s7\n\t"
      "vldmia %[r3]!, {s8-s11}\n\t"
      "vmla.f32 s3, s8, s4\n\t"
      "vmla.f32 s3, s9, s5\n\t"
      "vmla.f32 s3, s10, s6\n\t"
      "vmla.f32 s3, s11, s7\n\t"
      "subs %[n], %[n], #4\n\t"
      "bge 3b\n"
      "4:\n\t"
      "adds %[n], %[n], #4\n\t"  // inputs left
      "beq 6f\n"
      "5:\n\t"
      "vldmia %[x]!, {s4}\n\t"
      "vldmia %[r0]!, {s8}\n\t"
      "vldmia %[r1]!, {s9}\n\t"
      "vldmia %[r2]!, {s10}\n\t"
      "vldmia %[r3]!, {s11}\n\t"
      "vmla.f32 s0, s8, s4\n\t"
      "vmla.f32 s1, s9, s4\n\t"
      "vmla.f32 s2, s10, s4\n\t"
      "vmla.f32 s3, s11, s4\n\t"
      "subs %[n], %[n], #1\n\t"
      "bne 5b\n"
      "6:\n\t"
      "vstmia %[y]!, {s0-s3}\n\t"
      "sub.w %[x], %[x], %[in], lsl #2\n\t"  // back to x[0]
      "mov %[r0], %[r3]\n\t"                 // the next group's first row
      "subs %[groups], %[groups], #1\n\t"
      "bne 0b\n\t"
      : [r0] "+r"(w), [r1] "=&r"(r1), [r2] "=&r"(r2), [r3] "=&r"(r3), [n] "=&r"(n), [x] "+r"(x), [b] "+r"(b),
        [y] "+r"(y), [groups] "+r"(groups)
      : [in] "r"(in)
      : "s0", "s1", "s2", "s3", "s4", "s5", "s6", "s7", "s8", "s9", "s10", "s11", "cc", "memory");
}
#endif

__attribute__((always_inline)) inline void dense(const real* w, const real* b, int in, int out, const real* x,
                                                 real* y) {
#if defined(KESTREL_MLP_ARM_VFP)
  const int groups = out / 4;
  if (in > 0 && groups > 0) {
    dense_vfp(w, b, in, groups, x, y);
    // The last out % 4 rows (none in a 64-64-4 network): the portable code.
    const int done = 4 * groups;
    if (done < out) dense_portable(w + done * in, b + done, in, out - done, x, y + done);
    return;
  }
#endif
  dense_portable(w, b, in, out, x, y);
}
}  // namespace detail

namespace detail {
// Finite, in a constant expression too (std::isfinite is not constexpr in C++17).
constexpr bool finite_c(real x) {
  return x == x && x <= std::numeric_limits<real>::max() && x >= -std::numeric_limits<real>::max();
}
constexpr bool all_finite_c(const real* v, int n) {
  for (int i = 0; i < n; ++i)
    if (!finite_c(v[i])) return false;
  return true;
}
}  // namespace detail

/// Every number finite, inv_std >= 0, obs_clip > 0, low <= high (of the parts the network has), and
/// a tanh squash where the clamp is left out. invalid_argument otherwise.
/// constexpr: a network generated into flash (python/kestrel/export.py) is checked by a
/// static_assert when it is compiled; weights filled at run time are checked by calling it.
template <int kObs, int kH1, int kH2, int kAct, unsigned kParts>
[[nodiscard]] constexpr Status validate_mlp(const MlpParams<kObs, kH1, kH2, kAct, kParts>& p) {
  using detail::all_finite_c;
  using detail::finite_c;
  using P = MlpParams<kObs, kH1, kH2, kAct, kParts>;
  if (p.activation != Activation::tanh && p.activation != Activation::elu && p.activation != Activation::relu)
    return Status::invalid_argument;
  if (p.output_squash != Squash::none && p.output_squash != Squash::tanh) return Status::invalid_argument;
  if constexpr (P::has_obs_norm) {
    if (!all_finite_c(p.obs_mean, kObs) || !all_finite_c(p.obs_inv_std, kObs) || !(p.obs_clip > 0) ||
        !finite_c(p.obs_clip))
      return Status::invalid_argument;
    for (int i = 0; i < kObs; ++i)
      if (p.obs_inv_std[i] < 0) return Status::invalid_argument;
  }
  for (int o = 0; o < kH1; ++o)
    if (!all_finite_c(p.hidden1.weight[o], kObs)) return Status::invalid_argument;
  for (int o = 0; o < kH2; ++o)
    if (!all_finite_c(p.hidden2.weight[o], kH1)) return Status::invalid_argument;
  for (int o = 0; o < kAct; ++o)
    if (!all_finite_c(p.output.weight[o], kH2)) return Status::invalid_argument;
  if (!all_finite_c(p.hidden1.bias, kH1) || !all_finite_c(p.hidden2.bias, kH2) || !all_finite_c(p.output.bias, kAct))
    return Status::invalid_argument;
  for (int i = 0; i < kAct; ++i) {
    if (!finite_c(p.action_scale[i]) || !finite_c(p.action_offset[i])) return Status::invalid_argument;
    if constexpr (P::has_action_clamp) {
      if (!finite_c(p.action_low[i]) || !finite_c(p.action_high[i]) || !(p.action_low[i] <= p.action_high[i]))
        return Status::invalid_argument;
    } else if (p.output_squash != Squash::tanh) {
      return Status::invalid_argument;  // an unsquashed output needs its clamp: it is unbounded
    }
  }
  return Status::ok;
}

/// The largest |action[i]| the network can output: |offset| + |scale| x the bound of the squashed,
/// clamped output (its clamp's bounds, or 1 for tanh; unbounded, +inf, without either). constexpr:
/// a firmware that clips the action to a task's range can prove at compile time that the clip
/// cannot act (platform/firmware/policy_loop.cpp).
template <int kObs, int kH1, int kH2, int kAct, unsigned kParts>
[[nodiscard]] constexpr real max_abs_action(const MlpParams<kObs, kH1, kH2, kAct, kParts>& p, int i) {
  using P = MlpParams<kObs, kH1, kH2, kAct, kParts>;
  real bound = std::numeric_limits<real>::infinity();
  if (p.output_squash == Squash::tanh) bound = 1;
  if constexpr (P::has_action_clamp) {
    const real lo = p.action_low[i] < 0 ? -p.action_low[i] : p.action_low[i];
    const real hi = p.action_high[i] < 0 ? -p.action_high[i] : p.action_high[i];
    const real m = lo > hi ? lo : hi;
    if (m < bound) bound = m;
  }
  const real s = p.action_scale[i] < 0 ? -p.action_scale[i] : p.action_scale[i];
  const real o = p.action_offset[i] < 0 ? -p.action_offset[i] : p.action_offset[i];
  return o + s * bound;
}
/// Every action within [-bound, bound] whatever the observation (max_abs_action).
template <int kObs, int kH1, int kH2, int kAct, unsigned kParts>
[[nodiscard]] constexpr bool actions_within(const MlpParams<kObs, kH1, kH2, kAct, kParts>& p, real bound) {
  for (int i = 0; i < kAct; ++i)
    if (!(max_abs_action(p, i) <= bound)) return false;
  return true;
}

/// A network of any size as plain pointers and dimensions: what bindings and tools evaluate (the
/// Python package's parity check), and what mlp_forward below runs with compile-time sizes, so
/// both go through the same arithmetic in the same order.
struct MlpView {
  int obs_dim, h1, h2, action_dim;
  Activation activation;
  const real *obs_mean, *obs_inv_std;  // both null: no normalisation (kMlpObsNorm left out)
  real obs_clip;
  const real *w1, *b1, *w2, *b2, *w3, *b3;  // row-major weight[out][in]
  const real *action_low, *action_high, *action_scale, *action_offset;  // low, high null: no clamp
  Squash output_squash;
};

template <int kObs, int kH1, int kH2, int kAct, unsigned kParts>
inline MlpView view_of(const MlpParams<kObs, kH1, kH2, kAct, kParts>& p) {
  using P = MlpParams<kObs, kH1, kH2, kAct, kParts>;
  const real* mean = nullptr;
  const real* inv_std = nullptr;
  real clip = 0;
  const real* low = nullptr;
  const real* high = nullptr;
  if constexpr (P::has_obs_norm) {
    mean = p.obs_mean;
    inv_std = p.obs_inv_std;
    clip = p.obs_clip;
  }
  if constexpr (P::has_action_clamp) {
    low = p.action_low;
    high = p.action_high;
  }
  return MlpView{kObs, kH1, kH2, kAct, p.activation, mean, inv_std, clip,
                 &p.hidden1.weight[0][0], p.hidden1.bias, &p.hidden2.weight[0][0], p.hidden2.bias,
                 &p.output.weight[0][0], p.output.bias, low, high, p.action_scale,
                 p.action_offset, p.output_squash};
}

/// One inference over a view; `scratch` holds obs_dim + h1 + h2 + action_dim reals. A non-finite
/// observation returns non_finite_input and leaves `action` untouched (the caller holds its last
/// command, as every controller does); so does a non-finite result (only reachable with weights
/// that validate_mlp refuses). No heap.
__attribute__((always_inline)) inline Status mlp_forward_view(const MlpView& v, const real* obs, real* action,
                                                              real* scratch) {
  real* xn = scratch;
  real* a1 = xn + v.obs_dim;
  real* a2 = a1 + v.h1;
  real* y = a2 + v.h2;
  const real* x = obs;
  for (int i = 0; i < v.obs_dim; ++i)
    if (!is_finite(obs[i])) return Status::non_finite_input;
  if (v.obs_mean != nullptr) {
    for (int i = 0; i < v.obs_dim; ++i)
      xn[i] = clamp((obs[i] - v.obs_mean[i]) * v.obs_inv_std[i], -v.obs_clip, v.obs_clip);
    x = xn;
  }
  detail::dense(v.w1, v.b1, v.obs_dim, v.h1, x, a1);
  detail::activate_all(v.activation, a1, v.h1);
  detail::dense(v.w2, v.b2, v.h1, v.h2, a1, a2);
  detail::activate_all(v.activation, a2, v.h2);
  detail::dense(v.w3, v.b3, v.h2, v.action_dim, a2, y);
  if (!all_finite(y, v.action_dim)) return Status::non_finite_input;
  if (v.output_squash == Squash::tanh) detail::squash_tanh_all(v.activation, y, v.action_dim);
  if (v.action_low != nullptr)
    for (int i = 0; i < v.action_dim; ++i) y[i] = clamp(y[i], v.action_low[i], v.action_high[i]);
  for (int i = 0; i < v.action_dim; ++i) action[i] = v.action_offset[i] + v.action_scale[i] * y[i];
  return Status::ok;
}

/// One inference with compile-time sizes (the loops' bounds are constants after inlining):
/// obs (kObs values) -> action (kAct values); statuses as mlp_forward_view. The activations live
/// on the stack (kObs + kH1 + kH2 + kAct reals).
// Inlined into its caller: with a constexpr network (the exported header) the activation and
// squash kinds are constants there, so only their code is linked.
template <int kObs, int kH1, int kH2, int kAct, unsigned kParts>
[[nodiscard]] __attribute__((always_inline)) inline Status mlp_forward(const MlpParams<kObs, kH1, kH2, kAct, kParts>& p,
                                                                       const real* obs, real* action) {
  real scratch[kObs + kH1 + kH2 + kAct];
  return mlp_forward_view(view_of(p), obs, action, scratch);
}

}  // namespace kestrel::policy
