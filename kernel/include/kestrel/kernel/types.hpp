// Scalar and fixed-size math types of the Kestrel core.
//
// Conventions, written once here and followed everywhere (docs/design.md):
//  - SI units; a non-SI quantity carries its unit in its name (yaw_rate_deg_s).
//  - World frame z up; default gravity (0, 0, -9.81) m/s^2.
//  - Body frame x forward, y left, z up (thrust along body +z).
//  - Frame suffixes: _w world, _b body, _v vehicle (yaw-only), _s sensor.
//  - Quaternions are xyzw (scalar last) in every public struct, array and file; q_wb rotates
//    body-frame vectors into the world frame (Hamilton product). See quaternion.hpp for the one
//    place where Eigen's (w, x, y, z) constructor is called.
//  - Wrench = [fx, fy, fz, tx, ty, tz] in the body frame.
//  - float by default; -DKESTREL_DOUBLE=ON switches the whole core to double.
//
// Every fixed-size type is Eigen::DontAlign: core structs are copied into structure-of-arrays
// storage and static MCU memory, where 16-byte alignment cannot be promised.
#pragma once

#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace kestrel {

#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
using real = double;
#else
using real = float;
#endif

template <int Rows, int Cols>
using Mat = Eigen::Matrix<real, Rows, Cols,
                          Eigen::DontAlign | ((Rows == 1 && Cols != 1) ? Eigen::RowMajor : Eigen::ColMajor)>;
using Vec2 = Mat<2, 1>;
using Vec3 = Mat<3, 1>;
using Vec4 = Mat<4, 1>;
using Vec6 = Mat<6, 1>;
using Mat3 = Mat<3, 3>;
using Quat = Eigen::Quaternion<real, Eigen::DontAlign>;

/// Literal helper so constants follow the build's scalar type without double promotion.
constexpr real operator""_r(long double v) { return static_cast<real>(v); }
constexpr real operator""_r(unsigned long long v) { return static_cast<real>(v); }

constexpr real kPi = static_cast<real>(3.14159265358979323846L);
constexpr real kTwoPi = static_cast<real>(6.28318530717958647692L);
constexpr real kStandardGravity = static_cast<real>(9.81L);  // m/s^2, Aerial Gym's value

/// Body-frame wrench [fx, fy, fz, tx, ty, tz] (N, N m).
struct Wrench {
  Vec3 force_b = Vec3::Zero();
  Vec3 torque_b = Vec3::Zero();

  Vec6 as_vec6() const {
    Vec6 w;
    w << force_b, torque_b;
    return w;
  }
  static Wrench from_vec6(const Vec6& w) {
    Wrench r;
    r.force_b = w.head<3>();
    r.torque_b = w.tail<3>();
    return r;
  }
};

/// The state of one rigid body as controllers read it and the integrator writes it.
/// Angular velocity is kept in the body frame (what a gyro measures and what Newton-Euler uses).
struct RigidBodyState {
  Vec3 position_w = Vec3::Zero();       // m
  Quat orientation_wb = Quat::Identity();  // rotates body vectors into the world
  Vec3 linvel_w = Vec3::Zero();         // m/s, world frame
  Vec3 angvel_b = Vec3::Zero();         // rad/s, body frame
};

}  // namespace kestrel
