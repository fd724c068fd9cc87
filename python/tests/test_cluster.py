"""kestrel.cluster on a real local Ray cluster (a head with no CPUs and two worker nodes on loopback,
ray.cluster_utils.Cluster): sweeps and rollouts give the same per-run rows, the same combined hash
and the same batches whether they run in one process, on 2 workers or on 4 and whatever order the
results arrive in; a worker killed mid-sweep costs only a retry; an invalid run is reported with
its error. Also env.first_env_index / total_num_envs themselves (no Ray needed)."""

import json
import os
import signal
import threading
import time

import numpy as np
import pytest

import kestrel
from kestrel import cluster

ray = pytest.importorskip("ray")

# Small worlds: the point is the bits, not the throughput. Episodes of 200 steps: a run of 450 steps
# ends and resets every env twice (resets draw from the per-env streams).
ENVS, STEPS = 8, 450
SCEN = {"task": {"name": "position_setpoint_task", "episode_len_env_steps": 200}}


@pytest.fixture(scope="module")
def ray_cluster():
    """A head (0 CPUs: no task runs there) and two worker nodes of 2 CPUs each, all on this
    machine; shut down whatever happens in the tests."""
    from ray.cluster_utils import Cluster

    os.environ["RAY_DISABLE_USAGE_STATS"] = "1"
    c = Cluster(initialize_head=True, head_node_args={"num_cpus": 0, "object_store_memory": 100 << 20,
                                                      "include_dashboard": False})
    try:
        for _ in range(2):
            c.add_node(num_cpus=2, object_store_memory=100 << 20)
        c.wait_for_nodes()
        ray.init(address=c.address, logging_level="ERROR", log_to_driver=False)
        yield c
    finally:
        ray.shutdown()
        c.shutdown()


# ---- the plan, the slice fields (no Ray) -----------------------------------------------------------

def test_plan_is_numbered_and_random_points_are_drawn_up_front():
    runs = cluster.plan_sweep({"a.x": [1, 2], "a.y": ["p", "q"]}, {"b.z": ("uniform", 0.0, 1.0)}, samples=3, seeds=2,
                              sample_seed=7)
    assert len(runs) == 2 * 2 * 3 * 2 and [r.run_id for r in runs] == list(range(24))
    assert runs[0].params[:2] == (("a.x", 1), ("a.y", "p")) and runs[-1].params[:2] == (("a.x", 2), ("a.y", "q"))
    again = cluster.plan_sweep({"a.x": [1, 2], "a.y": ["p", "q"]}, {"b.z": ("uniform", 0.0, 1.0)}, samples=3, seeds=2,
                               sample_seed=7)
    assert runs == again  # the random points depend on sample_seed only
    zs = {dict(r.params)["b.z"] for r in runs}
    assert len(zs) == 3 and all(0 <= z <= 1 for z in zs)
    assert cluster.parse_grid_arg("controller.k_pos=[[2,2,1],[3,3,2]]") == ("controller.k_pos", [[2, 2, 1], [3, 3, 2]])
    assert cluster.parse_grid_arg("env.max_latency_physics_steps=0,2") == ("env.max_latency_physics_steps", [0, 2])
    assert cluster.parse_random_arg("task.reward.crash_reward=uniform(-100, -10)") == (
        "task.reward.crash_reward", ("uniform", -100, -10))


@pytest.mark.parametrize("call, message", [
    (lambda: cluster.parse_grid_arg("controller.k_pos"), "--grid: expected KEY=V1,V2"),
    (lambda: cluster.parse_grid_arg("seed=1,2"), "set by the sweep itself"),
    (lambda: cluster.parse_random_arg("a.b=normal(0,1)"), "distribution 'normal'; allowed: uniform, loguniform, randint, choice"),
    (lambda: cluster.plan_sweep(seeds=0), "seeds: expected a count >= 1"),
    (lambda: cluster.plan_sweep(random={"a.b": ("uniform", 2, 1)}, samples=2), "uniform expects LO <= HI"),
    (lambda: cluster.plan_sweep(random={"a.b": ("uniform", 0, 1)}), "samples: expected an integer >= 1"),
    (lambda: cluster.sweep("position_setpoint_task", envs=0), "envs: expected an integer >= 1"),
    (lambda: cluster.sweep("position_setpoint_task", policy="random"), "policy: expected scripted or zero"),
    (lambda: cluster.sweep("no_such_task"), "scenario: expected a scenario file"),
    (lambda: kestrel.make_task("position_setpoint_task", num_envs=4, first_env_index=6, total_num_envs=8),
     "first_env_index: environments 6..9 lie beyond total_num_envs 8"),
    (lambda: kestrel.make_task("position_setpoint_task", num_envs=4, first_env_index=-1), "first_env_index: expected an integer in [0,"),
    (lambda: kestrel.make_task("position_setpoint_task", env={"name": "empty", "total_num_envs": -2}), "total_num_envs"),
])
def test_bad_input_names_the_argument(call, message):
    with pytest.raises(ValueError, match=None) as e:
        call()
    assert message in str(e.value), str(e.value)


def _scripted_rollout(env, steps):
    """obs / rewards / flags of `steps` scripted steps (the actions computed in global order)."""
    out = []
    obs, _ = env.reset()
    out.append(obs.copy())
    for _ in range(steps):
        obs, rew, term, trunc, info = env.step(env.scripted_actions())
        out += [obs.copy(), rew.copy(), term.copy(), trunc.copy()]
    return out


@pytest.mark.parametrize("gym_id, over", [
    ("Kestrel-PositionSetpoint-v0", {"task": {"episode_len_env_steps": 15}}),
    # disturbances and latency draw from the per-env streams every step
    ("Kestrel-PositionSetpointPosition-v0", {"env": {"name": "empty", "enable_disturbance": True, "sample_timestep_for_latency": True},
                                              "task": {"episode_len_env_steps": 15}}),
    ("Kestrel-PositionSetpoint-v0", {"backend": "planar", "task": {"episode_len_env_steps": 15}}),  # Box2D backend
    ("Kestrel-GoalBoxThroughGap-v0", {"task": {"episode_len_env_steps": 15}}),  # a custom task's own stream
])
def test_slices_with_first_env_index_are_the_global_envs(gym_id, over):
    """Environments 5..11 of a run of 12, built alone with first_env_index 5, behave bit for bit as
    rows 5..11 of the 12-env world (episodes end and reset on their own streams in the window)."""
    full = _scripted_rollout(kestrel.make_vec(gym_id, num_envs=12, seed=3, threads=1, **over), 40)
    part = _scripted_rollout(kestrel.make_vec(gym_id, num_envs=7, seed=3, threads=1, first_env_index=5, total_num_envs=12, **over), 40)
    assert any(a.dtype == bool and a.any() for a in full)  # some episode ended
    for a, b in zip(full, part):
        np.testing.assert_array_equal(a[5:12], b)
    # ... and without the field a 7-env world is envs 0..6, not 5..11 (the test can fail)
    plain = _scripted_rollout(kestrel.make_vec(gym_id, num_envs=7, seed=3, threads=1, **over), 40)
    assert not np.array_equal(full[0][5:12], plain[0])


def test_articulated_slice_keeps_its_grid_cell():
    """The legged backend's env origins lie on a grid sized by the whole run (total_num_envs)."""
    over = {"task": {"episode_len_env_steps": 20}}
    full = kestrel.make_vec("Kestrel-Go2-Flat-v0", num_envs=6, seed=1, threads=1, **over)
    part = kestrel.make_vec("Kestrel-Go2-Flat-v0", num_envs=2, seed=1, threads=1, first_env_index=4, total_num_envs=6, **over)
    a = np.zeros((6, full.single_action_space.shape[0]), np.float32)
    rng = np.random.default_rng(0)
    for _ in range(8):
        a[:] = rng.uniform(-0.5, 0.5, a.shape)
        o_full = full.step(a)[0].copy()
        o_part = part.step(np.ascontiguousarray(a[4:6]))[0]
        np.testing.assert_array_equal(o_full[4:6], o_part)


# ---- sweeps ------------------------------------------------------------------------------------------

# Two gain settings, the second invalid (a negative position gain), times disturbances off / on,
# times 3 seeds: 12 runs, 6 failing.
GRID = {"controller.k_pos": [[2.5, 2.5, 1.5], [-1.0, 2.0, 1.0]], "env.enable_disturbance": [False, True]}


def _hashed(rows):
    return [{k: r[k] for k in cluster._HASHED} for r in rows]


@pytest.fixture(scope="module")
def reference():
    """The single-process run (no Ray)."""
    return cluster.sweep(SCEN, grid=GRID, seeds=3, envs=ENVS, steps=STEPS, address="local")


def test_reference_sweep_rows_and_invalid_runs(reference):
    rows = reference.rows
    assert [r["run_id"] for r in rows] == list(range(12))
    bad = [r for r in rows if r["status"] == "error"]
    assert len(bad) == 6 and all("k_pos" in r["error"] for r in bad), [r["error"] for r in bad]
    ok = [r for r in rows if r["status"] == "ok"]
    assert all(r["episodes"] > 0 and len(r["state_hash"]) == 16 for r in ok)
    assert len({r["state_hash"] for r in ok}) == 6  # every (seed, disturbance) differs
    assert all(r["episodes"] == 2 * ENVS and r["successes"] > 0 for r in ok)  # the scripted Lee flights reach targets
    assert all(r["faults"] == "saturated" for r in ok)  # fault bits as names (the 4 m steps saturate the motors)
    assert reference.workers is None and len(reference.combined_hash) == 64


@pytest.mark.parametrize("workers, runs_per_task, order", [(1, 1, None), (2, 1, "reversed"), (4, 1, "shuffled"), (4, 3, None)])
def test_sweep_on_the_cluster_equals_one_process(ray_cluster, reference, workers, runs_per_task, order):
    n_tasks = -(-12 // runs_per_task)
    submit = None if order is None else (list(reversed(range(n_tasks))) if order == "reversed"
                                         else list(np.random.default_rng(5).permutation(n_tasks)))
    res = cluster.sweep(SCEN, grid=GRID, seeds=3, envs=ENVS, steps=STEPS, workers=workers,
                        runs_per_task=runs_per_task, submit_order=submit)
    assert res.workers == workers
    assert _hashed(res.rows) == _hashed(reference.rows)
    assert res.combined_hash == reference.combined_hash
    # the work really ran in Ray workers, not here
    assert os.getpid() not in {r["pid"] for r in res.rows}


def test_worker_killed_mid_sweep_costs_only_a_retry(ray_cluster, tmp_path):
    """A worker process is SIGKILLed while it runs a run; Ray re-runs its task elsewhere: every run
    is present exactly once and the combined hash is the single-process one."""
    plan = dict(grid={"controller.k_pos": [[2.5, 2.5, 1.5]]}, seeds=6, envs=2048, steps=600)
    ref = cluster.sweep(SCEN, address="local", **plan)
    marks = tmp_path / "started"
    marks.mkdir()

    def record(run_id, d=str(marks)):  # runs in the worker: which process started which run
        open(os.path.join(d, f"{run_id}-{os.getpid()}"), "w").close()

    killed: list = []

    def killer():
        # The first run to start is killed 0.1 s in, mid-run (a run takes ~0.5-1 s here).
        deadline = time.time() + 60
        while time.time() < deadline and not killed:
            names = sorted(os.listdir(marks))
            if names:
                run_id, pid = map(int, names[0].split("-"))
                time.sleep(0.1)
                os.kill(pid, signal.SIGKILL)
                killed.append((run_id, pid))
                return
            time.sleep(0.02)

    t = threading.Thread(target=killer)
    t.start()
    try:
        res = cluster.sweep(SCEN, workers=2, on_run_start=record, max_retries=3, **plan)
    finally:
        t.join()
    assert killed, "no worker was killed"
    run_id, pid = killed[0]
    assert [r["run_id"] for r in res.rows] == list(range(6))  # every run, exactly once
    assert all(r["status"] == "ok" for r in res.rows), [r["error"] for r in res.rows]
    assert res.rows[run_id]["pid"] != pid  # the killed run's row came from the retry
    starts = [n for n in os.listdir(marks) if n.startswith(f"{run_id}-")]
    assert len(starts) >= 2  # the run started twice: once in the killed worker, once in its retry
    assert _hashed(res.rows) == _hashed(ref.rows) and res.combined_hash == ref.combined_hash


def test_sweep_command_writes_table_plot_and_hash(ray_cluster, reference, tmp_path):
    import pyarrow.parquet as pq

    from kestrel.cli import main

    out = tmp_path / "sw"
    scen = tmp_path / "ps.yaml"
    scen.write_text("task: {name: position_setpoint_task, episode_len_env_steps: 200}\n")
    args = ["sweep", str(scen), "--grid", "controller.k_pos=[[2.5,2.5,1.5],[-1.0,2.0,1.0]]",
            "--grid", "env.enable_disturbance=false,true", "--seeds", "3", "--envs", str(ENVS), "--steps", str(STEPS),
            "--workers", "2", "--out", str(out), "--quiet"]
    assert main(args) == 0
    meta = json.loads((out / "sweep.json").read_text())
    assert meta["combined_hash"] == reference.combined_hash and meta["errors"] == 6
    t = pq.read_table(out / "runs.parquet").to_pylist()
    assert [r["run_id"] for r in t] == list(range(12))
    assert [r["state_hash"] for r in t] == [r["state_hash"] for r in reference.rows]
    assert (out / "summary.png").stat().st_size > 10_000
    assert main(args[:-3] + ["--format", "csv", "--out", str(out), "--quiet"]) == 0
    assert (out / "runs.csv").read_text().count("\n") == 13
    # bad arguments: status 2 and the argument named
    assert main(["sweep", "position_setpoint_task", "--grid", "nokey"]) == 2


def test_sweep_command_connects_to_a_cluster_by_address(ray_cluster, reference, tmp_path):
    """`kestrel sweep --address HEAD:PORT` from another process, as a user points it at a cluster."""
    import subprocess
    import sys

    out = tmp_path / "sw"
    p = subprocess.run([sys.executable, "-m", "kestrel", "sweep", "position_setpoint_task", "--task-len", "x"],
                       capture_output=True, text=True)
    assert p.returncode == 2 and "unrecognized arguments" in p.stderr
    cmd = [sys.executable, "-m", "kestrel", "sweep", str(_write_scen(tmp_path)),
           "--grid", "controller.k_pos=[[2.5,2.5,1.5],[-1.0,2.0,1.0]]", "--grid", "env.enable_disturbance=false,true",
           "--seeds", "3", "--envs", str(ENVS), "--steps", str(STEPS), "--address", ray_cluster.address,
           "--out", str(out), "--format", "csv", "--quiet"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=240)
    assert p.returncode == 0, p.stderr[-2000:]
    assert json.loads((out / "sweep.json").read_text())["combined_hash"] == reference.combined_hash
    assert "run 6 (seed 0" in p.stdout and "controller.k_pos[0]: expected a number in [0, 1e+06]" in p.stdout


def _write_scen(d):
    f = d / "ps.yaml"
    f.write_text("task: {name: position_setpoint_task, episode_len_env_steps: 200}\n")
    return f


# ---- rollouts ----------------------------------------------------------------------------------------

ROLL_OVER = {"task": {"episode_len_env_steps": 12}, "action_scale": [2, 2, 2, 1], "vehicle_frame_obs": True}


def _local_stream(n_envs, steps, seed=4):
    """The single-process batches and their digest, as RayVectorEnv.stream_hash computes it."""
    import hashlib

    env = kestrel.make_vec("Kestrel-PositionSetpoint-v0", num_envs=n_envs, seed=seed, threads=1, **ROLL_OVER)
    h = hashlib.sha256()
    obs, _ = env.reset(seed=seed)
    h.update(obs.tobytes())
    rng = np.random.default_rng(11)
    for _ in range(steps):
        a = rng.uniform(-1, 1, (n_envs, 4)).astype(np.float32)
        obs, rew, term, trunc, info = env.step(a)
        h.update(obs.tobytes()); h.update(rew.tobytes()); h.update(term.tobytes()); h.update(trunc.tobytes())
        if "final_obs" in info:
            ended = term | trunc
            h.update(np.where(ended[:, None], info["final_obs"], 0).tobytes())
    return h.hexdigest(), env.task.infos


@pytest.mark.parametrize("workers", [1, 2, 4])
def test_distributed_rollout_equals_one_process(ray_cluster, workers):
    ref_hash, ref_infos = _local_stream(10, 30)
    env = cluster.RayVectorEnv("Kestrel-PositionSetpoint-v0", num_envs=10, seed=4, workers=workers, threads=1, **ROLL_OVER)
    try:
        assert env.slices[0][0] == 0 and sum(c for _, c in env.slices) == 10 and len(env.slices) == workers
        env.reset(seed=4)
        rng = np.random.default_rng(11)
        for _ in range(30):
            env.step(rng.uniform(-1, 1, (10, 4)).astype(np.float32))
        assert env.stream_hash == ref_hash
        inf = env.task.infos
        assert inf["episodes"] == ref_infos["episodes"] > 0 and inf["successes"] == ref_infos["successes"]
        assert inf["episode_reward_sum"] == pytest.approx(ref_infos["episode_reward_sum"], rel=1e-12)
    finally:
        env.close()


def test_rsl_rl_learns_on_ray_actors_as_on_one_process(ray_cluster):
    """rsl_rl's PPO (kestrel.adapters.RslRlVecEnv, unchanged) on a RayVectorEnv of 2 actors: after
    two updates the policy's weights are bit-identical to the same training on one process."""
    import torch
    from rsl_rl.runners import OnPolicyRunner

    from kestrel.adapters import RslRlVecEnv
    from kestrel.train import _rsl_rl_cfg
    import argparse

    args = argparse.Namespace(rollout=8, hidden=[32, 32], obs_norm=False, init_std=0.5, epochs=2, minibatches=2,
                              gamma=0.99, lam=0.95, entropy=0.0, lr=1e-3)

    def train(env):
        torch.manual_seed(0)
        runner = OnPolicyRunner(RslRlVecEnv(env, reward_scale=0.02, squash=True), _rsl_rl_cfg(args), log_dir=None, device="cpu")
        runner.learn(num_learning_iterations=2)
        return torch.cat([p.detach().flatten() for p in runner.alg.actor.parameters()])

    local = train(kestrel.make_vec("Kestrel-PositionSetpoint-v0", num_envs=8, seed=2, threads=1, **ROLL_OVER))
    env = cluster.RayVectorEnv("Kestrel-PositionSetpoint-v0", num_envs=8, seed=2, workers=2, **ROLL_OVER)
    try:
        dist = train(env)
    finally:
        env.close()
    assert torch.equal(local, dist)


def test_navigation_curriculum_is_refused(ray_cluster):
    with pytest.raises(ValueError, match="obstacle curriculum level shared by every environment"):
        cluster.RayVectorEnv("Kestrel-Navigation-v0", num_envs=4, workers=2)
