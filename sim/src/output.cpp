#include "kestrel/sim/output.hpp"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace kestrel::sim {

bool write_trajectory_csv(const World& w, const std::string& path, std::string& error) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) {
    error = path + ": cannot write";
    return false;
  }
  std::fprintf(f, "env,step,x_m,y_m,z_m\n");
  for (int e = 0; e < w.trace_envs(); ++e)
    for (int k = 0; k < w.trace_length(); ++k) {
      const Vec3& p = w.trace_point(e, k);
      std::fprintf(f, "%d,%d,%.6g,%.6g,%.6g\n", e, k + 1, static_cast<double>(p[0]), static_cast<double>(p[1]), static_cast<double>(p[2]));
    }
  std::fclose(f);
  return true;
}

bool write_env_csv(const World& w, const std::string& path, std::string& error) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) {
    error = path + ": cannot write";
    return false;
  }
  std::fprintf(f, "env,robot,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,target_x_m,target_y_m,target_z_m,env_steps,crashes,resets,timeouts,out_of_bounds,successes\n");
  for (int e = 0; e < w.num_envs(); ++e)
    for (int r = 0; r < w.robots_per_env(); ++r) {
      const RigidBodyState& s = w.robot_state(e, r);
      const Vec3& t = w.target(e, r);
      const EnvStats& st = w.stats(e);
      std::fprintf(f, "%d,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%llu,%u,%u,%u,%u,%u\n", e, r,
                   static_cast<double>(s.position_w[0]), static_cast<double>(s.position_w[1]), static_cast<double>(s.position_w[2]),
                   static_cast<double>(s.linvel_w[0]), static_cast<double>(s.linvel_w[1]), static_cast<double>(s.linvel_w[2]),
                   static_cast<double>(t[0]), static_cast<double>(t[1]), static_cast<double>(t[2]),
                   static_cast<unsigned long long>(st.env_steps), st.crashes, st.resets, st.timeouts, st.out_of_bounds, st.successes);
    }
  std::fclose(f);
  return true;
}

namespace {
struct Canvas {
  int w, h;
  std::vector<unsigned char> rgb;
  Canvas(int width, int height) : w(width), h(height), rgb(static_cast<std::size_t>(width) * height * 3, 255) {}
  void put(int x, int y, const unsigned char c[3]) {
    if (x < 0 || y < 0 || x >= w || y >= h) return;
    for (int k = 0; k < 3; ++k) rgb[(static_cast<std::size_t>(y) * w + x) * 3 + k] = c[k];
  }
  void line(int x0, int y0, int x1, int y1, const unsigned char c[3]) {
    const int dx = std::abs(x1 - x0), sx = x0 < x1 ? 1 : -1, dy = -std::abs(y1 - y0), sy = y0 < y1 ? 1 : -1;
    int err = dx + dy;
    for (;;) {
      put(x0, y0, c);
      if (x0 == x1 && y0 == y1) break;
      const int e2 = 2 * err;
      if (e2 >= dy) { err += dy; x0 += sx; }
      if (e2 <= dx) { err += dx; y0 += sy; }
    }
  }
};
}  // namespace

bool write_png_rgb(const std::string& path, int W, int H, const unsigned char* rgb, std::string& error) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) {
    error = path + ": cannot write";
    return false;
  }
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  if (png == nullptr || info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(f);
    error = path + ": PNG encoding failed";
    return false;
  }
  png_init_io(png, f);
  png_set_IHDR(png, info, static_cast<png_uint_32>(W), static_cast<png_uint_32>(H), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < H; ++y) png_write_row(png, const_cast<png_bytep>(&rgb[static_cast<std::size_t>(y) * static_cast<std::size_t>(W) * 3]));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::fclose(f);
  return true;
}

bool write_trajectory_png(const World& world, const std::string& path, std::string& error) {
  const int W = 640, H = 480, M = 20;
  Canvas cv(W, H);
  Vec3 lo, hi;
  world.lower_upper_bounds(0, lo, hi);
  const double sx = (W - 2 * M) / static_cast<double>(hi[0] - lo[0]), sy = (H - 2 * M) / static_cast<double>(hi[1] - lo[1]);
  const double s = std::min(sx, sy);
  auto px = [&](real x) { return M + static_cast<int>(std::lround((x - lo[0]) * s)); };
  auto py = [&](real y) { return H - M - static_cast<int>(std::lround((y - lo[1]) * s)); };
  const unsigned char grey[3] = {160, 160, 160}, black[3] = {0, 0, 0};
  cv.line(px(lo[0]), py(lo[1]), px(hi[0]), py(lo[1]), black);
  cv.line(px(hi[0]), py(lo[1]), px(hi[0]), py(hi[1]), black);
  cv.line(px(hi[0]), py(hi[1]), px(lo[0]), py(hi[1]), black);
  cv.line(px(lo[0]), py(hi[1]), px(lo[0]), py(lo[1]), black);
  for (int i = 0; i < world.num_obstacles(0); ++i) {
    const Obstacle& o = world.obstacle(0, i);
    const int x0 = px(o.aabb_min_w[0]), x1 = px(o.aabb_max_w[0]), y0 = py(o.aabb_min_w[1]), y1 = py(o.aabb_max_w[1]);
    cv.line(x0, y0, x1, y0, grey);
    cv.line(x1, y0, x1, y1, grey);
    cv.line(x1, y1, x0, y1, grey);
    cv.line(x0, y1, x0, y0, grey);
  }
  const unsigned char palette[6][3] = {{220, 30, 30}, {30, 120, 220}, {30, 170, 60}, {200, 120, 0}, {140, 40, 180}, {0, 160, 160}};
  for (int e = 0; e < world.trace_envs(); ++e)
    for (int k = 1; k < world.trace_length(); ++k) {
      const Vec3& a = world.trace_point(e, k - 1);
      const Vec3& b = world.trace_point(e, k);
      if ((a - b).norm() > 1) continue;  // a reset: do not draw the jump back to the start
      cv.line(px(a[0]), py(a[1]), px(b[0]), py(b[1]), palette[e % 6]);
    }
  return write_png_rgb(path, W, H, cv.rgb.data(), error);
}

bool write_sensor_pngs(const World& world, int env, const std::string& dir, std::vector<std::string>& written,
                       std::string& error) {
  if (env < 0 || env >= world.num_envs()) {
    error = "image env " + std::to_string(env) + " out of range [0, " + std::to_string(world.num_envs()) + ")";
    return false;
  }
  for (int k = 0; k < world.num_sensors(); ++k) {
    const SensorConfig& c = world.sensor_config(k);
    if (c.kind == SensorKind::imu) continue;
    const int W = world.sensor_width(k), H = world.sensor_height(k);
    const std::size_t n = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
    const bool cam = c.kind == SensorKind::camera;
    const sensors::RangeOutputParams& rp = cam ? c.camera.range : c.lidar.range;
    const bool depth = cam && c.camera.calculate_depth;
    // Grey = value / max_range in [0, 1] (normalised outputs are already divided); out-of-range
    // values (negative, or the far value) clamp to black / white.
    const real* r = world.sensor_ranges(env, k);
    std::vector<unsigned char> grey(n * 3), seg(n * 3);
    for (std::size_t i = 0; i < n; ++i) {
      const real v = rp.normalize_range ? r[i] : r[i] / rp.max_range;
      const real c01 = std::min(1_r, std::max(0_r, v));
      const unsigned char g = static_cast<unsigned char>(std::lround(255 * static_cast<double>(c01)));
      grey[3 * i] = grey[3 * i + 1] = grey[3 * i + 2] = g;
    }
    // Segmentation: black without a hit, grey for the ground (id 0), a hashed colour per id.
    const std::int32_t* sg = world.sensor_segmentation(env, k);
    for (std::size_t i = 0; i < n; ++i) {
      unsigned char* px = &seg[3 * i];
      if (sg[i] < 0) {
        px[0] = px[1] = px[2] = 0;
      } else if (sg[i] == 0) {
        px[0] = px[1] = px[2] = 128;
      } else {
        const std::uint32_t h = static_cast<std::uint32_t>(sg[i]) * 2654435761u;  // Knuth's multiplicative hash
        px[0] = static_cast<unsigned char>(64 + (h >> 24) % 192);
        px[1] = static_cast<unsigned char>(64 + (h >> 16) % 192);
        px[2] = static_cast<unsigned char>(64 + (h >> 8) % 192);
      }
    }
    const std::string base = dir + "/sensor_" + c.name;
    const std::string range_path = base + (depth ? "_depth.png" : "_range.png"), seg_path = base + "_segmentation.png";
    if (!write_png_rgb(range_path, W, H, grey.data(), error) || !write_png_rgb(seg_path, W, H, seg.data(), error)) return false;
    written.push_back(range_path);
    written.push_back(seg_path);
  }
  return true;
}

}  // namespace kestrel::sim
