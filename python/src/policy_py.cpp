// kestrel._core.mlp_forward: the core's policy network (policy/mlp.hpp, mlp_forward_view: the
// same arithmetic the firmware's compile-time network runs) over a batch of observations, for the
// export's parity check against PyTorch.
#include <cstdint>
#include <string>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include "kestrel/policy/mlp.hpp"

namespace nb = nanobind;
using namespace nb::literals;

namespace {

using Vec = nb::ndarray<const float, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Mat = nb::ndarray<const float, nb::ndim<2>, nb::c_contig, nb::device::cpu>;

void need(bool ok, const std::string& what) {
  if (!ok) throw nb::value_error(what.c_str());
}

}  // namespace

void bind_policy(nb::module_& m) {
  m.def(
      "mlp_forward",
      [](int activation, Mat w1, Vec b1, Mat w2, Vec b2, Mat w3, Vec b3, Vec obs_mean, Vec obs_inv_std, float obs_clip,
         Vec action_low, Vec action_high, Vec action_scale, Vec action_offset, Mat obs, int squash) {
        const int n_obs = static_cast<int>(w1.shape(1)), h1 = static_cast<int>(w1.shape(0));
        const int h2 = static_cast<int>(w2.shape(0)), n_act = static_cast<int>(w3.shape(0));
        need(activation >= 0 && activation <= 2, "activation: expected 0 (tanh), 1 (elu) or 2 (relu)");
        need(squash == 0 || squash == 1, "squash: expected 0 (none) or 1 (tanh)");
        need(static_cast<int>(w2.shape(1)) == h1 && static_cast<int>(w3.shape(1)) == h2, "w1/w2/w3: shapes do not chain");
        need(static_cast<int>(b1.shape(0)) == h1 && static_cast<int>(b2.shape(0)) == h2 && static_cast<int>(b3.shape(0)) == n_act,
             "b1/b2/b3: expected one bias per layer output");
        need(static_cast<int>(obs_mean.shape(0)) == n_obs && static_cast<int>(obs_inv_std.shape(0)) == n_obs,
             "obs_mean/obs_inv_std: expected obs_dim values");
        for (const Vec* v : {&action_low, &action_high, &action_scale, &action_offset})
          need(static_cast<int>(v->shape(0)) == n_act, "action_low/high/scale/offset: expected action_dim values");
        need(static_cast<int>(obs.shape(1)) == n_obs, "obs: expected shape (N, obs_dim)");
        const kestrel::policy::MlpView v{n_obs, h1, h2, n_act, static_cast<kestrel::policy::Activation>(activation),
                                         obs_mean.data(), obs_inv_std.data(), obs_clip, w1.data(), b1.data(),
                                         w2.data(), b2.data(), w3.data(), b3.data(), action_low.data(),
                                         action_high.data(), action_scale.data(), action_offset.data(),
                                         static_cast<kestrel::policy::Squash>(squash)};
        const std::size_t n = obs.shape(0);
        float* out = new float[n * static_cast<std::size_t>(n_act)];
        float* scratch = new float[static_cast<std::size_t>(n_obs + h1 + h2 + n_act)];
        std::size_t failed = 0;
        for (std::size_t i = 0; i < n; ++i) {
          float* a = out + i * static_cast<std::size_t>(n_act);
          for (int k = 0; k < n_act; ++k) a[k] = 0;
          if (kestrel::policy::mlp_forward_view(v, obs.data() + i * static_cast<std::size_t>(n_obs), a, scratch) !=
              kestrel::Status::ok)
            ++failed;
        }
        delete[] scratch;
        if (failed > 0) {
          delete[] out;
          throw nb::value_error("obs: non-finite observations (the core refuses them)");
        }
        nb::capsule owner(out, [](void* p) noexcept { delete[] static_cast<float*>(p); });
        return nb::ndarray<nb::numpy, float, nb::ndim<2>>(out, {n, static_cast<std::size_t>(n_act)}, owner);
      },
      "activation"_a, "w1"_a, "b1"_a, "w2"_a, "b2"_a, "w3"_a, "b3"_a, "obs_mean"_a, "obs_inv_std"_a, "obs_clip"_a,
      "action_low"_a, "action_high"_a, "action_scale"_a, "action_offset"_a, "obs"_a, "squash"_a = 0,
      "The core's policy network (policy/mlp.hpp) over a batch of observations (N, obs_dim) -> (N, action_dim).");
}
