#!/bin/sh
# Issue 18: how far can anything scale on this machine's cores? The same compute-bound probe
# (kestrel_cpu_probe --tput: independent integer multiplies, and the legacy-SSE float loop) run as
# T copies at once, one pinned to each of the first T cores, for T = 1, 2, 4, 8, 16: the sum of
# their rates over T = 1's rate is the most any code without shared data can scale here (virtual
# CPUs that are hyperthreads of one physical core, or a host shared with other tenants, hold it
# below T). Compare with the harness's 1 -> 16 threads (ab_device.sh, lanes_device.sh).
#
#   bench/sim/core_scaling.sh CARRY OUT_DIR [ROUNDS] [THREADS]      (ROUNDS 3, THREADS "1 2 4 8 16")
#
# CARRY holds kestrel_cpu_probe with lib/ (bench/sim/lanes_carry.sh, plus the probe). Writes
# OUT_DIR/scaling.csv (round, copies, core, mul_per_ns_median, sse_ns_per_iter_median) and
# OUT_DIR/speedup.csv (round, copies, the copies' summed multiply rate over one copy's).
# Timings are figures, never assertions.
set -u
c=${1:?usage: core_scaling.sh CARRY OUT_DIR [ROUNDS] [THREADS]}
out=${2:?usage: core_scaling.sh CARRY OUT_DIR [ROUNDS] [THREADS]}
rounds=${3:-3}
threads=${4:-"1 2 4 8 16"}
mkdir -p "$out"
n=$(nproc)
echo "round,copies,core,mul_per_ns_median,sse_ns_per_iter_median" > "$out/scaling.csv"
for r in $(seq 1 "$rounds"); do
  for t in $threads; do
    [ "$t" -gt "$n" ] && continue
    k=0
    while [ "$k" -lt "$t" ]; do
      taskset -c "$k" "$c/lib/ld-linux-x86-64.so.2" --library-path "$c/lib" "$c/kestrel_cpu_probe" --tput 5 200 > "$out/p_$k.txt" 2>&1 &
      k=$((k + 1))
    done
    wait
    k=0
    while [ "$k" -lt "$t" ]; do
      sed -n "s/^mul_per_ns min [0-9.]* median \([0-9.]*\) .*sse_ns_per_iter min [0-9.]* median \([0-9.]*\) .*/$r,$t,$k,\1,\2/p" "$out/p_$k.txt" >> "$out/scaling.csv"
      k=$((k + 1))
    done
  done
done
rm -f "$out"/p_*.txt
# Per copy count: the summed multiply rate over one copy's (median over rounds).
awk -F, 'NR > 1 { s[$1 "," $2] += $4; if ($2 == 1) one[$1] = $4 }
  END { for (k in s) { split(k, a, ","); printf "%s,%s,%.3f\n", a[1], a[2], s[k] / one[a[1]] } }' "$out/scaling.csv" |
  sort -t, -k2,2n -k1,1n > "$out/speedup.tmp"
{ echo "round,copies,summed_mul_rate_over_one_copy"; cat "$out/speedup.tmp"; } > "$out/speedup.csv"
rm -f "$out/speedup.tmp"
cat "$out/speedup.csv"
