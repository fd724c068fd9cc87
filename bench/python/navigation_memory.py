"""The measurement behind run `ph3` of bench/results/python/navigation_sweep.csv: `kestrel train`
with every navigation_task environment (training and evaluation) wrapped so that its observation
carries, after the task's own, the image cells of LAG, 2 LAG, ... (K - 1) LAG env-steps before (a
memory of the last frames for a feed-forward policy). A new episode's history starts filled with
its first image. A prototype, in Python around the vector env: the task has no such observation
yet, and the export to the core's MLP does not know it.

    .venv/bin/python bench/python/navigation_memory.py K LAG -- Kestrel-Navigation-v0 \\
        --eval-episodes 512 --threads 2 --final-eval-episodes 1024 --out runs/nav/ph3 --export 0

(`ph3`: K 3, LAG 10, with the defaults of stop 37; 78.2 % success on the 1024 episodes.)
"""
import sys

import gymnasium as gym
import numpy as np

import kestrel.train as train

IMAGE0 = 17  # navigation_task's state part; the image cells follow it


class WithMemory:
    """A KestrelVectorEnv whose observations end with the image cells of earlier env-steps."""

    def __init__(self, env, frames: int, lag: int):
        self.env, self.frames, self.lag = env, frames, lag
        od = env.single_observation_space.shape[0]
        self.cells = od - IMAGE0
        self.span = lag * (frames - 1) + 1  # env-steps of history kept, the current one included
        self.ring = np.zeros((env.num_envs, self.span, self.cells), np.float32)
        self.t = 0
        self.out = np.zeros((env.num_envs, od + (frames - 1) * self.cells), np.float32)
        self.single_observation_space = gym.spaces.Box(-np.inf, np.inf, (self.out.shape[1],), np.float32)

    def __getattr__(self, name):
        return getattr(self.env, name)

    def _write(self, obs, new_episode):
        od = obs.shape[1]
        self.out[:, :od] = obs
        image = obs[:, IMAGE0:]
        if new_episode is None:  # a reset of every environment
            self.t = 0
            self.ring[:] = image[:, None, :]
        else:
            self.t += 1
            self.ring[:, self.t % self.span] = image
            self.ring[new_episode] = image[new_episode][:, None, :]
        for j in range(1, self.frames):
            self.out[:, od + (j - 1) * self.cells: od + j * self.cells] = self.ring[:, (self.t - j * self.lag) % self.span]
        return self.out

    @property
    def current_observations(self):
        return self.out

    def reset(self, **kwargs):
        obs, info = self.env.reset(**kwargs)
        return self._write(obs, None), info

    def step(self, actions):
        obs, rewards, terminated, truncated, info = self.env.step(actions)
        return self._write(obs, terminated | truncated), rewards, terminated, truncated, info

    def close(self):
        self.env.close()


def main(argv: list[str]) -> None:
    frames, lag = int(argv[1]), int(argv[2])
    if frames < 1 or lag < 1 or argv[3] != "--":
        raise SystemExit("usage: navigation_memory.py K LAG -- <kestrel train arguments>")
    make_vec = train.make_vec

    def make_with_memory(*args, **kwargs):
        env = WithMemory(make_vec(*args, **kwargs), frames, lag)
        env.reset()
        return env

    train.make_vec = make_with_memory  # the training and the evaluation environments alike
    train.main(argv[4:])


if __name__ == "__main__":
    main(sys.argv)
