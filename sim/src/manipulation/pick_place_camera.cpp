// Cameras of the SO-101 pick-and-place scene (sim/pick_place_camera.hpp).
#include "kestrel/sim/pick_place_camera.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "kestrel/sensors/geometry.hpp"
#include "kestrel/sim/output.hpp"

namespace kestrel::sim {

namespace dy = kestrel::dynamics;

namespace {

// Camera frame (x fwd, y left, z up) -> frame rotation looking from eye to target with `up` up.
Mat3 look_rotation(const Vec3& eye, const Vec3& target, const Vec3& up) {
  const Vec3 f = (target - eye).normalized();
  Vec3 left = up.cross(f);
  if (left.norm() < 1e-6_r) left = Vec3(0, 1, 0).cross(f);  // looking along up: any left will do
  left.normalize();
  const Vec3 u = f.cross(left);
  Mat3 R;
  R.col(0) = f;
  R.col(1) = left;
  R.col(2) = u;
  return R;
}

enum Kind : std::uint8_t { kBox = 0, kSphere = 1, kCapsule = 2 };

// One primitive prepared for a frame: the camera's origin and the ray-direction basis in the
// primitive's frame (d_local = m0 + a m1 + b m2 for the camera-frame ray (1, a, b)), the light in
// its frame, its albedo x 255 and its pixel rectangle.
struct Prim {
  real o[3];
  real m0[3], m1[3], m2[3];
  real l[3];
  real size[3];
  real albedo255[3];
  int col_lo, col_hi, row_lo, row_hi;
  Kind kind;
  std::uint8_t entity;
};

// Conservative pixel range [lo, hi] along one image axis of a sphere with centre (x fwd, s
// sideways: +y left or +z up) and radius rr in the camera frame, where pixel coordinate =
// c - f s/x - 0.5. False when the sphere lies wholly behind the camera on this axis.
bool axis_span(double x, double s, double rr, double c, double f, int n, int& lo, int& hi) {
  const double rho = std::sqrt(x * x + s * s);
  constexpr double kHalfPi = 1.5707963267948966;
  if (rho <= rr * 1.0001 + 1e-9) {  // the disk holds the camera's origin: every direction
    lo = 0;
    hi = n - 1;
    return true;
  }
  const double th = std::atan2(s, x), al = std::asin(std::min(1.0, rr / rho));
  const double a0 = th - al, a1 = th + al;
  if (a0 >= kHalfPi || a1 <= -kHalfPi) return false;
  // Larger angle (more left / up) -> smaller pixel coordinate.
  const double p_lo = a1 >= kHalfPi - 1e-9 ? -1e30 : c - f * std::tan(a1) - 0.5;
  const double p_hi = a0 <= -kHalfPi + 1e-9 ? 1e30 : c - f * std::tan(a0) - 0.5;
  const double lo_d = std::floor(p_lo) - 1, hi_d = std::ceil(p_hi) + 1;
  if (hi_d < 0 || lo_d > n - 1) return false;
  lo = lo_d < 0 ? 0 : static_cast<int>(lo_d);
  hi = hi_d > n - 1 ? n - 1 : static_cast<int>(hi_d);
  return lo <= hi;
}

bool is_dark_part(const std::string& name) {
  return name.find("motor") != std::string::npos || name.find("pad") != std::string::npos ||
         name.find("follower") != std::string::npos;
}

inline std::uint8_t channel(real albedo255, real intensity) {
  const real v = albedo255 * intensity + 0.5_r;
  return v >= 255 ? std::uint8_t(255) : static_cast<std::uint8_t>(v);
}

}  // namespace

CameraSpec look_at_camera(const Vec3& eye_w, const Vec3& target_w, real hfov_rad, int width, int height) {
  CameraSpec c;
  c.pos_m = eye_w;
  c.R = look_rotation(eye_w, target_w, Vec3(0, 0, 1));
  c.attach_body = -1;
  c.width = width;
  c.height = height;
  c.hfov_rad = hfov_rad;
  return c;
}

CameraSpec front_camera(int width, int height) {
  return look_at_camera(Vec3(0.55_r, 0, 0.35_r), Vec3(0.15_r, 0.05_r, 0.08_r), 1.2217305_r, width, height);
}

CameraSpec wrist_camera(const PickPlaceWorld& world, int width, int height) {
  CameraSpec c;
  c.attach_body = world.tcp_body();
  c.pos_m = Vec3(0, -0.03_r, 0.055_r);
  c.R = look_rotation(c.pos_m, Vec3(0, 0, -0.015_r), Vec3(0, 0, 1));
  c.width = width;
  c.height = height;
  c.hfov_rad = 1.5707963_r;  // 90 deg
  c.near_m = 0.005_r;
  c.far_m = 5;
  return c;
}

void camera_pose_w(const PickPlaceWorld& world, const CameraSpec& cam, Vec3& pos_w, Mat3& R_wc) {
  if (cam.attach_body < 0) {
    pos_w = cam.pos_m;
    R_wc = cam.R;
    return;
  }
  const dy::Transform X = world.body_pose(cam.attach_body);  // E: world -> body, r: body origin
  pos_w = X.r + X.E.transpose() * cam.pos_m;
  R_wc = X.E.transpose() * cam.R;
}

Status render_camera(const PickPlaceWorld& world, const CameraSpec& cam, std::uint8_t* rgb, float* depth_m,
                     std::uint8_t* segmentation, const CameraLook& look) {
  const int W = cam.width, H = cam.height;
  if (W < 1 || W > kMaxCameraWidth || H < 1 || H > kMaxCameraHeight || !(cam.hfov_rad > 0) || !(cam.hfov_rad < 3.14159_r) ||
      !(cam.near_m >= 0) || !(cam.far_m > cam.near_m) || !std::isfinite(cam.far_m))
    return Status::invalid_argument;
  Vec3 eye;
  Mat3 R_wc;
  camera_pose_w(world, cam, eye, R_wc);
  if (!eye.allFinite() || !R_wc.allFinite()) return Status::invalid_argument;

  const real f = static_cast<real>(W) / 2 / std::tan(cam.hfov_rad / 2);
  const real inv_f = 1 / f;
  const real cx = static_cast<real>(W) / 2, cy = static_cast<real>(H) / 2;
  const Mat3 R_cw = R_wc.transpose();

  // The frame's primitives: the table, the robot file's world-fixed geoms (the base), then the
  // scene's shapes.
  Prim prim[kMaxCameraShapes];
  int n = 0;
  bool overflow = false;
  auto add = [&](dy::ShapeType type, const Vec3& size, const Mat3& R_ws, const Vec3& p_w, std::uint8_t entity, const Vec3& albedo) {
    if (n >= kMaxCameraShapes) {
      overflow = true;
      return;
    }
    real rr = 0;
    Kind kind = kBox;
    switch (type) {
      case dy::ShapeType::box:
        kind = kBox;
        rr = size.norm();
        break;
      case dy::ShapeType::sphere:
        kind = kSphere;
        rr = size[0];
        break;
      case dy::ShapeType::capsule:
        kind = kCapsule;
        rr = size[0] + size[1];
        break;
      case dy::ShapeType::convex:
        return;  // the SO-101 model and its scene are primitives (pick_place.cpp refuses meshes)
    }
    const Vec3 c = R_cw * (p_w - eye);  // centre in the camera frame
    Prim& p = prim[n];
    // Cull: wholly nearer than near or beyond far, or outside the image on either axis.
    if (c[0] + rr < cam.near_m || c[0] - rr > cam.far_m) return;
    if (!axis_span(c[0], c[1], rr, cx, f, W, p.col_lo, p.col_hi)) return;
    if (!axis_span(c[0], c[2], rr, cy, f, H, p.row_lo, p.row_hi)) return;
    const Mat3 M = R_ws.transpose() * R_wc;  // camera -> primitive
    const Vec3 o = R_ws.transpose() * (eye - p_w);
    const Vec3 l = R_ws.transpose() * look.light_dir_w;
    for (int k = 0; k < 3; ++k) {
      p.o[k] = o[k];
      p.m0[k] = M(k, 0);
      p.m1[k] = M(k, 1);
      p.m2[k] = M(k, 2);
      p.l[k] = l[k];
      p.size[k] = size[k];
      p.albedo255[k] = albedo[k] * 255;
    }
    p.kind = kind;
    p.entity = entity;
    ++n;
  };
  add(dy::ShapeType::box, look.table_half_m, Mat3::Identity(), look.table_center_w, static_cast<std::uint8_t>(PickPlaceEntity::table),
      look.table_rgb);
  // Albedo of the arm's i-th moving shape: the i-th geom of the file on a body (scene_shapes' order).
  const std::vector<RobotGeom>& geoms = world.robot().geoms;
  for (const RobotGeom& g : geoms) {
    if (g.body >= 0) continue;
    dy::CollisionShape s;
    if (!to_collision_shape(g, s)) continue;  // a plane (the file's floor): the table stands for it
    add(s.type, s.size, s.R_b, s.p_b, static_cast<std::uint8_t>(PickPlaceEntity::robot),
        is_dark_part(g.name) ? look.robot_dark_rgb : look.robot_rgb);
  }
  PickPlaceShape shapes[kMaxCameraShapes];
  const int ns = world.scene_shapes(shapes, kMaxCameraShapes);
  if (ns > kMaxCameraShapes) return Status::capacity_exceeded;
  std::size_t geom_cursor = 0;
  for (int i = 0; i < ns; ++i) {
    const PickPlaceShape& s = shapes[i];
    Vec3 albedo = look.robot_rgb;
    switch (s.entity) {
      case PickPlaceEntity::table: albedo = look.table_rgb; break;
      case PickPlaceEntity::cube: albedo = look.cube_rgb; break;
      case PickPlaceEntity::box: albedo = look.box_rgb; break;
      case PickPlaceEntity::robot:
        while (geom_cursor < geoms.size() && geoms[geom_cursor].body < 0) ++geom_cursor;
        if (geom_cursor < geoms.size()) {
          if (is_dark_part(geoms[geom_cursor].name)) albedo = look.robot_dark_rgb;
          ++geom_cursor;
        }
        break;
    }
    const Mat3 E_T = s.X_body.E.transpose();  // body -> world
    add(s.shape.type, s.shape.size, E_T * s.shape.R_b, s.X_body.r + E_T * s.shape.p_b, static_cast<std::uint8_t>(s.entity), albedo);
  }
  if (overflow) return Status::capacity_exceeded;

  // One row of hit records.
  real best_t[kMaxCameraWidth];
  real best_ndl[kMaxCameraWidth];
  std::int16_t best_id[kMaxCameraWidth];
  const real tmin = cam.near_m, tfar = cam.far_m;
  const real ambient = look.ambient, diffuse = look.diffuse;
  const float no_hit = std::numeric_limits<float>::infinity();
  for (int row = 0; row < H; ++row) {
    const real b = (cy - static_cast<real>(row) - 0.5_r) * inv_f;
    for (int col = 0; col < W; ++col) {
      best_t[col] = tfar;
      best_id[col] = -1;
    }
    for (int k = 0; k < n; ++k) {
      const Prim& p = prim[k];
      if (row < p.row_lo || row > p.row_hi) continue;
      const real base[3] = {p.m0[0] + b * p.m2[0], p.m0[1] + b * p.m2[1], p.m0[2] + b * p.m2[2]};
      for (int col = p.col_lo; col <= p.col_hi; ++col) {
        const real a = (cx - static_cast<real>(col) - 0.5_r) * inv_f;
        const real d[3] = {base[0] + a * p.m1[0], base[1] + a * p.m1[1], base[2] + a * p.m1[2]};
        sensors::LocalHit h;
        bool hit = false;
        switch (p.kind) {
          case kBox: hit = sensors::intersect_box(p.o, d, p.size, tmin, best_t[col], h); break;
          case kSphere: hit = sensors::intersect_sphere(p.o, d, p.size[0], tmin, best_t[col], h); break;
          case kCapsule: hit = sensors::intersect_capsule(p.o, d, p.size[0], p.size[1], tmin, best_t[col], h); break;
        }
        if (!hit || !(h.t < best_t[col])) continue;  // equal depths: the earlier primitive keeps the pixel
        best_t[col] = h.t;
        best_id[col] = static_cast<std::int16_t>(k);
        best_ndl[col] = h.n[0] * p.l[0] + h.n[1] * p.l[1] + h.n[2] * p.l[2];
      }
    }
    const std::size_t off = static_cast<std::size_t>(row) * static_cast<std::size_t>(W);
    for (int col = 0; col < W; ++col) {
      const int id = best_id[col];
      const std::size_t px = off + static_cast<std::size_t>(col);
      if (id < 0) {
        if (depth_m != nullptr) depth_m[px] = no_hit;
        if (segmentation != nullptr) segmentation[px] = kCameraNoHitSegment;
        if (rgb != nullptr) {
          rgb[3 * px] = look.sky_rgb[0];
          rgb[3 * px + 1] = look.sky_rgb[1];
          rgb[3 * px + 2] = look.sky_rgb[2];
        }
        continue;
      }
      const Prim& p = prim[id];
      if (depth_m != nullptr) depth_m[px] = static_cast<float>(best_t[col]);
      if (segmentation != nullptr) segmentation[px] = p.entity;
      if (rgb != nullptr) {
        const real ndl = best_ndl[col];
        const real I = ambient + diffuse * (ndl > 0 ? ndl : real(0));
        rgb[3 * px] = channel(p.albedo255[0], I);
        rgb[3 * px + 1] = channel(p.albedo255[1], I);
        rgb[3 * px + 2] = channel(p.albedo255[2], I);
      }
    }
  }
  return Status::ok;
}

bool write_camera_pngs(const std::string& rgb_path, const std::string& depth_path, int width, int height, const std::uint8_t* rgb,
                       const float* depth_m, std::string& error) {
  if (width < 1 || height < 1) {
    error = "write_camera_pngs: expected a positive width and height";
    return false;
  }
  if (!rgb_path.empty() && !write_png_rgb(rgb_path, width, height, rgb, error)) return false;
  if (depth_path.empty()) return true;
  const std::size_t count = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  std::vector<std::uint16_t> mm(count);  // millimetres, rounded; 0: no hit
  for (std::size_t i = 0; i < count; ++i) {
    const float d = depth_m[i];
    std::uint16_t v = 0;
    if (std::isfinite(d) && d > 0) {
      const double m = std::floor(static_cast<double>(d) * 1000.0 + 0.5);
      v = m >= 65535 ? std::uint16_t(65535) : static_cast<std::uint16_t>(m);
    }
    mm[i] = v;
  }
  return write_png_gray16(depth_path, width, height, mm.data(), error);
}

}  // namespace kestrel::sim
