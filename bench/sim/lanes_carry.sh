#!/bin/sh
# Packs the host build's `kestrel` and `kestrel_bench_sim` with every shared library `ldd` lists
# and the loader, so they run on another x86-64 Linux machine (the device machine) whatever its
# own libraries: bench/sim/lanes_device.sh runs them through CARRY/lib/ld-linux-x86-64.so.2.
#
#   bench/sim/lanes_carry.sh [BUILD_DIR] CARRY     (BUILD_DIR: build/host)
set -eu
if [ $# -ge 2 ]; then b=$1; c=$2; else b=build/host; c=${1:?usage: lanes_carry.sh [BUILD_DIR] CARRY}; fi
mkdir -p "$c/lib"
cp "$b/sim/kestrel" "$b/bench/sim/kestrel_bench_sim" "$c/"
for f in "$c/kestrel" "$c/kestrel_bench_sim"; do
  ldd "$f" | awk '/=>/ {print $3} /ld-linux/ {print $1}' | while read -r l; do [ -f "$l" ] && cp -L "$l" "$c/lib/"; done
done
ls -la "$c" "$c/lib" | head -40
