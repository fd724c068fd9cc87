#!/bin/sh
# Runs the deterministic control benchmark of one MCU build tree (Cortex-M or RISC-V) under QEMU
# and writes
#   bench/results/<target>/control.csv  instructions per call + painted stack bytes per function
#   bench/results/<target>/memory.csv   flash / static RAM of the control stack (minimal images)
#   bench/results/<target>/memory_breakdown.csv  the quad control stack's bytes by role and symbol
#   bench/results/<target>/memory_breakdown_baked.csv  the same for the baked quad stack
#   bench/results/<target>/memory_breakdown_policy.csv the trained position policy alone (observation,
#                                       MLP, action clip; weights in flash) by role and symbol
#   bench/results/<target>/stack.csv    static worst-case stack bound per entry point from GCC's
#                                       call graph (stack_usage.py, -fcallgraph-info=su)
#
#   bench/control/run-mcu-bench.sh <mcu build dir> <target name, e.g. cortex-m4f>
#   (KESTREL_BENCH_JOBS: parallel build and compile jobs, default 2)
#
# The build dir is a configured MCU tree (e.g. build/host/mcu-cortex-m4f, which the host preset
# builds, cmake --preset cortex-m4f, or build/host/mcu-rv32imafc / cmake --preset rv32imafc);
# this script builds the bench images in it. QEMU, its options and the binutils come from the
# tree's cache (KESTREL_MCU_QEMU, KESTREL_MCU_QEMU_OPTIONS, KESTREL_MCU_SIZE).
# Determinism check: the image is run twice and the two outputs must be byte-identical (under
# -icount shift=0,sleep=off QEMU is a deterministic machine); the image itself also fails if a
# measurement repeated in the same run differs by more than one SysTick tick.
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:?usage: run-mcu-bench.sh <mcu build dir> <target>}
target=${2:?usage: run-mcu-bench.sh <mcu build dir> <target>}
build=$(cd "$build" && pwd)
out="$root/bench/results/$target"
mkdir -p "$out"

jobs=${KESTREL_BENCH_JOBS:-2}
export KESTREL_BENCH_JOBS="$jobs"  # stack_usage.py's compile jobs
cmake --build "$build" -j "$jobs" --target kestrel_control_bench kestrel_stack_empty kestrel_stack_cascade \
  kestrel_stack_cascade_quad kestrel_stack_cascade_quad_baked kestrel_stack_capi kestrel_stack_policy
cache() { sed -n "s/^$1:[A-Z]*=//p" "$build/CMakeCache.txt"; }
machine=$(cache KESTREL_BOARD)
qemu=${QEMU:-$(cache KESTREL_MCU_QEMU)}
qemu=${qemu:-qemu-system-arm}
qemu_opts=$(cache KESTREL_MCU_QEMU_OPTIONS | tr ';' ' ')
size=${ARM_SIZE:-$(cache KESTREL_MCU_SIZE)}
size=${size:-arm-none-eabi-size}
# nm/objdump for memory_breakdown.py: the size program's prefix (arm-none-eabi-, riscv64-unknown-elf-).
export KESTREL_BINUTILS_PREFIX="${size%size}"
# The images' folder: bench/control/mcu in a Cortex-M tree (older trees: bench/control-mcu).
imgdir="$build/bench/control/mcu"
[ -d "$imgdir" ] || imgdir="$build/bench/control-mcu"
elf="$imgdir/kestrel_control_bench.elf"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for run in 1 2; do
  sh "$root/platform/cortex-m/run-qemu.sh" --qemu "$qemu" --machine "$machine" $qemu_opts --elf "$elf" \
     --name kestrel_control_bench --timeout 300 \
     --expect-output "determinism: every measurement repeated within one tick" > "$tmp/run$run.txt" 2>&1 || {
    cat "$tmp/run$run.txt"; echo "run-mcu-bench: the bench image failed" >&2; exit 1; }
  # Only the image's own output (run-qemu.sh adds lines with timings of the host).
  grep -v '^run-qemu:' "$tmp/run$run.txt" > "$tmp/out$run.txt"
done
if ! cmp -s "$tmp/out1.txt" "$tmp/out2.txt"; then
  diff "$tmp/out1.txt" "$tmp/out2.txt" || true
  echo "run-mcu-bench: FAIL: two runs of the same image gave different figures" >&2
  exit 1
fi
echo "run-mcu-bench: deterministic: two runs identical"
sed -n '/^csv-begin$/,/^csv-end$/p' "$tmp/out1.txt" | sed '1d;$d' > "$out/control.csv"

# Flash = text + data, static RAM = data + bss without the linker-reserved main stack and its
# guard (.stack is NOLOAD, counted in bss by size -B; take it from the section table instead).
mem() {
  f="$imgdir/kestrel_stack_$1.elf"
  set -- $("$size" -B "$f" | tail -n 1)
  text=$1 data=$2 bss=$3
  stack=$("$size" -A "$f" | awk '$1 == ".stack" { print $2 }')
  echo "$text $data $((bss - ${stack:-0}))"
}
set -- $(mem empty); e_text=$1 e_data=$2 e_bss=$3
{
  echo "image,text_bytes,data_bytes,bss_bytes,flash_bytes,static_ram_bytes,flash_minus_empty,static_ram_minus_empty"
  # cascade: the control stack with the default rotor capacity (12); cascade_quad: the same with
  # the allocation library built for 4 rotors (KESTREL_MAX_ROTORS=4), as a quad's firmware would;
  # cascade_quad_baked: the quad stack with parameters, allocation model and initial state
  # generated at build time (bench/control/mcu/baked_cascade.hpp; no on-board set-up code);
  # policy: the trained position policy alone (observation -> 13-64-64-4 MLP -> action clip, its
  # weights constexpr in flash, validate_mlp at start-up), no controller behind it: its flash and
  # static RAM are this image minus the empty one.
  for img in empty cascade cascade_quad cascade_quad_baked capi policy; do
    set -- $(mem $img)
    echo "$img,$1,$2,$3,$(($1 + $2)),$(($2 + $3)),$(($1 + $2 - e_text - e_data)),$(($2 + $3 - e_data - e_bss))"
  done
} > "$out/memory.csv"
# Where the quad control stack's bytes go (per-step code, set-up code, static initialisation,
# read-only data, static RAM; one row per symbol).
python3 "$root/bench/control/memory_breakdown.py" "$imgdir/kestrel_stack_empty.elf" \
  "$imgdir/kestrel_stack_cascade_quad.elf" "$out/memory_breakdown.csv" > /dev/null
python3 "$root/bench/control/memory_breakdown.py" "$imgdir/kestrel_stack_empty.elf" \
  "$imgdir/kestrel_stack_cascade_quad_baked.elf" "$out/memory_breakdown_baked.csv" > /dev/null
# The policy image by symbol: the weights' object (kPositionPolicy, .rodata) and the code.
python3 "$root/bench/control/memory_breakdown.py" "$imgdir/kestrel_stack_empty.elf" \
  "$imgdir/kestrel_stack_policy.elf" "$out/memory_breakdown_policy.csv" > /dev/null
# Static worst-case stack (GCC's frame sizes over the call graph); control.csv's stack_bytes column
# is the painted-stack measurement of one call. KESTREL_BENCH_NO_STACK_BOUND=1 skips it (it compiles
# every core source again) and keeps an existing stack.csv.
if [ -z "${KESTREL_BENCH_NO_STACK_BOUND:-}" ]; then
  python3 "$root/bench/control/stack_usage.py" "$build" "$out/stack.csv"
fi
echo "run-mcu-bench: wrote $out/control.csv, $out/memory.csv, $out/memory_breakdown{,_baked,_policy}.csv and $out/stack.csv"
cat "$out/control.csv" "$out/memory.csv"
[ -f "$out/stack.csv" ] && cat "$out/stack.csv"
exit 0
