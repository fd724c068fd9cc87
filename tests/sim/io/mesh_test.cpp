// Mesh loading (OBJ, ASCII and binary STL) on a known mesh, and mesh obstacles colliding as their
// convex hull: a unit cube loaded from each format must answer like the analytic box.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "kestrel/sim/collision.hpp"
#include "kestrel/sim/mesh.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/world.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {
// Unit cube [-0.5, 0.5]^3: 8 vertices, 12 triangles (6 quads).
const float kV[8][3] = {{-.5f, -.5f, -.5f}, {.5f, -.5f, -.5f}, {.5f, .5f, -.5f}, {-.5f, .5f, -.5f},
                        {-.5f, -.5f, .5f},  {.5f, -.5f, .5f},  {.5f, .5f, .5f},  {-.5f, .5f, .5f}};
const int kQuads[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {2, 3, 7, 6}, {1, 2, 6, 5}, {0, 4, 7, 3}};

std::string tmp(const char* name) { return std::string(::testing::TempDir()) + name; }

std::string write_obj() {
  const std::string p = tmp("cube.obj");
  std::ofstream f(p);
  f << "# cube\no cube\n";
  for (const auto& v : kV) f << "v " << v[0] << " " << v[1] << " " << v[2] << "\n";
  f << "vn 0 0 1\n";
  for (const auto& q : kQuads) f << "f " << q[0] + 1 << "//1 " << q[1] + 1 << "//1 " << q[2] + 1 << " " << q[3] - 8 << "\n";
  return p;  // the last index of each face is written relative (negative), the others 1-based
}
template <class Emit>
void each_triangle(Emit emit) {
  for (const auto& q : kQuads) {
    emit(kV[q[0]], kV[q[1]], kV[q[2]]);
    emit(kV[q[0]], kV[q[2]], kV[q[3]]);
  }
}
std::string write_ascii_stl() {
  const std::string p = tmp("cube_ascii.stl");
  std::ofstream f(p);
  f << "solid cube\n";
  each_triangle([&](const float* a, const float* b, const float* c) {
    f << " facet normal 0 0 0\n  outer loop\n";
    for (const float* v : {a, b, c}) f << "   vertex " << v[0] << " " << v[1] << " " << v[2] << "\n";
    f << "  endloop\n endfacet\n";
  });
  f << "endsolid cube\n";
  return p;
}
std::string write_binary_stl() {
  const std::string p = tmp("cube_binary.stl");
  std::ofstream f(p, std::ios::binary);
  char header[80] = {};
  std::strcpy(header, "solid but binary");  // binary files may start with "solid" too
  f.write(header, 80);
  const std::uint32_t n = 12;
  f.write(reinterpret_cast<const char*>(&n), 4);
  each_triangle([&](const float* a, const float* b, const float* c) {
    const float normal[3] = {0, 0, 0};
    f.write(reinterpret_cast<const char*>(normal), 12);
    for (const float* v : {a, b, c}) f.write(reinterpret_cast<const char*>(v), 12);
    const std::uint16_t attr = 0;
    f.write(reinterpret_cast<const char*>(&attr), 2);
  });
  return p;
}
}  // namespace

TEST(SimMesh, LoadsCubeFromObjAsciiStlBinaryStl) {
  for (const std::string& p : {write_obj(), write_ascii_stl(), write_binary_stl()}) {
    TriangleMesh m;
    std::string err;
    ASSERT_TRUE(load_mesh(p, m, err)) << err;
    EXPECT_EQ(m.vertices.size(), 8u) << p;
    EXPECT_EQ(m.triangles.size(), 12u) << p;
    Vec3 mn = Vec3::Constant(1e9_r), mx = Vec3::Constant(-1e9_r);
    for (const Vec3& v : m.vertices) {
      mn = mn.cwiseMin(v);
      mx = mx.cwiseMax(v);
    }
    EXPECT_EQ(mn, Vec3::Constant(-0.5_r)) << p;
    EXPECT_EQ(mx, Vec3::Constant(0.5_r)) << p;
    for (const auto& t : m.triangles)
      for (int i : t) EXPECT_TRUE(i >= 0 && i < 8);
  }
}

TEST(SimMesh, BadFilesGiveMessages) {
  TriangleMesh m;
  std::string err;
  EXPECT_FALSE(load_mesh(tmp("missing.obj"), m, err));
  EXPECT_NE(err.find("cannot open"), std::string::npos);
  EXPECT_FALSE(load_mesh(tmp("x.ply"), m, err));
  EXPECT_NE(err.find("unknown mesh format"), std::string::npos);
  const std::string p = tmp("bad.obj");
  std::ofstream(p) << "v 0 0 0\nv 1 0 0\nf 1 2 7\n";
  EXPECT_FALSE(load_mesh(p, m, err));
  EXPECT_NE(err.find("line 3"), std::string::npos) << err;
  EXPECT_TRUE(m.vertices.empty());  // untouched
}

TEST(SimMesh, ConvexHullCollidesLikeTheBox) {
  TriangleMesh m;
  std::string err;
  ASSERT_TRUE(load_mesh(write_binary_stl(), m, err)) << err;
  Shape hull;
  hull.type = ShapeType::convex_hull;
  hull.vertices = m.vertices.data();
  hull.num_vertices = static_cast<int>(m.vertices.size());
  hull.position_w = Vec3(1, 2, 3);
  hull.orientation_wb = Quat(Eigen::AngleAxis<real>(0.4_r, Vec3(0, 0, 1)));
  Shape box = hull;
  box.type = ShapeType::box;
  box.half_extents_m = Vec3::Constant(0.5_r);
  box.vertices = nullptr;
  box.num_vertices = 0;
  Vec3 hmn, hmx, bmn, bmx;
  shape_aabb(hull, hmn, hmx);
  shape_aabb(box, bmn, bmx);
  EXPECT_LT((hmn - bmn).norm(), 1e-5);
  EXPECT_LT((hmx - bmx).norm(), 1e-5);
  // Robot spheres and boxes at and around the obstacle: same hit, depth and normal as the box.
  for (const Vec3& off : {Vec3(0.6_r, 0, 0), Vec3(0, 0.65_r, 0.1_r), Vec3(0, 0, 0.55_r), Vec3(2, 0, 0), Vec3(0.3_r, 0.3_r, 0.62_r)}) {
    for (ShapeType t : {ShapeType::sphere, ShapeType::box}) {
      Shape robot;
      robot.type = t;
      robot.radius_m = 0.2_r;
      robot.half_extents_m = Vec3(0.15_r, 0.15_r, 0.05_r);
      robot.position_w = hull.position_w + off;
      const Contact kh = collide(robot, hull), kb = collide(robot, box);
      ASSERT_EQ(kh.hit, kb.hit) << off.transpose();
      if (!kh.hit) continue;
      EXPECT_NEAR(kh.depth_m, kb.depth_m, 2e-3) << off.transpose();
      EXPECT_GT(kh.normal_w.dot(kb.normal_w), 0.99) << off.transpose();
    }
  }
}

TEST(SimMesh, MeshObstaclesInAWorld) {
  WorldConfig c;
  ASSERT_TRUE(registries().envs.make("empty", c.env));
  c.env.num_envs = 4;
  AssetClass a;
  a.name = "cubes";
  a.kind = AssetKind::mesh;
  a.mesh_file = write_obj();
  a.num_assets = 3;
  a.min_num_assets = 3;
  c.env.assets.push_back(a);
  c.task.kind = TaskKind::hover;
  c.env.reset_on_collision = false;
  std::string err;
  auto w = World::create(c, err);
  ASSERT_TRUE(w) << err;
  ASSERT_EQ(w->num_obstacles(0), 3);
  EXPECT_EQ(w->obstacle(0, 0).shape.type, ShapeType::convex_hull);
  w->robot_state(0, 0).position_w = w->obstacle(0, 1).shape.position_w + Vec3(0.6_r, 0, 0);  // 0.1 m inside
  w->step(1);
  EXPECT_TRUE(w->crashed(0, 0));
  EXPECT_GT(w->contact_force_w(0, 0)[0], 0);  // pushed out along +x
  // A missing file fails at set-up with the class and file named.
  c.env.assets[0].mesh_file = tmp("nope.stl");
  EXPECT_FALSE(World::create(c, err));
  EXPECT_NE(err.find("env.assets.cubes"), std::string::npos) << err;
}

// Fuzz finding F3: a 4-vertex OBJ obstacle ~5e22 m long made libccd's MPR loop forever (its portal
// loops ignore max_iterations), so `kestrel run` hung in the first steps. Mesh coordinates are
// bounded at load, with the file, the vertex, the field and the allowed range in the message.
TEST(SimMesh, FarVerticesAreRefusedAtLoad) {
  const std::string data = std::string(KESTREL_SIM_TEST_DIR) + "/data/";
  TriangleMesh m;
  std::string err;
  EXPECT_FALSE(load_mesh(data + "fuzz_f3_long.obj", m, err));
  EXPECT_NE(err.find("fuzz_f3_long.obj: vertex 2 coordinate x = -5e+22 is out of range; allowed: a finite value with |x| <= "
                     "1e+06 m (kMaxMeshCoordinateM"),
            std::string::npos)
      << err;
  EXPECT_FALSE(load_mesh(data + "fuzz_f2_far.obj", m, err));  // the F2 file: 1e9 m
  EXPECT_NE(err.find("vertex 2 coordinate x = -1e+09 is out of range"), std::string::npos) << err;
  EXPECT_TRUE(m.vertices.empty());
  // At the bound: accepted.
  const std::string p = tmp("edge.obj");
  std::ofstream(p) << "v 0 0 0\nv -1e6 0 0\nv 0 0.5 5\nf 1 2 3\n";
  EXPECT_TRUE(load_mesh(p, m, err)) << err;
  // Through a scenario's asset class (the fuzz report's scene): refused at set-up, naming the class.
  WorldConfig c;
  ASSERT_TRUE(registries().envs.make("empty", c.env));
  c.env.num_envs = 1;
  AssetClass a;
  a.name = "m";
  a.kind = AssetKind::mesh;
  a.mesh_file = data + "fuzz_f3_long.obj";
  a.num_assets = a.min_num_assets = 2;
  a.max_angular_speed_rad_s = 1;
  c.env.assets.push_back(a);
  EXPECT_FALSE(World::create(c, err));
  EXPECT_NE(err.find("env.assets.m: "), std::string::npos) << err;
  EXPECT_NE(err.find("kMaxMeshCoordinateM"), std::string::npos) << err;
}

// F3's second line of defence: a hull built in code (no loader) with the 5e22 m vertex still
// returns from collide() (the MPR call has a budget of support calls), answering "no contact".
TEST(SimMesh, MprGivesUpInsteadOfLoopingOnAbsurdHulls) {
  const Vec3 v[4] = {Vec3(0, 0, 0), Vec3(-5e22_r, 0, 0), Vec3(0, 0.5_r, 5), Vec3(1, -5.5_r, 0)};
  Shape hull;
  hull.type = ShapeType::convex_hull;
  hull.vertices = v;
  hull.num_vertices = 4;
  hull.position_w = Vec3(1, 1, 1);
  hull.orientation_wb = Quat(Eigen::AngleAxis<real>(0.3_r, Vec3(0, 0, 1)));
  for (ShapeType t : {ShapeType::box, ShapeType::cylinder, ShapeType::capsule}) {
    Shape robot;
    robot.type = t;
    robot.radius_m = 0.2_r;
    robot.half_length_m = 0.1_r;
    robot.half_extents_m = Vec3(0.15_r, 0.15_r, 0.05_r);
    for (const Vec3& off : {Vec3(0, 0, 0), Vec3(0.5_r, 0.2_r, 1), Vec3(-3, 0, 0.5_r)}) {
      robot.position_w = hull.position_w + off;
      const Contact k = collide(robot, hull);  // returns (before the guard: never)
      if (k.hit) {
        EXPECT_TRUE(std::isfinite(k.depth_m));
      }
    }
  }
}

namespace {
// The welding of the loader before F8 (linear search from the newest vertex, operator==), kept
// here as the reference the hash map must reproduce index for index.
int old_vertex_index(std::vector<Vec3>& vs, const Vec3& v) {
  for (std::size_t i = vs.size(); i-- > 0;)
    if (vs[i] == v) return static_cast<int>(i);
  vs.push_back(v);
  return static_cast<int>(vs.size() - 1);
}
std::string write_binary_stl_soup(const char* name, const std::vector<std::array<float, 9>>& tris) {
  const std::string p = tmp(name);
  std::ofstream f(p, std::ios::binary);
  char header[80] = {};
  f.write(header, 80);
  const std::uint32_t n = static_cast<std::uint32_t>(tris.size());
  f.write(reinterpret_cast<const char*>(&n), 4);
  for (const auto& t : tris) {
    const float normal[3] = {0, 0, 1};
    f.write(reinterpret_cast<const char*>(normal), 12);
    f.write(reinterpret_cast<const char*>(t.data()), 36);
    const std::uint16_t attr = 0;
    f.write(reinterpret_cast<const char*>(&attr), 2);
  }
  return p;
}
}  // namespace

// Fuzz finding F8: STL vertex welding searched linearly per vertex, quadratic in the vertex count
// (random binary STLs of 10k / 20k / 40k triangles took 0.76 / 2.64 / 9.1 s to load). Now a hash
// map on the coordinate bits; the vertex numbering must be exactly the old one (first appearance),
// -0 and +0 still one vertex. (Timing, not asserted: the 40k-triangle grid below loads in ~20 ms
// on the shared 2-core build machine.)
TEST(SimMesh, StlWeldingMatchesTheLinearSearchAndScales) {
  // A small soup with repeats in every order, -0 next to +0, and a vertex used once.
  std::vector<std::array<float, 9>> soup;
  const float pts[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-0.0f, 1, 0}, {1, 1, -0.0f}, {0.5f, 0.25f, 3}};
  const int order[8][3] = {{0, 1, 2}, {2, 1, 4}, {3, 4, 1}, {5, 0, 3}, {4, 5, 2}, {1, 3, 0}, {2, 2, 5}, {0, 4, 3}};
  for (const auto& o : order) {
    std::array<float, 9> t{};
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) t[3 * k + c] = pts[o[k]][c];
    soup.push_back(t);
  }
  TriangleMesh m;
  std::string err;
  ASSERT_TRUE(load_mesh(write_binary_stl_soup("soup.stl", soup), m, err)) << err;
  std::vector<Vec3> ref;
  ASSERT_EQ(m.triangles.size(), soup.size());
  for (std::size_t t = 0; t < soup.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const Vec3 v(soup[t][3 * k], soup[t][3 * k + 1], soup[t][3 * k + 2]);
      EXPECT_EQ(m.triangles[t][k], old_vertex_index(ref, v)) << t << " " << k;
    }
  ASSERT_EQ(m.vertices.size(), ref.size());
  EXPECT_EQ(m.vertices.size(), 5u);  // (0,1,0) and (-0,1,0) are one vertex, as (1,1,0) and (1,1,-0)
  for (std::size_t i = 0; i < ref.size(); ++i) EXPECT_EQ(m.vertices[i], ref[i]) << i;

  // A 142 x 142-cell grid as a soup: 40,328 triangles, (142 + 1)^2 = 20,449 distinct vertices.
  const int n = 142;
  std::vector<std::array<float, 9>> grid;
  auto at = [](int i, int j) { return std::array<float, 3>{0.01f * static_cast<float>(i), 0.01f * static_cast<float>(j), 0.0f}; };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const std::array<float, 3> a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
      grid.push_back({a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2]});
      grid.push_back({a[0], a[1], a[2], c[0], c[1], c[2], d[0], d[1], d[2]});
    }
  ASSERT_EQ(grid.size(), 40328u);
  ASSERT_TRUE(load_mesh(write_binary_stl_soup("grid.stl", grid), m, err)) << err;
  EXPECT_EQ(m.triangles.size(), 40328u);
  EXPECT_EQ(m.vertices.size(), 20449u);
  // First-appearance numbering: cell (0, 0) gives vertices 0, 1, 2, then d = 3.
  EXPECT_EQ(m.triangles[0][0], 0);
  EXPECT_EQ(m.triangles[0][1], 1);
  EXPECT_EQ(m.triangles[0][2], 2);
  EXPECT_EQ(m.triangles[1][2], 3);
}
