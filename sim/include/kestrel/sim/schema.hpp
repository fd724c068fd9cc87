// One schema per config struct (issue 10): a table of the struct's fields, each with its scenario
// key (the member's own name, units in the name), its unit, its type, the values it allows and a
// line of documentation. The scenario parser (sim/src/io/scenario.cpp) reads every field through
// these tables, so the key, the range check and the error message are written once; the scenario
// reference (docs/scenario_reference.md, `kestrel schema`) is generated from the same tables, and
// a test keeps the committed copy equal to what they generate.
//
// Keys handled by code rather than a row (a nested map or list: env.assets, env.terrain,
// robot.collision_shape, robot.urdf) are listed per schema as `structural` with their own line.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "kestrel/sim/config.hpp"

namespace kestrel::sim {

enum class FieldType : std::uint8_t { real_number, integer, boolean, vec3, range, choice };

template <class S>
struct Field {
  const char* key = "";     // scenario key: the member's name
  const char* unit = "";    // SI unit ("" for none)
  FieldType type = FieldType::real_number;
  real S::*r = nullptr;     // real_number, range (min)
  real S::*r_max = nullptr; // range (max)
  int S::*i = nullptr;      // integer
  bool S::*b = nullptr;     // boolean
  Vec3 S::*v = nullptr;     // vec3
  double lo = 0, hi = 0;    // allowed values (vec3: each component); integer: hi < lo means no upper bound
  const char* limit = nullptr;  // integer: the sim/limits.hpp constant that bounds it (named in errors)
  const char* choices = nullptr;  // choice: "a, b, c" (the allowed names, in order)
  bool (*set_choice)(S&, const std::string&) = nullptr;  // choice: false for a name not in choices
  const char* (*get_choice)(const S&) = nullptr;          // choice: the current name (docs)
  const char* doc = "";
  const char* alias = nullptr;  // an older key still read (nullptr: none)
};

struct StructuralKey {
  const char* key;
  const char* doc;
};

template <class S>
struct Schema {
  const char* section;  // "sim", "env", "env.assets[]", ...
  const char* doc;
  const Field<S>* fields;
  std::size_t count;
  const StructuralKey* structural;  // nested maps/lists read by code
  std::size_t num_structural;
};

const Schema<SimParams>& sim_schema();
const Schema<SimulatorConfig>& simulator_schema();
const Schema<EnvConfig>& env_schema();
const Schema<AssetClass>& asset_schema();
const Schema<TerrainConfig>& terrain_schema();
const Schema<RobotConfig>& robot_schema();
const Schema<ShapeSpec>& shape_schema();
const Schema<ControllerConfig>& controller_schema();
const Schema<TaskConfig>& task_schema();
const Schema<CurriculumConfig>& curriculum_schema();
const Schema<NavigationConfig>& navigation_schema();
const Schema<NavigationRewardParams>& navigation_reward_schema();

/// The same ranges for a config built in code (C++, tests) rather than read from a file: every
/// field of every schema within its allowed values, vectors finite, ranges ordered; assets and
/// their classes included. False and a message naming section.key and the allowed values. Both
/// backends call it when they are built, so a value a scenario file could not hold cannot reach a
/// world by another road.
[[nodiscard]] bool check_config_fields(const WorldConfig& config, std::string& error);

/// The scenario reference in Markdown: per section, every key with its unit, type, allowed values,
/// default (the struct's, before a registry preset) and documentation.
std::string scenario_reference_markdown();

}  // namespace kestrel::sim
