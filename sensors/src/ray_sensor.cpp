// Ray tables, presets, mounting, noise and the render loop (see ray_sensor.hpp).
#include "kestrel/sensors/ray_sensor.hpp"

#include <cmath>

#include "kestrel/kernel/quaternion.hpp"

namespace kestrel::sensors {

namespace {

// Values shared by the Aerial Gym configs (base_sensor_config.py / base_*_config.py).
const Vec3 kBaseMinTranslation(0.07_r, -0.06_r, 0.01_r), kBaseMaxTranslation(0.12_r, 0.03_r, 0.04_r);
const Vec3 kBaseMinEuler(-5, -5, -5), kBaseMaxEuler(5, 5, 5);
const Vec3 kBaseNominalPosition(0.10_r, 0, 0.03_r);

MountParams mount(bool randomize, const Vec3& tmin, const Vec3& tmax, const Vec3& emin, const Vec3& emax) {
  MountParams m;
  m.nominal_position_b = kBaseNominalPosition;
  m.nominal_euler_deg = Vec3::Zero();
  m.randomize_placement = randomize;
  m.min_translation_b = tmin;
  m.max_translation_b = tmax;
  m.min_euler_deg = emin;
  m.max_euler_deg = emax;
  m.fixed_pose_at_range_mean = true;  // warp sensor semantics
  return m;
}

RangeOutputParams range(real rmin, real rmax, bool normalize, real far, real near) {
  RangeOutputParams r;
  r.min_range = rmin;
  r.max_range = rmax;
  r.normalize_range = normalize;
  r.far_out_of_range_value = far;
  r.near_out_of_range_value = near;
  return r;
}

NoiseParams range_noise(bool enable, real a, real b, real c, real mean_offset, real dropout) {
  NoiseParams n;
  n.enable_sensor_noise = enable;
  n.model = NoiseParams::Model::range_dependent;
  n.a = a;
  n.b = b;
  n.c = c;
  n.mean_offset = mean_offset;
  n.pixel_dropout_prob = dropout;
  return n;
}

NoiseParams multiplier_noise(bool enable, real multiplier, real dropout) {
  NoiseParams n;
  n.enable_sensor_noise = enable;
  n.model = NoiseParams::Model::multiplier;
  n.std_dev_multiplier = multiplier;
  n.pixel_dropout_prob = dropout;
  return n;
}

LidarParams lidar(std::uint32_t h, std::uint32_t w, real hmin, real hmax, real vmin, real vmax) {
  LidarParams p;
  p.height = h;
  p.width = w;
  p.horizontal_fov_deg_min = hmin;
  p.horizontal_fov_deg_max = hmax;
  p.vertical_fov_deg_min = vmin;
  p.vertical_fov_deg_max = vmax;
  return p;
}

CameraParams camera(std::uint32_t h, std::uint32_t w, real hfov) {
  CameraParams p;
  p.height = h;
  p.width = w;
  p.horizontal_fov_deg = hfov;
  p.calculate_depth = true;
  p.output = OutputFlags{false, false, true};
  // Every camera config: randomize_placement ranges and nominal pose of the base camera config.
  p.mount = mount(true, kBaseMinTranslation, kBaseMaxTranslation, kBaseMinEuler, kBaseMaxEuler);
  p.noise = multiplier_noise(false, 0.01_r, 0.01_r);
  return p;
}

// OS0-128 class values (os0_128_config.py), inherited by OS0-64 / OS1-64 / OS2-64.
LidarParams os0_128_family(std::uint32_t h, real vmin, real vmax, real rmin, real rmax) {
  LidarParams p = lidar(h, 512, -180, 180, vmin, vmax);
  p.range = range(rmin, rmax, true, 35, -35);
  p.output = OutputFlags{false, false, true};
  // Mount inherited from base_lidar_config.py.
  p.mount = mount(true, kBaseMinTranslation, kBaseMaxTranslation, kBaseMinEuler, kBaseMaxEuler);
  return p;
}

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

}  // namespace

LidarParams lidar_preset_base() {
  LidarParams p = lidar(128, 512, -180, 180, -45, 45);
  p.range = range(0.2_r, 10, true, 10, -10);
  p.output = OutputFlags{false, false, true};
  p.mount = mount(true, kBaseMinTranslation, kBaseMaxTranslation, kBaseMinEuler, kBaseMaxEuler);
  p.noise = range_noise(true, 0.00001_r, 0.00001_r, 0.00001_r, -0.05_r, 0);
  return p;
}

LidarParams lidar_preset_osdome_64() {
  LidarParams p = lidar(64, 512, -180, 180, 0, 90);
  p.range = range(0.5_r, 20, true, 10, -10);  // out-of-range values inherited (base max_range 10)
  p.output = OutputFlags{false, false, true};
  p.mount = mount(false, Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero());
  p.noise = range_noise(false, 0.00038089_r, -0.00343351_r, 0.01553284_r, -0.025_r, 0);
  return p;
}

LidarParams lidar_preset_os0_128() {
  LidarParams p = os0_128_family(128, -45, 45, 0.2_r, 35);
  p.noise = range_noise(false, 3.36239104e-05_r, -3.17199061e-04_r, 9.61903860e-03_r, -0.05_r, 0);
  return p;
}

LidarParams lidar_preset_os0_64() {
  LidarParams p = os0_128_family(64, -45, 45, 0.2_r, 35);
  p.noise = range_noise(false, 3.36239104e-05_r, -3.17199061e-04_r, 9.61903860e-03_r, -0.025_r, 0);
  return p;
}

LidarParams lidar_preset_os1_64() {
  LidarParams p = os0_128_family(64, -22.5_r, 22.5_r, 0.7_r, 90);
  p.noise = range_noise(false, 3.08287454e-06_r, -4.07347360e-06_r, 5.30757302e-03_r, -0.025_r, 0);
  return p;
}

LidarParams lidar_preset_os2_64() {
  LidarParams p = os0_128_family(64, -11.25_r, 11.25_r, 0.7_r, 200);
  p.noise = range_noise(false, 3.08287454e-06_r, -4.07347360e-06_r, 5.30757302e-03_r, -0.025_r, 0);
  return p;
}

LidarParams lidar_preset_rs_airy() {
  LidarParams p = lidar(48, 120, -180, 180, 0, 90);
  p.range = range(0.2_r, 10, false, 10, -10);  // out-of-range values inherited from the base class
  p.output = OutputFlags{true, true, false};
  p.mount = mount(true, Vec3(-0.05_r, 0, 0), Vec3(-0.05_r, 0, 0), Vec3(0, -90, 0), Vec3(0, -90, 0));
  p.noise = range_noise(false, 0.00038089_r, -0.00343351_r, 0.01553284_r, -0.025_r, 0);
  return p;
}

LidarParams lidar_preset_pmd_flexx2() {
  LidarParams p = lidar(172, 224, -28, 28, -22, 22);
  p.range = range(0.2_r, 5, true, 5, -5);
  p.output = OutputFlags{false, false, false};
  p.mount = mount(true, Vec3(0.07_r, -0.06_r, 0.02_r), Vec3(0.12_r, 0.03_r, 0.06_r), kBaseMinEuler, kBaseMaxEuler);
  p.noise = range_noise(false, 3.08287454e-06_r, -4.07347360e-06_r, 5.30757302e-03_r, -0.025_r, 0.01_r);
  return p;
}

LidarParams lidar_preset_vl53l5cx() {
  LidarParams p = lidar(8, 8, -45, 45, -45, 45);
  p.range = range(0.2_r, 4, false, -1, -1);
  p.output = OutputFlags{false, false, false};
  p.mount = mount(false, kBaseMinTranslation, kBaseMaxTranslation, kBaseMinEuler, kBaseMaxEuler);
  // The config's sensor_noise has only pixel_std_dev_multiplier / pixel_dropout_prob (Aerial Gym's
  // WarpSensor reads std_a.. and would fail on it); the multiplier model is applied.
  p.noise = multiplier_noise(true, 0.02_r, 0.01_r);
  return p;
}

CameraParams camera_preset_base() {
  CameraParams p = camera(135, 240, 87);
  p.range = range(0.2_r, 10, true, 10, -10);
  return p;
}

CameraParams camera_preset_d455() {
  CameraParams p = camera(270, 480, 87);
  p.range = range(0.2_r, 15, true, 15, -15);
  return p;
}

CameraParams camera_preset_oakd() {
  CameraParams p = camera(270, 480, 72);
  p.range = range(0.7_r, 12, true, 12, -12);
  p.output.segmentation_camera = false;
  p.mount.randomize_placement = false;
  return p;
}

CameraParams camera_preset_oakd_pro_w() {
  CameraParams p = camera_preset_oakd();  // subclass of the OAK-D config
  p.horizontal_fov_deg = 127;
  p.range.min_range = 0.2_r;              // max 12; out-of-range values inherited (12, -12)
  return p;
}

void lidar_ray(const LidarParams& p, std::uint32_t i, std::uint32_t j, real out[3]) {
  // Angles and directions in double as the reference computes them (cheap: once per sensor).
  const double hmax = static_cast<double>(p.horizontal_fov_deg_max) * kDegToRad;
  const double hmin = static_cast<double>(p.horizontal_fov_deg_min) * kDegToRad;
  const double vmax = static_cast<double>(p.vertical_fov_deg_max) * kDegToRad;
  const double vmin = static_cast<double>(p.vertical_fov_deg_min) * kDegToRad;
  const double el = p.height > 1 ? vmax - (vmax - vmin) * static_cast<double>(i) / static_cast<double>(p.height - 1) : vmax;
  const double az = p.width > 1 ? hmax - (hmax - hmin) * static_cast<double>(j) / static_cast<double>(p.width - 1) : hmax;
  const real d[3] = {static_cast<real>(std::cos(az) * std::cos(el)), static_cast<real>(std::sin(az) * std::cos(el)),
                     static_cast<real>(std::sin(el))};
  const real inv = 1 / std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  for (int k = 0; k < 3; ++k) out[k] = d[k] * inv;
}

Status lidar_rays(const LidarParams& p, RayTable& t) {
  if (p.height == 0 || p.width == 0) return Status::invalid_argument;
  const std::uint32_t n = p.height * p.width;
  if (t.dirs_s == nullptr || t.depth_scale == nullptr || t.capacity < n) return Status::capacity_exceeded;
  for (std::uint32_t i = 0; i < p.height; ++i) {
    for (std::uint32_t j = 0; j < p.width; ++j) {
      lidar_ray(p, i, j, &t.dirs_s[3 * (i * p.width + j)]);
      t.depth_scale[i * p.width + j] = 1;
    }
  }
  t.height = p.height;
  t.width = p.width;
  return Status::ok;
}

namespace {

// Unit optical-frame direction of integer pixel (x, y) (golden: no half-pixel offset).
void optical_dir(const CameraParams& p, std::uint32_t x, std::uint32_t y, real o[3]) {
  const double f =
      (static_cast<double>(p.width) / 2.0) / std::tan(static_cast<double>(p.horizontal_fov_deg) * kDegToRad / 2.0);
  const real inv_f = static_cast<real>(1.0 / f);
  const real u0 = static_cast<real>(p.width) / 2, v0 = static_cast<real>(p.height) / 2;
  o[0] = (static_cast<real>(x) - u0) * inv_f;
  o[1] = (static_cast<real>(y) - v0) * inv_f;
  o[2] = 1;
  const real inv = 1 / std::sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
  for (int k = 0; k < 3; ++k) o[k] *= inv;
}

}  // namespace

void camera_ray(const CameraParams& p, std::uint32_t y, std::uint32_t x, real out[3], real& depth_scale) {
  real principal[3], o[3];
  optical_dir(p, p.width / 2, p.height / 2, principal);  // golden quirk 11: integer principal pixel
  optical_dir(p, x, y, o);
  out[0] = o[2];  // optical -> sensor: (z, -x, -y)
  out[1] = -o[0];
  out[2] = -o[1];
  depth_scale = p.calculate_depth ? o[0] * principal[0] + o[1] * principal[1] + o[2] * principal[2] : 1_r;
}

Status camera_rays(const CameraParams& p, RayTable& t) {
  if (p.height == 0 || p.width == 0 || !(p.horizontal_fov_deg > 0) || !(p.horizontal_fov_deg < 180))
    return Status::invalid_argument;
  const std::uint32_t n = p.height * p.width;
  if (t.dirs_s == nullptr || t.depth_scale == nullptr || t.capacity < n) return Status::capacity_exceeded;
  for (std::uint32_t y = 0; y < p.height; ++y)
    for (std::uint32_t x = 0; x < p.width; ++x)
      camera_ray(p, y, x, &t.dirs_s[3 * (y * p.width + x)], t.depth_scale[y * p.width + x]);
  t.height = p.height;
  t.width = p.width;
  return Status::ok;
}

Mount sample_mount(const MountParams& p, RngStream& rng) {
  Vec3 pos = p.nominal_position_b, eul = p.nominal_euler_deg;
  if (p.fixed_pose_at_range_mean) {
    pos = Vec3::Zero();
    eul = (p.min_euler_deg + p.max_euler_deg) / 2;
  }
  if (p.randomize_placement) {
    for (int k = 0; k < 3; ++k) pos[k] = rng.uniform(p.min_translation_b[k], p.max_translation_b[k]);
    for (int k = 0; k < 3; ++k) eul[k] = rng.uniform(p.min_euler_deg[k], p.max_euler_deg[k]);
  }
  const real s = kPi / 180;
  Mount m;
  m.position_b = pos;
  m.orientation_bs = quat_from_euler_xyz(eul[0] * s, eul[1] * s, eul[2] * s);
  return m;
}

SensorPose sensor_pose(const RigidBodyState& body, const Mount& m) {
  SensorPose sp;
  sp.position_w = body.position_w + rotate(body.orientation_wb, m.position_b);
  sp.orientation_ws = (body.orientation_wb * m.orientation_bs).normalized();
  return sp;
}

void apply_noise(const NoiseParams& p, real* values, std::uint32_t n, RngStream& rng, real dropout_value) {
  if (!p.enable_sensor_noise || p.model == NoiseParams::Model::none) return;
  for (std::uint32_t i = 0; i < n; ++i) {
    const real u = rng.uniform();
    const real g = rng.normal();
    const real r = values[i];
    if (p.model == NoiseParams::Model::range_dependent) {
      const real stddev = p.a * r * r + p.b * r + p.c;
      values[i] = (r - p.mean_offset) + g * stddev;  // Aerial Gym: N(mean = r - mean_offset, std)
    } else {
      values[i] = r + g * (p.std_dev_multiplier * r);
    }
    if (u < p.pixel_dropout_prob) values[i] = dropout_value;
  }
}

// Tile packets (Scene::intersect_tile) where the host has vector lanes for their per-ray loops;
// on a scalar FPU (the MCUs) they would only add stack (a few KB per tile) and code, so render
// casts ray by ray there. Both give the same bits.
#ifndef KESTREL_SENSORS_TILE_PACKETS
#if defined(__SSE2__) || defined(__ARM_NEON) || defined(__AVX__)
#define KESTREL_SENSORS_TILE_PACKETS 1
#else
#define KESTREL_SENSORS_TILE_PACKETS 0
#endif
#endif

Status render(const Scene& scene, const SensorPose& pose, const RayTable& table, const RangeOutputParams& op,
              bool depth, SensorOutput& out, const NoiseParams* noise, RngStream* rng) {
  const std::uint32_t n = table.height * table.width;
  if (scene.dirty() || n == 0 || table.dirs_s == nullptr || n > table.capacity || !(op.max_range > 0))
    return Status::invalid_argument;
  if (noise != nullptr && noise->enable_sensor_noise && noise->model != NoiseParams::Model::none &&
      (rng == nullptr || out.range == nullptr))
    return Status::invalid_argument;
  const Mat3 r = rotation_matrix(pose.orientation_ws.normalized());
  const real o[3] = {pose.position_w[0], pose.position_w[1], pose.position_w[2]};
  // All rays share the sensor origin: the image is cast in tiles of kTile x kTile neighbouring
  // rays; each tile gathers the objects its cone of directions can reach once (nearest first, the
  // origin already in each object's frame) and every ray of the tile walks that short list
  // instead of the instance BVH. Results are those of Scene::intersect, ray by ray.
  constexpr std::uint32_t kTile = 8;
  const std::uint32_t rows = table.height, cols = table.width;
  real dirs[kTile * kTile][3];
  ConeCandidates cand;
  for (std::uint32_t i0 = 0; i0 < rows; i0 += kTile) {
    const std::uint32_t i1 = i0 + kTile < rows ? i0 + kTile : rows;
    for (std::uint32_t j0 = 0; j0 < cols; j0 += kTile) {
      const std::uint32_t j1 = j0 + kTile < cols ? j0 + kTile : cols;
      // World directions of the tile, their mean axis, cone half angle and longest range.
      real axis[3] = {0, 0, 0}, tile_tmax = 0;
      std::uint32_t m = 0;
      for (std::uint32_t i = i0; i < i1; ++i) {
        for (std::uint32_t j = j0; j < j1; ++j, ++m) {
          const std::uint32_t idx = i * cols + j;
          const real* ds = &table.dirs_s[3 * idx];
          real* d = dirs[m];
          d[0] = r(0, 0) * ds[0] + r(0, 1) * ds[1] + r(0, 2) * ds[2];
          d[1] = r(1, 0) * ds[0] + r(1, 1) * ds[1] + r(1, 2) * ds[2];
          d[2] = r(2, 0) * ds[0] + r(2, 1) * ds[1] + r(2, 2) * ds[2];
          for (int k = 0; k < 3; ++k) axis[k] += d[k];
          const real scale = depth && table.depth_scale != nullptr ? table.depth_scale[idx] : 1_r;
          const real tm = op.max_range / scale;
          tile_tmax = tm > tile_tmax ? tm : tile_tmax;
        }
      }
      const real an = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
      real cos_half = -2;  // any direction
      if (an > 1e-3_r * static_cast<real>(m)) {
        for (int k = 0; k < 3; ++k) axis[k] /= an;
        cos_half = 1;
        for (std::uint32_t q = 0; q < m; ++q) {
          const real c = (dirs[q][0] * axis[0] + dirs[q][1] * axis[1] + dirs[q][2] * axis[2]) /
                         std::sqrt(dirs[q][0] * dirs[q][0] + dirs[q][1] * dirs[q][1] + dirs[q][2] * dirs[q][2]);
          cos_half = c < cos_half ? c : cos_half;
        }
        cos_half -= 1e-5_r;  // rounding margin (never narrower than the rays)
      }
      scene.gather_cone(o, axis, cos_half, tile_tmax, cand);
#if KESTREL_SENSORS_TILE_PACKETS
      // The whole tile at once (meshes walked once per tile, see Scene::intersect_tile).
      real tile_tmaxs[kTile * kTile];
      SceneHit tile_hits[kTile * kTile];
      bool tile_found[kTile * kTile];
      m = 0;
      for (std::uint32_t i = i0; i < i1; ++i) {
        for (std::uint32_t j = j0; j < j1; ++j, ++m) {
          const std::uint32_t idx = i * cols + j;
          const real scale = depth && table.depth_scale != nullptr ? table.depth_scale[idx] : 1_r;
          tile_tmaxs[m] = op.max_range / scale;  // depth: a far cut that is a plane (golden convention)
        }
      }
      scene.intersect_tile(cand, dirs, m, 0, tile_tmaxs, tile_hits, tile_found);
#endif
      m = 0;
      for (std::uint32_t i = i0; i < i1; ++i) {
        for (std::uint32_t j = j0; j < j1; ++j, ++m) {
          const std::uint32_t idx = i * cols + j;
          const real* ds = &table.dirs_s[3 * idx];
          const real* d = dirs[m];
          const real scale = depth && table.depth_scale != nullptr ? table.depth_scale[idx] : 1_r;
#if KESTREL_SENSORS_TILE_PACKETS
          const SceneHit& hit = tile_hits[m];
          const bool found = tile_found[m];
#else
          // Depth: cast to max_range / scale so the far cut is a plane (golden convention).
          const real tmax = op.max_range / scale;
          SceneHit hit;
          const bool found = scene.intersect(cand, make_ray(o, d), 0, tmax, hit);
#endif
          const real t = found ? hit.t : kNoHitValue;
          if (out.range != nullptr) out.range[idx] = found ? t * scale : kNoHitValue;
          if (out.segmentation != nullptr)
            out.segmentation[idx] = found ? static_cast<std::int32_t>(hit.seg_id) : kNoHitSegment;
          if (out.points != nullptr) {
            for (int k = 0; k < 3; ++k)
              out.points[3 * idx + k] = out.points_in_world_frame ? o[k] + t * d[k] : t * ds[k];
          }
          if (out.normals_w != nullptr) {
            for (int k = 0; k < 3; ++k) out.normals_w[3 * idx + k] = found ? hit.normal_w[k] : 0_r;
          }
        }
      }
    }
  }
  if (out.points != nullptr && !out.points_in_world_frame) {
    // Sensor-frame point cloud: range rules on the norm, then normalisation (Aerial Gym).
    for (std::uint32_t i = 0; i < n; ++i) {
      real* pt = &out.points[3 * i];
      const real nrm = std::sqrt(pt[0] * pt[0] + pt[1] * pt[1] + pt[2] * pt[2]);
      if (nrm > op.max_range)
        for (int k = 0; k < 3; ++k) pt[k] = op.far_out_of_range_value;
      const real nrm2 = std::sqrt(pt[0] * pt[0] + pt[1] * pt[1] + pt[2] * pt[2]);
      if (nrm2 < op.min_range)
        for (int k = 0; k < 3; ++k) pt[k] = op.near_out_of_range_value;
      if (op.normalize_range)
        for (int k = 0; k < 3; ++k) pt[k] = pt[k] / op.max_range;
    }
  }
  if (out.range == nullptr) return Status::ok;
  if (noise != nullptr) apply_noise(*noise, out.range, n, *rng, op.near_out_of_range_value);
  for (std::uint32_t i = 0; i < n; ++i) {
    real v = out.range[i];
    if (v > op.max_range) v = op.far_out_of_range_value;  // two successive rules (Aerial Gym)
    if (v < op.min_range) v = op.near_out_of_range_value;
    if (op.normalize_range) v = v / op.max_range;
    out.range[i] = v;
  }
  return Status::ok;
}

}  // namespace kestrel::sensors
