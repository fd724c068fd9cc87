#!/usr/bin/env python3
"""Regenerates the committed seed corpora (tests/fuzz/corpus/<target>/) from the repository's own
scenarios and data files and the reproducers of the first campaign (docs/notes/fuzz.md,
F1-F8; the data files are tests/sim/data/fuzz_*). Run from anywhere; overwrites the corpora.
Harness input formats: see the comment at the top of each fuzz_*.cpp."""
import glob, os, shutil, struct

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
OUT = os.path.join(ROOT, "tests", "fuzz", "corpus")
DATA = os.path.join(ROOT, "tests", "sim", "data")


def put(target, name, data):
    d = os.path.join(OUT, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def read(p):
    with open(p, "rb") as f:
        return f.read()


shutil.rmtree(OUT, ignore_errors=True)

# --- scenario: the repository's scenarios, then hand-written seeds for each input surface.
for p in sorted(glob.glob(os.path.join(ROOT, "sim", "scenarios", "*.yaml")) +
                glob.glob(os.path.join(ROOT, "tests", "sim", "*.yaml")) +
                [os.path.join(ROOT, "tests", "firmware", "base_quadrotor.yaml")]):
    put("fuzz_scenario", os.path.relpath(p, ROOT).replace("/", "_"), read(p))
seeds = {
    # F2: obstacle 1e9 m out (now refused by load_mesh's coordinate bound); F3: 5e22 m long hull.
    "f2_far_mesh_obstacle.yaml": "env: {name: empty, num_envs: 1, assets: [{name: m, kind: mesh, mesh_file: fuzz_f2_far.obj, "
                                 "num_assets: 2, max_angular_speed_rad_s: 1}]}\nrobot: base_quadrotor\n",
    "f2_far_cube.yaml": "env: {name: empty, num_envs: 1, assets: [{name: c, kind: cube, num_assets: 1, min_size_m: [1e8, 1, 1], "
                        "max_size_m: [1e8, 1, 1]}]}\nrobot: base_quadrotor\n",
    "f3_long_mesh_obstacle.yaml": "env: {name: empty, num_envs: 1, assets: [{name: m, kind: mesh, mesh_file: fuzz_f3_long.obj, "
                                  "num_assets: 2, max_angular_speed_rad_s: 1}]}\nrobot: base_quadrotor\n",
    # F4: height maps whose header asks for 17 GB / 1 TB.
    "f4_huge_pgm.yaml": "env: {name: empty, num_envs: 1, terrain: {type: heightfield, image_file: fuzz_f4_huge.pgm}}\n",
    "f4_huge_png.yaml": "env: {name: empty, num_envs: 1, terrain: {type: heightfield, image_file: fuzz_f4_huge.png}}\n",
    # F5: counts without an upper bound (now field errors).
    "f5_robots_per_env.yaml": "robot: {name: base_quadrotor, robots_per_env: 2000000000}\n",
    "f5_cubes.yaml": "env: {name: empty, assets: [{name: c, kind: cube, num_assets: 200000000}]}\n",
    "f5_trees.yaml": "env: {name: empty, assets: [{name: t, kind: tree, num_assets: 600000000}]}\n",
    "f5_substeps.yaml": "sim: {name: base_sim, substeps: 2000000000}\n",
    # Other surfaces: URDF robot, PGM/PNG terrain, trimesh terrain, mesh asset, procedural, planar.
    "urdf_robot.yaml": "env: {name: empty, num_envs: 2}\nrobot: {name: base_quadrotor, urdf: quad.urdf, robots_per_env: 2}\n",
    "pgm_terrain.yaml": "env: {name: empty, num_envs: 1, terrain: {type: heightfield, image_file: heightmap.pgm, "
                        "horizontal_scale_m: 0.5, vertical_scale_m: 0.01, measure_heights: true}}\n",
    "png_terrain.yaml": "env: {name: empty, num_envs: 1, terrain: {type: heightfield, image_file: heightmap16.png, "
                        "vertical_scale_m: 0.0001}}\n",
    "trimesh_terrain.yaml": "env: {name: empty, num_envs: 1, terrain: {type: trimesh, mesh_file: slope_terrain.obj}}\n",
    "mesh_asset.yaml": "env: {name: empty, num_envs: 2, assets: [{name: r, kind: mesh, mesh_file: rock.obj, num_assets: 3}]}\n",
    "procedural.yaml": "env: {name: empty, num_envs: 1, terrain: {type: heightfield, procedural: pyramid_stairs, "
                       "length_x_m: 6, width_y_m: 6}}\nrobot: {name: base_quadrotor}\n",
    "heights_list.yaml": "env: {name: empty, num_envs: 1, terrain: {type: heightfield, nx: 2, ny: 2, heights_m: [[0, 0.1], [0.2, 0.3]]}}\n",
    "planar_lidar.yaml": "simulator: {name: planar, vehicle: multirotor, lidar_beams: 16}\nenv: {name: planar_obstacles, num_envs: 2}\n",
    "planar_car.yaml": "simulator: planar\nenv: {name: planar_obstacles, num_envs: 2}\nrobot: ground_vehicle\n",
    "sensors.yaml": "env: {name: forest, num_envs: 1}\nsensors: [imu, {name: depth_camera, every: 4}]\n",
}
for n, t in seeds.items():
    put("fuzz_scenario", n, t)

# --- urdf
put("fuzz_urdf", "quad.urdf", read(os.path.join(DATA, "quad.urdf")))
put("fuzz_urdf", "box_body.urdf", """<robot name="b"><link name="base_link"><inertial><mass value="0.5"/>
<inertia ixx="0.01" iyy="0.01" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial>
<collision><geometry><box size="0.3 0.3 0.1"/></geometry></collision></link></robot>
""")
put("fuzz_urdf", "tiny_mass.urdf", """<robot name="t"><link name="base_link"><inertial><mass value="1e-40"/>
<inertia ixx="1e-3" iyy="1e-3" izz="1e-3" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>
""")

# --- mesh: byte 0 even = .obj, odd = .STL
for n in ("rock.obj", "slope_terrain.obj", "fuzz_f2_far.obj", "fuzz_f3_long.obj"):
    put("fuzz_mesh", n, b"\x00" + read(os.path.join(DATA, n)))
put("fuzz_mesh", "ascii.stl", b"\x01solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
    b"endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0.2\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n")
tris = [((0, 0, 0), (1, 0, 0), (0, 1, 0)), ((1, 0, 0), (1, 1, 0.5), (0, 1, 0)), ((0, 0, 0), (0, 1, 0), (0, 0, 1))]
stl = b"kestrel binary stl".ljust(80, b" ") + struct.pack("<I", len(tris))
for t in tris:
    stl += struct.pack("<3f", 0, 0, 1) + b"".join(struct.pack("<3f", *v) for v in t) + b"\0\0"
put("fuzz_mesh", "binary.stl", b"\x01" + stl)
# Found by the first regression run: denormal coordinates -> centroid extent ~1e-40, bin scale inf,
# 0 * inf = NaN converted to int in sensors/src/bvh.cpp (UBSan). Kept as found.
put("fuzz_mesh", "bvh_denormal_extent.stl", bytes.fromhex(
    "016b65737472656c2062696e6172792001016b65737472656c2062696e6172792073746c2020202020202020206b65737472"
    "656c2062696e6172792073746c2020202020202020202020202020202020200300000000000000000000000000803f000000"
    "00000000803f0000803f0000003f00020000000000803f00000000000000000000000000000000803f000000000000000000"
    "0000003f000200000000803f0000000000000000003f000000000000803f00000000000000000000000000000000803f0000"
    "00000000000000000000000000000000803f00000000000000000000000000803f0000"))

# --- heightmap: byte 0 bit 0 = .png, bits 1-3 / 4-6 the scales
for n in ("heightmap.pgm", "fuzz_f4_huge.pgm"):
    put("fuzz_heightmap", n, b"\x00" + read(os.path.join(DATA, n)))
for n in ("heightmap16.png", "rgb.png", "fuzz_f4_huge.png"):
    put("fuzz_heightmap", n, b"\x01" + read(os.path.join(DATA, n)))
put("fuzz_heightmap", "p2.pgm", b"\x12P2\n3 2\n255\n0 10 20\n30 40 255\n")
put("fuzz_heightmap", "p5_16bit.pgm", b"\x24P5\n2 2\n65535\n" + bytes([0, 1, 255, 255, 16, 0, 0, 0]))

# --- capi: [preset][mask] records: 0 state(13 f) | 1 comp(idx, f) | 2 setpoint(mode, 4 f) | 3 dt(f)
#     | 4 motor failure(motor, f) | 5 clear | 6 pwm(3 f) | 7 step(count-1). Float: tag < 0x80 = table
#     (0 0, 1 1, 2 -1, 3 0.5, 4 NaN, 5 inf, 6 -inf, 7 FLT_MAX, 8 -FLT_MAX, 9 FLT_MIN, 10 1e-40, 11 1e10,
#     12 1e30, 13 -1e30, 14 0.01, 15 9.81), tag >= 0x80 = the next 4 bytes.
def raw(x):
    return b"\x80" + struct.pack("<f", x)

STEP4 = b"\x07\x03"
put("fuzz_capi", "hover_steps", b"\x00\x00" + STEP4 * 4)
put("fuzz_capi", "f1_angvel_3p4e38", b"\x00\x00" + b"\x01\x0a" + raw(3.4e38) + STEP4 + b"\x01\x0a\x00" + STEP4)
put("fuzz_capi", "f1_gain_1e37", b"\x00\x20" + b"\x01\x01" + raw(1e37) + b"\x01\x0c" + raw(10.0) + STEP4)
put("fuzz_capi", "f1_motor_model_nan_setpoint", b"\x00\x80\x01" + b"\x01\x0a" + raw(3.4e38) + STEP4 +
    b"\x02\x00\x04\x00\x01\x00" + STEP4)
put("fuzz_capi", "f6_dt_1e18", b"\x01\x00" + b"\x03" + raw(1e18) + STEP4 + b"\x03\x0e" + STEP4)
put("fuzz_capi", "f7_zero_quat", b"\x00\x00" + b"\x01\x06\x00" + STEP4 + b"\x01\x06" + raw(1000.0) + STEP4)
put("fuzz_capi", "modes_failure_pwm", b"\x02\x00" + b"\x02\x01\x01\x00\x00\x00" + STEP4 + b"\x02\x02\x00\x03\x00\x00" + STEP4 +
    b"\x02\x03\x00\x00\x00\x01" + STEP4 + b"\x04\x01\x00" + STEP4 + b"\x05" + b"\x06\x03" + raw(1000.0) + raw(2000.0) + STEP4)
put("fuzz_capi", "bad_params", b"\x00\x07" + b"\x00" + b"\x04\x01\x01" + STEP4)
