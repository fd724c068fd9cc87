#!/usr/bin/env python3
"""A bench program's progress line (issue 15), run by ctest as
`python3 progress_test.py [--erased] UNIT PROGRAM ARGS...` with ARGS making a run of a couple of seconds.

The same run three times, as tests/sim/cli_progress_test.py does for `kestrel run`:
  1. stderr a pipe (not a terminal): no progress text at all;
  2. stderr a pseudo-terminal: lines "UNIT DONE / TOTAL (P%), RATE UNIT/s, T left", the
     percentages rising within a total, and the program's table (stdout) as in run 1; the last
     line complete (100%) and ended by a newline, or with --erased (a line per case, erased before
     the case's row prints: bench_sim, bench_task) the terminal's line erased at the end;
  3. stderr a pseudo-terminal with --quiet: nothing on it.
Standard library only (pty), so it needs no virtual environment.
"""
import os
import re
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "support"))
from pty_run import run, value  # noqa: E402


def main():
    args = sys.argv[1:]
    erased = args[0] == "--erased"
    if erased:
        args = args[1:]
    unit, cmd = args[0], args[1:]
    line = re.compile(r"\r  " + re.escape(unit) + r" ([0-9.]+[kMG]?) / ([0-9.]+[kMG]?) \((\d+)%\), ([0-9.]+[kMG]?) "
                      + re.escape(unit) + r"/s, ([^\r\n\x1b]*) left\x1b\[K")
    rc, out_pipe, err_pipe = run(cmd, tty=False)
    assert rc == 0, (rc, out_pipe, err_pipe)
    assert f"{unit}/s" not in err_pipe and "\r" not in err_pipe, f"progress on a pipe: {err_pipe!r}"

    rc, out_tty, err_tty = run(cmd, tty=True)
    assert rc == 0, (rc, out_tty, err_tty)
    found = line.findall(err_tty)
    assert len(found) >= 2, f"expected progress lines on the terminal, got {err_tty!r}"
    for _, total, _, _, _ in found:
        assert value(total) > 0
    if erased:
        pct = [int(p) for _, _, p, _, _ in found]
        assert max(pct) <= 100, pct
        assert err_tty.endswith("\r\x1b[K") and "\n" not in err_tty, repr(err_tty[-80:])
    else:
        totals = {t for _, t, _, _, _ in found}
        assert len(totals) == 1, totals
        pct = [int(p) for _, _, p, _, _ in found]
        assert pct == sorted(pct) and pct[0] < 100 and pct[-1] == 100, pct
        assert value(found[-1][0]) == value(found[-1][1])
        assert err_tty.rstrip("\r\n").endswith("left\x1b[K") and err_tty.endswith("\n"), repr(err_tty[-80:])
    # The table itself is the same program output (timings differ: compare its shape).
    assert len(out_tty.splitlines()) == len(out_pipe.splitlines()), (out_pipe, out_tty)

    rc, out_q, err_q = run(cmd + ["--quiet"], tty=True)
    assert rc == 0, (rc, out_q, err_q)
    assert f"{unit}/s" not in err_q and "\r" not in err_q, f"progress despite --quiet: {err_q!r}"
    print(f"progress_test: {os.path.basename(cmd[0])}: {len(found)} lines on a terminal, none on a pipe or with --quiet")


if __name__ == "__main__":
    main()
