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
// Weights live wherever the caller puts them: a `const MlpParams` generated into flash by
// python/kestrel/export.py (hex-float literals), or static storage filled at set-up.
#pragma once

#include <cstddef>
#include <cstdint>

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

template <int kObs, int kH1, int kH2, int kAct>
struct MlpParams {
  static_assert(kObs > 0 && kH1 > 0 && kH2 > 0 && kAct > 0, "layer sizes must be positive");
  static constexpr int obs_dim = kObs;
  static constexpr int action_dim = kAct;
  Activation activation;
  // Observation normalisation as in training: x = clamp((obs - mean) * inv_std, -clip, clip)
  // (SB3 VecNormalize, rsl_rl EmpiricalNormalization; identity: mean 0, inv_std 1, clip large).
  real obs_mean[kObs];
  real obs_inv_std[kObs];
  real obs_clip;
  DenseLayer<kObs, kH1> hidden1;
  DenseLayer<kH1, kH2> hidden2;
  DenseLayer<kH2, kAct> output;  // the Gaussian's mean (deterministic action)
  // Action mapping: action = offset + scale * clamp(squash(y), low, high) (the learner's squash or
  // clip to the action space, then the task's scaling into controller units).
  real action_low[kAct];
  real action_high[kAct];
  real action_scale[kAct];
  real action_offset[kAct];
  Squash output_squash;  // last, so that a zero-initialised (static) network has none
};

namespace detail {
inline real activate(Activation a, real x) {
  switch (a) {
    case Activation::tanh: return tanh_det(x);
    case Activation::elu: return x > 0 ? x : exp_det(x) - 1;
    case Activation::relu: return x > 0 ? x : 0;
  }
  return x;
}
// y = b + W x, each output summed in input order (-ffp-contract=off: no fused multiply-add on any
// target). Four outputs at a time share each load of x[i] (a 64-64 network is ~5,200
// multiply-adds: on the Cortex-M4F the loads, not the FPU, set the cost); the sums and their order
// are those of the plain loop, so the bits are too.
__attribute__((always_inline)) inline void dense(const real* w, const real* b, int in, int out, const real* x,
                                                 real* y) {
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
}  // namespace detail

/// Every number finite, inv_std >= 0, obs_clip > 0, low <= high. invalid_argument otherwise.
template <int kObs, int kH1, int kH2, int kAct>
[[nodiscard]] Status validate_mlp(const MlpParams<kObs, kH1, kH2, kAct>& p) {
  if (p.activation != Activation::tanh && p.activation != Activation::elu && p.activation != Activation::relu)
    return Status::invalid_argument;
  if (p.output_squash != Squash::none && p.output_squash != Squash::tanh) return Status::invalid_argument;
  if (!all_finite(p.obs_mean, kObs) || !all_finite(p.obs_inv_std, kObs) || !(p.obs_clip > 0) || !is_finite(p.obs_clip))
    return Status::invalid_argument;
  for (int i = 0; i < kObs; ++i)
    if (p.obs_inv_std[i] < 0) return Status::invalid_argument;
  if (!all_finite(&p.hidden1.weight[0][0], kObs * kH1) || !all_finite(p.hidden1.bias, kH1) ||
      !all_finite(&p.hidden2.weight[0][0], kH1 * kH2) || !all_finite(p.hidden2.bias, kH2) ||
      !all_finite(&p.output.weight[0][0], kH2 * kAct) || !all_finite(p.output.bias, kAct))
    return Status::invalid_argument;
  for (int i = 0; i < kAct; ++i)
    if (!is_finite(p.action_low[i]) || !is_finite(p.action_high[i]) || !(p.action_low[i] <= p.action_high[i]) ||
        !is_finite(p.action_scale[i]) || !is_finite(p.action_offset[i]))
      return Status::invalid_argument;
  return Status::ok;
}

/// A network of any size as plain pointers and dimensions: what bindings and tools evaluate (the
/// Python package's parity check), and what mlp_forward below runs with compile-time sizes, so
/// both go through the same arithmetic in the same order.
struct MlpView {
  int obs_dim, h1, h2, action_dim;
  Activation activation;
  const real *obs_mean, *obs_inv_std;
  real obs_clip;
  const real *w1, *b1, *w2, *b2, *w3, *b3;  // row-major weight[out][in]
  const real *action_low, *action_high, *action_scale, *action_offset;
  Squash output_squash;
};

template <int kObs, int kH1, int kH2, int kAct>
inline MlpView view_of(const MlpParams<kObs, kH1, kH2, kAct>& p) {
  return MlpView{kObs, kH1, kH2, kAct, p.activation, p.obs_mean, p.obs_inv_std, p.obs_clip,
                 &p.hidden1.weight[0][0], p.hidden1.bias, &p.hidden2.weight[0][0], p.hidden2.bias,
                 &p.output.weight[0][0], p.output.bias, p.action_low, p.action_high, p.action_scale,
                 p.action_offset, p.output_squash};
}

/// One inference over a view; `scratch` holds obs_dim + h1 + h2 + action_dim reals. A non-finite
/// observation returns non_finite_input and leaves `action` untouched (the caller holds its last
/// command, as every controller does); so does a non-finite result (only reachable with weights
/// that validate_mlp refuses). No heap.
__attribute__((always_inline)) inline Status mlp_forward_view(const MlpView& v, const real* obs, real* action,
                                                              real* scratch) {
  real* x = scratch;
  real* a1 = x + v.obs_dim;
  real* a2 = a1 + v.h1;
  real* y = a2 + v.h2;
  for (int i = 0; i < v.obs_dim; ++i) {
    if (!is_finite(obs[i])) return Status::non_finite_input;
    x[i] = clamp((obs[i] - v.obs_mean[i]) * v.obs_inv_std[i], -v.obs_clip, v.obs_clip);
  }
  detail::dense(v.w1, v.b1, v.obs_dim, v.h1, x, a1);
  for (int i = 0; i < v.h1; ++i) a1[i] = detail::activate(v.activation, a1[i]);
  detail::dense(v.w2, v.b2, v.h1, v.h2, a1, a2);
  for (int i = 0; i < v.h2; ++i) a2[i] = detail::activate(v.activation, a2[i]);
  detail::dense(v.w3, v.b3, v.h2, v.action_dim, a2, y);
  if (!all_finite(y, v.action_dim)) return Status::non_finite_input;
  for (int i = 0; i < v.action_dim; ++i) {
    const real u = v.output_squash == Squash::tanh ? tanh_det(y[i]) : y[i];
    action[i] = v.action_offset[i] + v.action_scale[i] * clamp(u, v.action_low[i], v.action_high[i]);
  }
  return Status::ok;
}

/// One inference with compile-time sizes (the loops' bounds are constants after inlining):
/// obs (kObs values) -> action (kAct values); statuses as mlp_forward_view. The activations live
/// on the stack (kObs + kH1 + kH2 + kAct reals).
template <int kObs, int kH1, int kH2, int kAct>
[[nodiscard]] Status mlp_forward(const MlpParams<kObs, kH1, kH2, kAct>& p, const real* obs, real* action) {
  real scratch[kObs + kH1 + kH2 + kAct];
  return mlp_forward_view(view_of(p), obs, action, scratch);
}

}  // namespace kestrel::policy
