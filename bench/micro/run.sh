#!/bin/sh
# Host micro-benchmarks: builds kestrel_bench_micro, runs it (3 repetitions, median kept), writes
#   bench/results/host/micro.csv          ns per call and calls/s per function x airframe x batch
#   bench/results/host/micro_context.txt  date, CPU, caches, load, the note below
# and re-renders bench/results/report.md (+ host/micro.png) with bench/control/render.py.
#
#   bench/micro/run.sh [build dir (default build/host)] [note, e.g. "machine shared with builds"]
#   bench/micro/run.sh --smoke <kestrel_bench_micro> <out dir>    (ctest bench_micro_smoke)
#
# Timings depend on the machine and on what else runs on it: say so in the note. Smoke mode runs
# every benchmark once at a tiny time budget and checks the conversion (all rows present); it
# writes only into <out dir>.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
# The project's .venv (matplotlib for render.py's charts) when there, else python3 (PYTHON overrides).
py=${PYTHON:-python3}
[ -z "${PYTHON:-}" ] && [ -x "$root/.venv/bin/python" ] && py="$root/.venv/bin/python"

if [ "${1:-}" = "--smoke" ]; then
  exe=${2:?usage: run.sh --smoke <kestrel_bench_micro> <out dir>}
  out=${3:?usage: run.sh --smoke <kestrel_bench_micro> <out dir>}
  mkdir -p "$out"
  "$exe" --benchmark_min_time=0.0001 --benchmark_repetitions=1 \
    --benchmark_out="$out/micro.json" --benchmark_out_format=json > "$out/console.txt"
  "$py" "$here/to_csv.py" "$out/micro.json" "$out/micro.csv" --note "smoke run" --args "smoke"
  exit 0
fi

build=${1:-$root/build/host}
note=${2:-"not given"}
cmake --build "$build" -j 2 --target kestrel_bench_micro
exe="$build/bench/micro/kestrel_bench_micro"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
args="--benchmark_min_time=0.2 --benchmark_repetitions=3 --benchmark_report_aggregates_only=true"
# shellcheck disable=SC2086
"$exe" $args --benchmark_out="$tmp/micro.json" --benchmark_out_format=json
mkdir -p "$root/bench/results/host"
"$py" "$here/to_csv.py" "$tmp/micro.json" "$root/bench/results/host/micro.csv" --note "$note" --args "$args"
"$py" "$root/bench/control/render.py"
