#!/bin/sh
# The SO-101 pick-and-place bench in one run (issue 14): Kestrel's scripted pick and place over
# 1000 randomised resets (success rate, physics steps/s with the grasp contacts on one core, the
# worlds batched and one at a time, interleaved in one run), then
# MuJoCo 3 replaying Kestrel's first episode on the same scene (bench/manipulation/mujoco_side_by_side.py),
# then the cameras; the figures land in bench/results/manipulation/ and side_by_side.csv holds the ratio.
#   bench/manipulation/side_by_side.sh [build dir=build/host] [episodes=1000]
set -eu
cd "$(dirname "$0")/../.."
BUILD="${1:-build/host}"
EPISODES="${2:-1000}"
OUT=bench/results/manipulation
mkdir -p "$OUT"
cmake --build "$BUILD" --target kestrel_bench_pick_place kestrel_bench_pick_place_camera -j2 >/dev/null
K=$("$BUILD"/bench/manipulation/kestrel_bench_pick_place "$EPISODES" 1 "$OUT/pick_place_episodes.csv" "$OUT/episode0_trace.csv")
echo "$K"
.venv/bin/python bench/manipulation/mujoco_side_by_side.py "$OUT/episode0_trace.csv" "$OUT/mujoco_side_by_side.csv"
"$BUILD"/bench/manipulation/kestrel_bench_pick_place_camera 3 "$OUT" "$OUT/pick_place_camera.csv"
.venv/bin/python - "$K" "$OUT" <<'PY'
import csv, re, sys, datetime, platform
line, out = sys.argv[1], sys.argv[2]
succ, total = map(int, re.search(r"(\d+)/(\d+) successes", line).groups())
k_sps = float(re.search(r"physics (\d+) steps/s on one core batched", line).group(1))
k_one = float(re.search(r"(\d+) steps/s one world at a time", line).group(1))
worlds = int(re.search(r"batched \((\d+) worlds", line).group(1))
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), platform.processor())
rows = list(csv.DictReader(open(f"{out}/mujoco_side_by_side.csv")))
with open(f"{out}/side_by_side.csv", "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["date", "cpu", "engine", "setting", "physics_steps_per_s_one_core", "kestrel_over_engine", "cube_lifted_m", "cube_in_box", "scripted_success"])
    w.writerow([datetime.date.today(), cpu, "kestrel", f"PGS 60 sweeps, dt 5 ms, {worlds} worlds batched", round(k_sps), 1.0, "", "", f"{succ}/{total}"])
    w.writerow([datetime.date.today(), cpu, "kestrel", "PGS 60 sweeps, dt 5 ms, one world at a time", round(k_one), round(k_one / k_sps, 2), "", "",
                "the same episodes, bit-identical"])
    for r in rows:
        m = float(r["physics_steps_per_s"])
        w.writerow([datetime.date.today(), cpu, r["engine"], f'{r["integrator"]} {r["cone"]} impratio {r["impratio"]}', round(m),
                    round(k_sps / m, 2), r["cube_z_at_lift_end_m"], r["cube_in_box"], "replay of episode 0"])
print(open(f"{out}/side_by_side.csv").read())
PY
