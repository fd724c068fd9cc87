"""Tasks written from Python the way LeIsaac (Isaac Lab's manager-based env) writes them: the scene's
entities by name, and observation, reward, termination and event (randomisation) terms as functions
of the scene, over a C++ task's worlds (so101_pick_place: Kestrel-SO101-PickPlace-v0).

    def cube_in_box(scene, xy=0.05, height=0.10):
        d = scene["cube"].pos_w - scene["box"].pos_w
        return (np.abs(d[:, 0]) < xy) & (np.abs(d[:, 1]) < xy) & (scene["cube"].pos_w[:, 2] < height)

    def randomize_object_uniform(scene, env_ids, rng, name, pose_range):
        ent = scene[name]
        pos = ent.default_pos_w[env_ids] + rng.uniform(*zip(*[pose_range.get(k, (0, 0)) for k in "xyz"]), (len(env_ids), 3))
        ent.set_pos(env_ids, pos)

    env = kestrel.SceneTask(
        base="Kestrel-SO101-PickPlace-v0", num_envs=64, scene="models/so101/pick_place_scene.usda",
        task={"pick_place": {"randomize_xy_m": 0}},          # the C++ reset's own draw off: the events draw
        terminations={"success": cube_in_box},
        events={"reset": [Term(randomize_object_uniform, params={"name": "cube", "pose_range": {"x": (-0.05, 0.05)}})]},
        rewards={"reach": Term(lambda s: -np.linalg.norm(s["cube"].pos_w - s["robot"].ee_pos_w, axis=1), weight=1.0)})

The scene (``env.scene``): ``scene["cube"]`` and ``scene["box"]`` (``pos_w`` (num_envs, 3),
``quat_xyzw`` (num_envs, 4), ``default_pos_w``, ``default_quat_xyzw``; ``set_pose(env_ids, pos,
quat)`` / ``set_pos(env_ids, pos)`` write), ``scene["robot"]`` (``joint_pos``, ``joint_vel``,
``joint_targets`` (num_envs, 6), ``ee_pos_w`` (num_envs, 3), ``ee_quat_xyzw`` (num_envs, 4),
``grip_force_N`` (num_envs,)). Names are case-insensitive. Every environment is its own world with
the robot's base at the origin, so positions are environment-local (Isaac Lab's env_origins are
zero here). The arrays are copies made once per step (after a write they are read again); the C++
task's own observations, rewards and flags stay readable as ``env.task.observations`` etc.

Terms: a callable or ``Term(fn, weight=1.0, params={})``; ``params`` are passed as keywords.
* observations: ``{name: fn(scene) -> (num_envs, k) or (num_envs,)}``, concatenated in order
  (float32). None: the C++ task's own observations (31 floats, sim/pick_place_task.hpp).
* rewards: ``{name: fn(scene) -> (num_envs,)}``, the sum of weight x term. None: the C++ task's
  shaped reward (its success bonus never fires: the C++ success rule is off in a SceneTask).
* terminations: ``{name: fn(scene) -> (num_envs,) bool}``, any ends the episode (terminated);
  ``episode_length`` (default: the scenario's task.episode_len_env_steps) truncates, as LeIsaac's
  time_out. None / {}: only the time limit. ``infos["terminations"][name]`` says which fired.
* events: ``{"startup": [...], "reset": [...]}``, ``fn(scene, env_ids, rng)`` with env_ids an int
  array and rng this env's ``numpy.random.Generator`` (seeded from the env's seed): startup once
  after the first build, reset after every reset of env_ids (after the C++ task's own reset,
  which draws the cube and box within +-task.pick_place.randomize_xy_m: set it to 0 when the
  events draw them).

The C++ task ends no episode by itself here (its success rule and time limit are turned off);
the env resets ended environments itself (Task.reset_idx), same-step autoreset as
``KestrelVectorEnv``: ``infos["final_obs"]`` holds the ended rows' last observations.
``env.scripted_actions()``: the C++ scripted pick and place for the current state (it re-plans
when an event moves an object).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

import kestrel
from kestrel.python_task import final_obs_infos

__all__ = ["SceneTask", "Term", "Scene"]

_NEVER = 1 << 30  # C++ episode length: never reached inside a SceneTask (its success is off: end_on_success)


@dataclass
class Term:
    """A term of a SceneTask: fn, its weight (rewards) and keyword params."""

    fn: Callable[..., Any]
    weight: float = 1.0
    params: dict = field(default_factory=dict)


def _term(name: str, t: Any) -> Term:
    if isinstance(t, Term):
        return t
    if callable(t):
        return Term(t)
    raise TypeError(f"term {name!r}: expected a callable or kestrel.scene_task.Term, got {type(t).__name__}")


class _Object:
    """The cube or the box of every environment."""

    def __init__(self, scene: "Scene", name: str):
        self._s, self.name = scene, name

    @property
    def pos_w(self) -> np.ndarray:
        """(num_envs, 3) m: the cube's centre; the box's floor's bottom-face centre."""
        return self._s._state()[f"{self.name}_pos_w"]

    @property
    def quat_xyzw(self) -> np.ndarray:
        """(num_envs, 4); the box is never rotated: (0, 0, 0, 1)."""
        if self.name == "box":
            q = np.zeros((self._s.num_envs, 4))
            q[:, 3] = 1.0
            return q
        return self._s._state()["cube_quat_xyzw"]

    @property
    def default_pos_w(self) -> np.ndarray:
        """(num_envs, 3): the scene's nominal position (before any randomisation)."""
        c = self._s.config
        p = np.array(c[f"{self.name}_pos_w"], dtype=np.float64)
        p[2] = c["cube_half_m"] if self.name == "cube" else 0.0
        return np.tile(p, (self._s.num_envs, 1))

    @property
    def default_quat_xyzw(self) -> np.ndarray:
        q = np.zeros((self._s.num_envs, 4))
        q[:, 3] = 1.0
        return q

    def set_pose(self, env_ids, pos, quat=None) -> None:
        """Writes the pose of env_ids (pos (k, 3) or (3,); quat (k, 4) or (4,), x y z w; None: the
        current orientation). The cube is set at rest; the box takes pos only (never rotated)."""
        ids = np.atleast_1d(np.asarray(env_ids, dtype=np.int64))
        pos = np.broadcast_to(np.asarray(pos, dtype=np.float64), (len(ids), 3))
        if quat is None:
            quat = self.quat_xyzw[ids]
        quat = np.broadcast_to(np.asarray(quat, dtype=np.float64), (len(ids), 4))
        for k, e in enumerate(ids.tolist()):
            self._s.task.set_object_pose(int(e), self.name, pos[k].tolist(), quat[k].tolist())
        self._s._dirty = True

    def set_pos(self, env_ids, pos) -> None:
        self.set_pose(env_ids, pos, None)


class _Robot:
    """The arm of every environment."""

    def __init__(self, scene: "Scene"):
        self._s = scene

    def _get(self, key: str) -> np.ndarray:
        return self._s._state()[key]

    joint_pos = property(lambda self: self._get("joint_pos"), doc="(num_envs, 6) rad")
    joint_vel = property(lambda self: self._get("joint_vel"), doc="(num_envs, 6) rad/s")
    joint_targets = property(lambda self: self._get("joint_targets"), doc="(num_envs, 6) rad: the last action's targets")
    ee_pos_w = property(lambda self: self._get("tcp_pos_w"), doc="(num_envs, 3) m: the tool centre point (gripper_frame)")
    ee_quat_xyzw = property(lambda self: self._get("tcp_quat_xyzw"), doc="(num_envs, 4), w >= 0")
    grip_force_N = property(lambda self: self._get("grip_force_N")[:, 0], doc="(num_envs,) N: the pads' force on the cube")


class Scene:
    """The entities of a so101_pick_place task by name: cube, box, robot."""

    def __init__(self, task: kestrel.Task):
        self.task = task
        self.num_envs = task.num_envs
        self.config = task.pick_place_config()
        self._cache: dict | None = None
        self._dirty = True
        self._entities = {"cube": _Object(self, "cube"), "box": _Object(self, "box"), "robot": _Robot(self)}

    def _state(self) -> dict:
        if self._dirty or self._cache is None:
            self._cache = self.task.pick_place_poses()
            self._dirty = False
        return self._cache

    def invalidate(self) -> None:
        self._dirty = True

    def keys(self):
        return self._entities.keys()

    def __getitem__(self, name: str):
        try:
            return self._entities[str(name).lower()]
        except KeyError:
            raise KeyError(f"scene: no entity {name!r}; entities: {', '.join(self._entities)}") from None

    @property
    def cube_in_box(self) -> np.ndarray:
        """(num_envs,) bool: the C++ world's cube_in_box (for comparison with Python terms)."""
        return self._state()["cube_in_box"]


class SceneTask(VectorEnv):
    """A gymnasium VectorEnv over a C++ task's worlds with Python terms (see the module)."""

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}

    def __init__(self, base: str = "Kestrel-SO101-PickPlace-v0", num_envs: int = 64, seed: int = 0, threads: int | None = None,
                 scene: Any = None, observations: Mapping[str, Any] | None = None, rewards: Mapping[str, Any] | None = None,
                 terminations: Mapping[str, Any] | None = None, events: Mapping[str, Any] | None = None,
                 episode_length: int | None = None, backend: str | None = None, **overrides: Any):
        if base in kestrel.GYM_IDS:
            task_id, defaults = kestrel.GYM_IDS[base]
        elif base in kestrel.task_ids():
            task_id, defaults = base, {}
        else:
            raise ValueError(f"base: unknown environment {base!r}; gymnasium ids: {', '.join(kestrel.GYM_IDS)}")
        if task_id != "so101_pick_place":
            raise ValueError(f"base: a SceneTask's scene (cube, box, robot) is so101_pick_place's; {base!r} is {task_id}")
        over = kestrel._merge(defaults, overrides)
        if scene is not None:
            over = kestrel._merge({"task": {"pick_place": {"scene_file": str(scene)}}}, over)
        # The C++ task never ends an episode here: this env's terms and time limit do.
        over = kestrel._merge(over, {"task": {"pick_place": {"end_on_success": False}}})
        self._task_id, self._over, self._threads, self._backend = task_id, over, threads, backend
        self.num_envs = int(num_envs)
        self._obs_terms = None if observations is None else {k: _term(k, v) for k, v in observations.items()}
        self._rew_terms = None if rewards is None else {k: _term(k, v) for k, v in rewards.items()}
        self._term_terms = {k: _term(k, v) for k, v in (terminations or {}).items()}
        ev = dict(events or {})
        bad = set(ev) - {"startup", "reset"}
        if bad:
            raise ValueError(f"events: unknown mode(s) {', '.join(sorted(bad))}; expected startup, reset")
        self._events = {m: [_term(f"{m}[{i}]", t) for i, t in enumerate(ev.get(m, []))] for m in ("startup", "reset")}
        self._episode_length = episode_length
        self._build(int(seed))
        od = self._obs().shape[1]
        self.single_observation_space = spaces.Box(-np.inf, np.inf, (od,), np.float32)
        lo, hi = self.task.action_bounds
        ad = self.task.action_dim
        self._lo, self._hi = np.asarray(lo, np.float32), np.asarray(hi, np.float32)
        self.single_action_space = spaces.Box(self._lo, self._hi, (ad,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.render_mode = None

    # ---- set-up -----------------------------------------------------------------------------------
    def _build(self, seed: int) -> None:
        cfg = kestrel.scenario(None, task_id=self._task_id, num_envs=self.num_envs, seed=seed, threads=self._threads, **self._over)
        self._len = int(self._episode_length or cfg.episode_len_env_steps)
        if self._len < 1:
            raise ValueError(f"episode_length: expected >= 1, got {self._len}")
        cfg.episode_len_env_steps = _NEVER
        self.task = kestrel.Task(cfg, self._backend or "")
        self.scene = Scene(self.task)
        self._seed = seed
        self.rng = np.random.default_rng([seed, 0x5CE7E])
        self._steps = np.zeros(self.num_envs, dtype=np.int64)
        all_ids = np.arange(self.num_envs)
        self._run_events("startup", all_ids)
        self._run_events("reset", all_ids)
        self._fresh = True

    def _run_events(self, mode: str, env_ids: np.ndarray) -> None:
        for t in self._events[mode]:
            t.fn(self.scene, env_ids, self.rng, **t.params)
            self.scene.invalidate()

    # ---- terms ------------------------------------------------------------------------------------
    def _obs(self) -> np.ndarray:
        if self._obs_terms is None:
            return np.array(self.task.observations, dtype=np.float32)
        cols = []
        for k, t in self._obs_terms.items():
            v = np.asarray(t.fn(self.scene, **t.params), dtype=np.float32)
            v = v.reshape(self.num_envs, -1) if v.ndim <= 2 else None
            if v is None or v.shape[0] != self.num_envs:
                raise ValueError(f"observations[{k!r}]: expected shape ({self.num_envs}, k) or ({self.num_envs},)")
            cols.append(v)
        return np.concatenate(cols, axis=1) if cols else np.zeros((self.num_envs, 0), np.float32)

    def _rewards(self) -> np.ndarray:
        if self._rew_terms is None:
            return np.array(self.task.rewards, dtype=np.float32)
        r = np.zeros(self.num_envs, np.float64)
        for k, t in self._rew_terms.items():
            v = np.asarray(t.fn(self.scene, **t.params), dtype=np.float64).reshape(-1)
            if v.shape != (self.num_envs,):
                raise ValueError(f"rewards[{k!r}]: expected shape ({self.num_envs},), got {v.shape}")
            r += t.weight * v
        return r.astype(np.float32)

    def _terminations(self) -> tuple[np.ndarray, dict]:
        out = np.zeros(self.num_envs, dtype=bool)
        fired = {}
        for k, t in self._term_terms.items():
            v = np.asarray(t.fn(self.scene, **t.params), dtype=bool).reshape(-1)
            if v.shape != (self.num_envs,):
                raise ValueError(f"terminations[{k!r}]: expected shape ({self.num_envs},), got {v.shape}")
            fired[k] = v
            out |= v
        return out, fired

    # ---- gymnasium API ----------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        if seed is not None and not (self._fresh and int(seed) == self._seed):
            self._build(int(seed))
        elif not self._fresh:
            ids = np.arange(self.num_envs)
            self.task.reset_idx(ids.tolist())
            self.scene.invalidate()
            self._run_events("reset", ids)
        self._fresh = False
        self._steps[:] = 0
        return self._obs(), {}

    def step(self, actions):
        a = np.ascontiguousarray(np.clip(np.asarray(actions, dtype=np.float32), self._lo, self._hi))
        self._fresh = False
        self.task.step(a)
        self.scene.invalidate()
        self._steps += 1
        rewards = self._rewards()
        terminated, fired = self._terminations()
        truncated = (self._steps >= self._len) & ~terminated
        obs = self._obs()
        infos: dict = {}
        done = terminated | truncated
        if done.any():
            ids = final_obs_infos(obs, done, infos)
            infos["terminations"] = fired
            self.task.reset_idx(ids.tolist())
            self.scene.invalidate()
            self._run_events("reset", ids)
            self._steps[ids] = 0
            obs = self._obs()
        return obs, rewards, terminated, truncated, infos

    def scripted_actions(self) -> np.ndarray:
        return self.task.scripted_actions()

    def close_extras(self, **kwargs: Any) -> None:
        self.task = None

    def __repr__(self) -> str:
        return f"SceneTask({self._task_id}, num_envs={self.num_envs})"
