// Constrained least-squares (active-set) allocator.
#include <cmath>
#include <limits>

#include "alloc_test_util.hpp"
#include "kestrel/allocation/cls_allocator.hpp"
#include "ktest.hpp"

using namespace alloc_test;

namespace {

Airframe g_airframe;
AllocationModel g_model;

Status cls(const ClsParams& p, AllocatorState& s, const Vec6& w, AllocationResult& out) {
  Status st = Status::invalid_argument;
  KEXPECT_NO_HEAP(st = allocate_cls(g_model, p, s, w, out));
  return st;
}

void expect_within_limits(const AllocationResult& out) {
  for (int i = 0; i < g_model.num_rotors; ++i) {
    KEXPECT_GE(out.thrust_N[i], g_model.thrust_min_N[i]);
    KEXPECT_LE(out.thrust_N[i], g_model.thrust_max_N[i]);
  }
}

/// ||W (A f - w)||^2 with the default weights.
double weighted_error2(const AllocationResult& out) {
  const ClsParams p;
  double e = 0;
  for (int k = 0; k < 6; ++k) {
    const double d = static_cast<double>(p.wrench_weight[k]) * static_cast<double>(out.wrench_unallocated(k));
    e += d * d;
  }
  return e;
}

}  // namespace

KTEST(Cls, MatchesPseudoInverseWhenUnconstrained) {
  const AirframeSpec* specs[] = {&kBaseQuadrotor, &kHexarotor, &kX500, &kBaseOctarotor, &kBaseRandom};
  for (const AirframeSpec* spec : specs) {
    const Status bst = build_preset(*spec, g_airframe, g_model);
    KASSERT_TRUE(bst == Status::ok || bst == Status::singular);
    // A reachable command well inside the limits. For the fully actuated frames, a small force
    // direction too; for the random frame's [-5, 5] N limits, a small command.
    const bool full = g_model.pinv_info.rank == 6;
    const real scale = spec == &kBaseRandom ? 0.2_r : 1.0_r;
    const real fz = spec == &kBaseRandom ? 1.0_r : spec->mass_kg * kStandardGravity;
    const Vec6 w = wrench(full ? 0.3_r * scale : 0, full ? -0.2_r * scale : 0, fz, 0.03_r * scale, -0.02_r * scale,
                          0.004_r * scale);
    real f_pinv[kMaxRotors];
    no_heap([&] { return apply_pinv(g_model, w, f_pinv); });
    AllocatorState s;
    AllocationResult out;
    KEXPECT_EQ(static_cast<int>(cls(ClsParams(), s, w, out)), static_cast<int>(Status::ok));
    KEXPECT_FALSE(out.any_saturated());
    KEXPECT_EQ(out.iterations, 1);  // cold start from 0 with nothing active: one solve
    // eps = 1e-5 biases the thrusts toward 0 by ~eps / sigma^2 of the weighted matrix.
    for (int i = 0; i < spec->num_rotors; ++i) KEXPECT_NEAR(out.thrust_N[i], f_pinv[i], 1e-3);
    for (int k = 0; k < 3; ++k) KEXPECT_NEAR(out.wrench_unallocated(k), 0.0, 1e-4 * (1 + std::fabs(fz)));
    for (int k = 3; k < 6; ++k) KEXPECT_NEAR(out.wrench_unallocated(k), 0.0, 2e-5);
  }
}

KTEST(Cls, RespectsBoundsAndBeatsClippedPseudoInverse) {
  KASSERT_EQ(static_cast<int>(build_preset(kBaseOctarotor, g_airframe, g_model)), static_cast<int>(Status::ok));
  // Large commands on the bidirectional octarotor: the pseudo-inverse exceeds +-6.25 N.
  const Vec6 cmds[] = {wrench(20, 0, 10.791_r, 0, 0, 0.5_r), wrench(0, -15, 20, 2, 0, 0), wrench(14, 14, 14, 2, -2, 2)};
  for (const Vec6& w : cmds) {
    AllocatorState sp, sc;
    AllocationResult clipped, out;
    KEXPECT_NO_HEAP((void)allocate_pinv(g_model, sp, w, clipped));
    KEXPECT_TRUE(clipped.any_saturated());
    const Status st = cls(ClsParams(), sc, w, out);
    KEXPECT_EQ(static_cast<int>(st), static_cast<int>(Status::ok));
    expect_within_limits(out);
    KEXPECT_TRUE(out.any_saturated());
    // Optimality against the simple alternative: never worse than clipping A+ w (up to the
    // regularisation term, which the CLS cost also contains).
    double reg = 0;
    for (int i = 0; i < 8; ++i) reg += 1e-5 * static_cast<double>(clipped.thrust_N[i] * clipped.thrust_N[i]);
    KEXPECT_LE(weighted_error2(out), weighted_error2(clipped) + reg);
    KEXPECT_LT(weighted_error2(out), 0.9 * weighted_error2(clipped));
    // Saturation bits are exactly the motors at their bounds.
    for (int i = 0; i < 8; ++i) {
      const bool at_bound = out.thrust_N[i] == g_model.thrust_min_N[i] || out.thrust_N[i] == g_model.thrust_max_N[i];
      KEXPECT_EQ(out.saturated(i), at_bound);
    }
  }
}

KTEST(Cls, WarmStartConvergesInFewerIterations) {
  KASSERT_EQ(static_cast<int>(build_preset(kBaseQuadrotor, g_airframe, g_model)), static_cast<int>(Status::singular));
  ClsParams warm_p, cold_p;
  cold_p.warm_start = false;
  AllocatorState warm_s, cold_s;
  int warm_iters = 0, cold_iters = 0;
  int steps = 0;
  for (int k = 0; k < 100; ++k) {
    // A slowly varying, often saturating command near full thrust (a 500 Hz loop's worth).
    const real t = 0.02_r * static_cast<real>(k);
    const Vec6 w = wrench(0, 0, 7.0_r, 0.15_r * std::sin(3 * t), 0.1_r * std::cos(2 * t), 0.02_r);
    AllocationResult a, b;
    KEXPECT_EQ(static_cast<int>(cls(warm_p, warm_s, w, a)), static_cast<int>(Status::ok));
    KEXPECT_EQ(static_cast<int>(cls(cold_p, cold_s, w, b)), static_cast<int>(Status::ok));
    warm_iters += a.iterations;
    cold_iters += b.iterations;
    // Same problem, same optimum (it is unique: eps > 0 makes the cost strictly convex).
    for (int i = 0; i < 4; ++i) KEXPECT_NEAR(a.thrust_N[i], b.thrust_N[i], 1e-4);
    ++steps;
  }
  KEXPECT_EQ(steps, 100);
  KEXPECT_LT(warm_iters, cold_iters);
  KEXPECT_LE(warm_iters, 130);  // mostly one solve per step
}

KTEST(Cls, HexarotorWithDeadMotorStillHoversAndReachesAttitudeCommands) {
  Airframe a;
  KASSERT_EQ(static_cast<int>(no_heap([&] { return make_airframe(kHexarotor, a); })), static_cast<int>(Status::ok));
  MotorHealth h;
  h.thrust_scale[0] = 0;  // front-right motor lost
  KASSERT_EQ(static_cast<int>(no_heap([&] { return build_allocation_model(a, h, g_model); })),
             static_cast<int>(Status::singular));
  const real mg = kHexarotor.mass_kg * kStandardGravity;
  AllocatorState s;
  AllocationResult out;

  // Hover: the five remaining motors carry the vehicle; the opposite motor (3, also a +1 rotor)
  // must go to ~0 to balance roll/pitch and yaw (Michieletto et al. 2018).
  KEXPECT_EQ(static_cast<int>(cls(ClsParams(), s, hover_wrench(kHexarotor), out)), static_cast<int>(Status::ok));
  expect_within_limits(out);
  KEXPECT_EQ(out.thrust_N[0], real(0));
  KEXPECT_LT(out.thrust_N[3], 1e-2);
  for (int i : {1, 2, 4, 5}) KEXPECT_NEAR(out.thrust_N[i], mg / 4, 1e-2);
  KEXPECT_NEAR(out.wrench_realized(2), mg, 1e-4 * mg);
  for (int k = 3; k < 6; ++k) KEXPECT_NEAR(out.wrench_unallocated(k), 0.0, 2e-5);
  // The pseudo-inverse of the healthy frame would have given motor 0 a sixth of the thrust: with
  // the dead motor the others were redistributed.
  KEXPECT_GT(out.thrust_N[1], mg / 6 + 1);

  // Reachable attitude commands: roll/pitch/yaw in the directions motor 3 can provide.
  const Vec6 reach[] = {wrench(0, 0, mg, 0.05_r, 0.1_r, 0.02_r), wrench(0, 0, mg, 0, 0, 0.05_r),
                        wrench(0, 0, mg, 0.3_r, 0.5_r, 0.01_r)};
  for (const Vec6& w : reach) {
    KEXPECT_EQ(static_cast<int>(cls(ClsParams(), s, w, out)), static_cast<int>(Status::ok));
    expect_within_limits(out);
    KEXPECT_EQ(out.thrust_N[0], real(0));
    KEXPECT_NEAR(out.wrench_unallocated(2), 0.0, 1e-4 * mg);
    for (int k = 3; k < 6; ++k) KEXPECT_NEAR(out.wrench_unallocated(k), 0.0, 3e-5);
  }
  // Yaw the other way needs motor 3 below zero: not reachable; the best feasible answer keeps
  // thrust and (weighted) attitude and reports the rest as unallocated.
  KEXPECT_EQ(static_cast<int>(cls(ClsParams(), s, wrench(0, 0, mg, 0, 0, -0.05_r), out)), static_cast<int>(Status::ok));
  expect_within_limits(out);
  KEXPECT_TRUE(out.saturated(3));
  KEXPECT_LT(out.wrench_unallocated(5), -0.01);
  KEXPECT_NEAR(out.wrench_unallocated(2), 0.0, 1e-4 * mg);
}

KTEST(Cls, WeakMotorIsRespectedAndTheOthersCompensate) {
  Airframe a;
  KASSERT_EQ(static_cast<int>(no_heap([&] { return make_airframe(kBaseOctarotor, a); })), static_cast<int>(Status::ok));
  MotorHealth h;
  h.thrust_scale[0] = 0.25_r;  // thruster 0 limited to +-1.5625 N
  KASSERT_EQ(static_cast<int>(no_heap([&] { return build_allocation_model(a, h, g_model); })),
             static_cast<int>(Status::ok));
  const Vec6 w = wrench(0, 0, 10.791_r, 0, 0, 0);  // pinv asks 2.34 N of thruster 0
  real f_pinv[kMaxRotors];
  no_heap([&] { return apply_pinv(g_model, w, f_pinv); });
  KEXPECT_GT(std::fabs(f_pinv[0]), 1.5625);
  AllocatorState s;
  AllocationResult out;
  KEXPECT_EQ(static_cast<int>(cls(ClsParams(), s, w, out)), static_cast<int>(Status::ok));
  expect_within_limits(out);
  KEXPECT_TRUE(out.saturated(0));
  // Fully actuated with 7 good thrusters: the wrench is still produced.
  for (int k = 0; k < 3; ++k) KEXPECT_NEAR(out.wrench_unallocated(k), 0.0, 2e-4);
  for (int k = 3; k < 6; ++k) KEXPECT_NEAR(out.wrench_unallocated(k), 0.0, 2e-5);
}

KTEST(Cls, IterationBoundGivesFeasibleNotConverged) {
  KASSERT_EQ(static_cast<int>(build_preset(kBaseOctarotor, g_airframe, g_model)), static_cast<int>(Status::ok));
  ClsParams p;
  p.max_iterations = 1;
  p.warm_start = false;
  AllocatorState s;
  AllocationResult out;
  const Vec6 w = wrench(20, 0, 10.791_r, 0, 0, 0.5_r);
  KEXPECT_EQ(static_cast<int>(cls(p, s, w, out)), static_cast<int>(Status::not_converged));
  KEXPECT_EQ(out.iterations, 1);
  expect_within_limits(out);
  KEXPECT_TRUE(all_finite(out.wrench_realized));
  KEXPECT_TRUE(s.faults.has(kFaultNotConverged));
}

KTEST(Cls, InvalidParametersAreRejected) {
  KASSERT_EQ(static_cast<int>(build_preset(kBaseQuadrotor, g_airframe, g_model)), static_cast<int>(Status::singular));
  AllocatorState s;
  AllocationResult out;
  const Vec6 w = hover_wrench(kBaseQuadrotor);
  ClsParams p;
  p.regularization = 0;
  KEXPECT_EQ(static_cast<int>(cls(p, s, w, out)), static_cast<int>(Status::invalid_argument));
  p = ClsParams();
  p.wrench_weight[4] = -1;
  KEXPECT_EQ(static_cast<int>(cls(p, s, w, out)), static_cast<int>(Status::invalid_argument));
  p = ClsParams();
  p.max_iterations = 0;
  KEXPECT_EQ(static_cast<int>(cls(p, s, w, out)), static_cast<int>(Status::invalid_argument));
  p = ClsParams();
  p.preferred_thrust_N[2] = std::numeric_limits<real>::quiet_NaN();
  KEXPECT_EQ(static_cast<int>(cls(p, s, w, out)), static_cast<int>(Status::invalid_argument));
}
