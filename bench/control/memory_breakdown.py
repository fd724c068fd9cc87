#!/usr/bin/env python3
"""Where the control stack's flash and static RAM go: the symbols of a control-stack image
(bench/control/mcu/stack_image.cpp) that the empty image does not have, by role.

    bench/control/memory_breakdown.py <empty.elf> <image.elf> [out.csv]

Roles come from the linked image's own call graph (arm-none-eabi-objdump -d: `bl`/`b` targets;
RISC-V, with KESTREL_BINUTILS_PREFIX=riscv64-unknown-elf-: `jal`/`j` targets and `jalr` with a
resolved target; so inlining is already accounted for): per-step code is everything reachable from cascade_step
(the function a flight controller calls every control period; policy_step in the policy image), set-up code what only setup()
reaches (airframe, pseudo-inverse, presets, resets), static initialisation what only the
_GLOBAL__sub_I_* constructors reach (zeroing of the state objects). Data symbols are split into
read-only data (flash) and RAM (.data/.bss). The CSV has one row per symbol (role, bytes, name)
after one total row per role.
"""
import csv
import re
import subprocess
import sys

import os

TOOL = os.environ.get("KESTREL_BINUTILS_PREFIX", "arm-none-eabi-")


def symbols(elf):
    out = subprocess.run([TOOL + "nm", "-S", elf], capture_output=True, text=True, check=True).stdout
    syms = {}
    for line in out.splitlines():
        p = line.split()
        if len(p) == 4:
            syms[p[3]] = (int(p[0], 16), int(p[1], 16), p[2])
    return syms


def ram_origin(elf):
    """The RAM region's start (__ram_start of the board's linker script: 0x20000000 on the Cortex-M
    boards, 0x80800000 on RISC-V virt, where "flash" is the DRAM below it)."""
    out = subprocess.run([TOOL + "nm", elf], capture_output=True, text=True, check=True).stdout
    for line in out.splitlines():
        p = line.split()
        if len(p) == 3 and p[2] == "__ram_start":
            return int(p[0], 16)
    return 0x20000000


def call_graph(elf):
    """{function start address: set of called addresses} and {address: name}, from the
    disassembly (addresses, not names: constructor aliases C1/C2 share one address)."""
    out = subprocess.run([TOOL + "objdump", "-d", "--no-show-raw-insn", elf], capture_output=True, text=True,
                         check=True).stdout
    graph, names, current = {}, {}, None
    head = re.compile(r"^([0-9a-f]+) <([^>]+)>:$")
    call = re.compile(r"\t(?:bl|blx|b|b\.w|b\.n|b[a-z][a-z]\.w|jal|j)\s+(?:ra,)?([0-9a-f]+) <([^>+]+)>"
                      r"|\tjalr\s.*# ([0-9a-f]+) <([^>+]+)>")
    for line in out.splitlines():
        m = head.match(line)
        if m:
            current = int(m.group(1), 16)
            names[current] = m.group(2)
            graph.setdefault(current, set())
            continue
        m = call.search(line)
        if m and current is not None:
            target = int(m.group(1) or m.group(3), 16)
            if target != current:
                graph[current].add(target)
    return graph, names


def reach(graph, roots):
    seen, todo = set(), list(roots)
    while todo:
        f = todo.pop()
        if f in seen:
            continue
        seen.add(f)
        todo.extend(graph.get(f, ()))
    return seen


def demangle(names):
    out = subprocess.run(["c++filt"], input="\n".join(names), capture_output=True, text=True).stdout
    return out.splitlines()


def main():
    if len(sys.argv) < 3:
        raise SystemExit(__doc__)
    empty, image = symbols(sys.argv[1]), symbols(sys.argv[2])
    graph, fnames = call_graph(sys.argv[2])
    roots = lambda pat: [a for a, n in fnames.items() if re.search(pat, n)]  # noqa: E731
    # cascade_step: the control-stack images; policy_step: the policy image (KESTREL_STACK_POLICY).
    step = reach(graph, roots(r"cascade_step|policy_step"))
    setup = reach(graph, roots(r"setup")) - step
    init = reach(graph, roots(r"^_GLOBAL__sub_I_")) - step - setup
    rows, seen_addr = [], set()
    ram = ram_origin(sys.argv[2])
    for name, (addr, size, kind) in sorted(image.items(), key=lambda kv: kv[1][0]):
        if name in empty or size == 0 or (addr, size) in seen_addr:
            continue  # aliases (C1/C2 constructors) once
        seen_addr.add((addr, size))
        if addr >= ram:
            role = "static RAM"
        elif kind in "TtWw":
            a = addr & ~1  # Thumb bit
            role = ("per-step code" if a in step else "set-up code" if a in setup else
                    "static initialisation" if a in init else "other code")
        else:
            role = "read-only data (flash)"
        rows.append((role, size, name))
    totals = {}
    for role, size, _ in rows:
        totals[role] = totals.get(role, 0) + size
    order = ["per-step code", "set-up code", "static initialisation", "other code", "read-only data (flash)", "static RAM"]
    rows.sort(key=lambda r: (order.index(r[0]), -r[1]))
    names = demangle([r[2] for r in rows])
    out = sys.argv[3] if len(sys.argv) > 3 else None
    lines = [("total", role, totals[role], "") for role in order if role in totals]
    lines += [("symbol", role, size, nm) for (role, size, _), nm in zip(rows, names)]
    if out:
        with open(out, "w", newline="") as f:
            w = csv.writer(f, lineterminator="\n")
            w.writerow(["row", "role", "bytes", "symbol"])
            w.writerows(lines)
    for kind, role, size, nm in lines:
        if kind == "total" or size >= 200:
            print(f"{kind:6} {role:24} {size:6} {nm[:110]}")


if __name__ == "__main__":
    main()
