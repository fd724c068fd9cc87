#!/bin/sh
# Issue 18, second half of the Intel-core measurement: how fast and how steady the core's clock is
# while `kestrel run` steps on it. Same carried layout as intel_core.sh (CARRY/lib with the loader,
# CARRY/kestrel_cpu_probe, CARRY/before/kestrel, optionally CARRY/perf/perf).
#
#   bench/sim/intel_core_clock.sh CARRY OUT_DIR
#
# Writes OUT_DIR/clock.txt (clock samples: on one core, on each core in turn, on all cores at
# once; perf stat if the machine exposes counters) and OUT_DIR/clock_runs.csv (`kestrel run`, empty
# scenario, 4,096 environments, 1 thread, pinned, each run between two clock samples on its
# core). The clock is a chain of dependent integer multiplies (3 cycles each on both vendors).
# Timings are figures, never assertions.
set -u
c=${1:?usage: intel_core_clock.sh CARRY OUT_DIR}
out=${2:?usage: intel_core_clock.sh CARRY OUT_DIR}
core=${CORE:-2}
runs=${RUNS:-8}
steps=${STEPS:-2000}
mkdir -p "$out"
ld="$c/lib/ld-linux-x86-64.so.2 --library-path $c/lib"
probe="$ld $c/kestrel_cpu_probe"
n=$(nproc)
scen="$out/empty.yaml"
printf 'env: {name: empty, num_envs: 4096}\n' > "$scen"
ghz() { taskset -c "$1" $probe --ghz "$2" 20 | sed 's/^ghz min \([0-9.]*\) median \([0-9.]*\) max \([0-9.]*\).*/\1 \2 \3/'; }
{
  date -u '+%Y-%m-%d %H:%M:%S UTC'
  grep -m1 'model name' /proc/cpuinfo
  echo "== perf stat (hardware counters, if exposed)"
  if [ -x "$c/perf/perf" ]; then
    taskset -c "$core" $ld "$c/perf/perf" stat -e cycles,instructions,task-clock -- $ld "$c/before/kestrel" run "$scen" --threads 1 \
      --steps "$steps" --quiet --out /tmp/icc_perf 2>&1 | grep -E 'cycles|instructions|task-clock|wall time|not supported|rror'
  fi
  echo "== clock on core $core: 50 samples of 20 ms"
  taskset -c "$core" $probe --ghz 50 20
  echo "== clock on each core in turn (min median max of 10 x 20 ms)"
  k=0
  while [ "$k" -lt "$n" ]; do
    echo "core $k: $(ghz "$k" 10)"
    k=$((k + 1))
  done
  echo "== clock on all $n cores at once (min median max of 10 x 20 ms)"
  k=0
  while [ "$k" -lt "$n" ]; do
    ghz "$k" 10 > "/tmp/icc_all_$k" &
    k=$((k + 1))
  done
  wait
  k=0
  while [ "$k" -lt "$n" ]; do
    echo "core $k: $(cat "/tmp/icc_all_$k")"
    k=$((k + 1))
  done
} > "$out/clock.txt" 2>&1
echo "run,core,envs,threads,steps,wall_s,env_steps_per_s,ghz_before_min,ghz_before_median,ghz_before_max,ghz_after_min,ghz_after_median,ghz_after_max" > "$out/clock_runs.csv"
one() {  # run-label core
  g0=$(ghz "$2" 5 | tr ' ' ',')
  o=$(taskset -c "$2" $ld "$c/before/kestrel" run "$scen" --threads 1 --steps "$steps" --quiet --out /tmp/icc_run 2>&1)
  g1=$(ghz "$2" 5 | tr ' ' ',')
  wall=$(printf '%s\n' "$o" | sed -n 's/.*wall time \([0-9.]*\) s, \([0-9.e+]*\) env-steps.*/\1,\2/p')
  echo "$1,$2,4096,1,$steps,$wall,$g0,$g1" >> "$out/clock_runs.csv"
}
i=1
while [ "$i" -le "$runs" ]; do
  one "$i" "$core"
  i=$((i + 1))
done
# The same on other cores, two runs each.
for k in ${OTHER_CORES:-0 5 9 13}; do
  [ "$k" -lt "$n" ] || continue
  one "c$k.1" "$k"
  one "c$k.2" "$k"
done
cat "$out/clock.txt"
cat "$out/clock_runs.csv"
