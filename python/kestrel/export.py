"""Export a trained actor to the core's policy network (policy/mlp.hpp) and to ONNX.

The core evaluates ``MlpParams<obs, h1, h2, act>``: observation normalisation
``clamp((obs - mean) * inv_std, -clip, clip)``, two hidden layers with one activation (tanh, ELU
or ReLU), an output layer (the Gaussian's mean: the deterministic action), then
``offset + scale * clamp(y, low, high)``. :class:`MlpSpec` holds exactly that, in float32, and is
built from a Stable-Baselines3 PPO model (with its VecNormalize) or an rsl_rl runner.

``write_header`` writes a C++ header with every number as a hex-float literal (exact: the header
reproduces the float32 weights bit for bit), for firmware to keep in flash. ``export_onnx`` writes
the same function as an ONNX graph (``obs`` -> ``action``, dynamic batch); ``onnx_forward`` runs it
with onnx's reference evaluator.

    kestrel export --rsl-rl runs/ps/checkpoints/rsl_rl_1720320.pt --squash tanh --action-scale 2,2,2,1 \\
        --low -1 --high 1 --no-obs-normalizer --header policy.hpp --onnx policy.onnx
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

ACTIVATIONS = {"tanh": 0, "elu": 1, "relu": 2}
SQUASH = {"none": 0, "tanh": 1}


@dataclasses.dataclass
class MlpSpec:
    activation: str                 # "tanh", "elu" or "relu"
    weights: list                   # [W1 (h1 x obs), W2 (h2 x h1), W3 (act x h2)] float32
    biases: list                    # [b1, b2, b3]
    obs_mean: np.ndarray
    obs_inv_std: np.ndarray
    obs_clip: float
    action_low: np.ndarray
    action_high: np.ndarray
    action_scale: np.ndarray
    action_offset: np.ndarray
    squash: str = "none"            # "none" or "tanh" (a squashed Gaussian's mean, before the clip)

    def __post_init__(self):
        if self.squash not in SQUASH:
            raise ValueError(f"squash: expected one of {sorted(SQUASH)}, got {self.squash!r}")
        if self.activation not in ACTIVATIONS:
            raise ValueError(f"activation: expected one of {sorted(ACTIVATIONS)}, got {self.activation!r}")
        if len(self.weights) != 3 or len(self.biases) != 3:
            raise ValueError("weights/biases: expected two hidden layers and an output layer (3 each)")
        f32 = lambda a: np.ascontiguousarray(np.asarray(a, dtype=np.float32))
        self.weights = [f32(w) for w in self.weights]
        self.biases = [f32(b) for b in self.biases]
        for name in ("obs_mean", "obs_inv_std", "action_low", "action_high", "action_scale", "action_offset"):
            setattr(self, name, f32(getattr(self, name)))
        w1, w2, w3 = self.weights
        if w2.shape[1] != w1.shape[0] or w3.shape[1] != w2.shape[0]:
            raise ValueError(f"weights: layer shapes do not chain: {[w.shape for w in self.weights]}")
        if self.obs_mean.shape != (self.obs_dim,) or self.obs_inv_std.shape != (self.obs_dim,):
            raise ValueError(f"obs_mean/obs_inv_std: expected shape ({self.obs_dim},)")
        for name in ("action_low", "action_high", "action_scale", "action_offset"):
            if getattr(self, name).shape != (self.action_dim,):
                raise ValueError(f"{name}: expected shape ({self.action_dim},)")

    @property
    def obs_dim(self) -> int:
        return int(self.weights[0].shape[1])

    @property
    def hidden(self) -> tuple:
        return int(self.weights[0].shape[0]), int(self.weights[1].shape[0])

    @property
    def action_dim(self) -> int:
        return int(self.weights[2].shape[0])

    def core_arrays(self) -> dict:
        """The arrays kestrel._core.mlp_forward takes (float32, C order)."""
        return dict(activation=ACTIVATIONS[self.activation], w1=self.weights[0], b1=self.biases[0],
                    w2=self.weights[1], b2=self.biases[1], w3=self.weights[2], b3=self.biases[2],
                    obs_mean=self.obs_mean, obs_inv_std=self.obs_inv_std, obs_clip=float(self.obs_clip),
                    action_low=self.action_low, action_high=self.action_high,
                    action_scale=self.action_scale, action_offset=self.action_offset, squash=SQUASH[self.squash])

    def torch_module(self):
        """The same function as a torch module (float32): the reference for parity and for ONNX."""
        import torch

        spec = self

        class Actor(torch.nn.Module):
            def __init__(self):
                super().__init__()
                self.register_buffer("mean", torch.from_numpy(spec.obs_mean.copy()))
                self.register_buffer("inv_std", torch.from_numpy(spec.obs_inv_std.copy()))
                self.register_buffer("low", torch.from_numpy(spec.action_low.copy()))
                self.register_buffer("high", torch.from_numpy(spec.action_high.copy()))
                self.register_buffer("scale", torch.from_numpy(spec.action_scale.copy()))
                self.register_buffer("offset", torch.from_numpy(spec.action_offset.copy()))
                self.clip = float(spec.obs_clip)
                layers = []
                for w, b in zip(spec.weights, spec.biases):
                    lin = torch.nn.Linear(w.shape[1], w.shape[0])
                    with torch.no_grad():
                        lin.weight.copy_(torch.from_numpy(w))
                        lin.bias.copy_(torch.from_numpy(b))
                    layers.append(lin)
                self.l1, self.l2, self.l3 = layers
                self.act = {"tanh": torch.nn.Tanh(), "elu": torch.nn.ELU(), "relu": torch.nn.ReLU()}[spec.activation]

            def forward(self, obs):
                x = torch.clamp((obs - self.mean) * self.inv_std, -self.clip, self.clip)
                y = self.l3(self.act(self.l2(self.act(self.l1(x)))))
                if spec.squash == "tanh":
                    y = torch.tanh(y)
                return self.offset + self.scale * torch.minimum(torch.maximum(y, self.low), self.high)

        return Actor().eval()


def from_sb3(model, vec_normalize=None) -> MlpSpec:
    """A Stable-Baselines3 PPO/A2C model with a Box action space (and its VecNormalize, if any)."""
    import torch

    policy = model.policy
    linears = [m for m in policy.mlp_extractor.policy_net if isinstance(m, torch.nn.Linear)]
    if len(linears) != 2 or not isinstance(policy.action_net, torch.nn.Linear):
        raise ValueError("model: expected net_arch with two hidden layers for the actor, e.g. [64, 64]")
    act_fn = policy.activation_fn
    name = {torch.nn.Tanh: "tanh", torch.nn.ELU: "elu", torch.nn.ReLU: "relu"}.get(act_fn)
    if name is None:
        raise ValueError(f"model: activation {act_fn} has no core equivalent (tanh, elu, relu)")
    layers = linears + [policy.action_net]
    obs_dim = layers[0].in_features
    if vec_normalize is not None and vec_normalize.norm_obs:
        rms = vec_normalize.obs_rms
        mean = np.asarray(rms.mean, dtype=np.float64)
        inv_std = 1.0 / np.sqrt(np.asarray(rms.var, dtype=np.float64) + vec_normalize.epsilon)
        clip = float(vec_normalize.clip_obs)
    else:
        mean, inv_std, clip = np.zeros(obs_dim), np.ones(obs_dim), 3.0e38
    space = model.action_space
    return MlpSpec(activation=name,
                   weights=[l.weight.detach().cpu().numpy() for l in layers],
                   biases=[l.bias.detach().cpu().numpy() for l in layers],
                   obs_mean=mean, obs_inv_std=inv_std, obs_clip=clip,
                   action_low=space.low, action_high=space.high,
                   action_scale=np.ones(space.shape), action_offset=np.zeros(space.shape))


def from_rsl_rl(actor_state_dict: dict, action_low, action_high, activation: str = "elu", eps: float = 1e-2,
                squash: str = "none", action_scale=None, obs_normalizer: bool = True) -> MlpSpec:
    """An rsl-rl-lib 5.x actor (MLPModel) from its state dict (a checkpoint's "actor_state_dict"):
    layers mlp.0 / mlp.2 / mlp.4 and, if present, its EmpiricalNormalization
    ((obs - mean) / (std + eps), no clip). The deterministic action is the mean, clipped to the
    action space as the training loop's evaluation does; `squash="tanh"` and `action_scale` give
    kestrel.adapters.RslRlVecEnv(squash=True) with make_vec(action_scale=...): a = scale tanh(y).
    `obs_normalizer=False` ignores a normalizer the checkpoint carries but training did not use."""
    sd = {k: v.detach().cpu().numpy() if hasattr(v, "detach") else np.asarray(v) for k, v in actor_state_dict.items()}
    keys = sorted((k for k in sd if k.startswith("mlp.") and k.endswith(".weight")), key=lambda k: int(k.split(".")[1]))
    if len(keys) != 3:
        raise ValueError(f"actor_state_dict: expected 3 linear layers (two hidden), got {keys}")
    weights = [sd[k] for k in keys]
    biases = [sd[k.replace(".weight", ".bias")] for k in keys]
    obs_dim = weights[0].shape[1]
    if obs_normalizer and "obs_normalizer._mean" in sd:
        mean = sd["obs_normalizer._mean"].reshape(obs_dim).astype(np.float64)
        std = sd["obs_normalizer._std"].reshape(obs_dim).astype(np.float64)
        inv_std = 1.0 / (std + eps)
    else:
        mean, inv_std = np.zeros(obs_dim), np.ones(obs_dim)
    n = weights[2].shape[0]
    low = np.broadcast_to(np.asarray(action_low, dtype=np.float32), (n,))
    high = np.broadcast_to(np.asarray(action_high, dtype=np.float32), (n,))
    scale = np.ones(n) if action_scale is None else np.broadcast_to(np.asarray(action_scale, dtype=np.float32), (n,))
    return MlpSpec(activation=activation, weights=weights, biases=biases, obs_mean=mean, obs_inv_std=inv_std,
                   obs_clip=3.0e38, action_low=low, action_high=high, action_scale=scale, action_offset=np.zeros(n),
                   squash=squash)


def _hex(v) -> str:
    v = float(np.float32(v))
    if math.isinf(v):
        raise ValueError("non-finite value in the network")
    return float.hex(v)


def write_header(spec: MlpSpec, path: str, name: str = "kPolicy", namespace: str = "kestrel::policy::generated") -> str:
    """C++ header defining `inline constexpr MlpParams<...> name` with hex-float literals."""
    h1, h2 = spec.hidden
    arr = lambda a: "{" + ", ".join(_hex(x) for x in np.asarray(a).ravel()) + "}"
    mat = lambda w: "{" + ", ".join(arr(row) for row in w) + "}"
    layer = lambda w, b: "{" + mat(w) + ", " + arr(b) + "}"
    clip = min(float(spec.obs_clip), 3.0e38)
    # Parts the network can do without (policy/mlp.hpp MlpParts): no normalisation where it is the
    # identity (mean 0, inv_std 1, a clip at 3e38 or beyond, i.e. trained without one; an input
    # beyond 3e38 then reaches the layer unclipped), no action clamp where a tanh squash already
    # keeps the output inside [low, high]. Each saves its numbers and its loop in flash.
    f32 = lambda a: np.asarray(a, np.float32)
    norm = not (np.all(f32(spec.obs_mean) == 0) and np.all(f32(spec.obs_inv_std) == 1) and clip >= 3.0e38)
    clamp = not (spec.squash == "tanh" and np.all(f32(spec.action_low) <= -1) and np.all(f32(spec.action_high) >= 1))
    parts = " | ".join(p for p, on in (("kestrel::policy::kMlpObsNorm", norm), ("kestrel::policy::kMlpActionClamp", clamp)) if on)
    t = f"MlpParams<{spec.obs_dim}, {h1}, {h2}, {spec.action_dim}"
    t += ">" if norm and clamp else f", {parts or '0u'}>"
    absent = "{}"
    text = f"""// Generated by python/kestrel/export.py (write_header): a trained actor as core code. Every
// number is the float32 weight written exactly as a hex-float literal. Do not edit.
#pragma once

#include "kestrel/policy/mlp.hpp"

namespace {namespace} {{

using {name}Type = kestrel::policy::{t};
inline constexpr {name}Type {name} = {{
    kestrel::policy::Activation::{spec.activation},
    {arr(spec.obs_mean) if norm else absent},
    {arr(spec.obs_inv_std) if norm else absent},
    {_hex(clip) if norm else absent},
    {layer(spec.weights[0], spec.biases[0])},
    {layer(spec.weights[1], spec.biases[1])},
    {layer(spec.weights[2], spec.biases[2])},
    {arr(spec.action_low) if clamp else absent},
    {arr(spec.action_high) if clamp else absent},
    {arr(spec.action_scale)},
    {arr(spec.action_offset)},
    kestrel::policy::Squash::{spec.squash},
}};
// Checked when it is compiled (validate_mlp is constexpr): a firmware flying it needs no check
// at start-up, nor its code in flash.
static_assert(kestrel::policy::validate_mlp({name}) == kestrel::Status::ok, "{name}: invalid network");

}}  // namespace {namespace}
"""
    with open(path, "w") as f:
        f.write(text)
    return path


def export_onnx(spec: MlpSpec, path: str, opset: int | None = None, dynamo: bool = False) -> str:
    """The same function as ``spec`` (normalisation, MLP, squash, clip, scale) as an ONNX graph:
    input ``obs`` float32 (batch, obs_dim), output ``action`` float32 (batch, action_dim), batch
    dimension dynamic. Written by torch.onnx.export from :meth:`MlpSpec.torch_module`; needs the
    ``onnx`` package (pinned in python/requirements.txt). ``dynamo=False`` (default) uses torch's
    TorchScript exporter: ~0.5 s, no packages beyond onnx (torch 2.13 warns that it is deprecated;
    the warning is silenced here). ``dynamo=True`` uses torch.export (needs onnxscript, ~10 s);
    both give the same operators (Sub, Mul, Clip, Gemm, Elu/Tanh/Relu, Max, Min, Add)."""
    import warnings

    import torch

    module = spec.torch_module()
    dummy = torch.zeros(1, spec.obs_dim, dtype=torch.float32)
    kw = {} if opset is None else {"opset_version": int(opset)}
    if dynamo:
        torch.onnx.export(module, (dummy,), path, input_names=["obs"], output_names=["action"],
                          dynamic_shapes={"obs": {0: torch.export.Dim("batch")}}, dynamo=True, **kw)
        return path
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*legacy TorchScript-based ONNX export.*")
        warnings.filterwarnings("ignore", message=".*feature will be removed.*")
        torch.onnx.export(module, (dummy,), path, input_names=["obs"], output_names=["action"],
                          dynamic_axes={"obs": {0: "batch"}, "action": {0: "batch"}}, dynamo=False, **kw)
    return path


def onnx_forward(path: str, obs: np.ndarray) -> np.ndarray:
    """Runs an exported graph with onnx's own reference evaluator (numpy; no onnxruntime needed)."""
    from onnx.reference import ReferenceEvaluator

    return ReferenceEvaluator(path).run(None, {"obs": np.ascontiguousarray(obs, dtype=np.float32)})[0]


def main(argv=None, prog: str = "python -m kestrel.export") -> int:
    """kestrel export (--rsl-rl CKPT | --sb3 MODEL.zip [--vecnormalize PKL]) [--header OUT.hpp] [--onnx OUT.onnx]"""
    import argparse

    p = argparse.ArgumentParser(prog=prog, description=main.__doc__)
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--rsl-rl", help="rsl-rl-lib checkpoint (.pt with actor_state_dict)")
    src.add_argument("--sb3", help="Stable-Baselines3 model (.zip)")
    p.add_argument("--vecnormalize", help="SB3 VecNormalize statistics (.pkl) saved with the model")
    p.add_argument("--low", type=float, default=-10.0, help="action clip low (rsl_rl; SB3 reads its action space)")
    p.add_argument("--high", type=float, default=10.0, help="action clip high")
    p.add_argument("--activation", default="elu", help="rsl_rl actor activation (default elu)")
    p.add_argument("--squash", default="none", choices=sorted(SQUASH), help="rsl_rl: tanh if trained with --squash")
    p.add_argument("--action-scale", help="rsl_rl: comma-separated scale after the squash (make_vec action_scale)")
    p.add_argument("--no-obs-normalizer", action="store_true", help="rsl_rl: trained without observation normalisation")
    p.add_argument("--header", help="C++ header to write (firmware: policy/mlp.hpp MlpParams)")
    p.add_argument("--name", default="kPolicy", help="name of the constexpr MlpParams in the header")
    p.add_argument("--onnx", help="also write an ONNX graph here")
    a = p.parse_args(argv)
    if not a.header and not a.onnx:
        p.error("nothing to write: give --header OUT.hpp and/or --onnx OUT.onnx")
    if a.rsl_rl:
        import torch

        ck = torch.load(a.rsl_rl, map_location="cpu", weights_only=False)
        scale = [float(x) for x in a.action_scale.split(",")] if a.action_scale else None
        spec = from_rsl_rl(ck["actor_state_dict"], a.low, a.high, activation=a.activation, squash=a.squash,
                           action_scale=scale, obs_normalizer=not a.no_obs_normalizer)
    else:
        from stable_baselines3 import PPO

        model = PPO.load(a.sb3, device="cpu")
        vn = None
        if a.vecnormalize:
            import pickle

            with open(a.vecnormalize, "rb") as f:
                vn = pickle.load(f)
        spec = from_sb3(model, vn)
    if a.header:
        write_header(spec, a.header, name=a.name)
        with open(a.header) as f:
            decl = next(line for line in f if line.startswith("using "))
        print(f"{a.header}: {a.name} = {decl.split('kestrel::policy::', 1)[1].rstrip().rstrip(';')} ({spec.activation})")
    if a.onnx:
        export_onnx(spec, a.onnx)
        print(f"{a.onnx}: ONNX graph of the same function")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
