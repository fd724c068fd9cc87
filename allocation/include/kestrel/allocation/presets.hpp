// Airframe and motor presets: one source of truth for each vehicle, as constexpr plain data.
//
// Aerial Gym robots (reference commit f0d0f05, golden/allocation.json and motor_model.json): the
// numbers below are the float32 values of the reference configs, so the matrices built from them
// equal the golden `allocation_matrix_A` bit for bit (float build) and exactly (double build:
// every value is a float32 literal widened without rounding).
//  - base_quadrotor: 0.25 kg, rotors at (+-0.13, +-0.13, 0) m, thrust along +z, [0, 2] N,
//    directions [1, -1, 1, -1], ratio 0.01; motors RK4 + rotor-speed state + discrete mixing.
//  - base_random: the reference's arbitrary 8-motor matrix (a fully actuated test frame),
//    [-5, 5] N; base_octarotor (= the ROV's thrusters): 8 tilted thrusters, [-6.25, 6.25] N.
//    Both are given by matrix only (the reference ships no geometry for them); mass 1.1 kg (the
//    ROV URDF's runtime value, golden/README.md).
//
// Kestrel's own frames (not in the reference):
//  - hexarotor: flat hex-X, arm 0.25 m, motors counter-clockwise seen from above starting at the
//    front-right arm (-30 deg), alternating directions (+1 first: PNPNPN), [0, 8] N, 2.4 kg
//    (hover at ~49 % thrust), ratio 0.016. Note: with alternating directions a single rotor loss
//    still allows hover only with the opposite rotor at zero thrust, and yaw becomes one-sided
//    (G. Michieletto, M. Ryll, A. Franchi, "Fundamental actuation properties of multirotors:
//    force-moment decoupling and fail-safe robustness", IEEE T-RO 34(3), 2018).
//  - x500: Holybro X500 class quad-X, 0.5 m motor-to-motor diagonal (arm 0.2475 m, +-0.175 m per
//    axis), 2.0 kg, [0, 10] N per motor, ratio 0.016 and motor constants from PX4's Gazebo x500
//    model (kf 8.54858e-6 N/(rad/s)^2, time constants 0.0125 s up / 0.025 s down). PX4 motor
//    order: 1 front-right CCW, 2 rear-left CCW, 3 front-left CW, 4 rear-right CW (CCW seen from
//    above = direction +1 about +z).
#pragma once

#include <cstdint>

#include "kestrel/allocation/airframe.hpp"
#include "kestrel/allocation/motor_model.hpp"

namespace kestrel::allocation {

enum class AirframePreset : std::uint8_t {
  base_quadrotor = 0,
  base_random,
  base_octarotor,
  base_rov,  // same thrusters and matrix as base_octarotor
  hexarotor,
  x500,
};
constexpr int kNumAirframePresets = 6;

namespace presets {

constexpr RotorSpec flat_rotor(real x_m, real y_m) { return RotorSpec{{x_m, y_m, 0}, {0, 0, 1}}; }

/// A preset with more rotors than a reduced KESTREL_MAX_ROTORS (airframe.hpp) holds: named, but
/// empty (num_rotors 0), so make_airframe rejects it with invalid_argument.
constexpr AirframeSpec unavailable(const char* name) {
  AirframeSpec s{};
  s.name = name;
  return s;
}

constexpr AirframeSpec base_quadrotor() {
  AirframeSpec s{};
  s.name = "base_quadrotor";
  s.num_rotors = 4;
  s.source = AirframeSource::rotor_geometry;
  s.thrust_min_N = 0.0f;
  s.thrust_max_N = 2.0f;
  s.thrust_to_torque_m = 0.01f;
  s.mass_kg = 0.25f;
  const std::int8_t dir[4] = {1, -1, 1, -1};
  s.rotors[0] = flat_rotor(0.13f, -0.13f);
  s.rotors[1] = flat_rotor(-0.13f, -0.13f);
  s.rotors[2] = flat_rotor(-0.13f, 0.13f);
  s.rotors[3] = flat_rotor(0.13f, 0.13f);
  for (int i = 0; i < 4; ++i) s.direction[i] = dir[i];
  return s;
}

constexpr AirframeSpec base_random() {
  if (kMaxRotors < 8) return unavailable("base_random");
  AirframeSpec s{};
  s.name = "base_random";
  s.num_rotors = 8;
  s.source = AirframeSource::matrix;
  s.thrust_min_N = -5.0f;
  s.thrust_max_N = 5.0f;
  s.thrust_to_torque_m = 0.01f;
  s.mass_kg = 1.1f;
  const std::int8_t dir[8] = {-1, 1, -1, 1, -1, 1, -1, 1};
  // One row of A per line, as in the reference config.
  // clang-format off
  const real a[6][8] = {
      {5.55111512e-17f, -0.321393818f, -0.45451948f, -0.342020154f, 0.969846308f, 0.342020154f, 0.866025388f, -0.754406512f},
      {1.0f, -0.342020154f, -0.707106769f, 0.0f, -0.173648179f, 0.939692616f, 0.5f, -0.173648179f},
      {1.66533454e-16f, -0.883022249f, 0.54167521f, 0.939692616f, 0.171010077f, 1.11022302e-16f, 1.11022302e-16f, 0.633022249f},
      {0.174999997f, 0.123788744f, -0.0569783375f, 0.134977162f, 0.0336959027f, -0.26653415f, -0.0788397491f, -0.0206893981f},
      {0.00999999978f, 0.278845131f, -0.043285232f, -0.272061765f, -0.197793856f, 0.0863687173f, 0.156554446f, -0.171261296f},
      {0.282487363f, -0.141735494f, -0.0858541131f, 0.0384858921f, -0.33346802f, 0.0836741477f, 0.00846777949f, -0.0874336287f},
  };
  // clang-format on
  for (int i = 0; i < 8; ++i) {
    s.direction[i] = dir[i];
    for (int r = 0; r < 6; ++r) s.matrix[r][i] = a[r][i];
  }
  return s;
}

constexpr AirframeSpec base_octarotor(const char* name = "base_octarotor") {
  if (kMaxRotors < 8) return unavailable(name);
  AirframeSpec s{};
  s.name = name;
  s.num_rotors = 8;
  s.source = AirframeSource::matrix;
  s.thrust_min_N = -6.25f;
  s.thrust_max_N = 6.25f;
  s.thrust_to_torque_m = 0.01f;
  s.mass_kg = 1.1f;
  const std::int8_t dir[8] = {1, -1, 1, -1, 1, -1, 1, -1};
  // One row of A per line, as in the reference config.
  // clang-format off
  const real a[6][8] = {
      {-0.788675129f, 0.211324871f, -0.211324871f, 0.788675129f, 0.788675129f, -0.211324871f, 0.211324871f, -0.788675129f},
      {0.211324871f, 0.788675129f, -0.788675129f, -0.211324871f, -0.211324871f, -0.788675129f, 0.788675129f, 0.211324871f},
      {0.577350259f, -0.577350259f, -0.577350259f, 0.577350259f, 0.577350259f, -0.577350259f, -0.577350259f, 0.577350259f},
      {0.142264977f, -0.215470046f, 0.257735044f, 0.0154700503f, -0.0154700503f, -0.257735044f, 0.215470046f, -0.142264977f},
      {-0.257735044f, 0.0154700503f, 0.142264977f, 0.215470046f, -0.215470046f, -0.142264977f, -0.0154700503f, 0.257735044f},
      {0.115470052f, -0.230940104f, -0.115470052f, 0.230940104f, -0.230940104f, 0.115470052f, 0.230940104f, -0.115470052f},
  };
  // clang-format on
  for (int i = 0; i < 8; ++i) {
    s.direction[i] = dir[i];
    for (int r = 0; r < 6; ++r) s.matrix[r][i] = a[r][i];
  }
  return s;
}

constexpr AirframeSpec hexarotor() {
  if (kMaxRotors < 6) return unavailable("hexarotor");
  AirframeSpec s{};
  s.name = "hexarotor";
  s.num_rotors = 6;
  s.source = AirframeSource::rotor_geometry;
  s.thrust_min_N = 0.0f;
  s.thrust_max_N = 8.0f;
  s.thrust_to_torque_m = 0.016f;
  s.mass_kg = 2.4f;
  // 0.25 m arms at -30, 30, 90, 150, 210, 270 deg: 0.25 cos 30 = 0.216506351, 0.25 sin 30 = 0.125.
  s.rotors[0] = flat_rotor(0.216506351f, -0.125f);
  s.rotors[1] = flat_rotor(0.216506351f, 0.125f);
  s.rotors[2] = flat_rotor(0.0f, 0.25f);
  s.rotors[3] = flat_rotor(-0.216506351f, 0.125f);
  s.rotors[4] = flat_rotor(-0.216506351f, -0.125f);
  s.rotors[5] = flat_rotor(0.0f, -0.25f);
  for (int i = 0; i < 6; ++i) s.direction[i] = static_cast<std::int8_t>(i % 2 == 0 ? 1 : -1);
  return s;
}

constexpr AirframeSpec x500() {
  AirframeSpec s{};
  s.name = "x500";
  s.num_rotors = 4;
  s.source = AirframeSource::rotor_geometry;
  s.thrust_min_N = 0.0f;
  s.thrust_max_N = 10.0f;
  s.thrust_to_torque_m = 0.016f;
  s.mass_kg = 2.0f;
  s.rotors[0] = flat_rotor(0.175f, -0.175f);   // 1 front-right, CCW
  s.rotors[1] = flat_rotor(-0.175f, 0.175f);   // 2 rear-left, CCW
  s.rotors[2] = flat_rotor(0.175f, 0.175f);    // 3 front-left, CW
  s.rotors[3] = flat_rotor(-0.175f, -0.175f);  // 4 rear-right, CW
  const std::int8_t dir[4] = {1, 1, -1, -1};
  for (int i = 0; i < 4; ++i) s.direction[i] = dir[i];
  return s;
}

// Motor models (Aerial Gym configs for its robots; see the file comment for the others).
constexpr MotorModelConfig motors_from(const AirframeSpec& a) {
  MotorModelConfig m{};
  m.num_motors = a.num_rotors;
  m.thrust_min_N = a.thrust_min_N;
  m.thrust_max_N = a.thrust_max_N;
  m.thrust_to_torque_m = a.thrust_to_torque_m;
  for (int i = 0; i < kMaxRotors; ++i) m.direction[i] = a.direction[i];
  return m;
}

constexpr MotorModelConfig base_quadrotor_motors() {
  MotorModelConfig m = motors_from(base_quadrotor());
  m.integrator = MotorIntegrator::rk4;
  m.use_rps = true;
  m.use_discrete_approximation = true;
  m.time_constant_increasing_min_s = 0.04f;
  m.time_constant_increasing_max_s = 0.04f;
  m.time_constant_decreasing_min_s = 0.04f;
  m.time_constant_decreasing_max_s = 0.04f;
  m.thrust_constant_min = 0.00000926312f;
  m.thrust_constant_max = 0.00001826312f;
  m.max_rate = 100000.0f;
  return m;
}

/// base_random and base_octarotor/ROV: force state, bidirectional thrusters.
constexpr MotorModelConfig thruster_motors(const AirframeSpec& a) {
  MotorModelConfig m = motors_from(a);
  m.integrator = MotorIntegrator::rk4;
  m.use_rps = false;
  m.use_discrete_approximation = true;
  m.time_constant_increasing_min_s = 0.01f;
  m.time_constant_increasing_max_s = 0.03f;
  m.time_constant_decreasing_min_s = 0.005f;
  m.time_constant_decreasing_max_s = 0.005f;
  m.max_rate = 100000.0f;
  return m;
}

constexpr MotorModelConfig px4_class_motors(const AirframeSpec& a) {
  MotorModelConfig m = motors_from(a);
  m.integrator = MotorIntegrator::rk4;
  m.use_rps = true;
  m.use_discrete_approximation = false;
  m.time_constant_increasing_min_s = 0.0125f;
  m.time_constant_increasing_max_s = 0.0125f;
  m.time_constant_decreasing_min_s = 0.025f;
  m.time_constant_decreasing_max_s = 0.025f;
  m.thrust_constant_min = 8.54858e-6f;
  m.thrust_constant_max = 8.54858e-6f;
  m.max_rate = 100000.0f;
  return m;
}

}  // namespace presets

inline constexpr AirframeSpec kBaseQuadrotor = presets::base_quadrotor();
inline constexpr AirframeSpec kBaseRandom = presets::base_random();
inline constexpr AirframeSpec kBaseOctarotor = presets::base_octarotor();
inline constexpr AirframeSpec kBaseRov = presets::base_octarotor("base_rov");
inline constexpr AirframeSpec kHexarotor = presets::hexarotor();
inline constexpr AirframeSpec kX500 = presets::x500();

inline constexpr MotorModelConfig kBaseQuadrotorMotors = presets::base_quadrotor_motors();
inline constexpr MotorModelConfig kBaseRandomMotors = presets::thruster_motors(kBaseRandom);
inline constexpr MotorModelConfig kBaseOctarotorMotors = presets::thruster_motors(kBaseOctarotor);
inline constexpr MotorModelConfig kHexarotorMotors = presets::px4_class_motors(kHexarotor);
inline constexpr MotorModelConfig kX500Motors = presets::px4_class_motors(kX500);

/// Preset lookup by id (ids, not pointers, cross API boundaries).
constexpr const AirframeSpec& airframe_spec(AirframePreset p) {
  switch (p) {
    case AirframePreset::base_random:
      return kBaseRandom;
    case AirframePreset::base_octarotor:
      return kBaseOctarotor;
    case AirframePreset::base_rov:
      return kBaseRov;
    case AirframePreset::hexarotor:
      return kHexarotor;
    case AirframePreset::x500:
      return kX500;
    case AirframePreset::base_quadrotor:
      break;
  }
  return kBaseQuadrotor;
}

constexpr const MotorModelConfig& motor_model_preset(AirframePreset p) {
  switch (p) {
    case AirframePreset::base_random:
      return kBaseRandomMotors;
    case AirframePreset::base_octarotor:
    case AirframePreset::base_rov:
      return kBaseOctarotorMotors;
    case AirframePreset::hexarotor:
      return kHexarotorMotors;
    case AirframePreset::x500:
      return kX500Motors;
    case AirframePreset::base_quadrotor:
      break;
  }
  return kBaseQuadrotorMotors;
}

}  // namespace kestrel::allocation
