#!/bin/sh
# The SO-101 pick-and-place bench (bench_pick_place.cpp) on another machine (the device machine's
# 16-core Xeon, which has no build tools for Kestrel): pack a build's kestrel_bench_pick_place with
# every shared library ldd lists, the loader and the models; run it there, one core, with the
# AVX-512 copy's 16 worlds per batched step and the AVX2 copy's 8. Figures, never assertions.
#
#   bench/manipulation/pick_place_device.sh pack BUILD_DIR CARRY
#   bench/manipulation/pick_place_device.sh run CARRY OUT_DIR [EPISODES=300]
#
# run writes OUT_DIR/machine.txt and OUT_DIR/pick_place_{avx2,avx512}.txt (the bench's summary
# line: successes, physics steps/s batched and one world at a time, interleaved, bit-identical).
set -eu
case "${1:-}" in
  pack)
    root=$(cd "$(dirname "$0")/../.." && pwd)
    b=${2:?usage: pick_place_device.sh pack BUILD_DIR CARRY}
    c=${3:?usage: pick_place_device.sh pack BUILD_DIR CARRY}
    mkdir -p "$c/pp/lib"
    cp "$b/bench/manipulation/kestrel_bench_pick_place" "$c/pp/"
    mkdir -p "$c/pp/models"
    cp -r "$root/models/so101" "$c/pp/models/"
    ldd "$b/bench/manipulation/kestrel_bench_pick_place" | awk '/=>/ {print $3} /ld-linux/ {print $1}' |
      while read -r l; do [ -f "$l" ] && cp -L "$l" "$c/pp/lib/"; done
    cp "$0" "$c/"
    ;;
  run)
    c=$(cd "${2:?usage: pick_place_device.sh run CARRY OUT_DIR [EPISODES]}" && pwd)
    out=${3:?usage: pick_place_device.sh run CARRY OUT_DIR [EPISODES]}
    episodes=${4:-300}
    mkdir -p "$out"
    P=$c/pp
    { date -u; lscpu | grep -E "Model name|^CPU\(s\)|Thread|MHz"; } > "$out/machine.txt" 2>&1
    for copy in avx512 avx2; do
      KESTREL_BATCH_KERNEL=$copy KESTREL_MODELS_DIR=$P/models taskset -c "$(( $(nproc) > 2 ? 2 : 0 ))" "$P/lib/ld-linux-x86-64.so.2" --library-path "$P/lib" \
        "$P/kestrel_bench_pick_place" "$episodes" 1 > "$out/pick_place_$copy.txt" 2>&1
      cat "$out/pick_place_$copy.txt"
    done
    ;;
  *)
    echo "usage: pick_place_device.sh pack BUILD_DIR CARRY | run CARRY OUT_DIR [EPISODES]" >&2
    exit 2
    ;;
esac
