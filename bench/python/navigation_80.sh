#!/bin/sh
# Issue 11's navigation_task goal (>= 80 % success at the obstacle curriculum's top level, on >= 1000
# episodes from seeds not used in training), the recipe of stop 45 (run m30l20r512 in
# bench/results/python/navigation_sweep.csv, figures in bench/results/python/README.md):
#
#  1. 32 M env-steps of `kestrel train Kestrel-Navigation-v0` with 256 environments, the training
#     robot's collision sphere 0.3 m instead of 0.2 m (navigation_margin.py: a crash in training
#     comes 0.1 m early; evaluations keep the task's 0.2 m), and the two earlier images of the
#     observation 0.2 and 0.4 s back (image_history_lag_env_steps 20 instead of 10);
#  2. 32 M more from its last checkpoint with 512 environments (twice the samples per update; phase 1
#     alone ends at 75.7 %, and 1024 environments in phase 2 gave 79.2 % after 24 M);
#  3. the last checkpoint on 1024 episodes of seed 1000004 (train.py's final evaluation) and, as a
#     second unseen sample, 1024 of seed 1000005.
#
# Each training phase runs on one simulator thread (about 21 min of learner + simulator time each on
# the 2-core machine; the two phases are sequential). Deterministic: the same seed gives the same
# evaluations for any thread count.
#
#   bench/python/navigation_80.sh [OUT_DIR]     (default runs/nav80)
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
out=${1:-runs/nav80}
py=.venv/bin/python
task='{"navigation": {"image_encoding": "proximity", "proximity_scale_m": 0.5, "image_history_frames": 2, "image_history_lag_env_steps": 20}}'
train() {  # navigation_margin.py 0.3 with the common arguments, then the caller's
  "$py" bench/python/navigation_margin.py 0.3 -- Kestrel-Navigation-v0 --threads 1 --export 0 --task-set "$task" "$@"
}
train --eval-episodes 512 --final-eval-episodes 1024 --out "$out/phase1"
ck1=$(ls "$out"/phase1/checkpoints/rsl_rl_*.pt | sed 's/.*rsl_rl_\([0-9]*\)\.pt/\1 &/' | sort -n | tail -1 | cut -d' ' -f2)
train --eval-episodes 512 --final-eval-episodes 1024 --envs 512 --steps 32000000 --eval-every 2000000 \
  --resume "$ck1" --out "$out/phase2"
ck2=$(ls "$out"/phase2/checkpoints/rsl_rl_*.pt | sed 's/.*rsl_rl_\([0-9]*\)\.pt/\1 &/' | sort -n | tail -1 | cut -d' ' -f2)
# The second unseen sample: --steps 0 only loads the checkpoint; the final evaluation's seed is
# --eval-seed + 1. --export 1 writes the policy's ONNX file and firmware header beside it.
train --eval-episodes 16 --eval-seed 1000004 --final-eval-episodes 1024 --envs 512 --steps 0 --resume "$ck2" \
  --out "$out/seed1000005" --export 1 --quiet
"$py" - "$out" <<'EOF'
import json, sys
out = sys.argv[1]
for name, seed in (("phase2", 1000004), ("seed1000005", 1000005)):
    f = json.load(open(f"{out}/{name}/summary.json"))["final_eval"]
    print(f"seed {seed}, {f['episodes']} episodes: success {100 * f['success_rate']:.1f} %, crashes {100 * f['crash_rate']:.1f} %")
EOF
