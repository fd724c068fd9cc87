#!/bin/sh
# A legged robot's full physics step on flat ground side by side with MuJoCo (bench_legged_step.cpp):
# builds kestrel_bench_legged_step in build/host (the project's default float build; MuJoCo in
# double, Debian's libmujoco 2.2.2 and the PyPI wheel's from .venv, python/requirements.txt's pin)
# and runs it pinned to one core.
#
#   bench/dynamics/run_legged.sh [CSV] [CORE] [MACHINE]
#     (default bench/results/host/legged_step_side_by_side.csv, core 0, machine label "host (the project's shared 2-core dev machine)")
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
csv=${1:-bench/results/host/legged_step_side_by_side.csv}
core=${2:-0}
machine=${3:-"host (the project's shared 2-core dev machine)"}
cmake --preset host > /dev/null
cmake --build build/host -j 2 --target kestrel_bench_legged_step
pin=""
command -v taskset > /dev/null && pin="taskset -c $core" && machine="$machine, pinned to core $core"
$pin build/host/bench/dynamics/kestrel_bench_legged_step --steps 5000 --reps 7 --machine "$machine" --csv "$csv"
