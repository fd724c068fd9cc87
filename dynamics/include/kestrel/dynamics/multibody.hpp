// Kinematic trees of rigid bodies on a fixed or floating base and their dynamics, after R. Featherstone,
// "Rigid Body Dynamics Algorithms", Springer 2008 (RBDA):
//   rnea  inverse dynamics, the recursive Newton-Euler algorithm (RBDA table 5.1);
//   crba  the joint-space mass matrix, the composite-rigid-body algorithm (RBDA table 6.2);
//   aba   forward dynamics, the articulated-body algorithm (RBDA table 7.1);
//   forward_kinematics, point_jacobian  body poses and the Jacobian of any point of any body.
// Each is a free function over a read-only model and a data object of fixed capacity, as
// Pinocchio's algorithms over (Model, Data): no heap, no exceptions, float or double.
//
// Bodies are numbered so that a body's parent has a smaller index (-1: the world, z up). Body i
// hangs from its parent by joint i: a revolute or prismatic joint with one degree of freedom along
// `axis` (a unit vector in the joint frame), a fixed joint with none, or, for a body hanging from
// the world, a free joint: a floating base (six degrees of freedom, RBDA section 9.3). Several
// bodies may hang from the world, so a model is a forest: a robot and the free objects it handles
// (an arm on a fixed base and the cube it picks) are one model, and contact.hpp couples them. The joint frame sits at
// X_tree[i] in the parent's frame; body i's frame is the joint frame moved by the joint: X_J(q)
// (rotation about / translation along the axis; the base's pose for the free joint).
// Capacities are template parameters; the degrees of freedom are numbered in body order.
//
// Coordinates (Pinocchio's, so that its models compare entry by entry): the configuration q has
// num_q entries and the velocities, accelerations and forces num_dofs. A free joint takes 7
// configuration entries [position of the base origin in the world (3), orientation quaternion
// base -> world, x y z w (4), unit] and 6 velocity entries [linear velocity of the base origin (3),
// angular velocity (3)], both in the base's own frame; its accelerations are the time
// derivatives of those (the base's spatial acceleration in its frame) and its "joint forces" the
// wrench on the base [force (3), moment about its origin (3)] in its frame. Every other joint
// takes one entry of each, or none.
#pragma once

#include <cmath>
#include <cstdint>
#include <type_traits>

#include <Eigen/Cholesky>

#include "kestrel/dynamics/lanes.hpp"
#include "kestrel/dynamics/spatial.hpp"
#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/status.hpp"

namespace kestrel::dynamics {

enum class JointType : std::uint8_t { revolute = 0, prismatic = 1, fixed = 2, free = 3 };

template <int kMaxBodies>
struct MultibodyModel {
  static_assert(kMaxBodies > 0, "a tree needs room for a body");
  static constexpr int max_bodies = kMaxBodies;
  int num_bodies = 0;
  int num_dofs = 0;                   // velocity coordinates, set by finish_model
  int num_q = 0;                      // configuration coordinates (num_dofs + 1 with a floating base)
  int parent[kMaxBodies] = {};        // -1: the world
  JointType joint[kMaxBodies] = {};
  Vec3 axis[kMaxBodies];              // unit, joint frame
  Transform X_tree[kMaxBodies];       // parent frame -> joint frame
  SpatialInertia body[kMaxBodies];    // in the body's frame
  int dof_index[kMaxBodies] = {};     // first velocity coordinate of joint i (set by finish_model; -1 for fixed)
  int q_index[kMaxBodies] = {};       // first configuration coordinate of joint i (-1 for fixed)
  // Per joint: the reflected rotor inertia (kg m^2 or kg, added to the mass matrix's diagonal, as
  // MuJoCo's and Pinocchio's armature) and viscous damping (N m s/rad or N s/m: a joint force
  // -damping * qd). Zero for a free joint.
  real armature[kMaxBodies] = {};
  real damping[kMaxBodies] = {};
  // Per joint, used by the constrained step (contact.hpp), not by rnea/crba/aba: position limits
  // (rad or m; has_limit false: none), Coulomb friction (N m or N, the largest force the joint's
  // dry friction resists motion with: MuJoCo's frictionloss) and the effort limit (N m or N;
  // 0: none) that the joint drive clamps its command to.
  bool has_limit[kMaxBodies] = {};
  real q_min[kMaxBodies] = {};
  real q_max[kMaxBodies] = {};
  real friction_loss[kMaxBodies] = {};
  real effort_limit[kMaxBodies] = {};
  // Set by finish_model: k (0, 1, 2) where joint i is revolute about +x, +y or +z of a joint frame
  // with no rotation in its parent (X_tree[i].E = 1, as in most robot files); -1 otherwise. aba
  // then takes X_up's rotation as the elementary rotation about axis k that it is (a third of the
  // multiplications of a general rotation's). Call finish_model again after changing axis or X_tree.
  std::int8_t elementary_axis[kMaxBodies] = {};
  // Set by finish_model: c where joint i's motion subspace S is the unit spatial vector e_c (a
  // revolute joint about +x, +y, +z: c = 0, 1, 2; a prismatic one along them: 3, 4, 5), whatever
  // X_tree; -1 otherwise. crba and rnea then read S . f as f[c] and I S as a column of I.
  std::int8_t unit_subspace[kMaxBodies] = {};
  Vec3 gravity_w = Vec3(0, 0, -9.81_r);
};

template <int kMaxBodies>
struct MultibodyData {
  // No motion subspace S: a revolute or prismatic joint's is constant in its frame, so it is the
  // model's (detail::motion_subspace); storing it per call was 4 % of aba.
  Transform Xup[kMaxBodies];  // parent frame -> body frame at the current q
  Vec6 v[kMaxBodies], a[kMaxBodies], f[kMaxBodies], c[kMaxBodies], pA[kMaxBodies], U[kMaxBodies];
  Mat6 IA[kMaxBodies];         // ABA's articulated inertias
  RigidInertia Ic[kMaxBodies];  // CRBA's composite inertias
  real inv_d[kMaxBodies] = {}, u[kMaxBodies] = {};  // ABA: 1 / (S^T Ia S + rotor), tau - S^T pA
};

/// The largest number of velocity coordinates of a model of capacity N: N + 5 (one floating base
/// adds 5 to its body's one). A forest with several free joints fits when its bodies leave room:
/// num_bodies + 5 x (free joints) <= N + 5, which finish_model checks.
template <int N>
constexpr int max_dofs() {
  return N + 5;
}

/// Numbers the degrees of freedom and checks the model: parents before children, unit axes,
/// positive masses and finite, symmetric positive semi-definite inertias with a positive diagonal,
/// free joints only on bodies hanging from the world (no armature or damping), and no more
/// velocity coordinates than max_dofs<N>(). invalid_argument otherwise (the model is then unusable).
template <int N>
[[nodiscard]] Status finish_model(MultibodyModel<N>& m) {
  if (m.num_bodies < 1 || m.num_bodies > N || !all_finite(m.gravity_w)) return Status::invalid_argument;
  int dof = 0, nq = 0;
  for (int i = 0; i < m.num_bodies; ++i) {
    if (m.parent[i] < -1 || m.parent[i] >= i) return Status::invalid_argument;
    if (m.joint[i] != JointType::revolute && m.joint[i] != JointType::prismatic && m.joint[i] != JointType::fixed &&
        m.joint[i] != JointType::free)
      return Status::invalid_argument;
    if (m.joint[i] == JointType::free && (m.parent[i] != -1 || m.armature[i] != 0 || m.damping[i] != 0 ||
                                         m.has_limit[i] || m.friction_loss[i] != 0 || m.effort_limit[i] != 0))
      return Status::invalid_argument;
    const SpatialInertia& b = m.body[i];
    if (!(b.mass > 0) || !is_finite(b.mass) || !all_finite(b.com) || !all_finite(b.inertia_com) ||
        !all_finite(m.X_tree[i].E) || !all_finite(m.X_tree[i].r))
      return Status::invalid_argument;
    const Mat3& I = b.inertia_com;
    if (!(I(0, 0) > 0 && I(1, 1) > 0 && I(2, 2) > 0) || !(I - I.transpose()).isZero(real(1e-6) * I.trace()))
      return Status::invalid_argument;
    m.elementary_axis[i] = -1;
    m.unit_subspace[i] = -1;
    if (m.joint[i] == JointType::fixed) {
      m.dof_index[i] = m.q_index[i] = -1;
      continue;
    }
    if (m.joint[i] == JointType::free) {
      m.dof_index[i] = dof;
      m.q_index[i] = nq;
      dof += 6;
      nq += 7;
      continue;
    }
    if (!all_finite(m.axis[i]) || std::fabs(m.axis[i].norm() - 1) > real(1e-4)) return Status::invalid_argument;
    if (!(m.armature[i] >= 0) || !is_finite(m.armature[i]) || !(m.damping[i] >= 0) || !is_finite(m.damping[i]))
      return Status::invalid_argument;
    if (!(m.friction_loss[i] >= 0) || !is_finite(m.friction_loss[i]) || !(m.effort_limit[i] >= 0) ||
        !is_finite(m.effort_limit[i]))
      return Status::invalid_argument;
    if (m.has_limit[i] && (!is_finite(m.q_min[i]) || !is_finite(m.q_max[i]) || !(m.q_min[i] <= m.q_max[i])))
      return Status::invalid_argument;
    m.dof_index[i] = dof++;
    m.q_index[i] = nq++;
    for (int k = 0; k < 3; ++k)
      if (m.axis[i] == Vec3::Unit(k)) {
        m.unit_subspace[i] = static_cast<std::int8_t>(m.joint[i] == JointType::revolute ? k : 3 + k);
        if (m.joint[i] == JointType::revolute && m.X_tree[i].E == Mat3::Identity())
          m.elementary_axis[i] = static_cast<std::int8_t>(k);
      }
  }
  if (dof > max_dofs<N>()) return Status::invalid_argument;
  m.num_dofs = dof;
  m.num_q = nq;
  return Status::ok;
}

/// Velocity coordinates of joint i: 0, 1 or 6.
template <int N>
inline int joint_dofs(const MultibodyModel<N>& m, int i) {
  return m.joint[i] == JointType::fixed ? 0 : (m.joint[i] == JointType::free ? 6 : 1);
}

namespace detail {
/// The motion subspace S of a revolute or prismatic joint ([axis; 0], [0; axis]); zero for a fixed
/// joint and for the free joint (whose columns joint_column gives).
template <int N>
inline Vec6 motion_subspace(const MultibodyModel<N>& m, int i) {
  switch (m.joint[i]) {
    case JointType::revolute: return spatial(m.axis[i], Vec3::Zero());
    case JointType::prismatic: return spatial(Vec3::Zero(), m.axis[i]);
    default: return Vec6::Zero();
  }
}

/// X_J(q) and the motion subspace S of joint i (RBDA table 4.1: revolute E = rot(axis, q)^T,
/// prismatic r = axis q).
template <int N>
inline void joint_transform(const MultibodyModel<N>& m, int i, const real* qi, Transform& XJ) {
  const Vec3& a = m.axis[i];
  const real q = qi != nullptr ? qi[0] : real(0);
  XJ = Transform();
  switch (m.joint[i]) {
    case JointType::revolute: {
      const real c = std::cos(q), s = std::sin(q), t = 1 - c;
      Mat3 R;  // rotation by q about a (Rodrigues)
      R << t * a[0] * a[0] + c, t * a[0] * a[1] - s * a[2], t * a[0] * a[2] + s * a[1],  //
          t * a[0] * a[1] + s * a[2], t * a[1] * a[1] + c, t * a[1] * a[2] - s * a[0],   //
          t * a[0] * a[2] - s * a[1], t * a[1] * a[2] + s * a[0], t * a[2] * a[2] + c;
      XJ.E = R.transpose();
      return;
    }
    case JointType::prismatic:
      XJ.r = a * q;
      return;
    case JointType::fixed:
      return;
    case JointType::free: {
      // World -> base: E = R^T with R the quaternion's rotation base -> world; r = the base's
      // position.
      const Quat Q(qi[6], qi[3], qi[4], qi[5]);  // wxyz constructor from [x y z w]
      XJ.E = Q.toRotationMatrix().transpose();
      XJ.r = Vec3(qi[0], qi[1], qi[2]);
      return;
    }
  }
}

/// The spatial component [angular; linear] that the free joint's velocity coordinate c moves.
inline int free_column_component(int c) { return c < 3 ? 3 + c : c - 3; }

/// Column c of joint i's motion subspace (c < joint_dofs): S for a one-dof joint; for the free
/// joint, the base-frame unit motions in the velocity coordinates' order [v; w] (linear first, as
/// Pinocchio), which are spatial [0; e_c] for c < 3 and [e_(c-3); 0] after.
template <int N>
inline Vec6 joint_column(const MultibodyModel<N>& m, int i, int c) {
  if (m.joint[i] != JointType::free) return motion_subspace(m, i);
  Vec6 s = Vec6::Zero();
  s[free_column_component(c)] = 1;
  return s;
}

/// joint_column(m, i, c) . f without forming the column: for the free joint, whose columns are
/// unit vectors, the one component of f it picks (CRBA and RNEA take these dot products for every
/// column of the base against every body's force; forming and summing a six-vector of zeros for
/// each was a fifth of CRBA).
template <int N>
inline real column_dot(const MultibodyModel<N>& m, int i, int c, const Vec6& f) {
  if (m.joint[i] == JointType::free) return f[free_column_component(c)];
  if (m.unit_subspace[i] >= 0) return f[m.unit_subspace[i]];  // S = e_c: the same value as the dot product
  return motion_subspace(m, i).dot(f);
}

/// I S for joint column c of body i (rigid_times(I, joint_column(m, i, c))) without the
/// products by S's zeros where S is a unit vector e_u (a free joint's columns, an axis-aligned
/// joint): I e_u is [Ibar e_u; -h x e_u] for an angular u, [h x e_v; m e_v] for a linear one
/// (v = u - 3), the values rigid_times gives.
template <int N>
inline Vec6 inertia_column(const MultibodyModel<N>& m, int i, int c, const RigidInertia& I) {
  const int u = m.joint[i] == JointType::free ? free_column_component(c) : m.unit_subspace[i];
  if (u < 0) return rigid_times(I, motion_subspace(m, i));
  Vec6 F;
  const Vec3& h = I.h;
  if (u < 3) {
    for (int r = 0; r < 3; ++r) F[r] = I.Ibar(r, u);
    const Vec3 e_x_h(u == 0 ? real(0) : (u == 1 ? h[2] : -h[1]), u == 1 ? real(0) : (u == 0 ? -h[2] : h[0]),
                     u == 2 ? real(0) : (u == 0 ? h[1] : -h[0]));  // e_u x h = -(h x e_u)
    F[3] = e_x_h[0];
    F[4] = e_x_h[1];
    F[5] = e_x_h[2];
  } else {
    const int v = u - 3;
    const Vec3 h_x_e(v == 0 ? real(0) : (v == 1 ? -h[2] : h[1]), v == 1 ? real(0) : (v == 0 ? h[2] : -h[0]),
                     v == 2 ? real(0) : (v == 0 ? -h[1] : h[0]));  // h x e_v
    F[0] = h_x_e[0];
    F[1] = h_x_e[1];
    F[2] = h_x_e[2];
    for (int r = 0; r < 3; ++r) F[3 + r] = r == v ? I.m : real(0);
  }
  return F;
}

/// S qd for joint i's coordinates starting at qd (nullptr or a fixed joint: zero).
template <int N>
inline Vec6 joint_motion(const MultibodyModel<N>& m, int i, const real* v) {
  switch (m.joint[i]) {
    case JointType::fixed: return Vec6::Zero();
    case JointType::free: return spatial(Vec3(v[3], v[4], v[5]), Vec3(v[0], v[1], v[2]));
    default: return motion_subspace(m, i) * v[0];
  }
}

/// Xup of every body at q. An elementary joint's Xup (see rotate_down) is written out with
/// the values joint_transform and compose give it: Rodrigues' terms by the axis's zeros are +0
/// (so 1 - c + c, c, 0 - s and 0 + s remain), the product by X_tree's identity adds exact zeros
/// to them, and r = r_tree + E_tree^T 0 = r_tree + 0.
template <int N>
inline void update_kinematics(const MultibodyModel<N>& m, MultibodyData<N>& d, const real* q) {
  for (int i = 0; i < m.num_bodies; ++i) {
    const int k = m.q_index[i];
    if (m.elementary_axis[i] >= 0) {
      const real qi = q[k], c = std::cos(qi), s = std::sin(qi);
      Transform& X = d.Xup[i];
      with_axis(m.elementary_axis[i], [&](auto K) {
        constexpr int e = decltype(K)::value, i1 = (e + 1) % 3, i2 = (e + 2) % 3;
        X.E(e, e) = (1 - c) + c;
        X.E(e, i1) = X.E(e, i2) = X.E(i1, e) = X.E(i2, e) = 0;
        X.E(i1, i1) = X.E(i2, i2) = c;
        X.E(i1, i2) = real(0) + s;
        X.E(i2, i1) = real(0) - s;
      });
      X.r = m.X_tree[i].r + Vec3::Zero();
      continue;
    }
    Transform XJ;
    joint_transform(m, i, k >= 0 ? q + k : nullptr, XJ);
    d.Xup[i] = compose(XJ, m.X_tree[i]);
  }
}

/// The base's acceleration that stands for gravity (RBDA section 5.3: a_0 = -g).
template <int N>
inline Vec6 base_acceleration(const MultibodyModel<N>& m) {
  return spatial(Vec3::Zero(), -m.gravity_w);
}

/// f(std::integral_constant<int, k>) for k = 0, 1, 2: code for an elementary axis with its indices
/// known at compile time (runtime indices would keep the small arrays in memory).
template <class F>
inline void with_axis(int k, F&& f) {
  switch (k) {
    case 0: f(std::integral_constant<int, 0>{}); return;
    case 1: f(std::integral_constant<int, 1>{}); return;
    default: f(std::integral_constant<int, 2>{}); return;
  }
}

// Body i's Xup rotation E in the products of rnea, crba and the constrained step. Where joint i is
// elementary (elementary_axis[i] = k >= 0: revolute about +x, +y or +z of an unrotated joint
// frame), E is zero outside its (k, k) entry and its 2 x 2 block on the other two axes, exactly:
// update_kinematics' Rodrigues terms there are products by the axis's zeros, and the product by
// X_tree's identity adds only exact zeros. Each component of E w, E^T f or E^T M E is then one
// product or the sum of two, whose value does not depend on the order of the additions: the
// entries are read as stored, so these give Eigen's 3 x 3 products bit for bit (up to the sign of
// an exact zero), with a third of their multiplications. Every other joint takes Eigen's products.

/// E w (kTranspose false) or E^T w (true) for body i's rotation E.
template <bool kTranspose, int N>
inline Vec3 rotate_body(const MultibodyModel<N>& m, int i, const Mat3& E, const Vec3& w) {
  if (m.elementary_axis[i] < 0) {
    if constexpr (kTranspose) return E.transpose() * w;
    else return E * w;
  }
  const auto at = [&E](auto r, auto c) -> real {
    if constexpr (kTranspose) return E(decltype(c)::value, decltype(r)::value);
    else return E(decltype(r)::value, decltype(c)::value);
  };
  using std::integral_constant;
  Vec3 res;
  with_axis(m.elementary_axis[i], [&](auto K) {
    constexpr int e = decltype(K)::value, i1 = (e + 1) % 3, i2 = (e + 2) % 3;
    using Ke = integral_constant<int, e>;
    using K1 = integral_constant<int, i1>;
    using K2 = integral_constant<int, i2>;
    res[e] = at(Ke{}, Ke{}) * w[e];
    res[i1] = at(K1{}, K1{}) * w[i1] + at(K1{}, K2{}) * w[i2];
    res[i2] = at(K2{}, K1{}) * w[i1] + at(K2{}, K2{}) * w[i2];
  });
  return res;
}
template <int N>
inline Vec3 rotate_down(const MultibodyModel<N>& m, int i, const Mat3& E, const Vec3& w) {
  return rotate_body<false>(m, i, E, w);
}
template <int N>
inline Vec3 rotate_up(const MultibodyModel<N>& m, int i, const Mat3& E, const Vec3& f) {
  return rotate_body<true>(m, i, E, f);
}
/// apply_motion(Xup[i], mv): [E w; E (v - r x w)].
template <int N>
inline Vec6 motion_down(const MultibodyModel<N>& m, int i, const Transform& X, const Vec6& mv) {
  const Vec3 w = ang(mv), v = lin(mv);
  return spatial(rotate_down(m, i, X.E, w), rotate_down(m, i, X.E, Vec3(v - X.r.cross(w))));
}
/// apply_force_transpose(Xup[i], f): [E^T n + r x (E^T f); E^T f].
template <int N>
inline Vec6 force_up(const MultibodyModel<N>& m, int i, const Transform& X, const Vec6& f) {
  const Vec3 f_a = rotate_up(m, i, X.E, lin(f));
  return spatial(Vec3(rotate_up(m, i, X.E, ang(f)) + X.r.cross(f_a)), f_a);
}
/// hat(x) hat(y) with each entry written out: y_a x_b off the diagonal, -(x_a1 y_a1 + x_a2 y_a2)
/// on it (a1, a2 the other two axes). Eigen's product of the two skew matrices sums these with
/// exact zeros: the same bits.
inline Mat3 hat_hat(const Vec3& x, const Vec3& y) {
  Mat3 P;
  P(0, 0) = -(x[1] * y[1] + x[2] * y[2]);
  P(1, 1) = -(x[2] * y[2] + x[0] * y[0]);
  P(2, 2) = -(x[0] * y[0] + x[1] * y[1]);
  P(0, 1) = y[0] * x[1];
  P(0, 2) = y[0] * x[2];
  P(1, 0) = y[1] * x[0];
  P(1, 2) = y[1] * x[2];
  P(2, 0) = y[2] * x[0];
  P(2, 1) = y[2] * x[1];
  return P;
}
/// rigid_to_parent(Xup[i], I) (RBDA eq. 2.66), the same bits: E^T Ibar E as (E^T Ibar) E, as
/// Eigen associates it, and the two products of skew matrices by hat_hat.
template <int N>
inline RigidInertia inertia_up(const MultibodyModel<N>& m, int i, const Transform& X, const RigidInertia& I) {
  const Mat3& E = X.E;
  const Vec3 g = rotate_up(m, i, E, I.h);
  RigidInertia o;
  o.m = I.m;
  o.h = g + I.m * X.r;
  Mat3 A;
  if (m.elementary_axis[i] < 0) {
    A = E.transpose() * I.Ibar * E;
  } else {
    with_axis(m.elementary_axis[i], [&](auto K) {
      constexpr int e = decltype(K)::value, i1 = (e + 1) % 3, i2 = (e + 2) % 3;
      Mat3 T;  // E^T Ibar
      for (int l = 0; l < 3; ++l) {
        T(e, l) = E(e, e) * I.Ibar(e, l);
        T(i1, l) = E(i1, i1) * I.Ibar(i1, l) + E(i2, i1) * I.Ibar(i2, l);
        T(i2, l) = E(i1, i2) * I.Ibar(i1, l) + E(i2, i2) * I.Ibar(i2, l);
      }
      for (int a = 0; a < 3; ++a) {  // (E^T Ibar) E
        A(a, e) = T(a, e) * E(e, e);
        A(a, i1) = T(a, i1) * E(i1, i1) + T(a, i2) * E(i2, i1);
        A(a, i2) = T(a, i1) * E(i1, i2) + T(a, i2) * E(i2, i2);
      }
    });
  }
  // Ibar_A = E^T Ibar E - r x (g x) - (h_A x)(r x).
  o.Ibar = A - hat_hat(X.r, g) - hat_hat(o.h, X.r);
  return o;
}

}  // namespace detail

namespace detail {
/// Every floating base's quaternion within 1e-3 of unit length (true without one). Out of line:
/// inlined into a caller whose q holds one fixed-base coordinate, GCC's -Warray-bounds cannot see
/// that the free joint's branch is dead and flags q[1..3].
template <int N>
__attribute__((noinline)) bool base_quaternion_ok(const MultibodyModel<N>& m, const real* q) {
  for (int i = 0; i < m.num_bodies; ++i) {
    if (m.joint[i] != JointType::free) continue;
    const real* qb = q + m.q_index[i] + 3;
    if (!(std::fabs(std::sqrt(qb[0] * qb[0] + qb[1] * qb[1] + qb[2] * qb[2] + qb[3] * qb[3]) - 1) <= real(1e-3)))
      return false;
  }
  return true;
}
}  // namespace detail

/// Inverse dynamics: the joint forces (N m, N) tau[num_dofs] that give the accelerations qdd at
/// (q, qd) under gravity, with an optional external force per body (f_ext[i], body frame, RBDA's
/// [n; f]; nullptr: none). With a floating base, tau's first six entries are the wrench the base
/// needs (zero for a motion the tree can make on its own).
template <int N>
void rnea(const MultibodyModel<N>& m, MultibodyData<N>& d, const real* q, const real* qd, const real* qdd, real* tau,
          const Vec6* f_ext = nullptr);

namespace detail {
/// rnea's two passes over kinematics (Xup) already at q: a caller that has just run crba or
/// forward_kinematics at the same q (step_constrained) skips computing them again.
template <int N>
void rnea_passes(const MultibodyModel<N>& m, MultibodyData<N>& d, const real* qd, const real* qdd, real* tau,
                 const Vec6* f_ext) {
  const Vec6 a0 = detail::base_acceleration(m);
  for (int i = 0; i < m.num_bodies; ++i) {
    const int k = m.dof_index[i], p = m.parent[i];
    const Vec6 vJ = k >= 0 ? detail::joint_motion(m, i, qd + k) : Vec6::Zero();
    const Vec6 vp = p >= 0 ? d.v[p] : Vec6::Zero();
    const Vec6 ap = p >= 0 ? d.a[p] : a0;
    d.v[i] = detail::motion_down(m, i, d.Xup[i], vp) + vJ;
    d.a[i] = detail::motion_down(m, i, d.Xup[i], ap) + cross_motion(d.v[i], vJ);
    if (k >= 0) d.a[i] += detail::joint_motion(m, i, qdd + k);
    d.f[i] = inertia_times(m.body[i], d.a[i]) + cross_force(d.v[i], inertia_times(m.body[i], d.v[i]));
    if (f_ext != nullptr) d.f[i] -= f_ext[i];
  }
  for (int i = m.num_bodies - 1; i >= 0; --i) {
    const int k = m.dof_index[i], p = m.parent[i];
    if (m.joint[i] == JointType::free) {
      for (int c = 0; c < 6; ++c) tau[k + c] = detail::column_dot(m, i, c, d.f[i]);
    } else if (k >= 0) {
      tau[k] = detail::column_dot(m, i, 0, d.f[i]) + m.armature[i] * qdd[k] + m.damping[i] * qd[k];
    }
    if (p >= 0) d.f[p] += detail::force_up(m, i, d.Xup[i], d.f[i]);
  }
}
}  // namespace detail

template <int N>
void rnea(const MultibodyModel<N>& m, MultibodyData<N>& d, const real* q, const real* qd, const real* qdd, real* tau,
          const Vec6* f_ext) {
  detail::update_kinematics(m, d, q);
  detail::rnea_passes(m, d, qd, qdd, tau, f_ext);
}

/// The joint-space mass matrix H (num_dofs x num_dofs, row-major in H[ld * row + col], ld >=
/// num_dofs, every entry written: zero between joints on different branches), symmetric
/// positive definite for a valid model.
template <int N>
void crba(const MultibodyModel<N>& m, MultibodyData<N>& d, const real* q, real* H, int ld);

namespace detail {
/// crba over kinematics (Xup) already at q (see rnea_passes).
template <int N>
void crba_passes(const MultibodyModel<N>& m, MultibodyData<N>& d, real* H, int ld) {
  for (int r = 0; r < m.num_dofs; ++r)
    for (int c = 0; c < m.num_dofs; ++c) H[ld * r + c] = 0;
  // Composite inertias, in their 10-number rigid-body form (RigidInertia: a sum of rigid bodies
  // is one; about 3x fewer operations per body than the 6 x 6 X^T I X).
  for (int i = 0; i < m.num_bodies; ++i) d.Ic[i] = rigid_inertia(m.body[i]);
  for (int i = m.num_bodies - 1; i >= 0; --i)
    if (m.parent[i] >= 0) d.Ic[m.parent[i]] += detail::inertia_up(m, i, d.Xup[i], d.Ic[i]);
  for (int i = 0; i < m.num_bodies; ++i) {
    const int k0 = m.dof_index[i];
    for (int c = 0; c < joint_dofs(m, i); ++c) {  // each of joint i's columns
      const int k = k0 + c;
      Vec6 F = detail::inertia_column(m, i, c, d.Ic[i]);
      for (int c2 = 0; c2 <= c; ++c2)  // the block of joint i itself
        H[ld * k + k0 + c2] = H[ld * (k0 + c2) + k] = detail::column_dot(m, i, c2, F);
      H[ld * k + k] += m.armature[i];
      for (int j = i; m.parent[j] >= 0;) {
        F = detail::force_up(m, j, d.Xup[j], F);
        j = m.parent[j];
        const int kj = m.dof_index[j];
        for (int cj = 0; cj < joint_dofs(m, j); ++cj)
          H[ld * k + kj + cj] = H[ld * (kj + cj) + k] = detail::column_dot(m, j, cj, F);
      }
    }
  }
}
}  // namespace detail

template <int N>
void crba(const MultibodyModel<N>& m, MultibodyData<N>& d, const real* q, real* H, int ld) {
  detail::update_kinematics(m, d, q);
  detail::crba_passes(m, d, H, ld);
}

// Lane values wider than the registers: see lanes.hpp on -Wpsabi.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"
namespace detail {

/// Storage of the batched ABA (MultibodyBatchData): the scalar path's Eigen types' element access,
/// v[k] and M(r, c), over arrays of lane values.
template <class T>
struct LaneVec3 {
  T v[3];
  T& operator[](int k) { return v[k]; }
  const T& operator[](int k) const { return v[k]; }
};
template <class T>
struct LaneVec6 {
  T v[6];
  T& operator[](int k) { return v[k]; }
  const T& operator[](int k) const { return v[k]; }
};
template <class T, int R>
struct LaneMat {
  T m[R * R];
  T& operator()(int r, int c) { return m[R * r + c]; }
  const T& operator()(int r, int c) const { return m[R * r + c]; }
};
template <class T>
struct LaneTransform {
  LaneMat<T, 3> E;
  LaneVec3<T> r;
};

/// Forward dynamics over any lane type T (real: one robot; Lanes<L>: L robots of one model),
/// Featherstone's articulated-body algorithm (RBDA table 7.1) with every spatial product written
/// out in 3 x 3 blocks:
///  - an articulated inertia is kept as its blocks [A B; B^T C] (A, C symmetric; the lower-left
///    block is never stored) and carried to the parent as X^T I X = [1 r x; 0 1] (E^T I E)
///    [1 0; -r x 1] (RBDA eq. 2.24's factors): three 3 x 3 congruences by E, then three products
///    with the skew matrix r x, about 200 multiplications where the dense 6 x 6 form takes 864;
///  - a revolute (prismatic) joint's U = I S takes the three angular (linear) columns of I
///    against the axis;
///  - the free joint's 6 x 6 solve is an LDL^T factorisation written out (the same operations
///    in every lane, where Eigen's LDLT would differ between a scalar and a vector type; no
///    square roots), and pass 3 multiplies by each joint's 1 / d from pass 2;
///  - a revolute joint about +x, +y or +z of an unrotated joint frame (elementary_axis) takes its
///    rotation as the elementary one it is: a 2 x 2 block in each product, and a symmetric block's
///    congruence by the double angle; its c has no k components, which Ia c skips;
///  - a joint's sine and cosine come from the kernel's sin_cos: in float the same bits on the host
///    and the MCUs (libm's sinf and cosf differ between glibc and newlib).
/// Every loop of a fixed small trip count carries `#pragma GCC unroll 8`: GCC 12 left the nested
/// and triangular ones rolled (a switch on the index inside RM and MR ran as a branch). The
/// rotations are lambdas forced inline (GCC had made them calls), and the working vectors live in
/// locals that stores through d cannot alias. With the unrolling alone the 18-dof floating-base
/// call fell from 1.16 to 1.01 us in double, with the locals to 0.94 us (1.33 us before stop 44;
/// bench/dynamics/run.sh; instructions per call 23,000 -> 19,000 under callgrind).
/// D is MultibodyData (T = real) or MultibodyBatchData (lanes); F the external-force vectors
/// (nullptr: none). q, qd, tau: the coordinates, lane values; out[num_dofs] receives qdd. The
/// inputs are checked by the callers. Returns the lanes (bit l) whose articulated inertia was
/// singular or whose accelerations are not finite; their `out` lanes are then meaningless.
template <class T, int N, class D, class F>
unsigned aba_kernel(const MultibodyModel<N>& m, D& d, const T* q, const T* qd, const T* tau, T* out, const F* f_ext,
                    real implicit_damping_dt) {
  using lanes::splat;
  unsigned bad = 0;
  // out = E w and out = E^T f for body i's Xup rotation E: general, or the elementary rotation
  // about axis k = elementary_axis[i] (E's c = E(i1, i1), s = E(i1, i2); see finish_model).
  const auto rotate = [](const auto& E, int k, const T* w, T* res) __attribute__((always_inline)) {
    if (k >= 0) {
      with_axis(k, [&](auto K) {
        constexpr int e = decltype(K)::value, i1 = (e + 1) % 3, i2 = (e + 2) % 3;
        const T c = E(i1, i1), s = E(i1, i2);
        res[e] = w[e];
        res[i1] = c * w[i1] + s * w[i2];
        res[i2] = c * w[i2] - s * w[i1];
      });
      return;
    }
    #pragma GCC unroll 8
    for (int r = 0; r < 3; ++r) res[r] = (E(r, 0) * w[0] + E(r, 1) * w[1]) + E(r, 2) * w[2];
  };
  const auto rotate_t = [](const auto& E, int k, const T* f, T* res) __attribute__((always_inline)) {
    if (k >= 0) {
      with_axis(k, [&](auto K) {
        constexpr int e = decltype(K)::value, i1 = (e + 1) % 3, i2 = (e + 2) % 3;
        const T c = E(i1, i1), s = E(i1, i2);
        res[e] = f[e];
        res[i1] = c * f[i1] - s * f[i2];
        res[i2] = s * f[i1] + c * f[i2];
      });
      return;
    }
    #pragma GCC unroll 8
    for (int r = 0; r < 3; ++r) res[r] = (E(0, r) * f[0] + E(1, r) * f[1]) + E(2, r) * f[2];
  };
  // Pass 1, base to tips: Xup = X_J(q) X_tree, velocities, velocity-product accelerations c,
  // the bodies' own inertias and bias forces.
  for (int i = 0; i < m.num_bodies; ++i) {
    const int k = m.dof_index[i], kq = m.q_index[i], p = m.parent[i];
    const Transform& Xt = m.X_tree[i];
    const Vec3& ax = m.axis[i];
    auto& X = d.Xup[i];
    T v[6], c[6];  // locals, stored at the end: stores through d could alias what is read next
    T vJ[6] = {};
    switch (m.joint[i]) {
      case JointType::revolute: {
        // E = R(q)^T E_tree, R the rotation by q about the axis (Rodrigues); r = r_tree.
        T co, si;
        lanes::sin_cos(q[kq], si, co);
        const int ek = m.elementary_axis[i];
        if (ek >= 0) {
          // About +x, +y or +z with E_tree = 1: E = R^T has c, s at (i1, i1), (i1, i2), (i2, i1), (i2, i2).
          with_axis(ek, [&](auto K) {
            constexpr int e = decltype(K)::value, i1 = (e + 1) % 3, i2 = (e + 2) % 3;
            #pragma GCC unroll 8
            for (int r = 0; r < 3; ++r) {
              #pragma GCC unroll 8
              for (int cc = 0; cc < 3; ++cc) X.E(r, cc) = T{};
              X.r[r] = splat<T>(Xt.r[r]);
            }
            X.E(e, e) = splat<T>(1);
            X.E(i1, i1) = co;
            X.E(i1, i2) = si;
            X.E(i2, i1) = -si;
            X.E(i2, i2) = co;
            vJ[e] = qd[k];
          });
          break;
        }
        const T t = splat<T>(1) - co;
        const real xx = ax[0] * ax[0], yy = ax[1] * ax[1], zz = ax[2] * ax[2];
        const real xy = ax[0] * ax[1], xz = ax[0] * ax[2], yz = ax[1] * ax[2];
        const T sx = si * ax[0], sy = si * ax[1], sz = si * ax[2];
        T R[3][3];
        R[0][0] = t * xx + co;
        R[0][1] = t * xy - sz;
        R[0][2] = t * xz + sy;
        R[1][0] = t * xy + sz;
        R[1][1] = t * yy + co;
        R[1][2] = t * yz - sx;
        R[2][0] = t * xz - sy;
        R[2][1] = t * yz + sx;
        R[2][2] = t * zz + co;
        #pragma GCC unroll 8
        for (int r = 0; r < 3; ++r)
          #pragma GCC unroll 8
          for (int cc = 0; cc < 3; ++cc) X.E(r, cc) = R[0][r] * Xt.E(0, cc) + R[1][r] * Xt.E(1, cc) + R[2][r] * Xt.E(2, cc);
        #pragma GCC unroll 8
        for (int r = 0; r < 3; ++r) X.r[r] = splat<T>(Xt.r[r]);
        #pragma GCC unroll 8
        for (int a = 0; a < 3; ++a) vJ[a] = qd[k] * ax[a];
        break;
      }
      case JointType::prismatic: {
        // E = E_tree; r = r_tree + E_tree^T (axis q).
        const Vec3 g = Xt.E.transpose() * ax;
        #pragma GCC unroll 8
        for (int r = 0; r < 3; ++r) {
          #pragma GCC unroll 8
          for (int cc = 0; cc < 3; ++cc) X.E(r, cc) = splat<T>(Xt.E(r, cc));
          X.r[r] = Xt.r[r] + g[r] * q[kq];
        }
        #pragma GCC unroll 8
        for (int a = 0; a < 3; ++a) vJ[3 + a] = qd[k] * ax[a];
        break;
      }
      case JointType::fixed:
        #pragma GCC unroll 8
        for (int r = 0; r < 3; ++r) {
          #pragma GCC unroll 8
          for (int cc = 0; cc < 3; ++cc) X.E(r, cc) = splat<T>(Xt.E(r, cc));
          X.r[r] = splat<T>(Xt.r[r]);
        }
        break;  // vJ = 0
      case JointType::free: {
        // X_J: E = R(Q)^T (Q base -> world, [x y z w]), r = the base's position; then X_tree.
        const T x = q[kq + 3], y = q[kq + 4], z = q[kq + 5], w = q[kq + 6];
        const T tx = x + x, ty = y + y, tz = z + z;
        const T one = splat<T>(1);
        T R[3][3];
        R[0][0] = one - (ty * y + tz * z);
        R[0][1] = tx * y - tz * w;
        R[0][2] = tx * z + ty * w;
        R[1][0] = tx * y + tz * w;
        R[1][1] = one - (tx * x + tz * z);
        R[1][2] = ty * z - tx * w;
        R[2][0] = tx * z - ty * w;
        R[2][1] = ty * z + tx * w;
        R[2][2] = one - (tx * x + ty * y);
        #pragma GCC unroll 8
        for (int r = 0; r < 3; ++r) {
          #pragma GCC unroll 8
          for (int cc = 0; cc < 3; ++cc) X.E(r, cc) = R[0][r] * Xt.E(0, cc) + R[1][r] * Xt.E(1, cc) + R[2][r] * Xt.E(2, cc);
          X.r[r] = Xt.r[r] + (Xt.E(0, r) * q[kq] + Xt.E(1, r) * q[kq + 1] + Xt.E(2, r) * q[kq + 2]);
        }
        #pragma GCC unroll 8
        for (int a = 0; a < 3; ++a) {
          vJ[a] = qd[k + 3 + a];
          vJ[3 + a] = qd[k + a];
        }
        break;
      }
    }
    // v = Xup v_parent + vJ (apply_motion: [E w; E (v - r x w)]); c = v x vJ (crm).
    if (p >= 0) {
      const auto& vp = d.v[p];
      const T wp[3] = {vp[0], vp[1], vp[2]};
      const T lw[3] = {vp[3] - (X.r[1] * vp[2] - X.r[2] * vp[1]), vp[4] - (X.r[2] * vp[0] - X.r[0] * vp[2]),
                       vp[5] - (X.r[0] * vp[1] - X.r[1] * vp[0])};
      T ew[3], el[3];
      rotate(X.E, m.elementary_axis[i], wp, ew);
      rotate(X.E, m.elementary_axis[i], lw, el);
      #pragma GCC unroll 8
      for (int r = 0; r < 3; ++r) {
        v[r] = ew[r] + vJ[r];
        v[3 + r] = el[r] + vJ[3 + r];
      }
    } else {
      #pragma GCC unroll 8
      for (int r = 0; r < 6; ++r) v[r] = vJ[r];
    }
    if (m.elementary_axis[i] >= 0) {
      // vJ = [qd e_k; 0]: c = [w x e_k; v x e_k] qd, whose k components are zero.
      with_axis(m.elementary_axis[i], [&](auto K) {
        constexpr int e = decltype(K)::value, i1 = (e + 1) % 3, i2 = (e + 2) % 3;
        const T w = vJ[e];
        c[e] = T{};
        c[i1] = v[i2] * w;
        c[i2] = -(v[i1] * w);
        c[3 + e] = T{};
        c[3 + i1] = v[3 + i2] * w;
        c[3 + i2] = -(v[3 + i1] * w);
      });
    } else {
      #pragma GCC unroll 8
      for (int r = 0; r < 3; ++r) {
        const int r1 = (r + 1) % 3, r2 = (r + 2) % 3;
        c[r] = v[r1] * vJ[r2] - v[r2] * vJ[r1];
        c[3 + r] = (v[r1] * vJ[3 + r2] - v[r2] * vJ[3 + r1]) + (v[3 + r1] * vJ[r2] - v[3 + r2] * vJ[r1]);
      }
    }
    #pragma GCC unroll 8
    for (int r = 0; r < 6; ++r) {
      d.v[i][r] = v[r];
      d.c[i][r] = c[r];
    }
    // The body's inertia at its origin as blocks [Ibar, h x; h x^T, m 1] (RBDA eq. 2.63; rigid_inertia's
    // numbers, written out: calling rigid_inertia here made GCC stop inlining it on the MCUs, +12 %
    // instructions for ABA and +4 % for CRBA on the M4F): Ibar = Ic + m (|c|^2 1 - c c^T), h = m c.
    // The body's numbers in locals first (the stores to I could alias them).
    const SpatialInertia& b = m.body[i];
    const real mass = b.mass;
    const real com[3] = {b.com[0], b.com[1], b.com[2]};
    real Ic[3][3];
    #pragma GCC unroll 8
    for (int r = 0; r < 3; ++r)
      #pragma GCC unroll 8
      for (int cc = 0; cc < 3; ++cc) Ic[r][cc] = b.inertia_com(r, cc);
    const real cc2 = (com[0] * com[0] + com[1] * com[1]) + com[2] * com[2];  // Eigen's dot's order
    auto& I = d.IA[i];
    #pragma GCC unroll 8
    for (int r = 0; r < 3; ++r)
      #pragma GCC unroll 8
      for (int cc = 0; cc < 3; ++cc) {
        I(r, cc) = splat<T>(Ic[r][cc] + mass * ((r == cc ? cc2 : real(0)) - com[r] * com[cc]));
        I(3 + r, 3 + cc) = splat<T>(r == cc ? mass : real(0));
      }
    const real h[3] = {mass * com[0], mass * com[1], mass * com[2]};
    I(0, 3) = splat<T>(0), I(1, 4) = splat<T>(0), I(2, 5) = splat<T>(0);
    I(0, 4) = splat<T>(-h[2]), I(0, 5) = splat<T>(h[1]);
    I(1, 3) = splat<T>(h[2]), I(1, 5) = splat<T>(-h[0]);
    I(2, 3) = splat<T>(-h[1]), I(2, 4) = splat<T>(h[0]);
    // pA = v x* (I v) - f_ext, with I v = [Ic w + c x f; f], f = m (v_lin - c x w) (inertia_times).
    T f[3], n[3];
    #pragma GCC unroll 8
    for (int r = 0; r < 3; ++r) {
      const int r1 = (r + 1) % 3, r2 = (r + 2) % 3;
      f[r] = mass * (v[3 + r] - (com[r1] * v[r2] - com[r2] * v[r1]));
    }
    #pragma GCC unroll 8
    for (int r = 0; r < 3; ++r) {
      const int r1 = (r + 1) % 3, r2 = (r + 2) % 3;
      n[r] = (Ic[r][0] * v[0] + Ic[r][1] * v[1] + Ic[r][2] * v[2]) +
             (com[r1] * f[r2] - com[r2] * f[r1]);
    }
    T pA[6];
    #pragma GCC unroll 8
    for (int r = 0; r < 3; ++r) {
      const int r1 = (r + 1) % 3, r2 = (r + 2) % 3;
      pA[r] = (v[r1] * n[r2] - v[r2] * n[r1]) + (v[3 + r1] * f[r2] - v[3 + r2] * f[r1]);
      pA[3 + r] = v[r1] * f[r2] - v[r2] * f[r1];
    }
    if (f_ext != nullptr)
      #pragma GCC unroll 8
      for (int r = 0; r < 6; ++r) pA[r] = pA[r] - f_ext[i][r];
    #pragma GCC unroll 8
    for (int r = 0; r < 6; ++r) d.pA[i][r] = pA[r];
  }
  // Pass 2, tips to base: articulated inertias and bias forces, each carried to the parent.
  for (int i = m.num_bodies - 1; i >= 0; --i) {
    const int k = m.dof_index[i], p = m.parent[i];
    if (m.joint[i] == JointType::free) continue;  // the root: solved in pass 3
    // I is updated in place; U, c and pA are worked on in locals, which the stores to I cannot
    // alias (through d they could, and every store made the compiler load them again).
    auto& I = d.IA[i];
    T pA[6], c[6], pa[6];
    #pragma GCC unroll 8
    for (int r = 0; r < 6; ++r) {
      pA[r] = d.pA[i][r];
      c[r] = d.c[i][r];
    }
    if (k >= 0) {
      // U = I S, d = S^T U (+ armature + h damping), u = tau - damping qd - S^T pA; then
      // Ia = I - U U^T / d and pa = pA + Ia c + U u / d.
      const Vec3& ax = m.axis[i];
      const int o = m.joint[i] == JointType::revolute ? 0 : 3;  // S's nonzero half
      T U[6];
      const int ek = m.elementary_axis[i];
      const real rotor = m.armature[i] + implicit_damping_dt * m.damping[i];
      T dd;
      if (ek >= 0) {
        // S = [e_k; 0]: U is I's column k (its lower half from the stored B: B^T's column k is B's row k).
        with_axis(ek, [&](auto K) {
          constexpr int e = decltype(K)::value;
          #pragma GCC unroll 8
          for (int r = 0; r < 3; ++r) {
            U[r] = I(r, e);
            U[3 + r] = I(e, 3 + r);
          }
          dd = U[e] + rotor;
          d.u[i] = (tau[k] - m.damping[i] * qd[k]) - pA[e];
        });
      } else {
        #pragma GCC unroll 8
        for (int r = 0; r < 6; ++r) {
          // Row r of I against the axis; I's lower-left block is B^T (never stored).
          const auto e = [&](int cc) -> T { return (r < 3 || o == 3) ? I(r, o + cc) : I(o + cc, r); };
          U[r] = (e(0) * ax[0] + e(1) * ax[1]) + e(2) * ax[2];
        }
        dd = (ax[0] * U[o] + ax[1] * U[o + 1]) + ax[2] * U[o + 2] + rotor;
        d.u[i] = (tau[k] - m.damping[i] * qd[k]) - ((ax[0] * pA[o] + ax[1] * pA[o + 1]) + ax[2] * pA[o + 2]);
      }
      bad |= lanes::not_positive(dd);
      const T inv_d = splat<T>(1) / dd;
      d.inv_d[i] = inv_d;  // pass 3 multiplies by it: no division on its base-to-tips chain
      T Ud[6];
      #pragma GCC unroll 8
      for (int r = 0; r < 6; ++r) Ud[r] = U[r] * inv_d;
      // The three stored blocks, A and C by their upper triangles.
      #pragma GCC unroll 8
      for (int r = 0; r < 3; ++r)
        #pragma GCC unroll 8
        for (int cc = r; cc < 3; ++cc) {
          I(r, cc) = I(r, cc) - U[r] * Ud[cc];
          I(3 + r, 3 + cc) = I(3 + r, 3 + cc) - U[3 + r] * Ud[3 + cc];
        }
      #pragma GCC unroll 8
      for (int r = 0; r < 3; ++r)
        #pragma GCC unroll 8
        for (int cc = 0; cc < 3; ++cc) I(r, 3 + cc) = I(r, 3 + cc) - U[r] * Ud[3 + cc];
      #pragma GCC unroll 8
      for (int r = 1; r < 3; ++r)
        #pragma GCC unroll 8
        for (int cc = 0; cc < r; ++cc) {
          I(r, cc) = I(cc, r);
          I(3 + r, 3 + cc) = I(3 + cc, 3 + r);
        }
      const T ud = d.u[i] * inv_d;
      if (ek >= 0) {
        // c = v x [qd e_k; 0] has zero k components (pass 1): Ia c over the other four.
        with_axis(ek, [&](auto K) {
          constexpr int e = decltype(K)::value, i1 = (e + 1) % 3, i2 = (e + 2) % 3;
          #pragma GCC unroll 8
          for (int r = 0; r < 3; ++r) {
            pa[r] = pA[r] + ((I(r, i1) * c[i1] + I(r, i2) * c[i2]) + (I(r, 3 + i1) * c[3 + i1] + I(r, 3 + i2) * c[3 + i2])) +
                    U[r] * ud;
            pa[3 + r] = pA[3 + r] +
                        ((I(i1, 3 + r) * c[i1] + I(i2, 3 + r) * c[i2]) +
                         (I(3 + r, 3 + i1) * c[3 + i1] + I(3 + r, 3 + i2) * c[3 + i2])) +
                        U[3 + r] * ud;
          }
        });
      } else {
        #pragma GCC unroll 8
        for (int r = 0; r < 3; ++r) {
          pa[r] = pA[r] + ((I(r, 0) * c[0] + I(r, 1) * c[1] + I(r, 2) * c[2]) + (I(r, 3) * c[3] + I(r, 4) * c[4] + I(r, 5) * c[5])) +
                  U[r] * ud;
          pa[3 + r] = pA[3 + r] +
                      ((I(0, 3 + r) * c[0] + I(1, 3 + r) * c[1] + I(2, 3 + r) * c[2]) +
                       (I(3 + r, 3) * c[3] + I(3 + r, 4) * c[4] + I(3 + r, 5) * c[5])) +
                      U[3 + r] * ud;
        }
      }
      #pragma GCC unroll 8
      for (int r = 0; r < 6; ++r) d.U[i][r] = U[r];  // for pass 3
    } else {
      // A fixed joint: vJ = 0, so c = 0 and pa = pA.
      #pragma GCC unroll 8
      for (int r = 0; r < 6; ++r) pa[r] = pA[r];
    }
    if (p < 0) continue;
    const auto& X = d.Xup[i];
    // X^T Ia X: first the congruences by E (A1 = E^T A E, B1 = E^T B E, C1 = E^T C E) ...
    T A1[3][3], B1[3][3], C1[3][3];
    const int ek = m.elementary_axis[i];
    if (ek >= 0) {
      // E the elementary rotation about axis k: M E mixes columns i1, i2 of M and E^T (M E) its
      // rows i1, i2; the rest passes through.
      with_axis(ek, [&](auto K) {
        constexpr int e = decltype(K)::value, i1 = (e + 1) % 3, i2 = (e + 2) % 3;
        const T co = X.E(i1, i1), si = X.E(i1, i2);
        const auto congruence = [&](int r0, int c0, T res[3][3]) {
          T Q[3][3];
          #pragma GCC unroll 8
          for (int r = 0; r < 3; ++r) {
            Q[r][e] = I(r0 + r, c0 + e);
            Q[r][i1] = I(r0 + r, c0 + i1) * co - I(r0 + r, c0 + i2) * si;
            Q[r][i2] = I(r0 + r, c0 + i1) * si + I(r0 + r, c0 + i2) * co;
          }
          #pragma GCC unroll 8
          for (int cc = 0; cc < 3; ++cc) {
            res[e][cc] = Q[e][cc];
            res[i1][cc] = co * Q[i1][cc] - si * Q[i2][cc];
            res[i2][cc] = si * Q[i1][cc] + co * Q[i2][cc];
          }
        };
        // A symmetric block M (A or C): row e rotates as a vector; the (i1, i2) block
        // [a b; b d] -> R^T [a b; b d] R by the double angle (cos 2q = co^2 - si^2, sin 2q =
        // 2 si co): with h = (a + d) / 2, g = (a - d) / 2 and t = g cos 2q - b sin 2q, a' = h + t,
        // d' = h - t, b' = g sin 2q + b cos 2q. 10 multiplications where the product above takes 24.
        const T c2 = co * co - si * si, s2 = splat<T>(2) * (si * co);
        const auto symmetric = [&](int r0, T res[3][3]) {
          const T me1 = I(r0 + e, r0 + i1), me2 = I(r0 + e, r0 + i2);
          const T a = I(r0 + i1, r0 + i1), b = I(r0 + i1, r0 + i2), dd = I(r0 + i2, r0 + i2);
          const T h = splat<T>(0.5) * (a + dd), g = splat<T>(0.5) * (a - dd);
          const T t = g * c2 - b * s2;
          res[e][e] = I(r0 + e, r0 + e);
          res[e][i1] = res[i1][e] = me1 * co - me2 * si;
          res[e][i2] = res[i2][e] = me1 * si + me2 * co;
          res[i1][i1] = h + t;
          res[i2][i2] = h - t;
          res[i1][i2] = res[i2][i1] = g * s2 + b * c2;
        };
        symmetric(0, A1);
        congruence(0, 3, B1);
        symmetric(3, C1);
      });
    } else {
      T PA[3][3], PB[3][3], PC[3][3];  // A E, B E, C E
      #pragma GCC unroll 8
      for (int r = 0; r < 3; ++r)
        #pragma GCC unroll 8
        for (int cc = 0; cc < 3; ++cc) {
          PA[r][cc] = (I(r, 0) * X.E(0, cc) + I(r, 1) * X.E(1, cc)) + I(r, 2) * X.E(2, cc);
          PB[r][cc] = (I(r, 3) * X.E(0, cc) + I(r, 4) * X.E(1, cc)) + I(r, 5) * X.E(2, cc);
          PC[r][cc] = (I(3 + r, 3) * X.E(0, cc) + I(3 + r, 4) * X.E(1, cc)) + I(3 + r, 5) * X.E(2, cc);
        }
      #pragma GCC unroll 8
      for (int r = 0; r < 3; ++r) {
        #pragma GCC unroll 8
        for (int cc = r; cc < 3; ++cc) {
          A1[r][cc] = (X.E(0, r) * PA[0][cc] + X.E(1, r) * PA[1][cc]) + X.E(2, r) * PA[2][cc];
          C1[r][cc] = (X.E(0, r) * PC[0][cc] + X.E(1, r) * PC[1][cc]) + X.E(2, r) * PC[2][cc];
        }
        #pragma GCC unroll 8
        for (int cc = 0; cc < 3; ++cc) B1[r][cc] = (X.E(0, r) * PB[0][cc] + X.E(1, r) * PB[1][cc]) + X.E(2, r) * PB[2][cc];
      }
      #pragma GCC unroll 8
      for (int r = 1; r < 3; ++r)
        #pragma GCC unroll 8
        for (int cc = 0; cc < r; ++cc) {
          A1[r][cc] = A1[cc][r];
          C1[r][cc] = C1[cc][r];
        }
    }
    // ... then the translation: B2 = B1 + R C1, A2 = A1 + R B1^T - B2 R with R = r x.
    const T rx = X.r[0], ry = X.r[1], rz = X.r[2];
    // (R M)[r][cc] for M given by a row accessor; (M R)[r][cc] likewise.
    const auto RM = [&](const auto& M, int r, int cc) -> T {
      switch (r) {
        case 0: return rz * -M(1, cc) + ry * M(2, cc);
        case 1: return rz * M(0, cc) - rx * M(2, cc);
        default: return ry * -M(0, cc) + rx * M(1, cc);
      }
    };
    const auto MR = [&](const auto& M, int r, int cc) -> T {
      switch (cc) {
        case 0: return M(r, 1) * rz - M(r, 2) * ry;
        case 1: return M(r, 2) * rx - M(r, 0) * rz;
        default: return M(r, 0) * ry - M(r, 1) * rx;
      }
    };
    const auto c1 = [&](int r, int cc) -> const T& { return C1[r][cc]; };
    const auto b1t = [&](int r, int cc) -> const T& { return B1[cc][r]; };
    T B2[3][3];
    #pragma GCC unroll 8
    for (int r = 0; r < 3; ++r)
      #pragma GCC unroll 8
      for (int cc = 0; cc < 3; ++cc) B2[r][cc] = B1[r][cc] + RM(c1, r, cc);
    const auto b2 = [&](int r, int cc) -> const T& { return B2[r][cc]; };
    auto& Ip = d.IA[p];
    #pragma GCC unroll 8
    for (int r = 0; r < 3; ++r) {
      #pragma GCC unroll 8
      for (int cc = r; cc < 3; ++cc) {
        Ip(r, cc) = Ip(r, cc) + ((A1[r][cc] + RM(b1t, r, cc)) - MR(b2, r, cc));
        Ip(3 + r, 3 + cc) = Ip(3 + r, 3 + cc) + C1[r][cc];
      }
      #pragma GCC unroll 8
      for (int cc = 0; cc < 3; ++cc) Ip(r, 3 + cc) = Ip(r, 3 + cc) + B2[r][cc];
    }
    #pragma GCC unroll 8
    for (int r = 1; r < 3; ++r)
      #pragma GCC unroll 8
      for (int cc = 0; cc < r; ++cc) {
        Ip(r, cc) = Ip(cc, r);
        Ip(3 + r, 3 + cc) = Ip(3 + cc, 3 + r);
      }
    // pA_parent += X^T pa = [E^T n + r x (E^T f); E^T f].
    auto& pp = d.pA[p];
    T fa[3], na[3];
    rotate_t(X.E, ek, pa + 3, fa);
    rotate_t(X.E, ek, pa, na);
    #pragma GCC unroll 8
    for (int r = 0; r < 3; ++r) {
      const int r1 = (r + 1) % 3, r2 = (r + 2) % 3;
      pp[r] = pp[r] + (na[r] + (X.r[r1] * fa[r2] - X.r[r2] * fa[r1]));
      pp[3 + r] = pp[3 + r] + fa[r];
    }
  }
  // Pass 3, base to tips: accelerations. a_0 = -g (RBDA section 5.3).
  for (int i = 0; i < m.num_bodies; ++i) {
    const int k = m.dof_index[i], p = m.parent[i];
    const auto& X = d.Xup[i];
    auto& a = d.a[i];
    const auto& c = d.c[i];
    T ap[6];
    if (p >= 0) {
      #pragma GCC unroll 8
      for (int r = 0; r < 6; ++r) ap[r] = d.a[p][r];
    } else {
      #pragma GCC unroll 8
      for (int r = 0; r < 3; ++r) {
        ap[r] = T{};
        ap[3 + r] = splat<T>(-m.gravity_w[r]);
      }
    }
    const T lw[3] = {ap[3] - (X.r[1] * ap[2] - X.r[2] * ap[1]), ap[4] - (X.r[2] * ap[0] - X.r[0] * ap[2]),
                     ap[5] - (X.r[0] * ap[1] - X.r[1] * ap[0])};
    T ew[3], el[3];
    const int ek = m.elementary_axis[i];
    rotate(X.E, ek, ap, ew);
    rotate(X.E, ek, lw, el);
    #pragma GCC unroll 8
    for (int r = 0; r < 3; ++r) {
      a[r] = ew[r] + c[r];
      a[3 + r] = el[r] + c[3 + r];
    }
    if (m.joint[i] == JointType::free) {
      // A six-dof joint to the world (RBDA section 9.3): the whole tree's articulated inertia IA
      // at the base takes the base wrench, so the joint's spatial acceleration y solves
      // IA y = tau_s - pA - IA a, tau_s the wrench in spatial order [moment; force].
      const auto& I = d.IA[i];
      const auto M = [&](int r, int cc) -> T { return (r >= 3 && cc < 3) ? I(cc, r) : (r <= cc || r >= 3 ? I(r, cc) : I(cc, r)); };
      T rhs[6];
      #pragma GCC unroll 8
      for (int r = 0; r < 6; ++r) {
        const T ts = r < 3 ? tau[k + 3 + r] : tau[k + r - 3];
        T Ia = M(r, 0) * a[0];
        #pragma GCC unroll 8
        for (int cc = 1; cc < 6; ++cc) Ia = Ia + M(r, cc) * a[cc];
        rhs[r] = (ts - d.pA[i][r]) - Ia;
      }
      // IA = L D L^T, L unit lower triangular, with W[r][j] = L[r][j] D[j] kept: the Cholesky
      // factor's six square roots, each on this serial chain, are not needed.
      T L[6][6], W[6][6];
      T inv_D[6];
      #pragma GCC unroll 8
      for (int j = 0; j < 6; ++j) {
        T s = M(j, j);
        #pragma GCC unroll 8
        for (int t = 0; t < j; ++t) s = s - L[j][t] * W[j][t];
        bad |= lanes::not_positive(s);
        inv_D[j] = splat<T>(1) / s;
        #pragma GCC unroll 8
        for (int r = j + 1; r < 6; ++r) {
          T e = M(r, j);
          #pragma GCC unroll 8
          for (int t = 0; t < j; ++t) e = e - L[r][t] * W[j][t];
          W[r][j] = e;
          L[r][j] = e * inv_D[j];
        }
      }
      T y[6];
      #pragma GCC unroll 8
      for (int r = 0; r < 6; ++r) {  // L z = rhs
        T e = rhs[r];
        #pragma GCC unroll 8
        for (int t = 0; t < r; ++t) e = e - L[r][t] * y[t];
        y[r] = e;
      }
      #pragma GCC unroll 8
      for (int r = 0; r < 6; ++r) y[r] = y[r] * inv_D[r];  // D w = z
      #pragma GCC unroll 8
      for (int r = 5; r >= 0; --r) {  // L^T y = w
        T e = y[r];
        #pragma GCC unroll 8
        for (int t = r + 1; t < 6; ++t) e = e - L[t][r] * y[t];
        y[r] = e;
      }
      #pragma GCC unroll 8
      for (int r = 0; r < 6; ++r) a[r] = a[r] + y[r];
      #pragma GCC unroll 8
      for (int cc = 0; cc < 3; ++cc) {
        out[k + cc] = y[3 + cc];  // linear first, as the velocity coordinates
        out[k + 3 + cc] = y[cc];
      }
      continue;
    }
    if (k < 0) continue;
    const auto& U = d.U[i];
    T Ua = U[0] * a[0];
    #pragma GCC unroll 8
    for (int r = 1; r < 6; ++r) Ua = Ua + U[r] * a[r];
    const T qdd = (d.u[i] - Ua) * d.inv_d[i];
    out[k] = qdd;
    if (ek >= 0) {
      a[ek] = a[ek] + qdd;
      continue;
    }
    const int o = m.joint[i] == JointType::revolute ? 0 : 3;
    #pragma GCC unroll 8
    for (int r = 0; r < 3; ++r) a[o + r] = a[o + r] + m.axis[i][r] * qdd;
  }
  for (int k = 0; k < m.num_dofs; ++k) bad |= lanes::not_finite(out[k]);
  return bad;
}

/// Bit l set where lane l's inputs are unusable for aba: a non-finite coordinate, or a base
/// quaternion off unit length by more than 1e-3.
template <class T, int N>
unsigned aba_input_check(const MultibodyModel<N>& m, const T* q, const T* qd, const T* tau) {
  unsigned bad = 0;
  for (int k = 0; k < m.num_q; ++k) bad |= lanes::not_finite(q[k]);
  for (int k = 0; k < m.num_dofs; ++k) bad |= lanes::not_finite(qd[k]) | lanes::not_finite(tau[k]);
  for (int i = 0; i < m.num_bodies; ++i) {
    if (m.joint[i] != JointType::free) continue;
    const T* qb = q + m.q_index[i] + 3;
    const T len = lanes::sqrt(qb[0] * qb[0] + qb[1] * qb[1] + qb[2] * qb[2] + qb[3] * qb[3]) - real(1);
    bad |= lanes::failing(len, [](real e) { return std::fabs(e) <= real(1e-3); });
  }
  return bad;
}

}  // namespace detail

/// Forward dynamics: the accelerations qdd[num_dofs] under the joint forces tau at (q, qd), with
/// optional external forces as rnea (with a floating base, tau's first six entries are a wrench
/// on the base, usually zero). Status::ok; non_finite_input (qdd untouched) for a non-finite
/// input, a base quaternion off unit length by more than 1e-3, or a singular articulated inertia
/// (a joint with no inertia behind it). Leaves Xup, v, c, a at (q, qd) in d.
///
/// implicit_damping_dt h > 0 solves (M + h D) qdd = tau - bias - D qd instead, D the joints'
/// viscous damping: the accelerations of a step of length h with the damping taken at the end of
/// the step (MuJoCo's implicit damping), which step_semi_implicit uses. In ABA it is the joint's
/// armature plus h times its damping.
template <int N>
[[nodiscard]] Status aba(const MultibodyModel<N>& m, MultibodyData<N>& d, const real* q, const real* qd, const real* tau,
                         real* qdd, const Vec6* f_ext = nullptr, real implicit_damping_dt = 0) {
  if (detail::aba_input_check(m, q, qd, tau) != 0) return Status::non_finite_input;
  real out[max_dofs<N>()];
  if (detail::aba_kernel<real>(m, d, q, qd, tau, out, f_ext, implicit_damping_dt) != 0) return Status::non_finite_input;
  for (int k = 0; k < m.num_dofs; ++k) qdd[k] = out[k];
  return Status::ok;
}

/// The working storage of aba_batch for L robots of one model (per body what MultibodyData holds
/// for aba, in lanes). About 80 x L reals per body: make it static or a member, not a local of a
/// small MCU stack.
template <int N, int L = 4>
struct MultibodyBatchData {
  using T = Lanes<L>;
  detail::LaneTransform<T> Xup[N];
  detail::LaneVec6<T> v[N], a[N], c[N], pA[N], U[N];
  detail::LaneMat<T, 6> IA[N];
  T inv_d[N], u[N];
};

/// aba for L robots of one model at once, robot l in lane l of every value: q[num_q], qd and
/// tau[num_dofs], qdd[num_dofs] (q[k][l] is robot l's coordinate k), f_ext[num_bodies] or
/// nullptr. Each lane's accelerations are the bits aba gives that robot alone (the same
/// operations, lane by lane; tests/dynamics/test_multibody.cpp). Returns the lanes (bit l) that
/// aba would refuse with non_finite_input; their qdd lanes are left as they were.
template <int N, int L>
[[nodiscard]] unsigned aba_batch(const MultibodyModel<N>& m, MultibodyBatchData<N, L>& d, const Lanes<L>* q,
                                 const Lanes<L>* qd, const Lanes<L>* tau, Lanes<L>* qdd,
                                 const detail::LaneVec6<Lanes<L>>* f_ext = nullptr, real implicit_damping_dt = 0) {
  using T = Lanes<L>;
  const unsigned refused = detail::aba_input_check(m, q, qd, tau);
  T out[max_dofs<N>()];
  const unsigned bad = refused | detail::aba_kernel<T>(m, d, q, qd, tau, out, f_ext, implicit_damping_dt);
  for (int k = 0; k < m.num_dofs; ++k) {
    if (bad == 0) {
      qdd[k] = out[k];
      continue;
    }
    for (int l = 0; l < L; ++l)
      if (((bad >> l) & 1u) == 0) qdd[k][l] = out[k][l];
  }
  return bad;
}

#pragma GCC diagnostic pop

namespace detail {
/// forward_kinematics over Xup already at q.
template <int N>
void world_poses(const MultibodyModel<N>& m, const MultibodyData<N>& d, Transform* X_world) {
  for (int i = 0; i < m.num_bodies; ++i)
    X_world[i] = m.parent[i] >= 0 ? compose(d.Xup[i], X_world[m.parent[i]]) : d.Xup[i];
}
}  // namespace detail

/// Every body's pose in the world: X_world[i] maps world coordinates to body i's (Plücker
/// transform world -> body; r is the body origin in world coordinates, E^T its orientation).
template <int N>
void forward_kinematics(const MultibodyModel<N>& m, MultibodyData<N>& d, const real* q, Transform* X_world) {
  detail::update_kinematics(m, d, q);
  detail::world_poses(m, d, X_world);
}

/// The Jacobian of a point fixed on a body: J (6 x num_dofs, row-major in J[ld * row + col])
/// with rows [linear velocity of the point (3); angular velocity of the body (3)], both in world
/// coordinates (Pinocchio's LOCAL_WORLD_ALIGNED frame Jacobian, rows in its linear-first order).
/// `X_world` from forward_kinematics at the same q; `point_b` in the body's frame.
template <int N>
void point_jacobian(const MultibodyModel<N>& m, const Transform* X_world, int body,
                    const Vec3& point_b, real* J, int ld) {
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < m.num_dofs; ++c) J[ld * r + c] = 0;
  const Vec3 p_w = X_world[body].r + X_world[body].E.transpose() * point_b;
  for (int j = body; j >= 0; j = m.parent[j]) {
    const int k0 = m.dof_index[j];
    const Mat3 Et = X_world[j].E.transpose();
    for (int c = 0; c < joint_dofs(m, j); ++c) {
      // Joint j's motion subspace in world coordinates: angular w, linear v at the world origin.
      // A free joint's columns are unit motions of the base: its axes, Et's columns.
      Vec3 w, v_p;
      if (m.joint[j] == JointType::free) {
        w = c < 3 ? Vec3::Zero() : Vec3(Et.col(c - 3));
        v_p = c < 3 ? Vec3(Et.col(c)) : Vec3(X_world[j].r.cross(w) + w.cross(p_w));
      } else {
        const Vec6 Sj = detail::motion_subspace(m, j);
        w = Et * ang(Sj);
        const Vec3 v = Et * lin(Sj) + X_world[j].r.cross(w);
        v_p = v + w.cross(p_w);
      }
      for (int a = 0; a < 3; ++a) {
        J[ld * a + k0 + c] = v_p[a];
        J[ld * (3 + a) + k0 + c] = w[a];
      }
    }
  }
}

namespace detail {
/// The positions' half of a semi-implicit Euler step: q advances by dt_s with the velocities v (see
/// step_semi_implicit; shared with contact.hpp's step_constrained).
template <int N>
void integrate_positions(const MultibodyModel<N>& m, real* q, const real* v_new, real dt_s) {
  for (int i = 0; i < m.num_bodies; ++i) {
    const int k = m.dof_index[i], j = m.q_index[i];
    if (k < 0) continue;
    if (m.joint[i] != JointType::free) {
      q[j] += dt_s * v_new[k];
      continue;
    }
    const Quat Q = quat_from_xyzw(q + j + 3);
    const Vec3 v_b(v_new[k], v_new[k + 1], v_new[k + 2]), w_b(v_new[k + 3], v_new[k + 4], v_new[k + 5]);
    const Vec3 dp = dt_s * rotate(Q, v_b);
    // q <- q (x) exp(dt w_b / 2): the deterministic sin_cos and quat_mul, the same bits on every target.
    const real angle = w_b.norm() * dt_s;
    Quat dq = Quat::Identity();
    if (angle > 0) {
      const Vec3 axis = w_b / w_b.norm();
      real sh = 0, ch = 1;
      sin_cos(angle * real(0.5), sh, ch);
      dq = quat_from_xyzw(axis[0] * sh, axis[1] * sh, axis[2] * sh, ch);
    }
    const Vec4 qn = to_xyzw(quat_mul(Q, dq));
    const real len = std::sqrt(qn.dot(qn));
    for (int a = 0; a < 3; ++a) q[j + a] += dp[a];
    for (int a = 0; a < 4; ++a) q[j + 3 + a] = qn[a] / len;
  }
}
}  // namespace detail

/// One step of length dt_s of semi-implicit (symplectic) Euler with implicit joint damping, the
/// scheme MuJoCo's default Euler integrator uses (E. Todorov, T. Erez, Y. Tassa, "MuJoCo: A physics
/// engine for model-based control", IROS 2012; mj_Euler): the accelerations with the damping taken
/// at the end of the step (aba's implicit_damping_dt), the velocities first, qd += dt qdd, then the
/// positions with the new velocities. A revolute or prismatic joint: q += dt qd. The free joint
/// (MuJoCo's mj_integratePos): the base origin moves by dt R v_b (R its orientation) and the
/// orientation turns by the body-frame rotation vector dt w_b (an exact exponential), then is
/// renormalised. Why: explicit Euler gains energy and needs dt < 2 I / D on a damped joint; this
/// keeps a conservative system's energy bounded and any damping stable at legged_gym's dt = 0.005 s
/// (tests/dynamics/test_multibody.cpp). qdd (num_dofs, may be null) receives the accelerations.
/// Status as aba; on any refusal q and qd are left as they were.
template <int N>
[[nodiscard]] Status step_semi_implicit(const MultibodyModel<N>& m, MultibodyData<N>& d, real* q, real* qd,
                                        const real* tau, real dt_s, real* qdd = nullptr,
                                        const Vec6* f_ext = nullptr) {
  if (!(dt_s > 0) || !is_finite(dt_s)) return Status::invalid_argument;
  real acc[max_dofs<N>()];
  const Status st = aba(m, d, q, qd, tau, acc, f_ext, dt_s);
  if (st != Status::ok) return st;
  const int n = m.num_dofs;
  real v_new[max_dofs<N>()] = {};
  for (int k = 0; k < n; ++k) v_new[k] = qd[k] + dt_s * acc[k];
  if (!all_finite(v_new, n)) return Status::non_finite_input;
  detail::integrate_positions(m, q, v_new, dt_s);
  for (int k = 0; k < n; ++k) qd[k] = v_new[k];
  if (qdd != nullptr)
    for (int k = 0; k < n; ++k) qdd[k] = acc[k];
  return Status::ok;
}

}  // namespace kestrel::dynamics
