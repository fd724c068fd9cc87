#include "kestrel/sim/output.hpp"

#include <png.h>

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <vector>

namespace kestrel::sim {

bool write_trajectory_csv(const World& w, const std::string& path, std::string& error) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) {
    error = path + ": cannot write";
    return false;
  }
  std::fprintf(f, "env,step,x_m,y_m,z_m,target_x_m,target_y_m,target_z_m,episode\n");
  for (int e = 0; e < w.trace_envs(); ++e)
    for (int k = 0; k < w.trace_length(); ++k) {
      const Vec3& p = w.trace_point(e, k);
      const Vec3& t = w.trace_target(e, k);
      std::fprintf(f, "%d,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%u\n", e, k + 1, static_cast<double>(p[0]), static_cast<double>(p[1]),
                   static_cast<double>(p[2]), static_cast<double>(t[0]), static_cast<double>(t[1]), static_cast<double>(t[2]),
                   static_cast<unsigned>(w.trace_episode(e, k)));
    }
  if (std::fclose(f) != 0) {
    error = path + ": cannot write";
    return false;
  }
  return true;
}

bool write_env_csv(const World& w, const std::string& path, std::string& error) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) {
    error = path + ": cannot write";
    return false;
  }
  std::fprintf(f, "env,robot,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,target_x_m,target_y_m,target_z_m,env_steps,crashes,resets,timeouts,out_of_bounds,successes,"
                  "lower_x_m,lower_y_m,lower_z_m,upper_x_m,upper_y_m,upper_z_m\n");
  for (int e = 0; e < w.num_envs(); ++e)
    for (int r = 0; r < w.robots_per_env(); ++r) {
      const RigidBodyState& s = w.robot_state(e, r);
      const Vec3& t = w.target(e, r);
      const EnvStats& st = w.stats(e);
      Vec3 lo, hi;
      w.lower_upper_bounds(e, lo, hi);
      std::fprintf(f, "%d,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%llu,%u,%u,%u,%u,%u,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n", e, r,
                   static_cast<double>(s.position_w[0]), static_cast<double>(s.position_w[1]), static_cast<double>(s.position_w[2]),
                   static_cast<double>(s.linvel_w[0]), static_cast<double>(s.linvel_w[1]), static_cast<double>(s.linvel_w[2]),
                   static_cast<double>(t[0]), static_cast<double>(t[1]), static_cast<double>(t[2]),
                   static_cast<unsigned long long>(st.env_steps), st.crashes, st.resets, st.timeouts, st.out_of_bounds, st.successes,
                   static_cast<double>(lo[0]), static_cast<double>(lo[1]), static_cast<double>(lo[2]), static_cast<double>(hi[0]),
                   static_cast<double>(hi[1]), static_cast<double>(hi[2]));
    }
  if (std::fclose(f) != 0) {
    error = path + ": cannot write";
    return false;
  }
  return true;
}

namespace {
const char* asset_kind_name(AssetKind k) {
  switch (k) {
    case AssetKind::tree: return "tree";
    case AssetKind::panel: return "panel";
    case AssetKind::cube: return "cube";
    case AssetKind::rod: return "rod";
    case AssetKind::small_wall: return "small_wall";
    case AssetKind::wall: return "wall";
    case AssetKind::thin: return "thin";
    case AssetKind::sphere: return "sphere";
    case AssetKind::mesh: return "mesh";
  }
  return "unknown";
}
const char* shape_type_name(ShapeType t) {
  switch (t) {
    case ShapeType::sphere: return "sphere";
    case ShapeType::box: return "box";
    case ShapeType::capsule: return "capsule";
    case ShapeType::cylinder: return "cylinder";
    case ShapeType::convex_hull: return "convex_hull";
  }
  return "unknown";
}
}  // namespace

bool write_obstacles_csv(const World& w, int envs, const std::string& path, std::string& error) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) {
    error = path + ": cannot write";
    return false;
  }
  // The shape's own parameters (pose as a unit quaternion, radius / half length along the local z
  // axis / box half extents) and its world bounding box: a plot draws the exact footprint of a
  // sphere, box, capsule or cylinder and falls back to the box for a convex hull (mesh).
  std::fprintf(f, "env,index,kind,shape,semantic_id,upright,x_m,y_m,z_m,qw,qx,qy,qz,radius_m,half_length_m,"
                  "half_x_m,half_y_m,half_z_m,aabb_min_x_m,aabb_min_y_m,aabb_min_z_m,aabb_max_x_m,aabb_max_y_m,aabb_max_z_m\n");
  for (int e = 0; e < std::min(envs, w.num_envs()); ++e)
    for (int i = 0; i < w.num_obstacles(e); ++i) {
      const Obstacle& o = w.obstacle(e, i);
      const Shape& sh = o.shape;
      const Quat& q = sh.orientation_wb;
      auto d = [](real v) { return static_cast<double>(v); };
      std::fprintf(f, "%d,%d,%s,%s,%d,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n",
                   e, i, asset_kind_name(o.kind), shape_type_name(sh.type), static_cast<int>(o.semantic_id), o.upright ? 1 : 0,
                   d(sh.position_w[0]), d(sh.position_w[1]), d(sh.position_w[2]), d(q.w()), d(q.x()), d(q.y()), d(q.z()),
                   d(sh.radius_m), d(sh.half_length_m), d(sh.half_extents_m[0]), d(sh.half_extents_m[1]), d(sh.half_extents_m[2]),
                   d(o.aabb_min_w[0]), d(o.aabb_min_w[1]), d(o.aabb_min_w[2]), d(o.aabb_max_w[0]), d(o.aabb_max_w[1]),
                   d(o.aabb_max_w[2]));
    }
  if (std::fclose(f) != 0) {
    error = path + ": cannot write";
    return false;
  }
  return true;
}

void print_plot_hint(const std::string& out_dir) {
  const char* by_caller = std::getenv("KESTREL_PLOT_BY_CALLER");
  if (by_caller != nullptr && *by_caller != '\0') return;
  std::printf("  plot: kestrel plot %s  (the Python package, .venv/bin/kestrel; or python -m kestrel.plots %s)\n", out_dir.c_str(),
              out_dir.c_str());
}

namespace {
/// One PNG of H rows of row_bytes each (bit_depth and color_type as libpng's IHDR).
bool write_png(const std::string& path, int W, int H, int bit_depth, int color_type, std::size_t row_bytes, const unsigned char* data,
               std::string& error) {
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
  png_set_IHDR(png, info, static_cast<png_uint_32>(W), static_cast<png_uint_32>(H), bit_depth, color_type, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < H; ++y) png_write_row(png, const_cast<png_bytep>(&data[static_cast<std::size_t>(y) * row_bytes]));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::fclose(f);
  return true;
}
}  // namespace

bool write_png_rgb(const std::string& path, int W, int H, const unsigned char* rgb, std::string& error) {
  return write_png(path, W, H, 8, PNG_COLOR_TYPE_RGB, static_cast<std::size_t>(W) * 3, rgb, error);
}

bool write_png_gray16(const std::string& path, int W, int H, const std::uint16_t* values, std::string& error) {
  const std::size_t count = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
  std::vector<unsigned char> be(2 * count);  // PNG's 16-bit samples are big-endian
  for (std::size_t i = 0; i < count; ++i) {
    be[2 * i] = static_cast<unsigned char>(values[i] >> 8);
    be[2 * i + 1] = static_cast<unsigned char>(values[i] & 0xff);
  }
  return write_png(path, W, H, 16, PNG_COLOR_TYPE_GRAY, static_cast<std::size_t>(W) * 2, be.data(), error);
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
