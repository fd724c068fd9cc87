"""Tasks written in Python over the Simulator's views (issue 11: "a custom task whose observations,
rewards and terminations are written in Python over the world's arrays").

A ``PythonTask`` subclass says what the agent sees, what it is paid and when an episode ends, in
numpy over the Simulator's zero-copy views (``sim.base_pos_w``, ``sim.target_w``,
``sim.world_data()``, ``sim.range_images(k)``, ...). ``PythonTaskVectorEnv`` runs it as a
``gymnasium.vector.VectorEnv`` with Aerial Gym's same-step autoreset: the Simulator's own
auto-reset is off, so the task reads each ended episode's final state (final observation,
reward, flags) before the env resets those environments through ``Simulator.reset_idx``.

    class Hover(kestrel.PythonTask):
        observation_dim = 6
        def observations(self, sim):
            return np.concatenate([sim.target_w - sim.base_pos_w, sim.base_lin_vel_b], axis=1)
        def rewards(self, sim, actions):
            return -np.linalg.norm(sim.target_w - sim.base_pos_w, axis=1)
        def terminations(self, sim):
            return sim.world_data()["crashed"].astype(bool)

    env = kestrel.PythonTaskVectorEnv(Hover(), {"env": "empty", "controller": "lee_velocity_control"}, num_envs=64)

The physics, the controller and the episode bookkeeping (time limit, bounds) stay in C++; only
the task's three functions run in Python, once per step for all environments.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

import kestrel



def final_obs_infos(obs: np.ndarray, done: np.ndarray, infos: dict) -> np.ndarray:
    """Same-step autoreset's infos (as KestrelVectorEnv): ``final_obs`` holds the ended rows' last
    observations (zeros elsewhere), ``_final_obs`` the mask. Returns the ended rows' indices."""
    ids = np.flatnonzero(done)
    final = np.zeros_like(obs)
    final[ids] = obs[ids]
    infos["final_obs"], infos["_final_obs"] = final, done.copy()
    return ids

class PythonTask:
    """Override observations, rewards and (optionally) terminations; all take the Simulator and
    return one row per robot (robots_per_env must be 1). Truncation is the scenario's
    task.episode_len_env_steps; leaving the environment's bounds terminates."""

    observation_dim: int = 0
    action_low: float = -1.0
    action_high: float = 1.0

    def observations(self, sim: kestrel.Simulator) -> np.ndarray:
        raise NotImplementedError

    def rewards(self, sim: kestrel.Simulator, actions: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def terminations(self, sim: kestrel.Simulator) -> np.ndarray:
        return np.zeros(sim.num_envs, dtype=bool)


class PythonTaskVectorEnv(VectorEnv):
    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP}

    def __init__(self, task: PythonTask, scenario: Any = None, num_envs: int = 64, seed: int = 0, threads: int | None = None,
                 backend: str | None = None):
        if not isinstance(task, PythonTask):
            raise TypeError(f"task: expected a kestrel.PythonTask, got {type(task).__name__}")
        if task.observation_dim < 1:
            raise ValueError("task.observation_dim: expected a positive integer")
        self.task = task
        self._scenario, self._threads, self._backend = scenario, threads, backend
        self.num_envs = int(num_envs)
        self._build(seed)
        if self.sim.robots_per_env != 1:
            raise ValueError("scenario: a PythonTask drives one robot per environment (robot.robots_per_env: 1)")
        self.single_observation_space = spaces.Box(-np.inf, np.inf, (task.observation_dim,), np.float32)
        self.single_action_space = spaces.Box(task.action_low, task.action_high, (self.sim.action_dim,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)

    def _build(self, seed: int) -> None:
        self.sim = kestrel.make_simulator(self._scenario, num_envs=self.num_envs, seed=int(seed), threads=self._threads,
                                          backend=self._backend)
        self.sim.set_auto_reset(False)
        self._seed = int(seed)
        self._steps = np.zeros(self.num_envs, dtype=np.int64)
        self._len = self.sim.episode_len_env_steps
        self._fresh = True  # built from self._seed and not stepped since

    def _obs(self) -> np.ndarray:
        obs = np.asarray(self.task.observations(self.sim), dtype=np.float32)
        if obs.shape != (self.num_envs, self.task.observation_dim):
            raise ValueError(f"{type(self.task).__name__}.observations: expected shape ({self.num_envs}, "
                             f"{self.task.observation_dim}), got {obs.shape}")
        return obs

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        if seed is not None and not (self._fresh and int(seed) == self._seed):
            # Every stream is a function of (seed, env): reset(seed=s) rebuilds the world from s,
            # so the same seed gives the same episodes again (gymnasium's reset contract).
            self._build(seed)
        elif not self._fresh:
            self.sim.reset_idx(list(range(self.num_envs)))
        self._fresh = False
        self._steps[:] = 0
        return self._obs(), {}

    def step(self, actions):
        a = np.ascontiguousarray(np.clip(np.asarray(actions, dtype=np.float32), self.task.action_low, self.task.action_high))
        self.sim.step(a.astype(kestrel._core.real_dtype, copy=False))
        self._steps += 1
        rewards = np.asarray(self.task.rewards(self.sim, a), dtype=np.float32).reshape(self.num_envs)
        terminated = np.asarray(self.task.terminations(self.sim), dtype=bool).reshape(self.num_envs)
        # The Simulator flags the episodes it would end (time limit, bounds, crash with
        # reset_on_collision): bounds and crashes terminate, the time limit truncates.
        flagged = np.asarray(self.sim.reset_buf, dtype=bool)
        truncated = (self._steps >= self._len) & ~terminated
        terminated = terminated | (flagged & ~truncated)
        obs = self._obs()
        infos: dict = {}
        done = terminated | truncated
        if done.any():
            ids = final_obs_infos(obs, done, infos)
            self.sim.reset_idx(ids.tolist())
            self._steps[ids] = 0
            obs = self._obs()
        return obs, rewards, terminated, truncated, infos
