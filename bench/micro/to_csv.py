#!/usr/bin/env python3
"""Converts kestrel_bench_micro's Google Benchmark JSON (--benchmark_out_format=json) into
bench/results/host/micro.csv, one row per function x airframe x batch:

    function,airframe,batch,ns_per_call,items_per_s,cv_percent,lane_bytes,working_set_kib,repetitions

ns_per_call is CPU time per iteration divided by the batch (one iteration calls the function once
per lane); with repetitions it is the median repetition's, and cv_percent is the repetitions'
standard deviation over their mean (empty with one repetition). items_per_s is Google Benchmark's
items_per_second (calls per CPU second). Instructions per call are not recorded: Google Benchmark
reads them through perf_event_open (libpfm), which the build machines (VMs without a PMU) lack;
the deterministic instruction counts are the MCU bench's (bench/results/<target>/control.csv).

A second file, micro_context.txt beside the CSV, keeps what the figures depend on (date, CPU,
caches, load, flags, a free-text note such as "machine shared with other jobs").

It also checks the run: every function/airframe must have a row for each batch size and every
figure must be positive; otherwise it exits 1 (the ctest smoke run relies on that).

    to_csv.py BENCH.json OUT.csv [--note TEXT] [--args TEXT]
"""
import csv
import json
import os
import sys

BATCHES = (1, 64, 4096)
UNIT_NS = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}


def parse_name(run_name):
    """'function/airframe/batch:N' -> (function, airframe, N)."""
    parts = run_name.split("/")
    if len(parts) != 3 or not parts[2].startswith("batch:"):
        raise ValueError(f"unexpected benchmark name {run_name!r} (want function/airframe/batch:N)")
    return parts[0], parts[1], int(parts[2][len("batch:"):])


def convert(doc):
    runs = {}  # (function, airframe, batch) -> {"iteration": [...], "median": b, "mean": b, "stddev": b}
    order = []
    for b in doc.get("benchmarks", []):
        if b.get("error_occurred"):
            raise ValueError(f"{b['name']}: {b.get('error_message', 'error')}")
        key = parse_name(b.get("run_name", b["name"]))
        if key not in runs:
            runs[key] = {"iteration": []}
            order.append(key)
        if b.get("run_type") == "aggregate":
            runs[key][b["aggregate_name"]] = b
        else:
            runs[key]["iteration"].append(b)
    rows = []
    for key in order:
        r = runs[key]
        function, airframe, batch = key
        reps = max(len(r["iteration"]), int(r.get("median", {}).get("repetitions", 0) or 0))
        best = r.get("median") or (r["iteration"][0] if r["iteration"] else None)
        if best is None:
            raise ValueError(f"{function}/{airframe}/batch:{batch}: no result")
        ns = best["cpu_time"] * UNIT_NS[best.get("time_unit", "ns")] / batch
        cv = ""
        if "mean" in r and "stddev" in r and r["mean"]["cpu_time"] > 0:
            cv = f"{100.0 * r['stddev']['cpu_time'] / r['mean']['cpu_time']:.1f}"
        rows.append({
            "function": function,
            "airframe": airframe,
            "batch": batch,
            "ns_per_call": f"{ns:.2f}",
            "items_per_s": f"{best.get('items_per_second', 0.0):.6g}",
            "cv_percent": cv,
            "lane_bytes": f"{best.get('lane_bytes', 0):.0f}",
            "working_set_kib": f"{best.get('working_set_kib', 0):.1f}",
            "repetitions": reps,
        })
    return rows


def check(rows):
    problems = []
    seen = {}
    for r in rows:
        seen.setdefault((r["function"], r["airframe"]), set()).add(r["batch"])
        if not float(r["ns_per_call"]) > 0 or not float(r["items_per_s"]) > 0:
            problems.append(f"{r['function']}/{r['airframe']}/batch:{r['batch']}: non-positive figure")
    for (f, a), got in seen.items():
        for n in BATCHES:
            if n not in got:
                problems.append(f"{f}/{a}: no row for batch {n}")
    if not rows:
        problems.append("no benchmark rows")
    return problems


def context_text(doc, note, args):
    c = doc.get("context", {})
    caches = ", ".join(f"L{x['level']}{'' if x['type'] == 'Unified' else x['type'][0].lower()} {x['size'] // 1024} KiB"
                       f" (shared by {x.get('num_sharing', 1)} CPU{'' if x.get('num_sharing', 1) == 1 else 's'})"
                       for x in c.get("caches", []))
    lines = [
        f"date: {c.get('date', '?')}",
        f"host: {c.get('num_cpus', '?')} CPUs at {c.get('mhz_per_cpu', '?')} MHz; caches: {caches}",
        f"load average at start: {', '.join(f'{v:.2f}' for v in c.get('load_avg', []))}",
        f"google benchmark library build: {c.get('library_build_type', '?')}; cpu scaling enabled: "
        f"{c.get('cpu_scaling_enabled', '?')}",
        f"arguments: {args}",
        f"note: {note}",
    ]
    return "\n".join(lines) + "\n"


def main(argv):
    note, args, pos = "", "", []
    i = 1
    while i < len(argv):
        if argv[i] == "--note":
            note, i = argv[i + 1], i + 2
        elif argv[i] == "--args":
            args, i = argv[i + 1], i + 2
        else:
            pos.append(argv[i])
            i += 1
    if len(pos) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    with open(pos[0]) as f:
        doc = json.load(f)
    try:
        rows = convert(doc)
    except (ValueError, KeyError) as e:
        print(f"to_csv: {pos[0]}: {e}", file=sys.stderr)
        return 1
    problems = check(rows)
    for p in problems:
        print(f"to_csv: {pos[0]}: {p}", file=sys.stderr)
    if problems:
        return 1
    fields = ["function", "airframe", "batch", "ns_per_call", "items_per_s", "cv_percent", "lane_bytes",
              "working_set_kib", "repetitions"]
    with open(pos[1], "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    with open(os.path.join(os.path.dirname(os.path.abspath(pos[1])), "micro_context.txt"), "w") as f:
        f.write(context_text(doc, note, args))
    print(f"to_csv: wrote {pos[1]} ({len(rows)} rows)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
