// One-sided Jacobi pseudo-inverse; see pinv.hpp for the method and its references.
#include "kestrel/allocation/pinv.hpp"

#include <cmath>
#include <limits>

#include "kestrel/kernel/math.hpp"

namespace kestrel::allocation {

namespace {

constexpr int kMaxLen = kMaxRotors;  // length of a column of G (N when G = A^T)
constexpr int kMaxCols = 6;          // columns of G: min(nonzero rows, N) <= 6

struct JacobiWork {
  real g[kMaxCols][kMaxLen];   // G, column by column (g[j] is column j, contiguous)
  real v[kMaxCols][kMaxCols];  // V, column by column
};

}  // namespace

Status pseudo_inverse(const EffectivenessMatrix& a, int num_cols, PinvMatrix& pinv, PinvInfo* info,
                      const PinvOptions& options) {
  pinv.setZero();
  PinvInfo result;
  if (info != nullptr) *info = result;
  if (num_cols < 1 || num_cols > kMaxRotors) return Status::invalid_argument;
  const int n = num_cols;
  for (int c = 0; c < n; ++c) {
    for (int r = 0; r < 6; ++r) {
      if (!is_finite(a(r, c))) return Status::invalid_argument;
    }
  }

  // Rows that are exactly zero (fx, fy of a flat multirotor) are left out: their A+ columns are
  // exactly zero, and the sweeps get shorter (the quadrotor becomes 4 x 4).
  int rows[6];
  int m = 0;
  for (int r = 0; r < 6; ++r) {
    bool nonzero = false;
    for (int c = 0; c < n; ++c) nonzero = nonzero || a(r, c) != 0;
    if (nonzero) rows[m++] = r;
  }
  if (m == 0) {
    result.converged = true;
    if (info != nullptr) *info = result;
    return Status::singular;
  }

  // Orthogonalise the smaller dimension: G = A_c (m x n) if n <= m, else G = A_c^T (n x m).
  const bool transposed = n > m;
  const int cols = transposed ? m : n;  // <= 6
  const int len = transposed ? n : m;   // <= 12
  JacobiWork w;
  for (int j = 0; j < cols; ++j) {
    for (int i = 0; i < len; ++i) w.g[j][i] = transposed ? a(rows[j], i) : a(rows[i], j);
    for (int i = 0; i < cols; ++i) w.v[j][i] = i == j ? real(1) : real(0);
  }

  constexpr real eps = std::numeric_limits<real>::epsilon();
  // Orthogonality target |g_p . g_q| <= tol ||g_p|| ||g_q||: a few ulps per element of a dot
  // product of `len` terms, reachable in float round-off.
  const real tol = static_cast<real>(4 * len) * eps;
  // A column whose squared norm is below this is numerical zero (the Frobenius norm is invariant
  // under the rotations): rotating noise against signal only wastes sweeps.
  real frob2 = 0;
  for (int j = 0; j < cols; ++j) {
    for (int i = 0; i < len; ++i) frob2 += w.g[j][i] * w.g[j][i];
  }
  const real tol2 = tol * tol;
  const real zero2 = frob2 * tol2;

  for (int sweep = 0; sweep < options.max_sweeps; ++sweep) {
    bool rotated = false;
    for (int p = 0; p < cols - 1; ++p) {
      for (int q = p + 1; q < cols; ++q) {
        real* gp = w.g[p];
        real* gq = w.g[q];
        real alpha = 0, beta = 0, gamma = 0;
        for (int i = 0; i < len; ++i) {
          alpha += gp[i] * gp[i];
          beta += gq[i] * gq[i];
          gamma += gp[i] * gq[i];
        }
        if (alpha <= zero2 || beta <= zero2) continue;
        if (gamma * gamma <= tol2 * (alpha * beta)) continue;
        rotated = true;
        ++result.rotations;
        // Rotation angle that zeroes the (p, q) inner product; t is the smaller root of
        // t^2 + 2 zeta t - 1 = 0 (|theta| <= pi/4), Demmel & Veselic (1992), eq. (4.2).
        const real zeta = (beta - alpha) / (2.0_r * gamma);
        const real t = (zeta >= 0 ? real(1) : real(-1)) / (std::fabs(zeta) + std::sqrt(1.0_r + zeta * zeta));
        const real cs = 1.0_r / std::sqrt(1.0_r + t * t);
        const real sn = cs * t;
        for (int i = 0; i < len; ++i) {
          const real x = gp[i], y = gq[i];
          gp[i] = cs * x - sn * y;
          gq[i] = sn * x + cs * y;
        }
        real* vp = w.v[p];
        real* vq = w.v[q];
        for (int i = 0; i < cols; ++i) {
          const real x = vp[i], y = vq[i];
          vp[i] = cs * x - sn * y;
          vq[i] = sn * x + cs * y;
        }
      }
    }
    result.sweeps = sweep + 1;
    if (!rotated) {
      result.converged = true;
      break;
    }
  }

  // Singular values: the column norms of G V.
  real sigma2[kMaxCols];
  real sigma2_max = 0;
  for (int j = 0; j < cols; ++j) {
    real s = 0;
    for (int i = 0; i < len; ++i) s += w.g[j][i] * w.g[j][i];
    sigma2[j] = s;
    if (s > sigma2_max) sigma2_max = s;
  }
  const real sigma_max = std::sqrt(sigma2_max);
  const real cutoff = options.relative_tolerance * sigma_max;
  real inv_sigma2[kMaxCols];
  real sigma_min_kept = 0;
  for (int j = 0; j < cols; ++j) {
    const real s = std::sqrt(sigma2[j]);
    if (sigma2_max > 0 && s > cutoff) {
      inv_sigma2[j] = 1.0_r / sigma2[j];
      if (result.rank == 0 || s < sigma_min_kept) sigma_min_kept = s;
      ++result.rank;
    } else {
      inv_sigma2[j] = 0;
    }
  }
  result.sigma_max = sigma_max;
  result.sigma_min_kept = sigma_min_kept;

  // Assemble A+ (n x 6); columns of the dropped zero rows stay zero.
  for (int r = 0; r < m; ++r) {
    for (int c = 0; c < n; ++c) {
      real s = 0;
      for (int j = 0; j < cols; ++j) {
        if (inv_sigma2[j] == 0) continue;
        // G = A_c: A+(c, r) = sum_j V(c, j) G(r, j) / s_j^2;  G = A_c^T: sum_j G(c, j) V(r, j) / s_j^2.
        s += transposed ? w.g[j][c] * w.v[j][r] * inv_sigma2[j] : w.v[j][c] * w.g[j][r] * inv_sigma2[j];
      }
      pinv(c, rows[r]) = s;
    }
  }

  if (info != nullptr) *info = result;
  if (!result.converged) return Status::not_converged;
  return result.rank < 6 ? Status::singular : Status::ok;
}

}  // namespace kestrel::allocation
