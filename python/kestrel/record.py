"""Runs driven from Python, their frames, and recordings in MCAP that Foxglove opens.

`kestrel run SCENARIO --record FILE` (and `--view`) runs the scenario here, through the bindings,
with the policy the C++ `kestrel run` uses (the World's own setpoints on rigid, the task's scripted
controller for RL tasks, pure pursuit on planar, the C++ run's random joint targets for legged
robots), so the final state hash is the one the C++ CLI prints for the same scenario and seed
(python/tests/test_viewer.py checks it). Each env-step it takes a Frame of the environments asked
for: robot states, commands (the actions the controllers got), motor thrusts, fault flags, feet,
contact forces, the terrain heights under the robot, the obstacles, and the sensor images.

The recording (MCAP, JSON-encoded messages with JSON-schema channels):

    /kestrel/scene          kestrel.Scene, once: robot geometry, terrain, envs recorded, dt
    /kestrel/state          kestrel.State, every env-step: per robot pos, quat (xyzw), velocities,
                            target, actions, motor thrusts, fault bits, crashed, feet, contacts,
                            sensor mounts (with the scene's range_rays: the point clouds)
    /kestrel/obstacles      kestrel.Obstacles, at the first step and whenever an env's layout changes
    /tf                     foxglove.FrameTransforms, every env-step: world -> env<e>/robot<r>
    /markers/obstacles      foxglove.SceneUpdate: env 0's obstacles as cubes, spheres, cylinders
    /env<e>/robot<r>/range<k>         foxglove.RawImage 32FC1 (m), every env-step
    /env<e>/robot<r>/segmentation<k>  foxglove.RawImage 16UC1, semantic id + 1 (0: no hit)

Foxglove's 3-D panel shows /tf and /markers/obstacles, its Image panel the images, its Plot panel
any field of /kestrel/state (e.g. /kestrel/state.thrust_N[0][1]). read_recording() reads a file
back into Frames, which is what `kestrel view --replay FILE` shows.
"""
from __future__ import annotations

import argparse
import base64
import dataclasses
import json
import os
import sys
from typing import Any, Iterator

import numpy as np

from . import _core

# kernel/status.hpp Fault bits, in bit order.
FAULT_BITS = ("non_finite_command", "non_finite_state", "command_out_of_range", "saturated", "singular",
              "unallocated", "motor_failure", "not_converged", "non_finite_output")

_SCHEMA_VERSION = 1


def fault_names(bits: int) -> list[str]:
    """The names of the fault bits set in `bits` (kernel/status.hpp Fault)."""
    return [n for k, n in enumerate(FAULT_BITS) if int(bits) >> k & 1]


# ---- frames ------------------------------------------------------------------------------------------

@dataclasses.dataclass
class Frame:
    """What one env-step looks like for the environments `envs` (robot rows: env-major, robots_per_env each)."""
    step: int
    time_s: float
    envs: list[int]
    robots: dict[str, np.ndarray]
    obstacles: dict[int, dict[str, Any]]
    images: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)


def robot_rows(envs: list[int], robots_per_env: int) -> np.ndarray:
    return np.array([e * robots_per_env + r for e in envs for r in range(robots_per_env)], dtype=np.int64)


def capture_frame(sim: _core.Simulator, envs: list[int], step: int, time_s: float, actions: np.ndarray | None = None,
                  images: bool = True, obstacles: bool = True) -> Frame:
    """A copy of the views of the envs asked for (the sim goes on stepping; the frame stays)."""
    rows = robot_rows(envs, sim.robots_per_env)
    r: dict[str, np.ndarray] = {
        "pos_w": np.array(sim.base_pos_w[rows], dtype=np.float64),
        "quat_xyzw": np.array(sim.base_quat_xyzw[rows], dtype=np.float64),
        "lin_vel_b": np.array(sim.base_lin_vel_b[rows], dtype=np.float64),
        "ang_vel_b": np.array(sim.base_ang_vel_b[rows], dtype=np.float64),
        "target_w": np.array(sim.target_w[rows], dtype=np.float64),
        "contact_forces_w": np.array(sim.contact_forces_w[rows], dtype=np.float64),
    }
    # The rigid World's own data (world_data, motors, obstacles); articulated robots and planar have none.
    try:
        wd = sim.world_data()
    except ValueError:
        wd = None
    rigid = wd is not None
    if rigid:
        r["actions"] = np.array(wd["actions"][rows][:, : sim.action_dim], dtype=np.float64)
        r["crashed"] = np.array(wd["crashed"][rows], dtype=bool).reshape(-1)
        thrust, faults = sim.motor_state()
        r["thrust_N"] = np.array(thrust[rows])
        r["faults"] = np.array(faults[rows], dtype=np.uint32)
    elif actions is not None:
        r["actions"] = np.array(actions[rows], dtype=np.float64)
    if sim.num_feet > 0:
        r["feet_pos_w"] = np.array(sim.feet_pos_w[rows], dtype=np.float64)
        r["link_contact_forces_w"] = np.array(sim.link_contact_forces_w[rows], dtype=np.float64)
    if sim.num_dofs > 0:
        r["dof_pos"] = np.array(sim.dof_pos[rows], dtype=np.float64)
    mh = sim.measured_heights
    if mh.shape[1] > 0:
        r["measured_heights"] = np.array(mh[rows], dtype=np.float64)
    obs: dict[int, dict[str, Any]] = {}
    if obstacles and rigid:
        obs = {e: sim.obstacles(e) for e in envs}
    im: dict[str, np.ndarray] = {}
    if images:
        for k in range(sim.num_range_images):
            im[f"range{k}"] = np.array(sim.range_images(k)[rows], dtype=np.float32)
            if rigid:
                im[f"segmentation{k}"] = np.array(sim.segmentation_images(k)[rows], dtype=np.int32)
        if rigid and sim.num_range_images > 0:
            # Each robot's sensor mounts (redrawn at resets when randomised): with the rays of
            # sensor_rays() and the robot's pose they turn a range image into world points, live
            # and in a replay (range_points_w).
            mounts = [sim.sensor_mounts(k) for k in range(sim.num_range_images)]
            r["sensor_mount_pos_b"] = np.stack([np.asarray(p)[rows] for p, _ in mounts], axis=1)
            r["sensor_mount_quat_bs"] = np.stack([np.asarray(q)[rows] for _, q in mounts], axis=1)
    return Frame(step=step, time_s=time_s, envs=list(envs), robots=r, obstacles=obs, images=im)


def obstacles_equal(a: dict[str, Any] | None, b: dict[str, Any] | None) -> bool:
    if a is None or b is None:
        return a is b
    keys = ("type", "radius_m", "half_length_m", "half_extents_m", "position_w", "orientation_xyzw")
    return all(np.array_equal(a[k], b[k]) for k in keys)


def sensor_rays(sim: _core.Simulator) -> list[dict[str, Any]]:
    """Every range image's rays (Simulator.range_image_rays), float32 directions: what turns pixels
    into points. Empty where the simulator has no ray sensors or no ray table (planar)."""
    out = []
    try:
        for k in range(sim.num_range_images):
            r = dict(sim.range_image_rays(k))
            r["dirs_s"] = np.asarray(r["dirs_s"], dtype=np.float32)
            r["depth_scale"] = np.asarray(r["depth_scale"], dtype=np.float32)
            out.append(r)
    except ValueError:
        return []
    return out


def _rotate_many(q_xyzw: np.ndarray, v: np.ndarray) -> np.ndarray:
    """v (..., 3) rotated by unit quaternions q (..., 4), xyzw, broadcast."""
    u, w = q_xyzw[..., :3], q_xyzw[..., 3:4]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def range_points_w(rays: dict[str, Any], image: np.ndarray, pos_w, quat_xyzw, mount_pos_b, mount_quat_bs) -> np.ndarray:
    """The world points of one robot's range image: (n, 3) for the pixels with a return, in image
    order. rays: one entry of sensor_rays(); image: (H, W) as range_images(k)[robot]; the robot's
    pose and that sensor's mount (Simulator.sensor_mounts). A pixel v returns when
    min_range_m <= v * value_scale_m < max_range_m (the no-return values are negative or the far
    value, max_range_m); its range along the ray is v * value_scale_m / depth_scale."""
    v = np.asarray(image, dtype=np.float64).reshape(-1) * float(rays["value_scale_m"])
    ok = np.isfinite(v) & (v >= float(rays["min_range_m"])) & (v < float(rays["max_range_m"]))
    d = np.asarray(rays["dirs_s"], dtype=np.float64).reshape(-1, 3)[ok]
    rng = v[ok] / np.asarray(rays["depth_scale"], dtype=np.float64).reshape(-1)[ok]
    p_s = d * rng[:, None]
    q_wb = np.asarray(quat_xyzw, dtype=np.float64)
    p_b = np.asarray(mount_pos_b, dtype=np.float64) + _rotate_many(np.asarray(mount_quat_bs, dtype=np.float64), p_s)
    return np.asarray(pos_w, dtype=np.float64) + _rotate_many(q_wb, p_b)


def sensor_origin_w(pos_w, quat_xyzw, mount_pos_b) -> np.ndarray:
    """Where a sensor sits in the world: p_wb + R_wb mount_pos_b."""
    return np.asarray(pos_w, dtype=np.float64) + _rotate_many(np.asarray(quat_xyzw, dtype=np.float64),
                                                              np.asarray(mount_pos_b, dtype=np.float64))


# ---- the run `kestrel run` does, from Python ---------------------------------------------------------

class ScriptedRun:
    """`kestrel run`'s run of a scenario, stepped from Python (see the module comment)."""

    def __init__(self, cfg: _core.Config, policy: str = "scripted"):
        if policy not in ("scripted", "zero"):
            raise ValueError(f"policy: expected scripted or zero, got {policy!r}")
        self.cfg, self.policy = cfg, policy
        self.task: _core.Task | None = None
        self.targets = None
        task_ids = set(_core.rl_task_ids())
        self.sim_only = _core.Simulator(cfg, "") if cfg.task not in task_ids else None
        sim = self.sim_only
        articulated = sim is not None and sim.num_dofs > 0
        if cfg.task in task_ids:
            self.task = _core.Task(cfg, "")
            self.sim = self.task.simulator
            if self.sim.num_dofs > 0 and cfg.task != "locomotion_task":
                raise ValueError(f"task {cfg.task}: drives multirotors; an articulated robot ({cfg.robot}) runs "
                                 "locomotion_task, or `kestrel run` with no task")
            self.mode = "task"
            self._task_actions = np.zeros((self.task.num_envs, self.task.action_dim), np.float32)
            if policy == "scripted":
                self._task_actions = np.ascontiguousarray(self.task.scripted_actions(), dtype=np.float32)
        else:
            self.sim = sim
            if articulated:
                self.mode = "joint_targets"
                self.targets = _core.ScriptedJointTargets(sim)
            elif sim.backend == "planar":
                self.mode = "planar"
            else:
                self.mode = "world"  # the World's own setpoints (Simulator.step(None)), as World::step
        self.steps_done = 0
        self.env_step_s = self.sim.dt_s * self.sim.decimation
        self.last_actions: np.ndarray | None = None

    @property
    def state_hash(self) -> int:
        return self.task.state_hash if self.task is not None else self.sim.state_hash

    def step(self, override: dict[int, np.ndarray] | None = None) -> None:
        """One env-step. override: robot row -> that robot's actions (teleoperation), the others as scripted."""
        if self.mode == "task":
            if self.policy == "scripted":
                self._task_actions[:] = self.task.scripted_actions()
            acts = self._task_actions
            if override:
                acts = acts.copy()
                for row, a in override.items():
                    acts[row] = a
            self.task.step(acts)
            self.last_actions = acts
        else:
            real = np.dtype(_core.real_dtype)
            if self.mode == "joint_targets":
                acts = np.ascontiguousarray(self.targets.next(), dtype=real)
            elif self.mode == "planar" or override:
                acts = np.ascontiguousarray(self.sim.scripted_actions(), dtype=real)
            else:
                acts = None
            if override:
                acts = acts.copy()
                for row, a in override.items():
                    acts[row] = np.asarray(a, dtype=real)
            self.sim.step(acts)
            self.last_actions = acts
        self.steps_done += 1

    def frame(self, envs: list[int], images: bool = True) -> Frame:
        return capture_frame(self.sim, envs, self.steps_done, self.steps_done * self.env_step_s, self.last_actions, images)


# ---- MCAP --------------------------------------------------------------------------------------------

def _obj(props: dict[str, Any], title: str = "") -> dict[str, Any]:
    return {"type": "object", "title": title, "properties": props}


_ARR = {"type": "array"}
_NUM = {"type": "number"}
_INT = {"type": "integer"}
_TIME = _obj({"sec": _INT, "nsec": _INT})
_VEC3 = _obj({"x": _NUM, "y": _NUM, "z": _NUM})
_QUAT = _obj({"x": _NUM, "y": _NUM, "z": _NUM, "w": _NUM})
_POSE = _obj({"position": _VEC3, "orientation": _QUAT})
_COLOR = _obj({"r": _NUM, "g": _NUM, "b": _NUM, "a": _NUM})

SCHEMAS: dict[str, dict[str, Any]] = {
    "kestrel.Scene": _obj({"version": _INT, "scenario": {"type": "string"}, "robot_name": {"type": "string"},
                           "robot_kind": {"type": "string"}, "backend": {"type": "string"}, "envs": _ARR,
                           "num_envs": _INT, "robots_per_env": _INT, "env_step_s": _NUM, "info": {"type": "object"}},
                          "kestrel.Scene"),
    "kestrel.State": _obj({"timestamp": _TIME, "step": _INT, "time_s": _NUM, "envs": _ARR,
                           **{k: _ARR for k in ("pos_w", "quat_xyzw", "lin_vel_b", "ang_vel_b", "target_w", "actions",
                                                "thrust_N", "faults", "fault_names", "crashed", "contact_forces_w",
                                                "feet_pos_w", "link_contact_forces_w", "dof_pos", "measured_heights",
                                                "sensor_mount_pos_b", "sensor_mount_quat_bs")}},
                          "kestrel.State"),
    "kestrel.Obstacles": _obj({"timestamp": _TIME, "step": _INT, "env": _INT,
                               **{k: _ARR for k in ("type", "radius_m", "half_length_m", "half_extents_m", "position_w",
                                                    "orientation_xyzw", "semantic_id", "asset_kind", "asset_class",
                                                    "hull_vertices_b")}}, "kestrel.Obstacles"),
    "foxglove.FrameTransforms": _obj({"transforms": {"type": "array", "items": _obj({
        "timestamp": _TIME, "parent_frame_id": {"type": "string"}, "child_frame_id": {"type": "string"},
        "translation": _VEC3, "rotation": _QUAT})}}, "foxglove.FrameTransforms"),
    "foxglove.RawImage": _obj({"timestamp": _TIME, "frame_id": {"type": "string"}, "width": _INT, "height": _INT,
                               "encoding": {"type": "string"}, "step": _INT,
                               "data": {"type": "string", "contentEncoding": "base64"}}, "foxglove.RawImage"),
    "foxglove.SceneUpdate": _obj({"deletions": _ARR, "entities": {"type": "array", "items": _obj({
        "timestamp": _TIME, "frame_id": {"type": "string"}, "id": {"type": "string"}, "lifetime": _TIME,
        "frame_locked": {"type": "boolean"}, "metadata": _ARR, "arrows": _ARR, "cubes": _ARR, "spheres": _ARR,
        "cylinders": _ARR, "lines": _ARR, "triangles": _ARR, "texts": _ARR, "models": _ARR})}}, "foxglove.SceneUpdate"),
}


def _jsonable(x: Any) -> Any:
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.floating,)):
        return float(x)
    if isinstance(x, dict):
        return {k: _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    return x


def _stamp(ns: int) -> dict[str, int]:
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


class McapRecorder:
    """Writes Frames to an MCAP file (see the module comment for the channels)."""

    def __init__(self, path: str, sim: _core.Simulator, envs: list[int], env_step_s: float, scenario: str = ""):
        from mcap.writer import CompressionType, Writer

        self.path, self.sim, self.envs, self.env_step_s = path, sim, list(envs), float(env_step_s)
        d = os.path.dirname(os.path.abspath(path))
        os.makedirs(d, exist_ok=True)
        self._f = open(path, "wb")
        self._w = Writer(self._f, compression=CompressionType.ZSTD)
        self._w.start(profile="", library="kestrel")
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, int] = {}
        self._seq = 0
        self._last_obstacles: dict[int, dict[str, Any]] = {}
        info = sim.scene_info()
        # The rays once (the mounts go with every state): a replay redraws the point clouds from them.
        info["range_rays"] = sensor_rays(sim)
        self.robots_per_env = sim.robots_per_env
        self._write("/kestrel/scene", "kestrel.Scene", 0, {
            "version": _SCHEMA_VERSION, "scenario": scenario, "robot_name": info["robot_name"],
            "robot_kind": info["robot_kind"], "backend": sim.backend, "envs": self.envs, "num_envs": sim.num_envs,
            "robots_per_env": sim.robots_per_env, "env_step_s": self.env_step_s, "info": _jsonable(info)})

    def _channel(self, topic: str, schema: str) -> int:
        if topic not in self._channels:
            if schema not in self._schemas:
                self._schemas[schema] = self._w.register_schema(name=schema, encoding="jsonschema",
                                                                data=json.dumps(SCHEMAS[schema]).encode())
            self._channels[topic] = self._w.register_channel(topic=topic, message_encoding="json",
                                                             schema_id=self._schemas[schema])
        return self._channels[topic]

    def _write(self, topic: str, schema: str, ns: int, msg: dict[str, Any]) -> None:
        cid = self._channel(topic, schema)
        self._w.add_message(channel_id=cid, log_time=ns, publish_time=ns, sequence=self._seq,
                            data=json.dumps(msg, separators=(",", ":")).encode())
        self._seq += 1

    def write(self, fr: Frame) -> None:
        ns = int(round(fr.time_s * 1e9))
        ts = _stamp(ns)
        state = {"timestamp": ts, "step": fr.step, "time_s": fr.time_s, "envs": fr.envs, **_jsonable(fr.robots)}
        if "faults" in fr.robots:
            state["fault_names"] = [fault_names(b) for b in fr.robots["faults"]]
        self._write("/kestrel/state", "kestrel.State", ns, state)
        rpe = self.robots_per_env
        tfs = []
        for i, (p, q) in enumerate(zip(fr.robots["pos_w"], fr.robots["quat_xyzw"])):
            e, r = fr.envs[i // rpe], i % rpe
            tfs.append({"timestamp": ts, "parent_frame_id": "world", "child_frame_id": f"env{e}/robot{r}",
                        "translation": {"x": p[0], "y": p[1], "z": p[2]},
                        "rotation": {"x": q[0], "y": q[1], "z": q[2], "w": q[3]}})
        self._write("/tf", "foxglove.FrameTransforms", ns, {"transforms": tfs})
        for e, ob in fr.obstacles.items():
            if obstacles_equal(ob, self._last_obstacles.get(e)):
                continue
            self._last_obstacles[e] = ob
            self._write("/kestrel/obstacles", "kestrel.Obstacles", ns,
                        {"timestamp": ts, "step": fr.step, "env": e, **_jsonable(ob)})
            if e == fr.envs[0]:
                self._write("/markers/obstacles", "foxglove.SceneUpdate", ns, _scene_update(ob, ts))
        for name, imgs in fr.images.items():
            for i, img in enumerate(imgs):
                e, r = fr.envs[i // rpe], i % rpe
                h, w = img.shape
                if name.startswith("range"):
                    data, enc, step = np.ascontiguousarray(img, dtype="<f4").tobytes(), "32FC1", 4 * w
                else:
                    data, enc, step = np.clip(img + 1, 0, 65535).astype("<u2").tobytes(), "16UC1", 2 * w
                self._write(f"/env{e}/robot{r}/{name}", "foxglove.RawImage", ns, {
                    "timestamp": ts, "frame_id": f"env{e}/robot{r}", "width": w, "height": h, "encoding": enc,
                    "step": step, "data": base64.b64encode(data).decode()})

    def close(self) -> None:
        if self._w is not None:
            self._w.finish()
            self._f.close()
            self._w = None

    def __enter__(self) -> "McapRecorder":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _scene_update(ob: dict[str, Any], ts: dict[str, int]) -> dict[str, Any]:
    cubes, spheres, cylinders = [], [], []
    colour = {"r": 0.2, "g": 0.45, "b": 0.95, "a": 1.0}
    for i in range(len(ob["type"])):
        p, q = ob["position_w"][i], ob["orientation_xyzw"][i]
        pose = {"position": {"x": p[0], "y": p[1], "z": p[2]}, "orientation": {"x": q[0], "y": q[1], "z": q[2], "w": q[3]}}
        t, rad, hl = int(ob["type"][i]), float(ob["radius_m"][i]), float(ob["half_length_m"][i])
        if t == 0:
            spheres.append({"pose": pose, "size": {"x": 2 * rad, "y": 2 * rad, "z": 2 * rad}, "color": colour})
        elif t in (2, 3):
            cylinders.append({"pose": pose, "size": {"x": 2 * rad, "y": 2 * rad, "z": 2 * hl + (2 * rad if t == 2 else 0)},
                              "bottom_scale": 1, "top_scale": 1, "color": colour})
        else:
            he = ob["half_extents_m"][i] if t == 1 else np.ptp(ob["hull_vertices_b"][i], axis=0) / 2 if len(ob["hull_vertices_b"][i]) else [0.1] * 3
            cubes.append({"pose": pose, "size": {"x": 2 * he[0], "y": 2 * he[1], "z": 2 * he[2]}, "color": colour})
    return {"deletions": [{"timestamp": ts, "type": 1, "id": ""}], "entities": [{
        "timestamp": ts, "frame_id": "world", "id": "obstacles", "lifetime": {"sec": 0, "nsec": 0}, "frame_locked": False,
        "metadata": [], "arrows": [], "cubes": cubes, "spheres": spheres, "cylinders": cylinders, "lines": [],
        "triangles": [], "texts": [], "models": []}]}


@dataclasses.dataclass
class Recording:
    scene: dict[str, Any]
    frames: list[Frame]


def read_recording(path: str) -> Recording:
    """A recording back as its scene and Frames (obstacles carried forward to every frame), with mcap's reader."""
    from mcap.reader import make_reader

    if not os.path.isfile(path):
        raise FileNotFoundError(f"recording: no such file {path!r}")
    scene: dict[str, Any] | None = None
    frames: list[Frame] = []
    obstacles: dict[int, dict[str, Any]] = {}
    images: dict[int, dict[str, list]] = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages(log_time_order=True):
            msg = json.loads(message.data)
            if channel.topic == "/kestrel/scene":
                scene = msg
            elif channel.topic == "/kestrel/obstacles":
                ob = {k: (np.asarray(v) if k != "hull_vertices_b" else [np.asarray(h, dtype=np.float64).reshape(-1, 3) for h in v])
                      for k, v in msg.items() if k not in ("timestamp", "step", "env")}
                obstacles = dict(obstacles)
                obstacles[msg["env"]] = ob
            elif channel.topic == "/kestrel/state":
                robots = {k: np.asarray(v) for k, v in msg.items()
                          if k not in ("timestamp", "step", "time_s", "envs", "fault_names")}
                frames.append(Frame(msg["step"], msg["time_s"], list(msg["envs"]), robots, obstacles))
            elif schema is not None and schema.name == "foxglove.RawImage":
                parts = channel.topic.strip("/").split("/")  # env<e>/robot<r>/<name>
                raw = base64.b64decode(msg["data"])
                if msg["encoding"] == "32FC1":
                    img = np.frombuffer(raw, "<f4").reshape(msg["height"], msg["width"])
                else:
                    img = np.frombuffer(raw, "<u2").reshape(msg["height"], msg["width"]).astype(np.int32) - 1
                images.setdefault(message.log_time, {}).setdefault(parts[2], []).append(img)
    if scene is None:
        raise ValueError(f"recording {path!r}: no /kestrel/scene message (not a kestrel recording)")
    for fr in frames:
        ns = int(round(fr.time_s * 1e9))
        fr.images = {k: np.stack(v) for k, v in images.get(ns, {}).items()}
    return Recording(scene, frames)


# ---- `kestrel run ... --record FILE / --view` -----------------------------------------------------------

def run_parser(prog: str = "kestrel run") -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog=prog, description=(
        "kestrel run from Python with a recording (--record FILE, MCAP) and/or the 3-D viewer (--view). "
        "Same scenario, policy and final state hash as the C++ `kestrel run`."))
    p.add_argument("scenario", nargs="?", default=None, help="scenario YAML (default: the embedded default scenario)")
    p.add_argument("--envs", type=int, default=None)
    p.add_argument("--steps", type=int, default=1000)
    p.add_argument("--threads", type=int, default=None)
    p.add_argument("--seed", type=int, default=None)
    p.add_argument("--task", default=None, help="an RL task id (runs its scripted controller)")
    p.add_argument("--policy", default="scripted", choices=("scripted", "zero"))
    p.add_argument("--out", default="kestrel_out", help="directory of summary.txt (default kestrel_out)")
    p.add_argument("--quiet", action="store_true")
    p.add_argument("--record", metavar="FILE", default=None, help="write the run to FILE (MCAP; Foxglove opens it)")
    p.add_argument("--record-envs", type=int, default=4, metavar="N",
                   help="record the first N environments (default 4; every robot of each)")
    p.add_argument("--no-images", action="store_true", help="leave the sensor images out of the recording")
    p.add_argument("--view", action="store_true", help="show the run in the 3-D viewer (a browser page)")
    p.add_argument("--view-envs", type=int, default=4, metavar="N", help="show the first N environments (default 4)")
    p.add_argument("--port", type=int, default=8080, help="viewer port (default 8080)")
    p.add_argument("--rate", type=float, default=None,
                   help="viewer: env-steps per second (default: real time, 1 / env-step duration)")
    return p


def load_run_config(scenario: str | None, task: str | None, envs: int | None, seed: int | None,
                    threads: int | None) -> tuple[_core.Config, str]:
    """The scenario as `kestrel run` reads it (file, --task's own scene, or the embedded default)."""
    if task is not None and task not in _core.rl_task_ids():
        raise ValueError(f"--task: unknown task {task!r}; registered task ids: {', '.join(_core.rl_task_ids())}")
    if scenario is not None:
        if task is not None:
            raise ValueError("--task with a scenario file: run it with the C++ `kestrel run` (no --record / --view), "
                             "or name the task inside the scenario")
        cfg, label = _core.load_scenario_file(scenario), scenario
    elif task is not None:
        cfg, label = _core.load_scenario_string(f"task: {task}\n", f"--task {task}"), f"--task {task}"
    else:
        cfg, label = _core.load_scenario_string(_core.default_scenario_yaml(), "<embedded default>"), "<embedded default>"
    if envs is not None:
        if envs < 1:
            raise ValueError(f"--envs: expected an integer >= 1, got {envs}")
        cfg.num_envs = envs
    if seed is not None:
        if seed < 0:
            raise ValueError(f"--seed: expected an integer >= 0, got {seed}")
        cfg.seed = seed
    cfg.num_threads = threads if threads is not None else max(1, os.cpu_count() or 1)
    return cfg, label


def run_main(argv: list[str], prog: str = "kestrel run") -> int:
    a = run_parser(prog).parse_args(argv)
    if a.steps < 1:
        print(f"{prog}: --steps expects an integer >= 1, got {a.steps}", file=sys.stderr)
        return 2
    try:
        cfg, label = load_run_config(a.scenario, a.task, a.envs, a.seed, a.threads)
        run = ScriptedRun(cfg, a.policy)
    except ValueError as e:
        print(f"kestrel: {e}", file=sys.stderr)
        return 1
    sim = run.sim
    rec_envs = list(range(min(max(1, a.record_envs), sim.num_envs)))
    recorder = McapRecorder(a.record, sim, rec_envs, run.env_step_s, label) if a.record else None
    viewer = None
    if a.view:
        from .viewer import LiveView

        viewer = LiveView(run, envs=list(range(min(max(1, a.view_envs), sim.num_envs))), port=a.port, rate=a.rate)
        print(f"kestrel run: viewer at {viewer.url}")
    print(f"kestrel run: {label} (from Python: {run.mode}, {sim.num_envs} envs, seed {cfg.seed}, steps {a.steps})", flush=True)
    from .progress import Progress

    # The C++ run's progress line, here too (a terminal only, off with --quiet): a recording with
    # images or a real-time view runs for minutes.
    progress = Progress(total=a.steps * sim.num_envs, unit="env-steps", desc="run", quiet=a.quiet)
    try:
        if recorder is not None:
            recorder.write(run.frame(rec_envs, images=not a.no_images))
        for _ in range(a.steps):
            if viewer is not None:
                viewer.step()
            else:
                run.step()
            if recorder is not None:
                recorder.write(run.frame(rec_envs, images=not a.no_images))
            progress.update(sim.num_envs)
        progress.close()
    finally:
        progress.close()
        if recorder is not None:
            recorder.close()
            print(f"  wrote {a.record} ({len(rec_envs)} envs x {a.steps + 1} frames; MCAP, opens in Foxglove)")
    os.makedirs(a.out, exist_ok=True)
    line = f"state hash: {run.state_hash:016x}"
    with open(os.path.join(a.out, "summary.txt"), "w") as f:
        f.write(f"kestrel run: {label} (from Python: {run.mode})\n{line}\n")
    print(line)
    if viewer is not None:
        viewer.hold()
    return 0
