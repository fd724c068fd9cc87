"""so101_pick_place from a USD scene (kestrel.pick_place_scene: make_vec(..., scene=path),
task.pick_place.scene_file) and from Python terms (kestrel.SceneTask, LeIsaac's manager-based
style): the example scene is the task's default scene; a modified scene moves the cube and the box;
scenes the task cannot represent are refused with the file, the prim and what is expected; the
scene views against the C++ state; LeIsaac's randomize_object_uniform and cube_in_box written in
Python against the C++ ones."""
import os
import re

import numpy as np
import pytest

pytest.importorskip("pxr")

import kestrel  # noqa: E402
from kestrel.pick_place_scene import pick_place_keys_from_usd  # noqa: E402
from kestrel.scene_task import Term  # noqa: E402
from kestrel.usd_scene import UsdSceneError  # noqa: E402

ID = "Kestrel-SO101-PickPlace-v0"


@pytest.fixture(scope="module")
def usda(root):
    return root / "models" / "so101" / "pick_place_scene.usda"


def _write(tmp_path, usda, edits, name="scene.usda"):
    """The example scene with text edits [(old, new)], each old found exactly once; so101.xml is
    resolved beside the original (kestrel:robotFile made absolute)."""
    text = usda.read_text()
    text = text.replace("@so101.xml@", "@" + str(usda.parent / "so101.xml") + "@")
    for old, new in edits:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    p = tmp_path / name
    p.write_text(text)
    return p


# ---- the scene file -> task.pick_place ------------------------------------------------------------

def test_example_scene_is_the_default_scene(usda):
    keys = pick_place_keys_from_usd(usda)
    default = kestrel.make_task("so101_pick_place", num_envs=1, threads=1).pick_place_config()
    scene = kestrel.make_task("so101_pick_place", num_envs=1, threads=1,
                              task={"pick_place": {"scene_file": str(usda)}}).pick_place_config()
    # The file's numbers are the defaults: nothing differs (the robot file is the same file).
    assert os.path.samefile(scene.pop("robot_file"), default.pop("robot_file"))
    for k, v in default.items():
        assert np.allclose(scene[k], v, rtol=1e-6, atol=1e-7), (k, scene[k], v)
    for k in ("cube_half_m", "cube_mass_kg", "cube_friction", "box_inner_half_m", "box_wall_m", "box_height_m",
              "box_friction", "table_friction"):
        assert keys[k] == pytest.approx(default[k], rel=1e-6), k
    assert keys["cube_pos_w"] == pytest.approx([0.2, 0.0, 0.0]) and keys["box_pos_w"] == pytest.approx([0.2, 0.15, 0.0])


def test_make_vec_scene_gives_the_default_episodes(usda):
    a = kestrel.make_vec(ID, num_envs=3, seed=5, threads=1)
    b = kestrel.make_vec(ID, num_envs=3, seed=5, threads=1, scene=usda)
    oa, _ = a.reset()
    ob, _ = b.reset()
    assert np.array_equal(oa, ob)
    for _ in range(20):
        a.step(a.scripted_actions())
        b.step(b.scripted_actions())
    assert a.state_hash == b.state_hash


def test_modified_scene_moves_cube_and_box(tmp_path, usda):
    p = _write(tmp_path, usda, [
        ("double3 xformOp:translate = (0.2, 0, 0.0125)", "double3 xformOp:translate = (0.25, -0.05, 0.0125)"),
        ("double3 xformOp:translate = (0.2, 0.15, 0)", "double3 xformOp:translate = (0.15, 0.2, 0)"),
        # A bigger box: inner 14 x 14 cm (walls at +-0.0725), walls 6 cm tall.
        ("double3 xformOp:scale = (0.1, 0.1, 0.005)", "double3 xformOp:scale = (0.14, 0.14, 0.005)"),
        ("double3 xformOp:translate = (0.0525, 0, 0.02)\n            double3 xformOp:scale = (0.005, 0.11, 0.04)",
         "double3 xformOp:translate = (0.0725, 0, 0.03)\n            double3 xformOp:scale = (0.005, 0.15, 0.06)"),
        ("double3 xformOp:translate = (-0.0525, 0, 0.02)\n            double3 xformOp:scale = (0.005, 0.11, 0.04)",
         "double3 xformOp:translate = (-0.0725, 0, 0.03)\n            double3 xformOp:scale = (0.005, 0.15, 0.06)"),
        ("double3 xformOp:translate = (0, 0.0525, 0.02)\n            double3 xformOp:scale = (0.1, 0.005, 0.04)",
         "double3 xformOp:translate = (0, 0.0725, 0.03)\n            double3 xformOp:scale = (0.14, 0.005, 0.06)"),
        ("double3 xformOp:translate = (0, -0.0525, 0.02)\n            double3 xformOp:scale = (0.1, 0.005, 0.04)",
         "double3 xformOp:translate = (0, -0.0725, 0.03)\n            double3 xformOp:scale = (0.14, 0.005, 0.06)"),
        ("float physics:mass = 0.011", "float physics:mass = 0.02"),
    ])
    keys = pick_place_keys_from_usd(p)
    assert keys["box_inner_half_m"] == pytest.approx(0.07) and keys["box_height_m"] == pytest.approx(0.06)
    assert keys["cube_mass_kg"] == pytest.approx(0.02)
    # No randomisation: the cube and the box exactly where the scene puts them.
    env = kestrel.make_vec(ID, num_envs=2, seed=1, threads=1, scene=p, task={"pick_place": {"randomize_xy_m": 0}})
    obs, _ = env.reset()
    for e in range(2):
        st = env.task.pick_place_state(e)
        assert st["cube_pos_w"] == pytest.approx([0.25, -0.05, 0.0125], abs=1e-6)
        assert st["box_pos_w"] == pytest.approx([0.15, 0.2, 0.0], abs=1e-6)
        walls = {s["index"]: s for s in st["shapes"] if s["entity"] == "box"}
        assert walls[2]["pos_w"][0] == pytest.approx(0.15 + 0.0725, abs=1e-6)  # the +x wall
        assert walls[2]["size"][2] == pytest.approx(0.03, abs=1e-7)
        # Observations: box - cube (28..31).
        assert obs[e, 28:31] == pytest.approx([-0.1, 0.25, -0.0125], abs=1e-5)
    assert env.task.pick_place_config()["cube_mass_kg"] == pytest.approx(0.02)
    # With the default randomisation: within +-0.05 of the new nominal positions.
    env = kestrel.make_vec(ID, num_envs=64, seed=2, threads=1, scene=p)
    env.reset()
    poses = env.task.pick_place_poses()
    assert np.all(np.abs(poses["cube_pos_w"][:, :2] - [0.25, -0.05]) <= 0.05 + 1e-6)
    assert np.all(np.abs(poses["box_pos_w"][:, :2] - [0.15, 0.2]) <= 0.05 + 1e-6)
    # Keys given beside the scene file win over the scene's.
    env = kestrel.make_vec(ID, num_envs=1, threads=1, scene=p, task={"pick_place": {"cube_mass_kg": 0.03}})
    assert env.task.pick_place_config()["cube_mass_kg"] == pytest.approx(0.03)


def test_robot_offset_is_subtracted(tmp_path, usda):
    # Everything shifted by (1, 2, 0.5): the same task in the robot's frame.
    p = _write(tmp_path, usda, [
        ("double3 xformOp:translate = (0, 0, 0)\n        quatf", "double3 xformOp:translate = (1, 2, 0.5)\n        quatf"),
        ("double3 xformOp:translate = (0.3, 0, -0.375)", "double3 xformOp:translate = (1.3, 2, 0.125)"),
        ("double3 xformOp:translate = (0.2, 0, 0.0125)", "double3 xformOp:translate = (1.2, 2, 0.5125)"),
        ("double3 xformOp:translate = (0.2, 0.15, 0)", "double3 xformOp:translate = (1.2, 2.15, 0.5)"),
    ])
    shifted, orig = pick_place_keys_from_usd(p), pick_place_keys_from_usd(usda)
    assert os.path.samefile(shifted.pop("robot_file"), orig.pop("robot_file"))
    for k, v in orig.items():
        assert shifted[k] == pytest.approx(v, abs=1e-6), k


@pytest.mark.parametrize("edits, expected", [
    # The cube a sphere.
    ([('def Cube "Cube"', 'def Sphere "Cube"'), ("double size = 0.025", "double radius = 0.0125")],
     r"Cube.*expected the cube's collider to be a box \(USD Cube\), got a sphere"),
    # No box.
    ([('def Xform "Box" (', 'def Xform "Crate" ('), ('kind = "component"', 'kind = "group"')],
     r"expected the open box: an entity named Box"),
    # The table top below z = 0.
    ([("double3 xformOp:translate = (0.3, 0, -0.375)", "double3 xformOp:translate = (0.3, 0, -0.4)")],
     r"/World/Table: expected the table's top face at z = 0.*got z = -0.025"),
    # One wall thicker.
    ([("double3 xformOp:translate = (0.0525, 0, 0.02)\n            double3 xformOp:scale = (0.005, 0.11, 0.04)",
       "double3 xformOp:translate = (0.054, 0, 0.02)\n            double3 xformOp:scale = (0.008, 0.11, 0.04)")],
     r"/World/Box/WallPosX: expected every wall as thick as the floor \(0.005 m.*got 0.008 m"),
    # The robot turned.
    ([("quatf xformOp:orient = (1, 0, 0, 0)\n        uniform token[] xformOpOrder = [\"xformOp:translate\", \"xformOp:orient\"]\n    }\n}",
       "quatf xformOp:orient = (0.7071068, 0, 0, 0.7071068)\n        uniform token[] xformOpOrder = [\"xformOp:translate\", \"xformOp:orient\"]\n    }\n}")],
     r"/World/Robot: expected the robot's base facing \+x"),
    # The cube floating.
    ([("double3 xformOp:translate = (0.2, 0, 0.0125)", "double3 xformOp:translate = (0.2, 0, 0.05)")],
     r"/World/Cube: expected the cube resting on the table"),
    # A box that is not square.
    ([("double3 xformOp:translate = (0, 0.0525, 0.02)", "double3 xformOp:translate = (0, 0.0625, 0.02)")],
     r"/World/Box/WallPosY: expected a square box"),
])
def test_scenes_the_task_cannot_represent_are_refused(tmp_path, usda, edits, expected):
    p = _write(tmp_path, usda, edits)
    with pytest.raises(UsdSceneError, match=expected) as e:
        pick_place_keys_from_usd(p)
    assert str(p) in str(e.value)
    with pytest.raises(ValueError, match=re.escape(str(p))):
        kestrel.make_vec(ID, num_envs=1, threads=1, scene=p)


def test_second_rigid_body_is_refused(tmp_path, usda):
    cube = usda.read_text().split('    def Cube "Cube" (')[1].split("\n    }\n")[0]
    extra = '    def Cube "Cube2" (' + cube.replace("(0.2, 0, 0.0125)", "(0.3, 0, 0.0125)") + "\n    }\n"
    p = _write(tmp_path, usda, [('    # The SO-101 arm:', extra + '    # The SO-101 arm:')])
    with pytest.raises(UsdSceneError, match=r"/World/Cube2: so101_pick_place has one movable object, the cube"):
        pick_place_keys_from_usd(p)


# ---- SceneTask: LeIsaac-style terms in Python ----------------------------------------------------------

def cube_in_box(scene, xy=0.05, height=0.10):
    """LeIsaac's cube_in_box: the cube's centre within +-xy of the box's centre in x and y, below height."""
    d = scene["cube"].pos_w - scene["box"].pos_w
    return (np.abs(d[:, 0]) < xy) & (np.abs(d[:, 1]) < xy) & (scene["cube"].pos_w[:, 2] < height)


def randomize_object_uniform(scene, env_ids, rng, name, pose_range):
    """LeIsaac's randomize_object_uniform: the object's default pose plus offsets drawn uniformly in
    pose_range (x, y, z in m; yaw in rad for the cube)."""
    ent = scene[name]
    k = len(env_ids)
    lo = np.array([pose_range.get(a, (0.0, 0.0))[0] for a in "xyz"])
    hi = np.array([pose_range.get(a, (0.0, 0.0))[1] for a in "xyz"])
    pos = ent.default_pos_w[env_ids] + rng.uniform(lo, hi, size=(k, 3))
    yaw = rng.uniform(*pose_range.get("yaw", (0.0, 0.0)), size=k)
    quat = np.stack([np.zeros(k), np.zeros(k), np.sin(yaw / 2), np.cos(yaw / 2)], axis=1)
    ent.set_pose(env_ids, pos, quat)


def test_scene_views_match_the_worlds(usda):
    env = kestrel.SceneTask(num_envs=3, seed=4, threads=1, scene=usda)
    env.reset()
    for _ in range(5):
        env.step(env.scripted_actions())
    s = env.scene
    for e in range(3):
        st = env.task.pick_place_state(e)
        assert s["cube"].pos_w[e] == pytest.approx(st["cube_pos_w"], abs=1e-7)
        assert s["Cube"].quat_xyzw[e] == pytest.approx(st["cube_quat_xyzw"], abs=1e-7)
        assert s["box"].pos_w[e] == pytest.approx(st["box_pos_w"], abs=1e-7)
        assert s["robot"].ee_pos_w[e] == pytest.approx(st["tcp_pos_w"], abs=1e-7)
        assert s["robot"].joint_pos[e] == pytest.approx(st["joint_pos"], abs=1e-7)
    # The default observations are the C++ task's (31).
    assert env.single_observation_space.shape == (31,)
    with pytest.raises(KeyError, match="entities: cube, box, robot"):
        s["orange"]


def test_set_pose_moves_objects_and_the_observations_follow():
    env = kestrel.SceneTask(num_envs=2, seed=0, threads=1, task={"pick_place": {"randomize_xy_m": 0}})
    env.reset()
    env.scene["box"].set_pos([1], [0.1, -0.2, 0.0])
    env.scene["cube"].set_pose([1], [0.12, -0.19, 0.0125], [0, 0, 0, 1])
    assert env.scene["box"].pos_w[1] == pytest.approx([0.1, -0.2, 0.0], abs=1e-6)
    assert env.scene["cube"].pos_w[1] == pytest.approx([0.12, -0.19, 0.0125], abs=1e-6)
    assert env.scene["box"].pos_w[0] == pytest.approx([0.2, 0.15, 0.0], abs=1e-6)  # env 0 untouched
    assert env.task.observations[1, 28:31] == pytest.approx([-0.02, -0.01, -0.0125], abs=1e-5)
    assert bool(env.scene.cube_in_box[1]) and not bool(env.scene.cube_in_box[0])
    with pytest.raises(ValueError, match='object: expected "cube" or "box"'):
        env.task.set_object_pose(0, "sphere", [0, 0, 0])
    with pytest.raises(ValueError, match="env: expected 0..1"):
        env.task.set_object_pose(2, "cube", [0, 0, 0.0125])


def test_python_randomize_object_uniform_reproduces_the_cpp_ranges():
    n = 400
    r = 0.05
    cpp = kestrel.SceneTask(num_envs=n, seed=11, threads=1)  # the C++ reset's randomize_object_uniform
    py = kestrel.SceneTask(num_envs=n, seed=11, threads=1, task={"pick_place": {"randomize_xy_m": 0}},
                           events={"reset": [Term(randomize_object_uniform, params={"name": "cube", "pose_range": {"x": (-r, r), "y": (-r, r)}}),
                                             Term(randomize_object_uniform, params={"name": "box", "pose_range": {"x": (-r, r), "y": (-r, r)}})]})
    for env in (cpp, py):
        env.reset()
        for name, nominal in (("cube", [0.2, 0.0, 0.0125]), ("box", [0.2, 0.15, 0.0])):
            p = env.scene[name].pos_w
            d = p - nominal
            assert np.all(np.abs(d[:, :2]) <= r + 1e-6), name
            assert np.allclose(d[:, 2], 0, atol=1e-7)
            # Uniform on [-r, r]: the sample's extremes near the ends, mean 0, std r / sqrt(3).
            assert np.all(d[:, :2].min(axis=0) < -0.9 * r) and np.all(d[:, :2].max(axis=0) > 0.9 * r), name
            assert np.all(np.abs(d[:, :2].mean(axis=0)) < 0.006), name
            assert np.allclose(d[:, :2].std(axis=0), r / np.sqrt(3), rtol=0.12), name
        # The observations see the drawn positions (box - cube).
        obs = env.task.observations
        assert np.allclose(obs[:, 28:31], env.scene["box"].pos_w - env.scene["cube"].pos_w, atol=1e-5)
    # A reset draws again (the events run after every reset).
    before = py.scene["cube"].pos_w.copy()
    py.reset()
    assert not np.allclose(before, py.scene["cube"].pos_w)


def test_python_cube_in_box_agrees_with_the_cpp_success_on_a_scripted_rollout(usda):
    n, seed = 4, 3
    base = kestrel.make_vec(ID, num_envs=n, seed=seed, threads=1)
    hold_steps, release_N = 10, 0.1  # the C++ success rule: in the box and released for 10 actions
    hold = np.zeros(n, dtype=np.int64)

    def success(scene):
        hold[:] = np.where(cube_in_box(scene) & (scene["robot"].grip_force_N < release_N), hold + 1, 0)
        return hold >= hold_steps

    def clear_hold(scene, env_ids, rng):
        hold[env_ids] = 0

    py = kestrel.SceneTask(num_envs=n, seed=seed, threads=1, scene=usda, terminations={"success": success},
                           events={"reset": [clear_hold]})
    # Both as built (KestrelVectorEnv.reset() would draw the cube and box once more; a fresh
    # SceneTask's reset() does not).
    py.reset()
    seen = set()
    ended_base = np.full(n, -1)
    ended_py = np.full(n, -1)
    for t in range(400):
        a = base.scripted_actions()
        assert np.array_equal(a, py.scripted_actions())
        _, _, term_b, trunc_b, _ = base.step(a)
        _, _, term_p, trunc_p, info = py.step(a)
        assert not trunc_b.any() and not trunc_p.any()
        for e in np.flatnonzero(term_b):
            if ended_base[e] < 0:
                ended_base[e] = t
        for e in np.flatnonzero(term_p):
            if ended_py[e] < 0:
                ended_py[e] = t
                assert info["terminations"]["success"][e]
        if not term_p.any():  # per step (no env reset in it): the Python term equals the C++ cube_in_box
            flags = cube_in_box(py.scene)
            assert np.array_equal(flags, py.scene.cube_in_box)
            seen.update(flags.tolist())
        if (ended_base >= 0).all() and (ended_py >= 0).all():
            break
    assert seen == {False, True}
    assert (ended_base >= 0).all(), ended_base
    assert np.array_equal(ended_base, ended_py), (ended_base, ended_py)
    assert base.task_infos["successes"] == n


def test_python_observations_rewards_and_time_limit():
    def rel(scene):
        return scene["cube"].pos_w - scene["robot"].ee_pos_w

    def reach(scene):
        return -np.linalg.norm(rel(scene), axis=1)

    env = kestrel.SceneTask(num_envs=2, seed=0, threads=1, episode_length=5,
                            observations={"joint_pos": lambda s: s["robot"].joint_pos, "rel": rel,
                                          "grip": lambda s: s["robot"].grip_force_N},
                            rewards={"reach": Term(reach, weight=2.0), "alive": Term(lambda s: np.ones(s.num_envs), weight=0.5)})
    obs, _ = env.reset()
    assert obs.shape == (2, 10) and env.single_observation_space.shape == (10,)
    a = env.scripted_actions()
    obs, rew, term, trunc, info = env.step(a)
    assert rew == pytest.approx(2.0 * reach(env.scene) + 0.5, abs=1e-5)
    assert obs[:, 6:9] == pytest.approx(rel(env.scene), abs=1e-6)
    for _ in range(3):
        _, _, term, trunc, info = env.step(env.scripted_actions())
        assert not trunc.any()
    _, _, term, trunc, info = env.step(env.scripted_actions())
    assert trunc.all() and not term.any() and info["_final_obs"].all()
    with pytest.raises(ValueError, match="so101_pick_place"):
        kestrel.SceneTask(base="Kestrel-Navigation-v0", num_envs=1)
    with pytest.raises(ValueError, match="events: unknown mode"):
        kestrel.SceneTask(num_envs=1, events={"interval": []})
