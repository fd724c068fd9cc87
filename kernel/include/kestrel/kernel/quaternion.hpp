// Quaternion and frame helpers.
//
// Public convention: quaternions are xyzw (scalar last), Hamilton product, and q_wb rotates
// body-frame vectors into the world frame. Eigen's Quaternion stores its coefficients as
// (x, y, z, w) too, but its four-scalar constructor takes (w, x, y, z): quat_from_xyzw() is the one
// place in Kestrel allowed to call that constructor.
//
// Euler angles follow Aerial Gym: roll, pitch, yaw with R = Rz(yaw) Ry(pitch) Rx(roll) (intrinsic
// Z-Y'-X'', i.e. extrinsic X then Y then Z). The "vehicle" frame is the yaw-only frame.
#pragma once

#include <cmath>

#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel {

/// The one conversion from xyzw components to an Eigen quaternion.
inline Quat quat_from_xyzw(real x, real y, real z, real w) { return Quat(w, x, y, z); }
inline Quat quat_from_xyzw(const real* xyzw) { return quat_from_xyzw(xyzw[0], xyzw[1], xyzw[2], xyzw[3]); }
inline Quat quat_from_xyzw(const Vec4& xyzw) { return quat_from_xyzw(xyzw[0], xyzw[1], xyzw[2], xyzw[3]); }

/// xyzw components of a quaternion.
inline Vec4 to_xyzw(const Quat& q) { return Vec4(q.x(), q.y(), q.z(), q.w()); }

/// Hamilton product a (x) b with the same bits on every target. Eigen's `a * b` for float
/// quaternions takes its SSE path on the x86-64 host (Geometry_SIMD.h, quat_product) and its
/// generic formula on the MCUs, and the two sum the four products of each component in different
/// orders, so the host's and the firmware's trajectories drifted apart from the second step of a
/// flight (ctest kestrel_firmware_policy.host_parity). This writes the SSE path's order out in
/// scalar code: the host's bits are unchanged (and so is sim/src/batch_kernel.inc, which mirrors
/// them), and every MCU now computes them too. Double builds keep Eigen's product (no cross-target
/// claim there; kernel/math.hpp's exp_det/tanh_det are the library's in double as well).
inline Quat quat_mul(const Quat& a, const Quat& b) {
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  return a * b;
#else
  const real ax = a.x(), ay = a.y(), az = a.z(), aw = a.w();
  const real bx = b.x(), by = b.y(), bz = b.z(), bw = b.w();
  return quat_from_xyzw((ax * bw - az * by) + (ay * bz + aw * bx),  //
                        (ay * bw - ax * bz) + (az * bx + aw * by),  //
                        (az * bw - ay * bx) + (ax * by + aw * bz),  //
                        (aw * bw - ax * bx) - (az * bz + ay * by));
#endif
}

/// |q| of xyzw components with the same bits on every target: Eigen's `norm()` of a float Vec4 is
/// one SSE reduction on the host, (x^2 + z^2) + (y^2 + w^2), and a pairwise unrolled sum on the
/// MCUs, (x^2 + y^2) + (z^2 + w^2); this is the host's order in scalar code (see quat_mul).
inline real norm_xyzw(const Vec4& q) {
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  return q.norm();
#else
  return std::sqrt((q[0] * q[0] + q[2] * q[2]) + (q[1] * q[1] + q[3] * q[3]));
#endif
}

/// Rotate v by q (q v q*), i.e. body -> world for q_wb.
inline Vec3 rotate(const Quat& q, const Vec3& v) { return q._transformVector(v); }
/// Rotate v by q^-1 (world -> body for q_wb). q must be unit.
inline Vec3 rotate_inverse(const Quat& q, const Vec3& v) { return q.conjugate()._transformVector(v); }

/// Rotation matrix of a (not necessarily unit) quaternion, as Aerial Gym's quat_to_rotation_matrix
/// does it: the formula for unit quaternions applied to the components as given.
inline Mat3 rotation_matrix(const Quat& q) { return q.toRotationMatrix(); }

/// Elementary rotations.
inline Mat3 rot_x(real a) {
  const real c = std::cos(a), s = std::sin(a);
  Mat3 r;
  r << 1, 0, 0, 0, c, -s, 0, s, c;
  return r;
}
inline Mat3 rot_y(real a) {
  const real c = std::cos(a), s = std::sin(a);
  Mat3 r;
  r << c, 0, s, 0, 1, 0, -s, 0, c;
  return r;
}
inline Mat3 rot_z(real a) {
  const real c = std::cos(a), s = std::sin(a);
  Mat3 r;
  r << c, -s, 0, s, c, 0, 0, 0, 1;
  return r;
}

/// R = Rz(yaw) Ry(pitch) Rx(roll).
inline Mat3 rotation_from_euler_xyz(real roll, real pitch, real yaw) { return rot_z(yaw) * rot_y(pitch) * rot_x(roll); }

/// Quaternion of R = Rz(yaw) Ry(pitch) Rx(roll) (closed form, half angles).
inline Quat quat_from_euler_xyz(real roll, real pitch, real yaw) {
  const real cr = std::cos(roll * 0.5_r), sr = std::sin(roll * 0.5_r);
  const real cp = std::cos(pitch * 0.5_r), sp = std::sin(pitch * 0.5_r);
  const real cy = std::cos(yaw * 0.5_r), sy = std::sin(yaw * 0.5_r);
  return quat_from_xyzw(sr * cp * cy - cr * sp * sy,  //
                        cr * sp * cy + sr * cp * sy,  //
                        cr * cp * sy - sr * sp * cy,  //
                        cr * cp * cy + sr * sp * sy);
}

/// Euler angles (roll, pitch, yaw) in [0, 2 pi) as the reference computes them before wrapping:
/// roll = atan2(2(wx+yz), w^2-x^2-y^2+z^2), pitch = asin(2(wy-zx)) (+-pi/2 once |arg| >= 1),
/// yaw = atan2(2(wz+xy), w^2+x^2-y^2-z^2), each taken modulo 2 pi.
inline Vec3 euler_xyz_two_pi(const Quat& q) {
  const real x = q.x(), y = q.y(), z = q.z(), w = q.w();
  const real roll = std::atan2(2 * (w * x + y * z), w * w - x * x - y * y + z * z);
  const real sinp = 2 * (w * y - z * x);
  const real pitch = std::fabs(sinp) >= 1 ? std::copysign(kPi / 2, sinp) : std::asin(sinp);
  const real yaw = std::atan2(2 * (w * z + x * y), w * w + x * x - y * y - z * z);
  return Vec3(wrap_two_pi(roll), wrap_two_pi(pitch), wrap_two_pi(yaw));
}

/// Euler angles (roll, pitch, yaw) wrapped to [-pi, pi) — the multirotor convention.
inline Vec3 euler_xyz(const Quat& q) {
  const Vec3 e = euler_xyz_two_pi(q);
  return Vec3(wrap_pi(e[0]), wrap_pi(e[1]), wrap_pi(e[2]));
}

/// Yaw-only "vehicle" orientation of q: rotation about world z by q's yaw.
inline Quat vehicle_quat(const Quat& q) {
  const real yaw = euler_xyz(q)[2];
  return quat_from_xyzw(0, 0, std::sin(yaw * 0.5_r), std::cos(yaw * 0.5_r));
}

/// hat(v) w = v x w.
inline Mat3 hat(const Vec3& v) {
  Mat3 m;
  m << 0, -v[2], v[1], v[2], 0, -v[0], -v[1], v[0], 0;
  return m;
}

/// Inverse of hat() for a skew-symmetric matrix (reads the lower-triangle entries, as Lee et al.).
inline Vec3 vee(const Mat3& m) { return Vec3(m(2, 1), m(0, 2), m(1, 0)); }

/// Euler-rate to body-rate map for a pure yaw rate r at roll phi, pitch theta:
/// w_b = (-sin(theta) r, sin(phi) cos(theta) r, cos(phi) cos(theta) r).
inline Vec3 body_rate_from_yaw_rate(real roll, real pitch, real yaw_rate) {
  return Vec3(-std::sin(pitch) * yaw_rate, std::sin(roll) * std::cos(pitch) * yaw_rate,
              std::cos(roll) * std::cos(pitch) * yaw_rate);
}

/// Quaternion of a rotation matrix (Shepperd's method: the best-conditioned of four candidates),
/// with a non-negative scalar part.
inline Quat quat_from_rotation_matrix(const Mat3& r) {
  Quat q(r);
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  return q;
}

}  // namespace kestrel
