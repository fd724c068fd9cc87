// Sensor outputs: lidar ranges in a closed room (exact), point clouds in sensor and world frames,
// out-of-range and normalisation rules, the camera's planar depth, segmentation, noise statistics
// from fixed seeds, mounting and the IMU model.
#include <cmath>
#include <cstring>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sensors/imu.hpp"
#include "kestrel/sensors/ray_sensor.hpp"
#include "ktest.hpp"
#include "test_scratch.hpp"

using namespace kestrel;
using namespace kestrel::sensors;

namespace {

SceneStorage<8> g_storage;
const Quat kIdentity = Quat::Identity();

// A test's ray table and outputs, taken from the shared test scratch (test_scratch.hpp) and sized
// by the largest table these tests cast, TiledMeshRenderIsBitIdenticalToSingleRays' 44 x 27
// camera: 42 KiB in a float build (as 2048-ray statics they held 72 KiB of the MCU core test
// image's RAM for the whole run). A table that outgrows it fails lidar_rays / camera_rays with
// capacity_exceeded, on the host as on the MCUs.
constexpr std::uint32_t kMaxRays = 44 * 27;
struct Rays {
  real dirs[3 * kMaxRays], scale[kMaxRays], range[kMaxRays], points[3 * kMaxRays];
  std::int32_t seg[kMaxRays];
  RayTable table() { return RayTable{dirs, scale, kMaxRays, 0, 0}; }
};

}  // namespace

KTEST(SensorRender, LidarInsideSphereReadsRadiusEverywhere) {
  Rays& b = ktest::scratch<Rays>();
  Scene s(g_storage);
  KASSERT_EQ(static_cast<int>(s.add(Shape::sphere(4), Vec3(1, 2, 3), kIdentity, 9)), 0);
  KASSERT_EQ(static_cast<int>(s.build()), 0);
  LidarParams p = lidar_preset_osdome_64();
  p.height = 16;
  p.width = 32;
  p.range.normalize_range = false;  // metres (the preset normalises)
  RayTable t = b.table();
  KASSERT_EQ(static_cast<int>(lidar_rays(p, t)), 0);
  SensorPose pose;
  pose.position_w = Vec3(1, 2, 3);
  pose.orientation_ws = quat_from_euler_xyz(0.3_r, -0.2_r, 1.1_r);
  SensorOutput out;
  out.range = b.range;
  out.segmentation = b.seg;
  out.points = b.points;
  Status st = Status::invalid_argument;
  KEXPECT_NO_HEAP(st = render(s, pose, t, p.range, false, out));
  KASSERT_EQ(static_cast<int>(st), 0);
  for (std::uint32_t i = 0; i < 16 * 32; ++i) {
    KEXPECT_NEAR(b.range[i], 4, 2e-5);
    KEXPECT_EQ(b.seg[i], 9);
    // Sensor-frame point = range x sensor-frame direction.
    for (int k = 0; k < 3; ++k) KEXPECT_NEAR(b.points[3 * i + k], 4 * b.dirs[3 * i + k], 1e-4);
  }
}

KTEST(SensorRender, FramesOutOfRangeAndNormalisation) {
  Rays& b = ktest::scratch<Rays>();
  // A wall at world x = 3 (box face), sensor at the origin yawed +90 deg: the wall is to its right.
  Scene s(g_storage);
  KASSERT_EQ(static_cast<int>(s.add(Shape::box(0.5_r, 50, 50), Vec3(3.5_r, 0, 0), kIdentity, 4)), 0);
  KASSERT_EQ(static_cast<int>(s.build()), 0);
  LidarParams p = lidar_preset_osdome_64();
  p.height = 1;
  p.width = 5;  // azimuth 180, 90, 0, -90, -180 deg at elevation 0
  p.vertical_fov_deg_min = p.vertical_fov_deg_max = 0;
  RayTable t = b.table();
  KASSERT_EQ(static_cast<int>(lidar_rays(p, t)), 0);
  SensorPose pose;
  pose.orientation_ws = quat_from_euler_xyz(0, 0, kPi / 2);
  SensorOutput out;
  out.range = b.range;
  out.points = b.points;
  out.points_in_world_frame = true;
  p.range.normalize_range = false;
  p.range.set_default_out_of_range_values();
  KASSERT_EQ(static_cast<int>(render(s, pose, t, p.range, false, out)), 0);
  // Column 3: azimuth -90 deg in the sensor = world +x -> the wall at 3 m.
  KEXPECT_NEAR(b.range[3], 3, 1e-5);
  KEXPECT_NEAR(b.points[9], 3, 1e-5);
  KEXPECT_NEAR(b.points[10], 0, 1e-5);
  // Others see nothing: -1 without normalisation.
  KEXPECT_EQ(b.range[0], -1);
  KEXPECT_EQ(b.range[2], -1);
  // Normalised: hit 3/20, no hit 1.0; too near -1.0.
  p.range.normalize_range = true;
  p.range.set_default_out_of_range_values();
  KASSERT_EQ(static_cast<int>(render(s, pose, t, p.range, false, out)), 0);
  KEXPECT_NEAR(b.range[3], 3.0 / 20.0, 1e-6);
  KEXPECT_EQ(b.range[2], 1);
  p.range.min_range = 3.5_r;
  KASSERT_EQ(static_cast<int>(render(s, pose, t, p.range, false, out)), 0);
  KEXPECT_EQ(b.range[3], -1);
  // Max range below the wall: a miss.
  p.range.min_range = 0.5_r;
  p.range.max_range = 2.5_r;
  p.range.set_default_out_of_range_values();
  KASSERT_EQ(static_cast<int>(render(s, pose, t, p.range, false, out)), 0);
  KEXPECT_EQ(b.range[3], 1);
}

KTEST(SensorRender, CameraDepthIsPlanarAndRangeIsAlongTheRay) {
  Rays& b = ktest::scratch<Rays>();
  // Wall 4 m in front of a camera looking along world +x; depth is measured along the principal
  // ray of pixel (W/2, H/2) (golden quirk 11), so on a wall perpendicular to the optical axis
  // depth = 4 / (principal . axis) everywhere... exactly t * scale with t = 4 / cos(angle to axis).
  Scene s(g_storage);
  KASSERT_EQ(static_cast<int>(s.add(Shape::box(0.5_r, 50, 50), Vec3(4.5_r, 0, 0), kIdentity, 3)), 0);
  KASSERT_EQ(static_cast<int>(s.build()), 0);
  CameraParams cp = camera_preset_base();
  cp.height = 18;
  cp.width = 32;
  cp.range.normalize_range = false;  // metres (the preset normalises)
  RayTable t = b.table();
  KASSERT_EQ(static_cast<int>(camera_rays(cp, t)), 0);
  SensorPose pose;
  SensorOutput out;
  out.range = b.range;
  out.segmentation = b.seg;
  KASSERT_EQ(static_cast<int>(render(s, pose, t, cp.range, true, out)), 0);
  for (std::uint32_t i = 0; i < 18 * 32; ++i) {
    const real x = b.dirs[3 * i];  // forward component = cos(angle to the optical axis)
    KEXPECT_NEAR(b.range[i], 4 / x * b.scale[i], 2e-5);
    KEXPECT_EQ(b.seg[i], 3);
  }
  // Pixel (W/2, H/2) is the principal pixel with an even H: it lies on the optical axis.
  KEXPECT_NEAR(b.range[9 * 32 + 16], 4, 1e-5);
  // Range mode.
  cp.calculate_depth = false;
  KASSERT_EQ(static_cast<int>(camera_rays(cp, t)), 0);
  KASSERT_EQ(static_cast<int>(render(s, pose, t, cp.range, false, out)), 0);
  KEXPECT_NEAR(b.range[0], 4 / b.dirs[0], 2e-5);
  // Sensor-frame convention: column 0 looks left (+y), row 0 looks up (+z).
  KEXPECT_GT(b.dirs[1], 0);
  KEXPECT_GT(b.dirs[2], 0);
}

namespace {

// A bumpy closed sphere (kRings x 2 kRings quads) whose triangle list is given twice: every
// triangle k has an identical twin k + half, so equal-distance hits inside one mesh pick the
// lower id; part ids make the winner visible in the segmentation.
constexpr int kRings = 3;  // small: it shares the test scratch with the ray buffers (10 KiB, 72 triangles)
constexpr std::uint32_t kRingVerts = 2 * kRings * (kRings + 1), kHalfTris = 2 * kRings * 2 * kRings;
constexpr std::uint32_t kTwinTris = 2 * kHalfTris;
struct TwinMesh {
  real v[3 * kRingVerts];
  std::uint32_t i[3 * kTwinTris], parts[kTwinTris];
  BvhNode nodes[bvh_node_capacity(kTwinTris)];
  std::uint32_t prims[kTwinTris];
  real cache[kTriangleCacheStride * kTwinTris];
  Aabb scratch[kTwinTris];
};
// The mesh test's buffers, together in the test scratch (~53 KiB: the largest user of it).
struct MeshScene {
  Rays rays;
  TwinMesh mesh;
};

bool build_twin_mesh(TwinMesh& g, TriangleMesh& mesh) {
  const int nu = 2 * kRings, nv = kRings;
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const real th = kPi * static_cast<real>(j) / static_cast<real>(nv), ph = kTwoPi * static_cast<real>(i) / static_cast<real>(nu);
      const real r = 1 + 0.15_r * std::sin(3 * ph) * std::sin(2 * th);
      real* v = &g.v[3 * (j * nu + i)];
      v[0] = r * std::sin(th) * std::cos(ph);
      v[1] = r * std::sin(th) * std::sin(ph);
      v[2] = r * std::cos(th);
    }
  std::uint32_t k = 0;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const std::uint32_t a = static_cast<std::uint32_t>(j * nu + i), b = static_cast<std::uint32_t>(j * nu + (i + 1) % nu);
      const std::uint32_t c = a + static_cast<std::uint32_t>(nu), d = b + static_cast<std::uint32_t>(nu);
      const std::uint32_t quad[6] = {a, c, b, b, c, d};
      for (std::uint32_t q = 0; q < 6; ++q) g.i[k++] = quad[q];
    }
  for (std::uint32_t q = 0; q < 3 * kHalfTris; ++q) g.i[3 * kHalfTris + q] = g.i[q];
  for (std::uint32_t t = 0; t < kTwinTris; ++t) g.parts[t] = 100 + t % 7 + (t >= kHalfTris ? 50 : 0);
  mesh = TriangleMesh{};
  mesh.vertices = g.v;
  mesh.vertex_count = kRingVerts;
  mesh.indices = g.i;
  mesh.triangle_count = kTwinTris;
  mesh.part_ids = g.parts;
  return mesh_build(mesh, MeshStorage{g.nodes, bvh_node_capacity(kTwinTris), g.prims, g.cache, g.scratch, kTwinTris}) ==
         Status::ok;
}

bool same_bits(real a, real b) { return std::memcmp(&a, &b, sizeof(real)) == 0; }

// Rays of the table cast by render (in tiles) and one by one through Scene::intersect must give
// the same range, segmentation and normal bits. Returns the number of differing rays.
std::uint32_t render_vs_single_rays(Rays& b, const Scene& s, const SensorPose& pose, const RayTable& t,
                                    const RangeOutputParams& op, bool depth) {
  real* const normals = b.points;  // no second 3 x kMaxRays buffer on the MCUs
  SensorOutput out;
  out.range = b.range;
  out.segmentation = b.seg;
  out.normals_w = normals;
  if (render(s, pose, t, op, depth, out) != Status::ok) return 0xffffffffu;
  const Mat3 r = rotation_matrix(pose.orientation_ws.normalized());
  const real o[3] = {pose.position_w[0], pose.position_w[1], pose.position_w[2]};
  std::uint32_t diffs = 0;
  for (std::uint32_t i = 0; i < t.height * t.width; ++i) {
    const real* ds = &t.dirs_s[3 * i];
    const real d[3] = {r(0, 0) * ds[0] + r(0, 1) * ds[1] + r(0, 2) * ds[2], r(1, 0) * ds[0] + r(1, 1) * ds[1] + r(1, 2) * ds[2],
                       r(2, 0) * ds[0] + r(2, 1) * ds[1] + r(2, 2) * ds[2]};
    const real sc = depth ? t.depth_scale[i] : 1_r;
    SceneHit h;
    const bool found = s.intersect(make_ray(o, d), 0, op.max_range / sc, h);
    real v = found ? h.t * sc : kNoHitValue;
    if (v > op.max_range) v = op.far_out_of_range_value;
    if (v < op.min_range) v = op.near_out_of_range_value;
    if (op.normalize_range) v = v / op.max_range;
    bool same = same_bits(v, b.range[i]) && b.seg[i] == (found ? static_cast<std::int32_t>(h.seg_id) : kNoHitSegment);
    for (int k = 0; k < 3; ++k) same = same && same_bits(found ? h.normal_w[k] : 0_r, normals[3 * i + k]);
    if (!same) ++diffs;
  }
  return diffs;
}

}  // namespace

KTEST(SensorRender, TiledMeshRenderIsBitIdenticalToSingleRays) {
  // Meshes are cast a tile at a time (Scene::intersect_tile on hosts with vector lanes): the same
  // bits as single rays, ties included (twin triangles in one mesh; two coincident instances of
  // it, where the lower object id must win), next to analytic shapes, with and without rotation.
  MeshScene& ms = ktest::scratch<MeshScene>();
  Rays& b = ms.rays;
  TriangleMesh mesh;
  KASSERT_TRUE(build_twin_mesh(ms.mesh, mesh));
  Scene s(g_storage);
  const Quat q = quat_from_euler_xyz(0.4_r, -0.3_r, 0.9_r);
  KASSERT_EQ(static_cast<int>(s.add(Shape::triangle_mesh(&mesh), Vec3(3, 0.5_r, 0.2_r), q, 1)), 0);
  KASSERT_EQ(static_cast<int>(s.add(Shape::triangle_mesh(&mesh), Vec3(3, 0.5_r, 0.2_r), q, 2)), 0);
  KASSERT_EQ(static_cast<int>(s.add(Shape::triangle_mesh(&mesh), Vec3(-2, 2, 0.5_r), kIdentity, 3)), 0);
  KASSERT_EQ(static_cast<int>(s.add(Shape::box(0.3_r, 0.3_r, 2), Vec3(2.6_r, -0.8_r, 0), q, 4)), 0);
  KASSERT_EQ(static_cast<int>(s.add(Shape::capsule(0.2_r, 1), Vec3(0.5_r, -3, 0), kIdentity, 5)), 0);
  KASSERT_EQ(static_cast<int>(s.add(Shape::plane(), Vec3(0, 0, -1.5_r), kIdentity, 6)), 0);
  KASSERT_EQ(static_cast<int>(s.build()), 0);
  SensorPose pose;
  pose.position_w = Vec3(0.1_r, 0.05_r, 0.3_r);
  pose.orientation_ws = quat_from_euler_xyz(0, 0.05_r, 0.1_r);
  LidarParams lp = lidar_preset_osdome_64();
  lp.height = 16;
  lp.width = 64;
  RayTable t = b.table();
  KASSERT_EQ(static_cast<int>(lidar_rays(lp, t)), 0);
  KEXPECT_EQ(render_vs_single_rays(b, s, pose, t, lp.range, false), 0u);
  CameraParams cp = camera_preset_base();
  cp.height = 27;  // not a multiple of the 8 x 8 tile: partial tiles too
  cp.width = 44;
  KASSERT_EQ(static_cast<int>(camera_rays(cp, t)), 0);
  KEXPECT_EQ(render_vs_single_rays(b, s, pose, t, cp.range, true), 0u);
  KEXPECT_EQ(render_vs_single_rays(b, s, pose, t, cp.range, false), 0u);
  // The camera sees the first instance (the twin triangles and the coincident instance never win).
  SensorOutput out;
  out.range = b.range;
  out.segmentation = b.seg;
  KASSERT_EQ(static_cast<int>(render(s, pose, t, cp.range, false, out)), 0);
  std::uint32_t on_mesh = 0;
  for (std::uint32_t i = 0; i < cp.height * cp.width; ++i) {
    KEXPECT_TRUE(b.seg[i] < 150);
    if (b.seg[i] >= 100) ++on_mesh;
  }
  KEXPECT_GT(on_mesh, 50u);
  Status st = Status::invalid_argument;
  KEXPECT_NO_HEAP(st = render(s, pose, t, cp.range, false, out));
  KEXPECT_EQ(static_cast<int>(st), 0);
}

KTEST(SensorRender, DirtySceneAndBadTableAreRefused) {
  Rays& b = ktest::scratch<Rays>();
  Scene s(g_storage);
  KASSERT_EQ(static_cast<int>(s.add(Shape::sphere(1), Vec3(3, 0, 0), kIdentity, 1)), 0);
  RayTable t = b.table();
  LidarParams p = lidar_preset_vl53l5cx();
  KASSERT_EQ(static_cast<int>(lidar_rays(p, t)), 0);
  SensorOutput out;
  out.range = b.range;
  KEXPECT_EQ(static_cast<int>(render(s, SensorPose{}, t, p.range, false, out)), static_cast<int>(Status::invalid_argument));
  RayTable small{b.dirs, b.scale, 10, 0, 0};
  KEXPECT_EQ(static_cast<int>(lidar_rays(p, small)), static_cast<int>(Status::capacity_exceeded));
}

namespace {

// The noise statistics' samples: the standard errors below are worked out for 2048 (16 KiB with
// its twin for the determinism check), more than the ray buffers hold.
constexpr std::uint32_t kNoiseSamples = 2048;
struct NoiseSamples {
  real values[kNoiseSamples], again[kNoiseSamples];
};

}  // namespace

KTEST(SensorRender, NoiseStatisticsFromFixedSeed) {
  // Range-dependent model at r = 5: std = 0.01 * 25 + 0.02 * 5 + 0.05 = 0.4, mean_offset -0.1
  // (Aerial Gym: mean = r - mean_offset = 5.1).
  NoiseParams np;
  np.model = NoiseParams::Model::range_dependent;
  np.a = 0.01_r;
  np.b = 0.02_r;
  np.c = 0.05_r;
  np.mean_offset = -0.1_r;
  np.pixel_dropout_prob = 0.1_r;
  constexpr std::uint32_t n = kNoiseSamples;
  NoiseSamples& ns = ktest::scratch<NoiseSamples>();
  real* const values = ns.values;
  real* const again = ns.again;
  for (std::uint32_t i = 0; i < n; ++i) values[i] = 5;
  RngStream rng(42, 0, kPurposeSensorNoise);
  KEXPECT_NO_HEAP(apply_noise(np, values, n, rng, 0));
  double sum = 0, sum2 = 0;
  int kept = 0, dropped = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (values[i] == 0) {
      ++dropped;
      continue;
    }
    sum += static_cast<double>(values[i]);
    sum2 += static_cast<double>(values[i]) * static_cast<double>(values[i]);
    ++kept;
  }
  const double mean = sum / kept, sd = std::sqrt(sum2 / kept - mean * mean);
  // 2048 samples: standard error of the mean 0.4 / 45 = 0.009; of the sd ~0.0063.
  KEXPECT_NEAR(mean, 5.1, 0.03);
  KEXPECT_NEAR(sd, 0.4, 0.025);
  KEXPECT_NEAR(static_cast<double>(dropped) / n, 0.1, 0.02);
  // Same seed, same values (determinism); multiplier model scales with the value.
  for (std::uint32_t i = 0; i < n; ++i) again[i] = 5;
  RngStream rng2(42, 0, kPurposeSensorNoise);
  apply_noise(np, again, n, rng2, 0);
  for (std::uint32_t i = 0; i < n; ++i) KEXPECT_EQ(again[i], values[i]);
  NoiseParams mp;
  mp.model = NoiseParams::Model::multiplier;
  mp.std_dev_multiplier = 0.02_r;
  for (std::uint32_t i = 0; i < n; ++i) values[i] = 10;
  RngStream rng3(7, 1, kPurposeSensorNoise);
  apply_noise(mp, values, n, rng3, 0);
  sum = sum2 = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    sum += static_cast<double>(values[i]);
    sum2 += static_cast<double>(values[i]) * static_cast<double>(values[i]);
  }
  const double m2 = sum / n;
  KEXPECT_NEAR(m2, 10, 0.015);
  KEXPECT_NEAR(std::sqrt(sum2 / n - m2 * m2), 0.2, 0.015);
}

KTEST(SensorRender, MountingNominalAndRandomised) {
  MountParams mp;
  mp.nominal_position_b = Vec3(0.1_r, 0, 0.05_r);
  mp.nominal_euler_deg = Vec3(0, 30, 0);
  RngStream rng(3, 5, kPurposePlacement);
  Mount m = sample_mount(mp, rng);
  RigidBodyState body;
  body.position_w = Vec3(1, 2, 3);
  body.orientation_wb = quat_from_euler_xyz(0, 0, kPi / 2);
  const SensorPose sp = sensor_pose(body, m);
  KEXPECT_NEAR(sp.position_w[0], 1, 1e-6);
  KEXPECT_NEAR(sp.position_w[1], 2.1, 1e-6);
  KEXPECT_NEAR(sp.position_w[2], 3.05, 1e-6);
  // Pitched 30 deg down (positive pitch about y tilts x toward -z), then yawed to world +y.
  const Vec3 fwd = rotate(sp.orientation_ws, Vec3(1, 0, 0));
  KEXPECT_NEAR(fwd[1], std::cos(kPi / 6), 1e-6);
  KEXPECT_NEAR(fwd[2], -0.5, 1e-6);
  mp.randomize_placement = true;
  mp.min_translation_b = Vec3(-0.1_r, -0.1_r, 0);
  mp.max_translation_b = Vec3(0.1_r, 0.1_r, 0.02_r);
  mp.min_euler_deg = Vec3(-5, -5, -5);
  mp.max_euler_deg = Vec3(5, 5, 5);
  for (int k = 0; k < 50; ++k) {
    m = sample_mount(mp, rng);
    KEXPECT_TRUE(m.position_b[0] >= -0.1_r && m.position_b[0] < 0.1_r);
    KEXPECT_TRUE(m.position_b[2] >= 0 && m.position_b[2] < 0.02_r);
    const Vec3 e = euler_xyz(m.orientation_bs) * (180 / kPi);
    for (int a = 0; a < 3; ++a) KEXPECT_LE(std::fabs(e[a]), 5.0001);
  }
}

KTEST(SensorImu, HoverGravityBiasNoiseAndSaturation) {
  ImuParams p;  // noise and bias off first: exact physics
  p.enable_noise = false;
  p.enable_bias = false;
  ImuState s;
  RngStream rng(1, 0, kPurposeSensorNoise);
  imu_reset(p, s, rng);
  ImuSample out;
  // Hovering, level: specific force +g along z; gyro reads the body rate.
  KASSERT_EQ(static_cast<int>(imu_update(p, s, kIdentity, Vec3::Zero(), Vec3(0.1_r, 0, 0), kIdentity, 0.005_r, rng, out)), 0);
  KEXPECT_NEAR(out.accel_s[2], 9.81, 1e-5);
  KEXPECT_NEAR(out.gyro_s[0], 0.1, 1e-7);
  // Rolled 90 deg: gravity appears along body y.
  KASSERT_EQ(static_cast<int>(imu_update(p, s, quat_from_euler_xyz(kPi / 2, 0, 0), Vec3::Zero(), Vec3::Zero(), kIdentity,
                                         0.005_r, rng, out)), 0);
  KEXPECT_NEAR(out.accel_s[1], 9.81, 1e-5);
  KEXPECT_NEAR(out.accel_s[2], 0, 1e-5);
  // Gravity compensation: free fall reads -g; compensated reads the kinematic acceleration.
  p.gravity_compensation = true;
  KASSERT_EQ(static_cast<int>(imu_update(p, s, kIdentity, Vec3(0, 0, -9.81_r), Vec3::Zero(), kIdentity, 0.005_r, rng, out)), 0);
  KEXPECT_NEAR(out.accel_s[2], -9.81, 1e-5);
  // Saturation.
  p.gravity_compensation = false;
  p.gyro_saturation = Vec3::Constant(1);
  KASSERT_EQ(static_cast<int>(imu_update(p, s, kIdentity, Vec3::Zero(), Vec3(0, 0, 3), kIdentity, 0.005_r, rng, out)), 0);
  KEXPECT_EQ(out.gyro_s[2], 1);
  KEXPECT_TRUE(out.saturated);
  // White-noise statistics of the BMI088 preset gyro at 200 Hz (bias walk off).
  ImuParams b = imu_preset_bmi088();
  b.enable_bias = false;
  RngStream r2(11, 3, kPurposeSensorNoise);
  double sum = 0, sum2 = 0;
  const int n = 2000;
  for (int k = 0; k < n; ++k) {
    KASSERT_EQ(static_cast<int>(imu_update(b, s, kIdentity, Vec3::Zero(), Vec3::Zero(), kIdentity, 0.005_r, r2, out)), 0);
    sum += static_cast<double>(out.gyro_s[0]);
    sum2 += static_cast<double>(out.gyro_s[0]) * static_cast<double>(out.gyro_s[0]);
  }
  const double expected_sd = static_cast<double>(b.gyro_noise_density[0]) / std::sqrt(0.005);
  const double m = sum / n;
  KEXPECT_NEAR(std::sqrt(sum2 / n - m * m), expected_sd, 0.05 * expected_sd);
  KEXPECT_NEAR(m, 0, 4 * expected_sd / std::sqrt(static_cast<double>(n)));
  // Initial bias within its range; dt <= 0 is an error.
  ImuParams v = imu_preset_vn100();
  RngStream r3(5, 0, kPurposeSensorNoise);
  imu_reset(v, s, r3);
  for (int k = 0; k < 3; ++k) KEXPECT_LE(std::fabs(s.gyro_bias_s[k]), v.gyro_initial_bias_max[k]);
  KEXPECT_EQ(static_cast<int>(imu_update(v, s, kIdentity, Vec3::Zero(), Vec3::Zero(), kIdentity, 0, r3, out)),
             static_cast<int>(Status::invalid_argument));
}

// The IMU's actual sensor frame is the nominal mount followed by the misalignment, both relative
// to the body: q_bs = q_bs_nominal * misalignment_bs (misalignment_bs is "the actual sensor frame
// relative to the nominal mount"). Two non-commuting 90 deg rotations make the order visible:
// nominal yaw 90 deg, misalignment roll 90 deg, so R_bs = Rz Rx and a reading is Rx^T Rz^T v.
// (The suite let the swapped composition through: tests/MUTANTS.md, mutant b.)
KTEST(SensorImu, MisalignmentComposesAfterTheNominalMount) {
  ImuParams p;
  p.enable_noise = false;
  p.enable_bias = false;
  ImuState s;
  s.misalignment_bs = quat_from_euler_xyz(kPi / 2, 0, 0);       // roll 90 deg
  const Quat nominal = quat_from_euler_xyz(0, 0, kPi / 2);      // yaw 90 deg
  RngStream rng(3, 0, kPurposeSensorNoise);
  ImuSample out;
  KASSERT_EQ(static_cast<int>(imu_update(p, s, kIdentity, Vec3::Zero(), Vec3(1, 2, 3), nominal, 0.005_r, rng, out)), 0);
  // Rz^T (1, 2, 3) = (2, -1, 3); Rx^T (2, -1, 3) = (2, 3, 1). Swapped order: (3, -1, -2).
  KEXPECT_NEAR(out.gyro_s[0], 2, 1e-5);
  KEXPECT_NEAR(out.gyro_s[1], 3, 1e-5);
  KEXPECT_NEAR(out.gyro_s[2], 1, 1e-5);
  // Level and still: specific force (0, 0, g) in the world reads Rx^T Rz^T (0, 0, g) = (0, g, 0)
  // (swapped: (g, 0, 0)).
  KEXPECT_NEAR(out.accel_s[0], 0, 1e-5);
  KEXPECT_NEAR(out.accel_s[1], 9.81, 1e-4);
  KEXPECT_NEAR(out.accel_s[2], 0, 1e-5);
}
