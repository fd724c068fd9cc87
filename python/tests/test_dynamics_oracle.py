"""The core's articulated-body dynamics (dynamics/multibody.hpp through kestrel._core.Multibody)
against Pinocchio (`pin` from PyPI) on the same random trees of revolute, prismatic and fixed
joints, on a fixed base and on a floating one (Pinocchio's free flyer): inverse dynamics (RNEA),
forward dynamics (ABA) and the joint-space mass matrix (CRBA) on 1000 random states each. The core runs in float32 here (the package's build), Pinocchio in double: the
tolerance is float32's, relative to each quantity's scale."""

import numpy as np
import pinocchio as pin

import kestrel

REVOLUTE, PRISMATIC, FIXED, FREE = 0, 1, 2, 3


def random_tree(rng: np.random.Generator, n: int):
    # Depth-first numbering (every subtree's bodies consecutive), which Pinocchio's CRBA assumes
    # (its mass-matrix sparsity uses each joint's subtree as a contiguous block): each body hangs
    # from a body on the path from the root to the previous one. The core takes any order with
    # parents first (its own tests use random ones).
    parent, path = [-1], [0]
    for i in range(1, n):
        k = int(rng.integers(0, len(path)))
        parent.append(path[k])
        path = path[: k + 1] + [i]
    parent = np.array(parent, np.int32)
    joint = rng.choice([REVOLUTE, REVOLUTE, PRISMATIC, FIXED], size=n).astype(np.int32)
    joint[0] = REVOLUTE
    unit = lambda: (lambda v: v / np.linalg.norm(v))(rng.normal(size=3))
    axis = np.array([unit() for _ in range(n)])
    E = np.array([pin.exp3(unit() * rng.uniform(-3, 3)) for _ in range(n)])  # parent -> joint coordinates
    r = rng.uniform(-0.3, 0.3, (n, 3))
    mass = rng.uniform(0.2, 3.0, n)
    com = rng.uniform(-0.1, 0.1, (n, 3))
    inertia = []
    for _ in range(n):
        R = pin.exp3(unit() * rng.uniform(-3, 3))
        inertia.append(R @ np.diag(rng.uniform(0.01, 0.1, 3)) @ R.T)
    inertia = np.array(inertia)
    inertia = 0.5 * (inertia + inertia.transpose(0, 2, 1))
    return parent, joint, axis, E, r, mass, com, inertia


def pinocchio_model(parent, joint, axis, E, r, mass, com, inertia, gravity, armature=None):
    """The same tree in Pinocchio: a movable joint per revolute / prismatic body; a fixed body's
    inertia appended to its parent's joint at its placement (Pinocchio merges fixed links so).
    Returns the model and, per body, (joint id, the body frame's placement in that joint's frame)."""
    model = pin.Model()
    model.gravity.linear = gravity
    owner = []  # per body: (pinocchio joint id, the body frame's placement in that joint's frame)
    for i in range(len(parent)):
        p_joint, p_place = (0, pin.SE3.Identity()) if parent[i] < 0 else owner[parent[i]]
        place = p_place * pin.SE3(E[i].T, r[i])  # the joint frame in the parent's joint frame
        body_inertia = pin.Inertia(mass[i], com[i], inertia[i])
        if joint[i] == FIXED:
            model.appendBodyToJoint(p_joint, body_inertia, place)
            owner.append((p_joint, place))
            continue
        if joint[i] == FREE:
            jm = pin.JointModelFreeFlyer()
        elif joint[i] == REVOLUTE:
            jm = pin.JointModelRevoluteUnaligned(axis[i])
        else:
            jm = pin.JointModelPrismaticUnaligned(axis[i])
        jid = model.addJoint(p_joint, jm, place, f"j{i}")
        model.appendBodyToJoint(jid, body_inertia, pin.SE3.Identity())
        owner.append((jid, pin.SE3.Identity()))
    if armature is not None:  # per dof, in body order (the movable joints')
        model.armature = np.concatenate([np.zeros(6) if joint[i] == FREE else [armature[i]]
                                         for i in range(len(parent)) if joint[i] != FIXED])
    return model, owner


def random_q(rng, n_q, floating):
    q = rng.uniform(-2, 2, n_q)
    if floating:  # [x y z qx qy qz qw]: a unit quaternion
        quat = rng.normal(size=4)
        q[3:7] = quat / np.linalg.norm(quat)
    return q


import pytest


@pytest.mark.parametrize("floating", [False, True])
def test_rnea_aba_crba_agree_with_pinocchio(floating):
    rng = np.random.default_rng(12 + floating)
    gravity = np.array([0.0, 0.0, -9.81])
    states = 0
    worst = {"rnea": 0.0, "aba": 0.0, "crba": 0.0}
    for tree in range(10):
        arrays = random_tree(rng, (2 if floating else 3) + tree % 8)
        if floating:
            arrays[1][0] = FREE
        f32 = [a.astype(np.float32) if a.dtype.kind == "f" else a for a in arrays]
        # Half the trees with rotor inertia (armature), which both add to the mass matrix's diagonal.
        armature = rng.uniform(0, 0.05, len(arrays[0])).astype(np.float32) if tree % 2 else np.zeros(len(arrays[0]), np.float32)
        if floating:
            armature[0] = 0  # none on the free joint
        core = kestrel.Multibody(*f32, gravity=gravity.astype(np.float32), armature=armature)
        model, _ = pinocchio_model(*arrays, gravity, armature=armature.astype(np.float64))
        data = model.createData()
        n = core.num_dofs
        assert model.nq == core.num_q and model.nv == n and core.num_q == n + (1 if floating else 0)
        for _ in range(100):
            q, v, a = random_q(rng, core.num_q, floating), rng.uniform(-2, 2, n), rng.uniform(-3, 3, n)
            q32, v32, a32 = (x.astype(np.float32) for x in (q, v, a))
            # Each side's inputs are the same float32 numbers.
            q, v, a = (x.astype(np.float64) for x in (q32, v32, a32))
            tau_ref = pin.rnea(model, data, q, v, a)
            tau = core.rnea(q32, v32, a32)
            scale = 1 + np.abs(tau_ref).max()
            worst["rnea"] = max(worst["rnea"], np.abs(tau - tau_ref).max() / scale)
            qdd_ref = pin.aba(model, data, q, v, tau_ref)
            qdd = core.aba(q32, v32, tau_ref.astype(np.float32))
            worst["aba"] = max(worst["aba"], np.abs(qdd - qdd_ref).max() / (1 + np.abs(qdd_ref).max()))
            M_ref = pin.crba(model, data, q)
            M_ref = np.triu(M_ref) + np.triu(M_ref, 1).T
            M = core.crba(q32)
            worst["crba"] = max(worst["crba"], np.abs(M - M_ref).max() / (1 + np.abs(M_ref).max()))
            states += 1
    assert states == 1000
    print("worst relative differences, core (float32) vs Pinocchio (double), floating base" if floating else
          "worst relative differences, core (float32) vs Pinocchio (double), fixed base", worst)
    # float32 against double: measured 1.5e-6 (RNEA), 7.1e-6 (ABA), 4.2e-7 (CRBA) relative to
    # each quantity's scale; a wrong term (a sign, a transform) is off by far more than this.
    assert worst["rnea"] < 2e-5 and worst["crba"] < 2e-5 and worst["aba"] < 1e-4, worst


def test_refuses_bad_trees_with_the_argument_named():
    rng = np.random.default_rng(3)
    parent, joint, axis, E, r, mass, com, inertia = (a.astype(np.float32) if a.dtype.kind == "f" else a
                                                     for a in random_tree(rng, 4))
    g = np.array([0, 0, -9.81], np.float32)
    with pytest.raises(ValueError, match="axis: expected shape"):
        kestrel._core.Multibody(parent, joint, axis[:, :2].copy(), E, r, mass, com, inertia, g)
    bad = parent.copy()
    bad[2] = 3  # a parent after its child
    with pytest.raises(ValueError, match="invalid tree"):
        kestrel._core.Multibody(bad, joint, axis, E, r, mass, com, inertia, g)
    with pytest.raises(ValueError, match="invalid tree"):
        kestrel._core.Multibody(parent, joint, axis, E, r, mass, com, inertia, g, damping=np.full(4, -1, np.float32))
    core = kestrel.Multibody(parent, joint, axis, E, r, mass, com, inertia, g)
    n = core.num_dofs
    with pytest.raises(ValueError, match="non-finite"):
        core.aba(np.zeros(n, np.float32), np.zeros(n, np.float32), np.full(n, np.nan, np.float32))
    with pytest.raises(ValueError, match="body: expected an index"):
        core.point_jacobian(np.zeros(n, np.float32), 9, np.zeros(3, np.float32))


@pytest.mark.parametrize("floating", [False, True])
def test_point_jacobians_agree_with_pinocchio(floating):
    """The Jacobian of a random point on every body (world-aligned, linear rows first) against
    Pinocchio's frame Jacobian (LOCAL_WORLD_ALIGNED) at a frame placed on that point."""
    rng = np.random.default_rng(21 + floating)
    g = np.array([0.0, 0.0, -9.81])
    worst = 0.0
    checked = 0
    for tree in range(8):
        arrays = random_tree(rng, 3 + tree % 6)
        if floating:
            arrays[1][0] = FREE
        f32 = [a.astype(np.float32) if a.dtype.kind == "f" else a for a in arrays]
        core = kestrel.Multibody(*f32, gravity=g.astype(np.float32))
        model, owner = pinocchio_model(*arrays, g)
        points = rng.uniform(-0.2, 0.2, (len(owner), 3)).astype(np.float32)
        frames = [model.addFrame(pin.Frame(f"p{b}", jid, place * pin.SE3(np.eye(3), points[b].astype(np.float64)), pin.FrameType.OP_FRAME))
                  for b, (jid, place) in enumerate(owner)]
        data = model.createData()
        for _ in range(20):
            q32 = random_q(rng, core.num_q, floating).astype(np.float32)
            q = q32.astype(np.float64)
            for b, fid in enumerate(frames):
                J_ref = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
                J = core.point_jacobian(q32, b, points[b])
                worst = max(worst, np.abs(J - J_ref).max() / (1 + np.abs(J_ref).max()))
                checked += 1
    assert checked > 500
    assert worst < 2e-5, worst
