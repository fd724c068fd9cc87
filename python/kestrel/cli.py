"""The `kestrel` console command of the Python package (pyproject.toml [project.scripts]).

    kestrel train TASK --learner rsl_rl --envs 256 --seed 0 --out runs/ps   # kestrel.train
    kestrel export --rsl-rl CKPT ... --onnx policy.onnx --header policy.hpp  # kestrel.export
    kestrel sweep SCENARIO --grid KEY=V1,V2 --seeds 8 --address auto        # kestrel.cluster (Ray)

`kestrel run SCENARIO` and the other scenario commands are the C++ CLI (build/host/sim/kestrel),
which this command does not replace: any other command is handed to that program (KESTREL_CLI, or
build/host/sim/kestrel under the current directory) when it exists; otherwise the command says so
and exits with status 2.
"""
from __future__ import annotations

import os
import sys

_COMMANDS = {
    "train": "train a policy with rsl_rl or Stable-Baselines3: progress bar, evaluations, checkpoints, TensorBoard, CSV, plot, ONNX",
    "export": "export a trained actor to a C++ header (firmware) and/or ONNX",
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
    if cmd == "sweep":  # kestrel.cluster: Ray tasks (or this process)
        from .cluster import sweep_main

        return sweep_main(rest, prog="kestrel sweep")
    cxx = os.environ.get("KESTREL_CLI") or os.path.join("build", "host", "sim", "kestrel")
    if os.path.isfile(cxx) and os.access(cxx, os.X_OK):
        os.execv(cxx, [cxx, *argv])  # the C++ CLI: kestrel run / list / ...
    print(f"kestrel: unknown command {cmd!r} (this is the Python package's command: train, export, sweep)\n\n{_usage()}",
          file=sys.stderr)
    return 2


if __name__ == "__main__":
    raise SystemExit(main())
