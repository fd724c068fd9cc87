"""MuJoCo on Kestrel's SO-101 pick-and-place scene, side by side (issue 14's bench).

Replays the joint targets of Kestrel's scripted pick and place (the first episode of
kestrel_bench_pick_place, written as bench/results/manipulation/episode0_trace.csv) in MuJoCo 3 (the
`mujoco` wheel, the tests' oracle) on the same scene: models/so101/so101.xml with the same servo
gains as Kestrel's PickPlaceConfig (arm kp 998.22 / kd 2.73, gripper kp 20 / kd 0.5, effort 2.94 N m),
the same 25 mm 11 g cube at the same start, the same box of five static boxes and the table plane,
dt 5 ms with the targets held for 4 steps. It reports, for each MuJoCo solver setting, whether the
cube rose with the gripper (its height when the lift ended, against Kestrel's), whether it ended in
the box (LeIsaac's cube_in_box), and MuJoCo's physics steps per second on one core for this scene.

    .venv/bin/python bench/manipulation/mujoco_side_by_side.py [trace.csv] [out.csv]

What differs: MuJoCo combines a pair's friction by the maximum (Kestrel: the mean), and its contacts
are soft (solref/solimp) where Kestrel's are hard constraints solved by PGS.
"""

from __future__ import annotations

import csv
import pathlib
import sys
import time

import mujoco
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
HALF = 0.0125
MASS = 0.011
BOX_INNER, BOX_WALL, BOX_HEIGHT = 0.05, 0.005, 0.04


def build(cube_xy, box_xy, integrator: str, cone: str, impratio: float) -> tuple[mujoco.MjModel, mujoco.MjData]:
    spec = mujoco.MjSpec.from_file(str(ROOT / "models/so101/so101.xml"))
    spec.option.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{integrator.upper()}")
    spec.option.cone = getattr(mujoco.mjtCone, f"mjCONE_{cone.upper()}")
    spec.option.impratio = impratio
    wb = spec.worldbody
    wb.add_geom(name="table", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[1, 1, 0.01], friction=[0.5, 0.005, 0.0001])
    cube = wb.add_body(name="cube", pos=[cube_xy[0], cube_xy[1], HALF])
    cube.add_freejoint()
    # so101.xml compiles with inertiafromgeom="false": the cube's inertia is given, a solid cube's.
    cube.explicitinertial = True
    cube.mass = MASS
    cube.inertia = [MASS * (2 * HALF) ** 2 / 6] * 3
    cube.ipos = [0, 0, 0]  # (MjSpec left it at the body position)
    cube.add_geom(name="cube", type=mujoco.mjtGeom.mjGEOM_BOX, size=[HALF] * 3, mass=MASS, friction=[1, 0.005, 0.0001])
    bx, by = box_xy
    parts = [((bx, by, BOX_WALL / 2), (BOX_INNER + BOX_WALL, BOX_INNER + BOX_WALL, BOX_WALL / 2))]
    for sign in (-1, 1):
        parts.append(((bx + sign * (BOX_INNER + BOX_WALL / 2), by, BOX_HEIGHT / 2), (BOX_WALL / 2, BOX_INNER + BOX_WALL, BOX_HEIGHT / 2)))
        parts.append(((bx, by + sign * (BOX_INNER + BOX_WALL / 2), BOX_HEIGHT / 2), (BOX_INNER, BOX_WALL / 2, BOX_HEIGHT / 2)))
    for i, (pos, size) in enumerate(parts):
        wb.add_geom(name=f"box{i}", type=mujoco.mjtGeom.mjGEOM_BOX, pos=list(pos), size=list(size), friction=[0.6, 0.005, 0.0001])
    model = spec.compile()
    # Kestrel's servo gains (PickPlaceConfig): a position actuator is gain kp, bias [0, -kp, -kv].
    for a in range(model.nu):
        grip = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, a) == "gripper"
        kp, kv = (20.0, 0.5) if grip else (998.22, 2.73)
        model.actuator_gainprm[a, 0] = kp
        model.actuator_biasprm[a, 1] = -kp
        model.actuator_biasprm[a, 2] = -kv
    data = mujoco.MjData(model)
    key = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, "home")
    if key >= 0:
        # The keyframe was written for the arm alone: its qpos has the arm's 6 entries.
        data.qpos[:6] = model.key_qpos[key][:6]
    cube_adr = model.jnt_qposadr[model.body_jntadr[model.body("cube").id]]
    data.qpos[cube_adr:cube_adr + 3] = [cube_xy[0], cube_xy[1], HALF]
    data.qpos[cube_adr + 3:cube_adr + 7] = [1, 0, 0, 0]
    mujoco.mj_forward(model, data)
    return model, data


def main() -> int:
    trace_path = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "bench/results/manipulation/episode0_trace.csv"
    out_path = pathlib.Path(sys.argv[2]) if len(sys.argv) > 2 else ROOT / "bench/results/manipulation/mujoco_side_by_side.csv"
    rows = list(csv.DictReader(open(trace_path)))
    targets = np.array([[float(r[f"q{j}"]) for j in range(6)] for r in rows])
    phases = np.array([int(r["phase"]) for r in rows])
    kestrel_cube = np.array([[float(r["cube_x"]), float(r["cube_y"]), float(r["cube_z"])] for r in rows])
    box_xy = (float(rows[0]["box_x"]), float(rows[0]["box_y"]))
    lift_end = int(np.nonzero(phases == 3)[0][-1])
    settings = [("euler", "pyramidal", 1.0), ("implicitfast", "pyramidal", 1.0), ("implicitfast", "elliptic", 10.0)]
    out = []
    for integrator, cone, impratio in settings:
        model, data = build(kestrel_cube[0, :2], box_xy, integrator, cone, impratio)
        cube_body = model.body("cube").id
        steps = 0
        z_at_lift_end = None
        t0 = time.perf_counter()
        for k, target in enumerate(targets):
            data.ctrl[:] = target
            for _ in range(4):
                mujoco.mj_step(model, data)
                steps += 1
            if k == lift_end:
                z_at_lift_end = float(data.xpos[cube_body][2])
        for _ in range(100):  # half a second to settle, as Kestrel's bench
            mujoco.mj_step(model, data)
            steps += 1
        seconds = time.perf_counter() - t0
        c = data.xpos[cube_body]
        in_box = abs(c[0] - box_xy[0]) < 0.05 and abs(c[1] - box_xy[1]) < 0.05 and c[2] < 0.10
        out.append({
            "engine": "mujoco " + mujoco.__version__, "integrator": integrator, "cone": cone, "impratio": impratio,
            "cube_z_at_lift_end_m": round(z_at_lift_end, 5), "kestrel_cube_z_at_lift_end_m": round(float(kestrel_cube[lift_end, 2]), 5),
            "cube_in_box": int(in_box), "final_cube_x": round(float(c[0]), 4), "final_cube_y": round(float(c[1]), 4),
            "final_cube_z": round(float(c[2]), 4), "physics_steps_per_s": round(steps / seconds),
        })
        print(out[-1])
    with open(out_path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(out[0]))
        w.writeheader()
        w.writerows(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
