#!/bin/sh
# Installs the Debian 12 packages Kestrel needs, only those that are missing. Sourced by the
# quick-start scripts; safe to run again.
set -eu
KESTREL_PACKAGES="build-essential cmake ninja-build pkg-config python3 libeigen3-dev libgtest-dev libgmock-dev \
libbenchmark-dev gcc-arm-none-eabi libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib \
binutils-arm-none-eabi qemu-system-arm qemu-system-misc gcc-riscv64-unknown-elf binutils-riscv64-unknown-elf \
picolibc-riscv64-unknown-elf libstdc++-arm-none-eabi-dev \
clang libclang-rt-14-dev libembree-dev libfcl-dev libccd-dev libyaml-cpp-dev libbox2d-dev libpng-dev libmujoco-dev libtinyxml2-dev \
chromium"  # chromium: headless, for the viewer's browser test (python/tests/test_viewer.py)
missing=""
for p in $KESTREL_PACKAGES; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing="$missing $p"
  fi
done
if [ -n "$missing" ]; then
  echo "kestrel: installing missing Debian packages:$missing"
  SUDO=""
  if [ "$(id -u)" != "0" ]; then SUDO="sudo"; fi
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends $missing
fi

# The Python side (python/, `pip install .`): a virtual environment of the project's, .venv/, with
# the pinned packages of python/requirements.txt (torch==2.13.0 first: a CPU build; a plain or newer
# torch would download a CUDA build of several GB). Skipped when the stamp (hash of the requirements
# and the interpreter) is current, so a second run costs nothing.
KESTREL_ROOT="$(cd "$(dirname "$0")/.." && pwd)"
VENV="$KESTREL_ROOT/.venv"
REQ="$KESTREL_ROOT/python/requirements.txt"
PY="${KESTREL_PYTHON:-python3}"
if [ ! -x "$VENV/bin/python" ]; then
  echo "kestrel: creating $VENV with $($PY --version 2>&1)"
  if ! "$PY" -m venv "$VENV"; then
    # Debian's own python3 needs python3-venv for ensurepip (a pyenv python3 has it built in).
    SUDO=""
    if [ "$(id -u)" != "0" ]; then SUDO="sudo"; fi
    $SUDO apt-get update -q
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends python3-venv
    rm -rf "$VENV"
    "$PY" -m venv "$VENV"
  fi
fi
stamp="$VENV/.kestrel-requirements"
want="$( (cat "$REQ"; "$VENV/bin/python" --version) | sha256sum | cut -d' ' -f1)"
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  echo "kestrel: installing the pinned Python packages ($REQ) into $VENV"
  "$VENV/bin/python" -m pip install -q --disable-pip-version-check "$(grep '^torch==' "$REQ")"
  "$VENV/bin/python" -m pip install -q --disable-pip-version-check -r "$REQ"
  echo "$want" > "$stamp"
fi
