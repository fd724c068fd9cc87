#!/usr/bin/env python3
"""Renders bench/results/<target>/control.csv and memory.csv into a markdown report
(bench/results/report.md) and one bar chart per target (bench/results/<target>/control.png),
so a change in cost shows up in review as a diff of committed text and images. The host
micro-benchmarks (bench/results/host/micro.csv, written by bench/micro/run.sh) get their own
section and host/micro.png (render_host_micro).

Standard library only (no matplotlib on the build machines): the PNG is drawn pixel by pixel
and written with zlib. Targets from the issue are checked in the report, not asserted here.
    python3 bench/control/render.py [results dir]
"""
import csv
import math
import os
import struct
import sys
import zlib

TARGETS = {  # issue 6: Kestrel's targets on the emulated Cortex-M4F (instructions, bytes)
    ("cascade_lee_position_desat_motors", "base_quadrotor"): 1500,
    ("pseudo_inverse", "base_quadrotor"): 10000,
}
PEERS = [  # measured side by side with public flight stacks (issue 6), Cortex-M4F, -O2
    ("Crazyflie controllerLee (position + attitude + rates)", 2287),
    ("Crazyflie power distribution", 161),
    ("PX4 attitude + rate controllers", 874),
    ("PX4 sequential desaturation, quad", 2400),
    ("PX4 pseudo-inverse (one time)", 23700),
]
FLASH_TARGET, RAM_TARGET = 12 * 1024, 512
# Issue 11: one 13-64-64-4 inference within 16,000 instructions on the Cortex-M4F (the STM32F405
# of the netduinoplus2 too: the same core, the same counts), and the policy controller alone (its
# code + float32 weights, the policy image minus the empty one) within 22 KB of flash.
POLICY_TARGETS = {
    ("mlp_forward_13_64_64_4_tanh", "policy"): 16000,
    ("mlp_forward_13_64_64_4_elu", "policy"): 16000,
}
POLICY_TARGET_BOARDS = ("cortex-m4f", "netduinoplus2")
POLICY_FLASH_TARGET = 22 * 1024


def png(path, rows, width=640, bar_h=14):
    """Horizontal bars of log-free linear length, one per row (label drawn by the markdown)."""
    height = bar_h * len(rows) + 4
    vmax = max(v for _, v in rows) or 1.0
    img = [[(255, 255, 255)] * width for _ in range(height)]
    for i, (_, v) in enumerate(rows):
        n = int((width - 4) * v / vmax)
        for y in range(2 + i * bar_h + 2, 2 + (i + 1) * bar_h - 2):
            for x in range(2, 2 + n):
                img[y][x] = (40, 90, 170) if i % 2 == 0 else (70, 130, 200)
    raw = b"".join(b"\x00" + bytes(c for px in row for c in px) for row in img)

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def short_symbol(name):
    """"void kestrel::allocation::(anonymous namespace)::mix_yaw<4>(Work<4>&, ...)" -> "mix_yaw<4>"."""
    name = name.replace("(anonymous namespace)", "{anon}")
    depth, end, start = 0, len(name), 0
    for i, ch in enumerate(name):
        if ch == "<":
            depth += 1
        elif ch == ">":
            depth -= 1
        elif depth == 0 and ch == "(":
            end = i
            break
        elif depth == 0 and ch == " ":
            start = i + 1  # a return type before the name
    name = name[start:end]
    depth, cut = 0, 0
    for i, ch in enumerate(name):  # last "::" outside template arguments
        if ch == "<":
            depth += 1
        elif ch == ">":
            depth -= 1
        elif depth == 0 and name.startswith("::", i):
            cut = i + 2
    return name[cut:]


def render_breakdown(results, target, image="cascade_quad", csv_name="memory_breakdown.csv",
                     what="the quad control stack's"):
    """<target>/memory_breakdown.csv (memory_breakdown.py): the quad control stack's bytes by role,
    with its largest symbols (memory_breakdown_baked.csv: the same for cascade_quad_baked;
    memory_breakdown_policy.csv: the policy controller alone)."""
    path = os.path.join(results, target, csv_name)
    if not os.path.isfile(path):
        return []
    with open(path) as f:
        rows = list(csv.DictReader(f))
    out = [f"Where {what} bytes go ({image} image minus the empty image; roles from",
           "the linked image's call graph, bench/control/memory_breakdown.py):", "",
           "| role | bytes | largest symbols |", "|---|---:|---|"]
    for t in (r for r in rows if r["row"] == "total"):
        syms = [r for r in rows if r["row"] == "symbol" and r["role"] == t["role"]][:4]
        names = ", ".join(f"{short_symbol(r['symbol'])} {r['bytes']}" for r in syms)
        out.append(f"| {t['role']} | {t['bytes']} | {names} |")
    return out + [""]


def render_policy_memory(results, target, mrows):
    """The policy image's row of memory.csv against the 22 KB goal, split into the weights' object
    and everything else (code) with memory_breakdown_policy.csv."""
    pol = next((r for r in mrows if r["image"] == "policy"), None)
    if pol is None:
        return []
    fl, ram = int(pol["flash_minus_empty"]), int(pol["static_ram_minus_empty"])
    weights = None
    path = os.path.join(results, target, "memory_breakdown_policy.csv")
    if os.path.isfile(path):
        with open(path) as f:
            weights = sum(int(r["bytes"]) for r in csv.DictReader(f)
                          if r["row"] == "symbol" and "kPositionPolicy" in r["symbol"])
    split = f" = {weights} B of float32 weights and normalisation/action constants (kPositionPolicy) + {fl - weights} B of code (and alignment)" \
        if weights else ""
    verdict = "met" if fl <= POLICY_FLASH_TARGET else "NOT met"
    return ["", f"Policy controller alone (policy image minus the empty image: observation builder -> 13-64-64-4 ELU MLP "
                f"of platform/firmware/position_policy.hpp -> action clip, the network checked at compile time): flash {fl} B{split} "
                f"(goal <= {POLICY_FLASH_TARGET} B: {verdict}), static RAM {ram} B (the held action; activations on the stack)."]


def render_stack(results, target, control_rows):
    """<target>/stack.csv (stack_usage.py): the static worst-case bound of each entry point beside
    the largest painted-stack measurement of the bench rows that call it."""
    path = os.path.join(results, target, "stack.csv")
    if not os.path.isfile(path):
        return []
    with open(path) as f:
        rows = list(csv.DictReader(f))
    painted = {}
    for r in control_rows:
        painted[r["function"]] = max(painted.get(r["function"], 0), int(r["stack_bytes"]))
    out = ["Worst-case stack: static bound (GCC `-fcallgraph-info=su` frame sizes over the whole call graph,",
           "no interrupt frame) and painted measurement (one call, one input; the largest bench row).", "",
           "| entry point | static bound bytes | painted bytes | deepest chain (frame bytes) |", "|---|---:|---:|---|"]
    for r in rows:
        ps = [painted[n] for n in r["painted_rows"].split() if n in painted]
        bound = r["static_bound_bytes"] or f"unbounded: {r['bound_problems']}"
        out.append(f"| {r['entry']} | {bound} | {max(ps) if ps else ''} | {r['deepest_chain']} |")
    unresolved = sorted({u for r in rows for u in r["unresolved_counted_as_0"].split()})
    if unresolved:
        out += ["", f"Callees outside the compiled sources, counted as 0 bytes (leaf library routines): {', '.join(unresolved)}."]
    return out + [""]


def render_host_micro(results):
    """Host micro-benchmarks (bench/micro, Google Benchmark): a table of ns per call at each batch
    size beside the Cortex-M4F instruction count of the same function, and host/micro.png (bars of
    ns per call, log scale, three per row: batch 1, 64, 4096). Returns the report's lines; nothing
    when host/micro.csv is absent."""
    path = os.path.join(results, "host", "micro.csv")
    if not os.path.isfile(path):
        return []
    with open(path) as f:
        rows = list(csv.DictReader(f))
    m4f = {}
    ctl = os.path.join(results, "cortex-m4f", "control.csv")
    if os.path.isfile(ctl):
        with open(ctl) as f:
            m4f = {(r["function"], r["airframe"]): r["instructions_per_call"] for r in csv.DictReader(f)}
    batches = sorted({int(r["batch"]) for r in rows})
    table, order = {}, []
    for r in rows:
        key = (r["function"], r["airframe"])
        if key not in table:
            table[key] = {}
            order.append(key)
        table[key][int(r["batch"])] = r
    out = ["## host: micro-benchmarks (Google Benchmark)", "",
           "CPU time per call (median of the repetitions) over N independent lanes (`bench/micro/bench_micro.cpp`:",
           "each lane its own state and output, inputs from fixed Philox streams); calls/s at batch 1; the",
           "Cortex-M4F instruction count of the same function from `cortex-m4f/control.csv` where it has the row.",
           "Wall-clock figures of a shared machine: compare rows of one run, not runs of different days.", ""]
    ctx = os.path.join(results, "host", "micro_context.txt")
    if os.path.isfile(ctx):
        with open(ctx) as f:
            out += [f"- {line.rstrip()}" for line in f if line.strip()]
        out.append("")
    head = " | ".join(f"ns/call N={n}" for n in batches)
    out += [f"| function | airframe | {head} | calls/s N={batches[0]} | spread % (N={batches[0]}) | M4F instructions/call |",
            "|---|---|" + "---:|" * (len(batches) + 3)]
    groups = []
    for key in order:
        cells = [table[key][n]["ns_per_call"] if n in table[key] else "" for n in batches]
        first = table[key].get(batches[0], {})
        ips = float(first.get("items_per_s", 0) or 0)
        out.append(f"| {key[0]} | {key[1]} | " + " | ".join(cells) +
                   f" | {ips:.3g} | {first.get('cv_percent', '')} | {m4f.get(key, '')} |")
        groups.append([float(c) if c else 0.0 for c in cells])
    _host_micro_png(os.path.join(results, "host", "micro.png"), groups)
    out += ["", "![host micro](host/micro.png) (per row of the table, bars for N = " + ", ".join(map(str, batches)) +
            " in dark to light blue; log scale, grey lines at 1 ns, 10 ns, 100 ns, 1 us, 10 us)", ""]
    return out


def _host_micro_png(path, groups, width=640, bar_h=6, gap=5):
    """Grouped horizontal bars, log10 of ns from 1 ns to the largest value (decade lines in grey)."""
    colours = [(30, 70, 150), (70, 130, 200), (150, 190, 230)]
    n = max((len(g) for g in groups), default=1)
    height = len(groups) * (n * bar_h + gap) + gap
    vmax = max((v for g in groups for v in g), default=10.0)
    span = math.log10(max(vmax, 10.0))
    img = [[(255, 255, 255)] * width for _ in range(height)]
    for d in range(int(span) + 1):
        x = 2 + int((width - 4) * d / span)
        for y in range(height):
            img[y][min(x, width - 1)] = (200, 200, 200)
    for i, g in enumerate(groups):
        for j, v in enumerate(g):
            length = int((width - 4) * math.log10(v) / span) if v > 1 else 0
            y0 = gap + i * (n * bar_h + gap) + j * bar_h
            for y in range(y0, y0 + bar_h - 1):
                for x in range(2, 2 + length):
                    img[y][x] = colours[j % len(colours)]
    raw = b"".join(b"\x00" + bytes(c for px in row for c in px) for row in img)

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def main():
    results = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "results")
    out = ["# Control benchmark (generated by bench/control/render.py)", "",
           "Instructions per call under QEMU `-icount shift=0` (SysTick, exact to one tick per region: 40",
           "instructions on the 25 MHz MPS2 boards, 125/21 = 5.95 on the 168 MHz netduinoplus2), GCC -O2;",
           "painted-stack bytes per call (one call, one input); flash / static RAM of minimal images minus",
           "an empty image (bench/control/mcu/stack_image.cpp); static worst-case stack bounds from GCC's",
           "frame sizes over the call graph (bench/control/stack_usage.py). Two runs of each image are",
           "identical (bench/control/run-mcu-bench.sh checks it).", ""]
    for target in sorted(os.listdir(results)):
        ctl = os.path.join(results, target, "control.csv")
        if not os.path.isfile(ctl):
            continue
        with open(ctl) as f:
            rows = list(csv.DictReader(f))
        out += [f"## {target}", "", "| function | airframe | instructions/call | painted stack bytes | target |", "|---|---|---:|---:|---|"]
        bars = []
        for r in rows:
            v = float(r["instructions_per_call"])
            t = TARGETS.get((r["function"], r["airframe"])) if target == "cortex-m4f" else None
            if target in POLICY_TARGET_BOARDS:
                t = POLICY_TARGETS.get((r["function"], r["airframe"]), t)
            verdict = "" if t is None else (f"<= {t}: met" if v <= t else f"<= {t}: NOT met")
            out.append(f"| {r['function']} | {r['airframe']} | {v:.1f} | {r['stack_bytes']} | {verdict} |")
            if r["function"] not in ("pseudo_inverse", "build_allocation_model"):
                bars.append((r["function"], v))
        png(os.path.join(results, target, "control.png"), bars)
        out += ["", f"![{target}]({target}/control.png) (bars: the table's rows in order, one-time pseudo-inverse rows left out)", ""]
        mem = os.path.join(results, target, "memory.csv")
        if os.path.isfile(mem):
            with open(mem) as f:
                mrows = list(csv.DictReader(f))
            out += ["| image | flash bytes | static RAM bytes | flash - empty | RAM - empty |", "|---|---:|---:|---:|---:|"]
            for r in mrows:
                out.append(f"| {r['image']} | {r['flash_bytes']} | {r['static_ram_bytes']} | {r['flash_minus_empty']} | {r['static_ram_minus_empty']} |")
            for casc in (r for r in mrows if r["image"] in ("cascade", "cascade_quad", "cascade_quad_baked")):
                if target != "cortex-m4f":
                    break
                fl, ram = int(casc["flash_minus_empty"]), int(casc["static_ram_minus_empty"])
                what = {"cascade_quad": "rotor capacity 4 (KESTREL_MAX_ROTORS=4)",
                        "cascade_quad_baked": "rotor capacity 4, parameters, allocation model and initial state generated "
                                              "at build time: no on-board pseudo-inverse or reset code, which a motor-failure "
                                              "re-allocation on board needs"}.get(casc["image"], "default rotor capacity 12")
                out += ["", f"Control stack ({casc['image']} image, {what}): flash {fl} B (target <= {FLASH_TARGET}: {'met' if fl <= FLASH_TARGET else 'NOT met'}), "
                            f"static RAM {ram} B (target <= {RAM_TARGET}: {'met' if ram <= RAM_TARGET else 'NOT met'})."]
            out += render_policy_memory(results, target, mrows)
            out.append("")
        out += render_breakdown(results, target)
        out += render_breakdown(results, target, "cascade_quad_baked", "memory_breakdown_baked.csv")
        out += render_breakdown(results, target, "policy", "memory_breakdown_policy.csv",
                                "the policy controller's (observation -> 13-64-64-4 MLP -> action clip)")
        out += render_stack(results, target, rows)
    out += render_host_micro(results)
    out += ["## Peers (issue 6, same emulator and compiler, not re-measured here)", "", "| peer | instructions/call |", "|---|---:|"]
    out += [f"| {n} | {v} |" for n, v in PEERS]
    with open(os.path.join(results, "report.md"), "w") as f:
        f.write("\n".join(out) + "\n")
    print("render: wrote", os.path.join(results, "report.md"))


if __name__ == "__main__":
    main()
