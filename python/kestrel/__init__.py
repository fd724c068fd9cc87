"""Kestrel from Python: scenarios, registries, RL tasks and the Simulator interface of Kestrel's
simulation harness (``sim/``), with gymnasium vector envs and thin adapters for Stable-Baselines3
and rsl_rl.

    import kestrel
    kestrel.list()                                   # the registries
    task = kestrel.make_task("position_setpoint_task", num_envs=64, seed=0)
    obs = task.observations                          # numpy view of the task's own buffer
    env = kestrel.make_vec("Kestrel-PositionSetpoint-v0", num_envs=1024, seed=0)
    obs, info = env.reset(seed=0)
    obs, rew, term, trunc, info = env.step(env.action_space.sample())
    sim = kestrel.make_simulator({"env": "empty", "sensors": ["vl53l5cx"]}, num_envs=8)
    depth = sim.range_images(0)                      # (8, 8, 8) read-only view of the ToF images

From the shell: `kestrel train TASK --learner rsl_rl --envs N --seed S --out DIR` (kestrel.cli).
"""

from __future__ import annotations

import builtins
import json
import os
from typing import Any, Mapping

from . import _core
from ._core import (Config, Multibody, RobotModel, Simulator, Task, box2d_hooks_active, load_robot_model, load_scenario_file,
                    load_scenario_string)

__all__ = [
    "Config",
    "Simulator",
    "Task",
    "box2d_hooks_active",
    "list",
    "register",
    "PythonTask",
    "PythonTaskVectorEnv",
    "SceneTask",
    "Multibody",
    "RobotModel",
    "load_robot_model",
    "load_scenario_file",
    "load_scenario_string",
    "make_simulator",
    "make_task",
    "make_vec",
    "scenario",
    "task_ids",
    "GYM_IDS",
]

_KINDS = ("sims", "envs", "robots", "controllers", "sensors", "tasks", "simulators")


def list(kind: str | None = None, descriptions: bool = False):  # noqa: A001 - the seeds' `list`
    """The registries: {kind: [names]} for every kind, or the names of one kind ('sims', 'envs',
    'robots', 'controllers', 'sensors', 'tasks', 'simulators'); with descriptions=True, (name,
    description) pairs. 'rl_tasks' gives the ids make_task accepts."""
    if kind == "rl_tasks":
        return task_ids()
    regs = _core.registries()
    if kind is not None and kind not in regs:
        raise ValueError(f"kind: expected one of {', '.join(_KINDS)}, rl_tasks; got {kind!r}")
    pick = (lambda rows: rows) if descriptions else (lambda rows: [n for n, _ in rows])
    if kind is not None:
        return pick(regs[kind])
    return {k: pick(v) for k, v in regs.items()}


_SINGULAR = {"sims": "sim", "envs": "env", "robots": "robot", "controllers": "controller", "sensors": "sensor",
             "tasks": "task", "simulators": "simulator"}
_DEFAULT_BASE = {"sim": "base_sim", "env": "empty", "robot": "base_quadrotor", "task": "position_setpoint",
                 "simulator": "rigid"}


def register(kind: str, name: str, base: str | None = None, description: str = "", **fields: Any) -> None:
    """Registers a preset at run time, as Aerial Gym's register_sim / register_env / register_robot:
    kind 'sim', 'env', 'robot', 'controller', 'sensor', 'task' or 'simulator' (plural accepted);
    the preset is `base` (a registered name; sims, envs, robots, tasks and simulators have a
    default) with `fields` overridden, under the scenario keys of that section
    (docs/scenario_reference.md), checked now. Scenarios, make_simulator and make_task can then
    name it. Errors (ValueError) name the kind, the name and the field.

        kestrel.register("sim", "falling_forwards", base="base_sim", gravity_w=[5.0, 0.0, -9.81])
    """
    k = _SINGULAR.get(kind, kind)
    if base is None:
        if k not in _DEFAULT_BASE:
            raise ValueError(f"register {kind} {name!r}: base: expected the name of a registered {k} to start from")
        base = _DEFAULT_BASE[k]
    section = dict(fields)
    section["name"] = base
    _core.register_preset(k, name, json.dumps(section), description)


def task_ids() -> builtins.list[str]:
    """Every RL task id (position_setpoint_task, navigation_task and the custom tasks)."""
    return _core.rl_task_ids()


def _merge(base: dict, over: Mapping[str, Any]) -> dict:
    out = dict(base)
    for k, v in over.items():
        if isinstance(v, Mapping) and isinstance(out.get(k), Mapping):
            out[k] = _merge(out[k], v)
        elif isinstance(v, Mapping) and isinstance(out.get(k), str):
            out[k] = _merge({"name": out[k]}, v)  # `env: forest` + {num_envs: 8} -> {name: forest, num_envs: 8}
        else:
            out[k] = v
    return out


def scenario(source: Any = None, *, task_id: str | None = None, num_envs: int | None = None, seed: int | None = None,
             threads: int | None = None, first_env_index: int | None = None, total_num_envs: int | None = None,
             **overrides: Any) -> Config:
    """A parsed scenario (kestrel.Config) from a file path, YAML text or a dict (the scenario file's
    sections: sim, env, robot, controller, task, sensors, seed, threads, simulator), with `task_id`
    naming an RL task and `overrides` merged into the dict's sections (e.g. controller=
    "lee_velocity_control", task={"episode_len_env_steps": 300}). num_envs, seed and threads are
    set last, as `kestrel run --envs --seed --threads` does. first_env_index / total_num_envs
    (env.first_env_index / env.total_num_envs) make the world environments first_env_index ..
    first_env_index + num_envs - 1 of a run of total_num_envs: each behaves as that environment of
    the whole run (its random streams, its grid cell), which kestrel.cluster's rollout actors use.
    Errors (ValueError) name the field and the allowed values."""
    if isinstance(source, Config):
        if task_id is not None or overrides:
            raise ValueError("scenario: a parsed Config takes num_envs/seed/threads only; pass a dict to override sections")
        cfg = source
    elif source is not None and not isinstance(source, Mapping) and (
            isinstance(source, os.PathLike) or (isinstance(source, str) and "\n" not in source and source.endswith((".yaml", ".yml", ".json")))):
        if task_id is not None or overrides:
            raise ValueError("scenario: a scenario file takes num_envs/seed/threads only; pass a dict to override sections")
        cfg = load_scenario_file(os.fspath(source))
    elif isinstance(source, str):
        if task_id is not None or overrides:
            raise ValueError("scenario: YAML text takes num_envs/seed/threads only; pass a dict to override sections")
        cfg = load_scenario_string(source, "<string>")
    elif source is None or isinstance(source, Mapping):
        d: dict = dict(source or {})
        if task_id is not None:
            t = d.get("task")
            d["task"] = _merge(t, {"name": task_id}) if isinstance(t, Mapping) else task_id
        d = _merge(d, overrides)
        t = d.get("task")
        if isinstance(t, Mapping) and isinstance(t.get("pick_place"), Mapping) and "scene_file" in t["pick_place"]:
            # task.pick_place.scene_file: a USD scene mapped onto so101_pick_place's keys here, in
            # Python (kestrel.pick_place_scene; the C++ parser does not read USD).
            from .pick_place_scene import expand_scene_file
            d = expand_scene_file(d)
        # JSON is YAML: the C++ scenario parser reads it and names the fields in its errors.
        cfg = load_scenario_string(json.dumps(d), "<dict>")
    else:
        raise TypeError(f"scenario: expected a file path, YAML text, a dict or a kestrel.Config; got {type(source).__name__}")
    if num_envs is not None:
        cfg.num_envs = int(num_envs)
    if seed is not None:
        cfg.seed = int(seed)
    if first_env_index is not None:
        cfg.first_env_index = int(first_env_index)
    if total_num_envs is not None:
        cfg.total_num_envs = int(total_num_envs)
    # The slice must lie inside its run (the scenario file's own values are checked by the parser;
    # num_envs may have changed since).
    last = cfg.first_env_index + cfg.num_envs - 1
    if cfg.total_num_envs and last >= cfg.total_num_envs:
        raise ValueError(f"first_env_index: environments {cfg.first_env_index}..{last} lie beyond total_num_envs "
                         f"{cfg.total_num_envs}; expected first_env_index + num_envs <= total_num_envs")
    if last >= 1 << 20:
        raise ValueError(f"first_env_index: environments {cfg.first_env_index}..{last} lie beyond the limit of "
                         f"{1 << 20} environments (kMaxNumEnvs); expected first_env_index + num_envs <= {1 << 20}")
    # As `kestrel run`: every core unless threads is given (results are identical for any count).
    cfg.num_threads = int(threads) if threads is not None else _default_threads()
    return cfg


def _default_threads() -> int:
    return max(1, os.cpu_count() or 1)


def make_task(task_id: str | None = None, *, scenario: Any = None, num_envs: int | None = None, seed: int | None = None,
              threads: int | None = None, backend: str | None = None, **overrides: Any) -> Task:
    """Builds an RL task (kestrel.Task) by id, on its own scene or a scenario's (file, YAML text,
    dict or Config), with section overrides. backend: 'rigid', 'planar' or None (KESTREL_SIMULATOR,
    else the scenario's `simulator:`, else rigid)."""
    if task_id is not None and task_id not in task_ids():
        raise ValueError(f"task_id: unknown task {task_id!r}; registered task ids: {', '.join(task_ids())}")
    if scenario is not None and not isinstance(scenario, Mapping) and task_id is not None:
        # A file / text / Config scenario: its task replaced by id, as `kestrel run SCENARIO --task ID`.
        raise ValueError("make_task: give a task id with a dict scenario (or name the task inside the scenario)")
    cfg = globals()["scenario"](scenario, task_id=task_id, num_envs=num_envs, seed=seed, threads=threads, **overrides)
    return Task(cfg, backend or "")


def make_simulator(scenario: Any = None, *, num_envs: int | None = None, seed: int | None = None, threads: int | None = None,
                   backend: str | None = None, **overrides: Any) -> Simulator:
    """The Simulator interface (sim/simulator.hpp) over a scenario, views as numpy arrays."""
    cfg = globals()["scenario"](scenario, num_envs=num_envs, seed=seed, threads=threads, **overrides)
    return Simulator(cfg, backend or "")


from .vector_env import GYM_IDS, KestrelVectorEnv, make_vec, register_envs  # noqa: E402
from .python_task import PythonTask, PythonTaskVectorEnv  # noqa: E402
from .scene_task import SceneTask  # noqa: E402

register_envs()
