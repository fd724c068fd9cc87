"""kestrel.lerobot_record (LeRobot v3.0 datasets written with pyarrow, read back, replayed) and
kestrel.so101_teleop (LeIsaac's keyboard map, the teleop loop) against a tiny deterministic fake of
the SO-101 pick-and-place VectorEnv (the real env is not needed)."""
import json

import numpy as np
import pytest

from kestrel_pure import load

pytest.importorskip("pyarrow")
rec = load("lerobot_record")
tel = load("so101_teleop")
TASK = "Pick the red cube and place it into the box"
H, W = 12, 16


class FakeArmEnv:
    """num_envs arms whose joints move a fixed fraction towards their targets each step (float32
    arithmetic: deterministic), with two cameras rendering the joint state; 'ee' mode resolves a
    fake IK (targets = joints + a fixed map of the deltas) and reports info['joint_targets']."""

    def __init__(self, num_envs=2, horizon=1000):
        self.num_envs, self.horizon = num_envs, horizon
        self.action_mode = "joint"
        self.unwrapped = self

    def set_action_mode(self, mode):
        assert mode in ("joint", "ee")
        self.action_mode = mode

    def _obs(self):
        img = np.zeros((self.num_envs, H, W, 3), np.uint8)
        img[..., 0] = (np.abs(self.q[:, :1, None]) * 100 % 255).astype(np.uint8)
        img[:, :, : self.t % W, 1] = 200
        return {"joint_pos": self.q.copy(), "images": {"front": img, "wrist": 255 - img}}

    def reset(self, seed=None):
        rng = np.random.default_rng(seed)
        self.q = rng.uniform(-0.5, 0.5, (self.num_envs, 6)).astype(np.float32)
        self.t = 0
        return self._obs(), {}

    def step(self, action):
        action = np.asarray(action)
        info = {}
        if self.action_mode == "ee":
            m = np.float32(0.5) * np.ones((5, 6), np.float32)
            target = (self.q + action.astype(np.float32) @ m).astype(np.float32)
            target[:, 5] = action[:, 4]
            info["joint_targets"] = target.copy()
        else:
            assert action.shape == (self.num_envs, 6) and action.dtype == np.float32
            target = action
        self.q = (self.q + np.float32(0.3) * (target - self.q)).astype(np.float32)
        self.t += 1
        done = np.full(self.num_envs, self.t >= self.horizon)
        return self._obs(), np.zeros(self.num_envs), np.zeros(self.num_envs, bool), done, info


class ScriptedLeader:
    """A joint-mode device: sinusoidal joint targets."""
    mode = "joint"

    def __init__(self):
        self.k = 0

    def action(self, obs):
        self.k += 1
        return np.sin(np.arange(6) + 0.1 * self.k).astype(np.float32)


def test_keyboard_map():
    kb = tel.KeyboardTeleop(gripper_target=0.5)
    assert kb.action().tolist() == [0, 0, 0, 0, 0.5]
    kb.press("w"); kb.press("Q"); kb.press("J")
    a = kb.action()
    assert a[:4] == pytest.approx([0.01, 0, 0.01, 0.15])
    kb.press("S")  # W and S cancel
    assert kb.action()[0] == 0
    kb.release("W"); kb.release("S"); kb.release("Q"); kb.release("J")
    kb.press("D"); kb.press("E"); kb.press("L")
    assert kb.action()[:4] == pytest.approx([0, -0.01, -0.01, -0.15])
    kb.release("D"); kb.release("E"); kb.release("L")
    kb.press("O")
    assert kb.action()[4] == pytest.approx(0.3) and kb.action()[4] == pytest.approx(0.1)
    for _ in range(10):
        g = kb.action()[4]
    assert g == pytest.approx(np.radians(-10))  # clipped at the gripper's range
    kb.release("O"); kb.press("U")
    assert kb.action()[4] == pytest.approx(np.radians(-10) + 0.2)
    kb.press("I")  # pitch: no axis in the ee mode
    assert kb.action()[:4].tolist() == [0, 0, 0, 0]
    assert not kb.started
    kb.press("B"); assert kb.started
    kb.press("N"); assert not kb.started and kb.take_reset() == "success" and kb.take_reset() is None
    kb.press("R"); assert kb.take_reset() == "failure"


def write_two_episodes(root):
    w = rec.LeRobotWriter.create(root, fps=30, cameras={"front": (H, W), "wrist": (H, W)})
    rng = np.random.default_rng(0)
    data = []
    for ep, n in enumerate((5, 7)):
        frames = []
        for i in range(n):
            f = {"observation.state": rng.standard_normal(6).astype(np.float32),
                 "action": rng.standard_normal(6).astype(np.float32),
                 "observation.images.front": rng.integers(0, 256, (H, W, 3), dtype=np.uint8),
                 "observation.images.wrist": rng.integers(0, 256, (H, W, 3), dtype=np.uint8)}
            w.add_frame(f, task=TASK)
            frames.append(f)
        assert w.save_episode(extra={"seed": 100 + ep}) == ep
        data.append(frames)
    w.finalize()
    return data


def test_dataset_round_trip(tmp_path):
    root = tmp_path / "ds"
    data = write_two_episodes(root)
    info = json.loads((root / "meta" / "info.json").read_text())
    assert info["codebase_version"] == "v3.0" and info["fps"] == 30
    assert (info["total_episodes"], info["total_frames"], info["total_tasks"]) == (2, 12, 1)
    assert info["features"]["observation.images.front"]["shape"] == [H, W, 3]
    assert sorted(p.relative_to(root).as_posix() for p in root.rglob("*") if p.is_file()) == [
        "data/chunk-000/file-000.parquet", "data/chunk-000/file-001.parquet", "meta/episodes/chunk-000/file-000.parquet",
        "meta/info.json", "meta/stats.json", "meta/tasks.parquet"]
    ds = rec.LeRobotEpisodes(root)
    assert len(ds) == 2 and ds.fps == 30 and ds.tasks == {0: TASK}
    for ep, frames in enumerate(data):
        e = ds.episode(ep)
        n = len(frames)
        assert e["observation.state"].shape == (n, 6) and e["observation.state"].dtype == np.float32
        assert e["frame_index"].tolist() == list(range(n))
        assert e["episode_index"].tolist() == [ep] * n
        assert e["index"].tolist() == list(range(5 * ep, 5 * ep + n))
        assert e["timestamp"] == pytest.approx(np.arange(n) / 30)
        assert e["task"] == [TASK] * n
        want = np.stack([f["action"] for f in frames])
        assert e["action"].tobytes() == want.tobytes()  # bit for bit
        assert e["observation.state"].tobytes() == np.stack([f["observation.state"] for f in frames]).tobytes()
        if not isinstance(e["observation.images.front"], list):  # Pillow decodes the PNGs
            assert np.array_equal(e["observation.images.front"], np.stack([f["observation.images.front"] for f in frames]))
        assert ds.episodes[ep]["kestrel/seed"] == 100 + ep
        assert ds.episodes[ep]["tasks"] == [TASK]
    stats = json.loads((root / "meta" / "stats.json").read_text())
    assert stats["action"]["count"] == [12]
    allact = np.concatenate([np.stack([f["action"] for f in fr]) for fr in data])
    assert stats["action"]["mean"] == pytest.approx(allact.astype(np.float64).mean(0))
    assert stats["action"]["std"] == pytest.approx(allact.astype(np.float64).std(0))


def test_dataset_refusals(tmp_path):
    w = rec.LeRobotWriter.create(tmp_path / "a", cameras={"front": (H, W)})
    with pytest.raises(KeyError, match="observation.images.front"):
        w.add_frame({"observation.state": np.zeros(6), "action": np.zeros(6)})
    with pytest.raises(ValueError, match=r"action: shape \(5,\)"):
        w.add_frame({"observation.state": np.zeros(6), "action": np.zeros(5),
                     "observation.images.front": np.zeros((H, W, 3), np.uint8)})
    with pytest.raises(ValueError, match="no frames"):
        w.save_episode()
    (tmp_path / "b").mkdir(); (tmp_path / "b" / "x").write_text("")
    with pytest.raises(FileExistsError):
        rec.LeRobotWriter.create(tmp_path / "b")


def test_teleop_records_and_replay_is_bit_exact(tmp_path):
    env = FakeArmEnv(num_envs=2, horizon=9)
    w = rec.LeRobotWriter.create(tmp_path / "ds", cameras={"front": (H, W), "wrist": (H, W)})
    stats = tel.teleop_loop(env, ScriptedLeader(), steps=20, recorder=w, seed=3)
    assert stats["saved"] == 2 and stats["frames"] == 20  # episodes of 9 + 9 frames (+2 unsaved)
    ds = rec.LeRobotEpisodes(tmp_path / "ds")
    assert [e["length"] for e in ds.episodes] == [9, 9]
    assert [e["kestrel/seed"] for e in ds.episodes] == [3, 4]
    for ep in range(2):
        states = rec.replay(FakeArmEnv(num_envs=2, horizon=9), tmp_path / "ds", ep)
        assert states.tobytes() == ds.episode(ep)["observation.state"].tobytes()


def test_keyboard_teleop_in_ee_mode(tmp_path):
    env = FakeArmEnv(num_envs=1, horizon=1000)
    kb = tel.KeyboardTeleop()
    w = rec.LeRobotWriter.create(tmp_path / "ds", cameras={"front": (H, W), "wrist": (H, W)})
    assert tel.teleop_loop(env, kb, steps=3, recorder=w, seed=0)["frames"] == 0  # not started: no frames
    assert env.action_mode == "ee"
    kb.press("B"); kb.press("W"); kb.press("O")
    kb.callbacks["N"] = lambda: None
    s = tel.teleop_loop(env, kb, steps=4, recorder=w, seed=0)
    assert s["frames"] == 4
    assert w.episode_frames == 4  # held across calls until a reset
    kb.press("N")  # success: the episode is saved, the env reset
    s = tel.teleop_loop(env, kb, steps=1, recorder=w, seed=0)
    assert s["saved"] == 1 and w.episode_frames == 0 and not kb.started
    ds = rec.LeRobotEpisodes(tmp_path / "ds")
    e = ds.episode(0)
    assert e["action"].shape == (4, 6)  # the joint targets the env's IK resolved


def test_lerobot_reads_the_dataset(tmp_path):
    """LeRobot's own reader, where lerobot is importable (not in the project's venv: see
    python/requirements.txt)."""
    ld = pytest.importorskip("lerobot.datasets.lerobot_dataset")
    root = tmp_path / "ds"
    data = write_two_episodes(root)
    ds = ld.LeRobotDataset("kestrel/test", root=root)
    assert ds.num_episodes == 2 and ds.num_frames == 12 and ds.fps == 30
    item = ds[6]  # episode 1, frame 1
    assert item["task"] == TASK and int(item["frame_index"]) == 1 and int(item["episode_index"]) == 1
    assert item["action"].numpy().tobytes() == data[1][1]["action"].tobytes()
    img = (item["observation.images.front"].numpy().transpose(1, 2, 0) * 255).round().astype(np.uint8)
    assert np.array_equal(img, data[1][1]["observation.images.front"])
