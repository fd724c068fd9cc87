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


class _Box:
    def __init__(self, n):
        self.shape = (n,)


class _FakeTask:
    def __init__(self, env, seed):
        self.env, self.seed = env, seed

    def render_camera(self, i, cam, width=640, height=480):
        img = np.zeros((height, width, 3), np.uint8)
        img[..., 0] = np.uint8(abs(float(self.env.q[i, 0])) * 100 % 255)
        img[:, : self.env.t % width, 1] = 200
        return (img if cam == "front" else 255 - img), None, None

    def pick_place_state(self, i):
        return {"cube_pos_w": [0.2, 0.0, float(self.env.q[i, 1])], "cube_quat_xyzw": [0, 0, 0, 1],
                "tcp_pos_w": [0, 0, 0], "grip_force_N": 0.0, "cube_in_box": False}


class FakeArmEnv:
    """The SO-101 env's interface (kestrel.so101_teleop): (n, 31) observations with the joints in
    0:6 and the applied joint targets in 12:18, the action mode fixed at construction ("joint": 6
    targets, "ee": 5 deltas through a fake IK), a task with render_camera / pick_place_state, and
    reset(seed) rebuilding only on a new seed. Joints move a fixed fraction towards their targets
    each step (float32 arithmetic: deterministic); episodes are truncated after `horizon` steps."""

    def __init__(self, num_envs=2, horizon=1000, mode="joint", seed=0):
        self.num_envs, self.horizon, self.mode = num_envs, horizon, mode
        self.single_action_space = _Box(5 if mode == "ee" else 6)
        self._build(seed)

    def _build(self, seed):
        self.task = _FakeTask(self, seed)
        self.rng = np.random.default_rng(seed)
        self._start()

    def _start(self):
        self.q = self.rng.uniform(-0.5, 0.5, (self.num_envs, 6)).astype(np.float32)
        self.targets = self.q.copy()
        self.t = 0

    def _obs(self):
        o = np.zeros((self.num_envs, 31), np.float32)
        o[:, 0:6], o[:, 12:18] = self.q, self.targets
        return o

    def reset(self, seed=None):
        if seed is not None and seed != self.task.seed:
            self._build(seed)
        else:
            self._start()
        return self._obs(), {}

    def step(self, action):
        action = np.asarray(action, np.float32)
        if self.mode == "ee":
            assert action.shape == (self.num_envs, 5)
            target = (self.q + action @ (np.float32(0.5) * np.ones((5, 6), np.float32))).astype(np.float32)
            target[:, 5] = action[:, 4]
        else:
            assert action.shape == (self.num_envs, 6) and action.dtype == np.float32
            target = action.copy()
        self.targets = target
        self.q = (self.q + np.float32(0.3) * (target - self.q)).astype(np.float32)
        self.t += 1
        done = np.full(self.num_envs, self.t >= self.horizon)
        obs, info = self._obs(), {}
        if done.any():
            info = {"final_obs": obs.copy(), "_final_obs": done.copy()}
            self._start()
            obs = self._obs()
        return obs, np.zeros(self.num_envs), np.zeros(self.num_envs, bool), done, info


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
    env = FakeArmEnv(num_envs=2, horizon=9, mode="joint")
    w = rec.LeRobotWriter.create(tmp_path / "ds", cameras={"front": (H, W), "wrist": (H, W)})
    # Episodes that end by the time limit (truncated) are not demonstrations: a success reset (N) saves.
    dev = ScriptedLeader()
    stats = tel.teleop_loop(env, dev, steps=20, recorder=w, seed=3)
    assert stats["saved"] == 0 and stats["discarded"] == 2 and stats["timeouts"] == 2 and stats["frames"] == 20

    class Saving(ScriptedLeader):
        def __init__(self):
            super().__init__()
            self.reset_request = None

        def take_reset(self):
            r = "success" if self.k and self.k % 7 == 0 and self.reset_request != self.k else None
            if r:
                self.reset_request = self.k
            return r

    assert w.episode_frames == 2  # the third episode's frames, until a reset
    w.clear_episode()
    stats = tel.teleop_loop(env, Saving(), steps=16, recorder=w, seed=3)
    assert stats["saved"] == 2 and stats["frames"] == 14
    ds = rec.LeRobotEpisodes(tmp_path / "ds")
    assert [e["length"] for e in ds.episodes] == [7, 7]
    assert [e["kestrel/seed"] for e in ds.episodes] == [3, 4]
    for ep in range(2):
        states = rec.replay(FakeArmEnv(num_envs=2, horizon=9, mode="joint"), tmp_path / "ds", ep)
        assert states.tobytes() == ds.episode(ep)["observation.state"].tobytes()


def test_keyboard_teleop_in_ee_mode(tmp_path):
    env = FakeArmEnv(num_envs=1, horizon=1000, mode="ee")
    kb = tel.KeyboardTeleop()
    w = rec.LeRobotWriter.create(tmp_path / "ds", cameras={"front": (H, W), "wrist": (H, W)})
    s = tel.teleop_loop(env, kb, steps=3, recorder=w, seed=0)
    assert s["frames"] == 0 and s["steps"] == 0  # not started: no frames, the env is not stepped
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
    assert np.all(np.diff(e["action"][:, 5]) <= 0) and e["action"][-1, 5] == pytest.approx(np.radians(-10))  # O closes
    with pytest.raises(ValueError, match="'joint'-mode device on an env in the 'ee' action mode"):
        tel.teleop_loop(env, ScriptedLeader(), steps=1)


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
