"""USD scenes (``.usd`` / ``.usda`` / ``.usdc`` / ``.usdz``) read into Kestrel's terms with Pixar's
``usd-core`` (``pxr``): the entities of a scene with their poses, collision shapes, masses, physics
materials and display colours, the way LeIsaac ties an Isaac Lab task to a USD scene.

    from kestrel.usd_scene import load_usd_scene
    scene = load_usd_scene("models/so101/pick_place_scene.usda")
    scene.entities["Cube"].position          # (0.2, 0.0, 0.0125) m, Kestrel's z-up world
    scene.subassets()                         # {"Cube": ..., "Robot": ...}: what LeIsaac's
                                              # parse_usd_and_create_subassets splits out
    scene.to_dict()                           # plain lists / floats, for a scenario dict

This module needs only numpy and pxr (not the compiled ``kestrel._core``).

What becomes an entity (named by its prim's name, which must be unique in the scene):

* ``robot``: a prim with the custom attribute ``asset kestrel:robotFile = @so101.xml@``, the robot
  model (MJCF ``.xml`` / ``.mjcf`` or ``.urdf``) that ``kestrel.load_robot_model`` reads; the path is
  resolved relative to the layer that authors it (not checked for existence here: the robot loader
  does that). Its pose is the spawn pose of the robot's base; its subtree is the robot's and is not
  read (a USD articulation - ``PhysicsArticulationRootAPI`` - without ``kestrel:robotFile`` is
  refused: Kestrel's robots come from their MJCF/URDF files).
* ``rigid``: a prim with ``PhysicsRigidBodyAPI`` (``kinematic`` when ``physics:kinematicEnabled``;
  ``static`` when ``physics:rigidBodyEnabled`` is false). Its shapes are the ``PhysicsCollisionAPI``
  prims of its subtree, down to a nested rigid body (a body of its own).
* ``static``: colliders with no rigid body above them. They are grouped under the nearest ancestor
  whose USD model kind is ``component`` (USD's "one asset" marker: the pick-place scene's open Box
  of a floor and four walls is one entity); a collider with no such ancestor is an entity alone.

Units and axes: lengths are converted to metres with the stage's ``metersPerUnit`` and masses to
kg with ``kilogramsPerUnit``; a ``upAxis = "Y"`` stage is rotated into Kestrel's z-up world (+90 deg
about x: USD's (x, y, z) becomes (x, -z, y)). ``metersPerUnit`` and ``upAxis`` must be authored: USD's
fallbacks (0.01, i.e. centimetres, and Y) silently scale or tip a scene written with metres and z
in mind, so an unauthored one is refused. Quaternions are (x, y, z, w), w >= 0.

Shapes (``Shape``), in their entity's frame (``position``, ``orientation``), every scale of the
xform stack below the entity folded into their sizes: ``box`` (``Cube``: ``half_extents``),
``sphere`` (``radius``), ``capsule`` (``radius``, ``height`` of the cylinder between the caps,
``axis``), ``cylinder`` (``radius``, full ``height``, ``axis``), ``mesh`` (``vertices`` (N, 3) in the
shape's frame, ``triangles`` (M, 3): polygons fan-triangulated, left-handed winding flipped; the
``physics:approximation`` of ``PhysicsMeshCollisionAPI`` kept as ``approximation``). A scale must
be along the shape's own axes (no shear), positive, and uniform where the shape demands (a sphere's
three axes, a capsule's or cylinder's two radial axes).

Mass (``rigid`` / ``kinematic``): the body's ``physics:mass`` (``PhysicsMassAPI``) when authored
(> 0); else the sum over its shapes of the shape's own ``physics:mass``, or density x volume with
the first authored density of: the shape's ``physics:density``, the body's, the bound physics
material's, else 1000 kg/m^3 (water; the UsdPhysics default). ``center_of_mass`` /
``diagonal_inertia`` / ``principal_axes`` are passed on when authored, else None (Kestrel computes
them from the shapes).

Materials: the material bound to each shape for purpose ``physics`` (``material:binding:physics``,
else the all-purpose binding, inherited down namespace) with ``PhysicsMaterialAPI``:
``static_friction``, ``dynamic_friction``, ``restitution`` (unauthored ones: UsdPhysics' fallback,
0). No such material: 0.5 / 0.5 / 0.0 (PhysX's default material, as Isaac Lab's
``RigidBodyMaterialCfg``). An entity's own ``static_friction`` /
``dynamic_friction`` / ``restitution`` are its shapes' when they all agree, else None (read the shapes).

Gravity: the first ``PhysicsScene`` prim's, in m/s^2 in Kestrel's frame (9.81 m/s^2 down when its
magnitude is unauthored), ``UsdScene.gravity``; None without a PhysicsScene.

Colours: ``primvars:displayColor`` (with inheritance from ancestors; several values are averaged):
per shape, and the entity's (its own prim's, else its first coloured shape's).

Refused, with ``UsdSceneError`` (a ``ValueError``) naming the file, the prim path, the attribute or
schema and what is allowed: a missing or unparsable file; xform ops that are not UsdGeom ops
(``xformOp:shear``), time-sampled-only ops, shear or mirroring; collision on prim types other than
Cube / Sphere / Capsule / Cylinder / Mesh (Cone, Plane, NurbsPatch, PointInstancer, ...); physics
inside a PointInstancer; joints outside a robot; non-zero initial velocities; a rigid body with no
collider; non-finite numbers; non-positive sizes; negative friction; restitution outside [0, 1];
duplicate entity names. Nothing half-built is returned: the scene is read whole or not at all.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Any, Iterable

import numpy as np
from pxr import Gf, Kind, Sdf, Tf, Usd, UsdGeom, UsdPhysics, UsdShade

__all__ = [
    "DEFAULT_DENSITY",
    "DEFAULT_MATERIAL",
    "ENTITY_KINDS",
    "ROBOT_FILE_ATTR",
    "SUPPORTED_COLLIDERS",
    "Entity",
    "Material",
    "Shape",
    "UsdScene",
    "UsdSceneError",
    "load_subassets",
    "load_usd_scene",
]

ROBOT_FILE_ATTR = "kestrel:robotFile"
ROBOT_FILE_SUFFIXES = (".xml", ".mjcf", ".urdf")
USD_SUFFIXES = (".usd", ".usda", ".usdc", ".usdz")
ENTITY_KINDS = ("robot", "rigid", "kinematic", "static")
SUBASSET_KINDS = ("robot", "rigid", "kinematic")
# USD prim type -> Kestrel shape type.
SUPPORTED_COLLIDERS = {"Cube": "box", "Sphere": "sphere", "Capsule": "capsule", "Cylinder": "cylinder", "Mesh": "mesh"}
DEFAULT_DENSITY = 1000.0  # kg/m^3 (water): UsdPhysics' default when no density is authored
EARTH_GRAVITY = 9.81  # m/s^2: UsdPhysics' default gravity magnitude


class UsdSceneError(ValueError):
    """A USD scene Kestrel cannot read: the message names the file, the prim, the attribute or schema
    and the allowed values."""


@dataclass(frozen=True)
class Material:
    """A physics material (``PhysicsMaterialAPI``), or the default when ``path`` is None."""

    path: str | None
    static_friction: float
    dynamic_friction: float
    restitution: float
    density: float | None = None  # kg/m^3, when authored (> 0)

    def to_dict(self) -> dict[str, Any]:
        return {"path": self.path, "static_friction": self.static_friction, "dynamic_friction": self.dynamic_friction,
                "restitution": self.restitution, "density": self.density}


DEFAULT_MATERIAL = Material(None, 0.5, 0.5, 0.0)


@dataclass
class Shape:
    """One collision shape in its entity's frame (metres; quaternion x y z w)."""

    type: str  # box | sphere | capsule | cylinder | mesh
    path: str
    position: tuple[float, float, float]
    orientation: tuple[float, float, float, float]
    material: Material
    color: tuple[float, float, float] | None = None
    half_extents: tuple[float, float, float] | None = None  # box
    radius: float | None = None  # sphere, capsule, cylinder
    height: float | None = None  # capsule (between the caps), cylinder (full)
    axis: str | None = None  # capsule, cylinder: X | Y | Z of the shape's frame
    vertices: np.ndarray | None = None  # mesh: (N, 3) float64, in the shape's frame
    triangles: np.ndarray | None = None  # mesh: (M, 3) int64
    approximation: str | None = None  # mesh: PhysicsMeshCollisionAPI physics:approximation
    mass: float | None = None  # the shape's own physics:mass (kg), when authored
    density: float | None = None  # the shape's own physics:density (kg/m^3), when authored

    def volume(self) -> float:
        """m^3 (a mesh: the volume its triangles enclose, 0 for an open one)."""
        if self.type == "box":
            hx, hy, hz = self.half_extents
            return 8.0 * hx * hy * hz
        r = self.radius
        if self.type == "sphere":
            return 4.0 / 3.0 * math.pi * r**3
        if self.type == "capsule":
            return math.pi * r * r * self.height + 4.0 / 3.0 * math.pi * r**3
        if self.type == "cylinder":
            return math.pi * r * r * self.height
        v = self.vertices[self.triangles]
        return abs(float(np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2])).sum()) / 6.0)

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {"type": self.type, "path": self.path, "position": list(self.position),
                             "orientation": list(self.orientation), "material": self.material.to_dict(),
                             "color": None if self.color is None else list(self.color)}
        if self.type == "box":
            d["half_extents"] = list(self.half_extents)
        elif self.type == "mesh":
            d["vertices"] = self.vertices.tolist()
            d["triangles"] = self.triangles.tolist()
            d["approximation"] = self.approximation
        else:
            d["radius"] = self.radius
            if self.type != "sphere":
                d["height"] = self.height
                d["axis"] = self.axis
        if self.mass is not None:
            d["mass"] = self.mass
        if self.density is not None:
            d["density"] = self.density
        return d


@dataclass
class Entity:
    """A named thing of the scene: a robot, a rigid (or kinematic) body, or a static collider."""

    name: str
    path: str
    kind: str  # robot | rigid | kinematic | static
    position: tuple[float, float, float]  # world, metres, z up
    orientation: tuple[float, float, float, float]  # world, x y z w
    shapes: list[Shape] = field(default_factory=list)
    mass: float | None = None  # kg; rigid and kinematic
    center_of_mass: tuple[float, float, float] | None = None  # entity frame, m; when authored
    diagonal_inertia: tuple[float, float, float] | None = None  # kg m^2; when authored
    principal_axes: tuple[float, float, float, float] | None = None  # x y z w; with diagonal_inertia
    color: tuple[float, float, float] | None = None
    robot_file: str | None = None  # robot: absolute path of the MJCF/URDF file

    def _common(self, attr: str) -> float | None:
        values = {getattr(s.material, attr) for s in self.shapes}
        return values.pop() if len(values) == 1 else None

    @property
    def static_friction(self) -> float | None:
        return self._common("static_friction")

    @property
    def dynamic_friction(self) -> float | None:
        return self._common("dynamic_friction")

    @property
    def restitution(self) -> float | None:
        return self._common("restitution")

    def to_dict(self) -> dict[str, Any]:
        """Plain lists, floats and strings (JSON-ready), for building a scenario."""

        def lst(v):
            return None if v is None else list(v)

        return {"name": self.name, "path": self.path, "kind": self.kind, "position": list(self.position),
                "orientation": list(self.orientation), "shapes": [s.to_dict() for s in self.shapes],
                "mass": self.mass, "center_of_mass": lst(self.center_of_mass),
                "diagonal_inertia": lst(self.diagonal_inertia), "principal_axes": lst(self.principal_axes),
                "static_friction": self.static_friction, "dynamic_friction": self.dynamic_friction,
                "restitution": self.restitution, "color": lst(self.color), "robot_file": self.robot_file}


@dataclass
class UsdScene:
    """A USD scene in Kestrel's terms: metres, kg, z up, quaternions x y z w."""

    path: str
    meters_per_unit: float  # as authored in the file
    up_axis: str  # as authored in the file ("Z" or "Y"; entities are z-up either way)
    kilograms_per_unit: float
    gravity: tuple[float, float, float] | None  # m/s^2, from the first PhysicsScene prim; None without one
    entities: dict[str, Entity]  # by name, in the stage's traversal order

    def subassets(self, include: Iterable[str] | None = None, exclude: Iterable[str] | None = None) -> dict[str, Entity]:
        """The scene split the way LeIsaac's ``parse_usd_and_create_subassets`` splits it: the
        robots (LeIsaac: the articulations) and the movable bodies (rigid and kinematic), by name;
        the static colliders stay in the scene (``entities``). ``include`` / ``exclude``: substrings
        of the prim path; an entity is kept when its path contains one of ``include`` (all when
        None) and none of ``exclude``."""
        inc = None if include is None else [str(s) for s in include]
        exc = [] if exclude is None else [str(s) for s in exclude]
        return {n: e for n, e in self.entities.items()
                if e.kind in SUBASSET_KINDS and (inc is None or any(s in e.path for s in inc))
                and not any(s in e.path for s in exc)}

    def to_dict(self) -> dict[str, Any]:
        return {"path": self.path, "meters_per_unit": self.meters_per_unit, "up_axis": self.up_axis,
                "kilograms_per_unit": self.kilograms_per_unit,
                "gravity": None if self.gravity is None else list(self.gravity),
                "entities": {n: e.to_dict() for n, e in self.entities.items()}}


def load_subassets(path: str | os.PathLike, include: Iterable[str] | None = None,
                   exclude: Iterable[str] | None = None) -> dict[str, Entity]:
    """``load_usd_scene(path).subassets(include, exclude)``: Kestrel's counterpart of LeIsaac's
    ``parse_usd_and_create_subassets``."""
    return load_usd_scene(path).subassets(include, exclude)


def load_usd_scene(path: str | os.PathLike) -> UsdScene:
    """Reads a USD scene (see the module's docstring for what it becomes and what is refused)."""
    file = os.fspath(path)
    if not os.path.isfile(file):
        raise UsdSceneError(f"{file}: no such file")
    if not file.lower().endswith(USD_SUFFIXES):
        raise UsdSceneError(f"{file}: not a USD file (allowed suffixes: {', '.join(USD_SUFFIXES)})")
    try:
        stage = Usd.Stage.Open(file, Usd.Stage.LoadAll)
    except Tf.ErrorException as e:
        raise UsdSceneError(f"{file}: cannot be parsed as USD: {_tf_message(e)}") from None
    if stage is None:
        raise UsdSceneError(f"{file}: cannot be opened as a USD stage")
    try:
        return _Reader(file, stage).read()
    except Tf.ErrorException as e:  # a value USD itself cannot read
        raise UsdSceneError(f"{file}: {_tf_message(e)}") from None


def _tf_message(e: Exception) -> str:
    lines = [ln.strip() for ln in str(e).splitlines() if ln.strip()]
    for ln in lines:  # Tf's messages read "Error in '<function>' at line N in file <source> : '<text>'"
        if "Error" in ln or "error" in ln:
            return ln.split(" : ", 1)[-1].strip("'")
    return lines[0] if lines else type(e).__name__


_ROTATE_Y_UP_TO_Z_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # +90 deg about x
_OP_NAMES = [t.name[len("Type"):] for t in UsdGeom.XformOp.Type.allValues if t.name != "TypeInvalid"]
ALLOWED_XFORM_OPS = tuple(n[0].lower() + n[1:] for n in _OP_NAMES)
_MATERIAL_PURPOSE = "physics"


def _quat_xyzw(r: np.ndarray) -> tuple[float, float, float, float]:
    """Rotation matrix (column vectors) -> unit quaternion (x, y, z, w), w >= 0."""
    m = r
    tr = m[0, 0] + m[1, 1] + m[2, 2]
    if tr > 0.0:
        s = 2.0 * math.sqrt(tr + 1.0)
        w, x, y, z = 0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        w, x, y, z = (m[2, 1] - m[1, 2]) / s, 0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        w, x, y, z = (m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s
    else:
        s = 2.0 * math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        w, x, y, z = (m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s
    q = np.array([x, y, z, w])
    q /= np.linalg.norm(q)
    if q[3] < 0.0:
        q = -q
    return tuple(float(v) + 0.0 for v in q)


def _clean(v: Iterable[float]) -> tuple[float, ...]:
    """Floats rounded to 12 significant digits (clears the round-off of composing transforms in
    double precision, and -0.0) for readable, comparable values."""
    return tuple(float(f"{float(x):.12g}") + 0.0 for x in v)


def _f32(v: float) -> float:
    """A value read from a float (32-bit) attribute as the shortest decimal that is the same float32
    (0.55, not 0.550000011920929); a value that is no float32 is returned as it is."""
    f = np.float32(v)
    return float(str(f)) if float(f) == v else float(v)


class _Reader:
    def __init__(self, file: str, stage: Usd.Stage):
        self.file = file
        self.stage = stage
        self.checked_xforms: set[str] = set()
        self.order: dict[str, int] = {}
        self.frames: dict[str, tuple[np.ndarray, np.ndarray]] = {}  # entity path -> world rotation, translation

    # -- errors and checked values ---------------------------------------------------------------
    def err(self, prim: Usd.Prim | str | None, what: str) -> UsdSceneError:
        where = "" if prim is None else f"{prim if isinstance(prim, str) else prim.GetPath()}: "
        return UsdSceneError(f"{self.file}: {where}{what}")

    def finite(self, prim, attr_name: str, value) -> np.ndarray:
        if isinstance(value, (Gf.Quatd, Gf.Quatf, Gf.Quath)):
            value = (value.GetReal(), *value.GetImaginary())
        a = np.asarray(value, dtype=np.float64)
        if not np.all(np.isfinite(a)):
            raise self.err(prim, f"{attr_name} = {value} is not finite (allowed: finite numbers)")
        return a

    def get(self, prim: Usd.Prim, attr: Usd.Attribute, authored_only: bool = False):
        """An attribute's value at the default time (None when it has none); refuses time samples
        without a default value."""
        if not attr or not attr.IsValid():
            return None
        if authored_only and not attr.HasAuthoredValue():
            return None
        value = attr.Get(Usd.TimeCode.Default())
        if value is None and attr.GetNumTimeSamples() > 0:
            raise self.err(prim, f"{attr.GetName()} has time samples only (allowed: a default value)")
        return value

    def scalar(self, prim, attr, authored_only=False, minimum=None, strict=False, maximum=None) -> float | None:
        value = self.get(prim, attr, authored_only)
        if value is None:
            return None
        v = _f32(float(self.finite(prim, attr.GetName(), value)))
        if minimum is not None and (v < minimum or (strict and v == minimum)) or maximum is not None and v > maximum:
            lo = "" if minimum is None else (f"> {minimum:g}" if strict else f">= {minimum:g}")
            hi = "" if maximum is None else f"<= {maximum:g}"
            raise self.err(prim, f"{attr.GetName()} = {v:g} is out of range (allowed: {' and '.join(x for x in (lo, hi) if x)})")
        return v

    # -- reading -----------------------------------------------------------------------------------
    def read(self) -> UsdScene:
        stage = self.stage
        if not stage.HasAuthoredMetadata("metersPerUnit"):
            raise self.err(None, "metersPerUnit is not authored (allowed: any positive number, e.g. metersPerUnit = 1 "
                                 "for metres; USD's fallback of 0.01 - centimetres - is not assumed)")
        if not stage.HasAuthoredMetadata("upAxis"):
            raise self.err(None, "upAxis is not authored (allowed: \"Z\" or \"Y\"; USD's fallback is not assumed)")
        mpu = float(self.finite(None, "metersPerUnit", UsdGeom.GetStageMetersPerUnit(stage)))
        if mpu <= 0.0:
            raise self.err(None, f"metersPerUnit = {mpu:g} (allowed: > 0)")
        up = str(UsdGeom.GetStageUpAxis(stage))
        if up not in ("Z", "Y"):
            raise self.err(None, f"upAxis = {up} is not supported (allowed: Z, Y)")
        kpu = float(self.finite(None, "kilogramsPerUnit", UsdPhysics.GetStageKilogramsPerUnit(stage)))
        if kpu <= 0.0:
            raise self.err(None, f"kilogramsPerUnit = {kpu:g} (allowed: > 0)")
        self.mpu, self.kpu = mpu, kpu
        self.world_rot = _ROTATE_Y_UP_TO_Z_UP if up == "Y" else np.eye(3)
        self.up_axis = up
        self.gravity: tuple[float, float, float] | None = None
        self.entities: list[Entity] = []
        self.statics: dict[str, Entity] = {}
        self.walk(stage.GetPseudoRoot(), owner=None, component=None)

        by_name: dict[str, Entity] = {}
        for e in sorted(self.entities, key=lambda e: self.order[e.path]):
            if e.name in by_name:
                raise self.err(e.path, f"entity name {e.name!r} is also the name of {by_name[e.name].path} "
                                       "(allowed: one entity per prim name; rename one of the prims)")
            if e.kind in ("rigid", "kinematic"):
                self.finish_body(e)
            if e.color is None:
                e.color = next((s.color for s in e.shapes if s.color is not None), None)
            by_name[e.name] = e
        return UsdScene(path=os.path.abspath(self.file), meters_per_unit=mpu, up_axis=up, kilograms_per_unit=kpu,
                        gravity=self.gravity, entities=by_name)

    def walk(self, prim: Usd.Prim, owner: Entity | None, component: Usd.Prim | None) -> None:
        children = prim.GetFilteredChildren(Usd.TraverseInstanceProxies(Usd.PrimDefaultPredicate))
        for child in children:
            self.order[str(child.GetPath())] = len(self.order)
            self.visit(child, owner, component)

    def visit(self, prim: Usd.Prim, owner: Entity | None, component: Usd.Prim | None) -> None:
        type_name = str(prim.GetTypeName())
        if prim.IsA(UsdPhysics.Scene):
            if self.gravity is None:
                self.gravity = self.read_gravity(prim)
            return
        if prim.IsA(UsdGeom.PointInstancer):
            for p in Usd.PrimRange(prim, Usd.TraverseInstanceProxies(Usd.PrimDefaultPredicate)):
                if p.HasAPI(UsdPhysics.CollisionAPI) or p.HasAPI(UsdPhysics.RigidBodyAPI):
                    raise self.err(p, f"physics in a PointInstancer ({prim.GetPath()}) is not supported (allowed "
                                      f"collider prim types: {', '.join(SUPPORTED_COLLIDERS)}, as plain prims)")
            return
        robot_attr = prim.GetAttribute(ROBOT_FILE_ATTR)
        if robot_attr and robot_attr.HasAuthoredValue():
            if owner is not None:
                raise self.err(prim, f"{ROBOT_FILE_ATTR} inside the rigid body {owner.path} is not supported "
                                     "(allowed: a robot prim outside every rigid body)")
            self.entities.append(self.read_robot(prim, robot_attr))
            return  # the robot's subtree is the robot's
        if prim.HasAPI(UsdPhysics.ArticulationRootAPI):
            raise self.err(prim, f"PhysicsArticulationRootAPI without {ROBOT_FILE_ATTR} is not supported (allowed: a "
                                 f"robot prim with `asset {ROBOT_FILE_ATTR} = @robot.xml@`, an MJCF or URDF file)")
        if prim.IsA(UsdPhysics.Joint):
            raise self.err(prim, f"{type_name} outside a robot prim is not supported (allowed: joints inside the "
                                 f"robot file that {ROBOT_FILE_ATTR} names)")
        if prim.HasAPI(UsdPhysics.RigidBodyAPI):
            body = UsdPhysics.RigidBodyAPI(prim)
            enabled = self.get(prim, body.GetRigidBodyEnabledAttr())
            kinematic = self.get(prim, body.GetKinematicEnabledAttr())
            for attr, unit in ((body.GetVelocityAttr(), "units/s"), (body.GetAngularVelocityAttr(), "deg/s")):
                v = self.get(prim, attr, authored_only=True)
                if v is not None and np.any(self.finite(prim, attr.GetName(), v) != 0.0):
                    raise self.err(prim, f"{attr.GetName()} = {tuple(v)} {unit} is not supported (allowed: 0; "
                                         "Kestrel's scenario sets initial velocities)")
            if enabled is False:
                owner = self.static_entity(prim)
            else:
                kind = "kinematic" if kinematic else "rigid"
                pos, rot, _ = self.pose(prim)
                owner = Entity(name=prim.GetName(), path=str(prim.GetPath()), kind=kind, position=pos,
                               orientation=rot, color=self.color(prim))
                self.frames[owner.path] = self.frame(prim)
                self.entities.append(owner)
        elif owner is None and Kind.Registry.IsA(Usd.ModelAPI(prim).GetKind() or "", Kind.Tokens.component):
            component = prim
        if prim.HasAPI(UsdPhysics.CollisionAPI):
            coll = UsdPhysics.CollisionAPI(prim)
            if self.get(prim, coll.GetCollisionEnabledAttr()) is not False:
                target = owner if owner is not None else self.static_entity(component if component is not None else prim)
                target.shapes.append(self.read_shape(prim, target))
        self.walk(prim, owner, component)

    def static_entity(self, prim: Usd.Prim) -> Entity:
        key = str(prim.GetPath())
        if key not in self.statics:
            pos, rot, _ = self.pose(prim)
            e = Entity(name=prim.GetName(), path=key, kind="static", position=pos, orientation=rot,
                       color=self.color(prim))
            self.frames[key] = self.frame(prim)
            self.statics[key] = e
            self.entities.append(e)
        return self.statics[key]

    # -- transforms ------------------------------------------------------------------------------
    def check_xform_ops(self, prim: Usd.Prim) -> None:
        """Every op of the prim and its ancestors: a UsdGeom op type, authored, finite."""
        p = prim
        while p and not p.IsPseudoRoot():
            key = str(p.GetPath())
            if key in self.checked_xforms:
                break
            self.checked_xforms.add(key)
            xf = UsdGeom.Xformable(p)
            if xf:
                order = xf.GetXformOpOrderAttr().Get() or []
                for token in order:
                    name = str(token)
                    if name == "!resetXformStack!":
                        continue
                    name = name.removeprefix("!invert!")
                    parts = name.split(":")
                    if len(parts) < 2 or parts[0] != "xformOp" or parts[1] not in ALLOWED_XFORM_OPS:
                        raise self.err(p, f"{name} is not supported (allowed ops: {', '.join(ALLOWED_XFORM_OPS)})")
                    attr = p.GetAttribute(name)
                    if not attr or not attr.HasAuthoredValue():
                        raise self.err(p, f"{name} is listed in xformOpOrder but has no value (allowed: "
                                          "an authored value for every listed op)")
                    self.finite(p, name, self.get(p, attr))
            p = p.GetParent()

    def world_matrix(self, prim: Usd.Prim) -> tuple[np.ndarray, np.ndarray]:
        """(linear 3x3 acting on column vectors, translation) of the prim's local-to-world, in the
        stage's units and axes."""
        self.check_xform_ops(prim)
        m = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode.Default()) if UsdGeom.Xformable(prim) \
            else Gf.Matrix4d(1.0)
        a = np.array(m, dtype=np.float64)  # row-vector convention: p_world = p_local @ a[:3, :3] + a[3, :3]
        self.finite(prim, "its local-to-world transform", a)
        return a[:3, :3].T.copy(), a[3, :3].copy()

    def decompose(self, prim: Usd.Prim, lin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """lin = rotation @ diag(scale): refuses shear and mirroring."""
        scale = np.linalg.norm(lin, axis=0)
        if np.any(scale < 1e-12):
            raise self.err(prim, f"its xform stack has a zero scale ({_fmt(scale)}) (allowed: scales > 0)")
        rot = lin / scale
        gram = rot.T @ rot
        if np.max(np.abs(gram - np.eye(3))) > 1e-6:
            raise self.err(prim, "its xform stack has shear (a non-uniform scale under a rotation, or a sheared "
                                 "xformOp:transform) (allowed: scales along the prim's own axes)")
        if np.linalg.det(rot) < 0.0:
            raise self.err(prim, f"its xform stack mirrors (a negative scale) (allowed: scales > 0)")
        return rot, scale

    def frame(self, prim: Usd.Prim) -> tuple[np.ndarray, np.ndarray]:
        """The prim's world rotation and translation (stage units and axes), its scale dropped."""
        lin, t = self.world_matrix(prim)
        rot, _ = self.decompose(prim, lin)
        return rot, t

    def pose(self, prim: Usd.Prim):
        rot, t = self.frame(prim)
        pos = _clean(self.world_rot @ t * self.mpu)
        return pos, _clean(_quat_xyzw(self.world_rot @ rot)), rot

    # -- entities ----------------------------------------------------------------------------------
    def read_robot(self, prim: Usd.Prim, attr: Usd.Attribute) -> Entity:
        value = self.get(prim, attr)
        if not isinstance(value, Sdf.AssetPath):
            raise self.err(prim, f"{ROBOT_FILE_ATTR} is a {attr.GetTypeName()} (allowed: an asset path, "
                                 f"`asset {ROBOT_FILE_ATTR} = @robot.xml@`)")
        rel = value.path
        if not rel.lower().endswith(ROBOT_FILE_SUFFIXES):
            raise self.err(prim, f"{ROBOT_FILE_ATTR} = @{rel}@ is not a robot model file (allowed suffixes: "
                                 f"{', '.join(ROBOT_FILE_SUFFIXES)})")
        resolved = value.resolvedPath
        if not resolved:  # resolution needs the file to exist; anchor it to the layer that says it
            spec = attr.GetPropertyStack(Usd.TimeCode.Default())
            layer = spec[0].layer if spec else self.stage.GetRootLayer()
            resolved = rel if os.path.isabs(rel) else os.path.join(os.path.dirname(layer.realPath), rel)
        lin, _ = self.world_matrix(prim)
        _, scale = self.decompose(prim, lin)
        if np.max(np.abs(scale - 1.0)) > 1e-6:
            raise self.err(prim, f"a scale of {_fmt(scale)} on the robot prim is not supported (allowed: 1; the "
                                 "robot file sets the robot's size)")
        pos, rot, _ = self.pose(prim)
        return Entity(name=prim.GetName(), path=str(prim.GetPath()), kind="robot", position=pos, orientation=rot,
                      color=self.color(prim), robot_file=os.path.normpath(os.path.abspath(resolved)))

    def finish_body(self, e: Entity) -> None:
        if not e.shapes:
            raise self.err(e.path, "PhysicsRigidBodyAPI without a collider (allowed: a rigid body with "
                                   "PhysicsCollisionAPI on itself or on prims below it)")
        prim = self.stage.GetPrimAtPath(e.path)
        mass_api = UsdPhysics.MassAPI(prim) if prim.HasAPI(UsdPhysics.MassAPI) else None
        body_density = None
        if mass_api is not None:
            mass = self.scalar(prim, mass_api.GetMassAttr(), authored_only=True, minimum=0.0)
            body_density = self.scalar(prim, mass_api.GetDensityAttr(), authored_only=True, minimum=0.0)
            com = self.get(prim, mass_api.GetCenterOfMassAttr(), authored_only=True)
            if com is not None and not np.all(np.asarray(com, dtype=np.float64) == -np.inf):  # -inf: unset
                c = self.finite(prim, "physics:centerOfMass", com)
                _, scale = self.decompose(prim, self.world_matrix(prim)[0])
                e.center_of_mass = _clean(c * scale * self.mpu)
            inertia = self.get(prim, mass_api.GetDiagonalInertiaAttr(), authored_only=True)
            if inertia is not None and np.any(self.finite(prim, "physics:diagonalInertia", inertia) != 0.0):
                e.diagonal_inertia = _clean(np.asarray(inertia) * self.kpu * self.mpu**2)
                axes = self.get(prim, mass_api.GetPrincipalAxesAttr(), authored_only=True)
                if axes is not None:
                    im = axes.GetImaginary()
                    q = self.finite(prim, "physics:principalAxes", [im[0], im[1], im[2], axes.GetReal()])
                    e.principal_axes = _clean(q / np.linalg.norm(q) if np.linalg.norm(q) > 0 else (0, 0, 0, 1))
            if mass:
                e.mass = mass * self.kpu
                return
        density_scale = self.kpu / self.mpu**3
        total = 0.0
        for s in e.shapes:
            if s.mass:
                total += s.mass
                continue
            density = next((d for d in (s.density, body_density and body_density * density_scale,
                                        s.material.density) if d), DEFAULT_DENSITY)
            volume = s.volume()
            if volume <= 0.0:
                raise self.err(s.path, "a mesh that encloses no volume gives no mass from a density (allowed: "
                                       "physics:mass on the body or the shape, PhysicsMassAPI)")
            total += density * volume
        e.mass = total

    def read_gravity(self, prim: Usd.Prim) -> tuple[float, float, float]:
        scene = UsdPhysics.Scene(prim)
        d = self.finite(prim, "physics:gravityDirection", self.get(prim, scene.GetGravityDirectionAttr()))
        mag = _f32(float(np.asarray(self.get(prim, scene.GetGravityMagnitudeAttr()), dtype=np.float64)))
        if math.isnan(mag) or mag == math.inf:
            raise self.err(prim, f"physics:gravityMagnitude = {mag} is not finite (allowed: finite numbers, or "
                                 "-inf for the default of 9.81 m/s^2)")
        g = EARTH_GRAVITY if mag == -math.inf else mag * self.mpu
        n = np.linalg.norm(d)
        direction = np.array([0.0, 0.0, -1.0]) if n == 0.0 else self.world_rot @ (d / n)
        return _clean(direction * g)

    # -- shapes ------------------------------------------------------------------------------------
    def read_shape(self, prim: Usd.Prim, entity: Entity) -> Shape:
        type_name = str(prim.GetTypeName())
        if type_name not in SUPPORTED_COLLIDERS:
            raise self.err(prim, f"PhysicsCollisionAPI on a {type_name or 'typeless prim'} is not supported "
                                 f"(allowed collider prim types: {', '.join(SUPPORTED_COLLIDERS)})")
        kind = SUPPORTED_COLLIDERS[type_name]
        e_rot, e_t = self.frames[entity.path]
        lin, t = self.world_matrix(prim)
        rel_rot, scale = self.decompose(prim, e_rot.T @ lin)
        rel_t = e_rot.T @ (t - e_t) * self.mpu
        scale = scale * self.mpu  # stage units -> metres, folded into the sizes
        shape = Shape(type=kind, path=str(prim.GetPath()), position=_clean(rel_t), orientation=_clean(_quat_xyzw(rel_rot)),
                      material=self.material(prim), color=self.color(prim))
        if prim.HasAPI(UsdPhysics.MassAPI):
            mapi = UsdPhysics.MassAPI(prim)
            m = self.scalar(prim, mapi.GetMassAttr(), authored_only=True, minimum=0.0)
            d = self.scalar(prim, mapi.GetDensityAttr(), authored_only=True, minimum=0.0)
            shape.mass = m * self.kpu if m else None
            shape.density = d * self.kpu / self.mpu**3 if d else None
        if kind == "box":
            size = self.scalar(prim, UsdGeom.Cube(prim).GetSizeAttr(), minimum=0.0, strict=True)
            shape.half_extents = _clean(0.5 * size * scale)
        elif kind == "sphere":
            r = self.scalar(prim, UsdGeom.Sphere(prim).GetRadiusAttr(), minimum=0.0, strict=True)
            self.uniform(prim, scale, (0, 1, 2), "Sphere")
            shape.radius = float(r * scale[0])
        elif kind in ("capsule", "cylinder"):
            g = UsdGeom.Capsule(prim) if kind == "capsule" else UsdGeom.Cylinder(prim)
            r = self.scalar(prim, g.GetRadiusAttr(), minimum=0.0, strict=True)
            h = self.scalar(prim, g.GetHeightAttr(), minimum=0.0, strict=(kind == "cylinder"))
            axis = str(self.get(prim, g.GetAxisAttr()))
            if axis not in ("X", "Y", "Z"):
                raise self.err(prim, f"axis = {axis} is not supported (allowed: X, Y, Z)")
            i = "XYZ".index(axis)
            radial = tuple(j for j in range(3) if j != i)
            self.uniform(prim, scale, radial, type_name)
            shape.radius, shape.height, shape.axis = float(r * scale[radial[0]]), float(h * scale[i]), axis
        else:
            self.read_mesh(prim, shape, scale)
        return shape

    def uniform(self, prim, scale, axes, type_name) -> None:
        s = scale[list(axes)]
        if np.max(s) - np.min(s) > 1e-9 * max(1.0, float(np.max(s))):
            raise self.err(prim, f"a non-uniform scale ({_fmt(scale / self.mpu)}) on a {type_name} is not supported "
                                 f"(allowed: equal scales along axes {', '.join('XYZ'[a] for a in axes)})")

    def read_mesh(self, prim: Usd.Prim, shape: Shape, scale: np.ndarray) -> None:
        mesh = UsdGeom.Mesh(prim)
        points = self.get(prim, mesh.GetPointsAttr())
        counts = self.get(prim, mesh.GetFaceVertexCountsAttr())
        indices = self.get(prim, mesh.GetFaceVertexIndicesAttr())
        if points is None or counts is None or indices is None or len(points) == 0 or len(counts) == 0:
            raise self.err(prim, "a Mesh collider needs points, faceVertexCounts and faceVertexIndices (allowed: "
                                 "a non-empty polygon mesh)")
        holes = self.get(prim, mesh.GetHoleIndicesAttr(), authored_only=True)
        if holes is not None and len(holes) > 0:
            raise self.err(prim, "holeIndices is not supported (allowed: an empty holeIndices)")
        pts = self.finite(prim, "points", points).reshape(-1, 3)
        counts = np.asarray(counts, dtype=np.int64)
        indices = np.asarray(indices, dtype=np.int64)
        if np.any(counts < 3):
            raise self.err(prim, f"faceVertexCounts has a face of {int(counts.min())} vertices (allowed: >= 3)")
        if int(counts.sum()) != len(indices):
            raise self.err(prim, f"faceVertexCounts sums to {int(counts.sum())} but faceVertexIndices has "
                                 f"{len(indices)} entries (allowed: equal)")
        if np.any(indices < 0) or np.any(indices >= len(pts)):
            raise self.err(prim, f"faceVertexIndices has an index outside 0..{len(pts) - 1} (allowed: indices of points)")
        tris = []
        start = 0
        for n in counts:  # fan from each face's first vertex
            f = indices[start:start + n]
            tris.extend((f[0], f[k], f[k + 1]) for k in range(1, n - 1))
            start += n
        triangles = np.array(tris, dtype=np.int64).reshape(-1, 3)
        if str(self.get(prim, mesh.GetOrientationAttr())) == "leftHanded":
            triangles = triangles[:, [0, 2, 1]]
        shape.vertices = pts * scale
        shape.triangles = triangles
        approx = "none"
        if prim.HasAPI(UsdPhysics.MeshCollisionAPI):
            approx = str(self.get(prim, UsdPhysics.MeshCollisionAPI(prim).GetApproximationAttr()))
        shape.approximation = approx

    # -- materials and colours -------------------------------------------------------------------
    def material(self, prim: Usd.Prim) -> Material:
        mat, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial(_MATERIAL_PURPOSE)
        if not mat or not mat.GetPrim().HasAPI(UsdPhysics.MaterialAPI):
            return DEFAULT_MATERIAL
        mprim = mat.GetPrim()
        api = UsdPhysics.MaterialAPI(mprim)
        sf = self.scalar(mprim, api.GetStaticFrictionAttr(), minimum=0.0)
        df = self.scalar(mprim, api.GetDynamicFrictionAttr(), minimum=0.0)
        rest = self.scalar(mprim, api.GetRestitutionAttr(), minimum=0.0, maximum=1.0)
        dens = self.scalar(mprim, api.GetDensityAttr(), authored_only=True, minimum=0.0)
        return Material(str(mprim.GetPath()), sf, df, rest, dens * self.kpu / self.mpu**3 if dens else None)

    def color(self, prim: Usd.Prim) -> tuple[float, float, float] | None:
        pv = UsdGeom.PrimvarsAPI(prim).FindPrimvarWithInheritance("displayColor")
        if not pv or not pv.HasAuthoredValue():
            return None
        value = pv.Get(Usd.TimeCode.Default())
        if value is None or len(value) == 0:
            return None
        c = self.finite(prim, "primvars:displayColor", value).reshape(-1, 3)
        return _clean(_f32(x) for x in (c[0] if np.all(c == c[0]) else c.mean(axis=0)))


def _fmt(v: np.ndarray) -> str:
    return "(" + ", ".join(f"{float(x):g}" for x in v) + ")"
