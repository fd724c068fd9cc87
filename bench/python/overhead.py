"""Python-side overhead of stepping a Kestrel task (issue 11's bench), measured side by side in one run:

  - throughput at 4096 environments on 2 threads: env-steps/s of KestrelVectorEnv.step from Python
    (one Python call per step: argument checks, GIL release, the C++ task step, the infos) vs the
    same task stepped by C++ alone (Task.step_n: the same actions, N steps inside one call);
  - per-call cost at 1 environment: Task.step (the binding) and KestrelVectorEnv.step, minus the
    C++ step itself.

Writes bench/results/python/overhead.csv. Usage: .venv/bin/python bench/python/overhead.py [--steps N]
"""
import argparse
import csv
import os
import platform
import time

import numpy as np

import kestrel
from kestrel.progress import Progress


def best_of(fn, repeats):
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--envs", type=int, default=4096)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--steps", type=int, default=300)
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--calls", type=int, default=100_000)
    p.add_argument("--quiet", action="store_true", help="no progress line (there is none when stderr is not a terminal)")
    p.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "results", "python", "overhead.csv"))
    args = p.parse_args()
    rows = []
    gid = "Kestrel-PositionSetpoint-v0"

    # Throughput: zero velocity actions (hover; the task's auto-resets happen as in training).
    env = kestrel.make_vec(gid, num_envs=args.envs, seed=0, threads=args.threads)
    env.reset()
    a = np.zeros((args.envs, env.task.action_dim), np.float32)
    env.task.step_n(a, 50)  # warm-up

    def py_loop():
        for _ in range(args.steps):
            env.step(a)

    def cpp_loop():
        env.task.step_n(a, args.steps)

    # A progress line on a terminal (kestrel.progress), in steps of the whole bench: the throughput
    # loops, then the three per-call loops at 1 env; updated between timed regions only.
    progress = Progress(total=2 * args.repeats * args.steps * args.envs + 3 * args.repeats * args.calls, unit="env-steps",
                        desc="overhead bench", quiet=args.quiet)
    # Interleaved, best of N each: the machine is shared, the best run is the least disturbed one.
    t_py, t_cpp = float("inf"), float("inf")
    for _ in range(args.repeats):
        t_py = min(t_py, best_of(py_loop, 1))
        progress.update(args.steps * args.envs)
        t_cpp = min(t_cpp, best_of(cpp_loop, 1))
        progress.update(args.steps * args.envs)
    sps_py, sps_cpp = args.envs * args.steps / t_py, args.envs * args.steps / t_cpp
    rows.append({"measure": f"env-steps/s, {args.envs} envs, {args.threads} threads, Python KestrelVectorEnv.step", "value": round(sps_py)})
    rows.append({"measure": f"env-steps/s, {args.envs} envs, {args.threads} threads, C++ Task.step_n (same task and actions)", "value": round(sps_cpp)})
    rows.append({"measure": "Python / C++ throughput ratio", "value": round(sps_py / sps_cpp, 4)})

    # Per call at 1 environment.
    one = kestrel.make_vec(gid, num_envs=1, seed=0, threads=1)
    one.reset()
    a1 = np.zeros((1, one.task.action_dim), np.float32)
    n = args.calls
    task = one.task

    def task_calls():
        for _ in range(n):
            task.step(a1)

    def env_calls():
        for _ in range(n):
            one.step(a1)

    def cpp_calls():
        task.step_n(a1, n)

    def timed(fn):
        t = best_of(fn, args.repeats) / n
        progress.update(args.repeats * n)
        return t

    t_task = timed(task_calls)
    t_env = timed(env_calls)
    t_c = timed(cpp_calls)
    progress.close()
    rows.append({"measure": "us per step, 1 env, C++ step only (Task.step_n)", "value": round(t_c * 1e6, 3)})
    rows.append({"measure": "us per step call, 1 env, kestrel.Task.step (binding)", "value": round(t_task * 1e6, 3)})
    rows.append({"measure": "us per step call, 1 env, KestrelVectorEnv.step (gymnasium API)", "value": round(t_env * 1e6, 3)})
    rows.append({"measure": "us Python overhead per call, binding (Task.step - C++ step)", "value": round((t_task - t_c) * 1e6, 3)})
    rows.append({"measure": "us Python overhead per call, vector env (VectorEnv.step - C++ step)", "value": round((t_env - t_c) * 1e6, 3)})
    rows.append({"measure": "machine", "value": f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"})

    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with open(args.out, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["measure", "value"])
        w.writeheader()
        w.writerows(rows)
    for r in rows:
        print(f"{r['measure']:<80} {r['value']}")
    print(f"wrote {os.path.abspath(args.out)}")


if __name__ == "__main__":
    main()
