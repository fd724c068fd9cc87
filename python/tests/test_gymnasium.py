"""gymnasium conformance: same-step autoreset with final_obs, terminated vs truncated, wrappers."""
import gymnasium
import numpy as np
from gymnasium.wrappers.vector import NormalizeObservation, RecordEpisodeStatistics

import kestrel


def test_same_step_autoreset_final_obs_and_flags():
    n, length = 6, 40
    env = kestrel.make_vec("Kestrel-PositionSetpoint-v0", num_envs=n, seed=2, threads=1, task={"episode_len_env_steps": length})
    obs, _ = env.reset()
    a = np.zeros((n, 4), np.float32)  # zero velocity: hover in place until the episode is truncated
    for k in range(length):
        prev = obs.copy()
        obs, r, term, trunc, info = env.step(a)
        if k < length - 1:
            assert "final_obs" not in info and not trunc.any()
    assert trunc.all() and not term.any()
    assert info["_final_obs"].all()
    final = info["final_obs"]
    # the final observation is the ended state (close to the previous one), the returned one a new episode
    assert np.allclose(final[:, :3], prev[:, :3], atol=0.05)
    assert not np.allclose(obs[:, :3], final[:, :3], atol=0.05)
    assert "success" in info and info["success"].dtype == np.bool_


def test_terminated_kept_apart_from_truncated():
    n = 8
    env = kestrel.make_vec("Kestrel-PositionSetpointMotors-v0", num_envs=n, seed=0, threads=1)
    env.reset()
    a = np.full((n, 4), -1.0, np.float32)  # motors off: every robot falls and crashes
    for _ in range(400):
        _, r, term, trunc, info = env.step(a)
        if term.any():
            break
    assert term.any() and not (term & trunc).any()
    assert np.all(r[term] == -20.0)
    assert info["_final_obs"][term].all()


def test_record_episode_statistics_same_step():
    n, length = 4, 25
    env = kestrel.make_vec("Kestrel-PositionSetpoint-v0", num_envs=n, seed=0, threads=1, task={"episode_len_env_steps": length})
    env = RecordEpisodeStatistics(env)
    env.reset(seed=0)
    for rounds in range(2):
        total = np.zeros(n)
        for k in range(length):
            obs, r, term, trunc, info = env.step(np.zeros((n, 4), np.float32))
            total += r
        assert "episode" in info and info["_episode"].all()
        assert np.allclose(info["episode"]["r"], total, rtol=1e-5) and np.all(info["episode"]["l"] == length)


def test_normalize_observation_and_statistics_next_step():
    # gymnasium's observation wrappers take NEXT_STEP envs only: autoreset_mode="next_step".
    n, length = 4, 25
    env = kestrel.make_vec("Kestrel-PositionSetpoint-v0", num_envs=n, seed=0, threads=1, task={"episode_len_env_steps": length},
                           autoreset_mode="next_step")
    assert env.metadata["autoreset_mode"] == gymnasium.vector.AutoresetMode.NEXT_STEP
    raw = env
    env = NormalizeObservation(RecordEpisodeStatistics(env))
    obs, _ = env.reset(seed=0)
    a = np.zeros((n, 4), np.float32)
    for k in range(length):
        obs, r, term, trunc, info = env.step(a)
    assert trunc.all() and "episode" in info and np.all(info["episode"]["l"] == length)
    final_raw = raw._out.copy()  # the env returned the final observations this step
    obs, r, term, trunc, info = env.step(a)  # the reset step of NEXT_STEP: reward 0, no flags
    assert np.all(r == 0) and not term.any() and not trunc.any()
    assert not np.allclose(raw.task.observations[:, :3], final_raw[:, :3], atol=0.05)
    assert obs.dtype == np.float32 and np.isfinite(obs).all()
    for k in range(length):
        obs, r, term, trunc, info = env.step(a)
    assert trunc.all() and np.all(info["episode"]["l"] == length)


def test_vector_env_checks():
    """The checks of gymnasium's check_env that apply to a vector env."""
    env = gymnasium.make_vec("Kestrel-PositionSetpoint-v0", num_envs=3, threads=1)
    obs, info = env.reset(seed=123)
    assert isinstance(info, dict) and env.observation_space.contains(obs)
    obs2, _ = env.reset(seed=123)
    assert np.array_equal(obs, obs2)  # reset(seed) is deterministic
    act = env.action_space.sample()
    assert env.action_space.contains(act)
    out = env.step(act)
    assert len(out) == 5 and isinstance(out[4], dict)
    assert out[1].dtype in (np.float32, np.float64) and out[2].shape == out[3].shape == (3,)
    assert env.observation_space.contains(out[0])
    env.close()


def test_normalised_actions_and_vehicle_frame_obs():
    # The trainer's interface for Kestrel-PositionSetpoint-v0 (issue 11): actions in [-1, 1] scaled
    # to +-2 m/s, +-1 rad/s; target - position in the vehicle frame (same distance). The linear
    # policy a = clip(e_vehicle / 2) then reaches every target.
    import kestrel
    from kestrel.train import evaluate

    plain = kestrel.make_vec("Kestrel-PositionSetpoint-v0", num_envs=8, seed=3, threads=1)
    env = kestrel.make_vec("Kestrel-PositionSetpoint-v0", num_envs=8, seed=3, threads=1, action_scale=[2, 2, 2, 1],
                           vehicle_frame_obs=True)
    assert np.all(env.single_action_space.high == 1) and np.all(env.single_action_space.low == -1)
    o0, o1 = plain.reset()[0].copy(), env.reset()[0].copy()
    np.testing.assert_allclose(np.linalg.norm(o0[:, :3], axis=1), np.linalg.norm(o1[:, :3], axis=1), rtol=1e-5)
    np.testing.assert_array_equal(o0[:, 3:], o1[:, 3:])
    a = np.full((8, 4), 0.25, np.float32)
    plain.step(np.ascontiguousarray(a * np.float32([2, 2, 2, 1])))
    env.step(a)
    assert plain.state_hash == env.state_hash  # the scaled action is exactly the task's action
    res = evaluate(lambda o: np.ascontiguousarray(np.concatenate([np.clip(o[:, :3] / 2, -1, 1), np.zeros((len(o), 1))], 1),
                                                  dtype=np.float32),
                   "Kestrel-PositionSetpoint-v0", episodes=64, seed=11, threads=1, action_scale=[2, 2, 2, 1], vehicle_frame_obs=True)
    assert res.success_rate >= 0.95 and res.crash_rate == 0, res


def test_action_offset_motor_commands():
    # The trainer's interface for Kestrel-PositionSetpointMotors-v0 (issue 11): normalised motor
    # commands around hover thrust, offset + scale * clip(a, -1, 1) N. The zero action is hover
    # (the task's own zero action is motors off: the robot falls); the mapping is exact.
    import pytest

    import kestrel

    hover = 0.25 * 9.81 / 4
    plain = kestrel.make_vec("Kestrel-PositionSetpointMotors-v0", num_envs=8, seed=3, threads=1)
    env = kestrel.make_vec("Kestrel-PositionSetpointMotors-v0", num_envs=8, seed=3, threads=1, action_scale=hover,
                           action_offset=hover)
    assert np.all(env.single_action_space.high == 1) and np.allclose(env.action_offset, hover)
    plain.reset(), env.reset()
    a = np.tile(np.float32([0.5, -0.25, 2.0, -3.0]), (8, 1))  # the last two clipped to +-1
    plain.step(np.ascontiguousarray(np.float32(hover) + np.float32(hover) * np.clip(a, -1, 1)))
    env.step(a)
    assert plain.state_hash == env.state_hash
    env.reset()
    crashes = 0
    for _ in range(200):
        _, _, te, _, _ = env.step(np.zeros((8, 4), np.float32))
        crashes += int(te.sum())
    assert crashes == 0
    with pytest.raises(ValueError, match="action_offset"):
        kestrel.make_vec("Kestrel-PositionSetpointMotors-v0", num_envs=2, seed=0, threads=1, action_offset=hover)
