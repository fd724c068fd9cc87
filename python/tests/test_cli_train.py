"""`kestrel train` (the package's console command, pyproject [project.scripts] -> kestrel.cli:main):
a tiny rsl_rl run writes TensorBoard event files that tensorboard's own EventAccumulator reads back
with the logged scalars (the evaluations equal to the CSV's), the CSV, the plot, checkpoints and
the final policy as ONNX agreeing with the learner's own policy."""
import csv
import os
import subprocess
import sys
from importlib.metadata import entry_points

import numpy as np

TASK = "Kestrel-PositionSetpoint-v0"


def _console_script():
    (ep,) = entry_points(group="console_scripts", name="kestrel")
    assert ep.value == "kestrel.cli:main"
    return ep


def test_console_command_is_installed_and_answers():
    _console_script()
    exe = os.path.join(os.path.dirname(sys.executable), "kestrel")
    assert os.access(exe, os.X_OK), exe
    r = subprocess.run([exe, "train", "-h"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and "usage: kestrel train" in r.stdout and "--learner" in r.stdout and "--tensorboard" in r.stdout
    r = subprocess.run([exe, "nope"], capture_output=True, text=True, timeout=60, env={**os.environ, "KESTREL_CLI": "/nonexistent"})
    assert r.returncode == 2 and "unknown command 'nope'" in r.stderr and "train" in r.stderr


def test_kestrel_train_writes_tensorboard_csv_plot_checkpoints_and_onnx(tmp_path, capfd):
    import json

    import onnx
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    out = tmp_path / "run"
    # 16 envs x 16 decisions x action repeat 10 = 2560 env-steps per rsl_rl update; 2 updates,
    # evaluated before, between and after (16 episodes of 100 env-steps on an unseen seed).
    rc = _console_script().load()(["train", TASK, "--learner", "rsl_rl", "--envs", "16", "--seed", "0", "--steps", "5120",
                                   "--eval-every", "2560", "--eval-episodes", "16", "--episode-len", "100",
                                   "--threads", "1", "--out", str(out)])
    assert rc == 0
    cap = capfd.readouterr()
    # stderr is a file here, not a terminal: no progress bar (issue 15), but the summary on stdout.
    assert "env-step" not in cap.err and "5.12k/5.12k" not in cap.err, cap.err
    assert '"env_steps": 5120' in cap.out

    with open(out / "log.csv") as f:
        rows = list(csv.DictReader(f))
    assert [int(r["env_steps"]) for r in rows] == [0, 2560, 5120]
    assert (out / "curves.png").stat().st_size > 10_000
    assert sorted(p.name for p in (out / "checkpoints").glob("*.pt")) == ["rsl_rl_2560.pt", "rsl_rl_5120.pt"]

    events = list(out.glob("events.out.tfevents.*"))
    assert len(events) == 1
    acc = EventAccumulator(str(out))
    acc.Reload()
    tags = set(acc.Tags()["scalars"])
    for t in ("eval/mean_return", "eval/success_rate", "eval/crash_rate", "eval/mean_length", "eval/final_distance_m",
              "time/train_s", "train/mean_episode_reward", "loss/learning_rate", "policy/mean_std", "perf/env_steps_per_s"):
        assert t in tags, (t, sorted(tags))
    assert any(t.startswith("loss/") and t != "loss/learning_rate" for t in tags)  # rsl_rl's own losses
    ev = acc.Scalars("eval/mean_return")
    assert [e.step for e in ev] == [0, 2560, 5120]
    np.testing.assert_allclose([e.value for e in ev], [float(r["mean_return"]) for r in rows], rtol=1e-6)
    np.testing.assert_allclose([e.value for e in acc.Scalars("eval/final_distance_m")],
                               [float(r["final_distance_m"]) for r in rows], rtol=1e-6)
    assert [e.step for e in acc.Scalars("policy/mean_std")] == [2560, 5120]  # one point per update
    assert all(np.isfinite(e.value) for e in acc.Scalars("train/mean_episode_reward"))

    summary = json.loads((out / "summary.json").read_text())
    ex = summary["export"]
    assert ex["vehicle_frame_obs"] is True and ex["observations"] >= 256
    assert ex["max_abs_diff_spec_vs_learner"] < 1e-5 and ex["max_abs_diff_onnx_vs_spec"] < 1e-5
    onnx.checker.check_model(onnx.load(ex["onnx"]))
    # Trained without a normaliser, squashed into [-1, 1]: exported without either part (export.py).
    assert "MlpParams<13, 64, 64, 4, 0u>" in (out / "policy.hpp").read_text()


def test_progress_bar_only_on_a_terminal_and_not_quiet():
    from kestrel.train import progress_enabled

    class Stream:
        def __init__(self, tty):
            self.tty = tty

        def isatty(self):
            return self.tty

    assert progress_enabled(False, Stream(True)) is True
    assert progress_enabled(True, Stream(True)) is False  # --quiet
    assert progress_enabled(False, Stream(False)) is False  # a file or a pipe
    assert progress_enabled(False, object()) is False  # no isatty at all


def test_training_progress_bar_on_a_pseudo_terminal(tmp_path):
    """With stderr on a pseudo-terminal the bar is drawn and reaches the end; --quiet silences it."""
    import pty_run

    exe = os.path.join(os.path.dirname(sys.executable), "kestrel")
    base = [exe, "train", TASK, "--learner", "rsl_rl", "--envs", "16", "--seed", "0", "--steps", "2560", "--eval-every", "2560",
            "--eval-episodes", "16", "--episode-len", "100", "--threads", "1", "--tensorboard", "0", "--export", "0"]
    for quiet in (False, True):
        # A terminal 120 columns wide (a fresh pseudo-terminal has 0, where tqdm draws an empty bar).
        cmd = base + ["--out", str(tmp_path / f"q{int(quiet)}")] + (["--quiet"] if quiet else [])
        rc, _, err = pty_run.run(cmd, timeout=300, columns=120, stdout=subprocess.DEVNULL)
        assert rc == 0
        if quiet:
            assert "env-step" not in err, err
        else:
            assert "2.56k/2.56k" in err and "env-step" in err, err


def test_train_task_set_reaches_the_training_envs_only(tmp_path):
    # --train-task-set: task keys for the training environments alone (training-side randomisation,
    # e.g. Go2's pushes every 4 s, that the evaluation must not see). Here the training episodes are
    # cut to 20 env-steps while the evaluation keeps --episode-len's 100: its episodes (no crash at
    # the start of training, which hovers under the Lee controller) run past 20 steps.
    from kestrel.train import main

    s = main([TASK, "--envs", "16", "--seed", "0", "--steps", "2560", "--eval-every", "2560", "--eval-episodes", "16",
              "--episode-len", "100", "--threads", "1", "--out", str(tmp_path), "--quiet", "--export", "0",
              "--tensorboard", "0", "--train-task-set", '{"episode_len_env_steps": 20}'])
    assert s["train_task_set"] == '{"episode_len_env_steps": 20}'
    assert s["initial"]["mean_length"] > 20 and s["final"]["mean_length"] > 20, (s["initial"], s["final"])
    with open(tmp_path / "summary.json") as f:
        import json

        assert json.load(f)["train_task_set"] == s["train_task_set"]
    # The training envs' episodes were the short ones: 2560 env-steps over 16 envs end >= 16 x 7 of them.
    assert s["train_episodes"] >= 16 * 7, s["train_episodes"]


def test_train_task_set_refuses_what_is_not_a_json_object(tmp_path):
    import pytest

    from kestrel.train import main

    for bad in ("{nope", "[1, 2]"):
        with pytest.raises(SystemExit, match="--train-task-set: expected a JSON object"):
            main([TASK, "--envs", "4", "--steps", "10", "--out", str(tmp_path), "--quiet", "--train-task-set", bad])


def test_sensors_replace_the_task_sensors(tmp_path):
    # --sensors: the robot's sensors as scenario entries; navigation_task's observations then pool
    # the new image (here a 4 x 4 ToF into 4 x 4 cells: 17 + 16 observations), and the summary keeps them.
    from kestrel.train import main

    s = main(["Kestrel-Navigation-v0", "--envs", "8", "--steps", "400", "--eval-every", "400", "--eval-episodes", "4",
              "--episode-len", "20", "--threads", "1", "--out", str(tmp_path), "--quiet", "--export", "1",
              "--sensors", '[{"name": "vl53l5cx", "height": 4, "width": 4, "max_range_m": 10}]',
              "--task-set", '{"navigation": {"pool_rows": 4, "pool_cols": 4}}'])
    assert s["sensors"] == '[{"name": "vl53l5cx", "height": 4, "width": 4, "max_range_m": 10}]'
    assert s["export"] is not None
    import onnx

    model = onnx.load(str(tmp_path / "policy.onnx"))
    dims = [d.dim_value for d in model.graph.input[0].type.tensor_type.shape.dim]
    assert dims[-1] == 17 + 16, dims


def test_navigation_trains_and_evaluates_on_proximity_cells_unless_told_otherwise(tmp_path):
    # Kestrel-Navigation-v0's default --task-set: image cells as proximities (and two earlier images), in training and in the
    # evaluations (the observation the policy is trained on); a --task-set of one's own replaces it.
    import json

    import numpy as np

    from kestrel.train import main
    from kestrel.vector_env import make_vec

    s = main(["Kestrel-Navigation-v0", "--envs", "4", "--steps", "40", "--eval-every", "40", "--eval-episodes", "2",
              "--episode-len", "10", "--threads", "1", "--out", str(tmp_path), "--quiet", "--export", "0"])
    task_set = json.loads(s["task_set"])
    assert task_set["navigation"]["image_encoding"] == "proximity"
    envs = [make_vec("Kestrel-Navigation-v0", num_envs=3, seed=4, threads=1, sensors=json.loads(s["sensors"]), **t)
            for t in ({"task": task_set}, {})]
    near, ranged = (e.reset(seed=4)[0][:, 17:] for e in envs)
    # The default also appends two earlier images (image_history_frames 2), at a reset the first one.
    assert task_set["navigation"]["image_history_frames"] == 2 and near.shape[1] == 3 * ranged.shape[1] == 3 * 64
    np.testing.assert_allclose(near[:, :64], 1.0 / (1.0 + ranged * (10.0 / 0.5)), rtol=1e-6)
    np.testing.assert_array_equal(near[:, 64:128], near[:, :64])
    np.testing.assert_array_equal(near[:, 128:], near[:, :64])
    s = main(["Kestrel-Navigation-v0", "--envs", "4", "--steps", "40", "--eval-every", "40", "--eval-episodes", "2",
              "--episode-len", "10", "--threads", "1", "--out", str(tmp_path / "own"), "--quiet", "--export", "0",
              "--task-set", '{"navigation": {"pool_rows": 4}}'])
    assert "image_encoding" not in s["task_set"]


def test_sensors_refuse_what_is_not_a_list_of_entries(tmp_path):
    import pytest

    from kestrel.train import main

    with pytest.raises(SystemExit, match="--sensors: expected a JSON list"):
        main(["Kestrel-Navigation-v0", "--envs", "4", "--steps", "10", "--out", str(tmp_path), "--quiet", "--sensors",
              '{"name": "vl53l5cx"}'])


def test_rnn_policy_trains_and_its_evaluation_copy_matches_the_model(tmp_path):
    # --rnn gru:16: rsl-rl-lib's RNNModel as actor and critic. The evaluation's policy (a copy with
    # its own hidden state, deciding every action-repeat env-steps) gives the model's own
    # deterministic actions step after step, and leaves the training rollout's hidden state alone.
    import argparse

    import pytest
    import torch
    from tensordict import TensorDict

    from kestrel.train import Learner, main
    from kestrel.vector_env import make_vec

    s = main(["Kestrel-Navigation-v0", "--envs", "8", "--steps", "960", "--eval-every", "960", "--eval-episodes", "4",
              "--episode-len", "30", "--threads", "1", "--out", str(tmp_path), "--quiet", "--rnn", "gru:16"])
    assert s["rnn"] == ["gru", 16] and s["export"] is None and s["env_steps"] >= 960

    env = make_vec("Kestrel-Navigation-v0", num_envs=6, seed=3, threads=1)
    args = argparse.Namespace(seed=0, torch_threads=1, learner="rsl_rl", obs_norm=1, squash=1, reward_scale=0.02,
                              action_repeat=5, shaping=0.0, gamma=0.98, rollout=4, hidden=[16, 16], init_std=1.0,
                              epochs=1, minibatches=1, lam=0.95, entropy=0.0, lr=1e-3, rnn=("gru", 8), resume=None)
    learner = Learner(args, env)
    learner.train(6 * 4 * 5)
    model = learner.runner.alg.get_policy()
    before = model.get_hidden_state().clone()
    act = learner.policy()
    assert act.hold == 5
    obs, _ = env.reset(seed=3)
    model_state = model.get_hidden_state()
    model.reset()
    for _ in range(4):
        a = act(obs)
        with torch.inference_mode():
            y = model(TensorDict({"policy": torch.from_numpy(np.array(obs))}, batch_size=[obs.shape[0]]))
        np.testing.assert_array_equal(a, torch.tanh(y).numpy())
        obs, *_ = env.step(a)
    model.reset(hidden_state=model_state)
    assert torch.equal(model.get_hidden_state(), before)
    with pytest.raises(ValueError, match="recurrent policy"):
        learner.spec()
    with pytest.raises(SystemExit, match="--rnn: expected TYPE:SIZE"):
        main(["Kestrel-Navigation-v0", "--envs", "4", "--steps", "10", "--out", str(tmp_path), "--quiet", "--rnn", "rnn:8"])
    with pytest.raises(SystemExit, match="no export"):
        main(["Kestrel-Navigation-v0", "--envs", "4", "--steps", "10", "--out", str(tmp_path), "--quiet", "--rnn", "gru:8",
              "--export", "1"])


def test_critic_sensors_reach_the_critic_alone(tmp_path):
    # --critic-sensors: a 360-degree ring appended to the training robots' sensors whose rays, as
    # proximities, the critic alone reads (asymmetric actor-critic). The actor and its export keep
    # the policy's 17 + 3 x 64 inputs; the critic takes those plus the ring's 4 x 12 rays. A ring
    # without noise changes nothing the policy sees: the training envs' observations and rewards
    # equal those of envs without it, step by step. A ring that stores normalised ranges gives the
    # same proximities (its values read in metres).
    import json

    import onnx
    import pytest
    import torch

    from kestrel.adapters import RslRlVecEnv
    from kestrel.train import _TASK_DEFAULTS, main, privileged_proximities
    from kestrel.vector_env import make_vec

    ring = [{"name": "vl53l5cx", "height": 4, "width": 12, "max_range_m": 10, "every": 5, "horizontal_fov_deg_min": -165,
             "horizontal_fov_deg_max": 165, "vertical_fov_deg_min": -30, "vertical_fov_deg_max": 30,
             "enable_sensor_noise": False}]
    s = main(["Kestrel-Navigation-v0", "--envs", "8", "--steps", "960", "--eval-every", "960", "--eval-episodes", "4",
              "--episode-len", "30", "--threads", "1", "--out", str(tmp_path), "--quiet", "--export", "1",
              "--critic-sensors", json.dumps(ring)])
    assert s["critic_sensors"] == ring
    ck = torch.load(sorted((tmp_path / "checkpoints").glob("*.pt"))[-1], map_location="cpu", weights_only=False)
    assert ck["actor_state_dict"]["mlp.0.weight"].shape[1] == 17 + 3 * 64
    assert ck["critic_state_dict"]["mlp.0.weight"].shape[1] == 17 + 3 * 64 + 4 * 12
    dims = [d.dim_value for d in onnx.load(str(tmp_path / "policy.onnx")).graph.input[0].type.tensor_type.shape.dim]
    assert dims[-1] == 17 + 3 * 64

    d = _TASK_DEFAULTS["Kestrel-Navigation-v0"]
    task, sensors = json.loads(d["task_set"]), json.loads(d["sensors"])
    with_ring = make_vec("Kestrel-Navigation-v0", num_envs=6, seed=2, threads=1, sensors=sensors + ring, task=task)
    without = make_vec("Kestrel-Navigation-v0", num_envs=6, seed=2, threads=1, sensors=sensors, task=task)
    read = privileged_proximities(with_ring, 1)
    venv = RslRlVecEnv(with_ring, squash=True, action_repeat=5, privileged=read)
    td, _ = venv.reset()
    without.reset(seed=2)
    assert td["privileged"].shape == (6, 48)
    ranges = np.asarray(with_ring.task.simulator.range_images(1), np.float32).reshape(6, -1)
    hit = (ranges >= 0) & (ranges < 10)
    np.testing.assert_allclose(td["privileged"].numpy(), np.where(hit, 1 / (1 + ranges / 0.5), 0), rtol=1e-6)
    assert 0 < hit.mean() < 1  # the ring sees obstacles and open space
    normalised = make_vec("Kestrel-Navigation-v0", num_envs=6, seed=2, threads=1,
                          sensors=sensors + [{**ring[0], "normalize_range": True}], task=task)
    normalised.reset(seed=2)
    assert np.asarray(normalised.task.simulator.range_images(1)).max() <= 1.0
    np.testing.assert_allclose(privileged_proximities(normalised, 1)(), td["privileged"].numpy(), rtol=1e-5, atol=1e-7)
    rng = np.random.default_rng(1)
    for _ in range(60):
        a = rng.uniform(-2, 2, (6, 3)).astype(np.float32)
        td, rew, *_ = venv.step(torch.from_numpy(a))
        total, ended = np.zeros(6), np.zeros(6, bool)  # the adapter's sum over the held action
        for _ in range(5):
            o, r, te, tr, _ = without.step(torch.tanh(torch.from_numpy(a)).numpy())
            total += np.where(ended, 0.0, r)
            ended |= te | tr
        np.testing.assert_array_equal(td["policy"].numpy(), o)
        np.testing.assert_array_equal(rew.numpy(), total.astype(np.float32))
    with pytest.raises(SystemExit, match="--critic-sensors: expected a JSON list"):
        main(["Kestrel-Navigation-v0", "--envs", "4", "--steps", "10", "--out", str(tmp_path), "--quiet",
              "--critic-sensors", '{"name": "vl53l5cx"}'])
    with pytest.raises(SystemExit, match="--critic-sensors: takes --learner rsl_rl"):
        main(["Kestrel-Navigation-v0", "--envs", "4", "--steps", "10", "--out", str(tmp_path), "--quiet", "--learner", "sb3",
              "--critic-sensors", json.dumps(ring)])
    with pytest.raises(SystemExit, match="the policy's sensors must be given"):
        main(["Kestrel-PositionSetpoint-v0", "--envs", "4", "--steps", "10", "--out", str(tmp_path), "--quiet",
              "--critic-sensors", json.dumps(ring)])
