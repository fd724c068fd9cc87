// Lee geometric controllers: T. Lee, M. Leok, N. H. McClamroch, "Geometric tracking control of a
// quadrotor UAV on SE(3)", IEEE CDC 2010 — as implemented by Aerial Gym (see lee.hpp).
//
// Cost notes (the whole cascade has ~1,500 instructions per step on a Cortex-M4F):
//  - the state quaternion is turned into a rotation matrix once; yaw, body z, and the Euler-rate
//    map all come out of that matrix without trig (attitude_frame());
//  - the Euler yaw rate r maps to the body rate r * (third row of R): that row is
//    (-sin(pitch), sin(roll) cos(pitch), cos(roll) cos(pitch)), Aerial Gym's map, with no angles;
//  - the acceleration controller's desired Euler angles are never formed: their cosines and
//    sines are ratios of force components;
//  - trig is called only on commanded angles (heading, attitude roll/pitch), never on the state;
//  - no matrix inverse anywhere; rotation errors use E = R^T R_d directly;
//  - finite checks of inputs and outputs are branch-free sums (nonfinite_probe()).
// Measured on the emulated Cortex-M4F (QEMU -icount, -O2, through update_controller()): about
// 410 instructions for lee_rates, 730-860 for the position-type controllers and the ROV, 900 for
// lee_attitude with newlib's sinf + cosf; kestrel::sin_cos (kernel math.hpp: Cephes polynomials,
// Cody-Waite reduction shared by sine and cosine) took ~25 instructions off each commanded angle
// and ~3.8 KB of newlib's Payne-Hanek reduction off the firmware's flash.
#include "kestrel/controllers/lee.hpp"

#include <cmath>

#include "kestrel/kernel/assert.hpp"
#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/quaternion.hpp"

namespace kestrel {
namespace {

// Below |F| = 1e-6 N the collective force has no usable direction (the reference divides by |F|
// and produces NaN at exactly zero). Any real thrust command is orders of magnitude above this.
constexpr real kMinForceSq = 1e-12_r;  // N^2
// |b3 x heading| below 1e-5: the heading lies (nearly) along the thrust axis and its projection,
// which defines b1, is dominated by rounding.
constexpr real kMinCrossSq = 1e-10_r;
// A command quaternion shorter than 1e-6 cannot be normalised meaningfully.
constexpr real kMinQuatNormSq = 1e-12_r;

// Rotation matrix of q as given (not re-normalised, like the reference).
inline Mat3 rotation_of(const Quat& q) {
  const real x = q.x(), y = q.y(), z = q.z(), w = q.w();
  const real xx = x * x, yy = y * y, zz = z * z;
  const real xy = x * y, xz = x * z, yz = y * z;
  const real wx = w * x, wy = w * y, wz = w * z;
  Mat3 r;
  r(0, 0) = 1 - 2 * (yy + zz);
  r(0, 1) = 2 * (xy - wz);
  r(0, 2) = 2 * (xz + wy);
  r(1, 0) = 2 * (xy + wz);
  r(1, 1) = 1 - 2 * (xx + zz);
  r(1, 2) = 2 * (yz - wx);
  r(2, 0) = 2 * (xz - wy);
  r(2, 1) = 2 * (yz + wx);
  r(2, 2) = 1 - 2 * (xx + yy);
  return r;
}

// R = Rz(yaw) Ry(pitch) Rx(roll) from the cosines and sines of the three angles.
inline Mat3 rotation_zyx(real cy, real sy, real cp, real sp, real cr, real sr) {
  Mat3 r;
  r(0, 0) = cy * cp;
  r(0, 1) = cy * sp * sr - sy * cr;
  r(0, 2) = cy * sp * cr + sy * sr;
  r(1, 0) = sy * cp;
  r(1, 1) = sy * sp * sr + cy * cr;
  r(1, 2) = sy * sp * cr - cy * sr;
  r(2, 0) = -sp;
  r(2, 1) = cp * sr;
  r(2, 2) = cp * cr;
  return r;
}

// Body rate of a pure Euler yaw rate: (-sin(pitch), sin(roll) cos(pitch), cos(roll) cos(pitch)) r,
// which is the third row of R times r (the world z axis seen from the body).
inline Vec3 body_rate_of_yaw_rate(const Mat3& r_wb, real yaw_rate) {
  return Vec3(r_wb(2, 0) * yaw_rate, r_wb(2, 1) * yaw_rate, r_wb(2, 2) * yaw_rate);
}

// Aerial Gym clamps only the body-z component of the desired rate (quirk 2: the reference does it
// in place on the caller's buffer; here it is always a copy).
inline Vec3 clamp_body_yaw_rate(const Vec3& w_d, real max_radps) {
  return Vec3(w_d[0], w_d[1], clamp(w_d[2], -max_radps, max_radps));
}

// Desired rotation from the collective force and a heading (Lee et al., Sec. IV; Aerial Gym's
// calculate_desired_orientation_for_position_velocity_control): b3 = F/|F|,
// b2 = normalise(b3 x (cos psi, sin psi, 0)), b1 = b2 x b3. Returns true when it had to fall back:
//  - |F| ~ 0: keep the current thrust axis (no attitude change is better than a random one);
//  - heading ~ parallel to b3: keep the current heading (project body x), and if body x is also
//    along b3, use -body z, which is the minimal rotation in that case (about body y).
inline bool rotation_from_force_heading(const Vec3& f_w, real cos_psi, real sin_psi, const Mat3& r_wb, Mat3& r_d) {
  bool singular = false;
  Vec3 b3;
  const real f2 = f_w.squaredNorm();
  if (f2 > kMinForceSq) {
    b3 = f_w * (1 / std::sqrt(f2));
  } else {
    b3 = r_wb.col(2);
    singular = true;
  }
  // b3 x (cos psi, sin psi, 0), written out.
  Vec3 b2(-b3[2] * sin_psi, b3[2] * cos_psi, b3[0] * sin_psi - b3[1] * cos_psi);
  real n2 = b2.squaredNorm();
  if (!(n2 > kMinCrossSq)) {
    singular = true;
    b2 = b3.cross(Vec3(r_wb.col(0)));
    n2 = b2.squaredNorm();
    if (!(n2 > kMinCrossSq)) {
      b2 = b3.cross(Vec3(-r_wb.col(2)));
      n2 = b2.squaredNorm();
    }
  }
  b2 *= 1 / std::sqrt(n2);
  r_d.col(0) = b2.cross(b3);
  r_d.col(1) = b2;
  r_d.col(2) = b3;
  return singular;
}

// w x (J w), written out (Eigen's cross() is not always inlined on the MCU).
inline Vec3 gyroscopic(const Mat3& j_b, const Vec3& w) {
  const Vec3 jw = j_b * w;
  return Vec3(w[1] * jw[2] - w[2] * jw[1], w[2] * jw[0] - w[0] * jw[2], w[0] * jw[1] - w[1] * jw[0]);
}

// Lee et al. eqs. (10), (11), (16): E = R^T R_d, e_R = 1/2 vee(E^T - E), e_w = w - E w_d,
// tau = -k_R e_R - k_w e_w + w x J w. kRateRef = false skips E w_d when w_d is identically zero
// (the compiler may not drop x * 0 itself: that would change NaN/inf semantics).
template <bool kRateRef>
inline Vec3 lee_torque(const LeeGains& g, const Mat3& j_b, const Mat3& r_wb, const Mat3& r_d, const Vec3& w_b,
                       const Vec3& w_d) {
  const Mat3 e = r_wb.transpose() * r_d;
  const Vec3 e_r(0.5_r * (e(1, 2) - e(2, 1)), 0.5_r * (e(2, 0) - e(0, 2)), 0.5_r * (e(0, 1) - e(1, 0)));
  Vec3 e_w = w_b;
  if (kRateRef) e_w -= e * w_d;
  return -g.k_rot.cwiseProduct(e_r) - g.k_angvel.cwiseProduct(e_w) + gyroscopic(j_b, w_b);
}

inline Vec4 xyzw_nonneg_w(const Quat& q) {
  Vec4 v = to_xyzw(q);
  if (v[3] < 0) v = -v;
  return v;
}

// Sum of v[i] * 0: +-0 when every value is finite, NaN otherwise (inf * 0 and NaN * 0 are NaN, and
// a NaN survives the sum). Branch-free, ~3 instructions per value on a Cortex-M4F against ~7 for
// an isfinite() test with a branch per value; these checks run on ~35 values every update.
// Exact under the project's flags: without -ffast-math the compiler may not fold v * 0 to 0.
inline real nonfinite_probe(const real* v, std::size_t n) {
  real acc = 0;
  for (std::size_t i = 0; i < n; ++i) acc += v[i] * 0;
  return acc;
}
inline real nonfinite_probe(const Vec3& v) { return v[0] * 0 + v[1] * 0 + v[2] * 0; }
inline real nonfinite_probe(const Vec4& v) { return v[0] * 0 + v[1] * 0 + v[2] * 0 + v[3] * 0; }

inline bool state_finite(const RigidBodyState& b) {
  const Quat& q = b.orientation_wb;
  const real probe = nonfinite_probe(b.position_w) + nonfinite_probe(b.linvel_w) + nonfinite_probe(b.angvel_b) +
                     (q.x() * 0 + q.y() * 0 + q.z() * 0 + q.w() * 0);
  return probe == 0;
}

inline Wrench reject(LeeState& s, std::uint32_t faults) {
  s.step_faults = faults;
  s.faults.raise(faults);
  return s.last_safe_wrench_b;
}

// Validates the inputs and copies the clipped action into a[0..n). False: the update is rejected
// (the held wrench is then in s.last_safe_wrench_b).
inline bool accept(const LeeParams& p, LeeState& s, const RigidBodyState& b, const real* action, std::size_t n,
                   real* a, std::uint32_t& faults) {
  KESTREL_ASSERT(action != nullptr);
  faults = 0;
  if (!(nonfinite_probe(action, n) == 0)) faults |= kFaultNonFiniteCommand;
  if (!state_finite(b)) faults |= kFaultNonFiniteState;
  if (faults != 0) {
    reject(s, faults);
    return false;
  }
  for (std::size_t i = 0; i < n; ++i) {
    real v = action[i];
    if (v < p.action_min) {
      v = p.action_min;
      faults |= kFaultCommandOutOfRange;
    } else if (v > p.action_max) {
      v = p.action_max;
      faults |= kFaultCommandOutOfRange;
    }
    a[i] = v;
  }
  return true;
}

// Stores the result of an accepted update, unless something non-finite came out of it.
inline Wrench commit(LeeState& s, const Vec3& force_b, const Vec3& torque_b, const Vec3& accel_w, const Vec4& q_d,
                     const Vec3& w_d, std::uint32_t faults) {
  const real probe = nonfinite_probe(force_b) + nonfinite_probe(torque_b) + nonfinite_probe(accel_w) +
                     nonfinite_probe(q_d) + nonfinite_probe(w_d);
  if (!(probe == 0)) {
    return reject(s, faults | kFaultNonFiniteOutput);
  }
  s.last_safe_wrench_b.force_b = force_b;
  s.last_safe_wrench_b.torque_b = torque_b;
  s.accel_command_w = accel_w;
  s.desired_quat_xyzw = q_d;
  s.desired_angvel_b = w_d;
  s.step_faults = faults;
  s.faults.raise(faults);
  return s.last_safe_wrench_b;
}

// Shared tail of the position-type controllers: F = m (a - g), fz = F . body z, R_d from F and a
// heading, torque with the given desired rate.
template <bool kRateRef>
inline Wrench finish_force_heading(const LeeParams& p, LeeState& s, const RigidBodyState& b, const AttitudeFrame& fr,
                                   const Vec3& accel_w, real cos_psi, real sin_psi, const Vec3& w_d,
                                   std::uint32_t faults) {
  const Vec3 f_w = (accel_w - p.gravity_w) * p.mass_kg;
  const real fz = f_w.dot(fr.r_wb.col(2));
  Mat3 r_d;
  if (rotation_from_force_heading(f_w, cos_psi, sin_psi, fr.r_wb, r_d)) faults |= kFaultSingular;
  const Vec3 tau = lee_torque<kRateRef>(s.gains, p.inertia_b, fr.r_wb, r_d, b.angvel_b, w_d);
  return commit(s, Vec3(0, 0, fz), tau, accel_w, xyzw_nonneg_w(quat_from_rotation_matrix(r_d)), w_d, faults);
}

// Velocity command rotated from the vehicle (yaw-only) frame into the world.
inline Vec3 vehicle_to_world(const AttitudeFrame& fr, real vx, real vy, real vz) {
  return Vec3(fr.cos_yaw * vx - fr.sin_yaw * vy, fr.sin_yaw * vx + fr.cos_yaw * vy, vz);
}

}  // namespace

AttitudeFrame attitude_frame(const Quat& q_wb) {
  AttitudeFrame f;
  f.r_wb = rotation_of(q_wb);
  // yaw = atan2(R10, R00) in the reference; its cosine and sine are the normalised pair.
  const real c = f.r_wb(0, 0), s = f.r_wb(1, 0);
  const real h2 = c * c + s * s;
  if (h2 > 0) {
    const real inv = 1 / std::sqrt(h2);
    f.cos_yaw = c * inv;
    f.sin_yaw = s * inv;
  }
  return f;
}

Status validate_lee_params(const LeeParams& p) {
  if (!is_finite(p.mass_kg) || !(p.mass_kg > 0)) return Status::invalid_argument;
  if (!all_finite(p.inertia_b) || !all_finite(p.gravity_w)) return Status::invalid_argument;
  if (!is_finite(p.max_yaw_rate_radps) || !(p.max_yaw_rate_radps >= 0)) return Status::invalid_argument;
  if (!is_finite(p.action_min) || !is_finite(p.action_max) || !(p.action_min < p.action_max)) {
    return Status::invalid_argument;
  }
  const LeeGains& lo = p.gain_ranges.min;
  const LeeGains& hi = p.gain_ranges.max;
  const Vec3* los[4] = {&lo.k_pos, &lo.k_vel, &lo.k_rot, &lo.k_angvel};
  const Vec3* his[4] = {&hi.k_pos, &hi.k_vel, &hi.k_rot, &hi.k_angvel};
  for (int i = 0; i < 4; ++i) {
    if (!all_finite(*los[i]) || !all_finite(*his[i])) return Status::invalid_argument;
    for (int k = 0; k < 3; ++k) {
      if (!((*los[i])[k] <= (*his[i])[k])) return Status::invalid_argument;
    }
  }
  return Status::ok;
}

LeeGains lee_nominal_gains(const LeeGainRanges& r) {
  // (max + min) / 2 in this order, as Aerial Gym computes K_*_tensor_current: in float this gives
  // the golden gains bit for bit (e.g. (0.2f + 0.1f) / 2 = 0.150000006f).
  LeeGains g;
  g.k_pos = (r.max.k_pos + r.min.k_pos) / 2;
  g.k_vel = (r.max.k_vel + r.min.k_vel) / 2;
  g.k_rot = (r.max.k_rot + r.min.k_rot) / 2;
  g.k_angvel = (r.max.k_angvel + r.min.k_angvel) / 2;
  return g;
}

LeeGains randomize_lee_gains(const LeeGainRanges& r, RngStream& rng) {
  LeeGains g;
  for (int k = 0; k < 3; ++k) g.k_pos[k] = rng.uniform(r.min.k_pos[k], r.max.k_pos[k]);
  for (int k = 0; k < 3; ++k) g.k_vel[k] = rng.uniform(r.min.k_vel[k], r.max.k_vel[k]);
  for (int k = 0; k < 3; ++k) g.k_rot[k] = rng.uniform(r.min.k_rot[k], r.max.k_rot[k]);
  for (int k = 0; k < 3; ++k) g.k_angvel[k] = rng.uniform(r.min.k_angvel[k], r.max.k_angvel[k]);
  return g;
}

LeeGainRanges lee_gain_ranges_default() {
  LeeGainRanges r;
  r.min.k_pos = Vec3(2.0_r, 2.0_r, 1.0_r);
  r.max.k_pos = Vec3(3.0_r, 3.0_r, 2.0_r);
  r.min.k_vel = Vec3(2.0_r, 2.0_r, 2.0_r);
  r.max.k_vel = Vec3(3.0_r, 3.0_r, 3.0_r);
  r.min.k_rot = Vec3(0.8_r, 0.8_r, 0.4_r);
  r.max.k_rot = Vec3(1.2_r, 1.2_r, 0.6_r);
  r.min.k_angvel = Vec3(0.1_r, 0.1_r, 0.1_r);
  r.max.k_angvel = Vec3(0.2_r, 0.2_r, 0.2_r);
  return r;
}

LeeGainRanges lee_gain_ranges_rov() {
  LeeGainRanges r;
  r.min.k_pos = Vec3(1.0_r, 1.0_r, 1.0_r);
  r.max.k_pos = r.min.k_pos;
  r.min.k_vel = Vec3(8.0_r, 8.0_r, 8.0_r);
  r.max.k_vel = r.min.k_vel;
  r.min.k_rot = Vec3(2.2_r, 2.2_r, 2.6_r);
  r.max.k_rot = r.min.k_rot;
  r.min.k_angvel = Vec3(2.1_r, 2.1_r, 2.1_r);
  r.max.k_angvel = Vec3(2.2_r, 2.2_r, 2.2_r);
  return r;
}

// Mass and inertia are written as the float32 values golden/controllers.json lists (what the
// simulator composes from the URDF in float32), so a double build sees the reference's inputs.
// Gravity and the yaw-rate limit use the kernel constants: in float they are the same bits as the
// listed 9.81000042 and 1.04719755.
LeeParams lee_params_base_quadrotor() {
  LeeParams p;
  p.mass_kg = 0.25_r;
  p.inertia_b = Mat3::Zero();
  p.inertia_b(0, 0) = 0.000845000031_r;
  p.inertia_b(1, 1) = 0.000845000031_r;
  p.inertia_b(2, 2) = 0.00169000006_r;
  p.gravity_w = Vec3(0, 0, -kStandardGravity);
  p.max_yaw_rate_radps = kPi / 3;
  p.gain_ranges = lee_gain_ranges_default();
  p.randomize_gains = false;  // lee_controller_config.py: randomize_params = False
  return p;
}

LeeParams lee_params_rov() {
  LeeParams p;
  p.mass_kg = 1.10000002_r;
  p.inertia_b = Mat3::Identity() * 0.0959999859_r;
  p.gravity_w = Vec3(0, 0, -kStandardGravity);
  p.max_yaw_rate_radps = kPi / 3;
  p.gain_ranges = lee_gain_ranges_rov();
  p.randomize_gains = true;  // fully_actuated_controller_rov.py: randomize_params = True
  return p;
}

void lee_reset(const LeeParams& params, LeeState& state) {
  state = LeeState();
  state.gains = lee_nominal_gains(params.gain_ranges);
}

void lee_reset(const LeeParams& params, LeeState& state, RngStream& rng) {
  lee_reset(params, state);
  if (params.randomize_gains) state.gains = randomize_lee_gains(params.gain_ranges, rng);
}

Wrench update_lee_position(const LeeParams& p, LeeState& s, const RigidBodyState& b, const real* action) {
  real a[kLeeActionDim];
  std::uint32_t faults = 0;
  if (!accept(p, s, b, action, kLeeActionDim, a, faults)) return s.last_safe_wrench_b;
  const AttitudeFrame fr = attitude_frame(b.orientation_wb);
  // a = K_pos (p_sp - p) + K_vel (0 - v)
  const Vec3 accel_w =
      s.gains.k_pos.cwiseProduct(Vec3(a[0], a[1], a[2]) - b.position_w) - s.gains.k_vel.cwiseProduct(b.linvel_w);
  real c_psi, s_psi;
  sin_cos(a[3], s_psi, c_psi);
  return finish_force_heading<false>(p, s, b, fr, accel_w, c_psi, s_psi, Vec3::Zero(), faults);
}

Wrench update_lee_velocity(const LeeParams& p, LeeState& s, const RigidBodyState& b, const real* action) {
  real a[kLeeActionDim];
  std::uint32_t faults = 0;
  if (!accept(p, s, b, action, kLeeActionDim, a, faults)) return s.last_safe_wrench_b;
  const AttitudeFrame fr = attitude_frame(b.orientation_wb);
  // The position term K_pos (p - p) is exactly zero and left out.
  const Vec3 accel_w = s.gains.k_vel.cwiseProduct(vehicle_to_world(fr, a[0], a[1], a[2]) - b.linvel_w);
  const Vec3 w_d = clamp_body_yaw_rate(body_rate_of_yaw_rate(fr.r_wb, a[3]), p.max_yaw_rate_radps);
  // Heading = current yaw (quirk 5): yaw is steered by the rate term only.
  return finish_force_heading<true>(p, s, b, fr, accel_w, fr.cos_yaw, fr.sin_yaw, w_d, faults);
}

Wrench update_lee_velocity_steering_angle(const LeeParams& p, LeeState& s, const RigidBodyState& b,
                                          const real* action) {
  real a[kLeeActionDim];
  std::uint32_t faults = 0;
  if (!accept(p, s, b, action, kLeeActionDim, a, faults)) return s.last_safe_wrench_b;
  const AttitudeFrame fr = attitude_frame(b.orientation_wb);
  const Vec3 accel_w = s.gains.k_vel.cwiseProduct(vehicle_to_world(fr, a[0], a[1], a[2]) - b.linvel_w);
  real c_psi, s_psi;
  sin_cos(a[3], s_psi, c_psi);
  return finish_force_heading<false>(p, s, b, fr, accel_w, c_psi, s_psi, Vec3::Zero(), faults);
}

Wrench update_lee_acceleration(const LeeParams& p, LeeState& s, const RigidBodyState& b, const real* action) {
  real a[kLeeActionDim];
  std::uint32_t faults = 0;
  if (!accept(p, s, b, action, kLeeActionDim, a, faults)) return s.last_safe_wrench_b;
  const AttitudeFrame fr = attitude_frame(b.orientation_wb);
  const Vec3 accel_w(a[0], a[1], a[2]);
  const Vec3 f_w = (accel_w - p.gravity_w) * p.mass_kg;
  const real fz = f_w.dot(fr.r_wb.col(2));
  // Quirk 4, reproduced because the golden data records it: the reference takes
  // pitch_d = atan2(Fx, Fz), roll_d = atan2(-Fy, sqrt(Fx^2 + Fz^2)) from the WORLD-frame force as
  // if it were expressed in the vehicle frame, then composes them with the current yaw:
  // R_d = Rz(yaw) Ry(pitch_d) Rx(roll_d). At yaw 90 deg a command along world +x tilts the thrust
  // toward world +y. The angles' cosines and sines are ratios of force components; atan2(0, 0) = 0
  // gives (1, 0), as in the reference.
  const real hxz2 = f_w[0] * f_w[0] + f_w[2] * f_w[2];
  real cp = 1, sp = 0, cr = 1, sr = 0;
  if (hxz2 > 0) {
    const real hxz = std::sqrt(hxz2);
    cp = f_w[2] / hxz;
    sp = f_w[0] / hxz;
    const real n = std::sqrt(hxz2 + f_w[1] * f_w[1]);
    cr = hxz / n;
    sr = -f_w[1] / n;
  } else if (f_w[1] != 0) {
    // Force along world y only: roll_d = -+90 deg, pitch_d = atan2(0, 0) = 0.
    cr = 0;
    sr = f_w[1] > 0 ? real(-1) : real(1);
  }
  if (!(f_w.squaredNorm() > kMinForceSq)) faults |= kFaultSingular;  // zero thrust: attitude is moot
  const Mat3 r_d = rotation_zyx(fr.cos_yaw, fr.sin_yaw, cp, sp, cr, sr);
  const Vec3 w_d = clamp_body_yaw_rate(body_rate_of_yaw_rate(fr.r_wb, a[3]), p.max_yaw_rate_radps);
  const Vec3 tau = lee_torque<true>(s.gains, p.inertia_b, fr.r_wb, r_d, b.angvel_b, w_d);
  return commit(s, Vec3(0, 0, fz), tau, accel_w, xyzw_nonneg_w(quat_from_rotation_matrix(r_d)), w_d, faults);
}

Wrench update_lee_attitude(const LeeParams& p, LeeState& s, const RigidBodyState& b, const real* action) {
  real a[kLeeActionDim];
  std::uint32_t faults = 0;
  if (!accept(p, s, b, action, kLeeActionDim, a, faults)) return s.last_safe_wrench_b;
  const AttitudeFrame fr = attitude_frame(b.orientation_wb);
  // Not tilt-compensated (quirk 5): the command scales the hover thrust.
  const real fz = (a[0] + 1) * p.mass_kg * p.gravity_w.norm();
  real cp, sp, cr, sr;
  sin_cos(a[2], sp, cp);
  sin_cos(a[1], sr, cr);
  const Mat3 r_d = rotation_zyx(fr.cos_yaw, fr.sin_yaw, cp, sp, cr, sr);
  const Vec3 w_d = clamp_body_yaw_rate(body_rate_of_yaw_rate(fr.r_wb, a[3]), p.max_yaw_rate_radps);
  const Vec3 tau = lee_torque<true>(s.gains, p.inertia_b, fr.r_wb, r_d, b.angvel_b, w_d);
  return commit(s, Vec3(0, 0, fz), tau, Vec3::Zero(), xyzw_nonneg_w(quat_from_rotation_matrix(r_d)), w_d, faults);
}

Wrench update_lee_rates(const LeeParams& p, LeeState& s, const RigidBodyState& b, const real* action) {
  real a[kLeeActionDim];
  std::uint32_t faults = 0;
  if (!accept(p, s, b, action, kLeeActionDim, a, faults)) return s.last_safe_wrench_b;
  // Quirk 1: the reference's thrust line, m (command - g_vector), raises for every batch size, and
  // for one environment would have read the command as a vertical acceleration offset. We use the
  // attitude controller's convention instead, so the two controllers share one thrust meaning:
  // fz = (command + 1) m |g| (command 0 = hover thrust).
  const real fz = (a[0] + 1) * p.mass_kg * p.gravity_w.norm();
  // The reference calls its torque routine with R_d = R, i.e. E = I (up to rounding): e_R = 0 and
  // e_w = w - w_d. Quirk 2: it clamps the body-z rate in the caller's action buffer; we clamp a copy.
  const Vec3 w_d = clamp_body_yaw_rate(Vec3(a[1], a[2], a[3]), p.max_yaw_rate_radps);
  const Vec3& w = b.angvel_b;
  const Vec3 tau = -s.gains.k_angvel.cwiseProduct(w - w_d) + gyroscopic(p.inertia_b, w);
  return commit(s, Vec3(0, 0, fz), tau, Vec3::Zero(), xyzw_nonneg_w(b.orientation_wb), w_d, faults);
}

Wrench update_rov_fully_actuated(const LeeParams& p, LeeState& s, const RigidBodyState& b, const real* action) {
  real a[kPoseActionDim];
  std::uint32_t faults = 0;
  if (!accept(p, s, b, action, kPoseActionDim, a, faults)) return s.last_safe_wrench_b;
  const Mat3 r_wb = rotation_of(b.orientation_wb);  // no yaw needed: skip attitude_frame()
  // Quirk 3: the reference normalises the command quaternion in the caller's buffer; we normalise a
  // copy. A (near-)zero quaternion gives what the reference's eps-clamped normalisation gives:
  // the identity attitude (level, heading +x), with kFaultSingular.
  Vec4 q_d(a[3], a[4], a[5], a[6]);
  const real n2 = q_d.squaredNorm();
  if (n2 > kMinQuatNormSq) {
    q_d *= 1 / std::sqrt(n2);
  } else {
    q_d = Vec4(0, 0, 0, 1);
    faults |= kFaultSingular;
  }
  const Vec3 accel_w =
      s.gains.k_pos.cwiseProduct(Vec3(a[0], a[1], a[2]) - b.position_w) - s.gains.k_vel.cwiseProduct(b.linvel_w);
  const Vec3 f_w = (accel_w - p.gravity_w) * p.mass_kg;
  const Vec3 f_b = r_wb.transpose() * f_w;  // all three components: the ROV is fully actuated
  const Mat3 r_d = rotation_of(quat_from_xyzw(q_d));
  const Vec3 tau = lee_torque<false>(s.gains, p.inertia_b, r_wb, r_d, b.angvel_b, Vec3::Zero());
  return commit(s, f_b, tau, accel_w, q_d, Vec3::Zero(), faults);
}

}  // namespace kestrel
