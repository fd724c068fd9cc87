// Episode-end rules shared by every backend and every task, written once. Before this header the
// out-of-bounds rule alone was typed in six places (World, planar backend, rigid Simulator, two
// task files, the planar tasks).
#pragma once

#include "kestrel/kernel/types.hpp"

namespace kestrel::sim {

/// A robot whose position leaves the environment's bounds by more than this ends its episode. The
/// margin lets a robot rest on a ground plane at the lower bound (or hug a wall) without ending.
constexpr real kOutOfBoundsMargin_m = 0.5_r;

/// True when p_w is outside [lower_w - margin, upper_w + margin] on any of the first `axes` axes
/// (3 on rigid, 2 in the plane). A NaN coordinate counts as outside.
inline bool out_of_bounds(const real* p_w, const real* lower_w, const real* upper_w, int axes) {
  bool out = false;
  for (int k = 0; k < axes; ++k)
    out = out || !(p_w[k] >= lower_w[k] - kOutOfBoundsMargin_m && p_w[k] <= upper_w[k] + kOutOfBoundsMargin_m);
  return out;
}
inline bool out_of_bounds(const Vec3& p_w, const Vec3& lower_w, const Vec3& upper_w, int axes = 3) {
  return out_of_bounds(p_w.data(), lower_w.data(), upper_w.data(), axes);
}

/// The scripted task's moving setpoint (TaskConfig::setpoint_speed_m_s > 0): one env-step moves it
/// by at most max_move_m (speed x env-step duration) straight towards the target.
inline Vec3 advance_setpoint(const Vec3& setpoint_w, const Vec3& target_w, real max_move_m) {
  const Vec3 to_target = target_w - setpoint_w;
  const real len = to_target.norm();
  return len <= max_move_m ? target_w : Vec3(setpoint_w + to_target * (max_move_m / len));
}

/// An episode that runs to its time limit succeeds when every robot ends within
/// TaskConfig::success_radius_m of its target (3-D distance; the planar backend passes its own).
inline bool within_success_radius(real distance_m, real success_radius_m) { return distance_m <= success_radius_m; }

}  // namespace kestrel::sim
