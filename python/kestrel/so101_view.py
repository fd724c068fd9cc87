"""kestrel.so101_view: the SO-101 pick-and-place scene live in the viewer's browser page (viser), for
`kestrel teleop --task Kestrel-SO101-PickPlace-v0` (kestrel.so101_teleop).

Drawn from Task.pick_place_state(env)["shapes"], every step: each collision shape of the arm, the
cube and the box as a box / cylinder (capsules) / sphere, in fixed entity colours (ENTITY_RGB:
robot orange with grey base and jaw pads, cube red, box blue, table brown), plus a table slab under
the scene; the front and wrist camera images in the side panel (Task.render_camera, small and every
few steps), a status line (tcp position, grip force, cube_in_box, episode) and the teleoperation
keys as the page's hotkeys (LeIsaac's map: kestrel.so101_teleop.KeyboardTeleop; B start, R reset as
failed, N reset as success). A hotkey reports key presses and auto-repeats, not releases: each
press holds its key for PAGE_KEY_HOLD_S (a held key's repeats keep it held).
"""
from __future__ import annotations

import threading
import time
from typing import Any

import numpy as np

from .so101_teleop import KeyboardTeleop, PAGE_KEY_HOLD_S
from .viewer import VIEW_FOV_RAD

ROBOT_RGB = (255, 110, 0)     # the viewer's robot orange (kestrel.viewer.ROBOT_RGB)
ROBOT_GREY_RGB = (90, 90, 90)
CUBE_RGB = (220, 20, 20)
BOX_RGB = (40, 90, 230)
TABLE_RGB = (150, 100, 60)
ENTITY_RGB = {"robot": ROBOT_RGB, "cube": CUBE_RGB, "box": BOX_RGB, "table": TABLE_RGB}
# The table: the world's z = 0 plane (the task has no table shape); a slab drawn under the scene.
TABLE_CENTER = (0.2, 0.05, -0.01)
TABLE_HALF = (0.35, 0.35, 0.01)
CAMERA = ((0.62, -0.42, 0.42), (0.18, 0.05, 0.06))  # default page camera: position, look-at (m, world)
KEY_LABELS = {"W": "forward (+x)", "S": "backward (-x)", "A": "left (+y)", "D": "right (-y)", "Q": "up", "E": "down",
              "J": "yaw left", "L": "yaw right", "I": "pitch up (ignored)", "K": "pitch down (ignored)",
              "U": "gripper open", "O": "gripper close", "B": "start control / recording",
              "R": "reset: failed (discard)", "N": "reset: success (save)"}


def _wxyz(R9) -> tuple[float, float, float, float]:
    """Unit quaternion (w, x, y, z) of a row-major 3 x 3 rotation."""
    m = np.asarray(R9, dtype=np.float64).reshape(3, 3)
    t = np.trace(m)
    if t > 0:
        s = 2.0 * np.sqrt(t + 1.0)
        q = (0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s)
    else:
        i = int(np.argmax(np.diag(m)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * np.sqrt(max(1e-12, 1.0 + m[i, i] - m[j, j] - m[k, k]))
        v = [0.0, 0.0, 0.0]
        v[i] = 0.25 * s
        v[j] = (m[j, i] + m[i, j]) / s
        v[k] = (m[k, i] + m[i, k]) / s
        q = ((m[k, j] - m[j, k]) / s, *v)
    q = np.asarray(q)
    q /= np.linalg.norm(q)
    return tuple(float(x) for x in q)


def shape_rgb(shape: dict) -> tuple[int, int, int]:
    if shape["entity"] == "robot":
        # The base's servo housing (the two lowest links) and the thin jaw pads grey, the rest orange.
        if shape["index"] < 2 or (shape["type"] == "box" and min(shape["size"]) <= 0.0025):
            return ROBOT_GREY_RGB
        return ROBOT_RGB
    return ENTITY_RGB.get(shape["entity"], (128, 128, 128))


class PickPlaceView:
    """A viser page showing env `env_index` of a Kestrel-SO101-PickPlace-v0 env."""

    def __init__(self, env, env_index: int = 0, port: int = 8080, host: str = "127.0.0.1",
                 image_size: tuple[int, int] = (320, 240), image_every: int = 3, title: str = "Kestrel SO-101"):
        import viser

        self.env, self.env_index = env, int(env_index)
        self.image_size, self.image_every = (int(image_size[0]), int(image_size[1])), max(1, int(image_every))
        self.server = viser.ViserServer(host=host, port=port, label=title, verbose=False)
        self.host, self.port = host, self.server.get_port()
        self.scene = self.server.scene
        self.scene.set_up_direction("+z")
        self.server.gui.configure_theme(show_logo=False, dark_mode=False)
        self._lock = threading.RLock()
        self._nodes: dict[tuple[str, int], Any] = {}
        self._kinds: dict[tuple[str, int], tuple] = {}
        self.frames_drawn = 0
        self.images_sent = 0
        self._draw_s = 0.0
        self.scene.add_box("/table", color=TABLE_RGB, dimensions=tuple(2 * np.asarray(TABLE_HALF)), position=TABLE_CENTER)
        self.set_camera(*CAMERA)
        self.server.on_client_connect(self._on_connect)
        self.status = self.server.gui.add_markdown("**SO-101 pick and place**")
        self._images: dict[str, Any] = {}
        w, h = self.image_size
        with self.server.gui.add_folder("Cameras"):
            for cam in ("front", "wrist"):
                self._images[cam] = self.server.gui.add_image(np.zeros((h, w, 3), np.uint8), label=cam, format="jpeg",
                                                              jpeg_quality=80)
        self._keys_md = None

    @property
    def url(self) -> str:
        return f"http://{self.host}:{self.port}/"

    def num_clients(self) -> int:
        return len(self.server.get_clients())

    def _on_connect(self, client) -> None:
        client.camera.fov = VIEW_FOV_RAD
        client.camera.up_direction = (0.0, 0.0, 1.0)
        client.camera.position = tuple(self._camera[0])
        client.camera.look_at = tuple(self._camera[1])

    def set_camera(self, position, lookat) -> None:
        """Every client's camera (and later clients') at position looking at lookat, z up, VIEW_FOV_RAD."""
        self._camera = (np.asarray(position, np.float64), np.asarray(lookat, np.float64))
        ic = self.server.initial_camera
        ic.up, ic.position, ic.look_at, ic.fov = (0.0, 0.0, 1.0), tuple(self._camera[0]), tuple(self._camera[1]), VIEW_FOV_RAD
        for c in self.server.get_clients().values():
            self._on_connect(c)

    def bind_keys(self, device) -> None:
        """The page's hotkeys drive `device` (KeyboardTeleop: every key; another device (the leader
        arm): B, R, N only) through device.press(key, hold_s=PAGE_KEY_HOLD_S)."""
        gui = self.server.gui
        keys = list(KEY_LABELS) if isinstance(device, KeyboardTeleop) else ["B", "R", "N"]
        with gui.add_folder("Teleop keys"):
            self._keys_md = gui.add_markdown(" / ".join(f"**{k}** {KEY_LABELS[k]}" for k in keys))
        self.presses: list[str] = []
        for k in keys:
            cmd = gui.add_command(f"{k}: {KEY_LABELS[k]}", hotkey=k)

            def on(_ev, k=k) -> None:
                self.presses.append(k)
                device.press(k, hold_s=PAGE_KEY_HOLD_S)

            cmd.on_trigger(on)

    # ---- drawing --------------------------------------------------------------------------------
    def _add(self, name: str, sh: dict):
        rgb, size = shape_rgb(sh), [float(x) for x in sh["size"]]
        if sh["type"] == "box":
            return self.scene.add_box(name, color=rgb, dimensions=tuple(2 * np.asarray(size)))
        if sh["type"] == "sphere":
            return self.scene.add_icosphere(name, radius=size[0], color=rgb)
        # capsule (radius, half-length along its z): drawn as a cylinder of the capsule's length
        return self.scene.add_cylinder(name, radius=size[0], height=2 * size[1] + 2 * size[0], color=rgb)

    def draw(self, state: dict, status: str = "") -> None:
        """Moves every shape to `state` (Task.pick_place_state) and sets the status line."""
        t0 = time.perf_counter()
        with self._lock, self.server.atomic():
            for sh in state["shapes"]:
                key = (sh["entity"], int(sh["index"]))
                kind = (sh["type"], tuple(round(float(x), 6) for x in sh["size"]))
                if key not in self._nodes or self._kinds[key] != kind:
                    if key in self._nodes:
                        self._nodes[key].remove()
                    self._nodes[key] = self._add(f"/so101/{key[0]}{key[1]}", sh)
                    self._kinds[key] = kind
                n = self._nodes[key]
                n.position = tuple(float(x) for x in sh["pos_w"])
                n.wxyz = _wxyz(sh["R_w"])
            if status:
                self.status.content = status
        self.frames_drawn += 1
        self._draw_s += time.perf_counter() - t0

    def show_images(self, images: dict[str, np.ndarray]) -> None:
        """Camera frames into the side panel (downscaled by an integer factor to about image_size)."""
        w = self.image_size[0]
        for cam, img in images.items():
            if cam in self._images:
                k = max(1, int(img.shape[1]) // w)
                self._images[cam].image = np.ascontiguousarray(img[::k, ::k])
        self.images_sent += 1

    def render_images(self) -> dict[str, np.ndarray]:
        w, h = self.image_size
        return {c: self.env.task.render_camera(self.env_index, c, width=w, height=h)[0] for c in self._images}

    def update(self, ctx: dict, status: str = "") -> None:
        """teleop_loop's on_step: draws the state; every image_every ticks the camera images (the
        recorded frames when this tick recorded some, else rendered at image_size)."""
        self.draw(self.env.task.pick_place_state(self.env_index), status)
        if ctx["stats"]["ticks"] % self.image_every == 0 or self.frames_drawn == 1:
            self.show_images(ctx["images"] or self.render_images())

    def close(self) -> None:
        self.server.stop()
