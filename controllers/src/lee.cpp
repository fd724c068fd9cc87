// Lee geometric controllers: T. Lee, M. Leok, N. H. McClamroch, "Geometric tracking control of a
// quadrotor UAV on SE(3)", IEEE CDC 2010 — as implemented by Aerial Gym (see lee.hpp).
//
// Cost notes (the Cortex-M4F cascade budget: Lee position + allocation + motor model <= ~1,500
// instructions per step):
//  - the state quaternion is turned into a rotation matrix once; yaw, body z, and the Euler-rate
//    map all come out of that matrix without trig (attitude_frame());
//  - the Euler yaw rate r maps to the body rate r * (third row of R): that row is
//    (-sin(pitch), sin(roll) cos(pitch), cos(roll) cos(pitch)), Aerial Gym's map, with no angles;
//  - the acceleration controller's desired Euler angles are never formed: their cosines and
//    sines are ratios of force components;
//  - trig is called only on commanded angles (heading, attitude roll/pitch), never on the state;
//  - no matrix inverse anywhere; rotation errors use E = R^T R_d directly;
//  - finite checks of inputs and outputs are branch-free sums (nonfinite_probe());
//  - e_R reads only the six off-diagonal entries of E (column dot products), E w_d is R^T (R_d w_d)
//    and is skipped where w_d = 0; w x J w takes 3 products with a diagonal J (flag set by
//    lee_reset); R_d's quaternion is Shepperd's method written out;
//  - the update path's helpers are forced inline, so R, R_d and intermediates stay in registers;
//  - update_lee_position checks the state once, through the output probe (see there).
// Measured on the emulated Cortex-M4F (QEMU -icount, -O2; bench/results/cortex-m4f/control.csv):
// update_lee_position 370 instructions per call (775 before the inlining and the partial E),
// ~380 for lee_rates, 490-620 for the other controllers (through update_controller()).
// kestrel::sin_cos (kernel math.hpp: Cephes polynomials, Cody-Waite reduction shared by sine and
// cosine, octant 0 inlined) replaces newlib's sinf + cosf (~160 instructions per angle and ~3.8 KB
// of Payne-Hanek reduction in the firmware's flash).
#include "kestrel/controllers/lee.hpp"

#include <cmath>

#include "kestrel/kernel/assert.hpp"
#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/quaternion.hpp"

namespace kestrel {
namespace {

// The helpers of the update path are forced inline: at -O2 GCC keeps the larger ones out of line,
// and every call then spills R, R_d and the returned vectors through the stack (measured: ~150 of
// update_lee_position's instructions on the Cortex-M4F were such loads, stores and call set-up).
// The price is flash: every controller carries its own copy (~6 KB more in the C API image,
// bench/results/cortex-m4f/memory.csv); out-of-line cold paths were tried and cost instructions.
#define KESTREL_LEE_INLINE __attribute__((always_inline)) inline


// Below |F| = 1e-6 N the collective force has no usable direction (the reference divides by |F|
// and produces NaN at exactly zero). Any real thrust command is orders of magnitude above this.
constexpr real kMinForceSq = 1e-12_r;  // N^2
// |b3 x heading| below 1e-5: the heading lies (nearly) along the thrust axis and its projection,
// which defines b1, is dominated by rounding.
constexpr real kMinCrossSq = 1e-10_r;
// A command quaternion shorter than 1e-6 cannot be normalised meaningfully.
constexpr real kMinQuatNormSq = 1e-12_r;

// Rotation matrix of q as given (not re-normalised, like the reference).
KESTREL_LEE_INLINE Mat3 rotation_of(const Quat& q) {
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
KESTREL_LEE_INLINE bool rotation_from_force_heading(const Vec3& f_w, real cos_psi, real sin_psi, const Mat3& r_wb, Mat3& r_d) {
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

// w x (J w), written out (Eigen's cross() is not always inlined on the MCU). With a diagonal J
// (LeeState::inertia_diagonal) J w is three products: the skipped terms are 0 * w_k with w finite
// (accept() checked it), so the bits are those of the full product.
KESTREL_LEE_INLINE Vec3 gyroscopic(const PlainMat3& j_b, bool j_diagonal, const Vec3& w) {
  real jw0, jw1, jw2;
  if (j_diagonal) {
    jw0 = j_b(0, 0) * w[0];
    jw1 = j_b(1, 1) * w[1];
    jw2 = j_b(2, 2) * w[2];
  } else {
    jw0 = j_b(0, 0) * w[0] + j_b(0, 1) * w[1] + j_b(0, 2) * w[2];
    jw1 = j_b(1, 0) * w[0] + j_b(1, 1) * w[1] + j_b(1, 2) * w[2];
    jw2 = j_b(2, 0) * w[0] + j_b(2, 1) * w[1] + j_b(2, 2) * w[2];
  }
  return Vec3(w[1] * jw2 - w[2] * jw1, w[2] * jw0 - w[0] * jw2, w[0] * jw1 - w[1] * jw0);
}

// Column i of R dotted with column j of R_d: entry (i, j) of E = R^T R_d.
KESTREL_LEE_INLINE real col_dot(const Mat3& r, int i, const Mat3& d, int j) {
  return r(0, i) * d(0, j) + r(1, i) * d(1, j) + r(2, i) * d(2, j);
}

// Lee et al. (2010) eqs. (10), (11), (16): E = R^T R_d, e_R = 1/2 vee(E^T - E), e_w = w - E w_d,
// tau = -k_R e_R - k_w e_w + w x J w. Only what the law reads is formed:
//  - e_R needs the six off-diagonal entries of E (each the dot product of a column of R with a
//    column of R_d: 18 products instead of the 27 of the full product, no 3x3 temporary);
//  - E w_d = R^T (R_d w_d) (two matrix-vector products, 18 products instead of 27 + 9), and
//    kRateRef = false skips it when w_d is identically zero (the compiler may not drop x * 0
//    itself: that would change NaN/inf semantics).
template <bool kRateRef>
KESTREL_LEE_INLINE Vec3 lee_torque(const LeeGains& g, const PlainMat3& j_b, bool j_diagonal, const Mat3& r_wb, const Mat3& r_d,
                       const Vec3& w_b, const Vec3& w_d) {
  const real e_r0 = 0.5_r * (col_dot(r_wb, 1, r_d, 2) - col_dot(r_wb, 2, r_d, 1));
  const real e_r1 = 0.5_r * (col_dot(r_wb, 2, r_d, 0) - col_dot(r_wb, 0, r_d, 2));
  const real e_r2 = 0.5_r * (col_dot(r_wb, 0, r_d, 1) - col_dot(r_wb, 1, r_d, 0));
  real e_w0 = w_b[0], e_w1 = w_b[1], e_w2 = w_b[2];
  if (kRateRef) {
    // v = R_d w_d (world frame), then E w_d = R^T v.
    const real v0 = r_d(0, 0) * w_d[0] + r_d(0, 1) * w_d[1] + r_d(0, 2) * w_d[2];
    const real v1 = r_d(1, 0) * w_d[0] + r_d(1, 1) * w_d[1] + r_d(1, 2) * w_d[2];
    const real v2 = r_d(2, 0) * w_d[0] + r_d(2, 1) * w_d[1] + r_d(2, 2) * w_d[2];
    e_w0 -= r_wb(0, 0) * v0 + r_wb(1, 0) * v1 + r_wb(2, 0) * v2;
    e_w1 -= r_wb(0, 1) * v0 + r_wb(1, 1) * v1 + r_wb(2, 1) * v2;
    e_w2 -= r_wb(0, 2) * v0 + r_wb(1, 2) * v1 + r_wb(2, 2) * v2;
  }
  const Vec3 gy = gyroscopic(j_b, j_diagonal, w_b);
  return Vec3(-(g.k_rot[0] * e_r0) - g.k_angvel[0] * e_w0 + gy[0], -(g.k_rot[1] * e_r1) - g.k_angvel[1] * e_w1 + gy[1],
              -(g.k_rot[2] * e_r2) - g.k_angvel[2] * e_w2 + gy[2]);
}

// Quaternion (x, y, z, w) of a rotation matrix with w >= 0: Shepperd's method as Eigen's
// Quaternion(Mat3) does it (the largest of trace / diagonal picks the pivot, one sqrt, one
// division), written out so that it inlines into the controller instead of an out-of-line Eigen
// call with its generic index arithmetic.
KESTREL_LEE_INLINE Vec4 xyzw_of_rotation(const Mat3& m) {
  real x, y, z, w;
  const real tr = m(0, 0) + m(1, 1) + m(2, 2);
  if (tr > 0) {
    real t = std::sqrt(tr + 1);
    w = 0.5_r * t;
    t = 0.5_r / t;
    x = (m(2, 1) - m(1, 2)) * t;
    y = (m(0, 2) - m(2, 0)) * t;
    z = (m(1, 0) - m(0, 1)) * t;
  } else if (m(0, 0) >= m(1, 1) && m(0, 0) >= m(2, 2)) {  // pivot x (Eigen: i = 0 unless beaten)
    real t = std::sqrt(m(0, 0) - m(1, 1) - m(2, 2) + 1);
    x = 0.5_r * t;
    t = 0.5_r / t;
    w = (m(2, 1) - m(1, 2)) * t;
    y = (m(1, 0) + m(0, 1)) * t;
    z = (m(2, 0) + m(0, 2)) * t;
  } else if (!(m(2, 2) > m(1, 1))) {  // pivot y
    real t = std::sqrt(m(1, 1) - m(2, 2) - m(0, 0) + 1);
    y = 0.5_r * t;
    t = 0.5_r / t;
    w = (m(0, 2) - m(2, 0)) * t;
    z = (m(2, 1) + m(1, 2)) * t;
    x = (m(0, 1) + m(1, 0)) * t;
  } else {  // pivot z
    real t = std::sqrt(m(2, 2) - m(0, 0) - m(1, 1) + 1);
    z = 0.5_r * t;
    t = 0.5_r / t;
    w = (m(1, 0) - m(0, 1)) * t;
    x = (m(0, 2) + m(2, 0)) * t;
    y = (m(1, 2) + m(2, 1)) * t;
  }
  if (w < 0) return Vec4(-x, -y, -z, -w);
  return Vec4(x, y, z, w);
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
KESTREL_LEE_INLINE real nonfinite_probe(const real* v, std::size_t n) {
  real acc = 0;
  for (std::size_t i = 0; i < n; ++i) acc += v[i] * 0;
  return acc;
}
KESTREL_LEE_INLINE real nonfinite_probe(const Vec3& v) { return v[0] * 0 + v[1] * 0 + v[2] * 0; }
KESTREL_LEE_INLINE real nonfinite_probe(const Vec4& v) { return v[0] * 0 + v[1] * 0 + v[2] * 0 + v[3] * 0; }

KESTREL_LEE_INLINE bool state_finite(const RigidBodyState& b) {
  const Quat& q = b.orientation_wb;
  const real probe = nonfinite_probe(b.position_w) + nonfinite_probe(b.linvel_w) + nonfinite_probe(b.angvel_b) +
                     (q.x() * 0 + q.y() * 0 + q.z() * 0 + q.w() * 0);
  return probe == 0;
}

KESTREL_LEE_INLINE Wrench reject(LeeState& s, std::uint32_t faults) {
  s.step_faults = faults;
  s.faults.raise(faults);
  return s.last_safe_wrench_b;
}

// Validates the inputs and copies the clipped action into a[0..n). False: the update is rejected
// (the held wrench is then in s.last_safe_wrench_b).
KESTREL_LEE_INLINE bool accept(const LeeParams& p, LeeState& s, const RigidBodyState& b, const real* action, std::size_t n,
                   real* a, std::uint32_t& faults) {
  KESTREL_ASSERT(action != nullptr);
  faults = 0;
  if (!(nonfinite_probe(action, n) == 0)) faults |= kFaultNonFiniteCommand;
  if (!state_finite(b)) faults |= kFaultNonFiniteState;
  if (faults != 0) {
    reject(s, faults);
    return false;
  }
  // In range (the usual case): two compares per component; clipping is the rare path.
  const real lo = p.action_min, hi = p.action_max;
  bool out_of_range = false;
  for (std::size_t i = 0; i < n; ++i) {
    a[i] = action[i];
    if (a[i] < lo || a[i] > hi) out_of_range = true;
  }
  if (out_of_range) {
    faults = kFaultCommandOutOfRange;
    for (std::size_t i = 0; i < n; ++i) a[i] = clamp(a[i], lo, hi);
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

// commit() for the thrust-only controllers: the force is (0, 0, fz), so the probe skips the two
// constant zeros, and with kRateRef = false the desired rate is the constant zero (nothing to
// probe). The stored intermediates are the same as commit() stores.
//
// The rejection is out of line and cold: it keeps its registers and loads off the update's path.
__attribute__((noinline, cold)) Wrench reject_nonfinite_output(LeeState& s, const RigidBodyState* unchecked_state,
                                                               std::uint32_t faults) {
  if (unchecked_state != nullptr && !state_finite(*unchecked_state)) return reject(s, kFaultNonFiniteState);
  return reject(s, faults | kFaultNonFiniteOutput);
}

// kStateChecked = false: the caller skipped the input check of the vehicle state because every
// state component reaches a probed output (see update_lee_position); a failed probe then first
// asks whether the state was at fault, so the flags are those the up-front check would raise.
template <bool kRateRef, bool kStateChecked = true>
KESTREL_LEE_INLINE Wrench commit_fz(LeeState& s, const RigidBodyState& b, real fz, const Vec3& torque_b,
                                   const Vec3& accel_w, const Vec4& q_d, const Vec3& w_d, std::uint32_t faults) {
  // accel_w needs no probe of its own: fz = m (a - g) . R e3 takes every component of it times a
  // finite factor or a non-finite R (inf * x and NaN * x are non-finite, 0 * inf is NaN), so a
  // non-finite a_i always makes fz non-finite.
  real probe = fz * 0 + nonfinite_probe(torque_b) + nonfinite_probe(q_d);
  if (kRateRef) probe += nonfinite_probe(w_d);
  if (!(probe == 0)) return reject_nonfinite_output(s, kStateChecked ? nullptr : &b, faults);
  s.last_safe_wrench_b.force_b = Vec3(0, 0, fz);
  s.last_safe_wrench_b.torque_b = torque_b;
  s.accel_command_w = accel_w;
  s.desired_quat_xyzw = q_d;
  s.desired_angvel_b = w_d;
  s.step_faults = faults;
  s.faults.raise(faults);
  return s.last_safe_wrench_b;
}

// Shared tail of the position-type controllers: F = m (a - g), fz = F . body z, R_d from F and a
// heading, torque with the given desired rate. Takes R only (the position controller needs no yaw
// of the state, so it skips attitude_frame()'s sqrt).
template <bool kRateRef, bool kStateChecked = true>
KESTREL_LEE_INLINE Wrench finish_force_heading(const LeeParams& p, LeeState& s, const RigidBodyState& b, const Mat3& r_wb,
                                   const Vec3& accel_w, real cos_psi, real sin_psi, const Vec3& w_d,
                                   std::uint32_t faults) {
  const Vec3 f_w((accel_w[0] - p.gravity_w[0]) * p.mass_kg, (accel_w[1] - p.gravity_w[1]) * p.mass_kg,
                 (accel_w[2] - p.gravity_w[2]) * p.mass_kg);
  const real fz = f_w[0] * r_wb(0, 2) + f_w[1] * r_wb(1, 2) + f_w[2] * r_wb(2, 2);
  Mat3 r_d;
  if (rotation_from_force_heading(f_w, cos_psi, sin_psi, r_wb, r_d)) faults |= kFaultSingular;
  const Vec3 tau = lee_torque<kRateRef>(s.gains, p.inertia_b, s.inertia_diagonal, r_wb, r_d, b.angvel_b, w_d);
  return commit_fz<kRateRef, kStateChecked>(s, b, fz, tau, accel_w, xyzw_of_rotation(r_d), w_d, faults);
}

// Velocity command rotated from the vehicle (yaw-only) frame into the world.
inline Vec3 vehicle_to_world(const AttitudeFrame& fr, real vx, real vy, real vz) {
  return Vec3(fr.cos_yaw * vx - fr.sin_yaw * vy, fr.sin_yaw * vx + fr.cos_yaw * vy, vz);
}

// attitude_frame(), inlined into the controllers (the public function wraps it).
KESTREL_LEE_INLINE AttitudeFrame frame_of(const Quat& q_wb) {
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

}  // namespace

AttitudeFrame attitude_frame(const Quat& q_wb) { return frame_of(q_wb); }

Status validate_lee_params(const LeeParams& p) {
  // The upper bounds (lee.hpp) refuse parameters with which overflow in the update is unavoidable.
  if (!is_finite(p.mass_kg) || !(p.mass_kg > 0) || !(p.mass_kg <= kLeeMaxMassKg)) return Status::invalid_argument;
  if (!all_finite(p.inertia_b) || !all_finite(p.gravity_w)) return Status::invalid_argument;
  if (!(p.inertia_b.map().cwiseAbs().maxCoeff() <= kLeeMaxInertiaKgm2)) return Status::invalid_argument;
  if (!(p.gravity_w.map().cwiseAbs().maxCoeff() <= kLeeMaxGravityMps2)) return Status::invalid_argument;
  if (!is_finite(p.max_yaw_rate_radps) || !(p.max_yaw_rate_radps >= 0)) return Status::invalid_argument;
  if (!is_finite(p.action_min) || !is_finite(p.action_max) || !(p.action_min < p.action_max)) {
    return Status::invalid_argument;
  }
  const LeeGains& lo = p.gain_ranges.min;
  const LeeGains& hi = p.gain_ranges.max;
  const PlainVec3* los[4] = {&lo.k_pos, &lo.k_vel, &lo.k_rot, &lo.k_angvel};
  const PlainVec3* his[4] = {&hi.k_pos, &hi.k_vel, &hi.k_rot, &hi.k_angvel};
  for (int i = 0; i < 4; ++i) {
    if (!all_finite(*los[i]) || !all_finite(*his[i])) return Status::invalid_argument;
    for (int k = 0; k < 3; ++k) {
      if (!((*los[i])[k] <= (*his[i])[k])) return Status::invalid_argument;
      if (!(std::fabs((*los[i])[k]) <= kLeeMaxGain) || !(std::fabs((*his[i])[k]) <= kLeeMaxGain)) {
        return Status::invalid_argument;
      }
    }
  }
  return Status::ok;
}

LeeGains lee_nominal_gains(const LeeGainRanges& r) {
  // (max + min) / 2 in this order, as Aerial Gym computes K_*_tensor_current: in float this gives
  // the golden gains bit for bit (e.g. (0.2f + 0.1f) / 2 = 0.150000006f).
  LeeGains g;
  g.k_pos = (r.max.k_pos.map() + r.min.k_pos.map()) / 2;
  g.k_vel = (r.max.k_vel.map() + r.min.k_vel.map()) / 2;
  g.k_rot = (r.max.k_rot.map() + r.min.k_rot.map()) / 2;
  g.k_angvel = (r.max.k_angvel.map() + r.min.k_angvel.map()) / 2;
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
  const PlainMat3& j = params.inertia_b;
  state.inertia_diagonal = j(0, 1) == 0 && j(0, 2) == 0 && j(1, 0) == 0 && j(1, 2) == 0 && j(2, 0) == 0 && j(2, 1) == 0;
}

void lee_reset(const LeeParams& params, LeeState& state, RngStream& rng) {
  lee_reset(params, state);
  if (params.randomize_gains) state.gains = randomize_lee_gains(params.gain_ranges, rng);
}

Wrench update_lee_position(const LeeParams& p, LeeState& s, const RigidBodyState& b, const real* action) {
  // Input handling as accept(), with the state check checked once, at the end: every component of
  // the state reaches a probed output (position and velocity -> accel_w -> fz, body rate ->
  // torque through k_w e_w, every quaternion component -> fz = F . R e3, whose entries
  // 2(xz + wy), 2(yz - wx), 1 - 2(xx + yy) hold all four; 0 * inf is NaN, so zero gains or zero
  // force do not hide one), so a non-finite state always fails commit_fz's probe, which then names
  // the state. The command is still checked first: clipping would turn +-inf into a finite value.
  KESTREL_ASSERT(action != nullptr);
  // Unrolled by hand (GCC -O2 keeps the loops, and the array then lives on the stack).
  real a0 = action[0], a1 = action[1], a2 = action[2], a3 = action[3];
  if (!(a0 * 0 + a1 * 0 + a2 * 0 + a3 * 0 == 0)) {
    return reject(s, kFaultNonFiniteCommand | (state_finite(b) ? 0u : std::uint32_t{kFaultNonFiniteState}));
  }
  // In range (the usual case): two compares per component and nothing else; clipping is the rare
  // path, with the same result as clamp() in accept().
  std::uint32_t faults = 0;
  const real lo = p.action_min, hi = p.action_max;
  if (a0 < lo || a0 > hi || a1 < lo || a1 > hi || a2 < lo || a2 > hi || a3 < lo || a3 > hi) {
    faults = kFaultCommandOutOfRange;
    a0 = clamp(a0, lo, hi);
    a1 = clamp(a1, lo, hi);
    a2 = clamp(a2, lo, hi);
    a3 = clamp(a3, lo, hi);
  }
  // Only R is needed (the heading is commanded): no attitude_frame(), whose yaw costs a sqrt.
  const Mat3 r_wb = rotation_of(b.orientation_wb);
  // a = K_pos (p_sp - p) + K_vel (0 - v), per component (no Eigen expression temporaries).
  const PlainVec3& kp = s.gains.k_pos;
  const PlainVec3& kv = s.gains.k_vel;
  const Vec3 accel_w(kp[0] * (a0 - b.position_w[0]) - kv[0] * b.linvel_w[0],
                     kp[1] * (a1 - b.position_w[1]) - kv[1] * b.linvel_w[1],
                     kp[2] * (a2 - b.position_w[2]) - kv[2] * b.linvel_w[2]);
  real c_psi, s_psi;
  sin_cos(a3, s_psi, c_psi);
  // w_d = 0 (Aerial Gym's position controller has no rate reference): lee_torque<false> skips E w_d.
  return finish_force_heading<false, false>(p, s, b, r_wb, accel_w, c_psi, s_psi, Vec3::Zero(), faults);
}

Wrench update_lee_velocity(const LeeParams& p, LeeState& s, const RigidBodyState& b, const real* action) {
  real a[kLeeActionDim];
  std::uint32_t faults = 0;
  if (!accept(p, s, b, action, kLeeActionDim, a, faults)) return s.last_safe_wrench_b;
  const AttitudeFrame fr = frame_of(b.orientation_wb);
  // The position term K_pos (p - p) is exactly zero and left out.
  const Vec3 accel_w = s.gains.k_vel.map().cwiseProduct(vehicle_to_world(fr, a[0], a[1], a[2]) - b.linvel_w);
  const Vec3 w_d = clamp_body_yaw_rate(body_rate_of_yaw_rate(fr.r_wb, a[3]), p.max_yaw_rate_radps);
  // Heading = current yaw (quirk 5): yaw is steered by the rate term only.
  return finish_force_heading<true>(p, s, b, fr.r_wb, accel_w, fr.cos_yaw, fr.sin_yaw, w_d, faults);
}

Wrench update_lee_velocity_steering_angle(const LeeParams& p, LeeState& s, const RigidBodyState& b,
                                          const real* action) {
  real a[kLeeActionDim];
  std::uint32_t faults = 0;
  if (!accept(p, s, b, action, kLeeActionDim, a, faults)) return s.last_safe_wrench_b;
  const AttitudeFrame fr = frame_of(b.orientation_wb);
  const Vec3 accel_w = s.gains.k_vel.map().cwiseProduct(vehicle_to_world(fr, a[0], a[1], a[2]) - b.linvel_w);
  real c_psi, s_psi;
  sin_cos(a[3], s_psi, c_psi);
  return finish_force_heading<false>(p, s, b, fr.r_wb, accel_w, c_psi, s_psi, Vec3::Zero(), faults);
}

Wrench update_lee_acceleration(const LeeParams& p, LeeState& s, const RigidBodyState& b, const real* action) {
  real a[kLeeActionDim];
  std::uint32_t faults = 0;
  if (!accept(p, s, b, action, kLeeActionDim, a, faults)) return s.last_safe_wrench_b;
  const AttitudeFrame fr = frame_of(b.orientation_wb);
  const Vec3 accel_w(a[0], a[1], a[2]);
  const Vec3 f_w = (accel_w - p.gravity_w.map()) * p.mass_kg;
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
  const Vec3 tau = lee_torque<true>(s.gains, p.inertia_b, s.inertia_diagonal, fr.r_wb, r_d, b.angvel_b, w_d);
  return commit(s, Vec3(0, 0, fz), tau, accel_w, xyzw_of_rotation(r_d), w_d, faults);
}

Wrench update_lee_attitude(const LeeParams& p, LeeState& s, const RigidBodyState& b, const real* action) {
  real a[kLeeActionDim];
  std::uint32_t faults = 0;
  if (!accept(p, s, b, action, kLeeActionDim, a, faults)) return s.last_safe_wrench_b;
  const AttitudeFrame fr = frame_of(b.orientation_wb);
  // Not tilt-compensated (quirk 5): the command scales the hover thrust.
  const real fz = (a[0] + 1) * p.mass_kg * p.gravity_w.map().norm();
  real cp, sp, cr, sr;
  sin_cos(a[2], sp, cp);
  sin_cos(a[1], sr, cr);
  const Mat3 r_d = rotation_zyx(fr.cos_yaw, fr.sin_yaw, cp, sp, cr, sr);
  const Vec3 w_d = clamp_body_yaw_rate(body_rate_of_yaw_rate(fr.r_wb, a[3]), p.max_yaw_rate_radps);
  const Vec3 tau = lee_torque<true>(s.gains, p.inertia_b, s.inertia_diagonal, fr.r_wb, r_d, b.angvel_b, w_d);
  return commit(s, Vec3(0, 0, fz), tau, Vec3::Zero(), xyzw_of_rotation(r_d), w_d, faults);
}

Wrench update_lee_rates(const LeeParams& p, LeeState& s, const RigidBodyState& b, const real* action) {
  real a[kLeeActionDim];
  std::uint32_t faults = 0;
  if (!accept(p, s, b, action, kLeeActionDim, a, faults)) return s.last_safe_wrench_b;
  // Quirk 1: the reference's thrust line, m (command - g_vector), raises for every batch size, and
  // for one environment would have read the command as a vertical acceleration offset. We use the
  // attitude controller's convention instead, so the two controllers share one thrust meaning:
  // fz = (command + 1) m |g| (command 0 = hover thrust).
  const real fz = (a[0] + 1) * p.mass_kg * p.gravity_w.map().norm();
  // The reference calls its torque routine with R_d = R, i.e. E = I (up to rounding): e_R = 0 and
  // e_w = w - w_d. Quirk 2: it clamps the body-z rate in the caller's action buffer; we clamp a copy.
  const Vec3 w_d = clamp_body_yaw_rate(Vec3(a[1], a[2], a[3]), p.max_yaw_rate_radps);
  const Vec3& w = b.angvel_b;
  const Vec3 tau = -s.gains.k_angvel.map().cwiseProduct(w - w_d) + gyroscopic(p.inertia_b, s.inertia_diagonal, w);
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
      s.gains.k_pos.map().cwiseProduct(Vec3(a[0], a[1], a[2]) - b.position_w) - s.gains.k_vel.map().cwiseProduct(b.linvel_w);
  const Vec3 f_w = (accel_w - p.gravity_w.map()) * p.mass_kg;
  const Vec3 f_b = r_wb.transpose() * f_w;  // all three components: the ROV is fully actuated
  const Mat3 r_d = rotation_of(quat_from_xyzw(q_d));
  const Vec3 tau = lee_torque<false>(s.gains, p.inertia_b, s.inertia_diagonal, r_wb, r_d, b.angvel_b, Vec3::Zero());
  return commit(s, f_b, tau, accel_w, q_d, Vec3::Zero(), faults);
}

#undef KESTREL_LEE_INLINE

}  // namespace kestrel
