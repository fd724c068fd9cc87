#!/bin/sh
# Installs the Debian 12 packages Kestrel needs, only those that are missing. Sourced by the
# quick-start scripts; safe to run again.
set -eu
KESTREL_PACKAGES="build-essential cmake ninja-build pkg-config python3 libeigen3-dev libgtest-dev libgmock-dev \
libbenchmark-dev gcc-arm-none-eabi libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib \
binutils-arm-none-eabi qemu-system-arm qemu-system-misc gcc-riscv64-unknown-elf picolibc-riscv64-unknown-elf \
libembree-dev libfcl-dev libccd-dev libyaml-cpp-dev libbox2d-dev libpng-dev libmujoco-dev libtinyxml2-dev"
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
