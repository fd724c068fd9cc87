// Kestrel vs Embree 3 on the same scenes and the same rays, single thread.
//
// Scene "mixed": an obstacle field of boxes, capsule tree trunks and a tessellated mesh (a few
// thousand triangles). Kestrel intersects boxes and capsules analytically (two-level: mesh BVH +
// instance BVH); Embree gets the boxes as triangles, the trunks as round linear curves (swept
// spheres with equal end radii = capsules) and the same mesh, all in one flat scene built with
// threads=1. Curves are Embree's slowest primitive, so this scene favours Kestrel.
// Scene "triangles" (issue 18): the same field made only of triangles, the same soup on both
// sides: boxes as 12 triangles, trunks as closed cylinders of kTrunkSegments sides, the mesh; one
// Kestrel TriangleMesh added once at the identity pose and one Embree triangle geometry built from
// the identical float vertex and index arrays. Triangles are Embree's fastest primitive.
// Rays: a 64 x 512 dome lidar and a 135 x 240 depth camera from inside the field. Kestrel's rays go
// through sensors::render (the full sensor path, post-processing included) and, separately, one at
// a time through Scene::intersect; Embree's through rtcIntersect1 one ray at a time and
// rtcIntersect4/8 on packets of 4/8 consecutive rays of a row (4x1 / 8x1 pixels: the image widths
// are multiples of 8, so a packet never straddles two rows). Hit distances are compared
// (mismatches counted). Kestrel's tiled render is also checked bit for bit against its own
// single-ray Scene::intersect (range, segmentation, normals): any difference fails the run.
// Timing: every figure is the best of kRounds rounds (each round: Kestrel and Embree passes in
// turn, so a load change on a shared machine hits both sides alike); ratios are of figures from
// this one run.
//
// Usage: kestrel_bench_raycast [--smoke] [--quiet] [--csv PATH]   (e.g. --csv bench/results/host/raycast.csv)
#include <embree3/rtcore.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/kernel/rng.hpp"
#include "kestrel/sensors/ray_sensor.hpp"
#include "kestrel/sim/progress.hpp"

using namespace kestrel;
using namespace kestrel::sensors;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

constexpr int kRounds = 3;
constexpr int kTrunkSegments = 24;  // sides of a tessellated trunk (chord error r (1 - cos(pi/24)) = 0.9 % of r)
// Corner order of a box: c = 0..7, x = - + + - - + + -, y = - - + + - - + +, z = - - - - + + + +.
constexpr unsigned kBoxTriangles[36] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                        2, 3, 7, 2, 7, 6, 1, 2, 6, 1, 6, 5, 3, 0, 4, 3, 4, 7};

struct Field {
  std::vector<Vec3> box_pos, box_half;
  std::vector<real> box_yaw;
  std::vector<Vec3> trunk_pos;
  std::vector<real> trunk_r, trunk_h;
  std::vector<real> mesh_v;
  std::vector<std::uint32_t> mesh_i;
  Vec3 mesh_pos;
};

// Deterministic obstacle field in a 20 x 20 m area around the origin.
Field make_field(int boxes, int trunks, int mesh_rings) {
  Field f;
  RngStream rng(2024, 0, kPurposePlacement);
  auto away = [&](real lo, real hi) {
    Vec3 p;
    do p = Vec3(rng.uniform(lo, hi), rng.uniform(lo, hi), 0);
    while (p.head<2>().norm() < 1.5_r);
    return p;
  };
  for (int i = 0; i < boxes; ++i) {
    Vec3 p = away(-10, 10);
    p[2] = rng.uniform(0, 3);
    f.box_pos.push_back(p);
    f.box_half.push_back(Vec3(rng.uniform(0.2_r, 1), rng.uniform(0.2_r, 1), rng.uniform(0.2_r, 1.5_r)));
    f.box_yaw.push_back(rng.uniform(0, kPi));
  }
  for (int i = 0; i < trunks; ++i) {
    Vec3 p = away(-10, 10);
    p[2] = 2;
    f.trunk_pos.push_back(p);
    f.trunk_r.push_back(rng.uniform(0.1_r, 0.35_r));
    f.trunk_h.push_back(2);
  }
  // A bumpy sphere ("rock") of 2 * rings * (2 rings) triangles, radius ~1.5 m, at (4, 3, 1).
  const int nu = 2 * mesh_rings, nv = mesh_rings;
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const real th = kPi * static_cast<real>(j) / static_cast<real>(nv), ph = kTwoPi * static_cast<real>(i) / static_cast<real>(nu);
      const real r = 1.5_r + 0.1_r * std::sin(5 * ph) * std::sin(3 * th);
      f.mesh_v.push_back(r * std::sin(th) * std::cos(ph));
      f.mesh_v.push_back(r * std::sin(th) * std::sin(ph));
      f.mesh_v.push_back(r * std::cos(th));
    }
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const std::uint32_t a = static_cast<std::uint32_t>(j * nu + i), b = static_cast<std::uint32_t>(j * nu + (i + 1) % nu);
      const std::uint32_t c = a + static_cast<std::uint32_t>(nu), d = b + static_cast<std::uint32_t>(nu);
      f.mesh_i.insert(f.mesh_i.end(), {a, c, b, b, c, d});
    }
  f.mesh_pos = Vec3(4, 3, 1);
  return f;
}

// The whole field as one triangle soup in the world frame (the "triangles" scene): boxes as 12
// triangles, trunks as closed cylinders (side quads + two cap fans) spanning the capsules' axis
// segment, the mesh moved to its position.
struct Soup {
  std::vector<real> v;
  std::vector<std::uint32_t> i;
};

Soup make_soup(const Field& f) {
  Soup s;
  auto vertex = [&](const Vec3& p) {
    for (int k = 0; k < 3; ++k) s.v.push_back(p[k]);
    return static_cast<std::uint32_t>(s.v.size() / 3 - 1);
  };
  for (size_t b = 0; b < f.box_pos.size(); ++b) {
    const Mat3 R = rotation_matrix(quat_from_euler_xyz(0, 0, f.box_yaw[b]));
    std::uint32_t base = 0;
    for (int c = 0; c < 8; ++c) {
      const Vec3 l((c == 1 || c == 2 || c == 5 || c == 6) ? 1 : -1, (c == 2 || c == 3 || c == 6 || c == 7) ? 1 : -1, c >= 4 ? 1 : -1);
      const std::uint32_t id = vertex(f.box_pos[b] + R * l.cwiseProduct(f.box_half[b]));
      if (c == 0) base = id;
    }
    for (unsigned k : kBoxTriangles) s.i.push_back(base + k);
  }
  for (size_t t = 0; t < f.trunk_pos.size(); ++t) {
    const Vec3& p = f.trunk_pos[t];
    const real r = f.trunk_r[t], h = f.trunk_h[t];
    const std::uint32_t lo_c = vertex(p - Vec3(0, 0, h)), hi_c = vertex(p + Vec3(0, 0, h));
    const std::uint32_t ring = static_cast<std::uint32_t>(s.v.size() / 3);
    for (int k = 0; k < kTrunkSegments; ++k) {
      const real a = kTwoPi * static_cast<real>(k) / static_cast<real>(kTrunkSegments);
      vertex(p + Vec3(r * std::cos(a), r * std::sin(a), -h));
      vertex(p + Vec3(r * std::cos(a), r * std::sin(a), h));
    }
    for (std::uint32_t k = 0; k < kTrunkSegments; ++k) {
      const std::uint32_t k1 = (k + 1) % kTrunkSegments;
      const std::uint32_t b0 = ring + 2 * k, t0 = b0 + 1, b1 = ring + 2 * k1, t1 = b1 + 1;
      s.i.insert(s.i.end(), {b0, b1, t1, b0, t1, t0, lo_c, b1, b0, hi_c, t0, t1});
    }
  }
  const std::uint32_t mesh_base = static_cast<std::uint32_t>(s.v.size() / 3);
  for (size_t k = 0; k < f.mesh_v.size() / 3; ++k)
    vertex(Vec3(f.mesh_v[3 * k], f.mesh_v[3 * k + 1], f.mesh_v[3 * k + 2]) + f.mesh_pos);
  for (std::uint32_t k : f.mesh_i) s.i.push_back(mesh_base + k);
  return s;
}

// Caller storage of one Kestrel mesh asset.
struct MeshBuffers {
  std::vector<BvhNode> nodes;
  std::vector<std::uint32_t> prims;
  std::vector<real> cache;
  std::vector<Aabb> scratch;
  explicit MeshBuffers(std::uint32_t ntri)
      : nodes(bvh_node_capacity(ntri)), prims(ntri), cache(kTriangleCacheStride * ntri), scratch(ntri) {}
  MeshStorage storage() {
    const std::uint32_t n = static_cast<std::uint32_t>(prims.size());
    return MeshStorage{nodes.data(), bvh_node_capacity(n), prims.data(), cache.data(), scratch.data(), n};
  }
};

// Caller storage of one Kestrel scene.
struct SceneBuffers {
  std::vector<SceneObject> objs;
  std::vector<BvhNode> nodes;
  std::vector<std::uint32_t> prims, map;
  std::vector<Aabb> boxes;
  Scene scene;
  explicit SceneBuffers(std::uint32_t n)
      : objs(n), nodes(bvh_node_capacity(n)), prims(n), map(n), boxes(n),
        scene(objs.data(), n, nodes.data(), bvh_node_capacity(n), prims.data(), boxes.data(), map.data()) {}
};

// One Embree triangle geometry from a Kestrel-layout vertex (x3, m) and index (x3) array.
void embree_add_triangles(RTCDevice dev, RTCScene es, const real* verts, size_t nv, const std::uint32_t* idx, size_t ntri,
                          const Vec3& offset) {
  RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
  float* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv));
  unsigned* ix = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), ntri));
  for (size_t i = 0; i < nv; ++i)
    for (int k = 0; k < 3; ++k) v[3 * i + static_cast<size_t>(k)] = static_cast<float>(verts[3 * i + static_cast<size_t>(k)] + offset[k]);
  for (size_t i = 0; i < 3 * ntri; ++i) ix[i] = idx[i];
  rtcCommitGeometry(g);
  rtcAttachGeometry(es, g);
  rtcReleaseGeometry(g);
}

struct Result {
  std::string sensor;
  const char* scene;
  std::uint32_t rays;
  double kestrel_mrays, kestrel_single_mrays, embree_mrays, embree4_mrays, embree8_mrays;
  long mismatches;
  long identity_diffs;  // render vs single-ray Scene::intersect, bitwise
  double kestrel_build_ms, embree_build_ms;
};

bool same_bits(real a, real b) { return std::memcmp(&a, &b, sizeof(real)) == 0; }

// One pass of packets of W rays (W = 4 or 8) along the table's row-major order, all lanes valid
// except at the end. Returns the seconds taken.
template <int W, typename RayHitW, typename Fn>
double embree_packets(RTCScene es, const std::vector<real>& dirs, std::uint32_t n, const Mat3& R, const Vec3& o,
                      real tfar, Fn&& intersect) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  alignas(64) RayHitW rh;
  alignas(64) int valid[W];
  const auto t1 = Clock::now();
  for (std::uint32_t i0 = 0; i0 < n; i0 += W) {
    for (int l = 0; l < W; ++l) {
      const std::uint32_t i = i0 + static_cast<std::uint32_t>(l);
      valid[l] = i < n ? -1 : 0;
      const std::uint32_t ii = i < n ? i : n - 1;
      const Vec3 d = R * Vec3(dirs[3 * ii], dirs[3 * ii + 1], dirs[3 * ii + 2]);
      rh.ray.org_x[l] = static_cast<float>(o[0]);
      rh.ray.org_y[l] = static_cast<float>(o[1]);
      rh.ray.org_z[l] = static_cast<float>(o[2]);
      rh.ray.dir_x[l] = static_cast<float>(d[0]);
      rh.ray.dir_y[l] = static_cast<float>(d[1]);
      rh.ray.dir_z[l] = static_cast<float>(d[2]);
      rh.ray.tnear[l] = 0;
      rh.ray.tfar[l] = static_cast<float>(tfar);
      rh.ray.mask[l] = 0xffffffffu;
      rh.ray.flags[l] = 0;
      rh.ray.time[l] = 0;
      rh.hit.geomID[l] = RTC_INVALID_GEOMETRY_ID;
    }
    intersect(valid, es, &ctx, &rh);
  }
  return seconds_since(t1);
}

// One pass of rtcIntersect1 over the table; with cmp, counts distance mismatches against cmp
// (-1: no hit) into *mismatches.
double embree_single(RTCScene es, const std::vector<real>& dirs, std::uint32_t n, const Mat3& R, const Vec3& o, real tfar,
                     const real* cmp, long* mismatches) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  const auto t1 = Clock::now();
  for (std::uint32_t i = 0; i < n; ++i) {
    const Vec3 d = R * Vec3(dirs[3 * i], dirs[3 * i + 1], dirs[3 * i + 2]);
    RTCRayHit rh;
    rh.ray.org_x = static_cast<float>(o[0]);
    rh.ray.org_y = static_cast<float>(o[1]);
    rh.ray.org_z = static_cast<float>(o[2]);
    rh.ray.dir_x = static_cast<float>(d[0]);
    rh.ray.dir_y = static_cast<float>(d[1]);
    rh.ray.dir_z = static_cast<float>(d[2]);
    rh.ray.tnear = 0;
    rh.ray.tfar = static_cast<float>(tfar);
    rh.ray.mask = 0xffffffffu;
    rh.ray.flags = 0;
    rh.ray.time = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(es, &ctx, &rh);
    if (cmp != nullptr) {
      const double e = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? -1.0 : static_cast<double>(rh.ray.tfar);
      if (std::fabs(e - static_cast<double>(cmp[i])) > 1e-3) ++*mismatches;
    }
  }
  return seconds_since(t1);
}

std::string load_average() {
  std::FILE* fp = std::fopen("/proc/loadavg", "r");
  char buf[64] = "?";
  if (fp != nullptr) {
    if (std::fscanf(fp, "%63s", buf) != 1) buf[0] = '?', buf[1] = 0;
    std::fclose(fp);
  }
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  bool smoke = false, quiet = false;
  const char* csv = nullptr;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--smoke") == 0) smoke = true;
    else if (std::strcmp(argv[i], "--quiet") == 0) quiet = true;
    else if (std::strcmp(argv[i], "--csv") == 0 && i + 1 < argc) csv = argv[++i];
    else csv = argv[i];  // legacy: bare path
  }
  const std::string load_start = load_average();
  const Field f = smoke ? make_field(10, 5, 8) : make_field(150, 60, 40);
  const Soup soup = make_soup(f);
  const int reps = smoke ? 1 : 20;
  const int rounds = smoke ? 1 : kRounds;
  const int build_reps = smoke ? 1 : 10;
  const std::uint32_t ntri = static_cast<std::uint32_t>(f.mesh_i.size() / 3);
  const std::uint32_t soup_ntri = static_cast<std::uint32_t>(soup.i.size() / 3);
  const std::uint32_t nobj = static_cast<std::uint32_t>(f.box_pos.size() + f.trunk_pos.size() + 1);

  // ---- Kestrel builds: mixed (mesh asset + analytic instances), triangles (one mesh) ----
  MeshBuffers mbuf(ntri), sbuf(soup_ntri);
  SceneBuffers mixed(nobj), tris(1);
  TriangleMesh mesh, soup_mesh;
  double k_mesh_build = 1e9, k_scene_build = 1e9, k_soup_build = 1e9;
  for (int r = 0; r < build_reps; ++r) {
    mesh = TriangleMesh{};
    mesh.vertices = f.mesh_v.data();
    mesh.vertex_count = static_cast<std::uint32_t>(f.mesh_v.size() / 3);
    mesh.indices = f.mesh_i.data();
    mesh.triangle_count = ntri;
    auto t0 = Clock::now();
    if (mesh_build(mesh, mbuf.storage()) != Status::ok) return 2;
    k_mesh_build = std::min(k_mesh_build, seconds_since(t0));
    Scene& scene = mixed.scene;
    scene.clear();
    t0 = Clock::now();
    std::uint32_t seg = 1;
    for (size_t i = 0; i < f.box_pos.size(); ++i)
      if (scene.add(Shape::box(f.box_half[i][0], f.box_half[i][1], f.box_half[i][2]), f.box_pos[i],
                    quat_from_euler_xyz(0, 0, f.box_yaw[i]), seg++) != Status::ok)
        return 2;
    for (size_t i = 0; i < f.trunk_pos.size(); ++i)
      if (scene.add(Shape::capsule(f.trunk_r[i], f.trunk_h[i]), f.trunk_pos[i], Quat::Identity(), seg++) != Status::ok) return 2;
    if (scene.add(Shape::triangle_mesh(&mesh), f.mesh_pos, Quat::Identity(), seg++) != Status::ok) return 2;
    if (scene.build() != Status::ok) return 2;
    k_scene_build = std::min(k_scene_build, seconds_since(t0));

    soup_mesh = TriangleMesh{};
    soup_mesh.vertices = soup.v.data();
    soup_mesh.vertex_count = static_cast<std::uint32_t>(soup.v.size() / 3);
    soup_mesh.indices = soup.i.data();
    soup_mesh.triangle_count = soup_ntri;
    t0 = Clock::now();
    if (mesh_build(soup_mesh, sbuf.storage()) != Status::ok) return 2;
    tris.scene.clear();
    if (tris.scene.add(Shape::triangle_mesh(&soup_mesh), Vec3::Zero(), Quat::Identity(), 1) != Status::ok) return 2;
    if (tris.scene.build() != Status::ok) return 2;
    k_soup_build = std::min(k_soup_build, seconds_since(t0));
  }

  // ---- Embree builds (flat scenes, one thread) ----
  RTCDevice dev = rtcNewDevice("threads=1");
  double e_build = 1e9, e_soup_build = 1e9;
  RTCScene es = nullptr, es_tris = nullptr;
  for (int r = 0; r < build_reps; ++r) {
    if (es) rtcReleaseScene(es);
    auto t0 = Clock::now();
    es = rtcNewScene(dev);
    // Boxes as 12 triangles each.
    {
      RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
      const size_t nb = f.box_pos.size();
      float* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 8 * nb));
      unsigned* ix = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), 12 * nb));
      for (size_t b = 0; b < nb; ++b) {
        const Mat3 R = rotation_matrix(quat_from_euler_xyz(0, 0, f.box_yaw[b]));
        for (int c = 0; c < 8; ++c) {
          const Vec3 l((c == 1 || c == 2 || c == 5 || c == 6) ? 1 : -1, (c == 2 || c == 3 || c == 6 || c == 7) ? 1 : -1, c >= 4 ? 1 : -1);
          const Vec3 w = f.box_pos[b] + R * l.cwiseProduct(f.box_half[b]);
          for (int k = 0; k < 3; ++k) v[3 * (8 * b + static_cast<size_t>(c)) + static_cast<size_t>(k)] = static_cast<float>(w[k]);
        }
        for (int k = 0; k < 36; ++k) ix[36 * b + static_cast<size_t>(k)] = kBoxTriangles[k] + 8 * static_cast<unsigned>(b);
      }
      rtcCommitGeometry(g);
      rtcAttachGeometry(es, g);
      rtcReleaseGeometry(g);
    }
    // Trunks: round linear curves with equal radii = capsules.
    {
      RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_ROUND_LINEAR_CURVE);
      const size_t nt = f.trunk_pos.size();
      float* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 2 * nt));
      unsigned* ix = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, sizeof(unsigned), nt));
      for (size_t t = 0; t < nt; ++t) {
        for (int e = 0; e < 2; ++e) {
          float* p = &v[4 * (2 * t + static_cast<size_t>(e))];
          p[0] = static_cast<float>(f.trunk_pos[t][0]);
          p[1] = static_cast<float>(f.trunk_pos[t][1]);
          p[2] = static_cast<float>(f.trunk_pos[t][2] + (e == 0 ? -f.trunk_h[t] : f.trunk_h[t]));
          p[3] = static_cast<float>(f.trunk_r[t]);
        }
        ix[t] = static_cast<unsigned>(2 * t);
      }
      rtcCommitGeometry(g);
      rtcAttachGeometry(es, g);
      rtcReleaseGeometry(g);
    }
    embree_add_triangles(dev, es, f.mesh_v.data(), f.mesh_v.size() / 3, f.mesh_i.data(), ntri, f.mesh_pos);
    rtcCommitScene(es);
    e_build = std::min(e_build, seconds_since(t0));

    if (es_tris) rtcReleaseScene(es_tris);
    t0 = Clock::now();
    es_tris = rtcNewScene(dev);
    embree_add_triangles(dev, es_tris, soup.v.data(), soup.v.size() / 3, soup.i.data(), soup_ntri, Vec3::Zero());
    rtcCommitScene(es_tris);
    e_soup_build = std::min(e_soup_build, seconds_since(t0));
  }

  // ---- Rays ----
  LidarParams lp = lidar_preset_osdome_64();
  lp.range.max_range = 20;
  CameraParams cp = camera_preset_base();
  if (smoke) {
    lp.height = 8;
    lp.width = 16;
    cp.height = 9;
    cp.width = 16;
  }
  const std::uint32_t nmax = std::max(lp.height * lp.width, cp.height * cp.width);
  std::vector<real> dirs(3 * nmax), scale(nmax), range(nmax), raw(nmax), normals(3 * nmax);
  std::vector<std::int32_t> segs(nmax);
  SensorPose pose;
  pose.position_w = Vec3(0.3_r, -0.2_r, 1.2_r);
  pose.orientation_ws = quat_from_euler_xyz(0, 0, 0.4_r);
  const Mat3 R = rotation_matrix(pose.orientation_ws);

  // The rays cast below, both scenes and sensors, on one progress line (issue 15; a terminal only,
  // off with --quiet): per scene and sensor and round, reps passes of each of the five methods;
  // then 1 raw, 1 compared Embree and 4 identity passes. Updated between passes, outside the timing.
  const double passes = 5.0 * reps * rounds + 6.0;
  kestrel::sim::ProgressLine progress(
      stderr, kestrel::sim::ProgressLine::enabled_for(quiet),
      2 * passes * (static_cast<double>(lp.height) * lp.width + static_cast<double>(cp.height) * cp.width), "rays");
  double rays_done = 0;
  auto progress_add = [&](double rays) {
    rays_done += rays;
    progress.update(rays_done);
  };
  std::vector<Result> results;
  for (int sc = 0; sc < 2; ++sc) {
    const bool tri_scene = sc == 1;
    const Scene& scene = tri_scene ? tris.scene : mixed.scene;
    RTCScene escene = tri_scene ? es_tris : es;
    for (int s = 0; s < 2; ++s) {
      RayTable table{dirs.data(), scale.data(), nmax, 0, 0};
      const bool is_cam = s == 1;
      if ((is_cam ? camera_rays(cp, table) : lidar_rays(lp, table)) != Status::ok) return 3;
      const RangeOutputParams op = is_cam ? cp.range : lp.range;
      const std::uint32_t n = table.height * table.width;
      const real tf = op.max_range;
      SensorOutput out;
      out.range = range.data();
      // Best (shortest) pass of each method over the rounds; each round runs the methods in turn.
      double tk = 1e9, tk1 = 1e9, te = 1e9, te4 = 1e9, te8 = 1e9;
      for (int round = 0; round < rounds; ++round) {
        for (int r = 0; r < reps; ++r) {  // Kestrel: range mode so both engines report the same quantity
          const auto t0 = Clock::now();
          if (render(scene, pose, table, op, false, out) != Status::ok) return 4;
          tk = std::min(tk, seconds_since(t0));
          progress_add(n);  // between reps, outside the timing
        }
        for (int r = 0; r < reps; ++r) {  // Kestrel, one Scene::intersect per ray (no tiles)
          const auto t0 = Clock::now();
          for (std::uint32_t i = 0; i < n; ++i) {
            const Vec3 d = R * Vec3(dirs[3 * i], dirs[3 * i + 1], dirs[3 * i + 2]);
            SceneHit h;
            raw[i] = scene.intersect(pose.position_w, d, 0, tf, h) ? h.t : -1_r;
          }
          tk1 = std::min(tk1, seconds_since(t0));
          progress_add(n);
        }
        for (int r = 0; r < reps; ++r) {
          te = std::min(te, embree_single(escene, dirs, n, R, pose.position_w, tf, nullptr, nullptr));
          progress_add(n);
        }
        for (int r = 0; r < reps; ++r) {
          te4 = std::min(te4, embree_packets<4, RTCRayHit4>(escene, dirs, n, R, pose.position_w, tf,
                                                            [](const int* v, RTCScene e, RTCIntersectContext* c, RTCRayHit4* h) {
                                                              rtcIntersect4(v, e, c, h);
                                                            }));
          progress_add(n);
        }
        for (int r = 0; r < reps; ++r) {
          te8 = std::min(te8, embree_packets<8, RTCRayHit8>(escene, dirs, n, R, pose.position_w, tf,
                                                            [](const int* v, RTCScene e, RTCIntersectContext* c, RTCRayHit8* h) {
                                                              rtcIntersect8(v, e, c, h);
                                                            }));
          progress_add(n);
        }
      }
      // Raw Kestrel distances (no post-processing) against Embree's, untimed.
      for (std::uint32_t i = 0; i < n; ++i) {
        const Vec3 d = R * Vec3(dirs[3 * i], dirs[3 * i + 1], dirs[3 * i + 2]);
        SceneHit h;
        raw[i] = scene.intersect(pose.position_w, d, 0, tf, h) ? h.t : -1_r;
      }
      long mismatches = 0;
      embree_single(escene, dirs, n, R, pose.position_w, tf, raw.data(), &mismatches);
      progress_add(2.0 * n);
      // Identity: the tiled render (all outputs) against single-ray Scene::intersect, both modes.
      long diffs = 0;
      for (int mode = 0; mode < 2; ++mode) {
        const bool depth = mode == 1;
        SensorOutput full;
        full.range = range.data();
        full.segmentation = segs.data();
        full.normals_w = normals.data();
        if (render(scene, pose, table, op, depth, full) != Status::ok) return 4;
        for (std::uint32_t i = 0; i < n; ++i) {
          const real* ds = &dirs[3 * i];
          const Mat3 Rr = rotation_matrix(pose.orientation_ws.normalized());
          const real d[3] = {Rr(0, 0) * ds[0] + Rr(0, 1) * ds[1] + Rr(0, 2) * ds[2],
                             Rr(1, 0) * ds[0] + Rr(1, 1) * ds[1] + Rr(1, 2) * ds[2],
                             Rr(2, 0) * ds[0] + Rr(2, 1) * ds[1] + Rr(2, 2) * ds[2]};
          const real o[3] = {pose.position_w[0], pose.position_w[1], pose.position_w[2]};
          const real sc_i = depth ? scale[i] : 1_r;
          SceneHit h;
          const bool found = scene.intersect(make_ray(o, d), 0, op.max_range / sc_i, h);
          real v = found ? h.t * sc_i : kNoHitValue;
          if (v > op.max_range) v = op.far_out_of_range_value;
          else if (v < op.min_range) v = op.near_out_of_range_value;
          if (op.normalize_range) v = v / op.max_range;
          bool same = same_bits(v, range[i]) && segs[i] == (found ? static_cast<std::int32_t>(h.seg_id) : kNoHitSegment);
          for (int k = 0; k < 3; ++k) same = same && same_bits(found ? h.normal_w[k] : 0_r, normals[3 * i + k]);
          if (!same) ++diffs;
        }
      }
      progress_add(4.0 * n);
      std::string name = is_cam ? "camera_135x240" : "lidar_64x512";
      if (tri_scene) name += "_triangles";
      results.push_back(Result{name, tri_scene ? "triangles" : "mixed", n, n / tk * 1e-6, n / tk1 * 1e-6, n / te * 1e-6,
                               n / te4 * 1e-6, n / te8 * 1e-6, mismatches, diffs,
                               (tri_scene ? k_soup_build : k_mesh_build + k_scene_build) * 1e3,
                               (tri_scene ? e_soup_build : e_build) * 1e3});
    }
  }
  const std::string load_end = load_average();

  progress.finish();
  std::printf("scene mixed: %zu boxes, %zu capsule trunks, %u mesh triangles (%u objects)\n", f.box_pos.size(), f.trunk_pos.size(),
              ntri, nobj);
  std::printf("scene triangles: %u triangles (boxes 12 each, trunks %d-sided cylinders %d each, the mesh), one mesh / one geometry\n",
              soup_ntri, kTrunkSegments, 4 * kTrunkSegments);
  std::printf("build mixed: kestrel mesh %.3f ms + instances %.3f ms = %.3f ms; embree (threads=1) %.3f ms; ratio embree/kestrel %.2f\n",
              k_mesh_build * 1e3, k_scene_build * 1e3, (k_mesh_build + k_scene_build) * 1e3, e_build * 1e3,
              e_build / (k_mesh_build + k_scene_build));
  std::printf("build triangles: kestrel %.3f ms; embree (threads=1) %.3f ms; ratio embree/kestrel %.2f\n", k_soup_build * 1e3,
              e_soup_build * 1e3, e_soup_build / k_soup_build);
  std::printf("best of %d rounds of %d passes; Mrays/s, one thread; load average %s at start, %s at end\n", rounds, reps,
              load_start.c_str(), load_end.c_str());
  for (const Result& r : results) {
    std::printf("%-24s %6u rays: kestrel render %.2f (single rays %.2f), embree rtcIntersect1 %.2f, 4 %.2f, 8 %.2f Mrays/s; "
                "kestrel/embree1 %.2f, kestrel/embree8 %.2f; mismatches %ld, render vs single-ray diffs %ld\n",
                r.sensor.c_str(), r.rays, r.kestrel_mrays, r.kestrel_single_mrays, r.embree_mrays, r.embree4_mrays, r.embree8_mrays,
                r.kestrel_mrays / r.embree_mrays, r.kestrel_mrays / r.embree8_mrays, r.mismatches, r.identity_diffs);
  }
  if (csv) {
    FILE* fp = std::fopen(csv, "w");
    if (fp == nullptr) {
      std::fprintf(stderr, "cannot write %s\n", csv);
      return 5;
    }
    // The first eleven columns are the original ones (ratio: render vs rtcIntersect1); new ones
    // are appended so readers by name or position keep working.
    std::fprintf(fp, "sensor,rays,kestrel_mrays_s,embree_rtcintersect1_mrays_s,ratio,mismatches,kestrel_build_ms,embree_build_ms,"
                     "embree_rtcintersect4_mrays_s,embree_rtcintersect8_mrays_s,render_vs_single_ray_diffs,"
                     "scene,kestrel_single_ray_mrays_s,ratio_vs_rtcintersect8,note\n");
    for (const Result& r : results)
      std::fprintf(fp, "%s,%u,%.4f,%.4f,%.4f,%ld,%.4f,%.4f,%.4f,%.4f,%ld,%s,%.4f,%.4f,best of %d rounds; packets 4x1/8x1 pixels of a row; "
                       "one thread; load average %s -> %s\n",
                   r.sensor.c_str(), r.rays, r.kestrel_mrays, r.embree_mrays, r.kestrel_mrays / r.embree_mrays, r.mismatches,
                   r.kestrel_build_ms, r.embree_build_ms, r.embree4_mrays, r.embree8_mrays, r.identity_diffs, r.scene,
                   r.kestrel_single_mrays, r.kestrel_mrays / r.embree8_mrays, rounds, load_start.c_str(), load_end.c_str());
    std::fclose(fp);
  }
  rtcReleaseScene(es);
  rtcReleaseScene(es_tris);
  rtcReleaseDevice(dev);
  long total = 0, rays = 0;
  for (const Result& r : results) {
    if (r.identity_diffs != 0) return 1;
    total += r.mismatches;
    rays += r.rays;
  }
  return total > rays / 100 ? 1 : 0;  // >1 % disagreement fails
}
