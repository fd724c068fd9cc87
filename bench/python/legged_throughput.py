"""Environment throughput of legged_gym's locomotion task (issue 13's bench): policy steps per second
of Kestrel-Go2-Flat-v0 (and ANYmal C) including the joint PD at 200 Hz (4 physics steps per policy
step), observations with noise, the reward terms, terminations, pushes and resets, stepped from
Python through the gymnasium VectorEnv with policy-like actions (N(0, 1), legged_gym's initial
policy std), at 1 and 2 threads; beside it the same task stepped by C++ alone (Task.step_n, fixed
actions). Goal (issue 13): >= 150,000 policy steps/s on 2 cores for Go2 flat; legged_gym reaches
about 123,000 with its learner on a GPU. Each configuration twice, in the same run: with the
batched constrained step (the default: several robots per SIMD step, the same results) and with
the scalar step for every robot (KESTREL_LEGGED_BATCH=off), so the column `constrained_step`
gives the ratio measured side by side.

Writes bench/results/python/legged_throughput.csv.
Usage: .venv/bin/python bench/python/legged_throughput.py [--envs 4096] [--steps 100]
"""
import argparse
import os
import time

import numpy as np

import kestrel
from bench_rows import cpu_model, write_rows
from kestrel.progress import Progress


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--envs", type=int, default=4096)
    p.add_argument("--steps", type=int, default=100)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--quiet", action="store_true", help="no progress line (there is none when stderr is not a terminal)")
    p.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "results", "python", "legged_throughput.csv"))
    args = p.parse_args()
    rows = []
    # A progress line on a terminal (kestrel.progress): 2 robots x 2 thread counts x 2 steps x repeats x 2 loops.
    progress = Progress(total=2 * 2 * 2 * args.repeats * 2 * args.steps * args.envs, unit="env-steps",
                        desc="legged throughput", quiet=args.quiet)
    for gid, threads, step in [(g, t, s) for g in ("Kestrel-Go2-Flat-v0", "Kestrel-AnymalC-Flat-v0") for t in (1, 2)
                               for s in ("batched", "scalar")]:
        # Read when the simulator is built (sim/src/backends/articulated.cpp).
        os.environ["KESTREL_LEGGED_BATCH"] = "on" if step == "batched" else "off"
        env = kestrel.make_vec(gid, num_envs=args.envs, seed=0, threads=threads)
        env.reset(seed=0)
        rng = np.random.default_rng(0)
        acts = [rng.standard_normal((args.envs, 12)).astype(np.float32) for _ in range(8)]
        for k in range(10):  # warm-up: out of the spawn transient
            env.step(acts[k % 8])
        best_py = best_cpp = float("inf")
        for _ in range(args.repeats):  # interleaved, best of N: the least disturbed run
            t0 = time.perf_counter()
            for k in range(args.steps):
                env.step(acts[k % 8])
            best_py = min(best_py, time.perf_counter() - t0)
            progress.update(args.steps * args.envs)  # outside the timed regions
            t0 = time.perf_counter()
            env.task.step_n(acts[0], args.steps)
            best_cpp = min(best_cpp, time.perf_counter() - t0)
            progress.update(args.steps * args.envs)
        n = args.envs * args.steps
        rows.append({"task": gid, "envs": args.envs, "threads": threads, "constrained_step": step,
                     "python_policy_steps_per_s": round(n / best_py), "cpp_policy_steps_per_s": round(n / best_cpp),
                     "physics_steps_per_policy_step": 4, "cpu": cpu_model(), "date": time.strftime("%Y-%m-%d", time.gmtime()),
                     "cores": os.cpu_count(), "goal_2_cores": 150_000 if "Go2" in gid else ""})
        progress.clear()
        print(rows[-1], flush=True)
        env.close()
    os.environ.pop("KESTREL_LEGGED_BATCH", None)
    progress.close()
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
