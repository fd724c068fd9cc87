// Run outputs: CSV logs and a PNG trajectory plot (libpng, lines rasterised with Bresenham's
// algorithm, J. E. Bresenham, IBM Systems Journal 4(1), 1965).
#pragma once

#include <string>
#include <vector>

#include "kestrel/sim/world.hpp"

namespace kestrel::sim {

/// trajectory.csv: env, step, x, y, z of the traced environments.
[[nodiscard]] bool write_trajectory_csv(const World& world, const std::string& path, std::string& error);
/// envs.csv: one row per environment: final state, target, counters.
[[nodiscard]] bool write_env_csv(const World& world, const std::string& path, std::string& error);
/// trajectory.png: x-y paths (top view) of the traced environments over the env bounds, with
/// the obstacles of environment 0 outlined by their AABBs.
[[nodiscard]] bool write_trajectory_png(const World& world, const std::string& path, std::string& error);

/// Rasterises the segment (x0, y0)-(x1, y1), in pixels, into a W x H RGB buffer (row-major, 3
/// bytes per pixel) with colour c; returns the pixels written. Any coordinates are accepted: far
/// ones (1e12 px) are clipped in floating point first, non-finite ones draw nothing.
std::size_t draw_line_rgb(unsigned char* rgb, int W, int H, double x0, double y0, double x1, double y1, const unsigned char c[3]);

/// RGB image (W x H, row-major, 3 bytes per pixel) as an 8-bit PNG.
[[nodiscard]] bool write_png_rgb(const std::string& path, int W, int H, const unsigned char* rgb, std::string& error);
/// For every ray sensor of robot 0 of environment `env`: dir/sensor_<name>_range.png (lidar, or a
/// camera without depth) or _depth.png (depth camera), grey = value / max_range, and
/// dir/sensor_<name>_segmentation.png (colour per id). Paths written are appended to `written`.
[[nodiscard]] bool write_sensor_pngs(const World& world, int env, const std::string& dir, std::vector<std::string>& written,
                                     std::string& error);

}  // namespace kestrel::sim
