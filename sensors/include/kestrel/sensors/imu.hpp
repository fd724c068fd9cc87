// IMU model: accelerometer and gyroscope with white noise, bias random walk, initial bias,
// mounting misalignment, saturation and gravity handling (Aerial Gym's IMU sensor).
//
// Discrete-time noise model of the continuous densities, as Aerial Gym's IMU sensor applies it
// (also the Kalibr "IMU noise model"): per step of dt, first the bias walks
//   bias += N(0, random_walk * sqrt(dt)), then output = true + bias + N(0, noise_density / sqrt(dt)),
// clamped per axis to +-saturation. Initial bias uniform in +-initial_bias_max at reset.
// The accelerometer measures specific force a - g in the sensor frame; with gravity_compensation
// the gravity term is removed (the measurement is the kinematic acceleration).
#pragma once

#include <cstdint>

#include "kestrel/kernel/rng.hpp"
#include "kestrel/kernel/status.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel::sensors {

/// Field names of Aerial Gym's IMU configs in brackets; per axis x, y, z.
struct ImuParams {
  Vec3 accel_noise_density = Vec3::Zero();     // m/s^2/sqrt(Hz)   [imu_noise_std 0..2]
  Vec3 gyro_noise_density = Vec3::Zero();      // rad/s/sqrt(Hz)   [imu_noise_std 3..5]
  Vec3 accel_bias_random_walk = Vec3::Zero();  // m/s^3/sqrt(Hz)   [bias_std 0..2]
  Vec3 gyro_bias_random_walk = Vec3::Zero();   // rad/s^2/sqrt(Hz) [bias_std 3..5]
  Vec3 accel_initial_bias_max = Vec3::Zero();  // m/s^2, uniform in +-max [max_bias_init_value 0..2]
  Vec3 gyro_initial_bias_max = Vec3::Zero();   // rad/s                   [max_bias_init_value 3..5]
  Vec3 accel_saturation = Vec3::Constant(1e6_r);  // m/s^2, clamp +-  [max_measurement_value 0..2]
  Vec3 gyro_saturation = Vec3::Constant(1e6_r);   // rad/s            [max_measurement_value 3..5]
  // Mounting misalignment, Euler angles (roll, pitch, yaw) uniform in [min, max] deg
  // [min/max_euler_rotation_deg]. Like Aerial Gym's IMU it is drawn at every reset whatever the
  // config's randomize_placement says (its IMU sensor never reads that flag; base: False, VN100
  // and BMI088: True, all with +-2 deg), so that flag has no field here.
  Vec3 misalignment_min_deg = Vec3::Zero();
  Vec3 misalignment_max_deg = Vec3::Zero();
  bool enable_noise = true;
  bool enable_bias = true;
  bool gravity_compensation = false;
  Vec3 gravity_w = Vec3(0, 0, -kStandardGravity);
  // Aerial Gym's world_frame = False (all configs) reads a body-frame force sensor; imu_update()
  // takes the world acceleration and body rates instead, which gives the same measurement.
};

// Presets reproducing github.com/ntnu-arl/aerial_gym_simulator aerial_gym/config/sensor_config/
// imu_config/ (model: aerial_gym/sensors/imu_sensor.py @ad20caeca535a46b36ff716b6f8fc2470c4508c9).
/// base_imu_config.py @ad20caeca535a46b36ff716b6f8fc2470c4508c9: noise 1.6890e-3 / 1.0679e-3,
/// bias walk 9.7828e-7 / 2.6542e-5, initial bias +-1e-3, clamp 100 m/s^2 / 10 rad/s, +-2 deg.
ImuParams imu_preset_base();
/// vn100_config.py @83bbdbe9f6125be98161a084bdf88cc26d3436de: noise 1.372931e-3 / 6.1087e-5,
/// bias walk 9.7828e-7 / 2.6542e-5, initial bias +-1e-3, clamp 100 / 10, +-2 deg.
ImuParams imu_preset_vn100();
/// bosch_bmi088_config.py @83bbdbe9f6125be98161a084bdf88cc26d3436de: accel noise 1.569064e-3
/// (x, y) / 1.8632635e-3 (z), gyro 2.4435e-4, bias walk 1.35647e-3 / 1.43527e-5, initial bias
/// +-1e-3, clamp 100 / 10, +-2 deg.
ImuParams imu_preset_bmi088();

struct ImuState {
  Vec3 accel_bias_s = Vec3::Zero();
  Vec3 gyro_bias_s = Vec3::Zero();
  Quat misalignment_bs = Quat::Identity();  // actual sensor frame relative to the nominal mount
};

struct ImuSample {
  Vec3 accel_s = Vec3::Zero();  // m/s^2
  Vec3 gyro_s = Vec3::Zero();   // rad/s
  bool saturated = false;
};

/// Draws initial biases and misalignment (rng: kPurposeSensorNoise stream of this environment).
void imu_reset(const ImuParams& p, ImuState& s, RngStream& rng);
/// One measurement. q_wb: body attitude; linacc_w: body acceleration in the world (m/s^2);
/// angvel_b: body rates; q_bs_nominal: nominal mount. dt must be > 0.
[[nodiscard]] Status imu_update(const ImuParams& p, ImuState& s, const Quat& q_wb, const Vec3& linacc_w,
                                const Vec3& angvel_b, const Quat& q_bs_nominal, real dt, RngStream& rng,
                                ImuSample& out);

}  // namespace kestrel::sensors
