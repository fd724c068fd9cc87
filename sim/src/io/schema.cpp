// The schema tables of the config structs (sim/schema.hpp) and the scenario reference generated
// from them. Ranges are those the scenario parser has always enforced; keys are the members' names.
#include "kestrel/sim/schema.hpp"

#include <cstdio>
#include <limits>
#include <sstream>
#include <utility>
#include <vector>

#include "kestrel/sim/limits.hpp"

namespace kestrel::sim {

namespace {

constexpr double kNoMax = -1;  // integer hi < lo: no upper bound

template <class S>
Field<S> real_f(const char* key, real S::*m, const char* unit, double lo, double hi, const char* doc, const char* alias = nullptr) {
  Field<S> f;
  f.key = key;
  f.unit = unit;
  f.type = FieldType::real_number;
  f.r = m;
  f.lo = lo;
  f.hi = hi;
  f.doc = doc;
  f.alias = alias;
  return f;
}
template <class S>
Field<S> int_f(const char* key, int S::*m, double lo, double hi, const char* limit, const char* doc) {
  Field<S> f;
  f.key = key;
  f.type = FieldType::integer;
  f.i = m;
  f.lo = lo;
  f.hi = hi;
  f.limit = limit;
  f.doc = doc;
  return f;
}
template <class S>
Field<S> bool_f(const char* key, bool S::*m, const char* doc) {
  Field<S> f;
  f.key = key;
  f.type = FieldType::boolean;
  f.b = m;
  f.doc = doc;
  return f;
}
template <class S>
Field<S> vec3_f(const char* key, Vec3 S::*m, const char* unit, const char* doc, const char* alias = nullptr) {
  Field<S> f;
  f.key = key;
  f.unit = unit;
  f.type = FieldType::vec3;
  f.v = m;
  f.lo = -1e9;
  f.hi = 1e9;
  f.doc = doc;
  f.alias = alias;
  return f;
}
template <class S>
Field<S> vec3b_f(const char* key, Vec3 S::*m, const char* unit, double lo, double hi, const char* doc) {
  Field<S> f = vec3_f<S>(key, m, unit, doc);
  f.lo = lo;
  f.hi = hi;
  return f;
}
template <class S>
Field<S> range_f(const char* key, real S::*mn, real S::*mx, const char* unit, double lo, double hi, const char* doc) {
  Field<S> f;
  f.key = key;
  f.unit = unit;
  f.type = FieldType::range;
  f.r = mn;
  f.r_max = mx;
  f.lo = lo;
  f.hi = hi;
  f.doc = doc;
  return f;
}
template <class S>
Field<S> choice_f(const char* key, const char* choices, bool (*set)(S&, const std::string&), const char* (*get)(const S&), const char* doc) {
  Field<S> f;
  f.key = key;
  f.type = FieldType::choice;
  f.choices = choices;
  f.set_choice = set;
  f.get_choice = get;
  f.doc = doc;
  return f;
}

/// Name <-> enum value tables for the choice fields (one list per enum, in declaration order).
template <class E, std::size_t N>
bool set_enum(const char* const (&names)[N], const std::string& v, E& out) {
  for (std::size_t k = 0; k < N; ++k)
    if (v == names[k]) {
      out = static_cast<E>(k);
      return true;
    }
  return false;
}
template <class E, std::size_t N>
const char* enum_name(const char* const (&names)[N], E e) {
  const auto k = static_cast<std::size_t>(e);
  return k < N ? names[k] : "?";
}
const char* const kIntegrators[] = {"semi_implicit_euler", "rk4"};
const char* const kVehicles[] = {"automatic", "ground_vehicle", "multirotor"};
using allocation::AirframePreset;
const std::pair<const char*, AirframePreset> kAirframes[] = {
    {"base_quadrotor", AirframePreset::base_quadrotor}, {"x500", AirframePreset::x500}, {"hexarotor", AirframePreset::hexarotor}};
template <class E, std::size_t N>
bool set_enum(const std::pair<const char*, E> (&names)[N], const std::string& v, E& out) {
  for (const auto& p : names)
    if (v == p.first) {
      out = p.second;
      return true;
    }
  return false;
}
template <class E, std::size_t N>
const char* enum_name(const std::pair<const char*, E> (&names)[N], E e) {
  for (const auto& p : names)
    if (p.second == e) return p.first;
  return "(a preset)";
}
const char* const kShapes[] = {"sphere", "box", "capsule", "cylinder"};
const std::pair<const char*, JointControlMode> kJointModes[] = {
    {"position", JointControlMode::position}, {"velocity", JointControlMode::velocity}, {"torque", JointControlMode::torque}};
const char* const kAssetKinds[] = {"tree", "panel", "cube", "rod", "small_wall", "wall", "thin", "sphere", "mesh"};
const char* const kTerrains[] = {"plane", "heightfield", "trimesh"};
const char* const kNavigationActionSpaces[] = {"forward_inclination", "velocity"};
const char* const kNavigationImageEncodings[] = {"range", "proximity"};
const char* const kNoiseModels[] = {"none", "range_dependent", "multiplier"};
const char* const kPickPlaceActionModes[] = {"joint_position", "ee_delta"};

}  // namespace

const Schema<SimParams>& sim_schema() {
  using S = SimParams;
  static const Field<S> f[] = {
      real_f<S>("dt_s", &S::dt_s, "s", 1e-6, 1, "physics step (Aerial Gym's sim dt)"),
      int_f<S>("substeps", &S::substeps, 1, kMaxSubsteps, "kMaxSubsteps", "integrator sub-steps per physics step (dynamics only)"),
      vec3_f<S>("gravity_w", &S::gravity_w, "m/s^2", "gravity, world frame (z up)"),
      choice_f<S>(
          "integrator", "rk4, semi_implicit_euler",
          [](S& s, const std::string& v) { return set_enum(kIntegrators, v, s.integrator); },
          [](const S& s) { return enum_name(kIntegrators, s.integrator); }, "rigid-body integrator (PhysX is semi-implicit)"),
      real_f<S>("contact_stiffness_N_m", &S::contact_stiffness_N_m, "N/m", 0, 1e9, "penalty contact spring along the normal"),
      real_f<S>("contact_damping_N_s_m", &S::contact_damping_N_s_m, "N s/m", 0, 1e9, "penalty contact damper along the normal"),
      real_f<S>("friction_coefficient", &S::friction_coefficient, "", 0, 100, "Coulomb friction coefficient"),
      real_f<S>("friction_damping_N_s_m", &S::friction_damping_N_s_m, "N s/m", 0, 1e9,
                "viscous regularisation of Coulomb friction inside the cone"),
      int_f<S>("solver_iterations", &S::solver_iterations, 1, 1000, nullptr,
               "articulated robots: projected Gauss-Seidel sweeps at most per physics step (warm-started)"),
  };
  static const Schema<S> s{"sim", "physics parameters (`sim: NAME` or a map with `name` and overrides)", f, std::size(f), nullptr, 0};
  return s;
}

const Schema<SimulatorConfig>& simulator_schema() {
  using S = SimulatorConfig;
  static const Field<S> f[] = {
      choice_f<S>(
          "vehicle", "automatic, ground_vehicle, multirotor",
          [](S& s, const std::string& v) { return set_enum(kVehicles, v, s.vehicle); },
          [](const S& s) { return enum_name(kVehicles, s.vehicle); }, "planar: what drives in the plane (automatic: by robot)"),
      real_f<S>("wheelbase_m", &S::wheelbase_m, "m", 1e-3, 100, "ground vehicle: front-to-rear axle distance"),
      real_f<S>("max_speed_m_s", &S::max_speed_m_s, "m/s", 1e-3, 1000, "ground vehicle: speed command limit"),
      real_f<S>("max_steering_rad", &S::max_steering_rad, "rad", 1e-3, 1.4, "ground vehicle: steering angle limit"),
      real_f<S>("altitude_m", &S::altitude_m, "m", -1e4, 1e4, "planar multirotor: the held flight height"),
      int_f<S>("lidar_beams", &S::lidar_beams, 0, kNoMax, nullptr, "planar 2-D lidar beams (0: none)"),
      real_f<S>("lidar_fov_rad", &S::lidar_fov_rad, "rad", 1e-3, static_cast<double>(kTwoPi), "planar lidar field of view, centred on body x"),
      real_f<S>("lidar_max_range_m", &S::lidar_max_range_m, "m", 1e-3, 1e4, "planar lidar maximum range"),
      real_f<S>("max_push_vel_xy_m_s", &S::max_push_vel_xy_m_s, "m/s", 0, 100, "push_robots: v_x, v_y drawn in [-max, max]"),
      real_f<S>("com_bias_max_m", &S::com_bias_max_m, "m", 0, 10,
                "planar: centre-of-mass offset x, y drawn in [-max, max]; articulated: the root body's, x, y and z"),
      range_f<S>("added_mass_kg", &S::added_mass_min_kg, &S::added_mass_max_kg, "kg", -1e6, 1e6,
                 "planar: added mass per reset, [min, max]; articulated: added to the root body"),
      range_f<S>("friction", &S::friction_min, &S::friction_max, "", -1, 100,
                 "articulated: ground contact friction coefficient drawn per reset, [min, max] (-1: not randomised)"),
      range_f<S>("restitution", &S::restitution_min, &S::restitution_max, "", -1, 1,
                 "articulated: ground contact restitution drawn per reset, [min, max] (-1: not randomised)"),
      range_f<S>("joint_armature_kg_m2", &S::joint_armature_min_kg_m2, &S::joint_armature_max_kg_m2, "kg m^2", -1, 1e4,
                 "articulated: each actuated joint's armature drawn per reset, [min, max] (-1: not randomised)"),
      real_f<S>("max_push_force_N", &S::max_push_force_N, "N", 0, 1e6,
                "articulated: push_links force components drawn in [-max, max] per link"),
      range_f<S>("motor_scale", &S::motor_scale_min, &S::motor_scale_max, "", 1e-3, 1e3, "planar: motor / drive constant scale, [min, max]"),
      range_f<S>("gain_scale", &S::gain_scale_min, &S::gain_scale_max, "", 1e-3, 1e3, "planar: controller gain scale, [min, max]"),
  };
  static const Schema<S> s{"simulator", "physics backend (`simulator: rigid|planar` or a map; KESTREL_SIMULATOR overrides the name)",
                           f, std::size(f), nullptr, 0};
  return s;
}

const Schema<EnvConfig>& env_schema() {
  using S = EnvConfig;
  static const Field<S> f[] = {
      int_f<S>("num_envs", &S::num_envs, 1, kMaxNumEnvs, "kMaxNumEnvs", "parallel environments"),
      int_f<S>("first_env_index", &S::first_env_index, 0, kMaxNumEnvs - 1, "kMaxNumEnvs - 1",
               "global index of environment 0 when this world is a slice of a larger run (random streams and env grid as that run's)"),
      int_f<S>("total_num_envs", &S::total_num_envs, 0, kMaxNumEnvs, "kMaxNumEnvs",
               "environments of the whole run this world is a slice of (0: num_envs; sizes the articulated env grid)"),
      real_f<S>("num_physics_steps_per_env_step_mean", &S::num_physics_steps_per_env_step_mean, "", 1, kMaxPhysicsStepsPerEnvStep,
                "physics steps per env-step (decimation), mean"),
      real_f<S>("num_physics_steps_per_env_step_std", &S::num_physics_steps_per_env_step_std, "", 0, kMaxPhysicsStepsPerEnvStep,
                "physics steps per env-step, standard deviation (drawn per reset)"),
      vec3_f<S>("lower_bound_min_m", &S::lower_bound_min_m, "m", "lower bound drawn per reset in [min, max]", "lower_bound_min"),
      vec3_f<S>("lower_bound_max_m", &S::lower_bound_max_m, "m", "", "lower_bound_max"),
      vec3_f<S>("upper_bound_min_m", &S::upper_bound_min_m, "m", "upper bound drawn per reset in [min, max]", "upper_bound_min"),
      vec3_f<S>("upper_bound_max_m", &S::upper_bound_max_m, "m", "", "upper_bound_max"),
      bool_f<S>("reset_on_collision", &S::reset_on_collision, "a crash ends the episode"),
      real_f<S>("collision_force_threshold_N", &S::collision_force_threshold_N, "N", 0, 1e9, "contact normal force counted as a crash",
                "collision_force_threshold"),
      bool_f<S>("create_ground_plane", &S::create_ground_plane, "a ground plane under the bounds"),
      int_f<S>("keep_same_env_for_num_episodes", &S::keep_same_env_for_num_episodes, 1, kNoMax, nullptr,
               "episodes on one obstacle layout before a new one is drawn"),
      bool_f<S>("sample_timestep_for_latency", &S::sample_timestep_for_latency, "per-reset action latency in physics steps"),
      int_f<S>("max_latency_physics_steps", &S::max_latency_physics_steps, 0, kMaxLatencyPhysicsSteps, "kMaxLatencyPhysicsSteps",
               "latency drawn in [0, max]"),
      bool_f<S>("perturb_observations", &S::perturb_observations, "Gaussian noise on what the controller sees"),
      real_f<S>("observation_noise_position_m", &S::observation_noise_position_m, "m", 0, 1e3, "position noise standard deviation"),
      real_f<S>("observation_noise_velocity_m_s", &S::observation_noise_velocity_m_s, "m/s", 0, 1e3, "velocity noise standard deviation"),
      bool_f<S>("enable_disturbance", &S::enable_disturbance, "random force / torque disturbances (Aerial Gym's robot `disturbance`)"),
      real_f<S>("prob_apply_disturbance", &S::prob_apply_disturbance, "", 0, 1, "probability per physics step"),
      vec3_f<S>("max_force_disturbance_N", &S::max_force_disturbance_N, "N", "disturbance force drawn in [-max, max], body frame"),
      vec3_f<S>("max_torque_disturbance_Nm", &S::max_torque_disturbance_Nm, "N m", "disturbance torque drawn in [-max, max], body frame"),
      real_f<S>("curriculum_level", &S::curriculum_level, "", 0, 1, "obstacle count between min_num_assets (0) and num_assets (1)"),
  };
  static const StructuralKey st[] = {
      {"include_asset_type", "map asset class -> true/false: drop the preset's classes set false"},
      {"assets", "list of asset class maps (section env.assets[]), appended to the preset's"},
      {"terrain", "the ground (section env.terrain)"},
  };
  static const Schema<S> s{"env", "environment (`env: NAME` or a map with `name` and overrides)", f, std::size(f), st, std::size(st)};
  return s;
}

const Schema<AssetClass>& asset_schema() {
  using S = AssetClass;
  static const Field<S> f[] = {
      choice_f<S>(
          "kind", "tree, panel, cube, rod, small_wall, wall, thin, sphere, mesh",
          [](S& s, const std::string& v) { return set_enum(kAssetKinds, v, s.kind); },
          [](const S& s) { return enum_name(kAssetKinds, s.kind); }, "shape family (required)"),
      int_f<S>("num_assets", &S::num_assets, 0, kMaxAssetsPerClass, "kMaxAssetsPerClass", "count at curriculum level 1"),
      int_f<S>("min_num_assets", &S::min_num_assets, 0, kNoMax, nullptr, "count at curriculum level 0 (default: num_assets)"),
      vec3_f<S>("min_position_ratio", &S::min_position_ratio, "", "position drawn in [min, max] x (upper - lower) from the lower bound"),
      vec3_f<S>("max_position_ratio", &S::max_position_ratio, "", ""),
      vec3_f<S>("min_euler_rad", &S::min_euler_rad, "rad", "orientation drawn in [min, max] (Euler XYZ)"),
      vec3_f<S>("max_euler_rad", &S::max_euler_rad, "rad", ""),
      vec3_f<S>("min_size_m", &S::min_size_m, "m", "size drawn in [min, max]; per kind (sim/src/scene/layout.cpp)"),
      vec3_f<S>("max_size_m", &S::max_size_m, "m", ""),
      bool_f<S>("keep_in_env", &S::keep_in_env, "the curriculum never removes it"),
      int_f<S>("semantic_id", &S::semantic_id, 0, kMaxAssetSemanticId, "kMaxAssetSemanticId", "segmentation id"),
      real_f<S>("max_speed_m_s", &S::max_speed_m_s, "m/s", 0, 1000, "moving obstacles: velocity drawn per reset in [-max, max]"),
      real_f<S>("max_angular_speed_rad_s", &S::max_angular_speed_rad_s, "rad/s", 0, 1000, "spinning obstacles: world-frame rate in [-max, max]"),
  };
  static const StructuralKey st[] = {{"name", "class name (required, unique)"},
                                     {"mesh_file", "kind mesh: .obj / .stl file, relative to the scenario"}};
  static const Schema<S> s{"env.assets[]", "one obstacle class", f, std::size(f), st, std::size(st)};
  return s;
}

const Schema<TerrainConfig>& terrain_schema() {
  using S = TerrainConfig;
  static const Field<S> f[] = {
      choice_f<S>(
          "type", "plane, heightfield, trimesh", [](S& s, const std::string& v) { return set_enum(kTerrains, v, s.type); },
          [](const S& s) { return enum_name(kTerrains, s.type); }, "ground model (required)"),
      real_f<S>("horizontal_scale_m", &S::horizontal_scale_m, "m", 1e-4, 1e3, "heightfield grid spacing"),
      real_f<S>("vertical_scale_m", &S::vertical_scale_m, "m", 1e-9, 1e3, "image pixel value -> metres"),
      vec3_f<S>("origin_m", &S::origin_m, "m", "grid centre x, y and a z offset (trimesh: a translation)"),
      real_f<S>("length_x_m", &S::length_x_m, "m", 1e-3, 1e4, "procedural grid length"),
      real_f<S>("width_y_m", &S::width_y_m, "m", 1e-3, 1e4, "procedural grid width"),
      real_f<S>("slope", &S::slope, "", -100, 100, "slope, pyramid_slope: rise per metre"),
      real_f<S>("platform_size_m", &S::platform_size_m, "m", 0, 1e4, "pyramid_*: flat top width"),
      real_f<S>("step_width_m", &S::step_width_m, "m", 1e-4, 1e4, "stairs: step width"),
      real_f<S>("step_height_m", &S::step_height_m, "m", -100, 100, "stairs: step height"),
      real_f<S>("min_height_m", &S::min_height_m, "m", -1e3, 1e3, "random_uniform: lowest height"),
      real_f<S>("max_height_m", &S::max_height_m, "m", -1e3, 1e3, "random_uniform: highest height"),
      real_f<S>("height_step_m", &S::height_step_m, "m", 1e-6, 1e3, "random_uniform: height quantum"),
      real_f<S>("downsampled_scale_m", &S::downsampled_scale_m, "m", 1e-4, 1e4, "random_uniform: spacing of the random samples"),
      int_f<S>("num_waves", &S::num_waves, 1, kMaxNumWaves, "kMaxNumWaves", "wave: number of waves"),
      real_f<S>("amplitude_m", &S::amplitude_m, "m", -100, 100, "wave: amplitude"),
      int_f<S>("num_rows", &S::num_rows, 1, 1000, nullptr, "curriculum/randomized: tile rows (difficulty levels, along x)"),
      int_f<S>("num_cols", &S::num_cols, 1, 1000, nullptr, "curriculum/randomized: tile columns (terrain types, along y)"),
      real_f<S>("tile_length_m", &S::tile_length_m, "m", 0.5, 1e3, "curriculum/randomized: tile size along x"),
      real_f<S>("tile_width_m", &S::tile_width_m, "m", 0.5, 1e3, "curriculum/randomized: tile size along y"),
      real_f<S>("border_size_m", &S::border_size_m, "m", 0, 1e3, "curriculum/randomized: flat border around the tiles"),
      int_f<S>("max_init_terrain_level", &S::max_init_terrain_level, 0, 1000, nullptr,
               "curriculum/randomized: robots start at a level drawn in [0, this]"),
      bool_f<S>("measure_heights", &S::measure_heights, "legged_gym's measured_heights around each robot"),
  };
  static const StructuralKey st[] = {
      {"heights_m", "heightfield: list of rows (row j = y index j) of heights, m"},
      {"image_file", "heightfield: .pgm / .png heightmap, relative to the scenario"},
      {"procedural", "heightfield generator: flat, slope, pyramid_slope, stairs, pyramid_stairs, random_uniform, wave, curriculum, randomized"},
      {"terrain_proportions", "curriculum/randomized: shares of smooth slope, rough slope, stairs up, stairs down, discrete obstacles (5 numbers >= 0, sum > 0)"},
      {"mesh_file", "trimesh: .obj / .stl file, relative to the scenario"},
      {"measured_points_x_m", "body-yaw-frame x offsets of the height points, m (alias measured_points_x)"},
      {"measured_points_y_m", "body-yaw-frame y offsets of the height points, m (alias measured_points_y)"},
      {"measured_points_x", "older name of measured_points_x_m"},
      {"measured_points_y", "older name of measured_points_y_m"},
  };
  static const Schema<S> s{"env.terrain", "the ground of every environment", f, std::size(f), st, std::size(st)};
  return s;
}

const Schema<RobotConfig>& robot_schema() {
  using S = RobotConfig;
  static const Field<S> f[] = {
      int_f<S>("robots_per_env", &S::robots_per_env, 1, kMaxRobotsPerEnv, "kMaxRobotsPerEnv", "robots in each environment"),
      choice_f<S>(
          "airframe", "base_quadrotor, x500, hexarotor", [](S& s, const std::string& v) { return set_enum(kAirframes, v, s.airframe); },
          [](const S& s) { return enum_name(kAirframes, s.airframe); }, "rotor layout and motor model preset"),
      real_f<S>("mass_kg", &S::mass_kg, "kg", 1e-6, 1e6, "mass"),
      vec3_f<S>("inertia_diag_kg_m2", &S::inertia_diag_kg_m2, "kg m^2", "principal inertia, body frame"),
      vec3_f<S>("linear_drag_b", &S::linear_drag_b, "N s/m", "linear drag, body frame"),
      vec3_f<S>("quadratic_drag_b", &S::quadratic_drag_b, "N s^2/m^2", "quadratic drag, body frame"),
      vec3_f<S>("angular_drag_b", &S::angular_drag_b, "N m s", "angular drag, body frame"),
      vec3_f<S>("quadratic_angular_drag_b", &S::quadratic_angular_drag_b, "N m s^2", "quadratic angular drag, body frame"),
      vec3_f<S>("min_init_position_ratio", &S::min_init_position_ratio, "", "start drawn in [min, max] x (upper - lower) from the lower bound"),
      vec3_f<S>("max_init_position_ratio", &S::max_init_position_ratio, "", ""),
      real_f<S>("max_init_yaw_rad", &S::max_init_yaw_rad, "rad", 0, static_cast<double>(kPi), "start yaw drawn in [-max, max]"),
      real_f<S>("max_init_linvel_m_s", &S::max_init_linvel_m_s, "m/s", 0, 100,
                "start velocity, each world-frame component drawn in [-max, max] (0: at rest)"),
      real_f<S>("max_init_angvel_rad_s", &S::max_init_angvel_rad_s, "rad/s", 0, 100,
                "start angular rate, each world-frame component drawn in [-max, max] (0: none)"),
      bool_f<S>("use_desaturation", &S::use_desaturation, "sequential desaturation (false: Aerial Gym's clamped pseudo-inverse)"),
      real_f<S>("joint_kp_Nm_rad", &S::joint_kp_Nm_rad, "N m/rad", 0, 1e5, "articulated: joint PD stiffness"),
      real_f<S>("joint_kd_Nms_rad", &S::joint_kd_Nms_rad, "N m s/rad", 0, 1e4, "articulated: joint PD damping"),
      real_f<S>("action_scale", &S::action_scale, "rad", 0, 100, "articulated: joint target offset per unit of action"),
      choice_f<S>(
          "joint_control_mode", "position, velocity, torque",
          [](S& s, const std::string& v) { return set_enum(kJointModes, v, s.joint_control_mode); },
          [](const S& s) { return enum_name(kJointModes, s.joint_control_mode); },
          "articulated: legged_gym's control_type (P: targets about home, V: joint speeds, T: torques)"),
      int_f<S>("joint_delay_steps", &S::joint_delay_steps, 0, 4, "the joint PD's delay line", "articulated: physics steps of action delay"),
      range_f<S>("joint_kp_scale", &S::joint_kp_scale_min, &S::joint_kp_scale_max, "", 1e-3, 1e3,
                 "articulated: joint stiffness scale drawn per reset, [min, max]"),
      range_f<S>("joint_kd_scale", &S::joint_kd_scale_min, &S::joint_kd_scale_max, "", 1e-3, 1e3,
                 "articulated: joint damping scale drawn per reset, [min, max]"),
      real_f<S>("joint_damping_Nms_rad", &S::joint_damping_Nms_rad, "N m s/rad", -1, 1e4,
                "articulated: passive viscous damping of every actuated joint (-1: the robot file's)"),
      real_f<S>("joint_friction_loss_Nm", &S::joint_friction_loss_Nm, "N m", -1, 1e4,
                "articulated: dry friction of every actuated joint (-1: the robot file's)"),
      real_f<S>("joint_armature_kg_m2", &S::joint_armature_kg_m2, "kg m^2", -1, 1e4,
                "articulated: rotor inertia of every actuated joint (-1: the robot file's)"),
      bool_f<S>("self_collisions", &S::self_collisions,
                "articulated: contacts between the robot's own links (not those a joint connects; the file's contype/conaffinity filter)"),
  };
  static const StructuralKey st[] = {
      {"urdf", "URDF file: mass, inertia, collision shape and rotors (the keys here override it)"},
      {"model", "articulated robot file (MJCF or URDF: joints, inertias, collision primitives, `home` keyframe); makes the robot articulated"},
      {"file", "a robot file with these same keys"},
      {"collision_shape", "the robot's collision shape (section robot.collision_shape)"},
  };
  static const Schema<S> s{"robot", "the robot (`robot: NAME` or a map with `name` and overrides)", f, std::size(f), st, std::size(st)};
  return s;
}

const Schema<ShapeSpec>& shape_schema() {
  using S = ShapeSpec;
  static const Field<S> f[] = {
      choice_f<S>(
          "type", "sphere, box, capsule, cylinder", [](S& s, const std::string& v) { return set_enum(kShapes, v, s.type); },
          [](const S& s) { return enum_name(kShapes, s.type); }, "shape (required)"),
      real_f<S>("radius_m", &S::radius_m, "m", 1e-4, 100, "sphere / capsule / cylinder radius"),
      real_f<S>("half_length_m", &S::half_length_m, "m", 0, 100, "capsule / cylinder: half the axis segment (local z)"),
      vec3_f<S>("half_extents_m", &S::half_extents_m, "m", "box half extents"),
  };
  static const Schema<S> s{"robot.collision_shape", "collision shape in the body frame", f, std::size(f), nullptr, 0};
  return s;
}

const Schema<ControllerConfig>& controller_schema() {
  using S = ControllerConfig;
  const double g = static_cast<double>(kLeeMaxGain);
  static const Field<S> f[] = {
      bool_f<S>("randomize_gains", &S::randomize_gains, "draw the Lee gains per reset within [min, max] (else the midpoints fly)"),
      vec3b_f<S>("k_pos_min", &S::k_pos_min, "m/s^2 per m", 0, g, "position gain range, min (Lee family; `k_pos: [x, y, z]` sets min = max)"),
      vec3b_f<S>("k_pos_max", &S::k_pos_max, "m/s^2 per m", 0, g, "position gain range, max (>= min)"),
      vec3b_f<S>("k_vel_min", &S::k_vel_min, "m/s^2 per m/s", 0, g, "velocity gain range, min (`k_vel` sets min = max)"),
      vec3b_f<S>("k_vel_max", &S::k_vel_max, "m/s^2 per m/s", 0, g, "velocity gain range, max"),
      vec3b_f<S>("k_rot_min", &S::k_rot_min, "N m per e_R", 0, g, "attitude gain range, min (`k_rot` sets min = max)"),
      vec3b_f<S>("k_rot_max", &S::k_rot_max, "N m per e_R", 0, g, "attitude gain range, max"),
      vec3b_f<S>("k_angvel_min", &S::k_angvel_min, "N m per rad/s", 0, g, "body-rate gain range, min (`k_angvel` sets min = max)"),
      vec3b_f<S>("k_angvel_max", &S::k_angvel_max, "N m per rad/s", 0, g, "body-rate gain range, max"),
      real_f<S>("max_yaw_rate_rad_s", &S::max_yaw_rate_rad_s, "rad/s", 0, 1e3, "clamp on the desired body-z rate"),
      real_f<S>("action_min", &S::action_min, "", -1e6, 1e6, "every action component is clipped to [action_min, action_max]"),
      real_f<S>("action_max", &S::action_max, "", -1e6, 1e6, "(> action_min)"),
  };
  static const StructuralKey st[] = {
      {"k_pos", "[x, y, z] in [0, 1e6], m/s^2 per m: a fixed position gain (k_pos_min = k_pos_max = it); not with k_pos_min / k_pos_max"},
      {"k_vel", "[x, y, z] in [0, 1e6], m/s^2 per m/s: a fixed velocity gain"},
      {"k_rot", "[x, y, z] in [0, 1e6], N m per e_R: a fixed attitude gain"},
      {"k_angvel", "[x, y, z] in [0, 1e6], N m per rad/s: a fixed body-rate gain"},
  };
  static const Schema<S> s{"controller",
                           "the controller (`controller: NAME`, a registry name, or a map with `name` and overrides); the gains are "
                           "the Lee family's (LeeParams: Aerial Gym's lee_controller_config by default; a base_rov airframe keeps the "
                           "ROV preset), each nominal gain the midpoint of its [min, max]",
                           f, std::size(f), st, std::size(st)};
  return s;
}

const Schema<TaskConfig>& task_schema() {
  using S = TaskConfig;
  static const Field<S> f[] = {
      int_f<S>("episode_len_env_steps", &S::episode_len_env_steps, 1, kNoMax, nullptr, "episode length"),
      real_f<S>("success_radius_m", &S::success_radius_m, "m", 0, 1e6, "an episode at its time limit succeeds within this of the target"),
      vec3_f<S>("min_target_ratio", &S::min_target_ratio, "", "target drawn in [min, max] x (upper - lower) from the lower bound"),
      vec3_f<S>("max_target_ratio", &S::max_target_ratio, "", ""),
      real_f<S>("clearance_m", &S::clearance_m, "m", 0, 100, "start and target clear every obstacle by this (beyond the bound radius)"),
      bool_f<S>("line_of_sight", &S::line_of_sight, "the straight path from start to target is clear too"),
      int_f<S>("placement_attempts", &S::placement_attempts, 1, kMaxPlacementAttempts, "kMaxPlacementAttempts",
               "candidate (start, target) pairs drawn per reset"),
      real_f<S>("setpoint_speed_m_s", &S::setpoint_speed_m_s, "m/s", 0, 1000, "moving setpoint speed towards the target (0: the target)"),
  };
  static const StructuralKey st[] = {{"curriculum", "the obstacle curriculum of navigation_task (section task.curriculum)"},
                                     {"navigation", "navigation_task's action scaling, pooling and reward (section task.navigation)"},
                                     {"locomotion", "locomotion_task's commands, observations and rewards (section task.locomotion)"},
                                     {"pick_place", "so101_pick_place's scene, action mode and reward (section task.pick_place)"},
                                     {"reward", "the reward's constants: position_setpoint_task's (section task.reward); for "
                                                "navigation_task the keys of task.navigation.reward"}};
  static const Schema<S> s{"task", "the scripted task (`task: NAME` or a map; an RL task id brings its own scene)", f, std::size(f),
                           st, std::size(st)};
  return s;
}

const Schema<NavigationConfig>& navigation_schema() {
  using S = NavigationConfig;
  static const Field<S> f[] = {
      choice_f<S>(
          "action_space", "forward_inclination, velocity",
          [](S& s, const std::string& v) { return set_enum(kNavigationActionSpaces, v, s.action_space); },
          [](const S& s) { return enum_name(kNavigationActionSpaces, s.action_space); },
          "forward_inclination: 3 actions (forward speed, climb angle, yaw rate; Aerial Gym's); velocity: 4 (vx, vy, vz, yaw rate)"),
      real_f<S>("max_speed_m_s", &S::max_speed_m_s, "m/s", 1e-3, 100,
                "forward_inclination: the top speed; velocity: actions [-1, 1] x this are the vx, vy, vz commands"),
      real_f<S>("max_inclination_rad", &S::max_inclination_rad, "rad", 0, 1.5707963, "forward_inclination: action 1 x this is the climb angle"),
      real_f<S>("max_yaw_rate_rad_s", &S::max_yaw_rate_rad_s, "rad/s", 0, 100, "actions [-1, 1] x this: the yaw-rate command"),
      int_f<S>("pool_rows", &S::pool_rows, 1, 64, nullptr, "range image min-pooled to pool_rows x pool_cols observation cells"),
      int_f<S>("pool_cols", &S::pool_cols, 1, 64, nullptr, ""),
      choice_f<S>(
          "image_encoding", "range, proximity",
          [](S& s, const std::string& v) { return set_enum(kNavigationImageEncodings, v, s.image_encoding); },
          [](const S& s) { return enum_name(kNavigationImageEncodings, s.image_encoding); },
          "an image cell for its nearest range r: range, r / max range (the reference's scale); proximity, 1 / (1 + r / proximity_scale_m)"),
      real_f<S>("proximity_scale_m", &S::proximity_scale_m, "m", 1e-3, 100, "proximity: the range whose cell reads 0.5"),
      int_f<S>("image_history_frames", &S::image_history_frames, 0, 16, nullptr,
               "earlier images appended after the current one (0: none); a new episode's are its first image"),
      int_f<S>("image_history_lag_env_steps", &S::image_history_lag_env_steps, 1, 1000, nullptr,
               "env-steps between the current image and the first earlier one, and between earlier ones"),
  };
  static const StructuralKey st[] = {{"reward", "the reward's constants (section task.navigation.reward)"}};
  static const Schema<S> s{"task.navigation", "navigation_task's actions, image observation and reward", f, std::size(f), st,
                           std::size(st)};
  return s;
}

const Schema<LocomotionConfig>& locomotion_schema() {
  using S = LocomotionConfig;
  constexpr double kBig = 1e6;
  static const Field<S> f[] = {
      real_f<S>("resampling_time_s", &S::resampling_time_s, "s", 1e-3, kBig, "commands resampled this often (and at each reset)"),
      bool_f<S>("heading_command", &S::heading_command, "the yaw-rate command is clip(0.5 x heading error, -1, 1)"),
      range_f<S>("lin_vel_x_m_s", &S::lin_vel_x_min_m_s, &S::lin_vel_x_max_m_s, "m/s", -100, 100, "forward velocity command range [min, max]"),
      range_f<S>("lin_vel_y_m_s", &S::lin_vel_y_min_m_s, &S::lin_vel_y_max_m_s, "m/s", -100, 100, "sideways velocity command range"),
      range_f<S>("ang_vel_yaw_rad_s", &S::ang_vel_yaw_min_rad_s, &S::ang_vel_yaw_max_rad_s, "rad/s", -100, 100,
                 "yaw-rate command range (without heading_command)"),
      range_f<S>("heading_rad", &S::heading_min_rad, &S::heading_max_rad, "rad", -10, 10, "heading command range (heading_command)"),
      real_f<S>("obs_scale_lin_vel", &S::obs_scale_lin_vel, "", 0, kBig, "observation scales (legged_gym's obs_scales)"),
      real_f<S>("obs_scale_ang_vel", &S::obs_scale_ang_vel, "", 0, kBig, ""),
      real_f<S>("obs_scale_dof_pos", &S::obs_scale_dof_pos, "", 0, kBig, ""),
      real_f<S>("obs_scale_dof_vel", &S::obs_scale_dof_vel, "", 0, kBig, ""),
      real_f<S>("obs_scale_height", &S::obs_scale_height, "", 0, kBig, "height samples: clip(base z - 0.5 - h, -1, 1) x this"),
      real_f<S>("clip_observations", &S::clip_observations, "", 0, kBig, "every observation clipped to +-this"),
      bool_f<S>("add_noise", &S::add_noise, "uniform observation noise +-(noise_* x noise_level x the observation's scale)"),
      real_f<S>("noise_level", &S::noise_level, "", 0, kBig, ""),
      real_f<S>("noise_lin_vel", &S::noise_lin_vel, "m/s", 0, kBig, ""),
      real_f<S>("noise_ang_vel", &S::noise_ang_vel, "rad/s", 0, kBig, ""),
      real_f<S>("noise_gravity", &S::noise_gravity, "", 0, kBig, ""),
      real_f<S>("noise_dof_pos", &S::noise_dof_pos, "rad", 0, kBig, ""),
      real_f<S>("noise_dof_vel", &S::noise_dof_vel, "rad/s", 0, kBig, ""),
      real_f<S>("noise_height", &S::noise_height, "m", 0, kBig, ""),
      bool_f<S>("only_positive_rewards", &S::only_positive_rewards, "the summed reward (before termination) clipped at 0"),
      real_f<S>("tracking_sigma", &S::tracking_sigma, "", 1e-9, kBig, "tracking rewards exp(-error^2 / sigma)"),
      real_f<S>("soft_dof_pos_limit", &S::soft_dof_pos_limit, "", 0, kBig, "share of the joint range beyond which dof_pos_limits penalises"),
      real_f<S>("soft_torque_limit", &S::soft_torque_limit, "", 0, kBig, "share of the effort limit beyond which torque_limits penalises"),
      real_f<S>("base_height_target_m", &S::base_height_target_m, "m", -kBig, kBig, "base_height term's target"),
      real_f<S>("max_contact_force_N", &S::max_contact_force_N, "N", 0, kBig, "feet_contact_forces penalises foot forces above this"),
      bool_f<S>("push_robots", &S::push_robots, "push every robot every push_interval_s (simulator.max_push_vel_xy_m_s)"),
      real_f<S>("push_interval_s", &S::push_interval_s, "s", 1e-3, kBig, ""),
      bool_f<S>("terrain_curriculum", &S::terrain_curriculum,
                "on a tiled terrain, move each robot a level up / down at its episode's end by the distance it walked"),
      real_f<S>("push_links_interval_s", &S::push_links_interval_s, "s", 0, kBig,
                "push every link (simulator.max_push_force_N) this often; 0: never"),
      range_f<S>("reset_dof_pos_scale", &S::reset_dof_pos_scale_min, &S::reset_dof_pos_scale_max, "", -kBig, kBig,
                 "at a reset each joint starts at home x U(min, max)"),
      real_f<S>("reset_base_vel_max", &S::reset_base_vel_max, "m/s, rad/s", 0, kBig, "at a reset each base velocity component is U(-max, max)"),
  };
  static const StructuralKey st[] = {
      {"scales", "the reward terms' scales (section task.locomotion.scales)"},
      {"penalize_contacts_on", "body-name fragments (case-insensitive) whose contacts the collision term counts; "
                               "default [thigh, calf, shank]"}};
  static const Schema<S> s{"task.locomotion", "locomotion_task's commands, observations, noise, reward parameters and pushes "
                                               "(legged_gym's LeggedRobotCfg)", f, std::size(f), st, std::size(st)};
  return s;
}

const Schema<PickPlaceTaskConfig>& pick_place_schema() {
  using S = PickPlaceTaskConfig;
  constexpr double kBig = 1e6;
  static const Field<S> f[] = {
      choice_f<S>(
          "action_mode", "joint_position, ee_delta",
          [](S& s, const std::string& v) { return set_enum(kPickPlaceActionModes, v, s.action_mode); },
          [](const S& s) { return enum_name(kPickPlaceActionModes, s.action_mode); },
          "joint_position: 6 absolute joint targets (rad, LeIsaac's); ee_delta: 5 (tool-centre-point dx, dy, dz in m, yaw "
          "delta in rad, gripper target in rad) through damped-least-squares IK, for teleoperation"),
      real_f<S>("dt_s", &S::dt_s, "s", 1e-5, 0.1, "physics step"),
      int_f<S>("decimation", &S::decimation, 1, 1000, nullptr, "physics steps per action (4 x 5 ms: 50 Hz actions)"),
      int_f<S>("solver_iterations", &S::solver_iterations, 1, 10000, nullptr, "contact solver iterations per physics step"),
      real_f<S>("arm_kp_Nm_rad", &S::arm_kp_Nm_rad, "N m/rad", 0, kBig, "the five arm joints' servo stiffness"),
      real_f<S>("arm_kd_Nms_rad", &S::arm_kd_Nms_rad, "N m s/rad", 0, kBig, "the arm joints' servo damping"),
      real_f<S>("gripper_kp_Nm_rad", &S::gripper_kp_Nm_rad, "N m/rad", 0, kBig, "the gripper's servo stiffness (the squeeze)"),
      real_f<S>("gripper_kd_Nms_rad", &S::gripper_kd_Nms_rad, "N m s/rad", 0, kBig, "the gripper's servo damping"),
      real_f<S>("cube_half_m", &S::cube_half_m, "m", 1e-3, 0.1, "the cube's half side"),
      real_f<S>("cube_mass_kg", &S::cube_mass_kg, "kg", 1e-4, 10, "the cube's mass"),
      real_f<S>("cube_friction", &S::cube_friction, "", 0, 10, "the cube's Coulomb friction coefficient"),
      vec3b_f<S>("cube_pos_w", &S::cube_pos_w, "m", -1, 1, "the cube's nominal centre x, y (z: resting on the table)"),
      vec3b_f<S>("box_pos_w", &S::box_pos_w, "m", -1, 1, "the box's nominal centre x, y (its floor's bottom face, z ignored)"),
      real_f<S>("box_inner_half_m", &S::box_inner_half_m, "m", 1e-3, 0.5, "the box's inner half side (square, inside the walls)"),
      real_f<S>("box_wall_m", &S::box_wall_m, "m", 1e-4, 0.1, "the thickness of the box's walls and floor"),
      real_f<S>("box_height_m", &S::box_height_m, "m", 1e-3, 0.5, "the walls' height above the table"),
      real_f<S>("box_friction", &S::box_friction, "", 0, 10, "the box's friction coefficient"),
      real_f<S>("table_friction", &S::table_friction, "", 0, 10, "the table's friction coefficient"),
      real_f<S>("randomize_xy_m", &S::randomize_xy_m, "m", 0, 0.5, "cube and box drawn uniformly within +-this in x and y at each reset"),
      real_f<S>("success_xy_m", &S::success_xy_m, "m", 1e-4, 1, "cube_in_box: the cube's centre within +-this of the box's in x and y"),
      real_f<S>("success_height_m", &S::success_height_m, "m", 1e-4, 1, "cube_in_box: the cube's centre below this"),
      int_f<S>("success_hold_steps", &S::success_hold_steps, 1, 100000, nullptr,
               "success (terminated): cube_in_box and released (pads' force < release_force_N) for this many consecutive actions"),
      real_f<S>("release_force_N", &S::release_force_N, "N", 0, kBig, "the pads' force on the cube below which it counts as released"),
      bool_f<S>("end_on_success", &S::end_on_success,
                "success ends the episode (terminated) with its bonus; false: the caller's own terms decide (kestrel.SceneTask)"),
      real_f<S>("ee_max_delta_m", &S::ee_max_delta_m, "m", 1e-5, 1, "ee_delta: each position delta clipped to +-this per action"),
      real_f<S>("ee_max_yaw_delta_rad", &S::ee_max_yaw_delta_rad, "rad", 0, 3.2, "ee_delta: the yaw delta clipped to +-this per action"),
      real_f<S>("reach_weight", &S::reach_weight, "", -kBig, kBig, "reward reach: weight x (1 - tanh(|cube - tcp| / reach_scale_m))"),
      real_f<S>("reach_scale_m", &S::reach_scale_m, "m", 1e-6, kBig, ""),
      real_f<S>("grasp_weight", &S::grasp_weight, "", -kBig, kBig, "reward grasp: weight while the pads squeeze the cube with > grasp_force_N"),
      real_f<S>("grasp_force_N", &S::grasp_force_N, "N", 0, kBig, ""),
      real_f<S>("lift_weight", &S::lift_weight, "", -kBig, kBig,
                "reward lift: weight x clip(cube height above its rest / lift_height_m, 0, 1) while grasped"),
      real_f<S>("lift_height_m", &S::lift_height_m, "m", 1e-6, kBig, ""),
      real_f<S>("place_weight", &S::place_weight, "", -kBig, kBig,
                "reward place: weight x (1 - tanh(|cube - box|_xy / place_scale_m)) while grasped and lifted, or in the box"),
      real_f<S>("place_scale_m", &S::place_scale_m, "m", 1e-6, kBig, ""),
      real_f<S>("success_reward", &S::success_reward, "", -kBig, kBig, "reward success: added on the step that succeeds"),
      choice_f<S>(
          "robot_file", "a robot file path (MJCF or URDF with the SO-101's six joints)",
          [](S& s, const std::string& v) {
            s.robot_file = v;
            return true;
          },
          [](const S& s) { return s.robot_file.c_str(); },
          "the arm's robot file (absolute, or relative to the working directory); empty: models/so101/so101.xml"),
  };
  static const Schema<S> s{"task.pick_place", "so101_pick_place's scene (sim/pick_place.hpp), action mode, success rule and shaped reward",
                           f, std::size(f), nullptr, 0};
  return s;
}

const Schema<LocomotionRewardScales>& locomotion_scales_schema() {
  using S = LocomotionRewardScales;
  constexpr double kBig = 1e9;
#define KESTREL_SCALE_ROW(name, doc) real_f<S>(#name, &S::name, "", -kBig, kBig, doc)
  static const Field<S> f[] = {
      KESTREL_SCALE_ROW(termination, "1 when a contact ended the episode (added after the only_positive clip)"),
      KESTREL_SCALE_ROW(tracking_lin_vel, "exp(-|cmd_xy - v_xy|^2 / sigma)"),
      KESTREL_SCALE_ROW(tracking_ang_vel, "exp(-(cmd_yaw - w_z)^2 / sigma)"),
      KESTREL_SCALE_ROW(lin_vel_z, "v_z^2 (body frame)"),
      KESTREL_SCALE_ROW(ang_vel_xy, "w_x^2 + w_y^2"),
      KESTREL_SCALE_ROW(orientation, "projected gravity x^2 + y^2"),
      KESTREL_SCALE_ROW(torques, "sum tau^2"),
      KESTREL_SCALE_ROW(dof_vel, "sum qd^2"),
      KESTREL_SCALE_ROW(dof_acc, "sum ((qd_last - qd) / dt)^2"),
      KESTREL_SCALE_ROW(base_height, "(base height - base_height_target_m)^2"),
      KESTREL_SCALE_ROW(feet_air_time, "sum over first contacts of (air time - 0.5 s), when |cmd_xy| > 0.1"),
      KESTREL_SCALE_ROW(collision, "penalised bodies touching (> 0.1 N)"),
      KESTREL_SCALE_ROW(feet_stumble, "1 if a foot's horizontal force exceeds 5 x its vertical"),
      KESTREL_SCALE_ROW(action_rate, "sum (a_last - a)^2"),
      KESTREL_SCALE_ROW(stand_still, "sum |q - home| when |cmd_xy| < 0.1"),
      KESTREL_SCALE_ROW(dof_pos_limits, "sum of the excursions beyond the soft position limits"),
      KESTREL_SCALE_ROW(torque_limits, "sum of |tau| beyond the soft torque limits"),
      KESTREL_SCALE_ROW(feet_contact_forces, "sum of foot forces beyond max_contact_force_N"),
  };
#undef KESTREL_SCALE_ROW
  static const Schema<S> s{"task.locomotion.scales", "legged_gym's rewards.scales: per second (x the policy step); 0 drops the term",
                           f, std::size(f), nullptr, 0};
  return s;
}

const Schema<NavigationRewardParams>& navigation_reward_schema() {
  using S = NavigationRewardParams;
  constexpr double kBig = 1e6;
#define KESTREL_REWARD_ROW(name, doc) real_f<S>(#name, &S::name, "", -kBig, kBig, doc)
  static const Field<S> f[] = {
      KESTREL_REWARD_ROW(pos_reward_magnitude, "magnitude x exp(-d^2 x exponent), d the distance to the goal (m)"),
      KESTREL_REWARD_ROW(pos_reward_exponent, ""),
      KESTREL_REWARD_ROW(very_close_to_goal_reward_magnitude, "the same, sharper near the goal"),
      KESTREL_REWARD_ROW(very_close_to_goal_reward_exponent, ""),
      KESTREL_REWARD_ROW(getting_closer_reward_multiplier, "x the distance gained this step (twice that when it is lost)"),
      KESTREL_REWARD_ROW(x_action_diff_penalty_magnitude, "penalties on the change of each action from the last step"),
      KESTREL_REWARD_ROW(x_action_diff_penalty_exponent, ""),
      KESTREL_REWARD_ROW(z_action_diff_penalty_magnitude, ""),
      KESTREL_REWARD_ROW(z_action_diff_penalty_exponent, ""),
      KESTREL_REWARD_ROW(yawrate_action_diff_penalty_magnitude, ""),
      KESTREL_REWARD_ROW(yawrate_action_diff_penalty_exponent, ""),
      KESTREL_REWARD_ROW(x_absolute_action_penalty_magnitude, "penalties on each action's size, x the curriculum progress"),
      KESTREL_REWARD_ROW(x_absolute_action_penalty_exponent, ""),
      KESTREL_REWARD_ROW(z_absolute_action_penalty_magnitude, ""),
      KESTREL_REWARD_ROW(z_absolute_action_penalty_exponent, ""),
      KESTREL_REWARD_ROW(yawrate_absolute_action_penalty_magnitude, ""),
      KESTREL_REWARD_ROW(yawrate_absolute_action_penalty_exponent, ""),
      KESTREL_REWARD_ROW(collision_penalty, "the reward of a crash (the episode ends)"),
      KESTREL_REWARD_ROW(clearance_penalty, "not in the reference (0: off): the reward per env-step at range 0 of the "
                                            "nearest obstacle in the range image, rising linearly to 0 at clearance_m"),
      real_f<S>("clearance_m", &S::clearance_m, "m", 1e-3, 1e3, "where clearance_penalty starts"),
      KESTREL_REWARD_ROW(sideslip_penalty, "not in the reference (0: off): the reward per env-step per m/s of the "
                                           "vehicle's sideways speed (the size of v_y in the body frame)"),
  };
#undef KESTREL_REWARD_ROW
  static const Schema<S> s{"task.navigation.reward", "Aerial Gym's navigation_task_config.reward_parameters (float32)", f,
                           std::size(f), nullptr, 0};
  return s;
}

const Schema<PositionSetpointRewardParams>& position_setpoint_reward_schema() {
  using S = PositionSetpointRewardParams;
  constexpr double kBig = 1e6;
  static const Field<S> f[] = {
      real_f<S>("pos_reward_magnitude_1", &S::pos_reward_magnitude_1, "", -kBig, kBig,
                "pos = magnitude_1 exp(-exponent_1 d^2) + magnitude_2 exp(-exponent_2 d^2), d = |target - position| (m)"),
      real_f<S>("pos_reward_exponent_1", &S::pos_reward_exponent_1, "1/m^2", -kBig, kBig, ""),
      real_f<S>("pos_reward_magnitude_2", &S::pos_reward_magnitude_2, "", -kBig, kBig, ""),
      real_f<S>("pos_reward_exponent_2", &S::pos_reward_exponent_2, "1/m^2", -kBig, kBig, ""),
      real_f<S>("distance_reward_offset_m", &S::distance_reward_offset_m, "m", -kBig, kBig, "dist = (offset - d) / divisor"),
      real_f<S>("distance_reward_divisor_m", &S::distance_reward_divisor_m, "m", 1e-6, kBig, ""),
      real_f<S>("up_reward_magnitude", &S::up_reward_magnitude, "", -kBig, kBig, "up = magnitude / (offset + tilt^2), tilt = |1 - up_z|"),
      real_f<S>("up_reward_offset", &S::up_reward_offset, "", 1e-6, kBig, ""),
      real_f<S>("spin_reward_magnitude", &S::spin_reward_magnitude, "", -kBig, kBig, "spin = magnitude / (1 + |body rates|^2)"),
      real_f<S>("crash_distance_m", &S::crash_distance_m, "m", 0, kBig, "d beyond this is a crash (the episode ends)"),
      real_f<S>("crash_reward", &S::crash_reward, "", -kBig, kBig, "the reward of a crash; otherwise pos + dist + pos (up + spin)"),
  };
  static const Schema<S> s{"task.reward", "position_setpoint_task's reward (Aerial Gym's compute_reward, float32)", f, std::size(f),
                           nullptr, 0};
  return s;
}

RaySensorFields ray_sensor_fields(const SensorConfig& c) {
  RaySensorFields f;
  const bool cam = c.kind == SensorKind::camera;
  const sensors::RangeOutputParams& r = cam ? c.camera.range : c.lidar.range;
  const sensors::OutputFlags& o = cam ? c.camera.output : c.lidar.output;
  const sensors::MountParams& m = cam ? c.camera.mount : c.lidar.mount;
  const sensors::NoiseParams& n = cam ? c.camera.noise : c.lidar.noise;
  f.every_env_steps = c.every_env_steps;
  f.height = static_cast<int>(cam ? c.camera.height : c.lidar.height);
  f.width = static_cast<int>(cam ? c.camera.width : c.lidar.width);
  f.horizontal_fov_deg_min = c.lidar.horizontal_fov_deg_min;
  f.horizontal_fov_deg_max = c.lidar.horizontal_fov_deg_max;
  f.vertical_fov_deg_min = c.lidar.vertical_fov_deg_min;
  f.vertical_fov_deg_max = c.lidar.vertical_fov_deg_max;
  f.horizontal_fov_deg = c.camera.horizontal_fov_deg;
  f.calculate_depth = c.camera.calculate_depth;
  f.min_range_m = r.min_range;
  f.max_range_m = r.max_range;
  f.normalize_range = r.normalize_range;
  f.far_out_of_range_value = r.far_out_of_range_value;
  f.near_out_of_range_value = r.near_out_of_range_value;
  f.return_pointcloud = o.return_pointcloud;
  f.pointcloud_in_world_frame = o.pointcloud_in_world_frame;
  f.segmentation_camera = o.segmentation_camera;
  f.nominal_position_b_m = m.nominal_position_b;
  f.nominal_euler_deg = m.nominal_euler_deg;
  f.randomize_placement = m.randomize_placement;
  f.min_translation_b_m = m.min_translation_b;
  f.max_translation_b_m = m.max_translation_b;
  f.min_euler_deg = m.min_euler_deg;
  f.max_euler_deg = m.max_euler_deg;
  f.fixed_pose_at_range_mean = m.fixed_pose_at_range_mean;
  f.enable_sensor_noise = n.enable_sensor_noise;
  f.noise_model = n.model;
  f.noise_a = n.a;
  f.noise_b = n.b;
  f.noise_c = n.c;
  f.noise_mean_offset_m = n.mean_offset;
  f.std_dev_multiplier = n.std_dev_multiplier;
  f.pixel_dropout_prob = n.pixel_dropout_prob;
  return f;
}

void set_ray_sensor_fields(const RaySensorFields& f, SensorConfig& c) {
  const bool cam = c.kind == SensorKind::camera;
  sensors::RangeOutputParams& r = cam ? c.camera.range : c.lidar.range;
  sensors::OutputFlags& o = cam ? c.camera.output : c.lidar.output;
  sensors::MountParams& m = cam ? c.camera.mount : c.lidar.mount;
  sensors::NoiseParams& n = cam ? c.camera.noise : c.lidar.noise;
  c.every_env_steps = f.every_env_steps;
  if (cam) {
    c.camera.height = static_cast<std::uint32_t>(f.height);
    c.camera.width = static_cast<std::uint32_t>(f.width);
    c.camera.horizontal_fov_deg = f.horizontal_fov_deg;
    c.camera.calculate_depth = f.calculate_depth;
  } else {
    c.lidar.height = static_cast<std::uint32_t>(f.height);
    c.lidar.width = static_cast<std::uint32_t>(f.width);
    c.lidar.horizontal_fov_deg_min = f.horizontal_fov_deg_min;
    c.lidar.horizontal_fov_deg_max = f.horizontal_fov_deg_max;
    c.lidar.vertical_fov_deg_min = f.vertical_fov_deg_min;
    c.lidar.vertical_fov_deg_max = f.vertical_fov_deg_max;
  }
  r.min_range = f.min_range_m;
  r.max_range = f.max_range_m;
  r.normalize_range = f.normalize_range;
  r.far_out_of_range_value = f.far_out_of_range_value;
  r.near_out_of_range_value = f.near_out_of_range_value;
  o.return_pointcloud = f.return_pointcloud;
  o.pointcloud_in_world_frame = f.pointcloud_in_world_frame;
  o.segmentation_camera = f.segmentation_camera;
  m.nominal_position_b = f.nominal_position_b_m;
  m.nominal_euler_deg = f.nominal_euler_deg;
  m.randomize_placement = f.randomize_placement;
  m.min_translation_b = f.min_translation_b_m;
  m.max_translation_b = f.max_translation_b_m;
  m.min_euler_deg = f.min_euler_deg;
  m.max_euler_deg = f.max_euler_deg;
  m.fixed_pose_at_range_mean = f.fixed_pose_at_range_mean;
  n.enable_sensor_noise = f.enable_sensor_noise;
  n.model = f.noise_model;
  n.a = f.noise_a;
  n.b = f.noise_b;
  n.c = f.noise_c;
  n.mean_offset = f.noise_mean_offset_m;
  n.std_dev_multiplier = f.std_dev_multiplier;
  n.pixel_dropout_prob = f.pixel_dropout_prob;
}

ImuSensorFields imu_sensor_fields(const SensorConfig& c) {
  ImuSensorFields f;
  static_cast<sensors::ImuParams&>(f) = c.imu;
  f.every_env_steps = c.every_env_steps;
  return f;
}

void set_imu_sensor_fields(const ImuSensorFields& f, SensorConfig& c) {
  c.imu = static_cast<const sensors::ImuParams&>(f);
  c.every_env_steps = f.every_env_steps;
}

bool check_sensor_cross_fields(const SensorConfig& c, const std::string& where, std::string& error) {
  auto fail = [&](const char* key, const std::string& what) {
    error = where + "." + key + ": " + what;
    return false;
  };
  auto ordered = [](const Vec3& a, const Vec3& b) { return a[0] <= b[0] && a[1] <= b[1] && a[2] <= b[2]; };
  if (c.kind == SensorKind::imu) {
    if (!ordered(c.imu.misalignment_min_deg, c.imu.misalignment_max_deg))
      return fail("misalignment_min_deg", "expected <= misalignment_max_deg on every axis");
    return true;
  }
  const RaySensorFields f = ray_sensor_fields(c);
  if (!(f.min_range_m < f.max_range_m)) return fail("min_range_m", "expected < max_range_m, got " + std::to_string(f.min_range_m) + " >= " + std::to_string(f.max_range_m));
  if (c.kind == SensorKind::lidar) {
    if (!(f.horizontal_fov_deg_min <= f.horizontal_fov_deg_max)) return fail("horizontal_fov_deg_min", "expected <= horizontal_fov_deg_max");
    if (!(f.vertical_fov_deg_min <= f.vertical_fov_deg_max)) return fail("vertical_fov_deg_min", "expected <= vertical_fov_deg_max");
  }
  if (!ordered(f.min_translation_b_m, f.max_translation_b_m)) return fail("min_translation_b_m", "expected <= max_translation_b_m on every axis");
  if (!ordered(f.min_euler_deg, f.max_euler_deg)) return fail("min_euler_deg", "expected <= max_euler_deg on every axis");
  return true;
}

namespace {

/// The rows every ray sensor has (range, output flags, mount, noise).
template <class Rows>
void ray_common_rows(Rows& v) {
  using S = RaySensorFields;
  v.push_back(int_f<S>("every_env_steps", &S::every_env_steps, 1, kMaxSensorEveryEnvSteps, "kMaxSensorEveryEnvSteps",
                       "render every this many env-steps (older key: every)"));
  v.back().alias = "every";
  v.push_back(int_f<S>("height", &S::height, 1, kMaxSensorSide, "kMaxSensorSide", "rows (scan lines) of the image"));
  v.push_back(int_f<S>("width", &S::width, 1, kMaxSensorSide, "kMaxSensorSide", "columns of the image"));
}
template <class Rows>
void ray_tail_rows(Rows& v) {
  using S = RaySensorFields;
  v.push_back(real_f<S>("min_range_m", &S::min_range_m, "m", 0, 1e4, "nearer returns read near_out_of_range_value (< max_range_m)"));
  v.push_back(real_f<S>("max_range_m", &S::max_range_m, "m", 1e-3, 1e4, "farther returns (and no hit) read far_out_of_range_value"));
  v.push_back(bool_f<S>("normalize_range", &S::normalize_range, "divide every value by max_range_m"));
  v.push_back(real_f<S>("far_out_of_range_value", &S::far_out_of_range_value, "m", -1e6, 1e6,
                        "value beyond max_range (kept from the preset when max_range_m changes, as Aerial Gym's classes do)"));
  v.push_back(real_f<S>("near_out_of_range_value", &S::near_out_of_range_value, "m", -1e6, 1e6, "value below min_range and of dropped pixels"));
  v.push_back(bool_f<S>("return_pointcloud", &S::return_pointcloud, "a point cloud instead of a range image"));
  v.push_back(bool_f<S>("pointcloud_in_world_frame", &S::pointcloud_in_world_frame, "point cloud in the world frame (raw)"));
  v.push_back(bool_f<S>("segmentation_camera", &S::segmentation_camera, "also render segment ids"));
  v.push_back(vec3b_f<S>("nominal_position_b_m", &S::nominal_position_b_m, "m", -100, 100, "mount position on the body (fixed_pose_at_range_mean false)"));
  v.push_back(vec3b_f<S>("nominal_euler_deg", &S::nominal_euler_deg, "deg", -360, 360, "mount roll, pitch, yaw (fixed_pose_at_range_mean false)"));
  v.push_back(bool_f<S>("randomize_placement", &S::randomize_placement, "draw the mount per reset in the ranges below"));
  v.push_back(vec3b_f<S>("min_translation_b_m", &S::min_translation_b_m, "m", -100, 100, "mount translation range, min"));
  v.push_back(vec3b_f<S>("max_translation_b_m", &S::max_translation_b_m, "m", -100, 100, "mount translation range, max (>= min)"));
  v.push_back(vec3b_f<S>("min_euler_deg", &S::min_euler_deg, "deg", -360, 360, "mount Euler range, min"));
  v.push_back(vec3b_f<S>("max_euler_deg", &S::max_euler_deg, "deg", -360, 360, "mount Euler range, max (>= min)"));
  v.push_back(bool_f<S>("fixed_pose_at_range_mean", &S::fixed_pose_at_range_mean,
                        "not randomised: zero translation, Euler (min + max) / 2 (Aerial Gym's warp sensors); false: the nominal pose"));
  v.push_back(bool_f<S>("enable_sensor_noise", &S::enable_sensor_noise, "apply noise_model"));
  v.push_back(choice_f<S>(
      "noise_model", "none, range_dependent, multiplier",
      [](S& s, const std::string& x) { return set_enum(kNoiseModels, x, s.noise_model); },
      [](const S& s) { return enum_name(kNoiseModels, s.noise_model); },
      "range_dependent: N(r - noise_mean_offset_m, std noise_a r^2 + noise_b r + noise_c); multiplier: N(r, std std_dev_multiplier r)"));
  v.push_back(real_f<S>("noise_a", &S::noise_a, "1/m", 0, 1e6, "range_dependent standard deviation a r^2 + b r + c, r^2 coefficient"));
  v.push_back(real_f<S>("noise_b", &S::noise_b, "", -1e6, 1e6, "range_dependent standard deviation, r coefficient"));
  v.push_back(real_f<S>("noise_c", &S::noise_c, "m", 0, 1e6, "range_dependent standard deviation, constant"));
  v.push_back(real_f<S>("noise_mean_offset_m", &S::noise_mean_offset_m, "m", -1e3, 1e3, "range_dependent mean offset (subtracted)"));
  v.push_back(real_f<S>("std_dev_multiplier", &S::std_dev_multiplier, "", 0, 100, "multiplier: standard deviation per metre of range"));
  v.push_back(real_f<S>("pixel_dropout_prob", &S::pixel_dropout_prob, "", 0, 1, "probability a pixel drops out (reads near_out_of_range_value)"));
}

}  // namespace

const Schema<RaySensorFields>& lidar_sensor_schema() {
  using S = RaySensorFields;
  static const std::vector<Field<S>> f = [] {
    std::vector<Field<S>> v;
    ray_common_rows(v);
    v.push_back(real_f<S>("horizontal_fov_deg_min", &S::horizontal_fov_deg_min, "deg", -180, 180, "azimuth of the last column"));
    v.push_back(real_f<S>("horizontal_fov_deg_max", &S::horizontal_fov_deg_max, "deg", -180, 180, "azimuth of column 0 (>= min)"));
    v.push_back(real_f<S>("vertical_fov_deg_min", &S::vertical_fov_deg_min, "deg", -90, 90, "elevation of the last row"));
    v.push_back(real_f<S>("vertical_fov_deg_max", &S::vertical_fov_deg_max, "deg", -90, 90, "elevation of row 0 (>= min)"));
    ray_tail_rows(v);
    return v;
  }();
  static const Schema<S> s{"sensors[] (lidar, ToF)",
                           "a lidar or multizone ToF entry of `sensors:` (`{name: vl53l5cx, every: 2, max_range_m: 3}`): "
                           "sensors::LidarParams; unset keys keep the preset's values (`kestrel list`), the defaults shown are the struct's",
                           f.data(), f.size(), nullptr, 0};
  return s;
}

const Schema<RaySensorFields>& camera_sensor_schema() {
  using S = RaySensorFields;
  static const std::vector<Field<S>> f = [] {
    std::vector<Field<S>> v;
    ray_common_rows(v);
    v.push_back(real_f<S>("horizontal_fov_deg", &S::horizontal_fov_deg, "deg", 1e-3, 179.9, "horizontal field of view"));
    v.push_back(bool_f<S>("calculate_depth", &S::calculate_depth, "depth along the optical axis (false: range along the ray)"));
    ray_tail_rows(v);
    return v;
  }();
  static const Schema<S> s{"sensors[] (camera)",
                           "a depth camera entry of `sensors:`: sensors::CameraParams; unset keys keep the preset's values, the "
                           "defaults shown are the struct's",
                           f.data(), f.size(), nullptr, 0};
  return s;
}

const Schema<ImuSensorFields>& imu_sensor_schema() {
  using S = ImuSensorFields;
  static const Field<S> f[] = {
      [] {
        Field<S> r = int_f<S>("every_env_steps", &S::every_env_steps, 1, kMaxSensorEveryEnvSteps, "kMaxSensorEveryEnvSteps",
                              "unused by the IMU (it updates every physics step); older key: every");
        r.alias = "every";
        return r;
      }(),
      vec3b_f<S>("accel_noise_density", &S::accel_noise_density, "m/s^2/sqrt(Hz)", 0, 1e3, "accelerometer white noise density"),
      vec3b_f<S>("gyro_noise_density", &S::gyro_noise_density, "rad/s/sqrt(Hz)", 0, 1e3, "gyroscope white noise density"),
      vec3b_f<S>("accel_bias_random_walk", &S::accel_bias_random_walk, "m/s^3/sqrt(Hz)", 0, 1e3, "accelerometer bias random walk"),
      vec3b_f<S>("gyro_bias_random_walk", &S::gyro_bias_random_walk, "rad/s^2/sqrt(Hz)", 0, 1e3, "gyroscope bias random walk"),
      vec3b_f<S>("accel_initial_bias_max", &S::accel_initial_bias_max, "m/s^2", 0, 1e3, "initial bias drawn in [-max, max]"),
      vec3b_f<S>("gyro_initial_bias_max", &S::gyro_initial_bias_max, "rad/s", 0, 1e3, "initial bias drawn in [-max, max]"),
      vec3b_f<S>("accel_saturation", &S::accel_saturation, "m/s^2", 1e-6, 1e9, "measurement clamp +-"),
      vec3b_f<S>("gyro_saturation", &S::gyro_saturation, "rad/s", 1e-6, 1e9, "measurement clamp +-"),
      vec3b_f<S>("misalignment_min_deg", &S::misalignment_min_deg, "deg", -180, 180, "mount misalignment drawn per reset in [min, max]"),
      vec3b_f<S>("misalignment_max_deg", &S::misalignment_max_deg, "deg", -180, 180, "(>= min)"),
      bool_f<S>("enable_noise", &S::enable_noise, "white noise on"),
      bool_f<S>("enable_bias", &S::enable_bias, "bias (initial + random walk) on"),
      bool_f<S>("gravity_compensation", &S::gravity_compensation, "subtract gravity from the accelerometer"),
  };
  static const Schema<S> s{"sensors[] (IMU)", "an IMU entry of `sensors:`: sensors::ImuParams (gravity is the sim's); unset keys keep the preset's",
                           f, std::size(f), nullptr, 0};
  return s;
}

const Schema<CurriculumConfig>& curriculum_schema() {
  using S = CurriculumConfig;
  static const Field<S> f[] = {
      int_f<S>("min_level", &S::min_level, 0, kNoMax, nullptr, "lowest level (env.curriculum_level 0)"),
      int_f<S>("max_level", &S::max_level, 0, kNoMax, nullptr, "highest level (env.curriculum_level 1); >= min_level"),
      int_f<S>("start_level", &S::start_level, 0, kNoMax, nullptr, "level of the first episodes (clamped into [min_level, max_level])"),
      int_f<S>("check_after_episodes", &S::check_after_episodes, 1, kNoMax, nullptr, "ended episodes per success-rate check"),
      int_f<S>("increase_step", &S::increase_step, 0, kNoMax, nullptr, "levels up when the rate exceeds success_rate_for_increase"),
      int_f<S>("decrease_step", &S::decrease_step, 0, kNoMax, nullptr, "levels down when the rate is below success_rate_for_decrease"),
      real_f<S>("success_rate_for_increase", &S::success_rate_for_increase, "", 0, 1, "success rate over a check that moves up"),
      real_f<S>("success_rate_for_decrease", &S::success_rate_for_decrease, "", 0, 1, "success rate over a check that moves down"),
  };
  static const Schema<S> s{"task.curriculum",
                           "min_level, max_level, start_level, check_after_episodes, increase_step, decrease_step, "
                           "success_rate_for_increase, success_rate_for_decrease: Aerial Gym's navigation curriculum "
                           "(increase_step = decrease_step = 0 holds the level at start_level)",
                           f, std::size(f), nullptr, 0};
  return s;
}

namespace {

std::string num(double v) {
  // Whole numbers in full (1048576, not 1.04858e+06): limits are read and compared by people.
  if (v == static_cast<double>(static_cast<long long>(v)) && v > -1e15 && v < 1e15) return std::to_string(static_cast<long long>(v));
  std::ostringstream s;
  s << v;
  return s.str();
}

template <class S>
void document(std::ostringstream& out, const Schema<S>& sc, const S& def = S{}) {
  out << "## `" << sc.section << "`\n\n" << sc.doc << ".\n\n| key | unit | type | allowed | default | meaning |\n|---|---|---|---|---|---|\n";
  for (std::size_t k = 0; k < sc.count; ++k) {
    const Field<S>& f = sc.fields[k];
    std::string type, allowed, dflt;
    switch (f.type) {
      case FieldType::real_number:
        type = "number";
        allowed = "[" + num(f.lo) + ", " + num(f.hi) + "]";
        dflt = num(def.*f.r);
        break;
      case FieldType::integer:
        type = "integer";
        allowed = f.hi < f.lo ? ">= " + num(f.lo) : "[" + num(f.lo) + ", " + num(f.hi) + "]" + (f.limit ? std::string(" (") + f.limit + ")" : "");
        dflt = std::to_string(def.*f.i);
        break;
      case FieldType::boolean:
        type = "bool";
        allowed = "true, false";
        dflt = (def.*f.b) ? "true" : "false";
        break;
      case FieldType::vec3: {
        type = "[x, y, z]";
        allowed = f.lo <= -1e9 && f.hi >= 1e9 ? std::string("numbers") : "each in [" + num(f.lo) + ", " + num(f.hi) + "]";
        const Vec3& v = def.*f.v;
        dflt = "[" + num(v[0]) + ", " + num(v[1]) + ", " + num(v[2]) + "]";
        break;
      }
      case FieldType::range:
        type = "[min, max]";
        allowed = "[" + num(f.lo) + ", " + num(f.hi) + "], min <= max";
        dflt = "[" + num(def.*f.r) + ", " + num(def.*f.r_max) + "]";
        break;
      case FieldType::choice:
        type = "name";
        allowed = f.choices;
        dflt = f.get_choice(def);
        break;
    }
    std::string key = std::string("`") + f.key + "`";
    if (f.alias) key += " (or `" + std::string(f.alias) + "`)";
    out << "| " << key << " | " << (f.unit[0] ? f.unit : "-") << " | " << type << " | " << allowed << " | " << dflt << " | " << f.doc << " |\n";
  }
  for (std::size_t k = 0; k < sc.num_structural; ++k)
    out << "| `" << sc.structural[k].key << "` | | | | | " << sc.structural[k].doc << " |\n";
  out << "\n";
}

}  // namespace

namespace {

template <class S>
bool check_fields(const Schema<S>& sc, const S& s, const std::string& where, std::string& error) {
  auto fail = [&](const Field<S>& f, const std::string& what) {
    error = where + "." + f.key + ": " + what;
    return false;
  };
  for (std::size_t k = 0; k < sc.count; ++k) {
    const Field<S>& f = sc.fields[k];
    switch (f.type) {
      case FieldType::real_number: {
        const double v = static_cast<double>(s.*f.r);
        if (!(v >= f.lo && v <= f.hi)) return fail(f, "expected a number in [" + num(f.lo) + ", " + num(f.hi) + "], got " + num(v));
        break;
      }
      case FieldType::integer: {
        const int v = s.*f.i;
        if (v < f.lo || (f.hi >= f.lo && v > f.hi))
          return fail(f, f.hi < f.lo ? "expected an integer >= " + num(f.lo) + ", got " + std::to_string(v)
                                     : "expected an integer in [" + num(f.lo) + ", " + num(f.hi) + "]" +
                                           (f.limit ? std::string(" (") + f.limit + ")" : "") + ", got " + std::to_string(v));
        break;
      }
      case FieldType::vec3: {
        const Vec3& v = s.*f.v;
        for (int i = 0; i < 3; ++i)
          if (!(static_cast<double>(v[i]) >= f.lo && static_cast<double>(v[i]) <= f.hi))
            return fail(f, "expected finite numbers in [" + num(f.lo) + ", " + num(f.hi) + "], got " + num(static_cast<double>(v[i])) +
                               " at [" + std::to_string(i) + "]");
        break;
      }
      case FieldType::range: {
        const double a = static_cast<double>(s.*f.r), b = static_cast<double>(s.*f.r_max);
        if (!(a >= f.lo && b <= f.hi && a <= b))
          return fail(f, "expected [min, max] with " + num(f.lo) + " <= min <= max <= " + num(f.hi) + ", got [" + num(a) + ", " + num(b) + "]");
        break;
      }
      case FieldType::boolean:
      case FieldType::choice: break;  // any value of the type is allowed
    }
  }
  return true;
}

}  // namespace

bool check_config_fields(const WorldConfig& c, std::string& error) {
  if (!check_fields(sim_schema(), c.sim, "sim", error) || !check_fields(simulator_schema(), c.simulator, "simulator", error) ||
      !check_fields(env_schema(), c.env, "env", error) || !check_fields(terrain_schema(), c.env.terrain, "env.terrain", error) ||
      !check_fields(robot_schema(), c.robot, "robot", error) || !check_fields(shape_schema(), c.robot.shape, "robot.collision_shape", error) ||
      !check_fields(task_schema(), c.task, "task", error) || !check_fields(curriculum_schema(), c.task.curriculum, "task.curriculum", error) ||
      !check_fields(navigation_schema(), c.task.navigation, "task.navigation", error) ||
      !check_fields(navigation_reward_schema(), c.task.navigation.reward, "task.navigation.reward", error) ||
      !check_fields(locomotion_schema(), c.task.locomotion, "task.locomotion", error) ||
      !check_fields(locomotion_scales_schema(), c.task.locomotion.scales, "task.locomotion.scales", error) ||
      !check_fields(pick_place_schema(), c.task.pick_place, "task.pick_place", error) ||
      !check_fields(position_setpoint_reward_schema(), c.task.reward, "task.reward", error) ||
      !check_fields(controller_schema(), c.controller, "controller", error))
    return false;
  for (const SensorConfig& sc : c.robot.sensors) {
    const std::string where = "sensors." + sc.name;
    const bool ok = sc.kind == SensorKind::imu ? check_fields(imu_sensor_schema(), imu_sensor_fields(sc), where, error)
                    : sc.kind == SensorKind::camera ? check_fields(camera_sensor_schema(), ray_sensor_fields(sc), where, error)
                                                    : check_fields(lidar_sensor_schema(), ray_sensor_fields(sc), where, error);
    if (!ok || !check_sensor_cross_fields(sc, where, error)) return false;
  }
  for (const AssetClass& a : c.env.assets)
    if (!check_fields(asset_schema(), a, "env.assets." + a.name, error)) return false;
  return true;
}

std::string scenario_reference_markdown() {
  std::ostringstream out;
  out << "# Scenario reference\n\n"
         "Generated from the schema tables (`sim/src/io/schema.cpp`) by `kestrel schema`; "
         "`tests/sim/io/scenario_test.cpp` keeps this file equal to what they generate. Every section is a registry name "
         "(`kestrel list`) or a map with `name` and the keys below; a key overrides the preset's value. Defaults are the "
         "struct's own, before a preset. Top level: `sim`, `env`, `robot`, `controller`, `task`, `sensors` (list of sensor "
         "names or maps `{name, every, ...}` with the keys of the sensor's kind below), `simulator`, `seed`, `threads` [1, " +
             std::to_string(kMaxThreads) + "], `max_memory_gib`.\n\n";
  document(out, sim_schema());
  document(out, simulator_schema());
  document(out, env_schema());
  document(out, asset_schema());
  document(out, terrain_schema());
  document(out, robot_schema());
  document(out, shape_schema());
  document(out, controller_schema());
  document(out, task_schema());
  document(out, curriculum_schema());
  document(out, navigation_schema());
  document(out, navigation_reward_schema());
  document(out, locomotion_schema());
  document(out, locomotion_scales_schema());
  document(out, pick_place_schema());
  document(out, position_setpoint_reward_schema());
  SensorConfig lidar, camera;
  lidar.kind = SensorKind::lidar;
  camera.kind = SensorKind::camera;
  document(out, lidar_sensor_schema(), ray_sensor_fields(lidar));
  document(out, camera_sensor_schema(), ray_sensor_fields(camera));
  document(out, imu_sensor_schema());
  return out.str();
}

}  // namespace kestrel::sim
