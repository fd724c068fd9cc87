// Scenario overrides of registry parameters (issue 19): sensor parameters, controller gains and
// reward constants reach the running world; bad values are refused naming the field, with nothing
// applied. URDF robots: `robot: {urdf: FILE}` alone, a centre of mass off the base origin, the
// thrust-to-weight refusal and the description of the robot flown.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/robot_model.hpp"
#include "kestrel/sim/scenario.hpp"
#include "kestrel/sim/schema.hpp"
#include "kestrel/sim/task.hpp"
#include "kestrel/sim/urdf.hpp"
#include "kestrel/sim/world.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {

const std::string kQuad = std::string(KESTREL_SIM_TEST_DIR) + "/data/quad.urdf";

WorldConfig load(const std::string& yaml) {
  WorldConfig c;
  std::string err;
  EXPECT_TRUE(load_scenario_string(yaml, "o.yaml", c, err)) << yaml << "\n" << err;
  return c;
}
std::string error_of(const std::string& yaml) {
  WorldConfig c;
  std::string err;
  EXPECT_FALSE(load_scenario_string(yaml, "o.yaml", c, err)) << yaml;
  return err;
}
std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path = std::string(::testing::TempDir()) + "/" + name;
  std::ofstream(path) << text;
  return path;
}

// A down-looking VL53L5CX (8 x 8, 90 x 90 deg) at 1.5 m over the ground plane: the centre pixels
// see the ground at ~1.5 m, the corners (60 deg off the vertical) at 3 m.
std::vector<real> tof_image(const std::string& overrides) {
  const std::string yaml =
      "env: {name: empty, num_envs: 1}\ntask: hover\n"
      "sensors: [{name: vl53l5cx, enable_sensor_noise: false, randomize_placement: false, fixed_pose_at_range_mean: false, "
      "nominal_position_b_m: [0, 0, 0], nominal_euler_deg: [0, 90, 0]" +
      overrides + "}]\n";
  const WorldConfig c = load(yaml);
  std::string err;
  auto w = World::create(c, err);
  EXPECT_TRUE(w) << err;
  if (!w) return {};
  RigidBodyState& st = w->robot_state(0, 0);
  st.position_w = Vec3(0, 0, 1.5_r);
  st.orientation_wb = Quat::Identity();
  w->render_sensors(0);
  const int n = w->sensor_height(0) * w->sensor_width(0);
  return std::vector<real>(w->sensor_ranges(0, 0), w->sensor_ranges(0, 0) + n);
}

}  // namespace

// ---- sensors ------------------------------------------------------------------------------------

TEST(SimOverrides, SensorKeysReachTheSensorConfig) {
  const WorldConfig c = load(
      "sensors: [{name: vl53l5cx, every: 2, max_range_m: 3.0, min_range_m: 0.1, noise_model: range_dependent, noise_c: 0.01, "
      "pixel_dropout_prob: 0.05, width: 4, height: 6}, {name: d455, horizontal_fov_deg: 60, calculate_depth: false}, "
      "{name: bmi088, gyro_noise_density: [1e-3, 1e-3, 2e-3], enable_bias: false}]\n");
  ASSERT_EQ(c.robot.sensors.size(), 3u);
  const SensorConfig& tof = c.robot.sensors[0];
  EXPECT_EQ(tof.every_env_steps, 2);
  EXPECT_EQ(tof.lidar.range.max_range, 3.0_r);
  EXPECT_EQ(tof.lidar.range.min_range, 0.1_r);
  EXPECT_EQ(tof.lidar.noise.model, sensors::NoiseParams::Model::range_dependent);
  EXPECT_EQ(tof.lidar.noise.c, 0.01_r);
  EXPECT_EQ(tof.lidar.noise.pixel_dropout_prob, 0.05_r);
  EXPECT_EQ(tof.lidar.width, 4u);
  EXPECT_EQ(tof.lidar.height, 6u);
  EXPECT_EQ(tof.lidar.horizontal_fov_deg_max, 45);  // untouched keys keep the preset's values
  EXPECT_EQ(c.robot.sensors[1].camera.horizontal_fov_deg, 60);
  EXPECT_FALSE(c.robot.sensors[1].camera.calculate_depth);
  EXPECT_EQ(c.robot.sensors[2].imu.gyro_noise_density[2], 2e-3_r);
  EXPECT_FALSE(c.robot.sensors[2].imu.enable_bias);
}

TEST(SimOverrides, TofMaxRangeOverrideChangesTheMeasuredRanges) {
  const std::vector<real> dflt = tof_image("");                       // preset: 0.2-4 m
  const std::vector<real> near = tof_image(", max_range_m: 2.0");     // beyond 2 m: far value (-1)
  const std::vector<real> wide = tof_image(", width: 4, height: 4");  // resolution reaches the image
  ASSERT_EQ(dflt.size(), 64u);
  ASSERT_EQ(near.size(), 64u);
  EXPECT_EQ(wide.size(), 16u);
  int beyond = 0;
  for (std::size_t i = 0; i < dflt.size(); ++i) {
    ASSERT_GT(dflt[i], 1.49_r) << i;  // every pixel sees the ground within 4 m
    ASSERT_LT(dflt[i], 3.01_r) << i;
    if (dflt[i] > 2.0_r) {
      ++beyond;
      EXPECT_EQ(near[i], -1) << i;  // the override's far_out_of_range_value
    } else {
      EXPECT_EQ(near[i], dflt[i]) << i;
    }
  }
  EXPECT_GT(beyond, 8);
}

TEST(SimOverrides, BadSensorValuesAreRefusedNamingTheField) {
  EXPECT_NE(error_of("sensors: [{name: vl53l5cx, max_range_m: -3}]").find("o.yaml: sensors[0].max_range_m: expected a number in [0.001, 10000]"),
            std::string::npos);
  EXPECT_NE(error_of("sensors: [{name: vl53l5cx, max_range_m: 0.1}]").find("sensors[0].min_range_m: expected < max_range_m"), std::string::npos);
  EXPECT_NE(error_of("sensors: [{name: vl53l5cx, noise_model: gaussian}]")
                .find("sensors[0].noise_model: expected one of none, range_dependent, multiplier, got \"gaussian\""),
            std::string::npos);
  EXPECT_NE(error_of("sensors: [{name: vl53l5cx, width: 0}]").find("sensors[0].width: expected an integer in [1, 4096] (kMaxSensorSide)"),
            std::string::npos);
  // Unknown keys: refused with the keys the sensor's kind allows (a camera key on a lidar too).
  const std::string e = error_of("sensors: [{name: vl53l5cx, horizontal_fov_deg: 60}]");
  EXPECT_NE(e.find("sensors[0].horizontal_fov_deg: unknown field; allowed: name, every_env_steps, height, width, horizontal_fov_deg_min"),
            std::string::npos)
      << e;
  EXPECT_NE(error_of("sensors: [{name: base_imu, max_range_m: 3}]").find("sensors[0].max_range_m: unknown field; allowed: name, every_env_steps, "
                                                                         "accel_noise_density"),
            std::string::npos);
  // Registering a sensor preset goes through the same rows.
  std::string err;
  ASSERT_TRUE(register_preset("sensor", "test_short_tof", "{name: vl53l5cx, max_range_m: 1.5}", "", err)) << err;
  EXPECT_EQ(load("sensors: [test_short_tof]\n").robot.sensors[0].lidar.range.max_range, 1.5_r);
  EXPECT_FALSE(register_preset("sensor", "test_bad_tof", "{name: vl53l5cx, pixel_dropout_prob: 2}", "", err));
  EXPECT_NE(err.find("sensor.pixel_dropout_prob: expected a number in [0, 1]"), std::string::npos) << err;
  // A config built in code is checked by the same table when a world is built.
  WorldConfig c = load("env: {name: empty, num_envs: 1}\nsensors: [vl53l5cx]\n");
  c.robot.sensors[0].lidar.noise.pixel_dropout_prob = 3;
  EXPECT_FALSE(World::create(c, err));
  EXPECT_NE(err.find("sensors.vl53l5cx.pixel_dropout_prob"), std::string::npos) << err;
}

// ---- controller ---------------------------------------------------------------------------------

TEST(SimOverrides, GainOverridesReachTheControllerAndChangeTheFlight) {
  const std::string base = "env: {name: empty, num_envs: 4}\ntask: position_setpoint\nseed: 3\n";
  const WorldConfig d = load(base + "controller: lee_position_control\n");
  const WorldConfig g = load(base + "controller: {name: lee_position_control, k_pos: [6, 6, 4], k_vel_min: [3, 3, 3], k_vel_max: [5, 5, 5], "
                                    "max_yaw_rate_rad_s: 0.5}\n");
  std::string err;
  auto wd = World::create(d, err);
  ASSERT_TRUE(wd) << err;
  auto wg = World::create(g, err);
  ASSERT_TRUE(wg) << err;
  const LeeParams& lee = wg->model().mr.ctrl.lee;
  EXPECT_EQ(lee.gain_ranges.min.k_pos, Vec3(6, 6, 4));
  EXPECT_EQ(lee.gain_ranges.max.k_pos, Vec3(6, 6, 4));
  EXPECT_EQ(lee_nominal_gains(lee.gain_ranges).k_vel, Vec3(4, 4, 4));  // the midpoint flies
  EXPECT_EQ(lee.max_yaw_rate_radps, 0.5_r);
  // The defaults are Aerial Gym's preset, unchanged.
  const LeeParams ref = lee_params_base_quadrotor();
  EXPECT_EQ(wd->model().mr.ctrl.lee.gain_ranges.min.k_pos, ref.gain_ranges.min.k_pos);
  EXPECT_EQ(wd->model().mr.ctrl.lee.gain_ranges.max.k_angvel, ref.gain_ranges.max.k_angvel);
  // Same seed, same starts and targets: only the gains differ, and the flight with them.
  EXPECT_EQ(wd->robot_state(0, 0).position_w, wg->robot_state(0, 0).position_w);
  wd->step(40);
  wg->step(40);
  EXPECT_NE(wd->state_hash(), wg->state_hash());
  EXPECT_GT((wd->robot_state(0, 0).position_w - wg->robot_state(0, 0).position_w).norm(), 1e-3_r);
}

TEST(SimOverrides, BadGainsAreRefusedNamingTheField) {
  const std::string c = "controller: {name: lee_position_control, ";
  EXPECT_NE(error_of(c + "k_pos: [-1, 2, 2]}").find("o.yaml: controller.k_pos[0]: expected a number in [0, 1e+06]"), std::string::npos);
  EXPECT_NE(error_of(c + "k_pos: [1, 2]}").find("controller.k_pos: expected a list of 3 numbers"), std::string::npos);
  EXPECT_NE(error_of(c + "k_pos: [1, 2, 3], k_pos_min: [1, 1, 1]}").find("controller.k_pos: give either k_pos"), std::string::npos);
  EXPECT_NE(error_of(c + "k_rot_min: [5, 5, 5]}").find("controller.k_rot_min: expected <= k_rot_max on every axis"), std::string::npos);
  EXPECT_NE(error_of(c + "k_vel_max: [1e7, 1, 1]}").find("controller.k_vel_max[0]: expected a number in [0, 1e+06]"), std::string::npos);
  EXPECT_NE(error_of(c + "action_min: 20}").find("controller.action_min: expected < action_max"), std::string::npos);
  const std::string e = error_of(c + "kp: [1, 1, 1]}");
  EXPECT_NE(e.find("controller.kp: unknown field; allowed: name, randomize_gains, k_pos_min, k_pos_max"), std::string::npos) << e;
  EXPECT_NE(e.find("k_angvel"), std::string::npos) << e;
}

// ---- reward -------------------------------------------------------------------------------------

TEST(SimOverrides, RewardOverrideChangesTheRewardByTheExpectedAmount) {
  const std::string base = "env: {name: empty, num_envs: 16}\nseed: 5\n";
  const WorldConfig d = load(base + "task: position_setpoint_task\n");
  const WorldConfig o = load(base + "task: {name: position_setpoint_task, reward: {distance_reward_offset_m: 30, crash_reward: -50}}\n");
  EXPECT_EQ(o.task.reward.distance_reward_offset_m, 30.0_r);
  EXPECT_EQ(o.task.reward.crash_reward, -50.0_r);
  std::string err;
  auto td = make_task(d, err);
  ASSERT_TRUE(td) << err;
  auto to = make_task(o, err);
  ASSERT_TRUE(to) << err;
  std::vector<float> zero(static_cast<std::size_t>(td->num_envs() * td->action_dim()), 0.0f);
  int compared = 0;
  for (int step = 0; step < 5; ++step) {
    td->step(zero.data());
    to->step(zero.data());
    for (int e = 0; e < td->num_envs(); ++e) {
      // dist = (offset - d) / 40: +10 m of offset is +0.25 on every step that is not a crash.
      const float rd = td->rewards()[e], ro = to->rewards()[e];
      if (rd == -20.0f) {
        EXPECT_EQ(ro, -50.0f) << e;
      } else {
        EXPECT_NEAR(ro - rd, 0.25f, 2e-5f) << e;
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 0);
  // The pure function: the defaults give the reference's bits; a spin magnitude of 0 removes pos x spin.
  const float e3[3] = {0.3f, -0.2f, 0.1f}, q[4] = {0.05f, -0.02f, 0.1f, 0.9933f}, w[3] = {0.4f, 0.1f, -0.3f};
  std::uint8_t c0 = 0, c1 = 0, c2 = 0;
  PositionSetpointRewardParams p;
  EXPECT_EQ(position_setpoint_reward(e3, q, w, 1.0f, c0), position_setpoint_reward(e3, q, w, 1.0f, c1, p));
  p.spin_reward_magnitude = 0;
  const float d2 = 0.3f * 0.3f + 0.2f * 0.2f + 0.1f * 0.1f;
  const float pos = 3.0f * std::exp(-8.0f * d2) + 2.0f * std::exp(-4.0f * d2);
  const float spin = 3.0f / (1.0f + 0.4f * 0.4f + 0.1f * 0.1f + 0.3f * 0.3f);
  EXPECT_NEAR(position_setpoint_reward(e3, q, w, 1.0f, c0) - position_setpoint_reward(e3, q, w, 1.0f, c2, p), pos * spin, 1e-5f);
}

TEST(SimOverrides, RewardKeysFollowTheTaskAndBadOnesAreRefused) {
  EXPECT_EQ(load("task: {name: navigation_task, reward: {collision_penalty: -50}}\n").task.navigation.reward.collision_penalty, -50.0_r);
  EXPECT_NE(error_of("task: {name: position_setpoint_task, reward: {distance_reward_divisor_m: 0}}")
                .find("task.reward.distance_reward_divisor_m: expected a number in [1e-06, 1e+06]"),
            std::string::npos);
  EXPECT_NE(error_of("task: {name: position_setpoint_task, reward: {crash_rewrd: 1}}")
                .find("task.reward.crash_rewrd: unknown field; allowed: name, pos_reward_magnitude_1"),
            std::string::npos);
  EXPECT_NE(error_of("task: {name: navigation_task, reward: {crash_reward: 1}}").find("task.reward.crash_reward: unknown field; allowed: name, pos_reward_magnitude"),
            std::string::npos);
  EXPECT_NE(error_of("task: {name: goal_box_through_gap, reward: {crash_reward: 1}}").find("task.reward: task goal_box_through_gap builds its reward"),
            std::string::npos);
}

TEST(SimOverrides, NothingIsHalfApplied) {
  WorldConfig c = load("controller: {name: lee_position_control, k_pos: [5, 5, 5]}\n");
  std::string err;
  // A good controller section and a bad sensor: refused, and `c` keeps what it held.
  EXPECT_FALSE(load_scenario_string("controller: {name: lee_position_control, k_pos: [1, 1, 1]}\nsensors: [{name: vl53l5cx, max_range_m: 0}]\n",
                                    "o.yaml", c, err));
  EXPECT_EQ(c.controller.k_pos_min, Vec3(5, 5, 5));
  EXPECT_TRUE(c.robot.sensors.empty());
}

// ---- URDF robots --------------------------------------------------------------------------------

namespace {
// A 0.25 kg quad whose 0.05 kg payload hangs 5 cm forward of the base link origin (centre of mass
// 1 cm forward: `base_x`, `payload_x` and the rotor hubs' x offset `rotor_dx` place them).
std::string offset_quad(double base_x, double payload_x, double rotor_dx) {
  auto num = [](double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.6f", v);
    return std::string(b);
  };
  std::string x = "<?xml version=\"1.0\"?>\n<robot name=\"offset_quad\">\n<link name=\"base_link\"><inertial><origin xyz=\"" + num(base_x) +
                  " 0 0\"/><mass value=\"0.2\"/><inertia ixx=\"8e-4\" ixy=\"0\" ixz=\"0\" iyy=\"8e-4\" iyz=\"0\" izz=\"1.6e-3\"/></inertial>"
                  "<collision><geometry><sphere radius=\"0.2\"/></geometry></collision></link>\n"
                  "<link name=\"payload\"><inertial><mass value=\"0.05\"/><inertia ixx=\"1e-5\" ixy=\"0\" ixz=\"0\" iyy=\"1e-5\" iyz=\"0\" "
                  "izz=\"1e-5\"/></inertial></link>\n<joint name=\"pj\" type=\"fixed\"><parent link=\"base_link\"/><child link=\"payload\"/>"
                  "<origin xyz=\"" +
                  num(payload_x) + " 0 0\"/></joint>\n";
  const double px[4] = {0.1, -0.1, -0.1, 0.1}, py[4] = {-0.1, -0.1, 0.1, 0.1};
  const char* axis[4] = {"0 0 1", "0 0 -1", "0 0 1", "0 0 -1"};
  for (int k = 0; k < 4; ++k) {
    const std::string n = std::to_string(k);
    x += "<link name=\"rotor_" + n + "\"/><joint name=\"r" + n + "\" type=\"continuous\"><parent link=\"base_link\"/><child link=\"rotor_" + n +
         "\"/><origin xyz=\"" + num(px[k] + rotor_dx) + " " + num(py[k]) + " 0\"/><axis xyz=\"" + axis[k] + "\"/></joint>\n";
  }
  return x + "</robot>\n";
}
}  // namespace

TEST(SimOverrides, UrdfWithOffsetCentreOfMassIsReexpressedAboutIt) {
  // A: the file's frame at the base link, centre of mass 1 cm forward of it. B: the same body
  // written with its origin at the centre of mass (base 1 cm back, payload at 4 cm, rotors 1 cm back).
  UrdfRobot a, b;
  std::string err;
  ASSERT_TRUE(load_urdf(write_temp("offset_a.urdf", offset_quad(0, 0.05, 0)), a, err)) << err;
  ASSERT_TRUE(load_urdf(write_temp("offset_b.urdf", offset_quad(-0.01, 0.04, -0.01)), b, err)) << err;
  EXPECT_NEAR(a.com_offset_m[0], 0.01, 1e-7);
  EXPECT_NEAR(b.com_offset_m.norm(), 0, 1e-7);
  EXPECT_NEAR(a.mass_kg, b.mass_kg, 1e-7);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(a.inertia_diag_kg_m2[k], b.inertia_diag_kg_m2[k], 1e-9) << k;
  // Parallel axis about the centre of mass: iyy = 8e-4 + 1e-5 + 0.2 * 0.01^2 + 0.05 * 0.04^2.
  EXPECT_NEAR(a.inertia_diag_kg_m2[1], 8e-4 + 1e-5 + 0.2 * 1e-4 + 0.05 * 0.0016, 1e-9);
  ASSERT_EQ(a.rotors.size(), 4u);
  for (int m = 0; m < 4; ++m)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(a.rotors[m].position_b_m[k], b.rotors[m].position_b_m[k], 1e-7) << m << k;
  EXPECT_NEAR(a.rotors[0].position_b_m[0], 0.09, 1e-7);  // 0.1 from the base origin = 0.09 from the centre of mass
}

TEST(SimOverrides, UrdfWithOffsetCentreOfMassHoversLevel) {
  const std::string path = write_temp("offset_fly.urdf", offset_quad(0, 0.05, 0));
  const WorldConfig c = load("env: {name: empty, num_envs: 4}\nrobot: {urdf: " + path + ", quadratic_drag_b: [0.01, 0.01, 0.01]}\ntask: hover\n");
  std::string err;
  auto w = World::create(c, err);
  ASSERT_TRUE(w) << err;
  w->step(300);
  EXPECT_EQ(w->summary().crashes, 0u);
  EXPECT_LT(w->summary().final_mean_distance_m, 0.05);
  for (int e = 0; e < 4; ++e) {
    const RigidBodyState& s = w->robot_state(e, 0);
    const Vec3 up = s.orientation_wb * Vec3::UnitZ();
    EXPECT_GT(up[2], std::cos(1.0 * kPi / 180)) << e;  // level within 1 deg
    EXPECT_LT(s.angvel_b.norm(), 0.05_r) << e;
    // The allocation carries the offset: front rotors (0, 3; 9 cm arm) lift more than the rear
    // ones (1, 2; 11 cm arm), in the ratio of the arms.
    const auto& m = w->motor_state(e, 0);
    EXPECT_NEAR(m.thrust_N[0] / m.thrust_N[1], 0.11 / 0.09, 0.02) << e;
    EXPECT_NEAR(m.thrust_N[3] / m.thrust_N[2], 0.11 / 0.09, 0.02) << e;
  }
}

TEST(SimOverrides, UrdfRobotWithoutNameStartsFromTheBaseQuadrotor) {
  const WorldConfig c = load("env: {name: empty, num_envs: 2}\nrobot: {urdf: " + kQuad + "}\ntask: hover\n");
  EXPECT_EQ(c.robot.name, "sample_quad");  // the URDF's <robot name>
  EXPECT_NEAR(c.robot.mass_kg, 0.25, 1e-7);
  EXPECT_EQ(c.robot.rotors.size(), 4u);
  EXPECT_EQ(c.robot.airframe, allocation::AirframePreset::base_quadrotor);
  std::string err;
  auto w = World::create(c, err);
  ASSERT_TRUE(w) << err;
  w->step(200);
  EXPECT_EQ(w->summary().crashes, 0u);
  // With other motors: the airframe key picks the preset whose limits the URDF rotors get.
  EXPECT_EQ(load("robot: {urdf: " + kQuad + ", airframe: x500}\n").robot.airframe, allocation::AirframePreset::x500);
}

TEST(SimOverrides, ThrustToWeightBelowOneIsRefusedAndTheRobotFlownIsDescribed) {
  const WorldConfig heavy = load("env: {name: empty, num_envs: 1}\nrobot: {urdf: " + kQuad + ", mass_kg: 0.97}\ntask: hover\n");
  std::string err;
  EXPECT_FALSE(World::create(heavy, err));
  EXPECT_NE(err.find("robot: thrust-to-weight ratio 0.84 < 1: sample_quad: mass 0.97 kg"), std::string::npos) << err;
  EXPECT_NE(err.find("4 rotors (URDF geometry, 4 x 2 N), max thrust 8 N, weight 9.516 N, T/W 0.84"), std::string::npos) << err;
  EXPECT_NE(err.find("robot.airframe"), std::string::npos) << err;
  // The same robot on x500 motors (4 x 10 N) flies.
  const WorldConfig x500 = load("env: {name: empty, num_envs: 1}\nrobot: {urdf: " + kQuad + ", mass_kg: 0.97, airframe: x500}\ntask: hover\n");
  EXPECT_TRUE(World::create(x500, err)) << err;
  EXPECT_NE(describe_robot(x500).find("T/W 4.20"), std::string::npos) << describe_robot(x500);
  const std::string d = describe_robot(load("robot: base_quadrotor\n"));
  EXPECT_NE(d.find("base_quadrotor: mass 0.25 kg, inertia diag [0.000845, 0.000845, 0.00169] kg m^2, 4 rotors (airframe preset, 4 x 2 N), "
                   "max thrust 8 N, weight 2.453 N, T/W 3.26"),
            std::string::npos)
      << d;
}
