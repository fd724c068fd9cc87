// Scenario files (YAML, parsed with yaml-cpp): name the sim, env, robot, controller, sensors and
// task by registry name, with field overrides. Example (sim/scenarios/default.yaml):
//
//   seed: 0
//   sim: base_sim                      # a name ...
//   env: {name: forest, num_envs: 1024} # ... or a map with name + overrides
//   robot: {name: base_quadrotor, robots_per_env: 1}
//   controller: lee_position_control
//   task: {name: position_setpoint, episode_len_env_steps: 500}
//   sensors: []
//
// A bad file gives one message naming the file, the field and the allowed values, e.g.
//   scenario.yaml: env.num_envs: expected a positive integer, got "-3"
// and leaves `out` untouched (everything is parsed into a temporary first).
#pragma once

#include <string>

#include "kestrel/sim/config.hpp"

namespace kestrel::sim {

[[nodiscard]] bool load_scenario_file(const std::string& path, WorldConfig& out, std::string& error);
/// `source_name` is what messages call the text (a file name, "<embedded default>").
[[nodiscard]] bool load_scenario_string(const std::string& text, const std::string& source_name, WorldConfig& out,
                                        std::string& error);
/// The same with the files the text names (meshes, height maps, robot files) relative to `base_dir`
/// (ending in '/'), as they are to a scenario file's folder: a file's scenario edited in memory
/// (kestrel.cluster's sweeps) keeps its meaning.
[[nodiscard]] bool load_scenario_string(const std::string& text, const std::string& source_name, const std::string& base_dir,
                                        WorldConfig& out, std::string& error);

/// Registers a preset at run time (Aerial Gym's register_sim / register_env / register_robot ...):
/// `kind` is one of sim, env, robot, controller, sensor, task, simulator; `section_yaml` is what a
/// scenario's section of that kind holds (a registry name, or a map with `name` = the base preset
/// and overrides of its fields, read through the schema: sim/schema.hpp), evaluated now; scenarios
/// can then name it. False and a message naming the kind, the name and the field (nothing
/// registered) on a bad kind, a taken or empty name, or a bad section.
[[nodiscard]] bool register_preset(const std::string& kind, const std::string& name, const std::string& section_yaml,
                                   const std::string& description, std::string& error);

/// The embedded default scenario: 1024 base quadrotors flying position setpoints through the forest.
const char* default_scenario_yaml();

}  // namespace kestrel::sim
