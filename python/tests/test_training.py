"""A short training run on a fixed seed raises the evaluation return clearly above the untrained
policy's (a margin, not a timing). rsl_rl's PPO from PyPI through kestrel.adapters.RslRlVecEnv;
Stable-Baselines3's PPO through Sb3VecEnv for a few updates (the adapter works end to end)."""
import numpy as np

import kestrel
from kestrel.train import evaluate, main


def test_rsl_rl_training_improves_return(tmp_path):
    # ~1 M env-steps with the task's tuned defaults (train._TASK_DEFAULTS): ~10 s on 2 cores
    # (rsl_rl's PPO from PyPI, torch on 1 thread).
    s = main(["Kestrel-PositionSetpoint-v0", "--learner", "rsl_rl", "--seed", "1", "--steps", "1000000",
              "--eval-every", "500000", "--eval-episodes", "256", "--eval-seed", "777",
              "--threads", "2", "--out", str(tmp_path), "--quiet"])
    before, after = s["initial"], s["final"]
    # Untrained (seeds 0, 1, 2 alike): return ~155-162, 40-52 % crashes, 4.4-5.8 m from the target
    # at the end. Trained 1 M env-steps, seeds 0 / 1 / 2: return 821 / 1907 / 1261, no crash,
    # 0.43 / 0.37 / 0.49 m. The margins hold for every one of those seeds, not only this one.
    assert after["mean_return"] > 3.0 * before["mean_return"], (before, after)
    assert after["final_distance_m"] < 1.0 < before["final_distance_m"] - 3.0, (before, after)
    assert after["crash_rate"] < 0.05 < before["crash_rate"], (before, after)
    assert (tmp_path / "log.csv").exists() and (tmp_path / "curves.png").exists()
    assert list((tmp_path / "checkpoints").glob("*.pt"))


def test_sb3_adapter_trains(tmp_path):
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecEnv

    from kestrel.adapters import Sb3VecEnv

    env = kestrel.make_vec("Kestrel-PositionSetpoint-v0", num_envs=64, seed=0, threads=1, task={"episode_len_env_steps": 50})
    venv = Sb3VecEnv(env)
    assert isinstance(venv, VecEnv)
    model = PPO("MlpPolicy", venv, n_steps=64, batch_size=1024, n_epochs=2, seed=0, device="cpu", verbose=0)
    model.learn(64 * 64 * 3)
    assert model.num_timesteps >= 64 * 64 * 3
    assert len(model.ep_info_buffer) > 0  # episodes reached SB3 through the adapter's infos
    res = evaluate(lambda o: model.predict(np.array(o), deterministic=True)[0].astype(np.float32), "Kestrel-PositionSetpoint-v0",
                   episodes=32, seed=5, threads=1, task={"episode_len_env_steps": 50})
    assert np.isfinite(res.mean_return)


def test_navigation_evaluation_at_the_top_level():
    """evaluate() on navigation_task: the curriculum held at a level through task.curriculum, the
    first episode of each environment told apart exactly (terminated within the success radius =
    success, else crash). Flying straight at the goal crashes far more at level 10 (every obstacle)
    than at level 0; a hover only times out."""
    def held(level):
        return {"curriculum": {"start_level": level, "increase_step": 0, "decrease_step": 0}, "episode_len_env_steps": 400}

    env = kestrel.make_vec("Kestrel-Navigation-v0", num_envs=2, seed=5, threads=1, task=held(10))
    assert env.task.infos["curriculum_level"] == 10
    env.close()

    # Actions (forward_inclination): speed (a0 + 1) / 2 x 2 m/s along the heading, climb a1 x 45 deg,
    # yaw rate a2 x 60 deg/s.
    def hover(obs):
        a = np.zeros((obs.shape[0], 3), np.float32)
        a[:, 0] = -1.0  # no speed
        return a

    def toward_goal(obs):  # turn to the goal (obs 0-2: unit error, vehicle frame), then full speed at it
        heading = np.arctan2(obs[:, 1], obs[:, 0])
        a = np.zeros((obs.shape[0], 3), np.float32)
        a[:, 0] = np.where(np.abs(heading) < 0.3, 1.0, -1.0)
        a[:, 1] = np.clip(np.arctan2(obs[:, 2], np.hypot(obs[:, 0], obs[:, 1])) / (np.pi / 4), -1, 1)
        a[:, 2] = np.clip(2.0 * heading, -1, 1)
        return a

    still = evaluate(hover, "Kestrel-Navigation-v0", episodes=48, seed=77, threads=1, task=held(10))
    top = evaluate(toward_goal, "Kestrel-Navigation-v0", episodes=48, seed=77, threads=1, task=held(10))
    bottom = evaluate(toward_goal, "Kestrel-Navigation-v0", episodes=48, seed=77, threads=1, task=held(0))
    assert still.episodes == top.episodes == bottom.episodes == 48
    assert still.success_rate == 0.0 and still.crash_rate == 0.0 and still.mean_length == 400
    assert top.success_rate + top.crash_rate <= 1.0 and bottom.success_rate + bottom.crash_rate <= 1.0
    assert top.crash_rate > bottom.crash_rate + 0.2, (top, bottom)
    assert bottom.final_distance_m < still.final_distance_m
