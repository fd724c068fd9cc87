// Airframe geometry and the control-effectiveness (allocation) matrix.
//
// The effectiveness matrix A (6 x N, rows fx, fy, fz, tx, ty, tz in the body frame) maps rotor
// thrusts f (N) to the body wrench w = A f. Column i is the wrench produced by one newton of rotor
// i's thrust applied at its motor link (Aerial Gym's "motor_link" mode):
//
//   force  = axis_b
//   torque = position_b x axis_b - direction * thrust_to_torque_m * axis_b
//
// The second torque term is the rotor's reaction (drag) torque about its own axis. `direction` is
// the sign of the rotor's angular velocity about its thrust axis: +1 spins counter-clockwise seen
// from the tip of the axis, so the body feels a clockwise reaction torque. Checked against the
// reference: the base quadrotor (directions [1, -1, 1, -1], ratio 0.01) has tz row
// [-0.01, 0.01, -0.01, 0.01] (golden/allocation.json).
//
// An airframe can also be given directly by its matrix (Aerial Gym's `base_random` and
// `base_octarotor` configs only ship the matrix); the directions are then used only for the
// per-motor reaction torque output (motor_axial_torques).
#pragma once

#include <cstdint>

#include "kestrel/kernel/status.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel::allocation {

/// Compile-time rotor capacity. Every per-rotor array in the allocation layer has this size and
/// loops run to the runtime rotor count only. 12 (the default) covers quad/hexa/octa/dodeca
/// frames and the 8-thruster ROV; saturation masks are 16-bit. A firmware for one frame may build
/// the allocation library with a smaller capacity (-DKESTREL_MAX_ROTORS=4 on the library and
/// everything that includes its headers, as a PUBLIC definition: the struct layouts depend on it)
/// to shrink every per-rotor array; presets with more rotors are then empty (num_rotors 0, which
/// make_airframe rejects) and results are bit-identical to the default build's.
#if !defined(KESTREL_MAX_ROTORS)
#define KESTREL_MAX_ROTORS 12
#endif
constexpr int kMaxRotors = KESTREL_MAX_ROTORS;
static_assert(kMaxRotors >= 1 && kMaxRotors <= 16, "KESTREL_MAX_ROTORS: 1..16 (saturation masks are std::uint16_t)");

/// A: (6 x kMaxRotors), rows [fx, fy, fz, tx, ty, tz]; columns >= num_rotors are zero.
using EffectivenessMatrix = Mat<6, kMaxRotors>;
/// A+: (kMaxRotors x 6); rows >= num_rotors are zero.
using PinvMatrix = Mat<kMaxRotors, 6>;

enum class AirframeSource : std::uint8_t {
  rotor_geometry,  // A is built from rotor positions, axes, directions and the torque ratio
  matrix,          // A is given as is (row-major, 6 x num_rotors)
};

/// One rotor's mounting. Plain data so presets can be constexpr.
struct RotorSpec {
  real position_b_m[3];  // rotor hub relative to the body reference point (m), body frame
  real axis_b[3];        // thrust direction (unit; normalised again when the airframe is built)
};

/// Airframe description as configured (plain data, constexpr-friendly; see presets.hpp).
struct AirframeSpec {
  const char* name = "";
  int num_rotors = 0;
  AirframeSource source = AirframeSource::rotor_geometry;
  real thrust_min_N = 0;  // per-rotor thrust limits (the motor model clamps to these)
  real thrust_max_N = 0;
  real thrust_to_torque_m = 0;             // reaction torque per newton of thrust (N m / N)
  real mass_kg = 0;                        // informational: vehicle mass the limits were sized for
  std::int8_t direction[kMaxRotors] = {};  // +1 / -1, see the file comment
  RotorSpec rotors[kMaxRotors] = {};       // used when source == rotor_geometry
  real matrix[6][kMaxRotors] = {};         // used when source == matrix (row-major A)
};

/// Runtime airframe: the effectiveness matrix and per-rotor limits.
struct Airframe {
  int num_rotors = 0;
  EffectivenessMatrix effectiveness = EffectivenessMatrix::Zero();  // A (6 x num_rotors used)
  real thrust_min_N[kMaxRotors] = {};
  real thrust_max_N[kMaxRotors] = {};
  real direction[kMaxRotors] = {};  // +1 / -1
  real thrust_to_torque_m = 0;
  real mass_kg = 0;
};

/// Column of A for one rotor (wrench per newton of thrust). axis_b must be unit length.
Vec6 rotor_effectiveness_column(const Vec3& position_b_m, const Vec3& axis_b, real direction, real thrust_to_torque_m);

/// Builds the runtime airframe. invalid_argument (out left zeroed) if the rotor count is outside
/// [1, kMaxRotors], a value is non-finite, an axis is zero, a direction is not +-1 or
/// thrust_min_N > thrust_max_N.
[[nodiscard]] Status make_airframe(const AirframeSpec& spec, Airframe& out);

/// Per-motor reaction torque about each motor's own axis, -direction * ratio * thrust (N m), as
/// Aerial Gym emits it in motor_link mode (allocation.json `motor_axial_torque_Nm`).
void motor_axial_torques(const Airframe& airframe, const real* thrust_N, real* axial_torque_Nm);

/// w = A f over the first num_rotors columns.
Vec6 wrench_from_thrusts(const EffectivenessMatrix& effectiveness, int num_rotors, const real* thrust_N);

}  // namespace kestrel::allocation
