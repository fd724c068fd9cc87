"""so101_pick_place as a gymnasium vector env (Kestrel-SO101-PickPlace-v0): spaces and shapes, the
observations at reset against forward kinematics of the robot file, the scripted pick and place
succeeding, success terminating, truncation at the episode length, thread-count independence."""
import numpy as np
import pytest

import kestrel

ID = "Kestrel-SO101-PickPlace-v0"
JOINTS = ["shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex", "wrist_roll", "gripper"]


@pytest.fixture(scope="module")
def model(root):
    return kestrel.load_robot_model(str(root / "models" / "so101" / "so101.xml"))


def _rot(axis, angle):
    """Active rotation by angle about the unit axis (Rodrigues)."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * (k @ k)


def _fk(model, q, body):
    """World pose (R body->world, p) of `body` at joint angles q: the core's tree (E_tree maps parent
    coordinates into the body's, r_tree is the body's origin in its parent's; revolute joints turn
    about axis in the body's frame)."""
    R, p = {-1: np.eye(3)}, {-1: np.zeros(3)}
    for i in range(body + 1):
        par = int(model.parent[i])
        Ri = R[par] @ model.E_tree[i].T
        if int(model.joint[i]) == 0:  # revolute
            Ri = Ri @ _rot(model.axis[i], q[int(model.q_index[i])])
        R[i], p[i] = Ri, p[par] + R[par] @ model.r_tree[i]
    return R[body], p[body]


def _quat_xyzw(R):
    w = np.sqrt(max(0.0, 1 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    x = np.copysign(np.sqrt(max(0.0, 1 + R[0, 0] - R[1, 1] - R[2, 2])) / 2, R[2, 1] - R[1, 2])
    y = np.copysign(np.sqrt(max(0.0, 1 - R[0, 0] + R[1, 1] - R[2, 2])) / 2, R[0, 2] - R[2, 0])
    z = np.copysign(np.sqrt(max(0.0, 1 - R[0, 0] - R[1, 1] + R[2, 2])) / 2, R[1, 0] - R[0, 1])
    return np.array([x, y, z, w])


def _limits(model):
    names = list(model.joint_names)
    idx = [names.index(j) for j in JOINTS]
    return np.array([model.q_min[i] for i in idx]), np.array([model.q_max[i] for i in idx])


def test_spaces_shapes_and_reset_observations(model):
    n = 4
    env = kestrel.make_vec(ID, num_envs=n, seed=3, threads=1)
    obs, info = env.reset()
    assert obs.shape == (n, 31) and obs.dtype == np.float32
    assert env.single_action_space.shape == (6,)
    lo, hi = _limits(model)
    assert np.allclose(env.single_action_space.low, lo, atol=1e-6)
    assert np.allclose(env.single_action_space.high, hi, atol=1e-6)
    home = np.asarray(model.home_q)[:6]
    # joints at the home keyframe, at rest; last actions = home
    assert np.allclose(obs[:, 0:6], home, atol=1e-6)
    assert np.all(obs[:, 6:12] == 0)
    assert np.allclose(obs[:, 12:18], home, atol=1e-6)
    # end effector = forward kinematics of gripper_frame at home
    R, p = _fk(model, home, list(model.body_names).index("gripper_frame"))
    q = _quat_xyzw(R)
    q = q if q[3] >= 0 else -q
    assert np.allclose(obs[:, 18:21], p, atol=1e-5)
    assert np.allclose(obs[:, 21:25], q, atol=1e-5)
    # cube on the table near (0.2, 0) and the box near (0.2, 0.15): relative positions
    cube = obs[:, 18:21] + obs[:, 25:28]
    box = cube + obs[:, 28:31]
    assert np.allclose(cube[:, 2], 0.0125, atol=1e-6)
    assert np.all(np.abs(cube[:, 0] - 0.20) <= 0.05 + 1e-6) and np.all(np.abs(cube[:, 1]) <= 0.05 + 1e-6)
    assert np.all(np.abs(box[:, 1] - 0.15) <= 0.05 + 1e-6) and np.allclose(box[:, 2], 0, atol=1e-6)
    assert len({tuple(np.round(c, 6)) for c in cube}) == n  # each env its own draw
    a = np.ascontiguousarray(np.repeat(home[None].astype(np.float32), n, 0))
    obs, r, term, trunc, info = env.step(a)
    assert obs.shape == (n, 31) and r.shape == (n,) and term.shape == (n,) and trunc.shape == (n,)
    assert np.all((r > 0) & (r < 1)) and not term.any() and not trunc.any()  # the reach term only
    assert env.task.controller == "so101_servo_pd"


def test_scripted_pick_and_place_succeeds():
    n = 8
    env = kestrel.make_vec(ID, num_envs=n, seed=0, threads=2)
    env.reset()
    first_end = np.zeros(n, bool)
    success = np.zeros(n, bool)
    for k in range(1000):  # the episode length: 20 s at 50 Hz
        obs, r, term, trunc, info = env.step(env.scripted_actions())
        new = (term | trunc) & ~first_end
        success |= new & term
        first_end |= term | trunc
        if first_end.all():
            break
    assert success.sum() >= 7, success
    assert env.task_infos["successes"] >= 7
    assert env.task.infos["rew_success"] >= 7 * 50


def test_success_terminates_and_truncation_at_length():
    n = 2
    env = kestrel.make_vec(ID, num_envs=n, seed=1, threads=1, task={"episode_len_env_steps": 20})
    obs, _ = env.reset()
    home = np.ascontiguousarray(obs[:, 0:6].copy())
    for k in range(20):
        obs, r, term, trunc, info = env.step(home)
        if k < 19:
            assert not trunc.any() and not term.any()
    assert trunc.all() and not term.any()
    assert info["_final_obs"].all()
    assert env.task_infos["truncations"] == 2 and env.task_infos["successes"] == 0
    # the scripted controller ends its episodes by success (terminated, not truncated)
    env = kestrel.make_vec(ID, num_envs=n, seed=1, threads=1)
    env.reset()
    for k in range(400):
        obs, r, term, trunc, info = env.step(env.scripted_actions())
        if term.any():
            break
    assert term.any() and not trunc.any()
    assert np.all(r[term] > 50)  # the success bonus
    final = info["final_obs"][term]
    cube = final[:, 18:21] + final[:, 25:28]
    box = cube + final[:, 28:31]
    assert np.all(np.abs(cube[:, :2] - box[:, :2]) < 0.05) and np.all(cube[:, 2] < 0.10)  # cube_in_box


def test_same_seed_same_observations_any_thread_count():
    n = 5
    envs = [kestrel.make_vec(ID, num_envs=n, seed=11, threads=t) for t in (1, 2)]
    outs = [e.reset()[0].copy() for e in envs]
    assert np.array_equal(outs[0], outs[1])
    for k in range(120):
        steps = [e.step(e.scripted_actions()) for e in envs]
        assert np.array_equal(steps[0][0], steps[1][0]), k
        assert np.array_equal(steps[0][1], steps[1][1]), k
    assert envs[0].state_hash == envs[1].state_hash
    assert envs[0].task.num_threads == 1 and envs[1].task.num_threads == 2


def test_ee_delta_mode():
    env = kestrel.make_vec(ID, num_envs=2, seed=0, threads=1, task={"pick_place": {"action_mode": "ee_delta"}})
    obs, _ = env.reset()
    assert env.single_action_space.shape == (5,)
    assert np.isclose(env.single_action_space.high[0], 0.02)
    p0 = obs[:, 18:21].copy()
    a = np.zeros((2, 5), np.float32)
    a[:, 4] = obs[:, 5]
    a[0, 2] = -0.01  # env 0 goes down 1 cm per action
    for k in range(4):
        obs, *_ = env.step(a)
    a[0, 2] = 0
    for k in range(40):
        obs, *_ = env.step(a)
    assert abs(obs[0, 20] - p0[0, 2] + 0.04) < 0.01
    assert np.linalg.norm(obs[1, 18:21] - p0[1]) < 0.01


def test_contacts_in_the_state_and_batched_worlds_match_worlds_alone(monkeypatch):
    """pick_place_state's contact count (the cube resting on the table: its four bottom corners, the
    arm at home in the air), and 20 environments stepped batched (16 lanes with AVX-512) or each alone
    (KESTREL_LEGGED_BATCH=off) give the same observations with noisy actions."""
    n = 20
    envs = []
    for mode in ("on", "off"):
        monkeypatch.setenv("KESTREL_LEGGED_BATCH", mode)  # read when the task is built
        envs.append(kestrel.make_vec(ID, num_envs=n, seed=0, threads=1))
    monkeypatch.delenv("KESTREL_LEGGED_BATCH")
    obs = [e.reset(seed=0)[0] for e in envs]
    home = obs[0][:, 0:6].copy()
    for k in range(5):
        for e in envs:
            e.step(home)
    assert [envs[0].task.pick_place_state(i)["contacts"] for i in range(n)] == [4] * n
    rng = np.random.default_rng(1)
    for k in range(30):
        a = (home + 0.8 * rng.standard_normal(home.shape)).astype(np.float32)
        o = [e.step(a)[0] for e in envs]
        assert np.array_equal(o[0], o[1]), k
    assert envs[0].task.state_hash == envs[1].task.state_hash
