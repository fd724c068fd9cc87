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
#include "test_scratch.hpp"
// The trained Go2 walking policy (issue 13) and observations recorded with it walking, with the
// actions the host's core gave (bench/python/export_go2_policy.py).
#include "../../platform/firmware/go2_flat_policy.hpp"
#include "go2_flat_cases.hpp"

using namespace kestrel;
namespace pl = kestrel::policy;

namespace {

using TestMlp = pl::MlpParams<13, 64, 64, 4>;

// A network with weights of the scale PyTorch's default initialisation gives (U(+-1/sqrt(fan_in))).
void random_mlp(TestMlp& p, pl::Activation a, std::uint32_t seed) {
  RngStream r(seed, 0, kPurposeUser);
  p.activation = a;
  p.output_squash = pl::Squash::none;  // a test that wants the squash sets it after
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

// 4.7 K floats: too big for an MCU test's stack. Each test takes the network it uses from the
// shared test scratch (test_scratch.hpp; the netduinoplus2 test image is short of RAM) and fills it.
using FullMlp = pl::MlpParams<13, 16, 16, 4>;
using LeanMlp = pl::MlpParams<13, 16, 16, 4, 0u>;  // no normalisation, no action clamp
struct FullAndLean {
  FullMlp full;
  LeanMlp lean;
};

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
  TestMlp& mlp = ktest::scratch<TestMlp>();
  for (int a = 0; a < 4; ++a) {
    // tanh, ELU, ReLU; then ELU with a tanh-squashed output (rsl_rl with squash, scaled actions).
    const pl::Activation act = static_cast<pl::Activation>(a < 3 ? a : 1);
    random_mlp(mlp, act, 11);
    mlp.output_squash = a == 3 ? pl::Squash::tanh : pl::Squash::none;
    KEXPECT_TRUE(pl::validate_mlp(mlp) == Status::ok);
    RngStream r(12, 0, kPurposeUser);
    double worst = 0;
    for (int n = 0; n < 500; ++n) {
      real obs[13], action[4] = {};
      for (int i = 0; i < 13; ++i) obs[i] = r.uniform(-3, 3);
      Status st = Status::invalid_argument;
      KEXPECT_NO_HEAP(st = pl::mlp_forward(mlp, obs, action));
      KEXPECT_TRUE(st == Status::ok);
      double ref[4];
      reference_forward(mlp, obs, ref);
      for (int o = 0; o < 4; ++o) {
        // numpy.allclose's measure: |a - ref| <= atol + rtol |ref| with rtol = atol = 1e-5; `worst`
        // is the largest |a - ref| - rtol |ref| (float accumulation over 64 terms gives ~1e-6).
        const double err = std::fabs(static_cast<double>(action[o]) - ref[o]) - 1e-5 * std::fabs(ref[o]);
        if (err > worst) worst = err;
      }
    }
    KEXPECT_LT(worst, 1e-5);
  }
}

KTEST(PolicyMlp, RefusesNonFiniteInputsAndWeights) {
  TestMlp& mlp = ktest::scratch<TestMlp>();
  random_mlp(mlp, pl::Activation::tanh, 3);
  real obs[13] = {}, action[4] = {9, 9, 9, 9};
  obs[5] = std::numeric_limits<real>::quiet_NaN();
  KEXPECT_TRUE(pl::mlp_forward(mlp, obs, action) == Status::non_finite_input);
  KEXPECT_TRUE(action[0] == 9 && action[3] == 9);  // untouched: the caller holds its last command
  obs[5] = std::numeric_limits<real>::infinity();
  KEXPECT_TRUE(pl::mlp_forward(mlp, obs, action) == Status::non_finite_input);
  obs[5] = 1e30_r;  // huge but finite: clipped by the normalisation, finite action
  KEXPECT_TRUE(pl::mlp_forward(mlp, obs, action) == Status::ok);
  KEXPECT_TRUE(all_finite(action, 4));
  mlp.hidden2.weight[3][7] = std::numeric_limits<real>::quiet_NaN();
  KEXPECT_TRUE(pl::validate_mlp(mlp) == Status::invalid_argument);
  random_mlp(mlp, pl::Activation::tanh, 3);
  mlp.action_low[1] = 2;  // low > high
  KEXPECT_TRUE(pl::validate_mlp(mlp) == Status::invalid_argument);
  random_mlp(mlp, pl::Activation::tanh, 3);
  mlp.obs_clip = 0;
  KEXPECT_TRUE(pl::validate_mlp(mlp) == Status::invalid_argument);
  random_mlp(mlp, pl::Activation::tanh, 3);
  mlp.activation = static_cast<pl::Activation>(7);
  KEXPECT_TRUE(pl::validate_mlp(mlp) == Status::invalid_argument);
}

#if !(defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE)
// tanh_f32 and exp_f32 as they were before the Cortex-M4F speed-up (sign tests around the
// polynomial, floor with a sign test): the current ones must give the same bits. Checked offline
// over all 2^32 floats on the host; here on an evenly spread 65,536 of them, on every target.
namespace {
namespace former {
float exp_f32(float x) {
  if (!(x == x)) return x;
  if (x > 88.72283905206835f) return std::numeric_limits<float>::infinity();
  if (x < -103.972077083991796f) return 0.0f;
  float zf = 1.44269504088896341f * x + 0.5f;
  int n = static_cast<int>(zf);
  if (zf < 0 && static_cast<float>(n) != zf) --n;
  const float fn = static_cast<float>(n);
  float r = x - fn * 0.693359375f;
  r = r - fn * -2.12194440e-4f;
  const float z = r * r;
  float y = ((((1.9875691500e-4f * r + 1.3981999507e-3f) * r + 8.3334519073e-3f) * r + 4.1665795894e-2f) * r +
             1.6666665459e-1f) * r + 5.0000001201e-1f;
  y = y * z + r + 1.0f;
  auto pow2 = [](int e) {
    const std::uint32_t u = static_cast<std::uint32_t>(e + 127) << 23;
    float f;
    std::memcpy(&f, &u, sizeof f);
    return f;
  };
  if (n > 127) return y * pow2(127) * pow2(n - 127);
  if (n < -126) return y * pow2(-126) * pow2(n + 126 < -126 ? -126 : n + 126);
  return y * pow2(n);
}
float tanh_f32(float x) {
  const bool neg = x < 0;
  const float ax = neg ? -x : x;
  float t;
  if (ax > 0.625f) {
    if (ax > 9.01091334f) return neg ? -1.0f : 1.0f;
    const float e = exp_f32(2 * ax);
    t = 1.0f - 2.0f / (e + 1.0f);
  } else {
    if (!(ax == ax)) return x;
    const float z = ax * ax;
    t = ((((-5.70498872745e-3f * z + 2.06390887954e-2f) * z - 5.37397155531e-2f) * z + 1.33314422036e-1f) * z -
         3.33332819422e-1f) * z * ax + ax;
  }
  return neg ? -t : t;
}
std::uint32_t bits(float f) {
  std::uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return u;
}
}  // namespace former
}  // namespace

KTEST(PolicyMath, ExpAndTanhSameBitsAsTheFormerForm) {
  int bad_exp = 0, bad_tanh = 0;
  std::uint32_t u = 0;
  for (int k = 0; k < 65536; ++k, u += 65537u) {
    float x;
    std::memcpy(&x, &u, sizeof x);
    bad_exp += former::bits(kestrel::detail::exp_f32(x)) != former::bits(former::exp_f32(x));
    bad_tanh += former::bits(kestrel::detail::tanh_f32(x)) != former::bits(former::tanh_f32(x));
  }
  const float specials[] = {0.0f, -0.0f, 0.625f, -0.625f, 0.62500006f, -0.62500006f, 9.01091334f, -9.01091334f,
                            88.72283905206835f, -103.972077083991796f, -87.5f, 1e-45f, -1e-45f,
                            std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                            std::numeric_limits<float>::quiet_NaN()};
  for (float x : specials) {
    bad_exp += former::bits(kestrel::detail::exp_f32(x)) != former::bits(former::exp_f32(x));
    bad_tanh += former::bits(kestrel::detail::tanh_f32(x)) != former::bits(former::tanh_f32(x));
  }
  KEXPECT_EQ(bad_exp, 0);
  KEXPECT_EQ(bad_tanh, 0);
}
#endif

KTEST(PolicyMlp, LayerLoopsSameBitsAsThePlainLoops) {
  // detail::dense (on the Cortex-M4F/M7: VFP assembly in blocks of 12, 4 and 1 inputs, 4 rows at a
  // time) against y = b + w x summed in input order, and activate_all against activate, bit for
  // bit, for sizes that reach every block and remainder path.
  static real w[65 * 9], b[9], x[65], y[9 + 1];
  RngStream r(31, 0, kPurposeUser);
  const int ins[] = {1, 2, 3, 4, 5, 7, 8, 11, 12, 13, 15, 16, 17, 23, 24, 25, 28, 64, 65};
  int bad = 0;
  for (int in : ins) {
    for (int out = 1; out <= 9; ++out) {
      for (int i = 0; i < in * out; ++i) w[i] = r.uniform(-1, 1);
      for (int o = 0; o < out; ++o) b[o] = r.uniform(-1, 1);
      for (int i = 0; i < in; ++i) x[i] = r.uniform(-3, 3);
      y[out] = 12345;  // not written
      pl::detail::dense(w, b, in, out, x, y);
      for (int o = 0; o < out; ++o) {
        real acc = b[o];
        for (int i = 0; i < in; ++i) acc += w[o * in + i] * x[i];
        bad += std::memcmp(&acc, &y[o], sizeof acc) != 0;
      }
      bad += y[out] != 12345;
    }
  }
  KEXPECT_EQ(bad, 0);
  // Activations over a spread of values and the special ones.
  int bad_act = 0;
  static real v[64], a[64];
  for (int act = 0; act < 3; ++act) {
    for (int k = 0; k < 4; ++k) {
      for (int i = 0; i < 64; ++i) v[i] = r.uniform(-3, 3) * (k == 0 ? 0.1_r : (k == 1 ? 1 : 40));
      if (k == 3) {
        v[0] = 0;
        v[1] = -0.0_r;
        v[2] = std::numeric_limits<real>::quiet_NaN();
        v[3] = std::numeric_limits<real>::infinity();
        v[4] = -std::numeric_limits<real>::infinity();
        v[5] = -200;
        v[6] = 0.625_r;
        v[7] = -0.625_r;
      }
      for (int i = 0; i < 64; ++i) a[i] = v[i];
      pl::detail::activate_all(static_cast<pl::Activation>(act), a, 64);
      for (int i = 0; i < 64; ++i) {
        const real e = pl::detail::activate(static_cast<pl::Activation>(act), v[i]);
        bad_act += std::memcmp(&e, &a[i], sizeof e) != 0;
      }
    }
  }
  KEXPECT_EQ(bad_act, 0);
}

KTEST(PolicyMlp, SameBitsOnEveryTarget) {
  TestMlp& mlp = ktest::scratch<TestMlp>();
  // FNV-1a over the bits of 1000 inferences per activation. The constant is the host's; the MCU
  // images run this same test, so a target that rounds differently fails here.
  std::uint64_t h = 1469598103934665603ull;
  for (int a = 0; a < 3; ++a) {
    random_mlp(mlp, static_cast<pl::Activation>(a), 21);
    RngStream r(22, 0, kPurposeUser);
    for (int n = 0; n < 1000; ++n) {
      real obs[13], action[4] = {};
      for (int i = 0; i < 13; ++i) obs[i] = r.uniform(-4, 4);
      if (pl::mlp_forward(mlp, obs, action) != Status::ok) h ^= 0xdead;
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

KTEST(PolicyMlp, TrainedGo2PolicySameBitsOnEveryTarget) {
  // legged_gym's locomotion policy for Go2 (48 observations, 128-64 ELU, 12 joint actions),
  // trained in the simulator (bench/results/python/go2_flat_rsl_rl_push4.*), on 64 observations of it
  // walking: the compiled network must give, on the host and on every emulated MCU, the bits the
  // host's core gave when they were recorded.
  namespace g = kestrel::policy::generated;
  int bad = 0, finite = 0;
  for (int c = 0; c < g::kGo2FlatCases; ++c) {
    real obs[48], action[12] = {};
    for (int i = 0; i < 48; ++i) obs[i] = static_cast<real>(g::kGo2FlatObs[c][i]);
    KEXPECT_EQ(static_cast<int>(pl::mlp_forward(g::kGo2FlatPolicy, obs, action)), static_cast<int>(Status::ok));
    for (int k = 0; k < 12; ++k) {
      finite += std::isfinite(action[k]) ? 1 : 0;
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
      // Double builds: the library's exp; within float rounding of the recorded float actions.
      bad += std::fabs(action[k] - static_cast<real>(g::kGo2FlatActions[c][k])) > 1e-4_r * (1 + std::fabs(action[k]));
#else
      bad += std::memcmp(&action[k], &g::kGo2FlatActions[c][k], sizeof(float)) != 0;
#endif
    }
  }
  KEXPECT_EQ(bad, 0);
  KEXPECT_EQ(finite, 12 * g::kGo2FlatCases);
}

KTEST(PolicyMlp, PartsLeftOutGiveTheSameBitsAsTheirIdentity) {
  // The exporter leaves out an identity normalisation and a clamp a tanh squash cannot reach: the
  // lean network must give the bits of the full one that carries them, and its flash is smaller.
  static_assert(sizeof(LeanMlp) + 26 * sizeof(real) + sizeof(real) + 8 * sizeof(real) - 8 <= sizeof(FullMlp),
                "the parts left out take no room");
  RngStream r(31, 0, kPurposeUser);
  FullAndLean& nets = ktest::scratch<FullAndLean>();
  FullMlp& f = nets.full;
  LeanMlp& g_lean = nets.lean;
  f.activation = pl::Activation::elu;
  f.output_squash = pl::Squash::tanh;
  f.obs_clip = 3.0e38_r;
  for (int i = 0; i < 13; ++i) {
    f.obs_mean[i] = 0;
    f.obs_inv_std[i] = 1;
  }
  const real s1 = 1 / std::sqrt(13.0_r), s2 = 1 / std::sqrt(16.0_r);
  for (int o = 0; o < 16; ++o) {
    for (int i = 0; i < 13; ++i) f.hidden1.weight[o][i] = r.uniform(-s1, s1);
    f.hidden1.bias[o] = r.uniform(-s1, s1);
    for (int i = 0; i < 16; ++i) f.hidden2.weight[o][i] = r.uniform(-s2, s2);
    f.hidden2.bias[o] = r.uniform(-s2, s2);
  }
  for (int o = 0; o < 4; ++o) {
    for (int i = 0; i < 16; ++i) f.output.weight[o][i] = r.uniform(-s2, s2);
    f.output.bias[o] = r.uniform(-s2, s2);
    f.action_low[o] = -1;
    f.action_high[o] = 1;
    f.action_scale[o] = 2;
    f.action_offset[o] = o == 2 ? 0.5_r : 0;
  }
  g_lean.activation = f.activation;
  g_lean.hidden1 = f.hidden1;
  g_lean.hidden2 = f.hidden2;
  g_lean.output = f.output;
  for (int o = 0; o < 4; ++o) {
    g_lean.action_scale[o] = f.action_scale[o];
    g_lean.action_offset[o] = f.action_offset[o];
  }
  g_lean.output_squash = pl::Squash::tanh;
  KEXPECT_TRUE(pl::validate_mlp(f) == Status::ok);
  KEXPECT_TRUE(pl::validate_mlp(g_lean) == Status::ok);
  int differ = 0;
  for (int n = 0; n < 1000; ++n) {
    real obs[13], a_full[4] = {}, a_lean[4] = {};
    for (int i = 0; i < 13; ++i) obs[i] = r.uniform(-40, 40);  // large: the squash saturates too
    KEXPECT_TRUE(pl::mlp_forward(f, obs, a_full) == Status::ok);
    KEXPECT_TRUE(pl::mlp_forward(g_lean, obs, a_lean) == Status::ok);
    differ += std::memcmp(a_full, a_lean, sizeof a_full) != 0;
  }
  KEXPECT_EQ(differ, 0);
  // Non-finite observations are refused without normalisation too, the action untouched.
  real obs[13] = {}, a[4] = {7, 7, 7, 7};
  obs[5] = std::numeric_limits<real>::infinity();
  KEXPECT_TRUE(pl::mlp_forward(g_lean, obs, a) == Status::non_finite_input);
  KEXPECT_TRUE(a[0] == 7 && a[3] == 7);
  // Without a clamp the output must be squashed (else it is unbounded): refused.
  g_lean.output_squash = pl::Squash::none;
  KEXPECT_TRUE(pl::validate_mlp(g_lean) == Status::invalid_argument);
  g_lean.output_squash = pl::Squash::tanh;
  // The bound the firmware's task clip is checked against: |offset| + |scale| (tanh in [-1, 1]).
  KEXPECT_TRUE(pl::max_abs_action(g_lean, 0) == 2 && pl::max_abs_action(g_lean, 2) == 2.5_r);
  KEXPECT_TRUE(pl::actions_within(g_lean, 2.5_r) && !pl::actions_within(g_lean, 2.4_r));
  // With a clamp, the tighter of it and the squash: [-1, 0.5] x 2 + 0 -> 2; unsquashed, the clamp's.
  f.action_low[0] = -1;
  f.action_high[0] = 0.5_r;
  KEXPECT_TRUE(pl::max_abs_action(f, 0) == 2);
  f.output_squash = pl::Squash::none;
  f.action_low[0] = -3;
  KEXPECT_TRUE(pl::max_abs_action(f, 0) == 6);
}
