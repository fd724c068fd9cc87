#!/bin/sh
# Issue 18 on a many-core machine: the harness's empty scenario with each copy of the batched robot
# step (KESTREL_BATCH_KERNEL=baseline|avx2|avx512: 4, 8 and 16 lanes; the same bits) over 1-16
# threads at 4,096 and 65,536 environments, copies interleaved within each repetition, then
# kestrel_bench_sim's per-copy rows on one pinned core. Binaries from bench/sim/lanes_carry.sh.
#
#   bench/sim/lanes_device.sh CARRY OUT_DIR [REPS] [THREADS]      (REPS 3, THREADS "1 2 4 8 16")
#   COPIES (default "baseline avx2 avx512"), STEPS_4096 / STEPS_65536 (default 6000 / 400: the
#   steps of the hashes recorded since 2026-11-27; ten times that for a scaling study, where the
#   16-thread runs of the defaults last only 0.06 s), BENCH=0 skips kestrel_bench_sim.
#
# Writes OUT_DIR/machine.txt (date, lscpu), runs.csv (copy, rep, envs, threads, steps, wall_s,
# env_steps_per_s, state_hash: one value per size for every copy and thread count, or the
# results depend on them), bench.csv / bench.txt. Timings are figures, never assertions.
set -u
c=${1:?usage: lanes_device.sh CARRY OUT_DIR [REPS] [THREADS]}
out=${2:?usage: lanes_device.sh CARRY OUT_DIR [REPS] [THREADS]}
reps=${3:-3}
threads=${4:-"1 2 4 8 16"}
copies=${COPIES:-baseline avx2 avx512}
mkdir -p "$out"
ld="$c/lib/ld-linux-x86-64.so.2 --library-path $c/lib"
sh "$(dirname "$0")/machine_info.sh" > "$out/machine.txt" 2>&1
scen="$out/empty.yaml"
printf 'env: {name: empty, num_envs: 4096}\n' > "$scen"
echo "copy,rep,envs,threads,steps,wall_s,env_steps_per_s,state_hash,robot_step" > "$out/runs.csv"
n=$(nproc)
run() {  # copy rep envs threads steps
  t=$4
  [ "$t" -gt "$n" ] && return
  cpus=0-$((t - 1))
  o=$(KESTREL_BATCH_KERNEL=$1 taskset -c "$cpus" $ld "$c/kestrel" run "$scen" --envs "$3" --threads "$t" --steps "$5" \
      --quiet --out "/tmp/lanes_$1" 2>&1)
  wall=$(printf '%s\n' "$o" | sed -n 's/.*wall time \([0-9.]*\) s, \([0-9.e+]*\) env-steps.*/\1,\2/p')
  hash=$(printf '%s\n' "$o" | sed -n 's/^state hash: //p')
  rs=$(printf '%s\n' "$o" | sed -n 's/^  robot step: //p' | tr ',' ';')
  echo "$1,$2,$3,$t,$5,$wall,$hash,$rs" >> "$out/runs.csv"
}
for r in $(seq 1 "$reps"); do
  for t in $threads; do
    for k in $copies; do
      # The same steps for every thread count, so each size has one state hash (~25 M env-steps:
      # ~5 s on one Xeon thread, ~0.5 s on 16).
      run "$k" "$r" 4096 "$t" "${STEPS_4096:-6000}"
      run "$k" "$r" 65536 "$t" "${STEPS_65536:-400}"
    done
  done
done
[ "${BENCH:-1}" = 1 ] && taskset -c 2 $ld "$c/kestrel_bench_sim" --quick --reps 5 --csv "$out/bench.csv" > "$out/bench.txt" 2>&1
grep -E 'Model name|^nproc|UTC' "$out/machine.txt"
column -s, -t < "$out/runs.csv" 2>/dev/null || cat "$out/runs.csv"
[ "${BENCH:-1}" = 1 ] && grep -A9 'kernel copies' "$out/bench.txt"
