#!/bin/sh
# Instructions per policy step of the legged locomotion task (legged_gym's, 4 physics steps per
# policy step), two builds of `kestrel` side by side under callgrind: exact counts, which the
# shared 2-core machine's timing noise (+-30 %) does not touch. Each side runs the Go2 and the
# ANYmal C flat scenarios for S1 and S2 policy steps of 64 environments on one thread; the
# difference of the two runs over (S2 - S1) x 64 is the count per policy step without the start-up.
# The state hash of each run is printed too: two trees that should give the same bits must agree.
#
#   bench/dynamics/instructions_ab.sh KESTREL_BASE KESTREL_NOW [CSV] [S1] [S2]   (S1 10, S2 60)
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
base=${1:?usage: instructions_ab.sh KESTREL_BASE KESTREL_NOW [CSV] [S1] [S2]}
now=${2:?usage: instructions_ab.sh KESTREL_BASE KESTREL_NOW [CSV] [S1] [S2]}
csv=${3:-}
s1=${4:-10}
s2=${5:-60}
envs=64
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
count() {  # binary scenario steps -> "instructions state_hash"
  n=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null "$1" run "$2" --envs "$envs" --steps "$3" --threads 1 \
      --out "$tmp/o" --quiet 2>&1 | awk '/refs:/ {gsub(",", "", $NF); print $NF}')
  echo "$n $(awk '/state hash/ {print $3}' "$tmp/o/summary.txt")"
}
rows="side,robot,policy_steps,instructions_per_policy_step,state_hash"
for robot in go2 anymal_c; do
  scenario="$root/sim/scenarios/${robot}_flat_locomotion.yaml"
  for side in base now; do
    bin=$base
    [ "$side" = now ] && bin=$now
    set -- $(count "$bin" "$scenario" "$s1")
    a=$1
    set -- $(count "$bin" "$scenario" "$s2")
    per=$(( ($1 - a) / ((s2 - s1) * envs) ))
    rows="$rows
$side,$robot,$((s2 - s1)),$per,$2"
  done
done
echo "$rows"
[ -n "$csv" ] && echo "$rows" > "$csv"
exit 0
