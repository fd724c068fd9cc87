"""The shipped robot files (models/: Unitree Go2, ANYbotics ANYmal C, the SO-101 arm) through the
loader (kestrel.load_robot_model, sim/articulated_robot.hpp) against MuJoCo and Pinocchio on the
SAME files: the core's rnea / crba / aba of the loaded tree on 1000 random states per robot (random
base pose and velocity for the floating quadrupeds, joint angles within their ranges, joint
velocities, accelerations and torques within the effort limits) against

  * MuJoCo 3.x from PyPI reading the file itself (mujoco.MjModel.from_xml_path): mj_forward's qacc
    under qfrc_applied, mj_rne, mj_fullM, with contacts, joint limits and dry friction switched off
    (opt.disableflags) so that only the rigid-body dynamics (with armature and viscous damping) is
    compared. The Python package's MuJoCo is not the loader's (Debian's C library 2.2), so this
    also checks that both compile the file alike;
  * Pinocchio 4.x: the tree rebuilt from the loaded arrays (test_dynamics_oracle.pinocchio_model),
    and for the Go2 also Pinocchio's own URDF parser on models/go2/go2.urdf (an independent reading
    of the same numbers).

MuJoCo's free joint conventions are converted as in test_dynamics_mujoco.py: qpos [x y z qw qx qy
qz], linear velocity in the world frame; the loader puts the base's X_tree at the identity, so the
core's q is MuJoCo's pose with the quaternion reordered. The SO-101's base is welded to the world
(no free joint): its q, v and torques are MuJoCo's as they are."""

import pathlib

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")
pin = pytest.importorskip("pinocchio")

import kestrel
from test_dynamics_mujoco import quat_matrix_xyzw
from test_dynamics_oracle import FREE, pinocchio_model

MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"
ROBOTS = {"go2": MODELS / "go2" / "go2.xml", "anymal_c": MODELS / "anymal_c" / "anymal_c.xml",
          "so101": MODELS / "so101" / "so101.xml"}
STATES = 1000


def floating(robot):
    return robot.joint[0] == FREE


def random_state(rng, robot):
    """q (core coordinates), v, a, tau in float32: a random base pose and twist (a floating base),
    joint angles within their ranges, velocities, accelerations and torques within the effort
    limits."""
    n_q, n = robot.num_q, robot.num_dofs
    q = np.zeros(n_q)
    if floating(robot):
        q[:3] = rng.uniform([-1, -1, 0], [1, 1, 1])
        quat = rng.normal(size=4)
        q[3:7] = quat / np.linalg.norm(quat)
        v = np.concatenate([rng.uniform(-1, 1, 3), rng.uniform(-2, 2, 3), rng.uniform(-5, 5, n - 6)])
        a = np.concatenate([rng.uniform(-3, 3, 3), rng.uniform(-5, 5, 3), rng.uniform(-10, 10, n - 6)])
    else:
        v, a = rng.uniform(-5, 5, n), rng.uniform(-10, 10, n)
    tau = np.zeros(n)
    for i in range(robot.num_bodies):
        k, j = robot.dof_index[i], robot.q_index[i]
        if robot.joint[i] in (FREE,) or k < 0:
            continue
        lo, hi = (robot.q_min[i], robot.q_max[i]) if robot.has_limit[i] else (-np.pi, np.pi)
        q[j] = rng.uniform(lo, hi)
        tau[k] = rng.uniform(-1, 1) * (robot.effort_limit[i] or 50.0)
    return (x.astype(np.float32) for x in (q, v, a, tau))


def per_dof(robot, values):
    """A per-body array (armature, damping) as per-dof, zero on the free joint's six."""
    out = np.zeros(robot.num_dofs)
    for i in range(robot.num_bodies):
        if robot.dof_index[i] >= 0 and robot.joint[i] != FREE:
            out[robot.dof_index[i]] = values[i]
    return out


def rigid_body_only(m):
    """Contacts, joint limits, Coulomb friction (frictionloss) and actuators (the SO-101's position
    servos pull towards ctrl = 0) off: the rigid-body dynamics of the tree under gravity, applied
    forces, armature and damping is left."""
    d = mujoco.mjtDisableBit
    m.opt.disableflags |= (int(d.mjDSBL_CONTACT) | int(d.mjDSBL_LIMIT) | int(d.mjDSBL_FRICTIONLOSS) |
                           int(d.mjDSBL_ACTUATION))
    return m


def test_loaded_trees_match_their_files():
    go2 = kestrel.load_robot_model(str(ROBOTS["go2"]))
    anymal = kestrel.load_robot_model(str(ROBOTS["anymal_c"]))
    for robot, mass in ((go2, 15.017), (anymal, 52.13485)):
        assert (robot.num_bodies, robot.num_dofs, robot.num_q) == (17, 18, 19)
        assert abs(float(robot.mass.sum()) - mass) < 1e-4 and abs(robot.total_mass - mass) < 1e-4
        assert len(robot.foot_bodies) == 4 and all(g >= 0 for g in robot.foot_geoms)
        assert all(robot.geoms[g]["type"] == "sphere" for g in robot.foot_geoms)
        assert robot.home_q is not None and robot.home_q.shape == (19,)
    assert [go2.body_names[b] for b in go2.foot_bodies] == ["FL_foot", "FR_foot", "RL_foot", "RR_foot"]
    assert [anymal.body_names[b] for b in anymal.foot_bodies] == ["LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"]
    np.testing.assert_allclose(go2.home_q[7:10], [0.1, 0.8, -1.5], atol=1e-6)
    np.testing.assert_allclose(anymal.home_q[7:], [0, 0.4, -0.8, 0, 0.4, -0.8, 0, -0.4, 0.8, 0, -0.4, 0.8], atol=1e-6)
    # Same home pose as MuJoCo's keyframe (w x y z -> x y z w).
    m = mujoco.MjModel.from_xml_path(str(ROBOTS["go2"]))
    key = m.key("home").qpos
    np.testing.assert_allclose(go2.home_q, np.concatenate([key[:3], key[4:7], key[3:4], key[7:]]), atol=1e-6)


def test_so101_loaded_tree_matches_its_file():
    """The SO-101 arm (models/so101/so101.xml): base welded to the world, 6 revolute joints named as
    LeRobot names them, gripper_frame a fixed body on the gripper; ranges, STS3215 parameters and
    effort limits (the position servos' force range), masses, home and the gripper pads as MuJoCo 3
    reads the same file."""
    path = ROBOTS["so101"]
    robot = kestrel.load_robot_model(str(path))
    m = mujoco.MjModel.from_xml_path(str(path))
    names = ["shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex", "wrist_roll", "gripper"]
    assert (robot.num_bodies, robot.num_dofs, robot.num_q) == (7, 6, 6) == (m.nbody - 2, m.nv, m.nq)
    assert robot.body_names == ["shoulder", "upper_arm", "lower_arm", "wrist", "gripper", "gripper_frame", "moving_jaw"]
    assert robot.joint_names == names[:5] + [""] + names[5:]
    assert not floating(robot) and robot.parent[0] == -1 and robot.joint[5] == 2  # gripper_frame: fixed
    assert robot.parent[5] == robot.parent[6] == robot.body_names.index("gripper")
    for i, jn in enumerate(robot.joint_names):
        if not jn:
            continue
        j = m.joint(jn)
        assert robot.has_limit[i] and abs(robot.q_min[i] - j.range[0]) < 1e-6 and abs(robot.q_max[i] - j.range[1]) < 1e-6
        act = m.actuator(jn)
        assert act.trnid[0] == j.id and m.actuator_forcelimited[act.id]
        assert abs(robot.effort_limit[i] - act.forcerange[1]) < 1e-6 and abs(robot.effort_limit[i] - 2.94) < 1e-6
        assert abs(act.gainprm[0] - 998.22) < 1e-9  # Menagerie's STS3215 position gain
        dof = j.dofadr[0]
        assert robot.dof_index[i] == dof
        assert abs(robot.armature[i] - m.dof_armature[dof]) < 1e-8 and abs(robot.damping[i] - m.dof_damping[dof]) < 1e-7
        assert abs(robot.friction_loss[i] - m.dof_frictionloss[dof]) < 1e-8
    np.testing.assert_allclose(robot.mass, m.body_mass[2:], rtol=1e-6)  # MuJoCo: world, base, then the core's
    assert abs(robot.total_mass - 0.485106) < 1e-5
    np.testing.assert_allclose(robot.home_q, m.key("home").qpos, atol=1e-6)
    # Every colliding geom, on the same body with the same size and friction; the base's is the world's.
    geoms = {g["name"]: g for g in robot.geoms}
    assert len(geoms) == len(robot.geoms) == m.ngeom
    for g in range(m.ngeom):
        ours = geoms[m.geom(g).name]
        assert ours["body"] == m.geom_bodyid[g] - 2  # -1 for the base (MuJoCo's body 1)
        assert ours["type"] == "box"
        np.testing.assert_allclose(ours["size"], m.geom_size[g], atol=1e-7)
        assert abs(ours["friction"] - m.geom_friction[g][0]) < 1e-7
    assert geoms["base"]["body"] == -1
    assert robot.body_names[geoms["fixed_jaw_pad"]["body"]] == "gripper"
    assert robot.body_names[geoms["moving_jaw_pad"]["body"]] == "moving_jaw"
    for pad in ("fixed_jaw_pad", "moving_jaw_pad"):
        np.testing.assert_allclose(geoms[pad]["size"], [0.002, 0.0075, 0.01], atol=1e-7)
        assert geoms[pad]["friction"] == pytest.approx(1.0)


def test_so101_tool_frame_jacobian_agrees_with_mujoco():
    """gripper_frame's Jacobian (linear rows first, world axes) by the core's point_jacobian of the
    loaded tree against MuJoCo's mj_jacBody on the file itself, on 1000 random joint angles within
    the ranges: the kinematic chain from the base to the tool centre point, axis by axis."""
    path = ROBOTS["so101"]
    robot = kestrel.load_robot_model(str(path))
    core = robot.multibody()
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    frame, body = robot.body_names.index("gripper_frame"), m.body("gripper_frame").id
    rng = np.random.default_rng(101)
    jacp, jacr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    worst = 0.0
    for _ in range(STATES):
        q32, _, _, _ = random_state(rng, robot)
        d.qpos[:] = q32.astype(np.float64)
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        mujoco.mj_jacBody(m, d, jacp, jacr, body)
        J = core.point_jacobian(q32, frame, np.zeros(3, np.float32))
        worst = max(worst, np.abs(J - np.vstack([jacp, jacr])).max())
    print(f"so101: gripper_frame Jacobian, worst difference core (float32) vs MuJoCo (double), {STATES} states:",
          f"{worst:.2e}")
    # Measured: 1.8e-7 (float32 on lever arms of at most 0.45 m); a link placed 1 mm off or an axis
    # turned by 1 mrad is off by 1e-3 or 4e-4.
    assert worst < 5e-6, worst


def test_errors_name_the_file():
    with pytest.raises(ValueError, match="no_such.xml: cannot open file"):
        kestrel.load_robot_model(str(MODELS / "no_such.xml"))


@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_aba_rnea_crba_agree_with_mujoco_on_the_same_file(name):
    path = ROBOTS[name]
    robot = kestrel.load_robot_model(str(path))
    core = robot.multibody()
    m = rigid_body_only(mujoco.MjModel.from_xml_path(str(path)))
    d = mujoco.MjData(m)
    n = robot.num_dofs
    assert (m.nq, m.nv) == (robot.num_q, n)
    # MuJoCo's own per-dof armature and damping (in double) against the loader's.
    np.testing.assert_allclose(per_dof(robot, robot.armature), m.dof_armature, atol=1e-7)
    np.testing.assert_allclose(per_dof(robot, robot.damping), m.dof_damping, atol=1e-6)
    arm, damp = m.dof_armature.copy(), m.dof_damping.copy()
    free = floating(robot)
    if free:
        arm[:6] = damp[:6] = 0
    rng = np.random.default_rng(1200 + len(name))
    worst = {"aba": 0.0, "rnea": 0.0, "crba": 0.0}
    M_mj = np.zeros((n, n))
    for _ in range(STATES):
        q32, v32, a32, t32 = random_state(rng, robot)
        q, v, a = (x.astype(np.float64) for x in (q32, v32, a32))
        T = np.eye(n)
        qpos = q
        if free:
            R = quat_matrix_xyzw(q[3:7])
            T[:3, :3] = R
            qpos = np.concatenate([q[:3], q[6:7], q[3:6], q[7:]])  # x y z w -> w x y z
        d.qpos[:] = qpos
        d.qvel[:] = T @ v
        d.qfrc_applied[:] = 0
        mujoco.mj_forward(m, d)
        # Inverse dynamics: mj_rne (M a + bias, armature not in it) plus armature and damping.
        d.qacc[:] = a
        if free:
            d.qacc[:3] = R @ (a[:3] + np.cross(v[3:6], v[:3]))
        tau_mj = np.zeros(n)
        mujoco.mj_rne(m, d, 1, tau_mj)
        tau_ref = T.T @ tau_mj + arm * a + damp * v
        tau = core.rnea(q32, v32, a32)
        worst["rnea"] = max(worst["rnea"], np.abs(tau - tau_ref).max() / (1 + np.abs(tau_ref).max()))
        # Mass matrix.
        mujoco.mj_fullM(m, d, M_mj)
        M_ref = T.T @ M_mj @ T
        worst["crba"] = max(worst["crba"], np.abs(core.crba(q32) - M_ref).max() / (1 + np.abs(M_ref).max()))
        # Forward dynamics under the random torques (damping is MuJoCo's passive force).
        tau_in = t32.astype(np.float64)
        d.qfrc_applied[:] = np.linalg.solve(T.T, tau_in)
        mujoco.mj_forward(m, d)
        qdd_ref = d.qacc.copy()
        if free:
            qdd_ref[:3] = R.T @ qdd_ref[:3] - np.cross(v[3:6], v[:3])
        qdd = core.aba(q32, v32, t32)
        worst["aba"] = max(worst["aba"], np.abs(qdd - qdd_ref).max() / (1 + np.abs(qdd_ref).max()))
    print(f"{name}: worst relative differences, core (float32) vs MuJoCo {mujoco.__version__} (double), {STATES} states:", worst)
    # float32 against double, relative to each quantity's scale, as test_dynamics_mujoco.py.
    # Measured (MuJoCo 3.17): go2 RNEA 3.3e-7, CRBA 2.9e-7, ABA 2.4e-7; anymal_c RNEA 5.0e-7, CRBA
    # 3.5e-7, ABA 7.5e-7 (these well-conditioned legs lose less than the random trees of
    # test_dynamics_mujoco.py); so101 RNEA 1.1e-7, CRBA 6.7e-9, ABA 2.0e-7 (its mass matrix, ~0.03
    # to 0.1 kg m^2, is below the scale's 1: these are absolute errors; its 0.028 kg m^2 armature
    # left out on one side would show as 2.8e-2). The bounds are that file's. A wrong conversion (a frame, a quaternion order, armature or damping on one side) is off by
    # 1e-2 or more.
    assert worst["rnea"] < 2e-5 and worst["crba"] < 2e-5 and worst["aba"] < 1e-4, worst


@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_aba_rnea_crba_agree_with_pinocchio(name):
    robot = kestrel.load_robot_model(str(ROBOTS[name]))
    core = robot.multibody()
    arrays = [robot.parent, robot.joint, robot.axis, robot.E_tree, robot.r_tree, robot.mass, robot.com, robot.inertia]
    d64 = [x.astype(np.float64) if x.dtype.kind == "f" else x for x in arrays]
    model, _ = pinocchio_model(*d64, robot.gravity.astype(np.float64), armature=robot.armature.astype(np.float64))
    data = model.createData()
    assert (model.nq, model.nv) == (robot.num_q, robot.num_dofs)
    damp = per_dof(robot, robot.damping.astype(np.float64))
    rng = np.random.default_rng(4100 + len(name))
    worst = {"aba": 0.0, "rnea": 0.0, "crba": 0.0}
    for _ in range(STATES):
        q32, v32, a32, t32 = random_state(rng, robot)
        q, v, a, t = (x.astype(np.float64) for x in (q32, v32, a32, t32))
        tau_ref = pin.rnea(model, data, q, v, a) + damp * v  # Pinocchio's RNEA has no joint damping
        worst["rnea"] = max(worst["rnea"], np.abs(core.rnea(q32, v32, a32) - tau_ref).max() / (1 + np.abs(tau_ref).max()))
        qdd_ref = pin.aba(model, data, q, v, t - damp * v)
        worst["aba"] = max(worst["aba"], np.abs(core.aba(q32, v32, t32) - qdd_ref).max() / (1 + np.abs(qdd_ref).max()))
        M_ref = pin.crba(model, data, q)
        M_ref = np.triu(M_ref) + np.triu(M_ref, 1).T
        worst["crba"] = max(worst["crba"], np.abs(core.crba(q32) - M_ref).max() / (1 + np.abs(M_ref).max()))
    print(f"{name}: worst relative differences, core (float32) vs Pinocchio {pin.__version__} (double), {STATES} states:", worst)
    # Measured (Pinocchio 4.1): go2 RNEA 2.7e-7, CRBA 3.2e-8, ABA 2.1e-7; anymal_c RNEA 3.3e-7,
    # CRBA 1.2e-7, ABA 5.6e-7; so101 RNEA 1.1e-7, CRBA 6.0e-9, ABA 2.2e-7.
    assert worst["rnea"] < 2e-5 and worst["crba"] < 2e-5 and worst["aba"] < 1e-4, worst


def test_go2_urdf_agrees_with_pinocchios_own_urdf_parser():
    """models/go2/go2.urdf read twice, by the loader (MuJoCo's URDF compiler) and by Pinocchio's
    URDF parser (which merges the fixed foot links into the calves): the same dynamics, and the
    same joint ranges and effort limits, dof by dof (matched by joint name)."""
    path = str(MODELS / "go2" / "go2.urdf")
    robot = kestrel.load_robot_model(path)
    core = robot.multibody()
    model = pin.buildModelFromUrdf(path)
    model.gravity.linear = robot.gravity.astype(np.float64)
    data = model.createData()
    assert (model.nq, model.nv) == (robot.num_q, robot.num_dofs)
    assert model.joints[1].shortname() == "JointModelFreeFlyer"
    # Pinocchio's dof of each of the core's joints (by name); the free joint first in both.
    perm = np.zeros(robot.num_dofs, int)
    perm[:6] = np.arange(6)
    for i, jn in enumerate(robot.joint_names):
        if robot.joint[i] in (0, 1):
            jid = model.getJointId(jn)
            perm[robot.dof_index[i]] = model.joints[jid].idx_v
            assert abs(model.lowerPositionLimit[model.joints[jid].idx_q] - robot.q_min[i]) < 1e-6
            assert abs(model.upperPositionLimit[model.joints[jid].idx_q] - robot.q_max[i]) < 1e-6
            assert abs(model.effortLimit[model.joints[jid].idx_v] - robot.effort_limit[i]) < 1e-5
    qperm = np.concatenate([np.arange(7), perm[6:] + 1])  # one more q than v (the quaternion)
    damp = per_dof(robot, robot.damping.astype(np.float64))
    rng = np.random.default_rng(77)
    worst = {"aba": 0.0, "rnea": 0.0, "crba": 0.0}
    for _ in range(STATES):
        q32, v32, a32, t32 = random_state(rng, robot)
        q, v, a, t = (x.astype(np.float64) for x in (q32, v32, a32, t32))
        qp, vp, ap, tp = np.zeros(model.nq), np.zeros(model.nv), np.zeros(model.nv), np.zeros(model.nv)
        qp[qperm], vp[perm], ap[perm], tp[perm] = q, v, a, t - damp * v
        tau_ref = pin.rnea(model, data, qp, vp, ap)[perm] + damp * v
        worst["rnea"] = max(worst["rnea"], np.abs(core.rnea(q32, v32, a32) - tau_ref).max() / (1 + np.abs(tau_ref).max()))
        qdd_ref = pin.aba(model, data, qp, vp, tp)[perm]
        worst["aba"] = max(worst["aba"], np.abs(core.aba(q32, v32, t32) - qdd_ref).max() / (1 + np.abs(qdd_ref).max()))
        M_ref = pin.crba(model, data, qp)
        M_ref = (np.triu(M_ref) + np.triu(M_ref, 1).T)[np.ix_(perm, perm)]
        worst["crba"] = max(worst["crba"], np.abs(core.crba(q32) - M_ref).max() / (1 + np.abs(M_ref).max()))
    print(f"go2.urdf: worst relative differences, core (float32) vs Pinocchio's URDF parser (double), {STATES} states:", worst)
    # Measured: RNEA 3.2e-7, CRBA 1.2e-8, ABA 3.6e-7.
    assert worst["rnea"] < 2e-5 and worst["crba"] < 2e-5 and worst["aba"] < 1e-4, worst
