// Spatial (6-D) vector algebra in Featherstone's Plücker coordinates: R. Featherstone, "Rigid
// Body Dynamics Algorithms", Springer 2008 (RBDA), chapter 2 and table 2.5.
//
// Conventions (RBDA's): a motion vector is [angular; linear] = [w; v] with v the velocity of the
// point at the frame's origin; a force vector is [moment about the origin; force] = [n; f]. A
// transform X from frame A to frame B is kept as (E, r): E rotates A coordinates into B
// coordinates and r is B's origin in A coordinates, so X m = [E w; E (v - r x w)]; forces
// transform by X* = X^{-T}, and the transpose X^T carries a force from B back to A. No 6 x 6
// matrix is formed: products are written on 3-vectors and 3 x 3 blocks (aba's articulated
// inertias, multibody.hpp).
//
// Core rules: no heap (Eigen fixed-size), no exceptions, float or double (kernel/types.hpp).
#pragma once

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel::dynamics {

using Mat6 = Eigen::Matrix<real, 6, 6, Eigen::DontAlign>;

/// Plücker transform A -> B as (E, r) (see above).
struct Transform {
  Mat3 E = Mat3::Identity();
  Vec3 r = Vec3::Zero();
};

inline Vec3 ang(const Vec6& m) { return m.template head<3>(); }
inline Vec3 lin(const Vec6& m) { return m.template tail<3>(); }
// Element by element: Eigen's comma initializer of a 6-vector from 3-vectors makes GCC 12 see a
// 4-float packet load past the end of a Vec3 (a -Warray-bounds false positive).
inline Vec6 spatial(const Vec3& a, const Vec3& l) {
  Vec6 s;
  s[0] = a[0];
  s[1] = a[1];
  s[2] = a[2];
  s[3] = l[0];
  s[4] = l[1];
  s[5] = l[2];
  return s;
}

/// X m for a motion vector.
inline Vec6 apply_motion(const Transform& X, const Vec6& m) {
  const Vec3 w = ang(m), v = lin(m);
  return spatial(X.E * w, X.E * (v - X.r.cross(w)));
}
/// X^T f: a force in B's coordinates carried back to A's.
inline Vec6 apply_force_transpose(const Transform& X, const Vec6& f) {
  const Vec3 f_a = X.E.transpose() * lin(f);
  return spatial(X.E.transpose() * ang(f) + X.r.cross(f_a), f_a);
}
/// X2 * X1 (first X1: A -> B, then X2: B -> C).
inline Transform compose(const Transform& X2, const Transform& X1) {
  Transform X;
  X.E = X2.E * X1.E;
  X.r = X1.r + X1.E.transpose() * X2.r;
  return X;
}
/// Motion cross product m x n (crm, RBDA eq. 2.31).
inline Vec6 cross_motion(const Vec6& m, const Vec6& n) {
  const Vec3 w = ang(m), v = lin(m);
  return spatial(w.cross(ang(n)), w.cross(lin(n)) + v.cross(ang(n)));
}
/// Force cross product m x* f (crf = -crm^T, RBDA eq. 2.32).
inline Vec6 cross_force(const Vec6& m, const Vec6& f) {
  const Vec3 w = ang(m), v = lin(m);
  return spatial(w.cross(ang(f)) + v.cross(lin(f)), w.cross(lin(f)));
}

/// A rigid body's inertia in its own frame: mass, centre of mass c and rotational inertia about
/// the centre of mass (RBDA eq. 2.63 builds the 6 x 6 form at the frame's origin).
struct SpatialInertia {
  real mass = 0;
  Vec3 com = Vec3::Zero();
  Mat3 inertia_com = Mat3::Zero();
};

/// A rigid body's inertia (or a rigid composite's: a sum of rigid-body inertias is one) at a
/// frame's origin, in that frame, in its 10 numbers (RBDA section 2.13, eq. 2.62): mass m, first
/// moment h = m c and rotational inertia about the origin Ibar, the 6 x 6 form being
/// [Ibar, h x; h x^T, m 1]. CRBA keeps its composite inertias so: moving one to the parent takes
/// three 3 x 3 products (rigid_to_parent) where the 6 x 6 form takes two 6 x 6 ones.
struct RigidInertia {
  real m = 0;
  Vec3 h = Vec3::Zero();
  Mat3 Ibar = Mat3::Zero();
  RigidInertia& operator+=(const RigidInertia& o) {
    m += o.m;
    h += o.h;
    Ibar += o.Ibar;
    return *this;
  }
};
inline RigidInertia rigid_inertia(const SpatialInertia& b) {
  const Mat3 C = hat(b.com);
  RigidInertia I;
  I.m = b.mass;
  I.h = b.mass * b.com;
  I.Ibar = b.inertia_com + b.mass * C * C.transpose();
  return I;
}
/// I s = [Ibar w + h x v; m v - h x w] for s = [w; v].
inline Vec6 rigid_times(const RigidInertia& I, const Vec6& s) {
  const Vec3 w = ang(s), v = lin(s);
  return spatial(I.Ibar * w + I.h.cross(v), I.m * v - I.h.cross(w));
}
/// The inertia given in frame B expressed in frame A, for X = (E, r) from A to B: X^T I X (RBDA
/// eq. 2.66): h_A = E^T h + m r, Ibar_A = E^T Ibar E - r x (E^T h) x - (h_A) x r x.
inline RigidInertia rigid_to_parent(const Transform& X, const RigidInertia& I) {
  const Vec3 g = X.E.transpose() * I.h;
  RigidInertia o;
  o.m = I.m;
  o.h = g + I.m * X.r;
  const Mat3 R = hat(X.r);
  o.Ibar = X.E.transpose() * I.Ibar * X.E - R * hat(g) - hat(o.h) * R;
  return o;
}

/// I m without forming the 6 x 6 matrix: [Ic w + c x (m (v - c x w)) ... ] (RBDA eq. 2.63 applied).
inline Vec6 inertia_times(const SpatialInertia& b, const Vec6& m) {
  const Vec3 w = ang(m), v = lin(m);
  const Vec3 f = b.mass * (v - b.com.cross(w));
  return spatial(b.inertia_com * w + b.com.cross(f), f);
}

}  // namespace kestrel::dynamics
