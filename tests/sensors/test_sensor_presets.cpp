// Presets against the numbers of Aerial Gym's sensor config classes
// (github.com/ntnu-arl/aerial_gym_simulator, aerial_gym/config/sensor_config/; commits in
// ray_sensor.hpp / imu.hpp), including the values a subclass inherits, and the warp-sensor mount
// rule for non-randomised sensors.
#include <cmath>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sensors/imu.hpp"
#include "kestrel/sensors/ray_sensor.hpp"
#include "ktest.hpp"

using namespace kestrel;
using namespace kestrel::sensors;

KTEST(SensorPresets, LidarsMatchAerialGymConfigs) {
  const LidarParams d = lidar_preset_osdome_64();  // osdome_64_config.py
  KEXPECT_EQ(d.height, 64u);
  KEXPECT_EQ(d.width, 512u);
  KEXPECT_EQ(d.horizontal_fov_deg_min, -180);
  KEXPECT_EQ(d.horizontal_fov_deg_max, 180);
  KEXPECT_EQ(d.vertical_fov_deg_min, 0);
  KEXPECT_EQ(d.vertical_fov_deg_max, 90);
  KEXPECT_EQ(d.range.min_range, 0.5_r);
  KEXPECT_EQ(d.range.max_range, 20);
  KEXPECT_TRUE(d.range.normalize_range);
  KEXPECT_EQ(d.range.far_out_of_range_value, 10);  // inherited from BaseLidarConfig (max 10)
  KEXPECT_EQ(d.range.near_out_of_range_value, -10);
  KEXPECT_TRUE(d.output.segmentation_camera);
  KEXPECT_FALSE(d.output.return_pointcloud);
  KEXPECT_FALSE(d.mount.randomize_placement);
  KEXPECT_FALSE(d.noise.enable_sensor_noise);
  KEXPECT_EQ(d.noise.a, 0.00038089_r);
  KEXPECT_EQ(d.noise.b, -0.00343351_r);
  KEXPECT_EQ(d.noise.c, 0.01553284_r);
  KEXPECT_EQ(d.noise.mean_offset, -0.025_r);

  const LidarParams o0 = lidar_preset_os0_128();  // os0_128_config.py
  KEXPECT_EQ(o0.height, 128u);
  KEXPECT_EQ(o0.vertical_fov_deg_min, -45);
  KEXPECT_EQ(o0.range.min_range, 0.2_r);
  KEXPECT_EQ(o0.range.max_range, 35);
  KEXPECT_EQ(o0.noise.mean_offset, -0.05_r);
  KEXPECT_TRUE(o0.mount.randomize_placement);
  KEXPECT_EQ(o0.mount.min_translation_b[0], 0.07_r);
  KEXPECT_EQ(o0.mount.max_translation_b[2], 0.04_r);
  KEXPECT_EQ(o0.mount.max_euler_deg[1], 5);
  KEXPECT_EQ(lidar_preset_os0_64().height, 64u);
  KEXPECT_EQ(lidar_preset_os0_64().noise.mean_offset, -0.025_r);

  const LidarParams o1 = lidar_preset_os1_64();  // os1_64_config.py
  KEXPECT_EQ(o1.vertical_fov_deg_max, 22.5_r);
  KEXPECT_EQ(o1.range.min_range, 0.7_r);
  KEXPECT_EQ(o1.range.max_range, 90);
  KEXPECT_EQ(o1.range.far_out_of_range_value, 35);  // inherited from OS_0_128_Config
  const LidarParams o2 = lidar_preset_os2_64();  // os2_64_config.py
  KEXPECT_EQ(o2.vertical_fov_deg_min, -11.25_r);
  KEXPECT_EQ(o2.range.max_range, 200);
  KEXPECT_EQ(o2.noise.c, 5.30757302e-03_r);

  const LidarParams a = lidar_preset_rs_airy();  // rslidar_airy_config.py
  KEXPECT_EQ(a.height, 48u);
  KEXPECT_EQ(a.width, 120u);
  KEXPECT_EQ(a.range.max_range, 10);
  KEXPECT_FALSE(a.range.normalize_range);
  KEXPECT_TRUE(a.output.return_pointcloud);
  KEXPECT_TRUE(a.output.pointcloud_in_world_frame);
  KEXPECT_FALSE(a.output.segmentation_camera);
  KEXPECT_EQ(a.mount.min_translation_b[0], -0.05_r);
  KEXPECT_EQ(a.mount.min_euler_deg[1], -90);

  const LidarParams f = lidar_preset_pmd_flexx2();  // pmd_flexx2_config.py
  KEXPECT_EQ(f.height, 172u);
  KEXPECT_EQ(f.width, 224u);
  KEXPECT_EQ(f.horizontal_fov_deg_max, 28);
  KEXPECT_EQ(f.vertical_fov_deg_min, -22);
  KEXPECT_EQ(f.range.max_range, 5);
  KEXPECT_EQ(f.mount.max_translation_b[2], 0.06_r);
  KEXPECT_EQ(f.noise.pixel_dropout_prob, 0.01_r);

  const LidarParams t = lidar_preset_vl53l5cx();  // st_vl53l5cx_config.py
  KEXPECT_EQ(t.height, 8u);
  KEXPECT_EQ(t.horizontal_fov_deg_min, -45);
  KEXPECT_EQ(t.vertical_fov_deg_max, 45);
  KEXPECT_EQ(t.range.min_range, 0.2_r);
  KEXPECT_EQ(t.range.max_range, 4);
  KEXPECT_FALSE(t.range.normalize_range);
  KEXPECT_EQ(t.range.far_out_of_range_value, -1);
  KEXPECT_TRUE(t.noise.enable_sensor_noise);
  KEXPECT_TRUE(t.noise.model == NoiseParams::Model::multiplier);
  KEXPECT_EQ(t.noise.std_dev_multiplier, 0.02_r);

  const LidarParams b = lidar_preset_base();  // base_lidar_config.py
  KEXPECT_EQ(b.height, 128u);
  KEXPECT_EQ(b.range.max_range, 10);
  KEXPECT_EQ(b.noise.mean_offset, -0.05_r);
  KEXPECT_TRUE(b.noise.enable_sensor_noise);
}

KTEST(SensorPresets, CamerasMatchAerialGymConfigs) {
  const CameraParams b = camera_preset_base();  // base_depth_camera_config.py
  KEXPECT_EQ(b.height, 135u);
  KEXPECT_EQ(b.width, 240u);
  KEXPECT_EQ(b.horizontal_fov_deg, 87);
  KEXPECT_EQ(b.range.min_range, 0.2_r);
  KEXPECT_EQ(b.range.max_range, 10);
  KEXPECT_TRUE(b.calculate_depth);
  KEXPECT_TRUE(b.range.normalize_range);
  KEXPECT_EQ(b.range.near_out_of_range_value, -10);
  KEXPECT_TRUE(b.output.segmentation_camera);
  KEXPECT_TRUE(b.mount.randomize_placement);
  KEXPECT_EQ(b.mount.nominal_position_b[0], 0.10_r);
  KEXPECT_EQ(b.mount.nominal_position_b[2], 0.03_r);
  KEXPECT_FALSE(b.noise.enable_sensor_noise);
  KEXPECT_EQ(b.noise.std_dev_multiplier, 0.01_r);
  const CameraParams d = camera_preset_d455();  // intel_realsense_d455_config.py
  KEXPECT_EQ(d.height, 270u);
  KEXPECT_EQ(d.width, 480u);
  KEXPECT_EQ(d.range.max_range, 15);
  KEXPECT_EQ(d.range.far_out_of_range_value, 15);
  const CameraParams k = camera_preset_oakd();  // luxonis_oak_d_config.py
  KEXPECT_EQ(k.height, 270u);
  KEXPECT_EQ(k.horizontal_fov_deg, 72);
  KEXPECT_EQ(k.range.min_range, 0.7_r);
  KEXPECT_EQ(k.range.max_range, 12);
  KEXPECT_FALSE(k.output.segmentation_camera);
  KEXPECT_FALSE(k.mount.randomize_placement);
  const CameraParams w = camera_preset_oakd_pro_w();  // luxonis_oak_d_pro_w_config.py
  KEXPECT_EQ(w.horizontal_fov_deg, 127);
  KEXPECT_EQ(w.range.min_range, 0.2_r);
  KEXPECT_EQ(w.range.far_out_of_range_value, 12);
}

KTEST(SensorPresets, ImusMatchAerialGymConfigs) {
  const ImuParams v = imu_preset_vn100();  // vn100_config.py
  KEXPECT_EQ(v.accel_noise_density[0], 0.001372931_r);
  KEXPECT_EQ(v.gyro_noise_density[2], 6.108652381980153e-05_r);
  KEXPECT_EQ(v.accel_bias_random_walk[1], 9.782812831313576e-07_r);
  KEXPECT_EQ(v.gyro_bias_random_walk[0], 2.6541629581345176e-05_r);
  KEXPECT_EQ(v.gyro_initial_bias_max[0], 1.0e-3_r);
  KEXPECT_EQ(v.accel_saturation[0], 100);
  KEXPECT_EQ(v.gyro_saturation[2], 10);
  KEXPECT_EQ(v.misalignment_max_deg[1], 2);
  KEXPECT_EQ(v.misalignment_min_deg[2], -2);
  KEXPECT_FALSE(v.gravity_compensation);
  const ImuParams m = imu_preset_bmi088();  // bosch_bmi088_config.py
  KEXPECT_EQ(m.accel_noise_density[0], 0.0015690639999999998_r);
  KEXPECT_EQ(m.accel_noise_density[2], 0.0018632634999999997_r);
  KEXPECT_EQ(m.gyro_noise_density[1], 0.0002443460952792061_r);
  KEXPECT_EQ(m.accel_bias_random_walk[2], 0.0013564659966250536_r);
  KEXPECT_EQ(m.gyro_bias_random_walk[2], 1.4352700094407325e-05_r);
  const ImuParams b = imu_preset_base();  // base_imu_config.py
  KEXPECT_EQ(b.accel_noise_density[1], 0.001688956233495657_r);
  KEXPECT_EQ(b.gyro_noise_density[0], 0.0010679343003532472_r);
  KEXPECT_TRUE(b.enable_noise && b.enable_bias);
  // Misalignment drawn within +-2 deg at reset.
  ImuState s;
  RngStream rng(9, 2, kPurposeSensorNoise);
  imu_reset(m, s, rng);
  const Vec3 e = euler_xyz(s.misalignment_bs) * (180 / kPi);
  for (int k = 0; k < 3; ++k) KEXPECT_LE(std::fabs(e[k]), 2.0001);
  for (int k = 0; k < 3; ++k) KEXPECT_LE(std::fabs(s.accel_bias_s[k]), 1.0e-3_r);
}

KTEST(SensorPresets, WarpMountRuleAndNoiseSemantics) {
  // Non-randomised warp sensor: zero translation, Euler (min + max) / 2 (nominal pose ignored).
  LidarParams t = lidar_preset_vl53l5cx();
  t.mount.min_euler_deg = Vec3(0, 10, 0);
  t.mount.max_euler_deg = Vec3(0, 30, 0);
  RngStream rng(1, 1, kPurposePlacement);
  const Mount m = sample_mount(t.mount, rng);
  KEXPECT_EQ(m.position_b[0], 0);
  KEXPECT_EQ(m.position_b[2], 0);
  KEXPECT_NEAR(euler_xyz(m.orientation_bs)[1], 20 * kPi / 180, 1e-6);
  // RS Airy: randomised with min = max -> exactly that pose.
  const Mount a = sample_mount(lidar_preset_rs_airy().mount, rng);
  KEXPECT_NEAR(a.position_b[0], -0.05, 1e-7);
  KEXPECT_NEAR(rotate(a.orientation_bs, Vec3(1, 0, 0))[2], 1, 1e-6);  // pitch -90: x looks up
  // Dropout reads the value passed (render passes near_out_of_range_value); zero std noise with
  // mean_offset -0.025 lengthens every range by 0.025 (Aerial Gym mean = r - mean_offset).
  NoiseParams np;
  np.model = NoiseParams::Model::range_dependent;
  np.mean_offset = -0.025_r;
  real v[4] = {1, 2, 3, 4};
  RngStream r2(3, 0, kPurposeSensorNoise);
  apply_noise(np, v, 4, r2, -7);
  for (int k = 0; k < 4; ++k) KEXPECT_NEAR(v[k], k + 1.025, 1e-6);
  np.pixel_dropout_prob = 1;
  apply_noise(np, v, 4, r2, -7);
  for (int k = 0; k < 4; ++k) KEXPECT_EQ(v[k], -7);
  np.enable_sensor_noise = false;
  v[0] = 1;
  apply_noise(np, v, 1, r2, -7);
  KEXPECT_EQ(v[0], 1);
}
