"""The 3-D viewer: a browser page, live or replaying a recording (viser).

    kestrel view [SCENARIO] [--envs N] [--view-envs N] [--port 8080]   # live: the scripted run, as `kestrel run`
    kestrel view --replay run.mcap                                     # a recording, with a time slider
    kestrel teleop [SCENARIO] [--record run.mcap]                      # live, robot 0 of env 0 on the keyboard / mouse
    kestrel run SCENARIO --view [--record run.mcap]
    kestrel train TASK --view [--view-envs 4] [--port 8080]            # the first training envs as they learn

then open http://127.0.0.1:8080 in a browser. From Python:

    v = Viewer(sim.scene_info(), robots_per_env=sim.robots_per_env, envs=[0, 1, 2, 3])
    v.set_viewer_camera(position=(0, -8, 6), lookat=(0, 0, 0))
    v.draw(capture_frame(sim, [0, 1, 2, 3], step, t))   # kestrel.record.capture_frame
    v.draw_debug_vis(height_samples=True, contacts=True)

Why viser: a pip package (Python server + a prebuilt three.js client inside the wheel, so the page
needs no CDN, no npm and no build step, which this network-closed setting requires), used for
robotics and NeRF work (nerfstudio), with the scene primitives a robot world needs (boxes,
spheres, cylinders, meshes, frames, point clouds, line segments), GUI sliders and images in the
same page, per-client camera control, scene clicks and hotkeys. Rerun (`rerun-sdk`) is the other
well-kept choice, but its viewer is a native / wasm app whose web build is fetched or served as a
large wasm bundle, and its input side (keyboard / clicks back to Python) is not an API, which
teleoperation needs.

What is drawn, per environment shown (environments side by side on a grid, `env_spacing_m`
apart): the robots with their body frames (multirotor: body, arms and rotor discs, a rotor
turns red when its motor has a fault bit; legged: base, feet and legs as lines; ground vehicle:
a box), the targets / setpoints (green spheres), the obstacles as their collision shapes (convex
hulls as their bounding boxes), the terrain (height field as a mesh; a plane as a grid), the ray
sensors' returns (lidar, ToF, depth camera) as point clouds in the world, with a few of the
selected robot's rays as segments, and beside the scene each sensor image of the selected robot
(depth in grey, segmentation in colour).
draw_debug_vis draws LeggedGym-Ex's debug visuals: the height samples (measured_heights) as
points, contacts as points and their forces as line segments (1 mm per newton).

Colours are fixed (ROBOT_RGB, OBSTACLE_RGB, TARGET_RGB) so a test can find the robot and the
obstacles in a screenshot where the world says they are (python/tests/test_viewer.py).
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import threading
import time
from typing import Any, Callable

import numpy as np

from .record import (Frame, Recording, ScriptedRun, capture_frame, fault_names, load_run_config, obstacles_equal,
                     range_points_w, read_recording, sensor_origin_w, sensor_rays)

ROBOT_RGB = (255, 110, 0)      # orange body
ROTOR_RGB = (60, 60, 60)
ROTOR_FAULT_RGB = (220, 0, 0)
OBSTACLE_RGB = (40, 90, 230)   # blue
TARGET_RGB = (30, 190, 60)     # green
TERRAIN_RGB = (170, 160, 140)
HEIGHT_SAMPLE_RGB = (255, 0, 200)
CONTACT_RGB = (255, 30, 30)
# Sensor returns, one colour per range image k (cycled): cyan, yellow, purple.
RAY_RGB = ((0, 200, 220), (230, 200, 0), (150, 60, 220))
RAY_LINES_MAX = 48  # rays drawn as segments for the image robot (a few: thousands would hide the scene)
# A depth camera alone is 32k returns a robot: the clouds are what a page can take at the run's rate
# (every 1 / RAY_PERIOD_S s of wall time at most, RAY_POINTS_MAX points per environment and image,
# every n-th return beyond that); a replay draws every frame it shows.
RAY_PERIOD_S = 0.1
RAY_POINTS_MAX = 30_000

# kernel/status.hpp: non_finite_command, non_finite_state, motor_failure, non_finite_output.
_ROTOR_ALARM = (1 << 0) | (1 << 1) | (1 << 6) | (1 << 8)

VIEW_FOV_RAD = math.radians(60.0)  # the vertical field of view set on every client (a test projects with it)


def quat_xyzw_to_wxyz(q: np.ndarray) -> np.ndarray:
    q = np.asarray(q, dtype=np.float64)
    return np.array([q[3], q[0], q[1], q[2]])


def _rotate(q_xyzw: np.ndarray, v: np.ndarray) -> np.ndarray:
    """v (n, 3) rotated by the unit quaternion q (xyzw)."""
    x, y, z, w = q_xyzw
    u = np.array([x, y, z])
    v = np.atleast_2d(v)
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def _axis_to_z_wxyz(axis: np.ndarray) -> np.ndarray:
    """The rotation (wxyz) that takes +z onto `axis`."""
    a = np.asarray(axis, dtype=np.float64)
    a = a / (np.linalg.norm(a) or 1.0)
    c = float(a[2])
    if c < -0.999999:
        return np.array([0.0, 1.0, 0.0, 0.0])
    v = np.cross([0.0, 0.0, 1.0], a)
    q = np.array([1.0 + c, v[0], v[1], v[2]])
    return q / np.linalg.norm(q)


def _colour_of_segment(ids: np.ndarray) -> np.ndarray:
    """A colour per segmentation id (black: no hit, grey: ground), as the C++ PNG writer's hash."""
    ids = ids.astype(np.int64)
    h = (ids.astype(np.uint64) * np.uint64(2654435761)) & np.uint64(0xFFFFFFFF)
    rgb = np.stack([(h >> np.uint64(s)) & np.uint64(0xFF) for s in (0, 8, 16)], axis=-1).astype(np.uint8)
    rgb = (rgb // 2 + 64).astype(np.uint8)
    rgb[ids == 0] = 128
    rgb[ids < 0] = 0
    return rgb


def depth_to_grey(img: np.ndarray) -> np.ndarray:
    """A range image as 8-bit grey, near = bright; no return black."""
    img = np.asarray(img, dtype=np.float64)
    ok = np.isfinite(img) & (img > 0)
    top = float(img[ok].max()) if ok.any() else 1.0
    g = np.where(ok, 255.0 * (1.0 - img / max(top, 1e-9)) * 0.8 + 40.0, 0.0)
    return np.repeat(np.clip(g, 0, 255).astype(np.uint8)[..., None], 3, axis=-1)


def _upscale(img: np.ndarray, min_size: int = 96) -> np.ndarray:
    k = max(1, int(math.ceil(min_size / max(1, min(img.shape[:2])))))
    return np.repeat(np.repeat(img, k, axis=0), k, axis=1)


class Viewer:
    """A viser server drawing Frames (kestrel.record.Frame) of the environments `envs`."""

    def __init__(self, scene_info: dict[str, Any], robots_per_env: int, envs: list[int], *, host: str = "127.0.0.1",
                 port: int = 8080, env_spacing_m: float | None = None, title: str = "Kestrel"):
        import viser

        if not envs:
            raise ValueError("envs: expected at least one environment to show")
        if not (0 <= int(port) <= 65535):
            raise ValueError(f"port: expected 0..65535, got {port}")
        self.info, self.rpe, self.envs = scene_info, int(robots_per_env), list(envs)
        self.server = viser.ViserServer(host=host, port=port, label=title, verbose=False)
        self.host, self.port = host, self.server.get_port()
        self.scene = self.server.scene
        self.scene.set_up_direction("+z")
        self.server.gui.configure_theme(show_logo=False, dark_mode=False)
        self.env_spacing_m = env_spacing_m
        self._offsets: dict[int, np.ndarray] = {}
        self._robot_nodes: dict[int, dict[str, Any]] = {}
        self._obstacle_nodes: dict[int, list] = {}
        self._obstacles_drawn: dict[int, dict[str, Any]] = {}
        self._images: dict[str, Any] = {}
        self._frame: Frame | None = None
        self._debug_heights = self._debug_contacts = False
        self._camera: tuple[np.ndarray, np.ndarray] | None = None
        self._lock = threading.RLock()
        self.image_robot = 0
        # Per range image k: its rays (sensor_rays: scene_info's "range_rays", live or from a recording).
        self._rays = [{**r, "dirs_s": np.asarray(r["dirs_s"], np.float64), "depth_scale": np.asarray(r["depth_scale"], np.float64)}
                      for r in scene_info.get("range_rays", [])]
        self._ray_points: dict[tuple[int, int], np.ndarray] = {}
        self.ray_period_s, self._last_rays = RAY_PERIOD_S, -math.inf
        self.server.on_client_connect(self._on_connect)
        self.status = self.server.gui.add_markdown("**Kestrel** viewer")

    # ---- geometry -----------------------------------------------------------------------------
    @property
    def url(self) -> str:
        return f"http://{self.host}:{self.port}/"

    def env_offset(self, env: int) -> np.ndarray:
        """Where env is drawn: the world's own frame for the first env shown, the others on a grid beside it."""
        if env not in self._offsets:
            k = self.envs.index(env)
            cols = max(1, int(math.ceil(math.sqrt(len(self.envs)))))
            s = self.env_spacing_m or 10.0
            self._offsets[env] = np.array([(k % cols) * s, -(k // cols) * s, 0.0])
        return self._offsets[env]

    def _on_connect(self, client) -> None:
        client.camera.fov = VIEW_FOV_RAD
        if self._camera is not None:
            client.camera.up_direction = (0.0, 0.0, 1.0)
            client.camera.position = tuple(self._camera[0])
            client.camera.look_at = tuple(self._camera[1])

    def set_viewer_camera(self, position, lookat) -> None:
        """LeggedGym-Ex's set_viewer_camera: every client's (and every later client's) camera at
        `position` looking at `lookat` (world frame, m), z up, VIEW_FOV_RAD vertical field of view."""
        p = np.asarray(position, dtype=np.float64).reshape(-1)
        t = np.asarray(lookat, dtype=np.float64).reshape(-1)
        if p.shape != (3,) or t.shape != (3,) or not (np.isfinite(p).all() and np.isfinite(t).all()):
            raise ValueError(f"set_viewer_camera: position and lookat: expected 3 finite numbers each, got {position!r}, {lookat!r}")
        if np.linalg.norm(p - t) < 1e-6:
            raise ValueError("set_viewer_camera: position and lookat must differ")
        self._camera = (p, t)
        ic = self.server.initial_camera
        ic.up, ic.position, ic.look_at, ic.fov = (0.0, 0.0, 1.0), tuple(p), tuple(t), VIEW_FOV_RAD
        for c in self.server.get_clients().values():
            self._on_connect(c)

    def num_clients(self) -> int:
        return len(self.server.get_clients())

    # ---- static scene -------------------------------------------------------------------------
    def draw_static(self) -> None:
        """Terrain (height field mesh or a grid for the plane) under every environment shown."""
        info = self.info
        for e in self.envs:
            off = self.env_offset(e)
            if info.get("terrain") == "heightfield" and "heights_m" in info:
                h = np.asarray(info["heights_m"], dtype=np.float64)
                ny, nx = h.shape
                # A coarse copy for the page (at most ~200 x 200 samples): what a person reads, not contact.
                sy, sx = max(1, ny // 200), max(1, nx // 200)
                h = h[::sy, ::sx]
                ny2, nx2 = h.shape
                d = float(info["height_spacing_m"])
                c = np.asarray(info["height_corner_w"], dtype=np.float64)
                xs = c[0] + np.arange(nx2) * d * sx
                ys = c[1] + np.arange(ny2) * d * sy
                X, Y = np.meshgrid(xs, ys)
                verts = np.stack([X, Y, h + c[2]], axis=-1).reshape(-1, 3) + off
                i = np.arange(ny2 * nx2).reshape(ny2, nx2)
                a, b, cc, dd = i[:-1, :-1], i[:-1, 1:], i[1:, :-1], i[1:, 1:]
                faces = np.concatenate([np.stack([a, b, dd], -1).reshape(-1, 3), np.stack([a, dd, cc], -1).reshape(-1, 3)])
                self.scene.add_mesh_simple(f"/env{e}/terrain", vertices=verts.astype(np.float32), faces=faces.astype(np.uint32),
                                           color=TERRAIN_RGB, flat_shading=False, side="double")
            else:
                s = self.env_spacing_m or 10.0
                self.scene.add_grid(f"/env{e}/ground", width=s, height=s, position=tuple(off + [0, 0, 0.0]),
                                    cell_size=1.0, section_size=5.0, plane="xy", cell_color=(200, 200, 200),
                                    section_color=(150, 150, 150))

    # ---- robots --------------------------------------------------------------------------------
    def _make_robot(self, e: int, r: int) -> dict[str, Any]:
        info, base = self.info, f"/env{e}/robot{r}"
        nodes: dict[str, Any] = {"frame": self.scene.add_frame(base, axes_length=0.3, axes_radius=0.012)}
        kind = info.get("robot_kind", "multirotor")
        shape = info.get("robot_shape", {})
        if kind == "multirotor":
            rp = np.asarray(info.get("rotor_position_b_m", np.zeros((0, 3))), dtype=np.float64).reshape(-1, 3)
            span = float(np.max(np.linalg.norm(rp[:, :2], axis=1))) if len(rp) else float(shape.get("radius_m", 0.2))
            body = max(0.08, 0.55 * span)
            nodes["body"] = self.scene.add_box(f"{base}/body", color=ROBOT_RGB, dimensions=(body, body, 0.35 * body))
            if len(rp):
                arms = np.stack([np.zeros_like(rp), rp], axis=1)
                self.scene.add_line_segments(f"{base}/arms", points=arms.astype(np.float32), colors=ROTOR_RGB, thickness=3.0, thickness_units="screen")
            axes = np.asarray(info.get("rotor_axis_b", np.zeros((0, 3))), dtype=np.float64).reshape(-1, 3)
            nodes["rotors"] = [
                self.scene.add_cylinder(f"{base}/rotor{k}", radius=0.45 * span * math.sin(math.pi / max(3, len(rp))) + 0.02,
                                        height=0.01, color=ROTOR_RGB, position=tuple(rp[k]), wxyz=tuple(_axis_to_z_wxyz(axes[k])),
                                        opacity=0.85)
                for k in range(len(rp))]
        elif kind == "articulated":
            he = shape.get("half_extents_m", (0.2, 0.1, 0.06))
            dims = (max(0.3, 2 * he[0]), max(0.15, 2 * he[1]), max(0.08, 2 * he[2]))
            nodes["body"] = self.scene.add_box(f"{base}/body", color=ROBOT_RGB, dimensions=dims)
        else:
            nodes["body"] = self.scene.add_box(f"{base}/body", color=ROBOT_RGB, dimensions=(0.5, 0.3, 0.2))
        nodes["target"] = self.scene.add_icosphere(f"/env{e}/target{r}", radius=0.12, color=TARGET_RGB, opacity=0.8)
        return nodes

    def _draw_robots(self, fr: Frame) -> None:
        rot_fault = fr.robots.get("faults")
        for i in range(len(fr.robots["pos_w"])):
            e, r = fr.envs[i // self.rpe], i % self.rpe
            if e not in self.envs:
                continue
            key = self.envs.index(e) * self.rpe + r
            if key not in self._robot_nodes:
                self._robot_nodes[key] = self._make_robot(e, r)
            n = self._robot_nodes[key]
            off = self.env_offset(e)
            n["frame"].position = tuple(fr.robots["pos_w"][i] + off)
            n["frame"].wxyz = tuple(quat_xyzw_to_wxyz(fr.robots["quat_xyzw"][i]))
            n["target"].position = tuple(fr.robots["target_w"][i] + off)
            if rot_fault is not None and n.get("rotors"):
                # A motor failure or a non-finite value shows on the rotors (saturation, common in
                # hard manoeuvres, only in the status line).
                bad = int(rot_fault[i]) & _ROTOR_ALARM != 0
                for rn in n["rotors"]:
                    rn.color = ROTOR_FAULT_RGB if bad else ROTOR_RGB
            if "feet_pos_w" in fr.robots:
                feet = fr.robots["feet_pos_w"][i] + off
                base = fr.robots["pos_w"][i] + off
                self.scene.add_point_cloud(f"/env{e}/feet{r}", points=feet.astype(np.float32),
                                           colors=np.tile(np.array(ROTOR_RGB, np.uint8), (len(feet), 1)), point_size=0.06,
                                           point_shape="circle")
                legs = np.stack([np.repeat(base[None], len(feet), 0), feet], axis=1)
                self.scene.add_line_segments(f"/env{e}/legs{r}", points=legs.astype(np.float32), colors=ROTOR_RGB, thickness=4.0, thickness_units="screen")

    # ---- obstacles -----------------------------------------------------------------------------
    def _draw_obstacles(self, fr: Frame) -> None:
        for e, ob in fr.obstacles.items():
            if e not in self.envs:
                continue
            prev = self._obstacles_drawn.get(e)
            same_shapes = prev is not None and len(prev["type"]) == len(ob["type"]) and all(
                np.array_equal(prev[k], ob[k]) for k in ("type", "radius_m", "half_length_m", "half_extents_m"))
            off = self.env_offset(e)
            if same_shapes:
                if obstacles_equal(prev, ob):
                    continue
                for h, p, q in zip(self._obstacle_nodes[e], ob["position_w"], ob["orientation_xyzw"]):
                    h.position, h.wxyz = tuple(np.asarray(p) + off), tuple(quat_xyzw_to_wxyz(q))
                self._obstacles_drawn[e] = ob
                continue
            for h in self._obstacle_nodes.get(e, []):
                h.remove()
            handles = []
            for k in range(len(ob["type"])):
                name = f"/env{e}/obstacles/o{k}"
                t = int(ob["type"][k])
                pos, wxyz = tuple(np.asarray(ob["position_w"][k]) + off), tuple(quat_xyzw_to_wxyz(ob["orientation_xyzw"][k]))
                rad, hl = float(ob["radius_m"][k]), float(ob["half_length_m"][k])
                if t == 0:
                    h = self.scene.add_icosphere(name, radius=rad, color=OBSTACLE_RGB, position=pos, wxyz=wxyz)
                elif t in (2, 3):
                    # A capsule is drawn as its cylinder plus the caps' length (close enough to read).
                    h = self.scene.add_cylinder(name, radius=rad, height=2 * hl + (2 * rad if t == 2 else 0.0),
                                                color=OBSTACLE_RGB, position=pos, wxyz=wxyz)
                elif t == 1:
                    he = np.asarray(ob["half_extents_m"][k], dtype=np.float64)
                    h = self.scene.add_box(name, color=OBSTACLE_RGB, dimensions=tuple(2 * he), position=pos, wxyz=wxyz)
                else:
                    v = np.asarray(ob["hull_vertices_b"][k], dtype=np.float64).reshape(-1, 3)
                    lo, hi = (v.min(0), v.max(0)) if len(v) else (np.full(3, -0.1), np.full(3, 0.1))
                    h = self.scene.add_frame(name, show_axes=False, position=pos, wxyz=wxyz)
                    self.scene.add_box(f"{name}/hull", color=OBSTACLE_RGB, dimensions=tuple(hi - lo),
                                       position=tuple((hi + lo) / 2))
                handles.append(h)
            self._obstacle_nodes[e] = handles
            self._obstacles_drawn[e] = ob

    # ---- images --------------------------------------------------------------------------------
    def _draw_images(self, fr: Frame) -> None:
        i = self.image_robot
        for name, imgs in sorted(fr.images.items()):
            if i >= len(imgs):
                continue
            img = imgs[i]
            rgb = _colour_of_segment(img) if name.startswith("segmentation") else depth_to_grey(img)
            rgb = _upscale(rgb)
            if name not in self._images:
                with self.server.gui.add_folder(f"Sensor {name}"):
                    self._images[name] = self.server.gui.add_image(rgb, label=f"env {fr.envs[i // self.rpe]} robot {i % self.rpe}: {name}",
                                                                   format="png")
            else:
                self._images[name].image = rgb

    # ---- sensor returns ------------------------------------------------------------------------
    def _draw_rays(self, fr: Frame) -> None:
        """Each range image's returns as a point cloud per environment shown (every robot of it), and
        for the image robot up to RAY_LINES_MAX rays as segments from the sensor to its hit."""
        mp, mq = fr.robots.get("sensor_mount_pos_b"), fr.robots.get("sensor_mount_quat_bs")
        now = time.monotonic()
        if mp is None or mq is None or now - self._last_rays < self.ray_period_s:
            return
        self._last_rays = now
        for k, rays in enumerate(self._rays):
            imgs = fr.images.get(f"range{k}")
            if imgs is None:
                continue
            rgb = np.array(RAY_RGB[k % len(RAY_RGB)], np.uint8)
            per_env: dict[int, list[np.ndarray]] = {}
            for i in range(len(fr.robots["pos_w"])):
                e = fr.envs[i // self.rpe]
                if e not in self.envs:
                    continue
                pos, q = fr.robots["pos_w"][i], fr.robots["quat_xyzw"][i]
                pts = range_points_w(rays, imgs[i], pos, q, mp[i][k], mq[i][k]) + self.env_offset(e)
                per_env.setdefault(e, []).append(pts)
                if i == self.image_robot:
                    o = sensor_origin_w(pos, q, mp[i][k]) + self.env_offset(e)
                    pick = pts[np.linspace(0, len(pts) - 1, min(RAY_LINES_MAX, len(pts))).astype(int)] if len(pts) else pts
                    segs = np.stack([np.repeat(o[None], len(pick), 0), pick], axis=1) if len(pick) else np.zeros((0, 2, 3))
                    self.scene.add_line_segments(f"/env{e}/rays{k}_lines", points=segs.astype(np.float32), colors=rgb,
                                                 thickness=1.5, thickness_units="screen")
            for e, chunks in per_env.items():
                pts = np.concatenate(chunks) if chunks else np.zeros((0, 3))
                if len(pts) > RAY_POINTS_MAX:
                    pts = pts[:: -(-len(pts) // RAY_POINTS_MAX)]
                self._ray_points[(e, k)] = pts
                self.scene.add_point_cloud(f"/env{e}/rays{k}", points=pts.astype(np.float32),
                                           colors=np.tile(rgb, (len(pts), 1)), point_size=0.04, point_shape="circle")

    def ray_points(self, env: int, k: int = 0) -> np.ndarray:
        """The points last sent for range image k of environment env (world frame plus the env's
        drawing offset, env_offset(env)), every robot of the env: (n, 3); empty if none drawn."""
        return self._ray_points.get((env, k), np.zeros((0, 3))).copy()

    # ---- debug drawing ---------------------------------------------------------------------------
    def draw_debug_vis(self, height_samples: bool = True, contacts: bool = True) -> None:
        """LeggedGym-Ex's draw_debug_vis: from now on, each drawn frame also shows the height
        samples (measured_heights, magenta points), the contact points (red) and their forces (red
        segments, 1 mm per newton). Off again with False."""
        self._debug_heights, self._debug_contacts = bool(height_samples), bool(contacts)
        if self._frame is not None:
            self._draw_debug(self._frame)

    def _draw_debug(self, fr: Frame) -> None:
        info = self.info
        hx = np.asarray(info.get("height_points_x_b", []), dtype=np.float64)
        hy = np.asarray(info.get("height_points_y_b", []), dtype=np.float64)
        pts_h, pts_c, segs = [], [], []
        for i in range(len(fr.robots["pos_w"])):
            e = fr.envs[i // self.rpe]
            if e not in self.envs:
                continue
            off, p, q = self.env_offset(e), fr.robots["pos_w"][i], fr.robots["quat_xyzw"][i]
            if self._debug_heights and "measured_heights" in fr.robots and len(hx):
                x, y, z, w = q
                yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))  # legged_gym turns the points by yaw only
                c, s = math.cos(yaw), math.sin(yaw)
                pts_h.append(np.stack([p[0] + c * hx - s * hy, p[1] + s * hx + c * hy, fr.robots["measured_heights"][i]], -1) + off)
            if self._debug_contacts:
                if "feet_pos_w" in fr.robots and "link_contact_forces_w" in fr.robots:
                    feet = fr.robots["feet_pos_w"][i]
                    links = fr.robots["link_contact_forces_w"][i]
                    foot_links = _foot_links(info, len(feet))
                    for f, li in zip(feet, foot_links):
                        force = links[li] if li is not None and li < len(links) else np.zeros(3)
                        if np.linalg.norm(force) > 1e-6:
                            pts_c.append(f + off)
                            segs.append([f + off, f + off + 1e-3 * force])
                cf = fr.robots["contact_forces_w"][i]
                if np.linalg.norm(cf) > 1e-6:
                    pts_c.append(p + off)
                    segs.append([p + off, p + off + 1e-3 * cf])
        self._set_points("/debug/height_samples", pts_h, HEIGHT_SAMPLE_RGB, 0.03)
        self._set_points("/debug/contacts", [np.asarray(pts_c).reshape(-1, 3)] if pts_c else [], CONTACT_RGB, 0.05)
        if segs:
            self.scene.add_line_segments("/debug/contact_forces", points=np.asarray(segs, np.float32), colors=CONTACT_RGB,
                                         thickness=3.0, thickness_units="screen")
        else:
            self.scene.add_line_segments("/debug/contact_forces", points=np.zeros((0, 2, 3), np.float32), colors=CONTACT_RGB)

    def _set_points(self, name: str, chunks: list, rgb, size: float) -> None:
        pts = np.concatenate([np.asarray(c).reshape(-1, 3) for c in chunks]) if chunks else np.zeros((0, 3))
        self.scene.add_point_cloud(name, points=pts.astype(np.float32),
                                   colors=np.tile(np.array(rgb, np.uint8), (len(pts), 1)), point_size=size,
                                   point_shape="circle")

    # ---- a frame ----------------------------------------------------------------------------------
    def draw(self, fr: Frame) -> None:
        """Moves everything to frame fr (robots, targets, obstacles, images, debug drawing)."""
        with self._lock, self.server.atomic():
            if self._frame is None:
                self.draw_static()
            self._frame = fr
            self._draw_robots(fr)
            self._draw_obstacles(fr)
            self._draw_images(fr)
            self._draw_rays(fr)
            if self._debug_heights or self._debug_contacts:
                self._draw_debug(fr)
            faults = fr.robots.get("faults")
            ftxt = ""
            if faults is not None and int(np.max(faults, initial=0)) != 0:
                ftxt = f"; faults of robot 0: {', '.join(fault_names(int(faults[0]))) or 'none'}"
            self.status.content = f"**Kestrel** step {fr.step}, t = {fr.time_s:.2f} s, envs {self.envs}{ftxt}"

    def close(self) -> None:
        self.server.stop()


def _foot_links(info: dict[str, Any], num_feet: int) -> list[int | None]:
    """Indices of the foot bodies among the links (link_contact_forces_w rows), by name."""
    names = list(info.get("link_names", []))
    feet = [i for i, n in enumerate(names) if "foot" in n.lower()]
    if len(feet) == num_feet:
        return feet
    return [None] * num_feet


def default_camera(scene_info: dict[str, Any], fr: Frame, offset: np.ndarray = np.zeros(3)) -> tuple[np.ndarray, np.ndarray]:
    """A camera behind and above the first robot, looking at it."""
    p = np.asarray(fr.robots["pos_w"][0], dtype=np.float64) + offset
    kind = scene_info.get("robot_kind")
    d = 2.0 if kind == "articulated" else 3.0
    return p + np.array([-0.9 * d, -0.9 * d, 0.8 * d]), p


# ---- live ---------------------------------------------------------------------------------------------

class Teleop:
    """Keyboard and mouse teleoperation of one robot (robot row `row`), on the page's hotkeys.

    Multirotor under lee_position_control (action [x, y, z, yaw]): W / S move the setpoint
    +x / -x, A / D +y / -y, R / F up / down (`step_m` each press), Q / E turn the yaw setpoint,
    and a click on the scene puts the setpoint where the ray meets the setpoint's height. Ground
    vehicle (action [speed, steering]): W / S speed up / down, A / D steer left / right. Space
    stops (multirotor: setpoint back to the robot's position)."""

    KEYS = ("w", "s", "a", "d", "r", "f", "q", "e", "space")

    def __init__(self, run: ScriptedRun, row: int = 0, step_m: float = 0.5):
        sim = run.sim
        self.run, self.row, self.step_m = run, int(row), float(step_m)
        ctrl = sim.controller
        if run.mode == "task":
            raise ValueError("teleop: an RL task's actions are its policy's; teleoperate a scenario without `task:` "
                             "(controller lee_position_control, or the planar ground vehicle)")
        if ctrl == "lee_position_control" and sim.action_dim == 4:
            if run.cfg.setpoint_speed_m_s > 0:
                raise ValueError(f"teleop: task.setpoint_speed_m_s is {run.cfg.setpoint_speed_m_s:g}: the World's moving "
                                 "setpoint would overwrite the commands; set it to 0 (kestrel.viewer.teleop_config does)")
            self.kind = "position"
            p = np.array(sim.base_pos_w[self.row], dtype=np.float64)
            self.command = np.array([p[0], p[1], max(p[2], 1.0), 0.0])
        elif ctrl == "velocity_steering_control":
            self.kind = "ground_vehicle"
            self.command = np.zeros(2)
        else:
            raise ValueError(f"teleop: controller {ctrl!r}: expected lee_position_control (multirotors) or "
                             "velocity_steering_control (planar ground vehicle)")
        self.presses: list[str] = []
        self._lock = threading.Lock()

    def key(self, k: str) -> None:
        if k not in self.KEYS:
            raise ValueError(f"key: expected one of {', '.join(self.KEYS)}, got {k!r}")
        with self._lock:
            self.presses.append(k)
            c, s = self.command, self.step_m
            if self.kind == "position":
                d = {"w": (0, s), "s": (0, -s), "a": (1, s), "d": (1, -s), "r": (2, s), "f": (2, -s),
                     "q": (3, math.pi / 8), "e": (3, -math.pi / 8)}.get(k)
                if d is not None:
                    c[d[0]] += d[1]
                    c[2] = max(c[2], 0.2)
                elif k == "space":
                    c[:3] = np.array(self.run.sim.base_pos_w[self.row], dtype=np.float64)
            else:
                d = {"w": (0, 0.5), "s": (0, -0.5), "a": (1, 0.1), "d": (1, -0.1)}.get(k)
                if d is not None:
                    c[d[0]] += d[1]
                    c[1] = float(np.clip(c[1], -0.6, 0.6))
                elif k == "space":
                    c[:] = 0

    def click(self, ray_origin, ray_direction, offset: np.ndarray) -> None:
        """A click: the setpoint goes where the ray meets the plane z = the setpoint's height."""
        if self.kind != "position":
            return
        o = np.asarray(ray_origin, dtype=np.float64) - offset
        d = np.asarray(ray_direction, dtype=np.float64)
        with self._lock:
            if abs(d[2]) < 1e-9:
                return
            t = (self.command[2] - o[2]) / d[2]
            if t > 0:
                self.command[:2] = (o + t * d)[:2]
                self.presses.append("click")

    def override(self) -> dict[int, np.ndarray]:
        with self._lock:
            return {self.row: self.command.copy()}


def teleop_config(cfg) -> None:
    """What a teleoperated run changes in its scenario: no moving setpoint (the keys move it) and
    episodes long enough not to reset the robot under the person's hands (one day of env-steps)."""
    cfg.setpoint_speed_m_s = 0.0
    cfg.episode_len_env_steps = max(cfg.episode_len_env_steps, 4_320_000)


class LiveView:
    """A ScriptedRun shown live in a Viewer: step() advances the run at `rate` env-steps per second
    (default: real time) and draws it; with teleop, robot 0 of the first env shown is driven from
    the page (Teleop)."""

    def __init__(self, run: ScriptedRun, envs: list[int], port: int = 8080, rate: float | None = None,
                 teleop: bool = False, host: str = "127.0.0.1", images: bool = True):
        self.run, self.envs, self.images = run, list(envs), images
        sim = run.sim
        # Teleop's checks first: a refusal then leaves no server behind.
        self.teleop = Teleop(run, row=self.envs[0] * sim.robots_per_env) if teleop else None
        bounds = [sim.env_bounds(e) for e in self.envs] if sim.backend == "rigid" else []
        spacing = max([float(hi[0] - lo[0]) for lo, hi in bounds] + [float(hi[1] - lo[1]) for lo, hi in bounds] + [4.0]) + 2.0
        info = sim.scene_info()
        info["range_rays"] = sensor_rays(sim)
        self.viewer = Viewer(info, sim.robots_per_env, self.envs, host=host, port=port, env_spacing_m=spacing)
        self.rate = float(rate) if rate else 1.0 / max(run.env_step_s, 1e-6)
        if not self.rate > 0:
            raise ValueError(f"rate: expected env-steps per second > 0, got {rate}")
        if self.teleop is not None:
            self._bind_teleop()
        self.paused = False
        pause = self.viewer.server.gui.add_checkbox("Pause", initial_value=False)

        @pause.on_update
        def _(_ev) -> None:
            self.paused = bool(pause.value)

        self._next = time.monotonic()
        fr = run.frame(self.envs, images=images)
        self.viewer.set_viewer_camera(*default_camera(self.viewer.info, fr, self.viewer.env_offset(self.envs[0])))
        self.viewer.draw(fr)

    def _bind_teleop(self) -> None:
        gui = self.viewer.server.gui
        t = self.teleop
        labels = {"w": "forward (+x) / faster", "s": "back (-x) / slower", "a": "left (+y) / steer left",
                  "d": "right (-y) / steer right", "r": "up", "f": "down", "q": "yaw left", "e": "yaw right",
                  "space": "stop"}
        with gui.add_folder("Teleop"):
            gui.add_markdown("Keys: W/S, A/D, R/F (up/down), Q/E (yaw), Space (stop); click the scene to move the setpoint.")
            self._teleop_text = gui.add_markdown("")
        for k in Teleop.KEYS:
            cmd = gui.add_command(f"Teleop: {labels[k]}", hotkey=k if k != "space" else "space")
            cmd.on_trigger(lambda _ev, k=k: t.key(k))
        off = self.viewer.env_offset(self.envs[0])

        @self.viewer.scene.on_click()
        def _(ev) -> None:
            t.click(ev.ray_origin, ev.ray_direction, off)

    @property
    def url(self) -> str:
        return self.viewer.url

    def step(self) -> None:
        """One env-step of the run (paced to the rate; held while paused), then draws it."""
        while self.paused:
            time.sleep(0.05)
        now = time.monotonic()
        if self._next > now:
            time.sleep(self._next - now)
        self._next = max(self._next + 1.0 / self.rate, time.monotonic() - 0.5)
        self.run.step(self.teleop.override() if self.teleop is not None else None)
        fr = self.run.frame(self.envs, images=self.images)
        if self.teleop is not None:
            fr.robots["target_w"][0] = self.teleop.command[:3] if self.teleop.kind == "position" else fr.robots["target_w"][0]
            self._teleop_text.content = f"command: {np.round(self.teleop.command, 2).tolist()}"
        self.viewer.draw(fr)

    def hold(self) -> None:
        """Keeps the page up after the run (Ctrl-C ends it)."""
        print(f"kestrel: the run is over; the viewer stays at {self.url} (Ctrl-C to quit)")
        try:
            while True:
                time.sleep(1.0)
        except KeyboardInterrupt:
            pass
        finally:
            self.close()

    def close(self) -> None:
        self.viewer.close()


# ---- training -----------------------------------------------------------------------------------------

class TrainView:
    """`kestrel train --view`: the first environments of a training vector env in a Viewer, drawn
    from inside env.step at most `fps` times a second of wall time (and at most every `every`
    env-steps), so the learner runs at nearly its own pace: a frame copies only the shown
    environments' rows (capture_frame) and viser sends only what changed. The sensor images and
    point clouds come with the frame when the task renders any (images=True)."""

    def __init__(self, env, view_envs: int = 4, port: int = 8080, host: str = "127.0.0.1", fps: float = 10.0,
                 every: int = 1, images: bool = True):
        task = getattr(env, "task", None)
        sim = getattr(task, "simulator", None) if task is not None else None
        if sim is None:
            raise ValueError("--view: the environments are not in this process (a Ray rollout env); "
                             "view one of its scenarios with `kestrel view` instead")
        if not fps > 0 or int(every) < 1:
            raise ValueError(f"--view-fps: expected > 0, got {fps}; --view-every: expected >= 1, got {every}")
        self.env, self.sim = env, sim
        self.envs = list(range(min(max(1, int(view_envs)), sim.num_envs)))
        self.min_period_s, self.every, self.images = 1.0 / float(fps), int(every), images
        self.env_step_s = sim.dt_s * sim.decimation
        self.steps = 0           # env.step calls seen
        self.frames_drawn = 0
        self.draw_s = 0.0        # wall time spent drawing (what the viewer costs the training)
        info = sim.scene_info()
        info["range_rays"] = sensor_rays(sim)
        bounds = [sim.env_bounds(e) for e in self.envs] if sim.backend == "rigid" else []
        spacing = max([float(hi[0] - lo[0]) for lo, hi in bounds] + [float(hi[1] - lo[1]) for lo, hi in bounds] + [4.0]) + 2.0
        self.viewer = Viewer(info, sim.robots_per_env, self.envs, host=host, port=port, env_spacing_m=spacing,
                             title="Kestrel training")
        self.viewer.ray_period_s = 0.0  # this class paces the frames itself (fps)
        fr = self._frame()
        self.viewer.set_viewer_camera(*default_camera(info, fr, self.viewer.env_offset(self.envs[0])))
        self._draw(fr)
        self._last_draw = time.monotonic()
        self._last_step = 0
        inner = env.step

        def step_and_draw(actions):
            out = inner(actions)
            self.steps += 1
            now = time.monotonic()
            if self.steps - self._last_step >= self.every and now - self._last_draw >= self.min_period_s:
                self._last_step, self._last_draw = self.steps, now
                self._draw(self._frame())
            return out

        env.step = step_and_draw  # the learner's adapters call env.step: every rollout step passes here

    @property
    def url(self) -> str:
        return self.viewer.url

    def _frame(self) -> Frame:
        return capture_frame(self.sim, self.envs, self.steps, self.steps * self.env_step_s, images=self.images)

    def _draw(self, fr: Frame) -> None:
        t0 = time.perf_counter()
        self.viewer.draw(fr)
        self.frames_drawn += 1
        self.draw_s += time.perf_counter() - t0

    def close(self) -> None:
        self.viewer.close()


# ---- replay -------------------------------------------------------------------------------------------

class ReplayView:
    """A recording in a Viewer with a time slider (and play / pause)."""

    def __init__(self, rec: Recording, envs: list[int] | None = None, port: int = 8080, host: str = "127.0.0.1"):
        if not rec.frames:
            raise ValueError("recording: it has no frames")
        self.rec = rec
        sc = rec.scene
        shown = list(envs) if envs else list(sc["envs"])
        missing = [e for e in shown if e not in sc["envs"]]
        if missing:
            raise ValueError(f"envs: {missing} not in the recording; it has envs {sc['envs']}")
        self.viewer = Viewer(sc["info"], sc["robots_per_env"], shown, host=host, port=port)
        self.viewer.ray_period_s = 0.0  # the frame the slider names, clouds included
        gui = self.viewer.server.gui
        self.slider = gui.add_slider("Time step", min=0, max=len(rec.frames) - 1, step=1, initial_value=0)
        self.play = gui.add_checkbox("Play", initial_value=False)
        self.slider.on_update(lambda _ev: self.show(int(self.slider.value)))
        first = rec.frames[0]
        self.viewer.set_viewer_camera(*default_camera(sc["info"], first, self.viewer.env_offset(shown[0])))
        self.show(0)

    @property
    def url(self) -> str:
        return self.viewer.url

    def show(self, k: int) -> None:
        if not 0 <= k < len(self.rec.frames):
            raise ValueError(f"k: expected a frame index in [0, {len(self.rec.frames)}), got {k}")
        self.viewer.draw(self.rec.frames[k])

    def serve(self) -> None:
        dt = float(self.rec.scene.get("env_step_s", 0.02)) or 0.02
        try:
            while True:
                if self.play.value:
                    k = (int(self.slider.value) + 1) % len(self.rec.frames)
                    self.slider.value = k  # on_update draws it
                time.sleep(dt)
        except KeyboardInterrupt:
            pass
        finally:
            self.viewer.close()


# ---- `kestrel view` / `kestrel teleop` -------------------------------------------------------------------

def view_parser(prog: str) -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog=prog, description="The 3-D viewer in a browser page (viser): live, a replay, or teleoperation.")
    p.add_argument("scenario", nargs="?", default=None, help="scenario YAML (default: the embedded default scenario)")
    p.add_argument("--replay", metavar="FILE", default=None, help="show a recording (kestrel run --record FILE) with a time slider")
    p.add_argument("--task", default=None)
    p.add_argument("--envs", type=int, default=None, help="environments simulated (default: the scenario's)")
    p.add_argument("--view-envs", type=int, default=4, metavar="N", help="environments shown (default 4)")
    p.add_argument("--steps", type=int, default=0, help="env-steps to run (default 0: until Ctrl-C)")
    p.add_argument("--seed", type=int, default=None)
    p.add_argument("--threads", type=int, default=None)
    p.add_argument("--port", type=int, default=8080)
    p.add_argument("--rate", type=float, default=None, help="env-steps per second (default: real time)")
    p.add_argument("--teleop", action="store_true", help="drive robot 0 of env 0 from the page's keyboard / mouse")
    p.add_argument("--debug-vis", action="store_true", help="draw height samples, contacts and contact forces")
    p.add_argument("--camera", type=float, nargs=6, metavar=("PX", "PY", "PZ", "LX", "LY", "LZ"), default=None,
                   help="camera position and look-at point (m, world)")
    p.add_argument("--screenshot", metavar="PNG", default=None,
                   help="after --steps env-steps, save a headless Chromium screenshot of the page and quit")
    p.add_argument("--size", type=int, nargs=2, default=(1280, 720), metavar=("W", "H"), help="screenshot size")
    p.add_argument("--record", metavar="FILE", default=None,
                   help="live (and teleop): also write the run to FILE (MCAP, as kestrel run --record), until --steps or Ctrl-C")
    p.add_argument("--record-envs", type=int, default=4, metavar="N", help="record the first N environments (default 4)")
    p.add_argument("--no-hold", action="store_true", help="quit when --steps are done (default: keep the page up)")
    p.add_argument("--quiet", action="store_true", help="no progress line (it is shown only on a terminal anyway)")
    return p


def _apply_view_options(viewer, a) -> None:
    """--camera EYE LOOKAT and --debug-vis, the same for a live run and a replay."""
    if a.camera:
        viewer.set_viewer_camera(a.camera[:3], a.camera[3:])
    if a.debug_vis:
        viewer.draw_debug_vis(True, True)


def view_main(argv: list[str], prog: str = "kestrel view", teleop: bool = False) -> int:
    a = view_parser(prog).parse_args(argv)
    a.teleop = a.teleop or teleop
    if a.replay is not None:
        if a.teleop:
            print(f"{prog}: --teleop drives a live run; a replay cannot be driven", file=sys.stderr)
            return 2
        try:
            rv = ReplayView(read_recording(a.replay), port=a.port)
        except (ValueError, FileNotFoundError) as e:
            print(f"kestrel: {e}", file=sys.stderr)
            return 1
        _apply_view_options(rv.viewer, a)
        if a.screenshot:
            return _screenshot(rv.viewer, a.screenshot, a.size, close=True)
        print(f"kestrel view: {a.replay}, {len(rv.rec.frames)} frames, at {rv.url}")
        rv.serve()
        return 0
    try:
        cfg, label = load_run_config(a.scenario, a.task, a.envs, a.seed, a.threads)
        if a.teleop:
            teleop_config(cfg)
        run = ScriptedRun(cfg)
        envs = list(range(min(max(1, a.view_envs), run.sim.num_envs)))
        live = LiveView(run, envs, port=a.port, rate=a.rate, teleop=a.teleop)
    except ValueError as e:
        print(f"kestrel: {e}", file=sys.stderr)
        return 1
    _apply_view_options(live.viewer, a)
    print(f"kestrel view: {label} ({run.mode}) at {live.url}" + (" (teleop: W/S A/D R/F Q/E, Space, click)" if a.teleop else ""),
          flush=True)
    recorder = None
    if a.record:
        from .record import McapRecorder

        rec_envs = list(range(min(max(1, a.record_envs), run.sim.num_envs)))
        recorder = McapRecorder(a.record, run.sim, rec_envs, run.env_step_s, label)
        recorder.write(_teleop_frame(live, rec_envs))
    from .progress import Progress

    # A teleoperated (or live) run can go on for minutes: a progress line on a terminal, open-ended
    # without --steps (env-steps done, rate, time so far).
    progress = Progress(total=a.steps * run.sim.num_envs if a.steps > 0 else None, unit="env-steps",
                        desc="teleop" + (" recording" if recorder else "") if a.teleop else "view", quiet=a.quiet)
    k = 0
    try:
        if a.screenshot:
            live.rate = 1e9  # as fast as it steps: the picture is of the state after --steps
            for _ in range(a.steps):
                live.step()
            return _screenshot(live.viewer, a.screenshot, a.size, close=False)
        while a.steps <= 0 or k < a.steps:
            live.step()
            k += 1
            if recorder is not None:
                recorder.write(_teleop_frame(live, rec_envs))
            progress.update(run.sim.num_envs)
        progress.close()
        if recorder is not None:
            recorder.close()
            print(f"kestrel view: wrote {a.record} ({len(rec_envs)} envs x {k + 1} frames)", flush=True)
            recorder = None
        if not a.no_hold:
            live.hold()
    except KeyboardInterrupt:
        pass
    finally:
        progress.close()
        if recorder is not None:  # Ctrl-C while recording: the file is finished, not lost
            recorder.close()
            print(f"kestrel view: wrote {a.record} ({len(rec_envs)} envs x {k + 1} frames)", flush=True)
        live.close()
    return 0


def _teleop_frame(live: LiveView, envs: list[int]) -> Frame:
    """The run's frame with the teleoperated robot's setpoint as its target (what the person set)."""
    fr = live.run.frame(envs)
    t = live.teleop
    if t is not None and t.kind == "position" and t.row < len(envs) * live.run.sim.robots_per_env:
        fr.robots["target_w"][t.row] = t.command[:3]
    return fr


def _screenshot(viewer: Viewer, path: str, size, close: bool) -> int:
    from .browser import HeadlessChromium

    try:
        with HeadlessChromium(width=size[0], height=size[1]) as b:
            b.open(viewer.url)
            rgb_robot = np.array(ROBOT_RGB)

            def drawn(img: np.ndarray) -> bool:
                return bool((np.abs(img.astype(int) - rgb_robot).sum(-1) < 120).sum() > 20)

            png, _ = b.screenshot_when(drawn, timeout_s=40)
            # The page's "software WebGL" notice (SwiftShader) is about the headless browser, not the scene.
            b.evaluate("document.querySelectorAll('.mantine-Notification-root button, .mantine-Notification-closeButton')"
                       ".forEach(x => x.click())")
            time.sleep(1.0)
            png = b.screenshot()
        with open(path, "wb") as f:
            f.write(png)
        print(f"kestrel view: wrote {path}")
        return 0
    finally:
        if close:
            viewer.close()
