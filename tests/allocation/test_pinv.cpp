// Jacobi pseudo-inverse: Penrose identities for every preset, rank detection, status codes, cost.
#include <cmath>
#include <limits>

#include "alloc_test_util.hpp"
#include "kestrel/allocation/pinv.hpp"
#include "ktest.hpp"

using namespace alloc_test;

namespace {

/// Largest |entry| of the four Penrose conditions, each divided by the float round-off scale of
/// its products (n max|A| max|A+|: A+ entries reach 25 for the quadrotor's yaw, so A A+ carries
/// ~1e-5 of pure representation error in float32). A wrong pseudo-inverse gives >= 1e-3 here.
struct PenroseErrors {
  double a_ap_a = 0, ap_a_ap = 0, sym_a_ap = 0, sym_ap_a = 0;
};

#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
constexpr double kPenroseTol = 1e-10;
#else
constexpr double kPenroseTol = 1e-6;
#endif

PenroseErrors penrose(const EffectivenessMatrix& a, const PinvMatrix& p, int n) {
  // Work in double on the used block so the check itself adds no float round-off.
  double A[6][kMaxRotors], P[kMaxRotors][6];
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < n; ++c) A[r][c] = static_cast<double>(a(r, c));
  }
  for (int c = 0; c < n; ++c) {
    for (int r = 0; r < 6; ++r) P[c][r] = static_cast<double>(p(c, r));
  }
  double AP[6][6] = {}, PA[kMaxRotors][kMaxRotors] = {};
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      for (int k = 0; k < n; ++k) AP[i][j] += A[i][k] * P[k][j];
    }
  }
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      for (int k = 0; k < 6; ++k) PA[i][j] += P[i][k] * A[k][j];
    }
  }
  PenroseErrors e;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < n; ++j) {
      double s = 0;
      for (int k = 0; k < 6; ++k) s += AP[i][k] * A[k][j];
      e.a_ap_a = std::fmax(e.a_ap_a, std::fabs(s - A[i][j]));
    }
    for (int j = 0; j < 6; ++j) e.sym_a_ap = std::fmax(e.sym_a_ap, std::fabs(AP[i][j] - AP[j][i]));
  }
  double pmax = 0;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < 6; ++j) {
      double s = 0;
      for (int k = 0; k < n; ++k) s += PA[i][k] * P[k][j];
      e.ap_a_ap = std::fmax(e.ap_a_ap, std::fabs(s - P[i][j]));
      pmax = std::fmax(pmax, std::fabs(P[i][j]));
    }
    for (int j = 0; j < n; ++j) e.sym_ap_a = std::fmax(e.sym_ap_a, std::fabs(PA[i][j] - PA[j][i]));
  }
  double amax = 0;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < n; ++j) amax = std::fmax(amax, std::fabs(A[i][j]));
  }
  const double scale = static_cast<double>(n) * amax * pmax;
  e.a_ap_a /= scale * amax;
  e.ap_a_ap /= scale * pmax;
  e.sym_a_ap /= scale;
  e.sym_ap_a /= scale;
  return e;
}

AllocationModel g_model;
Airframe g_airframe;

}  // namespace

KTEST(Pinv, PenroseIdentitiesForAllPresets) {
  for (int p = 0; p < kNumAirframePresets; ++p) {
    const AirframeSpec& spec = airframe_spec(static_cast<AirframePreset>(p));
    KASSERT_EQ(static_cast<int>(no_heap([&] { return make_airframe(spec, g_airframe); })),
               static_cast<int>(Status::ok));
    PinvMatrix pinv;
    PinvInfo info;
    Status st = Status::invalid_argument;
    KEXPECT_NO_HEAP(st = pseudo_inverse(g_airframe.effectiveness, spec.num_rotors, pinv, &info));
    KEXPECT_TRUE(st == Status::ok || st == Status::singular);
    KEXPECT_TRUE(info.converged);
    const PenroseErrors e = penrose(g_airframe.effectiveness, pinv, spec.num_rotors);
    KEXPECT_LT(e.a_ap_a, kPenroseTol);    // A A+ A = A
    KEXPECT_LT(e.ap_a_ap, kPenroseTol);   // A+ A A+ = A+
    KEXPECT_LT(e.sym_a_ap, kPenroseTol);  // (A A+)^T = A A+
    KEXPECT_LT(e.sym_ap_a, kPenroseTol);  // (A+ A)^T = A+ A
    for (int i = spec.num_rotors; i < kMaxRotors; ++i) {
      for (int k = 0; k < 6; ++k) KEXPECT_EQ(pinv(i, k), real(0));
    }
  }
}

KTEST(Pinv, RankDetectionAndStatus) {
  struct Expect {
    AirframePreset preset;
    int rank;
    Status status;
  };
  const Expect expect[] = {
      {AirframePreset::base_quadrotor, 4, Status::singular}, {AirframePreset::base_random, 6, Status::ok},
      {AirframePreset::base_octarotor, 6, Status::ok},       {AirframePreset::base_rov, 6, Status::ok},
      {AirframePreset::hexarotor, 4, Status::singular},      {AirframePreset::x500, 4, Status::singular},
  };
  for (const Expect& e : expect) {
    Status st = Status::invalid_argument;
    KEXPECT_NO_HEAP(st = build_preset(airframe_spec(e.preset), g_airframe, g_model));
    KEXPECT_EQ(static_cast<int>(st), static_cast<int>(e.status));
    KEXPECT_EQ(g_model.pinv_info.rank, e.rank);
    KEXPECT_EQ(g_model.faults.has(kFaultSingular), e.rank < 6);
  }
  // A flat multirotor's fx, fy columns of A+ are exactly zero (no quirk-10 leak).
  KASSERT_EQ(static_cast<int>(build_preset(kBaseQuadrotor, g_airframe, g_model)), static_cast<int>(Status::singular));
  for (int i = 0; i < 4; ++i) {
    KEXPECT_EQ(g_model.pinv(i, 0), real(0));
    KEXPECT_EQ(g_model.pinv(i, 1), real(0));
  }
  // Singular values of the quadrotor: fz 2, roll/pitch 0.26, yaw 0.02.
  KEXPECT_NEAR(g_model.pinv_info.sigma_max, 2.0, 1e-6);
  KEXPECT_NEAR(g_model.pinv_info.sigma_min_kept, 0.02, 1e-7);
}

KTEST(Pinv, DeadMotorDropsRankAndGetsZeroRow) {
  MotorHealth h;
  h.thrust_scale[1] = 0;
  KASSERT_EQ(static_cast<int>(build_preset(kBaseQuadrotor, g_airframe, g_model, h)),
             static_cast<int>(Status::singular));
  KEXPECT_EQ(g_model.pinv_info.rank, 3);
  for (int k = 0; k < 6; ++k) KEXPECT_EQ(g_model.pinv(1, k), real(0));
  KEXPECT_EQ(g_model.dead_mask, 1u << 1);
  KEXPECT_TRUE(g_model.faults.has(kFaultMotorFailure));
  // The octarotor keeps full rank with one thruster lost.
  h = MotorHealth();
  h.thrust_scale[5] = 0;
  KEXPECT_EQ(static_cast<int>(build_preset(kBaseOctarotor, g_airframe, g_model, h)), static_cast<int>(Status::ok));
  KEXPECT_EQ(g_model.pinv_info.rank, 6);
  for (int k = 0; k < 6; ++k) KEXPECT_EQ(g_model.pinv(5, k), real(0));
  const PenroseErrors e = penrose(g_model.effectiveness.map(), g_model.pinv.map(), 8);
  KEXPECT_LT(e.a_ap_a, kPenroseTol);
  KEXPECT_LT(e.ap_a_ap, kPenroseTol);
}

KTEST(Pinv, DegenerateMatrices) {
  EffectivenessMatrix a = EffectivenessMatrix::Zero();
  PinvMatrix p;
  PinvInfo info;
  Status st = Status::ok;
  // All zero: rank 0, pinv zero.
  KEXPECT_NO_HEAP(st = pseudo_inverse(a, 4, p, &info));
  KEXPECT_EQ(static_cast<int>(st), static_cast<int>(Status::singular));
  KEXPECT_EQ(info.rank, 0);
  KEXPECT_EQ(p.cwiseAbs().maxCoeff(), real(0));
  // Two identical columns: rank 1, the pseudo-inverse splits evenly.
  a(2, 0) = 1;
  a(2, 1) = 1;
  KEXPECT_NO_HEAP(st = pseudo_inverse(a, 2, p, &info));
  KEXPECT_EQ(info.rank, 1);
  KEXPECT_NEAR(p(0, 2), 0.5, 1e-7);
  KEXPECT_NEAR(p(1, 2), 0.5, 1e-7);
  // A tiny but non-zero column relative to the others is below the rank tolerance.
  a(3, 2) = 0.01_r * PinvOptions().relative_tolerance;
  KEXPECT_NO_HEAP(st = pseudo_inverse(a, 3, p, &info));
  KEXPECT_EQ(info.rank, 1);
  // Invalid inputs.
  KEXPECT_EQ(static_cast<int>(no_heap([&] { return pseudo_inverse(a, 0, p, &info); })),
             static_cast<int>(Status::invalid_argument));
  KEXPECT_EQ(static_cast<int>(no_heap([&] { return pseudo_inverse(a, kMaxRotors + 1, p, &info); })),
             static_cast<int>(Status::invalid_argument));
  a(1, 1) = std::numeric_limits<real>::quiet_NaN();
  KEXPECT_EQ(static_cast<int>(no_heap([&] { return pseudo_inverse(a, 3, p, &info); })),
             static_cast<int>(Status::invalid_argument));
  KEXPECT_EQ(info.rank, 0);
  KEXPECT_EQ(p.cwiseAbs().maxCoeff(), real(0));
}

KTEST(Pinv, TwelveRotorsAndSweepBound) {
  // A full-capacity, fully actuated frame: 12 rotors with tilted axes (alternating +-30 deg).
  EffectivenessMatrix a = EffectivenessMatrix::Zero();
  for (int i = 0; i < kMaxRotors; ++i) {
    const real ang = kTwoPi * static_cast<real>(i) / static_cast<real>(kMaxRotors);
    // Uneven arms and heights so that no rows of A are orthogonal by symmetry.
    const real arm = 0.3_r + 0.01_r * static_cast<real>(i);
    const Vec3 pos(arm * std::cos(ang), arm * std::sin(ang), 0.02_r * static_cast<real>(i % 3));
    const real tilt = (i % 2 == 0 ? 0.5_r : -0.5_r);
    const Vec3 axis = Vec3(-std::sin(ang) * tilt, std::cos(ang) * tilt, 1).normalized();
    a.col(i) = rotor_effectiveness_column(pos, axis, i % 2 == 0 ? 1 : -1, 0.015_r);
  }
  PinvMatrix p;
  PinvInfo info;
  Status st = Status::invalid_argument;
  KEXPECT_NO_HEAP(st = pseudo_inverse(a, kMaxRotors, p, &info));
  KEXPECT_EQ(static_cast<int>(st), static_cast<int>(Status::ok));
  KEXPECT_EQ(info.rank, 6);
  KEXPECT_TRUE(info.converged);
  KEXPECT_LE(info.sweeps, 8);
  const PenroseErrors e = penrose(a, p, kMaxRotors);
  KEXPECT_LT(e.a_ap_a, kPenroseTol);
  KEXPECT_LT(e.ap_a_ap, kPenroseTol);
  // With one sweep allowed the result is flagged, still finite.
  PinvOptions opt;
  opt.max_sweeps = 1;
  KEXPECT_EQ(static_cast<int>(no_heap([&] { return pseudo_inverse(a, kMaxRotors, p, &info, opt); })),
             static_cast<int>(Status::not_converged));
  KEXPECT_FALSE(info.converged);
  KEXPECT_TRUE(all_finite(p));
}

KTEST(Pinv, QuadrotorCostIsSmall) {
  // The quadrotor (4 x 4 after dropping the fx, fy rows) converges in a handful of sweeps; the
  // Cortex-M4F budget (<= 10,000 instructions) is met with ~15 rotations of 4-vectors.
  KASSERT_EQ(static_cast<int>(no_heap([&] { return make_airframe(kBaseQuadrotor, g_airframe); })),
             static_cast<int>(Status::ok));
  PinvMatrix p;
  PinvInfo info;
  Status st = Status::invalid_argument;
  KEXPECT_NO_HEAP(st = pseudo_inverse(g_airframe.effectiveness, 4, p, &info));
  KEXPECT_EQ(static_cast<int>(st), static_cast<int>(Status::singular));
  KEXPECT_LE(info.sweeps, 5);
  KEXPECT_LE(info.rotations, 20);  // 13 in float, 17 in double (tighter orthogonality target)
}
