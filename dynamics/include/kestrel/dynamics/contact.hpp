// Contacts with friction, joint limits and joint dry friction for the articulated-body dynamics of
// multibody.hpp, as velocity-level constraints solved once per time step.
//
// The model (time-stepping with impulses, D. E. Stewart and J. C. Trinkle, "An implicit
// time-stepping scheme for rigid body dynamics with inelastic collisions and Coulomb friction",
// IJNME 39, 1996; M. Anitescu and F. A. Potra, Nonlinear Dynamics 14, 1997): a step of length h
// first takes the unconstrained velocities v* = qd + h (H + h D)^-1 (tau - bias) (the semi-implicit
// Euler step of step_semi_implicit, damping implicit), then finds constraint impulses lambda so
// that v = v* + (H + h D)^-1 J^T lambda satisfies, row by row:
//   contact normal      J_n v >= target, lambda_n >= 0, complementary (no pull, no penetration);
//   contact friction    the tangential impulse within Coulomb's cone |lambda_t| <= mu lambda_n
//                       and opposing the sliding velocity when on its edge (isotropic cone, not
//                       a pyramid: the friction does not depend on the direction of sliding);
//   joint limit         the joint moves no further than its limit (one-sided, as a contact);
//   joint dry friction  |lambda| <= F h with the joint at rest inside (MuJoCo's frictionloss).
// The positions then move with v (semi-implicit Euler), so a resting contact stays at rest.
//
// Solver: projected Gauss-Seidel over the Delassus matrix W = J (H + h D)^-1 J^T, a row at a time,
// each contact's two friction rows projected together onto the cone (K. Erleben, "Velocity-based
// shock propagation for multibody dynamics animation", ACM TOG 26(2), 2007; E. Catto's sequential
// impulses, GDC 2006). A fixed iteration cap and a fixed row order make the result a function of
// the inputs alone (the determinism contract). Each row's diagonal is increased by
// `regularization` times itself (constraint force mixing, as ODE's CFM), which keeps W's
// redundant rows (four corners of a box on a plane) from stalling the iteration.
//
// Targets (the right-hand side), after Box2D's speculative contacts and position correction:
// a gap s > 0 may close by at most s this step (target -s / h: a fast body meets the ground at the
// step it arrives, with no tunnelling and no early stop); a penetration -s beyond `slop_m` is
// removed at `baumgarte` of it per step (target baumgarte (-s - slop) / h; J. Baumgarte, CMAME 1,
// 1972), never faster than max_push_mps (a robot spawned half in the ground climbs out instead of
// being launched: Box2D caps its push-out speed the same way). Restitution: a contact closing faster than `restitution_threshold_mps` that would close
// this step leaves at e times its approach speed (Newton's law of impact).
//
// Core rules: no heap (fixed-capacity arrays in the caller's scratch ConstraintData), no
// exceptions, float or double. Units: metres, seconds, newtons, radians.
#pragma once

#include <cstdint>
#include <limits>

#include "kestrel/dynamics/multibody.hpp"

namespace kestrel::dynamics {

/// A contact between a body and the environment or another body of the same model (a gripper's pad
/// and the cube it holds): the point (world coordinates), the unit normal pointing from the other
/// side into `body` (the direction `body` is pushed; `body_b` is pushed the other way), the signed
/// gap (m; negative: penetration), and the combined friction coefficient and restitution of the
/// pair. The constraint acts on the relative velocity of the two bodies' material points at
/// `point_w`.
struct ContactPoint {
  int body = -1;
  int body_b = -1;  // the other body (-1: the environment, which does not move)
  Vec3 point_w = Vec3::Zero();
  Vec3 normal_w = Vec3(0, 0, 1);
  real separation_m = 0;
  real friction = 1;
  real restitution = 0;
  // The caller's name for this contact from step to step (e.g. shape x 8 + corner; -1: none), by
  // which a WarmStart finds its impulses of the previous step.
  std::int32_t key = -1;
};

/// The impulses of one robot's previous step (caller storage, kept per robot between steps), by
/// row key: PGS started from them needs a few sweeps on resting contacts, where from zero it stops
/// at its sweep cap short of convergence and the robot creeps (a standing Go2: 0.1 mm/s at 60
/// sweeps). Warm starting is what Box2D and Bullet do (E. Catto, "Iterative dynamics with temporal
/// coherence", GDC 2005). Rows beyond kMaxRows start from zero.
template <int kMaxRows>
struct WarmStart {
  int count = 0;
  std::int32_t key[kMaxRows] = {};
  real lambda[kMaxRows] = {};
};

/// Solver settings (see the file comment). Units in the names; the others are fractions.
struct ConstraintParams {
  int iterations = 60;                      // PGS sweeps at most
  real tolerance_mps = real(1e-6);          // stop once no impulse changes by more than this x W_ii
  real baumgarte = real(0.2);               // share of a penetration removed per step
  real slop_m = real(5e-4);                 // penetration left alone (no jitter at rest)
  real max_push_mps = 1;                    // fastest a penetration is undone (Box2D's contact push speed)
  real restitution_threshold_mps = real(0.5);  // slower impacts do not bounce
  real limit_margin = real(0.02);           // rad or m: a joint this close to a limit gets its row
  real regularization = real(1e-6);         // relative constraint force mixing on W's diagonal
  // True when the caller has just run forward_kinematics(m, d, q, cd.X_world) with the same d, cd
  // and q (for its collision tests, as the simulator does) and changed none of them since: the
  // step then takes those kinematics instead of computing them again (a tenth of a legged step).
  bool poses_current = false;
};

enum class RowKind : std::uint8_t { normal = 0, tangent = 1, limit = 2, joint_friction = 3 };

/// The solver's scratch and its results, of compile-time capacity: kMaxBodies as the model's,
/// kMaxContacts contact points per step. Caller storage (static on an MCU, one per thread in a
/// batch); nothing persists between steps except the results.
template <int kMaxBodies, int kMaxContacts>
struct ConstraintData {
  static_assert(kMaxContacts >= 0, "contact capacity");
  static constexpr int kDofs = max_dofs<kMaxBodies>();
  static constexpr int kRows = 3 * kMaxContacts + 3 * kMaxBodies;  // 3 per contact, 3 per joint (two limits, friction)
  real H[kDofs][kDofs];  // mass matrix + h D at the step's start, then its L^T D L factors
  int dof_parent[kDofs];  // the velocity coordinate each one hangs from (-1: none)
  // Per velocity coordinate k: k and its ancestors, deepest first (chain_of[k][0..chain_len[k])),
  // and L's entries along that chain in the same order, L_chain[k][j] = L(k, chain_of[k][j + 1]).
  // Built once per step: a row's solves then run over contiguous arrays instead of walking the
  // parent links and gathering L through them at every row (about a twelfth of a standing Go2's step).
  std::int16_t chain_of[kDofs][kDofs];
  std::int16_t chain_len[kDofs];
  real L_chain[kDofs][kDofs];
  Transform X_world[kMaxBodies];
  real J[kRows][kDofs];  // constraint rows
  static constexpr int kRowsPad = (kRows + 3) / 4 * 4;
  real ZT[kDofs][kRowsPad];  // column i: L^-T J_i^T, half of the solve (W = Z^T D^-1 Z), stored by coordinate
  real ZDT[kDofs][kRowsPad];  // ZT's row k divided by D_k, all rows of it at once (vector divisions)
  std::int32_t key[kRows];   // the row's name between steps (WarmStart; -1: none)
  std::int16_t leaf[kRows];  // the deepest velocity coordinate row i involves (its chain up from there; -1: none)
  std::int16_t leaf_b[kRows];  // a two-body contact's second chain (-1: none); row i involves the union
  real W[kRows][kRowsPad];  // Delassus matrix (zeros in the columns from num_rows to a multiple of 4)
  real b[kRows], target[kRows], lambda[kRows], lo[kRows], hi[kRows];
  RowKind kind[kRows];
  std::int16_t owner[kRows];  // the contact (normal, tangent rows) or the velocity coordinate (joint rows)
  int num_rows = 0;

  // Results of the last step: the force (N) each contact applied to its body, world coordinates,
  // at its point (impulse / h; a two-body contact's body_b takes the opposite force); the limit and dry-friction forces per velocity coordinate (N m or
  // N); the sweeps the solver used.
  Vec3 contact_force_w[kMaxContacts > 0 ? kMaxContacts : 1];
  real joint_constraint_force[kDofs] = {};
  int iterations_used = 0;
};

namespace detail {

/// Row r's velocity coordinates, deepest first: the union of the chains up from leaf[r] and
/// leaf_b[r] (both descend, since a coordinate's parent has a smaller index, so they merge like two
/// sorted lists). Returns how many were written to `chain`.
template <class CD>
inline int row_chain(const CD& cd, int r, std::int16_t* chain) {
  int a = cd.leaf[r], b = cd.leaf_b[r], len = 0;
  while (a >= 0 || b >= 0) {
    const int i = a > b ? a : b;
    chain[len++] = static_cast<std::int16_t>(i);
    if (a == i) a = cd.dof_parent[a];
    if (b == i) b = cd.dof_parent[b];
  }
  return len;
}

/// Two unit tangents completing the unit normal n to a right-handed basis (t1, t2, n), chosen by a
/// fixed rule so that the same normal always gives the same tangents.
inline void tangent_basis(const Vec3& n, Vec3& t1, Vec3& t2) {
  const Vec3 helper = std::fabs(n[2]) < real(0.9) ? Vec3(0, 0, 1) : Vec3(1, 0, 0);
  t1 = helper.cross(n);
  t1 /= t1.norm();
  t2 = n.cross(t1);
}

/// For each velocity coordinate, the one it hangs from in the tree (-1: none): the previous one
/// within a joint (the free joint's six), else the last one of the nearest ancestor joint that has
/// any. This is the sparsity pattern of the mass matrix (RBDA section 6.5).
template <int N>
void dof_parents(const MultibodyModel<N>& m, int* parent_dof) {
  for (int i = 0; i < m.num_bodies; ++i) {
    const int k0 = m.dof_index[i];
    if (k0 < 0) continue;
    int up = -1;
    for (int a = m.parent[i]; a >= 0 && up < 0; a = m.parent[a])
      if (m.dof_index[a] >= 0) up = m.dof_index[a] + joint_dofs(m, a) - 1;
    parent_dof[k0] = up;
    for (int c = 1; c < joint_dofs(m, i); ++c) parent_dof[k0 + c] = k0 + c - 1;
  }
}

/// cd's chain_of and chain_len from dof_parent (see ConstraintData).
template <class CD>
void build_chains(CD& cd, int n) {
  for (int k = 0; k < n; ++k) {
    int len = 0;
    for (int j = k; j >= 0; j = cd.dof_parent[j]) cd.chain_of[k][len++] = static_cast<std::int16_t>(j);
    cd.chain_len[k] = static_cast<std::int16_t>(len);
  }
}

/// cd.H = L^T D L in place (lower triangle: L below the diagonal, D on it), visiting only the
/// entries the tree's branches leave non-zero: Featherstone's LTDL factorisation (RBDA table 6.3),
/// whose cost falls with the number of branches (a quadruped's four legs), over the chains of
/// build_chains (the ancestors read from an array, not walked link by link); then L_chain. Why
/// not Eigen's LLT: its dynamic-size kernels may allocate a blocking workspace, which the core
/// may not. False if a pivot is not positive (a singular or non-finite matrix).
template <class CD>
bool ltdl_factor(CD& cd, int n) {
  for (int k = n - 1; k >= 0; --k) {
    real* Hk = cd.H[k];
    if (!(Hk[k] > 0) || !is_finite(Hk[k])) return false;
    const std::int16_t* ch = cd.chain_of[k];
    const int len = cd.chain_len[k];
    for (int m = 1; m < len; ++m) {
      const int i = ch[m];
      const real a = Hk[i] / Hk[k];
      real* Hi = cd.H[i];
      for (int q = m; q < len; ++q) Hi[ch[q]] -= Hk[ch[q]] * a;
      Hk[i] = a;
    }
  }
  for (int k = 0; k < n; ++k)
    for (int j = 1; j < cd.chain_len[k]; ++j) cd.L_chain[k][j - 1] = cd.H[k][cd.chain_of[k][j]];
  return true;
}

/// x = (L^T D L)^-1 x in place, with the factors of ltdl_factor (RBDA table 6.4's solves).
template <class CD>
void ltdl_solve(const CD& cd, int n, real* x) {
  for (int i = n - 1; i >= 0; --i) {  // L^T z = b
    const std::int16_t* ch = cd.chain_of[i] + 1;
    const real* L = cd.L_chain[i];
    const real xi = x[i];
    for (int q = 0; q + 1 < cd.chain_len[i]; ++q) x[ch[q]] -= L[q] * xi;
  }
  for (int i = 0; i < n; ++i) x[i] /= cd.H[i][i];
  for (int i = 0; i < n; ++i) {  // L x = z
    const std::int16_t* ch = cd.chain_of[i] + 1;
    const real* L = cd.L_chain[i];
    real xi = x[i];
    for (int q = 0; q + 1 < cd.chain_len[i]; ++q) xi -= L[q] * x[ch[q]];
    x[i] = xi;
  }
}

/// Rows solved together by chain_solve: at most this many.
constexpr int kChainGroup = 8;

/// z = L^-T z for a group of G <= kChainGroup rows along one chain (zc[a][g] = z_g[chain[a]], len
/// of them): the coordinates after chain[k] are exactly chain[k]'s ancestors, so the entries of L
/// they need are L_chain[chain[k]] in the same order, contiguous. A row whose leaf lies higher up
/// the chain has zeros below it, which the steps there leave as they are: each row gets the bits
/// of its own solve. Why groups: one row's solve is a chain of dependent multiply-subtracts, one
/// per coordinate pair (latency-bound, a tenth of a standing Go2's step); G rows side by side
/// share the loads and fill the pipeline (a contact's three rows, a leg's joint rows).
/// All kChainGroup lanes are computed (unused ones hold zeros): a fixed width the compiler turns
/// into whole vector operations.
template <int kLd>
inline void chain_solve(const std::int16_t* chain, int len, const real (*L_chain)[kLd], real (*zc)[kChainGroup]) {
  using Group = Eigen::Array<real, kChainGroup, 1, Eigen::DontAlign>;
  for (int k = 0; k < len; ++k) {
    const real* Lk = L_chain[chain[k]];  // Lk[j]: L(chain[k], chain[k + 1 + j])
    const Group zk = Eigen::Map<const Group>(zc[k]);  // a copy: no aliasing with the rows below
    for (int a = k + 1; a < len; ++a) Eigen::Map<Group>(zc[a]) -= Lk[a - k - 1] * zk;
  }
}

/// Row r's chain of velocity coordinates (row_chain's) without walking the links for a row on one
/// chain: cd.chain_of of its leaf; a two-body row's merged chain is written to `buffer`. Sets
/// *chain and returns the length.
template <class CD>
inline int row_chain_view(const CD& cd, int r, std::int16_t* buffer, const std::int16_t** chain) {
  if (cd.leaf_b[r] < 0) {
    *chain = cd.leaf[r] >= 0 ? cd.chain_of[cd.leaf[r]] : buffer;
    return cd.leaf[r] >= 0 ? cd.chain_len[cd.leaf[r]] : 0;
  }
  *chain = buffer;
  return row_chain(cd, r, buffer);
}

/// The projected Gauss-Seidel sweeps of step_constrained over cd's first `rows` rows (W, b,
/// target, lo, hi, kind, owner as the step writes them; W's columns from rows to a multiple of 4
/// zero), from the impulses in cd.lambda, sweeps first .. p.iterations - 1; friction[c]: contact
/// c's coefficient. Returns the sweeps used, counted from zero (iterations_used). A sweep depends on
/// the impulses it starts from alone (u is summed afresh), so the sweeps can be resumed: the
/// batched legged step (sim/src/backends/articulated_batch.hpp) hands a lane it has swept in
/// SIMD lanes to this function to finish, with the bits of one uninterrupted run.
template <class CD>
int pgs_sweeps(CD& cd, int rows, const real* friction, const ConstraintParams& p, int first = 0) {
  const int rows_pad = (rows + 3) / 4 * 4;
  using Four = Eigen::Array<real, 4, 1, Eigen::DontAlign>;
  // Projected Gauss-Seidel over residuals u = b - target + W lambda kept for all rows at once:
  // summed afresh at the start of every sweep (column by column, u += W_c lambda_c, for every row
  // together: no chain of dependent additions, and it vectorises; W is symmetric (step_constrained mirrors it),
  // so column c is row c), then updated as each impulse changes within the sweep (u += W_r delta).
  // Summing W_r . lambda serially for every row instead is a chain of additions as long as the row
  // count, a fifth of a standing Go2's step. The fresh sum makes a sweep that starts converged
  // change nothing, so it stops (updated incrementally only, u's rounding kept a standing ANYmal's
  // changes at ~1e-6 m/s, the tolerance, for all 60 sweeps). Fixed orders: the same bits on every
  // target.
  real u[CD::kRowsPad];
  for (int c = rows; c < rows_pad; ++c) u[c] = 0;
  // u += W_r delta, four rows at a time, over the rows from `from` on (from the block that holds
  // it). Within a sweep only the rows not yet visited (from r on) need it: the next sweep sums u
  // afresh and nothing else reads it, so the rows behind are left stale (half the work, the same
  // values where they are read). W's and u's padding past the rows holds zeros.
  auto apply = [&](int r, real delta, int from) {
    if (delta == 0) return;
    const real* w = cd.W[r];
    for (int c = from & ~3; c < rows_pad; c += 4) Eigen::Map<Four>(u + c) += Eigen::Map<const Four>(w + c) * delta;
  };
  auto residual = [&](int r) { return u[r]; };
  int sweep = first;
  for (; sweep < p.iterations && rows > 0; ++sweep) {
    real change = 0;
    for (int c = 0; c < rows; ++c) u[c] = cd.b[c] - cd.target[c];
    for (int c = 0; c < rows; ++c) apply(c, cd.lambda[c], 0);
    for (int r = 0; r < rows;) {
      const real diag = cd.W[r][r] * (1 + p.regularization);
      if (!(diag > 0)) {  // a row nothing can move (a contact on a welded base): no impulse
        r += cd.kind[r] == RowKind::normal ? 3 : 1;
        continue;
      }
      if (cd.kind[r] == RowKind::normal) {
        // The normal row, then the contact's two friction rows projected onto the cone.
        const real ln = std::max(real(0), cd.lambda[r] - residual(r) / diag);
        change = std::max(change, std::fabs(ln - cd.lambda[r]) * diag);
        apply(r, ln - cd.lambda[r], r);
        cd.lambda[r] = ln;
        // Gauss-Seidel within the pair: the second friction row sees the first's new impulse
        // (through W's one entry between them; u takes both once they are projected).
        real lt[2];
        for (int a = 1; a <= 2; ++a) {
          const real da = cd.W[r + a][r + a] * (1 + p.regularization);
          const real res = a == 1 ? residual(r + 1) : residual(r + 2) + cd.W[r + 2][r + 1] * (lt[0] - cd.lambda[r + 1]);
          lt[a - 1] = da > 0 ? cd.lambda[r + a] - res / da : real(0);
        }
        const real limit = friction[cd.owner[r]] * ln;
        const real mag = std::sqrt(lt[0] * lt[0] + lt[1] * lt[1]);
        const real scale = mag > limit ? (mag > 0 ? limit / mag : real(0)) : real(1);
        for (int a = 1; a <= 2; ++a) {
          const real v = lt[a - 1] * scale;
          change = std::max(change, std::fabs(v - cd.lambda[r + a]) * cd.W[r + a][r + a]);
          apply(r + a, v - cd.lambda[r + a], r + a);
          cd.lambda[r + a] = v;
        }
        r += 3;
        continue;
      }
      real l = cd.lambda[r] - residual(r) / diag;
      l = std::min(std::max(l, cd.lo[r]), cd.hi[r]);
      change = std::max(change, std::fabs(l - cd.lambda[r]) * diag);
      apply(r, l - cd.lambda[r], r);
      cd.lambda[r] = l;
      ++r;
    }
    if (change <= p.tolerance_mps) {
      ++sweep;
      break;
    }
  }
  return sweep;
}

template <int N>
bool valid_contacts(const MultibodyModel<N>& m, const ContactPoint* c, int count) {
  for (int i = 0; i < count; ++i) {
    if (c[i].body < 0 || c[i].body >= m.num_bodies) return false;
    if (c[i].body_b < -1 || c[i].body_b >= m.num_bodies || c[i].body_b == c[i].body) return false;
    if (!all_finite(c[i].point_w) || !all_finite(c[i].normal_w) || !is_finite(c[i].separation_m)) return false;
    if (std::fabs(c[i].normal_w.norm() - 1) > real(1e-3)) return false;
    if (!(c[i].friction >= 0) || !is_finite(c[i].friction)) return false;
    if (!(c[i].restitution >= 0) || !(c[i].restitution <= 1)) return false;
  }
  return true;
}

}  // namespace detail

/// One step of length dt_s with contacts, joint limits and joint dry friction (see the file
/// comment): q, qd advance in place; `contacts` (num_contacts <= kMaxContacts; may be null when 0)
/// were found at q (collide_halfspace below, or the caller's own geometry). cd receives the
/// contact forces. Status::ok; invalid_argument for a bad dt, count or contact (body or body_b out
/// of range, body_b == body, non-unit normal, negative friction, restitution outside [0, 1]); non_finite_input as aba's
/// (non-finite input, a singular mass matrix, a result that would not be finite). On any refusal
/// q and qd are left as they were.
///
/// drive_kp, drive_kd (per velocity coordinate, N m/rad and N m s/rad, or null): the stiffness and
/// damping of the joint drives whose torques tau already holds (a PD law kp (q* - q) - kd qd). They
/// are taken implicitly, at the end of the step, as MuJoCo's implicit integrators treat actuator
/// gains (and D. Baraff, A. Witkin, "Large steps in cloth simulation", SIGGRAPH 1998, springs):
/// the explicit PD of legged_gym needs kd h < 2 I on every joint, which a light calf (I ~ 0.003
/// kg m^2) with kd = 2 at h = 5 ms breaks; this does not.
template <int N, int C, int W = 1>
[[nodiscard]] Status step_constrained(const MultibodyModel<N>& m, MultibodyData<N>& d, ConstraintData<N, C>& cd, real* q,
                                      real* qd, const real* tau, real dt_s, const ContactPoint* contacts, int num_contacts,
                                      const ConstraintParams& p = ConstraintParams(), const real* drive_kp = nullptr,
                                      const real* drive_kd = nullptr, WarmStart<W>* warm = nullptr) {
  using CD = ConstraintData<N, C>;
  constexpr int kDofs = CD::kDofs;
  const int n = m.num_dofs;
  if (!(dt_s > 0) || !is_finite(dt_s) || num_contacts < 0 || num_contacts > C || (num_contacts > 0 && contacts == nullptr))
    return Status::invalid_argument;
  if (!detail::valid_contacts(m, contacts, num_contacts)) return Status::invalid_argument;
  if (!all_finite(q, m.num_q) || !all_finite(qd, n) || !all_finite(tau, n)) return Status::non_finite_input;
  if (!detail::base_quaternion_ok(m, q)) return Status::non_finite_input;

  // The unconstrained step: (H + h D) a = tau - bias, bias = rnea at zero acceleration (Coriolis,
  // centrifugal, gravity and the damping force D qd).
  if (!p.poses_current) detail::update_kinematics(m, d, q);
  detail::crba_passes(m, d, &cd.H[0][0], kDofs);
  for (int i = 0; i < m.num_bodies; ++i)
    if (m.dof_index[i] >= 0 && m.joint[i] != JointType::free) cd.H[m.dof_index[i]][m.dof_index[i]] += dt_s * m.damping[i];
  real zero[kDofs] = {}, acc[kDofs];
  detail::rnea_passes(m, d, qd, zero, acc, static_cast<const Vec6*>(nullptr));  // the kinematics at q, as crba's
  for (int k = 0; k < n; ++k) acc[k] = tau[k] - acc[k];
  if (drive_kp != nullptr || drive_kd != nullptr) {
    // The drives' torques in tau, kp (q* - q) - kd qd, taken at the end of the step:
    // (H + h kd + h^2 kp) a = tau - bias - h kp qd.
    for (int k = 0; k < n; ++k) {
      const real kp = drive_kp != nullptr ? drive_kp[k] : real(0), kd = drive_kd != nullptr ? drive_kd[k] : real(0);
      if (!(kp >= 0) || !(kd >= 0) || !is_finite(kp) || !is_finite(kd)) return Status::invalid_argument;
      cd.H[k][k] += dt_s * kd + dt_s * dt_s * kp;
      acc[k] -= dt_s * kp * qd[k];
    }
  }
  detail::dof_parents(m, cd.dof_parent);
  detail::build_chains(cd, n);
  if (!detail::ltdl_factor(cd, n)) return Status::non_finite_input;
  detail::ltdl_solve(cd, n, acc);
  real v_free[kDofs];
  for (int k = 0; k < n; ++k) v_free[k] = qd[k] + dt_s * acc[k];
  if (!all_finite(v_free, n)) return Status::non_finite_input;

  // The rows.
  if (!p.poses_current) detail::world_poses(m, d, cd.X_world);  // the kinematics still at q
  int rows = 0;
  auto new_row = [&](RowKind kind, int owner) -> int {
    const int r = rows++;
    for (int k = 0; k < n; ++k) cd.J[r][k] = 0;
    cd.kind[r] = kind;
    cd.owner[r] = static_cast<std::int16_t>(owner);
    cd.lambda[r] = 0;
    cd.key[r] = -1;
    cd.leaf[r] = cd.leaf_b[r] = -1;
    cd.target[r] = 0;
    cd.lo[r] = 0;
    cd.hi[r] = std::numeric_limits<real>::infinity();
    return r;
  };
  real Jp[6 * kDofs], Jq[6 * kDofs];
  auto chain_leaf = [&](int body) {  // the last velocity coordinate on the body's chain (-1: none)
    for (int b = body; b >= 0; b = m.parent[b])
      if (m.dof_index[b] >= 0) return m.dof_index[b] + joint_dofs(m, b) - 1;
    return -1;
  };
  for (int c = 0; c < num_contacts; ++c) {
    const ContactPoint& ct = contacts[c];
    const Transform& Xb = cd.X_world[ct.body];
    point_jacobian(m, cd.X_world, ct.body, Vec3(Xb.E * (ct.point_w - Xb.r)), Jp, kDofs);
    if (ct.body_b >= 0) {  // the relative velocity: body's point minus body_b's point at the same place
      const Transform& Xo = cd.X_world[ct.body_b];
      point_jacobian(m, cd.X_world, ct.body_b, Vec3(Xo.E * (ct.point_w - Xo.r)), Jq, kDofs);
      for (int k = 0; k < 3 * kDofs; ++k) Jp[k] -= Jq[k];
    }
    Vec3 t1, t2;
    detail::tangent_basis(ct.normal_w, t1, t2);
    const Vec3 dir[3] = {ct.normal_w, t1, t2};
    const int leaf = chain_leaf(ct.body), leaf_b = ct.body_b >= 0 ? chain_leaf(ct.body_b) : -1;
    for (int a = 0; a < 3; ++a) {
      const int r = new_row(a == 0 ? RowKind::normal : RowKind::tangent, c);
      cd.leaf[r] = static_cast<std::int16_t>(leaf);
      cd.leaf_b[r] = static_cast<std::int16_t>(leaf_b);
      if (ct.key >= 0) cd.key[r] = 3 * ct.key + a;
      for (int k = 0; k < n; ++k) cd.J[r][k] = dir[a][0] * Jp[k] + dir[a][1] * Jp[kDofs + k] + dir[a][2] * Jp[2 * kDofs + k];
    }
    const int rn = rows - 3;
    const real s = ct.separation_m;
    real target = s > 0 ? -s / dt_s : std::min(p.baumgarte * (-s > p.slop_m ? -s - p.slop_m : 0) / dt_s, p.max_push_mps);
    real v_before = 0;
    for (int k = 0; k < n; ++k) v_before += cd.J[rn][k] * qd[k];
    if (ct.restitution > 0 && v_before < -p.restitution_threshold_mps && s + dt_s * v_before <= 0)
      target = std::max(target, -ct.restitution * v_before);
    cd.target[rn] = target;
  }
  for (int i = 0; i < m.num_bodies; ++i) {
    const int k = m.dof_index[i];
    if (k < 0 || m.joint[i] == JointType::free) continue;
    if (m.has_limit[i]) {
      const real qi = q[m.q_index[i]];
      const real gap[2] = {qi - m.q_min[i], m.q_max[i] - qi};  // lower, upper
      const real toward[2] = {-v_free[k], v_free[k]};        // speed toward each limit
      for (int side = 0; side < 2; ++side) {
        if (gap[side] > p.limit_margin + dt_s * std::max(toward[side], real(0))) continue;
        const int r = new_row(RowKind::limit, k);
        cd.leaf[r] = static_cast<std::int16_t>(k);
        cd.key[r] = -(2 + 3 * k + side);  // joint rows: negative keys below -1
        cd.J[r][k] = side == 0 ? real(1) : real(-1);
        cd.target[r] = gap[side] > 0 ? -gap[side] / dt_s : std::min(p.baumgarte * -gap[side] / dt_s, p.max_push_mps);
      }
    }
    if (m.friction_loss[i] > 0) {
      const int r = new_row(RowKind::joint_friction, k);
      cd.leaf[r] = static_cast<std::int16_t>(k);
      cd.key[r] = -(4 + 3 * k);
      cd.J[r][k] = 1;
      cd.lo[r] = -m.friction_loss[i] * dt_s;
      cd.hi[r] = m.friction_loss[i] * dt_s;
    }
  }
  cd.num_rows = rows;

  // W = J (H + h D)^-1 J^T = Z^T D^-1 Z with Z = L^-T J^T, each column solved along the row's chain
  // of velocity coordinates alone (a foot's row touches the base and its leg, nothing else; a
  // two-body contact's, the two bodies' chains), which is where the tree's sparsity pays (RBDA
  // section 6.5); b = J v*. The chain is deepest first, so each coordinate is final before it is
  // passed up.
  using Four = Eigen::Array<real, 4, 1, Eigen::DontAlign>;
  std::int16_t merged[kDofs];  // a two-body row's chain
  const int rows_pad = (rows + 3) / 4 * 4;  // W's rows are summed four columns at a time below
  for (int k = 0; k < n; ++k)
    for (int c = 0; c < rows_pad; ++c) cd.ZT[k][c] = 0;
  for (int r0 = 0; r0 < rows;) {
    if (cd.leaf_b[r0] >= 0 || cd.leaf[r0] < 0) {  // a two-body row (or one that moves nothing): alone
      real z[kDofs];
      for (int k = 0; k < n; ++k) z[k] = 0;
      const int len = detail::row_chain(cd, r0, merged);
      for (int a = 0; a < len; ++a) z[merged[a]] = cd.J[r0][merged[a]];
      for (int a = 0; a < len; ++a) {
        const int i = merged[a];
        for (int j = cd.dof_parent[i]; j >= 0; j = cd.dof_parent[j]) z[j] -= cd.H[i][j] * z[i];
      }
      for (int a = 0; a < len; ++a) cd.ZT[merged[a]][r0] = z[merged[a]];
      real bv = 0;
      for (int a = 0; a < len; ++a) bv += cd.J[r0][merged[a]] * v_free[merged[a]];
      cd.b[r0] = bv;
      ++r0;
      continue;
    }
    // The group: the rows from r0 on, while each one's leaf has the previous rows' leaves on its
    // chain (the same leaf, or a deeper joint of the same leg).
    int r1 = r0 + 1;
    for (; r1 < rows && r1 - r0 < detail::kChainGroup && cd.leaf_b[r1] < 0 && cd.leaf[r1] >= 0; ++r1) {
      const int deep = cd.leaf[r1], prev = cd.leaf[r1 - 1];
      const int off = cd.chain_len[deep] - cd.chain_len[prev];
      if (off < 0 || cd.chain_of[deep][off] != prev) break;
    }
    const int G = r1 - r0;
    const std::int16_t* chain = cd.chain_of[cd.leaf[r1 - 1]];
    const int len = cd.chain_len[cd.leaf[r1 - 1]];
    real zc[kDofs][detail::kChainGroup];
    int start[detail::kChainGroup];  // where each row's own chain begins on the group's
    for (int a = 0; a < len; ++a)
      for (int g = 0; g < detail::kChainGroup; ++g) zc[a][g] = 0;
    for (int g = 0; g < G; ++g) {
      const int r = r0 + g;
      start[g] = len - cd.chain_len[cd.leaf[r]];
      for (int a = start[g]; a < len; ++a) zc[a][g] = cd.J[r][chain[a]];
    }
    detail::chain_solve(chain, len, cd.L_chain, zc);
    for (int g = 0; g < G; ++g) {
      const int r = r0 + g;
      real bv = 0;
      for (int a = start[g]; a < len; ++a) {
        cd.ZT[chain[a]][r] = zc[a][g];
        bv += cd.J[r][chain[a]] * v_free[chain[a]];
      }
      cd.b[r] = bv;
    }
    r0 = r1;
  }
  // Z_rk / D_k for every row at once, four divisions per instruction.
  for (int k = 0; k < n; ++k) {
    const Four D = Four::Constant(cd.H[k][k]);
    for (int c = 0; c < rows_pad; c += 4) Eigen::Map<Four>(cd.ZDT[k] + c) = Eigen::Map<const Four>(cd.ZT[k] + c) / D;
  }
  for (int r = 0; r < rows; ++r) {
    // Row r of W's lower triangle, sum_k (Z_rk / D_k) Z_ck over row r's chain, in the chain's
    // order (Z is stored by coordinate for it): four columns c <= r at a time, summed in
    // registers (stored and reloaded per coordinate, one column at a time, the sums were a
    // dependent chain through memory; the additions are the same, in the same order). ZT's
    // columns up to rows_pad are written (zeros past the rows).
    const std::int16_t* chain;
    const int len = detail::row_chain_view(cd, r, merged, &chain);
    real zd[kDofs];
    for (int k = 0; k < len; ++k) zd[k] = cd.ZDT[chain[k]][r];
    real* w = cd.W[r];
    for (int c0 = 0; c0 <= r; c0 += 4) {
      Four sum = Four::Zero();
      for (int k = 0; k < len; ++k) sum += zd[k] * Eigen::Map<const Four>(cd.ZT[chain[k]] + c0);
      Eigen::Map<Four>(w + c0) = sum;  // past r: rewritten by the mirror below (later rows) or the padding
    }
    for (int c = 0; c < r; ++c) cd.W[c][r] = w[c];
    for (int c = rows; c < rows_pad; ++c) w[c] = 0;
  }

  if (warm != nullptr) {
    // Start from the previous step's impulses of the same rows (looked up by key; most rows keep
    // their index, which is tried first), clamped to this step's bounds.
    for (int r = 0; r < rows; ++r) {
      if (cd.key[r] == -1) continue;
      int found = -1;
      if (r < warm->count && warm->key[r] == cd.key[r]) found = r;
      for (int k = 0; found < 0 && k < warm->count; ++k)
        if (warm->key[k] == cd.key[r]) found = k;
      if (found < 0) continue;
      real l = warm->lambda[found];
      if (cd.kind[r] == RowKind::normal) l = std::max(l, real(0));
      if (cd.kind[r] == RowKind::limit || cd.kind[r] == RowKind::joint_friction) l = std::min(std::max(l, cd.lo[r]), cd.hi[r]);
      cd.lambda[r] = l;
    }
    for (int r = 0; r < num_contacts; ++r) {  // friction within the cone of the warm normal impulse
      const int rn = 3 * r;
      const real lim = contacts[r].friction * cd.lambda[rn];
      const real mag = std::sqrt(cd.lambda[rn + 1] * cd.lambda[rn + 1] + cd.lambda[rn + 2] * cd.lambda[rn + 2]);
      if (mag > lim) {
        const real s = mag > 0 ? lim / mag : real(0);
        cd.lambda[rn + 1] *= s;
        cd.lambda[rn + 2] *= s;
      }
    }
  }
  real friction[C > 0 ? C : 1] = {};  // zeros past the contacts (never read; -Wmaybe-uninitialized cannot see that)
  for (int c = 0; c < num_contacts; ++c) friction[c] = contacts[c].friction;
  const int sweep = detail::pgs_sweeps(cd, rows, friction, p);
  cd.iterations_used = sweep;
  if (warm != nullptr) {
    warm->count = rows < W ? rows : W;
    for (int r = 0; r < warm->count; ++r) {
      warm->key[r] = cd.key[r];
      warm->lambda[r] = cd.lambda[r];
    }
  }

  // v = v* + Y^T lambda, then the positions with it.
  // J^T lambda over whole rows (every coordinate at once, vectorised): off a row's chain its
  // entries are exact zeros, which change no sum, so this is the sum over the chains.
  real v_new[kDofs] = {};
  {
    using Dense = Eigen::Array<real, Eigen::Dynamic, 1>;  // a view: Map never allocates
    Eigen::Map<Dense> v(v_new, n);
    for (int r = 0; r < rows; ++r)
      if (cd.lambda[r] != 0) v += Eigen::Map<const Dense>(cd.J[r], n) * cd.lambda[r];
  }
  detail::ltdl_solve(cd, n, v_new);  // (H + h D)^-1 J^T lambda
  for (int k = 0; k < n; ++k) v_new[k] += v_free[k];
  if (!all_finite(v_new, n)) return Status::non_finite_input;
  detail::integrate_positions(m, q, v_new, dt_s);
  for (int k = 0; k < n; ++k) qd[k] = v_new[k];

  for (int c = 0; c < num_contacts; ++c) cd.contact_force_w[c] = Vec3::Zero();
  for (int k = 0; k < n; ++k) cd.joint_constraint_force[k] = 0;
  for (int r = 0; r < rows; ++r) {
    const real f = cd.lambda[r] / dt_s;
    if (r < 3 * num_contacts) {  // contact rows come first, three per contact: normal, t1, t2
      const ContactPoint& ct = contacts[r / 3];
      Vec3 t1, t2;
      detail::tangent_basis(ct.normal_w, t1, t2);
      cd.contact_force_w[r / 3] += f * (r % 3 == 0 ? ct.normal_w : r % 3 == 1 ? t1 : t2);
    } else {
      cd.joint_constraint_force[cd.owner[r]] += f * cd.J[r][cd.owner[r]];
    }
  }
  return Status::ok;
}

// ----------------------------------------------------------------------------------------------
// Collision geometry against a half-space (the ground, a slope).

enum class ShapeType : std::uint8_t { sphere = 0, capsule = 1, box = 2, convex = 3 };

/// Contacts a convex shape gives with a half-space at most (its deepest vertices): the keys' room
/// per shape, as a box's eight corners.
constexpr int kMaxConvexContacts = 8;

/// A collision primitive fixed on a body: its centre p_b and orientation R_b (shape -> body) in
/// the body's frame; size: sphere [radius, -, -]; capsule [radius, half-length of the segment
/// along the shape's z, -]; box [half extents]; convex: the vertices of a convex mesh (a robot's
/// collision mesh, reduced to its hull's extreme points) in the shape's frame, `points` (caller
/// storage, num_points of them; size unused). Its friction coefficient and restitution. Convex
/// shapes collide with half-spaces (collide_halfspace), not with other shapes (collide_shapes
/// gives them no contact).
struct CollisionShape {
  int body = -1;
  ShapeType type = ShapeType::sphere;
  Mat3 R_b = Mat3::Identity();
  Vec3 p_b = Vec3::Zero();
  Vec3 size = Vec3::Zero();
  real friction = 1;
  real restitution = 0;
  const Vec3* points = nullptr;  // convex only
  int num_points = 0;
};

/// The ground as the half-space n . x <= offset_m (n unit, world coordinates, pointing out of the
/// ground), with its friction coefficient and restitution.
struct HalfSpace {
  Vec3 normal_w = Vec3(0, 0, 1);
  real offset_m = 0;
  real friction = 1;
  real restitution = 0;
};

/// The contacts of the shapes with the half-space whose gap is below margin_m (a positive margin
/// lets step_constrained catch a fast body at the step it arrives): a sphere's deepest point, a
/// capsule's two end spheres, a box's corners, a convex shape's vertices (its kMaxConvexContacts
/// deepest, in vertex order, so a vertex keeps its key while the set stays the same). The pair's friction and restitution are the means
/// of the two (PhysX's default combine mode, which legged_gym's friction ranges assume). Writes at
/// most `capacity` contacts and returns how many were found (more than capacity: the caller's
/// capacity is too small; the first `capacity` are written).
inline int collide_halfspace(const CollisionShape* shapes, int num_shapes, const Transform* X_world, const HalfSpace& g,
                             real margin_m, ContactPoint* out, int capacity, int first_shape_key = 0) {
  int found = 0;
  int shape = 0, point = 0;  // the contact's key: (first_shape_key + shape) x 8 + point
  auto add = [&](int body, const Vec3& point_w, real gap, const CollisionShape& s) {
    const int this_point = point++;
    if (!(gap < margin_m)) return;
    if (found < capacity) {
      ContactPoint& c = out[found];
      c.body = body;
      c.body_b = -1;
      c.point_w = point_w;
      c.normal_w = g.normal_w;
      c.separation_m = gap;
      c.friction = real(0.5) * (s.friction + g.friction);
      c.restitution = real(0.5) * (s.restitution + g.restitution);
      c.key = (first_shape_key + shape) * 8 + this_point;
    }
    ++found;
  };
  for (int i = 0; i < num_shapes; ++i) {
    const CollisionShape& s = shapes[i];
    shape = i;
    point = 0;
    const Transform& X = X_world[s.body];
    const Vec3 c_w = X.r + X.E.transpose() * s.p_b;
    // A capsule or box whose every point is above the margin by 0.1 mm more (no rounding of the
    // gaps below comes near that) has no contact: its points are skipped (their keys with them, as
    // points not below the margin are), which leaves the result as it was and spares the
    // orientation and the corners of a legged robot's trunk and upper legs in stance.
    if (s.type == ShapeType::capsule || s.type == ShapeType::box) {
      const real reach = s.type == ShapeType::capsule ? s.size[0] + s.size[1] : s.size.norm();
      if (g.normal_w.dot(c_w) - g.offset_m - reach > margin_m + real(1e-4)) continue;
    }
    const Mat3 R_w = X.E.transpose() * s.R_b;  // shape -> world
    switch (s.type) {
      case ShapeType::sphere:
        add(s.body, c_w - s.size[0] * g.normal_w, g.normal_w.dot(c_w) - g.offset_m - s.size[0], s);
        break;
      case ShapeType::capsule:
        for (int e = -1; e <= 1; e += 2) {
          const Vec3 end = c_w + R_w * Vec3(0, 0, real(e) * s.size[1]);
          add(s.body, end - s.size[0] * g.normal_w, g.normal_w.dot(end) - g.offset_m - s.size[0], s);
        }
        break;
      case ShapeType::box:
        for (int k = 0; k < 8; ++k) {
          const Vec3 corner = c_w + R_w * Vec3((k & 1) ? s.size[0] : -s.size[0], (k & 2) ? s.size[1] : -s.size[1],
                                               (k & 4) ? s.size[2] : -s.size[2]);
          add(s.body, corner, g.normal_w.dot(corner) - g.offset_m, s);
        }
        break;
      case ShapeType::convex: {
        // The kMaxConvexContacts deepest vertices below the margin: a threshold gap raised until
        // few enough remain (selection without sorting storage), ties kept in vertex order.
        int chosen[kMaxConvexContacts];
        real chosen_gap[kMaxConvexContacts];
        int n = 0;
        for (int k = 0; k < s.num_points; ++k) {
          const real gap = g.normal_w.dot(X.r + X.E.transpose() * (s.p_b + s.R_b * s.points[k])) - g.offset_m;
          if (!(gap < margin_m)) continue;
          if (n < kMaxConvexContacts) {
            chosen[n] = k;
            chosen_gap[n++] = gap;
            continue;
          }
          int worst = 0;  // the shallowest chosen vertex, replaced by a deeper one
          for (int j = 1; j < n; ++j)
            if (chosen_gap[j] > chosen_gap[worst]) worst = j;
          if (gap < chosen_gap[worst]) {
            for (int j = worst; j + 1 < n; ++j) chosen[j] = chosen[j + 1], chosen_gap[j] = chosen_gap[j + 1];
            chosen[n - 1] = k;
            chosen_gap[n - 1] = gap;
          }
        }
        for (int j = 0; j < n; ++j) {
          const Vec3 v_w = c_w + R_w * s.points[chosen[j]];
          add(s.body, v_w, chosen_gap[j], s);
        }
        break;
      }
    }
  }
  return found;
}

// ----------------------------------------------------------------------------------------------
// Collision geometry between two shapes (a gripper's pads and the cube, the cube and a container's
// walls): narrow phase only, the caller chooses the pairs.

namespace detail {

/// Signed distance from p to the surface of a box of half extents h centred at the origin (the
/// box's frame): positive outside, negative inside. `closest` receives the nearest surface point
/// and `normal` the box's outward unit normal there (outside: along p - closest; inside: the face
/// nearest p, the first of equally near ones, so the same input gives the same face).
inline real box_point_distance(const Vec3& h, const Vec3& p, Vec3& closest, Vec3& normal) {
  const Vec3 q(std::fabs(p[0]) - h[0], std::fabs(p[1]) - h[1], std::fabs(p[2]) - h[2]);
  if (q[0] > 0 || q[1] > 0 || q[2] > 0) {
    for (int a = 0; a < 3; ++a) closest[a] = std::min(std::max(p[a], -h[a]), h[a]);
    const Vec3 d = p - closest;
    const real dist = d.norm();
    normal = d / dist;
    return dist;
  }
  int a = 0;
  if (q[1] > q[a]) a = 1;
  if (q[2] > q[a]) a = 2;
  const real side = p[a] < 0 ? real(-1) : real(1);
  normal = Vec3::Zero();
  normal[a] = side;
  closest = p;
  closest[a] = side * h[a];
  return q[a];
}

/// The closest points of segments [p0, p1] and [q0, q1] (either may be a point): the parameters
/// s, t in [0, 1] (C. Ericson, "Real-Time Collision Detection", Morgan Kaufmann 2005, section
/// 5.1.9).
inline void segment_closest(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, real& s, real& t) {
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const real a = d1.dot(d1), e = d2.dot(d2), f = d2.dot(r);
  const real eps = real(1e-12);
  auto clamp01 = [](real x) { return std::min(std::max(x, real(0)), real(1)); };
  if (a <= eps && e <= eps) {
    s = t = 0;
    return;
  }
  if (a <= eps) {
    s = 0;
    t = clamp01(f / e);
    return;
  }
  const real c = d1.dot(r);
  if (e <= eps) {
    t = 0;
    s = clamp01(-c / a);
    return;
  }
  const real b = d1.dot(d2), denom = a * e - b * b;
  s = denom > eps * a * e ? clamp01((b * f - c * e) / denom) : real(0);  // parallel: any s; take 0
  t = (b * s + f) / e;
  if (t < 0) {
    t = 0;
    s = clamp01(-c / a);
  } else if (t > 1) {
    t = 1;
    s = clamp01((b - c) / a);
  }
}

/// A sphere's or capsule's core segment in the world (a sphere's is a point) and its radius.
inline real shape_segment(const CollisionShape& s, const Vec3& c_w, const Mat3& R_w, Vec3& e0, Vec3& e1) {
  const Vec3 half = s.type == ShapeType::capsule ? Vec3(R_w.col(2) * s.size[1]) : Vec3::Zero();
  e0 = c_w - half;
  e1 = c_w + half;
  return s.size[0];
}

}  // namespace detail

/// A shape's centre and orientation (shape -> world) in the world; X_body is its body's pose
/// (Plücker world -> body, as forward_kinematics gives) or the identity for a world shape.
inline void shape_pose(const CollisionShape& s, const Transform& X_body, Vec3& c_w, Mat3& R_w) {
  R_w = X_body.E.transpose() * s.R_b;
  c_w = X_body.r + X_body.E.transpose() * s.p_b;
}

/// A radius that bounds the shape about its centre (collide_shapes' broad phase, or a caller's own over many pairs).
inline real bounding_radius(const CollisionShape& s) {
  switch (s.type) {
    case ShapeType::sphere: return s.size[0];
    case ShapeType::capsule: return s.size[0] + s.size[1];
    case ShapeType::box: return s.size.norm();
    case ShapeType::convex: {
      real r = 0;
      for (int k = 0; k < s.num_points; ++k) r = std::max(r, s.points[k].norm());
      return r;
    }
  }
  return 0;
}

/// The contacts between shape a, on body a.body (>= 0), and shape b, on body b.body or on the world
/// (b.body = -1, X_b the identity: its p_b and R_b are then world coordinates), whose gap is below
/// margin_m; each contact pushes a.body along its normal and b.body against it (ContactPoint's
/// body and body_b). X_a, X_b: the bodies' poses (forward_kinematics). The pairs:
///  - sphere or capsule with sphere or capsule: one contact between the closest points of their
///    core segments (two parallel capsules side by side touch at one point of their overlap);
///  - sphere or capsule with box: each end sphere (a sphere's one) against the box;
///  - box with box: the separating axis of least penetration; on a face axis, the other box's
///    incident face clipped to the reference face (up to 8 contacts: a cube on a floor gets its
///    four corners, a pad pressed on a cube's face its four), on an edge axis one contact between
///    the two edges.
/// Friction and restitution are the pair's means (as collide_halfspace). Keys: key_base + the
/// point's index below 16, so a caller gives each pair its own key_base (multiples of 16). Writes
/// at most `capacity` contacts and returns how many were found (more than capacity: too small).
inline int collide_shapes(const CollisionShape& a, const Transform& X_a, const CollisionShape& b, const Transform& X_b,
                          real margin_m, ContactPoint* out, int capacity, std::int32_t key_base = 0) {
  if (a.type == ShapeType::convex || b.type == ShapeType::convex) return 0;  // half-spaces only (see CollisionShape)
  Vec3 ca, cb;
  Mat3 Ra, Rb;
  shape_pose(a, X_a, ca, Ra);
  shape_pose(b, X_b, cb, Rb);
  if ((ca - cb).norm() > bounding_radius(a) + bounding_radius(b) + margin_m) return 0;
  int found = 0;
  auto add = [&](int index, const Vec3& point_w, const Vec3& normal_w, real gap) {
    if (!(gap < margin_m)) return;
    if (found < capacity) {
      ContactPoint& c = out[found];
      c.body = a.body;
      c.body_b = b.body;
      c.point_w = point_w;
      c.normal_w = normal_w;
      c.separation_m = gap;
      c.friction = real(0.5) * (a.friction + b.friction);
      c.restitution = real(0.5) * (a.restitution + b.restitution);
      c.key = key_base + index;
    }
    ++found;
  };
  // A sphere (centre p_w, radius r) against box `box` (centre c, orientation R); sign +1 when the
  // sphere is on a (the box pushes it along the box's normal), -1 when on b.
  auto sphere_box = [&](int index, const Vec3& p_w, real r, const CollisionShape& box, const Vec3& c, const Mat3& R,
                        real sign) {
    Vec3 closest, normal;
    const real dist = detail::box_point_distance(box.size, Vec3(R.transpose() * (p_w - c)), closest, normal);
    const Vec3 n_w = R * normal;  // out of the box
    add(index, p_w - r * n_w, sign * n_w, dist - r);
  };
  // Box against box by the separating axis test over the 15 axes (3 face normals of each, 9 edge
  // cross products; S. Gottschalk, M. Lin, D. Manocha, "OBBTree", SIGGRAPH 1996) and, on the axis of
  // least penetration: for a face axis, the other box's incident face clipped against the
  // reference face's sides (Sutherland-Hodgman), each clipped point below the reference face a
  // contact (up to 8: a pad on a cube's face gets its four corners, a cube on a pad's face the
  // pad's); for an edge axis, one contact between the two edges (the scheme of R. Smith's ODE
  // dBoxBox and E. Catto's Box2D manifolds). Face axes are preferred unless an edge axis separates
  // more by 1e-5 m, so a resting face does not flip between them from step to step.
  auto box_box = [&](const Vec3& ha, const Vec3& pa, const Mat3& RA, const Vec3& hb, const Vec3& pb, const Mat3& RB) {
    const Vec3 d = pb - pa;
    real best = -std::numeric_limits<real>::infinity();
    int best_axis = -1;  // 0-2: a's faces, 3-5: b's, 6-14: edges
    Vec3 best_L = Vec3::Zero();
    auto support = [](const Vec3& L, const Mat3& R, const Vec3& h) {
      return std::fabs(L.dot(R.col(0))) * h[0] + std::fabs(L.dot(R.col(1))) * h[1] + std::fabs(L.dot(R.col(2))) * h[2];
    };
    for (int axis = 0; axis < 15; ++axis) {
      Vec3 L;
      if (axis < 3) L = RA.col(axis);
      else if (axis < 6) L = RB.col(axis - 3);
      else {
        L = RA.col((axis - 6) / 3).cross(RB.col((axis - 6) % 3));
        const real len = L.norm();
        if (len < real(1e-4)) continue;  // parallel edges: a face axis covers them
        L /= len;
      }
      const real sep = std::fabs(d.dot(L)) - support(L, RA, ha) - support(L, RB, hb);
      if (sep > margin_m) return;  // separated
      const real bias = axis < 6 ? real(0) : real(1e-5);
      if (sep > best + bias) {
        best = sep;
        best_axis = axis;
        best_L = L;
      }
    }
    if (best_axis < 0) return;
    const Vec3 n = d.dot(best_L) > 0 ? Vec3(-best_L) : best_L;  // from b into a
    if (best_axis >= 6) {
      // The edge of each box nearest the other, along its own axis.
      const int ia = (best_axis - 6) / 3, ib = (best_axis - 6) % 3;
      Vec3 ea = pa, eb = pb;
      for (int k = 0; k < 3; ++k) {
        if (k != ia) ea += (RA.col(k).dot(-n) > 0 ? ha[k] : -ha[k]) * RA.col(k);
        if (k != ib) eb += (RB.col(k).dot(n) > 0 ? hb[k] : -hb[k]) * RB.col(k);
      }
      real s = 0, t = 0;
      detail::segment_closest(ea - ha[ia] * RA.col(ia), ea + ha[ia] * RA.col(ia), eb - hb[ib] * RB.col(ib),
                              eb + hb[ib] * RB.col(ib), s, t);
      const Vec3 qa = ea + (2 * s - 1) * ha[ia] * RA.col(ia), qb = eb + (2 * t - 1) * hb[ib] * RB.col(ib);
      add(8, real(0.5) * (qa + qb), n, best);
      return;
    }
    // Reference face on the box whose axis won, incident face on the other.
    const bool ref_b = best_axis >= 3;
    const Mat3& Rr = ref_b ? RB : RA;
    const Mat3& Ri = ref_b ? RA : RB;
    const Vec3& hr = ref_b ? hb : ha;
    const Vec3& hi = ref_b ? ha : hb;
    const Vec3& pr = ref_b ? pb : pa;
    const Vec3& pi = ref_b ? pa : pb;
    const int r_axis = best_axis % 3;
    const Vec3 nr = ref_b ? n : Vec3(-n);  // the reference face's outward normal (towards the other box)
    // The incident face: the other box's face most against nr.
    int i_axis = 0;
    real most = 0;
    for (int k = 0; k < 3; ++k)
      if (std::fabs(Ri.col(k).dot(nr)) > most) {
        most = std::fabs(Ri.col(k).dot(nr));
        i_axis = k;
      }
    const real i_sign = Ri.col(i_axis).dot(nr) > 0 ? real(-1) : real(1);
    const int u = (i_axis + 1) % 3, v = (i_axis + 2) % 3;
    const Vec3 fc = pi + i_sign * hi[i_axis] * Ri.col(i_axis);
    Vec3 poly[8], next[8];
    int count = 4;
    const real su[4] = {-1, 1, 1, -1}, sv[4] = {-1, -1, 1, 1};
    for (int k = 0; k < 4; ++k) poly[k] = fc + su[k] * hi[u] * Ri.col(u) + sv[k] * hi[v] * Ri.col(v);
    // Clip against the reference face's four sides: |(x - pr) . Rr_k| <= hr_k for its two other axes.
    for (int side = 0; side < 4 && count > 0; ++side) {
      const int k = (r_axis + 1 + side / 2) % 3;
      const Vec3 dir = (side % 2 == 0 ? real(1) : real(-1)) * Rr.col(k);
      const real lim = hr[k];
      int out_n = 0;
      for (int e = 0; e < count; ++e) {
        const Vec3& p0 = poly[e];
        const Vec3& p1 = poly[(e + 1) % count];
        const real d0 = dir.dot(p0 - pr) - lim, d1 = dir.dot(p1 - pr) - lim;
        if (d0 <= 0 && out_n < 8) next[out_n++] = p0;
        if ((d0 <= 0) != (d1 <= 0) && out_n < 8) next[out_n++] = p0 + (d0 / (d0 - d1)) * (p1 - p0);
      }
      count = out_n;
      for (int e = 0; e < count; ++e) poly[e] = next[e];
    }
    for (int k = 0; k < count; ++k) {
      const real gap = nr.dot(poly[k] - pr) - hr[r_axis];
      // The point on the incident face; moved halfway to the reference face so that both bodies'
      // material points agree to first order.
      add(k, poly[k] - real(0.5) * gap * nr, n, gap);
    }
  };
  const bool round_a = a.type != ShapeType::box, round_b = b.type != ShapeType::box;
  if (round_a && round_b) {
    Vec3 a0, a1, b0, b1;
    const real ra = detail::shape_segment(a, ca, Ra, a0, a1), rb = detail::shape_segment(b, cb, Rb, b0, b1);
    real s = 0, t = 0;
    detail::segment_closest(a0, a1, b0, b1, s, t);
    const Vec3 pa = a0 + s * (a1 - a0), pb = b0 + t * (b1 - b0);
    const Vec3 d = pa - pb;
    const real dist = d.norm();
    // Coincident core points: push along the world's z (any fixed direction; the case is degenerate).
    const Vec3 n = dist > real(1e-9) ? Vec3(d / dist) : Vec3(0, 0, 1);
    add(0, pb + rb * n, n, dist - ra - rb);
  } else if (round_a || round_b) {
    const CollisionShape& round = round_a ? a : b;
    const CollisionShape& box = round_a ? b : a;
    Vec3 e0, e1;
    const real r = detail::shape_segment(round, round_a ? ca : cb, round_a ? Ra : Rb, e0, e1);
    const real sign = round_a ? real(1) : real(-1);
    sphere_box(0, e0, r, box, round_a ? cb : ca, round_a ? Rb : Ra, sign);
    if (round.type == ShapeType::capsule) sphere_box(1, e1, r, box, round_a ? cb : ca, round_a ? Rb : Ra, sign);
  } else {
    box_box(a.size, ca, Ra, b.size, cb, Rb);
  }
  return found;
}

}  // namespace kestrel::dynamics
