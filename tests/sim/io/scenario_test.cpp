#include <gtest/gtest.h>

#include <limits>

#include "kestrel/sim/scenario.hpp"
#include "kestrel/sim/world.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {
std::string error_of(const std::string& text) {
  WorldConfig c;
  c.seed = 1234;
  std::string err;
  EXPECT_FALSE(load_scenario_string(text, "scenario.yaml", c, err)) << text;
  EXPECT_EQ(c.seed, 1234u);  // nothing half-written
  return err;
}
}  // namespace

TEST(SimScenario, DefaultLoadsAndBuilds) {
  WorldConfig c;
  std::string err;
  ASSERT_TRUE(load_scenario_string(default_scenario_yaml(), "default", c, err)) << err;
  EXPECT_EQ(c.env.name, "forest");
  EXPECT_EQ(c.env.num_envs, 1024);
  EXPECT_EQ(c.controller.kind, ControllerKind::lee_position);
  c.env.num_envs = 4;
  EXPECT_TRUE(World::create(c, err)) << err;
}

TEST(SimScenario, FileOnDiskWithOverrides) {
  WorldConfig c;
  std::string err;
  ASSERT_TRUE(load_scenario_file(KESTREL_SIM_TEST_DIR "/../../sim/scenarios/default.yaml", c, err)) << err;
  ASSERT_TRUE(load_scenario_string("sim: {name: falling_forwards, dt_s: 0.005}\n"
                                   "env: {name: env_with_obstacles, num_envs: 8, reset_on_collision: false,"
                                   " include_asset_type: {panels: false}}\n"
                                   "robot: {name: base_quadrotor, robots_per_env: 2, collision_shape: {type: box, half_extents_m: [0.15, 0.15, 0.05]}}\n"
                                   "controller: {name: lee_velocity_control}\n"
                                   "seed: 9\n",
                                   "s.yaml", c, err))
      << err;
  EXPECT_FLOAT_EQ(c.sim.dt_s, 0.005f);
  EXPECT_GT(c.sim.gravity_w[0], 4.0f);
  EXPECT_FALSE(c.env.reset_on_collision);
  for (const auto& a : c.env.assets) EXPECT_NE(a.name, "panels");
  EXPECT_EQ(c.robot.robots_per_env, 2);
  EXPECT_EQ(c.robot.shape.type, ShapeType::box);
  EXPECT_EQ(c.controller.kind, ControllerKind::lee_velocity);
  EXPECT_EQ(c.seed, 9u);
}

TEST(SimScenario, ClearErrors) {
  EXPECT_EQ(error_of("env: {name: empty, num_envs: -3}"),
            "scenario.yaml: env.num_envs: expected an integer in [1, 1048576] (kMaxNumEnvs), got \"-3\"");
  EXPECT_EQ(error_of("robot: quadx"), "scenario.yaml: robot: unknown robot \"quadx\"; known: anymal_c, base_quadrotor, go2, ground_vehicle, hexarotor, x500");
  EXPECT_NE(error_of("env: nowhere").find("known: dynamic, empty, env_with_obstacles, forest, goal_box_room, legged_flat, legged_rough, lidar_navigation"), std::string::npos);
  EXPECT_NE(error_of("env: {name: empty, num_env: 3}").find("env.num_env: unknown field; allowed: name,"), std::string::npos);
  EXPECT_NE(error_of("env: {name: empty, reset_on_collision: maybe}").find("env.reset_on_collision: expected true or false"),
            std::string::npos);
  EXPECT_NE(error_of("sim: {name: base_sim, integrator: verlet}").find("expected one of rk4, semi_implicit_euler"), std::string::npos);
  EXPECT_NE(error_of("env: {name: forest, include_asset_type: {rocks: true}}").find("known: trees"), std::string::npos);
  EXPECT_NE(error_of("sensors: [lidar]").find("unknown sensors \"lidar\""), std::string::npos);
  EXPECT_NE(error_of("env: [1, 2").find("scenario.yaml: "), std::string::npos);  // YAML syntax error
  EXPECT_NE(error_of("bogus: 1").find("(top level).bogus: unknown field"), std::string::npos);
}

TEST(SimScenario, MissingFileNamesIt) {
  WorldConfig c;
  std::string err;
  EXPECT_FALSE(load_scenario_file("/nonexistent/x.yaml", c, err));
  EXPECT_EQ(err, "/nonexistent/x.yaml: cannot open file");
}

// Fuzz finding F5: counts without an upper bound ended in std::bad_alloc, signed overflow (a tree
// class of 6e8 assets: 6e8 * 4 slots) or a hang (2e9 substeps per physics step). Every count now
// has a documented maximum (sim/limits.hpp), refused with the field and the allowed range.
TEST(SimScenario, CountsHaveUpperBoundsNamedInTheMessage) {
  EXPECT_EQ(error_of("robot: {name: base_quadrotor, robots_per_env: 2000000000}"),
            "scenario.yaml: robot.robots_per_env: expected an integer in [1, 1024] (kMaxRobotsPerEnv), got \"2000000000\"");
  EXPECT_EQ(error_of("env: {name: empty, assets: [{name: c, kind: cube, num_assets: 200000000}]}"),
            "scenario.yaml: env.assets.c.num_assets: expected an integer in [0, 65536] (kMaxAssetsPerClass), got \"200000000\"");
  EXPECT_EQ(error_of("env: {name: empty, assets: [{name: t, kind: tree, num_assets: 600000000}]}"),
            "scenario.yaml: env.assets.t.num_assets: expected an integer in [0, 65536] (kMaxAssetsPerClass), got \"600000000\"");
  EXPECT_EQ(error_of("sim: {name: base_sim, substeps: 2000000000}"),
            "scenario.yaml: sim.substeps: expected an integer in [1, 1000] (kMaxSubsteps), got \"2000000000\"");
  EXPECT_EQ(error_of("env: {name: empty, num_envs: 2000000000}"),
            "scenario.yaml: env.num_envs: expected an integer in [1, 1048576] (kMaxNumEnvs), got \"2000000000\"");
  EXPECT_EQ(error_of("env: {name: empty, max_latency_physics_steps: 2147483647}"),
            "scenario.yaml: env.max_latency_physics_steps: expected an integer in [0, 1000] (kMaxLatencyPhysicsSteps), got "
            "\"2147483647\"");
  EXPECT_EQ(error_of("threads: 100000"), "scenario.yaml: threads: expected an integer in [1, 1024] (kMaxThreads), got \"100000\"");
  EXPECT_NE(error_of("env: {name: empty, num_physics_steps_per_env_step_mean: 1e6}")
                .find("env.num_physics_steps_per_env_step_mean: expected a number in [1, 1000]"),
            std::string::npos);
  // Several classes each within its bound, together beyond the slots of one environment (two
  // large classes also overflowed the `cap +=` sum).
  std::string many = "env: {name: empty, assets: [";
  for (int i = 0; i < 5; ++i) many += std::string(i ? ", " : "") + "{name: t" + std::to_string(i) + ", kind: tree, num_assets: 60000}";
  many += "]}";
  EXPECT_EQ(error_of(many),
            "scenario.yaml: env.assets (obstacle slots per environment: the sum of num_assets, a tree counting 4): 1200000 is out "
            "of range; allowed: 0..1048576 (kMaxObstacleSlotsPerEnv)");
  EXPECT_NE(error_of("max_memory_gib: 0").find("max_memory_gib: expected a number in"), std::string::npos);
}

// The same bounds for a config built in code (the C++ API, or kestrel run --envs after loading).
TEST(SimScenario, WorldCreateChecksTheBoundsOfConfigsBuiltInCode) {
  auto refused = [](const WorldConfig& c) {
    std::string err;
    EXPECT_FALSE(World::create(c, err));
    return err;
  };
  WorldConfig c;
  c.env.num_envs = 1;
  c.robot.robots_per_env = 2000000000;
  EXPECT_EQ(refused(c), "robot.robots_per_env: expected an integer in [1, 1024] (kMaxRobotsPerEnv), got 2000000000");
  c = WorldConfig();
  c.env.num_envs = 1;
  c.sim.substeps = 2000000000;
  EXPECT_EQ(refused(c), "sim.substeps: expected an integer in [1, 1000] (kMaxSubsteps), got 2000000000");
  c = WorldConfig();
  c.env.num_envs = 1 << 30;
  EXPECT_EQ(refused(c), "env.num_envs: expected an integer in [1, 1048576] (kMaxNumEnvs), got 1073741824");
  c = WorldConfig();
  c.env.num_envs = 1;
  AssetClass t;
  t.name = "t";
  t.kind = AssetKind::tree;
  t.num_assets = 600000000;
  t.min_num_assets = 0;
  c.env.assets.push_back(t);
  EXPECT_EQ(asset_class_slots(t), 2147483647);  // saturated, never negative (was signed overflow)
  EXPECT_EQ(refused(c), "env.assets.t.num_assets: expected an integer in [0, 65536] (kMaxAssetsPerClass), got 600000000");
  c = WorldConfig();
  c.env.num_envs = 1;
  c.env.max_latency_physics_steps = 2147483647;  // rng % (max + 1) overflowed
  EXPECT_EQ(refused(c), "env.max_latency_physics_steps: expected an integer in [0, 1000] (kMaxLatencyPhysicsSteps), got 2147483647");
  // The schema's ranges hold for code-built configs too (sim/schema.hpp check_config_fields),
  // fields the World never checked itself included: a NaN friction or disturbance limit.
  c = WorldConfig();
  c.env.num_envs = 1;
  c.sim.friction_coefficient = std::numeric_limits<real>::quiet_NaN();
  EXPECT_EQ(refused(c), "sim.friction_coefficient: expected a number in [0, 100], got nan");
  c = WorldConfig();
  c.env.num_envs = 1;
  c.env.max_force_disturbance_N[1] = std::numeric_limits<real>::infinity();
  EXPECT_EQ(refused(c).find("env.max_force_disturbance_N: expected finite numbers in [-1000000000, 1000000000], got inf at [1]"), 0u);
}

// Set-up estimates the memory a world needs before allocating any of it, and refuses beyond
// max_memory_gib (default 4 GiB; scenario `max_memory_gib`, kestrel run --max-memory-gib).
TEST(SimScenario, MemoryEstimateRefusesBeforeAllocating) {
  WorldConfig c;
  std::string err;
  ASSERT_TRUE(load_scenario_string("env: {name: empty, num_envs: 1000000, assets: [{name: c, kind: cube, num_assets: 1000}]}\n",
                                   "big.yaml", c, err))
      << err;
  EXPECT_GT(World::estimate_bytes(c), 100.0 * (1u << 30));
  EXPECT_FALSE(World::create(c, err));
  EXPECT_EQ(err.find("memory: this world needs about 1"), 0u) << err;
  EXPECT_NE(err.find("more than max_memory_gib = 4 GiB"), std::string::npos) << err;
  // The cap is a setting: a small world under a tiny cap is refused, under the default it builds.
  ASSERT_TRUE(load_scenario_string("env: {name: empty, num_envs: 64}\nmax_memory_gib: 0.00001\n", "small.yaml", c, err)) << err;
  EXPECT_FALSE(World::create(c, err));
  EXPECT_NE(err.find("more than max_memory_gib = 1e-05 GiB"), std::string::npos) << err;
  c.max_memory_gib = kDefaultMaxMemoryGiB;
  auto w = World::create(c, err);
  ASSERT_TRUE(w) << err;
  // The estimate is what the built world reports.
  EXPECT_EQ(World::estimate_bytes(c), static_cast<double>(w->bytes_per_env()) * w->num_envs());
}

// ---- Schema tables (sim/schema.hpp): one table per config struct drives the parser and the docs.

#include <fstream>
#include <sstream>

#include "kestrel/sim/schema.hpp"

namespace {

/// A value the field allows, as YAML, and a check that the parsed struct holds it.
template <class S>
std::string valid_yaml(const Field<S>& f, double& expect) {
  std::ostringstream y;
  y.precision(9);
  switch (f.type) {
    case FieldType::real_number:
      expect = f.lo + (f.hi - f.lo) * 0.25;
      if (f.hi - f.lo > 1e6) expect = f.lo + 3.5;  // a round number inside huge ranges
      y << expect;
      break;
    case FieldType::integer:
      expect = f.hi < f.lo ? f.lo + 2 : (f.lo + 1 <= f.hi ? f.lo + 1 : f.lo);
      y << static_cast<int>(expect);
      break;
    case FieldType::boolean:
      expect = 1;
      y << "true";
      break;
    case FieldType::vec3:
      expect = 0.125;
      y << (f.lo >= 0 ? "[0.125, 0.25, 0.5]" : "[0.125, -0.25, 0.5]");  // bounded rows (gains) take no negatives
      break;
    case FieldType::range:
      expect = f.lo + (f.hi - f.lo) * 0.25;
      if (f.hi - f.lo > 1e6) expect = f.lo + 3.5;
      y << "[" << expect << ", " << expect << "]";
      break;
    case FieldType::choice: {
      expect = 0;
      const std::string c = f.choices;
      y << c.substr(c.rfind(", ") == std::string::npos ? 0 : c.rfind(", ") + 2);  // the last choice
      break;
    }
  }
  return y.str();
}

template <class S>
void expect_field(const Field<S>& f, const S& s, double expect, const std::string& where) {
  switch (f.type) {
    case FieldType::real_number: EXPECT_FLOAT_EQ(static_cast<float>(s.*f.r), static_cast<float>(expect)) << where; break;
    case FieldType::integer: EXPECT_EQ(s.*f.i, static_cast<int>(expect)) << where; break;
    case FieldType::boolean: EXPECT_TRUE(s.*f.b) << where; break;
    case FieldType::vec3: EXPECT_EQ((s.*f.v)[2], 0.5_r) << where; break;
    case FieldType::range:
      EXPECT_FLOAT_EQ(static_cast<float>(s.*f.r), static_cast<float>(expect)) << where;
      EXPECT_FLOAT_EQ(static_cast<float>(s.*f.r_max), static_cast<float>(expect)) << where;
      break;
    case FieldType::choice: {
      const std::string c = f.choices;
      EXPECT_EQ(std::string(f.get_choice(s)), c.substr(c.rfind(", ") == std::string::npos ? 0 : c.rfind(", ") + 2)) << where;
      break;
    }
  }
}

/// Every row of a section's schema: a valid value under its own key reaches its member; a value
/// outside the allowed set is refused with a message naming section.key.
/// `context` (if given) adds keys other than the one under test, so that rules between fields
/// (the controller's min <= max) hold for any value a row allows.
template <class S>
void every_row(const Schema<S>& sc, const char* preset, S WorldConfig::*member, std::string (*context)(const std::string& key) = nullptr) {
  for (std::size_t k = 0; k < sc.count; ++k) {
    const Field<S>& f = sc.fields[k];
    double expect = 0;
    const std::string text = std::string(sc.section) + ": {name: " + preset + ", " + (context ? context(f.key) : std::string()) + f.key +
                             ": " + valid_yaml(f, expect) + "}\n";
    WorldConfig c;
    std::string err;
    ASSERT_TRUE(load_scenario_string(text, "s.yaml", c, err)) << text << err;
    expect_field(f, c.*member, expect, text);
    if (f.type == FieldType::real_number || (f.type == FieldType::integer && f.hi >= f.lo)) {
      const std::string bad_text = std::string(sc.section) + ": {name: " + preset + ", " + f.key + ": 1e12}\n";
      EXPECT_NE(error_of(bad_text).find(std::string(sc.section) + "." + f.key + ": expected"), std::string::npos) << bad_text;
    }
  }
}

/// The same for a nested section of task: `wrap` puts "key: value" inside the section's map, `get`
/// reads the struct back from the parsed config.
template <class S, class Wrap, class Get>
void every_nested_row(const Schema<S>& sc, Wrap wrap, Get get) {
  for (std::size_t k = 0; k < sc.count; ++k) {
    const Field<S>& f = sc.fields[k];
    double expect = 0;
    const std::string text = wrap(std::string(f.key) + ": " + valid_yaml(f, expect));
    WorldConfig c;
    std::string err;
    ASSERT_TRUE(load_scenario_string(text, "s.yaml", c, err)) << text << err;
    expect_field(f, get(c), expect, text);
    if (f.type == FieldType::real_number || (f.type == FieldType::integer && f.hi >= f.lo)) {
      const std::string bad_text = wrap(std::string(f.key) + ": 1e12");
      EXPECT_NE(error_of(bad_text).find(std::string(sc.section) + "." + f.key + ": expected"), std::string::npos) << bad_text;
    }
  }
}

}  // namespace

TEST(SimScenario, NestedTaskSectionsAreReachable) {
  const auto task = [](const std::string& inner) { return "task: {name: navigation_task, " + inner + "}\n"; };
  every_nested_row(
      curriculum_schema(), [&](const std::string& kv) { return task("curriculum: {" + kv + "}"); },
      [](const WorldConfig& c) -> const CurriculumConfig& { return c.task.curriculum; });
  every_nested_row(
      navigation_schema(), [&](const std::string& kv) { return task("navigation: {" + kv + "}"); },
      [](const WorldConfig& c) -> const NavigationConfig& { return c.task.navigation; });
  every_nested_row(
      navigation_reward_schema(), [&](const std::string& kv) { return task("navigation: {reward: {" + kv + "}}"); },
      [](const WorldConfig& c) -> const NavigationRewardParams& { return c.task.navigation.reward; });
  EXPECT_NE(error_of(task("navigation: {max_sped_m_s: 1}")).find("task.navigation.max_sped_m_s: unknown field"), std::string::npos);
  EXPECT_NE(error_of(task("navigation: {reward: 3}")).find("task.navigation.reward"), std::string::npos);
}

TEST(SimScenario, EverySchemaRowIsReachableUnderItsOwnName) {
  every_row(sim_schema(), "base_sim", &WorldConfig::sim);
  // total_num_envs must cover first_env_index + num_envs (the whole run a slice belongs to).
  every_row(env_schema(), "empty", &WorldConfig::env,
            [](const std::string& key) { return key == "total_num_envs" ? std::string("num_envs: 1, ") : std::string(); });
  every_row(robot_schema(), "base_quadrotor", &WorldConfig::robot);
  every_row(task_schema(), "position_setpoint", &WorldConfig::task);
  every_row(simulator_schema(), "rigid", &WorldConfig::simulator);
  every_row(controller_schema(), "lee_position_control", &WorldConfig::controller, [](const std::string& key) {
    // Widest ranges on every other gain and action bound, so the row's own value keeps min <= max.
    std::string ctx;
    for (const char* g : {"k_pos", "k_vel", "k_rot", "k_angvel"}) {
      if (key != std::string(g) + "_min") ctx += std::string(g) + "_min: [0, 0, 0], ";
      if (key != std::string(g) + "_max") ctx += std::string(g) + "_max: [1e6, 1e6, 1e6], ";
    }
    if (key != "action_min") ctx += "action_min: -1e6, ";
    if (key != "action_max") ctx += "action_max: 1e6, ";
    return ctx;
  });
}

TEST(SimScenario, OlderKeysStillRead) {
  WorldConfig a, b;
  std::string err;
  ASSERT_TRUE(load_scenario_string("env: {name: empty, collision_force_threshold: 2.5, lower_bound_min: [-7, -7, 0]}", "a", a, err)) << err;
  ASSERT_TRUE(load_scenario_string("env: {name: empty, collision_force_threshold_N: 2.5, lower_bound_min_m: [-7, -7, 0]}", "b", b, err)) << err;
  EXPECT_EQ(a.env.collision_force_threshold_N, 2.5_r);
  EXPECT_EQ(b.env.collision_force_threshold_N, 2.5_r);
  EXPECT_EQ(a.env.lower_bound_min_m, b.env.lower_bound_min_m);
  EXPECT_NE(error_of("env: {name: empty, collision_force_threshold: -1}").find("env.collision_force_threshold: expected a number in [0, "),
            std::string::npos);
}

TEST(SimScenario, ReferenceDocMatchesTheSchemas) {
  // docs/scenario_reference.md is generated (`kestrel schema > docs/scenario_reference.md`); a
  // schema change without regenerating it fails here.
  std::ifstream f(KESTREL_SIM_TEST_DIR "/../../docs/scenario_reference.md");
  ASSERT_TRUE(f.good());
  std::stringstream committed;
  committed << f.rdbuf();
  EXPECT_EQ(committed.str(), scenario_reference_markdown());
}

TEST(SimScenario, RegisterPresetAtRunTime) {
  std::string err;
  // Aerial Gym's "falling forwards" sim, registered from a section and then named by a scenario.
  ASSERT_TRUE(register_preset("sim", "test_falling_sideways", "{name: base_sim, gravity_w: [0, 5, -9.81], dt_s: 0.005}",
                              "gravity tilted towards +y", err))
      << err;
  WorldConfig c;
  ASSERT_TRUE(load_scenario_string("sim: test_falling_sideways\nenv: {name: empty, num_envs: 2}\n", "s.yaml", c, err)) << err;
  EXPECT_EQ(c.sim.gravity_w[1], 5.0_r);
  EXPECT_EQ(c.sim.dt_s, 0.005_r);
  EXPECT_EQ(c.sim.name, "test_falling_sideways");
  ASSERT_TRUE(register_preset("env", "test_small_forest", "{name: forest, num_envs: 3, curriculum_level: 0.5}", "", err)) << err;
  ASSERT_TRUE(load_scenario_string("env: test_small_forest\n", "s.yaml", c, err)) << err;
  EXPECT_EQ(c.env.num_envs, 3);
  EXPECT_FALSE(c.env.assets.empty());  // the forest's trees came with the base
  // Refusals name what was wrong and register nothing.
  EXPECT_FALSE(register_preset("sim", "test_falling_sideways", "base_sim", "", err));
  EXPECT_NE(err.find("the name is taken"), std::string::npos) << err;
  EXPECT_FALSE(register_preset("sim", "test_bad_dt", "{name: base_sim, dt_s: 5}", "", err));
  EXPECT_NE(err.find("register sim \"test_bad_dt\": sim.dt_s: expected a number in [1e-06, 1]"), std::string::npos) << err;
  EXPECT_FALSE(load_scenario_string("sim: test_bad_dt\n", "s.yaml", c, err));
  EXPECT_FALSE(register_preset("gizmo", "x", "{}", "", err));
  EXPECT_NE(err.find("kind: expected one of sim, env, robot"), std::string::npos) << err;
}

TEST(SimScenario, EverySensorRowIsReachableUnderItsOwnName) {
  // Each row of the lidar / ToF, camera and IMU schemas: a valid value under its key reaches the
  // sensor's config; a value out of range is refused naming sensors[0].key. `context` widens the
  // other side of each min / max pair so the row's own value keeps the rules between fields.
  const auto ray_context = [](const std::string& key, bool lidar) {
    std::string ctx;
    const std::pair<const char*, const char*> pairs[] = {{"min_range_m", "0"}, {"max_range_m", "1e4"}, {"horizontal_fov_deg_min", "-180"},
                                                         {"horizontal_fov_deg_max", "180"}, {"vertical_fov_deg_min", "-90"},
                                                         {"vertical_fov_deg_max", "90"}, {"min_translation_b_m", "[-100, -100, -100]"},
                                                         {"max_translation_b_m", "[100, 100, 100]"}, {"min_euler_deg", "[-360, -360, -360]"},
                                                         {"max_euler_deg", "[360, 360, 360]"}};
    for (const auto& p : pairs)
      if (key != p.first && (lidar || std::string(p.first).find("fov_deg_m") == std::string::npos)) ctx += std::string(p.first) + ": " + p.second + ", ";
    return ctx;
  };
  const auto rows = [&](const Schema<RaySensorFields>& sc, const char* preset, bool lidar) {
    for (std::size_t k = 0; k < sc.count; ++k) {
      const Field<RaySensorFields>& f = sc.fields[k];
      double expect = 0;
      const std::string text = std::string("sensors: [{name: ") + preset + ", " + ray_context(f.key, lidar) + f.key + ": " + valid_yaml(f, expect) + "}]\n";
      WorldConfig c;
      std::string err;
      ASSERT_TRUE(load_scenario_string(text, "s.yaml", c, err)) << text << err;
      expect_field(f, ray_sensor_fields(c.robot.sensors[0]), expect, text);
      if (f.type == FieldType::real_number || (f.type == FieldType::integer && f.hi >= f.lo)) {
        const std::string bad_text = std::string("sensors: [{name: ") + preset + ", " + f.key + ": 1e12}]\n";
        EXPECT_NE(error_of(bad_text).find(std::string("sensors[0].") + f.key + ": expected"), std::string::npos) << bad_text;
      }
    }
  };
  rows(lidar_sensor_schema(), "vl53l5cx", true);
  rows(camera_sensor_schema(), "d455", false);
  const Schema<ImuSensorFields>& imu = imu_sensor_schema();
  for (std::size_t k = 0; k < imu.count; ++k) {
    const Field<ImuSensorFields>& f = imu.fields[k];
    double expect = 0;
    std::string ctx;
    if (std::string(f.key) != "misalignment_min_deg") ctx += "misalignment_min_deg: [-180, -180, -180], ";
    if (std::string(f.key) != "misalignment_max_deg") ctx += "misalignment_max_deg: [180, 180, 180], ";
    const std::string text = "sensors: [{name: bmi088, " + ctx + f.key + ": " + valid_yaml(f, expect) + "}]\n";
    WorldConfig c;
    std::string err;
    ASSERT_TRUE(load_scenario_string(text, "s.yaml", c, err)) << text << err;
    expect_field(f, imu_sensor_fields(c.robot.sensors[0]), expect, text);
  }
}
