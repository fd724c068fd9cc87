"""kestrel.usd_scene: USD scenes (usd-core's pxr) read into Kestrel's entities: the SO-101
pick-and-place scene (models/so101/pick_place_scene.usda), unit and up-axis conversion, mesh
colliders, masses, and every refusal naming the file, the prim and the attribute."""

import importlib.util
import json
import math
import pathlib
import sys

import numpy as np
import pytest

pytest.importorskip("pxr")

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENE = ROOT / "models" / "so101" / "pick_place_scene.usda"

try:
    from kestrel import usd_scene
except ImportError:
    # kestrel/__init__.py imports the compiled kestrel._core; where it is not built (a venv with only
    # usd-core, numpy and pytest) the module is loaded from its file: it needs only numpy and pxr.
    _spec = importlib.util.spec_from_file_location("kestrel_usd_scene", ROOT / "python" / "kestrel" / "usd_scene.py")
    usd_scene = importlib.util.module_from_spec(_spec)
    sys.modules[_spec.name] = usd_scene  # dataclasses look their module up by name
    _spec.loader.exec_module(usd_scene)

load_usd_scene = usd_scene.load_usd_scene
UsdSceneError = usd_scene.UsdSceneError
approx = pytest.approx


def write(tmp_path, body, name="scene.usda", mpu="1", up="Z", header_extra=""):
    """A .usda file with the given metadata and a /World holding `body`."""
    meta = "".join(f"    {line}\n" for line in (
        *([f"metersPerUnit = {mpu}"] if mpu is not None else []),
        *([f'upAxis = "{up}"'] if up is not None else []),
        *([header_extra] if header_extra else [])))
    body = body.replace("{ ", "{\n").replace(" }", "\n}")  # one-line prims: usda wants a newline there
    p = tmp_path / name
    p.write_text(f"#usda 1.0\n(\n{meta})\n\ndef Xform \"World\"\n{{\n{body}\n}}\n")
    return p


def rotate(q, v):
    """Vector v rotated by the quaternion q = (x, y, z, w)."""
    x, y, z, w = q
    u = np.array([x, y, z])
    v = np.asarray(v, dtype=float)
    return v + 2.0 * np.cross(u, np.cross(u, v) + w * v)


# -- the shipped pick-and-place scene ------------------------------------------------------------


@pytest.fixture(scope="module")
def scene():
    return load_usd_scene(SCENE)


def test_scene_entities_and_kinds(scene):
    assert scene.meters_per_unit == 1.0 and scene.up_axis == "Z"
    assert list(scene.entities) == ["Table", "Cube", "Box", "Robot"]
    assert {n: e.kind for n, e in scene.entities.items()} == {
        "Table": "static", "Cube": "rigid", "Box": "static", "Robot": "robot"}
    assert {n: e.path for n, e in scene.entities.items()} == {
        "Table": "/World/Table", "Cube": "/World/Cube", "Box": "/World/Box", "Robot": "/World/Robot"}
    assert scene.gravity == approx((0.0, 0.0, -9.81))


def test_scene_transforms(scene):
    e = scene.entities
    assert e["Table"].position == approx((0.3, 0.0, -0.375))
    assert e["Cube"].position == approx((0.2, 0.0, 0.0125))
    assert e["Box"].position == approx((0.2, 0.15, 0.0))
    assert e["Robot"].position == approx((0.0, 0.0, 0.0))
    for ent in e.values():
        assert ent.orientation == approx((0.0, 0.0, 0.0, 1.0))
    # The table's top is the plane z = 0: 1.2 x 0.8 m, 0.75 m thick (a unit cube scaled).
    (table,) = e["Table"].shapes
    assert table.type == "box" and table.half_extents == approx((0.6, 0.4, 0.375))
    assert e["Table"].position[2] + table.half_extents[2] == approx(0.0, abs=1e-12)
    # The cube rests on it.
    (cube,) = e["Cube"].shapes
    assert cube.half_extents == approx((0.0125, 0.0125, 0.0125))
    assert e["Cube"].position[2] - cube.half_extents[2] == approx(0.0, abs=1e-12)


def test_scene_box_is_one_entity_of_five_scaled_cubes(scene):
    box = scene.entities["Box"]
    shapes = {s.path.rsplit("/", 1)[1]: s for s in box.shapes}
    assert list(shapes) == ["Floor", "WallPosX", "WallNegX", "WallPosY", "WallNegY"]
    assert shapes["Floor"].half_extents == approx((0.05, 0.05, 0.0025))
    assert shapes["Floor"].position == approx((0.0, 0.0, 0.0025))
    assert shapes["WallPosX"].half_extents == approx((0.0025, 0.055, 0.02))
    assert shapes["WallPosY"].half_extents == approx((0.05, 0.0025, 0.02))
    # Inner 10 x 10 cm, walls 4 cm tall and 5 mm thick, standing on the table.
    px, nx, py, ny = (shapes[n] for n in ("WallPosX", "WallNegX", "WallPosY", "WallNegY"))
    assert px.position[0] - px.half_extents[0] - (nx.position[0] + nx.half_extents[0]) == approx(0.10)
    assert py.position[1] - py.half_extents[1] - (ny.position[1] + ny.half_extents[1]) == approx(0.10)
    for w in (px, nx, py, ny):
        assert 2 * w.half_extents[2] == approx(0.04) and w.position[2] - w.half_extents[2] == approx(0.0, abs=1e-12)
        assert 2 * min(w.half_extents[:2]) == approx(0.005)
    assert box.mass is None


def test_scene_mass_materials_colours(scene):
    cube, table, box = (scene.entities[n] for n in ("Cube", "Table", "Box"))
    assert cube.mass == approx(0.011)
    assert (cube.static_friction, cube.dynamic_friction, cube.restitution) == (1.0, 1.0, 0.0)
    assert cube.shapes[0].material.path == "/World/PhysicsMaterials/CubeMaterial"
    assert (table.static_friction, table.dynamic_friction, table.restitution) == (0.5, 0.4, 0.0)
    # The box's material and colour are bound / authored once on /World/Box, inherited by its walls.
    assert (box.static_friction, box.dynamic_friction, box.restitution) == (0.6, 0.5, 0.1)
    assert all(s.material.path == "/World/PhysicsMaterials/BoxMaterial" for s in box.shapes)
    assert cube.color == (0.85, 0.1, 0.1)
    assert box.color == (0.2, 0.4, 0.8) and all(s.color == (0.2, 0.4, 0.8) for s in box.shapes)
    assert table.color == (0.55, 0.4, 0.25)


def test_scene_robot_and_subassets(scene):
    robot = scene.entities["Robot"]
    assert robot.robot_file == str(ROOT / "models" / "so101" / "so101.xml")
    assert robot.shapes == [] and robot.mass is None
    # LeIsaac's split: the robot and the movable bodies; the static colliders stay in the scene.
    assert list(scene.subassets()) == ["Cube", "Robot"]
    assert list(scene.subassets(include=["Cube"])) == ["Cube"]
    assert list(scene.subassets(exclude=["/World/Robot"])) == ["Cube"]
    assert list(usd_scene.load_subassets(SCENE)) == ["Cube", "Robot"]
    d = json.loads(json.dumps(scene.to_dict()))
    assert d["entities"]["Cube"]["shapes"][0]["half_extents"] == approx([0.0125] * 3)
    assert d["entities"]["Robot"]["robot_file"].endswith("models/so101/so101.xml")


# -- units, axes, shapes, masses -----------------------------------------------------------------


def test_y_up_centimetres_are_metres_z_up(tmp_path):
    # A Y-up stage in centimetres: Kestrel turns it +90 deg about x, (x, y, z) -> (x, -z, y), x 0.01.
    p = write(tmp_path, """
    def PhysicsScene "Physics"
    {
        vector3f physics:gravityDirection = (0, -1, 0)
        float physics:gravityMagnitude = 981
    }
    def Cube "Crate" (prepend apiSchemas = ["PhysicsRigidBodyAPI", "PhysicsCollisionAPI"])
    {
        double size = 4
        double3 xformOp:translate = (10, 2, -30)
        float xformOp:rotateY = 90
        uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateY"]
    }
    def Sphere "Ball" (prepend apiSchemas = ["PhysicsRigidBodyAPI", "PhysicsCollisionAPI", "PhysicsMassAPI"])
    {
        double radius = 2
        float physics:density = 0.0007
        double3 xformOp:translate = (0, 2, 0)
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }
    def Cube "Floor" (prepend apiSchemas = ["PhysicsCollisionAPI"])
    {
        double size = 1
        double3 xformOp:translate = (0, -5, 0)
        double3 xformOp:scale = (200, 10, 100)
        uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:scale"]
    }""", mpu="0.01", up="Y")
    s = load_usd_scene(p)
    assert s.meters_per_unit == 0.01 and s.up_axis == "Y"
    assert s.gravity == approx((0.0, 0.0, -9.81))
    crate, ball, floor = (s.entities[n] for n in ("Crate", "Ball", "Floor"))
    assert crate.position == approx((0.10, 0.30, 0.02))
    # The crate's up (its y) is Kestrel's z; its yaw of 90 deg about USD's y is one about Kestrel's z.
    assert rotate(crate.orientation, (0, 1, 0)) == approx((0, 0, 1), abs=1e-9)
    assert rotate(crate.orientation, (1, 0, 0)) == approx((0, 1, 0), abs=1e-9)
    assert crate.shapes[0].half_extents == approx((0.02, 0.02, 0.02))
    assert crate.mass == approx(1000.0 * 0.04**3)  # the default density, 1000 kg/m^3
    assert ball.position == approx((0.0, 0.0, 0.02))
    assert ball.shapes[0].radius == approx(0.02)
    assert ball.mass == approx(700.0 * 4.0 / 3.0 * math.pi * 0.02**3)  # 0.0007 kg/cm^3 = 700 kg/m^3
    assert floor.position == approx((0.0, 0.0, -0.05))
    # Half extents stay in the floor's own frame (y is its thickness); its frame is turned.
    assert floor.shapes[0].half_extents == approx((1.0, 0.05, 0.5))
    assert rotate(floor.orientation, (0, 1, 0)) == approx((0, 0, 1), abs=1e-9)


def test_mesh_quad_becomes_two_triangles(tmp_path):
    p = write(tmp_path, """
    def Mesh "Ramp" (prepend apiSchemas = ["PhysicsCollisionAPI", "PhysicsMeshCollisionAPI"])
    {
        point3f[] points = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
        int[] faceVertexCounts = [4]
        int[] faceVertexIndices = [0, 1, 2, 3]
        uniform token physics:approximation = "none"
        double3 xformOp:translate = (1, 2, 3)
        double3 xformOp:scale = (2, 3, 1)
        uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:scale"]
    }""")
    (ramp,) = load_usd_scene(p).entities.values()
    assert ramp.kind == "static" and ramp.position == approx((1, 2, 3))
    (mesh,) = ramp.shapes
    assert mesh.type == "mesh" and mesh.approximation == "none"
    assert mesh.triangles.tolist() == [[0, 1, 2], [0, 2, 3]]
    assert mesh.vertices == approx(np.array([[0, 0, 0], [2, 0, 0], [2, 3, 0], [0, 3, 0]]))
    assert mesh.volume() == 0.0


def test_capsule_cylinder_and_a_body_of_several_shapes(tmp_path):
    p = write(tmp_path, """
    def Xform "Dumbbell" (prepend apiSchemas = ["PhysicsRigidBodyAPI", "PhysicsMassAPI"])
    {
        float physics:mass = 2.5
        double3 xformOp:translate = (0, 0, 1)
        float3 xformOp:rotateXYZ = (0, 0, 90)
        uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateXYZ"]
        def Capsule "Bar" (prepend apiSchemas = ["PhysicsCollisionAPI"])
        {
            double radius = 0.01
            double height = 0.2
            uniform token axis = "X"
        }
        def Cylinder "Plate" (prepend apiSchemas = ["PhysicsCollisionAPI"])
        {
            double radius = 0.05
            double height = 0.02
            uniform token axis = "X"
            double3 xformOp:translate = (0.1, 0, 0)
            uniform token[] xformOpOrder = ["xformOp:translate"]
        }
    }""")
    body = load_usd_scene(p).entities["Dumbbell"]
    assert body.kind == "rigid" and body.mass == 2.5
    assert rotate(body.orientation, (1, 0, 0)) == approx((0, 1, 0), abs=1e-9)
    bar, plate = body.shapes
    assert (bar.type, bar.radius, bar.height, bar.axis) == ("capsule", 0.01, 0.2, "X")
    assert (plate.type, plate.radius, plate.height, plate.axis) == ("cylinder", 0.05, 0.02, "X")
    assert plate.position == approx((0.1, 0.0, 0.0))  # in the body's frame
    assert body.static_friction == 0.5 and body.restitution == 0.0  # no material: PhysX's default


def test_kinematic_body(tmp_path):
    p = write(tmp_path, """
    def Cube "Pusher" (prepend apiSchemas = ["PhysicsRigidBodyAPI", "PhysicsCollisionAPI"])
    {
        double size = 0.1
        bool physics:kinematicEnabled = 1
    }""")
    assert load_usd_scene(p).entities["Pusher"].kind == "kinematic"


# -- refusals: each names the file, the prim and the attribute or schema ------------------------


def refused(p, *parts):
    with pytest.raises(UsdSceneError) as info:
        load_usd_scene(p)
    msg = str(info.value)
    for part in parts:
        assert part in msg, msg
    return msg


def test_refuses_shear_op(tmp_path):
    p = write(tmp_path, """
    def Cube "Cube" (prepend apiSchemas = ["PhysicsCollisionAPI"])
    {
        matrix4d xformOp:shear = ( (1, 0, 0, 0), (0.5, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1) )
        uniform token[] xformOpOrder = ["xformOp:shear"]
    }""")
    msg = refused(p, "scene.usda", "/World/Cube", "xformOp:shear is not supported", "allowed ops:")
    assert "translate" in msg and "orient" in msg and "rotateXYZ" in msg and "transform" in msg


def test_refuses_sheared_transform(tmp_path):
    p = write(tmp_path, """
    def Cube "Cube" (prepend apiSchemas = ["PhysicsCollisionAPI"])
    {
        matrix4d xformOp:transform = ( (1, 0, 0, 0), (0.5, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1) )
        uniform token[] xformOpOrder = ["xformOp:transform"]
    }""")
    refused(p, "scene.usda", "/World/Cube", "shear")


@pytest.mark.parametrize("prim", [
    'def Cone "Thing" (prepend apiSchemas = ["PhysicsCollisionAPI"]) { double radius = 1\n double height = 1 }',
    'def Plane "Thing" (prepend apiSchemas = ["PhysicsCollisionAPI"]) {}',
    'def NurbsPatch "Thing" (prepend apiSchemas = ["PhysicsCollisionAPI"]) {}',
])
def test_refuses_unsupported_collider_types(tmp_path, prim):
    p = write(tmp_path, prim)
    refused(p, "scene.usda", "/World/Thing", "PhysicsCollisionAPI on a", "is not supported",
            "allowed collider prim types: Cube, Sphere, Capsule, Cylinder, Mesh")


def test_refuses_physics_in_point_instancer(tmp_path):
    p = write(tmp_path, """
    def PointInstancer "Pebbles"
    {
        def Sphere "Proto" (prepend apiSchemas = ["PhysicsCollisionAPI"]) { double radius = 0.01 }
    }""")
    refused(p, "scene.usda", "/World/Pebbles/Proto", "PointInstancer", "allowed collider prim types")


def test_refuses_missing_and_unparsable_files(tmp_path):
    refused(tmp_path / "nowhere.usda", "nowhere.usda", "no such file")
    bad = tmp_path / "broken.usda"
    bad.write_text("#usda 1.0\ndef Xform \"World\" {\n    double3 xformOp:translate = (1, 2\n")
    refused(bad, "broken.usda", "cannot be parsed as USD")
    txt = tmp_path / "scene.txt"
    txt.write_text("hello")
    refused(txt, "scene.txt", "allowed suffixes: .usd, .usda, .usdc, .usdz")


@pytest.mark.parametrize("attr,prim", [
    ("radius", 'def Sphere "Ball" (prepend apiSchemas = ["PhysicsCollisionAPI"]) { double radius = inf }'),
    ("xformOp:translate", 'def Sphere "Ball" (prepend apiSchemas = ["PhysicsCollisionAPI"]) '
                          '{ double3 xformOp:translate = (nan, 0, 0)\n uniform token[] xformOpOrder = ["xformOp:translate"] }'),
    ("physics:mass", 'def Sphere "Ball" (prepend apiSchemas = ["PhysicsRigidBodyAPI", "PhysicsCollisionAPI", '
                     '"PhysicsMassAPI"]) { float physics:mass = inf }'),
])
def test_refuses_non_finite_numbers(tmp_path, attr, prim):
    p = write(tmp_path, prim)
    refused(p, "scene.usda", "/World/Ball", attr, "is not finite", "allowed: finite numbers")


def test_refuses_duplicate_names(tmp_path):
    p = write(tmp_path, """
    def Xform "Left" { def Cube "Block" (prepend apiSchemas = ["PhysicsCollisionAPI"]) {} }
    def Xform "Right" { def Cube "Block" (prepend apiSchemas = ["PhysicsCollisionAPI"]) {} }""")
    refused(p, "scene.usda", "/World/Right/Block", "/World/Left/Block", "'Block'", "allowed: one entity per prim name")


def test_refuses_unauthored_units_and_up_axis(tmp_path):
    body = 'def Cube "Block" (prepend apiSchemas = ["PhysicsCollisionAPI"]) {}'
    refused(write(tmp_path, body, name="a.usda", mpu=None), "a.usda", "metersPerUnit is not authored")
    refused(write(tmp_path, body, name="b.usda", up=None), "b.usda", "upAxis is not authored")


def test_refuses_other_unsupported_physics(tmp_path):
    cases = {
        "art.usda": ('def Xform "Arm" (prepend apiSchemas = ["PhysicsArticulationRootAPI"]) {}',
                     ("/World/Arm", "PhysicsArticulationRootAPI", "kestrel:robotFile")),
        "joint.usda": ('def PhysicsRevoluteJoint "Hinge" {}', ("/World/Hinge", "PhysicsRevoluteJoint", "outside a robot")),
        "nocoll.usda": ('def Xform "Ghost" (prepend apiSchemas = ["PhysicsRigidBodyAPI"]) {}',
                        ("/World/Ghost", "without a collider")),
        "vel.usda": ('def Cube "Shot" (prepend apiSchemas = ["PhysicsRigidBodyAPI", "PhysicsCollisionAPI"]) '
                     '{ vector3f physics:velocity = (1, 0, 0) }', ("/World/Shot", "physics:velocity", "allowed: 0")),
        "robot.usda": ('def Xform "Arm" { custom asset kestrel:robotFile = @arm.obj@ }',
                       ("/World/Arm", "kestrel:robotFile", "allowed suffixes: .xml, .mjcf, .urdf")),
        "scale.usda": ('def Sphere "Egg" (prepend apiSchemas = ["PhysicsCollisionAPI"]) { double3 xformOp:scale = (1, 2, 1)'
                       '\n uniform token[] xformOpOrder = ["xformOp:scale"] }', ("/World/Egg", "non-uniform scale", "Sphere")),
        "friction.usda": ('def Material "Ice" (prepend apiSchemas = ["PhysicsMaterialAPI"]) '
                          '{ float physics:staticFriction = -1 }\n'
                          'def Cube "Block" (prepend apiSchemas = ["PhysicsCollisionAPI", "MaterialBindingAPI"]) '
                          '{ rel material:binding:physics = </World/Ice> }',
                          ("/World/Ice", "physics:staticFriction = -1", "allowed: >= 0")),
    }
    for name, (body, parts) in cases.items():
        refused(write(tmp_path, body, name=name), name, *parts)
