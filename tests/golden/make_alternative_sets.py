#!/usr/bin/env python3
"""Writes golden reference sets of the same format as tests/golden/reference/ but with other case
counts, to prove that the parity tests accept any reference set (issue 17).

Values cannot be re-derived without Aerial Gym, so every case is a real one: the sets resample,
reorder and drop the public cases (and shorten motor traces), which changes every count the tests
could have hard-coded while each value still agrees with the reference.

  <out>/alternative/  passes: other counts of every kind of case (see ALTERNATIVE below)
  <out>/truncated/    fails:  one kind of case missing from each file
  <out>/empty/        fails:  every case list empty

Usage: make_alternative_sets.py [--reference DIR] --out DIR   (standard library only)
"""
import argparse
import copy
import json
import os
import random

FILES = ("allocation", "motor_model", "controllers", "sensor_rays", "rewards")

# The alternative set, per file (the public set's counts in brackets).
ALTERNATIVE = {
    # robots reordered; per robot (saturated, unsaturated) cases drawn with replacement:
    # 7 saturated in all [24], 61 unsaturated [66].
    "allocation": {"base_octarotor": (2, 30), "base_quadrotor": (4, 3), "base_random": (1, 28)},
    # 5 configurations [9] (both integrators, both states), 8 runs [18], one trace cut to 120 steps [200].
    "motor_model": {"configurations": (3, 0, 6, 7, 2), "single_run": (0, 6), "short": (6, 120)},
    # cases per controller drawn with replacement [40 each], controllers reordered.
    "controllers": (17, 52, 5, 40, 23, 61, 9),
    # the 8 x 16 lidar and the camera [plus the OSDome], rays shuffled: 50 [128] and 100 [144].
    "sensor_rays": {"sensors": (2, 1), "rays": (100, 50)},
    # cases drawn with replacement [40], both outcomes present.
    "rewards": 57,
}


def load(ref, name):
    with open(os.path.join(ref, name + ".json")) as f:
        return json.load(f)


def save(out, name, data):
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, name + ".json"), "w") as f:
        json.dump(data, f, indent=1)


def note(data, what):
    data["source"]["alternative_set"] = what


def saturated(case):
    return case["any_saturated"]


def crashed(case):
    return case["crashes_out"] > 0


def draw(rng, cases, n, keep=lambda c: True):
    pool = [c for c in cases if keep(c)]
    return [copy.deepcopy(rng.choice(pool)) for _ in range(n)]


def alternative(rng, sets):
    alloc = sets["allocation"]
    robots = {}
    for name, (n_sat, n_unsat) in ALTERNATIVE["allocation"].items():
        robot = alloc["robots"][name]
        cases = draw(rng, robot["cases"], n_sat, saturated) + draw(rng, robot["cases"], n_unsat, lambda c: not saturated(c))
        rng.shuffle(cases)
        robot["cases"] = cases
        robots[name] = robot
    alloc["robots"] = robots

    motor = sets["motor_model"]
    spec = ALTERNATIVE["motor_model"]
    configs = [motor["configurations"][i] for i in spec["configurations"]]
    for i in spec["single_run"]:
        motor["configurations"][i]["runs"] = motor["configurations"][i]["runs"][:1]
    index, steps = spec["short"]
    short = motor["configurations"][index]
    short["reference_thrust_N"] = short["reference_thrust_N"][:steps]
    for run in short["runs"]:
        run["thrust_N"] = run["thrust_N"][:steps]
    motor["configurations"] = configs

    ctrl = sets["controllers"]
    names = list(ctrl["controllers"])
    rng.shuffle(names)
    controllers = {}
    for name, n in zip(names, ALTERNATIVE["controllers"]):
        c = ctrl["controllers"][name]
        picks = [rng.randrange(len(c["cases"])) for _ in range(n)]
        c["cases"] = [copy.deepcopy(c["cases"][i]) for i in picks]
        partial = c.get("partial_torque_only")
        if partial is not None:  # lee_rates: per-case arrays parallel to the cases
            for key in ("torque_body", "command_after_in_place_clamp"):
                partial[key] = [partial[key][i] for i in picks]
        controllers[name] = c
    ctrl["controllers"] = controllers
    del ctrl["source"]["num_cases_per_controller"]  # differs per controller here

    rays = sets["sensor_rays"]
    sensors = []
    for i, n in zip(ALTERNATIVE["sensor_rays"]["sensors"], ALTERNATIVE["sensor_rays"]["rays"]):
        s = rays["sensors"][i]
        s["rays"] = rng.sample(s["rays"], n)
        s["full_grid"] = False
        sensors.append(s)
    rays["sensors"] = sensors

    rew = sets["rewards"]
    n = ALTERNATIVE["rewards"]
    rew["cases"] = draw(rng, rew["cases"], n // 4, crashed) + draw(rng, rew["cases"], n - n // 4, lambda c: not crashed(c))
    rng.shuffle(rew["cases"])

    for data in sets.values():
        note(data, "resampled, reordered and shortened from the public set by tests/golden/make_alternative_sets.py")
    return sets


def truncated(sets):
    """One kind of case missing per file: each test must fail on it."""
    for robot in sets["allocation"]["robots"].values():
        robot["cases"] = [c for c in robot["cases"] if not saturated(c)]
    motor = sets["motor_model"]
    motor["configurations"] = [c for c in motor["configurations"] if not c["params"]["use_rps"]]
    del sets["controllers"]["controllers"]["lee_attitude_control"]
    rays = sets["sensor_rays"]
    rays["sensors"] = [s for s in rays["sensors"] if s["kind"] == "lidar"]
    sets["rewards"]["cases"] = [c for c in sets["rewards"]["cases"] if not crashed(c)]
    for data in sets.values():
        note(data, "truncated (one kind of case removed) by tests/golden/make_alternative_sets.py")
    return sets


def empty(sets):
    """Every list of cases empty: each test must fail on it."""
    for robot in sets["allocation"]["robots"].values():
        robot["cases"] = []
    sets["motor_model"]["configurations"] = []
    for c in sets["controllers"]["controllers"].values():
        c["cases"] = []
        if "partial_torque_only" in c:
            for key in ("torque_body", "command_after_in_place_clamp"):
                c["partial_torque_only"][key] = []
    for s in sets["sensor_rays"]["sensors"]:
        s["rays"] = []
    sets["rewards"]["cases"] = []
    for data in sets.values():
        note(data, "emptied by tests/golden/make_alternative_sets.py")
    return sets


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--reference", default=os.path.join(here, "reference"))
    p.add_argument("--out", required=True)
    p.add_argument("--seed", type=int, default=17)
    args = p.parse_args()
    public = {name: load(args.reference, name) for name in FILES}
    variants = {
        "alternative": alternative(random.Random(args.seed), copy.deepcopy(public)),
        "truncated": truncated(copy.deepcopy(public)),
        "empty": empty(copy.deepcopy(public)),
    }
    for variant, sets in variants.items():
        for name, data in sets.items():
            save(os.path.join(args.out, variant), name, data)


if __name__ == "__main__":
    main()
