// Bounds of the harness's inputs (see limits.hpp for the values and why they exist).
#include "kestrel/sim/limits.hpp"

#include <sstream>

#include "kestrel/sim/config.hpp"
#include "kestrel/sim/world.hpp"

namespace kestrel::sim {

std::string out_of_range(const std::string& field, long long value, long long lo, long long hi, const char* name) {
  return field + ": " + std::to_string(value) + " is out of range; allowed: " + std::to_string(lo) + ".." + std::to_string(hi) +
         " (" + name + ")";
}

bool check_config_limits(const WorldConfig& c, std::string& error) {
  auto in = [&](const std::string& field, long long v, long long lo, long long hi, const char* name) {
    if (v >= lo && v <= hi) return true;
    error = out_of_range(field, v, lo, hi, name);
    return false;
  };
  auto in_real = [&](const std::string& field, double v, double lo, double hi, const char* name) {
    if (v >= lo && v <= hi) return true;  // NaN fails
    std::ostringstream s;
    s << field << ": " << v << " is out of range; allowed: [" << lo << ", " << hi << "] (" << name << ")";
    error = s.str();
    return false;
  };
  const EnvConfig& e = c.env;
  if (!in("env.num_envs", e.num_envs, 1, kMaxNumEnvs, "kMaxNumEnvs")) return false;
  // A slice's environments must be inside the run it is a slice of (and global indices fit the limit).
  if (!in("env.first_env_index", e.first_env_index, 0, kMaxNumEnvs - e.num_envs, "kMaxNumEnvs - env.num_envs")) return false;
  if (e.total_num_envs != 0 &&
      !in("env.total_num_envs", e.total_num_envs, static_cast<long long>(e.first_env_index) + e.num_envs, kMaxNumEnvs,
          "0, or at least env.first_env_index + env.num_envs"))
    return false;
  if (!in("robot.robots_per_env", c.robot.robots_per_env, 1, kMaxRobotsPerEnv, "kMaxRobotsPerEnv")) return false;
  if (!in("sim.substeps", c.sim.substeps, 1, kMaxSubsteps, "kMaxSubsteps")) return false;
  if (!in_real("env.num_physics_steps_per_env_step_mean", static_cast<double>(e.num_physics_steps_per_env_step_mean), 1,
               kMaxPhysicsStepsPerEnvStep, "kMaxPhysicsStepsPerEnvStep"))
    return false;
  if (!in_real("env.num_physics_steps_per_env_step_std", static_cast<double>(e.num_physics_steps_per_env_step_std), 0,
               kMaxPhysicsStepsPerEnvStep, "kMaxPhysicsStepsPerEnvStep"))
    return false;
  if (!in("env.max_latency_physics_steps", e.max_latency_physics_steps, 0, kMaxLatencyPhysicsSteps, "kMaxLatencyPhysicsSteps"))
    return false;
  if (!in("threads", c.num_threads, 1, kMaxThreads, "kMaxThreads")) return false;
  long long slots = 0;
  for (const AssetClass& a : e.assets) {
    const std::string f = "env.assets." + a.name;
    if (!in(f + ".num_assets", a.num_assets, 0, kMaxAssetsPerClass, "kMaxAssetsPerClass")) return false;
    if (!in(f + ".min_num_assets", a.min_num_assets, 0, a.num_assets, "at most num_assets")) return false;
    if (!in(f + ".semantic_id", a.semantic_id, 0, kMaxAssetSemanticId, "kMaxAssetSemanticId")) return false;
    // asset_class_slots() cannot overflow here: num_assets * (1 + kTreeBranches) <= 262,144.
    slots += asset_class_slots(a);
  }
  if (slots > kMaxObstacleSlotsPerEnv) {
    error = out_of_range("env.assets (obstacle slots per environment: the sum of num_assets, a tree counting " +
                             std::to_string(1 + kTreeBranches) + ")",
                         slots, 0, kMaxObstacleSlotsPerEnv, "kMaxObstacleSlotsPerEnv");
    return false;
  }
  for (const SensorConfig& s : c.robot.sensors) {
    if (!in("sensors." + s.name + ".every", s.every_env_steps, 1, kMaxSensorEveryEnvSteps, "kMaxSensorEveryEnvSteps"))
      return false;
  }
  const TerrainConfig& t = e.terrain;
  if (t.type == TerrainType::heightfield && t.procedural == "wave" &&
      !in("env.terrain.num_waves", t.num_waves, 1, kMaxNumWaves, "kMaxNumWaves"))
    return false;
  if (t.measure_heights) {
    const long long n = static_cast<long long>(t.measured_points_x_m.size()) * static_cast<long long>(t.measured_points_y_m.size());
    if (!in("env.terrain.measured_points_x x measured_points_y (points per robot)", n, 1, kMaxMeasuredHeightPoints,
            "kMaxMeasuredHeightPoints"))
      return false;
  }
  if (!(c.max_memory_gib > 0) || !(c.max_memory_gib <= kMaxMemoryGiBSetting)) {
    std::ostringstream s;
    s << "max_memory_gib: " << c.max_memory_gib << " is out of range; allowed: (0, " << kMaxMemoryGiBSetting << "] GiB";
    error = s.str();
    return false;
  }
  return true;
}

}  // namespace kestrel::sim
