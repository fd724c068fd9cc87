#!/bin/sh
# Builds and runs every test: the host tests (GoogleTest), the same core tests and the firmware
# example on the emulated Cortex-M4F under QEMU (run from the host ctest), and the host tests
# again under AddressSanitizer + UBSan. Installs missing Debian packages first.
set -eu
cd "$(dirname "$0")/.."
./scripts/deps.sh
jobs=$(nproc 2>/dev/null || echo 2)

echo "== host + Cortex-M4F (QEMU)"
cmake --preset host
cmake --build --preset host -j "$jobs"
ctest --preset host -j "$jobs"

echo "== host with AddressSanitizer + UBSan"
cmake --preset host-asan
cmake --build --preset host-asan -j "$jobs"
ctest --preset host-asan -j "$jobs"
echo "== all tests passed"
