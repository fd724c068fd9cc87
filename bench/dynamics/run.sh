#!/bin/sh
# The core's articulated-body dynamics side by side with Pinocchio (bench_dynamics.cpp): configures
# build/bench-pin with KESTREL_BENCH_PINOCCHIO=ON (Pinocchio from the pin wheel in .venv, which
# scripts/deps.sh installs; its headers take about 90 s of one core to compile), builds
# kestrel_bench_dynamics there and runs it pinned to one core.
#
#   bench/dynamics/run.sh [CSV] [CORE]     (default bench/results/host/dynamics_side_by_side.csv, core 0)
#
# Then the same program in float (kestrel_bench_dynamics_f32: Kestrel's rows, the 4-lane batched
# ABA in SSE2's four-float registers) into CSV's name with _f32 before .csv.
#
# The committed figures of bench/results/device/dynamics_side_by_side.csv were taken with the
# binary built so and run on the device machine (its 16-core Xeon) with its two shared libraries.
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
csv=${1:-bench/results/host/dynamics_side_by_side.csv}
core=${2:-0}
cmake --preset host -B build/bench-pin -DKESTREL_BENCH_PINOCCHIO=ON > /dev/null
cmake --build build/bench-pin --target kestrel_bench_dynamics kestrel_bench_dynamics_f32
pin=""
command -v taskset > /dev/null && pin="taskset -c $core"
$pin build/bench-pin/bench/dynamics/kestrel_bench_dynamics --calls 200000 --reps 7 --csv "$csv"
$pin build/bench-pin/bench/dynamics/kestrel_bench_dynamics_f32 --calls 200000 --reps 7 --csv "${csv%.csv}_f32.csv"
