#!/bin/sh
# Issue 18 at the H200 torch step's peak size: `kestrel run` of the empty scenario with 1,048,576
# environments on 1 and T threads (pinned to the first cores), REPS repetitions, the same steps
# for both so the state hash must agree. Binaries from bench/sim/lanes_carry.sh.
#
#   bench/sim/million_device.sh CARRY OUT_DIR [REPS] [THREADS] [STEPS]   (3, 16, 200)
#
# Writes OUT_DIR/million.csv (rep, envs, threads, steps, wall_s, env_steps_per_s, state_hash) and
# OUT_DIR/machine.txt. Timings are figures, never assertions.
set -u
c=${1:?usage: million_device.sh CARRY OUT_DIR [REPS] [THREADS] [STEPS]}
out=${2:?usage: million_device.sh CARRY OUT_DIR [REPS] [THREADS] [STEPS]}
reps=${3:-3}
threads=${4:-16}
steps=${5:-200}
mkdir -p "$out"
sh "$(dirname "$0")/machine_info.sh" > "$out/machine.txt" 2>&1
ld="$c/lib/ld-linux-x86-64.so.2 --library-path $c/lib"
scen=$(mktemp)
printf 'env: {name: empty, num_envs: 4096}\n' > "$scen"
echo "rep,envs,threads,steps,wall_s,env_steps_per_s,state_hash" > "$out/million.csv"
for r in $(seq 1 "$reps"); do
  for t in 1 "$threads"; do
    o=$(taskset -c "0-$((t - 1))" $ld "$c/kestrel" run "$scen" --envs 1048576 --threads "$t" --steps "$steps" --quiet \
        --out /tmp/million_out 2>&1)
    w=$(printf '%s\n' "$o" | sed -n 's/.*wall time \([0-9.]*\) s, \([0-9.e+]*\) env-steps.*/\1,\2/p')
    h=$(printf '%s\n' "$o" | sed -n 's/^state hash: //p')
    echo "$r,1048576,$t,$steps,$w,$h" >> "$out/million.csv"
  done
done
rm -f "$scen"
cat "$out/million.csv"
