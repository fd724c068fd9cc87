#include "kestrel/sim/output.hpp"

#include <png.h>

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdarg>
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
/// Liang-Barsky: clips the segment to [xmin, xmax] x [ymin, ymax] in place. False: nothing of it
/// is inside (or a coordinate is not finite). An endpoint inside the box is left exactly as given.
/// A moved endpoint lies on the edge that clipped it (set exactly: with endpoints ~1e40 px away,
/// x0 + t dx has an absolute rounding error far above a pixel) and is clamped into the box.
bool clip_segment(double& x0, double& y0, double& x1, double& y1, double xmin, double xmax, double ymin, double ymax) {
  if (!std::isfinite(x0) || !std::isfinite(y0) || !std::isfinite(x1) || !std::isfinite(y1)) return false;
  const double dx = x1 - x0, dy = y1 - y0;
  if (!std::isfinite(dx) || !std::isfinite(dy)) return false;
  double t0 = 0, t1 = 1;
  int e0 = -1, e1 = -1;  // the edge (0 xmin, 1 xmax, 2 ymin, 3 ymax) that set t0 / t1
  auto edge = [&](int id, double p, double q) {  // keeps the part with p t <= q
    if (p == 0) return q >= 0;
    const double r = q / p;
    if (p < 0) {
      if (r > t1) return false;
      if (r > t0) t0 = r, e0 = id;
    } else {
      if (r < t0) return false;
      if (r < t1) t1 = r, e1 = id;
    }
    return true;
  };
  if (!edge(0, -dx, x0 - xmin) || !edge(1, dx, xmax - x0) || !edge(2, -dy, y0 - ymin) || !edge(3, dy, ymax - y0)) return false;
  const double ox = x0, oy = y0;
  const double edges[4] = {xmin, xmax, ymin, ymax};
  auto place = [&](int id, double t, double& x, double& y) {
    x = std::min(xmax, std::max(xmin, ox + t * dx));
    y = std::min(ymax, std::max(ymin, oy + t * dy));
    (id < 2 ? x : y) = edges[id];
  };
  if (e1 >= 0) place(e1, t1, x1, y1);
  if (e0 >= 0) place(e0, t0, x0, y0);
  return true;
}
}  // namespace

std::size_t draw_line_rgb(unsigned char* rgb, int W, int H, double x0, double y0, double x1, double y1, const unsigned char c[3]) {
  // Clipped in floating point to a 2-pixel border around the canvas before anything becomes an
  // int (fuzz F2: obstacles ~1e9 m away gave pixel coordinates beyond int, overflow in the
  // Bresenham error terms and a crash). What is drawn inside the canvas is unchanged: segments
  // within the border are not touched, and the rest of a long one lies off the canvas.
  if (!clip_segment(x0, y0, x1, y1, -2.0, W + 1.0, -2.0, H + 1.0)) return 0;
  int ix0 = static_cast<int>(std::lround(x0)), iy0 = static_cast<int>(std::lround(y0));
  const int ix1 = static_cast<int>(std::lround(x1)), iy1 = static_cast<int>(std::lround(y1));
  const int dx = std::abs(ix1 - ix0), sx = ix0 < ix1 ? 1 : -1, dy = -std::abs(iy1 - iy0), sy = iy0 < iy1 ? 1 : -1;
  int err = dx + dy;
  std::size_t drawn = 0;
  for (;;) {
    if (ix0 >= 0 && iy0 >= 0 && ix0 < W && iy0 < H) {
      for (int k = 0; k < 3; ++k) rgb[(static_cast<std::size_t>(iy0) * static_cast<std::size_t>(W) + static_cast<std::size_t>(ix0)) * 3 + k] = c[k];
      ++drawn;
    }
    if (ix0 == ix1 && iy0 == iy1) break;
    const int e2 = 2 * err;
    if (e2 >= dy) { err += dy; ix0 += sx; }
    if (e2 <= dx) { err += dx; iy0 += sy; }
  }
  return drawn;
}

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
  std::vector<unsigned char> rgb(static_cast<std::size_t>(W) * H * 3, 255);
  Vec3 lo, hi;
  world.lower_upper_bounds(0, lo, hi);
  const double sx = (W - 2 * M) / static_cast<double>(hi[0] - lo[0]), sy = (H - 2 * M) / static_cast<double>(hi[1] - lo[1]);
  const double s = std::min(sx, sy);
  // Metres -> pixels, kept in double (a far coordinate must not be converted to int: draw_line_rgb
  // clips first). Within +-1e9 pixels the value is rounded here as before (the same pixels).
  auto snap = [](double v) { return std::fabs(v) <= 1e9 ? static_cast<double>(std::lround(v)) : v; };
  auto px = [&](real x) { return M + snap(static_cast<double>(x - lo[0]) * s); };
  auto py = [&](real y) { return H - M - snap(static_cast<double>(y - lo[1]) * s); };
  auto line = [&](double x0, double y0, double x1, double y1, const unsigned char c[3]) {
    (void)draw_line_rgb(rgb.data(), W, H, x0, y0, x1, y1, c);
  };
  const unsigned char grey[3] = {160, 160, 160}, black[3] = {0, 0, 0};
  line(px(lo[0]), py(lo[1]), px(hi[0]), py(lo[1]), black);
  line(px(hi[0]), py(lo[1]), px(hi[0]), py(hi[1]), black);
  line(px(hi[0]), py(hi[1]), px(lo[0]), py(hi[1]), black);
  line(px(lo[0]), py(hi[1]), px(lo[0]), py(lo[1]), black);
  for (int i = 0; i < world.num_obstacles(0); ++i) {
    const Obstacle& o = world.obstacle(0, i);
    const double x0 = px(o.aabb_min_w[0]), x1 = px(o.aabb_max_w[0]), y0 = py(o.aabb_min_w[1]), y1 = py(o.aabb_max_w[1]);
    line(x0, y0, x1, y0, grey);
    line(x1, y0, x1, y1, grey);
    line(x1, y1, x0, y1, grey);
    line(x0, y1, x0, y0, grey);
  }
  const unsigned char palette[6][3] = {{220, 30, 30}, {30, 120, 220}, {30, 170, 60}, {200, 120, 0}, {140, 40, 180}, {0, 160, 160}};
  for (int e = 0; e < world.trace_envs(); ++e)
    for (int k = 1; k < world.trace_length(); ++k) {
      const Vec3& a = world.trace_point(e, k - 1);
      const Vec3& b = world.trace_point(e, k);
      if ((a - b).norm() > 1) continue;  // a reset: do not draw the jump back to the start
      line(px(a[0]), py(a[1]), px(b[0]), py(b[1]), palette[e % 6]);
    }
  return write_png_rgb(path, W, H, rgb.data(), error);
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

std::string success_rate_text(std::uint64_t episodes, std::uint64_t fallback_episodes, std::uint64_t successes) {
  char buf[256];
  const std::uint64_t real = episodes >= fallback_episodes ? episodes - fallback_episodes : 0;
  if (episodes == 0) return "success rate n/a (0 episodes)";
  if (fallback_episodes == 0) {
    std::snprintf(buf, sizeof buf, "success rate %.1f%%", 100.0 * static_cast<double>(successes) / static_cast<double>(episodes));
  } else if (real == 0) {
    std::snprintf(buf, sizeof buf, "success rate n/a (0 real episodes; %" PRIu64 " placement fallbacks not counted)", fallback_episodes);
  } else {
    std::snprintf(buf, sizeof buf,
                  "success rate %.1f%% (%" PRIu64 " of %" PRIu64 " real episodes; %" PRIu64 " placement fallbacks not counted)",
                  100.0 * static_cast<double>(successes) / static_cast<double>(real), successes, real, fallback_episodes);
  }
  return buf;
}

std::string placement_fallback_text(const std::string& env_name, std::uint64_t fallbacks, std::uint64_t placements,
                                    double robot_bound_plus_clearance_m, bool line_of_sight) {
  if (fallbacks == 0) return "";
  char buf[768];
  const double share = placements > 0 ? 100.0 * static_cast<double>(fallbacks) / static_cast<double>(placements) : 100.0;
  int n = std::snprintf(buf, sizeof buf,
                        "placement fallbacks: %" PRIu64 " of %" PRIu64 " placements (%.1f%%) found no clear start/target%s pair "
                        "and hover at their start (not counted as successes)",
                        fallbacks, placements, share, line_of_sight ? "/path" : "");
  char sphere[64] = "the robot's bounding sphere plus task.clearance_m";
  if (robot_bound_plus_clearance_m > 0) std::snprintf(sphere, sizeof sphere, "a %.2f m sphere", robot_bound_plus_clearance_m);
  if (share > 5.0 && n > 0 && static_cast<std::size_t>(n) < sizeof buf)
    std::snprintf(buf + n, sizeof buf - static_cast<std::size_t>(n),
                  "\n  warning: env %s is too dense for this placement rule (%s%s); raise task.placement_attempts "
                  "(<= 64), lower task.clearance_m%s, or use an emptier environment",
                  env_name.c_str(), sphere,
                  line_of_sight ? " swept along a straight line from the start box to the target box" : " at start and target",
                  line_of_sight ? ", set task.line_of_sight: false (then give the controller obstacle avoidance)" : "");
  return buf;
}

void RunReport::say(const char* fmt, ...) {
  char buf[2048];
  va_list ap;
  va_start(ap, fmt);
  const int n = std::vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  if (n < 0) return;
  std::fputs(buf, stdout);
  text_ += buf;
}

bool RunReport::write(const std::string& path, std::string& error) const {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) {
    error = path + ": cannot write";
    return false;
  }
  const bool ok = std::fwrite(text_.data(), 1, text_.size(), f) == text_.size();
  if (std::fclose(f) != 0 || !ok) {
    error = path + ": cannot write";
    return false;
  }
  return true;
}

bool RunReport::finish(const std::string& out_dir, std::uint64_t state_hash, std::string& error) {
  char hash[64];
  std::snprintf(hash, sizeof hash, "state hash: %016" PRIx64 "\n", state_hash);
  keep(hash);
  if (!write(out_dir + "/summary.txt", error)) return false;
  std::printf("  wrote %s/summary.txt\n%s", out_dir.c_str(), hash);
  return true;
}

void report_episodes(RunReport& rep, const WorldSummary& s, real success_radius_m) {
  rep.say("  crashes %" PRIu64 ", resets %" PRIu64 " (timeouts %" PRIu64 ", out of bounds %" PRIu64 ")\n", s.crashes,
          s.resets, s.timeouts, s.out_of_bounds);
  // Success is counted over every finished real episode (a crash or an exit ends one
  // unsuccessfully), not only over the timed-out ones; a fallback episode hovers at its start and is
  // counted apart, never as a success (issue 19).
  char crash_rate[32] = "n/a (0 episodes)";
  if (s.episodes_done > 0)
    std::snprintf(crash_rate, sizeof crash_rate, "%.1f%%", 100.0 * static_cast<double>(s.crashes) / static_cast<double>(s.episodes_done));
  rep.say("  episodes %" PRIu64 ": %s (within %.2f m of the target at timeout), crash rate %s\n", s.episodes_done,
          success_rate_text(s.episodes_done, s.fallback_episodes, s.successes).c_str(),
          static_cast<double>(success_radius_m), crash_rate);
}

bool write_trace_csv(const std::string& path, const char* columns, const real* trace, int envs, long long steps,
                     std::string& error) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) {
    error = path + ": cannot write";
    return false;
  }
  std::fprintf(f, "env,step,%s\n", columns);
  for (int e = 0; e < envs; ++e)
    for (long long k = 0; k < steps; ++k) {
      const real* t = &trace[(static_cast<std::size_t>(e) * static_cast<std::size_t>(steps) + static_cast<std::size_t>(k)) * 3];
      std::fprintf(f, "%d,%lld,%.6g,%.6g,%.6g\n", e, k, static_cast<double>(t[0]), static_cast<double>(t[1]),
                   static_cast<double>(t[2]));
    }
  if (std::fclose(f) != 0) {
    error = path + ": cannot write";
    return false;
  }
  return true;
}

}  // namespace kestrel::sim
