#include "kestrel/sim/scenario.hpp"

#include <yaml-cpp/yaml.h>

#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "kestrel/sim/limits.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/task.hpp"
#include "kestrel/sim/terrain.hpp"
#include "kestrel/sim/urdf.hpp"

namespace kestrel::sim {

namespace {

struct ScenarioError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

[[noreturn]] void bad(const std::string& field, const std::string& msg) { throw ScenarioError(field + ": " + msg); }

std::string scalar_text(const YAML::Node& n) {
  if (n.IsScalar()) return n.Scalar();
  return n.IsSequence() ? "a list" : n.IsMap() ? "a map" : "nothing";
}

int get_int(const YAML::Node& n, const std::string& f, int min_value) {
  int v = 0;
  if (!n.IsScalar() || !YAML::convert<int>::decode(n, v) || v < min_value)
    bad(f, (min_value == 1 ? std::string("expected a positive integer") : "expected an integer >= " + std::to_string(min_value)) +
               ", got \"" + scalar_text(n) + "\"");
  return v;
}
/// A count with an upper bound (sim/limits.hpp): `max_name` names the constant in the message.
int get_int(const YAML::Node& n, const std::string& f, int min_value, int max_value, const char* max_name) {
  int v = 0;
  if (!n.IsScalar() || !YAML::convert<int>::decode(n, v) || v < min_value || v > max_value)
    bad(f, "expected an integer in [" + std::to_string(min_value) + ", " + std::to_string(max_value) + "] (" + max_name +
               "), got \"" + scalar_text(n) + "\"");
  return v;
}
real get_real(const YAML::Node& n, const std::string& f, double lo, double hi) {
  double v = 0;
  if (!n.IsScalar() || !YAML::convert<double>::decode(n, v) || !(v >= lo && v <= hi)) {
    std::ostringstream s;
    s << "expected a number in [" << lo << ", " << hi << "], got \"" << scalar_text(n) << "\"";
    bad(f, s.str());
  }
  return static_cast<real>(v);
}
bool get_bool(const YAML::Node& n, const std::string& f) {
  bool v = false;
  if (!n.IsScalar() || !YAML::convert<bool>::decode(n, v)) bad(f, "expected true or false, got \"" + scalar_text(n) + "\"");
  return v;
}
Vec3 get_vec3(const YAML::Node& n, const std::string& f) {
  if (!n.IsSequence() || n.size() != 3) bad(f, "expected a list of 3 numbers, got " + scalar_text(n));
  Vec3 v;
  for (int i = 0; i < 3; ++i) v[i] = get_real(n[i], f + "[" + std::to_string(i) + "]", -1e9, 1e9);
  return v;
}

/// name + override map of a section; checks keys against the allowed set.
std::string section_name(const YAML::Node& n, const std::string& section) {
  if (n.IsScalar()) return n.Scalar();
  if (!n.IsMap()) bad(section, "expected a registry name or a map with `name`");
  if (!n["name"]) bad(section + ".name", "missing");
  return n["name"].Scalar();
}
void check_keys(const YAML::Node& n, const std::string& section, const std::set<std::string>& allowed) {
  if (!n.IsMap()) return;
  for (const auto& kv : n) {
    const std::string k = kv.first.Scalar();
    if (k == "name" || allowed.count(k) != 0) continue;
    std::string list = "name";
    for (const auto& a : allowed) list += ", " + a;
    bad(section + "." + k, "unknown field; allowed: " + list);
  }
}
template <class T>
T lookup(const Registry<T>& reg, const std::string& name, const std::string& section) {
  T out;
  if (!reg.make(name, out)) bad(section, "unknown " + section + " \"" + name + "\"; known: " + reg.joined());
  return out;
}

// `simulator: planar` or `simulator: {name: planar, vehicle: multirotor, lidar_beams: 64}`
// (physics backend of sim/simulator.hpp; KESTREL_SIMULATOR overrides the name at run time).
void parse_simulator(const YAML::Node& n, SimulatorConfig& s) {
  s = lookup(registries().simulators, section_name(n, "simulator"), "simulator");
  check_keys(n, "simulator", {"vehicle", "wheelbase_m", "max_speed_m_s", "max_steering_rad", "altitude_m", "lidar_beams",
                              "lidar_fov_rad", "lidar_max_range_m", "max_push_vel_xy_m_s", "added_mass_kg", "com_bias_max_m",
                              "motor_scale", "gain_scale"});
  if (!n.IsMap()) return;
  if (n["vehicle"]) {
    const std::string v = n["vehicle"].Scalar();
    if (v == "automatic") s.vehicle = PlanarVehicle::automatic;
    else if (v == "ground_vehicle") s.vehicle = PlanarVehicle::ground_vehicle;
    else if (v == "multirotor") s.vehicle = PlanarVehicle::multirotor;
    else bad("simulator.vehicle", "expected one of automatic, ground_vehicle, multirotor, got \"" + v + "\"");
  }
  if (n["wheelbase_m"]) s.wheelbase_m = get_real(n["wheelbase_m"], "simulator.wheelbase_m", 1e-3, 100);
  if (n["max_speed_m_s"]) s.max_speed_m_s = get_real(n["max_speed_m_s"], "simulator.max_speed_m_s", 1e-3, 1000);
  if (n["max_steering_rad"]) s.max_steering_rad = get_real(n["max_steering_rad"], "simulator.max_steering_rad", 1e-3, 1.4);
  if (n["altitude_m"]) s.altitude_m = get_real(n["altitude_m"], "simulator.altitude_m", -1e4, 1e4);
  if (n["lidar_beams"]) s.lidar_beams = get_int(n["lidar_beams"], "simulator.lidar_beams", 0);
  if (n["lidar_fov_rad"]) s.lidar_fov_rad = get_real(n["lidar_fov_rad"], "simulator.lidar_fov_rad", 1e-3, 6.2831853);
  if (n["lidar_max_range_m"]) s.lidar_max_range_m = get_real(n["lidar_max_range_m"], "simulator.lidar_max_range_m", 1e-3, 1e4);
  if (n["max_push_vel_xy_m_s"]) s.max_push_vel_xy_m_s = get_real(n["max_push_vel_xy_m_s"], "simulator.max_push_vel_xy_m_s", 0, 100);
  if (n["com_bias_max_m"]) s.com_bias_max_m = get_real(n["com_bias_max_m"], "simulator.com_bias_max_m", 0, 10);
  // Ranges as [min, max] lists.
  auto range = [&](const char* key, real lo, real hi, real& mn, real& mx) {
    const YAML::Node r = n[key];
    if (!r) return;
    const std::string f = std::string("simulator.") + key;
    if (!r.IsSequence() || r.size() != 2) bad(f, "expected [min, max], got " + scalar_text(r));
    mn = get_real(r[0], f + "[0]", lo, hi);
    mx = get_real(r[1], f + "[1]", lo, hi);
    if (mn > mx) bad(f, "expected min <= max");
  };
  range("added_mass_kg", -1e6, 1e6, s.added_mass_min_kg, s.added_mass_max_kg);
  range("motor_scale", 1e-3, 1e3, s.motor_scale_min, s.motor_scale_max);
  range("gain_scale", 1e-3, 1e3, s.gain_scale_min, s.gain_scale_max);
}

void parse_sim(const YAML::Node& n, SimParams& s) {
  s = lookup(registries().sims, section_name(n, "sim"), "sim");
  check_keys(n, "sim", {"dt_s", "substeps", "gravity_w", "integrator", "contact_stiffness_N_m", "contact_damping_N_s_m",
                        "friction_coefficient"});
  if (!n.IsMap()) return;
  if (n["dt_s"]) s.dt_s = get_real(n["dt_s"], "sim.dt_s", 1e-6, 1);
  if (n["substeps"]) s.substeps = get_int(n["substeps"], "sim.substeps", 1, kMaxSubsteps, "kMaxSubsteps");
  if (n["gravity_w"]) s.gravity_w = get_vec3(n["gravity_w"], "sim.gravity_w");
  if (n["integrator"]) {
    const std::string v = n["integrator"].Scalar();
    if (v == "rk4") s.integrator = Integrator::rk4;
    else if (v == "semi_implicit_euler") s.integrator = Integrator::semi_implicit_euler;
    else bad("sim.integrator", "expected one of rk4, semi_implicit_euler, got \"" + v + "\"");
  }
  if (n["contact_stiffness_N_m"]) s.contact_stiffness_N_m = get_real(n["contact_stiffness_N_m"], "sim.contact_stiffness_N_m", 0, 1e9);
  if (n["contact_damping_N_s_m"]) s.contact_damping_N_s_m = get_real(n["contact_damping_N_s_m"], "sim.contact_damping_N_s_m", 0, 1e9);
  if (n["friction_coefficient"]) s.friction_coefficient = get_real(n["friction_coefficient"], "sim.friction_coefficient", 0, 100);
}

std::string resolve_path(const std::string& dir, const std::string& path) {
  return (!path.empty() && path[0] == '/') ? path : dir + path;
}

std::vector<real> get_real_list(const YAML::Node& n, const std::string& f) {
  if (!n.IsSequence() || n.size() == 0) bad(f, "expected a non-empty list of numbers, got " + scalar_text(n));
  std::vector<real> v;
  for (std::size_t i = 0; i < n.size(); ++i) v.push_back(get_real(n[i], f + "[" + std::to_string(i) + "]", -1e6, 1e6));
  return v;
}

/// env.terrain (TerrainConfig; files are read when the world is built, see sim/terrain.hpp).
void parse_terrain(const YAML::Node& n, TerrainConfig& t, const std::string& dir, const std::string& source) {
  const std::string f = "env.terrain";
  if (!n.IsMap() || !n["type"]) bad(f, "expected a map with `type` (plane, heightfield or trimesh)");
  check_keys(n, f, {"type", "horizontal_scale_m", "vertical_scale_m", "origin_m", "heights_m", "image_file", "procedural",
                    "length_x_m", "width_y_m", "slope", "platform_size_m", "step_width_m", "step_height_m", "min_height_m",
                    "max_height_m", "height_step_m", "downsampled_scale_m", "num_waves", "amplitude_m", "mesh_file",
                    "measure_heights", "measured_points_x", "measured_points_y"});
  t = TerrainConfig();
  t.source_file = source;
  const std::string type = n["type"].Scalar();
  if (type == "plane") t.type = TerrainType::plane;
  else if (type == "heightfield") t.type = TerrainType::heightfield;
  else if (type == "trimesh") t.type = TerrainType::trimesh;
  else bad(f + ".type", "expected one of plane, heightfield, trimesh, got \"" + type + "\"");
  if (n["horizontal_scale_m"]) t.horizontal_scale_m = get_real(n["horizontal_scale_m"], f + ".horizontal_scale_m", 1e-4, 1e3);
  if (n["vertical_scale_m"]) t.vertical_scale_m = get_real(n["vertical_scale_m"], f + ".vertical_scale_m", 1e-9, 1e3);
  if (n["origin_m"]) t.origin_m = get_vec3(n["origin_m"], f + ".origin_m");
  if (const YAML::Node h = n["heights_m"]) {
    if (!h.IsSequence() || h.size() < 2) bad(f + ".heights_m", "expected a list of >= 2 rows (row j = y index j) of >= 2 heights");
    for (std::size_t j = 0; j < h.size(); ++j) {
      const std::vector<real> row = get_real_list(h[j], f + ".heights_m[" + std::to_string(j) + "]");
      if (j == 0) t.nx = static_cast<int>(row.size());
      if (static_cast<int>(row.size()) != t.nx || t.nx < 2)
        bad(f + ".heights_m[" + std::to_string(j) + "]", "expected " + std::to_string(std::max(t.nx, 2)) + " heights, as every row");
      t.heights_m.insert(t.heights_m.end(), row.begin(), row.end());
    }
    t.ny = static_cast<int>(h.size());
  }
  if (n["image_file"]) t.image_file = resolve_path(dir, n["image_file"].Scalar());
  if (n["mesh_file"]) t.mesh_file = resolve_path(dir, n["mesh_file"].Scalar());
  if (n["procedural"]) {
    t.procedural = n["procedural"].Scalar();
    const std::string names = terrain_procedural_names();
    bool known = false;
    std::istringstream ns(names);
    for (std::string w; std::getline(ns, w, ',');) known = known || (w.substr(w.find_first_not_of(' ')) == t.procedural);
    if (!known) bad(f + ".procedural", "unknown generator \"" + t.procedural + "\"; allowed: " + names);
  }
  if (n["length_x_m"]) t.length_x_m = get_real(n["length_x_m"], f + ".length_x_m", 1e-3, 1e4);
  if (n["width_y_m"]) t.width_y_m = get_real(n["width_y_m"], f + ".width_y_m", 1e-3, 1e4);
  if (n["slope"]) t.slope = get_real(n["slope"], f + ".slope", -100, 100);
  if (n["platform_size_m"]) t.platform_size_m = get_real(n["platform_size_m"], f + ".platform_size_m", 0, 1e4);
  if (n["step_width_m"]) t.step_width_m = get_real(n["step_width_m"], f + ".step_width_m", 1e-4, 1e4);
  if (n["step_height_m"]) t.step_height_m = get_real(n["step_height_m"], f + ".step_height_m", -100, 100);
  if (n["min_height_m"]) t.min_height_m = get_real(n["min_height_m"], f + ".min_height_m", -1e3, 1e3);
  if (n["max_height_m"]) t.max_height_m = get_real(n["max_height_m"], f + ".max_height_m", -1e3, 1e3);
  if (n["height_step_m"]) t.height_step_m = get_real(n["height_step_m"], f + ".height_step_m", 1e-6, 1e3);
  if (n["downsampled_scale_m"]) t.downsampled_scale_m = get_real(n["downsampled_scale_m"], f + ".downsampled_scale_m", 1e-4, 1e4);
  if (n["num_waves"]) t.num_waves = get_int(n["num_waves"], f + ".num_waves", 1, kMaxNumWaves, "kMaxNumWaves");
  if (n["amplitude_m"]) t.amplitude_m = get_real(n["amplitude_m"], f + ".amplitude_m", -100, 100);
  if (n["measure_heights"]) t.measure_heights = get_bool(n["measure_heights"], f + ".measure_heights");
  if (n["measured_points_x"]) t.measured_points_x_m = get_real_list(n["measured_points_x"], f + ".measured_points_x");
  if (n["measured_points_y"]) t.measured_points_y_m = get_real_list(n["measured_points_y"], f + ".measured_points_y");
  if (t.type == TerrainType::heightfield) {
    const int sources = (t.heights_m.empty() ? 0 : 1) + (t.image_file.empty() ? 0 : 1) + (t.procedural.empty() ? 0 : 1);
    if (sources != 1) bad(f, "type heightfield needs exactly one of heights_m, image_file, procedural");
  }
  if (t.type == TerrainType::trimesh && t.mesh_file.empty()) bad(f + ".mesh_file", "missing (type trimesh needs an .obj or .stl file)");
}

/// env.assets: extra asset classes (e.g. meshes from OBJ/STL files), appended to the env's classes.
void parse_assets(const YAML::Node& n, EnvConfig& e, const std::string& dir) {
  if (!n.IsSequence()) bad("env.assets", "expected a list of asset class maps");
  const std::pair<const char*, AssetKind> kinds[] = {{"tree", AssetKind::tree},       {"panel", AssetKind::panel},
                                                     {"cube", AssetKind::cube},       {"rod", AssetKind::rod},
                                                     {"small_wall", AssetKind::small_wall}, {"wall", AssetKind::wall},
                                                     {"thin", AssetKind::thin},       {"sphere", AssetKind::sphere},
                                                     {"mesh", AssetKind::mesh}};
  for (std::size_t i = 0; i < n.size(); ++i) {
    const YAML::Node a = n[i];
    std::string f = "env.assets[" + std::to_string(i) + "]";
    if (!a.IsMap() || !a["name"] || !a["kind"]) bad(f, "expected a map with `name` and `kind`");
    AssetClass c;
    c.name = a["name"].Scalar();
    f = "env.assets." + c.name;
    for (const AssetClass& o : e.assets)
      if (o.name == c.name) bad(f, "duplicate asset class name");
    check_keys(a, f, {"kind", "num_assets", "min_num_assets", "min_position_ratio", "max_position_ratio", "min_euler_rad",
                      "max_euler_rad", "min_size_m", "max_size_m", "keep_in_env", "semantic_id", "max_speed_m_s",
                      "max_angular_speed_rad_s", "mesh_file"});
    const std::string k = a["kind"].Scalar();
    bool found = false;
    for (const auto& p : kinds)
      if (k == p.first) {
        c.kind = p.second;
        found = true;
      }
    if (!found) bad(f + ".kind", "expected one of tree, panel, cube, rod, small_wall, wall, thin, sphere, mesh, got \"" + k + "\"");
    if (a["num_assets"]) c.num_assets = get_int(a["num_assets"], f + ".num_assets", 0, kMaxAssetsPerClass, "kMaxAssetsPerClass");
    c.min_num_assets = a["min_num_assets"] ? get_int(a["min_num_assets"], f + ".min_num_assets", 0) : c.num_assets;
    if (c.min_num_assets > c.num_assets) bad(f + ".min_num_assets", "expected <= num_assets");
    if (a["min_position_ratio"]) c.min_position_ratio = get_vec3(a["min_position_ratio"], f + ".min_position_ratio");
    if (a["max_position_ratio"]) c.max_position_ratio = get_vec3(a["max_position_ratio"], f + ".max_position_ratio");
    if (a["min_euler_rad"]) c.min_euler_rad = get_vec3(a["min_euler_rad"], f + ".min_euler_rad");
    if (a["max_euler_rad"]) c.max_euler_rad = get_vec3(a["max_euler_rad"], f + ".max_euler_rad");
    if (a["min_size_m"]) c.min_size_m = get_vec3(a["min_size_m"], f + ".min_size_m");
    if (a["max_size_m"]) c.max_size_m = get_vec3(a["max_size_m"], f + ".max_size_m");
    if (a["keep_in_env"]) c.keep_in_env = get_bool(a["keep_in_env"], f + ".keep_in_env");
    if (a["semantic_id"]) c.semantic_id = get_int(a["semantic_id"], f + ".semantic_id", 0, kMaxAssetSemanticId, "kMaxAssetSemanticId");
    if (a["max_speed_m_s"]) c.max_speed_m_s = get_real(a["max_speed_m_s"], f + ".max_speed_m_s", 0, 1000);
    if (a["max_angular_speed_rad_s"]) c.max_angular_speed_rad_s = get_real(a["max_angular_speed_rad_s"], f + ".max_angular_speed_rad_s", 0, 1000);
    if (a["mesh_file"]) c.mesh_file = resolve_path(dir, a["mesh_file"].Scalar());
    if (c.kind == AssetKind::mesh && c.mesh_file.empty()) bad(f + ".mesh_file", "missing (kind mesh needs an .obj or .stl file)");
    if (c.kind != AssetKind::mesh && !c.mesh_file.empty()) bad(f + ".mesh_file", "only for kind mesh");
    if (e.assets.size() >= 255) bad(f, "too many asset classes (at most 255)");
    e.assets.push_back(c);
  }
}

void parse_env(const YAML::Node& n, EnvConfig& e, const std::string& dir, const std::string& source) {
  e = lookup(registries().envs, section_name(n, "env"), "env");
  check_keys(n, "env", {"num_envs", "num_physics_steps_per_env_step_mean", "num_physics_steps_per_env_step_std",
                        "lower_bound_min", "lower_bound_max", "upper_bound_min", "upper_bound_max", "reset_on_collision",
                        "collision_force_threshold", "create_ground_plane", "keep_same_env_for_num_episodes",
                        "sample_timestep_for_latency", "max_latency_physics_steps", "perturb_observations",
                        "enable_disturbance", "prob_apply_disturbance", "curriculum_level", "include_asset_type", "assets",
                        "terrain"});
  if (!n.IsMap()) return;
  if (n["num_envs"]) e.num_envs = get_int(n["num_envs"], "env.num_envs", 1, kMaxNumEnvs, "kMaxNumEnvs");
  if (n["num_physics_steps_per_env_step_mean"])
    e.num_physics_steps_per_env_step_mean = get_real(n["num_physics_steps_per_env_step_mean"], "env.num_physics_steps_per_env_step_mean", 1,
                                                     kMaxPhysicsStepsPerEnvStep);
  if (n["num_physics_steps_per_env_step_std"])
    e.num_physics_steps_per_env_step_std = get_real(n["num_physics_steps_per_env_step_std"], "env.num_physics_steps_per_env_step_std", 0,
                                                    kMaxPhysicsStepsPerEnvStep);
  if (n["lower_bound_min"]) e.lower_bound_min_m = get_vec3(n["lower_bound_min"], "env.lower_bound_min");
  if (n["lower_bound_max"]) e.lower_bound_max_m = get_vec3(n["lower_bound_max"], "env.lower_bound_max");
  if (n["upper_bound_min"]) e.upper_bound_min_m = get_vec3(n["upper_bound_min"], "env.upper_bound_min");
  if (n["upper_bound_max"]) e.upper_bound_max_m = get_vec3(n["upper_bound_max"], "env.upper_bound_max");
  if (n["reset_on_collision"]) e.reset_on_collision = get_bool(n["reset_on_collision"], "env.reset_on_collision");
  if (n["collision_force_threshold"]) e.collision_force_threshold_N = get_real(n["collision_force_threshold"], "env.collision_force_threshold", 0, 1e9);
  if (n["create_ground_plane"]) e.create_ground_plane = get_bool(n["create_ground_plane"], "env.create_ground_plane");
  if (n["keep_same_env_for_num_episodes"]) e.keep_same_env_for_num_episodes = get_int(n["keep_same_env_for_num_episodes"], "env.keep_same_env_for_num_episodes", 1);
  if (n["sample_timestep_for_latency"]) e.sample_timestep_for_latency = get_bool(n["sample_timestep_for_latency"], "env.sample_timestep_for_latency");
  if (n["max_latency_physics_steps"])
    e.max_latency_physics_steps = get_int(n["max_latency_physics_steps"], "env.max_latency_physics_steps", 0, kMaxLatencyPhysicsSteps,
                                          "kMaxLatencyPhysicsSteps");
  if (n["perturb_observations"]) e.perturb_observations = get_bool(n["perturb_observations"], "env.perturb_observations");
  if (n["enable_disturbance"]) e.enable_disturbance = get_bool(n["enable_disturbance"], "env.enable_disturbance");
  if (n["prob_apply_disturbance"]) e.prob_apply_disturbance = get_real(n["prob_apply_disturbance"], "env.prob_apply_disturbance", 0, 1);
  if (n["curriculum_level"]) e.curriculum_level = get_real(n["curriculum_level"], "env.curriculum_level", 0, 1);
  if (const YAML::Node inc = n["include_asset_type"]) {
    if (!inc.IsMap()) bad("env.include_asset_type", "expected a map of asset class -> true/false");
    std::string known;
    for (const AssetClass& c : e.assets) known += (known.empty() ? "" : ", ") + c.name;
    for (const auto& kv : inc) {
      const std::string cls = kv.first.Scalar();
      bool found = false;
      for (std::size_t i = 0; i < e.assets.size(); ++i) {
        if (e.assets[i].name != cls) continue;
        found = true;
        if (!get_bool(kv.second, "env.include_asset_type." + cls)) {
          e.assets.erase(e.assets.begin() + static_cast<long>(i));
        }
        break;
      }
      if (!found) bad("env.include_asset_type." + cls, "unknown asset class; known: " + (known.empty() ? std::string("(none)") : known));
    }
  }
  if (n["assets"]) parse_assets(n["assets"], e, dir);
  if (n["terrain"]) parse_terrain(n["terrain"], e.terrain, dir, source);
}

void parse_robot_map(const YAML::Node& n, RobotConfig& r, const std::string& where, const std::string& dir) {
  check_keys(n, where, {"robots_per_env", "mass_kg", "inertia_diag_kg_m2", "airframe", "collision_shape", "use_desaturation",
                        "linear_drag_b", "quadratic_drag_b", "angular_drag_b", "quadratic_angular_drag_b", "file", "urdf",
                        "max_init_yaw_rad"});
  if (!n.IsMap()) return;
  if (n["urdf"]) {
    // Mass, inertia, collision shape and rotors from a URDF (sim/urdf.hpp); the fields below override it.
    std::string err;
    if (!apply_urdf(resolve_path(dir, n["urdf"].Scalar()), r, err)) bad(where + ".urdf", err);
  }
  if (n["robots_per_env"]) r.robots_per_env = get_int(n["robots_per_env"], where + ".robots_per_env", 1, kMaxRobotsPerEnv, "kMaxRobotsPerEnv");
  if (n["mass_kg"]) r.mass_kg = get_real(n["mass_kg"], where + ".mass_kg", 1e-6, 1e6);
  if (n["inertia_diag_kg_m2"]) r.inertia_diag_kg_m2 = get_vec3(n["inertia_diag_kg_m2"], where + ".inertia_diag_kg_m2");
  // Start yaw drawn in [-max, max] (Aerial Gym's base quadrotor: pi/6; the registered default: pi).
  if (n["max_init_yaw_rad"]) r.max_init_yaw_rad = get_real(n["max_init_yaw_rad"], where + ".max_init_yaw_rad", 0, 3.14159265358979);
  if (n["use_desaturation"]) r.use_desaturation = get_bool(n["use_desaturation"], where + ".use_desaturation");
  if (n["linear_drag_b"]) r.linear_drag_b = get_vec3(n["linear_drag_b"], where + ".linear_drag_b");
  if (n["quadratic_drag_b"]) r.quadratic_drag_b = get_vec3(n["quadratic_drag_b"], where + ".quadratic_drag_b");
  if (n["angular_drag_b"]) r.angular_drag_b = get_vec3(n["angular_drag_b"], where + ".angular_drag_b");
  if (n["quadratic_angular_drag_b"]) r.quadratic_angular_drag_b = get_vec3(n["quadratic_angular_drag_b"], where + ".quadratic_angular_drag_b");
  if (n["airframe"]) {
    const std::string v = n["airframe"].Scalar();
    using P = allocation::AirframePreset;
    const std::pair<const char*, P> names[] = {{"base_quadrotor", P::base_quadrotor}, {"x500", P::x500}, {"hexarotor", P::hexarotor}};
    bool ok = false;
    for (const auto& p : names)
      if (v == p.first) {
        r.airframe = p.second;
        ok = true;
      }
    if (!ok) bad(where + ".airframe", "expected one of base_quadrotor, x500, hexarotor, got \"" + v + "\"");
  }
  if (const YAML::Node s = n["collision_shape"]) {
    const std::string f = where + ".collision_shape";
    check_keys(s, f, {"type", "radius_m", "half_length_m", "half_extents_m"});
    if (!s.IsMap() || !s["type"]) bad(f, "expected a map with `type`");
    const std::string t = s["type"].Scalar();
    if (t == "sphere") r.shape.type = ShapeType::sphere;
    else if (t == "box") r.shape.type = ShapeType::box;
    else if (t == "capsule") r.shape.type = ShapeType::capsule;
    else if (t == "cylinder") r.shape.type = ShapeType::cylinder;
    else bad(f + ".type", "expected one of sphere, box, capsule, cylinder, got \"" + t + "\"");
    if (s["radius_m"]) r.shape.radius_m = get_real(s["radius_m"], f + ".radius_m", 1e-4, 100);
    if (s["half_length_m"]) r.shape.half_length_m = get_real(s["half_length_m"], f + ".half_length_m", 0, 100);
    if (s["half_extents_m"]) r.shape.half_extents_m = get_vec3(s["half_extents_m"], f + ".half_extents_m");
  }
}

void parse_robot(const YAML::Node& n, RobotConfig& r, const std::string& dir) {
  r = lookup(registries().robots, section_name(n, "robot"), "robot");
  if (n.IsMap() && n["file"]) {
    // A robot file: the same fields as the robot section, in a file of its own.
    const std::string path = n["file"].Scalar();
    const std::string full = (!path.empty() && path[0] == '/') ? path : dir + path;
    YAML::Node rf;
    try {
      rf = YAML::LoadFile(full);
    } catch (const YAML::Exception& ex) {
      bad("robot.file", "cannot read robot file \"" + full + "\": " + ex.what());
    }
    const std::size_t slash = full.find_last_of('/');  // a URDF named in the robot file is relative to it
    parse_robot_map(rf, r, "robot.file(" + path + ")", slash == std::string::npos ? std::string() : full.substr(0, slash + 1));
  }
  parse_robot_map(n, r, "robot", dir);
}

WorldConfig parse(const YAML::Node& root, const std::string& dir, const std::string& source) {
  if (!root.IsMap()) bad("(top level)", "expected a map with sim, env, robot, controller, task, sensors, seed");
  check_keys(root, "(top level)", {"sim", "env", "robot", "controller", "task", "sensors", "seed", "threads", "simulator", "max_memory_gib"});
  WorldConfig c;
  // An RL task (sim/task.hpp) brings its own scene: the sections the file leaves out default to
  // the task's sim, env, robot, controller and sensors instead of the harness defaults.
  TaskDefaults td;
  const bool task_scene = root["task"] && (root["task"].IsScalar() || root["task"].IsMap()) &&
                          task_defaults(section_name(root["task"], "task"), td);
  parse_sim(root["sim"] ? root["sim"] : YAML::Node(td.sim), c.sim);
  parse_env(root["env"] ? root["env"] : YAML::Node(td.env), c.env, dir, source);
  parse_robot(root["robot"] ? root["robot"] : YAML::Node(td.robot), c.robot, dir);
  const YAML::Node ctrl = root["controller"] ? root["controller"] : YAML::Node(td.controller);
  c.controller = lookup(registries().controllers, section_name(ctrl, "controller"), "controller");
  check_keys(ctrl, "controller", {"randomize_gains"});
  if (ctrl.IsMap() && ctrl["randomize_gains"]) c.controller.randomize_gains = get_bool(ctrl["randomize_gains"], "controller.randomize_gains");
  const YAML::Node task = root["task"] ? root["task"] : YAML::Node("position_setpoint");
  c.task = lookup(registries().tasks, section_name(task, "task"), "task");
  check_keys(task, "task", {"episode_len_env_steps", "success_radius_m", "clearance_m", "line_of_sight", "placement_attempts",
                            "setpoint_speed_m_s"});
  if (task.IsMap() && task["setpoint_speed_m_s"])
    c.task.setpoint_speed_m_s = get_real(task["setpoint_speed_m_s"], "task.setpoint_speed_m_s", 0, 1000);
  if (task.IsMap() && task["clearance_m"]) c.task.clearance_m = get_real(task["clearance_m"], "task.clearance_m", 0, 100);
  if (task.IsMap() && task["line_of_sight"]) c.task.line_of_sight = get_bool(task["line_of_sight"], "task.line_of_sight");
  if (task.IsMap() && task["placement_attempts"])
    c.task.placement_attempts = get_int(task["placement_attempts"], "task.placement_attempts", 1);
  if (task.IsMap() && task["episode_len_env_steps"]) c.task.episode_len_env_steps = get_int(task["episode_len_env_steps"], "task.episode_len_env_steps", 1);
  if (task.IsMap() && task["success_radius_m"]) c.task.success_radius_m = get_real(task["success_radius_m"], "task.success_radius_m", 0, 1e6);
  // Sensors attach to the robot: `sensors: [base_depth_camera, {name: vl53l5cx, every: 2}]`.
  if (task_scene && !root["sensors"]) {
    for (const auto& ts : td.sensors) {
      SensorConfig sc = lookup(registries().sensors, ts.first, "sensors");
      sc.every_env_steps = ts.second;
      c.robot.sensors.push_back(sc);
    }
  }
  if (const YAML::Node s = root["sensors"]) {
    if (!s.IsSequence()) bad("sensors", "expected a list of sensor names or {name, every} maps");
    for (std::size_t i = 0; i < s.size(); ++i) {
      const std::string field = "sensors[" + std::to_string(i) + "]";
      if (!s[i].IsScalar() && !s[i].IsMap()) bad(field, "expected a sensor name or a map with `name`");
      SensorConfig sc = lookup(registries().sensors, section_name(s[i], field), "sensors");
      check_keys(s[i], field, {"every"});
      if (s[i].IsMap() && s[i]["every"])
        sc.every_env_steps = get_int(s[i]["every"], field + ".every", 1, kMaxSensorEveryEnvSteps, "kMaxSensorEveryEnvSteps");
      c.robot.sensors.push_back(sc);
    }
  }
  if (root["simulator"]) parse_simulator(root["simulator"], c.simulator);
  if (root["seed"]) c.seed = static_cast<std::uint64_t>(get_int(root["seed"], "seed", 0));
  if (root["threads"]) c.num_threads = get_int(root["threads"], "threads", 1, kMaxThreads, "kMaxThreads");
  if (root["max_memory_gib"]) c.max_memory_gib = get_real(root["max_memory_gib"], "max_memory_gib", 1e-6, kMaxMemoryGiBSetting);
  // The bounds that span fields (obstacle slots summed over the classes, measured points x * y).
  if (std::string lerr; !check_config_limits(c, lerr)) throw ScenarioError(lerr);
  return c;
}

bool load(const std::function<YAML::Node()>& read, const std::string& name, const std::string& dir, WorldConfig& out,
          std::string& error) {
  try {
    WorldConfig tmp = parse(read(), dir, name);
    out = tmp;  // only a fully validated config reaches the caller
    return true;
  } catch (const ScenarioError& e) {
    error = name + ": " + e.what();
  } catch (const YAML::Exception& e) {
    error = name + ": " + e.what();
  }
  return false;
}

}  // namespace

bool load_scenario_file(const std::string& path, WorldConfig& out, std::string& error) {
  std::ifstream f(path);
  if (!f) {
    error = path + ": cannot open file";
    return false;
  }
  const std::size_t slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
  return load([&] { return YAML::LoadFile(path); }, path, dir, out, error);
}

bool load_scenario_string(const std::string& text, const std::string& source_name, WorldConfig& out, std::string& error) {
  return load([&] { return YAML::Load(text); }, source_name, "", out, error);
}

const char* default_scenario_yaml() {
  return "# Embedded default: 1024 quadrotors flying position setpoints through the forest.\n"
         "seed: 0\n"
         "sim: base_sim\n"
         "env: {name: forest, num_envs: 1024}\n"
         "robot: base_quadrotor\n"
         "controller: lee_position_control\n"
         "# Start, target and the straight path between them clear the trees by 0.2 m; the setpoint\n"
         "# moves along that path at 2 m/s (a 10 m step response of the Lee controller curves up to\n"
         "# 2 m off the line and into the trees); 8 s episodes.\n"
         "task: {name: position_setpoint, episode_len_env_steps: 800, setpoint_speed_m_s: 2, clearance_m: 0.2,\n"
         "       line_of_sight: true, placement_attempts: 64}\n"
         "sensors: []\n";
}

}  // namespace kestrel::sim
