// Moore-Penrose pseudo-inverse of a 6 x N effectiveness matrix without heap.
//
// One-sided (Hestenes) Jacobi SVD: J. Demmel, K. Veselic, "Jacobi's method is more accurate than
// QR", SIAM J. Matrix Anal. Appl. 13(4), 1992; M. R. Hestenes, "Inversion of matrices by
// biorthogonalization", J. SIAM 6(1), 1958. Plane rotations orthogonalise the columns of G (either
// A or A^T, whichever has fewer columns, so at most 6 columns and 15 pairs per sweep); with
// G V = U S the pseudo-inverse follows without forming U or dividing by small numbers twice:
//   G = A   (N <= rows): A+ = V S^-2 (A V)^T
//   G = A^T (N >  rows): A+ = (A^T V) S^-2 V^T
// Why not the alternatives: Eigen's JacobiSVD / CompleteOrthogonalDecomposition may allocate even
// at fixed size (measured: malloc on every call on Cortex-M4); an eigen-decomposition of A A^T
// squares the condition number, which costs float32 about two digits on the yaw direction
// (singular value ~0.02 vs ~2 for thrust).
//
// Rank deficiency is expected (a flat multirotor cannot make fx, fy: the quadrotor is rank 4):
// rows of A that are exactly zero are dropped before the sweeps (their A+ columns are exactly 0,
// as in exact arithmetic — torch's float32 pinv leaves ~2e-4 there, golden quirk 10), and
// singular values below relative_tolerance * sigma_max are treated as zero, like
// torch.linalg.pinv's rtol. A dead motor's zero column gives an exactly zero A+ row.
#pragma once

#include <limits>

#include "kestrel/allocation/airframe.hpp"
#include "kestrel/kernel/status.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel::allocation {

struct PinvOptions {
  /// Singular values <= relative_tolerance * sigma_max count as zero (rank). 1000 eps: 1.2e-4 in
  /// float (far below the smallest legitimate ratio of a multirotor, ~0.005 for yaw, and far above
  /// float32 Jacobi round-off, ~1e-6), 2.2e-13 in double.
  real relative_tolerance = 1000 * std::numeric_limits<real>::epsilon();
  /// Sweep bound. Convergence is quadratic; the presets need 1-4 sweeps (the last one checks). Hitting the bound
  /// returns not_converged with a usable (slightly less accurate) result.
  int max_sweeps = 12;
};

struct PinvInfo {
  int rank = 0;
  int sweeps = 0;
  int rotations = 0;  // plane rotations applied (a cost measure)
  bool converged = false;
  real sigma_max = 0;
  real sigma_min_kept = 0;  // smallest singular value counted in the rank (0 if rank 0)
};

/// A+ of the 6 x num_cols matrix A (columns >= num_cols ignored; rows >= num_cols of `pinv` are
/// set to zero). Returns:
///  - invalid_argument: num_cols outside [1, kMaxRotors] or A non-finite (pinv zeroed, rank 0);
///  - not_converged: the sweep bound was hit (pinv usable);
///  - singular: rank < 6 (pinv is the exact pseudo-inverse, usable; like the reference's warning);
///  - ok: rank 6.
[[nodiscard]] Status pseudo_inverse(const EffectivenessMatrix& a, int num_cols, PinvMatrix& pinv,
                                    PinvInfo* info = nullptr, const PinvOptions& options = PinvOptions());

}  // namespace kestrel::allocation
