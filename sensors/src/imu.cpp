// IMU model (see imu.hpp).
#include "kestrel/sensors/imu.hpp"

#include <cmath>

#include "kestrel/kernel/quaternion.hpp"

namespace kestrel::sensors {

namespace {

constexpr real kDeg = kPi / 180;

// Shared by all three configs: max_bias_init_value, max_measurement_value, +-2 deg misalignment.
ImuParams common(const Vec3& acc_noise, real gyro_noise, real acc_walk, real gyro_walk) {
  ImuParams p;
  p.accel_noise_density = acc_noise;
  p.gyro_noise_density = Vec3::Constant(gyro_noise);
  p.accel_bias_random_walk = Vec3::Constant(acc_walk);
  p.gyro_bias_random_walk = Vec3::Constant(gyro_walk);
  p.accel_initial_bias_max = Vec3::Constant(1.0e-3_r);
  p.gyro_initial_bias_max = Vec3::Constant(1.0e-3_r);
  p.accel_saturation = Vec3::Constant(100);
  p.gyro_saturation = Vec3::Constant(10);
  p.misalignment_min_deg = Vec3::Constant(-2);
  p.misalignment_max_deg = Vec3::Constant(2);
  p.enable_noise = true;
  p.enable_bias = true;
  p.gravity_compensation = false;
  return p;
}

}  // namespace

ImuParams imu_preset_base() {
  return common(Vec3::Constant(0.001688956233495657_r), 0.0010679343003532472_r, 9.782812831313576e-07_r,
                2.6541629581345176e-05_r);
}

ImuParams imu_preset_vn100() {
  return common(Vec3::Constant(0.001372931_r), 6.108652381980153e-05_r, 9.782812831313576e-07_r,
                2.6541629581345176e-05_r);
}

ImuParams imu_preset_bmi088() {
  return common(Vec3(0.0015690639999999998_r, 0.0015690639999999998_r, 0.0018632634999999997_r),
                0.0002443460952792061_r, 0.0013564659966250536_r, 1.4352700094407325e-05_r);
}

void imu_reset(const ImuParams& p, ImuState& s, RngStream& rng) {
  for (int k = 0; k < 3; ++k) {
    s.accel_bias_s[k] =
        p.enable_bias ? rng.uniform(-p.accel_initial_bias_max[k], p.accel_initial_bias_max[k]) : 0_r;
    s.gyro_bias_s[k] = p.enable_bias ? rng.uniform(-p.gyro_initial_bias_max[k], p.gyro_initial_bias_max[k]) : 0_r;
  }
  real e[3];
  for (int k = 0; k < 3; ++k) e[k] = rng.uniform(p.misalignment_min_deg[k] * kDeg, p.misalignment_max_deg[k] * kDeg);
  s.misalignment_bs = quat_from_euler_xyz(e[0], e[1], e[2]);  // identity when both ranges are 0
}

Status imu_update(const ImuParams& p, ImuState& s, const Quat& q_wb, const Vec3& linacc_w, const Vec3& angvel_b,
                  const Quat& q_bs_nominal, real dt, RngStream& rng, ImuSample& out) {
  if (!(dt > 0)) return Status::invalid_argument;
  if (!linacc_w.allFinite() || !angvel_b.allFinite() || !q_wb.coeffs().allFinite()) return Status::non_finite_input;
  const Quat q_bs = (q_bs_nominal * s.misalignment_bs).normalized();
  const Quat q_ws = (q_wb * q_bs).normalized();
  const Vec3 f_w = p.gravity_compensation ? linacc_w : Vec3(linacc_w - p.gravity_w);
  Vec3 acc = rotate_inverse(q_ws, f_w);
  Vec3 gyr = rotate_inverse(q_bs, angvel_b);
  // Fixed draw count per call (6 white + 6 walk) whatever the flags: stream positions stay aligned.
  const real sdt = std::sqrt(dt);
  for (int k = 0; k < 3; ++k) {
    const real na = rng.normal(), ng = rng.normal(), wa = rng.normal(), wg = rng.normal();
    if (p.enable_bias) {
      s.accel_bias_s[k] += wa * p.accel_bias_random_walk[k] * sdt;
      s.gyro_bias_s[k] += wg * p.gyro_bias_random_walk[k] * sdt;
      acc[k] += s.accel_bias_s[k];
      gyr[k] += s.gyro_bias_s[k];
    }
    if (p.enable_noise) {
      acc[k] += na * p.accel_noise_density[k] / sdt;
      gyr[k] += ng * p.gyro_noise_density[k] / sdt;
    }
  }
  out.saturated = false;
  for (int k = 0; k < 3; ++k) {
    if (std::fabs(acc[k]) > p.accel_saturation[k]) {
      acc[k] = std::copysign(p.accel_saturation[k], acc[k]);
      out.saturated = true;
    }
    if (std::fabs(gyr[k]) > p.gyro_saturation[k]) {
      gyr[k] = std::copysign(p.gyro_saturation[k], gyr[k]);
      out.saturated = true;
    }
  }
  out.accel_s = acc;
  out.gyro_s = gyr;
  return Status::ok;
}

}  // namespace kestrel::sensors
