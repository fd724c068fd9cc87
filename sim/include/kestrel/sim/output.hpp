// Run outputs: CSV logs (trajectory, per-environment state, obstacles) that the `kestrel` console
// script plots with matplotlib (python/kestrel/plots.py, issue 15), sensor images as PNG (libpng:
// the one image the C++ side still writes, with no Python in the loop), and the run's summary and
// progress line.
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "kestrel/sim/progress.hpp"  // ProgressLine, here before it had its own library
#include "kestrel/sim/world.hpp"

namespace kestrel::sim {

/// trajectory.csv: env, step, x, y, z of robot 0 of the traced environments, with the target and
/// the episode number (resets before it) of every point.
[[nodiscard]] bool write_trajectory_csv(const World& world, const std::string& path, std::string& error);
/// envs.csv: one row per environment: final state, target, counters, the environment's bounds.
[[nodiscard]] bool write_env_csv(const World& world, const std::string& path, std::string& error);
/// obstacles.csv: the obstacles of the first `envs` environments as they stand at the end of the
/// run (each environment's last layout): asset kind, shape, pose, sizes and bounding box, so a
/// plot draws their footprints without the scenario.
[[nodiscard]] bool write_obstacles_csv(const World& world, int envs, const std::string& path, std::string& error);

/// RGB image (W x H, row-major, 3 bytes per pixel) as an 8-bit PNG.
[[nodiscard]] bool write_png_rgb(const std::string& path, int W, int H, const unsigned char* rgb, std::string& error);
/// A 16-bit grey PNG of W x H values (row-major), e.g. depth in millimetres.
[[nodiscard]] bool write_png_gray16(const std::string& path, int W, int H, const std::uint16_t* values, std::string& error);
/// For every ray sensor of robot 0 of environment `env`: dir/sensor_<name>_range.png (lidar, or a
/// camera without depth) or _depth.png (depth camera), grey = value / max_range, and
/// dir/sensor_<name>_segmentation.png (colour per id). Paths written are appended to `written`.
[[nodiscard]] bool write_sensor_pngs(const World& world, int env, const std::string& dir, std::vector<std::string>& written,
                                     std::string& error);

/// The success rate of a run's summary (issue 19): successes over the real episodes only, the
/// fallback episodes (hovering at the start, never successes) named apart, "n/a" when no real
/// episode finished: "success rate 99.6%", "success rate 80.0% (32 of 40 real episodes; 473
/// placement fallbacks not counted)", "success rate n/a (0 episodes)".
std::string success_rate_text(std::uint64_t episodes, std::uint64_t fallback_episodes, std::uint64_t successes);
/// The warning printed when placements fell back (empty when none did): how many of the
/// placements found no clear (start, target) pair, and, when that is more than 5 % of them, that
/// the environment is too dense for the placement rule, with the ways out (the sphere's radius
/// is named when robot_bound_plus_clearance_m > 0).
std::string placement_fallback_text(const std::string& env_name, std::uint64_t fallbacks, std::uint64_t placements,
                                    double robot_bound_plus_clearance_m, bool line_of_sight);

class RunReport;
/// A scripted run's episode lines, the same on every backend: crashes and resets, then the
/// episodes with the success rate over real episodes (success_rate_text) and the crash rate.
void report_episodes(RunReport& rep, const WorldSummary& s, real success_radius_m);

/// The first envs traces of a run (x, y, third value per step, env-major: trace[(e * steps + k) * 3])
/// as CSV with the columns "env,step," + columns. false (error names the file) if it cannot write.
[[nodiscard]] bool write_trace_csv(const std::string& path, const char* columns, const real* trace, int envs,
                                   long long steps, std::string& error);

/// Prints how to plot what a run wrote to out_dir ("  plot: kestrel plot DIR ..."): this program
/// writes CSVs only; the Python package draws them. Not printed when KESTREL_PLOT_BY_CALLER is set
/// (the console script's `kestrel run`, which plots right after).
void print_plot_hint(const std::string& out_dir);


/// What a run prints as its summary, also kept to be written as DIR/summary.txt (`kestrel run
/// --out DIR`, every run kind).
class RunReport {
 public:
  /// printf to stdout, and kept.
  void say(const char* fmt, ...) __attribute__((format(printf, 2, 3)));
  /// Kept only (not printed now: the caller prints it later).
  void keep(const std::string& line) { text_ += line; }
  const std::string& text() const { return text_; }
  /// Writes the kept text to path.
  [[nodiscard]] bool write(const std::string& path, std::string& error) const;
  /// Ends a run's report: keeps "state hash: <16 hex digits>", writes out_dir/summary.txt and
  /// prints "  wrote out_dir/summary.txt" and the hash line. false (error set) if it cannot write.
  [[nodiscard]] bool finish(const std::string& out_dir, std::uint64_t state_hash, std::string& error);

 private:
  std::string text_;
};

}  // namespace kestrel::sim
