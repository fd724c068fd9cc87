#!/usr/bin/env python3
"""Renders bench/results/<target>/control.csv and memory.csv into a markdown report
(bench/results/report.md) and one bar chart per target (bench/results/<target>/control.png),
so a change in cost shows up in review as a diff of committed text and images. The host
micro-benchmarks (bench/results/host/micro.csv, written by bench/micro/run.sh) get their own
section and host/micro.png (render_host_micro), the ray-casting comparison with Embree
(bench/results/host/raycast.csv, written by kestrel_bench_raycast) its own and host/raycast.png
(render_host_raycast).

The charts are matplotlib's (pinned in python/requirements.txt, installed in .venv/ by
scripts/deps.sh): labelled bars, units, the targets. Targets from the issue are checked in the
report, not asserted here.
    .venv/bin/python bench/control/render.py [results dir]
"""
import csv
import math
import os
import sys

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


def _pyplot():
    try:
        import matplotlib
    except ImportError:
        sys.exit("render: matplotlib is missing: run this with .venv/bin/python (scripts/deps.sh installs it "
                 "from python/requirements.txt)")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def png(path, rows, title):
    """Horizontal bars, one per (label, instructions per call, target or None) row, in the table's
    order from the top; log scale (the rows span 200 to 200,000 instructions), each bar labelled
    with its value, a row's target as a red dashed mark across its bar."""
    plt = _pyplot()
    from matplotlib.lines import Line2D

    n = len(rows)
    fig, ax = plt.subplots(figsize=(10, 0.28 * n + 1.6), layout="constrained")
    ys = list(range(n))
    vals = [v for _, v, _ in rows]
    ax.barh(ys, vals, color=["#2f5aa8" if i % 2 == 0 else "#5b8fd0" for i in ys], height=0.72)
    ax.set_xscale("log")
    vmax = max(vals + [t for _, _, t in rows if t]) if rows else 10
    ax.set_xlim(min(vals) / 2 if vals else 1, vmax * 4)
    any_target = False
    for y, (_, v, t) in zip(ys, rows):
        if t:
            any_target = True
            ax.plot([t, t], [y - 0.48, y + 0.48], color="tab:red", linestyle="--", linewidth=1.6)
        # The value after the bar (and after the target mark, where it is further right).
        label = f"{v:,.0f}" + (f"  (target <= {t:,}: {'met' if v <= t else 'NOT met'})" if t else "")
        ax.text(max(v, t or 0) * 1.08, y, label, va="center", fontsize=7, color="tab:red" if t and v > t else "black")
    ax.set_yticks(ys, [label for label, _, _ in rows], fontsize=7.5)
    ax.invert_yaxis()
    ax.set_xlabel("instructions per call (log scale; QEMU -icount shift=0, GCC -O2)")
    ax.grid(axis="x", which="both", alpha=0.25)
    ax.set_title(title, fontsize=10, loc="left")
    if any_target:
        ax.legend(handles=[Line2D([], [], color="tab:red", linestyle="--", label="target (issue 6 / 11)")], loc="lower right",
                  fontsize=8)
    fig.savefig(path, dpi=100)
    plt.close(fig)


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
    _host_micro_png(os.path.join(results, "host", "micro.png"), [f"{f} ({a})" for f, a in order], groups, batches)
    out += ["", "![host micro](host/micro.png) (per row of the table, bars for N = " + ", ".join(map(str, batches)) +
            " in dark to light blue; ns per call, log scale)", ""]
    return out


def _host_micro_png(path, labels, groups, batches):
    """Grouped horizontal bars: per function x airframe (one row of the table), one bar per batch
    size N, ns per call on a log scale, each bar labelled with its value."""
    plt = _pyplot()
    colours = ["#1e4696", "#4682c8", "#96bee6"]
    n = len(batches)
    h = 0.8 / max(1, n)
    fig, ax = plt.subplots(figsize=(10, 0.42 * len(groups) + 1.8), layout="constrained")
    for j, b in enumerate(batches):
        ys = [i + (j - (n - 1) / 2) * h for i in range(len(groups))]
        vals = [g[j] if j < len(g) else 0.0 for g in groups]
        ax.barh(ys, vals, height=h * 0.95, color=colours[j % len(colours)], label=f"N = {b} lane{'s' if b != 1 else ''}")
        for y, v in zip(ys, vals):
            if v > 0:
                ax.text(v * 1.05, y, f"{v:,.0f}" if v >= 100 else f"{v:.3g}", va="center", fontsize=5.5)
    ax.set_xscale("log")
    top = max((v for g in groups for v in g), default=10.0)
    ax.set_xlim(right=top * 2.5)
    ax.set_yticks(range(len(groups)), labels, fontsize=7.5)
    ax.invert_yaxis()
    ax.set_xlabel("CPU time per call (ns, log scale; median of the repetitions)")
    ax.grid(axis="x", which="both", alpha=0.25)
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title("host micro-benchmarks (Google Benchmark, bench/micro): ns per call by batch size", fontsize=10, loc="left")
    fig.savefig(path, dpi=100)
    plt.close(fig)


# Issue 18: on the triangles-only scene, Kestrel's render at least Embree's rtcIntersect8 rate on
# the coherent camera rays (the same rays and triangles, one thread, measured in one run).
RAYCAST_GOAL = ("camera_135x240_triangles", 1.0)


def render_host_raycast(results):
    """Ray casting vs Embree 3 (bench/raycast, written by kestrel_bench_raycast --csv): a table of
    Mrays/s per sensor and scene (Kestrel's tiled render and single rays; Embree's rtcIntersect1/4/8)
    with the ratios measured in the same run, and host/raycast.png (grouped bars). Rows of an older
    CSV without the scene / single-ray columns are shown with those cells empty. Returns the
    report's lines; nothing when host/raycast.csv is absent."""
    path = os.path.join(results, "host", "raycast.csv")
    if not os.path.isfile(path):
        return []
    with open(path) as f:
        rows = list(csv.DictReader(f))
    out = ["## host: ray casting vs Embree 3 (bench/raycast)", "",
           "Mrays/s, one thread, the same rays and scene on both sides, every figure of a row from one run",
           "(`build/host/bench/raycast/kestrel_bench_raycast --csv bench/results/host/raycast.csv`). Scene",
           "`mixed`: boxes, capsule trunks and a mesh; Kestrel intersects boxes and capsules analytically, Embree",
           "gets the trunks as round curves (its slowest primitive). Scene `triangles`: the same field as one",
           "triangle soup on both sides. Kestrel: `render` (8x8 tiles) and `Scene::intersect` one ray at a time;",
           "Embree: `rtcIntersect1`, and `rtcIntersect4/8` on 4x1 / 8x1 pixel packets of a row.", ""]
    notes = sorted({r.get("note", "") for r in rows if r.get("note")})
    out += [f"- {n}" for n in notes]
    if notes:
        out.append("")
    out += ["| sensor | scene | rays | Kestrel render | Kestrel single rays | Embree 1 | Embree 4 | Embree 8 | "
            "render / Embree 1 | render / Embree 8 | distance mismatches | render vs single-ray diffs |",
            "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    labels, groups = [], []
    for r in rows:
        k, e1, e8 = float(r["kestrel_mrays_s"]), float(r["embree_rtcintersect1_mrays_s"]), float(r["embree_rtcintersect8_mrays_s"])
        single = r.get("kestrel_single_ray_mrays_s", "")
        scene = r.get("scene", "") or "mixed"
        out.append(f"| {r['sensor']} | {scene} | {r['rays']} | {k:.2f} | {float(single):.2f} | " if single else
                   f"| {r['sensor']} | {scene} | {r['rays']} | {k:.2f} |  | ")
        out[-1] += (f"{e1:.2f} | {float(r['embree_rtcintersect4_mrays_s']):.2f} | {e8:.2f} | {k / e1:.2f}x | {k / e8:.2f}x | "
                    f"{r['mismatches']} | {r['render_vs_single_ray_diffs']} |")
        labels.append(f"{r['sensor']}")
        groups.append([k, float(single) if single else 0.0, e1, float(r["embree_rtcintersect4_mrays_s"]), e8])
    goal = next((r for r in rows if r["sensor"] == RAYCAST_GOAL[0]), None)
    if goal is not None:
        ratio = float(goal["kestrel_mrays_s"]) / float(goal["embree_rtcintersect8_mrays_s"])
        out += ["", f"Issue 18 goal, {RAYCAST_GOAL[0]}: Kestrel render >= {RAYCAST_GOAL[1]:.1f}x Embree rtcIntersect8: "
                    f"{ratio:.2f}x, {'met' if ratio >= RAYCAST_GOAL[1] else 'NOT met'}."]
    _host_raycast_png(os.path.join(results, "host", "raycast.png"), labels, groups)
    out += ["", "![host raycast](host/raycast.png) (per row of the table: Kestrel render, Kestrel single rays, Embree "
                "rtcIntersect1, 4, 8; Mrays/s)", ""]
    return out


def _host_raycast_png(path, labels, groups):
    """Grouped horizontal bars: per sensor row, Kestrel (render, single rays) in greens and Embree
    (rtcIntersect1/4/8) in blues, Mrays/s on a linear scale, each bar labelled with its value."""
    plt = _pyplot()
    series = [("Kestrel render (8x8 tiles)", "#1b7837"), ("Kestrel Scene::intersect, single rays", "#7fbf7b"),
              ("Embree rtcIntersect1", "#96bee6"), ("Embree rtcIntersect4 (4x1)", "#4682c8"),
              ("Embree rtcIntersect8 (8x1)", "#1e4696")]
    n = len(series)
    h = 0.8 / n
    fig, ax = plt.subplots(figsize=(10, 0.9 * len(groups) + 1.8), layout="constrained")
    for j, (name, colour) in enumerate(series):
        ys = [i + (j - (n - 1) / 2) * h for i in range(len(groups))]
        vals = [g[j] for g in groups]
        ax.barh(ys, vals, height=h * 0.95, color=colour, label=name)
        for y, v in zip(ys, vals):
            if v > 0:
                ax.text(v + 0.2, y, f"{v:.1f}", va="center", fontsize=6.5)
    top = max((v for g in groups for v in g), default=10.0)
    ax.set_xlim(0, top * 1.15)
    ax.set_yticks(range(len(groups)), labels, fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel("million rays per second, one thread (higher is better)")
    ax.grid(axis="x", alpha=0.25)
    ax.legend(loc="lower right", fontsize=7.5)
    ax.set_title("ray casting, Kestrel vs Embree 3 (bench/raycast): same rays, same scene, one run", fontsize=10, loc="left")
    fig.savefig(path, dpi=100)
    plt.close(fig)


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
                bars.append((f"{r['function']} ({r['airframe']})", v, t))
        png(os.path.join(results, target, "control.png"), bars,
            f"{target}: instructions per call\n(the table's rows; one-time pseudo-inverse rows left out)")
        out += ["", f"![{target}]({target}/control.png) (bars: the table's rows in order, one-time pseudo-inverse rows left out; "
                    "log scale, targets dashed red)", ""]
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
    out += render_host_raycast(results)
    out += ["## Peers (issue 6, same emulator and compiler, not re-measured here)", "", "| peer | instructions/call |", "|---|---:|"]
    out += [f"| {n} | {v} |" for n, v in PEERS]
    with open(os.path.join(results, "report.md"), "w") as f:
        f.write("\n".join(out) + "\n")
    print("render: wrote", os.path.join(results, "report.md"))


if __name__ == "__main__":
    main()
