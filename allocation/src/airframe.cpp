#include "kestrel/allocation/airframe.hpp"

#include <cmath>

#include "kestrel/kernel/math.hpp"

namespace kestrel::allocation {

Vec6 rotor_effectiveness_column(const Vec3& position_b_m, const Vec3& axis_b, real direction, real thrust_to_torque_m) {
  Vec6 col;
  const Vec3 torque = position_b_m.cross(axis_b) - (direction * thrust_to_torque_m) * axis_b;
  col << axis_b, torque;
  return col;
}

Status make_airframe(const AirframeSpec& spec, Airframe& out) {
  out = Airframe();
  const int n = spec.num_rotors;
  if (n < 1 || n > kMaxRotors) return Status::invalid_argument;
  if (!is_finite(spec.thrust_min_N) || !is_finite(spec.thrust_max_N) || !is_finite(spec.thrust_to_torque_m) ||
      spec.thrust_min_N > spec.thrust_max_N) {
    return Status::invalid_argument;
  }
  Airframe a;
  a.num_rotors = n;
  a.thrust_to_torque_m = spec.thrust_to_torque_m;
  a.mass_kg = spec.mass_kg;
  for (int i = 0; i < n; ++i) {
    if (spec.direction[i] != 1 && spec.direction[i] != -1) return Status::invalid_argument;
    a.direction[i] = static_cast<real>(spec.direction[i]);
    a.thrust_min_N[i] = spec.thrust_min_N;
    a.thrust_max_N[i] = spec.thrust_max_N;
    if (spec.source == AirframeSource::matrix) {
      for (int r = 0; r < 6; ++r) {
        if (!is_finite(spec.matrix[r][i])) return Status::invalid_argument;
        a.effectiveness(r, i) = spec.matrix[r][i];
      }
    } else {
      const RotorSpec& rs = spec.rotors[i];
      const Vec3 p(rs.position_b_m[0], rs.position_b_m[1], rs.position_b_m[2]);
      Vec3 axis(rs.axis_b[0], rs.axis_b[1], rs.axis_b[2]);
      if (!all_finite(p) || !all_finite(axis)) return Status::invalid_argument;
      const real norm = axis.norm();
      if (!(norm > 0)) return Status::invalid_argument;
      // Normalise only when needed: a preset's exact unit axis (0, 0, 1) must stay bit-exact so the
      // matrix equals the reference's float32 values.
      if (norm != real(1)) axis /= norm;
      a.effectiveness.col(i) = rotor_effectiveness_column(p, axis, a.direction[i], a.thrust_to_torque_m);
    }
  }
  out = a;
  return Status::ok;
}

void motor_axial_torques(const Airframe& airframe, const real* thrust_N, real* axial_torque_Nm) {
  for (int i = 0; i < airframe.num_rotors; ++i) {
    axial_torque_Nm[i] = -airframe.direction[i] * airframe.thrust_to_torque_m * thrust_N[i];
  }
}

Vec6 wrench_from_thrusts(const EffectivenessMatrix& effectiveness, int num_rotors, const real* thrust_N) {
  // Column-wise accumulation: A is column-major, so each motor's column is contiguous.
  real w[6] = {0, 0, 0, 0, 0, 0};
  for (int i = 0; i < num_rotors; ++i) {
    const real f = thrust_N[i];
    for (int r = 0; r < 6; ++r) w[r] += effectiveness(r, i) * f;
  }
  Vec6 out;
  out << w[0], w[1], w[2], w[3], w[4], w[5];
  return out;
}

}  // namespace kestrel::allocation
