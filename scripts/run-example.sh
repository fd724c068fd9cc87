#!/bin/sh
# Main job:
#  1. the closed-loop firmware examples (Lee position controller -> sequential-desaturation
#     allocation -> motor model -> rigid-body plant) on the host and on an emulated Cortex-M4F
#     (QEMU mps2-an386, -icount shift=0), printing tracking error, cost per control step and the
#     image's flash/RAM use; then the trained position policy flying the same vehicle beside Lee;
#  2. the simulation harness's embedded default scenario (`kestrel run`: 1024 quadrotors flying
#     position setpoints through the forest), printing its summary and state hash and writing
#     CSV logs to build/kestrel-run/, then its trajectory plot (matplotlib, python/kestrel/plots.py,
#     run as a script with .venv's Python: no need to build the Python package for it).
# Installs missing Debian packages first.
set -eu
cd "$(dirname "$0")/.."
./scripts/deps.sh
jobs=$(nproc 2>/dev/null || echo 2)

echo "== building (host)"
cmake --preset host >/dev/null
# kestrel_package: also every library the install rules copy, so `cmake --install build/host`
# (and build/cortex-m4f) works on the trees this script leaves (docs/packaging.md).
cmake --build --preset host --target kestrel_firmware_host kestrel_firmware_policy_host kestrel kestrel_package -j "$jobs"
echo "== building (Cortex-M4F)"
cmake --preset cortex-m4f >/dev/null
cmake --build --preset cortex-m4f --target kestrel_firmware kestrel_firmware_policy kestrel_package -j "$jobs"

echo
echo "== host"
./build/host/platform/firmware/kestrel_firmware_host
echo
echo "== emulated Cortex-M4F"
elf=build/cortex-m4f/platform/firmware/kestrel_firmware.elf
sh platform/cortex-m/check-image.sh arm-none-eabi-nm arm-none-eabi-size "$elf" platform/cortex-m/heap-symbols.txt
sh platform/cortex-m/run-qemu.sh --machine mps2-an386 --elf "$elf" --name kestrel_firmware --timeout 300

echo
echo "== the trained position policy (policy/mlp.hpp, platform/firmware/position_policy.hpp) beside Lee"
./build/host/platform/firmware/kestrel_firmware_policy_host
elf=build/cortex-m4f/platform/firmware/kestrel_firmware_policy.elf
sh platform/cortex-m/check-image.sh arm-none-eabi-nm arm-none-eabi-size "$elf" platform/cortex-m/heap-symbols.txt
sh platform/cortex-m/run-qemu.sh --machine mps2-an386 --elf "$elf" --name kestrel_firmware_policy --timeout 300

echo
echo "== simulation harness: kestrel run (embedded default scenario)"
KESTREL_PLOT_BY_CALLER=1 ./build/host/sim/kestrel run --out build/kestrel-run
.venv/bin/python python/kestrel/plots.py build/kestrel-run
