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
  std::uint32_t successes = 0;            // real episodes that ended (timeout) within the success radius
  std::uint32_t fallback_episodes = 0;    // finished episodes whose placement fell back (target = start):
                                          // never successes, not in the success rate's denominator
  double tracking_error_sum_m = 0;        // sum over env-steps and robots of |setpoint - position|
  double final_distance_sum_m = 0;        // sum over finished episodes of the mean robot distance to target
  std::uint32_t placements = 0;           // robot placements (every reset, the first included)
  std::uint32_t placement_fallbacks = 0;  // of which: no clear (start, target) pair
  std::uint32_t reset_errors = 0;         // non-ok statuses of the core's resets (planar; the World counts its own)
};

struct WorldSummary {
  std::uint64_t env_steps = 0;
  std::uint64_t crashes = 0, resets = 0, timeouts = 0, out_of_bounds = 0, episodes_done = 0, successes = 0;
  std::uint64_t placements = 0, placement_fallbacks = 0;
  std::uint64_t fallback_episodes = 0;  // of episodes_done: placed by a fallback (hovering), never a success
  double mean_tracking_error_m = 0;
  double final_mean_distance_m = 0;   // mean distance to target over robots at the end of the run
  double episode_end_distance_m = 0;  // mean distance to target when an episode ends (any reason)
  std::uint32_t fault_bits = 0;       // OR of every robot's latched chain faults (kernel/status.hpp)
  std::uint64_t reset_errors = 0;     // non-ok statuses from the core while resetting robots
  /// Finished episodes with a real (start, target) pair: the success rate's denominator.
  std::uint64_t real_episodes() const { return episodes_done - fallback_episodes; }
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
  s.placements += e.placements;
  s.placement_fallbacks += e.placement_fallbacks;
  s.fallback_episodes += e.fallback_episodes;
  s.reset_errors += e.reset_errors;
}

}  // namespace kestrel::sim
