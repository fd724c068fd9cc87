#!/bin/sh
# ctest kestrel_cascade_capacity_parity: runs the cascade parity image of the default rotor
# capacity and of the quad build (cascade_parity.cpp) under QEMU and passes only if both exit 0
# and print the same output hash.
#   compare-parity.sh <run-qemu.sh> <qemu> <machine> <default image.elf> <quad image.elf>
set -u
runner=$1 qemu=$2 machine=$3 a=$4 b=$5
hash_of() {
  out=$(sh "$runner" --qemu "$qemu" --machine "$machine" --elf "$1" --name cascade_parity --timeout 120 2>&1) || {
    printf '%s\n' "$out"; echo "compare-parity: FAIL: $1 did not exit 0" >&2; return 1; }
  line=$(printf '%s\n' "$out" | grep '^cascade parity:')
  echo "$line" >&2
  printf '%s\n' "$line" | sed -n 's/.*hash //p'
}
ha=$(hash_of "$a") || exit 1
hb=$(hash_of "$b") || exit 1
if [ -z "$ha" ] || [ "$ha" != "$hb" ]; then
  echo "compare-parity: FAIL: the capacities give different outputs ($ha vs $hb)" >&2
  exit 1
fi
echo "compare-parity: bit-identical across capacities (hash $ha)"
