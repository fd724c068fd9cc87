// Airframe geometry -> effectiveness matrix: sign conventions, presets, validation.
#include <cmath>
#include <limits>

#include "alloc_test_util.hpp"
#include "ktest.hpp"

using namespace alloc_test;

KTEST(Airframe, QuadrotorSignConventionMatchesReference) {
  Airframe a;
  KASSERT_EQ(static_cast<int>(no_heap([&] { return make_airframe(kBaseQuadrotor, a); })), static_cast<int>(Status::ok));
  KEXPECT_EQ(a.num_rotors, 4);
  // golden/allocation.json base_quadrotor: fz ones, tx [-0.13, -0.13, 0.13, 0.13],
  // ty [-0.13, 0.13, 0.13, -0.13], tz = -direction * 0.01 with directions [1, -1, 1, -1].
  const real tx[4] = {-0.13f, -0.13f, 0.13f, 0.13f};
  const real ty[4] = {-0.13f, 0.13f, 0.13f, -0.13f};
  const real tz[4] = {-0.01f, 0.01f, -0.01f, 0.01f};
  for (int i = 0; i < 4; ++i) {
    KEXPECT_EQ(a.effectiveness(0, i), real(0));
    KEXPECT_EQ(a.effectiveness(1, i), real(0));
    KEXPECT_EQ(a.effectiveness(2, i), real(1));
    KEXPECT_EQ(a.effectiveness(3, i), tx[i]);
    KEXPECT_EQ(a.effectiveness(4, i), ty[i]);
    KEXPECT_EQ(a.effectiveness(5, i), tz[i]);
    KEXPECT_EQ(a.thrust_min_N[i], real(0));
    KEXPECT_EQ(a.thrust_max_N[i], real(2));
  }
  for (int i = 4; i < kMaxRotors; ++i) {
    for (int r = 0; r < 6; ++r) KEXPECT_EQ(a.effectiveness(r, i), real(0));
  }
}

KTEST(Airframe, ColumnIsForceAndMomentPlusReactionTorque) {
  // A tilted rotor: torque = p x axis - direction * ratio * axis.
  const Vec3 p(0.2_r, -0.1_r, 0.05_r);
  const Vec3 axis = Vec3(0.1_r, 0.2_r, 1.0_r).normalized();
  const Vec6 col = rotor_effectiveness_column(p, axis, -1, 0.02_r);
  const Vec3 torque = p.cross(axis) + 0.02_r * axis;
  for (int k = 0; k < 3; ++k) {
    KEXPECT_NEAR(col(k), axis(k), 1e-7);
    KEXPECT_NEAR(col(3 + k), torque(k), 1e-7);
  }
  // make_airframe normalises a non-unit axis.
  AirframeSpec s = kBaseQuadrotor;
  s.rotors[0].axis_b[0] = 0.2f;
  s.rotors[0].axis_b[2] = 2.0f;
  Airframe a;
  KASSERT_EQ(static_cast<int>(no_heap([&] { return make_airframe(s, a); })), static_cast<int>(Status::ok));
  KEXPECT_NEAR(a.effectiveness.col(0).head<3>().norm(), 1.0, 1e-6);
}

KTEST(Airframe, AllPresetsBuildAndHoverIsReachable) {
  for (int p = 0; p < kNumAirframePresets; ++p) {
    const AirframeSpec& spec = airframe_spec(static_cast<AirframePreset>(p));
    Airframe a;
    KEXPECT_EQ(static_cast<int>(no_heap([&] { return make_airframe(spec, a); })), static_cast<int>(Status::ok));
    KEXPECT_EQ(a.num_rotors, spec.num_rotors);
    KEXPECT_GT(spec.mass_kg, 0);
    // Hover needs less than the sum of the max thrusts along +z.
    real fz_max = 0;
    for (int i = 0; i < a.num_rotors; ++i) {
      const real col_fz = a.effectiveness(2, i);
      fz_max += col_fz > 0 ? col_fz * a.thrust_max_N[i] : col_fz * a.thrust_min_N[i];
    }
    KEXPECT_GT(fz_max, spec.mass_kg * kStandardGravity);
    const MotorModelConfig& mm = motor_model_preset(static_cast<AirframePreset>(p));
    KEXPECT_EQ(mm.num_motors, spec.num_rotors);
    KEXPECT_EQ(static_cast<int>(validate(mm)), static_cast<int>(Status::ok));
    KEXPECT_EQ(mm.thrust_max_N, spec.thrust_max_N);
  }
}

KTEST(Airframe, HexarotorAndX500Geometry) {
  Airframe hex, x500;
  KASSERT_EQ(static_cast<int>(no_heap([&] { return make_airframe(kHexarotor, hex); })), static_cast<int>(Status::ok));
  KASSERT_EQ(static_cast<int>(no_heap([&] { return make_airframe(kX500, x500); })), static_cast<int>(Status::ok));
  for (int i = 0; i < 6; ++i) {
    // Arm length 0.25 m: |(tx, ty)| per newton equals the arm.
    const real arm = std::sqrt(hex.effectiveness(3, i) * hex.effectiveness(3, i) +
                               hex.effectiveness(4, i) * hex.effectiveness(4, i));
    KEXPECT_NEAR(arm, 0.25, 1e-6);
    KEXPECT_NEAR(hex.effectiveness(5, i), (i % 2 == 0 ? -0.016 : 0.016), 1e-7);
  }
  // Equal thrusts on a symmetric frame give a pure fz.
  const real f[6] = {1, 1, 1, 1, 1, 1};
  const Vec6 w = no_heap([&] { return wrench_from_thrusts(hex.effectiveness, 6, f); });
  KEXPECT_NEAR(w(2), 6.0, 1e-6);
  for (int k = 3; k < 6; ++k) KEXPECT_NEAR(w(k), 0.0, 1e-6);
  // X500: 0.5 m motor-to-motor diagonal, PX4 order (1 FR CCW, 2 RL CCW, 3 FL CW, 4 RR CW).
  for (int i = 0; i < 4; ++i) {
    const real arm = std::sqrt(x500.effectiveness(3, i) * x500.effectiveness(3, i) +
                               x500.effectiveness(4, i) * x500.effectiveness(4, i));
    KEXPECT_NEAR(2 * arm, 0.495, 1e-3);  // motor-to-motor diagonal
  }
  KEXPECT_LT(x500.effectiveness(3, 0), 0);  // right side (y < 0): tx = y < 0
  KEXPECT_GT(x500.effectiveness(3, 2), 0);  // left side: tx > 0
  KEXPECT_LT(x500.effectiveness(4, 0), 0);  // front (x > 0): ty = -x < 0
  KEXPECT_GT(x500.effectiveness(4, 1), 0);  // rear: ty > 0
  KEXPECT_LT(x500.effectiveness(5, 0), 0);  // CCW rotor: clockwise reaction torque
  KEXPECT_LT(x500.effectiveness(5, 1), 0);
  KEXPECT_GT(x500.effectiveness(5, 2), 0);
  KEXPECT_GT(x500.effectiveness(5, 3), 0);
}

KTEST(Airframe, InvalidSpecsAreRejected) {
  Airframe a;
  AirframeSpec s = kBaseQuadrotor;
  s.num_rotors = 0;
  KEXPECT_EQ(static_cast<int>(no_heap([&] { return make_airframe(s, a); })),
             static_cast<int>(Status::invalid_argument));
  KEXPECT_EQ(a.num_rotors, 0);
  s.num_rotors = kMaxRotors + 1;
  KEXPECT_EQ(static_cast<int>(no_heap([&] { return make_airframe(s, a); })),
             static_cast<int>(Status::invalid_argument));
  s = kBaseQuadrotor;
  s.direction[2] = 0;
  KEXPECT_EQ(static_cast<int>(no_heap([&] { return make_airframe(s, a); })),
             static_cast<int>(Status::invalid_argument));
  s = kBaseQuadrotor;
  s.rotors[1].axis_b[2] = 0;
  KEXPECT_EQ(static_cast<int>(no_heap([&] { return make_airframe(s, a); })),
             static_cast<int>(Status::invalid_argument));
  s = kBaseQuadrotor;
  s.thrust_min_N = 3;
  KEXPECT_EQ(static_cast<int>(no_heap([&] { return make_airframe(s, a); })),
             static_cast<int>(Status::invalid_argument));
  s = kBaseRandom;
  s.matrix[4][3] = std::numeric_limits<real>::quiet_NaN();
  KEXPECT_EQ(static_cast<int>(no_heap([&] { return make_airframe(s, a); })),
             static_cast<int>(Status::invalid_argument));
  s = kBaseQuadrotor;
  s.rotors[0].position_b_m[0] = std::numeric_limits<real>::infinity();
  KEXPECT_EQ(static_cast<int>(no_heap([&] { return make_airframe(s, a); })),
             static_cast<int>(Status::invalid_argument));
}

KTEST(Airframe, AxialTorqueIsMinusDirectionRatioThrust) {
  Airframe a;
  KASSERT_EQ(static_cast<int>(no_heap([&] { return make_airframe(kBaseOctarotor, a); })), static_cast<int>(Status::ok));
  real f[8], tq[8];
  for (int i = 0; i < 8; ++i) f[i] = static_cast<real>(i) - 3.5_r;
  no_heap([&] { return motor_axial_torques(a, f, tq); });
  for (int i = 0; i < 8; ++i) KEXPECT_EQ(tq[i], -a.direction[i] * 0.01f * f[i]);
}
