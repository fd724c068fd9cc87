"""The rigid World's data (sim/world_data.hpp) from Python without copies: Simulator.world_data()
gives read-only numpy views straight over the arrays a step writes (issue 10's model/data split,
issue 11's zero-copy access). Checked against the Simulator's own views, across steps."""
import numpy as np
import pytest

import kestrel


def _sim(**kw):
    return kestrel.make_simulator({"env": "env_with_obstacles", "task": "position_setpoint"}, num_envs=6, seed=3, threads=2,
                                  backend="rigid", **kw)


def _ptr(a):
    return a.__array_interface__["data"][0]


def test_views_are_the_world_state_in_place_across_steps():
    sim = _sim()
    wd = sim.world_data()
    pos, quat, vel = wd["position_w"], wd["orientation_xyzw"], wd["linvel_w"]
    assert pos.shape == (6, 3) and quat.shape == (6, 4) and wd["crashed"].shape == (6,)
    assert not pos.flags.writeable and not pos.flags.c_contiguous  # strided over the state rows
    before = pos.copy()
    p0 = _ptr(pos)
    for _ in range(25):
        sim.step(None)
        # Same memory, new values: the view is the World's state, not a snapshot.
        assert _ptr(sim.world_data()["position_w"]) == p0
        np.testing.assert_array_equal(pos, sim.base_pos_w)
        np.testing.assert_array_equal(quat, sim.base_quat_xyzw)
        np.testing.assert_array_equal(wd["target_w"], sim.target_w)
        np.testing.assert_array_equal(wd["contact_force_w"], sim.contact_forces_w)
    assert not np.array_equal(before, pos)
    # World-frame velocity rotated into the body frame is the Simulator's base_lin_vel_b.
    q = quat.astype(np.float64)
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    r = np.stack([np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
                  np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
                  np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1)], -2)
    vb = np.einsum("nji,nj->ni", r, vel.astype(np.float64))
    np.testing.assert_allclose(vb, sim.base_lin_vel_b, atol=1e-5)


def test_obstacles_and_bounds():
    sim = _sim()
    wd = sim.world_data()
    n = wd["num_obstacles"]
    lo, hi = wd["lower_w"], wd["upper_w"]
    assert n.shape == (6,) and (n > 0).all()
    obs = wd["obstacle_position_w"]
    assert obs.shape[0] == 6 and obs.shape[2] == 3 and obs.shape[1] >= n.max()
    for e in range(6):
        lo_e, hi_e = sim.env_bounds(e)
        np.testing.assert_array_equal(lo[e], lo_e)
        np.testing.assert_array_equal(hi[e], hi_e)
        used = obs[e, : n[e]]
        # Obstacles stand inside the bounds (walls just outside them, by their thickness).
        assert (used >= lo[e] - 0.2).all() and (used <= hi[e] + 0.2).all()


def test_views_are_read_only_and_planar_refuses():
    wd = _sim().world_data()
    with pytest.raises(ValueError):
        wd["position_w"][0, 0] = 1.0
    planar = kestrel.make_simulator({"env": "planar_obstacles", "robot": "ground_vehicle", "simulator": "planar"}, num_envs=2,
                                    seed=0, threads=1, backend="planar")
    with pytest.raises(ValueError, match="use simulator: rigid"):
        planar.world_data()
