"""Zero-copy: the arrays view the task's own buffers for its lifetime; torch shares them."""
import numpy as np
import torch

import kestrel


def test_same_data_pointer_over_many_steps():
    env = kestrel.make_vec("Kestrel-PositionSetpoint-v0", num_envs=4, seed=0, threads=1)
    obs, _ = env.reset()
    a = np.zeros((4, 4), np.float32)
    ptrs = None
    for _ in range(10_000):
        o, r, te, tr, info = env.step(a)
        p = (o.ctypes.data, r.ctypes.data, te.ctypes.data, tr.ctypes.data)
        ptrs = ptrs or p
        assert p == ptrs
    assert o is obs and np.shares_memory(o, env.task.observations)
    assert env.task.infos["episodes"] > 0  # auto-resets happened in between


def test_fresh_views_share_memory_and_torch_from_numpy_shares():
    t = kestrel.make_task("position_setpoint_task", num_envs=3, threads=1)
    o1, o2 = t.observations, t.observations
    assert np.shares_memory(o1, o2) and o1.ctypes.data == o2.ctypes.data
    assert np.shares_memory(t.rewards, t.rewards)
    tt = torch.from_numpy(o1)
    before = tt.clone()
    t.step(np.ones((3, 4), np.float32))
    assert tt.data_ptr() == o1.ctypes.data
    assert not torch.equal(before, tt)  # the tensor sees the step without a copy
    assert torch.equal(tt, torch.from_numpy(t.observations))


def test_views_keep_the_task_alive():
    t = kestrel.make_task("position_setpoint_task", num_envs=2, threads=1)
    o = t.observations
    expected = o.copy()
    del t
    import gc
    gc.collect()
    assert np.array_equal(o, expected)  # the array owns a reference to the task
