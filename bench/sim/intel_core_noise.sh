#!/bin/sh
# Issue 18, third part of the Intel-core measurement: does the one-thread rate move with the size of
# the world (cache / memory contention) or with the core (a busy sibling hyperthread of another
# tenant), while the clock stays put? Rounds of: a clock sample (latency-bound multiply chain), a
# throughput sample (independent multiplies; the legacy-SSE loop), then `kestrel run` of the empty
# scenario, 1 thread, on the same core at 256 (fits in L2), 4,096 and 65,536 environments, ~4 M
# env-steps each. Same carried layout as intel_core.sh.
#
#   bench/sim/intel_core_noise.sh CARRY OUT_DIR
#
# Writes OUT_DIR/noise.csv (with the core's busy and steal ticks from /proc/stat over the three
# runs: steal is time the hypervisor ran something else on that virtual CPU). Timings are figures,
# never assertions.
set -u
c=${1:?usage: intel_core_noise.sh CARRY OUT_DIR}
out=${2:?usage: intel_core_noise.sh CARRY OUT_DIR}
core=${CORE:-2}
rounds=${ROUNDS:-12}
mkdir -p "$out"
ld="$c/lib/ld-linux-x86-64.so.2 --library-path $c/lib"
probe="$ld $c/kestrel_cpu_probe"
scen="$out/empty.yaml"
printf 'env: {name: empty, num_envs: 4096}\n' > "$scen"
echo "round,core,ghz_median,mul_per_ns_median,sse_ns_median,rate_256,rate_4096,rate_65536,busy_ticks,steal_ticks" > "$out/noise.csv"
# /proc/stat's line for the core: user nice system idle iowait irq softirq steal (ticks of 10 ms).
ticks() { awk -v c="cpu$core" '$1 == c {print $2 + $3 + $4 + $7 + $8, $9}' /proc/stat; }
rate() {  # envs steps
  taskset -c "$core" $ld "$c/before/kestrel" run "$scen" --envs "$1" --threads 1 --steps "$2" --quiet --out /tmp/icn 2>&1 |
    sed -n 's/.*wall time [0-9.]* s, \([0-9.e+]*\) env-steps.*/\1/p'
}
i=1
while [ "$i" -le "$rounds" ]; do
  g=$(taskset -c "$core" $probe --ghz 5 20 | sed 's/^ghz min [0-9.]* median \([0-9.]*\).*/\1/')
  t=$(taskset -c "$core" $probe --tput 5 20 | sed 's/^mul_per_ns min [0-9.]* median \([0-9.]*\) max [0-9.]*; sse_ns_per_iter min [0-9.]* median \([0-9.]*\).*/\1,\2/')
  set -- $(ticks)
  b0=$1 s0=$2
  r1=$(rate 256 16000)
  r2=$(rate 4096 1000)
  r3=$(rate 65536 64)
  set -- $(ticks)
  echo "$i,$core,$g,$t,$r1,$r2,$r3,$(($1 - b0)),$(($2 - s0))" >> "$out/noise.csv"
  i=$((i + 1))
done
cat "$out/noise.csv"
