"""kestrel.plots (issue 15): the figures are matplotlib's, drawn from the CSVs the runs write.

`kestrel run` through the console script writes trajectory.png after the C++ harness's CSVs;
`kestrel plot DIR` draws it for any run; obstacle footprints are the shapes' exact outlines; the
learning curves carry labelled axes and the target line."""
import csv
import json
import math
import os
import struct
import subprocess
import sys
import zlib

import pytest

from kestrel import plots

EXE = os.path.join(os.path.dirname(sys.executable), "kestrel")


def png_info(path):
    """(width, height, {tEXt key: value}) of a PNG, read from its chunks."""
    with open(path, "rb") as f:
        data = f.read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    pos, text, size = 8, {}, None
    while pos < len(data):
        n, tag = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if tag == b"IHDR":
            size = struct.unpack(">II", body[:8])
        elif tag == b"tEXt":
            k, v = body.split(b"\0", 1)
            text[k.decode()] = v.decode("latin-1")
        elif tag == b"zTXt":
            k, rest = body.split(b"\0", 1)
            text[k.decode()] = zlib.decompress(rest[1:]).decode("latin-1")
        pos += 12 + n
    return size[0], size[1], text


def colours(path):
    import matplotlib.image as mpimg
    import numpy as np

    img = mpimg.imread(path)[..., :3]
    return img, np.unique((img.reshape(-1, 3) * 255).round().astype(int), axis=0)


def test_run_through_console_script_writes_matplotlib_trajectory(kestrel_cli, tmp_path):
    out = tmp_path / "run"
    env = {**os.environ, "KESTREL_CLI": str(kestrel_cli)}
    r = subprocess.run([EXE, "run", "--envs", "8", "--steps", "300", "--threads", "2", "--out", str(out)],
                       capture_output=True, text=True, timeout=300, env=env)
    assert r.returncode == 0, r.stderr
    assert f"wrote {out}/trajectory.png" in r.stdout
    assert "plot: kestrel plot" not in r.stdout  # the hint is for the C++ program run alone
    assert "state hash: " in r.stdout and "env-steps/s," not in r.stderr  # stderr is a pipe: no progress line
    w, h, text = png_info(out / "trajectory.png")
    # 6 traced envs: 3 columns x 2 rows of top views and the altitude panel, 100 dpi.
    assert (w, h) == (1420, 1260)
    assert text.get("Software", "").startswith("Matplotlib"), text
    img, cols = colours(out / "trajectory.png")
    assert len(cols) > 200  # text, lines, patches: a real figure, not a blank canvas
    red_star = ((img[..., 0] > 0.8) & (img[..., 1] < 0.25) & (img[..., 2] < 0.25)).sum()
    assert red_star > 200, red_star  # the targets (tab:red stars) are drawn
    # --no-plot: the run only.
    out2 = tmp_path / "run2"
    r = subprocess.run([EXE, "run", "--envs", "4", "--steps", "20", "--threads", "2", "--out", str(out2), "--no-plot"],
                       capture_output=True, text=True, timeout=300, env=env)
    assert r.returncode == 0, r.stderr
    assert (out2 / "trajectory.csv").exists() and not (out2 / "trajectory.png").exists()
    # The C++ program alone says how to plot; `kestrel plot DIR` then draws the same figure.
    r = subprocess.run([str(kestrel_cli), "run", "--envs", "4", "--steps", "20", "--threads", "2", "--out", str(out2)],
                       capture_output=True, text=True, timeout=300)
    assert f"plot: kestrel plot {out2}" in r.stdout
    r = subprocess.run([EXE, "plot", str(out2)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and f"wrote {out2}/trajectory.png" in r.stdout, r.stderr
    assert png_info(out2 / "trajectory.png")[:2] == (1420, 1260)


def test_planar_trajectory_without_obstacles_or_targets(kestrel_cli, root, tmp_path):
    out = tmp_path / "planar"
    subprocess.run([str(kestrel_cli), "run", str(root / "sim" / "scenarios" / "planar_multirotor.yaml"), "--envs", "2",
                    "--steps", "50", "--threads", "2", "--out", str(out)], check=True, capture_output=True)
    with open(out / "trajectory.csv") as f:
        assert next(csv.reader(f)) == ["env", "step", "x_m", "y_m", "yaw_rad"]
    path = plots.plot_trajectory(str(out))
    w, h, _ = png_info(path)
    assert (w, h) == (960, 550)  # 2 top views, no altitude panel (the planar trace has no z)


def test_plot_errors_name_the_path(tmp_path):
    r = subprocess.run([EXE, "plot", str(tmp_path / "nope")], capture_output=True, text=True, timeout=120)
    assert r.returncode == 1 and f"{tmp_path / 'nope'}: no such file or directory" in r.stderr
    r = subprocess.run([EXE, "plot", str(tmp_path)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 1 and "neither trajectory.csv" in r.stderr and str(tmp_path) in r.stderr
    (tmp_path / "x.csv").write_text("a,b\n1,2\n")
    r = subprocess.run([EXE, "plot", str(tmp_path / "x.csv")], capture_output=True, text=True, timeout=120)
    assert r.returncode == 1 and "needs an env_steps column" in r.stderr


def _row(**kw):
    base = dict(x_m=0, y_m=0, z_m=0, qw=1, qx=0, qy=0, qz=0, radius_m=0, half_length_m=0, half_x_m=0, half_y_m=0, half_z_m=0,
                aabb_min_x_m=0, aabb_min_y_m=0, aabb_max_x_m=0, aabb_max_y_m=0)
    base.update(kw)
    return {k: str(v) for k, v in base.items()}


def test_obstacle_footprints_are_the_shapes_outlines():
    kind, (cx, cy, r) = plots.obstacle_footprint(_row(shape="sphere", x_m=1, y_m=2, radius_m=0.5))
    assert kind == "circle" and (cx, cy, r) == (1.0, 2.0, 0.5)
    # A box yawed 90 degrees: its 2 x 1 m footprint turns into 1 x 2 m.
    c, s = math.cos(math.pi / 4), math.sin(math.pi / 4)
    kind, poly = plots.obstacle_footprint(_row(shape="box", x_m=3, half_x_m=1, half_y_m=0.5, half_z_m=2, qw=c, qz=s))
    xs, ys = [p[0] for p in poly], [p[1] for p in poly]
    assert kind == "polygon" and len(poly) == 4
    assert max(xs) - min(xs) == pytest.approx(1.0) and max(ys) - min(ys) == pytest.approx(2.0)
    assert sum(xs) / 4 == pytest.approx(3.0)
    # A vertical cylinder stands on a circle; one lying along x covers 2 (half length + 0) x 2 r.
    kind, geo = plots.obstacle_footprint(_row(shape="cylinder", radius_m=0.3, half_length_m=1))
    assert kind == "circle" and geo[2] == 0.3
    c, s = math.cos(math.pi / 4), math.sin(math.pi / 4)  # 90 degrees about y: local z -> world x
    kind, poly = plots.obstacle_footprint(_row(shape="cylinder", radius_m=0.3, half_length_m=1, qw=c, qy=s))
    xs, ys = [p[0] for p in poly], [p[1] for p in poly]
    assert max(xs) - min(xs) == pytest.approx(2.0, abs=1e-6) and max(ys) - min(ys) == pytest.approx(0.6, abs=1e-3)
    kind, poly = plots.obstacle_footprint(_row(shape="capsule", radius_m=0.3, half_length_m=1, qw=c, qy=s))
    xs = [p[0] for p in poly]
    assert max(xs) - min(xs) == pytest.approx(2.6, abs=1e-6)  # plus the end spheres
    kind, poly = plots.obstacle_footprint(_row(shape="convex_hull", aabb_min_x_m=-1, aabb_min_y_m=-2, aabb_max_x_m=1,
                                               aabb_max_y_m=2))
    assert sorted(poly) == [(-1, -2), (-1, 2), (1, -2), (1, 2)]


def test_episodes_split_by_column_or_by_jump():
    rows = [{"x_m": "0", "y_m": "0", "episode": "0"}, {"x_m": "0.1", "y_m": "0", "episode": "0"},
            {"x_m": "0.2", "y_m": "0", "episode": "1"}]
    assert [len(e) for e in plots._episodes(rows)] == [2, 1]  # the column decides, not the distance
    rows = [{"x_m": "0", "y_m": "0"}, {"x_m": "0.5", "y_m": "0"}, {"x_m": "5", "y_m": "5"}, {"x_m": "5.1", "y_m": "5"}]
    assert [len(e) for e in plots._episodes(rows)] == [2, 2]  # no column: a jump over 1 m is a reset
    assert plots._nice_length(12.0) == 2 and plots._nice_length(0.9) == 0.1 and plots._nice_length(60) == 10


def test_learning_curves_from_a_log(tmp_path):
    import numpy as np

    log = tmp_path / "log.csv"
    with open(log, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["env_steps", "mean_return", "success_rate", "crash_rate", "mean_length", "final_distance_m"])
        for k in range(5):
            w.writerow([k * 1000, 10 * k, k / 4, 1 - k / 4, 100 + k, 1.0])
    (tmp_path / "summary.json").write_text(json.dumps({"task": "Kestrel-PositionSetpoint-v0", "controller": "lee_velocity_control",
                                                       "learner": "rsl_rl", "envs": 16, "seed": 3, "target_success": 0.9}))
    assert plots._curves_title(str(log)) == ("Kestrel-PositionSetpoint-v0 (lee_velocity_control), rsl_rl, 16 envs, seed 3", 0.9)
    r = subprocess.run([EXE, "plot", str(tmp_path)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    w, h, text = png_info(tmp_path / "curves.png")
    assert (w, h) == (1485, 440) and text.get("Software", "").startswith("Matplotlib")
    img, cols = colours(tmp_path / "curves.png")
    green = ((img[..., 1] - np.maximum(img[..., 0], img[..., 2])) > 0.25).sum()
    assert green > 50  # the dashed target line (tab:green) of --target-success


def test_progress_line_for_benchmarks():
    """kestrel.progress: not before 0.5 s, at most every 0.25 s, a complete last line; nothing
    when the stream is not a terminal or with quiet."""
    from kestrel.progress import Progress, format_line

    class Tty:
        def __init__(self, tty=True):
            self.text, self.tty = "", tty

        def isatty(self):
            return self.tty

        def write(self, s):
            self.text += s

        def flush(self):
            pass

    now = [0.0]
    s = Tty()
    p = Progress(total=1000, unit="env-steps", desc="bench", stream=s, clock=lambda: now[0])
    for t, n in ((0.2, 100), (0.6, 400), (0.7, 100), (1.0, 400)):
        now[0] = t
        p.update(n)
    p.close()
    assert p.lines == 3
    assert s.text == ("\r" + format_line("bench", 500, 1000, "env-steps", 0.6) + "\x1b[K" +
                      "\r" + format_line("bench", 1000, 1000, "env-steps", 1.0) + "\x1b[K" +
                      "\r" + format_line("bench", 1000, 1000, "env-steps", 1.0) + "\x1b[K\n")
    assert format_line("bench", 500, 1000, "env-steps", 0.6) == "  bench: 500 / 1.0k env-steps (50%), 833 env-steps/s, 0.6 s left"
    assert format_line("b", 1e6, 1e8, "x", 10.0) == "  b: 1.00M / 100.00M x (1%), 100.0k x/s, 16 min 30 s left"
    for stream, quiet in ((Tty(False), False), (Tty(True), True)):
        q = Progress(total=10, stream=stream, quiet=quiet, clock=lambda: now[0])
        now[0] = 5.0
        q.update(10)
        q.close()
        assert stream.text == "" and q.lines == 0


def test_open_ended_progress_line():
    """total=None (a teleoperated recording until Ctrl-C): done, rate and time so far; no total,
    percentage or time left; still terminal-only."""
    from kestrel.progress import Progress, format_line

    assert format_line("teleop", 1500, None, "env-steps", 3.0) == "  teleop: 1.5k env-steps, 500 env-steps/s, 3.0 s"

    class Tty:
        text = ""

        def __init__(self, tty):
            self.tty = tty

        def isatty(self):
            return self.tty

        def write(self, s):
            self.text += s

        def flush(self):
            pass

    now = [0.0]
    s, pipe = Tty(True), Tty(False)
    for stream in (s, pipe):
        now[0] = 0.0
        p = Progress(total=None, unit="env-steps", desc="teleop", stream=stream, clock=lambda: now[0])
        for t in (0.3, 0.6, 0.9):
            now[0] = t
            p.update(100)
        p.close()
    assert s.text == ("\r" + format_line("teleop", 200, None, "env-steps", 0.6) + "\x1b[K" +
                      "\r" + format_line("teleop", 300, None, "env-steps", 0.9) + "\x1b[K" +
                      "\r" + format_line("teleop", 300, None, "env-steps", 0.9) + "\x1b[K\n")
    assert pipe.text == ""
