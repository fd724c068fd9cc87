"""Sensor images on the Python Simulator: Simulator.range_images(k) / range_image(robot, k) are
read-only numpy views of the C++ RangeImage buffers (no copy, strides from row_step / col_step,
the simulator kept alive by the array); segmentation_images(k) likewise on rigid. Values are
checked against geometry: a ToF sensor pointed at the ground from a known height reads that height."""
import gc

import numpy as np
import pytest

import kestrel

REAL = np.dtype(kestrel._core.real_dtype)
# Nose down: +90 deg about body y takes body x (the sensor's axis) to world -z. Nose up: -90 deg.
NOSE_DOWN = (0.0, np.sin(np.pi / 4), 0.0, np.cos(np.pi / 4))
NOSE_UP = (0.0, -np.sin(np.pi / 4), 0.0, np.cos(np.pi / 4))


def _tof_sim(num_envs=3, **kw):
    # VL53L5CX: 8 x 8 zones, 90 x 90 deg, 0.2-4 m, no return = -1, 2 % range noise, 1 % dropouts,
    # mount randomised at each reset; "empty": a ground plane and nothing else.
    return kestrel.make_simulator({"env": "empty", "sensors": ["vl53l5cx"], "task": "position_setpoint"},
                                  num_envs=num_envs, seed=0, threads=1, backend="rigid", **kw)


def _centre(img):
    c = img[3:5, 3:5].ravel()
    c = c[c > 0]  # dropouts read -1
    assert c.size >= 2
    return float(np.median(c))


def test_rigid_range_image_reads_the_distance_to_the_ground():
    sim = _tof_sim()
    info = sim.range_image_info(0)
    assert sim.num_range_images == 1
    assert (info["height"], info["width"], info["max_range_m"]) == (8, 8, 4.0)
    assert info["horizontal_fov_rad"] == pytest.approx(np.pi / 2, rel=1e-6)
    img = sim.range_images(0)
    assert img.shape == (3, 8, 8) and img.dtype == REAL and not img.flags.writeable
    assert img.strides == (64 * REAL.itemsize, 8 * REAL.itemsize, REAL.itemsize)
    seg = sim.segmentation_images(0)
    assert seg.shape == (3, 8, 8) and seg.dtype == np.int32

    # env 0 at 1 m and env 1 at 2 m looking straight down, env 2 at 2 m looking straight up.
    pos = np.array([[0, 0, 1.0], [0, 0, 2.0], [0, 0, 2.0]], REAL)
    quat = np.array([NOSE_DOWN, NOSE_DOWN, NOSE_UP], REAL)
    sim.reset_root_states([0, 1, 2], pos, quat)
    sim.update_sensors()
    # The view taken before the reset sees the new images (same buffer).
    assert _centre(img[0]) == pytest.approx(1.0, rel=0.12)
    assert _centre(img[1]) == pytest.approx(2.0, rel=0.12)
    assert _centre(img[0]) < info["max_range_m"] and _centre(img[1]) > 1.5 * _centre(img[0])
    # Off-centre zones are further (ground seen at an angle): the corners read more than the centre.
    corners = np.array([img[0, 0, 0], img[0, 0, 7], img[0, 7, 0], img[0, 7, 7]])
    assert np.median(corners[corners > 0]) > 1.2 * _centre(img[0])
    # Looking up over an empty world: no returns at all, and no segment.
    assert np.all(img[2] == -1) and np.all(seg[2] == -1)
    # The ground is segment 0 wherever a zone returned.
    assert np.all(seg[0][img[0] > 0] == 0) and np.all(seg[1][img[1] > 0] == 0)
    # range_image(robot, k) is the same memory as range_images(k)[robot].
    one = sim.range_image(1, 0)
    assert one.shape == (8, 8) and np.shares_memory(one, img) and one.ctypes.data == img[1].ctypes.data
    with pytest.raises(ValueError, match="read-only"):
        img[0, 0, 0] = 1.0


def test_range_view_is_zero_copy_across_steps_and_keeps_the_simulator_alive():
    sim = _tof_sim(num_envs=4)
    img = sim.range_images()
    ptr = img.ctypes.data
    before = img.copy()
    changed = 0
    for _ in range(20):
        sim.step(sim.scripted_actions())
        again = sim.range_images()
        assert again.ctypes.data == ptr and np.shares_memory(again, img)
        assert np.array_equal(again, img, equal_nan=True)
        changed += not np.array_equal(img, before)
        before = img.copy()
    assert changed >= 15  # the held view changes step after step (the robots fly; noise)
    assert np.any((img > 0) & (img < 4.0))  # the lower zones see the ground
    kept = img.copy()
    del sim, again
    gc.collect()
    assert np.array_equal(img, kept)  # the array holds a reference to the simulator


def test_planar_lidar_is_one_row_left_to_right_with_a_negative_stride(root):
    sim = kestrel.make_simulator(str(root / "sim" / "scenarios" / "planar_multirotor.yaml"), num_envs=3, threads=1,
                                 backend="planar")
    beams = sim.lidar_beams
    info = sim.range_image_info(0)
    assert sim.num_range_images == 1 and (info["height"], info["width"], info["col_step"]) == (1, beams, -1)
    img = sim.range_images(0)
    assert img.shape == (3, 1, beams) and img.strides[2] == -REAL.itemsize
    ptr = img.ctypes.data
    for _ in range(5):
        prev = img.copy()
        sim.step(sim.scripted_actions())
        # Column 0 is the leftmost beam: the lidar row (clockwise first) read backwards, no copy.
        assert np.array_equal(img[:, 0, :], sim.lidar_ranges_m[:, ::-1])
        assert np.shares_memory(img, sim.lidar_ranges_m) and sim.range_images(0).ctypes.data == ptr
    assert not np.array_equal(img, prev)
    assert np.any(img < info["max_range_m"])  # pillars, boxes or the yard's bounds in range
    with pytest.raises(ValueError, match="planar.*segmentation"):
        sim.segmentation_images(0)


def test_range_image_errors_name_the_argument():
    sim = _tof_sim(num_envs=2)
    with pytest.raises(ValueError, match=r"k: expected an image index in \[0, 1\)"):
        sim.range_images(1)
    with pytest.raises(ValueError, match=r"robot: expected a robot index in \[0, 2\)"):
        sim.range_image(2, 0)
    bare = kestrel.make_simulator({"env": "empty", "task": "position_setpoint"}, num_envs=1, threads=1, backend="rigid")
    assert bare.num_range_images == 0
    with pytest.raises(ValueError, match="sensors:"):
        bare.range_images()
    with pytest.raises(ValueError, match="quat_xyzw"):
        sim.reset_root_states([0], np.zeros((1, 3), REAL), np.zeros((1, 3), REAL))
    with pytest.raises(ValueError):  # a zero quaternion is refused by the backend, nothing changes
        sim.reset_root_states([0], np.zeros((1, 3), REAL), np.zeros((1, 4), REAL))
