#!/bin/sh
# Two builds of `kestrel` side by side on the harness's empty scenario (issue 18): the same
# 4,096- and 65,536-environment runs over 1-16 threads, the two sides interleaved within each
# repetition, pinned to the first T cores. Carries from bench/sim/lanes_carry.sh (binary, its
# shared libraries and loader), so it runs on the device machine as well as here.
#
#   bench/sim/ab_device.sh CARRY_BASE CARRY_NOW OUT_DIR [REPS] [THREADS]   (REPS 3, THREADS "1 2 4 8 16")
#
# Writes OUT_DIR/machine.txt (date, lscpu) and OUT_DIR/runs.csv (side, rep, envs, threads, steps,
# wall_s, env_steps_per_s, state_hash: the two sides must give one hash per size, whatever the
# thread count). Timings are figures, never assertions.
set -u
base=${1:?usage: ab_device.sh CARRY_BASE CARRY_NOW OUT_DIR [REPS] [THREADS]}
now=${2:?usage: ab_device.sh CARRY_BASE CARRY_NOW OUT_DIR [REPS] [THREADS]}
out=${3:?usage: ab_device.sh CARRY_BASE CARRY_NOW OUT_DIR [REPS] [THREADS]}
reps=${4:-3}
threads=${5:-"1 2 4 8 16"}
mkdir -p "$out"
sh "$(dirname "$0")/machine_info.sh" > "$out/machine.txt" 2>&1
scen="$out/empty.yaml"
printf 'env: {name: empty, num_envs: 4096}\n' > "$scen"
echo "side,rep,envs,threads,steps,wall_s,env_steps_per_s,state_hash" > "$out/runs.csv"
n=$(nproc)
run() {  # side carry rep envs threads steps
  t=$5
  [ "$t" -gt "$n" ] && return
  o=$(taskset -c "0-$((t - 1))" "$2/lib/ld-linux-x86-64.so.2" --library-path "$2/lib" "$2/kestrel" run "$scen" \
      --envs "$4" --threads "$t" --steps "$6" --quiet --out "/tmp/ab_$1" 2>&1)
  wall=$(printf '%s\n' "$o" | sed -n 's/.*wall time \([0-9.]*\) s, \([0-9.e+]*\) env-steps.*/\1,\2/p')
  hash=$(printf '%s\n' "$o" | sed -n 's/^state hash: //p')
  echo "$1,$3,$4,$t,$6,$wall,$hash" >> "$out/runs.csv"
}
for r in $(seq 1 "$reps"); do
  for t in $threads; do
    for side in base now; do
      c=$base
      [ "$side" = now ] && c=$now
      run "$side" "$c" "$r" 4096 "$t" 6000
      run "$side" "$c" "$r" 65536 "$t" 400
    done
  done
done
grep -E 'Model name|^nproc|UTC' "$out/machine.txt"
column -s, -t < "$out/runs.csv" 2>/dev/null || cat "$out/runs.csv"
