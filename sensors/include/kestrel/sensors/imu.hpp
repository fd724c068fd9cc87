// IMU model: accelerometer and gyroscope with white noise, bias random walk, initial bias,
// mounting misalignment, saturation and gravity handling (Aerial Gym's IMU sensor).
//
// Discrete-time noise model of the continuous densities (J. Rehder et al., "Extending kalibr",
// ICRA 2016; the Kalibr "IMU noise model" note): per step of dt,
//   white noise std = noise_density / sqrt(dt),   bias += N(0, random_walk * sqrt(dt)).
// The accelerometer measures specific force a - g in the sensor frame; with gravity_compensation
// the gravity term is removed (the measurement is the kinematic acceleration).
#pragma once

#include <cstdint>

#include "kestrel/kernel/rng.hpp"
#include "kestrel/kernel/status.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel::sensors {

struct ImuParams {
  real accel_noise_density = 0;      // m/s^2/sqrt(Hz)
  real gyro_noise_density = 0;       // rad/s/sqrt(Hz)
  real accel_bias_random_walk = 0;   // m/s^3/sqrt(Hz)
  real gyro_bias_random_walk = 0;    // rad/s^2/sqrt(Hz)
  real accel_initial_bias_max = 0;   // m/s^2, initial bias uniform in +-max per axis
  real gyro_initial_bias_max = 0;    // rad/s
  real misalignment_max_deg = 0;     // mounting misalignment, Euler angles uniform in +-max
  real accel_saturation = 1e6_r;     // m/s^2, |output| clipped per axis
  real gyro_saturation = 1e6_r;      // rad/s
  bool enable_noise = true;
  bool enable_bias = true;
  bool gravity_compensation = false;
  Vec3 gravity_w = Vec3(0, 0, -kStandardGravity);
};

/// Assumption-labelled presets.
/// Aerial Gym-like base IMU (small generic MEMS values; assumption, documented in imu.cpp).
ImuParams imu_preset_base();
/// VectorNav VN-100 (datasheet: accel 0.14 mg/sqrt(Hz), gyro 0.0035 deg/s/sqrt(Hz), +-16 g,
/// +-2000 deg/s; bias random walks from VectorNav support figures used with Kalibr).
ImuParams imu_preset_vn100();
/// Bosch BMI088 (datasheet: accel 175 ug/sqrt(Hz) (x, y), +-24 g; gyro 0.014 deg/s/sqrt(Hz),
/// +-2000 deg/s).
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
