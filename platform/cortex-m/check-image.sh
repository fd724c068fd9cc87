#!/bin/sh
# Checks a linked Kestrel MCU image (ELF) and reports its memory use.
#   check-image.sh <arm-none-eabi-nm> <arm-none-eabi-size> <image.elf> <heap-symbols.txt>
# Fails if the image has an undefined (non-weak) symbol, or defines or references any heap symbol
# (heap-symbols.txt, plus anything named __wrap_*/__real_*/__malloc_*). Prints flash use
# (text + data) and RAM use (.data + .bss; the main stack reserved by the linker script apart).
set -eu
nm=$1 size=$2 elf=$3 list=$4
[ -f "$elf" ] || { echo "check-image: no such image: $elf" >&2; exit 1; }

status=0
syms=$("$nm" "$elf")

undef=$(printf '%s\n' "$syms" | awk '$1 == "U" { print $2 }')
weak_undef=$(printf '%s\n' "$syms" | awk '($1 == "w" || $1 == "v") && NF == 2 { print $2 }')
if [ -n "$undef" ]; then
  echo "FAIL undefined symbols:"; printf '  %s\n' $undef; status=1
else
  echo "undefined symbols: none${weak_undef:+ (weak, unresolved: $(echo $weak_undef))}"
fi

heap=$(printf '%s\n' "$syms" | awk -v list="$list" '
  BEGIN { while ((getline line < list) > 0) { sub(/#.*/, "", line); gsub(/[ \t]/, "", line); if (line != "") bad[line] = 1 } }
  { name = $NF; if ((name in bad) || name ~ /^__(wrap|real)_/ || name ~ /^__malloc_/) print $0 }')
if [ -n "$heap" ]; then
  echo "FAIL heap symbols in the image:"; printf '%s\n' "$heap" | sed 's/^/  /'; status=1
else
  echo "heap symbols: none"
fi

# Flash: Berkeley text + data (code, constants, vector table, init arrays, and the load image of
# .data). RAM: the .data and .bss sections of the linker script (Berkeley "data" would also count
# .init_array, which stays in flash); the NOLOAD .stack section is reported apart.
set -- $("$size" -B "$elf" | awk 'NR == 2 { print $1, $2 }')
text=$1 data=$2
set -- $("$size" -A "$elf" | awk '$1 == ".data" { d = $2 } $1 == ".bss" { b = $2 } $1 == ".stack" { s = $2 }
                               END { print d + 0, b + 0, s + 0 }')
ram_data=$1 ram_bss=$2 stack=$3
echo "flash: $((text + data)) bytes (text $text + data $data)"
echo "RAM:   $((ram_data + ram_bss)) bytes (.data $ram_data + .bss $ram_bss), plus $stack bytes main stack (on Cortex-M incl. its 1 KiB MPU guard)"
exit $status
