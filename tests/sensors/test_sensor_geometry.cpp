// Scene geometry: analytic hits on every shape, normals, segmentation ids, the stable tie break,
// BVH capacity errors, and moving obstacles (a dirty scene is refused until rebuilt).
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sensors/scene.hpp"
#include "ktest.hpp"

using namespace kestrel;
using namespace kestrel::sensors;

namespace {

SceneStorage<16> g_storage;

// Cube mesh of half size 1 (12 triangles), built into static storage.
const real kCubeVerts[8 * 3] = {-1, -1, -1, 1, -1, -1, 1, 1, -1, -1, 1, -1, -1, -1, 1, 1, -1, 1, 1, 1, 1, -1, 1, 1};
const std::uint32_t kCubeIdx[12 * 3] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                        2, 3, 7, 2, 7, 6, 1, 2, 6, 1, 6, 5, 3, 0, 4, 3, 4, 7};
const std::uint32_t kCubeParts[12] = {10, 10, 11, 11, 12, 12, 13, 13, 14, 14, 15, 15};
BvhNode g_mesh_nodes[bvh_node_capacity(12)];
std::uint32_t g_mesh_prims[12];
real g_mesh_cache[12 * kTriangleCacheStride];
Aabb g_mesh_scratch[12];

Status build_cube(TriangleMesh& m) {
  m.vertices = kCubeVerts;
  m.vertex_count = 8;
  m.indices = kCubeIdx;
  m.triangle_count = 12;
  m.part_ids = kCubeParts;
  MeshStorage st{g_mesh_nodes, bvh_node_capacity(12), g_mesh_prims, g_mesh_cache, g_mesh_scratch, 12};
  return mesh_build(m, st);
}

bool cast(const Scene& s, const Vec3& o, const Vec3& d, SceneHit& h) { return s.intersect(o, d.normalized(), 0, 100, h); }

const Quat kIdentity = Quat::Identity();

}  // namespace

KTEST(SensorGeometry, AnalyticPrimitivesHitExactly) {
  Scene s(g_storage);
  KASSERT_EQ(static_cast<int>(s.add(Shape::box(0.5_r, 1, 2), Vec3(5, 0, 0), kIdentity, 1)), 0);
  KASSERT_EQ(static_cast<int>(s.add(Shape::sphere(1), Vec3(0, 6, 0), kIdentity, 2)), 0);
  KASSERT_EQ(static_cast<int>(s.add(Shape::capsule(0.5_r, 1), Vec3(-7, 0, 0), kIdentity, 3)), 0);
  KASSERT_EQ(static_cast<int>(s.add(Shape::cylinder(0.25_r, 1), Vec3(0, -8, 0), kIdentity, 4)), 0);
  KASSERT_EQ(static_cast<int>(s.add(Shape::plane(), Vec3(0, 0, -3), kIdentity, 5)), 0);
  Status st = Status::invalid_argument;
  KEXPECT_NO_HEAP(st = s.build());
  KASSERT_EQ(static_cast<int>(st), 0);
  SceneHit h;
  const Vec3 o(0, 0, 0);
  KASSERT_TRUE(cast(s, o, Vec3(1, 0, 0), h));
  KEXPECT_NEAR(h.t, 4.5, 1e-6);
  KEXPECT_NEAR(h.normal_w[0], -1, 1e-6);
  KEXPECT_EQ(h.seg_id, 1u);
  KASSERT_TRUE(cast(s, o, Vec3(0, 1, 0), h));
  KEXPECT_NEAR(h.t, 5, 1e-5);
  KEXPECT_NEAR(h.normal_w[1], -1, 1e-5);
  KEXPECT_EQ(h.seg_id, 2u);
  KASSERT_TRUE(cast(s, o, Vec3(-1, 0, 0), h));
  KEXPECT_NEAR(h.t, 6.5, 1e-5);
  KEXPECT_EQ(h.seg_id, 3u);
  KASSERT_TRUE(cast(s, o, Vec3(0, -1, 0), h));
  KEXPECT_NEAR(h.t, 7.75, 1e-5);
  KEXPECT_EQ(h.seg_id, 4u);
  KASSERT_TRUE(cast(s, o, Vec3(0, 0, -1), h));
  KEXPECT_NEAR(h.t, 3, 1e-6);
  KEXPECT_NEAR(h.normal_w[2], 1, 1e-6);
  KEXPECT_EQ(h.seg_id, 5u);
  // Capsule cap: from above the capsule, straight down onto the hemisphere top at z = 1.5.
  KASSERT_TRUE(cast(s, Vec3(-7, 0, 2), Vec3(0, 0, -1), h));
  KEXPECT_NEAR(h.t, 0.5, 1e-6);
  KEXPECT_NEAR(h.normal_w[2], 1, 1e-6);
  // Cylinder cap: flat at z = 1.
  KASSERT_TRUE(cast(s, Vec3(0.1_r, -8, 3), Vec3(0, 0, -1), h));
  KEXPECT_NEAR(h.t, 2, 1e-6);
  KEXPECT_NEAR(h.normal_w[2], 1, 1e-6);
  // Oblique ray to the sphere: |o + t d - c| = r analytically.
  const Vec3 d = Vec3(0.05_r, 1, 0.1_r).normalized();
  KASSERT_TRUE(cast(s, o, d, h));
  const Vec3 p = o + h.t * d;
  KEXPECT_NEAR((p - Vec3(0, 6, 0)).norm(), 1, 1e-5);
  // Nothing upward.
  KEXPECT_FALSE(cast(s, o, Vec3(0, 0, 1), h));
}

KTEST(SensorGeometry, RotatedBoxAndMeshWithPartIds) {
  TriangleMesh cube;
  KASSERT_EQ(static_cast<int>(build_cube(cube)), 0);
  Scene s(g_storage);
  // Box rotated 45 deg about z: its corner points at the origin, at distance 5 - sqrt(2) * 0.5.
  KASSERT_EQ(static_cast<int>(s.add(Shape::box(0.5_r, 0.5_r, 0.5_r), Vec3(5, 0, 0), quat_from_euler_xyz(0, 0, kPi / 4), 7)), 0);
  // Mesh cube rotated 90 deg about x, at y = -4: face at y = -3.
  KASSERT_EQ(static_cast<int>(s.add(Shape::triangle_mesh(&cube), Vec3(0, -4, 0), quat_from_euler_xyz(kPi / 2, 0, 0), 99)), 0);
  KASSERT_EQ(static_cast<int>(s.build()), 0);
  SceneHit h;
  KASSERT_TRUE(cast(s, Vec3(0, 0, 0.1_r), Vec3(1, 0, 0), h));
  KEXPECT_NEAR(h.t, 5 - 0.70710678, 1e-5);
  KASSERT_TRUE(cast(s, Vec3(0.2_r, 0, 0.3_r), Vec3(0, -1, 0), h));
  KEXPECT_NEAR(h.t, 3, 1e-5);
  KEXPECT_NEAR(h.normal_w[1], 1, 1e-5);  // faces the sensor
  // The face toward the sensor (world +y) is the local -z face (Rx(90) maps -z to +y): part 10.
  KEXPECT_EQ(h.seg_id, 10u);
  KEXPECT_TRUE(h.prim == 0u || h.prim == 1u);
}

KTEST(SensorGeometry, EqualDistanceHitsResolveToLowestId) {
  Scene s(g_storage);
  // Two identical boxes at the same place, added in either order: the lower object id wins.
  for (int order = 0; order < 2; ++order) {
    s.clear();
    KASSERT_EQ(static_cast<int>(s.add(Shape::box(1, 1, 1), Vec3(5, 0, 0), kIdentity, order == 0 ? 21u : 22u)), 0);
    KASSERT_EQ(static_cast<int>(s.add(Shape::box(1, 1, 1), Vec3(5, 0, 0), kIdentity, order == 0 ? 22u : 21u)), 0);
    for (int k = 0; k < 6; ++k)  // filler objects change the BVH layout
      KASSERT_EQ(static_cast<int>(s.add(Shape::sphere(0.2_r), Vec3(-3, static_cast<real>(k), 0), kIdentity, 0)), 0);
    KASSERT_EQ(static_cast<int>(s.build()), 0);
    SceneHit h;
    KASSERT_TRUE(cast(s, Vec3(0, 0, 0), Vec3(1, 0, 0), h));
    KEXPECT_NEAR(h.t, 4, 1e-6);
    KEXPECT_EQ(h.object, 0u);
    KEXPECT_EQ(h.seg_id, order == 0 ? 21u : 22u);
  }
  // Two cube-mesh triangles share the diagonal edge: a ray through the edge takes the lower id.
  TriangleMesh cube;
  KASSERT_EQ(static_cast<int>(build_cube(cube)), 0);
  s.clear();
  KASSERT_EQ(static_cast<int>(s.add(Shape::triangle_mesh(&cube), Vec3(0, 0, 0), kIdentity, 0)), 0);
  KASSERT_EQ(static_cast<int>(s.build()), 0);
  SceneHit h;
  KASSERT_TRUE(cast(s, Vec3(0, 0, -5), Vec3(0, 0, 1), h));  // through (0,0,-1): diagonal of triangles 0 and 1
  KEXPECT_NEAR(h.t, 4, 1e-6);
  KEXPECT_EQ(h.prim, 0u);
}

KTEST(SensorGeometry, HeightFieldGridTraversal) {
  // 5 x 4 samples, 0.5 m spacing: a ramp z = 0.2 x.
  static real heights[4 * 5];
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 5; ++i) heights[j * 5 + i] = 0.2_r * 0.5_r * static_cast<real>(i);
  HeightField hf;
  hf.heights = heights;
  hf.nx = 5;
  hf.ny = 4;
  hf.dx = hf.dy = 0.5_r;
  KASSERT_EQ(static_cast<int>(height_field_prepare(hf)), 0);
  Scene s(g_storage);
  KASSERT_EQ(static_cast<int>(s.add(Shape::heights(&hf), Vec3(10, 0, 0), kIdentity, 8)), 0);
  KASSERT_EQ(static_cast<int>(s.build()), 0);
  SceneHit h;
  // Straight down at x = 11.3 (local 1.3): z = 0.26.
  KASSERT_TRUE(cast(s, Vec3(11.3_r, 0.7_r, 5), Vec3(0, 0, -1), h));
  KEXPECT_NEAR(h.t, 5 - 0.26, 1e-5);
  KEXPECT_EQ(h.seg_id, 8u);
  const real nn = std::sqrt(1 + 0.04_r);
  KEXPECT_NEAR(h.normal_w[0], -0.2 / nn, 1e-5);
  KEXPECT_NEAR(h.normal_w[2], 1 / nn, 1e-5);
  // Grazing ray along +x at z = 0.25 from the left: hits the ramp where 0.2 x = 0.25 -> x = 1.25.
  KASSERT_TRUE(cast(s, Vec3(0, 1.1_r, 0.25_r), Vec3(1, 0, 0), h));
  KEXPECT_NEAR(h.t, 11.25, 1e-4);
  // Diagonal descending ray crossing several cells.
  const Vec3 o(10.1_r, 0.1_r, 1), d = Vec3(1, 0.6_r, -0.5_r).normalized();
  KASSERT_TRUE(cast(s, o, d, h));
  const Vec3 p = o + h.t * d;
  KEXPECT_NEAR(p[2], 0.2 * (p[0] - 10), 1e-5);
}

KTEST(SensorGeometry, CapacityAndInvalidInputAreStatuses) {
  SceneObject objs[2];
  BvhNode nodes[bvh_node_capacity(2)];
  std::uint32_t prims[2], map[2];
  Aabb boxes[2];
  Scene s(objs, 2, nodes, bvh_node_capacity(2), prims, boxes, map);
  KEXPECT_EQ(static_cast<int>(s.add(Shape::sphere(1), Vec3(0, 0, 0), kIdentity, 0)), 0);
  KEXPECT_EQ(static_cast<int>(s.add(Shape::sphere(-1), Vec3(0, 0, 0), kIdentity, 0)),
             static_cast<int>(Status::invalid_argument));
  KEXPECT_EQ(static_cast<int>(s.add(Shape::sphere(1), Vec3(1, 0, 0), kIdentity, 0)), 0);
  KEXPECT_EQ(static_cast<int>(s.add(Shape::sphere(1), Vec3(2, 0, 0), kIdentity, 0)),
             static_cast<int>(Status::capacity_exceeded));
  // BVH storage too small for the primitives: an answer, not a crash.
  Aabb pb[4];
  for (int i = 0; i < 4; ++i) {
    const real lo[3] = {static_cast<real>(i), 0, 0}, hi[3] = {static_cast<real>(i) + 0.5_r, 1, 1};
    pb[i].grow(lo);
    pb[i].grow(hi);
  }
  BvhNode few[3];
  std::uint32_t idx[4];
  Bvh bvh;
  bvh.nodes = few;
  bvh.node_capacity = 3;
  bvh.prim_index = idx;
  bvh.prim_capacity = 4;
  KEXPECT_EQ(static_cast<int>(bvh_build(pb, 4, BvhBuildParams{}, bvh)), static_cast<int>(Status::capacity_exceeded));
  // Mesh index out of range.
  const real v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::uint32_t bad[3] = {0, 1, 7};
  TriangleMesh m;
  m.vertices = v;
  m.vertex_count = 3;
  m.indices = bad;
  m.triangle_count = 1;
  MeshStorage st{g_mesh_nodes, bvh_node_capacity(12), g_mesh_prims, g_mesh_cache, g_mesh_scratch, 12};
  KEXPECT_EQ(static_cast<int>(mesh_build(m, st)), static_cast<int>(Status::invalid_argument));
}

KTEST(SensorGeometry, MovingObstacleIsSeenAfterRebuildAndDirtySceneIsRefused) {
  Scene s(g_storage);
  std::uint32_t id = 0;
  KASSERT_EQ(static_cast<int>(s.add(Shape::box(0.5_r, 0.5_r, 0.5_r), Vec3(3, 0, 0), kIdentity, 1, &id)), 0);
  KASSERT_EQ(static_cast<int>(s.build()), 0);
  SceneHit h;
  KASSERT_TRUE(cast(s, Vec3(0, 0, 0), Vec3(1, 0, 0), h));
  KEXPECT_NEAR(h.t, 2.5, 1e-6);
  KASSERT_EQ(static_cast<int>(s.set_pose(id, Vec3(6, 0, 0), kIdentity)), 0);
  KEXPECT_TRUE(s.dirty());
  KEXPECT_FALSE(cast(s, Vec3(0, 0, 0), Vec3(1, 0, 0), h));
  KASSERT_EQ(static_cast<int>(s.build()), 0);
  KASSERT_TRUE(cast(s, Vec3(0, 0, 0), Vec3(1, 0, 0), h));
  KEXPECT_NEAR(h.t, 5.5, 1e-6);
}
