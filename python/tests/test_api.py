"""API: registries, make by id, scenarios from a dict / file / YAML text, spaces and shapes, the Simulator."""
import json

import gymnasium
import numpy as np
import pytest

import kestrel


def test_list_registries():
    regs = kestrel.list()
    for kind in ("sims", "envs", "robots", "controllers", "sensors", "tasks", "simulators"):
        assert regs[kind], kind
    assert "forest" in regs["envs"] and "lee_velocity_control" in regs["controllers"]
    assert "position_setpoint_task" in kestrel.task_ids() and "navigation_task" in kestrel.task_ids()
    assert dict(kestrel.list("sims", descriptions=True))["falling_forwards"]
    with pytest.raises(ValueError, match="kind: expected one of sims"):
        kestrel.list("nope")


def test_make_task_by_id_with_overrides():
    t = kestrel.make_task("position_setpoint_task", num_envs=5, seed=3, threads=1, controller="lee_attitude_control",
                          task={"episode_len_env_steps": 50})
    assert (t.name, t.num_envs, t.obs_dim, t.action_dim, t.seed) == ("position_setpoint_task", 5, 13, 4, 3)
    assert t.controller == "lee_attitude_control" and t.episode_len_env_steps == 50
    assert t.observations.shape == (5, 13) and t.observations.dtype == np.float32
    assert t.rewards.shape == (5,) and t.terminations.dtype == np.bool_ and t.truncations.shape == (5,)
    a = np.zeros((5, 4), np.float32)
    for _ in range(50):
        t.step(a)
    assert t.truncations.all() and t.infos["truncations"] == 5  # zero attitude action = hover: no crash


def test_scenario_from_dict_file_and_text_agree(root):
    path = root / "sim" / "scenarios" / "position_setpoint_attitude.yaml"
    d = {"seed": 0, "env": {"name": "empty", "num_envs": 64}, "controller": "lee_attitude_control",
         "task": "position_setpoint_task"}
    hashes = []
    for src in (str(path), d, json.dumps(d)):
        t = kestrel.make_task(scenario=src, num_envs=16, seed=2, threads=1)
        for _ in range(20):
            t.step(t.scripted_actions())
        hashes.append(t.state_hash)
    assert hashes[0] == hashes[1] == hashes[2]


def test_vector_env_spaces_and_gymnasium_make_vec():
    env = gymnasium.make_vec("Kestrel-PositionSetpoint-v0", num_envs=7, seed=0, threads=1)
    assert isinstance(env.unwrapped, gymnasium.vector.VectorEnv)
    assert env.num_envs == 7
    assert env.single_observation_space.shape == (13,) and env.observation_space.shape == (7, 13)
    assert env.single_action_space.shape == (4,) and env.action_space.shape == (7, 4)
    assert np.all(env.single_action_space.low == -10) and np.all(env.single_action_space.high == 10)
    assert env.metadata["autoreset_mode"] == gymnasium.vector.AutoresetMode.SAME_STEP
    obs, info = env.reset(seed=1)
    assert obs.shape == (7, 13) and env.observation_space.contains(obs)
    obs, rew, term, trunc, info = env.step(env.action_space.sample())
    assert rew.shape == (7,) and term.dtype == np.bool_ and trunc.dtype == np.bool_
    nav = kestrel.make_vec("Kestrel-Navigation-v0", num_envs=2, threads=1)
    assert nav.single_observation_space.shape[0] == nav.task.obs_dim and nav.single_action_space.high[0] == 1.0
    nav.step(np.zeros((2, nav.task.action_dim), np.float32))


def test_simulator_views(root):
    sim = kestrel.make_simulator(root / "sim" / "scenarios" / "planar_multirotor.yaml", num_envs=6, seed=0, threads=1)
    assert sim.backend == "planar"
    pos = sim.base_pos_w
    assert pos.shape == (sim.num_robots, 3) and sim.base_quat_xyzw.shape == (sim.num_robots, 4)
    assert sim.base_lin_vel_b.shape == (sim.num_robots, 3) and sim.base_ang_vel_b.shape == (sim.num_robots, 3)
    assert sim.contact_forces_w.shape == (sim.num_robots, 3) and sim.reset_buf.shape == (6,)
    before = pos.copy()
    for _ in range(50):
        sim.step(sim.scripted_actions())
    assert pos.ctypes.data == sim.base_pos_w.ctypes.data  # a view: moved in place
    assert not np.array_equal(before, pos)
    sim.reset_idx([0, 3])
    with pytest.raises(ValueError, match="env_ids: expected ids in"):
        sim.reset_idx([6])
    rigid = kestrel.make_simulator({"env": {"name": "empty", "num_envs": 3}}, threads=1, backend="rigid")
    rigid.step(None)
    assert rigid.base_pos_w.shape == (3, 3) and np.isfinite(rigid.base_pos_w).all()


def test_box2d_allocation_hooks_take_effect_in_the_module():
    # sim/src/backends/planar.cpp's b2Alloc_Default / b2Free_Default interpose on libbox2d.so's inside the
    # extension module too (it exports them; libbox2d's PLT finds the module first in its scope).
    assert kestrel.box2d_hooks_active()
    sim = kestrel.make_simulator({"simulator": "planar", "env": {"name": "planar_obstacles", "num_envs": 8}}, threads=2)
    for _ in range(200):
        sim.step(sim.scripted_actions())
    assert sim.step_heap_fallbacks == 0
