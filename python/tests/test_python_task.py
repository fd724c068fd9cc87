"""Registering presets from Python (kestrel.register) and tasks written in Python over the
Simulator's views (kestrel.PythonTask / PythonTaskVectorEnv)."""
import numpy as np
import pytest

import kestrel


def test_register_a_sim_and_fly_in_it():
    kestrel.register("sim", "py_falling_forwards", base="base_sim", description="gravity tilted towards +x",
                     gravity_w=[5.0, 0.0, -9.81])
    assert "py_falling_forwards" in kestrel.list("sims")
    drift = {}
    for sim_name in ("base_sim", "py_falling_forwards"):
        sim = kestrel.make_simulator({"sim": sim_name, "env": "empty", "controller": "lee_attitude_control"}, num_envs=4, seed=1,
                                     threads=1, backend="rigid")
        wd = sim.world_data()
        for _ in range(40):  # the World's own actions: hover thrust, level attitude
            sim.step(None)
        drift[sim_name] = float(wd["linvel_w"][:, 0].mean())
    # 0.4 s of +5 m/s^2 with the thrust holding only the vertical: about 2 m/s along +x.
    assert abs(drift["base_sim"]) < 0.05
    assert 1.5 < drift["py_falling_forwards"] < 2.5
    with pytest.raises(ValueError, match="the name is taken"):
        kestrel.register("sims", "py_falling_forwards", gravity_w=[0.0, 0.0, -9.81])
    with pytest.raises(ValueError, match=r"sim.dt_s: expected a number in \[1e-06, 1\]"):
        kestrel.register("sim", "py_bad", dt_s=3.0)
    with pytest.raises(ValueError, match="base: expected the name of a registered controller"):
        kestrel.register("controller", "py_ctrl")
    kestrel.register("env", "py_few_trees", base="forest", num_envs=3, curriculum_level=0.0)
    assert kestrel.scenario({"env": "py_few_trees"}).num_envs == 3


class Hover(kestrel.PythonTask):
    observation_dim = 6
    action_low, action_high = -3.0, 3.0  # m/s, the Lee velocity controller's command

    def observations(self, sim):
        # The error in the yaw-only vehicle frame: lee_velocity_control's command frame.
        e = sim.target_w - sim.base_pos_w
        yaw = sim.base_euler_xyz[:, 2]
        c, s = np.cos(yaw), np.sin(yaw)
        e_v = np.stack([c * e[:, 0] + s * e[:, 1], -s * e[:, 0] + c * e[:, 1], e[:, 2]], axis=1)
        return np.concatenate([e_v, sim.base_lin_vel_b], axis=1)

    def rewards(self, sim, actions):
        return -np.linalg.norm(sim.target_w - sim.base_pos_w, axis=1)

    def terminations(self, sim):
        return sim.world_data()["crashed"].astype(bool)


SCENE = {"env": "empty", "controller": "lee_velocity_control", "task": {"name": "position_setpoint", "episode_len_env_steps": 150}}


def _rollout(policy, seed=0, steps=300):
    env = kestrel.PythonTaskVectorEnv(Hover(), SCENE, num_envs=16, seed=seed, threads=1, backend="rigid")
    obs, _ = env.reset(seed=seed)
    rewards, truncs = [], 0
    for _ in range(steps):
        # The observation is the task's function of the Simulator's views, computed independently here.
        e = env.sim.target_w - env.sim.base_pos_w
        np.testing.assert_allclose(np.linalg.norm(obs[:, :3], axis=1), np.linalg.norm(e, axis=1), atol=1e-5)
        np.testing.assert_array_equal(obs[:, 2], e[:, 2])
        obs, r, term, trunc, info = env.step(policy(obs))
        rewards.append(r.copy())
        truncs += int(trunc.sum())
        if trunc.any():
            assert info["_final_obs"][trunc].all()
    return np.array(rewards), truncs


def test_python_task_runs_truncates_and_rewards_a_good_policy():
    toward = lambda obs: np.concatenate([np.clip(2 * obs[:, :3], -3, 3), np.zeros((len(obs), 1))], axis=1).astype(np.float32)
    still = lambda obs: np.zeros((len(obs), 4), dtype=np.float32)
    r_good, truncs = _rollout(toward)
    r_still, _ = _rollout(still)
    assert truncs == 2 * 16  # every episode hits the 150-step limit twice in 300 steps
    # Flying towards the target earns clearly more than hovering where it started.
    assert r_good.mean() > r_still.mean() + 0.5
    # Same seed, same stream: from a new env, and from the same env reset with that seed again.
    r_again, _ = _rollout(toward)
    np.testing.assert_array_equal(r_good, r_again)
    env = kestrel.PythonTaskVectorEnv(Hover(), SCENE, num_envs=16, seed=0, threads=1, backend="rigid")
    first, _ = env.reset(seed=0)
    env.step(toward(first))
    again, _ = env.reset(seed=0)
    np.testing.assert_array_equal(first, again)


def test_python_task_checks_its_outputs():
    class Wrong(Hover):
        observation_dim = 5

    env = kestrel.PythonTaskVectorEnv(Wrong(), SCENE, num_envs=4, seed=0, threads=1, backend="rigid")
    with pytest.raises(ValueError, match=r"Wrong.observations: expected shape \(4, 5\), got \(4, 6\)"):
        env.reset()
