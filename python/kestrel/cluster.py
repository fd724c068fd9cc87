"""Kestrel beyond one machine: parameter sweeps and training rollouts on a Ray cluster.

    from kestrel import cluster
    res = cluster.sweep("position_setpoint_task", grid={"controller.k_pos": [[2, 2, 1], [3, 3, 2]]},
                        seeds=8, envs=64, steps=500, address="auto")      # or "ray://head:10001", or workers=4
    res.combined_hash, res.rows                                           # one row per run, in run order
    res.write_table("sweep/runs.parquet"); res.plot("sweep/summary.png")

    env = cluster.RayVectorEnv("Kestrel-PositionSetpoint-v0", num_envs=4096, workers=4, address="auto")
    # a gymnasium VectorEnv: kestrel.adapters.RslRlVecEnv(env) / Sb3VecEnv(env) train on it as on make_vec's

From the shell: `kestrel sweep SCENARIO --grid KEY=V1,V2 --random KEY=uniform(LO,HI) --samples N --seeds N
--address auto|ray://HOST:PORT --out DIR` and `kestrel train ... --address auto --rollout-workers 4`.

The engine is Ray (its tasks for sweeps, its actors for rollouts); Kestrel adds no scheduler.

Determinism that does not depend on how the work is split:

- Sweeps: the plan (grid points x seeds, random points drawn from ``sample_seed``) is made in the
  driver before anything is split, and each run gets its global index ``run_id``. A run is one
  batched world built and stepped inside one task, so its row depends on (scenario, params, seed,
  envs, steps) only, never on the worker, the node or the order results arrive in; the table is
  sorted by run_id and the combined hash is SHA-256 over each run's deterministic fields in run_id
  order. A worker killed mid-run costs a retry of its task (Ray re-runs it: the same row); rows are
  keyed by run_id and checked to be present exactly once.
- Rollouts: the actor holding environments k0 .. k0+n-1 builds its world with
  ``env.first_env_index = k0`` and ``env.total_num_envs = N``, so environment k of the slice draws
  from the streams of global environment k0+k (RngStream(seed, k0+k, purpose)) and, on the
  articulated backend, stands in the same grid cell: the concatenated batches are bit-identical to
  one process's ``make_vec(num_envs=N)`` for any number of workers. That holds for tasks whose
  environments never read each other: position_setpoint_task, locomotion_task and the custom tasks.
  navigation_task's obstacle curriculum is one level shared by every environment, moved by the
  success rate of all of them: a slice would move its own. RayVectorEnv refuses it unless the
  curriculum is held (task.curriculum increase_step = decrease_step = 0).
"""

from __future__ import annotations

import copy
import csv
import hashlib
import itertools
import json
import math
import os
import re
import sys
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Mapping, Sequence

import numpy as np

import kestrel
from . import _core

__all__ = ["RunSpec", "SweepResult", "plan_sweep", "parse_grid_arg", "parse_random_arg", "run_one", "sweep",
           "RayVectorEnv", "connect", "FAULT_NAMES", "sweep_main"]

# kernel/include/kestrel/kernel/status.hpp's Fault bits, for the table's readable `faults` column.
FAULT_NAMES = ("non_finite_command", "non_finite_state", "command_out_of_range", "saturated", "singular",
               "unallocated", "motor_failure", "not_converged", "non_finite_output")

# The row fields that are the same whoever runs the run: the combined hash covers exactly these.
_HASHED = ("run_id", "seed", "params", "status", "error", "envs", "steps", "episodes", "terminations", "truncations",
           "crashes", "successes", "success_rate", "mean_episode_reward", "mean_tracking_error_m", "final_mean_distance_m",
           "fault_bits", "reset_errors", "state_hash")


# ---- the plan ------------------------------------------------------------------------------------

@dataclass(frozen=True)
class RunSpec:
    """One run of a sweep: its global index (the key of its row), seed and parameter values."""
    run_id: int
    seed: int
    params: tuple  # ((dotted key, value), ...), in the order the parameters were given


def _value(text: str) -> Any:
    """A command-line value as YAML reads it (numbers, lists, booleans, names)."""
    import yaml

    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as e:
        raise ValueError(f"cannot read {text!r} as a value ({e})") from None


_KEY = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*$")


def _check_key(key: str, arg: str) -> str:
    if not _KEY.match(key):
        raise ValueError(f"{arg}: expected KEY=VALUES with KEY a dotted scenario key such as controller.k_pos or "
                         f"task.reward.crash_reward; got key {key!r}")
    if key in ("seed", "threads") or key.startswith(("env.num_envs", "env.first_env_index", "env.total_num_envs")):
        raise ValueError(f"{arg}: {key} is set by the sweep itself (--seeds, --envs, --threads); sweep another key")
    return key


def parse_grid_arg(arg: str) -> tuple[str, list]:
    """``KEY=V1,V2,...`` (each value read as YAML: 0.5, true, lee_velocity_control) or
    ``KEY=[V1, V2, ...]`` (a YAML list, for values that are lists themselves: [[2,2,1],[3,3,2]])."""
    if "=" not in arg:
        raise ValueError(f"--grid: expected KEY=V1,V2,... or KEY=[V1, V2, ...], got {arg!r}")
    key, text = arg.split("=", 1)
    key = _check_key(key.strip(), "--grid")
    text = text.strip()
    values = _value(text) if text.startswith("[") else [_value(t.strip()) for t in text.split(",")]
    if not isinstance(values, list) or not values:
        raise ValueError(f"--grid {key}: expected a non-empty list of values, got {text!r}")
    return key, values


_DISTS = {"uniform": 2, "loguniform": 2, "randint": 2, "choice": None}


def parse_random_arg(arg: str) -> tuple[str, tuple]:
    """``KEY=uniform(LO,HI)``, ``KEY=loguniform(LO,HI)``, ``KEY=randint(LO,HI)`` (HI included) or
    ``KEY=choice(V1,V2,...)``: a distribution sampled --samples times in the driver."""
    m = re.match(r"^\s*([^=]+)=\s*(\w+)\((.*)\)\s*$", arg)
    if not m:
        raise ValueError(f"--random: expected KEY=DIST(ARGS) with DIST one of {', '.join(_DISTS)}, got {arg!r}")
    key, dist, inner = _check_key(m.group(1).strip(), "--random"), m.group(2), m.group(3)
    if dist not in _DISTS:
        raise ValueError(f"--random {key}: distribution {dist!r}; allowed: {', '.join(_DISTS)}")
    args = _value(f"[{inner}]")
    return key, (dist, *args) if isinstance(args, list) else (dist,)


def _check_dist(key: str, d: Sequence) -> tuple:
    if isinstance(d, str):
        return parse_random_arg(f"{key}={d}")[1]
    d = tuple(d)
    if not d or d[0] not in _DISTS:
        raise ValueError(f"random[{key!r}]: expected (DIST, ARGS...) with DIST one of {', '.join(_DISTS)}, got {d!r}")
    n = _DISTS[d[0]]
    if n is not None:
        if len(d) != 1 + n or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in d[1:]):
            raise ValueError(f"random[{key!r}]: {d[0]} expects two numbers (LO, HI), got {d[1:]!r}")
        if not d[1] <= d[2] or (d[0] == "loguniform" and d[1] <= 0):
            raise ValueError(f"random[{key!r}]: {d[0]} expects LO <= HI{' and LO > 0' if d[0] == 'loguniform' else ''}, got {d[1:]!r}")
    elif len(d) < 2:
        raise ValueError(f"random[{key!r}]: choice expects at least one value")
    return d


def plan_sweep(grid: Mapping[str, Sequence] | None = None, random: Mapping[str, Any] | None = None, samples: int = 0,
               seeds: int | Sequence[int] = 1, sample_seed: int = 0) -> list[RunSpec]:
    """The runs of a sweep, numbered: every grid point (Cartesian product, the first key slowest)
    times every random point (``samples`` draws of the ``random`` distributions from numpy's
    PCG64 seeded with ``sample_seed``, drawn here, before any split) times every seed. run_id =
    (point index) x len(seeds) + seed index."""
    grid = dict(grid or {})
    random = {k: _check_dist(k, v) for k, v in dict(random or {}).items()}
    if isinstance(seeds, (int, np.integer)) and not isinstance(seeds, bool):
        if seeds < 1:
            raise ValueError(f"seeds: expected a count >= 1 or a list of seeds >= 0, got {seeds}")
        seed_list = list(range(int(seeds)))
    else:
        seed_list = [int(s) for s in seeds]
        if not seed_list or min(seed_list) < 0 or len(set(seed_list)) != len(seed_list):
            raise ValueError(f"seeds: expected a count >= 1 or a list of distinct seeds >= 0, got {list(seeds)!r}")
    for k, v in grid.items():
        _check_key(k, "grid")
        if isinstance(v, (str, bytes)) or not isinstance(v, Sequence) or len(v) == 0:
            raise ValueError(f"grid[{k!r}]: expected a non-empty list of values, got {v!r}")
    for k in random:
        _check_key(k, "random")
        if k in grid:
            raise ValueError(f"random[{k!r}]: the key is also in grid; give it one or the other")
    if random and samples < 1:
        raise ValueError(f"samples: expected an integer >= 1 with random parameters, got {samples}")
    if samples and not random:
        raise ValueError("samples: given without random parameters (--random KEY=DIST(...))")
    grid_points = [tuple(zip(grid.keys(), combo)) for combo in itertools.product(*grid.values())] if grid else [()]
    rand_points: list[tuple] = [()]
    if random:
        rng = np.random.default_rng(sample_seed)
        rand_points = []
        for _ in range(samples):
            pt = []
            for k, d in random.items():
                kind = d[0]
                if kind == "uniform":
                    v = float(rng.uniform(d[1], d[2]))
                elif kind == "loguniform":
                    v = float(math.exp(rng.uniform(math.log(d[1]), math.log(d[2]))))
                elif kind == "randint":
                    v = int(rng.integers(int(d[1]), int(d[2]), endpoint=True))
                else:
                    v = d[1 + int(rng.integers(0, len(d) - 1))]
                pt.append((k, v))
            rand_points.append(tuple(pt))
    runs: list[RunSpec] = []
    for point in itertools.product(grid_points, rand_points):
        params = point[0] + point[1]
        for s in seed_list:
            runs.append(RunSpec(len(runs), s, params))
    return runs


# ---- one run ---------------------------------------------------------------------------------------

def _set_dotted(d: dict, key: str, value: Any, sections: Mapping[str, str] | None = None) -> None:
    parts = key.split(".")
    cur = d
    for i, p in enumerate(parts[:-1]):
        nxt = cur.get(p)
        if nxt is None and i == 0 and sections and p in sections:
            # A section the scenario leaves to its task's scene (env, robot, ...): the override
            # starts from the preset the scenario resolved to, as a file naming it would.
            nxt = sections[p]
        if isinstance(nxt, str):  # `controller: lee_velocity_control` + controller.k_pos -> {name: ..., k_pos: ...}
            nxt = {"name": nxt}
        elif not isinstance(nxt, dict):
            nxt = {}
        cur[p] = nxt
        cur = nxt
    cur[parts[-1]] = value


@dataclass
class _Scenario:
    """A sweep's scenario as plain data shipped to the workers: the dict, and the folder the files
    it names are relative to (a scenario file's own folder)."""
    data: dict
    base_dir: str
    name: str
    sections: dict = field(default_factory=dict)  # section -> the preset name it resolved to


def _load_scenario(scenario: Any, task: str | None) -> _Scenario:
    if isinstance(scenario, _Scenario):
        return scenario
    if isinstance(scenario, Mapping):
        data, base, name = copy.deepcopy(dict(scenario)), "", "<dict>"
    elif isinstance(scenario, (str, os.PathLike)) and (os.fspath(scenario).endswith((".yaml", ".yml", ".json"))
                                                      or os.path.isfile(os.fspath(scenario))):
        import yaml

        path = os.fspath(scenario)
        try:
            with open(path) as f:
                data = yaml.safe_load(f)
        except OSError as e:
            raise ValueError(f"scenario: cannot read {path!r} ({e.strerror})") from None
        if not isinstance(data, dict):
            raise ValueError(f"scenario: {path}: expected a map with sim, env, robot, controller, task, ... at the top")
        base, name = os.path.dirname(os.path.abspath(path)), path
    elif isinstance(scenario, str) and scenario in kestrel.task_ids():
        data, base, name = {"task": scenario}, "", scenario
    elif isinstance(scenario, str) and scenario in kestrel.GYM_IDS:
        tid, defaults = kestrel.GYM_IDS[scenario]
        # The id's sections over its task (a task preset such as locomotion_go2 names the task itself).
        data, base, name = kestrel._merge({"task": tid}, copy.deepcopy(defaults)), "", scenario
    else:
        raise ValueError(f"scenario: expected a scenario file (.yaml), a dict, a task id ({', '.join(kestrel.task_ids())}) "
                         f"or a gymnasium id; got {scenario!r}")
    if task is not None:
        if task not in kestrel.task_ids():
            raise ValueError(f"task: unknown task {task!r}; registered task ids: {', '.join(kestrel.task_ids())}")
        t = data.get("task")
        data["task"] = kestrel._merge(t, {"name": task}) if isinstance(t, Mapping) else task
    # The scenario as a whole must parse (a run's own parameters may still make it invalid: that run
    # is reported). A sweep flies an RL task under its scripted controller (as `kestrel run --task`):
    # success, crashes and episodes are the task's. A scenario naming none flies position_setpoint_task.
    cfg = _core.load_scenario_string(json.dumps(data), name, base)
    if cfg.task not in kestrel.task_ids():
        t = data.get("task")
        data["task"] = {**t, "name": "position_setpoint_task"} if isinstance(t, Mapping) else "position_setpoint_task"
        cfg = _core.load_scenario_string(json.dumps(data), name, base)
    sections = {"sim": cfg.sim, "env": cfg.env, "robot": cfg.robot, "controller": cfg.controller}
    return _Scenario(data, base, name, sections)


def _row_base(spec: RunSpec, envs: int, steps: int) -> dict:
    return {"run_id": spec.run_id, "seed": spec.seed, "params": json.dumps(dict(spec.params), sort_keys=True),
            "status": "ok", "error": "", "envs": envs, "steps": steps}


def _finish_row(row: dict, t0: float) -> dict:
    for k in _HASHED:
        row.setdefault(k, "" if k in ("error", "state_hash", "params", "status") else 0)
    row["faults"] = ",".join(n for i, n in enumerate(FAULT_NAMES) if int(row["fault_bits"]) >> i & 1)
    row["wall_s"] = round(time.perf_counter() - t0, 4)
    row["pid"] = os.getpid()
    return row


def run_one(scenario: Any, spec: RunSpec, envs: int = 64, steps: int = 1000, threads: int = 1, policy: str = "scripted",
            on_run_start: Callable[[int], None] | None = None) -> dict:
    """Runs one sweep run in this process and returns its row: the scenario with spec.params set
    (dotted keys), spec.seed, ``envs`` environments, ``steps`` task steps under the task's scripted
    controller (policy 'scripted') or zero actions ('zero'). A run whose scenario is invalid, or
    that fails while running, gives a row with status 'error' and the message; it never raises."""
    t0 = time.perf_counter()
    sc = _load_scenario(scenario, None)
    row = _row_base(spec, envs, steps)
    if on_run_start is not None:
        on_run_start(spec.run_id)
    try:
        data = copy.deepcopy(sc.data)
        for k, v in spec.params:
            _set_dotted(data, k, v, sc.sections)
        # Messages name the run, not how the scenario was given (file, dict, id): a row, and so the
        # combined hash, is the same for the same scenario whichever way it came in.
        cfg = _core.load_scenario_string(json.dumps(data), f"run {spec.run_id}", sc.base_dir)
        cfg.num_envs = int(envs)
        cfg.seed = int(spec.seed)
        cfg.num_threads = int(threads)
        task = kestrel.Task(cfg, "")
        if policy == "scripted":
            for _ in range(steps):
                task.step(task.scripted_actions())
        else:
            zeros = np.zeros((task.num_envs, task.action_dim), np.float32)
            for _ in range(steps):
                task.step(zeros)
        inf, summ = task.infos, task.summary
        row.update(episodes=int(inf["episodes"]), terminations=int(inf["terminations"]),
                   truncations=int(inf["truncations"]), crashes=int(inf["crashes"]), successes=int(inf["successes"]),
                   success_rate=float(inf["success_rate"]), mean_episode_reward=float(inf["mean_episode_reward"]),
                   mean_tracking_error_m=float(summ["mean_tracking_error_m"]),
                   final_mean_distance_m=float(summ["final_mean_distance_m"]), fault_bits=int(summ["fault_bits"]),
                   reset_errors=int(summ["reset_errors"]), state_hash=f"{task.state_hash:016x}")
    except Exception as e:  # noqa: BLE001 - a bad run is a row, not the end of the sweep
        row.update(status="error", error=f"{type(e).__name__}: {e}")
    return _finish_row(row, t0)


def _run_chunk(scenario: _Scenario, specs: list, envs: int, steps: int, threads: int, policy: str, on_run_start) -> list:
    return [run_one(scenario, s, envs, steps, threads, policy, on_run_start) for s in specs]


def combined_hash(rows: Iterable[Mapping]) -> str:
    """SHA-256 over each row's deterministic fields (_HASHED) in run_id order: equal for the same
    plan whoever ran which run, in whatever order."""
    h = hashlib.sha256()
    for r in sorted(rows, key=lambda r: r["run_id"]):
        h.update(json.dumps({k: r[k] for k in _HASHED}, sort_keys=True, separators=(",", ":")).encode())
        h.update(b"\n")
    return h.hexdigest()


# ---- Ray -----------------------------------------------------------------------------------------

def _ray():
    try:
        import ray
    except ImportError:
        raise ImportError("kestrel.cluster needs ray (pip install 'ray==2.58.0', pinned in python/requirements.txt)") from None
    return ray


def connect(address: str | None = None, workers: int | None = None, object_store_mb: int = 150):
    """Connects this process to Ray: the connection it already has, else ``address`` ('auto': the
    cluster `ray start` runs on this machine; 'ray://HOST:10001': Ray Client; 'HOST:6379': a head),
    else a Ray on this machine with ``workers`` CPUs (worker processes). Returns the ray module."""
    ray = _ray()
    if ray.is_initialized():
        return ray
    os.environ.setdefault("RAY_DISABLE_USAGE_STATS", "1")  # no telemetry from a simulator run
    kw: dict[str, Any] = {"include_dashboard": False, "logging_level": "ERROR", "log_to_driver": False}
    if address not in (None, "", "local"):
        ray.init(address=address, **({} if str(address).startswith("ray://") else {"logging_level": "ERROR"}))
    else:
        if workers is None or workers < 1:
            raise ValueError(f"workers: expected an integer >= 1 to start Ray on this machine, got {workers!r}")
        ray.init(num_cpus=int(workers), object_store_memory=object_store_mb << 20, **kw)
    return ray


@dataclass
class SweepResult:
    rows: list          # one dict per run, sorted by run_id
    combined_hash: str
    wall_s: float
    workers: int | None  # concurrent tasks (None: in this process)
    tasks: int
    settings: dict = field(default_factory=dict)

    @property
    def errors(self) -> list:
        return [r for r in self.rows if r["status"] != "ok"]

    def write_table(self, path: str) -> str:
        """The rows as Parquet (path ending in .parquet, pyarrow) or CSV (.csv)."""
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        cols = list(self.rows[0].keys()) if self.rows else list(_HASHED)
        if path.endswith(".parquet"):
            import pyarrow as pa
            import pyarrow.parquet as pq

            pq.write_table(pa.table({c: [r.get(c) for r in self.rows] for c in cols}), path)
        elif path.endswith(".csv"):
            with open(path, "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=cols)
                w.writeheader()
                w.writerows(self.rows)
        else:
            raise ValueError(f"path: expected a file name ending in .parquet or .csv, got {path!r}")
        return path

    def plot(self, path: str, title: str = "") -> str:
        """Success rate, tracking error and crashes per run against the first swept parameter (or the seed)."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        ok = [r for r in self.rows if r["status"] == "ok"]
        params = [json.loads(r["params"]) for r in ok]
        keys = list(params[0]) if ok else []
        # x: the parameter with the most distinct values (numbers on a number axis; lists, names and
        # booleans one position per value), else the seed.
        distinct = {k: sorted({json.dumps(p[k]) for p in params}) for k in keys}
        xkey = max(keys, key=lambda k: len(distinct[k]), default=None)
        if xkey is not None and len(distinct[xkey]) > 1 and all(
                isinstance(p[xkey], (int, float)) and not isinstance(p[xkey], bool) for p in params):
            xs, xlabel = [p[xkey] for p in params], xkey
        elif xkey is not None and len(distinct[xkey]) > 1:
            labels = distinct[xkey]
            xs = [labels.index(json.dumps(p[xkey])) for p in params]
            xlabel = f"{xkey} (" + ", ".join(f"{i}: {l}" for i, l in enumerate(labels)) + ")"
        else:
            xs, xlabel = [r["seed"] for r in ok], "seed"
        fig, ax = plt.subplots(1, 3, figsize=(13, 3.8))
        panels = (("success_rate", "success rate (real episodes)"), ("mean_tracking_error_m", "mean tracking error (m)"),
                  ("crashes", "crashed episodes per run"))
        seeds = [r["seed"] for r in ok]
        for a, (k, lab) in zip(ax, panels):
            a.scatter(xs, [r[k] for r in ok], c=seeds, cmap="viridis", s=18)
            a.set_xlabel(xlabel if len(xlabel) < 70 else xlabel[:67] + "...", fontsize=8)
            if xlabel.endswith(")") and xkey is not None and xlabel.startswith(f"{xkey} ("):
                a.set_xticks(range(len(distinct[xkey])))
            a.set_ylabel(lab)
            a.grid(alpha=0.3)
        ne = len(self.rows) - len(ok)
        fig.suptitle(title or f"{len(self.rows)} runs ({ne} failed), colour = seed; combined hash {self.combined_hash[:16]}",
                     fontsize=10)
        fig.tight_layout()
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        fig.savefig(path, dpi=110)
        plt.close(fig)
        return path


def sweep(scenario: Any, *, grid: Mapping[str, Sequence] | None = None, random: Mapping[str, Any] | None = None,
          samples: int = 0, seeds: int | Sequence[int] = 1, sample_seed: int = 0, task: str | None = None,
          envs: int = 64, steps: int = 1000, threads: int = 1, policy: str = "scripted", address: str | None = None,
          workers: int | None = None, runs_per_task: int = 1, max_retries: int = 3, progress: bool = False,
          on_run_start: Callable[[int], None] | None = None, submit_order: Sequence[int] | None = None) -> SweepResult:
    """Fans a scenario out over Ray tasks and gathers one row per run (see the module's doc).

    scenario: a scenario file, dict, task id or gymnasium id; grid / random / samples / seeds /
    sample_seed: the plan (plan_sweep); envs: environments of each run's batched world, stepped on
    ``threads`` threads (the task's Ray CPUs); steps: task steps per run; policy: 'scripted' or
    'zero'. address / workers: in this process (both None), a Ray on this machine with ``workers``
    worker processes (address None), or a cluster ('auto', 'ray://HOST:PORT'; workers then caps
    the tasks in flight, default every CPU of the cluster). runs_per_task: runs per Ray task (fewer,
    longer tasks when runs are short); max_retries: Ray's retries of a task whose worker died.
    on_run_start(run_id) runs in the worker before each run (instrumentation; the tests record
    the worker's pid with it to kill one). submit_order: a permutation of the task indices (tests:
    results must not depend on it)."""
    if policy not in ("scripted", "zero"):
        raise ValueError(f"policy: expected scripted or zero, got {policy!r}")
    for name, v, lo in (("envs", envs, 1), ("steps", steps, 1), ("threads", threads, 1), ("runs_per_task", runs_per_task, 1),
                        ("max_retries", max_retries, 0)):
        if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or v < lo:
            raise ValueError(f"{name}: expected an integer >= {lo}, got {v!r}")
    if workers is not None and (not isinstance(workers, (int, np.integer)) or workers < 1):
        raise ValueError(f"workers: expected an integer >= 1, got {workers!r}")
    sc = _load_scenario(scenario, task)
    runs = plan_sweep(grid, random, samples, seeds, sample_seed)
    chunks = [runs[i:i + runs_per_task] for i in range(0, len(runs), runs_per_task)]
    order = list(range(len(chunks))) if submit_order is None else [int(i) for i in submit_order]
    if sorted(order) != list(range(len(chunks))):
        raise ValueError(f"submit_order: expected a permutation of 0..{len(chunks) - 1}")
    settings = {"scenario": sc.name, "envs": envs, "steps": steps, "threads": threads, "policy": policy,
                "runs": len(runs), "runs_per_task": runs_per_task, "address": address, "sample_seed": sample_seed}
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(runs), unit="run", desc="kestrel sweep", file=sys.stderr)
    t0 = time.perf_counter()
    by_id: dict[int, dict] = {}

    def take(rows: list) -> None:
        for r in rows:
            if r["run_id"] in by_id:  # a result delivered twice would be a bug in the gathering
                raise RuntimeError(f"sweep: run {r['run_id']} delivered twice")
            by_id[r["run_id"]] = r
        if bar is not None:
            bar.update(len(rows))

    if address == "local" and workers is not None:
        raise ValueError("workers: address 'local' runs in this process; give workers without an address for a Ray on this machine")
    if address == "local" or (address in (None, "") and workers is None and not _ray_connected()):
        for i in order:  # the single-process reference: no Ray at all
            take(_run_chunk(sc, chunks[i], envs, steps, threads, policy, on_run_start))
        used_workers = None
    else:
        ray = connect(address, workers)
        remote = ray.remote(_run_chunk).options(num_cpus=threads, max_retries=max_retries, retry_exceptions=False)
        cap = workers or max(1, int(ray.cluster_resources().get("CPU", 1) // threads))
        used_workers = cap
        sc_ref = ray.put(sc)
        pending: dict = {}
        queue = list(order)
        while queue or pending:
            while queue and len(pending) < cap:
                i = queue.pop(0)
                pending[remote.remote(sc_ref, chunks[i], envs, steps, threads, policy, on_run_start)] = i
            done, _ = ray.wait(list(pending), num_returns=1)
            for ref in done:
                i = pending.pop(ref)
                try:
                    take(ray.get(ref))
                except ray.exceptions.RayError as e:
                    # The task's worker died more often than max_retries (or its node went away):
                    # its runs are reported with the reason; the sweep goes on.
                    msg = f"{type(e).__name__}: task lost after {max_retries} retries: {str(e).splitlines()[0][:300]}"
                    take([_finish_row({**_row_base(s, envs, steps), "status": "error", "error": msg}, time.perf_counter())
                          for s in chunks[i]])
    if bar is not None:
        bar.close()
    missing = [r.run_id for r in runs if r.run_id not in by_id]
    if missing or len(by_id) != len(runs):
        raise RuntimeError(f"sweep: runs missing from the results: {missing[:20]}")
    rows = [by_id[r.run_id] for r in runs]
    # Parameter columns (one per key) beside the JSON `params`, for tables and plots: numbers stay
    # numbers and booleans booleans where every run's value is one; anything else is JSON text, so
    # each column has one type (Parquet).
    keys = list(dict.fromkeys(k for r in runs for k, _ in r.params))
    values = {k: [dict(s.params).get(k) for s in runs] for k in keys}
    for k, vs in values.items():
        numeric = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in vs)
        boolean = all(isinstance(v, bool) for v in vs)
        for r, v in zip(rows, vs):
            r[f"p.{k}"] = float(v) if numeric else v if boolean else json.dumps(v)
    return SweepResult(rows, combined_hash(rows), time.perf_counter() - t0, used_workers, len(chunks), settings)


def _ray_connected() -> bool:
    try:
        import ray
    except ImportError:
        return False
    return ray.is_initialized()


# ---- rollouts ------------------------------------------------------------------------------------

class _RolloutWorker:
    """A Ray actor holding environments first .. first+count-1 of a run of `total` (a KestrelVectorEnv)."""

    def __init__(self, env_id: str, first: int, count: int, total: int, seed: int, threads: int, overrides: dict):
        self.env = kestrel.make_vec(env_id, num_envs=count, seed=seed, threads=threads, first_env_index=first,
                                    total_num_envs=total, **overrides)

    def spec(self) -> dict:
        e, t = self.env, self.env.task
        return {"obs_dim": t.obs_dim, "action_dim": t.action_dim, "low": float(e.single_action_space.low[0]),
                "high": float(e.single_action_space.high[0]), "name": t.name, "controller": t.controller,
                "episode_len_env_steps": t.episode_len_env_steps, "success_radius_m": t.success_radius_m,
                "pid": os.getpid()}

    def reset(self, seed):
        obs, _ = self.env.reset(seed=seed)
        return obs.copy()

    def step(self, actions):
        # Copies: the env's arrays are views its next step rewrites, and Ray serialises them now anyway.
        # Large arrays arrive as read-only views of Ray's object store; the binding takes writable
        # C-contiguous float32 (np.require copies only then).
        obs, rew, term, trunc, info = self.env.step(np.require(actions, np.float32, ["C", "W"]))
        return (obs.copy(), rew.copy(), term.copy(), trunc.copy(),
                info["final_obs"].copy() if "final_obs" in info else None,
                info["success"].copy() if "success" in info else None)

    def current_observations(self):
        return self.env.current_observations.copy()

    def infos(self) -> dict:
        return self.env.task_infos

    def scripted_actions(self):
        return self.env.scripted_actions()


class _TaskView:
    """What the learners' adapters and kestrel.train read from ``env.task``, for a RayVectorEnv."""

    def __init__(self, owner: "RayVectorEnv", spec: dict, seed: int):
        self._owner = owner
        self.name, self.controller = spec["name"], spec["controller"]
        self.episode_len_env_steps = spec["episode_len_env_steps"]
        self.success_radius_m = spec["success_radius_m"]
        self.obs_dim, self.action_dim, self.num_envs, self.seed = spec["obs_dim"], spec["action_dim"], owner.num_envs, seed

    @property
    def infos(self) -> dict:
        """The task counters summed over the slices (rates recomputed from the sums)."""
        parts = self._owner._ray.get([a.infos.remote() for a in self._owner._actors])
        out: dict = {}
        for k in ("steps", "episodes", "terminations", "truncations", "crashes", "successes", "episode_reward_sum"):
            out[k] = sum(p[k] for p in parts)
        out["steps"] = parts[0]["steps"]  # task steps: every slice steps together
        out["mean_episode_reward"] = out["episode_reward_sum"] / out["episodes"] if out["episodes"] else 0.0
        out["fallback_episodes"] = sum(p["fallback_episodes"] for p in parts)
        real = out["episodes"] - out["fallback_episodes"]
        out["success_rate"] = out["successes"] / real if real else 0.0
        out["curriculum_level"] = parts[0]["curriculum_level"]
        out["curriculum_changes"] = parts[0]["curriculum_changes"]
        return out


from gymnasium import spaces as _spaces  # noqa: E402
from gymnasium.vector import AutoresetMode as _AutoresetMode, VectorEnv as _VectorEnv  # noqa: E402
from gymnasium.vector.utils import batch_space as _batch_space  # noqa: E402


class RayVectorEnv(_VectorEnv):
    """A gymnasium VectorEnv whose environments live in Ray actors on any node of a cluster: actor
    j holds a contiguous slice of the global environments (a KestrelVectorEnv built with
    first_env_index / total_num_envs); step() sends each actor its rows of the actions and
    concatenates their observation / reward / flag batches in global order. The learner (rsl_rl
    through kestrel.adapters.RslRlVecEnv, or SB3 through Sb3VecEnv) runs in this process, unchanged.
    The batches are bit-identical to make_vec(id, num_envs) in one process for any ``workers``
    (``stream_hash`` digests them, step by step). Same-step autoreset as KestrelVectorEnv.

    id: a gymnasium id (kestrel.GYM_IDS) or task id; workers: actors (environments split as evenly
    as possible, the first ones one larger); threads: simulator threads (and Ray CPUs) per actor;
    address: as connect(); overrides: make_vec's (action_scale, vehicle_frame_obs, task={...}, ...)."""

    metadata = {"autoreset_mode": _AutoresetMode.SAME_STEP, "render_modes": []}

    def __init__(self, id: str, num_envs: int = 1024, seed: int = 0, workers: int = 2, threads: int = 1,
                 address: str | None = None, **overrides: Any):
        if not isinstance(num_envs, (int, np.integer)) or num_envs < 1:
            raise ValueError(f"num_envs: expected an integer >= 1, got {num_envs!r}")
        if not isinstance(workers, (int, np.integer)) or not 1 <= workers <= num_envs:
            raise ValueError(f"workers: expected an integer in [1, num_envs = {num_envs}], got {workers!r}")
        if not isinstance(threads, (int, np.integer)) or threads < 1:
            raise ValueError(f"threads: expected an integer >= 1, got {threads!r}")
        for k in ("first_env_index", "total_num_envs", "autoreset_mode"):
            if k in overrides:
                raise ValueError(f"{k}: set by RayVectorEnv itself (slices in global order, same-step autoreset)")
        if overrides.get("scenario") is not None and not isinstance(overrides["scenario"], Mapping):
            raise ValueError("scenario: RayVectorEnv takes a dict scenario (a file or Config cannot carry each slice's "
                             "first_env_index); load the file into a dict first")
        task_id = kestrel.GYM_IDS[id][0] if id in kestrel.GYM_IDS else id
        if task_id == "navigation_task":
            cur = (overrides.get("task") or {}).get("curriculum", {}) if isinstance(overrides.get("task"), Mapping) else {}
            if not (cur.get("increase_step") == 0 and cur.get("decrease_step") == 0):
                raise ValueError(
                    f"id: {id} (navigation_task) moves one obstacle curriculum level shared by every environment, by the "
                    "success rate of all of them; split over workers each slice would move its own, so its rollouts would "
                    "depend on the split. Hold the curriculum (task={'curriculum': {'increase_step': 0, 'decrease_step': 0}}) "
                    "or use one process (kestrel.make_vec). Partition-invariant: position_setpoint_task, locomotion_task, "
                    "the custom tasks.")
        self._ray = connect(address, workers * threads)
        n, w = int(num_envs), int(workers)
        sizes = [n // w + (1 if j < n % w else 0) for j in range(w)]
        self.slices = [(sum(sizes[:j]), sizes[j]) for j in range(w)]
        actor = self._ray.remote(_RolloutWorker).options(num_cpus=threads, max_restarts=0)
        self._actors = [actor.remote(id, first, count, n, int(seed), int(threads), overrides) for first, count in self.slices]
        specs = self._ray.get([a.spec.remote() for a in self._actors])
        s0 = specs[0]
        self.worker_pids = [s["pid"] for s in specs]
        self.num_envs = n
        self._seed = int(seed)
        self.task = _TaskView(self, s0, self._seed)
        self.single_observation_space = _spaces.Box(-np.inf, np.inf, (s0["obs_dim"],), np.float32)
        self.observation_space = _batch_space(self.single_observation_space, n)
        self.single_action_space = _spaces.Box(s0["low"], s0["high"], (s0["action_dim"],), np.float32)
        self.action_space = _batch_space(self.single_action_space, n)
        self.render_mode = None
        self.closed = False
        self._is_setpoint = s0["name"] == "position_setpoint_task"
        self._obs = np.concatenate(self._ray.get([a.current_observations.remote() for a in self._actors]))
        self._hash = hashlib.sha256()

    @property
    def stream_hash(self) -> str:
        """SHA-256 of every batch handed out since construction (reset observations; per step the
        observations, rewards, terminated, truncated flags and final observations), in global env
        order: equal across any number of workers when the rollouts are partition-invariant."""
        return self._hash.hexdigest()

    def _digest(self, *arrays) -> None:
        for a in arrays:
            if a is not None:
                self._hash.update(np.ascontiguousarray(a).tobytes())

    def reset(self, *, seed: int | list | None = None, options: dict | None = None):
        if isinstance(seed, (list, tuple)):
            seed = seed[0] if len(seed) else None
        if options:
            raise ValueError("options: RayVectorEnv resets every environment (env_ids are not supported)")
        s = None if seed is None else int(seed)
        if s is not None:
            self._seed = s
            self.task.seed = s
        # A seed rebuilds each slice with it; None resets the tasks in place, as KestrelVectorEnv.
        self._obs = np.concatenate(self._ray.get([a.reset.remote(s) for a in self._actors]))
        self._digest(self._obs)
        return self._obs, {}

    def step(self, actions):
        a = np.ascontiguousarray(actions, dtype=np.float32)
        if a.shape != (self.num_envs, self.single_action_space.shape[0]):
            raise ValueError(f"actions: expected shape {(self.num_envs, self.single_action_space.shape[0])}, got {a.shape}")
        parts = self._ray.get([act.step.remote(a[f:f + c]) for act, (f, c) in zip(self._actors, self.slices)])
        obs = np.concatenate([p[0] for p in parts])
        rew = np.concatenate([p[1] for p in parts])
        term = np.concatenate([p[2] for p in parts])
        trunc = np.concatenate([p[3] for p in parts])
        self._obs = obs
        infos: dict[str, Any] = {}
        if any(p[4] is not None for p in parts):
            # Slices where no episode ended send no final observations: their rows are the
            # (unused) current ones, as KestrelVectorEnv's buffer holds stale rows there.
            final = np.concatenate([p[4] if p[4] is not None else p[0] for p in parts])
            ended = np.logical_or(term, trunc)
            infos["final_obs"], infos["_final_obs"] = final, ended
            if self._is_setpoint:
                succ = np.concatenate([p[5] if p[5] is not None else np.zeros(len(p[1]), bool) for p in parts])
                infos["success"], infos["_success"] = succ, ended.copy()
            self._digest(obs, rew, term, trunc, np.where(ended[:, None], final, 0))
        else:
            self._digest(obs, rew, term, trunc)
        return obs, rew, term, trunc, infos

    @property
    def current_observations(self) -> np.ndarray:
        return self._obs

    @property
    def task_infos(self) -> dict:
        return self.task.infos

    def scripted_actions(self) -> np.ndarray:
        return np.concatenate(self._ray.get([a.scripted_actions.remote() for a in self._actors]))

    def close_extras(self, **kwargs: Any) -> None:
        for a in getattr(self, "_actors", []):
            try:
                self._ray.kill(a)
            except Exception:  # noqa: BLE001 - already gone with its node
                pass
        self._actors = []

    def __repr__(self) -> str:
        return f"RayVectorEnv({self.task.name}, num_envs={self.num_envs}, workers={len(self.slices)})"


# ---- `kestrel sweep` -------------------------------------------------------------------------------

def sweep_main(argv: list[str] | None = None, prog: str = "kestrel sweep") -> int:
    import argparse

    p = argparse.ArgumentParser(prog=prog, description=(
        "Fan a scenario out over Ray tasks (or this process) and gather one row per run: success, crashes, "
        "tracking error, faults, final state hash; a table (Parquet or CSV), a summary plot and the combined hash."))
    p.add_argument("scenario", help="scenario file (.yaml), task id or gymnasium id")
    p.add_argument("--task", default=None, help="RL task id to fly (default: the scenario's, else position_setpoint_task)")
    p.add_argument("--grid", action="append", default=[], metavar="KEY=V1,V2",
                   help="a swept scenario key (dotted, e.g. controller.k_pos=[[2,2,1],[3,3,2]] or env.max_latency_physics_steps=0,2); "
                        "repeat for a Cartesian product")
    p.add_argument("--random", action="append", default=[], metavar="KEY=DIST(..)",
                   help="a randomised key: uniform(LO,HI), loguniform(LO,HI), randint(LO,HI), choice(A,B,...); with --samples")
    p.add_argument("--samples", type=int, default=0, help="random points drawn (with --random)")
    p.add_argument("--sample-seed", type=int, default=0, help="seed of the random points' draw")
    p.add_argument("--seeds", type=int, default=1, help="seeds 0..N-1 per point")
    p.add_argument("--envs", type=int, default=64, help="environments of each run's batched world")
    p.add_argument("--steps", type=int, default=1000, help="task steps per run (position_setpoint_task: 500 per episode)")
    p.add_argument("--threads", type=int, default=1, help="simulator threads per run (the Ray task's CPUs)")
    p.add_argument("--policy", choices=["scripted", "zero"], default="scripted")
    p.add_argument("--address", default=None,
                   help="Ray cluster: auto (`ray start` on this machine), ray://HOST:10001 (Ray Client), HOST:6379; "
                        "local or omitted: this machine (with --workers: a Ray of that many worker processes, else this process)")
    p.add_argument("--workers", type=int, default=None, help="worker processes on this machine / tasks in flight on a cluster")
    p.add_argument("--runs-per-task", type=int, default=1)
    p.add_argument("--max-retries", type=int, default=3, help="retries of a task whose worker died")
    p.add_argument("--out", default="kestrel_sweep", help="folder for runs.parquet|csv, summary.png, sweep.json")
    p.add_argument("--format", choices=["parquet", "csv"], default="parquet")
    p.add_argument("--quiet", action="store_true")
    a = p.parse_args(argv)
    try:
        grid = dict(parse_grid_arg(g) for g in a.grid)
        rnd = dict(parse_random_arg(r) for r in a.random)
        res = sweep(a.scenario, grid=grid, random=rnd, samples=a.samples, seeds=a.seeds, sample_seed=a.sample_seed,
                    task=a.task, envs=a.envs, steps=a.steps, threads=a.threads, policy=a.policy, address=a.address,
                    workers=a.workers, runs_per_task=a.runs_per_task, max_retries=a.max_retries, progress=not a.quiet)
    except ValueError as e:
        print(f"{prog}: {e}", file=sys.stderr)
        return 2
    table = res.write_table(os.path.join(a.out, f"runs.{a.format}"))
    png = res.plot(os.path.join(a.out, "summary.png"), title=f"{res.settings['scenario']}: {len(res.rows)} runs, "
                   f"{len(res.errors)} failed; combined hash {res.combined_hash[:16]}")
    with open(os.path.join(a.out, "sweep.json"), "w") as f:
        json.dump({**res.settings, "combined_hash": res.combined_hash, "wall_s": round(res.wall_s, 3),
                   "workers": res.workers, "tasks": res.tasks, "errors": len(res.errors)}, f, indent=1)
    ok = [r for r in res.rows if r["status"] == "ok"]
    eps = sum(r["episodes"] for r in ok)
    print(f"{prog}: {len(res.rows)} runs ({len(res.errors)} failed) in {res.wall_s:.1f} s on "
          f"{'this process' if res.workers is None else f'{res.workers} Ray workers'}; "
          f"success {sum(r['successes'] for r in ok)}/{eps} episodes, crashes {sum(r['crashes'] for r in ok)}")
    for r in res.errors[:10]:
        print(f"  run {r['run_id']} (seed {r['seed']}, {r['params']}): {r['error']}")
    print(f"  combined hash {res.combined_hash}\n  wrote {table}, {png}, {os.path.join(a.out, 'sweep.json')}")
    return 1 if ok == [] and res.rows else 0
