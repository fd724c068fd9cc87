"""kestrel.so101_teleop: teleoperation of the SO-101 pick-and-place task (LeIsaac's
teleop_se3_agent.py): a device (KeyboardTeleop, or kestrel.feetech.So101Leader) drives a gymnasium
VectorEnv, optionally recording LeRobot episodes (kestrel.lerobot_record.LeRobotWriter).

The env (Kestrel-SO101-PickPlace-v0) has two action modes, chosen by `set_action_mode(env, mode)`
(env.set_action_mode(mode) when it has one, else env.unwrapped.action_mode = mode):
  "joint": 6 absolute joint targets (rad): shoulder_pan, shoulder_lift, elbow_flex, wrist_flex,
           wrist_roll, gripper                                           (the leader arm)
  "ee":    tcp position delta (3, m), yaw delta (1, rad), gripper target (1, rad)   (the keyboard; IK)
Observations: `joint_state(obs, info, i)` is obs["joint_pos"][i] (obs a dict) or obs[i, :6]; camera
frames are obs["images"][cam][i] or obs[f"images.{cam}"][i] ((h, w, 3) uint8). In "ee" mode the
recorded action is the joint targets the env resolved, info["joint_targets"][i], so that every
dataset's actions are joint targets (LeRobot's so101 features) and replay in "joint" mode reproduces it.

Keyboard (LeIsaac's SO101Keyboard key map; a held key acts every control step):
    W / S   forward / backward          0.01 m per step   (LeIsaac: along the gripper's z axis)
    A / D   left / right                0.01 m per step   (LeIsaac: shoulder_pan -/+ 0.2 rad)
    Q / E   up / down                   0.01 m per step   (LeIsaac: along the gripper's x axis)
    J / L   yaw left / right            0.15 rad per step
    I / K   pitch up / down             0.15 rad per step (LeIsaac; no pitch in the ee action mode: ignored)
    U / O   gripper open / close        0.2 rad per step of the gripper target
    B start control (and recording), R reset: task failed (episode discarded),
    N reset: task succeeded (episode saved)
Here the deltas are in the robot base frame (the env's ee mode), LeIsaac's in the gripper frame.
"""
from __future__ import annotations

import math
from typing import Any, Callable, Mapping, Sequence

import numpy as np

SO101_GRIPPER_RANGE = (math.radians(-10.0), math.radians(100.0))


class KeyboardTeleop:
    """Pressed keys -> the ee action (dx, dy, dz, dyaw, gripper_target) per control step; no display
    needed: feed it press(key) / release(key) from any source (a terminal, the viewer's page, tests)."""

    mode = "ee"
    POS, ROT, JOINT = 0.01, 0.15, 0.20  # LeIsaac's pos / rot / joint sensitivities per step
    # key -> (axis, sign): axes 0..2 tcp x/y/z, 3 yaw, 4 pitch (ignored), 5 gripper
    KEYMAP = {"W": (0, +1), "S": (0, -1), "A": (1, +1), "D": (1, -1), "Q": (2, +1), "E": (2, -1),
              "J": (3, +1), "L": (3, -1), "I": (4, +1), "K": (4, -1), "U": (5, +1), "O": (5, -1)}

    def __init__(self, sensitivity: float = 1.0, gripper_range: tuple[float, float] = SO101_GRIPPER_RANGE,
                 gripper_target: float | None = None):
        self.sensitivity = sensitivity
        self.gripper_range = gripper_range
        self.gripper_target = gripper_range[1] if gripper_target is None else gripper_target
        self.held: set[str] = set()
        self.started = False
        self.reset_request: str | None = None  # "failure" (R) / "success" (N), consumed by take_reset()
        self.callbacks: dict[str, Callable[[], None]] = {}

    def press(self, key: str) -> None:
        k = key.upper()
        if k in self.KEYMAP:
            self.held.add(k)
        elif k == "B":
            self.started = True
        elif k in ("R", "N"):
            self.started = False
            self.reset_request = "failure" if k == "R" else "success"
        if k in self.callbacks:
            self.callbacks[k]()

    def release(self, key: str) -> None:
        self.held.discard(key.upper())

    def take_reset(self) -> str | None:
        r, self.reset_request = self.reset_request, None
        return r

    def reset(self, gripper_position: float | None = None) -> None:
        """After an env reset: no held keys; the gripper target follows the gripper's position."""
        self.held.clear()
        if gripper_position is not None:
            self.gripper_target = float(gripper_position)

    def action(self, observation: Any = None) -> np.ndarray:
        """(dx, dy, dz, dyaw, gripper_target) for this step from the held keys."""
        d = np.zeros(6)
        for k in self.held:
            axis, sign = self.KEYMAP[k]
            d[axis] += sign
        s = self.sensitivity
        self.gripper_target = float(np.clip(self.gripper_target + d[5] * self.JOINT * s, *self.gripper_range))
        return np.array([d[0] * self.POS * s, d[1] * self.POS * s, d[2] * self.POS * s, d[3] * self.ROT * s,
                         self.gripper_target])


def set_action_mode(env, mode: str) -> None:
    if hasattr(env, "set_action_mode"):
        env.set_action_mode(mode)
    elif hasattr(getattr(env, "unwrapped", env), "action_mode"):
        env.unwrapped.action_mode = mode


def joint_state(obs, info, i: int = 0) -> np.ndarray:
    if isinstance(obs, Mapping):
        return np.asarray(obs["joint_pos"][i], dtype=np.float32)
    return np.asarray(obs, dtype=np.float32)[i, :6]


def camera_frames(obs, cameras: Sequence[str], i: int = 0) -> dict[str, np.ndarray]:
    out = {}
    for cam in cameras:
        if isinstance(obs, Mapping) and "images" in obs:
            out[cam] = np.asarray(obs["images"][cam][i])
        else:
            out[cam] = np.asarray(obs[f"images.{cam}"][i])
    return out


def teleop_loop(env, device, steps: int, recorder=None, *, task: str | None = None, seed: int | None = None,
                env_index: int = 0, cameras: Sequence[str] | None = None, on_step: Callable | None = None) -> dict:
    """Runs `steps` control steps of `env` driven by `device` (an object with .mode "joint"/"ee" and
    .action(obs) -> the action of env `env_index`, e.g. KeyboardTeleop or So101Leader); the other
    envs get the same action. With a recorder (LeRobotWriter), each started step is a frame
    (state before the step, the joint-target action, camera frames, task); an episode is saved when
    the device asks for a success reset (N) or the env ends it (terminated/truncated), discarded on
    a failure reset (R). Devices without `started` are always started. Returns counts."""
    from .lerobot_record import DEFAULT_TASK

    task = task or DEFAULT_TASK
    if cameras is None and recorder is not None:
        cameras = [k.split(".", 2)[2] for k, ft in recorder.features.items() if ft["dtype"] == "image"]
    set_action_mode(env, device.mode)
    n_envs = getattr(env, "num_envs", 1)
    ep_seed = seed
    obs, info = env.reset(seed=ep_seed)
    stats = {"steps": 0, "frames": 0, "saved": 0, "discarded": 0}

    def new_episode(save: bool):
        nonlocal obs, info, ep_seed
        if recorder is not None and recorder.episode_frames:
            if save:
                recorder.save_episode(extra={"seed": ep_seed})
                stats["saved"] += 1
            else:
                recorder.clear_episode()
                stats["discarded"] += 1
        ep_seed = None if ep_seed is None else ep_seed + 1
        obs, info = env.reset(seed=ep_seed)
        if hasattr(device, "reset"):
            q = joint_state(obs, info, env_index)
            device.reset(gripper_position=float(q[5])) if isinstance(device, KeyboardTeleop) else device.reset()

    for _ in range(steps):
        req = device.take_reset() if hasattr(device, "take_reset") else None
        if req is not None:
            new_episode(save=req == "success")
            continue
        started = getattr(device, "started", True)
        state = joint_state(obs, info, env_index)
        a = np.asarray(device.action(obs), dtype=np.float32) if started else None
        if a is None:  # not started: hold (zero deltas / the current joints)
            a = (np.array([0, 0, 0, 0, state[5]], np.float32) if device.mode == "ee" else state.copy())
        batch = np.repeat(a[None], n_envs, axis=0)
        frame_images = camera_frames(obs, cameras, env_index) if (recorder is not None and started) else {}
        obs_next, _, term, trunc, info = env.step(batch)
        if recorder is not None and started:
            if device.mode == "ee":
                if "joint_targets" not in info:
                    raise KeyError("recording in the ee action mode needs info['joint_targets'] (the IK's joint targets)")
                joint_action = np.asarray(info["joint_targets"][env_index], dtype=np.float32)
            else:
                joint_action = a
            frame = {"observation.state": state, "action": joint_action}
            frame.update({f"observation.images.{c}": im for c, im in frame_images.items()})
            recorder.add_frame(frame, task=task)
            stats["frames"] += 1
        obs = obs_next
        stats["steps"] += 1
        if on_step is not None:
            on_step(stats)
        if bool(np.asarray(term)[env_index]) or bool(np.asarray(trunc)[env_index]):
            new_episode(save=True)
    return stats
