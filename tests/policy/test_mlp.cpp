// The policy network: deterministic activations against the library, the forward pass against a
// double-precision reference, refusals, no heap, and a frozen hash of 1000 inferences that the
// host and every emulated MCU must reproduce bit for bit (the same test binary runs on both).
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/rng.hpp"
#include "kestrel/policy/mlp.hpp"
#include "ktest.hpp"

using namespace kestrel;
namespace pl = kestrel::policy;

namespace {

using TestMlp = pl::MlpParams<13, 64, 64, 4>;

// A network with weights of the scale PyTorch's default initialisation gives (U(+-1/sqrt(fan_in))).
void random_mlp(TestMlp& p, pl::Activation a, std::uint32_t seed) {
  RngStream r(seed, 0, kPurposeUser);
  p.activation = a;
  for (int i = 0; i < 13; ++i) {
    p.obs_mean[i] = r.uniform(-0.5_r, 0.5_r);
    p.obs_inv_std[i] = r.uniform(0.5_r, 2);
  }
  p.obs_clip = 5;
  const real s1 = 1 / std::sqrt(13.0_r), s2 = 1 / std::sqrt(64.0_r);
  for (int o = 0; o < 64; ++o) {
    for (int i = 0; i < 13; ++i) p.hidden1.weight[o][i] = r.uniform(-s1, s1);
    p.hidden1.bias[o] = r.uniform(-s1, s1);
    for (int i = 0; i < 64; ++i) p.hidden2.weight[o][i] = r.uniform(-s2, s2);
    p.hidden2.bias[o] = r.uniform(-s2, s2);
  }
  for (int o = 0; o < 4; ++o) {
    for (int i = 0; i < 64; ++i) p.output.weight[o][i] = r.uniform(-s2, s2);
    p.output.bias[o] = r.uniform(-s2, s2);
    p.action_low[o] = -1;
    p.action_high[o] = 1;
    p.action_scale[o] = 2;
    p.action_offset[o] = o == 2 ? 0.5_r : 0;
  }
}

double act_ref(pl::Activation a, double x) {
  switch (a) {
    case pl::Activation::tanh: return std::tanh(x);
    case pl::Activation::elu: return x > 0 ? x : std::expm1(x);
    case pl::Activation::relu: return x > 0 ? x : 0;
  }
  return x;
}

void reference_forward(const TestMlp& p, const real* obs, double* y) {
  double x[13], h1[64], h2[64];
  for (int i = 0; i < 13; ++i) {
    double v = (static_cast<double>(obs[i]) - p.obs_mean[i]) * p.obs_inv_std[i];
    x[i] = v < -p.obs_clip ? -p.obs_clip : (v > p.obs_clip ? p.obs_clip : v);
  }
  for (int o = 0; o < 64; ++o) {
    double a = p.hidden1.bias[o];
    for (int i = 0; i < 13; ++i) a += static_cast<double>(p.hidden1.weight[o][i]) * x[i];
    h1[o] = act_ref(p.activation, a);
  }
  for (int o = 0; o < 64; ++o) {
    double a = p.hidden2.bias[o];
    for (int i = 0; i < 64; ++i) a += static_cast<double>(p.hidden2.weight[o][i]) * h1[i];
    h2[o] = act_ref(p.activation, a);
  }
  for (int o = 0; o < 4; ++o) {
    double a = p.output.bias[o];
    for (int i = 0; i < 64; ++i) a += static_cast<double>(p.output.weight[o][i]) * h2[i];
    if (p.output_squash == pl::Squash::tanh) a = std::tanh(a);
    a = a < p.action_low[o] ? p.action_low[o] : (a > p.action_high[o] ? p.action_high[o] : a);
    y[o] = p.action_offset[o] + p.action_scale[o] * a;
  }
}

TestMlp g_mlp;  // static storage, as firmware keeps it (4.7 K floats: too big for an MCU test's stack)

}  // namespace

KTEST(PolicyMath, ExpAndTanhMatchTheLibrary) {
  // 4001 points over the activations' working range: within 2 float ulps relative (exp) and
  // 2e-7 absolute + 2 ulps (tanh); special values exact.
  double worst_exp = 0, worst_tanh = 0;
  for (int k = -2000; k <= 2000; ++k) {
    const real x = static_cast<real>(k) * 0.01_r;
    const double e = std::exp(static_cast<double>(x));
    const double re = std::fabs(static_cast<double>(exp_det(x)) - e) / e;
    if (re > worst_exp) worst_exp = re;
    const double t = std::tanh(static_cast<double>(x));
    const double at = std::fabs(static_cast<double>(tanh_det(x)) - t) / (std::fabs(t) + 1e-30);
    if (std::fabs(t) > 1e-3 && at > worst_tanh) worst_tanh = at;
  }
  KEXPECT_LT(worst_exp, 2.5e-7);
  KEXPECT_LT(worst_tanh, 2.5e-7);
  KEXPECT_TRUE(exp_det(0) == 1);
  KEXPECT_TRUE(tanh_det(0) == 0);
  KEXPECT_TRUE(tanh_det(20) == 1 && tanh_det(-20) == -1);
  KEXPECT_TRUE(exp_det(-200) == 0);
  KEXPECT_TRUE(exp_det(100) > 1e38_r * 1e1_r || !is_finite(exp_det(100)));
  KEXPECT_TRUE(tanh_det(1e-20_r) == 1e-20_r);  // odd polynomial: exact for tiny x
  const real nan = std::numeric_limits<real>::quiet_NaN();
  KEXPECT_FALSE(is_finite(exp_det(nan)));
  KEXPECT_FALSE(is_finite(tanh_det(nan)));
}

KTEST(PolicyMlp, ForwardMatchesDoubleReference) {
  for (int a = 0; a < 4; ++a) {
    // tanh, ELU, ReLU; then ELU with a tanh-squashed output (rsl_rl with squash, scaled actions).
    const pl::Activation act = static_cast<pl::Activation>(a < 3 ? a : 1);
    random_mlp(g_mlp, act, 11);
    g_mlp.output_squash = a == 3 ? pl::Squash::tanh : pl::Squash::none;
    KEXPECT_TRUE(pl::validate_mlp(g_mlp) == Status::ok);
    RngStream r(12, 0, kPurposeUser);
    double worst = 0;
    for (int n = 0; n < 500; ++n) {
      real obs[13], action[4];
      for (int i = 0; i < 13; ++i) obs[i] = r.uniform(-3, 3);
      Status st = Status::invalid_argument;
      KEXPECT_NO_HEAP(st = pl::mlp_forward(g_mlp, obs, action));
      KEXPECT_TRUE(st == Status::ok);
      double ref[4];
      reference_forward(g_mlp, obs, ref);
      for (int o = 0; o < 4; ++o) {
        // numpy.allclose's measure: |a - ref| <= atol + rtol |ref| with rtol = atol = 1e-5; `worst`
        // is the largest |a - ref| - rtol |ref| (float accumulation over 64 terms gives ~1e-6).
        const double err = std::fabs(static_cast<double>(action[o]) - ref[o]) - 1e-5 * std::fabs(ref[o]);
        if (err > worst) worst = err;
      }
    }
    KEXPECT_LT(worst, 1e-5);
  }
  g_mlp.output_squash = pl::Squash::none;
}

KTEST(PolicyMlp, RefusesNonFiniteInputsAndWeights) {
  random_mlp(g_mlp, pl::Activation::tanh, 3);
  real obs[13] = {}, action[4] = {9, 9, 9, 9};
  obs[5] = std::numeric_limits<real>::quiet_NaN();
  KEXPECT_TRUE(pl::mlp_forward(g_mlp, obs, action) == Status::non_finite_input);
  KEXPECT_TRUE(action[0] == 9 && action[3] == 9);  // untouched: the caller holds its last command
  obs[5] = std::numeric_limits<real>::infinity();
  KEXPECT_TRUE(pl::mlp_forward(g_mlp, obs, action) == Status::non_finite_input);
  obs[5] = 1e30_r;  // huge but finite: clipped by the normalisation, finite action
  KEXPECT_TRUE(pl::mlp_forward(g_mlp, obs, action) == Status::ok);
  KEXPECT_TRUE(all_finite(action, 4));
  g_mlp.hidden2.weight[3][7] = std::numeric_limits<real>::quiet_NaN();
  KEXPECT_TRUE(pl::validate_mlp(g_mlp) == Status::invalid_argument);
  random_mlp(g_mlp, pl::Activation::tanh, 3);
  g_mlp.action_low[1] = 2;  // low > high
  KEXPECT_TRUE(pl::validate_mlp(g_mlp) == Status::invalid_argument);
  random_mlp(g_mlp, pl::Activation::tanh, 3);
  g_mlp.obs_clip = 0;
  KEXPECT_TRUE(pl::validate_mlp(g_mlp) == Status::invalid_argument);
  random_mlp(g_mlp, pl::Activation::tanh, 3);
  g_mlp.activation = static_cast<pl::Activation>(7);
  KEXPECT_TRUE(pl::validate_mlp(g_mlp) == Status::invalid_argument);
}

KTEST(PolicyMlp, SameBitsOnEveryTarget) {
  // FNV-1a over the bits of 1000 inferences per activation. The constant is the host's; the MCU
  // images run this same test, so a target that rounds differently fails here.
  std::uint64_t h = 1469598103934665603ull;
  for (int a = 0; a < 3; ++a) {
    random_mlp(g_mlp, static_cast<pl::Activation>(a), 21);
    RngStream r(22, 0, kPurposeUser);
    for (int n = 0; n < 1000; ++n) {
      real obs[13], action[4];
      for (int i = 0; i < 13; ++i) obs[i] = r.uniform(-4, 4);
      if (pl::mlp_forward(g_mlp, obs, action) != Status::ok) h ^= 0xdead;
      unsigned char b[sizeof action];
      std::memcpy(b, action, sizeof action);
      for (unsigned char c : b) {
        h ^= c;
        h *= 1099511628211ull;
      }
    }
  }
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  KEXPECT_NE(h, 0u);  // double builds use the library's exp/tanh: no cross-target claim
#else
  KEXPECT_EQ(h, 20800889262732618ull);
#endif
}
