"""Train a policy on a Kestrel task with a learner from PyPI, evaluate it, log and plot.

    kestrel train Kestrel-PositionSetpoint-v0 --learner rsl_rl --seed 0 --threads 1 \\
        --out runs/ps --target-success 0.95

(`kestrel train` is the package's console command, kestrel.cli; `python -m kestrel.train` is the same)

(that task's defaults: _TASK_DEFAULTS below; 100 % success after 1.7 M env-steps, 14 s of training
on 2 cores, bench/results/python/README.md; Kestrel-PositionSetpointMotors-v0, direct motor
commands: 95 % after 2.9 M env-steps, 38 s)

Every --eval-every env-steps (and at the end) the deterministic policy is evaluated on
--eval-episodes episodes of a separate env seeded with --eval-seed (never a training seed): one
episode per environment, success rate (position setpoint: truncated within the task's success
radius; other tasks: terminated without a crash is not told apart, so success = the task's own
count), crash rate, mean return, mean episode length, final distance. Writes DIR/log.csv (one row per
evaluation), DIR/curves.png (return, success rate, episode length over env-steps),
DIR/checkpoints/*.pt (one per evaluation), DIR/summary.json, TensorBoard event files in DIR
(`tensorboard --logdir DIR`; x axis env-steps: eval/* per evaluation, train/* per learner update
from the training envs' episodes, loss/*, policy/mean_std, perf/* from rsl_rl's update; SB3 writes
its own under DIR/sb3/) and the final policy as DIR/policy.onnx and DIR/policy.hpp (kestrel.export:
the deterministic action the env takes, scaled; summary.json's "export" gives its agreement with
the learner's own policy). With --target-success the run stops at the first evaluation that
reaches it. Times: `train_s` is the wall time spent in the learner and the simulator (evaluations
excluded), `sim_s` the part of it in env.step. `--view` shows the first --view-envs training
environments in the 3-D viewer (kestrel.viewer.TrainView, at most --view-fps frames a second, the
drawing outside sim_s; summary.json's "view" gives the frames drawn and the time they took).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
import time
from dataclasses import dataclass, asdict
from typing import Callable

import numpy as np

import kestrel
from .vector_env import GYM_IDS, KestrelVectorEnv, make_vec


@dataclass
class EvalResult:
    episodes: int
    mean_return: float
    success_rate: float
    crash_rate: float
    mean_length: float
    final_distance_m: float
    # locomotion_task: mean over every step of the first episodes of |cmd_xy - v_xy| (m/s) and
    # |cmd_yaw - w_z| (rad/s), the commands the step was given and the true (noise-free) velocities
    # after it; NaN for other tasks. Its success is an episode that reaches the time limit, its
    # crash a fall (base contact).
    lin_vel_error_m_s: float = float("nan")
    yaw_rate_error_rad_s: float = float("nan")


def evaluate(policy: Callable[[np.ndarray], np.ndarray], env_id: str, episodes: int = 1024, seed: int = 1_000_003,
             threads: int | None = None, **overrides) -> EvalResult:
    """One episode in each of `episodes` environments seeded with `seed`; deterministic policy."""
    env = make_vec(env_id, num_envs=episodes, seed=seed, threads=threads, **overrides)
    obs, _ = env.reset(seed=seed)
    n = env.num_envs
    done = np.zeros(n, bool)
    ret = np.zeros(n)
    length = np.zeros(n, np.int64)
    success = np.zeros(n, bool)
    crash = np.zeros(n, bool)
    dist = np.zeros(n)
    setpoint = env.task.name == "position_setpoint_task"
    # navigation_task: its observation 3 is the distance to the goal, so the first episode of each
    # environment is told apart exactly: a termination is a crash; a truncation (the time limit)
    # within the success radius a success (Aerial Gym's rule), else a timeout.
    navigation = env.task.name == "navigation_task"
    radius = env.task.success_radius_m
    locomotion = env.task.name == "locomotion_task"
    lin_err = yaw_err = 0.0
    err_steps = 0
    if locomotion:
        # Commands from the observations (columns 9-11, scaled by the task's obs scales and free of
        # noise), taken before the step that follows them.
        scale_lin, scale_yaw = _loco_obs_scales(env_id, overrides)
    before = env.task.infos
    hold = max(1, int(getattr(policy, "hold", 1)))  # a recurrent policy decides every `hold` env-steps
    t = 0
    action = None
    while not done.all():
        if locomotion:
            cmd_xy = obs[:, 9:11] / scale_lin
            cmd_yaw = obs[:, 11] / scale_yaw
        if t % hold == 0:
            action = policy(obs)
        t += 1
        obs, r, te, tr, info = env.step(action)
        alive = ~done
        if locomotion:
            live = alive & ~(te | tr)
            if live.any():
                v, w = env.task.base_lin_vel_b, env.task.base_ang_vel_b
                lin_err += float(np.linalg.norm(cmd_xy[live] - v[live, :2], axis=1).sum())
                yaw_err += float(np.abs(cmd_yaw[live] - w[live, 2]).sum())
                err_steps += int(live.sum())
        ret[alive] += r[alive]
        length[alive] += 1
        ended = (te | tr) & alive
        if ended.any():
            crash[ended] = te[ended] if setpoint else False
            if "success" in info:
                success[ended] = info["success"][ended]
            if setpoint:
                dist[ended] = np.linalg.norm(info["final_obs"][ended, :3], axis=1)
            if locomotion:
                crash[ended] = te[ended]
                success[ended] = tr[ended] & ~te[ended]
            if navigation:
                d = info["final_obs"][ended, 3]
                dist[ended] = d
                success[ended] = tr[ended] & ~te[ended] & (d < radius)
                crash[ended] = te[ended]
            done |= ended
    if not setpoint and not navigation and not locomotion:  # the task's own counters over exactly the first episodes is not available: use its rates
        inf = env.task.infos
        eps = max(1, inf["episodes"] - before["episodes"])
        success[:] = False
        success[: int(round(n * (inf["successes"] - before["successes"]) / eps))] = True
        crash[: int(round(n * (inf["crashes"] - before["crashes"]) / eps))] = True
    env.close()
    res = EvalResult(n, float(ret.mean()), float(success.mean()), float(crash.mean()), float(length.mean()),
                     float(dist.mean()) if setpoint or navigation else float("nan"))
    if locomotion and err_steps > 0:
        res.lin_vel_error_m_s = lin_err / err_steps
        res.yaw_rate_error_rad_s = yaw_err / err_steps
    return res


def _loco_obs_scales(env_id: str, overrides: dict) -> tuple[float, float]:
    """locomotion_task's command observation scales (obs_scale_lin_vel, obs_scale_ang_vel) for this id."""
    sec = dict(overrides.get("task", {}).get("locomotion", {})) if isinstance(overrides.get("task"), dict) else {}
    return float(sec.get("obs_scale_lin_vel", 2.0)), float(sec.get("obs_scale_ang_vel", 0.25))


class _Timer:
    """Accumulates the time spent inside env.step (the simulator's share)."""

    def __init__(self, env: KestrelVectorEnv):
        self.sim_s = 0.0
        inner = env.step

        def timed(actions):
            t0 = time.perf_counter()
            out = inner(actions)
            self.sim_s += time.perf_counter() - t0
            return out

        env.step = timed  # type: ignore[method-assign]


def privileged_proximities(env: KestrelVectorEnv, count: int, scale_m: float = 0.5) -> Callable[[], np.ndarray]:
    """The critic's privileged observations of --critic-sensors: the last `count` ray images of
    every robot (the sensors appended after the policy's own), each ray as the proximity
    1 / (1 + r / scale_m) the navigation observation uses (r in metres; a ray without a return,
    r outside [0, max_range_m): 0), flattened per environment. Read from the simulator's image
    views when called (after each step and reset)."""
    cache: dict = {}

    def layout(sim):
        # Per image: its metres per stored value (a sensor with normalize_range stores fractions
        # of its range) and its range in metres; looked up once per simulator, not per step.
        if cache.get("sim") is not sim:
            total = sim.num_range_images
            rays = [sim.range_image_rays(k) for k in range(total - count, total)]
            cache.update(sim=sim, first=total - count,
                         scales=[(float(r["value_scale_m"]), float(r["max_range_m"])) for r in rays])
        return cache["first"], cache["scales"]

    def read() -> np.ndarray:
        sim = env.task.simulator  # looked up each call: a reset with a seed rebuilds the task
        first, scales = layout(sim)
        parts = []
        for j, (value_m, max_m) in enumerate(scales):
            r = np.asarray(sim.range_images(first + j), np.float32) * np.float32(value_m)
            hit = np.isfinite(r) & (r >= 0) & (r < max_m)
            prox = np.where(hit, 1.0 / (1.0 + np.where(hit, r, 0.0) / scale_m), 0.0)
            parts.append(prox.reshape(r.shape[0], -1).astype(np.float32))
        return np.concatenate(parts, axis=1)

    return read


def _rsl_rl_cfg(args) -> dict:
    # --rnn: rsl-rl-lib's RNNModel for actor and critic (a GRU or LSTM over the observations, then
    # the MLP), legged_gym's ActorCriticRecurrent in rsl-rl-lib 5's form; PPO then trains on whole
    # rollouts per environment with the hidden states reset at episode ends.
    model = "rsl_rl.models.MLPModel"
    rnn: dict = {}
    if getattr(args, "rnn", None):
        model = "rsl_rl.models.RNNModel"
        rnn = {"rnn_type": args.rnn[0], "rnn_hidden_dim": args.rnn[1], "rnn_num_layers": 1}
    return {
        "num_steps_per_env": args.rollout,
        "save_interval": 10**9,
        "obs_groups": {"actor": ["policy"],
                       "critic": ["policy", "privileged"] if getattr(args, "critic_sensors", None) else ["policy"]},
        "actor": {"class_name": model, "hidden_dims": list(args.hidden), "activation": "elu",
                  "obs_normalization": bool(args.obs_norm), **rnn,
                  "distribution_cfg": {"class_name": "rsl_rl.modules.GaussianDistribution", "init_std": args.init_std}},
        "critic": {"class_name": model, "hidden_dims": list(args.hidden), "activation": "elu",
                   "obs_normalization": bool(args.obs_norm), **rnn},
        "algorithm": {"class_name": "rsl_rl.algorithms.PPO", "num_learning_epochs": args.epochs,
                      "num_mini_batches": args.minibatches, "clip_param": 0.2, "gamma": args.gamma, "lam": args.lam,
                      "value_loss_coef": 1.0, "entropy_coef": args.entropy, "learning_rate": args.lr,
                      "max_grad_norm": 1.0, "schedule": "adaptive", "desired_kl": 0.01},
        "check_for_nan": False,
    }


class _RecurrentInference:
    """The deterministic policy of an rsl-rl-lib RNNModel with a hidden state of its own (zeros,
    sized by the first batch): the training rollout's states are left alone. The model's own
    pieces in its order: observation normaliser, RNN, MLP, the distribution's deterministic output."""

    def __init__(self, model):
        import copy

        self.norm = copy.deepcopy(model.obs_normalizer)
        self.rnn = copy.deepcopy(model.rnn.rnn)
        self.mlp = copy.deepcopy(model.mlp)
        self.out = model.distribution.as_deterministic_output_module() if model.distribution is not None else None
        for m in (self.norm, self.rnn, self.mlp):
            m.eval()
        self.state = None

    def __call__(self, obs):
        x, self.state = self.rnn(self.norm(obs).unsqueeze(0), self.state)
        y = self.mlp(x.squeeze(0))
        return self.out(y) if self.out is not None else y


class Learner:
    """train(env_steps) and a deterministic numpy policy, for either learner."""

    def __init__(self, args, env: KestrelVectorEnv):
        import torch

        torch.manual_seed(args.seed)
        torch.set_num_threads(max(1, args.torch_threads))
        self.kind = args.learner
        self.env = env
        self.obs_norm = bool(args.obs_norm)
        if self.kind == "rsl_rl":
            import contextlib
            import io

            from rsl_rl.runners import OnPolicyRunner

            from .adapters import RslRlVecEnv

            self.squash = bool(args.squash) and float(env.single_action_space.high[0]) == 1.0
            self.venv = RslRlVecEnv(env, reward_scale=args.reward_scale, squash=self.squash, action_repeat=args.action_repeat,
                                     distance_shaping=args.shaping if env.task.name == "position_setpoint_task" else 0.0,
                                     gamma=args.gamma,
                                     privileged=privileged_proximities(env, len(args.critic_sensors))
                                     if getattr(args, "critic_sensors", None) else None)
            with contextlib.redirect_stdout(io.StringIO()):
                self.runner = OnPolicyRunner(self.venv, _rsl_rl_cfg(args), log_dir=None, device="cpu")
            self.steps_per_iter = args.rollout * env.num_envs * self.venv.action_repeat
            # rsl_rl calls logger.log(...) after every update; with log_dir=None it writes nothing
            # (and, with a log_dir, it would open a new event file and save a model per learn()
            # call). Its statistics go to on_update instead, into the trainer's one writer.
            rsl_log = self.runner.logger.log

            def log_update(**kw):
                rsl_log(**kw)
                scalars = {f"loss/{k}": float(v) for k, v in kw["loss_dict"].items()}
                scalars["loss/learning_rate"] = float(kw["learning_rate"])
                scalars["policy/mean_std"] = float(kw["action_std"].detach().mean())
                dt = kw["collect_time"] + kw["learn_time"]
                scalars["perf/collection_s"] = float(kw["collect_time"])
                scalars["perf/learning_s"] = float(kw["learn_time"])
                scalars["perf/env_steps_per_s"] = self.steps_per_iter / dt if dt > 0 else 0.0
                if self.on_update is not None:
                    self.on_update(self.steps_per_iter, scalars)

            self.runner.logger.log = log_update
            if getattr(args, "resume", None):
                # Training goes on from a checkpoint of the same task (actor, critic, optimizer).
                self.runner.load(args.resume)
        elif self.kind == "sb3":
            from stable_baselines3 import PPO
            from stable_baselines3.common.vec_env import VecNormalize

            from .adapters import Sb3VecEnv

            self.venv = VecNormalize(Sb3VecEnv(env), norm_obs=True, norm_reward=False, gamma=args.gamma)
            n_steps = args.rollout
            self.model = PPO("MlpPolicy", self.venv, n_steps=n_steps, batch_size=max(64, n_steps * env.num_envs // args.minibatches),
                             n_epochs=args.epochs, gamma=args.gamma, gae_lambda=args.lam, learning_rate=args.lr, ent_coef=args.entropy,
                             policy_kwargs={"net_arch": list(args.hidden), "log_std_init": float(np.log(args.init_std))},
                             seed=args.seed, device="cpu", verbose=0,
                             tensorboard_log=os.path.join(args.out, "sb3") if args.tensorboard else None)
            self.steps_per_iter = n_steps * env.num_envs
        else:
            raise ValueError(f"--learner: expected rsl_rl or sb3, got {self.kind!r}")

    # Called after every learner update with (env-steps of that update, {tag: scalar}).
    on_update: Callable[[int, dict], None] | None = None

    def train(self, env_steps: int) -> int:
        iters = max(1, env_steps // self.steps_per_iter)
        if self.kind == "rsl_rl":
            import contextlib
            import io

            with contextlib.redirect_stdout(io.StringIO()):
                self.runner.learn(iters)
            self.runner.current_learning_iteration += 1
        else:
            from stable_baselines3.common.callbacks import BaseCallback

            learner = self

            class OnRollout(BaseCallback):
                def _on_step(self) -> bool:
                    return True

                def _on_rollout_end(self) -> None:
                    if learner.on_update is not None:
                        learner.on_update(learner.steps_per_iter, {})

            self.model.learn(iters * self.steps_per_iter, reset_num_timesteps=False, callback=OnRollout(),
                             tb_log_name="PPO")
        return iters * self.steps_per_iter

    def policy(self) -> Callable[[np.ndarray], np.ndarray]:
        import torch

        if self.kind == "rsl_rl":
            from tensordict import TensorDict

            net = self.runner.get_inference_policy()
            recurrent = bool(getattr(net, "is_recurrent", False))
            if recurrent:
                net = _RecurrentInference(net)
            low, high = self.env.single_action_space.low, self.env.single_action_space.high
            same = bool(np.all(low == low[0]) and np.all(high == high[0]))
            lo = float(low[0]) if same else torch.as_tensor(low)
            hi = float(high[0]) if same else torch.as_tensor(high)
            squash = self.squash

            def act(obs: np.ndarray) -> np.ndarray:
                with torch.inference_mode():
                    if recurrent:
                        a = net(torch.from_numpy(np.array(obs)))
                    else:
                        o = TensorDict({"policy": torch.from_numpy(np.array(obs))}, batch_size=[obs.shape[0]])
                        a = net(o)
                    a = torch.tanh(a) if squash else a.clamp(lo, hi)
                    return a.numpy().astype(np.float32, copy=False)

            if recurrent:
                # Its state moves once per decision, as in training: the evaluation holds each
                # action for the training's action repeat (a feed-forward policy decides every
                # env-step there).
                act.hold = self.venv.action_repeat  # type: ignore[attr-defined]
            return act
        venv = self.venv
        model = self.model

        def act_sb3(obs: np.ndarray) -> np.ndarray:
            a, _ = model.predict(venv.normalize_obs(np.array(obs)), deterministic=True)
            return np.ascontiguousarray(a, dtype=np.float32)

        return act_sb3

    def spec(self):
        """The deterministic policy as kestrel.export's MlpSpec, in the env's action units (after
        the env's action_scale): what the env is given for an observation."""
        from . import export

        scale = self.env.action_scale
        offset = self.env.action_offset
        if self.kind == "rsl_rl":
            if getattr(self.runner.alg.get_policy(), "is_recurrent", False):
                raise ValueError("a recurrent policy (--rnn) has no export to the core's feed-forward MLP")
            space = self.env.single_action_space
            spec = export.from_rsl_rl(self.runner.alg.save()["actor_state_dict"], space.low, space.high, activation="elu",
                                      squash="tanh" if self.squash else "none", action_scale=scale,
                                      obs_normalizer=bool(self.obs_norm))
        else:
            spec = export.from_sb3(self.model, self.venv)
            if scale is not None:
                spec.action_scale = np.asarray(scale, np.float32)
        if offset is not None:
            spec.action_offset = np.asarray(offset, np.float32)
        return spec

    def save(self, path: str) -> None:
        if self.kind == "rsl_rl":
            self.runner.save(path)
            self.runner.alg.train_mode()
        else:
            self.model.save(path)
            self.venv.save(path + ".vecnormalize.pkl")


def _json_arg(flag: str, text: str, kind: type, what: str):
    """A JSON argument of type `kind` (dict or list), else a clear exit naming the flag and `what`."""
    try:
        value = json.loads(text)
    except json.JSONDecodeError as e:
        raise SystemExit(f"{flag}: expected {what}, got {text!r} ({e})")
    if not isinstance(value, kind):
        raise SystemExit(f"{flag}: expected {what}, got {text!r}")
    return value


def _task_keys(flag: str, text: str) -> dict:
    """A --task-set style argument: a JSON object of scenario `task:` keys, else a clear exit."""
    return _json_arg(flag, text, dict, "a JSON object of task section keys")


def plot(rows: list[dict], path: str, title: str, target_success: float | None = None) -> None:
    """The learning curves (kestrel.plots.plot_learning_curves: labelled axes with units, legends,
    the --target-success line)."""
    from .plots import plot_learning_curves

    plot_learning_curves(rows, path, title, target_success)


def progress_enabled(quiet: bool, stream=None) -> bool:
    """The progress bar (issue 15): on a terminal only, never with --quiet (a log file or a pipe
    gets no carriage-return lines)."""
    stream = sys.stderr if stream is None else stream
    isatty = getattr(stream, "isatty", None)
    return not quiet and callable(isatty) and bool(isatty())


# Hover thrust per motor of base_quadrotor: 0.25 kg x 9.81 m/s^2 / 4 (the thrust the World resets
# the motors to).
_HOVER_N = 0.25 * 9.81 / 4

# Normalised action spaces the trainer uses by default. Kestrel-PositionSetpoint-v0 (Lee velocity
# control): the task clips actions to +-10 (m/s, rad/s); a unit-std initial Gaussian over that
# range and a policy that must hold a hover to within 0.3 m learnt to fly towards the target but
# not to settle on it (1-3 % success after 25 M env-steps). The scripted policy that reaches every
# target (vehicle-frame error, norm <= 2 m/s) needs no more, so the learner acts in [-1, 1]
# scaled to +-2 m/s and +-1 rad/s of yaw rate (Aerial Gym's action transformation).
_AUTO_ACTION_SCALE: dict[str, list[float]] = {
    "Kestrel-PositionSetpoint-v0": [2.0, 2.0, 2.0, 1.0],
    # Direct motor commands (base_quadrotor: 0.25 kg, 4 motors clamped to [0, 2] N). The task takes
    # thrusts in N, clipped to +-10, so a zero action is motors off (the robot falls) and a
    # Gaussian around it is at or below 0 N half the time. The learner acts in [-1, 1]
    # mapped to hover +- hover (offset below): [0, 1.226] N per motor, thrust-to-weight 0-2, and
    # the zero action is hover thrust (no dead zone below 0 N where the gradient vanishes).
    "Kestrel-PositionSetpointMotors-v0": [_HOVER_N] * 4,
}
_AUTO_ACTION_OFFSET: dict[str, list[float]] = {
    "Kestrel-PositionSetpointMotors-v0": [_HOVER_N] * 4,
}

# Motors: yaw is not held by a controller (the start yaw is drawn in +-pi), so the target in the
# vehicle frame spares the network the rotation by yaw (linear and angular velocity are body-frame).
_VEHICLE_FRAME_OBS = {"Kestrel-PositionSetpoint-v0", "Kestrel-PositionSetpointMotors-v0"}

# Defaults of the options left unset on the command line (help: "None" = these).
_GENERIC_DEFAULTS = {"envs": 4096, "steps": 20_000_000, "eval_every": 2_000_000, "rollout": 24, "gamma": 0.99,
                     "obs_norm": 1, "squash": 0, "action_repeat": 1, "shaping": 0.0, "init_std": 1.0, "hidden": "64,64",
                     "entropy": 0.0, "reward_scale": 0.02, "eval_episodes": 1024}
# locomotion_task (issue 13): legged_gym's PPO (LeggedRobotCfgPPO: 24 steps per env per update, gamma
# 0.99, lambda 0.95, entropy 0.01, lr 1e-3 adaptive, 5 epochs x 4 minibatches, init std 1.0) with
# networks of two hidden layers, 128-64 ELU (legged_gym's flat ANYmal has 128-64-32; the core's MLP,
# policy/mlp.hpp, which flies the policy in the firmware, has two hidden layers), rewards as the task gives them
# (already x dt), no observation normalisation (the task scales its observations), actions as
# given (joint targets home + action_scale x a). Fewer environments than legged_gym's 4096, for
# more updates per env-step on two cores. Evaluations run 1000-step (20 s) episodes.
_LEGGED_DEFAULTS = {"envs": 1024, "steps": 30_000_000, "eval_every": 2_500_000, "rollout": 24, "gamma": 0.99,
                    "obs_norm": 0, "squash": 0, "action_repeat": 1, "shaping": 0.0, "init_std": 1.0,
                    "hidden": "128,64", "entropy": 0.01, "reward_scale": 1.0, "eval_episodes": 256}
# Issue 11: Kestrel-PositionSetpoint-v0 (Lee velocity control) stalled at 1-3 % success after 25 M
# env-steps with the generic settings. What each change fixes (bench/results/python/README.md):
# - normalised actions (_AUTO_ACTION_SCALE) squashed with tanh (a clamped Gaussian's mean drifts
#   past the bound with no gradient and the deterministic policy saturates: crashes);
# - the error in the vehicle frame (_VEHICLE_FRAME_OBS): the target policy becomes linear;
# - action repeat 10 (the learner decides at 10 Hz; its credit assignment at 100 Hz saw almost no
#   effect of one action through the velocity loop) with gamma 0.96 per decision (~0.996 per step);
# - potential-based distance shaping (optimal policy unchanged): the task's reward is flat far
#   from the target;
# - no observation normalisation: the running mean of target - position is ~3.4 m (starts are on
#   one side), which put the target itself far outside the normalised inputs' range;
# - 256 envs x 16 decisions per update: 10 x more updates per env-step than 4096 x 24.
# navigation_task's range sensor for training: the VL53L5CX preset (8 x 8 zones, 90 x 90 deg) with
# each zone the nearest return of 4 x 4 rays (the task min-pools the 32 x 32 image to 8 x 8), a
# 10 m range and a frame every 5 env-steps (20 Hz, one per decision at action repeat 5).
NAV_ZONE_SENSOR = json.dumps([{"name": "vl53l5cx", "height": 32, "width": 32, "max_range_m": 10, "every": 5}])

_TASK_DEFAULTS: dict[str, dict] = {
    "Kestrel-PositionSetpoint-v0": {"envs": 256, "steps": 4_000_000, "eval_every": 250_000, "rollout": 16,
                                    "gamma": 0.96, "obs_norm": 0, "squash": 1, "action_repeat": 10,
                                    "shaping": 300.0, "init_std": 1.0},
    # Direct motor commands (end-to-end; issue 11): the velocity defaults above with what an
    # attitude loop the policy must now close itself needs (bench/results/python/README.md):
    # - actions around hover thrust (_AUTO_ACTION_SCALE / _AUTO_ACTION_OFFSET) squashed with tanh
    #   (without the offset, actions [-1, 1] x 2 N clamped to [0, 2] N: 0 % after 6 M env-steps);
    # - the target in the vehicle frame (_VEHICLE_FRAME_OBS);
    # - action repeat 2 (50 Hz decisions) with gamma 0.98 per decision (~0.99 per env-step) and
    #   512 envs x 32 decisions per update: the velocity defaults (10 Hz, 256 x 16, gamma 0.96)
    #   crashed 74-100 % and never succeeded within 6 M env-steps; 100 Hz (action repeat 1,
    #   64 decisions, gamma 0.99) reached 8-15 % at 6 M with twice the learner time per env-step;
    # - the same distance shaping, init std 1.0 and no observation normalisation as the velocity
    #   task (init std 0.5 took 4.9 M env-steps to 95 % on seeds 0-2, 1.0 took 2.9-3.9 M).
    "Kestrel-PositionSetpointMotors-v0": {"envs": 512, "steps": 40_000_000, "eval_every": 1_000_000, "rollout": 32,
                                          "gamma": 0.98, "obs_norm": 0, "squash": 1, "action_repeat": 2,
                                          "shaping": 300.0, "init_std": 1.0},
    # navigation_task (bench/results/python/README.md): action repeat 5 (20 Hz decisions) with gamma
    # 0.98 per decision, 256 envs x 24 decisions per update, tanh-squashed actions, observation
    # normalisation (the range image and the distance); action repeat 1 never succeeded in 4.5 M
    # env-steps. Since stop 35, what took level-10 success from 42 % (60 M env-steps) past 60 %:
    # - the ToF's 8 x 8 zones each the nearest of 4 x 4 rays (32 x 32 rays min-pooled: a zone sees
    #   the nearest target in its cone, as the sensor does; one ray per zone missed rods and panel
    #   edges between rays) to 10 m, rendered every 5 env-steps (20 Hz, once per decision: the
    #   cost of the 8 x 8 image every env-step);
    # - 256-256 networks (64-64: 51 %, 128-128: 58 % at the same budget);
    # - training only: the curriculum moves up above 40 % success (down below 25 %) instead of the
    #   reference's 70 % / 60 %, which the exploring policy seldom reached, so it trained at levels
    #   0-2 for most of the run; and a crash costs -500 instead of -100;
    # - training only (stop 36): the absolute-action penalties on yaw rate and climb, which the
    #   reference scales up with the curriculum to 1.5 (-1.3 per env-step at full yaw rate, half
    #   of what flying towards the goal earns at level 10), at 0.3, so that turning away from an
    #   obstacle costs little: 65.0 % against 63.5 % on the final 1024 episodes, 70.7 % against
    #   64.8 % at the last 512-episode evaluation.
    # - training and evaluation (stop 37): the image cells as proximities 1 / (1 + r / 0.5 m)
    #   (task.navigation.image_encoding) instead of r / 10 m, where everything within 2 m, what an
    #   avoidance decision turns on, lay in the bottom fifth of [0, 1]: with the reference's start
    #   (the task's default since stop 37), 69.3 % / 29.4 % crashes against 60.5 % / 39.3 % on the
    #   final 1024 episodes (runs/nav px and sp in navigation_sweep.csv).
    # - training and evaluation (stop 38): the images of 10 and 20 env-steps before after the
    #   current one (task.navigation.image_history_frames 2, lag 10: two and four sensor frames
    #   back), so that the feed-forward policy sees which way an obstacle moves in its view;
    #   prototyped around the vector env in stop 37 (a wrapper since removed, run ph3):
    #   78.2 % / 19.8 % against 69.1 % / 30.3 % on the final 1024 episodes. A crash at -1000
    #   (training only) alone gave 73.3 % / 25.2 % (run c1000), with the history 67.3 % / 28.9 %
    #   (run hc): not kept.
    "Kestrel-Navigation-v0": {"envs": 256, "steps": 32_000_000, "eval_every": 4_000_000, "rollout": 24,
                              "gamma": 0.98, "obs_norm": 1, "squash": 1, "action_repeat": 5, "init_std": 1.0,
                              "hidden": "256,256", "sensors": NAV_ZONE_SENSOR,
                              "task_set": json.dumps({"navigation": {"image_encoding": "proximity", "proximity_scale_m": 0.5,
                                                                     "image_history_frames": 2,
                                                                     "image_history_lag_env_steps": 10}}),
                              "train_task_set": json.dumps({"curriculum": {"success_rate_for_increase": 0.4,
                                                                           "success_rate_for_decrease": 0.25},
                                                            "navigation": {"reward": {
                                                                "collision_penalty": -500,
                                                                "yawrate_absolute_action_penalty_magnitude": 0.3,
                                                                "z_absolute_action_penalty_magnitude": 0.3}}})},
}


def _export(learner: Learner, args, overrides: dict) -> dict:
    """DIR/policy.onnx and DIR/policy.hpp of the final policy, and how closely the exported
    function (torch module, ONNX reference evaluator) reproduces the learner's own deterministic
    policy on observations of the evaluation seed's first steps."""
    from . import export

    spec = learner.spec()
    env = make_vec(args.task, num_envs=64, seed=args.eval_seed, threads=args.threads, **overrides)
    obs, _ = env.reset(seed=args.eval_seed)
    act = learner.policy()
    scale = 1.0 if env.action_scale is None else env.action_scale
    offset = 0.0 if env.action_offset is None else env.action_offset
    rows, want = [], []
    for _ in range(4):
        a = act(obs)
        rows.append(np.array(obs, np.float32))
        want.append(np.asarray(a, np.float32) * scale + offset)
        obs, *_ = env.step(a)
    env.close()
    data, want = np.concatenate(rows), np.concatenate(want)
    onnx_path = export.export_onnx(spec, os.path.join(args.out, "policy.onnx"))
    header = export.write_header(spec, os.path.join(args.out, "policy.hpp"), name="kPolicy")
    import torch

    with torch.no_grad():
        got_torch = spec.torch_module()(torch.from_numpy(data)).numpy()
    got_onnx = export.onnx_forward(onnx_path, data)
    return {"onnx": onnx_path, "header": header, "observations": int(data.shape[0]),
            "max_abs_diff_spec_vs_learner": float(np.abs(got_torch - want).max()),
            "max_abs_diff_onnx_vs_spec": float(np.abs(got_onnx - got_torch).max()),
            "vehicle_frame_obs": overrides.get("vehicle_frame_obs", False)}


def main(argv: list[str] | None = None, prog: str = "python -m kestrel.train") -> dict:
    p = argparse.ArgumentParser(prog=prog, description=__doc__.split("\n\n")[0])
    p.add_argument("task", nargs="?", default="Kestrel-PositionSetpoint-v0",
                   help=f"gymnasium id ({', '.join(GYM_IDS)}) or task id ({', '.join(kestrel.task_ids())})")
    p.add_argument("--learner", choices=["rsl_rl", "sb3"], default="rsl_rl")
    p.add_argument("--envs", type=int, default=None)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--steps", type=int, default=None, help="env-steps to train at most")
    p.add_argument("--out", default="runs/kestrel")
    p.add_argument("--threads", type=int, default=None, help="simulator threads (default: every core)")
    p.add_argument("--torch-threads", type=int, default=1, help="torch threads (1: small MLPs gain nothing from more, and OpenMP threads spin against the simulator's)")
    p.add_argument("--eval-every", type=int, default=None, help="env-steps between evaluations")
    p.add_argument("--eval-episodes", type=int, default=None, help="episodes per evaluation (default 1024, legged ids 256)")
    p.add_argument("--eval-seed", type=int, default=1_000_003, help="seed of the evaluation env (unseen in training)")
    p.add_argument("--eval-level", default="top",
                   help="tasks with a curriculum (navigation_task): the level the evaluation holds ('top': "
                        "task.curriculum.max_level; 'train': the curriculum runs as in training; or a number)")
    p.add_argument("--target-success", type=float, default=None, help="stop at the first evaluation reaching it")
    p.add_argument("--rollout", type=int, default=None, help="learner steps (decisions) per env per update")
    p.add_argument("--hidden", default=None, help="actor and critic hidden layer sizes, comma list (default 64,64; "
                   "the legged ids: 128,64; Kestrel-Navigation-v0: 256,256); the export to the core's MLP takes two hidden layers")
    p.add_argument("--rnn", default=None,
                   help="rsl_rl: a recurrent actor and critic, TYPE:SIZE with TYPE gru or lstm (e.g. gru:64): rsl-rl-lib's "
                        "RNNModel, its state reset at episode ends; evaluated with the training's action repeat; no --export")
    p.add_argument("--final-eval-episodes", type=int, default=None,
                   help="after training, evaluate the final policy on this many episodes too (summary.json: final_eval)")
    p.add_argument("--resume", default=None, help="rsl_rl: go on from this checkpoint (.pt of a run of the same task and networks)")
    p.add_argument("--epochs", type=int, default=5)
    p.add_argument("--minibatches", type=int, default=4)
    p.add_argument("--lr", type=float, default=1e-3)
    p.add_argument("--gamma", type=float, default=None)
    p.add_argument("--obs-norm", type=int, default=None, help="rsl_rl: running observation normalisation (1/0)")
    p.add_argument("--squash", type=int, default=None, help="rsl_rl, normalised actions: tanh instead of a clamp (1/0)")
    p.add_argument("--action-repeat", type=int, default=None, help="rsl_rl: env-steps each learner action is held")
    p.add_argument("--shaping", type=float, default=None, help="rsl_rl, position setpoint: potential-based distance shaping (reward units per m)")
    p.add_argument("--lam", type=float, default=0.95, help="GAE lambda")
    p.add_argument("--entropy", type=float, default=None)
    p.add_argument("--init-std", type=float, default=None)
    p.add_argument("--reward-scale", type=float, default=None, help="rsl_rl: rewards times this (no value normalisation there; default 0.02, legged ids 1)")
    p.add_argument("--episode-len", type=int, default=None, help="override task.episode_len_env_steps")
    p.add_argument("--task-set", default=None,
                   help="scenario `task:` keys as a JSON object, e.g. '{\"navigation\": {\"action_space\": \"velocity\"}}' "
                        "(docs/scenario_reference.md; checked like a scenario's); it replaces a task's default one "
                        "(Kestrel-Navigation-v0's proximity image encoding)")
    p.add_argument("--sensors", default=None,
                   help="the robot's sensors as a JSON list of scenario `sensors:` entries (replacing the task's), e.g. "
                        "'[{\"name\": \"vl53l5cx\", \"max_range_m\": 10}]' (docs/scenario_reference.md; checked like a scenario's)")
    p.add_argument("--critic-sensors", default=None,
                   help="rsl_rl: sensors (a JSON list of scenario sensor entries) appended to the training robots' for the "
                        "critic alone (asymmetric actor-critic): each ray as a proximity 1/(1 + r/0.5 m); the policy, its "
                        "evaluation and its export never see them; needs the policy's sensors (--sensors or the task's default)")
    p.add_argument("--train-task-set", default=None,
                   help="scenario `task:` keys as a JSON object for the training environments only, on top of --task-set: "
                        "training-side randomisation the evaluation must not see (it replaces a task's default one: "
                        "Kestrel-Navigation-v0's curriculum thresholds, crash penalty and yaw-rate / climb penalties), e.g. more frequent pushes "
                        "'{\"locomotion\": {\"push_interval_s\": 4}}'")
    p.add_argument("--action-scale", default="auto",
                   help="normalised actions in [-1, 1] times these (comma list, one or one per action), 'none' for the "
                        "task's own +-10 actions; auto: " + ", ".join(f"{k} {v}" for k, v in _AUTO_ACTION_SCALE.items()))
    p.add_argument("--action-offset", default="auto",
                   help="with --action-scale: the env is given offset + scale * a (comma list, 'none' for 0); auto: "
                        + ", ".join(f"{k} {v}" for k, v in _AUTO_ACTION_OFFSET.items()))
    p.add_argument("--vehicle-frame-obs", choices=["auto", "on", "off"], default="auto",
                   help="position setpoint: target - position rotated into the vehicle frame (auto: on for "
                        + ", ".join(sorted(_VEHICLE_FRAME_OBS)) + ")")
    p.add_argument("--tensorboard", type=int, default=1, help="TensorBoard event files in --out (1/0)")
    p.add_argument("--export", type=int, default=None,
                   help="write the final policy as --out/policy.onnx and policy.hpp (1/0; default 1, with --rnn 0)")
    p.add_argument("--address", default=None,
                   help="train with the environments in Ray actors (kestrel.cluster.RayVectorEnv): auto, ray://HOST:10001, "
                        "HOST:6379, or local (a Ray on this machine); the learner stays in this process")
    p.add_argument("--rollout-workers", type=int, default=None,
                   help="Ray actors holding the environments (each a slice, --threads threads each; default 2 with --address)")
    p.add_argument("--view", action="store_true",
                   help="show the first training environments in the 3-D viewer (a browser page) as they learn")
    p.add_argument("--view-envs", type=int, default=4, metavar="N", help="--view: environments shown (default 4)")
    p.add_argument("--view-fps", type=float, default=10.0,
                   help="--view: frames drawn per second of wall time at most (default 10; drawing costs the learner time)")
    p.add_argument("--port", type=int, default=8080, help="--view: the viewer's port (default 8080; 0: any free port)")
    p.add_argument("--quiet", action="store_true")
    args = p.parse_args(argv)
    legged = GYM_IDS.get(args.task, (args.task,))[0] == "locomotion_task"
    for k, v in {**_GENERIC_DEFAULTS, **(_LEGGED_DEFAULTS if legged else {}), **_TASK_DEFAULTS.get(args.task, {})}.items():
        if getattr(args, k) is None:
            setattr(args, k, v)
    if isinstance(args.hidden, str):
        try:
            args.hidden = [int(x) for x in args.hidden.split(",")]
        except ValueError:
            raise SystemExit(f"--hidden: expected a comma list of layer sizes, e.g. 128,64,32; got {args.hidden!r}")
        if not args.hidden or min(args.hidden) < 1:
            raise SystemExit(f"--hidden: expected positive layer sizes, got {args.hidden!r}")

    if args.rnn is not None:
        kind, _, size = args.rnn.partition(":")
        if kind not in ("gru", "lstm") or not size.isdigit() or int(size) < 1:
            raise SystemExit(f"--rnn: expected TYPE:SIZE with TYPE gru or lstm and SIZE >= 1, e.g. gru:64; got {args.rnn!r}")
        if args.learner != "rsl_rl":
            raise SystemExit(f"--rnn: takes --learner rsl_rl (got {args.learner})")
        if args.export:
            raise SystemExit("--rnn: a recurrent policy has no export to the core's feed-forward MLP (leave out --export)")
        args.rnn = (kind, int(size))
    if args.export is None:
        args.export = 0 if args.rnn else 1

    overrides = {}
    scale = _AUTO_ACTION_SCALE.get(args.task) if args.action_scale == "auto" else (
        None if args.action_scale.lower() == "none" else [float(x) for x in args.action_scale.split(",")])
    if scale is not None:
        overrides["action_scale"] = scale
    offset = _AUTO_ACTION_OFFSET.get(args.task) if args.action_offset == "auto" else (
        None if args.action_offset.lower() == "none" else [float(x) for x in args.action_offset.split(",")])
    if offset is not None and scale is not None:
        overrides["action_offset"] = offset
    else:
        offset = None
    vframe = args.task in _VEHICLE_FRAME_OBS if args.vehicle_frame_obs == "auto" else args.vehicle_frame_obs == "on"
    if vframe:
        overrides["vehicle_frame_obs"] = True
    if args.task_set:
        overrides["task"] = _task_keys("--task-set", args.task_set)
    if args.sensors:
        overrides["sensors"] = _json_arg("--sensors", args.sensors, list, "a JSON list of sensor entries")
    if args.episode_len:
        overrides["task"] = {**overrides.get("task", {}), "episode_len_env_steps": args.episode_len}
    train_overrides = overrides
    if args.critic_sensors:
        if args.learner != "rsl_rl":
            raise SystemExit(f"--critic-sensors: takes --learner rsl_rl (got {args.learner})")
        args.critic_sensors = _json_arg("--critic-sensors", args.critic_sensors, list, "a JSON list of sensor entries")
        if not args.critic_sensors:
            raise SystemExit("--critic-sensors: expected at least one sensor entry, got []")
        if "sensors" not in overrides:
            raise SystemExit("--critic-sensors: the policy's sensors must be given too (--sensors), so that the "
                             "critic's are appended after them")
        train_overrides = {**overrides, "sensors": list(overrides["sensors"]) + list(args.critic_sensors)}
    if args.train_task_set:
        from . import _merge

        train_set = _task_keys("--train-task-set", args.train_task_set)
        train_overrides = {**train_overrides, "task": _merge(dict(overrides.get("task", {})), train_set)}
    os.makedirs(os.path.join(args.out, "checkpoints"), exist_ok=True)
    if args.address is not None or args.rollout_workers is not None:
        # Environments on a Ray cluster, in slices keyed by global index: the same batches as one
        # process's make_vec for any number of workers (kestrel.cluster).
        from .cluster import RayVectorEnv

        workers = args.rollout_workers or 2
        if workers < 1:
            raise SystemExit(f"--rollout-workers: expected an integer >= 1, got {workers}")
        env = RayVectorEnv(args.task, num_envs=args.envs, seed=args.seed, workers=workers, threads=args.threads or 1,
                           address=None if args.address in (None, "local") else args.address, **train_overrides)
    else:
        env = make_vec(args.task, num_envs=args.envs, seed=args.seed, threads=args.threads, **train_overrides)
    eval_overrides = dict(overrides)
    if env.task.name == "navigation_task" and args.eval_level != "train":
        # Evaluated at one level, held (no curriculum steps): Aerial Gym reports its navigation
        # success at the curriculum's top level.
        task_over = dict(eval_overrides.get("task", {}))
        top = task_over.get("curriculum", {}).get("max_level", 10)  # CurriculumConfig's default
        level = top if args.eval_level == "top" else int(args.eval_level)
        task_over["curriculum"] = {**task_over.get("curriculum", {}), "start_level": level, "increase_step": 0,
                                   "decrease_step": 0}
        eval_overrides["task"] = task_over
    timer = _Timer(env)
    view = None
    if args.view:
        from .viewer import TrainView

        try:
            # Wraps env.step after the timer: the drawing is not counted as simulator time.
            view = TrainView(env, view_envs=args.view_envs, port=args.port, fps=args.view_fps)
        except ValueError as e:
            raise SystemExit(f"kestrel train: {e}")
        print(f"kestrel train: viewer at {view.url} (envs {view.envs})", flush=True)
    learner = Learner(args, env)
    rows: list[dict] = []
    t_train = 0.0
    done_steps = 0
    live_steps = 0  # env-steps of the updates so far (moves within a chunk)

    writer = None
    if args.tensorboard:
        from torch.utils.tensorboard import SummaryWriter

        writer = SummaryWriter(log_dir=args.out, flush_secs=5)
        writer.add_text("config", "    " + json.dumps({k: v for k, v in vars(args).items()}, indent=1).replace("\n", "\n    "), 0)

    log_f = open(os.path.join(args.out, "log.csv"), "w", newline="")
    log_w = None
    from tqdm import tqdm

    bar = tqdm(total=args.steps, unit="env-step", unit_scale=True, disable=not progress_enabled(args.quiet),
               desc=f"{args.learner} {args.task}")
    prev_infos = env.task.infos

    def on_update(n: int, scalars: dict) -> None:
        """After each learner update: the training envs' episodes since the last one, the learner's statistics."""
        nonlocal live_steps, prev_infos
        live_steps += n
        bar.update(n)
        inf = env.task.infos
        eps = inf["episodes"] - prev_infos["episodes"]
        if eps > 0:
            scalars["train/episodes"] = eps
            scalars["train/mean_episode_reward"] = (inf["episode_reward_sum"] - prev_infos["episode_reward_sum"]) / eps
            scalars["train/success_rate"] = (inf["successes"] - prev_infos["successes"]) / eps
            scalars["train/crash_rate"] = (inf["crashes"] - prev_infos["crashes"]) / eps
            bar.set_postfix(train_success=f"{scalars['train/success_rate']:.2f}", **last_eval, refresh=False)
        prev_infos = inf
        if writer is not None:
            for k, v in scalars.items():
                writer.add_scalar(k, v, live_steps)

    learner.on_update = on_update
    last_eval: dict = {}

    def eval_row() -> dict:
        nonlocal log_w
        t0 = time.perf_counter()
        res = evaluate(learner.policy(), args.task, args.eval_episodes, args.eval_seed, args.threads, **eval_overrides)
        row = {"env_steps": done_steps, "train_s": round(t_train, 3), "sim_s": round(timer.sim_s, 3), **asdict(res),
               "eval_s": round(time.perf_counter() - t0, 3), "train_level": env.task.infos.get("curriculum_level", 0),
               # locomotion_task on legged_gym's tiled terrain: the training envs' mean terrain level now.
               "train_terrain_level": round(float(env.task.infos.get("mean_terrain_level", 0.0)), 3)}
        rows.append(row)
        if log_w is None:
            log_w = csv.DictWriter(log_f, fieldnames=list(row.keys()))
            log_w.writeheader()
        log_w.writerow(row)
        log_f.flush()
        if writer is not None:
            for k in ("mean_return", "success_rate", "crash_rate", "mean_length", "final_distance_m"):
                if np.isfinite(row[k]):
                    writer.add_scalar(f"eval/{k}", row[k], done_steps)
            for k in ("train_s", "sim_s", "eval_s"):
                writer.add_scalar(f"time/{k}", row[k], done_steps)
            writer.flush()
        last_eval.clear()
        last_eval.update(eval_ret=f"{row['mean_return']:.0f}", eval_success=f"{row['success_rate']:.3f}")
        bar.set_postfix(**last_eval)
        return row

    row = eval_row()  # the untrained policy
    reached = None
    while done_steps < args.steps:
        chunk = min(args.eval_every, args.steps - done_steps)
        t0 = time.perf_counter()
        n = learner.train(chunk)
        t_train += time.perf_counter() - t0
        done_steps += n
        if live_steps != done_steps:  # the learner's updates did not all report
            bar.update(done_steps - live_steps)
            live_steps = done_steps
        row = eval_row()
        learner.save(os.path.join(args.out, "checkpoints", f"{args.learner}_{done_steps}.pt"))
        if args.target_success is not None and row["success_rate"] >= args.target_success:
            reached = row
            break
    bar.close()

    log_f.close()
    final_eval = None
    if args.final_eval_episodes:
        t0 = time.perf_counter()
        res = evaluate(learner.policy(), args.task, args.final_eval_episodes, args.eval_seed + 1, args.threads, **eval_overrides)
        final_eval = {**asdict(res), "seed": args.eval_seed + 1, "eval_s": round(time.perf_counter() - t0, 3)}
    exported = _export(learner, args, overrides) if args.export else None
    if writer is not None:
        writer.close()
    view_summary = None
    if view is not None:
        view_summary = {"url": view.url, "envs": view.envs, "env_step_calls": view.steps, "frames_drawn": view.frames_drawn,
                        "draw_s": round(view.draw_s, 3)}
        view.close()
    plot(rows, os.path.join(args.out, "curves.png"),
         f"{args.task} ({env.task.controller}), {args.learner}, {args.envs} envs, seed {args.seed}", args.target_success)
    summary = {"task": args.task, "controller": env.task.controller, "learner": args.learner, "envs": args.envs,
               "seed": args.seed, "action_scale": scale, "action_offset": offset,
               "action_repeat": args.action_repeat, "shaping": args.shaping, "obs_norm": args.obs_norm, "squash": args.squash,
               "vehicle_frame_obs": vframe, "rollout": args.rollout, "epochs": args.epochs,
               "minibatches": args.minibatches, "lr": args.lr, "gamma": args.gamma, "init_std": args.init_std,
               "entropy": args.entropy, "reward_scale": args.reward_scale, "eval_seed": args.eval_seed, "eval_episodes": args.eval_episodes,
               "env_steps": done_steps, "train_s": round(t_train, 2), "sim_s": round(timer.sim_s, 2),
               "sim_share": round(timer.sim_s / t_train, 3) if t_train > 0 else None,
               "target_success": args.target_success, "reached": reached, "final": rows[-1], "initial": rows[0],
               "final_eval": final_eval, "hidden": list(args.hidden), "rnn": list(args.rnn) if args.rnn else None,
               "sensors": args.sensors, "critic_sensors": args.critic_sensors, "task_set": args.task_set,
               "train_task_set": args.train_task_set, "resume": args.resume,
               "train_episodes": int(env.task.infos.get("episodes", 0)),
               "export": exported, "tensorboard": args.out if args.tensorboard else None, "cpu_count": os.cpu_count(),
               "view": view_summary}
    with open(os.path.join(args.out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=2)
    if not args.quiet:
        print(json.dumps({k: summary[k] for k in ("env_steps", "train_s", "sim_share", "final")}, indent=1))
    return summary


if __name__ == "__main__":
    main()
