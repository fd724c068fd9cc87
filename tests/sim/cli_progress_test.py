#!/usr/bin/env python3
"""`kestrel run`'s progress line (issue 15), run by ctest as `python3 cli_progress_test.py KESTREL OUT_DIR`.

The same run (4096 envs x 1000 steps, 1 thread: several seconds, far beyond the line's first 0.5 s)
three times:
  1. stderr a pipe (not a terminal): no progress text at all;
  2. stderr a pseudo-terminal: progress lines "env-steps DONE / 4.10M (P%), RATE env-steps/s, T s
     left", the total right, the percentages rising, the last line complete (100%) and ended by a
     newline; stdout (the summary) carries the same state hash as run 1;
  3. stderr a pseudo-terminal with --quiet: nothing on it.
Standard library only (pty), so it needs no virtual environment.
"""
import os
import re
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
import pty_run  # noqa: E402
from pty_run import value  # noqa: E402

ENVS, STEPS = 4096, 1000
LINE = re.compile(r"\r  env-steps ([0-9.]+[kMG]?) / ([0-9.]+[kMG]?) \((\d+)%\), ([0-9.]+[kMG]?) env-steps/s, ([^\r\n\x1b]*) left\x1b\[K")


def run(kestrel, out_dir, tty, quiet):
    cmd = [kestrel, "run", "--envs", str(ENVS), "--steps", str(STEPS), "--threads", "1", "--out", out_dir]
    if quiet:
        cmd.append("--quiet")
    return pty_run.run(cmd, tty=tty)


def main():
    kestrel, out_dir = sys.argv[1], sys.argv[2]
    rc, out_pipe, err_pipe = run(kestrel, out_dir, tty=False, quiet=False)
    assert rc == 0, (rc, out_pipe, err_pipe)
    assert "env-steps/s," not in err_pipe and "\r" not in err_pipe, f"progress on a pipe: {err_pipe!r}"
    hash_pipe = re.search(r"state hash: ([0-9a-f]{16})", out_pipe).group(1)

    rc, out_tty, err_tty = run(kestrel, out_dir, tty=True, quiet=False)
    assert rc == 0, (rc, out_tty, err_tty)
    lines = LINE.findall(err_tty)
    assert len(lines) >= 2, f"expected progress lines on a terminal, got {err_tty!r}"
    total = ENVS * STEPS
    percents = [int(p) for _, _, p, _, _ in lines]
    for done, tot, pct, rate, left in lines:
        assert abs(value(tot) - total) <= 0.005 * total, (tot, total)
        # The figures are rounded to 3 significant digits (4,096,000 shows as 4.10M).
        assert 0 <= value(done) <= 1.005 * total and abs(100 * value(done) / total - int(pct)) <= 1.0, (done, pct)
        assert value(rate) > 0, rate
    assert percents == sorted(percents), percents
    # The terminal turns the final newline into CR LF.
    assert percents[-1] == 100 and (err_tty.endswith("\x1b[K\n") or err_tty.endswith("\x1b[K\r\n")), err_tty[-80:]
    assert lines[-1][4].endswith("0.0 s"), lines[-1]  # nothing left at the end
    wall = float(re.search(r"wall time ([0-9.]+) s", out_tty).group(1))
    assert wall > 0.5, f"the run took {wall} s: too short to show a progress line; make the test run larger"
    hash_tty = re.search(r"state hash: ([0-9a-f]{16})", out_tty).group(1)
    assert hash_tty == hash_pipe, (hash_tty, hash_pipe)  # the line changes nothing of the run

    rc, out_q, err_q = run(kestrel, out_dir, tty=True, quiet=True)
    assert rc == 0, (rc, out_q, err_q)
    assert "env-steps/s," not in err_q, f"--quiet printed progress: {err_q!r}"
    assert re.search(r"state hash: ([0-9a-f]{16})", out_q).group(1) == hash_pipe
    print(f"progress: none on a pipe, {len(lines)} lines on a terminal ({percents[0]}% .. 100%), none with --quiet; "
          f"state hash {hash_pipe} in all three")


if __name__ == "__main__":
    main()
