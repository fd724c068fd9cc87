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

/// The scenario's flat view of a ray sensor (`sensors: [{name, every, max_range_m, ...}]`): one key
/// per parameter of sensors::LidarParams / CameraParams and of their range, output, mount and noise
/// parts (the members' names, units added where the member has none: range.max_range ->
/// max_range_m, noise.a -> noise_a). Read from a preset by ray_sensor_fields, written back by
/// set_ray_sensor_fields; the lidar rows and the camera rows are two schemas over this one struct.
struct RaySensorFields {
  int every_env_steps = 1;
  int height = 64, width = 512;
  real horizontal_fov_deg_min = -180, horizontal_fov_deg_max = 180;  // lidar
  real vertical_fov_deg_min = 0, vertical_fov_deg_max = 90;          // lidar
  real horizontal_fov_deg = 87;                                      // camera
  bool calculate_depth = true;                                       // camera
  real min_range_m = 0.5_r, max_range_m = 20;
  bool normalize_range = false;
  real far_out_of_range_value = -1, near_out_of_range_value = -1;
  bool return_pointcloud = false, pointcloud_in_world_frame = false, segmentation_camera = true;
  Vec3 nominal_position_b_m = Vec3::Zero(), nominal_euler_deg = Vec3::Zero();
  bool randomize_placement = false;
  Vec3 min_translation_b_m = Vec3::Zero(), max_translation_b_m = Vec3::Zero();
  Vec3 min_euler_deg = Vec3::Zero(), max_euler_deg = Vec3::Zero();
  bool fixed_pose_at_range_mean = false;
  bool enable_sensor_noise = true;
  sensors::NoiseParams::Model noise_model = sensors::NoiseParams::Model::none;
  real noise_a = 0, noise_b = 0, noise_c = 0, noise_mean_offset_m = 0;
  real std_dev_multiplier = 0.01_r, pixel_dropout_prob = 0;
};
/// The IMU's scenario view: sensors::ImuParams' members (gravity_w excepted: the sim's) and every.
struct ImuSensorFields : sensors::ImuParams {
  int every_env_steps = 1;
};
/// A sensor's parameters as the flat fields of its kind, and back (every_env_steps included).
RaySensorFields ray_sensor_fields(const SensorConfig& c);
void set_ray_sensor_fields(const RaySensorFields& f, SensorConfig& c);
ImuSensorFields imu_sensor_fields(const SensorConfig& c);
void set_imu_sensor_fields(const ImuSensorFields& f, SensorConfig& c);
/// The checks between fields of a sensor (min < max range, fov min <= max, translation and Euler
/// ranges ordered). False and "where.key: ..." naming the field.
[[nodiscard]] bool check_sensor_cross_fields(const SensorConfig& c, const std::string& where, std::string& error);

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
const Schema<LocomotionConfig>& locomotion_schema();
const Schema<LocomotionRewardScales>& locomotion_scales_schema();
const Schema<PickPlaceTaskConfig>& pick_place_schema();
const Schema<PositionSetpointRewardParams>& position_setpoint_reward_schema();
const Schema<RaySensorFields>& lidar_sensor_schema();   // lidar and ToF presets
const Schema<RaySensorFields>& camera_sensor_schema();  // depth cameras
const Schema<ImuSensorFields>& imu_sensor_schema();

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
