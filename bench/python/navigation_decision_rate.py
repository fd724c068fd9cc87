"""A navigation checkpoint evaluated at several decision intervals (env-steps each action is held).

Training holds each action for the adapter's action repeat (5 env-steps: 20 Hz decisions for
Kestrel-Navigation-v0). This evaluates the checkpoint's deterministic actor on the same unseen
episodes with the action held for 1 (a decision every env-step) and for the training's repeat, so
the effect of the evaluation's decision rate is measured rather than assumed.

    .venv/bin/python bench/python/navigation_decision_rate.py bench/results/python/navigation_zones_rsl_rl.pt \
        --holds 1,5 --episodes 1024 --seed 1000004
"""
from __future__ import annotations

import argparse
import csv
import json
import os
import sys
import time

import numpy as np


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("checkpoint", help="rsl_rl checkpoint (.pt) of a Kestrel-Navigation-v0 run with its defaults")
    p.add_argument("--holds", default="1,5", help="comma list of decision intervals (env-steps)")
    p.add_argument("--episodes", type=int, default=1024)
    p.add_argument("--seed", type=int, default=1_000_004)
    p.add_argument("--threads", type=int, default=None)
    p.add_argument("--csv", default=None, help="append one row per interval to this CSV")
    p.add_argument("--label", default="", help="the run's name in the CSV")
    a = p.parse_args(argv)

    import torch

    from kestrel import export
    from kestrel.train import _TASK_DEFAULTS, _task_keys, evaluate

    d = _TASK_DEFAULTS["Kestrel-Navigation-v0"]
    overrides = {"task": _task_keys("--task-set", d["task_set"]),
                 "sensors": json.loads(d["sensors"])}
    task = dict(overrides["task"])
    task["curriculum"] = {"start_level": 10, "increase_step": 0, "decrease_step": 0}
    overrides["task"] = task
    ck = torch.load(a.checkpoint, map_location="cpu", weights_only=False)
    spec = export.from_rsl_rl(ck["actor_state_dict"], -1.0, 1.0, activation="elu", squash="tanh")
    net = spec.torch_module()

    rows = []
    for hold in [int(x) for x in a.holds.split(",")]:
        def act(obs, net=net):
            with torch.inference_mode():
                return net(torch.from_numpy(np.array(obs, np.float32))).numpy()
        act.hold = hold
        t0 = time.perf_counter()
        r = evaluate(act, "Kestrel-Navigation-v0", episodes=a.episodes, seed=a.seed, threads=a.threads, **overrides)
        row = {"run": a.label or os.path.basename(a.checkpoint), "decision_interval_env_steps": hold,
               "episodes": r.episodes, "seed": a.seed, "success_rate": r.success_rate, "crash_rate": r.crash_rate,
               "timeout_rate": 1.0 - r.success_rate - r.crash_rate, "mean_length": r.mean_length,
               "final_distance_m": r.final_distance_m, "eval_s": round(time.perf_counter() - t0, 2)}
        rows.append(row)
        print(json.dumps(row), flush=True)
    if a.csv:
        new = not os.path.exists(a.csv)
        with open(a.csv, "a", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            if new:
                w.writeheader()
            w.writerows(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
