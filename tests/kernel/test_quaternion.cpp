#include "kestrel/kernel/quaternion.hpp"

#include "ktest.hpp"

using namespace kestrel;

namespace {
constexpr double kTol = 2e-6;
}

KTEST(Quaternion, XyzwRoundTripIsTheOnlyConversion) {
  const Quat q = quat_from_xyzw(0.1_r, -0.2_r, 0.3_r, 0.9_r);
  KEXPECT_EQ(q.x(), 0.1_r);
  KEXPECT_EQ(q.y(), -0.2_r);
  KEXPECT_EQ(q.z(), 0.3_r);
  KEXPECT_EQ(q.w(), 0.9_r);
  const Vec4 v = to_xyzw(q);
  KEXPECT_EQ(v[0], 0.1_r);
  KEXPECT_EQ(v[3], 0.9_r);
  // Eigen's own coefficient storage is xyzw as well.
  KEXPECT_EQ(q.coeffs()[3], 0.9_r);
}

KTEST(Quaternion, RotatesBodyToWorld) {
  // 90 deg about z: body x -> world y.
  const Quat q = quat_from_euler_xyz(0, 0, kPi / 2);
  const Vec3 v = rotate(q, Vec3(1, 0, 0));
  KEXPECT_NEAR(v[0], 0, kTol);
  KEXPECT_NEAR(v[1], 1, kTol);
  KEXPECT_NEAR(v[2], 0, kTol);
  const Vec3 b = rotate_inverse(q, Vec3(0, 1, 0));
  KEXPECT_NEAR(b[0], 1, kTol);
}

KTEST(Quaternion, EulerMatchesRotationMatrixComposition) {
  const real r = 0.3_r, p = -0.4_r, y = 2.5_r;
  const Mat3 m = rotation_from_euler_xyz(r, p, y);
  const Mat3 mq = rotation_matrix(quat_from_euler_xyz(r, p, y));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) KEXPECT_NEAR(m(i, j), mq(i, j), kTol);
  const Vec3 e = euler_xyz(quat_from_euler_xyz(r, p, y));
  KEXPECT_NEAR(e[0], r, 1e-5);
  KEXPECT_NEAR(e[1], p, 1e-5);
  KEXPECT_NEAR(e[2], y, 1e-5);
}

KTEST(Quaternion, EulerWrapsLikeTheReference) {
  // Yaw exactly pi (quaternion (0,0,1,0)) wraps to -pi in [-pi, pi), as in golden case 1.
  const Vec3 e = euler_xyz(quat_from_xyzw(0, 0, 1, 0));
  KEXPECT_NEAR(e[2], -kPi, 1e-6);
  // The [0, 2pi) variant (ROV convention) keeps -0.5 rad as 2pi - 0.5.
  const Vec3 e2 = euler_xyz_two_pi(quat_from_euler_xyz(0, 0, -0.5_r));
  KEXPECT_NEAR(e2[2], kTwoPi - 0.5_r, 1e-5);
  // Negated quaternion (same rotation) gives the same angles.
  const Quat q = quat_from_euler_xyz(0.2_r, 0.1_r, -1.0_r);
  Quat qn = q;
  qn.coeffs() = -q.coeffs();
  const Vec3 a = euler_xyz(q), b = euler_xyz(qn);
  for (int i = 0; i < 3; ++i) KEXPECT_NEAR(a[i], b[i], 1e-6);
}

KTEST(Quaternion, GimbalLockPitchSaturates) {
  const Vec3 e = euler_xyz(quat_from_euler_xyz(0, kPi / 2, 0));
  KEXPECT_NEAR(e[1], kPi / 2, 1e-3);
}

KTEST(Quaternion, VehicleFrameKeepsOnlyYaw) {
  const Quat q = quat_from_euler_xyz(0.4_r, -0.3_r, 1.2_r);
  const Vec3 e = euler_xyz(vehicle_quat(q));
  KEXPECT_NEAR(e[0], 0, 1e-6);
  KEXPECT_NEAR(e[1], 0, 1e-6);
  KEXPECT_NEAR(e[2], 1.2_r, 1e-5);
}

KTEST(Quaternion, HatVeeAreInverse) {
  const Vec3 a(0.3_r, -1.2_r, 2.0_r), b(-0.7_r, 0.5_r, 0.25_r);
  const Vec3 c1 = hat(a) * b, c2 = a.cross(b);
  for (int i = 0; i < 3; ++i) KEXPECT_NEAR(c1[i], c2[i], 1e-6);
  const Vec3 v = vee(hat(a));
  for (int i = 0; i < 3; ++i) KEXPECT_EQ(v[i], a[i]);
}

KTEST(Quaternion, YawRateToBodyRate) {
  // Level: body rate is the yaw rate about z.
  Vec3 w = body_rate_from_yaw_rate(0, 0, 0.7_r);
  KEXPECT_NEAR(w[2], 0.7, 1e-7);
  KEXPECT_NEAR(w[0], 0, 1e-7);
  // Rolled 90 deg: yaw rate appears on body y.
  w = body_rate_from_yaw_rate(kPi / 2, 0, 1);
  KEXPECT_NEAR(w[1], 1, 1e-6);
  KEXPECT_NEAR(w[2], 0, 1e-6);
}

KTEST(Quaternion, FromRotationMatrixHasNonNegativeScalar) {
  const Quat q = quat_from_rotation_matrix(rotation_from_euler_xyz(0.1_r, 0.2_r, 3.1_r));
  KEXPECT_GE(q.w(), 0);
  const Quat r = quat_from_euler_xyz(0.1_r, 0.2_r, 3.1_r);
  KEXPECT_NEAR(std::fabs(q.dot(r)), 1, 1e-6);
}

KTEST(Math, WrapPi) {
  KEXPECT_NEAR(wrap_pi(3 * kPi / 2), -kPi / 2, 1e-6);
  KEXPECT_NEAR(wrap_pi(-3 * kPi / 2), kPi / 2, 1e-6);
  KEXPECT_NEAR(wrap_pi(0.25_r), 0.25, 1e-7);
  KEXPECT_EQ(sign0(0), 0);
  KEXPECT_EQ(sign0(-2), -1);
}
