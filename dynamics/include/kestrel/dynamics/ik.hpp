// Inverse kinematics by damped least squares on the articulated model of multibody.hpp: the joint
// angles that put a point of a body (an arm's tool centre point) at a position and, optionally,
// its frame at an orientation.
//
// Each iteration takes the 6-row pose error e = [position error (m); orientation error (the
// rotation vector of R_target R^T, rad) x orientation_weight] and the point's Jacobian J
// (point_jacobian, rows weighted the same way), and steps the joints by
//   dq = J^T (J J^T + lambda^2 I)^-1 e,
// the damped least-squares (Levenberg-Marquardt) step of C. W. Wampler, "Manipulator inverse
// kinematic solutions based on vector formulations and damped least-squares methods", IEEE SMC
// 16(1), 1986, and Y. Nakamura, H. Hanafusa, J. Dyn. Sys. Meas. Control 108(3), 1986 (see S. R.
// Buss, "Introduction to inverse kinematics with Jacobian transpose, pseudoinverse and damped least
// squares methods", 2004). Why damped: near a singularity (an arm stretched out, a 5-joint arm asked
// for an orientation it cannot reach exactly) the pseudo-inverse's steps blow up, the damped step
// stays bounded and trades a little accuracy for it. The error one iteration aims at is clamped to
// max_error_m (Buss's clamped target), the step scaled down as a whole when a joint would move more
// than max_step_rad, and the result clamped into the joints' limits, so the answer is always a pose
// the arm can take.
//
// Only one-dof joints move (a floating base, if any, stays where it is). Core rules: no heap, no
// exceptions, float or double; a 6 x 6 solve by Eigen's fixed-size LDLT.
#pragma once

#include <Eigen/Cholesky>

#include "kestrel/dynamics/multibody.hpp"

namespace kestrel::dynamics {

struct IkParams {
  int iterations = 20;              // at most
  real damping = real(0.02);        // lambda (m, and rad x weight): larger is steadier and less exact
  real max_step_rad = real(0.2);    // per joint per iteration (the step is scaled down as a whole)
  real max_error_m = real(0.05);    // the weighted error one iteration aims to remove at most
  real tolerance_m = real(1e-4);    // stop once the weighted error's norm is below this
  real orientation_weight = real(0.1);  // metres per radian of orientation error (0: position only)
};

struct IkResult {
  real position_error_m = 0;     // at the returned q
  real orientation_error_rad = 0;  // at the returned q (0 when no orientation was asked)
  int iterations = 0;
};

/// Moves q (num_q entries, in place) so that the point point_b of `body` reaches target_w and,
/// when target_R_w is not null, the body's frame (body -> world rotation) reaches *target_R_w.
/// Status::ok (the result says how close it came); invalid_argument for a body out of range or a
/// non-finite target, non_finite_input for a non-finite q (q untouched on both).
template <int N>
[[nodiscard]] Status solve_ik(const MultibodyModel<N>& m, MultibodyData<N>& d, real* q, int body, const Vec3& point_b,
                              const Vec3& target_w, const Mat3* target_R_w, const IkParams& p, IkResult& result) {
  constexpr int kDofs = max_dofs<N>();
  if (body < 0 || body >= m.num_bodies || !all_finite(target_w) || !all_finite(point_b)) return Status::invalid_argument;
  if (target_R_w != nullptr && !all_finite(*target_R_w)) return Status::invalid_argument;
  if (!all_finite(q, m.num_q)) return Status::non_finite_input;
  Transform X[N];
  real J[6 * kDofs];
  using Vec6r = Eigen::Matrix<real, 6, 1>;
  using Mat6r = Eigen::Matrix<real, 6, 6>;
  const real w = target_R_w != nullptr ? p.orientation_weight : real(0);
  auto error = [&](Vec6r& e, real& pos_err, real& rot_err) {
    forward_kinematics(m, d, q, X);
    const Mat3 R = X[body].E.transpose();  // body -> world
    const Vec3 p_w = X[body].r + R * point_b;
    const Vec3 ep = target_w - p_w;
    Vec3 er = Vec3::Zero();
    if (target_R_w != nullptr) {
      // The rotation vector of R_err = R_target R^T (world frame), by the angle-axis of its
      // quaternion: exact for any angle below pi.
      const Mat3 Re = *target_R_w * R.transpose();
      const Eigen::Quaternion<real> qe(Re);
      const Vec3 v = qe.vec();
      const real s = v.norm();
      if (s > real(1e-12)) {
        const real c = qe.w();
        const real angle = real(2) * std::atan2(s, c < 0 ? -c : c);
        er = (c < 0 ? real(-1) : real(1)) * angle / s * v;
      }
    }
    for (int a = 0; a < 3; ++a) {
      e[a] = ep[a];
      e[3 + a] = w * er[a];
    }
    pos_err = ep.norm();
    rot_err = er.norm();
  };
  Vec6r e;
  real pos_err = 0, rot_err = 0;
  error(e, pos_err, rot_err);
  int it = 0;
  for (; it < p.iterations && e.norm() > p.tolerance_m; ++it) {
    point_jacobian(m, X, body, point_b, J, kDofs);
    for (int i = 0; i < m.num_bodies; ++i)  // only one-dof joints move
      if (m.joint[i] == JointType::free)
        for (int c = 0; c < 6; ++c)
          for (int r = 0; r < 6; ++r) J[kDofs * r + m.dof_index[i] + c] = 0;
    for (int r = 3; r < 6; ++r)
      for (int k = 0; k < m.num_dofs; ++k) J[kDofs * r + k] *= w;
    Mat6r A = Mat6r::Identity() * (p.damping * p.damping);
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c <= r; ++c) {
        real s = 0;
        for (int k = 0; k < m.num_dofs; ++k) s += J[kDofs * r + k] * J[kDofs * c + k];
        A(r, c) += s;
        if (c != r) A(c, r) += s;
      }
    // A far target is approached in steps of at most max_error_m (Buss's clamped target: the
    // linearisation holds only near q, and an unclamped far error makes the step jump about).
    Vec6r ec = e;
    const real en = ec.norm();
    if (en > p.max_error_m) ec *= p.max_error_m / en;
    const Vec6r y = A.ldlt().solve(ec);
    real dq[kDofs] = {}, largest = 0;
    for (int i = 0; i < m.num_bodies; ++i) {
      const int k = m.dof_index[i];
      if (k < 0 || m.joint[i] == JointType::free) continue;
      for (int r = 0; r < 6; ++r) dq[k] += J[kDofs * r + k] * y[r];
      largest = std::max(largest, std::fabs(dq[k]));
    }
    // The whole step scaled down together (clipping joints one by one would turn it).
    const real scale = largest > p.max_step_rad ? p.max_step_rad / largest : real(1);
    for (int i = 0; i < m.num_bodies; ++i) {
      const int k = m.dof_index[i];
      if (k < 0 || m.joint[i] == JointType::free) continue;
      real& qi = q[m.q_index[i]];
      qi += scale * dq[k];
      if (m.has_limit[i]) qi = std::min(std::max(qi, m.q_min[i]), m.q_max[i]);
    }
    error(e, pos_err, rot_err);
  }
  result.position_error_m = pos_err;
  result.orientation_error_rad = rot_err;
  result.iterations = it;
  return Status::ok;
}

}  // namespace kestrel::dynamics
