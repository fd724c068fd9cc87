"""Issue 11: where a navigation policy crashes. Runs an rsl_rl checkpoint of Kestrel-Navigation-v0
(kestrel train's navigation defaults) on N level-10 episodes of seed 1000004 with a second,
noise-free sensor on the robot that the policy never reads: a 360 x 160-degree ring of 9 x 72 rays
rendered every env-step (it leaves the policy's observations unchanged: the same crashes with and
without it). At each crash, one env-step before it: the direction of the nearest return in the body
frame, the velocity's direction and speed, the yaw rate. Prints histograms; writes CHECKPOINT.crashes.json.

    .venv/bin/python bench/python/navigation_crash_geometry.py CHECKPOINT.pt [N] ['{task.navigation keys}']

The task keys (JSON) are added to the defaults' task.navigation, e.g. '{"action_space": "velocity"}'.
"""
import json
import sys

import numpy as np
import torch

from kestrel.vector_env import make_vec
from kestrel.export import from_rsl_rl
from kestrel.train import _TASK_DEFAULTS

if len(sys.argv) < 2:
    raise SystemExit(__doc__)
pt = sys.argv[1]; n = int(sys.argv[2]) if len(sys.argv) > 2 else 512
task_extra = json.loads(sys.argv[3]) if len(sys.argv) > 3 else {}
d = _TASK_DEFAULTS["Kestrel-Navigation-v0"]
task = json.loads(d["task_set"]); task["navigation"].update(task_extra)
task["curriculum"] = {"start_level": 10, "increase_step": 0, "decrease_step": 0}
ring = {"name": "vl53l5cx", "height": 9, "width": 72, "max_range_m": 10, "every": 1, "horizontal_fov_deg_min": -177.5,
        "horizontal_fov_deg_max": 177.5, "vertical_fov_deg_min": -80, "vertical_fov_deg_max": 80,
        "enable_sensor_noise": False}
sensors = json.loads(d["sensors"]) + [ring]
ck = torch.load(pt, map_location="cpu", weights_only=False)
spec = from_rsl_rl(ck["actor_state_dict"], -1.0, 1.0, squash="tanh")
actor = spec.torch_module()
env = make_vec("Kestrel-Navigation-v0", num_envs=n, seed=1000004, threads=2, task=task, sensors=sensors)
obs, _ = env.reset(seed=1000004)
sim = env.task.simulator
k = sim.num_range_images - 1
rays = sim.range_image_rays(k)
assert all(np.allclose(m, m0) for m, m0 in zip(sim.sensor_mounts(k), ([0, 0, 0], [0, 0, 0, 1])))  # ray directions are body-frame
dirs = rays["dirs_s"].reshape(-1, 3); vs = rays["value_scale_m"]
done = np.zeros(n, bool); rec = []
while not done.all():
    with torch.no_grad():
        a = actor(torch.from_numpy(np.asarray(obs, np.float32))).numpy()
    r = np.asarray(sim.range_images(k), np.float32).reshape(n, -1) * vs
    r = np.where(np.isfinite(r) & (r > 0), r, 99.0)
    j = r.argmin(1)
    v = np.array(env.task.base_lin_vel_b, dtype=np.float64); w = np.array(env.task.base_ang_vel_b, dtype=np.float64)
    snap = (r[np.arange(n), j].copy(), dirs[j].copy(), v, w, a.copy())
    obs, rew, te, tr, info = env.step(a)
    ended = (te | tr) & ~done
    for e in np.nonzero(ended & te)[0]:
        rmin, dd, vv, ww, aa = (s[e] for s in snap)
        rec.append(dict(rmin=float(rmin), az=float(np.degrees(np.arctan2(dd[1], dd[0]))), el=float(np.degrees(np.arcsin(dd[2]))),
                        speed=float(np.linalg.norm(vv)), vaz=float(np.degrees(np.arctan2(vv[1], vv[0]))),
                        vz=float(vv[2]), wz=float(ww[2]), a=aa.tolist()))
    done |= ended
print("crashes", len(rec), "of", n)
az = np.array([x["az"] for x in rec]); el = np.array([x["el"] for x in rec]); vaz = np.array([x["vaz"] for x in rec])
sp = np.array([x["speed"] for x in rec]); wz = np.array([x["wz"] for x in rec])
print("nearest-obstacle azimuth |deg| hist (0-22.5-45-67.5-90-135-180):", np.histogram(np.abs(az), [0, 22.5, 45, 67.5, 90, 135, 180.1])[0])
print("elevation hist (-90,-45,-20,20,45,90):", np.histogram(el, [-90, -45, -20, 20, 45, 90])[0])
print("velocity azimuth |deg| hist (0,10,20,45,90,180):", np.histogram(np.abs(vaz), [0, 10, 20, 45, 90, 180.1])[0])
print("speed median", np.median(sp), "yaw rate |median|", np.median(np.abs(wz)))
print("azimuth of obstacle relative to velocity |deg|:", np.histogram(np.abs((az - vaz + 180) % 360 - 180), [0, 22.5, 45, 67.5, 90, 135, 180.1])[0])
json.dump(rec, open(pt + ".crashes.json", "w"))
