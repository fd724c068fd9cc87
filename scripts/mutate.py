#!/usr/bin/env python3
"""Mutation run over the core (no Mull on Debian 12: `apt-cache policy mull` finds nothing).

Hand-picked operators over kernel/ controllers/ allocation/ sensors/ robots/ policy/ sources
(src/*.cpp): '+' <-> '-' in arithmetic, '<' <-> '<=', '>' <-> '>=', the constant 0.5 -> 0.75,
1e-5 -> 1e-2, and swapped operands of '*' on quaternions; plus the four mutants of
tests/MUTANTS.md, always included. One mutant at a time: apply it, rebuild kestrel_core_tests in
build/mutate (host preset, Release, MCU tests off; ccache if the environment sets it), run it with
a timeout, restore the file with `git checkout -- FILE`. A mutant is killed when the build of the
tests still succeeds and the tests fail or time out; one that does not compile is not counted.

    scripts/mutate.py [--sample N] [--seed S] [--timeout SECONDS] [--list] [--report FILE]

The sample is drawn from every candidate (sorted by file, line, operator) with random.Random(seed),
so a run is reproducible for a given tree.
"""
import argparse, os, random, re, subprocess, sys, time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
DIRS = ["kernel", "controllers", "allocation", "sensors", "robots", "policy"]
BUILD = os.path.join(ROOT, "build", "mutate")

# (name, regex, replacement). Applied to code lines only (comments, #-lines and string literals skipped).
OPERATORS = [
    ("plus->minus", re.compile(r"(?<=[\w)\]]) \+ (?=[\w(])"), " - "),
    ("minus->plus", re.compile(r"(?<=[\w)\]]) - (?=[\w(])"), " + "),
    ("lt->le", re.compile(r"(?<=[\w)\]]) < (?=[\w(-])"), " <= "),
    ("le->lt", re.compile(r" <= "), " < "),
    ("gt->ge", re.compile(r"(?<=[\w)\]]) > (?=[\w(-])"), " >= "),
    ("ge->gt", re.compile(r" >= "), " > "),
    ("0.5->0.75", re.compile(r"\b0\.5(_r|f)?\b"), None),
    ("1e-5->1e-2", re.compile(r"\b1e-5(_r|f)?\b"), None),
    ("swap-quat-mul", re.compile(r"\b((?:q\w*|\w*quat\w*|\w*orientation\w*|\w*_q)(?:\.\w+\(\))?) \* "
                                 r"((?:q\w*|\w*quat\w*|\w*orientation\w*|\w*misalignment\w*|\w*_q)\w*(?:\.\w+\(\))?)\b"), None),
]

# tests/MUTANTS.md: (id, file, original, mutant); each original occurs once in its file.
FIXED = [
    ("a", "allocation/src/sequential_desaturation.cpp", "headroom * (w.hi[i] - w.lo[i])", "headroom * (w.hi[i] + w.lo[i])"),
    ("b", "sensors/src/imu.cpp", "q_bs_nominal * s.misalignment_bs", "s.misalignment_bs * q_bs_nominal"),
    ("c", "allocation/src/sequential_desaturation.cpp", "1e-5_r * (hi - lo)", "1e-2_r * (hi - lo)"),
    ("d", "allocation/src/sequential_desaturation.cpp", "gain = 0.5_r * desaturation_gain", "gain = 0.75_r * desaturation_gain"),
]


def code_part(line):
    """The line with string literals blanked and // comments cut (same length up to the cut)."""
    s = re.sub(r'"(\\.|[^"\\])*"', lambda m: '"' + " " * (len(m.group(0)) - 2) + '"', line)
    i = s.find("//")
    return s if i < 0 else s[:i]


def candidates():
    out = []
    for d in DIRS:
        src = os.path.join(ROOT, d, "src")
        if not os.path.isdir(src):
            continue
        for f in sorted(os.listdir(src)):
            if not f.endswith(".cpp"):
                continue
            rel = os.path.join(d, "src", f)
            in_block = False
            for ln, line in enumerate(open(os.path.join(ROOT, rel)).read().split("\n"), 1):
                st = line.strip()
                if in_block:
                    if "*/" in st:
                        in_block = False
                    continue
                if st.startswith("/*"):
                    in_block = "*/" not in st
                    continue
                if st.startswith("#") or st.startswith("//") or st.startswith("*"):
                    continue
                code = code_part(line)
                for name, rx, rep in OPERATORS:
                    for m in rx.finditer(code):
                        if name == "0.5->0.75":
                            new = "0.75" + (m.group(1) or "")
                        elif name == "1e-5->1e-2":
                            new = "1e-2" + (m.group(1) or "")
                        elif name == "swap-quat-mul":
                            new = m.group(2) + " * " + m.group(1)
                        else:
                            new = rep
                        out.append({"file": rel, "line": ln, "col": m.start(), "end": m.end(), "op": name,
                                    "orig": line[m.start():m.end()], "new": new})
    return out


def fixed_mutants():
    out = []
    for mid, rel, orig, new in FIXED:
        text = open(os.path.join(ROOT, rel)).read()
        lines = text.split("\n")
        assert text.count(orig) == 1, (rel, orig)
        for ln, line in enumerate(lines, 1):
            if orig in line:
                col = line.index(orig)
                out.append({"file": rel, "line": ln, "col": col, "end": col + len(orig), "op": "MUTANTS.md " + mid,
                            "orig": orig, "new": new})
    return out


def apply(m):
    path = os.path.join(ROOT, m["file"])
    lines = open(path).read().split("\n")
    l = lines[m["line"] - 1]
    assert l[m["col"]:m["end"]] == m["orig"], (m, l)
    lines[m["line"] - 1] = l[:m["col"]] + m["new"] + l[m["end"]:]
    open(path, "w").write("\n".join(lines))


def restore(m):
    subprocess.run(["git", "checkout", "--", m["file"]], cwd=ROOT, check=True)


def sh(cmd, timeout):
    try:
        return subprocess.run(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=timeout).returncode
    except subprocess.TimeoutExpired:
        return "timeout"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sample", type=int, default=40)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--timeout", type=int, default=300, help="seconds for one run of kestrel_core_tests")
    ap.add_argument("--jobs", default="2")
    ap.add_argument("--list", action="store_true", help="print the chosen mutants and exit")
    ap.add_argument("--report", help="append a markdown summary to this file")
    a = ap.parse_args()
    dirty = subprocess.run(["git", "status", "--porcelain", "--"] + DIRS, cwd=ROOT, stdout=subprocess.PIPE, text=True).stdout
    if dirty.strip():
        sys.exit("mutate.py: uncommitted changes under the core directories (mutants are reverted with git checkout):\n" + dirty)
    cands = candidates()
    rng = random.Random(a.seed)
    chosen = fixed_mutants() + rng.sample(cands, min(a.sample, len(cands)))
    print(f"mutate.py: {len(cands)} candidate mutants, running {len(chosen)} (4 of tests/MUTANTS.md + {len(chosen) - 4} "
          f"drawn with seed {a.seed})", flush=True)
    if a.list:
        for m in chosen:
            print(f"  {m['file']}:{m['line']}:{m['col'] + 1}  {m['op']}: {m['orig']!r} -> {m['new']!r}")
        return
    if not os.path.exists(os.path.join(BUILD, "build.ninja")):
        subprocess.run(["cmake", "--preset", "host", "-B", BUILD, "-DKESTREL_MCU_TESTS=OFF", "-DKESTREL_INSTALL=OFF",
                        "-DKESTREL_BUILD_BENCH=OFF"], cwd=ROOT, check=True, stdout=subprocess.DEVNULL)
    build = ["cmake", "--build", BUILD, "-j", a.jobs, "--target", "kestrel_core_tests"]
    test = [os.path.join(BUILD, "tests", "kestrel_core_tests"), "--gtest_brief=1"]
    if sh(build, 1800) != 0 or sh(test, a.timeout) != 0:
        sys.exit("mutate.py: the unmutated tree does not build or pass kestrel_core_tests")
    results = []
    for i, m in enumerate(chosen, 1):
        t0 = time.time()
        apply(m)
        try:
            b = sh(build, 900)
            if b != 0:
                verdict = "stillborn"
            else:
                r = sh(test, a.timeout)
                verdict = "killed (timeout)" if r == "timeout" else ("killed" if r != 0 else "SURVIVED")
        finally:
            restore(m)
        m["verdict"] = verdict
        results.append(m)
        print(f"[{i}/{len(chosen)}] {verdict:16s} {m['file']}:{m['line']}:{m['col'] + 1}  {m['op']}: {m['orig']!r} -> {m['new']!r} "
              f"({time.time() - t0:.0f} s)", flush=True)
    sh(build, 1800)  # leave build/mutate matching the tree
    counted = [m for m in results if m["verdict"] != "stillborn"]
    killed = [m for m in counted if m["verdict"].startswith("killed")]
    survived = [m for m in counted if m["verdict"] == "SURVIVED"]
    score = 100.0 * len(killed) / max(1, len(counted))
    summary = (f"{len(killed)} killed / {len(counted)} compiled mutants = {score:.1f}% "
               f"({len(results) - len(counted)} did not compile; seed {a.seed}, sample {a.sample})")
    print("mutate.py: " + summary)
    for m in survived:
        print(f"  survived: {m['file']}:{m['line']}:{m['col'] + 1}  {m['op']}: {m['orig']!r} -> {m['new']!r}")
    if a.report:
        with open(a.report, "a") as f:
            f.write(f"\n### Run of {time.strftime('%Y-%m-%d')} (`scripts/mutate.py --sample {a.sample} --seed {a.seed}`)\n\n")
            f.write(f"Score: {summary}.\n\n| | mutant | where | verdict |\n|---|---|---|---|\n")
            for i, m in enumerate(results, 1):
                f.write(f"| {i} | {m['op']}: `{m['orig']}` -> `{m['new']}` | `{m['file']}:{m['line']}:{m['col'] + 1}` | {m['verdict']} |\n")
    sys.exit(0)


if __name__ == "__main__":
    main()
