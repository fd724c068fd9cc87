"""Bad input raises a Python exception naming the argument and the allowed values; the env still steps."""
import numpy as np
import pytest

import kestrel


@pytest.fixture
def env():
    return kestrel.make_vec("Kestrel-PositionSetpoint-v0", num_envs=4, seed=0, threads=1)


def _still_steps(env):
    o, r, te, tr, _ = env.step(np.zeros((4, 4), np.float32))
    assert np.isfinite(o).all() and np.isfinite(r).all()


def test_wrong_dtype(env):
    with pytest.raises(TypeError, match=r"actions: expected dtype float32, got float64"):
        env.step(np.zeros((4, 4)))
    with pytest.raises(TypeError, match=r"actions: expected a numpy float32 array of shape \(4, 4\)"):
        env.step([[0.0] * 4] * 4)
    _still_steps(env)


def test_wrong_shape_and_layout(env):
    with pytest.raises(ValueError, match=r"actions: expected shape \(4, 4\) = \(num_envs, action_dim\), got \(4, 3\)"):
        env.step(np.zeros((4, 3), np.float32))
    with pytest.raises(ValueError, match=r"expected shape \(4, 4\).*got \(16,\)"):
        env.step(np.zeros(16, np.float32))
    with pytest.raises(ValueError, match="C-contiguous"):
        env.step(np.zeros((4, 8), np.float32)[:, ::2])
    _still_steps(env)


def test_nan_and_inf_actions(env):
    before = env.task.state_hash
    a = np.zeros((4, 4), np.float32)
    a[1, 2] = np.nan
    with pytest.raises(ValueError, match=r"actions: expected finite values, got nan at \[1, 2\]"):
        env.step(a)
    a[1, 2] = np.inf
    with pytest.raises(ValueError, match="expected finite values"):
        env.step(a)
    assert env.task.state_hash == before  # nothing was stepped
    _still_steps(env)


def test_unknown_ids_and_fields():
    with pytest.raises(ValueError, match="task_id: unknown task 'nope'; registered task ids: .*position_setpoint_task"):
        kestrel.make_task("nope")
    with pytest.raises(ValueError, match="id: unknown environment 'Nope-v0'; gymnasium ids: Kestrel-PositionSetpoint-v0"):
        kestrel.make_vec("Nope-v0")
    with pytest.raises(ValueError, match='controller: unknown controller "nope"; known: direct_motor_control'):
        kestrel.make_task("position_setpoint_task", controller="nope")
    with pytest.raises(ValueError, match="env.num_envs: expected an integer in"):
        kestrel.make_task("position_setpoint_task", env={"name": "empty", "num_envs": -3})
    with pytest.raises(ValueError, match="env.bogus: unknown field; allowed: name"):
        kestrel.make_task("position_setpoint_task", env={"name": "empty", "bogus": 1})
    with pytest.raises(ValueError, match="backend: expected one of rigid, planar"):
        kestrel.make_task("position_setpoint_task", backend="mujoco")
    with pytest.raises(ValueError, match="num_envs: expected an integer >= 1"):
        kestrel.make_task("position_setpoint_task", num_envs=0)
