"""The navigation_task sweep of stops 35-45 (bench/results/python/navigation_sweep.csv: one row per
evaluation of each run, 512 level-10 episodes of seed 1000003) as level-10 success over env-steps,
one line per run, labelled by what it changed.

    .venv/bin/python bench/python/plot_navigation_sweep.py [CSV] [PNG]
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(argv: list[str]) -> None:
    src = argv[1] if len(argv) > 1 else "bench/results/python/navigation_sweep.csv"
    dst = argv[2] if len(argv) > 2 else src[:-4] + ".png"
    runs: dict[str, list[dict]] = defaultdict(list)
    for row in csv.DictReader(open(src)):
        runs[row["run"]].append(row)
    # Tall enough for the legend beside the axes: about 0.13 in per run.
    fig, ax = plt.subplots(figsize=(15, max(6.5, 0.13 * len(runs) + 1.0)))
    cmap = plt.get_cmap("tab20")
    for k, (run, rows) in enumerate(runs.items()):
        r0 = rows[0]
        label = (f"{run}: {r0['sensor'][:28]}, {r0['hidden']}, up/down {r0['train_curriculum_up_down'].split(' ')[0]}, "
                 f"crash {r0['train_collision_penalty']}")
        if r0["other"] not in ("-", ""):
            label += f", {r0['other'][:30]}"
        x = [int(r["env_steps"]) / 1e6 for r in rows]
        y = [100 * float(r["level10_success_rate"]) for r in rows]
        committed = "committed" in r0["other"]
        ax.plot(x, y, marker="o", color="k" if committed else cmap(k % 20), lw=2.5 if committed else 1, label=label)
    ax.axhline(80, color="k", ls="--", lw=1, label="issue 11's goal (80 %)")
    ax.set_xlabel("env-steps (millions)")
    ax.set_ylabel("success at curriculum level 10 (%, 512 episodes of seed 1000003)")
    ax.set_title("navigation_task, rsl_rl PPO: what each change did (2-core machine, stops 35-45)")
    ax.set_ylim(0, 100)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6.5, loc="upper left", bbox_to_anchor=(1.01, 1.0))  # beside the axes: one row per run
    fig.tight_layout()
    fig.savefig(dst, dpi=110)
    print(dst)


if __name__ == "__main__":
    main(sys.argv)
