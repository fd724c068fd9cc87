// Run outputs: CSV logs and a PNG trajectory plot (libpng, lines rasterised with Bresenham's
// algorithm, J. E. Bresenham, IBM Systems Journal 4(1), 1965).
#pragma once

#include <string>

#include "kestrel/sim/world.hpp"

namespace kestrel::sim {

/// trajectory.csv: env, step, x, y, z of the traced environments.
[[nodiscard]] bool write_trajectory_csv(const World& world, const std::string& path, std::string& error);
/// envs.csv: one row per environment: final state, target, counters.
[[nodiscard]] bool write_env_csv(const World& world, const std::string& path, std::string& error);
/// trajectory.png: x-y paths (top view) of the traced environments over the env bounds, with
/// the obstacles of environment 0 outlined by their AABBs.
[[nodiscard]] bool write_trajectory_png(const World& world, const std::string& path, std::string& error);

}  // namespace kestrel::sim
