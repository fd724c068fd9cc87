"""The trained actor as core code: kestrel.export's network, evaluated by the core's MLP
(policy/mlp.hpp through kestrel._core.mlp_forward), agrees with PyTorch's forward pass within
1e-5 relative on 10^4 recorded observations, and the generated C++ header reproduces the float32
weights bit for bit and computes the same actions when compiled."""
import os
import pathlib
import shutil
import subprocess

import numpy as np
import pytest
import torch

import kestrel
from kestrel import export

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def recorded():
    """10,048 observations of the position-setpoint task under random actions, and an SB3 PPO
    actor (64-64 tanh, untrained weights) with VecNormalize statistics of those observations."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    from kestrel.adapters import Sb3VecEnv

    env = kestrel.make_vec("Kestrel-PositionSetpoint-v0", num_envs=64, seed=3, threads=1)
    obs, _ = env.reset(seed=3)
    rng = np.random.default_rng(0)
    rows = [np.array(obs)]
    for _ in range(156):
        a = rng.uniform(-1, 1, size=env.action_space.shape).astype(np.float32)
        obs, *_ = env.step(a)
        rows.append(np.array(obs))
    data = np.concatenate(rows).astype(np.float32)
    torch.manual_seed(0)
    venv = VecNormalize(Sb3VecEnv(kestrel.make_vec("Kestrel-PositionSetpoint-v0", num_envs=4, seed=1, threads=1)),
                        norm_obs=True, norm_reward=False)
    venv.obs_rms.update(data.astype(np.float64))
    model = PPO("MlpPolicy", venv, n_steps=8, batch_size=32, policy_kwargs={"net_arch": [64, 64]}, seed=0, device="cpu")
    return data, model, venv


def test_core_mlp_matches_pytorch_on_recorded_observations(recorded):
    data, model, venv = recorded
    assert data.shape[0] >= 10_000
    spec = export.from_sb3(model, venv)
    assert (spec.obs_dim, spec.hidden, spec.action_dim, spec.activation) == (13, (64, 64), 4, "tanh")
    core = kestrel._core.mlp_forward(**spec.core_arrays(), obs=data)
    # PyTorch: SB3's own deterministic prediction on VecNormalize's normalisation ...
    ref, _ = model.predict(venv.normalize_obs(data.astype(np.float64)), deterministic=True)
    np.testing.assert_allclose(core, ref, rtol=1e-5, atol=1e-5)
    # ... and the exported function as a torch module.
    with torch.no_grad():
        ref2 = spec.torch_module()(torch.from_numpy(data)).numpy()
    np.testing.assert_allclose(core, ref2, rtol=1e-5, atol=1e-5)
    # Not vacuous: the actions vary and are not all clipped.
    assert core.std(axis=0).min() > 1e-3
    assert np.mean(np.abs(core) < 0.999) > 0.5


def test_core_mlp_refuses_bad_input(recorded):
    data, model, venv = recorded
    spec = export.from_sb3(model, venv)
    bad = data[:4].copy()
    bad[2, 5] = np.nan
    with pytest.raises(ValueError, match="obs"):
        kestrel._core.mlp_forward(**spec.core_arrays(), obs=bad)
    with pytest.raises(ValueError, match="obs"):
        kestrel._core.mlp_forward(**spec.core_arrays(), obs=data[:4, :12].copy())


@pytest.mark.skipif(shutil.which("g++") is None, reason="needs g++")
@pytest.mark.parametrize("kind", ["sb3_tanh_vecnormalize", "rsl_rl_elu_squash_no_normaliser"])
def test_generated_header_is_exact_and_computes_the_same_actions(recorded, tmp_path, kind):
    data, model, venv = recorded
    lean = kind.startswith("rsl_rl")
    spec = _rsl_rl_like_spec(obs_normalizer=False) if lean else export.from_sb3(model, venv)
    header = export.write_header(spec, str(tmp_path / "policy_weights.hpp"), name="kPolicy")
    text = pathlib.Path(header).read_text()
    # The parts a network does without are left out of its type (policy/mlp.hpp MlpParts): an
    # rsl_rl actor trained without a normaliser, squashed by tanh into [-1, 1], has neither the
    # normalisation nor the action clamp; SB3's with VecNormalize keeps both.
    assert ("MlpParams<13, 64, 64, 4, 0u>" in text) == lean
    assert ("MlpParams<13, 64, 64, 4>" in text) == (not lean)
    # Every weight is written exactly (hex-float literals round-trip float32 bit for bit).
    w1_text = text.split(f"kestrel::policy::Activation::{spec.activation},")[1]
    first = float.fromhex(w1_text.split("{{{")[1].split(",")[0])
    assert np.float32(first) == spec.weights[0][0, 0]
    # Compiled into a program, the header gives the binding's bits.
    n = 64
    np.savetxt(tmp_path / "obs.txt", data[:n].view(np.uint32), fmt="%u")
    prog = tmp_path / "run.cpp"
    prog.write_text('#include <cstdio>\n#include <cstdint>\n#include <cstring>\n#include "policy_weights.hpp"\n'
                    'int main() { using namespace kestrel::policy::generated; static_assert(kPolicy.obs_dim == 13);\n'
                    '  for (int r = 0; r < %d; ++r) { float o[13]; for (int i = 0; i < 13; ++i) { unsigned u;\n'
                    '    if (std::scanf("%%u", &u) != 1) return 2; std::memcpy(&o[i], &u, 4); }\n'
                    '    float a[4]; if (kestrel::policy::mlp_forward(kPolicy, o, a) != kestrel::Status::ok) return 3;\n'
                    '    for (float v : a) { unsigned u; std::memcpy(&u, &v, 4); std::printf("%%u\\n", u); } } }\n' % n)
    exe = tmp_path / "run"
    subprocess.run(["g++", "-std=c++17", "-O2", "-ffp-contract=off", "-I", str(tmp_path), "-I", str(ROOT / "policy/include"),
                    "-I", str(ROOT / "kernel/include"), "-isystem", "/usr/include/eigen3", str(prog),
                    str(ROOT / "kernel/src/status.cpp"), "-o", str(exe)], check=True)
    out = subprocess.run([str(exe)], stdin=open(tmp_path / "obs.txt"), capture_output=True, text=True, check=True).stdout
    got = np.array([int(x) for x in out.split()], dtype=np.uint32).view(np.float32).reshape(n, 4)
    want = kestrel._core.mlp_forward(**spec.core_arrays(), obs=data[:n])
    assert np.array_equal(got.view(np.uint32), want.view(np.uint32))


def _rsl_rl_like_spec(seed=0, obs_normalizer=True):
    """An rsl-rl-lib MLPModel state dict (13-64-64-4, ELU) with an observation normaliser, exported
    as trained with squash=tanh and action_scale [2, 2, 2, 1] (kestrel train's position-setpoint defaults)."""
    rng = np.random.default_rng(seed)
    sd = {"mlp.0.weight": rng.normal(0, 0.4, (64, 13)), "mlp.0.bias": rng.normal(0, 0.1, 64),
          "mlp.2.weight": rng.normal(0, 0.15, (64, 64)), "mlp.2.bias": rng.normal(0, 0.1, 64),
          "mlp.4.weight": rng.normal(0, 0.15, (4, 64)), "mlp.4.bias": rng.normal(0, 0.1, 4),
          "obs_normalizer._mean": rng.normal(0, 1, (1, 13)), "obs_normalizer._std": rng.uniform(0.5, 3, (1, 13))}
    sd = {k: torch.from_numpy(v.astype(np.float32)) for k, v in sd.items()}
    return export.from_rsl_rl(sd, -1, 1, activation="elu", squash="tanh", action_scale=[2, 2, 2, 1],
                              obs_normalizer=obs_normalizer)


@pytest.mark.parametrize("kind", ["sb3_tanh_vecnormalize", "rsl_rl_elu_squash"])
def test_onnx_export_checks_and_matches_torch_with_the_reference_evaluator(recorded, tmp_path, kind):
    import onnx

    data, model, venv = recorded
    spec = export.from_sb3(model, venv) if kind.startswith("sb3") else _rsl_rl_like_spec()
    path = export.export_onnx(spec, str(tmp_path / "policy.onnx"))
    m = onnx.load(path)
    onnx.checker.check_model(m, full_check=True)  # also infers and checks every shape
    assert [i.name for i in m.graph.input] == ["obs"] and [o.name for o in m.graph.output] == ["action"]
    # 500 recorded observations through onnx's own numpy evaluator (no onnxruntime), batch dynamic.
    obs = data[::20][:500]
    assert obs.shape == (500, 13)
    got = export.onnx_forward(path, obs)
    with torch.no_grad():
        want = spec.torch_module()(torch.from_numpy(obs)).numpy()
    assert got.shape == (500, 4) and got.dtype == np.float32
    # Within 1e-5 relative to each action's size (elementwise relative where it is not near 0).
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-5 * float(np.abs(want).max()))
    np.testing.assert_allclose(export.onnx_forward(path, obs[:3]), want[:3], rtol=1e-5, atol=1e-6)  # another batch size
    # And the core's MLP computes the same function (what the firmware flies).
    core = kestrel._core.mlp_forward(**spec.core_arrays(), obs=obs)
    np.testing.assert_allclose(got, core, rtol=1e-5, atol=1e-5 * float(np.abs(want).max()))
    # Not vacuous: actions vary, and the squashed one is not saturated.
    assert want.std(axis=0).min() > 1e-3
    if kind.startswith("rsl_rl"):
        assert np.all(np.abs(got) <= np.array([2, 2, 2, 1]) + 1e-6) and np.mean(np.abs(got / [2, 2, 2, 1]) < 0.99) > 0.5
