#!/bin/sh
# Issue 18, "why is one Intel core ~3x slower than one AMD core": the device machine's side of the
# measurement, in one run. Prebuilt binaries (built on the 2-core machine, copied with their
# shared libraries and loader, run through that loader so the device's own libc does not matter):
#
#   CARRY/lib/                 ld-linux-x86-64.so.2 and every library `ldd` lists
#   CARRY/kestrel_cpu_probe    bench/sim/cpu_probe.cpp (g++ -O2 -pthread)
#   CARRY/xinuse_preload.so    bench/sim/xinuse_preload.c: XINUSE of the main thread at start and exit
#   CARRY/<variant>/kestrel, CARRY/<variant>/kestrel_bench_sim   for each variant named in VARIANTS
#
#   bench/sim/intel_core.sh CARRY OUT_DIR [PAIRS]
#
# Writes OUT_DIR/machine.txt (date, lscpu, flags), probe.txt, runs.csv (`kestrel run` of the empty
# scenario, variants interleaved in each pair: 1 thread pinned to one core at 4,096 and 65,536
# environments, then 1-16 threads; the state hash of every run, which must not depend on the variant
# or the thread count), bench_<variant>.csv and .txt (kestrel_bench_sim: the per-stage split).
# Timings are figures, never assertions.
set -u
c=${1:?usage: intel_core.sh CARRY OUT_DIR [PAIRS]}
out=${2:?usage: intel_core.sh CARRY OUT_DIR [PAIRS]}
pairs=${3:-3}
variants=${VARIANTS:-before after}
core=${CORE:-2}
mkdir -p "$out"
ld="$c/lib/ld-linux-x86-64.so.2 --library-path $c/lib"
sh "$(dirname "$0")/machine_info.sh" > "$out/machine.txt" 2>&1
taskset -c "$core" $ld "$c/kestrel_cpu_probe" > "$out/probe.txt" 2>&1
echo "--- the same probe, a second run" >> "$out/probe.txt"
taskset -c "$core" $ld "$c/kestrel_cpu_probe" >> "$out/probe.txt" 2>&1
scen="$out/empty.yaml"
printf 'env: {name: empty, num_envs: 4096}\n' > "$scen"
echo "variant,pair,envs,threads,steps,wall_s,env_steps_per_s,state_hash,xinuse_start,xinuse_exit,robot_step" > "$out/runs.csv"
run() {  # variant pair envs threads steps cpus
  o=$(taskset -c "$6" $ld --preload "$c/xinuse_preload.so" "$c/$1/kestrel" run "$scen" --envs "$3" --threads "$4" --steps "$5" \
      --quiet --out "/tmp/intel_core_$1" 2>&1)
  wall=$(printf '%s\n' "$o" | sed -n 's/.*wall time \([0-9.]*\) s, \([0-9.e+]*\) env-steps.*/\1,\2/p')
  hash=$(printf '%s\n' "$o" | sed -n 's/^state hash: //p')
  xs=$(printf '%s\n' "$o" | sed -n 's/^xinuse_preload: XINUSE at start //p')
  xe=$(printf '%s\n' "$o" | sed -n 's/^xinuse_preload: XINUSE at exit //p')
  rs=$(printf '%s\n' "$o" | sed -n 's/^  robot step: //p' | tr ',' ';')
  echo "$1,$2,$3,$4,$5,$wall,$hash,$xs,$xe,$rs" >> "$out/runs.csv"
}
all=0-$(($(nproc) - 1))
for p in $(seq 1 "$pairs"); do
  for v in $variants; do
    run "$v" "$p" 4096 1 2000 "$core"
    run "$v" "$p" 65536 1 150 "$core"
    run "$v" "$p" 4096 16 4000 "$all"
    run "$v" "$p" 65536 16 600 "$all"
  done
done
# Thread sweep at 65,536 environments, one pass per variant, interleaved per thread count.
for t in 1 2 4 8 16; do
  for v in $variants; do
    run "$v" sweep 65536 "$t" 300 "$all"
  done
done
for v in $variants; do
  taskset -c "$core" $ld "$c/$v/kestrel_bench_sim" --quick --reps 7 --csv "$out/bench_$v.csv" > "$out/bench_$v.txt" 2>&1
done
cat "$out/machine.txt" | grep -E 'Model name|model name|^nproc|UTC'
cat "$out/probe.txt"
column -s, -t < "$out/runs.csv" 2>/dev/null || cat "$out/runs.csv"
for v in $variants; do echo "== $v"; grep -E -A5 '^Split|^The same stages' "$out/bench_$v.txt"; grep -A8 '^empty env' "$out/bench_$v.txt"; grep -E 'MuJoCo|16 envs|1 env:' "$out/bench_$v.txt"; done
