#!/bin/sh
# A long fuzzing campaign on one target of tests/fuzz/: scripts/run-fuzz.sh TARGET SECONDS
#   TARGET: scenario, urdf, mesh, heightmap or capi (or fuzz_<name>).
# Builds the host-fuzz preset's target, fuzzes from the committed corpus (tests/fuzz/corpus/<target>,
# read only) plus a growing campaign corpus in build/fuzz-campaign/<target>/corpus, writes findings
# (crash-*, timeout-*, oom-*) to build/fuzz-campaign/<target>/, and appends a row (date, commit,
# seconds, executions, coverage, corpus size, findings) to tests/fuzz/CAMPAIGNS.md.
# Fork mode: a finding does not end the campaign. Add a reproducer to the committed corpus (and a
# unit test) once its defect is fixed. FUZZ_JOBS=N runs N workers (default 1).
set -eu
cd "$(dirname "$0")/.."
[ $# -eq 2 ] || { echo "usage: $0 TARGET SECONDS" >&2; exit 2; }
t=${1#fuzz_}; target=fuzz_$t; secs=$2
[ -d "tests/fuzz/corpus/$target" ] || { echo "run-fuzz: unknown target $1 (tests/fuzz/corpus/$target missing)" >&2; exit 2; }
cmake --preset host-fuzz >/dev/null
cmake --build --preset host-fuzz -j "$(nproc 2>/dev/null || echo 2)" --target "$target"
out=build/fuzz-campaign/$t
mkdir -p "$out/corpus" "$out/work"
dict=""
[ -f "tests/fuzz/$target.dict" ] && dict="-dict=tests/fuzz/$target.dict"
log=$out/fuzz-$(date +%Y%m%d-%H%M%S).log
before=$(ls "$out" | grep -c -E '^(crash|timeout|oom|leak)-' || true)
KESTREL_FUZZ_WORK_DIR=$PWD/$out/work "build/host-fuzz/tests/fuzz/$target" -max_total_time="$secs" -fork="${FUZZ_JOBS:-1}" \
  -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1 -rss_limit_mb=4096 -timeout=10 -max_len=4096 $dict \
  -artifact_prefix="$out/" "$out/corpus" "tests/fuzz/corpus/$target" >"$log" 2>&1 || true
after=$(ls "$out" | grep -c -E '^(crash|timeout|oom|leak)-' || true)
last=$(grep -E '^#[0-9]+' "$log" | tail -1)
execs=$(echo "$last" | sed -n 's/^#\([0-9]*\).*/\1/p')
cov=$(echo "$last" | sed -n 's/.*cov: \([0-9]*\).*/\1/p')
corp=$(ls "$out/corpus" | wc -l)
found=$((after - before))
findings="none"
if [ "$found" -gt 0 ]; then
  findings="$found new artifact(s) in $out: $(ls -t "$out" | grep -E '^(crash|timeout|oom|leak)-' | head -n "$found" | tr '\n' ' ')"
fi
row="| $(date -u +%Y-%m-%d) | $(git rev-parse --short HEAD) | $target | $secs s | ${execs:-?} | ${cov:-?} | $corp | $findings |"
echo "$row" >> tests/fuzz/CAMPAIGNS.md
echo "$row"
echo "run-fuzz: log $log"
