"""Headless Chromium driven through the DevTools protocol: screenshots of the viewer and key presses.

Used by the viewer's browser test (python/tests/test_viewer.py) and by `kestrel view --screenshot`
(the README's picture). Debian's `chromium` only: nothing is downloaded, and the page's WebGL runs
on SwiftShader (no GPU). The DevTools protocol is spoken over a websocket with the `websockets`
package that viser already needs, so no driver program and no browser download are involved.

    with HeadlessChromium(width=1280, height=720) as browser:
        browser.open("http://127.0.0.1:8080/")
        png = browser.screenshot_when(lambda img: ...)
        browser.press_key("w")

The browser process and its profile directory are removed on exit, also after an error.
"""
from __future__ import annotations

import base64
import io
import json
import os
import shutil
import signal
import subprocess
import tempfile
import time
import urllib.request
from typing import Callable

import numpy as np

CHROMIUM_CANDIDATES = ("chromium", "chromium-browser", "google-chrome")


def find_chromium() -> str | None:
    """The Chromium executable: KESTREL_CHROMIUM, else the first of chromium / chromium-browser on PATH."""
    env = os.environ.get("KESTREL_CHROMIUM")
    if env:
        return env if os.path.isfile(env) and os.access(env, os.X_OK) else None
    for name in CHROMIUM_CANDIDATES:
        p = shutil.which(name)
        if p:
            return p
    return None


def png_to_array(png: bytes) -> np.ndarray:
    """(H, W, 3) uint8 RGB of a PNG (matplotlib's reader: it is already a pinned dependency)."""
    import matplotlib.image

    img = matplotlib.image.imread(io.BytesIO(png), format="png")
    if img.dtype != np.uint8:
        img = np.clip(np.rint(img * 255.0), 0, 255).astype(np.uint8)
    return img[:, :, :3]


class HeadlessChromium:
    """One headless Chromium with one page, driven over the DevTools protocol."""

    def __init__(self, width: int = 1280, height: int = 720, executable: str | None = None, timeout_s: float = 30.0):
        if width < 64 or height < 64:
            raise ValueError(f"width, height: expected at least 64 pixels each, got {width} x {height}")
        self.width, self.height, self.timeout_s = int(width), int(height), float(timeout_s)
        self.executable = executable or find_chromium()
        if self.executable is None:
            raise FileNotFoundError(
                "chromium: no Chromium found (KESTREL_CHROMIUM, or chromium on PATH; Debian: apt-get install chromium)")
        self._proc: subprocess.Popen | None = None
        self._profile: str | None = None
        self._ws = None
        self._next_id = 0

    # ---- process ------------------------------------------------------------------------------
    def __enter__(self) -> "HeadlessChromium":
        try:
            self.start()
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def start(self) -> None:
        self._profile = tempfile.mkdtemp(prefix="kestrel-chromium-")
        # What headless Chromium needs as root in a container with no network and no GPU: no sandbox
        # (root), SwiftShader for WebGL, and none of the background services that would try to reach
        # the network. Port 0: Chromium picks a free port and writes it to DevToolsActivePort.
        args = [self.executable, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                "--disable-background-networking", "--disable-component-update", "--disable-sync",
                "--disable-default-apps", "--disable-extensions", "--mute-audio", "--hide-scrollbars",
                "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist",
                f"--user-data-dir={self._profile}", f"--window-size={self.width},{self.height}",
                "--remote-debugging-address=127.0.0.1", "--remote-debugging-port=0", "about:blank"]
        self._proc = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.DEVNULL, start_new_session=True)
        port_file = os.path.join(self._profile, "DevToolsActivePort")
        deadline = time.monotonic() + self.timeout_s
        port = None
        while time.monotonic() < deadline:
            if self._proc.poll() is not None:
                raise RuntimeError(f"chromium: {self.executable} exited with status {self._proc.returncode} at start")
            try:
                with open(port_file) as f:
                    first = f.readline().strip()
                if first:
                    port = int(first)
                    break
            except (FileNotFoundError, ValueError):
                pass
            time.sleep(0.05)
        if port is None:
            raise TimeoutError(f"chromium: no DevTools port within {self.timeout_s:.0f} s")
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=self.timeout_s) as r:
            targets = json.load(r)
        page = next((t for t in targets if t.get("type") == "page"), None)
        if page is None:
            raise RuntimeError("chromium: no page target")
        from websockets.sync.client import connect

        self._ws = connect(page["webSocketDebuggerUrl"], max_size=None, open_timeout=self.timeout_s)
        self.call("Page.enable")
        self.call("Emulation.setDeviceMetricsOverride", width=self.width, height=self.height, deviceScaleFactor=1,
                  mobile=False)

    def close(self) -> None:
        if self._ws is not None:
            try:
                self._ws.close()
            except Exception:
                pass
            self._ws = None
        if self._proc is not None:
            if self._proc.poll() is None:
                # Its own session (start_new_session): the renderer and GPU processes go with it.
                try:
                    os.killpg(self._proc.pid, signal.SIGTERM)
                except ProcessLookupError:
                    pass
                try:
                    self._proc.wait(timeout=5)
                except subprocess.TimeoutExpired:
                    try:
                        os.killpg(self._proc.pid, signal.SIGKILL)
                    except ProcessLookupError:
                        pass
                    self._proc.wait(timeout=5)
            self._proc = None
        if self._profile is not None:
            shutil.rmtree(self._profile, ignore_errors=True)
            self._profile = None

    # ---- DevTools protocol ---------------------------------------------------------------------
    def call(self, method: str, **params):
        """Sends one command and returns its result (events that arrive meanwhile are dropped)."""
        if self._ws is None:
            raise RuntimeError("chromium: not started")
        self._next_id += 1
        mid = self._next_id
        self._ws.send(json.dumps({"id": mid, "method": method, "params": params}))
        deadline = time.monotonic() + self.timeout_s
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"chromium: no answer to {method} within {self.timeout_s:.0f} s")
            msg = json.loads(self._ws.recv(timeout=left))
            if msg.get("id") == mid:
                if "error" in msg:
                    raise RuntimeError(f"chromium: {method}: {msg['error']}")
                return msg.get("result", {})

    def open(self, url: str) -> None:
        """Navigates and waits for the load event (the page's own scripts then connect and draw)."""
        self.call("Page.navigate", url=url)
        deadline = time.monotonic() + self.timeout_s
        while time.monotonic() < deadline:
            if self.evaluate("document.readyState") == "complete" and self.evaluate("location.href").startswith(url[:20]):
                return
            time.sleep(0.1)
        raise TimeoutError(f"chromium: {url} did not load within {self.timeout_s:.0f} s")

    def evaluate(self, expression: str):
        deadline = time.monotonic() + self.timeout_s
        while True:
            try:
                r = self.call("Runtime.evaluate", expression=expression, returnByValue=True)
                return r.get("result", {}).get("value")
            except RuntimeError as e:
                # A navigation in flight: the old context is gone and the new one not yet there.
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.1)

    def screenshot(self) -> bytes:
        """The page as PNG bytes (retried while a navigation swaps the page's renderer)."""
        deadline = time.monotonic() + self.timeout_s
        while True:
            try:
                return base64.b64decode(self.call("Page.captureScreenshot", format="png")["data"])
            except RuntimeError as e:
                if "Not attached" not in str(e) or time.monotonic() > deadline:
                    raise
                time.sleep(0.2)

    def screenshot_when(self, ready: Callable[[np.ndarray], bool], timeout_s: float = 30.0,
                        interval_s: float = 0.5) -> tuple[bytes, np.ndarray]:
        """Screenshots until ready(rgb) is true (the scene has arrived and is drawn); the last one
        otherwise, after timeout_s. Returns (png, rgb)."""
        deadline = time.monotonic() + timeout_s
        while True:
            png = self.screenshot()
            rgb = png_to_array(png)
            if ready(rgb) or time.monotonic() >= deadline:
                return png, rgb
            time.sleep(interval_s)

    def press_key(self, key: str) -> None:
        """A key press and release on the page, as a person's keyboard sends them (key: "w", "ArrowUp", ...)."""
        code = {"ArrowUp": "ArrowUp", "ArrowDown": "ArrowDown", "ArrowLeft": "ArrowLeft",
                "ArrowRight": "ArrowRight", " ": "Space"}.get(key, f"Key{key.upper()}" if len(key) == 1 else key)
        vk = {"ArrowUp": 38, "ArrowDown": 40, "ArrowLeft": 37, "ArrowRight": 39, " ": 32}.get(
            key, ord(key.upper()) if len(key) == 1 else 0)
        text = key if len(key) == 1 else ""
        self.call("Input.dispatchKeyEvent", type="keyDown", key=key, code=code, text=text,
                  windowsVirtualKeyCode=vk, nativeVirtualKeyCode=vk)
        self.call("Input.dispatchKeyEvent", type="keyUp", key=key, code=code, windowsVirtualKeyCode=vk,
                  nativeVirtualKeyCode=vk)


def project_point(p_w, cam, look, fov_rad: float, width: int, height: int) -> tuple[float, float]:
    """Pixel (u, v) of world point p_w through a z-up pinhole camera at cam looking at look with a
    vertical field of view fov_rad (the viewer's camera model): where the browser tests look for a
    drawn object's colour."""
    import math

    import numpy as np

    f = np.asarray(look, float) - np.asarray(cam, float)
    f /= np.linalg.norm(f)
    r = np.cross(f, [0.0, 0.0, 1.0])
    r /= np.linalg.norm(r)
    up = np.cross(r, f)
    d = np.asarray(p_w, float) - np.asarray(cam, float)
    x, y, z = d @ r, d @ up, d @ f
    assert z > 0, "point behind the camera"
    focal = (height / 2) / math.tan(fov_rad / 2)
    return width / 2 + focal * x / z, height / 2 - focal * y / z
