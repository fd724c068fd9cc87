// Active-set constrained least squares; see cls_allocator.hpp for the method and its sources.
#include "kestrel/allocation/cls_allocator.hpp"

#include <cmath>
#include <limits>

#include "kestrel/kernel/math.hpp"

namespace kestrel::allocation {

namespace {

constexpr int kMaxRows = 6 + kMaxRotors;

/// Least-squares solve of the stacked subproblem on the free motors:
///   min || [W A_F; s I] p - [d; s e] ||,  d = W (w - A f), e = (f_pref - f)_F, s = sqrt(eps)
/// by Householder QR (Golub & Van Loan, "Matrix Computations", alg. 5.3.2). The matrix has full
/// column rank because of the s I block, so R's diagonal is at least s in magnitude.
struct Subproblem {
  int cols = 0;
  int rows = 0;
  real m[kMaxRotors][kMaxRows];  // column-major: m[j] is column j
  real rhs[kMaxRows];
};

void qr_solve(Subproblem& sp, real* p) {
  const int nc = sp.cols, nr = sp.rows;
  for (int k = 0; k < nc; ++k) {
    real* ck = sp.m[k];
    real norm2 = 0;
    for (int r = k; r < nr; ++r) norm2 += ck[r] * ck[r];
    const real norm = std::sqrt(norm2);
    if (!(norm > 0)) continue;                    // not reachable with eps > 0; keeps a zero column harmless
    const real alpha = ck[k] > 0 ? -norm : norm;  // sign chosen to avoid cancellation in v0
    const real v0 = ck[k] - alpha;
    const real vtv = norm2 - ck[k] * ck[k] + v0 * v0;
    ck[k] = v0;  // ck[k..nr) now holds the Householder vector v
    const real scale = 2.0_r / vtv;
    for (int j = k + 1; j < nc; ++j) {
      real* cj = sp.m[j];
      real s = 0;
      for (int r = k; r < nr; ++r) s += ck[r] * cj[r];
      s *= scale;
      for (int r = k; r < nr; ++r) cj[r] -= s * ck[r];
    }
    real s = 0;
    for (int r = k; r < nr; ++r) s += ck[r] * sp.rhs[r];
    s *= scale;
    for (int r = k; r < nr; ++r) sp.rhs[r] -= s * ck[r];
    ck[k] = alpha;  // R(k, k)
  }
  // Back substitution R p = Q^T rhs (first nc rows); R(k, j) = m[j][k] for j > k.
  for (int k = nc - 1; k >= 0; --k) {
    real s = sp.rhs[k];
    for (int j = k + 1; j < nc; ++j) s -= sp.m[j][k] * p[j];
    p[k] = s / sp.m[k][k];
  }
}

}  // namespace

Status allocate_cls(const AllocationModel& model, const ClsParams& params, AllocatorState& state,
                    const Vec6& wrench_cmd, AllocationResult& out) {
  const int n = model.num_rotors;
  if (n < 1 || n > kMaxRotors) return Status::invalid_argument;
  const real eps_reg = params.regularization;
  if (!is_finite(eps_reg) || !(eps_reg > 0) || params.max_iterations < 1) return Status::invalid_argument;
  for (int r = 0; r < 6; ++r) {
    if (!is_finite(params.wrench_weight[r]) || params.wrench_weight[r] < 0) return Status::invalid_argument;
  }
  if (!all_finite(params.preferred_thrust_N, n)) return Status::invalid_argument;
  if (!all_finite(wrench_cmd)) return detail::hold_allocation(model, state, out);

  const real* lo = model.thrust_min_N;
  const real* hi = model.thrust_max_N;
  const real* pref = params.preferred_thrust_N;
  const real sqrt_eps = std::sqrt(eps_reg);

  // Weighted effectiveness W A (column i contiguous) and weighted command W w.
  real wa[kMaxRotors][6];
  real ww[6];
  real col_norm_max = 0;
  for (int r = 0; r < 6; ++r) ww[r] = params.wrench_weight[r] * wrench_cmd(r);
  for (int i = 0; i < n; ++i) {
    real c2 = 0;
    for (int r = 0; r < 6; ++r) {
      wa[i][r] = params.wrench_weight[r] * model.effectiveness(r, i);
      c2 += wa[i][r] * wa[i][r];
    }
    const real c = std::sqrt(c2);
    if (c > col_norm_max) col_norm_max = c;
  }

  // Initial point and working set. Every iterate stays feasible.
  real f[kMaxRotors];
  std::int8_t act[kMaxRotors];
  const bool warm = params.warm_start && state.num_rotors == n;
  for (int i = 0; i < n; ++i) {
    if (!(hi[i] > lo[i])) {  // fixed (dead): never free
      f[i] = lo[i];
      act[i] = -1;
    } else if (warm && state.active[i] < 0) {
      f[i] = lo[i];
      act[i] = -1;
    } else if (warm && state.active[i] > 0) {
      f[i] = hi[i];
      act[i] = 1;
    } else {
      f[i] = clamp(warm ? state.last_thrust_N[i] : pref[i], lo[i], hi[i]);
      act[i] = 0;
    }
  }

  constexpr real kEps = std::numeric_limits<real>::epsilon();
  Subproblem sp;
  int free_idx[kMaxRotors];
  real p[kMaxRotors];
  int iter = 0;
  bool converged = false;
  while (iter < params.max_iterations) {
    ++iter;
    // Weighted residual d = W (w - A f).
    real d[6];
    for (int r = 0; r < 6; ++r) d[r] = ww[r];
    for (int i = 0; i < n; ++i) {
      for (int r = 0; r < 6; ++r) d[r] -= wa[i][r] * f[i];
    }

    int nf = 0;
    for (int i = 0; i < n; ++i) {
      if (act[i] == 0) free_idx[nf++] = i;
    }
    if (nf > 0) {
      sp.cols = nf;
      sp.rows = 6 + nf;
      for (int j = 0; j < nf; ++j) {
        const int i = free_idx[j];
        real* col = sp.m[j];
        for (int r = 0; r < 6; ++r) col[r] = wa[i][r];
        for (int r = 6; r < 6 + nf; ++r) col[r] = 0;
        col[6 + j] = sqrt_eps;
        sp.rhs[6 + j] = sqrt_eps * (pref[i] - f[i]);
      }
      for (int r = 0; r < 6; ++r) sp.rhs[r] = d[r];
      qr_solve(sp, p);

      // Largest step in [0, 1] that stays feasible; the first bound met joins the working set.
      real step = 1;
      int blocking = -1;
      std::int8_t side = 0;
      for (int j = 0; j < nf; ++j) {
        const int i = free_idx[j];
        const real target = f[i] + p[j];
        if (p[j] > 0 && target > hi[i]) {
          const real a = (hi[i] - f[i]) / p[j];
          if (a < step) {
            step = a;
            blocking = i;
            side = 1;
          }
        } else if (p[j] < 0 && target < lo[i]) {
          const real a = (lo[i] - f[i]) / p[j];
          if (a < step) {
            step = a;
            blocking = i;
            side = -1;
          }
        }
      }
      if (blocking >= 0) {
        if (step < 0) step = 0;  // round-off: a blocking motor already a hair past its bound
        for (int j = 0; j < nf; ++j) {
          const int i = free_idx[j];
          f[i] = clamp(f[i] + step * p[j], lo[i], hi[i]);
        }
        f[blocking] = side > 0 ? hi[blocking] : lo[blocking];
        act[blocking] = side;
        continue;
      }
      for (int j = 0; j < nf; ++j) {
        const int i = free_idx[j];
        f[i] = clamp(f[i] + p[j], lo[i], hi[i]);
      }
    }

    // Optimal on this working set: check the multipliers of the motors held at a bound. With
    // r = W (A f - w), the cost's half-gradient is g = (W A)^T r + eps (f - f_pref); a motor at its
    // min is optimal there if g_i >= 0, at its max if g_i <= 0.
    real res[6];
    real scale = 0;
    for (int r = 0; r < 6; ++r) {
      res[r] = -ww[r];
      scale += std::fabs(ww[r]);
    }
    for (int i = 0; i < n; ++i) {
      for (int r = 0; r < 6; ++r) res[r] += wa[i][r] * f[i];
    }
    for (int r = 0; r < 6; ++r) scale += std::fabs(res[r] + ww[r]);
    // Round-off in g is a few ulps of the terms that make it up; a multiplier within that of
    // zero is zero (releasing on noise would cycle until the iteration bound).
    const real tol = 256 * kEps * (col_norm_max * scale + eps_reg * scale);
    real worst = -tol;
    int release = -1;
    for (int i = 0; i < n; ++i) {
      if (act[i] == 0 || !(hi[i] > lo[i])) continue;
      real g = eps_reg * (f[i] - pref[i]);
      for (int r = 0; r < 6; ++r) g += wa[i][r] * res[r];
      const real lambda = act[i] < 0 ? g : -g;
      if (lambda < worst) {
        worst = lambda;
        release = i;
      }
    }
    if (release < 0) {
      converged = true;
      break;
    }
    act[release] = 0;
  }

  std::uint16_t low = 0, high = 0;
  for (int i = 0; i < n; ++i) {
    out.thrust_N[i] = f[i];
    state.active[i] = act[i];
    if (!(hi[i] > lo[i])) continue;
    if (act[i] < 0) low = static_cast<std::uint16_t>(low | (1u << i));
    if (act[i] > 0) high = static_cast<std::uint16_t>(high | (1u << i));
  }
  for (int i = n; i < kMaxRotors; ++i) state.active[i] = 0;
  out.saturated_low_mask = low;
  out.saturated_high_mask = high;
  out.iterations = iter;
  if (const Status fs = detail::finish_allocation(model, state, wrench_cmd, out); fs != Status::ok) return fs;
  if (!converged) {
    state.faults.raise(kFaultNotConverged);
    return Status::not_converged;
  }
  return Status::ok;
}

}  // namespace kestrel::allocation
