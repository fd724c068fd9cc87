#!/bin/sh
# Side by side: the harness bench (kestrel_bench_sim) and the task bench (kestrel_bench_task) of a
# base commit and of this tree, in interleaved pairs pinned to two cores, in one run (issue 10:
# "measured side by side against the commit before the redesign"). Timings are figures, never
# assertions.
#
#   bench/sim/side_by_side.sh BASE_COMMIT [PAIRS] [OUT_DIR]
#
# Environment: ONLY=SUBSTRING passes --only to the task bench; BASE_BIN=DIR NOW_BIN=DIR run
# prebuilt binaries (DIR/kestrel_bench_sim, DIR/kestrel_bench_task; DIR/lib on LD_LIBRARY_PATH)
# instead of building, e.g. on the device machine, which has no compiler packages; PIN=CPUS the
# cores to pin to (default 0,1).
#
# Builds BASE in a git worktree under build/side_by_side/ (bench targets only; a base without
# bench_task.cpp gets today's copy), then writes OUT_DIR/harness.csv and OUT_DIR/task.csv with one
# row per (side, pair, case) and OUT_DIR/summary.csv with medians and best-of ratios
# (bench/sim/side_by_side_summary.py). The figures in bench/results/device/ were taken this way on
# the device machine (16-core Xeon, binaries and their shared libraries copied there).
set -eu
base=${1:?usage: side_by_side.sh BASE_COMMIT [PAIRS] [OUT_DIR]}
pairs=${2:-10}
out=${3:-build/side_by_side/out}
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
mkdir -p "$out"
if [ -n "${BASE_BIN:-}" ] && [ -n "${NOW_BIN:-}" ]; then
  base_dir=$BASE_BIN
  now_dir=$NOW_BIN
  export LD_LIBRARY_PATH="$BASE_BIN/lib:$NOW_BIN/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
else
  wt=build/side_by_side/base
  mkdir -p build/side_by_side
  [ -d "$wt" ] || git worktree add --detach "$wt" "$base"
  [ -f "$wt/bench/sim/bench_task.cpp" ] || { cp bench/sim/bench_task.cpp "$wt/bench/sim/"; printf '%s\n' \
    'add_executable(kestrel_bench_task bench_task.cpp)' 'target_link_libraries(kestrel_bench_task PRIVATE kestrel_sim kestrel_flags)' \
    >> "$wt/bench/sim/CMakeLists.txt"; }
  (cd "$wt" && cmake --preset host >/dev/null && cmake --build --preset host --target kestrel_bench_sim kestrel_bench_task)
  cmake --build --preset host --target kestrel_bench_sim kestrel_bench_task
  base_dir=$wt/build/host/bench/sim
  now_dir=build/host/bench/sim
fi
only=""
[ -n "${ONLY:-}" ] && only="--only $ONLY"
pin="taskset -c ${PIN:-0,1}"
command -v taskset >/dev/null || pin=""
echo "side,pair,case,envs,threads,env_steps_per_s,ns_per_env_step,note" > "$out/harness.csv"
echo "side,pair,task,controller,backend,envs,threads,ns_per_env_step" > "$out/task.csv"
start=$(date +%s)
for i in $(seq 1 "$pairs"); do
  for side in base now; do
    # A progress line on a terminal (issue 15): runs done of 2 x pairs, elapsed, time left at the
    # mean pace so far; nothing when stderr is a file or a pipe, or with QUIET=1.
    if [ -t 2 ] && [ "${QUIET:-0}" != 1 ]; then
      done_runs=$(( (i - 1) * 2 + $([ "$side" = base ] && echo 0 || echo 1) ))
      el=$(( $(date +%s) - start ))
      left="?"
      [ "$done_runs" -gt 0 ] && left=$(( el * (2 * pairs - done_runs) / done_runs ))
      printf '\r  side by side: run %d of %d (pair %d, %s), %d s elapsed, %s s left\033[K' \
        "$((done_runs + 1))" "$((2 * pairs))" "$i" "$side" "$el" "$left" >&2
    fi
    dir=$([ "$side" = base ] && echo "$base_dir" || echo "$now_dir")
    $pin "$dir/kestrel_bench_sim" --quick --reps 7 --csv "$out/r.csv" >/dev/null
    tail -n +2 "$out/r.csv" | sed "s/^/$side,$i,/" >> "$out/harness.csv"
    # shellcheck disable=SC2086
    $pin "$dir/kestrel_bench_task" --reps 2 $only | grep -E '^[a-z_]+,' | grep -v '^task,' | sed "s/^/$side,$i,/" >> "$out/task.csv"
  done
done
if [ -t 2 ] && [ "${QUIET:-0}" != 1 ]; then printf '\r  side by side: %d runs in %d s\033[K\n' "$((2 * pairs))" "$(( $(date +%s) - start ))" >&2; fi
python3 bench/sim/side_by_side_summary.py "$out"
