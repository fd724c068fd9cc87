"""Issue 15's remaining pieces: the ray sensors' returns as point clouds in the viewer (live and in a
replay), `kestrel train --view`, and `kestrel teleop --record` with its progress line.

The point clouds are checked against geometry, not against the code that drew them: every drawn
point of a lidar and of a depth camera on robots among the forest's trees lies on the surface the
segmentation image names (the ground plane, or a tree capsule of that semantic id), and at the
distance the sensor reports from the sensor's own pose (range along the ray for the lidar, depth
along the optical axis for the camera)."""
from __future__ import annotations

import json
import os
import re
import sys

import numpy as np
import pytest

import kestrel
from kestrel import record, viewer

# A lidar (normalised values: the pixel times max_range_m is metres) and a depth camera (depth
# along the optical axis, normalised, its mount drawn at random per reset), noise off so each
# return is exact; few rays so the test is fast.
SENSORS = [
    {"name": "os0_128", "height": 16, "width": 72, "enable_sensor_noise": False},
    {"name": "base_depth_camera", "height": 12, "width": 20, "enable_sensor_noise": False},
]


def _sensor_sim():
    return kestrel.make_simulator({"env": "forest", "task": "position_setpoint", "sensors": SENSORS},
                                  num_envs=2, seed=5, threads=1, backend="rigid")


def _rot(q, v):
    """v rotated by the unit quaternion q (xyzw), written out here (not the viewer's helper)."""
    x, y, z, w = q
    R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    return np.asarray(v) @ R.T


def _dist_to_capsule(p, c, q, r, hl):
    """Distance from points p (n, 3) to the surface of a capsule (axis = its z) centred at c."""
    a = _rot(q, [0.0, 0.0, 1.0])
    t = np.clip((p - c) @ a, -hl, hl)
    return np.linalg.norm(p - (c + t[:, None] * a), axis=1) - r


def _surface_distance(p, seg_id, ob):
    """|distance| from each point to the nearest obstacle of semantic id seg_id (0: the ground z = 0)."""
    if seg_id == 0:
        return np.abs(p[:, 2])
    best = np.full(len(p), np.inf)
    for k in np.nonzero(np.asarray(ob["semantic_id"]) == seg_id)[0]:
        t = int(ob["type"][k])
        c, q = np.asarray(ob["position_w"][k]), np.asarray(ob["orientation_xyzw"][k])
        if t == 2:  # capsule
            d = _dist_to_capsule(p, c, q, float(ob["radius_m"][k]), float(ob["half_length_m"][k]))
        elif t == 0:  # sphere
            d = np.linalg.norm(p - c, axis=1) - float(ob["radius_m"][k])
        else:
            pytest.fail(f"obstacle type {t}: the forest's trees are capsules and spheres")
        best = np.minimum(best, np.abs(d))
    return best


def test_ray_points_lie_on_the_surfaces_at_the_reported_distances():
    sim = _sensor_sim()
    for _ in range(15):  # fly a little: the robots tilt and move, the mounts stay as drawn at reset
        sim.step(sim.scripted_actions())
    envs = [0, 1]
    fr = record.capture_frame(sim, envs, 15, 0.15)
    info = sim.scene_info()
    info["range_rays"] = record.sensor_rays(sim)
    assert [r["kind"] for r in info["range_rays"]] == ["lidar", "camera"]
    v = viewer.Viewer(info, sim.robots_per_env, envs, port=0)
    try:
        v.draw(fr)
        pos, quat = np.array(sim.base_pos_w), np.array(sim.base_quat_xyzw)
        checked = {0: 0, 1: 0}
        for k in (0, 1):
            rays = sim.range_image_rays(k)
            mpos, mquat = sim.sensor_mounts(k)
            img, seg = np.array(sim.range_images(k), np.float64), np.array(sim.segmentation_images(k))
            assert img.shape[1:] == rays["dirs_s"].shape[:2]
            for e in envs:
                drawn = v.ray_points(e, k) - v.env_offset(e)
                i = e  # one robot per env
                vals = img[i].reshape(-1) * rays["value_scale_m"]
                ok = (vals >= rays["min_range_m"]) & (vals < rays["max_range_m"])
                assert len(drawn) == ok.sum() > 20, (k, e, len(drawn), ok.sum())
                ids = seg[i].reshape(-1)[ok]
                assert (ids >= 0).all()
                ob = sim.obstacles(e)
                for sid in np.unique(ids):
                    p = drawn[ids == sid]
                    assert _surface_distance(p, int(sid), ob).max() < 2e-3, (k, e, sid)
                # The distance from the sensor: its origin from the robot pose and its mount.
                o = pos[i] + _rot(quat[i], mpos[i])
                if rays["kind"] == "lidar":
                    d = np.linalg.norm(drawn - o, axis=1)
                else:  # depth along the optical axis: the sensor frame's +x
                    axis = _rot(quat[i], _rot(mquat[i], [1.0, 0.0, 0.0]))
                    d = (drawn - o) @ axis
                np.testing.assert_allclose(d, vals[ok], rtol=1e-4, atol=2e-4)
                checked[k] += int(ok.sum())
                # Both kinds of surface are seen by the lidar: the ground and trees.
                if k == 0:
                    assert (ids == 0).any() and (ids > 0).any(), np.unique(ids)
        assert checked[0] > 200 and checked[1] > 40
        # A mount drawn at random really is used (not the identity): the camera's differs per env.
        assert not np.allclose(sim.sensor_mounts(1)[1][0], sim.sensor_mounts(1)[1][1])
    finally:
        v.close()


def test_ray_points_replay_from_a_recording(tmp_path):
    sim = _sensor_sim()
    path = str(tmp_path / "rays.mcap")
    with record.McapRecorder(path, sim, [0, 1], sim.dt_s * sim.decimation) as rec:
        for s in range(4):
            sim.step(sim.scripted_actions())
            rec.write(record.capture_frame(sim, [0, 1], s + 1, (s + 1) * 0.01))
    live_info = sim.scene_info()
    live_info["range_rays"] = record.sensor_rays(sim)
    live = viewer.Viewer(live_info, 1, [0, 1], port=0)
    rv = viewer.ReplayView(record.read_recording(path), port=0)
    try:
        live.draw(record.capture_frame(sim, [0, 1], 4, 0.04))
        rv.show(3)
        for k in (0, 1):
            for e in (0, 1):
                a, b = live.ray_points(e, k), rv.viewer.ray_points(e, k)
                assert len(a) > 20 and a.shape == b.shape
                np.testing.assert_allclose(b, a, atol=1e-5)
    finally:
        live.close()
        rv.viewer.close()


def test_planar_has_no_ray_table_and_the_viewer_draws_without_one():
    sim = kestrel.make_simulator({"simulator": {"name": "planar", "lidar_beams": 16}, "task": "position_setpoint"},
                                 num_envs=1, seed=0, threads=1)
    assert record.sensor_rays(sim) == []
    with pytest.raises(ValueError, match="planar"):
        sim.range_image_rays(0)


def test_train_view_draws_the_training_envs_as_they_learn():
    env = kestrel.make_vec("Kestrel-PositionSetpoint-v0", num_envs=8, seed=0, threads=1)
    tv = viewer.TrainView(env, view_envs=3, port=0, fps=1e6)
    try:
        env.reset(seed=0)
        sim = env.task.simulator
        for _ in range(5):
            env.step(np.zeros((8, env.single_action_space.shape[0]), np.float32))
        assert tv.steps == 5 and tv.frames_drawn == 6  # the first frame, then one per step at this rate
        # What the page shows is the training envs' state now: robot 0 of each env shown.
        for e in tv.envs:
            node = tv.viewer._robot_nodes[e]["frame"]
            np.testing.assert_allclose(np.array(node.position) - tv.viewer.env_offset(e), sim.base_pos_w[e], atol=1e-5)
        # At a low rate it draws far less often than the learner steps.
        tv.min_period_s = 3600.0
        for _ in range(5):
            env.step(np.zeros((8, env.single_action_space.shape[0]), np.float32))
        assert tv.frames_drawn == 6
    finally:
        tv.close()


def test_kestrel_train_view_finishes_and_drew(tmp_path):
    from kestrel.train import main

    out = tmp_path / "run"
    summary = main(["Kestrel-PositionSetpoint-v0", "--envs", "16", "--seed", "0", "--steps", "2560",
                    "--eval-every", "2560", "--eval-episodes", "8", "--episode-len", "100", "--threads", "1",
                    "--tensorboard", "0", "--export", "0", "--out", str(out), "--quiet",
                    "--view", "--view-envs", "2", "--port", "0", "--view-fps", "1e6"])
    assert summary["env_steps"] == 2560
    view = summary["view"]
    assert view["envs"] == [0, 1] and re.match(r"http://127\.0\.0\.1:\d+/", view["url"])
    # The learner's env.step calls went through the viewer (2560 env-steps = 16 envs x 16 decisions
    # x 10 repeats: at least the 16 rollout decisions), and at this frame rate every one was drawn
    # after the first frame.
    assert view["env_step_calls"] >= 16 and view["frames_drawn"] == view["env_step_calls"] + 1, view
    assert json.load(open(out / "summary.json"))["view"]["frames_drawn"] == view["frames_drawn"]


def _run_on_pty(cmd, timeout=120):
    """cmd with stderr on a pseudo-terminal: (returncode, stdout, stderr)."""
    import pty_run

    return pty_run.run(cmd, timeout=timeout)


def test_teleop_records_with_a_progress_line(tmp_path):
    exe = os.path.join(os.path.dirname(sys.executable), "kestrel")
    path = tmp_path / "teleop.mcap"
    steps = 150
    cmd = [exe, "teleop", "--envs", "2", "--steps", str(steps), "--rate", "150", "--port", "0", "--record", str(path),
           "--no-hold"]
    rc, out, err = _run_on_pty(cmd)
    assert rc == 0, (out, err)
    assert f"wrote {path}" in out
    # The progress line on the terminal: env-steps of both envs, rising, the last one complete.
    lines = re.findall(r"\r  teleop recording: ([0-9.]+k?) / 300 env-steps \((\d+)%\)", err)
    assert len(lines) >= 2, err
    assert lines[-1] == ("300", "100") and int(lines[0][1]) < 100
    rec = record.read_recording(str(path))
    assert len(rec.frames) == steps + 1
    # Robot 0 holds the teleop setpoint (no key pressed: where it started, at least 1 m up).
    t0 = rec.frames[0].robots["target_w"][0]
    assert t0[2] >= 1.0
    for fr in rec.frames:
        np.testing.assert_allclose(fr.robots["target_w"][0], t0)
    # --quiet: nothing on the terminal but what a failure would print.
    rc, out, err = _run_on_pty(cmd[:-3] + ["--steps", "60", "--no-hold", "--quiet"])
    assert rc == 0 and "teleop" not in err and "\r" not in err, err
