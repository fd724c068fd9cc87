"""The `kestrel` console command of the Python package (pyproject.toml [project.scripts]).

    kestrel train TASK --learner rsl_rl --envs 256 --seed 0 --out runs/ps   # kestrel.train
    kestrel export --rsl-rl CKPT ... --onnx policy.onnx --header policy.hpp  # kestrel.export
    kestrel view [SCENARIO] | --replay run.mcap; kestrel teleop [SCENARIO]   # kestrel.viewer
    kestrel teleop --task Kestrel-SO101-PickPlace-v0 --device keyboard [--record DIR]   # kestrel.so101_teleop
    kestrel replay DIR [--episode K]                                         # SO-101 episodes, bit for bit
    kestrel run SCENARIO --record run.mcap [--view]                          # kestrel.record
    kestrel sweep SCENARIO --grid KEY=V1,V2 --seeds 8 --address auto        # kestrel.cluster (Ray)

`kestrel run SCENARIO` and the other scenario commands are the C++ CLI (build/host/sim/kestrel),
which this command does not replace: any other command is handed to that program (KESTREL_CLI, or
build/host/sim/kestrel under the current directory) when it exists; otherwise the command says so
and exits with status 2. `run` goes to it as a child process, and then this command draws the run's
figures from the CSVs it wrote (kestrel.plots: the C++ program cannot import matplotlib); `--no-plot`
skips that. `kestrel plot DIR` draws them for any earlier run.
"""
from __future__ import annotations

import os
import sys

_COMMANDS = {
    "train": "train a policy with rsl_rl or Stable-Baselines3: progress bar, evaluations, checkpoints, TensorBoard, CSV, plot, ONNX",
    "export": "export a trained actor to a C++ header (firmware) and/or ONNX",
    "view": "the 3-D viewer in a browser page (viser): a live run, or --replay FILE with a time slider",
    "teleop": "the viewer with robot 0 of env 0 driven from the page's keyboard and mouse; SO-101 pick and place "
              "(--task Kestrel-SO101-PickPlace-v0 --device keyboard|so101leader [--record DIR])",
    "replay": "re-run recorded SO-101 episodes (a LeRobot dataset of kestrel teleop --record) and check them bit for bit",
    "plot": "draw a run's figures (trajectory.png, curves.png) from its CSVs with matplotlib",
    "run": "the C++ harness's `kestrel run`, then its trajectory plot (--no-plot: without; --record FILE / --view: through the bindings)",
    "sweep": "fan a scenario over a parameter grid / random draws and seeds on Ray (or this process): table, plot, combined hash",
}


def _usage() -> str:
    rows = "\n".join(f"  {k:<8} {v}" for k, v in _COMMANDS.items())
    return (f"usage: kestrel COMMAND [ARGS]  (kestrel COMMAND -h for its options)\n\ncommands:\n{rows}\n\n"
            "Other commands (`kestrel run SCENARIO`, ...) go to the C++ CLI, build/host/sim/kestrel (or KESTREL_CLI), if built.")


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(_usage())
        return 0 if argv else 2
    cmd, rest = argv[0], argv[1:]
    if cmd == "train":
        from .train import main as train_main

        train_main(rest, prog="kestrel train")
        return 0
    if cmd == "export":
        from .export import main as export_main

        return export_main(rest, prog="kestrel export")
    if cmd == "teleop" and _so101_teleop(rest):
        from .so101_teleop import teleop_main

        return teleop_main(rest, prog="kestrel teleop")
    if cmd == "replay":
        from .so101_teleop import replay_main

        return replay_main(rest, prog="kestrel replay")
    if cmd in ("view", "teleop"):
        from .viewer import view_main

        return view_main(rest, prog=f"kestrel {cmd}", teleop=cmd == "teleop")
    if cmd == "run" and any(a == "--view" or a == "--record" or a.startswith("--record=") for a in rest):
        # A recording or the viewer needs every step's state: the run goes through the bindings (kestrel.record).
        from .record import run_main

        return run_main(rest)
    if cmd == "plot":
        from .plots import main as plot_main

        return plot_main(rest, prog="kestrel plot")
    if cmd == "sweep":  # kestrel.cluster: Ray tasks (or this process)
        from .cluster import sweep_main

        return sweep_main(rest, prog="kestrel sweep")
    cxx = os.environ.get("KESTREL_CLI") or os.path.join("build", "host", "sim", "kestrel")
    if os.path.isfile(cxx) and os.access(cxx, os.X_OK):
        if cmd == "run":
            return _run_and_plot(cxx, rest)
        os.execv(cxx, [cxx, *argv])  # the C++ CLI: kestrel list / schema / ...
    print(f"kestrel: unknown command {cmd!r} (this is the Python package's command: train, export, view, teleop, replay, plot, sweep)\n\n{_usage()}",
          file=sys.stderr)
    return 2


def _so101_teleop(args: list[str]) -> bool:
    """`kestrel teleop` of the SO-101 task (--device, or --task naming it) rather than the viewer's."""
    for i, x in enumerate(args):
        if x == "--device" or x.startswith("--device="):
            return True
        v = x.split("=", 1)[1] if x.startswith("--task=") else (args[i + 1] if x == "--task" and i + 1 < len(args) else None)
        if v is not None and v in ("Kestrel-SO101-PickPlace-v0", "so101_pick_place"):
            return True
    return False


def _run_and_plot(cxx: str, args: list[str]) -> int:
    """`kestrel run ARGS`: the C++ harness as a child (its stdout, stderr and terminal are this
    process's: the progress line still sees a terminal), then trajectory.png from the CSVs it wrote
    to --out (default kestrel_out, the C++ program's default). Its exit status, or 1 if plotting failed."""
    import subprocess

    plot = "--no-plot" not in args
    args = [a for a in args if a != "--no-plot"]
    out_dir = "kestrel_out"
    for i, a in enumerate(args[:-1]):
        if a == "--out":
            out_dir = args[i + 1]  # the last --out wins, as in the C++ parser
    # KESTREL_PLOT_BY_CALLER: the C++ program leaves out its "plot: kestrel plot DIR" hint.
    rc = subprocess.call([cxx, "run", *args], env={**os.environ, "KESTREL_PLOT_BY_CALLER": "1"})
    if rc != 0 or not plot or any(a in ("-h", "--help") for a in args):
        return rc
    sys.stdout.flush()
    try:
        from .plots import plot_trajectory

        print(f"  wrote {plot_trajectory(out_dir)}")
    except Exception as ex:  # the run itself succeeded: say what is missing, keep its CSVs
        print(f"kestrel run: the run's CSVs are in {out_dir}, but its plot failed: {type(ex).__name__}: {ex}\n"
              f"  (retry with `kestrel plot {out_dir}`)", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
