#!/bin/sh
# Issue 12's scaling figure: a Go2 on flat ground under random joint targets (task joint_targets:
# legged_gym's dt 5 ms, decimation 4, the joint PD, four foot contacts, resets on base contact)
# from 256 to 65,536 environments, 1 and 2 threads, through `kestrel run`. Writes
# bench/results/host/legged_scaling.csv: wall time, env-steps/s, ns per physics step per
# environment, and the state hash, which must be the same for 1 and 2 threads at each size.
# Cost per physics step flat within +-20 % over the sizes is the goal. Timings are figures.
# Each run twice: the batched constrained step (the default: several robots per SIMD step,
# sim/src/backends/articulated_batch.hpp) and the scalar step for every robot
# (KESTREL_LEGGED_BATCH=off), interleaved; both must give the same hash.
#
#   bench/dynamics/legged_scaling.sh [KESTREL_BINARY] [OUT_CSV]
set -eu
bin=${1:-build/host/sim/kestrel}
out=${2:-bench/results/host/legged_scaling.csv}
scen=$(cd "$(dirname "$0")" && pwd)/go2_joint_targets.yaml
note="$(date -u '+%Y-%m-%d %H:%M UTC'), load average $(cut -d' ' -f1 /proc/loadavg) at start, $(nproc)-core $(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //')"
echo "envs,threads,step,env_steps,wall_s,env_steps_per_s,ns_per_physics_step_per_env,state_hash,note" > "$out"
for envs in 256 1024 4096 16384 65536; do
  # The same 10 env-steps (40 physics steps, from the spawn) at every size: the cost per step
  # depends on the episode's phase (robots landing, then stepping under new targets), so sizes
  # are compared over the same phase.
  steps=10
  for t in 1 2; do
   for step in batched scalar; do
    batch=on
    [ "$step" = scalar ] && batch=off
    o=$(KESTREL_LEGGED_BATCH=$batch "$bin" run "$scen" --envs "$envs" --threads "$t" --steps "$steps" --quiet --out /tmp/legged_scaling_out 2>&1)
    wall=$(printf '%s\n' "$o" | sed -n 's/.*wall time \([0-9.]*\) s, \([0-9.e+]*\) env-steps.*/\1,\2/p')
    hash=$(printf '%s\n' "$o" | sed -n 's/^state hash: //p')
    rate=${wall#*,}
    ns=$(awk -v r="$rate" -v t="$t" 'BEGIN { printf "%.1f", 1e9 * t / (r * 4) }')
    echo "$envs,$t,$step,$((envs * steps)),$wall,$ns,$hash,\"$note\"" >> "$out"
    echo "envs $envs threads $t $step: $wall (ns per physics step per env per thread: $ns) hash $hash"
   done
  done
done
awk -F, 'NR > 1 { k = $2 " threads, " $3; n[k]++; s[k] += $7; v[k, n[k]] = $7; h[$1] = h[$1] == "" ? $8 : h[$1]; if (h[$1] != $8) bad = 1 }
         END { for (t in n) { m = s[t] / n[t]; w = 0; for (i = 1; i <= n[t]; i++) { d = v[t, i] / m - 1; if (d < 0) d = -d; if (d > w) w = d }
               printf "%s: %.0f ns per physics step per env per thread, within +-%.0f%% of it over the sizes (goal +-20%%)\n", t, m, 100 * w }
               if (bad) { print "state hashes differ between thread counts or steps"; exit 1 } }' "$out"
