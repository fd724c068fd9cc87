"""A periodic progress line for long Python work (benchmarks, `kestrel run --record / --view`, teleop
recordings; issue 15), the twin of `kestrel run`'s (sim/include/kestrel/sim/progress.hpp):

    with Progress(total=4 * 3 * 100 * 4096, unit="env-steps", desc="legged throughput") as p:
        ...; p.update(n)

"\\r  legged throughput: 1.23M / 4.92M env-steps (25%), 2.1M env-steps/s, 1.8 s left", rewritten in
place on stderr at most every 0.25 s from 0.5 s in, and once more, complete, with a newline at the
end. Only when stderr is a terminal and not quiet: a log file or a pipe gets nothing. Training has
tqdm's bar (kestrel.train) under the same rule.
"""
from __future__ import annotations

import sys
import time


def _si(v: float) -> str:
    for limit, div, suffix, fmt in ((1e3, 1, "", "{:.0f}"), (1e6, 1e3, "k", "{:.1f}"), (1e9, 1e6, "M", "{:.2f}")):
        if v < limit:
            return fmt.format(v / div) + suffix
    return f"{v / 1e9:.2f}G"


def format_line(desc: str, done: float, total: float | None, unit: str, elapsed_s: float) -> str:
    rate = done / elapsed_s if elapsed_s > 0 else 0.0
    if total is None:
        # Open-ended work (teleoperation until Ctrl-C): what is done, the rate and the time so far.
        return f"  {desc}: {_si(done)} {unit}, {_si(rate)} {unit}/s, {elapsed_s:.1f} s"
    left = "? s left"
    if rate > 0:
        s = (total - done) / rate
        left = f"{s:.1f} s left" if s < 60 else f"{int(s) // 60} min {int(s) % 60:02d} s left"
    pct = 100 * done / total if total > 0 else 0.0
    return f"  {desc}: {_si(done)} / {_si(total)} {unit} ({pct:.0f}%), {_si(rate)} {unit}/s, {left}"


class Progress:
    FIRST_AFTER_S, INTERVAL_S = 0.5, 0.25

    def __init__(self, total: float | None, unit: str = "steps", desc: str = "", quiet: bool = False, stream=None,
                 clock=time.perf_counter):
        """total None: open-ended (no percentage or time left), e.g. a teleoperated recording."""
        self.stream = sys.stderr if stream is None else stream
        isatty = getattr(self.stream, "isatty", None)
        self.enabled = not quiet and (total is None or total > 0) and callable(isatty) and bool(isatty())
        self.total, self.unit, self.desc, self.clock = (None if total is None else float(total)), unit, desc, clock
        self.done, self.lines, self._last = 0.0, 0, None
        self._t0 = clock()

    def update(self, n: float = 1) -> None:
        self.done += n
        if not self.enabled:
            return
        t = self.clock() - self._t0
        if t < self.FIRST_AFTER_S or (self._last is not None and t - self._last < self.INTERVAL_S):
            return
        self._last = t
        self.stream.write("\r" + format_line(self.desc, self.done, self.total, self.unit, t) + "\x1b[K")
        self.stream.flush()
        self.lines += 1

    def clear(self) -> None:
        """Erases the line (before printing something else on the terminal; the next update redraws it)."""
        if self.enabled and self.lines:
            self.stream.write("\r\x1b[K")
            self.stream.flush()

    def close(self) -> None:
        if self.enabled and self.lines:
            t = self.clock() - self._t0
            self.stream.write("\r" + format_line(self.desc, self.done, self.total, self.unit, t) + "\x1b[K\n")
            self.stream.flush()
            self.lines += 1
        self.enabled = False

    def __enter__(self) -> "Progress":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
