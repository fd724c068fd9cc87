"""Thin adapters from a KestrelVectorEnv to the learners' own vector-env APIs, unchanged from PyPI:

- ``RslRlVecEnv``: rsl-rl-lib's ``rsl_rl.env.VecEnv`` (get_observations -> TensorDict, step ->
  (obs, rewards, dones, extras) with ``extras["time_outs"]`` for truncations).
- ``Sb3VecEnv``: Stable-Baselines3's ``VecEnv`` (reset / step_async / step_wait with per-env info
  dicts carrying ``terminal_observation``, ``TimeLimit.truncated`` and ``episode``).

Both hand the learner a copy of the observations: the env's arrays are views rewritten in place by
the next step, and both learners keep the previous step's observation object until after the next
step (rsl_rl's transition, SB3's ``_last_obs``). That copy is the only one per step.
"""

from __future__ import annotations

from typing import Any, Callable, Sequence

import numpy as np

from .vector_env import KestrelVectorEnv


def _success(info: dict, n: int) -> np.ndarray | None:
    s = info.get("success")
    return None if s is None else s


class RslRlVecEnv:
    """rsl_rl's VecEnv over a KestrelVectorEnv (observation group "policy", used by actor and critic;
    with `privileged`, a group "privileged" for the critic alone)."""

    def __new__(cls, *args, **kwargs):
        # Subclass rsl_rl.env.VecEnv lazily, so importing kestrel does not import torch/rsl_rl.
        from rsl_rl.env import VecEnv

        impl = type("KestrelRslRlVecEnv", (_RslRlImpl, VecEnv), {})
        return impl(*args, **kwargs)


class _RslRlImpl:
    def __init__(self, env: KestrelVectorEnv, device: str = "cpu", reward_scale: float = 1.0, squash: bool = False,
                 action_repeat: int = 1, distance_shaping: float = 0.0, gamma: float = 0.99,
                 privileged: Callable[[], np.ndarray] | None = None):
        import torch

        # privileged: a function giving (num_envs, k) float32 observations of the current state
        # for the critic alone (observation group "privileged"; the actor, its evaluation and its
        # export never see them): asymmetric actor-critic (L. Pinto et al., "Asymmetric Actor
        # Critic for Image-Based Robot Learning", RSS 2018), the value function told what the
        # policy's sensor cannot see.
        self._privileged = privileged

        # distance_shaping k (position setpoint): the learner's reward gets the potential-based term
        # gamma * Phi(s') - Phi(s) with Phi = -k * |target - position| (Ng, Harada & Russell 1999: the
        # optimal policy is unchanged). The task's own reward is flat (1/40 per m) until ~0.7 m from the
        # target, where its peak of ~30 per step is; with the shaping the first updates already pull
        # towards the target. The env's rewards (and every evaluation) are untouched.
        self.shaping = float(distance_shaping)
        self.gamma = float(gamma)
        # action_repeat k: each learner action is held for k env-steps (rewards summed; an env that
        # ends within them reports done with the reward up to its end, and its new episode's first
        # steps take the rest of that action). The learner decides at 1/k of the env rate: k times
        # fewer (and k times more consequential) decisions per env-step for its credit assignment,
        # and k times less learner time per env-step.
        self.action_repeat = max(1, int(action_repeat))
        # squash: the learner's (unbounded Gaussian) actions go through tanh into [-1, 1] instead of
        # being clamped (for normalised action spaces). With a clamp, a mean beyond the bound gets no
        # gradient and drifts; the deterministic policy clamp(mean) then saturates where the
        # stochastic one did not.
        self.squash = bool(squash)
        # rsl_rl has no value normalisation: the position setpoint reward (up to ~30 per step,
        # returns in the thousands) needs scaling, or the value loss dominates the clipped gradient.
        self.reward_scale = float(reward_scale)
        self._torch = torch
        self.env = env
        self.num_envs = env.num_envs
        self.num_actions = env.single_action_space.shape[0]
        self.max_episode_length = -(-env.task.episode_len_env_steps // self.action_repeat)
        self.episode_length_buf = torch.zeros(self.num_envs, dtype=torch.long)
        self.device = device
        self.cfg = {"task": env.task.name, "controller": env.task.controller, "num_envs": self.num_envs}
        # One bound for every component (most tasks), or one per component (so101_pick_place's joint ranges).
        low, high = env.single_action_space.low, env.single_action_space.high
        same = bool(np.all(low == low[0]) and np.all(high == high[0]))
        self._low = float(low[0]) if same else torch.as_tensor(low)
        self._high = float(high[0]) if same else torch.as_tensor(high)
        self._episodes = 0
        self._successes = 0

    def _obs(self, obs: np.ndarray):
        from tensordict import TensorDict

        groups = {"policy": self._torch.from_numpy(obs.copy())}
        if self._privileged is not None:
            groups["privileged"] = self._torch.from_numpy(np.ascontiguousarray(self._privileged(), dtype=np.float32))
        return TensorDict(groups, batch_size=[self.num_envs])

    def get_observations(self):
        return self._obs(self.env.current_observations)

    def reset(self):
        obs, _ = self.env.reset()
        self.episode_length_buf.zero_()
        return self._obs(obs), {}

    def step(self, actions):
        torch = self._torch
        a = actions.detach().to("cpu", torch.float32)
        a = (torch.tanh(a) if self.squash else a.clamp_(self._low, self._high)).contiguous().numpy()
        d0 = np.linalg.norm(self.env.current_observations[:, :3], axis=1) if self.shaping else None
        if self.action_repeat == 1:
            obs, rew, term, trunc, info = self.env.step(a)
            dones = np.logical_or(term, trunc)
            time_outs = trunc & ~term
            s = info.get("success")
            succ = None if s is None or not dones.any() else s[dones]
            rew = rew.copy()
            if self.shaping:
                d1 = np.linalg.norm(obs[:, :3], axis=1)
                if dones.any():
                    d1[dones] = np.linalg.norm(info["final_obs"][dones, :3], axis=1)
        else:
            total = np.zeros(self.num_envs)
            dones = np.zeros(self.num_envs, bool)
            time_outs = np.zeros(self.num_envs, bool)
            succ_l = []
            d_end = np.zeros(self.num_envs)
            for _ in range(self.action_repeat):
                obs, rew, term, trunc, info = self.env.step(a)
                total += np.where(dones, 0.0, rew)
                ended = np.logical_or(term, trunc) & ~dones
                if ended.any():
                    if self.shaping:
                        d_end[ended] = np.linalg.norm(info["final_obs"][ended, :3], axis=1)
                    time_outs |= ended & trunc & ~term
                    if "success" in info:
                        succ_l.append(info["success"][ended])
                    dones |= ended
            succ = np.concatenate(succ_l) if succ_l else None
            rew = total.astype(np.float32)
            if self.shaping:
                d1 = np.where(dones, d_end, np.linalg.norm(obs[:, :3], axis=1))
        if self.shaping:
            rew = rew + (self.shaping * (d0 - self.gamma * d1)).astype(np.float32)
        self.episode_length_buf += 1
        d = torch.from_numpy(dones)
        self.episode_length_buf[d] = 0
        extras: dict[str, Any] = {"time_outs": torch.from_numpy(time_outs).float(), "log": {}}
        if succ is not None and len(succ):
            extras["log"]["/success_rate"] = float(succ.mean())
        r = torch.from_numpy(rew)
        if self.reward_scale != 1.0:
            r.mul_(self.reward_scale)
        return self._obs(obs), r, d.long(), extras


class Sb3VecEnv:
    """Stable-Baselines3's VecEnv over a KestrelVectorEnv."""

    def __new__(cls, *args, **kwargs):
        from stable_baselines3.common.vec_env import VecEnv

        impl = type("KestrelSb3VecEnv", (_Sb3Impl, VecEnv), {})
        return impl(*args, **kwargs)


class _Sb3Impl:
    def __init__(self, env: KestrelVectorEnv):
        self.env = env
        super().__init__(env.num_envs, env.single_observation_space, env.single_action_space)  # SB3 VecEnv.__init__
        self._actions = None
        self._ret = np.zeros(env.num_envs)
        self._len = np.zeros(env.num_envs, dtype=np.int64)

    def reset(self):
        seed = self._seeds[0] if self._seeds and self._seeds[0] is not None else None
        obs, _ = self.env.reset(seed=seed)
        self._reset_seeds()
        self._reset_options()
        self._ret[:] = 0
        self._len[:] = 0
        return obs.copy()

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.ascontiguousarray(actions, dtype=np.float32)

    def step_wait(self):
        obs, rew, term, trunc, info = self.env.step(self._actions)
        dones = np.logical_or(term, trunc)
        self._ret += rew
        self._len += 1
        infos: list[dict] = [{} for _ in range(self.num_envs)]
        if dones.any():
            final = info["final_obs"] if "final_obs" in info else None
            s = info.get("success")
            for i in np.flatnonzero(dones):
                d = infos[i]
                if final is not None:
                    d["terminal_observation"] = final[i].copy()
                d["TimeLimit.truncated"] = bool(trunc[i] and not term[i])
                d["episode"] = {"r": float(self._ret[i]), "l": int(self._len[i])}
                if s is not None:
                    d["is_success"] = bool(s[i])
            self._ret[dones] = 0
            self._len[dones] = 0
        return obs.copy(), rew.copy(), dones, infos

    def close(self) -> None:
        self.env.close()

    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        return [getattr(self.env, attr_name)] * len(self._idx(indices))

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        setattr(self.env, attr_name, value)

    def env_method(self, method_name: str, *args, indices=None, **kwargs) -> list[Any]:
        return [getattr(self.env, method_name)(*args, **kwargs)] * len(self._idx(indices))

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return [False] * len(self._idx(indices))

    def _idx(self, indices) -> Sequence[int]:
        if indices is None:
            return range(self.num_envs)
        return [indices] if isinstance(indices, int) else list(indices)
