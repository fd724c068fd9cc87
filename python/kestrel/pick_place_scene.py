"""A USD scene mapped onto so101_pick_place's scene keys (``task.pick_place``), the way LeIsaac
ties its SO-101 pick-and-place task to a USD scene.

    from kestrel.pick_place_scene import pick_place_keys_from_usd
    pick_place_keys_from_usd("models/so101/pick_place_scene.usda")
    # {"robot_file": ".../so101.xml", "cube_half_m": 0.0125, "cube_mass_kg": 0.011, ...}

    env = kestrel.make_vec("Kestrel-SO101-PickPlace-v0", num_envs=8, scene="models/so101/pick_place_scene.usda")
    # or, in any scenario dict given to kestrel.scenario / make_task / make_vec:
    #   task: {name: so101_pick_place, pick_place: {scene_file: models/so101/pick_place_scene.usda}}

The scene is read by ``kestrel.usd_scene.load_usd_scene`` and must be the task's scene: a robot, a
table, one cube and one open box, nothing else. Mapping rules (positions in the robot's base frame:
the robot's spawn position is subtracted from every entity's; its orientation must be the identity,
facing +x):

* robot: the one entity of kind ``robot`` (``kestrel:robotFile``) -> ``robot_file``; the world's
  arm needs the SO-101's six joints (the C++ loader checks them).
* cube: the entity named ``Cube`` (any case), else the one ``rigid`` entity: one box collider
  (USD ``Cube``) with three equal half extents, centred on the entity, axis-aligned, resting on
  the table (centre z = half side) -> ``cube_half_m``, ``cube_mass_kg`` (the entity's mass),
  ``cube_friction`` (its static friction), ``cube_pos_w`` (x, y, 0).
* box: the entity named ``Box``, else the one ``static`` entity of five box colliders: a floor and
  four walls, all axis-aligned and standing on the table (bottom faces at z = 0), the walls as
  thick as the floor and all of one thickness (``box_wall_m``), of one height (``box_height_m``),
  the +-x and +-y walls at the same inner half side (``box_inner_half_m``: a square box, inner
  faces at centre +- inner half); each wall spans the inner side (its long half extent between
  the inner half and the inner half + wall) and the floor lies under the inside (its half side
  between the inner half and the outer half). Its floor's centre -> ``box_pos_w`` (x, y, 0); its
  parts' common static friction -> ``box_friction``. (The C++ world's floor always spans the
  outer footprint and its +-x walls the outer side; within a wall's thickness that is the same box.)
* table: the entity named ``Table``, else the one other ``static`` entity: one axis-aligned box
  collider whose top face is z = 0 (the robot's base height) -> ``table_friction`` (the C++ table
  is the infinite plane z = 0).
* gravity: a PhysicsScene's gravity must be 9.81 m/s^2 down (the world's), or absent.

Everything else keeps the task's defaults (gains, time step, randomize_xy_m, success rule, ...).
Anything the world cannot represent raises ``UsdSceneError`` naming the file, the prim and what is
expected: a sphere for the cube, no box, a table top off z = 0, walls of different thickness, a
second movable object, a rotated robot, ...
"""

from __future__ import annotations

import os
from typing import Any

from .usd_scene import Entity, UsdScene, UsdSceneError, load_usd_scene

__all__ = ["pick_place_keys_from_usd", "pick_place_keys_from_scene", "SCENE_KEYS"]

# The task.pick_place keys a scene sets.
SCENE_KEYS = ("robot_file", "cube_half_m", "cube_mass_kg", "cube_friction", "cube_pos_w", "box_pos_w", "box_inner_half_m",
              "box_wall_m", "box_height_m", "box_friction", "table_friction")
TOL_M = 1e-5  # geometric agreement (USD stores float32 orientations and often float32 sizes)
GRAVITY = 9.81


def pick_place_keys_from_usd(path: str | os.PathLike) -> dict[str, Any]:
    """The task.pick_place keys of the scene in the USD file at path (see the module's rules)."""
    return pick_place_keys_from_scene(load_usd_scene(path))


def _identity(q) -> bool:
    x, y, z, w = q
    return abs(abs(w) - 1.0) < 1e-6 and max(abs(x), abs(y), abs(z)) < 1e-5


def _fmt(v) -> str:
    return "(" + ", ".join(f"{float(a):.6g}" for a in v) + ")"


def pick_place_keys_from_scene(scene: UsdScene) -> dict[str, Any]:
    """The task.pick_place keys of a loaded UsdScene (see the module's rules)."""
    f = scene.path

    def err(prim: str, what: str) -> UsdSceneError:
        return UsdSceneError(f"{f}: prim {prim}: {what} (so101_pick_place's scene: kestrel/pick_place_scene.py)")

    ents = scene.entities
    if scene.gravity is not None:
        gx, gy, gz = scene.gravity
        if abs(gx) > 1e-6 or abs(gy) > 1e-6 or abs(gz + GRAVITY) > 1e-3:
            raise UsdSceneError(f"{f}: PhysicsScene: expected gravity 9.81 m/s^2 along -z (the world's), got {_fmt(scene.gravity)} m/s^2")

    # The robot: its base is the world's origin.
    robots = [e for e in ents.values() if e.kind == "robot"]
    if len(robots) != 1:
        raise UsdSceneError(f"{f}: expected exactly one robot (a prim with kestrel:robotFile, the SO-101), got "
                            f"{len(robots)}" + (f": {', '.join(e.path for e in robots)}" if robots else ""))
    robot = robots[0]
    if not _identity(robot.orientation):
        raise err(robot.path, f"expected the robot's base facing +x (orientation (x, y, z, w) = (0, 0, 0, 1): the task's "
                              f"world frame is the robot's base frame), got orientation {_fmt(robot.orientation)}")
    origin = robot.position

    def rel(p):
        return tuple(float(p[k] - origin[k]) for k in range(3))

    def by_name(name: str) -> Entity | None:
        hits = [e for e in ents.values() if e.name.lower() == name]
        return hits[0] if len(hits) == 1 else None

    def named_or_only(name: str, candidates: list[Entity], expected: str) -> Entity:
        """The entity called `name` (any case), else the one candidate; an error naming what was expected."""
        e = by_name(name)
        if e is not None:
            return e
        if len(candidates) != 1:
            raise UsdSceneError(f"{f}: expected {expected}, got {len(candidates)}"
                                + (f": {', '.join(c.path for c in candidates)}" if candidates else ""))
        return candidates[0]

    def boxes(e: Entity, role: str) -> list[tuple[str, tuple, tuple]]:
        """(path, centre in the robot frame, half extents) of e's shapes: boxes, axis-aligned."""
        if not _identity(e.orientation):
            raise err(e.path, f"expected the {role} axis-aligned (orientation identity), got orientation {_fmt(e.orientation)}")
        out = []
        for s in e.shapes:
            if s.type != "box":
                raise err(s.path, f"expected a box collider (USD Cube) for the {role}, got a {s.type}")
            if not _identity(s.orientation):
                raise err(s.path, f"expected the {role}'s box axis-aligned (no rotation), got orientation {_fmt(s.orientation)}")
            c = rel(tuple(e.position[k] + s.position[k] for k in range(3)))
            out.append((s.path, c, tuple(float(h) for h in s.half_extents)))
        return out

    # The cube: "Cube", else the only rigid entity.
    movable = [e for e in ents.values() if e.kind in ("rigid", "kinematic")]
    cube = named_or_only("cube", movable, "one movable object, the cube (an entity named Cube, or the only rigid body)")
    if cube.kind != "rigid":
        raise err(cube.path, f"expected the cube to be a dynamic rigid body (PhysicsRigidBodyAPI), got kind {cube.kind}")
    others = [e for e in movable if e is not cube]
    if others:
        raise err(others[0].path, "so101_pick_place has one movable object, the cube "
                                  f"({cube.path}); expected no other rigid or kinematic body")
    if len(cube.shapes) != 1:
        raise err(cube.path, f"expected the cube to be one box collider (USD Cube), got {len(cube.shapes)} colliders")
    if cube.shapes[0].type != "box":
        raise err(cube.shapes[0].path, f"expected the cube's collider to be a box (USD Cube), got a {cube.shapes[0].type}")
    (cpath, cc, ch), = boxes(cube, "cube")
    if max(ch) - min(ch) > TOL_M:
        raise err(cpath, f"expected a cube (three equal half extents), got half extents {_fmt(ch)} m")
    if any(abs(cube.shapes[0].position[k]) > TOL_M for k in range(3)):
        raise err(cpath, f"expected the cube's collider centred on its body, got offset {_fmt(cube.shapes[0].position)} m")
    half = ch[0]
    if abs(cc[2] - half) > 1e-4:
        raise err(cube.path, f"expected the cube resting on the table (centre z = half side {half:.6g} m above the robot's "
                             f"base), got z = {cc[2]:.6g} m")
    if cube.mass is None or not cube.mass > 0:
        raise err(cube.path, f"expected a positive mass, got {cube.mass}")
    cube_mu = cube.static_friction
    if cube_mu is None:
        raise err(cube.path, "expected one friction for the cube's collider")

    statics = [e for e in ents.values() if e.kind == "static"]
    # The box: "Box", else the static entity of five colliders.
    box = named_or_only("box", [e for e in statics if len(e.shapes) == 5],
                        "the open box: an entity named Box, or the only static entity of five box colliders (a floor and four walls)")
    if box.kind != "static":
        raise err(box.path, f"expected the box to be static (colliders without a rigid body), got kind {box.kind}")
    if len(box.shapes) != 5:
        raise err(box.path, f"expected the box as five box colliders (a floor and four walls), got {len(box.shapes)}")
    parts = boxes(box, "box")
    # The floor: the part lowest down; the walls: the rest, two along x and two along y of its centre.
    floor = min(parts, key=lambda p: p[1][2] + p[2][2])
    walls = [p for p in parts if p is not floor]
    fpath, fc, fh = floor
    w = 2.0 * fh[2]
    for path, c, h in parts:
        if abs(c[2] - h[2]) > 1e-4:
            raise err(path, f"expected the box's part standing on the table (bottom face z = 0), got bottom z = {c[2] - h[2]:.6g} m")
    xw = [p for p in walls if abs(p[1][1] - fc[1]) < TOL_M and abs(p[1][0] - fc[0]) > TOL_M]
    yw = [p for p in walls if abs(p[1][0] - fc[0]) < TOL_M and abs(p[1][1] - fc[1]) > TOL_M]
    if len(xw) != 2 or len(yw) != 2 or (xw[0][1][0] - fc[0]) * (xw[1][1][0] - fc[0]) > 0 or \
            (yw[0][1][1] - fc[1]) * (yw[1][1][1] - fc[1]) > 0:
        raise err(box.path, "expected a floor and four walls centred on the floor's centre line: one at -x, one at +x "
                            f"(same y as the floor), one at -y, one at +y (same x); floor {fpath} at {_fmt(fc)} m, walls at "
                            + ", ".join(_fmt(p[1]) for p in walls))
    inner = None
    height = None
    for axis, group in ((0, xw), (1, yw)):
        for path, c, h in group:
            t = 2.0 * h[axis]
            if abs(t - w) > TOL_M:
                raise err(path, f"expected every wall as thick as the floor ({w:.6g} m: so101_pick_place's box has one "
                                f"thickness), got {t:.6g} m")
            i = abs(c[axis] - fc[axis]) - h[axis]
            if inner is None:
                inner = i
            elif abs(i - inner) > TOL_M:
                raise err(path, f"expected a square box: every wall's inner face {inner:.6g} m from the centre, got {i:.6g} m")
            if height is None:
                height = 2.0 * h[2]
            elif abs(2.0 * h[2] - height) > TOL_M:
                raise err(path, f"expected every wall of one height ({height:.6g} m), got {2.0 * h[2]:.6g} m")
            along = h[1 - axis]
            if not (inner - TOL_M <= along <= inner + w + TOL_M):
                raise err(path, f"expected the wall to span the box's inner side (half length in [{inner:.6g}, "
                                f"{inner + w:.6g}] m), got {along:.6g} m")
    for k in range(2):
        if not (inner - TOL_M <= fh[k] <= inner + w + TOL_M):
            raise err(fpath, f"expected the floor under the box's inside (half side in [{inner:.6g}, {inner + w:.6g}] m), "
                             f"got half extents {_fmt(fh)} m")
    if not inner > 0 or not height > w:
        raise err(box.path, f"expected walls taller than the floor around a positive inside, got inner half {inner:.6g} m, "
                            f"height {height:.6g} m")
    box_mu = box.static_friction
    if box_mu is None:
        raise err(box.path, "expected one friction (physics material) for the box's five parts")

    # The table: "Table", else the one other static entity.
    rest = [e for e in statics if e is not box]
    table = named_or_only("table", rest, "the table: an entity named Table, or the only static entity besides the box")
    if table.kind != "static":
        raise err(table.path, f"expected the table to be static (a collider without a rigid body), got kind {table.kind}")
    extra = [e for e in rest if e is not table]
    if extra:
        raise err(extra[0].path, "so101_pick_place's scene is a table, a cube, a box and the robot; expected no other entity")
    if len(table.shapes) != 1:
        raise err(table.path, f"expected the table as one box collider, got {len(table.shapes)} colliders")
    (tpath, tc, th), = boxes(table, "table")
    top = tc[2] + th[2]
    if abs(top) > 1e-4:
        raise err(tpath, f"expected the table's top face at z = 0 (the robot's base height, {origin[2]:.6g} m in the file), "
                         f"got z = {top:.6g} m" + (" relative to the robot's base" if origin[2] != 0 else ""))
    table_mu = table.static_friction
    if table_mu is None:
        raise err(table.path, "expected one friction for the table")
    for what, (x, y) in (("cube", cc[:2]), ("box", fc[:2])):
        if not (abs(x - tc[0]) <= th[0] and abs(y - tc[1]) <= th[1]):
            raise err(cube.path if what == "cube" else box.path, f"expected the {what} on the table top "
                      f"(x in {tc[0] - th[0]:.6g}..{tc[0] + th[0]:.6g}, y in {tc[1] - th[1]:.6g}..{tc[1] + th[1]:.6g} m), "
                      f"got ({x:.6g}, {y:.6g})")

    def r(v: float) -> float:
        return float(round(v, 9))

    return {
        "robot_file": robot.robot_file,
        "cube_half_m": r(half),
        "cube_mass_kg": r(cube.mass),
        "cube_friction": r(cube_mu),
        "cube_pos_w": [r(cc[0]), r(cc[1]), 0.0],
        "box_pos_w": [r(fc[0]), r(fc[1]), 0.0],
        "box_inner_half_m": r(inner),
        "box_wall_m": r(w),
        "box_height_m": r(height),
        "box_friction": r(box_mu),
        "table_friction": r(table_mu),
    }


def expand_scene_file(d: dict) -> dict:
    """A scenario dict with task.pick_place.scene_file replaced by the keys the scene gives (the
    keys written beside scene_file win: they override the scene's). Other dicts are returned as is."""
    task = d.get("task")
    if not isinstance(task, dict):
        return d
    pp = task.get("pick_place")
    if not isinstance(pp, dict) or "scene_file" not in pp:
        return d
    pp = dict(pp)
    path = pp.pop("scene_file")
    if not isinstance(path, (str, os.PathLike)):
        raise ValueError(f"task.pick_place.scene_file: expected a USD file path, got {path!r}")
    keys = pick_place_keys_from_usd(path)
    keys.update(pp)
    out = dict(d)
    out["task"] = dict(task, pick_place=keys)
    return out

