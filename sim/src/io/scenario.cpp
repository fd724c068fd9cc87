#include "kestrel/sim/scenario.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "kestrel/sim/custom_task.hpp"
#include "kestrel/sim/limits.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/schema.hpp"
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
Vec3 get_vec3(const YAML::Node& n, const std::string& f, double lo = -1e9, double hi = 1e9) {
  if (!n.IsSequence() || n.size() != 3) bad(f, "expected a list of 3 numbers, got " + scalar_text(n));
  Vec3 v;
  for (int i = 0; i < 3; ++i) v[i] = get_real(n[i], f + "[" + std::to_string(i) + "]", lo, hi);
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

/// Reads every key of a section through its schema (sim/schema.hpp): the keys it allows (its
/// fields, their older aliases, its structural keys and `name`), each value's type and range, and
/// the messages naming the field. Structural keys are left to the caller.
template <class S>
void apply_schema(const YAML::Node& n, const std::string& where, const Schema<S>& sc, S& s) {
  if (!n.IsMap()) return;
  for (const auto& kv : n) {
    const std::string k = kv.first.Scalar();
    bool ok = k == "name";
    for (std::size_t i = 0; i < sc.count && !ok; ++i) ok = k == sc.fields[i].key || (sc.fields[i].alias && k == sc.fields[i].alias);
    for (std::size_t i = 0; i < sc.num_structural && !ok; ++i) ok = k == sc.structural[i].key;
    if (ok) continue;
    std::string list = "name";
    for (std::size_t i = 0; i < sc.count; ++i) list += std::string(", ") + sc.fields[i].key;
    for (std::size_t i = 0; i < sc.num_structural; ++i) list += std::string(", ") + sc.structural[i].key;
    bad(where + "." + k, "unknown field; allowed: " + list);
  }
  for (std::size_t i = 0; i < sc.count; ++i) {
    const Field<S>& f = sc.fields[i];
    // Which key the file used (a Node cannot be re-assigned once invalid: yaml-cpp throws).
    const bool by_alias = !n[f.key] && f.alias != nullptr && n[f.alias];
    const char* used = by_alias ? f.alias : f.key;
    const YAML::Node v = n[used];
    if (!v) continue;
    const std::string name = where + "." + used;
    switch (f.type) {
      case FieldType::real_number: s.*f.r = get_real(v, name, f.lo, f.hi); break;
      case FieldType::integer:
        s.*f.i = f.hi < f.lo ? get_int(v, name, static_cast<int>(f.lo))
                             : get_int(v, name, static_cast<int>(f.lo), static_cast<int>(f.hi), f.limit ? f.limit : "limit");
        break;
      case FieldType::boolean: s.*f.b = get_bool(v, name); break;
      case FieldType::vec3: s.*f.v = get_vec3(v, name, f.lo, f.hi); break;
      case FieldType::range: {
        if (!v.IsSequence() || v.size() != 2) bad(name, "expected [min, max], got " + scalar_text(v));
        const real mn = get_real(v[0], name + "[0]", f.lo, f.hi), mx = get_real(v[1], name + "[1]", f.lo, f.hi);
        if (mn > mx) bad(name, "expected min <= max");
        s.*f.r = mn;
        s.*f.r_max = mx;
        break;
      }
      case FieldType::choice:
        if (!v.IsScalar() || !f.set_choice(s, v.Scalar()))
          bad(name, std::string("expected one of ") + f.choices + ", got \"" + scalar_text(v) + "\"");
        break;
    }
  }
}

// `simulator: planar` or `simulator: {name: planar, vehicle: multirotor, lidar_beams: 64}`
// (physics backend of sim/simulator.hpp; KESTREL_SIMULATOR overrides the name at run time).
void parse_simulator(const YAML::Node& n, SimulatorConfig& s) {
  s = lookup(registries().simulators, section_name(n, "simulator"), "simulator");
  apply_schema(n, "simulator", simulator_schema(), s);
}

/// The task section's own keys and its nested `curriculum` map (task.curriculum).
void apply_task(const YAML::Node& n, TaskConfig& t) {
  apply_schema(n, "task", task_schema(), t);
  if (!n.IsMap()) return;
  if (const YAML::Node cur = n["curriculum"]) {
    if (!cur.IsMap()) bad("task.curriculum", "expected a map of " + std::string(curriculum_schema().doc));
    apply_schema(cur, "task.curriculum", curriculum_schema(), t.curriculum);
  }
  if (const YAML::Node r = n["reward"]) {
    // The reward constants of the task the section names (TaskConfig::reward / navigation.reward).
    if (!r.IsMap()) bad("task.reward", "expected a map of the reward's constants");
    if (t.name == "navigation_task") {
      apply_schema(r, "task.reward", navigation_reward_schema(), t.navigation.reward);
    } else if (custom_tasks().has(t.name)) {
      bad("task.reward", "task " + t.name + " builds its reward from terms in code (sim/custom_task.hpp); task.reward sets "
                         "position_setpoint_task's and navigation_task's constants");
    } else {
      apply_schema(r, "task.reward", position_setpoint_reward_schema(), t.reward);
    }
  }
  if (const YAML::Node lo = n["locomotion"]) {
    if (!lo.IsMap()) bad("task.locomotion", "expected a map of " + std::string(locomotion_schema().doc));
    apply_schema(lo, "task.locomotion", locomotion_schema(), t.locomotion);
    if (const YAML::Node sc = lo["scales"]) {
      if (!sc.IsMap()) bad("task.locomotion.scales", "expected a map of reward term names to scales");
      apply_schema(sc, "task.locomotion.scales", locomotion_scales_schema(), t.locomotion.scales);
    }
    if (const YAML::Node pc = lo["penalize_contacts_on"]) {
      if (!pc.IsSequence()) bad("task.locomotion.penalize_contacts_on", "expected a list of body-name fragments, e.g. [thigh, calf]");
      t.locomotion.penalize_contacts_on.clear();
      for (std::size_t i = 0; i < pc.size(); ++i) {
        if (!pc[i].IsScalar() || pc[i].as<std::string>().empty())
          bad("task.locomotion.penalize_contacts_on[" + std::to_string(i) + "]", "expected a non-empty body-name fragment");
        t.locomotion.penalize_contacts_on.push_back(pc[i].as<std::string>());
      }
    }
  }
  if (const YAML::Node pp = n["pick_place"]) {
    if (!pp.IsMap()) bad("task.pick_place", "expected a map of " + std::string(pick_place_schema().doc));
    apply_schema(pp, "task.pick_place", pick_place_schema(), t.pick_place);
  }
  if (const YAML::Node nav = n["navigation"]) {
    if (!nav.IsMap()) bad("task.navigation", "expected a map of max_speed_m_s, max_yaw_rate_rad_s, pool_rows, pool_cols, reward");
    apply_schema(nav, "task.navigation", navigation_schema(), t.navigation);
    if (const YAML::Node r = nav["reward"]) {
      if (!r.IsMap()) bad("task.navigation.reward", "expected a map of the reward's constants");
      apply_schema(r, "task.navigation.reward", navigation_reward_schema(), t.navigation.reward);
    }
  }
}

/// controller: a registry name or a map of ControllerConfig's keys (schema rows) plus k_pos, k_vel,
/// k_rot, k_angvel: a fixed gain (min = max). Cross-field rules checked here name the field.
void parse_controller(const YAML::Node& n, ControllerConfig& c) {
  c = lookup(registries().controllers, section_name(n, "controller"), "controller");
  apply_schema(n, "controller", controller_schema(), c);
  if (!n.IsMap()) return;
  const struct {
    const char* key;
    Vec3 ControllerConfig::*min;
    Vec3 ControllerConfig::*max;
  } gains[] = {{"k_pos", &ControllerConfig::k_pos_min, &ControllerConfig::k_pos_max},
               {"k_vel", &ControllerConfig::k_vel_min, &ControllerConfig::k_vel_max},
               {"k_rot", &ControllerConfig::k_rot_min, &ControllerConfig::k_rot_max},
               {"k_angvel", &ControllerConfig::k_angvel_min, &ControllerConfig::k_angvel_max}};
  for (const auto& g : gains) {
    const std::string key = g.key, f = "controller." + key;
    if (const YAML::Node v = n[g.key]) {
      if (n[key + "_min"] || n[key + "_max"]) bad(f, "give either " + key + " (a fixed gain) or " + key + "_min / " + key + "_max, not both");
      if (!v.IsSequence() || v.size() != 3) bad(f, "expected a list of 3 numbers, got " + scalar_text(v));
      Vec3 x;
      for (int i = 0; i < 3; ++i) x[i] = get_real(v[i], f + "[" + std::to_string(i) + "]", 0, static_cast<double>(kLeeMaxGain));
      c.*g.min = x;
      c.*g.max = x;
    }
    for (int i = 0; i < 3; ++i)
      if (!((c.*g.min)[i] <= (c.*g.max)[i]))
        bad("controller." + key + "_min", "expected <= " + key + "_max on every axis, got " + std::to_string((c.*g.min)[i]) + " > " +
                                              std::to_string((c.*g.max)[i]) + " at [" + std::to_string(i) + "]");
  }
  if (!(c.action_min < c.action_max)) bad("controller.action_min", "expected < action_max");
}

/// One entry of `sensors:` (or a registered sensor): the preset, then the keys of its kind's schema
/// (sim/schema.hpp: lidar / ToF, camera, IMU), then the rules between fields.
SensorConfig parse_sensor(const YAML::Node& n, const std::string& field) {
  if (!n.IsScalar() && !n.IsMap()) bad(field, "expected a sensor name or a map with `name`");
  SensorConfig sc = lookup(registries().sensors, section_name(n, field), "sensors");
  if (!n.IsMap()) return sc;
  const std::string& where = field;
  if (sc.kind == SensorKind::imu) {
    ImuSensorFields f = imu_sensor_fields(sc);
    apply_schema(n, where, imu_sensor_schema(), f);
    set_imu_sensor_fields(f, sc);
  } else {
    RaySensorFields f = ray_sensor_fields(sc);
    apply_schema(n, where, sc.kind == SensorKind::camera ? camera_sensor_schema() : lidar_sensor_schema(), f);
    set_ray_sensor_fields(f, sc);
  }
  std::string err;
  if (!check_sensor_cross_fields(sc, where, err)) throw ScenarioError(err);
  return sc;
}

void parse_sim(const YAML::Node& n, SimParams& s) {
  s = lookup(registries().sims, section_name(n, "sim"), "sim");
  apply_schema(n, "sim", sim_schema(), s);
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
  t = TerrainConfig();
  t.source_file = source;
  apply_schema(n, f, terrain_schema(), t);
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
  if (n["terrain_proportions"]) {
    t.terrain_proportions = get_real_list(n["terrain_proportions"], f + ".terrain_proportions");
    double sum = 0;
    bool ok = t.terrain_proportions.size() == 5;
    for (real v : t.terrain_proportions) {
      ok = ok && v >= 0 && std::isfinite(v);
      sum += static_cast<double>(v);
    }
    if (!ok || !(sum > 0))
      bad(f + ".terrain_proportions",
          "expected 5 numbers >= 0 with a positive sum: smooth slope, rough slope, stairs up, stairs down, discrete obstacles");
  }
  for (const char* k : {"measured_points_x_m", "measured_points_x"})
    if (n[k]) t.measured_points_x_m = get_real_list(n[k], f + "." + k);
  for (const char* k : {"measured_points_y_m", "measured_points_y"})
    if (n[k]) t.measured_points_y_m = get_real_list(n[k], f + "." + k);
  if (t.type == TerrainType::heightfield) {
    const int sources = (t.heights_m.empty() ? 0 : 1) + (t.image_file.empty() ? 0 : 1) + (t.procedural.empty() ? 0 : 1);
    if (sources != 1) bad(f, "type heightfield needs exactly one of heights_m, image_file, procedural");
  }
  if (t.type == TerrainType::trimesh && t.mesh_file.empty()) bad(f + ".mesh_file", "missing (type trimesh needs an .obj or .stl file)");
}

/// env.assets: extra asset classes (e.g. meshes from OBJ/STL files), appended to the env's classes.
void parse_assets(const YAML::Node& n, EnvConfig& e, const std::string& dir) {
  if (!n.IsSequence()) bad("env.assets", "expected a list of asset class maps");
  for (std::size_t i = 0; i < n.size(); ++i) {
    const YAML::Node a = n[i];
    std::string f = "env.assets[" + std::to_string(i) + "]";
    if (!a.IsMap() || !a["name"] || !a["kind"]) bad(f, "expected a map with `name` and `kind`");
    AssetClass c;
    c.name = a["name"].Scalar();
    f = "env.assets." + c.name;
    for (const AssetClass& o : e.assets)
      if (o.name == c.name) bad(f, "duplicate asset class name");
    apply_schema(a, f, asset_schema(), c);
    if (!a["min_num_assets"]) c.min_num_assets = c.num_assets;  // default: every asset at every level
    if (c.min_num_assets > c.num_assets) bad(f + ".min_num_assets", "expected <= num_assets");
    if (a["mesh_file"]) c.mesh_file = resolve_path(dir, a["mesh_file"].Scalar());
    if (c.kind == AssetKind::mesh && c.mesh_file.empty()) bad(f + ".mesh_file", "missing (kind mesh needs an .obj or .stl file)");
    if (c.kind != AssetKind::mesh && !c.mesh_file.empty()) bad(f + ".mesh_file", "only for kind mesh");
    if (e.assets.size() >= 255) bad(f, "too many asset classes (at most 255)");
    e.assets.push_back(c);
  }
}

void parse_env(const YAML::Node& n, EnvConfig& e, const std::string& dir, const std::string& source) {
  e = lookup(registries().envs, section_name(n, "env"), "env");
  apply_schema(n, "env", env_schema(), e);
  if (!n.IsMap()) return;
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
  if (!n.IsMap()) return;
  if (n["urdf"]) {
    // Mass, inertia, collision shape and rotors from a URDF (sim/urdf.hpp); the fields below override it.
    std::string err, urdf_name;
    if (!apply_urdf(resolve_path(dir, n["urdf"].Scalar()), r, err, &urdf_name)) bad(where + ".urdf", err);
    if (r.name.empty()) r.name = urdf_name.empty() ? std::string("urdf_robot") : urdf_name;
  }
  if (n["model"]) {
    // An articulated robot file (sim/articulated_robot.hpp), read when the simulator is built.
    if (!n["model"].IsScalar() || n["model"].Scalar().empty()) bad(where + ".model", "expected the path of an MJCF or URDF file");
    r.model_file = resolve_path(dir, n["model"].Scalar());
    r.kind = robots::RobotKind::articulated;
    if (!n["name"]) r.name = "articulated_robot";
  }
  apply_schema(n, where, robot_schema(), r);
  if (const YAML::Node s = n["collision_shape"]) {
    const std::string f = where + ".collision_shape";
    if (!s.IsMap() || !s["type"]) bad(f, "expected a map with `type`");
    apply_schema(s, f, shape_schema(), r.shape);
  }
}

void parse_robot(const YAML::Node& n, RobotConfig& r, const std::string& dir) {
  // `robot: {urdf: FILE}` (README): without `name` a URDF robot starts from base_quadrotor (its
  // motors, 4 x 2 N, unless `airframe` says otherwise) and is named after the URDF's <robot name>.
  const bool urdf_only = n.IsMap() && !n["name"] && n["urdf"];
  r = lookup(registries().robots, urdf_only ? std::string("base_quadrotor") : section_name(n, "robot"), "robot");
  if (urdf_only) r.name.clear();
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
  parse_robot(root["robot"] ? root["robot"] : YAML::Load(td.robot), c.robot, dir);  // a name or a {name, fields} map
  const YAML::Node ctrl = root["controller"] ? root["controller"] : YAML::Node(td.controller);
  parse_controller(ctrl, c.controller);
  const YAML::Node task = root["task"] ? root["task"] : YAML::Node("position_setpoint");
  c.task = lookup(registries().tasks, section_name(task, "task"), "task");
  apply_task(task, c.task);
  // Sensors attach to the robot: `sensors: [base_depth_camera, {name: vl53l5cx, every: 2}]`.
  if (task_scene && !root["sensors"]) {
    for (const auto& ts : td.sensors) {
      SensorConfig sc = lookup(registries().sensors, ts.first, "sensors");
      sc.every_env_steps = ts.second;
      c.robot.sensors.push_back(sc);
    }
  }
  if (const YAML::Node s = root["sensors"]) {
    if (!s.IsSequence()) bad("sensors", "expected a list of sensor names or {name, every, ...} maps");
    for (std::size_t i = 0; i < s.size(); ++i) c.robot.sensors.push_back(parse_sensor(s[i], "sensors[" + std::to_string(i) + "]"));
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

bool load_scenario_string(const std::string& text, const std::string& source_name, const std::string& base_dir,
                          WorldConfig& out, std::string& error) {
  std::string dir = base_dir;
  if (!dir.empty() && dir.back() != '/') dir += '/';
  return load([&] { return YAML::Load(text); }, source_name, dir, out, error);
}

bool register_preset(const std::string& kind, const std::string& name, const std::string& section_yaml,
                     const std::string& description, std::string& error) {
  const std::string where = "register " + kind + " \"" + name + "\": ";
  Registries& r = registries();
  auto add = [&](auto& registry, auto value) {
    if (name.empty() || registry.has(name)) {
      error = where + (name.empty() ? "expected a non-empty name" : "the name is taken; registered: " + registry.joined());
      return false;
    }
    return registry.add(name, description, [value] { return value; });
  };
  try {
    const YAML::Node n = YAML::Load(section_yaml);
    if (kind == "sim") {
      SimParams v;
      parse_sim(n, v);
      v.name = name;
      return add(r.sims, v);
    }
    if (kind == "env") {
      EnvConfig v;
      parse_env(n, v, "", "<register>");
      v.name = name;
      return add(r.envs, v);
    }
    if (kind == "robot") {
      RobotConfig v;
      parse_robot(n, v, "");
      v.name = name;
      return add(r.robots, v);
    }
    if (kind == "simulator") {
      SimulatorConfig v;
      parse_simulator(n, v);
      return add(r.simulators, v);
    }
    if (kind == "task") {
      TaskConfig v = lookup(r.tasks, section_name(n, "task"), "task");
      apply_task(n, v);
      v.name = name;
      return add(r.tasks, v);
    }
    if (kind == "controller") {
      // The controller's name stays its kind's (it selects the control law); the preset adds options.
      ControllerConfig v;
      parse_controller(n, v);
      return add(r.controllers, v);
    }
    if (kind == "sensor") {
      SensorConfig v = parse_sensor(n, "sensor");
      v.name = name;
      return add(r.sensors, v);
    }
    error = where + "kind: expected one of sim, env, robot, controller, sensor, task, simulator";
    return false;
  } catch (const ScenarioError& e) {
    error = where + e.what();
  } catch (const YAML::Exception& e) {
    error = where + e.what();
  }
  return false;
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
