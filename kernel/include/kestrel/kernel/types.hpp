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
#include <type_traits>

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

/// A fixed-size matrix held as a plain array in Eigen's storage order (column-major), for the
/// read-only parameter structs (LeeParams, AllocationModel). Why not a Mat there: Eigen 3.4's
/// constructors are not constexpr, so an object holding an Eigen matrix can never be
/// constant-initialised; GCC places even a `const` one in RAM and fills it at start-up. A plain
/// array with constexpr constructors is, so a `constexpr LeeParams` baked at build time stays in
/// flash (the 512-byte-RAM control stack, bench/control/mcu/baked_cascade.hpp).
/// Element access and assignment from Eigen work as on a Mat; in expressions use map(), a view
/// that costs nothing (the same loads an Eigen member would compile to).
template <int Rows, int Cols = 1>
struct PlainMat {
  using Matrix = Mat<Rows, Cols>;
  real v[Rows * Cols];

  constexpr PlainMat() : v{} {}
  /// All Rows * Cols entries in storage order: `PlainVec3 g_w = {0, 0, -9.81f};` (constexpr).
  template <typename... T, typename = std::enable_if_t<sizeof...(T) == Rows * Cols && sizeof...(T) != 1 &&
                                                        (std::is_arithmetic_v<T> && ...)>>
  constexpr PlainMat(T... entries) : v{static_cast<real>(entries)...} {}  // NOLINT(google-explicit-constructor)
  /// From any Eigen matrix expression of this size (set-up code: `gains.k_pos = Vec3(...)`).
  template <typename Derived>
  PlainMat(const Eigen::MatrixBase<Derived>& m) : v{} {  // NOLINT(google-explicit-constructor)
    map() = m;
  }

  Eigen::Map<Matrix> map() { return Eigen::Map<Matrix>(v); }
  Eigen::Map<const Matrix> map() const { return Eigen::Map<const Matrix>(v); }
  // No implicit conversion to Matrix: passing one where a `const Mat&` is expected would copy the
  // whole matrix on every call, silently (a 12 x 6 model is 288 bytes per hot-path call).
  template <typename Derived>
  PlainMat& operator=(const Eigen::MatrixBase<Derived>& m) {
    map() = m;
    return *this;
  }
  PlainMat& operator*=(real s) {
    for (real& x : v) x *= s;
    return *this;
  }
  /// Exact, element by element (as Eigen's == on matrices).
  friend bool operator==(const PlainMat& a, const PlainMat& b) { return a.map() == b.map(); }
  friend bool operator!=(const PlainMat& a, const PlainMat& b) { return !(a == b); }
  constexpr real& operator()(int i) { return v[i]; }
  constexpr const real& operator()(int i) const { return v[i]; }
  constexpr real& operator[](int i) { return v[i]; }
  constexpr const real& operator[](int i) const { return v[i]; }
  constexpr real& operator()(int row, int col) { return v[row + Rows * col]; }
  constexpr const real& operator()(int row, int col) const { return v[row + Rows * col]; }
  real* data() { return v; }
  const real* data() const { return v; }
};
using PlainVec3 = PlainMat<3, 1>;
using PlainMat3 = PlainMat<3, 3>;

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
