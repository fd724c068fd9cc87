#!/bin/sh
# Builds and runs every test: the host tests (GoogleTest), the same core tests and the firmware
# examples on the emulated Cortex-M4F and on 32-bit RISC-V (rv32imac, rv32imafc; QEMU virt) under
# QEMU (run from the host ctest: mcu.cortex-m4f, mcu.rv32imac, mcu.rv32imafc), and the host tests
# again under AddressSanitizer + UBSan, then the Python package (python/: built into .venv/ with
# pip, build tree cached in build/python/) and its tests (pytest python/tests), the fuzz targets'
# regression runs (clang + libFuzzer, tests/fuzz/) and the multi-threaded step under
# ThreadSanitizer (only those tests' executables are built). Installs missing
# Debian packages and the pinned Python packages first.
set -eu
start=$(date +%s)  # stages print the seconds since here (deps included)
cd "$(dirname "$0")/.."
./scripts/deps.sh
jobs=$(nproc 2>/dev/null || echo 2)

# Each stage also prints the disk space left: the build trees and .venv take about 6 GB together
# (host 1.0, ASan 1.2, TSan 0.9, fuzz 0.6, .venv 2.4 GB on 2026-11-28), the Debian packages more;
# a CI run once stopped at the AddressSanitizer link with "No space left on device".
free_mb() { df -Pm . | awk 'NR == 2 { print $4 }'; }
stage() { echo "== $1 (at $(( $(date +%s) - start )) s, $(free_mb) MB free)"; }
stage "host + Cortex-M4F + RISC-V rv32imac/rv32imafc (QEMU)"
cmake --preset host
cmake --build --preset host -j "$jobs"
ctest --preset host -j "$jobs"

stage "host with AddressSanitizer + UBSan"
cmake --preset host-asan
cmake --build --preset host-asan -j "$jobs"
ctest --preset host-asan -j "$jobs"
stage "fuzz regression (clang + libFuzzer)"
# The five fuzz targets over their committed corpora, a fixed number of runs from a fixed seed
# (tests/fuzz/CMakeLists.txt); long campaigns: scripts/run-fuzz.sh.
cmake --preset host-fuzz
cmake --build --preset host-fuzz -j "$jobs"
ctest --preset host-fuzz
stage "ThreadSanitizer (multi-threaded world/task/planar step)"
# Builds only the task and backend test executables (the sim library under TSan dominates the
# cost) and runs their tests that step with >= 2 threads (the test preset's name filter): rigid
# World through SimulatorRigid and the tasks, planar, navigation/custom/goal-box tasks. The World
# hash tests of kestrel_sim_tests (SimWorld/SimSensors/SimTerrain/SimBatchStep.*Threads*) also pass
# under TSan but are left out for time; kestrel_sim_mt_heap_tests does not build at -O1
# (-Wmismatched-new-delete in its operator delete) and replaces malloc, which TSan intercepts.
cmake --preset host-tsan
cmake --build --preset host-tsan -j "$jobs"
ctest --preset host-tsan -j "$jobs"
stage "Python"
# Non-editable install of the package (scikit-build-core: build/python/, incremental), then pytest.
# The determinism test compares with the CLI built above (build/host/sim/kestrel).
CMAKE_BUILD_PARALLEL_LEVEL="$jobs" .venv/bin/python -m pip install -q --disable-pip-version-check --no-build-isolation .
.venv/bin/python -m pytest -q python/tests
stage "all tests passed"
