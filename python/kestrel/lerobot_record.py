"""kestrel.lerobot_record: teleoperated episodes as a LeRobot dataset (format v3.0, what lerobot
0.4.x's LeRobotDataset writes and reads), written with pyarrow alone, and their replay.

Why not lerobot's own writer: no lerobot release on the package index admits the project's pins
(0.4.x: torch<2.8 / <2.11, torchvision, datasets<5, av, draccus==0.10.0 ...; 0.3.2: gymnasium<1.0;
0.1.0: torchvision<0.18); see python/requirements.txt. The on-disk layout below was checked against
a dataset written by LeRobotDataset.create / add_frame / save_episode (lerobot 0.4.4), and the
tests read this writer's datasets back with LeRobotDataset where lerobot is importable.

    root/
      meta/info.json                      codebase_version "v3.0", fps, robot_type, totals, features
      meta/tasks.parquet                  task_index, indexed by the task string (pandas index)
      meta/stats.json                     min/max/mean/std/count per feature over the dataset
      meta/episodes/chunk-000/file-000.parquet   one row per episode: episode_index, tasks, length,
                                          data/chunk_index, data/file_index, dataset_from_index,
                                          dataset_to_index, meta/episodes/..., stats/<feature>/<stat>
      data/chunk-000/file-NNN.parquet     the frames: observation.state, action (fixed-size float32
                                          lists), observation.images.<cam> (struct<bytes, path>: a PNG),
                                          timestamp, frame_index, episode_index, index, task_index

One data file per episode (LeRobot rolls files by size; readers take every file under data/), so a
crash loses at most the episode being recorded. Images are stored as PNG inside the parquet, as
LeRobot does with use_videos=False (no ffmpeg/av needed).

    w = LeRobotWriter.create("out/ds", fps=30, cameras={"front": (480, 640), "wrist": (480, 640)})
    w.add_frame({"observation.state": q, "action": a, "observation.images.front": rgb, ...},
                task="Pick the red cube and place it into the box")
    w.save_episode(extra={"seed": 7})      # or w.clear_episode() to drop it
    w.finalize()
"""
from __future__ import annotations

import json
import math
import os
import pathlib
import struct
import zlib
from typing import Any, Mapping

import numpy as np

CODEBASE_VERSION = "v3.0"
CHUNKS_SIZE = 1000
SO101_STATE_NAMES = ["shoulder_pan.pos", "shoulder_lift.pos", "elbow_flex.pos", "wrist_flex.pos", "wrist_roll.pos",
                     "gripper.pos"]
DEFAULT_TASK = "Pick the red cube and place it into the box"
DATA_PATH = "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
EPISODES_PATH = "meta/episodes/chunk-000/file-000.parquet"
DEFAULT_FEATURES = {
    "timestamp": {"dtype": "float32", "shape": [1], "names": None},
    "frame_index": {"dtype": "int64", "shape": [1], "names": None},
    "episode_index": {"dtype": "int64", "shape": [1], "names": None},
    "index": {"dtype": "int64", "shape": [1], "names": None},
    "task_index": {"dtype": "int64", "shape": [1], "names": None},
}


def so101_features(cameras: Mapping[str, tuple[int, int]] = {"front": (480, 640), "wrist": (480, 640)}) -> dict:
    """LeRobot features of the SO-101 pick-and-place episodes: 6 joint states, 6 joint targets
    (rad) and one RGB image per camera."""
    f = {"observation.state": {"dtype": "float32", "shape": [6], "names": list(SO101_STATE_NAMES)},
         "action": {"dtype": "float32", "shape": [6], "names": list(SO101_STATE_NAMES)}}
    for cam, (h, w) in cameras.items():
        f[f"observation.images.{cam}"] = {"dtype": "image", "shape": [int(h), int(w), 3],
                                          "names": ["height", "width", "channels"]}
    return f


def encode_png(rgb: np.ndarray) -> bytes:
    """An 8-bit RGB PNG of an (h, w, 3) uint8 array (zlib only)."""
    a = np.ascontiguousarray(rgb, dtype=np.uint8)
    if a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"an image must be (height, width, 3) uint8, got shape {a.shape}")
    h, w, _ = a.shape
    raw = b"".join(b"\x00" + a[y].tobytes() for y in range(h))  # filter type 0 per row

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


def _hf_feature(ft: dict) -> dict:
    """The Hugging Face `datasets` feature (the parquet schema's 'huggingface' metadata)."""
    if ft["dtype"] == "image":
        return {"_type": "Image"}
    if list(ft["shape"]) == [1]:
        return {"dtype": ft["dtype"], "_type": "Value"}
    return {"feature": {"dtype": ft["dtype"], "_type": "Value"}, "length": int(ft["shape"][0]), "_type": "List"}


def _stats(values: np.ndarray, image: bool = False) -> dict:
    if image:  # per channel over the frames, in [0, 1], shaped (3, 1, 1) as LeRobot does
        # From each channel's histogram of the uint8 values (exact, and ~50x cheaper than float64
        # reductions over a 640 x 480 episode, which took seconds per camera).
        flat = np.ascontiguousarray(values, dtype=np.uint8).reshape(-1, values.shape[-1])
        levels = np.arange(256, dtype=np.float64) / 255.0
        st = {k: [] for k in ("min", "max", "mean", "std")}
        for c in range(flat.shape[1]):
            hist = np.bincount(flat[:, c], minlength=256).astype(np.float64)
            nz = np.nonzero(hist)[0]
            n = hist.sum()
            mean = float(hist @ levels) / n
            st["min"].append(levels[nz[0]]); st["max"].append(levels[nz[-1]]); st["mean"].append(mean)
            st["std"].append(math.sqrt(max(0.0, float(hist @ (levels - mean) ** 2) / n)))
        out = {k: np.asarray(v, dtype=np.float64).reshape(-1, 1, 1) for k, v in st.items()}
    else:
        v = values.reshape(len(values), -1)
        out = {k: getattr(v.astype(np.float64) if k in ("mean", "std") else v, k)(axis=0)
               for k in ("min", "max", "mean", "std")}
    out["count"] = np.array([len(values)], dtype=np.int64)
    return out


def _merge_stats(a: dict | None, b: dict) -> dict:
    if a is None:
        return b
    out = {}
    for key in b:
        sa, sb = a[key], b[key]
        na, nb = float(sa["count"][0]), float(sb["count"][0])
        n = na + nb
        mean = (na * np.asarray(sa["mean"]) + nb * np.asarray(sb["mean"])) / n
        var = (na * (np.asarray(sa["std"]) ** 2 + (np.asarray(sa["mean"]) - mean) ** 2)
               + nb * (np.asarray(sb["std"]) ** 2 + (np.asarray(sb["mean"]) - mean) ** 2)) / n
        out[key] = {"min": np.minimum(sa["min"], sb["min"]), "max": np.maximum(sa["max"], sb["max"]),
                    "mean": mean, "std": np.sqrt(var), "count": np.array([int(n)], dtype=np.int64)}
    return out


def _jsonable(x):
    if isinstance(x, dict):
        return {k: _jsonable(v) for k, v in x.items()}
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    return x


class LeRobotWriter:
    """Writes episodes in LeRobot's v3.0 layout (see the module docstring)."""

    def __init__(self, root, info: dict, tasks: dict[str, int], episodes: list[dict], stats: dict | None):
        self.root = pathlib.Path(root)
        self.info = info
        self.features = info["features"]
        self.fps = info["fps"]
        self.tasks = tasks
        self.episodes = episodes
        self.stats = stats
        self._buffer: list[dict] = []
        self._buffer_tasks: list[str] = []

    @classmethod
    def create(cls, root, fps: int = 30, features: dict | None = None, cameras=None, robot_type: str = "so101_follower",
               repo_id: str = "kestrel/so101_pick_place") -> "LeRobotWriter":
        """A new dataset at root (which must not exist or be empty). features: LeRobot's features
        dict (default: so101_features(cameras))."""
        import pyarrow  # noqa: F401  (fail here, not at the first episode)

        root = pathlib.Path(root)
        if root.exists() and any(root.iterdir()):
            raise FileExistsError(f"{root}: not empty; a LeRobot dataset is created in a new directory")
        if features is None:
            features = so101_features(cameras) if cameras is not None else so101_features()
        features = {**{k: dict(v, shape=list(v["shape"])) for k, v in features.items()}, **DEFAULT_FEATURES}
        info = {"codebase_version": CODEBASE_VERSION, "robot_type": robot_type, "total_episodes": 0, "total_frames": 0,
                "total_tasks": 0, "chunks_size": CHUNKS_SIZE, "data_files_size_in_mb": 100,
                "video_files_size_in_mb": 200, "fps": int(fps), "splits": {}, "data_path": DATA_PATH,
                "video_path": None, "features": features, "kestrel": {"repo_id": repo_id}}
        (root / "meta").mkdir(parents=True, exist_ok=True)
        w = cls(root, info, {}, [], None)
        w._write_info()
        return w

    # -- frames
    def add_frame(self, frame: Mapping[str, Any], task: str = DEFAULT_TASK) -> None:
        """One frame: every non-default feature (arrays of the feature's shape; images (h, w, 3)
        uint8); timestamp is frame_index / fps unless given."""
        row = {}
        for key, ft in self.features.items():
            if key in DEFAULT_FEATURES:
                continue
            if key not in frame:
                raise KeyError(f"frame has no {key!r} (features: {', '.join(self.features)})")
            v = np.asarray(frame[key])
            want = tuple(ft["shape"])
            if v.shape != want:
                raise ValueError(f"{key}: shape {v.shape}, the dataset's feature is {want}")
            row[key] = v.astype(np.uint8 if ft["dtype"] == "image" else ft["dtype"], copy=True)
        if "timestamp" in frame:
            row["timestamp"] = np.float32(frame["timestamp"])
        self._buffer.append(row)
        self._buffer_tasks.append(str(task))

    @property
    def episode_frames(self) -> int:
        return len(self._buffer)

    def clear_episode(self) -> None:
        self._buffer.clear()
        self._buffer_tasks.clear()

    def save_episode(self, extra: Mapping[str, Any] | None = None) -> int:
        """Writes the buffered frames as the next episode; its index. extra: JSON-able values stored
        in the episode's row of meta/episodes as kestrel/<key> (e.g. the reset seed for replay)."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        n = len(self._buffer)
        if n == 0:
            raise ValueError("save_episode: no frames added")
        ep = len(self.episodes)
        start = self.info["total_frames"]
        for t in self._buffer_tasks:
            if t not in self.tasks:
                self.tasks[t] = len(self.tasks)
        cols: dict[str, np.ndarray] = {}
        for key, ft in self.features.items():
            if key in DEFAULT_FEATURES or ft["dtype"] == "image":
                continue
            cols[key] = np.stack([r[key] for r in self._buffer])
        cols["timestamp"] = np.array([r.get("timestamp", np.float32(i / self.fps)) for i, r in enumerate(self._buffer)],
                                     dtype=np.float32)
        cols["frame_index"] = np.arange(n, dtype=np.int64)
        cols["episode_index"] = np.full(n, ep, dtype=np.int64)
        cols["index"] = np.arange(start, start + n, dtype=np.int64)
        cols["task_index"] = np.array([self.tasks[t] for t in self._buffer_tasks], dtype=np.int64)

        arrays, fields, ep_stats = [], [], {}
        for key, ft in self.features.items():
            if ft["dtype"] == "image":
                imgs = np.stack([r[key] for r in self._buffer])
                arr = pa.array([{"bytes": encode_png(im), "path": f"frame-{i:06d}.png"} for i, im in enumerate(imgs)],
                               type=pa.struct([("bytes", pa.binary()), ("path", pa.string())]))
                ep_stats[key] = _stats(imgs, image=True)
            else:
                v = cols[key]
                if list(ft["shape"]) == [1]:
                    arr = pa.array(v)
                else:
                    flat = pa.array(v.reshape(-1))
                    arr = pa.FixedSizeListArray.from_arrays(flat, int(ft["shape"][0]))
                ep_stats[key] = _stats(v)
            arrays.append(arr)
            fields.append(pa.field(key, arr.type))
        hf = {"info": {"features": {k: _hf_feature(ft) for k, ft in self.features.items()}}}
        schema = pa.schema(fields, metadata={b"huggingface": json.dumps(hf).encode()})
        chunk, file = divmod(ep, CHUNKS_SIZE)
        path = self.root / DATA_PATH.format(chunk_index=chunk, file_index=file)
        path.parent.mkdir(parents=True, exist_ok=True)
        pq.write_table(pa.Table.from_arrays(arrays, schema=schema), path)

        row = {"episode_index": ep, "tasks": sorted(set(self._buffer_tasks), key=self.tasks.get), "length": n,
               "data/chunk_index": chunk, "data/file_index": file, "dataset_from_index": start,
               "dataset_to_index": start + n, "meta/episodes/chunk_index": 0, "meta/episodes/file_index": 0}
        for k, v in (extra or {}).items():
            row[f"kestrel/{k}"] = v
        for fk, st in ep_stats.items():
            for sk, sv in st.items():
                row[f"stats/{fk}/{sk}"] = np.asarray(sv).tolist()
        self.episodes.append(row)
        self.stats = _merge_stats(self.stats, ep_stats)
        self.info["total_episodes"] = ep + 1
        self.info["total_frames"] = start + n
        self.info["total_tasks"] = len(self.tasks)
        self.info["splits"] = {"train": f"0:{ep + 1}"}
        self._write_meta()
        self.clear_episode()
        return ep

    def finalize(self) -> None:
        """Nothing is held open (every episode is complete on disk); kept for LeRobotDataset's API."""
        self.clear_episode()

    # -- metadata
    def _write_info(self):
        with open(self.root / "meta" / "info.json", "w") as f:
            json.dump(self.info, f, indent=4)

    def _write_meta(self):
        import pyarrow as pa
        import pyarrow.parquet as pq

        self._write_info()
        with open(self.root / "meta" / "stats.json", "w") as f:
            json.dump(_jsonable(self.stats), f, indent=4)
        names = list(self.tasks)
        pandas_meta = {"index_columns": ["__index_level_0__"],
                       "column_indexes": [{"name": None, "field_name": None, "pandas_type": "unicode",
                                           "numpy_type": "object", "metadata": {"encoding": "UTF-8"}}],
                       "columns": [{"name": "task_index", "field_name": "task_index", "pandas_type": "int64",
                                    "numpy_type": "int64", "metadata": None},
                                   {"name": None, "field_name": "__index_level_0__", "pandas_type": "unicode",
                                    "numpy_type": "object", "metadata": None}],
                       "attributes": {}, "creator": {"library": "pyarrow", "version": pa.__version__}}
        tasks = pa.table({"task_index": pa.array([self.tasks[t] for t in names], pa.int64()),
                          "__index_level_0__": pa.array(names, pa.string())})
        tasks = tasks.replace_schema_metadata({b"pandas": json.dumps(pandas_meta).encode()})
        pq.write_table(tasks, self.root / "meta" / "tasks.parquet")
        p = self.root / EPISODES_PATH
        p.parent.mkdir(parents=True, exist_ok=True)
        pq.write_table(pa.Table.from_pylist(self.episodes), p)


# -- reading back --------------------------------------------------------------------------------

class LeRobotEpisodes:
    """A LeRobot v3.0 dataset read with pyarrow: info, tasks, episodes and each episode's columns."""

    def __init__(self, root):
        import pyarrow.parquet as pq

        self.root = pathlib.Path(root)
        with open(self.root / "meta" / "info.json") as f:
            self.info = json.load(f)
        if self.info.get("codebase_version") != CODEBASE_VERSION:
            raise ValueError(f"{self.root}: codebase_version {self.info.get('codebase_version')!r}, expected {CODEBASE_VERSION}")
        self.fps = self.info["fps"]
        t = pq.read_table(self.root / "meta" / "tasks.parquet").to_pydict()
        index_col = "__index_level_0__" if "__index_level_0__" in t else "task"
        self.tasks = dict(zip(t["task_index"], t[index_col]))
        ep_files = sorted((self.root / "meta" / "episodes").glob("*/*.parquet"))
        self.episodes = [r for f in ep_files for r in pq.read_table(f).to_pylist()]

    def __len__(self):
        return len(self.episodes)

    def episode(self, index: int) -> dict[str, np.ndarray]:
        """Column name -> array (n, ...) of one episode; images decoded to (n, h, w, 3) uint8 when
        Pillow is present, else left as PNG bytes."""
        import pyarrow.parquet as pq

        ep = self.episodes[index]
        path = self.root / self.info["data_path"].format(chunk_index=ep["data/chunk_index"], file_index=ep["data/file_index"])
        table = pq.read_table(path)
        lo = ep["dataset_from_index"]
        idx = np.asarray(table.column("index").to_numpy())
        rows = np.nonzero((idx >= lo) & (idx < ep["dataset_to_index"]))[0]
        table = table.take(rows)
        out = {}
        for key, ft in self.info["features"].items():
            col = table.column(key)
            if ft["dtype"] == "image":
                out[key] = _decode_images([v["bytes"] for v in col.to_pylist()])
            elif list(ft["shape"]) == [1]:
                out[key] = col.to_numpy()
            else:
                flat = col.combine_chunks().flatten().to_numpy()
                out[key] = flat.reshape(len(table), *ft["shape"])
        out["task"] = [self.tasks[i] for i in out["task_index"]]
        return out

    def actions(self, index: int) -> np.ndarray:
        return self.episode(index)["action"]


def _decode_images(pngs):
    try:
        import io

        from PIL import Image
    except ImportError:
        return pngs
    return np.stack([np.asarray(Image.open(io.BytesIO(b)).convert("RGB")) for b in pngs])


def replay(env, root, episode_index: int, seed: int | None = None, env_index: int = 0):
    """Steps `env` (the SO-101 env in the joint_position action mode) with a recorded episode's
    actions from a reset with the episode's seed (kestrel/seed in meta/episodes, or `seed`); returns
    the joint states observed before each step, (n, 6) float32: equal, bit for bit, to the episode's
    observation.state when the env is deterministic. kestrel.so101_teleop.replay_episode also
    compares the cube's poses."""
    from .so101_teleop import env_mode, joint_state, reset_episode

    ds = LeRobotEpisodes(root)
    ep = ds.episodes[episode_index]
    if seed is None:
        seed = ep.get("kestrel/seed")
    actions = ds.actions(episode_index)
    if env_mode(env) != "joint":
        raise ValueError("replay: the env must be in the joint_position action mode")
    obs = reset_episode(env, seed)
    batch = np.zeros((env.num_envs, 6), np.float32)
    states = []
    for a in actions:
        states.append(joint_state(obs, env_index))
        batch[:] = np.asarray(a, np.float32)[None]
        obs = env.step(batch)[0]
    return np.stack(states).astype(np.float32)
