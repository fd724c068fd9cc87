"""Plots issue 18's thread scaling: the empty scenario's env-steps/s over threads, one line per
kernel copy and environment count (median of the repetitions, each repetition's runs as dots),
against linear scaling from the one-thread median.

    .venv/bin/python bench/sim/plot_scaling.py RUNS.csv OUT.png [TITLE]

RUNS.csv: bench/sim/lanes_device.sh's runs.csv (copy, rep, envs, threads, steps, wall_s,
env_steps_per_s, state_hash, ...). Also prints the table of medians and the 1 -> N speed-ups.
"""
import csv
import statistics
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main() -> int:
    if len(sys.argv) < 3:
        print(__doc__)
        return 2
    runs = defaultdict(list)  # (copy, envs) -> [(threads, rate)]
    hashes = defaultdict(set)  # envs -> hashes (one per size, or the results depend on the copy or threads)
    with open(sys.argv[1], newline="") as f:
        for row in csv.DictReader(f):
            if not row["env_steps_per_s"]:
                continue
            runs[(row["copy"], int(row["envs"]))].append((int(row["threads"]), float(row["env_steps_per_s"])))
            hashes[int(row["envs"])].add(row["state_hash"])
    for envs, h in sorted(hashes.items()):
        if len(h) != 1:
            print(f"error: {envs} environments gave {len(h)} state hashes: {sorted(h)}", file=sys.stderr)
            return 1
    fig, ax = plt.subplots(figsize=(7, 4.5))
    print("copy,envs,threads,median_M_env_steps_per_s,speedup_vs_1_thread")
    for (copy, envs), pts in sorted(runs.items()):
        by_t = defaultdict(list)
        for t, r in pts:
            by_t[t].append(r / 1e6)
        ts = sorted(by_t)
        med = [statistics.median(by_t[t]) for t in ts]
        for t, m in zip(ts, med):
            print(f"{copy},{envs},{t},{m:.1f},{m / med[0]:.2f}")
        line = ax.plot(ts, med, marker="o", label=f"{copy}, {envs:,} envs")[0]
        ax.scatter([t for t, _ in pts], [r / 1e6 for _, r in pts], s=8, color=line.get_color(), alpha=0.4)
        ax.plot(ts, [med[0] * t for t in ts], linestyle=":", color=line.get_color(), linewidth=0.8)
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xticks([1, 2, 4, 8, 16])
    ax.set_xticklabels(["1", "2", "4", "8", "16"])
    ax.set_xlabel("threads (pinned to the first cores)")
    ax.set_ylabel("M env-steps/s (empty scenario)")
    ax.set_title(sys.argv[3] if len(sys.argv) > 3 else "kestrel run, empty scenario: thread scaling")
    ax.axhline(150, color="grey", linewidth=0.8, linestyle="--")
    ax.text(1.05, 160, "issue 18 goal at 16 threads: 150 M", fontsize=8, color="grey")
    ax.grid(True, which="both", linewidth=0.3)
    ax.legend(fontsize=8, title="dotted: linear from 1 thread", title_fontsize=8)
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=120)
    print(f"wrote {sys.argv[2]}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
