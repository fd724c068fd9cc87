"""A Kestrel task as a ``gymnasium.vector.VectorEnv`` (gymnasium 1.x API).

The C++ task steps every environment at once and resets the ones that ended inside ``step``
(Aerial Gym's behaviour), so the env declares ``AutoresetMode.SAME_STEP``: after a step that ended
environment i, ``obs[i]`` is its next episode's first observation, ``infos["final_obs"][i]`` the
observation that ended the episode and ``infos["_final_obs"][i]`` is True. Terminated (crash,
success where the task ends on it) and truncated (episode length reached) are kept apart.

Zero-copy: ``obs``, ``rewards``, ``terminated``, ``truncated`` and ``infos["final_obs"]`` are numpy
views of the task's own buffers, rewritten in place by the next step (copy them to keep them; the
learners' adapters copy into their rollout buffers anyway). Actions must be a C-contiguous float32
array of shape (num_envs, action_dim); they are read in place.

gymnasium's observation wrappers (NormalizeObservation, ...) accept only NEXT_STEP or DISABLED
envs (they could not transform ``final_obs``): ``autoreset_mode="next_step"`` gives gymnasium's
NEXT_STEP semantics instead. The step that ends environment i returns its final observation in
``obs[i]`` (obs is then a copy: a persistent buffer with those rows replaced), and the next step
ignores i's action for the caller: the C++ task has already started i's next episode, so after
stepping it the env resets i once more (Task.reset_idx) and returns that episode's first
observation with reward 0 and both flags False. The task's own counters (task_infos) then include
the rare episode that ended inside that discarded step.

Episode statistics: wrap with ``gymnasium.wrappers.vector.RecordEpisodeStatistics`` for
``infos["episode"]`` (r, l, t) and its mask; the env itself adds ``infos["success"]`` (position
setpoint: episode truncated within the task's success radius) and ``infos["kestrel"]`` (the task's
running totals) to the infos of steps where an episode ended.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
import gymnasium
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

import kestrel

def _LEGGED_GYM_JOINTS(robot: str) -> dict:
    return {"name": robot, "joint_damping_Nms_rad": 0.0, "joint_friction_loss_Nm": 0.0, "joint_armature_kg_m2": 0.0}


# Gymnasium id -> (task id, default section overrides).
GYM_IDS: dict[str, tuple[str, dict]] = {
    # Aerial Gym's position_setpoint_task through Lee velocity control: [vx, vy, vz] (m/s, vehicle
    # frame) and yaw rate (rad/s); the fastest of the three action spaces to train here.
    # Start yaw in +-pi/6 as Aerial Gym's base quadrotor (the registered robot draws it in +-pi).
    "Kestrel-PositionSetpoint-v0": ("position_setpoint_task", {"controller": "lee_velocity_control",
                                                               "robot": {"name": "base_quadrotor", "max_init_yaw_rad": 0.5235988}}),
    # ... through Lee position control with setpoints relative to the robot (world frame): the
    # easiest action space (the scripted policy is action = obs[0:3]); the training test uses it.
    "Kestrel-PositionSetpointPosition-v0": ("position_setpoint_task", {"controller": "lee_position_control"}),
    # ... through Aerial Gym's shipped lee_attitude_control: [thrust, roll, pitch, yaw_rate].
    "Kestrel-PositionSetpointAttitude-v0": ("position_setpoint_task", {"controller": "lee_attitude_control"}),
    # ... with direct motor commands (end-to-end).
    "Kestrel-PositionSetpointMotors-v0": ("position_setpoint_task", {"controller": "direct_motor_control"}),
    # navigation_task's own scene, robot start included (the reference's init_config: facing the
    # goal's end within +-pi/6, velocities and rates within +-0.2).
    "Kestrel-Navigation-v0": ("navigation_task", {}),
    "Kestrel-GoalBoxThroughGap-v0": ("goal_box_through_gap", {}),
    # legged_gym's locomotion task (locomotion_task) with each robot's rewards: the registered task
    # presets locomotion_go2 (LeggedGym-Ex's Go2 scales) and locomotion_anymal_c_flat / _rough
    # (legged_gym's configs); `kestrel list` describes them.
    # The robots' joints as legged_gym's assets have them: no passive damping, dry friction or
    # rotor inertia (the MJCF files carry MuJoCo Menagerie's; Go2's damping of 2 N m s/rad is four
    # times the drive's kd, and an open-loop trot then barely moves the robot).
    "Kestrel-Go2-Flat-v0": ("locomotion_task", {"robot": _LEGGED_GYM_JOINTS("go2"), "env": "legged_flat", "task": "locomotion_go2"}),
    # Rough: legged_gym's tiled terrain with its curriculum, and its ground-friction randomisation
    # (domain_rand.randomize_friction, friction_range [0.5, 1.25]).
    "Kestrel-Go2-Rough-v0": ("locomotion_task", {"robot": _LEGGED_GYM_JOINTS("go2"), "env": "legged_rough", "task": "locomotion_go2",
                                                 "simulator": {"name": "rigid", "friction": [0.5, 1.25]}}),
    "Kestrel-AnymalC-Flat-v0": ("locomotion_task", {"robot": _LEGGED_GYM_JOINTS("anymal_c"), "env": "legged_flat",
                                                    "task": "locomotion_anymal_c_flat"}),
    "Kestrel-AnymalC-Rough-v0": ("locomotion_task", {"robot": _LEGGED_GYM_JOINTS("anymal_c"), "env": "legged_rough",
                                                     "task": "locomotion_anymal_c_rough", "simulator": {"name": "rigid", "friction": [0.5, 1.25]}}),
    # LeIsaac's SO-101 pick-and-place (so101_pick_place, sim/pick_place_task.hpp): 31 state
    # observations, 6 absolute joint targets bounded by the joint ranges; task={"pick_place":
    # {"action_mode": "ee_delta"}} for the teleoperation action space (5: tcp delta, yaw delta, gripper).
    "Kestrel-SO101-PickPlace-v0": ("so101_pick_place", {}),
}


def _action_bound(task: str, controller: str) -> float:
    """The range the task clips each action to (the action space's bounds)."""
    if task == "position_setpoint_task":
        return 10.0  # Aerial Gym's robot clips actions to +-10 (task.hpp)
    if task == "locomotion_task":
        return 100.0  # legged_gym's clip_actions: joint targets are home + action_scale x action
    if controller == "lee_position_control":
        return 10.0
    return 1.0  # navigation_task and the custom tasks: normalised actions in [-1, 1]


class KestrelVectorEnv(VectorEnv):
    """``num_envs`` environments of one Kestrel task stepped in C++ on ``threads`` threads."""

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}

    def __init__(self, task_id: str = "position_setpoint_task", num_envs: int | None = 1024, seed: int = 0,
                 threads: int | None = None, scenario: Any = None, backend: str | None = None,
                 render_mode: str | None = None, autoreset_mode: str | AutoresetMode = AutoresetMode.SAME_STEP,
                 action_scale: Any = None, vehicle_frame_obs: bool = False, action_offset: Any = None,
                 **overrides: Any):
        names = {"same_step": AutoresetMode.SAME_STEP, "next_step": AutoresetMode.NEXT_STEP,
                 "samestep": AutoresetMode.SAME_STEP, "nextstep": AutoresetMode.NEXT_STEP}
        mode = autoreset_mode if isinstance(autoreset_mode, AutoresetMode) else names.get(str(autoreset_mode).lower())
        if mode not in (AutoresetMode.SAME_STEP, AutoresetMode.NEXT_STEP):
            raise ValueError(f"autoreset_mode: expected same_step or next_step, got {autoreset_mode!r}")
        self.metadata = dict(self.metadata, autoreset_mode=mode)
        self._next_step = mode == AutoresetMode.NEXT_STEP
        if render_mode is not None:
            raise ValueError(f"render_mode: Kestrel vector envs do not render; expected None, got {render_mode!r}")
        self._task_id, self._scenario, self._backend = task_id, scenario, backend
        self._overrides, self._threads = overrides, threads
        self._num_envs_req = None if num_envs is None else int(num_envs)  # None: the scenario's
        self._seed = int(seed)
        self._build(self._seed)
        self.num_envs = self.task.num_envs
        od, ad = self.task.obs_dim, self.task.action_dim
        self.single_observation_space = spaces.Box(-np.inf, np.inf, (od,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        bound = _action_bound(self.task.name, self.task.controller)
        # action_scale (opt-in, a number or one per action): a normalised action space [-1, 1]
        # that step() clips and multiplies by action_scale before the task sees it (Aerial Gym's
        # action transformation), e.g. Lee velocity control [2, 2, 2, 1] -> +-2 m/s, +-1 rad/s.
        # A learner with a unit-variance initial policy then explores in a sensible range
        # instead of the task's +-10 clip. None: the task's own actions and bounds.
        self._scale = None
        if action_scale is not None:
            sc = np.broadcast_to(np.asarray(action_scale, np.float32), (ad,)).copy()
            if not np.all(np.isfinite(sc)) or np.any(sc <= 0):
                raise ValueError(f"action_scale: expected positive finite values, got {action_scale!r}")
            self._scale = sc
            self._scaled = np.empty((self.task.num_envs, ad), np.float32)
            bound = 1.0
        self.action_scale = None if self._scale is None else self._scale.copy()
        # action_offset (with action_scale only, a number or one per action): the task is given
        # offset + scale * clip(a, -1, 1), so a normalised action of 0 can mean something other
        # than the task's 0. Direct motor commands: offset = hover thrust per motor, so the zero
        # action hovers (the task's zero action is motors off: the robot falls).
        self._offset = None
        if action_offset is not None:
            if self._scale is None:
                raise ValueError("action_offset: only with action_scale (a normalised action space)")
            off = np.broadcast_to(np.asarray(action_offset, np.float32), (ad,)).copy()
            if not np.all(np.isfinite(off)):
                raise ValueError(f"action_offset: expected finite values, got {action_offset!r}")
            self._offset = off
        self.action_offset = None if self._offset is None else self._offset.copy()
        # vehicle_frame_obs (opt-in, position setpoint only): observations 0-2 (target - position,
        # world frame) rotated about world z by -yaw into the vehicle frame, the frame in which
        # Lee velocity control reads [vx, vy, vz] (the same rotation as the reward's
        # vehicle_frame_error). The policy a = clip(e_vehicle) then flies straight at the target;
        # with the world-frame error a start yaw of up to pi/6 makes it spiral in, and a small MLP
        # must learn the yaw rotation from the quaternion. The returned observations are then a
        # copy (final_obs too); the norm of 0-2, the distance, is unchanged.
        self._vehicle_frame = bool(vehicle_frame_obs)
        if self._vehicle_frame and not self._is_setpoint:
            raise ValueError("vehicle_frame_obs: only for position_setpoint_task")
        per = self.task.action_bounds  # per-component bounds (so101_pick_place: the joint ranges)
        if per is not None and self._scale is None:
            self.single_action_space = spaces.Box(np.asarray(per[0], np.float32), np.asarray(per[1], np.float32), (ad,), np.float32)
        else:
            self.single_action_space = spaces.Box(-bound, bound, (ad,), np.float32)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.render_mode = None
        self.closed = False

    # ---- set-up ------------------------------------------------------------------------------
    def _build(self, seed: int) -> None:
        if self._scenario is not None and not isinstance(self._scenario, dict):
            self.task = kestrel.make_task(None, scenario=self._scenario, num_envs=self._num_envs_arg(), seed=seed,
                                          threads=self._threads, backend=self._backend)
        else:
            self.task = kestrel.make_task(self._task_id, scenario=self._scenario, num_envs=self._num_envs_arg(), seed=seed,
                                          threads=self._threads, backend=self._backend, **self._overrides)
        t = self.task
        # Views of the task's buffers, made once: the same memory for the task's lifetime.
        self._obs, self._final_obs = t.observations, t.final_observations
        self._rewards, self._terminated, self._truncated = t.rewards, t.terminations, t.truncations
        self._ended = np.zeros(t.num_envs, dtype=bool)
        self._out = np.empty_like(self._obs)  # next_step mode: obs with final rows
        self._pending: list[int] = []
        self._radius = t.success_radius_m
        self._is_setpoint = t.name == "position_setpoint_task"
        self._obs_vf = np.empty_like(self._obs)
        self._final_vf = np.empty_like(self._obs)

    def _vf(self, src: np.ndarray, dst: np.ndarray) -> np.ndarray:
        """src with columns 0-2 rotated into the vehicle frame (yaw as get_euler_xyz), into dst."""
        if not self._vehicle_frame:
            return src
        np.copyto(dst, src)
        x, y, z, w = src[:, 3], src[:, 4], src[:, 5], src[:, 6]
        yaw = np.arctan2(2 * (w * z + x * y), w * w + x * x - y * y - z * z)
        c, s = np.cos(yaw), np.sin(yaw)
        dst[:, 0] = c * src[:, 0] + s * src[:, 1]
        dst[:, 1] = -s * src[:, 0] + c * src[:, 1]
        return dst

    def _num_envs_arg(self) -> int | None:
        return self._num_envs_req

    # ---- gymnasium API -------------------------------------------------------------------------
    def reset(self, *, seed: int | list | None = None, options: dict | None = None):
        """Resets every environment. A new seed (an int, or a list whose first entry is used)
        rebuilds the task with that seed: the same seed gives the same episodes, whatever the
        thread count. options: {"env_ids": [...]} resets only those environments."""
        if isinstance(seed, (list, tuple)):
            seed = seed[0] if len(seed) else None
        if seed is not None and int(seed) != self.task.seed:
            self._seed = int(seed)
            self._build(self._seed)
        elif options and "env_ids" in options:
            self.task.reset_idx([int(i) for i in options["env_ids"]])
            self._pending = [i for i in self._pending if i not in set(options["env_ids"])]
            return self._vf(self._obs, self._obs_vf), {}
        else:
            self.task.reset()
        self._pending = []
        return self._vf(self._obs, self._obs_vf), {}

    def step(self, actions):
        if self._scale is not None:
            a = self._scaled
            np.clip(actions, -1.0, 1.0, out=a)
            a *= self._scale
            if self._offset is not None:
                a += self._offset
            actions = a
        any_ended = self.task.step(actions)
        if self._pending:  # next_step mode: the envs that ended last step start their episode now
            self.task.reset_idx(self._pending)
            self._pending = []
            any_ended = bool(self._terminated.any() or self._truncated.any())
        term, trunc = self._terminated, self._truncated
        if not any_ended:
            return self._vf(self._obs, self._obs_vf), self._rewards, term, trunc, {}
        ended = self._ended
        np.logical_or(term, trunc, out=ended)
        infos: dict[str, Any] = {"final_obs": self._vf(self._final_obs, self._final_vf), "_final_obs": ended.copy()}
        if self._is_setpoint:
            d = np.linalg.norm(self._final_obs[:, :3], axis=1)
            infos["success"] = ended & trunc & (d < self._radius)
            infos["_success"] = infos["_final_obs"]
        if self._next_step:
            out = self._out
            np.copyto(out, self._vf(self._obs, self._obs_vf))
            out[ended] = infos["final_obs"][ended]
            self._pending = np.flatnonzero(ended).tolist()
            del infos["final_obs"], infos["_final_obs"]
            return out, self._rewards, term, trunc, infos
        return self._vf(self._obs, self._obs_vf), self._rewards, term, trunc, infos

    def close_extras(self, **kwargs: Any) -> None:
        self.task = None

    # ---- extras --------------------------------------------------------------------------------
    @property
    def state_hash(self) -> int:
        return self.task.state_hash

    @property
    def current_observations(self) -> np.ndarray:
        """The observations the last reset/step returned (same-step mode), as the learner sees them."""
        return self._vf(self._obs, self._obs_vf)

    @property
    def task_infos(self) -> dict:
        """The task's running episode statistics (episodes, crashes, successes, ...)."""
        return self.task.infos

    def scripted_actions(self) -> np.ndarray:
        a = self.task.scripted_actions()
        if self._scale is None:
            return a
        off = 0.0 if self._offset is None else self._offset
        return np.ascontiguousarray((a - off) / self._scale, dtype=np.float32)

    def __repr__(self) -> str:
        return f"KestrelVectorEnv({self.task.name if self.task else self._task_id}, num_envs={self.num_envs})"


def _make(task_id: str, defaults: dict, num_envs: int | None = 1024, seed: int = 0, threads: int | None = None, **kwargs: Any):
    # Section overrides merge into the id's own (task={"episode_len_env_steps": 20} on top of the
    # id's `task: locomotion_go2` keeps the preset), as kestrel.scenario merges them.
    over = kestrel._merge(defaults, kwargs)
    return KestrelVectorEnv(task_id=task_id, num_envs=num_envs, seed=seed, threads=threads, **over)


def make_vec(id: str, num_envs: int = 1024, seed: int = 0, threads: int | None = None, scene: Any = None,
             **overrides: Any) -> KestrelVectorEnv:
    """A Kestrel vector env by gymnasium id (GYM_IDS) or task id (kestrel.task_ids()), with section
    overrides (controller=..., env={...}, task={...}, scenario=..., backend=...).

    scene (so101_pick_place): a USD scene file (models/so101/pick_place_scene.usda and its kind)
    mapped onto task.pick_place's scene keys by kestrel.pick_place_scene (the same as the override
    task={"pick_place": {"scene_file": path}}); keys given in task={"pick_place": {...}} win."""
    if scene is not None:
        if overrides.get("scenario") is not None and not isinstance(overrides["scenario"], dict):
            raise ValueError("scene: give it with section overrides or a dict scenario, not a scenario file or text "
                             "(or write task.pick_place.scene_file in a dict)")
        overrides = kestrel._merge({"task": {"pick_place": {"scene_file": os.fspath(scene)}}}, overrides)
    if id in GYM_IDS:
        task_id, defaults = GYM_IDS[id]
    elif id in kestrel.task_ids():
        task_id, defaults = id, {}
    else:
        raise ValueError(f"id: unknown environment {id!r}; gymnasium ids: {', '.join(GYM_IDS)}; "
                         f"task ids: {', '.join(kestrel.task_ids())}")
    return _make(task_id, defaults, num_envs=num_envs, seed=seed, threads=threads, **overrides)


def _entry(gym_id: str):
    def create(num_envs: int = 1024, seed: int = 0, threads: int | None = None, **kwargs: Any) -> KestrelVectorEnv:
        return make_vec(gym_id, num_envs=num_envs, seed=seed, threads=threads, **kwargs)
    return create


def register_envs() -> None:
    """Registers GYM_IDS with gymnasium (vector entry points: gymnasium.make_vec(id, num_envs=N))."""
    for gym_id in GYM_IDS:
        if gym_id not in gymnasium.registry:
            gymnasium.register(id=gym_id, vector_entry_point=_entry(gym_id))
