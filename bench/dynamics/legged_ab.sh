#!/bin/sh
# Two builds of kestrel_bench_legged_step side by side (a standing Go2 and ANYmal C, Kestrel's
# constrained step against MuJoCo 2.2 in the same process): the two binaries interleaved, REPS
# times each, pinned to one core. Pack each build first (`legged_ab.sh pack BUILD_DIR CARRY`:
# the binary, every shared library ldd lists, the loader and the models), so the pair runs on
# the device machine as well as here.
#
#   bench/dynamics/legged_ab.sh pack BUILD_DIR CARRY
#   bench/dynamics/legged_ab.sh run CARRY_BASE CARRY_NOW OUT_DIR [REPS] [CORE]   (REPS 12, CORE 0)
#
# Writes OUT_DIR/machine.txt and OUT_DIR/{base,now}_REP.csv (the bench's own CSV), then
# OUT_DIR/summary.csv: per robot and side, the fastest and median Kestrel ns per step and MuJoCo's
# (file defaults) over the repetitions. Figures, never assertions.
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
case "${1:-}" in
  pack)
    b=${2:?usage: legged_ab.sh pack BUILD_DIR CARRY}
    c=${3:?usage: legged_ab.sh pack BUILD_DIR CARRY}
    mkdir -p "$c/lib"
    cp "$b/bench/dynamics/kestrel_bench_legged_step" "$c/"
    cp -r "$root/models" "$c/"
    ldd "$c/kestrel_bench_legged_step" | awk '/=>/ {print $3} /ld-linux/ {print $1}' |
      while read -r l; do [ -f "$l" ] && cp -L "$l" "$c/lib/"; done
    ;;
  run)
    base=${2:?usage: legged_ab.sh run CARRY_BASE CARRY_NOW OUT_DIR [REPS] [CORE]}
    now=${3:?usage: legged_ab.sh run CARRY_BASE CARRY_NOW OUT_DIR [REPS] [CORE]}
    out=${4:?usage: legged_ab.sh run CARRY_BASE CARRY_NOW OUT_DIR [REPS] [CORE]}
    reps=${5:-12}
    core=${6:-0}
    mkdir -p "$out"
    { date -u; lscpu | grep -E "Model name|^CPU\(s\)|Thread|MHz"; } > "$out/machine.txt" 2>&1
    for r in $(seq 1 "$reps"); do
      for side in base now; do
        c=$base
        [ "$side" = now ] && c=$now
        taskset -c "$core" "$c/lib/ld-linux-x86-64.so.2" --library-path "$c/lib" "$c/kestrel_bench_legged_step" \
          --steps 5000 --reps 5 --quiet --models "$c/models" --machine "$side" --csv "$out/${side}_$r.csv" > /dev/null
      done
    done
    python3 - "$out" <<'PY'
import csv, glob, statistics, sys
out = sys.argv[1]
rows = []
for side in ("base", "now"):
    k, mj = {}, {}
    for f in sorted(glob.glob(f"{out}/{side}_*.csv")):
        for r in csv.DictReader(l for l in open(f) if not l.startswith("#")):
            if r["mujoco_config"] != "file_defaults":
                continue
            k.setdefault(r["robot"], []).append(float(r["kestrel_ns_per_step"]))
            mj.setdefault(r["robot"], []).append(float(r["mujoco_ns_per_step"]))
    for robot in k:
        rows.append([side, robot, len(k[robot]), round(min(k[robot]), 1), round(statistics.median(k[robot]), 1),
                     round(min(mj[robot]), 1), round(statistics.median(mj[robot]), 1),
                     round(min(mj[robot]) / min(k[robot]), 3)])
with open(f"{out}/summary.csv", "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["side", "robot", "reps", "kestrel_ns_min", "kestrel_ns_median", "mujoco_ns_min", "mujoco_ns_median", "mujoco_over_kestrel_min"])
    w.writerows(rows)
for r in rows:
    print(*r)
PY
    ;;
  *) echo "usage: legged_ab.sh pack BUILD_DIR CARRY | run CARRY_BASE CARRY_NOW OUT_DIR [REPS] [CORE]" >&2; exit 2 ;;
esac
