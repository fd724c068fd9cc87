#!/bin/sh
# Runs a Kestrel MCU image under QEMU with semihosting and judges the result (Cortex-M and RISC-V).
#   run-qemu.sh --qemu <qemu-system-arm|qemu-system-riscv32> --machine <mps2-anNNN|virt>
#               --elf <image.elf> --name <argv0> [--bios <none|file>]
#               [--golden-default <dir>] [--timeout <seconds>] [--ktest]
#               [--expect-status <n>] [--expect-output <extended regex>] [--save-output <file>]
# The golden directory passed to the image (second semihosting argument) is $KESTREL_GOLDEN_DIR
# if set and non-empty, else --golden-default. -icount shift=0 makes timing deterministic: each
# instruction advances virtual time by 1 ns (SysTick at 25 MHz on the MPS2 boards: one tick per 40
# instructions; at 168 MHz on the netduinoplus2: 21 ticks per 125 instructions).
# sleep=off: while the core idles (WFI) virtual time jumps to the next timer deadline instead of
# following the host's clock, so a loop paced by SysTick runs as fast as QEMU can go and its
# measurements repeat bit for bit (with the default sleep=on the firmware example took 12.5 s of
# wall time for its 12 s flight and its per-step costs varied by a few instructions run to run).
# RISC-V virt: --bios none (no OpenSBI; the ELF is loaded at 0x80000000, where hart 0 starts in
# M-mode); mcycle/minstret then count exactly one per instruction (board.hpp).
# Passes if QEMU exits 0 (the image's exit status, through semihosting SYS_EXIT; or the status
# given with --expect-status), with --ktest the output has a line "<N> passed, 0 failed" with
# N >= 1, and with --expect-output a line matches that regex. Extra QEMU options can be
# given in $KESTREL_QEMU_EXTRA_ARGS (e.g. "-d unimp,guest_errors").
# --save-output: the image's output is also written to <file> (removed first, so a failed or
# interrupted run never leaves an earlier run's output behind) for a later ctest to read
# (platform/firmware: kestrel_firmware_policy.host_parity).
set -u
qemu=qemu-system-arm machine= bios= elf= name=image golden_default= timeout=600 ktest=0 expect_status=0 expect_output= save_output=
while [ $# -gt 0 ]; do
  case $1 in
    --qemu) qemu=$2; shift 2 ;;
    --machine) machine=$2; shift 2 ;;
    --bios) bios=$2; shift 2 ;;
    --elf) elf=$2; shift 2 ;;
    --name) name=$2; shift 2 ;;
    --golden-default) golden_default=$2; shift 2 ;;
    --timeout) timeout=$2; shift 2 ;;
    --ktest) ktest=1; shift ;;
    --expect-status) expect_status=$2; shift 2 ;;
    --expect-output) expect_output=$2; shift 2 ;;
    --save-output) save_output=$2; shift 2 ;;
    *) echo "run-qemu: unknown argument $1" >&2; exit 2 ;;
  esac
done
if ! command -v "$qemu" >/dev/null 2>&1; then
  case $qemu in *riscv*) pkg=qemu-system-misc ;; *) pkg=qemu-system-arm ;; esac
  echo "run-qemu: $qemu not found; install it (Debian: apt-get install $pkg)" >&2
  exit 1
fi
[ -f "$elf" ] || { echo "run-qemu: no such image: $elf" >&2; exit 1; }

golden=${KESTREL_GOLDEN_DIR:-$golden_default}
# -semihosting-config is a comma-separated option list: a literal comma is written ",,".
esc() { printf '%s' "$1" | sed 's/,/,,/g'; }
semi="enable=on,target=native,arg=$(esc "$name")"
[ -n "$golden" ] && semi="$semi,arg=$(esc "$golden")"

[ -n "$save_output" ] && rm -f "$save_output"
log=$(mktemp "${TMPDIR:-/tmp}/kestrel-qemu.XXXXXX")
trap 'rm -f "$log"' EXIT INT TERM
biosopt=""
[ -n "$bios" ] && biosopt="-bios $bios"
echo "run-qemu: $qemu -M $machine $biosopt -nographic -semihosting-config $semi -icount shift=0,sleep=off -kernel $elf"
start=$(date +%s)
# shellcheck disable=SC2086  # biosopt and KESTREL_QEMU_EXTRA_ARGS are word lists on purpose
timeout -k 5 "$timeout" "$qemu" -M "$machine" $biosopt -nographic -semihosting-config "$semi" \
  -icount shift=0,sleep=off ${KESTREL_QEMU_EXTRA_ARGS:-} -kernel "$elf" </dev/null >"$log" 2>&1
rc=$?
end=$(date +%s)
cat "$log"
[ -n "$save_output" ] && cp "$log" "$save_output"
echo "run-qemu: exit status $rc after $((end - start)) s"
if [ $rc -eq 124 ] || [ $rc -eq 137 ]; then
  echo "run-qemu: FAIL: timed out after $timeout s" >&2
  exit 1
fi
if [ $rc -ne "$expect_status" ]; then
  echo "run-qemu: FAIL: the image exited with status $rc, expected $expect_status" >&2
  exit 1
fi
if [ $ktest -eq 1 ] && ! grep -Eq '^[1-9][0-9]* passed, 0 failed(, [0-9]+ skipped)?$' "$log"; then
  echo "run-qemu: FAIL: no '<N> passed, 0 failed' line in the output" >&2
  exit 1
fi
if [ -n "$expect_output" ] && ! grep -Eq -- "$expect_output" "$log"; then
  echo "run-qemu: FAIL: no line matches '$expect_output'" >&2
  exit 1
fi
exit 0
