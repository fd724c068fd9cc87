"""kestrel.so101_teleop: teleoperation of the SO-101 pick-and-place task (LeIsaac's
teleop_se3_agent.py) on Kestrel-SO101-PickPlace-v0: a device (KeyboardTeleop, or the SO-101 leader
arm, kestrel.feetech.So101Leader) drives the env at 30 Hz, optionally shown live in the viewer
(kestrel.so101_view) and recorded as a LeRobot dataset (kestrel.lerobot_record.LeRobotWriter).

    kestrel teleop --task Kestrel-SO101-PickPlace-v0 --device keyboard [--record DIR] [--episodes N]
    kestrel teleop --task Kestrel-SO101-PickPlace-v0 --device so101leader --port /dev/ttyACM0 --calibration leader.json
    kestrel replay DIR [--episode K]

The env (make_env): physics dt 1/120 s, decimation 4 (30 Hz actions, LeIsaac's recording rate).
The action mode is chosen when the env is made (task.pick_place.action_mode):
  joint_position (6): absolute joint targets (rad): shoulder_pan, shoulder_lift, elbow_flex,
           wrist_flex, wrist_roll, gripper                                  (the leader arm)
  ee_delta (5): tcp position delta (3, m), yaw delta (1, rad), gripper target (1, rad)   (the keyboard; IK)
Observations (31 floats per env): joint positions obs[:, 0:6]; the joint targets the last action
applied obs[:, 12:18] (in ee_delta mode the IK's), which are what a dataset records as the action,
so every dataset is joint-space (LeRobot's so101 features) and replays in joint_position mode.
Camera frames come from env.task.render_camera(env_index, "front" | "wrist", width, height).

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
Until B the env is not stepped (LeIsaac renders only); an episode ends on success (the env's
`terminated`: saved), N (saved), R (discarded) or the time limit (truncated: discarded, not a
demonstration of success); each episode starts from a reset with its own seed (seed, seed + 1, ...),
stored with the episode (meta/episodes kestrel/seed) for replay.
"""
from __future__ import annotations

import math
import sys
import threading
import time
from typing import Any, Callable, Sequence

import numpy as np

SO101_GRIPPER_RANGE = (math.radians(-10.0), math.radians(100.0))
TASK_ID = "Kestrel-SO101-PickPlace-v0"
CONTROL_HZ = 30                 # LeIsaac records at 30 fps
PHYSICS_DT_S = 1.0 / 120.0      # x DECIMATION = 1/30 s per action
DECIMATION = 4
CAMERAS = ("front", "wrist")
RECORD_SIZE = (640, 480)        # (width, height) of the recorded camera frames
CUBE_POSE_KEY = "kestrel.cube_pose_w"   # cube position (3) + quaternion xyzw (4), float32: replay checks it
PAGE_KEY_HOLD_S = 0.1           # a key press from the viewer's page holds the key this long (repeats extend it)


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
        self.clock = time.monotonic
        self._until: dict[str, float] = {}  # keys held until a time (presses from the viewer's page)
        self._lock = threading.RLock()      # press() comes from the viewer's thread, action() from the loop's

    def press(self, key: str, hold_s: float | None = None) -> None:
        """Key down; with hold_s the key is released by itself hold_s seconds later (unless pressed
        again: a page's hotkeys report key presses and their auto-repeats, never the key's release)."""
        with self._lock:
            self._press(key.upper(), hold_s)
        cb = self.callbacks.get(key.upper())
        if cb is not None:
            cb()

    def _press(self, k: str, hold_s: float | None) -> None:
        if k in self.KEYMAP:
            self.held.add(k)
            if hold_s is not None:
                self._until[k] = self.clock() + float(hold_s)
            else:
                self._until.pop(k, None)
        elif k == "B":
            self.started = True
        elif k in ("R", "N"):
            self.started = False
            self.reset_request = "failure" if k == "R" else "success"

    def release(self, key: str) -> None:
        with self._lock:
            self.held.discard(key.upper())
            self._until.pop(key.upper(), None)

    def take_reset(self) -> str | None:
        with self._lock:
            r, self.reset_request = self.reset_request, None
        return r

    def reset(self, gripper_position: float | None = None, release_keys: bool = True) -> None:
        """After an env reset: no held keys; the gripper target follows the gripper's position."""
        with self._lock:
            if release_keys:
                self.held.clear()
                self._until.clear()
            if gripper_position is not None:
                self.gripper_target = float(gripper_position)

    def action(self, observation: Any = None) -> np.ndarray:
        """(dx, dy, dz, dyaw, gripper_target) for this step from the held keys."""
        with self._lock:
            now = self.clock()
            for k, t in list(self._until.items()):
                if now >= t:
                    self.held.discard(k)
                    del self._until[k]
            return self._action()

    def _action(self) -> np.ndarray:
        d = np.zeros(6)
        for k in self.held:
            axis, sign = self.KEYMAP[k]
            d[axis] += sign
        s = self.sensitivity
        self.gripper_target = float(np.clip(self.gripper_target + d[5] * self.JOINT * s, *self.gripper_range))
        return np.array([d[0] * self.POS * s, d[1] * self.POS * s, d[2] * self.POS * s, d[3] * self.ROT * s,
                         self.gripper_target])




class LeaderTeleop:
    """The SO-101 leader arm (kestrel.feetech.So101Leader, or anything with joint_targets()) as a
    device of the joint_position mode: its joint angles are the follower's targets. Started from
    the first step (no B needed); R / N (the viewer's page) reset as for the keyboard."""

    mode = "joint"

    def __init__(self, leader):
        self.leader = leader
        self.started = True
        self.reset_request: str | None = None
        self._lock = threading.Lock()

    def press(self, key: str, hold_s: float | None = None) -> None:
        k = key.upper()
        with self._lock:
            if k == "B":
                self.started = True
            elif k in ("R", "N"):
                self.reset_request = "failure" if k == "R" else "success"

    def release(self, key: str) -> None:
        pass

    def take_reset(self) -> str | None:
        with self._lock:
            r, self.reset_request = self.reset_request, None
        return r

    def action(self, observation: Any = None) -> np.ndarray:
        return np.asarray(self.leader.joint_targets(), dtype=np.float32)


class ScriptedDevice:
    """The task's scripted pick-and-place (env.scripted_actions(), joint_position mode) as a device:
    demonstrations without a person (tests, a dataset to try a pipeline on)."""

    mode = "joint"
    started = True

    def __init__(self, env, env_index: int = 0):
        self.env, self.env_index = env, env_index

    def action(self, observation: Any = None) -> np.ndarray:
        return np.asarray(self.env.scripted_actions()[self.env_index], dtype=np.float32)


# ---- the env ------------------------------------------------------------------------------------

def make_env(mode: str = "ee", num_envs: int = 1, seed: int = 0, episode_s: float = 120.0, threads: int | None = 1,
             **pick_place: Any):
    """Kestrel-SO101-PickPlace-v0 for teleoperation: 30 Hz actions (dt 1/120 s, decimation 4), the
    action mode of the device ("ee": ee_delta, the keyboard; "joint": joint_position, the leader
    arm, replay), episodes truncated after episode_s seconds; pick_place: more task.pick_place keys."""
    import kestrel

    if mode not in ("ee", "joint"):
        raise ValueError(f"mode: expected 'ee' or 'joint', got {mode!r}")
    pp = {"action_mode": "ee_delta" if mode == "ee" else "joint_position", "dt_s": PHYSICS_DT_S,
          "decimation": DECIMATION, **pick_place}
    steps = max(1, int(round(episode_s * CONTROL_HZ)))
    return kestrel.make_vec(TASK_ID, num_envs=num_envs, seed=seed, threads=threads,
                            task={"pick_place": pp, "episode_len_env_steps": steps})


def env_mode(env) -> str:
    """"ee" (5 actions: ee_delta) or "joint" (6: joint_position), from the env's action dimension."""
    dim = int(env.single_action_space.shape[0])
    if dim not in (5, 6):
        raise ValueError(f"env: {dim} actions; expected the SO-101 pick-and-place env (5: ee_delta, 6: joint_position)")
    return "ee" if dim == 5 else "joint"


def control_hz(env) -> float:
    t = env.task
    return 1.0 / (t.simulator.dt_s * t.simulator.decimation)


def reset_episode(env, seed: int | None):
    """Resets every env of `env` to the start a task built with `seed` has (env.reset(seed) rebuilds
    the task only when the seed differs from its current one, else it draws the next episode):
    what recording and replay both go through, so the same seed is the same start."""
    if seed is None:
        return env.reset()[0]
    if env.task.seed == int(seed):
        env.reset(seed=int(seed) + 1)
    return env.reset(seed=int(seed))[0]


def joint_state(obs, i: int = 0) -> np.ndarray:
    return np.array(obs[i, 0:6], dtype=np.float32)


def render_cameras(env, i: int = 0, cameras: Sequence[str] = CAMERAS, size=RECORD_SIZE) -> dict[str, np.ndarray]:
    """RGB (h, w, 3) uint8 per camera of env i (Task.render_camera)."""
    w, h = size
    return {c: env.task.render_camera(i, c, width=int(w), height=int(h))[0] for c in cameras}


def cube_pose(state: dict) -> np.ndarray:
    return np.array(list(state["cube_pos_w"]) + list(state["cube_quat_xyzw"]), dtype=np.float32)


def dataset_features(cameras: Sequence[str] = CAMERAS, size=RECORD_SIZE) -> dict:
    """The recorded features: LeRobot's SO-101 state / action / images, plus the cube's pose
    (CUBE_POSE_KEY, not an observation: LeRobot's policies take only observation.* and action)."""
    from .lerobot_record import so101_features

    f = so101_features({c: (int(size[1]), int(size[0])) for c in cameras})
    f[CUBE_POSE_KEY] = {"dtype": "float32", "shape": [7], "names": ["x", "y", "z", "qx", "qy", "qz", "qw"]}
    return f


def teleop_loop(env, device, steps: int | None = None, recorder=None, *, task: str | None = None, seed: int | None = 0,
                env_index: int = 0, cameras: Sequence[str] | None = None, episodes: int | None = None,
                rate_hz: float | None = None, on_step: Callable[[dict], None] | None = None,
                stop: Callable[[], bool] | None = None) -> dict:
    """Runs `env` (make_env) driven by `device` (.mode "ee"/"joint" matching the env's action mode,
    .action(obs) -> the action of env `env_index`; optional .started, .take_reset(), .reset()) for
    `steps` ticks (None: until `episodes` episodes are saved or stop() is true), paced to rate_hz
    (None: as fast as it goes). The other envs get the same action. A tick steps the env once the
    device is started; with a recorder (LeRobotWriter, features dataset_features()) each such step
    is a frame: the joint state before the step, the joint targets the step applied, the camera
    frames before the step (the recorder's image size), the cube's pose, the task string. Episodes
    end as the module docstring says. on_step(ctx) after every tick: ctx has env, obs, stats,
    started, images (the frames recorded this tick, or {}). Returns the counts."""
    from .lerobot_record import DEFAULT_TASK

    task = task or DEFAULT_TASK
    mode = env_mode(env)
    if device.mode != mode:
        raise ValueError(f"device: a {device.mode!r}-mode device on an env in the {mode!r} action mode "
                         f"(make_env(mode={device.mode!r}))")
    size = RECORD_SIZE
    if recorder is not None:
        img_keys = [k for k, ft in recorder.features.items() if ft["dtype"] == "image"]
        if cameras is None:
            cameras = [k.split(".", 2)[2] for k in img_keys]
        if img_keys:
            h, w = recorder.features[img_keys[0]]["shape"][:2]
            size = (w, h)
    cameras = list(cameras or [])
    n_envs = env.num_envs
    stats = {"ticks": 0, "steps": 0, "frames": 0, "saved": 0, "discarded": 0, "successes": 0, "timeouts": 0,
             "episode": 0, "seed": seed}
    ep_seed = seed
    obs = reset_episode(env, ep_seed)
    if isinstance(device, KeyboardTeleop):  # keys already down stay down (the loop's own start)
        device.reset(gripper_position=float(obs[env_index, 5]), release_keys=False)
    elif hasattr(device, "reset"):
        device.reset()
    batch = np.zeros((n_envs, env.single_action_space.shape[0]), np.float32)
    period = 1.0 / rate_hz if rate_hz else 0.0
    next_t = time.monotonic()

    def new_episode(save: bool) -> None:
        nonlocal obs, ep_seed
        if recorder is not None and recorder.episode_frames:
            if save:
                recorder.save_episode(extra={"seed": ep_seed})
                stats["saved"] += 1
            else:
                recorder.clear_episode()
                stats["discarded"] += 1
        elif recorder is None and save:
            stats["saved"] += 1
        ep_seed = None if ep_seed is None else ep_seed + 1
        stats["episode"] += 1
        stats["seed"] = ep_seed
        obs = reset_episode(env, ep_seed)
        if isinstance(device, KeyboardTeleop):
            device.reset(gripper_position=float(obs[env_index, 5]))
        elif hasattr(device, "reset"):
            device.reset()

    while (steps is None or stats["ticks"] < steps) and (episodes is None or stats["saved"] < episodes):
        if stop is not None and stop():
            break
        if period:
            now = time.monotonic()
            if next_t > now:
                time.sleep(next_t - now)
            next_t = max(next_t + period, time.monotonic() - 0.25)
        stats["ticks"] += 1
        req = device.take_reset() if hasattr(device, "take_reset") else None
        if req is not None:
            new_episode(save=req == "success")
            if on_step is not None:
                on_step({"env": env, "obs": obs, "stats": stats, "started": False, "images": {}})
            continue
        started = bool(getattr(device, "started", True))
        images: dict[str, np.ndarray] = {}
        if not started:  # LeIsaac: nothing moves before B
            if on_step is not None:
                on_step({"env": env, "obs": obs, "stats": stats, "started": False, "images": images})
            continue
        recording = recorder is not None
        state = joint_state(obs, env_index)
        a = np.asarray(device.action(obs), dtype=np.float32).reshape(-1)
        batch[:] = a[None]
        if recording:
            images = render_cameras(env, env_index, cameras, size)
            cube = cube_pose(env.task.pick_place_state(env_index))
        obs_next, _, term, trunc, info = env.step(batch)
        stats["steps"] += 1
        t_i, tr_i = bool(term[env_index]), bool(trunc[env_index])
        ended = t_i or tr_i
        if recording:
            # The joint targets the step applied (ee mode: the IK's); an ended env has been reset
            # inside the step, its last observation is in final_obs.
            src = info["final_obs"] if ended else obs_next
            frame = {"observation.state": state, "action": np.array(src[env_index, 12:18], dtype=np.float32),
                     CUBE_POSE_KEY: cube}
            frame.update({f"observation.images.{c}": im for c, im in images.items()})
            frame = {k: v for k, v in frame.items() if k in recorder.features}
            recorder.add_frame(frame, task=task)
            stats["frames"] += 1
        obs = obs_next
        if on_step is not None:
            on_step({"env": env, "obs": obs, "stats": stats, "started": True, "images": images})
        if ended:
            stats["successes" if t_i else "timeouts"] += 1
            new_episode(save=t_i)
    return stats


# ---- replay -------------------------------------------------------------------------------------

def replay_episode(root, episode: int = 0, env=None, seed: int | None = None, check: bool = True) -> dict:
    """Re-runs a recorded episode's actions (joint targets) in the joint_position mode from a reset
    with its stored seed (or `seed`) and compares, bit for bit, every frame's joint state
    (observation.state) and, when recorded, the cube's pose. Returns {"frames", "states",
    "cube_poses", "state_equal", "cube_equal", "first_mismatch"}; check=True raises AssertionError
    on a difference."""
    from .lerobot_record import LeRobotEpisodes

    ds = LeRobotEpisodes(root)
    if not 0 <= episode < len(ds):
        raise ValueError(f"episode: {episode} not in the dataset (it has {len(ds)})")
    if ds.fps != CONTROL_HZ:
        raise ValueError(f"{root}: recorded at {ds.fps} fps; this env steps at {CONTROL_HZ} Hz")
    ep = ds.episodes[episode]
    seed = ep.get("kestrel/seed") if seed is None else seed
    data = ds.episode(episode)
    env = env if env is not None else make_env("joint", seed=0 if seed is None else int(seed))
    if env_mode(env) != "joint":
        raise ValueError("replay: the env must be in the joint_position action mode")
    obs = reset_episode(env, seed)
    batch = np.zeros((env.num_envs, 6), np.float32)
    states, cubes = [], []
    for a in data["action"]:
        states.append(joint_state(obs, 0))
        cubes.append(cube_pose(env.task.pick_place_state(0)))
        batch[:] = np.asarray(a, np.float32)[None]
        obs = env.step(batch)[0]
    states, cubes = np.stack(states), np.stack(cubes)
    rec_states = np.asarray(data["observation.state"], np.float32)
    s_eq = states.tobytes() == rec_states.tobytes()
    bad = np.nonzero(np.any(states.view(np.uint32) != rec_states.view(np.uint32), axis=1))[0]
    c_eq = None
    if CUBE_POSE_KEY in data:
        rec_c = np.asarray(data[CUBE_POSE_KEY], np.float32)
        c_eq = cubes.tobytes() == rec_c.tobytes()
        bad = np.union1d(bad, np.nonzero(np.any(cubes.view(np.uint32) != rec_c.view(np.uint32), axis=1))[0])
    out = {"frames": len(states), "states": states, "cube_poses": cubes, "state_equal": s_eq, "cube_equal": c_eq,
           "first_mismatch": int(bad[0]) if len(bad) else None, "seed": seed}
    if check and (not s_eq or c_eq is False):
        raise AssertionError(f"replay of episode {episode}: frame {out['first_mismatch']} differs "
                             f"(joint states equal: {s_eq}, cube poses equal: {c_eq})")
    return out


def replay_main(argv: list[str], prog: str = "kestrel replay") -> int:
    import argparse

    p = argparse.ArgumentParser(prog=prog, description="Re-run recorded SO-101 episodes (a LeRobot dataset of "
                                "`kestrel teleop --record`) in the joint_position mode from their seeds and check "
                                "joint states and cube poses bit for bit.")
    p.add_argument("dataset", help="the dataset's directory")
    p.add_argument("--episode", type=int, default=None, help="episode index (default: every episode)")
    a = p.parse_args(argv)
    from .lerobot_record import LeRobotEpisodes

    try:
        n = len(LeRobotEpisodes(a.dataset))
    except (FileNotFoundError, ValueError) as e:
        print(f"{prog}: {e}", file=sys.stderr)
        return 1
    eps = [a.episode] if a.episode is not None else list(range(n))
    bad = 0
    for k in eps:
        try:
            r = replay_episode(a.dataset, k, check=False)
        except ValueError as e:
            print(f"{prog}: {e}", file=sys.stderr)
            return 1
        ok = r["state_equal"] and r["cube_equal"] is not False
        bad += not ok
        cube = {None: "not recorded", True: "bit-identical", False: "DIFFER"}[r["cube_equal"]]
        print(f"episode {k}: {r['frames']} frames from seed {r['seed']}: joint states "
              f"{'bit-identical' if r['state_equal'] else 'DIFFER'}, cube poses {cube}"
              + ("" if ok else f" (first difference at frame {r['first_mismatch']})"), flush=True)
    return 1 if bad else 0


def teleop_parser(prog: str):
    import argparse

    p = argparse.ArgumentParser(prog=prog, description="Teleoperate the SO-101 pick-and-place task (LeIsaac's "
                                "teleop_se3_agent.py): keyboard (ee_delta) or the SO-101 leader arm (joint_position), "
                                "at 30 Hz, shown in the browser viewer, optionally recorded as a LeRobot dataset.")
    p.add_argument("--task", default=TASK_ID, help=f"only {TASK_ID}")
    p.add_argument("--device", choices=("keyboard", "so101leader"), default="keyboard")
    p.add_argument("--port", default="/dev/ttyACM0", help="so101leader: the leader arm's serial port")
    p.add_argument("--calibration", default=None, metavar="FILE.json", help="so101leader: LeRobot's calibration JSON")
    p.add_argument("--num-envs", type=int, default=1, help="environments (env 0 is shown and recorded; the others "
                   "get the same actions)")
    p.add_argument("--record", metavar="DIR", default=None, help="record episodes as a LeRobot v3.0 dataset in DIR (new)")
    p.add_argument("--episodes", type=int, default=None, help="stop after N saved episodes")
    p.add_argument("--seed", type=int, default=0, help="the first episode's reset seed (then seed + 1, ...)")
    p.add_argument("--steps", type=int, default=0, help="stop after N control ticks (default 0: no limit)")
    p.add_argument("--episode-s", type=float, default=120.0, help="an episode's time limit (s; then discarded)")
    p.add_argument("--record-size", type=int, nargs=2, default=RECORD_SIZE, metavar=("W", "H"),
                   help="recorded camera frames (default 640 480)")
    p.add_argument("--rate", type=float, default=float(CONTROL_HZ), help="control ticks per second of wall time "
                   "(default 30: real time; 0: as fast as it goes)")
    p.add_argument("--no-view", action="store_true", help="no browser viewer (a progress line on the terminal)")
    p.add_argument("--view-port", type=int, default=8080, help="the viewer's HTTP port (0: any free port)")
    p.add_argument("--view-size", type=int, nargs=2, default=(320, 240), metavar=("W", "H"),
                   help="the camera images in the viewer's side panel")
    p.add_argument("--view-every", type=int, default=3, help="update the side panel's images every N ticks")
    p.add_argument("--state-file", default=None, metavar="FILE.json",
                   help="keep FILE.json up to date with the tcp position, grip force, cube_in_box, episode counts")
    p.add_argument("--quiet", action="store_true", help="no progress line")
    return p


def _status(env, stats: dict, started: bool, i: int = 0) -> tuple[dict, str]:
    s = env.task.pick_place_state(i)
    tcp = [round(float(x), 4) for x in s["tcp_pos_w"]]
    d = {"ticks": stats["ticks"], "steps": stats["steps"], "started": started, "episode": stats["episode"],
         "saved": stats["saved"], "discarded": stats["discarded"], "frames": stats["frames"], "tcp_pos_w": tcp,
         "grip_force_N": round(float(s["grip_force_N"]), 3), "cube_in_box": bool(s["cube_in_box"]),
         "joint_pos": [round(float(x), 4) for x in s["joint_pos"]], "cube_pos_w": [round(float(x), 4) for x in s["cube_pos_w"]]}
    line = (f"tcp ({tcp[0]:+.3f}, {tcp[1]:+.3f}, {tcp[2]:+.3f}) m, grip {d['grip_force_N']:.2f} N, "
            f"cube in box: {'yes' if d['cube_in_box'] else 'no'}, episode {stats['episode']} "
            f"(saved {stats['saved']}){'' if started else ', press B to start'}")
    return d, line


def teleop_main(argv: list[str], prog: str = "kestrel teleop") -> int:
    import json
    import os

    from .progress import Progress

    a = teleop_parser(prog).parse_args(argv)
    if a.task != TASK_ID:
        print(f"{prog}: --task {a.task!r}: this teleoperation is for {TASK_ID}", file=sys.stderr)
        return 2
    if a.num_envs < 1:
        print(f"{prog}: --num-envs: expected >= 1, got {a.num_envs}", file=sys.stderr)
        return 2
    mode = "ee" if a.device == "keyboard" else "joint"
    try:
        env = make_env(mode, num_envs=a.num_envs, seed=a.seed, episode_s=a.episode_s)
    except ValueError as e:
        print(f"{prog}: {e}", file=sys.stderr)
        return 1
    if a.device == "keyboard":
        device = KeyboardTeleop()
    else:
        from .feetech import FeetechError, So101Leader

        try:
            device = LeaderTeleop(So101Leader(a.port, a.calibration))
        except (OSError, FeetechError, ValueError) as e:
            print(f"{prog}: the leader arm on {a.port}: {e}", file=sys.stderr)
            return 1
    recorder = None
    if a.record:
        from .lerobot_record import LeRobotWriter

        try:
            recorder = LeRobotWriter.create(a.record, fps=CONTROL_HZ, features=dataset_features(CAMERAS, tuple(a.record_size)))
        except FileExistsError as e:
            print(f"{prog}: {e}", file=sys.stderr)
            return 1
    view = None
    if not a.no_view:
        from .so101_view import PickPlaceView

        view = PickPlaceView(env, 0, port=a.view_port, image_size=tuple(a.view_size), image_every=a.view_every)
        view.bind_keys(device)
        print(f"kestrel teleop: {TASK_ID} ({a.device}, {'ee_delta' if mode == 'ee' else 'joint_position'}, "
              f"{CONTROL_HZ} Hz) at {view.url}", flush=True)
    else:
        print(f"kestrel teleop: {TASK_ID} ({a.device}) without the viewer", flush=True)
    if a.device == "keyboard" and view is None:
        print("kestrel teleop: the keyboard is read from the viewer's page; without it nothing starts (B)",
              file=sys.stderr, flush=True)
    progress = Progress(total=None, unit="ticks", desc="teleop", quiet=a.quiet)
    t0 = time.monotonic()
    last = {"t": 0.0}

    def on_step(ctx) -> None:
        st = ctx["stats"]
        if view is not None:
            d, line = _status(env, st, ctx["started"])
            view.update(ctx, status=f"**SO-101** {line}")
        now = time.monotonic()
        if a.state_file or progress.enabled:
            if now - last["t"] >= 0.1:
                last["t"] = now
                d, line = _status(env, st, ctx["started"])
                if view is not None:
                    d["view_frames"], d["presses"] = view.frames_drawn, list(getattr(view, "presses", []))
                if a.state_file:
                    tmp = a.state_file + ".tmp"
                    with open(tmp, "w") as f:
                        json.dump(d, f)
                    os.replace(tmp, a.state_file)
                progress.desc = line
        progress.update(1)

    stats = None
    try:
        stats = teleop_loop(env, device, steps=a.steps or None, recorder=recorder, seed=a.seed,
                            episodes=a.episodes, rate_hz=a.rate or None, on_step=on_step)
    except KeyboardInterrupt:
        pass
    finally:
        progress.close()
        if recorder is not None and recorder.episode_frames:
            recorder.clear_episode()  # an unfinished episode is not a demonstration
        if view is not None:
            view.close()
        if hasattr(device, "leader"):
            device.leader.close()
    wall = time.monotonic() - t0
    if stats is not None:
        print(f"kestrel teleop: {stats['ticks']} ticks ({stats['steps']} env-steps) in {wall:.1f} s "
              f"({stats['ticks'] / max(wall, 1e-9):.1f} ticks/s), episodes saved {stats['saved']}, "
              f"discarded {stats['discarded']}, frames {stats['frames']}", flush=True)
    if recorder is not None:
        print(f"kestrel teleop: dataset {a.record} ({recorder.info['total_episodes']} episodes, "
              f"{recorder.info['total_frames']} frames)", flush=True)
    return 0
