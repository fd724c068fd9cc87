"""Sweep and rollout throughput of kestrel.cluster against the number of Ray worker processes
(1, 2, 4 on this machine), with the overhead per task and per rollout step; writes
bench/results/cluster/{sweep,rollout}.csv and cluster_throughput.png.

    .venv/bin/python bench/python/cluster_throughput.py [--quick]

Every Ray configuration is a fresh `ray.init(num_cpus=W)` on this machine (worker processes =
W); its workers are warmed up (imports, first world) before anything is timed. Baselines: the
same work in this process without Ray. The legged figures (Go2 flat) are what the paper estimate
in bench/results/cluster/README.md starts from.
"""

from __future__ import annotations

import argparse
import csv
import os
import platform
import time

import numpy as np

import kestrel
from kestrel import cluster

OUT = os.path.join(os.path.dirname(__file__), "..", "results", "cluster")
REPEATS = 3  # every timing is the best of this many: the 2-core machine is shared, and load only slows


def best_of(fn):
    """(shortest wall time, last result) of REPEATS calls of fn."""
    best, out = float("inf"), None
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def _ray_session(workers: int):
    import ray

    os.environ.setdefault("RAY_DISABLE_USAGE_STATS", "1")
    ray.init(num_cpus=workers, object_store_memory=200 << 20, include_dashboard=False, logging_level="ERROR",
             log_to_driver=False)
    return ray


def bench_sweep(workers_list, runs, envs, steps, tiny_runs) -> list[dict]:
    """Per worker count: the sweep on Ray and, in the same minute, the same sweep in this process
    (the machine is shared: a baseline measured minutes apart compares different loads)."""
    rows = []
    plan = dict(grid={"controller.k_pos": [[2.0, 2.0, 1.0], [3.0, 3.0, 2.0]]}, seeds=runs // 2, envs=envs, steps=steps)
    tiny = dict(seeds=tiny_runs, envs=1, steps=1)
    env_steps = runs * envs * steps
    for w in workers_list:
        ray = _ray_session(w)
        try:
            cluster.sweep("position_setpoint_task", workers=w, seeds=2 * w, envs=8, steps=5)  # warm every worker
            wall, res = best_of(lambda: cluster.sweep("position_setpoint_task", workers=w, **plan))
            local_s, ref = best_of(lambda: cluster.sweep("position_setpoint_task", address="local", **plan))
            tiny_wall = best_of(lambda: cluster.sweep("position_setpoint_task", workers=w, **tiny))[0]
            tiny_local = best_of(lambda: cluster.sweep("position_setpoint_task", address="local", **tiny))[0] / tiny_runs
        finally:
            ray.shutdown()
        # Overhead per task: the wall time of the tasks of 1-env, 1-step runs, times the tasks that
        # run at once (at most the cores), less the same run in this process.
        per_task = tiny_wall * min(w, os.cpu_count() or 1) / tiny_runs
        rows.append({"workers": w, "runs": runs, "envs": envs, "steps": steps, "wall_s": wall, "runs_per_s": runs / wall,
                     "env_steps_per_s": env_steps / wall, "one_process_wall_s": local_s,
                     "one_process_env_steps_per_s": env_steps / local_s, "speedup_vs_one_process": local_s / wall,
                     "tiny_task_s": tiny_wall / tiny_runs, "tiny_run_one_process_s": tiny_local,
                     "overhead_per_task_ms": (per_task - tiny_local) * 1e3, "same_hash": res.combined_hash == ref.combined_hash})
        r = rows[-1]
        print(f"sweep: {w} workers {wall:.2f} s ({r['env_steps_per_s']:,.0f} env-steps/s; one process {local_s:.2f} s), "
              f"overhead/task {r['overhead_per_task_ms']:.1f} ms, same hash {r['same_hash']}")
    return rows


def _time_steps(env, steps, n, ad, seed=0):
    rng = np.random.default_rng(seed)
    acts = [rng.uniform(-1, 1, (n, ad)).astype(np.float32) for _ in range(4)]
    env.reset(seed=seed)
    for k in range(3):
        env.step(acts[k % 4])

    def run():
        for k in range(steps):
            env.step(acts[k % 4])
    return best_of(run)[0]


def bench_rollout(workers_list, cases) -> list[dict]:
    """Per worker count and env: RayVectorEnv's step over every actor, and in the same session the
    one-process vector env on 1 and 2 threads; the round trip alone with one env per actor."""
    rows = []
    for w in workers_list:
        ray = _ray_session(w)
        try:
            for gym_id, n, steps, over in cases:
                env = cluster.RayVectorEnv(gym_id, num_envs=n, seed=0, workers=w, threads=1, **over)
                ad = env.single_action_space.shape[0]
                wall = _time_steps(env, steps, n, ad)
                env.close()
                tiny = cluster.RayVectorEnv(gym_id, num_envs=w, seed=0, workers=w, threads=1, **over)
                tiny_wall = _time_steps(tiny, 200, w, ad)
                tiny.close()
                local = {}
                for threads in (1, 2):
                    e = kestrel.make_vec(gym_id, num_envs=n, seed=0, threads=threads, **over)
                    local[threads] = _time_steps(e, steps, n, ad)
                    e.close()
                rows.append({"env": gym_id, "workers": w, "num_envs": n, "steps": steps, "wall_s": wall,
                             "env_steps_per_s": n * steps / wall, "ms_per_step": wall / steps * 1e3,
                             "round_trip_ms": tiny_wall / 200 * 1e3,
                             "one_process_1_thread_env_steps_per_s": n * steps / local[1],
                             "one_process_2_threads_env_steps_per_s": n * steps / local[2]})
                r = rows[-1]
                print(f"rollout {gym_id} {n} envs: {w} actors {r['env_steps_per_s']:,.0f} env-steps/s, round trip "
                      f"{r['round_trip_ms']:.2f} ms; one process {r['one_process_1_thread_env_steps_per_s']:,.0f} (1 thread), "
                      f"{r['one_process_2_threads_env_steps_per_s']:,.0f} (2 threads)")
        finally:
            ray.shutdown()
    return rows


def write_csv(path, rows):
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})


def plot(sweep_rows, roll_rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 3, figsize=(15, 4.2))
    ws = [r["workers"] for r in sweep_rows]
    ax[0].plot(ws, [r["env_steps_per_s"] / 1e6 for r in sweep_rows], "o-", label="Ray tasks")
    ax[0].plot(ws, [r["one_process_env_steps_per_s"] / 1e6 for r in sweep_rows], "s--", color="gray",
               label="one process, no Ray (same minute)")
    b = sweep_rows[0]
    ax[0].set_xlabel("Ray worker processes")
    ax[0].set_ylabel("sweep throughput (M env-steps/s)")
    ax[0].set_title(f"sweep: {b['runs']} runs x {b['envs']} envs x {b['steps']} steps", fontsize=9)
    ax[0].set_ylim(bottom=0)
    ax[1].plot(ws, [r["overhead_per_task_ms"] for r in sweep_rows], "o-", label="per sweep task")
    for gym_id in dict.fromkeys(r["env"] for r in roll_rows):
        rr = [r for r in roll_rows if r["env"] == gym_id]
        ax[1].plot([r["workers"] for r in rr], [r["round_trip_ms"] for r in rr], "s-", label=f"per rollout step, {gym_id}")
    ax[1].set_xlabel("Ray worker processes / actors")
    ax[1].set_ylabel("overhead (ms)")
    ax[1].set_title("overhead: a 1-env 1-step task less the run; a step of 1 env per actor", fontsize=9)
    ax[1].set_ylim(bottom=0)
    for gym_id in dict.fromkeys(r["env"] for r in roll_rows):
        rr = [r for r in roll_rows if r["env"] == gym_id]
        line = ax[2].plot([r["workers"] for r in rr], [r["env_steps_per_s"] for r in rr], "o-",
                          label=f"{gym_id} ({rr[0]['num_envs']} envs), Ray actors")
        ax[2].plot([r["workers"] for r in rr], [r["one_process_1_thread_env_steps_per_s"] for r in rr], "s--", lw=1,
                   color=line[0].get_color(), label=f"{gym_id}, one process 1 thread")
    ax[2].set_yscale("log")
    ax[2].set_xlabel("Ray actors (1 simulator thread each)")
    ax[2].set_ylabel("rollout throughput (env-steps/s, log)")
    ax[2].set_title("rollouts: the learner's step over every actor", fontsize=9)
    for a in ax:
        a.set_xticks([1, 2, 4])
        a.grid(alpha=0.3)
        a.legend(fontsize=7)
    fig.suptitle(f"kestrel.cluster on this {os.cpu_count()}-core machine (shared); 4 workers oversubscribe the cores; "
                 f"best of {REPEATS}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--quick", action="store_true", help="smaller sizes (a smoke test of the script)")
    a = p.parse_args()
    os.makedirs(OUT, exist_ok=True)
    workers = [1, 2, 4]
    if a.quick:
        sw = bench_sweep(workers, runs=8, envs=32, steps=50, tiny_runs=16)
        cases = [("Kestrel-PositionSetpoint-v0", 256, 20, {}), ("Kestrel-Go2-Flat-v0", 64, 5, {})]
    else:
        sw = bench_sweep(workers, runs=32, envs=1024, steps=500, tiny_runs=64)
        cases = [("Kestrel-PositionSetpoint-v0", 4096, 100, {}), ("Kestrel-Go2-Flat-v0", 1024, 30, {})]
    ro = bench_rollout(workers, cases)
    write_csv(os.path.join(OUT, "sweep.csv"), sw)
    write_csv(os.path.join(OUT, "rollout.csv"), ro)
    plot(sw, ro, os.path.join(OUT, "cluster_throughput.png"))
    print(f"wrote {OUT}/sweep.csv, rollout.csv, cluster_throughput.png")


if __name__ == "__main__":
    main()
