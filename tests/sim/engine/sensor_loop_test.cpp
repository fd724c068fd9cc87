// Sensors in the loop: registry entries, scenario parsing, analytic ranges in known scenes, moving
// obstacles seen at their new place, determinism over thread counts, no heap in the step with a
// camera attached, PNG output sizes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <sys/stat.h>

#include "heap_counter.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/output.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/scenario.hpp"
#include "kestrel/sim/world.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {
SensorConfig sensor(const char* name) {
  SensorConfig s;
  EXPECT_TRUE(registries().sensors.make(name, s)) << name;
  return s;
}
// Exact mount at the body origin, no noise, metres (not normalised): the analytic value is the
// rendered one.
SensorConfig exact_camera() {
  SensorConfig s = sensor("base_depth_camera");
  s.camera.mount = sensors::MountParams();
  s.camera.noise.enable_sensor_noise = false;
  s.camera.range.normalize_range = false;
  s.camera.range.set_default_out_of_range_values();
  return s;
}
std::unique_ptr<World> build(const WorldConfig& c) {
  std::string err;
  auto w = World::create(c, err);
  EXPECT_TRUE(w) << err;
  return w;
}
// One robot starting at a known point (ratio 0.5, 0.5, 0.5 of the empty env: (0, 0, 2.5)), yaw 0.
WorldConfig known_start(int num_envs = 1) {
  WorldConfig c;
  EXPECT_TRUE(registries().envs.make("empty", c.env));
  c.env.num_envs = num_envs;
  c.robot.min_init_position_ratio = c.robot.max_init_position_ratio = Vec3(0.5_r, 0.5_r, 0.5_r);
  c.robot.max_init_yaw_rad = 0;
  c.task.kind = TaskKind::hover;
  c.seed = 7;
  return c;
}
real centre(const World& w, int sensor) {
  return w.sensor_ranges(0, sensor)[static_cast<std::size_t>(w.sensor_height(sensor) / 2) * static_cast<std::size_t>(w.sensor_width(sensor)) +
                                    static_cast<std::size_t>(w.sensor_width(sensor) / 2)];
}
std::uint32_t be32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | std::uint32_t{p[3]};
}
}  // namespace

TEST(SimSensors, BuiltinsRegisteredAndUnknownListed) {
  for (const char* n : {"osdome_64", "os0_128", "base_depth_camera", "d455", "vl53l5cx", "base_imu", "bmi088"})
    EXPECT_TRUE(registries().sensors.has(n)) << n;
  EXPECT_EQ(sensor("d455").kind, SensorKind::camera);
  EXPECT_EQ(sensor("vl53l5cx").kind, SensorKind::lidar);
  EXPECT_EQ(sensor("bmi088").kind, SensorKind::imu);
  WorldConfig c;
  std::string err;
  ASSERT_TRUE(load_scenario_string("sensors: [base_depth_camera, {name: vl53l5cx, every: 2}, base_imu]\n", "t", c, err)) << err;
  ASSERT_EQ(c.robot.sensors.size(), 3u);
  EXPECT_EQ(c.robot.sensors[0].name, "base_depth_camera");
  EXPECT_EQ(c.robot.sensors[0].every_env_steps, 1);
  EXPECT_EQ(c.robot.sensors[1].name, "vl53l5cx");
  EXPECT_EQ(c.robot.sensors[1].every_env_steps, 2);
  EXPECT_FALSE(load_scenario_string("sensors: [kinect]\n", "t", c, err));
  EXPECT_NE(err.find("unknown sensors \"kinect\"; known: "), std::string::npos) << err;
  EXPECT_NE(err.find("d455"), std::string::npos) << err;
  EXPECT_FALSE(load_scenario_string("sensors: [{name: d455, every: 0}]\n", "t", c, err));
  EXPECT_NE(err.find("every"), std::string::npos) << err;
  EXPECT_FALSE(load_scenario_string("sensors: [{name: d455, rate: 3}]\n", "t", c, err));
  EXPECT_NE(err.find("unknown field"), std::string::npos) << err;
}

TEST(SimSensors, DownLookingCameraSeesGroundAtItsHeight) {
  WorldConfig c = known_start();
  SensorConfig cam = exact_camera();
  cam.camera.mount.nominal_euler_deg = Vec3(0, 90, 0);  // pitch +90 deg: the optical axis points down
  c.robot.sensors.push_back(cam);
  auto w = build(c);
  RigidBodyState& st = w->robot_state(0, 0);
  st.position_w = Vec3(0.3_r, -0.2_r, 1.75_r);
  st.orientation_wb = Quat::Identity();
  w->render_sensors(0);
  EXPECT_NEAR(centre(*w, 0), 1.75_r, 1e-4_r);
  EXPECT_EQ(w->sensor_segmentation(0, 0)[static_cast<std::size_t>(w->sensor_height(0) / 2) * static_cast<std::size_t>(w->sensor_width(0))], 0);
}

TEST(SimSensors, BoxInFrontAtKnownDistanceThenMovingBoxSeenAtNewPlace) {
  WorldConfig c = known_start();
  AssetClass box;
  box.name = "box";
  box.kind = AssetKind::cube;
  box.num_assets = box.min_num_assets = 1;
  box.min_position_ratio = box.max_position_ratio = Vec3(0.8_r, 0.5_r, 0.5_r);  // (3, 0, 2.5)
  box.min_size_m = box.max_size_m = Vec3(1, 1, 1);                                // half extent 0.5
  box.semantic_id = 9;
  c.env.assets.push_back(box);
  c.robot.sensors.push_back(exact_camera());
  SensorConfig lidar = sensor("os0_128");
  lidar.lidar.mount = sensors::MountParams();
  lidar.lidar.noise.enable_sensor_noise = false;
  c.robot.sensors.push_back(lidar);
  auto w = build(c);
  ASSERT_EQ(w->num_obstacles(0), 1);
  const Vec3 p0 = w->robot_state(0, 0).position_w;
  ASSERT_NEAR(p0[0], 0, 1e-6);
  // At reset (the start is (0, 0, 2.5)), the box face is at x = 2.5.
  EXPECT_NEAR(centre(*w, 0), 2.5_r, 1e-4_r);
  EXPECT_EQ(w->sensor_segmentation(0, 0)[static_cast<std::size_t>(w->sensor_height(0) / 2) * static_cast<std::size_t>(w->sensor_width(0)) +
                                         static_cast<std::size_t>(w->sensor_width(0) / 2)],
            9);
  // OS0-128 is normalised by 35 m; its middle row looks horizontally, column W/2 straight ahead
  // (azimuth runs from +180 to -180 deg, so W/2 of an even width is 180/255.5 deg off: still the face).
  EXPECT_NEAR(w->sensor_ranges(0, 1)[64 * 512 + 256] * 35, 2.5_r, 0.02_r);
  // Move the box towards the robot at 5 m/s: after one env-step (one 0.01 s physics step) the
  // image shows it 5 cm closer (the hovering robot moves by far less than a millimetre).
  w->obstacle(0, 0).linvel_w = Vec3(-5, 0, 0);
  w->step(1);
  const real expected = w->obstacle(0, 0).shape.position_w[0] - 0.5_r - w->robot_state(0, 0).position_w[0];
  EXPECT_NEAR(w->obstacle(0, 0).shape.position_w[0], 2.95_r, 1e-5_r);
  EXPECT_NEAR(centre(*w, 0), expected, 2e-3_r);
  EXPECT_LT(centre(*w, 0), 2.46_r);
}

TEST(SimSensors, ImuMeasuresSpecificForceWhileHovering) {
  WorldConfig c = known_start();
  SensorConfig imu = sensor("base_imu");
  imu.imu.enable_noise = false;
  imu.imu.enable_bias = false;
  imu.imu.misalignment_min_deg = imu.imu.misalignment_max_deg = Vec3::Zero();
  c.robot.sensors.push_back(imu);
  auto w = build(c);
  w->step(50);
  const sensors::ImuSample& s = w->imu_sample(0, 0);
  // Hovering: the specific force balances gravity, +g along body z.
  EXPECT_NEAR(s.accel_s[2], kStandardGravity, 0.3_r);
  EXPECT_NEAR(s.accel_s[0], 0, 0.3_r);
  EXPECT_EQ(w->sensor_ranges(0, 0), nullptr);
}

TEST(SimSensors, HashIdenticalFor1_2_4ThreadsWithSensors) {
  std::uint64_t h[3] = {};
  const int threads[3] = {1, 2, 4};
  for (int t = 0; t < 3; ++t) {
    WorldConfig c;
    ASSERT_TRUE(registries().envs.make("dynamic", c.env));
    c.env.num_envs = 9;
    c.seed = 3;
    c.num_threads = threads[t];
    c.robot.sensors.push_back(sensor("vl53l5cx"));   // noisy ToF, randomised nothing
    c.robot.sensors.push_back(sensor("base_imu"));   // noisy IMU
    SensorConfig cam = sensor("base_depth_camera");  // randomised mount
    cam.every_env_steps = 3;
    c.robot.sensors.push_back(cam);
    auto w = build(c);
    w->step(40);
    h[t] = w->state_hash();
  }
  EXPECT_EQ(h[0], h[1]);
  EXPECT_EQ(h[0], h[2]);
}

TEST(SimSensors, NoHeapInsideStepWithCamera) {
  for (const char* env : {"forest", "dynamic"}) {
    WorldConfig c;
    ASSERT_TRUE(registries().envs.make(env, c.env));
    c.env.num_envs = 4;
    c.task.episode_len_env_steps = 60;  // timeouts: resets and new layouts inside the counted steps
    c.robot.sensors.push_back(sensor("base_depth_camera"));
    c.robot.sensors.push_back(sensor("bmi088"));
    auto w = build(c);
    kestrel::test::HeapCounter counter;
    w->step(150);  // includes resets and new layouts
    EXPECT_EQ(counter.allocations(), 0u) << env;
    EXPECT_GT(w->summary().resets, 0u) << env;
  }
}

TEST(SimSensors, PngFilesHaveTheSensorSize) {
  WorldConfig c;
  ASSERT_TRUE(registries().envs.make("forest", c.env));
  c.env.num_envs = 3;
  c.robot.sensors.push_back(sensor("base_depth_camera"));
  c.robot.sensors.push_back(sensor("vl53l5cx"));
  c.robot.sensors.push_back(sensor("base_imu"));
  auto w = build(c);
  w->step(5);
  const std::string dir = std::string(::testing::TempDir()) + "/kestrel_sensor_png";
  ::mkdir(dir.c_str(), 0755);
  std::vector<std::string> written;
  std::string err;
  ASSERT_TRUE(write_sensor_pngs(*w, 2, dir, written, err)) << err;
  ASSERT_EQ(written.size(), 4u);
  EXPECT_EQ(written[0], dir + "/sensor_base_depth_camera_depth.png");
  EXPECT_EQ(written[1], dir + "/sensor_base_depth_camera_segmentation.png");
  EXPECT_EQ(written[2], dir + "/sensor_vl53l5cx_range.png");
  const std::uint32_t sizes[4][2] = {{240, 135}, {240, 135}, {8, 8}, {8, 8}};
  for (std::size_t i = 0; i < 4; ++i) {
    std::FILE* f = std::fopen(written[i].c_str(), "rb");
    ASSERT_NE(f, nullptr) << written[i];
    unsigned char hdr[24] = {};
    ASSERT_EQ(std::fread(hdr, 1, 24, f), 24u);
    std::fclose(f);
    EXPECT_EQ(hdr[1], 'P');
    EXPECT_EQ(be32(hdr + 16), sizes[i][0]) << written[i];  // IHDR width
    EXPECT_EQ(be32(hdr + 20), sizes[i][1]) << written[i];  // IHDR height
  }
  EXPECT_FALSE(write_sensor_pngs(*w, 3, dir, written, err));
}
