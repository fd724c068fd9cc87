#!/usr/bin/env python3
"""Static worst-case stack use of the control stack's entry points on a Cortex-M build, from GCC's
own per-function frame sizes and call graph (-fcallgraph-info=su, GCC >= 10: the .su figures of
-fstack-usage plus the call edges, one .ci file per object).

    bench/control/stack_usage.py <mcu build dir> [out.csv] [--strict]

--strict (the ctest kestrel_stack_usage): exit 1 if an entry point is missing or its bound is
unknown (recursion, an unresolved indirect call or a dynamic frame appeared in the control path).

Every core source (kernel/, controllers/, allocation/, sensors/, platform/capi/) and the
control-stack image (bench/control/mcu/stack_image.cpp, cascade variant) is compiled again with
exactly the command in the build's compile_commands.json plus -fcallgraph-info=su, into a
temporary folder (the build itself is not touched; the flag does not change code generation).
The bound of a function is its own frame plus the largest bound of anything it calls, over the
whole call graph. It is an upper bound for the path it finds, provided the report says:
  - no recursion and no indirect call on the way (both would make the bound unknown: reported),
  - no dynamic frame (alloca / VLA: reported),
  - the callees outside the compiled sources (newlib's memcpy/memset, libgcc) are listed under
    "unresolved" and counted as 0 bytes: they are leaf routines of a few words each.
An interrupt taken on top adds its exception frame (32 bytes, 104 with the FP context) and its
handler's own use; not included. The painted-stack figures (bench/control/mcu/control_bench.cpp,
control.csv column stack_bytes) measure one call with one input; this bound covers every path.
"""
import concurrent.futures
import csv
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
# The core, the C API, and the board runtime (assertion and fault paths end in its console).
CORE_DIRS = ("kernel/", "controllers/", "allocation/", "robots/", "sensors/", "platform/capi/", "platform/cortex-m/src/",
             "platform/riscv/src/", "platform/mcu/src/", "platform/common/")

# Entry points: (name in the report, demangled-name prefix of the function, control.csv rows whose
# painted stack measures the same call (their maximum is reported beside the bound)).
ENTRIES = [
    ("cascade_step (Lee position -> sequential desaturation -> motor model)", "{anonymous}::cascade_step(",
     ["cascade_lee_position_desat_motors"]),
    ("update_lee_position", "kestrel::update_lee_position(", ["update_lee_position"]),
    ("allocate_sequential_desaturation", "kestrel::allocation::allocate_sequential_desaturation(",
     ["allocate_sequential_desaturation_saturated", "allocate_sequential_desaturation_feasible"]),
    ("motor_model_step", "kestrel::allocation::motor_model_step(", ["motor_model_step_rk4_rps"]),
    ("update_controller (any kind)", "kestrel::update_controller(", []),
    ("allocate_cls", "kestrel::allocation::allocate_cls(", ["allocate_cls_warm"]),
    ("pseudo_inverse", "kestrel::allocation::pseudo_inverse(", ["pseudo_inverse"]),
    ("build_allocation_model", "kestrel::allocation::build_allocation_model(", ["build_allocation_model"]),
    ("kestrel_step (C API)", "kestrel_step(", ["kestrel_step_capi"]),
    ("sensors::render (ToF scan)", "kestrel::sensors::render(", ["tof_scan_vl53l5cx_8x8"]),
]

# Indirect calls with a known target set: caller prefix -> (callee prefixes, note). An indirect call
# anywhere else makes the bound unknown.
INDIRECT = {
    # controllers/src/controller.cpp: the dispatch table kTable's lee_update entries.
    "kestrel::update_controller(": (["kestrel::update_lee_position(", "kestrel::update_lee_velocity(",
                                     "kestrel::update_lee_acceleration(", "kestrel::update_lee_attitude(",
                                     "kestrel::update_lee_rates(", "kestrel::update_lee_velocity_steering_angle(",
                                     "kestrel::update_rov_fully_actuated("], None),
    # kernel/src/assert.cpp: a handler installed with set_assert_handler (none in the firmware and
    # bench images; the default handler is a direct call and is counted).
    "kestrel::assert_failed(": ([], "a user-installed assert handler is not counted"),
}

NODE = re.compile(r'node: \{ title: "([^"]*)" label: "((?:[^"\\]|\\.)*)"')
EDGE = re.compile(r'edge: \{ sourcename: "([^"]*)" targetname: "([^"]*)"')
SIZE = re.compile(r"\\n(\d+) bytes \(([a-z,]+)\)")


def compile_ci(build):
    with open(os.path.join(build, "compile_commands.json")) as f:
        cmds = json.load(f)
    jobs = []
    seen = set()
    for c in cmds:
        rel = os.path.relpath(c["file"], ROOT)
        is_core = rel.startswith(CORE_DIRS)
        is_image = rel == "bench/control/mcu/stack_image.cpp" and "KESTREL_STACK_CASCADE" in c["command"]
        if not (is_core or is_image) or rel in seen or not rel.endswith((".cpp", ".c")):
            continue
        seen.add(rel)
        jobs.append((rel, c))
    tmp = tempfile.mkdtemp(prefix="kestrel-stack-")

    def run(job):
        rel, c = job
        args = shlex.split(c["command"])
        i = args.index("-o")
        out = os.path.join(tmp, rel.replace("/", "_") + ".o")
        args[i + 1] = out
        r = subprocess.run(args + ["-fcallgraph-info=su"], cwd=c["directory"], capture_output=True, text=True)
        if r.returncode != 0:
            raise SystemExit(f"stack_usage: compiling {rel} failed:\n{r.stderr}")
        return os.path.join(tmp, rel.replace("/", "_") + ".ci")

    try:
        # KESTREL_BENCH_JOBS (run-mcu-bench.sh passes it): the machine may be shared.
        jobs_n = max(1, int(os.environ.get("KESTREL_BENCH_JOBS", "2")))
        with concurrent.futures.ThreadPoolExecutor(max_workers=jobs_n) as ex:
            return tmp, list(ex.map(run, jobs))
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def parse(ci_files):
    frames, kinds, labels, edges = {}, {}, {}, {}
    for path in ci_files:
        with open(path) as f:
            # GCC names a node of an alias emitted in this unit (a C1 constructor for its C2 body)
            # "<source file>:<symbol>": the same function as <symbol>.
            text = re.sub(r'"/[^"]*:([A-Za-z_][^"]*)"', r'"\1"', f.read())
        for title, label in NODE.findall(text):
            labels.setdefault(title, label.split("\\n")[0])
            m = SIZE.search(label)
            if m:  # a definition (declarations carry no size)
                frames[title] = max(frames.get(title, 0), int(m.group(1)))
                kinds[title] = m.group(2)
        for src, dst in EDGE.findall(text):
            edges.setdefault(src, set()).add(dst)
    # A complete-object constructor/destructor (C1/D1) called where only its base-object twin
    # (C2/D2, the same code) is defined.
    for src in edges:
        for dst in list(edges[src]):
            twin = re.sub(r"([CD])1E", r"\g<1>2E", dst)
            if dst not in frames and twin in frames:
                edges[src].discard(dst)
                edges[src].add(twin)
    # GCC's split-off parts (f.part.0, f.constprop.0) are labelled "0(...)": name them after f.
    for t in frames:
        if labels[t].startswith("0("):
            base = re.sub(r"\.(part|constprop|isra|cold)\.\d+$", "", t)
            name = labels[base] if base in labels else subprocess.run(
                ["c++filt", base], capture_output=True, text=True).stdout.strip()
            name = name.replace("(anonymous namespace)", "{anonymous}").split("(")[0]
            labels[t] = name + "[" + t[len(base) + 1:] + "]" + labels[t][1:]
    return frames, kinds, labels, edges


def strip_return_type(label):
    """"kestrel::Status kestrel::allocation::f(...)" -> "kestrel::allocation::f(...)": drops what
    precedes the last space outside template brackets before the parameter list."""
    depth, cut = 0, -1
    for i, ch in enumerate(label):
        if ch == "<":
            depth += 1
        elif ch == ">":
            depth -= 1
        elif ch == "(" and depth == 0:
            break
        elif ch == " " and depth == 0:
            cut = i
    return label[cut + 1:]


def resolve_indirect(frames, labels, edges):
    """Replaces __indirect_call edges of the callers in INDIRECT by their known targets."""
    notes = set()
    for caller in list(edges):
        if "__indirect_call" not in edges[caller]:
            continue
        name = strip_return_type(labels.get(caller, caller))
        for prefix, (targets, note) in INDIRECT.items():
            if name.startswith(prefix):
                edges[caller].discard("__indirect_call")
                for t in frames:
                    if any(strip_return_type(labels[t]).startswith(p) for p in targets):
                        edges[caller].add(t)
                if note:
                    notes.add(note)
    return notes


def bound(fn, frames, kinds, edges, memo, active):
    """(bytes, path, problems, unresolved) of the deepest call chain from fn."""
    if fn in memo:
        return memo[fn]
    if fn in active:
        return (0, [], {f"recursion through {fn}"}, set())
    if fn not in frames:
        if fn == "__indirect_call":
            return (0, [], {"indirect call"}, set())
        return (0, [], set(), {fn})
    active.add(fn)
    best, best_path, problems, unresolved = 0, [], set(), set()
    if kinds.get(fn, "static") != "static":
        problems.add(f"{kinds[fn]} frame in {fn}")
    for callee in sorted(edges.get(fn, ())):
        b, p, pr, un = bound(callee, frames, kinds, edges, memo, active)
        problems |= pr
        unresolved |= un
        if b > best:
            best, best_path = b, p
    active.discard(fn)
    memo[fn] = (frames[fn] + best, [fn] + best_path, problems, unresolved)
    return memo[fn]


def main():
    strict = "--strict" in sys.argv
    args = [a for a in sys.argv[1:] if a != "--strict"]
    if not args:
        raise SystemExit(__doc__)
    build = os.path.abspath(args[0])
    out = args[1] if len(args) > 1 else None
    failures = []
    tmp, ci_files = compile_ci(build)
    try:
        frames, kinds, labels, edges = parse(ci_files)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    notes = resolve_indirect(frames, labels, edges)
    memo = {}
    rows = []
    for name, prefix, bench_rows in ENTRIES:
        fns = sorted(t for t in frames if strip_return_type(labels[t]).startswith(prefix))
        if not fns:
            print(f"stack_usage: {name}: no function {prefix}... in the build", file=sys.stderr)
            failures.append(name)
            continue
        # Overloads (e.g. two build_allocation_model): the largest.
        b, path, problems, unresolved = max((bound(f, frames, kinds, edges, memo, set()) for f in fns), key=lambda r: r[0])
        chain = " > ".join(f"{re.sub(r'[(].*', '', strip_return_type(labels[f]))}[{frames[f]}]" for f in path)
        if problems:
            failures.append(name)
        rows.append({"entry": name, "static_bound_bytes": b if not problems else "",
                     "bound_problems": "; ".join(sorted(problems)),
                     "unresolved_counted_as_0": " ".join(sorted(unresolved)), "deepest_chain": chain,
                     "painted_rows": " ".join(bench_rows)})
    fields = ["entry", "static_bound_bytes", "bound_problems", "unresolved_counted_as_0", "deepest_chain", "painted_rows"]
    if out:
        with open(out, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=fields, lineterminator="\n")
            w.writeheader()
            w.writerows(rows)
    for n in sorted(notes):
        print("stack_usage: note:", n)
    for r in rows:
        print(f"{r['entry']}: {r['static_bound_bytes'] or 'unbounded'} bytes"
              f"{' (' + r['bound_problems'] + ')' if r['bound_problems'] else ''}; {r['deepest_chain']}")
    if strict and failures:
        print("stack_usage: FAIL: no bound for: " + ", ".join(failures), file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
