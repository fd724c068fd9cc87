#!/bin/sh
# ctest kestrel_cascade_capacity_parity: runs the cascade parity images (cascade_parity.cpp) of
# the default rotor capacity, of the quad build and, when given, of the baked quad build (model
# and parameters generated on the host at build time; that image also checks the baked model
# against the one it builds on board, bit for bit) under QEMU and passes only if every image exits
# 0 and all print the same output hash.
#   compare-parity.sh <run-qemu.sh> <qemu> <machine>[:<run-qemu.sh options>] <default image.elf> <quad image.elf> [<baked image.elf>...]
set -u
runner=$1 qemu=$2 machine=${3%%:*} opts=
case $3 in *:*) opts=$(printf '%s' "${3#*:}" | tr ';' ' ') ;; esac
shift 3
hash_of() {
  out=$(sh "$runner" --qemu "$qemu" --machine "$machine" $opts --elf "$1" --name cascade_parity --timeout 120 2>&1) || {
    printf '%s\n' "$out" >&2; echo "compare-parity: FAIL: $1 did not exit 0" >&2; return 1; }
  printf '%s\n' "$out" | grep '^baked model:' >&2
  line=$(printf '%s\n' "$out" | grep '^cascade parity:')
  echo "$line" >&2
  printf '%s\n' "$line" | sed -n 's/.*hash //p'
}
[ $# -ge 2 ] || { echo "compare-parity: need at least two images" >&2; exit 2; }
first=""
for img in "$@"; do
  h=$(hash_of "$img") || exit 1
  if [ -z "$h" ]; then
    echo "compare-parity: FAIL: no hash from $img" >&2
    exit 1
  fi
  if [ -z "$first" ]; then
    first=$h
  elif [ "$h" != "$first" ]; then
    echo "compare-parity: FAIL: $img gives different outputs ($h vs $first)" >&2
    exit 1
  fi
done
echo "compare-parity: bit-identical across capacities and the baked build (hash $first, $# images)"
