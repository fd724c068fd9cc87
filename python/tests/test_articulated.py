"""Articulated robots through the Simulator interface from Python (sim/src/backends/articulated.cpp):
Go2 and ANYmal C from the registry and from a scenario file stand and step under joint targets;
legged_gym's views (dof_pos, dof_vel, torques, feet_pos_w, link_contact_forces_w) are zero-copy
numpy arrays of the right shapes and values; reset_dofs writes exactly and refuses bad input with
the argument named; the same seed gives the same state hash for 1 and 2 threads."""

import pathlib

import numpy as np
import pytest

import kestrel

ROOT = pathlib.Path(__file__).resolve().parents[2]
DT = kestrel._core.real_dtype


def legged(robot="go2", envs=4, threads=1, seed=5, **over):
    scenario = {"robot": robot, "sim": "fast_sim", "task": "joint_targets",
                "env": {"name": "empty", "num_physics_steps_per_env_step_mean": 4}}
    scenario.update(over)
    return kestrel.make_simulator(scenario, num_envs=envs, threads=threads, seed=seed)


@pytest.mark.parametrize("robot,mass", [("go2", 15.017), ("anymal_c", 52.135)])
def test_stands_and_the_views_add_up(robot, mass):
    sim = legged(robot)
    n = sim.num_robots
    assert (sim.num_dofs, sim.num_feet, sim.num_links) == (12, 4, 17)
    zero = np.zeros((n, 12), dtype=DT)
    dof_pos, forces = sim.dof_pos, sim.link_contact_forces_w
    for _ in range(150):  # 3 s
        sim.step(zero)
    # Zero-copy: the same buffers, rewritten in place.
    assert sim.dof_pos.__array_interface__["data"][0] == dof_pos.__array_interface__["data"][0]
    assert sim.link_contact_forces_w.__array_interface__["data"][0] == forces.__array_interface__["data"][0]
    assert sim.dof_pos.shape == (n, 12) and sim.torques.shape == (n, 12)
    assert sim.feet_pos_w.shape == (n, 4, 3) and forces.shape == (n, 17, 3)
    # Standing: the ground carries the weight, through the feet, which rest on the ground.
    np.testing.assert_allclose(forces[:, :, 2].sum(axis=1), mass * 9.81, rtol=0.02)
    model = kestrel.load_robot_model(str(ROOT / "models" / robot / f"{robot}.xml"))
    feet = list(model.foot_bodies)
    assert forces[:, feet, 2].sum(axis=1) == pytest.approx(forces[:, :, 2].sum(axis=1), rel=0.01)
    assert np.all(np.abs(sim.feet_pos_w[:, :, 2]) < 0.05)
    # The joint PD at rest: torque = kp (home - q) - kd qd, within the effort limits.
    home = np.array([model.home_q[i] for i in range(7, 19)], dtype=np.float64)
    kp, kd = {"go2": (20.0, 0.5), "anymal_c": (80.0, 2.0)}[robot]
    np.testing.assert_allclose(sim.torques, kp * (home - sim.dof_pos) - kd * sim.dof_vel, atol=0.05)
    assert np.all(sim.base_pos_w[:, 2] > 0.2)


def test_scenario_file_runs_under_random_targets():
    cfg = kestrel.load_scenario_file(str(ROOT / "sim" / "scenarios" / "go2_rough.yaml"))
    sim = kestrel.Simulator(cfg, "")
    rng = np.random.default_rng(0)
    for _ in range(60):
        sim.step(rng.uniform(-1, 1, size=(sim.num_robots, sim.num_dofs)).astype(DT))
    assert np.all(np.isfinite(sim.dof_pos)) and np.all(np.isfinite(sim.base_pos_w))
    assert np.abs(sim.torques).max() > 1.0  # the targets move the joints


def test_reset_dofs_exact_and_errors_name_the_argument():
    sim = legged("go2", envs=3)
    pos = np.linspace(-0.2, 0.2, 24, dtype=DT).reshape(2, 12)
    vel = np.full((2, 12), 0.5, dtype=DT)
    sim.reset_dofs([0, 2], pos, vel)
    np.testing.assert_array_equal(sim.dof_pos[[0, 2]], pos)
    np.testing.assert_array_equal(sim.dof_vel[[0, 2]], vel)
    with pytest.raises(ValueError, match="dof_pos: expected shape"):
        sim.reset_dofs([0], pos, vel)
    with pytest.raises(TypeError, match="dof_vel: expected dtype"):
        sim.reset_dofs([0, 2], pos, vel.astype(np.float64 if np.dtype(DT) == np.float32 else np.float32))
    with pytest.raises(ValueError, match="env id 9"):
        sim.reset_dofs([0, 9], pos, vel)
    bad = pos.copy()
    bad[1, 3] = np.nan
    with pytest.raises(ValueError, match=r"dof_pos: expected finite values, got nan at \[1, 3\]"):
        sim.reset_dofs([0, 2], bad, vel)
    np.testing.assert_array_equal(sim.dof_pos[[0, 2]], pos)  # nothing changed
    quad = kestrel.make_simulator({"env": "empty"}, num_envs=2)
    with pytest.raises(ValueError, match="no joints"):
        quad.reset_dofs([0], np.zeros((1, 0), dtype=DT), np.zeros((1, 0), dtype=DT))
    with pytest.raises(ValueError, match="simulator: rigid"):
        legged("go2", simulator="planar")


def test_same_seed_same_hash_for_one_and_two_threads():
    def run(threads):
        sim = legged("anymal_c", envs=5, threads=threads, seed=9)
        rng = np.random.default_rng(1)
        for _ in range(40):
            sim.step(rng.uniform(-2, 2, size=(5, 12)).astype(DT))
        return sim.state_hash
    assert run(1) == run(2)


def test_gain_scale_views():
    sim = kestrel.make_simulator(
        {"robot": {"name": "go2", "joint_kp_scale": [0.8, 1.2], "joint_kd_scale": [0.5, 1.5]}, "sim": "fast_sim",
         "task": "joint_targets", "env": {"name": "empty"}}, num_envs=6, seed=3)
    kp, kd = sim.dr_kp_scale, sim.dr_kd_scale
    assert kp.shape == (6,) and kd.shape == (6,)
    assert np.all((kp >= 0.8) & (kp <= 1.2)) and np.all((kd >= 0.5) & (kd <= 1.5))
    assert len(set(kp.tolist())) == 6  # drawn per robot


def test_measured_heights_view():
    sim = kestrel.make_simulator(
        {"robot": "go2", "sim": "fast_sim", "task": "joint_targets",
         "env": {"name": "empty", "terrain": {"type": "heightfield", "procedural": "slope", "slope": 0.2,
                                              "measure_heights": True}}}, num_envs=2)
    h = sim.measured_heights
    assert h.shape == (2, 17 * 11)
    np.testing.assert_allclose(h[:, 16 * 11 + 5] - h[:, 5], 0.32, atol=0.01)
    assert legged("go2", envs=2).measured_heights.shape == (2, 0)


def test_domain_randomisation_views_and_push_links():
    # legged_gym's / LeggedGym-Ex's randomisation from the scenario's simulator section, as
    # zero-copy views drawn per robot at each reset.
    sim = legged("go2", envs=6, seed=4, simulator={
        "name": "rigid", "friction": [0.5, 1.25], "restitution": [0.0, 0.5], "added_mass_kg": [-1.0, 3.0], "com_bias_max_m": 0.05,
        "joint_armature_kg_m2": [0.005, 0.02], "max_push_force_N": 50.0})
    mu, e, dm, com, arm = (sim.dr_friction_values, sim.dr_restitution_values, sim.dr_added_base_mass,
                           sim.dr_base_com_bias, sim.dr_joint_armature)
    assert mu.shape == (6,) and e.shape == (6,) and dm.shape == (6,) and com.shape == (6, 3) and arm.shape == (6, 12)
    assert np.all((mu >= 0.5) & (mu <= 1.25)) and np.all((e >= 0) & (e <= 0.5)) and np.all((dm >= -1) & (dm <= 3))
    assert np.all(np.abs(com) <= 0.05) and np.all((arm >= 0.005) & (arm <= 0.02))
    assert len(set(mu.tolist())) == 6
    before = mu.copy()
    sim.reset_idx([2])
    assert sim.dr_friction_values.__array_interface__["data"][0] == mu.__array_interface__["data"][0]
    assert mu[2] != before[2] and mu[3] == before[3]  # redrawn for the reset env only, in place
    # push_links moves the robots against the same robots unpushed.
    ref = legged("go2", envs=6, seed=4, simulator={
        "name": "rigid", "friction": [0.5, 1.25], "restitution": [0.0, 0.5], "added_mass_kg": [-1.0, 3.0], "com_bias_max_m": 0.05,
        "joint_armature_kg_m2": [0.005, 0.02], "max_push_force_N": 50.0})
    ref.reset_idx([2])
    zero = np.zeros((6, 12), dtype=DT)
    sim.push_links()
    sim.step(zero)
    ref.step(zero)
    assert np.abs(sim.base_lin_vel_b - ref.base_lin_vel_b).max() > 0.01
    with pytest.raises(ValueError, match="simulator.restitution"):
        legged("go2", envs=1, simulator={"name": "rigid", "restitution": [0.5, 0.2]})
    quad = kestrel.make_simulator({"env": "empty"}, num_envs=2)
    with pytest.raises(ValueError, match="articulated only"):
        quad.push_links()
    assert quad.dr_joint_armature.shape == (2, 0) and np.all(quad.dr_friction_values == -1)


def test_terrain_curriculum_from_python():
    sim = legged("go2", envs=8, seed=2, env={"name": "empty", "num_physics_steps_per_env_step_mean": 4, "terrain": {
        "type": "heightfield", "procedural": "curriculum", "num_rows": 4, "num_cols": 4, "border_size_m": 2,
        "max_init_terrain_level": 0}})
    assert sim.num_terrain_levels == 4
    np.testing.assert_array_equal(sim.terrain_levels, np.zeros(8))
    np.testing.assert_array_equal(sim.terrain_types, np.arange(8) // 2)
    origins = sim.env_origins_w
    assert origins.shape == (8, 3)
    assert np.all(np.abs(sim.base_pos_w[:, :2] - origins[:, :2]) <= 1.0)
    x0 = origins[0, 0]
    sim.update_terrain_curriculum([0, 1], [True, False], [False, True])
    assert sim.terrain_levels[0] == 1 and sim.terrain_levels[1] == 0
    assert origins[0, 0] == pytest.approx(x0 + 8.0)  # one tile along x, in place
    with pytest.raises(ValueError, match="move_up and move_down"):
        sim.update_terrain_curriculum([0, 1], [True], [False, False])
    with pytest.raises(ValueError, match="tiled terrain"):
        legged("go2", envs=2).update_terrain_curriculum([0], [True], [False])
