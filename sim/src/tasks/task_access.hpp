// The narrow set of robot and world accessors the tasks read and write (one robot per
// environment, robot 0). Tasks go through these instead of reaching into the World, so moving
// them onto the simulator interface (legged_gym-Ex's Simulator: base_pos, base_quat, base_lin_vel
// and base_ang_vel in the body frame, contact state, reset_root_states, actions) means
// re-implementing this file only.
#pragma once

#include <cmath>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/episode.hpp"
#include "kestrel/sim/world.hpp"

namespace kestrel::sim::task_access {

/// Robot 0's state as a task sees it.
struct RobotView {
  Vec3 position_w;
  Quat orientation_wb;  // xyzw in every array a task writes
  Vec3 linvel_w;
  Vec3 linvel_b;
  Vec3 angvel_b;
};

inline RobotView robot(const World& w, int env) {
  const RigidBodyState& st = w.robot_state(env, 0);
  RobotView v;
  v.position_w = st.position_w;
  v.orientation_wb = st.orientation_wb;
  v.linvel_w = st.linvel_w;
  v.linvel_b = rotate_inverse(st.orientation_wb, st.linvel_w);
  v.angvel_b = st.angvel_b;
  return v;
}

/// Contact force above the environment's threshold during the last env-step.
inline bool contact_crash(const World& w, int env) { return w.crashed(env, 0); }

/// The World's out-of-bounds rule (0.5 m margin around the environment's bounds, see
/// World::env_step), evaluated on robot 0.
inline bool out_of_bounds(const World& w, int env) {
  Vec3 lo, hi;
  w.lower_upper_bounds(env, lo, hi);
  const Vec3& p = w.robot_state(env, 0).position_w;
  return sim::out_of_bounds(p, lo, hi);
}

inline void bounds(const World& w, int env, Vec3& lower_w, Vec3& upper_w) { w.lower_upper_bounds(env, lower_w, upper_w); }

/// Writes robot 0's controller action (n values).
inline void set_action(World& w, int env, const real* a, int n) {
  real* dst = w.action(env, 0);
  for (int k = 0; k < n; ++k) dst[k] = a[k];
}

/// Yaw of the yaw-only vehicle frame (atan2 form of Aerial Gym's get_euler_xyz).
inline real yaw_of(const Quat& q) {
  const real x = q.x(), y = q.y(), z = q.z(), w = q.w();
  return std::atan2(2 * (w * z + x * y), w * w + x * x - y * y - z * z);
}

/// World-frame vector expressed in the vehicle frame (rotation by -yaw about z).
inline Vec3 world_to_vehicle(const Quat& q, const Vec3& v_w) {
  const real yaw = yaw_of(q), c = std::cos(yaw), s = std::sin(yaw);
  return Vec3(c * v_w[0] + s * v_w[1], -s * v_w[0] + c * v_w[1], v_w[2]);
}

}  // namespace kestrel::sim::task_access
