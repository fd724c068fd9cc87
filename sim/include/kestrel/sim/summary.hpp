// Run summaries every backend reports in the same shape (per-environment counters summed over
// episodes), kept apart from any backend so that the Simulator interface needs none of them.
#pragma once

#include <cstdint>

namespace kestrel::sim {

/// Per-environment counters (summed over its episodes).
struct EnvStats {
  std::uint64_t env_steps = 0;
  std::uint32_t crashes = 0;  // env-steps ending with a robot above the force threshold
  std::uint32_t resets = 0;   // resets after set-up (crash, timeout, out of bounds)
  std::uint32_t timeouts = 0;
  std::uint32_t out_of_bounds = 0;
  std::uint32_t episodes_done = 0;
  std::uint32_t successes = 0;            // episodes that ended (timeout) within the success radius
  double tracking_error_sum_m = 0;        // sum over env-steps and robots of |setpoint - position|
  double final_distance_sum_m = 0;        // sum over finished episodes of the mean robot distance to target
  std::uint32_t placement_fallbacks = 0;  // robot placements with no clear (start, target) pair
  std::uint32_t reset_errors = 0;         // non-ok statuses of the core's resets (planar; the World counts its own)
};

struct WorldSummary {
  std::uint64_t env_steps = 0;
  std::uint64_t crashes = 0, resets = 0, timeouts = 0, out_of_bounds = 0, episodes_done = 0, successes = 0;
  std::uint64_t placement_fallbacks = 0;
  double mean_tracking_error_m = 0;
  double final_mean_distance_m = 0;   // mean distance to target over robots at the end of the run
  double episode_end_distance_m = 0;  // mean distance to target when an episode ends (any reason)
  std::uint32_t fault_bits = 0;       // OR of every robot's latched chain faults (kernel/status.hpp)
  std::uint64_t reset_errors = 0;     // non-ok statuses from the core while resetting robots
};

/// Adds one environment's event counters to a summary's totals (both backends summarise this way;
/// the error and distance means are the caller's).
inline void add_env_counters(WorldSummary& s, const EnvStats& e) {
  s.env_steps += e.env_steps;
  s.crashes += e.crashes;
  s.resets += e.resets;
  s.timeouts += e.timeouts;
  s.out_of_bounds += e.out_of_bounds;
  s.episodes_done += e.episodes_done;
  s.successes += e.successes;
  s.placement_fallbacks += e.placement_fallbacks;
  s.reset_errors += e.reset_errors;
}

}  // namespace kestrel::sim
