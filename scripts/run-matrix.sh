#!/bin/sh
# Cross matrix: configures, builds and tests every MCU target and the double-precision host build,
# then prints one line per target. Separate build folders (build/matrix-*) so it never touches the
# preset builds. Not part of scripts/run-tests.sh: a full run takes a long time on two cores.
# Usage: scripts/run-matrix.sh [-jN]
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
jobs=${1:--j2}
results=""

run() {  # name, configure args...
  name=$1; shift
  dir="$root/build/matrix-$name"
  log="$dir.log"
  status="ok"
  if ! cmake -S "$@" -B "$dir" -G Ninja >"$log" 2>&1; then status="configure FAILED"
  elif ! cmake --build "$dir" "$jobs" >>"$log" 2>&1; then status="build FAILED"
  elif [ -n "${KESTREL_MATRIX_NO_TEST:-}" ]; then status="built (no tests)"
  else
    if (cd "$dir" && ctest $jobs --output-on-failure -E "Sim|kestrel_cli|World|Collision|Scenario|Registry|Mesh") >>"$log" 2>&1; then
      status="tests passed"
    else
      status="tests FAILED"
    fi
    summary=$(grep -E "tests passed|tests failed" "$log" | tail -1)
    status="$status ($summary)"
  fi
  results="$results$(printf '%-15s %s  [log: %s]' "$name" "$status" "$log")
"
}

run cortex-m3  "$root" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/toolchain-cortex-m3.cmake"
run cortex-m4f "$root" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/toolchain-cortex-m4f.cmake"
run cortex-m7  "$root" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/toolchain-cortex-m7.cmake"
run netduinoplus2 "$root" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/toolchain-stm32f405.cmake"
run rv32imac   "$root" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/toolchain-rv32imac.cmake"
run rv32imafc  "$root" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/toolchain-rv32imafc.cmake"
run host-double "$root" -DCMAKE_BUILD_TYPE=Release -DKESTREL_DOUBLE=ON -DKESTREL_MCU_TESTS=OFF

printf '\n%-15s %s\n' target result
printf '%s' "$results"
case "$results" in *FAILED*) exit 1 ;; esac
exit 0
