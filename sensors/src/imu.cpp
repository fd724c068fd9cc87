// IMU model (see imu.hpp).
#include "kestrel/sensors/imu.hpp"

#include <cmath>

#include "kestrel/kernel/quaternion.hpp"

namespace kestrel::sensors {

namespace {
constexpr real kDeg = kPi / 180;
constexpr real kG = kStandardGravity;
}  // namespace

ImuParams imu_preset_base() {
  // Assumption: generic consumer MEMS figures of the magnitude Aerial Gym's base IMU uses
  // (white noise ~1e-3 class, small bias walks); no misalignment; +-16 g and +-2000 deg/s.
  ImuParams p;
  p.accel_noise_density = 2.0e-3_r;
  p.gyro_noise_density = 1.7e-4_r;
  p.accel_bias_random_walk = 3.0e-3_r;
  p.gyro_bias_random_walk = 1.9e-5_r;
  p.accel_initial_bias_max = 0.05_r;
  p.gyro_initial_bias_max = 0.005_r;
  p.accel_saturation = 16 * kG;
  p.gyro_saturation = 2000 * kDeg;
  return p;
}

ImuParams imu_preset_vn100() {
  ImuParams p;
  p.accel_noise_density = 0.14e-3_r * kG;       // 0.14 mg/sqrt(Hz) = 1.373e-3
  p.gyro_noise_density = 0.0035_r * kDeg;       // 6.11e-5 rad/s/sqrt(Hz)
  p.accel_bias_random_walk = 5.0e-5_r;          // VectorNav support figure (Kalibr configs)
  p.gyro_bias_random_walk = 3.9e-5_r;           // idem (assumption)
  p.accel_initial_bias_max = 0.04_r * 1e-3_r * kG * 10;  // in-run stability 0.04 mg -> +-0.4 mg turn-on
  p.gyro_initial_bias_max = 10 * kDeg / 3600;   // 10 deg/h in-run bias stability
  p.accel_saturation = 16 * kG;
  p.gyro_saturation = 2000 * kDeg;
  return p;
}

ImuParams imu_preset_bmi088() {
  ImuParams p;
  p.accel_noise_density = 175e-6_r * kG;        // 1.717e-3 m/s^2/sqrt(Hz)
  p.gyro_noise_density = 0.014_r * kDeg;        // 2.44e-4 rad/s/sqrt(Hz)
  p.accel_bias_random_walk = 1.0e-3_r;          // assumption (not in the datasheet)
  p.gyro_bias_random_walk = 2.0e-5_r;           // assumption
  p.accel_initial_bias_max = 0.02_r * kG;       // datasheet zero-g offset +-20 mg
  p.gyro_initial_bias_max = 1 * kDeg;           // datasheet zero-rate offset +-1 deg/s
  p.accel_saturation = 24 * kG;
  p.gyro_saturation = 2000 * kDeg;
  return p;
}

void imu_reset(const ImuParams& p, ImuState& s, RngStream& rng) {
  for (int k = 0; k < 3; ++k) {
    s.accel_bias_s[k] = p.enable_bias ? rng.uniform(-p.accel_initial_bias_max, p.accel_initial_bias_max) : 0_r;
    s.gyro_bias_s[k] = p.enable_bias ? rng.uniform(-p.gyro_initial_bias_max, p.gyro_initial_bias_max) : 0_r;
  }
  const real m = p.misalignment_max_deg * kDeg;
  const real r = rng.uniform(-m, m), pi = rng.uniform(-m, m), y = rng.uniform(-m, m);
  s.misalignment_bs = quat_from_euler_xyz(r, pi, y);  // identity when m = 0
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
      s.accel_bias_s[k] += wa * p.accel_bias_random_walk * sdt;
      s.gyro_bias_s[k] += wg * p.gyro_bias_random_walk * sdt;
      acc[k] += s.accel_bias_s[k];
      gyr[k] += s.gyro_bias_s[k];
    }
    if (p.enable_noise) {
      acc[k] += na * p.accel_noise_density / sdt;
      gyr[k] += ng * p.gyro_noise_density / sdt;
    }
  }
  out.saturated = false;
  for (int k = 0; k < 3; ++k) {
    if (std::fabs(acc[k]) > p.accel_saturation) {
      acc[k] = std::copysign(p.accel_saturation, acc[k]);
      out.saturated = true;
    }
    if (std::fabs(gyr[k]) > p.gyro_saturation) {
      gyr[k] = std::copysign(p.gyro_saturation, gyr[k]);
      out.saturated = true;
    }
  }
  out.accel_s = acc;
  out.gyro_s = gyr;
  return Status::ok;
}

}  // namespace kestrel::sensors
