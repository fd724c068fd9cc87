"""legged_gym's locomotion task (locomotion_task) from Python: the gymnasium ids of Go2 and ANYmal C
(flat and rough), their spaces and per-robot reward configs, the observation against the
simulator's noise-free views, bit-identical streams for 1 and 2 threads, and evaluate()'s
tracking errors."""
import gymnasium
import numpy as np
import pytest

import kestrel
from kestrel.train import evaluate
from kestrel.vector_env import GYM_IDS


@pytest.mark.parametrize("gym_id,obs_dim", [("Kestrel-Go2-Flat-v0", 48), ("Kestrel-AnymalC-Flat-v0", 48),
                                            ("Kestrel-Go2-Rough-v0", 48 + 187), ("Kestrel-AnymalC-Rough-v0", 48 + 187)])
def test_ids_and_spaces(gym_id, obs_dim):
    env = gymnasium.make_vec(gym_id, num_envs=2, seed=0, threads=1)
    inner = env.unwrapped if hasattr(env, "unwrapped") else env
    assert inner.task.name == "locomotion_task"
    assert env.single_observation_space.shape == (obs_dim,)
    assert env.single_action_space.shape == (12,)
    assert env.single_action_space.high[0] == 100.0  # legged_gym's clip_actions
    obs, _ = env.reset(seed=3)
    assert obs.shape == (2, obs_dim) and np.all(np.isfinite(obs))
    obs, r, te, tr, _ = env.step(np.zeros((2, 12), np.float32))
    assert np.all(np.isfinite(r)) and r.dtype == np.float32
    env.close()


def test_robot_configs_reach_the_task():
    # ANYmal C flat: no heading command, yaw rate drawn in +-1.5 rad/s; Go2: heading command, so the
    # yaw-rate command is 0.5 x the heading error clipped to +-1 (observation 11 = it x 0.25).
    assert GYM_IDS["Kestrel-AnymalC-Flat-v0"][1]["task"] == "locomotion_anymal_c_flat"
    yaw = []
    for gym_id in ("Kestrel-AnymalC-Flat-v0", "Kestrel-Go2-Flat-v0"):
        # A task override merges into the id's preset (it does not replace it).
        env = kestrel.make_vec(gym_id, num_envs=256, seed=1, threads=2, task={"episode_len_env_steps": 50})
        assert env.task.episode_len_env_steps == 50
        obs, _ = env.reset()
        yaw.append(np.abs(obs[:, 11] / 0.25).max())
        env.close()
    assert 1.0 < yaw[0] <= 1.5, yaw
    assert yaw[1] <= 1.0 + 1e-6, yaw


def test_observation_against_the_views():
    env = kestrel.make_vec("Kestrel-Go2-Flat-v0", num_envs=8, seed=2, threads=1)
    env.reset()
    rng = np.random.default_rng(0)
    for _ in range(10):
        a = rng.normal(0, 0.5, (8, 12)).astype(np.float32)
        obs, *_ = env.step(a)
    v = env.task.base_lin_vel_b
    w = env.task.base_ang_vel_b
    # Noise: +-0.1 m/s x 2 on the linear velocity, +-0.2 rad/s x 0.25 on the angular one.
    assert np.all(np.abs(obs[:, 0:3] - 2 * v) <= 0.2 + 1e-5)
    assert np.all(np.abs(obs[:, 3:6] - 0.25 * w) <= 0.05 + 1e-5)
    assert np.array_equal(obs[:, 36:48], a)  # the last actions, noise-free
    g = obs[:, 6:9]
    assert np.allclose(np.linalg.norm(g, axis=1), 1.0, atol=0.1) and np.all(g[:, 2] < -0.5)  # standing
    env.close()


def _stream(threads):
    env = kestrel.make_vec("Kestrel-Go2-Flat-v0", num_envs=6, seed=4, threads=threads, task={"episode_len_env_steps": 20})
    env.reset()
    rng = np.random.default_rng(7)
    out = []
    for _ in range(45):
        obs, r, te, tr, _ = env.step(rng.normal(0, 1, (6, 12)).astype(np.float32))
        out += [obs.copy(), r.copy(), te.copy(), tr.copy()]
    h = env.state_hash
    env.close()
    return out, h


def test_bit_identical_for_1_and_2_threads():
    a, ha = _stream(1)
    b, hb = _stream(2)
    assert ha == hb
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    assert any(t.any() for t in a[3::4])  # episodes truncated (and reset) inside the stream


def test_evaluate_tracking_errors():
    # Standing still: the linear tracking error is the mean commanded speed (|cmd| in [0.2, 1.41]
    # m/s, or 0), and no episode of 100 steps falls.
    def stand(obs):
        return np.zeros((obs.shape[0], 12), np.float32)

    res = evaluate(stand, "Kestrel-Go2-Flat-v0", episodes=32, seed=9, threads=2, task={"episode_len_env_steps": 100})
    assert res.episodes == 32 and res.mean_length == 100
    assert res.crash_rate == 0.0 and res.success_rate == 1.0
    assert 0.4 < res.lin_vel_error_m_s < 1.0, res
    assert 0.0 < res.yaw_rate_error_rad_s < 1.0, res


def test_rsl_rl_training_improves_return(tmp_path):
    # legged_gym's PPO settings (train._LEGGED_DEFAULTS) on 256 envs for ~0.6 M env-steps (~35 s on
    # 2 cores). Untrained (the initial network's mean action), seeds 0 / 1 / 2: return 3.8 / 3.3 / 3.7
    # with 11-14 % falls (reset velocities, the 0.5-1.5 x home joint spread, the push at 15 s);
    # after 0.3-0.6 M env-steps 5.6-6.3 with 0-5 % falls. Walking to the commands takes ~25 M more
    # (bench/results/python/go2_flat_rsl_rl.*).
    from kestrel.train import main

    s = main(["Kestrel-Go2-Flat-v0", "--envs", "256", "--seed", "0", "--steps", "600000", "--eval-every", "300000",
              "--eval-episodes", "64", "--eval-seed", "777", "--threads", "2", "--out", str(tmp_path), "--quiet",
              "--export", "0", "--tensorboard", "0"])
    before, after = s["initial"], s["final"]
    assert after["mean_return"] > 1.3 * before["mean_return"], (before, after)
    assert after["crash_rate"] < before["crash_rate"], (before, after)
    assert np.isfinite(after["lin_vel_error_m_s"]) and after["lin_vel_error_m_s"] < 0.8
    assert (tmp_path / "curves.png").exists()
