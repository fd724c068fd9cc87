#!/bin/sh
# The batched legged constrained step (sim/src/backends/articulated_batch.hpp) on another machine
# (the device machine's 16-core Xeon, which has no build tools for Kestrel): pack a build's
# kestrel_bench_legged_step and `kestrel` binaries with every shared library ldd lists, the loader
# and the models; run them there. Figures, never assertions.
#
#   bench/dynamics/legged_batch_device.sh pack BUILD_DIR CARRY
#   bench/dynamics/legged_batch_device.sh run CARRY OUT_DIR
#
# run writes OUT_DIR/machine.txt; OUT_DIR/legged_step_{avx2,avx512}.csv (a standing Go2 and ANYmal C:
# the scalar step, the batched step with the AVX2 copy's 8 or the AVX-512 copy's 16 robots per
# step, MuJoCo 2.2.2, one core); OUT_DIR/go2_joint_targets.csv (`kestrel run`: 16,384 Go2s under
# random joint targets, 10 env-steps, 1, 2 and 16 threads, the batched step in both copies and the
# scalar one; the state hash must be the same on every row).
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
pack_binary() {  # binary, destination folder
  mkdir -p "$2/lib"
  cp "$1" "$2/"
  cp -r "$root/models" "$2/"
  ldd "$1" | awk '/=>/ {print $3} /ld-linux/ {print $1}' | while read -r l; do [ -f "$l" ] && cp -L "$l" "$2/lib/"; done
}
case "${1:-}" in
  pack)
    b=${2:?usage: legged_batch_device.sh pack BUILD_DIR CARRY}
    c=${3:?usage: legged_batch_device.sh pack BUILD_DIR CARRY}
    pack_binary "$b/bench/dynamics/kestrel_bench_legged_step" "$c/bench"
    # MuJoCo from PyPI (the bench loads it with dlopen, so ldd does not list it): the wheel's library.
    for l in "$root"/.venv/lib/python3*/site-packages/mujoco/libmujoco.so.*; do [ -f "$l" ] && cp -L "$l" "$c/bench/lib/libmujoco_pypi.so"; done
    pack_binary "$b/sim/kestrel" "$c/kestrel"
    cp "$0" "$c/"
    cp "$root/bench/dynamics/go2_joint_targets.yaml" "$c/go2.yaml"
    ;;
  run)
    c=$(cd "${2:?usage: legged_batch_device.sh run CARRY OUT_DIR}" && pwd)
    out=${3:?usage: legged_batch_device.sh run CARRY OUT_DIR}
    mkdir -p "$out"
    B=$c/bench
    K=$c/kestrel
    { date -u; lscpu | grep -E "Model name|^CPU\(s\)|Thread|MHz"; } > "$out/machine.txt" 2>&1
    for copy in avx2 avx512; do
      KESTREL_BATCH_KERNEL=$copy taskset -c 2 "$B/lib/ld-linux-x86-64.so.2" --library-path "$B/lib" "$B/kestrel_bench_legged_step" \
        --steps 5000 --reps 5 --quiet --models "$B/models" --machine "device machine, $copy copy" \
        --mujoco-pypi "$([ -f "$B/lib/libmujoco_pypi.so" ] && echo "$B/lib/libmujoco_pypi.so" || echo none)" \
        --csv "$out/legged_step_$copy.csv" > "$out/legged_step_$copy.txt" 2>&1
    done
    echo "envs,threads,copy,step,wall_s,env_steps_per_s,state_hash" > "$out/go2_joint_targets.csv"
    for t in 1 2 16; do
      for copy in avx2 avx512; do
        for mode in on off; do
          [ "$mode" = off ] && [ "$copy" = avx512 ] && continue
          o=$(KESTREL_BATCH_KERNEL=$copy KESTREL_LEGGED_BATCH=$mode KESTREL_MODELS_DIR=$K/models \
            "$K/lib/ld-linux-x86-64.so.2" --library-path "$K/lib" "$K/kestrel" run "$c/go2.yaml" --envs 16384 --threads $t \
            --steps 10 --quiet --out /tmp/legged_batch_device_out 2>&1)
          w=$(printf '%s\n' "$o" | sed -n 's/.*wall time \([0-9.]*\) s, \([0-9.e+]*\) env-steps.*/\1,\2/p')
          h=$(printf '%s\n' "$o" | sed -n 's/^state hash: //p')
          step=batched
          [ "$mode" = off ] && step=scalar
          echo "16384,$t,$copy,$step,$w,$h" >> "$out/go2_joint_targets.csv"
        done
      done
    done
    cat "$out/go2_joint_targets.csv"
    ;;
  *)
    echo "usage: legged_batch_device.sh pack BUILD_DIR CARRY | run CARRY OUT_DIR" >&2
    exit 2
    ;;
esac
