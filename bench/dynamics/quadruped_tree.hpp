// The quadruped tree the dynamics benches time (the MCU bench's control_bench.cpp and the host's
// bench_dynamics.cpp, so both measure one model): a trunk and four legs of three revolute joints
// (hip abduction about x, hip and knee flexion about y), Go2-like masses and lengths, 13 bodies;
// on a fixed trunk (12 dofs) or a floating one (a free joint: 18 velocity coordinates, 19
// configuration coordinates, as a legged robot is simulated). Plus the states they are timed at:
// a bent stance with joint velocities, the trunk tilted and moving.
#pragma once

#include "kestrel/dynamics/contact.hpp"
#include "kestrel/dynamics/multibody.hpp"

namespace kestrel::bench_trees {

inline Status make_quadruped_tree(dynamics::MultibodyModel<13>& m, bool floating) {
  namespace dy = kestrel::dynamics;
  auto link = [](real mass, const Vec3& com, const Vec3& diag) {
    dy::SpatialInertia b;
    b.mass = mass;
    b.com = com;
    b.inertia_com = diag.asDiagonal();
    return b;
  };
  m = dy::MultibodyModel<13>{};
  m.num_bodies = 13;
  m.parent[0] = -1;
  m.joint[0] = floating ? dy::JointType::free : dy::JointType::fixed;
  m.body[0] = link(6.9_r, Vec3::Zero(), Vec3(0.03_r, 0.1_r, 0.11_r));
  for (int leg = 0; leg < 4; ++leg) {
    const real sx = leg < 2 ? 1 : -1, sy = leg % 2 == 0 ? 1 : -1;
    const int hip = 1 + 3 * leg;
    m.parent[hip] = 0;
    m.X_tree[hip].r = Vec3(0.19_r * sx, 0.05_r * sy, 0);
    m.axis[hip] = Vec3(1, 0, 0);
    m.body[hip] = link(0.68_r, Vec3(0, 0.01_r * sy, 0), Vec3(0.0005_r, 0.0009_r, 0.0006_r));
    m.parent[hip + 1] = hip;
    m.X_tree[hip + 1].r = Vec3(0, 0.09_r * sy, 0);
    m.axis[hip + 1] = Vec3(0, 1, 0);
    m.body[hip + 1] = link(1.0_r, Vec3(0, 0, -0.03_r), Vec3(0.005_r, 0.005_r, 0.001_r));
    m.parent[hip + 2] = hip + 1;
    m.X_tree[hip + 2].r = Vec3(0, 0, -0.21_r);
    m.axis[hip + 2] = Vec3(0, 1, 0);
    m.body[hip + 2] = link(0.24_r, Vec3(0, 0, -0.1_r), Vec3(0.001_r, 0.001_r, 0.00003_r));
  }
  for (int b = 1; b < 13; ++b) m.joint[b] = dy::JointType::revolute;
  const Status s = dy::finish_model(m);
  if (s != Status::ok) return s;
  return m.num_dofs == (floating ? 18 : 12) ? Status::ok : Status::invalid_argument;
}

/// The timed state: q (num_q), qd, qdd (num_dofs) of the fixed (12) or floating (19 / 18) tree.
inline void quadruped_state(bool floating, real* q, real* qd, real* qdd) {
  const int base_q = floating ? 7 : 0, base_v = floating ? 6 : 0;
  const real trunk_q[7] = {0.1_r, -0.2_r, 0.3_r, 0.0499792_r, 0.0998334_r, 0, 0.9937403_r};  // unit quaternion
  for (int k = 0; k < base_q; ++k) q[k] = trunk_q[k];
  for (int k = 0; k < base_v; ++k) {
    qd[k] = 0.2_r * static_cast<real>(k % 3) - 0.1_r;
    qdd[k] = 0.5_r * static_cast<real>(k % 2) - 0.2_r;
  }
  for (int k = 0; k < 12; ++k) {
    q[base_q + k] = k % 3 == 0 ? 0.05_r : k % 3 == 1 ? 0.8_r : -1.5_r;
    qd[base_v + k] = 0.1_r * static_cast<real>(k % 5) - 0.2_r;
    qdd[base_v + k] = 0.3_r * static_cast<real>(k % 4) - 0.4_r;
  }
}

/// The feet: a 2 cm sphere at the end of each calf (bodies 3, 6, 9, 12), friction 1.
inline void quadruped_feet(dynamics::CollisionShape* feet) {
  for (int leg = 0; leg < 4; ++leg) {
    feet[leg] = dynamics::CollisionShape{};
    feet[leg].body = 3 + 3 * leg;
    feet[leg].p_b = Vec3(0, 0, -0.21_r);
    feet[leg].size = Vec3(0.02_r, 0, 0);
  }
}

/// The floating tree standing at rest on the plane z = 0: trunk level, legs at the bent stance of
/// quadruped_state (hip 0.05, thigh 0.8, knee -1.5 rad), the trunk at the height where the lowest
/// foot touches the ground (found by forward kinematics).
inline void quadruped_standing_state(const dynamics::MultibodyModel<13>& m, dynamics::MultibodyData<13>& d, real* q,
                                     real* qd) {
  const real base[7] = {0, 0, 0, 0, 0, 0, 1};
  for (int k = 0; k < 7; ++k) q[k] = base[k];
  for (int k = 0; k < 12; ++k) q[7 + k] = k % 3 == 0 ? 0.05_r : k % 3 == 1 ? 0.8_r : -1.5_r;
  for (int k = 0; k < 18; ++k) qd[k] = 0;
  dynamics::Transform X[13];
  dynamics::forward_kinematics(m, d, q, X);
  dynamics::CollisionShape feet[4];
  quadruped_feet(feet);
  real lowest = 0;
  for (const auto& f : feet) {
    const Vec3 p = X[f.body].r + X[f.body].E.transpose() * f.p_b;
    lowest = p[2] - f.size[0] < lowest ? p[2] - f.size[0] : lowest;
  }
  q[2] = -lowest;
}

}  // namespace kestrel::bench_trees
