"""Can the top curriculum level of Kestrel-Navigation-v0 be flown at all? For the level-10 layouts of
evaluation seeds: a 3-D grid of 0.1 m cells over each environment's bounds, a cell free when its
centre lies farther than R from every obstacle (the robot's collision sphere, radius 0.2 m, plus a
margin) and from the bounds' faces; a flood fill from the start cell; the layout is solvable at R
when the fill reaches a cell within the success radius (1 m) of the goal. Also the length of that
route (6-connected cells, so up to sqrt(3) longer than the Euclidean one) against the straight
line, and the speed it asks for in the 10 s episode.

Writes bench/results/python/navigation_solvable.csv (one row per margin).
Usage: .venv/bin/python bench/python/navigation_solvable.py [--envs 512] [--seed 1000003]
"""
import argparse
import csv
import os

import numpy as np

import kestrel

CELL_M = 0.1
SUCCESS_RADIUS_M = 1.0


def _rotation(q_xyzw):
    x, y, z, w = q_xyzw
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def occupied(obstacles: dict, axes, radius_m: float) -> np.ndarray:
    """Cells whose centre is within radius_m of an obstacle (boxes, spheres; capsules and cylinders
    as capsules), each obstacle tested only over its bounding box grown by radius_m."""
    occ = np.zeros(tuple(len(a) for a in axes), bool)
    for i in range(len(obstacles["type"])):
        t, c = obstacles["type"][i], obstacles["position_w"][i]
        rot = _rotation(obstacles["orientation_xyzw"][i])
        r, hl, he = obstacles["radius_m"][i], obstacles["half_length_m"][i], obstacles["half_extents_m"][i]
        if t == 1:
            ext = np.abs(rot) @ he
        elif t == 0:
            ext = np.full(3, r)
        elif t in (2, 3):
            ext = np.abs(rot) @ np.array([r, r, hl + r])
        else:
            raise SystemExit(f"obstacle {i}: shape type {t} (a convex hull) is not handled here")
        idx = [np.nonzero((a >= lo) & (a <= hi))[0] for a, lo, hi in zip(axes, c - ext - radius_m, c + ext + radius_m)]
        if any(len(k) == 0 for k in idx):
            continue
        local = (np.stack(np.meshgrid(*(a[k] for a, k in zip(axes, idx)), indexing="ij"), -1) - c) @ rot
        if t == 1:
            q = np.abs(local) - he
            d = np.linalg.norm(np.maximum(q, 0), axis=-1) + np.minimum(q.max(-1), 0)
        elif t == 0:
            d = np.linalg.norm(local, axis=-1) - r
        else:
            zc = np.clip(local[..., 2], -hl, hl)
            d = np.sqrt(local[..., 0] ** 2 + local[..., 1] ** 2 + (local[..., 2] - zc) ** 2) - r
        block = np.ix_(*idx)
        occ[block] |= d <= radius_m
    return occ


def route_cells(start, goal, lower, upper, obstacles, radius_m):
    """Cells (6-connected steps) from the start to the goal's success ball; -1 none; -2 start not free."""
    axes = [np.arange(lower[k] + CELL_M / 2, upper[k], CELL_M) for k in range(3)]
    occ = occupied(obstacles, axes, radius_m)
    for k in range(3):  # the floor and the bounds' faces (out of bounds is a crash too)
        sl = [slice(None)] * 3
        sl[k] = (axes[k] - lower[k] <= radius_m) | (upper[k] - axes[k] <= radius_m)
        occ[tuple(sl)] = True
    free = ~occ
    s = tuple(min(max(int((start[k] - axes[k][0]) / CELL_M + 0.5), 0), len(axes[k]) - 1) for k in range(3))
    if not free[s]:
        return -2
    near = np.linalg.norm(np.stack(np.meshgrid(*axes, indexing="ij"), -1) - goal, axis=-1) < SUCCESS_RADIUS_M
    reach = np.zeros_like(free)
    reach[s] = True
    steps = 0
    while not (reach & near).any():
        n = reach.copy()
        n[1:] |= reach[:-1]
        n[:-1] |= reach[1:]
        n[:, 1:] |= reach[:, :-1]
        n[:, :-1] |= reach[:, 1:]
        n[:, :, 1:] |= reach[:, :, :-1]
        n[:, :, :-1] |= reach[:, :, 1:]
        n &= free
        if (n == reach).all():
            return -1
        reach = n
        steps += 1
    return steps


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--envs", type=int, default=512)
    p.add_argument("--seed", type=int, default=1_000_003)
    p.add_argument("--margins", default="0,0.15,0.3", help="clearance beyond the robot's 0.2 m sphere, m (comma list)")
    p.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "results", "python", "navigation_solvable.csv"))
    args = p.parse_args()
    env = kestrel.make_vec("Kestrel-Navigation-v0", num_envs=args.envs, seed=args.seed, threads=1,
                           task={"curriculum": {"start_level": 10, "increase_step": 0, "decrease_step": 0}})
    env.reset(seed=args.seed)
    sim = env.task.simulator
    wd = sim.world_data()
    episode_s = 10.0  # the task's 1000 env-steps of 10 ms
    rows = []
    for margin in (float(m) for m in args.margins.split(",")):
        radius = 0.2 + margin
        cells, straight = [], []
        for e in range(args.envs):
            start, goal = np.asarray(wd["position_w"][e]), np.asarray(wd["target_w"][e])
            cells.append(route_cells(start, goal, wd["lower_w"][e], wd["upper_w"][e], sim.obstacles(e), radius))
            straight.append(np.linalg.norm(goal - start) - SUCCESS_RADIUS_M)
        cells, straight = np.array(cells), np.array(straight)
        ok = cells >= 0
        route = cells[ok] * CELL_M
        rows.append({"seed": args.seed, "envs": args.envs, "level": 10, "robot_radius_m": 0.2, "margin_m": margin,
                     "solvable": round(float(ok.mean()), 4), "no_route": round(float((cells == -1).mean()), 4),
                     "start_not_free": round(float((cells == -2).mean()), 4),
                     "straight_m_median": round(float(np.median(straight)), 2),
                     "route_6conn_m_median": round(float(np.median(route)), 2) if ok.any() else "",
                     "route_6conn_m_p90": round(float(np.quantile(route, 0.9)), 2) if ok.any() else "",
                     "speed_for_p90_route_m_s": round(float(np.quantile(route, 0.9)) / episode_s, 2) if ok.any() else ""})
        print(rows[-1])
    with open(args.out, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print("wrote", args.out)


if __name__ == "__main__":
    main()
