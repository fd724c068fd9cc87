"""The 3-D viewer in a real browser, keyboard teleoperation through it, and recordings read back.

The browser tests start the viewer (viser) on a scenario, open it in Debian's headless Chromium
(SwiftShader WebGL) through the DevTools protocol, and look at the screenshot: the robot's and an
obstacle's world positions, projected through the camera the test sets, must have the robot's
and the obstacle's colours, and the robot's colour must not be where the robot is not. Servers
and browsers are closed in `finally` / context managers, also when a check fails.
"""
from __future__ import annotations

import io
import math
import re
import subprocess
import time
from contextlib import redirect_stdout

import numpy as np
import pytest

import kestrel
from kestrel import record, viewer
from kestrel.browser import HeadlessChromium, find_chromium, project_point

needs_chromium = pytest.mark.skipif(find_chromium() is None, reason="no chromium (apt-get install chromium)")

W, H = 960, 600

SCENE = {
    "env": {"name": "empty", "num_envs": 1, "assets": [{
        "name": "block", "kind": "cube", "num_assets": 1, "min_num_assets": 1,
        "min_position_ratio": [0.75, 0.5, 0.12], "max_position_ratio": [0.75, 0.5, 0.12],
        "min_size_m": [1.0, 1.0, 1.0], "max_size_m": [1.0, 1.0, 1.0]}]},
    "robot": "base_quadrotor", "controller": "lee_position_control", "sensors": [],
}


def project(p_w, cam, look, fov=viewer.VIEW_FOV_RAD, w=W, h=H):
    """Pixel (u, v) of world point p_w through the viewer's camera at cam looking at look."""
    return project_point(p_w, cam, look, fov, w, h)


def colour_count(img, uv, rgb_test, radius=5):
    u, v = int(round(uv[0])), int(round(uv[1]))
    patch = img[max(0, v - radius): v + radius + 1, max(0, u - radius): u + radius + 1].astype(int)
    return int(rgb_test(patch).sum())


def is_robot(p):  # the orange body under the page's lights
    r, g, b = p[..., 0], p[..., 1], p[..., 2]
    return (r > 150) & (g > 30) & (g < 170) & (b < 90) & (r - g > 60)


def is_obstacle(p):  # the blue obstacles under the page's lights
    r, g, b = p[..., 0], p[..., 1], p[..., 2]
    return (b > 120) & (b - r > 60) & (b - g > 30)


@pytest.fixture
def scene_sim():
    sim = kestrel.make_simulator(SCENE, num_envs=1, seed=0, threads=1)
    real = np.dtype(kestrel._core.real_dtype)
    # The robot somewhere clear of the obstacle, exactly (the test knows where it must be drawn).
    ob = sim.obstacles(0)
    assert len(ob["type"]) == 1
    p = np.array([[ob["position_w"][0][0] - 3.0, ob["position_w"][0][1] + 0.5, 1.5]], real)
    sim.reset_root_states([0], p, np.array([[0, 0, 0, 1]], real))
    return sim


@needs_chromium
def test_browser_draws_robot_and_obstacle_where_the_world_says(scene_sim, tmp_path):
    sim = scene_sim
    fr = record.capture_frame(sim, [0], 0, 0.0)
    robot_w = fr.robots["pos_w"][0]
    ob = fr.obstacles[0]
    obstacle_w = np.asarray(ob["position_w"][0])
    look = (robot_w + obstacle_w) / 2
    cam = look + np.array([0.0, -5.5, 3.0])
    v = viewer.Viewer(sim.scene_info(), sim.robots_per_env, [0], port=0)
    try:
        v.set_viewer_camera(cam, look)
        v.draw(fr)
        ru, ou = project(robot_w, cam, look), project(obstacle_w, cam, look)
        assert abs(ru[0] - ou[0]) > 80, "the test's robot and obstacle must be apart on screen"
        with HeadlessChromium(W, H) as b:
            b.open(v.url)
            png, img = b.screenshot_when(
                lambda im: colour_count(im, ru, is_robot) > 10 and colour_count(im, ou, is_obstacle) > 10, timeout_s=45)
        (tmp_path / "viewer.png").write_bytes(png)
        assert img.shape == (H, W, 3)
        assert colour_count(img, ru, is_robot) > 10, f"no robot colour at {ru} (screenshot {tmp_path / 'viewer.png'})"
        assert colour_count(img, ou, is_obstacle) > 10, f"no obstacle colour at {ou}"
        # And not where they are not: the robot's colour is absent at the obstacle and at the
        # robot's mirror image across the screen's centre line, the obstacle's at its own mirror
        # image (the robot's site is not checked for blue: its body frame's z axis is blue).
        assert colour_count(img, ou, is_robot) == 0
        assert colour_count(img, (W - ru[0], ru[1]), is_robot) == 0
        assert colour_count(img, (W - ou[0], ou[1]), is_obstacle) == 0
        # The drawn robot is where the world says, not anywhere on screen: its pixels' centroid is
        # within 25 px of the projection.
        mask = is_robot(img.astype(int))
        mask[:200, :330] = False  # the page's orange "software WebGL" notice, top left, is not the scene
        vv, uu = np.nonzero(mask)
        assert len(uu) > 10
        assert math.hypot(uu.mean() - ru[0], vv.mean() - ru[1]) < 25
    finally:
        v.close()


@needs_chromium
def test_keyboard_teleop_through_the_page():
    cfg, _ = record.load_run_config(None, None, 1, 0, 1)
    viewer.teleop_config(cfg)
    run = record.ScriptedRun(cfg)
    live = viewer.LiveView(run, [0], port=0, rate=1000.0, teleop=True)
    try:
        t = live.teleop
        start = t.command.copy()
        with HeadlessChromium(W, H) as b:
            b.open(live.url)
            b.screenshot_when(lambda im: is_robot(im.astype(int)).sum() > 5, timeout_s=45)
            deadline = time.monotonic() + 20
            # Keys go to the page as a keyboard sends them; viser's hotkeys call back into Python.
            while time.monotonic() < deadline and t.presses.count("w") < 2:
                if live.viewer.num_clients() > 0:
                    b.press_key("w")
                    b.press_key("r")
                time.sleep(0.4)
        assert t.presses.count("w") >= 2, f"key presses seen: {t.presses}"
        n_w, n_r = t.presses.count("w"), t.presses.count("r")
        np.testing.assert_allclose(t.command[0], start[0] + n_w * t.step_m)
        np.testing.assert_allclose(t.command[2], start[2] + n_r * t.step_m)
        # The robot is flown to the new setpoint: 300 env-steps later it is at least twice as near.
        before = np.linalg.norm(np.array(run.sim.base_pos_w[0]) - t.command[:3])
        for _ in range(300):
            live.step()
        after = np.linalg.norm(np.array(run.sim.base_pos_w[0]) - t.command[:3])
        assert after < 0.5 * before
    finally:
        live.close()


def test_teleop_refuses_what_it_cannot_drive():
    cfg, _ = record.load_run_config(None, "position_setpoint_task", 2, 0, 1)
    with pytest.raises(ValueError, match="teleop: an RL task"):
        viewer.Teleop(record.ScriptedRun(cfg))
    cfg, _ = record.load_run_config(None, None, 1, 0, 1)
    with pytest.raises(ValueError, match="teleop: task.setpoint_speed_m_s is 2"):
        viewer.Teleop(record.ScriptedRun(cfg))
    viewer.teleop_config(cfg)
    t = viewer.Teleop(record.ScriptedRun(cfg))
    with pytest.raises(ValueError, match="key: expected one of w, s"):
        t.key("x")


def test_set_viewer_camera_checks_its_arguments(scene_sim):
    v = viewer.Viewer(scene_sim.scene_info(), 1, [0], port=0)
    try:
        with pytest.raises(ValueError, match="position and lookat: expected 3 finite numbers"):
            v.set_viewer_camera((0, 0), (1, 1, 1))
        with pytest.raises(ValueError, match="must differ"):
            v.set_viewer_camera((1, 1, 1), (1, 1, 1))
        v.set_viewer_camera((0, -5, 3), (0, 0, 0))
        np.testing.assert_allclose(v.server.initial_camera.position, (0, -5, 3))
    finally:
        v.close()


def _hash_line(text: str) -> str:
    m = re.search(r"state hash: ([0-9a-f]{16})", text)
    assert m, text
    return m.group(1)


def test_record_reads_back_and_matches_the_cxx_run(tmp_path, root):
    path = tmp_path / "run.mcap"
    scenario = str(root / "sim" / "scenarios" / "forest_camera.yaml")
    args = [scenario, "--envs", "3", "--steps", "40", "--threads", "1", "--seed", "5", "--out", str(tmp_path / "py")]
    out = io.StringIO()
    with redirect_stdout(out):
        assert record.run_main(args + ["--record", str(path), "--record-envs", "2"]) == 0
    py_hash = _hash_line(out.getvalue())

    # The reader of the format itself (mcap), channel by channel.
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    topics = {c.topic: summary.schemas[c.schema_id].name for c in summary.channels.values()}
    assert topics["/kestrel/state"] == "kestrel.State"
    assert topics["/tf"] == "foxglove.FrameTransforms"
    assert topics["/markers/obstacles"] == "foxglove.SceneUpdate"
    assert topics["/env0/robot0/range0"] == "foxglove.RawImage"
    assert topics["/env1/robot0/segmentation0"] == "foxglove.RawImage"
    counts = {summary.channels[k].topic: v for k, v in summary.statistics.channel_message_counts.items()}
    assert counts["/kestrel/state"] == 41 and counts["/tf"] == 41 and counts["/env1/robot0/range0"] == 41

    rec = record.read_recording(str(path))
    assert rec.scene["envs"] == [0, 1] and rec.scene["robot_kind"] == "multirotor"
    assert len(rec.frames) == 41
    last = rec.frames[-1]
    assert last.step == 40
    # The recorded last state is the simulator's: rerun the same scenario in Python to compare.
    cfg, _ = record.load_run_config(scenario, None, 3, 5, 1)
    again = record.ScriptedRun(cfg)
    for _ in range(40):
        again.step()
    np.testing.assert_allclose(last.robots["pos_w"], again.sim.base_pos_w[:2], rtol=0, atol=1e-6)
    thrust, faults = again.sim.motor_state()
    assert last.robots["thrust_N"].shape == (2, 4)
    np.testing.assert_allclose(last.robots["thrust_N"], thrust[:2], atol=1e-6)
    np.testing.assert_array_equal(last.robots["faults"], faults[:2])
    assert (last.robots["thrust_N"] > 0).all()  # hovering: every rotor pushes
    img = again.sim.range_images(0)
    assert last.images["range0"].shape == (2,) + img.shape[1:]
    np.testing.assert_allclose(last.images["range0"], img[:2], atol=1e-6)
    np.testing.assert_array_equal(last.images["segmentation0"], again.sim.segmentation_images(0)[:2])
    assert len(last.obstacles[0]["type"]) > 0  # the forest's trees
    assert _hash_line(f"state hash: {again.state_hash:016x}") == py_hash

    # The same scenario, seed and steps through the C++ CLI: the same final state.
    import os
    cli = os.environ.get("KESTREL_CLI") or str(root / "build" / "host" / "sim" / "kestrel")
    if not os.path.exists(cli):
        pytest.skip(f"{cli} not built: the C++ run's hash is not compared")
    r = subprocess.run([cli, "run", *args[:-2], "--out", str(tmp_path / "cxx"), "--quiet"], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert _hash_line(r.stdout) == py_hash


def test_legged_run_hash_matches_the_cxx_run_and_replays(tmp_path, root, kestrel_cli):
    scenario = str(root / "sim" / "scenarios" / "go2_rough.yaml")
    args = [scenario, "--envs", "2", "--steps", "20", "--threads", "1", "--seed", "2"]
    out = io.StringIO()
    with redirect_stdout(out):
        assert record.run_main(args + ["--out", str(tmp_path / "py"), "--record", str(tmp_path / "go2.mcap"),
                                       "--record-envs", "1"]) == 0
    r = subprocess.run([str(kestrel_cli), "run", *args, "--out", str(tmp_path / "cxx"), "--quiet"], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert _hash_line(r.stdout) == _hash_line(out.getvalue())
    rec = record.read_recording(str(tmp_path / "go2.mcap"))
    assert rec.frames[-1].robots["feet_pos_w"].shape == (1, 4, 3)
    assert len(rec.frames) == 21
    rv = viewer.ReplayView(rec, port=0)
    try:
        # The time slider moves the drawn frame.
        rv.slider.value = 3
        deadline = time.monotonic() + 5
        while rv.viewer._frame.step != rec.frames[3].step and time.monotonic() < deadline:
            time.sleep(0.05)
        assert rv.viewer._frame.step == rec.frames[3].step
    finally:
        rv.viewer.close()


def test_draw_debug_vis_draws_height_samples_and_contacts():
    sim = kestrel.make_simulator({
        "sim": "fast_sim", "robot": "go2", "task": "joint_targets",
        "env": {"name": "empty", "terrain": {"type": "heightfield", "procedural": "random_uniform", "length_x_m": 8,
                                             "width_y_m": 8, "min_height_m": -0.03, "max_height_m": 0.03,
                                             "height_step_m": 0.005, "measure_heights": True}}}, num_envs=1, seed=1, threads=1)
    for _ in range(40):
        sim.step(None)
    fr = record.capture_frame(sim, [0], 40, 0.8)
    info = sim.scene_info()
    assert info["terrain"] == "heightfield" and info["heights_m"].ndim == 2
    v = viewer.Viewer(info, 1, [0], port=0)
    try:
        v.draw(fr)
        v.draw_debug_vis(height_samples=True, contacts=True)
        nodes = v.scene._handle_from_node_name
        hs = nodes["/debug/height_samples"].points
        assert len(hs) == sim.measured_heights.shape[1] > 0
        # The samples are drawn on the terrain the robot measured, around the robot.
        # (viser keeps point clouds in float16: a few mm at these sizes)
        np.testing.assert_allclose(np.sort(hs[:, 2]), np.sort(fr.robots["measured_heights"][0]), atol=2e-3)
        assert np.abs(hs[:, :2].mean(0) - fr.robots["pos_w"][0, :2]).max() < 0.5
        # Standing on its feet: foot contacts with their forces, drawn from the feet.
        cp = nodes["/debug/contacts"].points
        assert len(cp) >= 2
        feet = fr.robots["feet_pos_w"][0]
        assert min(np.linalg.norm(feet - cp[0], axis=1)) < 2e-3
        segs = nodes["/debug/contact_forces"].points
        assert segs.shape[1:] == (2, 3) and (segs[:, 1, 2] > segs[:, 0, 2]).all()  # the ground pushes up
        v.draw_debug_vis(height_samples=False, contacts=False)
        assert len(nodes["/debug/height_samples"].points) == 0
    finally:
        v.close()


def test_simulator_hooks_reach_the_attached_viewer():
    """LeggedGym-Ex's set_viewer_camera / draw_debug_vis on the Simulator: kept before a viewer
    attaches, handed to it on attach and on every later call; bad input refused by name."""
    sim = kestrel.make_simulator({"sim": "fast_sim", "robot": "go2", "task": "joint_targets", "env": "empty"},
                                 num_envs=1, seed=1, threads=1)
    sim.set_viewer_camera((0.0, -3.0, 2.0), (0.0, 0.0, 0.3))
    with pytest.raises(ValueError, match="must differ"):
        sim.set_viewer_camera((1, 1, 1), (1, 1, 1))
    with pytest.raises(ValueError, match="finite"):
        sim.set_viewer_camera((math.nan, 0, 0), (0, 0, 0))
    req = sim.viewer_request
    assert req["camera_set"] and req["camera_position_w"] == (0.0, -3.0, 2.0)
    assert not req["debug_contacts"]
    with pytest.raises(TypeError, match="no set_viewer_camera"):
        sim.attach_viewer(object())
    for _ in range(40):
        sim.step(None)
    fr = record.capture_frame(sim, [0], 40, 0.8)
    v = viewer.Viewer(sim.scene_info(), 1, [0], port=0)
    try:
        sim.attach_viewer(v)  # the camera asked for above reaches the page's camera
        np.testing.assert_allclose(v.server.initial_camera.position, (0, -3, 2))
        np.testing.assert_allclose(v.server.initial_camera.look_at, (0, 0, 0.3), atol=1e-6)
        v.draw(fr)
        nodes = v.scene._handle_from_node_name
        assert "/debug/contacts" not in nodes or len(nodes["/debug/contacts"].points) == 0
        sim.draw_debug_vis(height_samples=False, contacts=True)  # through the Simulator
        assert len(nodes["/debug/contacts"].points) >= 2  # the standing robot's feet
        sim.attach_viewer(None)
        sim.set_viewer_camera((0.0, -6.0, 4.0), (0.0, 0.0, 0.0))  # detached: kept, not sent
        np.testing.assert_allclose(v.server.initial_camera.position, (0, -3, 2))
    finally:
        v.close()


def test_task_run_with_record_has_the_cxx_hash(tmp_path, kestrel_cli):
    args = ["--task", "navigation_task", "--envs", "2", "--steps", "30", "--threads", "1", "--seed", "1"]
    out = io.StringIO()
    with redirect_stdout(out):
        assert record.run_main(args + ["--out", str(tmp_path / "py"), "--record", str(tmp_path / "nav.mcap")]) == 0
    r = subprocess.run([str(kestrel_cli), "run", *args, "--out", str(tmp_path / "cxx"), "--quiet"], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert _hash_line(r.stdout) == _hash_line(out.getvalue())
    rec = record.read_recording(str(tmp_path / "nav.mcap"))
    assert len(rec.frames) == 31 and rec.frames[-1].robots["actions"].shape == (2, 4)
