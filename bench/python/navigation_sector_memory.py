"""A prototype behind issue 11's navigation runs: `kestrel train` with every navigation_task
environment (training and evaluation) wrapped so that its observation ends with a remembered
360-degree obstacle ring around the vehicle, built from its own 90-degree range image.

Why: on hp2's checkpoint (bench/results/python/navigation_zones_rsl_rl.pt), 103 of 512 level-10
episodes of seed 1000004 crash, and in 72 of them the nearest zone of the last image before the
crash lies in the image's first or last column: the vehicle clips an obstacle it is passing, which
is leaving its view sideways. A feed-forward policy forgets it once it has left the view (the task's
history holds 0.2 s). PX4's collision prevention keeps such a memory for forward-looking sensors:
an obstacle-distance histogram around the vehicle, filled from the sensor's view as it turns.

What the wrapper adds: every image's nearest return within 3 m in each of the 8 zone columns
among the zones whose return lies within +-0.5 m of the vehicle's height, as a point in the world, kept for MEMORY_S seconds (a ring per
environment, emptied at the episode's start); after each env-step, the points within +-0.5 m of the
vehicle's height binned by bearing in the vehicle's yaw frame into SECTORS sectors, each sector the
proximity 1 / (1 + d / 0.5 m) of its nearest point at horizontal distance d (0: none).

    .venv/bin/python bench/python/navigation_sector_memory.py SECTORS MEMORY_S -- Kestrel-Navigation-v0 \\
        --eval-episodes 512 --threads 2 --final-eval-episodes 1024 --out runs/nav/sm --export 0
"""
import sys

import gymnasium as gym
import numpy as np

import kestrel.train as train

IMAGE0 = 17  # navigation_task's state part; the image cells (8 x 8 zones, row-major) follow it
ROWS = COLS = 8
SCALE_M = 0.5  # the task's proximity scale (Kestrel-Navigation-v0's task_set)
ENV_DT_S = 0.01


def _quat_rot(q):
    """Rotation matrices (n, 3, 3) of xyzw quaternions (n, 4)."""
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    R = np.empty((q.shape[0], 3, 3))
    R[:, 0, 0] = 1 - 2 * (y * y + z * z)
    R[:, 0, 1] = 2 * (x * y - w * z)
    R[:, 0, 2] = 2 * (x * z + w * y)
    R[:, 1, 0] = 2 * (x * y + w * z)
    R[:, 1, 1] = 1 - 2 * (x * x + z * z)
    R[:, 1, 2] = 2 * (y * z - w * x)
    R[:, 2, 0] = 2 * (x * z - w * y)
    R[:, 2, 1] = 2 * (y * z + w * x)
    R[:, 2, 2] = 1 - 2 * (x * x + y * y)
    return R


class SectorMemory:
    """A KestrelVectorEnv whose observations end with SECTORS remembered obstacle proximities."""

    def __init__(self, env, sectors: int, memory_s: float):
        self.env, self.sectors = env, sectors
        od = env.single_observation_space.shape[0]
        self.od = od
        n = env.num_envs
        self.slots = max(1, int(round(memory_s / (5 * ENV_DT_S))))  # images kept (one per 5 env-steps)
        self.pts = np.zeros((n, self.slots * COLS, 3))
        self.valid = np.zeros((n, self.slots * COLS), bool)
        self.head = np.zeros(n, np.int64)
        self.last = np.full((n, ROWS * COLS), -1.0, np.float32)
        self.out = np.zeros((n, od + sectors), np.float32)
        self.single_observation_space = gym.spaces.Box(-np.inf, np.inf, (od + sectors,), np.float32)
        self._dirs = None

    def __getattr__(self, name):
        return getattr(self.env, name)

    def _zone_dirs(self, sim):
        if self._dirs is None:
            d = np.asarray(sim.range_image_rays(0)["dirs_s"], np.float64)  # (H, W, 3), sensor frame
            h, w = d.shape[:2]
            z = d.reshape(ROWS, h // ROWS, COLS, w // COLS, 3).mean(axis=(1, 3))
            self._dirs = z / np.linalg.norm(z, axis=-1, keepdims=True)  # (8, 8, 3)
        return self._dirs

    def _update(self, obs, fresh):
        sim = self.env.task.simulator
        n = obs.shape[0]
        if fresh is not None and fresh.any():
            self.valid[fresh] = False
            self.head[fresh] = 0
            self.last[fresh] = -1.0
        zones = obs[:, IMAGE0:IMAGE0 + ROWS * COLS]
        new = np.any(zones != self.last, axis=1)  # a new image (rendered every 5 env-steps)
        pos = np.asarray(sim.base_pos_w, np.float64)[:n]
        R_wb = _quat_rot(np.asarray(sim.base_quat_xyzw, np.float64)[:n])
        if new.any():
            idx = np.nonzero(new)[0]
            self.last[idx] = zones[idx]
            mp, mq = sim.sensor_mounts(0)
            mp, R_bs = np.asarray(mp)[idx], _quat_rot(np.asarray(mq)[idx])
            # Every zone's return as a point in the world, then per column the nearest of those
            # within +-0.5 m of the vehicle's height (the floor and what lies above or below the
            # flight level are not what it clips when passing).
            prox = zones[idx].reshape(-1, ROWS * COLS).astype(np.float64)
            r = SCALE_M * (1.0 / np.maximum(prox, 1e-6) - 1.0)
            dirs = self._zone_dirs(sim).reshape(ROWS * COLS, 3)  # sensor frame
            p_b = mp[:, None, :] + np.einsum("mij,kj->mki", R_bs, dirs) * r[..., None]
            p_all = pos[idx, None, :] + np.einsum("mij,mkj->mki", R_wb[idx], p_b)
            level = (prox > 1.0 / (1.0 + 3.0 / SCALE_M)) & (np.abs(p_all[..., 2] - pos[idx, None, 2]) < 0.5)
            score = np.where(level, prox, -1.0).reshape(-1, ROWS, COLS)
            row = np.argmax(score, axis=1)  # (m, 8): each column's nearest zone at the flight level
            hit = np.take_along_axis(score, row[:, None, :], axis=1)[:, 0, :] > 0
            k = row * COLS + np.arange(COLS)[None, :]
            p_w = np.take_along_axis(p_all, k[..., None], axis=1)
            slot = self.head[idx] % self.slots
            cols = slot[:, None] * COLS + np.arange(COLS)[None, :]
            self.pts[idx[:, None], cols] = p_w
            self.valid[idx[:, None], cols] = hit
            self.head[idx] += 1
        rel = self.pts - pos[:, None, :]
        fwd = R_wb[:, :2, 0]
        fwd = fwd / np.maximum(np.linalg.norm(fwd, axis=1, keepdims=True), 1e-9)
        x = rel[..., 0] * fwd[:, None, 0] + rel[..., 1] * fwd[:, None, 1]
        y = -rel[..., 0] * fwd[:, None, 1] + rel[..., 1] * fwd[:, None, 0]
        d = np.hypot(x, y)
        ok = self.valid & (np.abs(rel[..., 2]) < 0.5)
        p = np.where(ok, 1.0 / (1.0 + d / SCALE_M), 0.0)
        sec = ((np.arctan2(y, x) + np.pi) * (self.sectors / (2 * np.pi))).astype(np.int64) % self.sectors
        self.out[:, :self.od] = obs
        for s in range(self.sectors):
            self.out[:, self.od + s] = np.max(np.where(sec == s, p, 0.0), axis=1)
        return self.out

    @property
    def current_observations(self):
        return self.out

    def reset(self, **kwargs):
        obs, info = self.env.reset(**kwargs)
        self._dirs = None
        return self._update(obs, np.ones(obs.shape[0], bool)), info

    def step(self, actions):
        obs, rewards, terminated, truncated, info = self.env.step(actions)
        return self._update(obs, terminated | truncated), rewards, terminated, truncated, info

    def close(self):
        self.env.close()


def main(argv: list[str]) -> None:
    sectors, memory_s = int(argv[1]), float(argv[2])
    if sectors < 1 or memory_s <= 0 or argv[3] != "--":
        raise SystemExit("usage: navigation_sector_memory.py SECTORS MEMORY_S -- <kestrel train arguments>")
    make_vec = train.make_vec

    def make_with_memory(*args, **kwargs):
        env = SectorMemory(make_vec(*args, **kwargs), sectors, memory_s)
        env.reset()
        return env

    train.make_vec = make_with_memory  # the training and the evaluation environments alike
    train.main(argv[4:])


if __name__ == "__main__":
    main(sys.argv)
