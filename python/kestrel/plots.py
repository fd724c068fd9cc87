"""Kestrel's figures, drawn with matplotlib from the CSV files the runs write (issue 15).

    kestrel plot DIR                 # DIR from `kestrel run --out DIR` or `kestrel train --out DIR`
    python -m kestrel.plots DIR      # the same
    python python/kestrel/plots.py DIR   # the same, without installing the package (no compiled module needed)
    kestrel plot LOG.csv --out curves.png --title "..." [--target-success 0.95]

What is drawn, from what is in DIR:

- trajectory.csv (+ envs.csv, obstacles.csv of the rigid simulator) -> trajectory.png: one top view
  per traced environment, axes in metres at equal scale with a scale bar, the environment's bounds,
  its obstacles' footprints as they stand at the end of the run (its last layout), the last
  episode's path with its start and target, earlier episodes faint (they flew other layouts),
  and, for 3-D runs, the altitude of every traced environment over the env-steps with its target.
- log.csv (kestrel train's evaluations) -> curves.png: the learning curves.

The C++ harness (build/host/sim/kestrel) writes the CSVs only: it cannot import matplotlib. This
module imports nothing of Kestrel's compiled extension, so it also runs as a plain script.
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import os
import sys
from collections import defaultdict

# Trajectory points drawn per environment at most: a long run's path is thinned (every k-th point,
# episode ends kept) so a 1e6-step trace still renders in seconds; the shape at figure resolution is
# the same.
MAX_POINTS_PER_ENV = 20000


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")  # files only: no display is needed or wanted
    import matplotlib.pyplot as plt

    return plt


def _read_csv(path: str) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _num(v: str) -> float:
    try:
        return float(v)
    except (TypeError, ValueError):
        return float("nan")


# ---------------------------------------------------------------------------------------------
# Trajectories


def _episodes(rows: list[dict]) -> list[list[dict]]:
    """Splits one environment's rows (in step order) into episodes: by the episode column where the
    run wrote one (rigid simulator), else where the robot jumps more than 1 m in one env-step (a
    reset: no vehicle here moves that fast)."""
    out: list[list[dict]] = []
    prev = None
    for r in rows:
        if "episode" in r and r["episode"] not in (None, ""):
            new = prev is None or r["episode"] != prev["episode"]
        else:
            new = prev is None or math.hypot(_num(r["x_m"]) - _num(prev["x_m"]), _num(r["y_m"]) - _num(prev["y_m"])) > 1.0
        if new:
            out.append([])
        out[-1].append(r)
        prev = r
    return out


def _thin(seg: list[dict], budget: int) -> list[dict]:
    if len(seg) <= budget or budget < 2:
        return seg
    k = math.ceil(len(seg) / budget)
    return seg[::k] + ([seg[-1]] if (len(seg) - 1) % k else [])


def _rot(q: tuple[float, float, float, float]):
    w, x, y, z = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def _hull(points: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """Convex hull (Andrew's monotone chain), counter-clockwise."""
    pts = sorted(set(points))
    if len(pts) <= 2:
        return pts

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list = []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    upper: list = []
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


def obstacle_footprint(o: dict) -> tuple[str, object]:
    """An obstacle row of obstacles.csv -> ("circle", (cx, cy, r)) or ("polygon", [(x, y), ...]): the
    exact top-view outline of a sphere, a box, a capsule or a cylinder in any pose (the convex hull
    of its projected corners / end circles), the bounding box for a convex hull (mesh)."""
    c = (_num(o["x_m"]), _num(o["y_m"]), _num(o["z_m"]))
    shape = o["shape"]
    if shape == "sphere":
        return "circle", (c[0], c[1], _num(o["radius_m"]))
    R = _rot((_num(o["qw"]), _num(o["qx"]), _num(o["qy"]), _num(o["qz"])))
    if shape == "box":
        h = (_num(o["half_x_m"]), _num(o["half_y_m"]), _num(o["half_z_m"]))
        pts = []
        for sx in (-1, 1):
            for sy in (-1, 1):
                for sz in (-1, 1):
                    v = (sx * h[0], sy * h[1], sz * h[2])
                    pts.append((c[0] + sum(R[0][k] * v[k] for k in range(3)), c[1] + sum(R[1][k] * v[k] for k in range(3))))
        return "polygon", _hull(pts)
    if shape in ("capsule", "cylinder"):
        r, hl = _num(o["radius_m"]), _num(o["half_length_m"])
        axis = (R[0][2], R[1][2], R[2][2])  # the local z axis in the world
        if abs(axis[2]) > 1 - 1e-9:  # vertical: its footprint is a circle
            return "circle", (c[0], c[1], r)
        pts = []
        u, v = (R[0][0], R[1][0], R[2][0]), (R[0][1], R[1][1], R[2][1])
        for s in (-1, 1):
            e = (c[0] + s * hl * axis[0], c[1] + s * hl * axis[1])
            for k in range(32):  # the end circle (a cylinder's) or end sphere's outline (a capsule's)
                a = 2 * math.pi * k / 32
                if shape == "capsule":
                    pts.append((e[0] + r * math.cos(a), e[1] + r * math.sin(a)))
                else:
                    pts.append((e[0] + r * (math.cos(a) * u[0] + math.sin(a) * v[0]),
                                e[1] + r * (math.cos(a) * u[1] + math.sin(a) * v[1])))
        return "polygon", _hull(pts)
    x0, y0, x1, y1 = (_num(o["aabb_min_x_m"]), _num(o["aabb_min_y_m"]), _num(o["aabb_max_x_m"]), _num(o["aabb_max_y_m"]))
    return "polygon", [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


def _nice_length(span: float) -> float:
    """A round scale-bar length (1, 2 or 5 x 10^k m) of about a fifth of the span."""
    if not span > 0 or not math.isfinite(span):
        return 1.0
    raw = span / 5
    p = 10 ** math.floor(math.log10(raw))
    return next(m * p for m in (5, 2, 1) if m * p <= raw) if raw >= p else p


def plot_trajectory(out_dir: str, png: str | None = None) -> str:
    """out_dir/trajectory.csv (+ envs.csv, obstacles.csv when there) -> out_dir/trajectory.png (or png).
    Returns the path written; raises FileNotFoundError naming the file when trajectory.csv is missing
    and ValueError when it holds no rows or lacks the x_m / y_m columns."""
    plt = _pyplot()
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle, Polygon, Rectangle
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

    tpath = os.path.join(out_dir, "trajectory.csv")
    if not os.path.isfile(tpath):
        raise FileNotFoundError(f"{tpath}: no such file (write it with `kestrel run --out {out_dir}`)")
    rows = _read_csv(tpath)
    if not rows:
        raise ValueError(f"{tpath}: no rows")
    if "x_m" not in rows[0] or "y_m" not in rows[0]:
        raise ValueError(f"{tpath}: columns {list(rows[0])} lack x_m and y_m")
    by_env: dict[int, list[dict]] = defaultdict(list)
    for r in rows:
        by_env[int(r["env"])].append(r)
    envs = sorted(by_env)
    for e in envs:
        by_env[e].sort(key=lambda r: int(r["step"]))
    three_d = "z_m" in rows[0]
    has_target = "target_x_m" in rows[0]
    bounds = {}
    epath = os.path.join(out_dir, "envs.csv")
    if os.path.isfile(epath):
        for r in _read_csv(epath):
            if "lower_x_m" in r and r.get("robot", "0") == "0":
                bounds[int(r["env"])] = (_num(r["lower_x_m"]), _num(r["lower_y_m"]), _num(r["upper_x_m"]), _num(r["upper_y_m"]))
    obstacles: dict[int, list[dict]] = defaultdict(list)
    opath = os.path.join(out_dir, "obstacles.csv")
    have_obstacles = os.path.isfile(opath)
    if have_obstacles:
        for r in _read_csv(opath):
            obstacles[int(r["env"])].append(r)
    summary_title = ""
    spath = os.path.join(out_dir, "summary.txt")
    if os.path.isfile(spath):
        with open(spath) as f:
            first = f.readline().strip()
        summary_title = first.replace("kestrel run: ", "")

    n = len(envs)
    cols = min(3, n)
    grid_rows = math.ceil(n / cols)
    extra = 1 if three_d else 0
    fig = plt.figure(figsize=(4.6 * cols + 0.4, 4.3 * grid_rows + 2.8 * extra + 1.2), layout="constrained")
    gs = fig.add_gridspec(grid_rows + extra, cols, height_ratios=[1.0] * grid_rows + [0.55] * extra)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for idx, e in enumerate(envs):
        ax = fig.add_subplot(gs[idx // cols, idx % cols])
        colour = colours[idx % len(colours)]
        eps = _episodes(by_env[e])
        xs_all = [_num(r["x_m"]) for r in by_env[e]]
        ys_all = [_num(r["y_m"]) for r in by_env[e]]
        for o in obstacles.get(e, []):
            kind, geo = obstacle_footprint(o)
            # Standing obstacles filled; overhead parts (tree branches, a ceiling: upright 0) only
            # outlined, so a ceiling over the whole environment does not hide what is under it.
            style = (dict(facecolor="0.55", edgecolor="0.3", linewidth=0.6, alpha=0.55) if o.get("upright", "1") == "1"
                     else dict(fill=False, edgecolor="0.45", linewidth=0.7, linestyle=":"))
            ax.add_patch(Circle(geo[:2], geo[2], **style) if kind == "circle" else Polygon(geo, closed=True, **style))
        if e in bounds:
            x0, y0, x1, y1 = bounds[e]
            ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, edgecolor="black", linestyle="--", linewidth=0.9))
        budget = max(2, MAX_POINTS_PER_ENV // max(1, len(eps)))
        for seg in eps[:-1]:
            seg = _thin(seg, budget)
            ax.plot([_num(r["x_m"]) for r in seg], [_num(r["y_m"]) for r in seg], color=colour, alpha=0.4, linewidth=1.0)
        last = _thin(eps[-1], MAX_POINTS_PER_ENV)
        lx, ly = [_num(r["x_m"]) for r in last], [_num(r["y_m"]) for r in last]
        ax.plot(lx, ly, color=colour, linewidth=1.8)
        ax.plot(lx[:1], ly[:1], marker="o", markersize=8, color="tab:green", markeredgecolor="black", linestyle="none", zorder=5)
        ax.plot(lx[-1:], ly[-1:], marker="s", markersize=5, color=colour, markeredgecolor="black", linestyle="none", zorder=5)
        if has_target:
            tx, ty = _num(last[-1]["target_x_m"]), _num(last[-1]["target_y_m"])
            ax.plot([tx], [ty], marker="*", markersize=15, color="tab:red", markeredgecolor="black", linestyle="none", zorder=6)
        ax.set_aspect("equal", adjustable="box")
        # Limits: the bounds (and anything flown outside them); without bounds (planar runs) a
        # square around the paths, so a straight drive does not shrink the axes to a sliver.
        x0, x1 = min(xs_all), max(xs_all)
        y0, y1 = min(ys_all), max(ys_all)
        if e in bounds:
            bx0, by0, bx1, by1 = bounds[e]
            x0, y0, x1, y1 = min(x0, bx0), min(y0, by0), max(x1, bx1), max(y1, by1)
        else:
            half = max(x1 - x0, y1 - y0, 1.0) / 2
            cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
            x0, x1, y0, y1 = cx - half, cx + half, cy - half, cy + half
        pad = 0.04 * max(x1 - x0, y1 - y0)
        ax.set_xlim(x0 - pad, x1 + pad)
        ax.set_ylim(y0 - pad, y1 + pad)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.grid(alpha=0.25)
        ax.set_title(f"env {e}: {len(eps)} episode{'s' if len(eps) != 1 else ''}, {len(by_env[e])} env-steps", fontsize=10)
        xl = ax.get_xlim()
        length = _nice_length(xl[1] - xl[0])
        ax.add_artist(AnchoredSizeBar(ax.transData, length, f"{length:g} m", "lower right", pad=0.4, sep=3, frameon=True,
                                      size_vertical=0, fontproperties={"size": 8}))
    handles = [Line2D([], [], color="0.3", linewidth=1.8, label="last episode's path (colour per env)"),
               Line2D([], [], color="0.3", alpha=0.4, linewidth=1.0, label="earlier episodes" +
                      (" (other obstacle layouts)" if have_obstacles else "")),
               Line2D([], [], marker="o", markersize=8, color="tab:green", markeredgecolor="black", linestyle="none",
                      label="start (first logged position)"),
               Line2D([], [], marker="s", markersize=5, color="0.5", markeredgecolor="black", linestyle="none", label="end")]
    if has_target:
        handles.append(Line2D([], [], marker="*", markersize=13, color="tab:red", markeredgecolor="black", linestyle="none",
                              label="target (last episode)"))
    if have_obstacles:
        handles.append(Rectangle((0, 0), 1, 1, facecolor="0.55", edgecolor="0.3", alpha=0.55,
                                 label="obstacles, top view (last layout)"))
        handles.append(Rectangle((0, 0), 1, 1, fill=False, edgecolor="0.45", linestyle=":",
                                 label="overhead parts (branches, ceiling)"))
    if bounds:
        handles.append(Rectangle((0, 0), 1, 1, fill=False, edgecolor="black", linestyle="--", label="environment bounds"))
    if three_d:
        ax = fig.add_subplot(gs[grid_rows, :])
        for idx, e in enumerate(envs):
            seg = _thin(by_env[e], MAX_POINTS_PER_ENV)
            steps = [int(r["step"]) for r in seg]
            ax.plot(steps, [_num(r["z_m"]) for r in seg], color=colours[idx % len(colours)], linewidth=1.2, label=f"env {e}")
            if has_target:
                ax.plot(steps, [_num(r["target_z_m"]) for r in seg], color=colours[idx % len(colours)], linewidth=0.9,
                        linestyle=":")
        if has_target:
            ax.plot([], [], color="0.3", linestyle=":", label="target altitude")
        ax.set_xlabel("env-step")
        ax.set_ylabel("altitude z (m)")
        ax.set_title("altitude of robot 0 over the run", fontsize=10)
        ax.grid(alpha=0.25)
        ax.legend(fontsize=8, ncol=min(7, n + 1), loc="upper right")
    fig.legend(handles=handles, loc="outside lower center", ncol=min(4, len(handles)), fontsize=9, frameon=False)
    fig.suptitle("Trajectories, top view" + (f": {summary_title}" if summary_title else ""), fontsize=12)
    png = png or os.path.join(out_dir, "trajectory.png")
    fig.savefig(png, dpi=100)
    plt.close(fig)
    return png


# ---------------------------------------------------------------------------------------------
# Learning curves


def plot_learning_curves(rows: list[dict], png: str, title: str, target_success: float | None = None) -> str:
    """kestrel train's evaluation rows (log.csv) -> png: mean return, success / crash rate (%),
    episode length (env-steps), and for locomotion the velocity tracking errors, over env-steps."""
    plt = _pyplot()
    if not rows:
        raise ValueError(f"{png}: no evaluation rows to plot")
    val = lambda r, k: _num(r.get(k, "nan")) if isinstance(r.get(k, "nan"), str) else float(r.get(k, float("nan")))
    x = [val(r, "env_steps") for r in rows]
    tracking = any(math.isfinite(val(r, "lin_vel_error_m_s")) for r in rows)
    fig, ax = plt.subplots(1, 4 if tracking else 3, figsize=(17 if tracking else 13.5, 4.0), layout="constrained")
    ax[0].plot(x, [val(r, "mean_return") for r in rows], marker="o", label="mean return")
    ax[0].set_title("evaluation return")
    ax[0].set_ylabel("return per episode (reward units)")
    ax[1].plot(x, [100 * val(r, "success_rate") for r in rows], marker="o", label="success")
    ax[1].plot(x, [100 * val(r, "crash_rate") for r in rows], marker="x", label="crash")
    if target_success is not None:
        ax[1].axhline(100 * target_success, color="tab:green", ls="--", lw=1, label=f"target {100 * target_success:g} %")
    ax[1].set_ylim(-3, 103)
    ax[1].set_title("success / crash rate")
    ax[1].set_ylabel("% of evaluation episodes")
    ax[2].plot(x, [val(r, "mean_length") for r in rows], marker="o", label="mean length")
    ax[2].set_title("episode length")
    ax[2].set_ylabel("env-steps per episode")
    if tracking:
        ax[3].plot(x, [val(r, "lin_vel_error_m_s") for r in rows], marker="o", label="|cmd_xy - v_xy| (m/s)")
        ax[3].plot(x, [val(r, "yaw_rate_error_rad_s") for r in rows], marker="x", label="|cmd_yaw - w_z| (rad/s)")
        ax[3].axhline(0.1, color="gray", ls="--", lw=1, label="goal 0.1 m/s")
        ax[3].set_title("velocity tracking error")
        ax[3].set_ylabel("mean error (m/s, rad/s)")
    for a in ax:
        a.set_xlabel("training env-steps")
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    fig.suptitle(title)
    fig.savefig(png, dpi=110)
    plt.close(fig)
    return png


def _curves_title(csv_path: str) -> tuple[str, float | None]:
    """The title (and target success) from the summary.json beside log.csv, or NAME.json beside NAME.csv."""
    base = os.path.splitext(csv_path)[0]
    for j in (base + ".json", os.path.join(os.path.dirname(csv_path), "summary.json")):
        if os.path.isfile(j):
            with open(j) as f:
                s = json.load(f)
            envs = s.get("envs")
            if envs is None and "--envs" in str(s.get("command", "")).split():  # a summary written by hand
                words = s["command"].split()
                envs = words[words.index("--envs") + 1]
            title = ", ".join(str(v) for v in (f"{s.get('task')}" + (f" ({s['controller']})" if s.get("controller") else ""),
                                                s.get("learner"), f"{envs} envs" if envs else None,
                                                f"seed {s.get('seed')}") if v)
            if isinstance(s.get("eval"), str):
                title += f"\nevaluation: {s['eval']}"
            return title, s.get("target_success")
    return os.path.basename(base), None


def plot_curves_csv(csv_path: str, png: str | None = None, title: str | None = None,
                    target_success: float | None = None) -> str:
    rows = _read_csv(csv_path)
    if not rows or "env_steps" not in rows[0]:
        raise ValueError(f"{csv_path}: not a learning-curve log (kestrel train's log.csv: needs an env_steps column and rows)")
    t, ts = _curves_title(csv_path)
    png = png or (os.path.join(os.path.dirname(csv_path), "curves.png") if os.path.basename(csv_path) == "log.csv"
                  else os.path.splitext(csv_path)[0] + ".png")
    return plot_learning_curves(rows, png, title or t, target_success if target_success is not None else ts)


def plot_dir(path: str) -> list[str]:
    """Everything drawable in a run's directory: trajectory.png and/or curves.png."""
    written = []
    if os.path.isfile(os.path.join(path, "trajectory.csv")):
        written.append(plot_trajectory(path))
    if os.path.isfile(os.path.join(path, "log.csv")):
        written.append(plot_curves_csv(os.path.join(path, "log.csv")))
    if not written:
        raise FileNotFoundError(f"{path}: neither trajectory.csv (kestrel run --out) nor log.csv (kestrel train --out) is there")
    return written


def main(argv: list[str] | None = None, prog: str = "kestrel plot") -> int:
    p = argparse.ArgumentParser(prog=prog, description="Draw a run's figures (matplotlib) from its CSV files.")
    p.add_argument("path", help="a directory of `kestrel run --out` or `kestrel train --out`, or a log.csv of kestrel train")
    p.add_argument("--out", default=None, help="the PNG to write (a CSV path only; default: beside the CSV)")
    p.add_argument("--title", default=None, help="learning curves: the figure's title (default: from the summary JSON)")
    p.add_argument("--target-success", type=float, default=None, help="learning curves: draw this success rate (0..1)")
    a = p.parse_args(argv)
    try:
        if os.path.isdir(a.path):
            if a.out or a.title:
                p.error("--out and --title go with a CSV file, not a directory")
            written = plot_dir(a.path)
        elif os.path.isfile(a.path):
            written = [plot_curves_csv(a.path, a.out, a.title, a.target_success)]
        else:
            raise FileNotFoundError(f"{a.path}: no such file or directory")
    except (FileNotFoundError, ValueError) as ex:
        print(f"{prog}: {ex}", file=sys.stderr)
        return 1
    for w in written:
        print(f"  wrote {w}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(prog="python -m kestrel.plots"))
