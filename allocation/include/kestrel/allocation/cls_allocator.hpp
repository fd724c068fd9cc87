// Constrained least-squares (CLS) allocator: bounded, weighted, regularised least squares solved
// by a primal active-set method.
//
//   minimise   || W (A f - w) ||^2 + eps || f - f_pref ||^2      subject to  f_min <= f <= f_max
//
// O. Harkegard, "Efficient active set algorithms for solving constrained least squares problems
// in aircraft control allocation", IEEE CDC 2002 (the WLS formulation and its active-set solver;
// here eps = 1/gamma of the paper with W_u = I), as used on flight controllers in float32 by
// E. J. J. Smeur, D. C. Hoeppener, C. de Wagter, "Prioritized control allocation for quadrotors
// subject to saturation", IMAV 2017 (Paparazzi's wls_alloc).
//
// Each iteration solves the equality-constrained subproblem on the free motors with a Householder
// QR of the stacked matrix [W A_free; sqrt(eps) I] (no normal equations: they would square the
// condition number, ~1e6 here, which float32 cannot carry), then either takes the full step and
// checks the Lagrange multipliers of the motors held at a bound (releasing the most negative one),
// or stops at the first bound it meets and adds that motor to the working set. Every iterate is
// feasible, so when the iteration bound is hit the answer is still within limits
// (Status::not_converged).
//
// Warm start (the working set and thrusts of the previous call, kept in AllocatorState): for
// commands that change little between control steps the previous working set is usually still
// optimal and one subproblem solve suffices.
//
// Motor failures: a dead motor has bounds [0, 0] and is simply never free; a weak motor has its
// bounds scaled. Both come from the AllocationModel (build_allocation_model with MotorHealth).
#pragma once

#include "kestrel/allocation/allocation_model.hpp"

namespace kestrel::allocation {

struct ClsParams {
  /// Diagonal of W for [fx, fy, fz, tx, ty, tz]. Torques weigh more than forces by about one over
  /// the arm length, so that when the command cannot be met, attitude wins over thrust.
  real wrench_weight[6] = {1, 1, 1, 10, 10, 10};
  /// eps (> 0): keeps the subproblem full rank (over-actuated frames have a null space) and picks,
  /// among thrusts producing the same wrench, the one closest to preferred_thrust_N. Small enough
  /// that the wrench error it causes is ~eps / sigma_min(W A)^2 (~2e-4 relative on yaw with the
  /// default weights), large enough to bound the condition number by ~sigma_max / sqrt(eps).
  real regularization = 1e-5_r;
  real preferred_thrust_N[kMaxRotors] = {};  // 0: minimum-norm thrust, the pseudo-inverse solution
  /// Bound on the active-set iterations (one subproblem solve each). Enough for any working set
  /// change of a 12-motor frame; hitting it returns not_converged with a feasible answer.
  int max_iterations = 40;
  bool warm_start = true;
};

/// Saturation bits: the motors held at a bound in the final working set (dead motors excluded).
/// out.iterations: subproblem solves. Returns ok, not_converged (feasible, latched
/// kFaultNotConverged), non_finite_input (last output held) or invalid_argument (empty model or
/// bad params: eps <= 0, negative or non-finite weight, max_iterations < 1).
[[nodiscard]] Status allocate_cls(const AllocationModel& model, const ClsParams& params, AllocatorState& state,
                                  const Vec6& wrench_cmd, AllocationResult& out);
[[nodiscard]] inline Status allocate_cls(const AllocationModel& model, const ClsParams& params, AllocatorState& state,
                                         const Wrench& wrench_cmd, AllocationResult& out) {
  return allocate_cls(model, params, state, wrench_cmd.as_vec6(), out);
}

}  // namespace kestrel::allocation
