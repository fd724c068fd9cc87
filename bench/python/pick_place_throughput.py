"""Environment throughput of LeIsaac's SO-101 pick-and-place task (issue 14) from Python, the way a
learner steps it: Kestrel-SO101-PickPlace-v0 through the gymnasium VectorEnv with policy-like
actions (the home pose plus N(0, sigma) per joint, fresh every step, as an untrained policy's are;
sigma 0.3 rad keeps most arms in the air, 1.0 rad swings them into the table, the box and the cube:
the contacts per environment are in the CSV), 4 physics steps per policy step (servos,
collision, the constrained step with the grasp contacts), observations, rewards and resets; at 1
and 2 threads. Each configuration twice in the same run, interleaved: with the worlds batched
(PickPlaceWorld::step_batch, the default: one world per SIMD lane, the same results) and with every
world stepped alone (KESTREL_LEGGED_BATCH=off); the two must end with the same state hash.

Writes bench/results/python/pick_place_throughput.csv.
Usage: .venv/bin/python bench/python/pick_place_throughput.py [--envs 1024] [--steps 50] [--repeats 3] [--noise 0.3 1.0]
"""
import argparse
import os
import time

import numpy as np

import kestrel
from bench_rows import cpu_model, write_rows

ID = "Kestrel-SO101-PickPlace-v0"


def run(envs, steps, threads, step, noise):
    """Timing of `steps` policy steps after a warm-up; returns (seconds, state hash, mean contacts
    per environment at the end)."""
    os.environ["KESTREL_LEGGED_BATCH"] = "on" if step == "batched" else "off"  # read when the task is built
    env = kestrel.make_vec(ID, num_envs=envs, seed=0, threads=threads)
    obs, _ = env.reset(seed=0)
    home = obs[:, 0:6].copy()
    rng = np.random.default_rng(0)
    acts = [(home + noise * rng.standard_normal(home.shape)).astype(np.float32) for _ in range(steps + 10)]
    for k in range(10):  # warm-up: out of the reset's first contacts
        env.step(acts[k])
    t0 = time.perf_counter()
    for k in range(steps):
        env.step(acts[10 + k])
    dt = time.perf_counter() - t0
    h = env.task.state_hash
    contacts = float(np.mean([env.task.pick_place_state(e)["contacts"] for e in range(envs)]))
    env.close()
    return dt, h, contacts


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--envs", type=int, default=1024)
    p.add_argument("--steps", type=int, default=50)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--noise", type=float, nargs="+", default=[0.3, 1.0], help="action std about the home pose, rad")
    p.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "results", "python", "pick_place_throughput.csv"))
    args = p.parse_args()
    rows = []
    for noise in args.noise:
        for threads in (1, 2):
            best = {"batched": float("inf"), "alone": float("inf")}
            hashes, contacts = {}, 0.0
            for _ in range(args.repeats):  # interleaved, best of N: the least disturbed run
                for step in ("batched", "alone"):
                    dt, h, contacts = run(args.envs, args.steps, threads, step, noise)
                    best[step] = min(best[step], dt)
                    hashes.setdefault(step, set()).add(h)
            same = len(hashes["batched"] | hashes["alone"]) == 1
            n = args.envs * args.steps
            for step in ("batched", "alone"):
                rows.append({"task": ID, "envs": args.envs, "threads": threads, "action_noise_rad": noise, "worlds": step,
                             "python_policy_steps_per_s": round(n / best[step]),
                             "physics_steps_per_s": round(4 * n / best[step]),
                             "batched_over_alone": round(best["alone"] / best["batched"], 2),
                             "contacts_per_env_at_end": round(contacts, 2),
                             "same_state_hash": int(same), "state_hash": f"{next(iter(hashes[step])):016x}",
                             "cpu": cpu_model(), "cores": os.cpu_count(), "date": time.strftime("%Y-%m-%d", time.gmtime())})
                print(rows[-1], flush=True)
            if not same:
                raise SystemExit(f"pick_place_throughput: the batched and the alone runs differ: {hashes}")
    os.environ.pop("KESTREL_LEGGED_BATCH", None)
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
