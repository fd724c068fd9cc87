#include <gtest/gtest.h>

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
            "scenario.yaml: env.num_envs: expected a positive integer, got \"-3\"");
  EXPECT_EQ(error_of("robot: quadx"), "scenario.yaml: robot: unknown robot \"quadx\"; known: base_quadrotor, ground_vehicle, hexarotor, x500");
  EXPECT_NE(error_of("env: nowhere").find("known: dynamic, empty, env_with_obstacles, forest, goal_box_room, lidar_navigation"), std::string::npos);
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
