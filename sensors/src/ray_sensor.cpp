// Ray tables, presets, mounting, noise and the render loop (see ray_sensor.hpp).
#include "kestrel/sensors/ray_sensor.hpp"

#include <cmath>

#include "kestrel/kernel/quaternion.hpp"

namespace kestrel::sensors {

namespace {

LidarParams lidar(std::uint32_t h, std::uint32_t w, real hmin, real hmax, real vmin, real vmax, real rmin, real rmax) {
  LidarParams p;
  p.height = h;
  p.width = w;
  p.horizontal_fov_deg_min = hmin;
  p.horizontal_fov_deg_max = hmax;
  p.vertical_fov_deg_min = vmin;
  p.vertical_fov_deg_max = vmax;
  p.range.min_range = rmin;
  p.range.max_range = rmax;
  p.range.set_default_out_of_range_values();
  return p;
}

CameraParams camera(std::uint32_t h, std::uint32_t w, real hfov, real rmin, real rmax) {
  CameraParams p;
  p.height = h;
  p.width = w;
  p.horizontal_fov_deg = hfov;
  p.range.min_range = rmin;
  p.range.max_range = rmax;
  p.range.set_default_out_of_range_values();
  return p;
}

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

}  // namespace

LidarParams lidar_preset_osdome_64() { return lidar(64, 512, -180, 180, 0, 90, 0.5_r, 20); }
LidarParams lidar_preset_os0_128() { return lidar(128, 512, -180, 180, -45, 45, 0.3_r, 35); }
LidarParams lidar_preset_os0_64() { return lidar(64, 512, -180, 180, -45, 45, 0.3_r, 35); }
LidarParams lidar_preset_os1_64() { return lidar(64, 512, -180, 180, -22.5_r, 22.5_r, 0.3_r, 120); }
LidarParams lidar_preset_os2_64() { return lidar(64, 512, -180, 180, -11.25_r, 11.25_r, 0.8_r, 240); }
LidarParams lidar_preset_rs_airy() { return lidar(48, 120, -180, 180, 0, 90, 0.1_r, 30); }
LidarParams lidar_preset_pmd_flexx2() { return lidar(172, 224, -28, 28, -22, 22, 0.1_r, 4); }
LidarParams lidar_preset_vl53l5cx() { return lidar(8, 8, -22.5_r, 22.5_r, -22.5_r, 22.5_r, 0.02_r, 4); }
CameraParams camera_preset_base() { return camera(135, 240, 87, 0.2_r, 10); }
CameraParams camera_preset_d455() { return camera(270, 480, 87, 0.4_r, 10); }
CameraParams camera_preset_oakd() { return camera(400, 640, 71.9_r, 0.35_r, 20); }

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

void apply_noise(const NoiseParams& p, real* values, std::uint32_t n, RngStream& rng) {
  if (p.model == NoiseParams::Model::none) return;
  for (std::uint32_t i = 0; i < n; ++i) {
    const real u = rng.uniform();
    const real g = rng.normal();
    const real r = values[i];
    real stddev;
    if (p.model == NoiseParams::Model::range_dependent) {
      stddev = p.a * r * r + p.b * r + p.c;
      values[i] = r + g * stddev + p.offset;
    } else {
      stddev = p.std_dev_multiplier * r;
      values[i] = r + g * stddev;
    }
    if (u < p.pixel_dropout_prob) values[i] = p.dropout_value;
  }
}

Status render(const Scene& scene, const SensorPose& pose, const RayTable& table, const RangeOutputParams& op,
              bool depth, SensorOutput& out, const NoiseParams* noise, RngStream* rng) {
  const std::uint32_t n = table.height * table.width;
  if (scene.dirty() || n == 0 || table.dirs_s == nullptr || n > table.capacity || !(op.max_range > 0))
    return Status::invalid_argument;
  if (noise != nullptr && noise->model != NoiseParams::Model::none && (rng == nullptr || out.range == nullptr))
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
      m = 0;
      for (std::uint32_t i = i0; i < i1; ++i) {
        for (std::uint32_t j = j0; j < j1; ++j, ++m) {
          const std::uint32_t idx = i * cols + j;
          const real* ds = &table.dirs_s[3 * idx];
          const real* d = dirs[m];
          const real scale = depth && table.depth_scale != nullptr ? table.depth_scale[idx] : 1_r;
          // Depth: cast to max_range / scale so the far cut is a plane (golden convention).
          const real tmax = op.max_range / scale;
          SceneHit hit;
          const bool found = scene.intersect(cand, make_ray(o, d), 0, tmax, hit);
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
  if (out.range == nullptr) return Status::ok;
  if (noise != nullptr) apply_noise(*noise, out.range, n, *rng);
  for (std::uint32_t i = 0; i < n; ++i) {
    real v = out.range[i];
    if (v > op.max_range) v = op.far_out_of_range_value;
    else if (v < op.min_range) v = op.near_out_of_range_value;
    if (op.normalize_range) v = v / op.max_range;
    out.range[i] = v;
  }
  return Status::ok;
}

}  // namespace kestrel::sensors
