#!/bin/sh
# ctest kestrel_firmware_policy.host_parity: the desktop harness reproduces the firmware's
# trajectory bit for bit. Runs the host build of the policy firmware example and compares its
# "trajectory hash" line (FNV-1a over the plant state bits of every step, policy flight and Lee
# flight; policy_loop.cpp) with the one the MCU image printed under QEMU (saved by the ctest
# kestrel_firmware_policy through run-qemu.sh --save-output). Fails if either line is missing or
# they differ.
#   compare-trajectory.sh <kestrel_firmware_policy_host> <saved QEMU output> [<extended regex>]
# With a regex (ctest kestrel_firmware.host_parity: the Lee firmware example, which prints no
# hash), the lines matching it are compared instead: the flight report's figures, printed to the
# digit, must be the same on the host and the MCU.
set -u
host_exe=${1:?usage: compare-trajectory.sh <host exe> <mcu output>}
mcu_out=${2:?usage: compare-trajectory.sh <host exe> <mcu output>}
[ -f "$mcu_out" ] || { echo "compare-trajectory: FAIL: no MCU output $mcu_out (run the ctest kestrel_firmware_policy)" >&2; exit 1; }
host=$("$host_exe") || { printf '%s\n' "$host"; echo "compare-trajectory: FAIL: $host_exe did not exit 0" >&2; exit 1; }
pattern=${3:-}
if [ -n "$pattern" ]; then
  line_of() { grep -E -- "$pattern"; }
else
  line_of() { grep -o 'trajectory hash (FNV-1a[^:]*): .*$' | head -n 1; }
fi
h=$(printf '%s\n' "$host" | line_of)
m=$(line_of < "$mcu_out")
printf 'host: %s\n' "$h"
printf 'mcu:  %s\n' "$m"
if [ -z "$h" ] || [ -z "$m" ]; then
  echo "compare-trajectory: FAIL: a trajectory hash line (or report line) is missing" >&2
  exit 1
fi
if [ "$h" != "$m" ]; then
  echo "compare-trajectory: FAIL: the host and the MCU flew different trajectories" >&2
  exit 1
fi
echo "compare-trajectory: host and MCU trajectories bit-identical"
