"""`kestrel teleop --task Kestrel-SO101-PickPlace-v0` (kestrel.so101_teleop, kestrel.so101_view) on
the real env: the leader arm over the simulated STS3215 bus, the keyboard in the ee_delta mode, a
recorded LeRobot episode replayed bit for bit, and the browser page driven by real key presses."""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time

import numpy as np
import pytest

pytest.importorskip("pyarrow")
from kestrel import feetech, lerobot_record as lr, so101_teleop as tel  # noqa: E402
from kestrel.browser import HeadlessChromium, find_chromium, project_point  # noqa: E402

TASK = "Pick the red cube and place it into the box"


def test_env_runs_at_30_hz_and_the_script_succeeds():
    env = tel.make_env("joint", seed=3)
    assert tel.env_mode(env) == "joint" and tel.control_hz(env) == pytest.approx(30.0, rel=1e-5)
    st = tel.teleop_loop(env, tel.ScriptedDevice(env), steps=400, seed=3, episodes=1)
    assert st["successes"] == 1 and st["saved"] == 1 and st["steps"] < 300  # ~140 steps (4.7 s)
    with pytest.raises(ValueError, match="'ee'-mode device on an env in the 'joint' action mode"):
        tel.teleop_loop(env, tel.KeyboardTeleop(), steps=1)


def test_leader_arm_over_the_simulated_bus_drives_the_follower():
    from kestrel.feetech_sim import SimulatedServoBus

    want = [0.3, -0.2, 0.5, 1.2, 0.4, 0.6]  # rad: a pose clear of the table, gripper half open
    cal = feetech.default_calibration()
    with SimulatedServoBus(ids=range(1, 7)) as bus:
        bus.set_all_ticks([feetech.radians_to_ticks(j, q, cal[j]) for j, q in zip(feetech.SO101_JOINTS, want)])
        leader = feetech.So101Leader(bus.port, cal, timeout=0.1)
        try:
            target = np.array(leader.joint_targets())
            assert np.abs(target - want).max() < 2e-3  # one tick is 0.05..0.08 degrees
            env = tel.make_env("joint", seed=1)
            st = tel.teleop_loop(env, tel.LeaderTeleop(leader), steps=60, seed=1)  # 2 s at 30 Hz
            assert st["steps"] == 60
            q = np.array(env.task.pick_place_state(0)["joint_pos"])
            # The follower's joints at the leader's angles: within 0.02 rad (servo sag under gravity).
            assert np.abs(q - target).max() < 0.02, (q, target)
            assert np.array_equal(np.array(env.task.pick_place_state(0)["joint_targets"], np.float32),
                                  target.astype(np.float32))
        finally:
            leader.close()


def test_keyboard_moves_the_tcp_and_closes_the_gripper():
    env = tel.make_env("ee", seed=2)
    kb = tel.KeyboardTeleop()
    kb.press("B")
    kb.press("W")
    log = []

    def on_step(ctx):
        k = ctx["stats"]["ticks"]
        s = env.task.pick_place_state(0)
        log.append((np.array(s["tcp_pos_w"]), float(s["joint_pos"][5])))
        if k == 5:
            kb.release("W")   # 5 steps of W: +5 cm in x
        if k == 40:
            kb.press("E")     # 3 steps of E: -3 cm in z
        if k == 43:
            kb.release("E")
            kb.press("O")     # close the gripper
        if k == 46:
            kb.release("O")

    tel.teleop_loop(env, kb, steps=75, seed=2, on_step=on_step)
    p0 = np.array(tel.reset_episode(env, 2)[0, 18:21])  # the home pose of seed 2 (the tcp before the keys)
    p_w, p_e = log[39][0], log[-1][0]
    d = p_w - p0
    assert d[0] == pytest.approx(0.05, abs=0.008) and abs(d[1]) < 0.005 and abs(d[2]) < 0.008, d
    d = p_e - p_w
    assert d[2] == pytest.approx(-0.03, abs=0.006) and abs(d[0]) < 0.005 and abs(d[1]) < 0.005, d
    assert log[40][1] > -0.02 and log[-1][1] < -0.12  # gripper from open-ish to closed (target -10 degrees)
    assert kb.gripper_target == pytest.approx(math.radians(-10))
    # A page's key press holds the key for hold_s of the teleop's clock, then lets go by itself.
    kb2, t = tel.KeyboardTeleop(), [0.0]
    kb2.clock = lambda: t[0]
    kb2.press("w", hold_s=0.1)
    assert kb2.action()[0] == pytest.approx(0.01)
    t[0] = 0.2
    assert kb2.action()[0] == 0 and not kb2.held


def test_record_and_replay_bit_for_bit(tmp_path, capsys):
    root = tmp_path / "ds"
    env = tel.make_env("joint", seed=11)
    w = lr.LeRobotWriter.create(root, fps=tel.CONTROL_HZ, features=tel.dataset_features())
    t0 = time.perf_counter()
    st = tel.teleop_loop(env, tel.ScriptedDevice(env), recorder=w, seed=11, episodes=1, steps=400)
    rec_s = time.perf_counter() - t0
    assert st["saved"] == 1 and st["successes"] == 1
    n = st["frames"]
    print(f"recorded {n} frames of 2 x 640x480 in {rec_s:.2f} s ({n / rec_s:.1f} frames/s, saving included)")
    ds = lr.LeRobotEpisodes(root)
    assert len(ds) == 1 and ds.fps == 30 and ds.tasks == {0: TASK}
    assert ds.episodes[0]["kestrel/seed"] == 11 and ds.episodes[0]["length"] == n
    e = ds.episode(0)
    assert e["observation.state"].shape == (n, 6) and e["action"].shape == (n, 6)
    assert e["task"] == [TASK] * n
    assert e["timestamp"] == pytest.approx(np.arange(n) / 30)
    for cam in ("front", "wrist"):
        imgs = e[f"observation.images.{cam}"]
        if not isinstance(imgs, list):
            assert imgs.shape == (n, 480, 640, 3) and imgs.dtype == np.uint8
        assert ds.info["features"][f"observation.images.{cam}"]["shape"] == [480, 640, 3]
    # The action is the joint targets applied: the next frame's state moves towards them, and the
    # last one ended in the box.
    assert e[tel.CUBE_POSE_KEY].shape == (n, 7)
    r = tel.replay_episode(root, 0)  # a fresh env, from the stored seed
    assert r["frames"] == n and r["state_equal"] and r["cube_equal"]
    assert r["states"].tobytes() == e["observation.state"].tobytes()
    assert r["cube_poses"].tobytes() == e[tel.CUBE_POSE_KEY].tobytes()
    other = tel.replay_episode(root, 0, seed=12, check=False)  # another start: caught
    assert not (other["state_equal"] and other["cube_equal"]) and other["first_mismatch"] is not None
    assert tel.replay_main([str(root)]) == 0
    assert "episode 0: " in capsys.readouterr().out


def test_record_in_ee_mode_replays_in_joint_mode(tmp_path):
    """Keyboard episodes are recorded as the joint targets the IK applied: they replay in the
    joint_position mode bit for bit."""
    env = tel.make_env("ee", seed=4)
    w = lr.LeRobotWriter.create(tmp_path / "ds", fps=30, features=tel.dataset_features(size=(64, 48)))
    kb = tel.KeyboardTeleop()
    kb.press("B"); kb.press("W"); kb.press("E"); kb.press("O")

    def on_step(ctx):
        if ctx["stats"]["ticks"] == 8:
            kb.release("W"); kb.release("E")
        if ctx["stats"]["ticks"] == 20:
            kb.press("N")  # success reset: saved

    st = tel.teleop_loop(env, kb, recorder=w, seed=4, steps=21, on_step=on_step)
    assert st["saved"] == 1 and st["frames"] == 20
    r = tel.replay_episode(tmp_path / "ds", 0)
    assert r["state_equal"] and r["cube_equal"] and r["frames"] == 20


def is_robot(p):  # the viewer's orange under the page's lights
    r, g, b = p[..., 0], p[..., 1], p[..., 2]
    return (r > 150) & (g > 30) & (g < 170) & (b < 90) & (r - g > 60)


@pytest.mark.skipif(find_chromium() is None, reason="no chromium (apt-get install chromium)")
def test_browser_keys_drive_the_arm(tmp_path):
    from kestrel import so101_view
    from kestrel.viewer import VIEW_FOV_RAD

    W, H = 960, 600
    state_file = tmp_path / "state.json"
    proc = subprocess.Popen([sys.executable, "-m", "kestrel", "teleop", "--task", tel.TASK_ID, "--device", "keyboard",
                             "--view-port", "0", "--state-file", str(state_file), "--steps", "3000", "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=os.environ.copy())
    try:
        url = None
        deadline = time.monotonic() + 30
        while url is None and time.monotonic() < deadline:
            line = proc.stdout.readline()
            if not line:
                break
            if "kestrel teleop:" in line and " at http" in line:
                url = line.rsplit(" at ", 1)[1].strip()
        assert url, "no viewer URL printed"

        def state():
            for _ in range(50):
                try:
                    return json.loads(state_file.read_text())
                except (FileNotFoundError, json.JSONDecodeError):
                    time.sleep(0.05)
            raise AssertionError("no state file")

        with HeadlessChromium(W, H) as b:
            b.open(url)
            cam, look = np.array(so101_view.CAMERA[0]), np.array(so101_view.CAMERA[1])
            def arm_drawn(im):
                m = is_robot(im.astype(int))
                m[:200, :330] = False  # the page's orange "software WebGL" notice, top left, is not the scene
                m[:, W - 340:] = False  # nor the side panel (the camera images show the arm too)
                return m.sum() > 500

            png, img = b.screenshot_when(arm_drawn, timeout_s=45)
            (tmp_path / "teleop.png").write_bytes(png)
            s0 = state()
            assert not s0["started"] and s0["steps"] == 0
            # The arm is drawn where the world says: orange around the projected tcp and its wrist.
            u, v = project_point(s0["tcp_pos_w"], cam, look, VIEW_FOV_RAD, W, H)
            mask = is_robot(img.astype(int))
            mask[:200, :330] = False  # the page's "software WebGL" notice
            mask[:, W - 340:] = False
            vv, uu = np.nonzero(mask)
            near = np.hypot(uu - u, vv - v) < 60
            assert near.sum() > 30, (u, v, len(uu), str(tmp_path / "teleop.png"))
            b.press_key("b")
            t_end = time.monotonic() + 20
            while not state()["started"] and time.monotonic() < t_end:
                b.press_key("b")
                time.sleep(0.3)
            s1 = state()
            assert s1["started"], s1
            # W held for about 0.6 s: key-downs with auto-repeat every 50 ms, then the key-up.
            t_end = time.monotonic() + 0.6
            b.call("Input.dispatchKeyEvent", type="keyDown", key="w", code="KeyW", text="w", windowsVirtualKeyCode=87,
                   nativeVirtualKeyCode=87)
            while time.monotonic() < t_end:
                time.sleep(0.05)
                b.call("Input.dispatchKeyEvent", type="keyDown", key="w", code="KeyW", text="w", autoRepeat=True,
                       windowsVirtualKeyCode=87, nativeVirtualKeyCode=87)
            b.call("Input.dispatchKeyEvent", type="keyUp", key="w", code="KeyW", windowsVirtualKeyCode=87,
                   nativeVirtualKeyCode=87)
            time.sleep(1.0)
            s2 = state()
            d = np.array(s2["tcp_pos_w"]) - np.array(s1["tcp_pos_w"])
            assert d[0] > 0.03 and abs(d[1]) < 0.01 and abs(d[2]) < 0.015, (s1, s2)
            assert s2["presses"].count("W") >= 3
            assert s2["view_frames"] > 30
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
