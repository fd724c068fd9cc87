// Observation builders shared by training and firmware: a trained policy must see the same
// inputs, computed by the same code, on the MCU as in the simulator (sim/src/task.cpp builds its
// observations with these; the firmware builds them from its state estimate).
#pragma once

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/kernel/rigid_body.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel::policy {

/// Aerial Gym's position_setpoint_task (process_obs_for_task): [target - position (world, m),
/// orientation quaternion xyzw, linear velocity (body, m/s), angular velocity (body, rad/s)].
constexpr int kPositionSetpointObsDim = 13;

inline void position_setpoint_observation(const RigidBodyState& st, const Vec3& target_w, float* obs) {
  const Vec3 e = target_w - st.position_w;
  const auto& q = st.orientation_wb.coeffs();  // Eigen stores xyzw
  for (int k = 0; k < 3; ++k) obs[k] = static_cast<float>(e[k]);
  for (int k = 0; k < 4; ++k) obs[3 + k] = static_cast<float>(q[k]);
  const Vec3 v_b = rotate_inverse(st.orientation_wb, st.linvel_w);
  for (int k = 0; k < 3; ++k) obs[7 + k] = static_cast<float>(v_b[k]);
  for (int k = 0; k < 3; ++k) obs[10 + k] = static_cast<float>(st.angvel_b[k]);
}

}  // namespace kestrel::policy
