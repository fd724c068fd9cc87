"""The core's articulated-body dynamics against MuJoCo (`mujoco` from PyPI), the second oracle
beside Pinocchio (test_dynamics_oracle.py): the same random trees written as MJCF, on a fixed base
and on a floating one (MuJoCo's free joint), with armature and viscous damping, on 1000 random
states each: forward dynamics (mj_forward's qacc under applied joint forces, damping included),
inverse dynamics (mj_rne plus the damping force, which MuJoCo keeps apart as a passive force) and
the joint-space mass matrix (mj_fullM).

MuJoCo's free joint differs from the core's (Pinocchio's) in three conventions, converted here, not
in the core: its position is the base's pose in the world (the core's, relative to the joint's
placement), [x y z qw qx qy qz] (the core's quaternion is xyzw), and its linear
velocity is the body origin's in the *world* frame (the core's, in the body frame), its angular
velocity in the body frame as the core's. With R the base orientation and T = diag(R, I) on the
free joint's six coordinates (identity on the others): v_mj = T v, a_mj = T a + [R (w x v_b); 0],
tau = T^T tau_mj and M = T^T M_mj T."""

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

import kestrel
from test_dynamics_oracle import FIXED, FREE, PRISMATIC, REVOLUTE, random_q, random_tree


def physical_inertias(rng, n):
    """Rotational inertias about the centre of mass that MuJoCo accepts (principal moments of a
    solid box, so A + B >= C): random_tree's are valid for Pinocchio but not always for MuJoCo."""
    out = []
    for _ in range(n):
        m = 1.0  # scaled by the body's mass below
        a, b, c = rng.uniform(0.05, 0.4, 3)
        d = np.array([b * b + c * c, a * a + c * c, a * a + b * b]) * m / 12
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        ang = rng.uniform(-3, 3)
        K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        R = np.eye(3) + np.sin(ang) * K + (1 - np.cos(ang)) * K @ K
        out.append(R @ np.diag(d) @ R.T)
    return np.array(out)


def mjcf(parent, joint, axis, E, r, mass, com, inertia, gravity, armature, damping):
    """The tree as MJCF: body i at (r_i, E_i^T) in its parent's frame, its joint at the body origin
    along axis_i, its inertia about com_i in the body frame; fixed bodies have no joint (welded)."""
    children = {i: [] for i in range(-1, len(parent))}
    for i, p in enumerate(parent):
        children[int(p)].append(i)

    def quat_wxyz(Rm):
        q = np.zeros(4)
        mujoco.mju_mat2Quat(q, np.ascontiguousarray(Rm).ravel())
        return q

    f = lambda v: " ".join(repr(float(x)) for x in np.ravel(v))

    def body(i):
        I = inertia[i]
        full = [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]
        s = f'<body name="b{i}" pos="{f(r[i])}" quat="{f(quat_wxyz(E[i].T))}">'
        s += f'<inertial pos="{f(com[i])}" mass="{float(mass[i])!r}" fullinertia="{f(full)}"/>'
        if joint[i] == FREE:
            s += f'<freejoint name="j{i}"/>'
        elif joint[i] in (REVOLUTE, PRISMATIC):
            kind = "hinge" if joint[i] == REVOLUTE else "slide"
            s += (f'<joint name="j{i}" type="{kind}" axis="{f(axis[i])}" armature="{float(armature[i])!r}" '
                  f'damping="{float(damping[i])!r}"/>')
        s += "".join(body(c) for c in children[i]) + "</body>"
        return s

    return ('<mujoco><compiler angle="radian" inertiafromgeom="false"/>'
            f'<option gravity="{f(gravity)}"><flag contact="disable"/></option>'
            f'<worldbody>{"".join(body(c) for c in children[-1])}</worldbody></mujoco>')


def quat_matrix_xyzw(q):
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


@pytest.mark.parametrize("floating", [False, True])
def test_aba_rnea_crba_agree_with_mujoco(floating):
    rng = np.random.default_rng(40 + floating)
    gravity = np.array([0.0, 0.0, -9.81])
    states = 0
    worst = {"aba": 0.0, "rnea": 0.0, "crba": 0.0}
    for tree in range(10):
        parent, joint, axis, E, r, mass, com, _ = random_tree(rng, (2 if floating else 3) + tree % 8)
        n_b = len(parent)
        inertia = physical_inertias(rng, n_b) * mass[:, None, None]
        if floating:
            joint[0] = FREE
        armature = rng.uniform(0, 0.05, n_b) * (tree % 2)
        damping = rng.uniform(0, 0.5, n_b)
        armature[joint == FREE] = 0
        damping[joint == FREE] = 0
        arrays = [parent, joint, axis, E, r, mass, com, inertia]
        f32 = [a.astype(np.float32) if a.dtype.kind == "f" else a for a in arrays]
        core = kestrel.Multibody(*f32, gravity=gravity.astype(np.float32), armature=armature.astype(np.float32),
                                 damping=damping.astype(np.float32))
        # MuJoCo gets the float32 numbers the core holds, in double.
        d64 = [a.astype(np.float64) if a.dtype.kind == "f" else a for a in f32]
        m = mujoco.MjModel.from_xml_string(mjcf(*d64, gravity, armature.astype(np.float32).astype(np.float64),
                                                damping.astype(np.float32).astype(np.float64)))
        d = mujoco.MjData(m)
        n = core.num_dofs
        assert m.nv == n and m.nq == core.num_q
        arm_dof = np.concatenate([np.zeros(6) if joint[i] == FREE else [armature[i]]
                                  for i in range(n_b) if joint[i] != FIXED]).astype(np.float32).astype(np.float64)
        damp_dof = np.concatenate([np.zeros(6) if joint[i] == FREE else [damping[i]]
                                   for i in range(n_b) if joint[i] != FIXED]).astype(np.float32).astype(np.float64)
        M_mj = np.zeros((n, n))
        E0T, r0 = d64[3][0].T, d64[4][0]
        for _ in range(100):
            q32 = random_q(rng, core.num_q, floating).astype(np.float32)
            v32 = rng.uniform(-2, 2, n).astype(np.float32)
            a32 = rng.uniform(-3, 3, n).astype(np.float32)
            q, v, a = (x.astype(np.float64) for x in (q32, v32, a32))
            T = np.eye(n)
            qpos = q.copy()
            a_mj = a.copy()
            if floating:
                # The core's free joint moves the base relative to its placement (r_0, E_0^T) in the
                # world, as Pinocchio's; MuJoCo's qpos is the base's pose in the world itself.
                R = E0T @ quat_matrix_xyzw(q[3:7])
                T[:3, :3] = R
                qpos[:3] = r0 + E0T @ q[:3]
                mujoco.mju_mat2Quat(qpos[3:7], R.ravel())  # MuJoCo: wxyz
                a_mj[:3] = R @ (a[:3] + np.cross(v[3:6], v[:3]))
            d.qpos[:] = qpos
            d.qvel[:] = T @ v
            # Inverse dynamics: MuJoCo's rne (M a + bias) in its coordinates, plus the damping force.
            mujoco.mj_forward(m, d)
            d.qacc[:] = a_mj
            tau_mj = np.zeros(n)
            mujoco.mj_rne(m, d, 1, tau_mj)
            # MuJoCo adds armature to its mass matrix, not to rne: the core's RNEA has both.
            tau_ref = T.T @ tau_mj + damp_dof * v + arm_dof * a
            tau = core.rnea(q32, v32, a32)
            worst["rnea"] = max(worst["rnea"], np.abs(tau - tau_ref).max() / (1 + np.abs(tau_ref).max()))
            # Forward dynamics under those forces: MuJoCo's qacc (damping as its passive force).
            tau_in32 = tau_ref.astype(np.float32)
            d.qfrc_applied[:] = np.linalg.solve(T.T, tau_in32.astype(np.float64))
            mujoco.mj_forward(m, d)
            qdd_ref = d.qacc.copy()
            if floating:  # back to the core's body-frame linear acceleration
                qdd_ref[:3] = R.T @ qdd_ref[:3] - np.cross(v[3:6], v[:3])
            qdd = core.aba(q32, v32, tau_in32)
            err = np.abs(qdd - qdd_ref).max() / (1 + np.abs(qdd_ref).max())
            worst["aba"] = max(worst["aba"], err)
            d.qfrc_applied[:] = 0
            mujoco.mj_fullM(m, d, M_mj)
            M_ref = T.T @ M_mj @ T
            M = core.crba(q32)
            worst["crba"] = max(worst["crba"], np.abs(M - M_ref).max() / (1 + np.abs(M_ref).max()))
            states += 1
    assert states == 1000
    print("worst relative differences, core (float32) vs MuJoCo (double), " + ("floating" if floating else "fixed") + " base", worst)
    # float32 against double, relative to each quantity's scale (as against Pinocchio). Measured:
    # RNEA 1.7e-6 / 9.4e-7 (fixed / floating), CRBA 3.3e-7 / 4.1e-7, ABA 3.0e-5 / 1.2e-4: forward
    # dynamics in float32 loses accuracy with the mass matrix's conditioning, and these box-shaped
    # bodies reach cond(M) ~ 2,400 (the largest ABA errors come with the largest cond(M), ~5e-8
    # each). A wrong convention (the free joint's frames, armature left out of a side, damping) is
    # off by 1e-2 to 10.
    assert worst["rnea"] < 2e-5 and worst["crba"] < 2e-5 and worst["aba"] < 3e-4, worst
