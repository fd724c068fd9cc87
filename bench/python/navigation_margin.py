"""A prototype behind issue 11's navigation runs: `kestrel train` with the training environments'
robot given a larger collision sphere than the evaluation's (radius R m instead of base_quadrotor's
0.2 m), so that a crash in training comes MARGIN = R - 0.2 m earlier: a policy that learns to keep
the inflated sphere clear keeps the real one clear by the margin. The evaluation environments
(and the reported figures) keep the task's robot unchanged.

Why: on hp2's checkpoint (bench/results/python/navigation_zones_rsl_rl.pt), 103 of 512 level-10
episodes of seed 1000004 crash, and in 72 of them the nearest zone of the last image before the
crash lies in the image's first or last column: the vehicle clips an obstacle it is passing. The
level-10 layouts leave room for it: bench/python/navigation_solvable.py finds a route for the
sphere with 0.15 m more clearance in all 512 of seed 1000003.

    .venv/bin/python bench/python/navigation_margin.py R -- Kestrel-Navigation-v0 \\
        --eval-episodes 512 --threads 2 --final-eval-episodes 1024 --out runs/nav/m30 --export 0
"""
import sys

import kestrel.train as train

# navigation_task's registered robot (sim/src/tasks/navigation_task.cpp, navigation_task_defaults):
# a robot section replaces it whole, so it is spelled out with the collision sphere added.
NAV_ROBOT = {"name": "base_quadrotor", "min_init_position_ratio": [0.1, 0.15, 0.15],
             "max_init_position_ratio": [0.2, 0.85, 0.85], "max_init_yaw_rad": 0.5235987755982988,
             "max_init_linvel_m_s": 0.2, "max_init_angvel_rad_s": 0.2}


def main(argv: list[str]) -> None:
    radius = float(argv[1])
    if not radius > 0 or argv[2] != "--":
        raise SystemExit("usage: navigation_margin.py RADIUS_M -- <kestrel train arguments>")
    make_vec = train.make_vec
    calls = {"n": 0}

    def make(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 1:  # kestrel.train's first environment is the training one; evaluations follow
            kwargs = {**kwargs, "robot": {**NAV_ROBOT, "collision_shape": {"type": "sphere", "radius_m": radius}}}
        return make_vec(*args, **kwargs)

    train.make_vec = make
    train.main(argv[3:])


if __name__ == "__main__":
    main(sys.argv)
