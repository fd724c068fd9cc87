// Observation builders shared by training and firmware: a trained policy must see the same
// inputs, computed by the same code, on the MCU as in the simulator (sim/src/tasks/task.cpp builds its
// observations with these; the firmware builds them from its state estimate).
#pragma once

#include <cmath>
#include <cstddef>
#include <type_traits>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/kernel/rigid_body.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel::policy {

/// Aerial Gym's position_setpoint_task (process_obs_for_task): [target - position (world, m),
/// orientation quaternion xyzw, linear velocity (body, m/s), angular velocity (body, rad/s)].
constexpr int kPositionSetpointObsDim = 13;

/// From flat state views (the Simulator's base_* arrays, or a firmware's estimate).
inline void position_setpoint_observation(const real pos_w[3], const real quat_xyzw[4], const real lin_vel_b[3],
                                          const real ang_vel_b[3], const real target_w[3], float* obs) {
  for (int k = 0; k < 3; ++k) obs[k] = static_cast<float>(target_w[k] - pos_w[k]);
  for (int k = 0; k < 4; ++k) obs[3 + k] = static_cast<float>(quat_xyzw[k]);
  for (int k = 0; k < 3; ++k) obs[7 + k] = static_cast<float>(lin_vel_b[k]);
  for (int k = 0; k < 3; ++k) obs[10 + k] = static_cast<float>(ang_vel_b[k]);
}

/// From a rigid-body state (world-frame linear velocity rotated into the body frame).
inline void position_setpoint_observation(const RigidBodyState& st, const Vec3& target_w, float* obs) {
  const Vec3 v_b = rotate_inverse(st.orientation_wb, st.linvel_w);
  const auto& q = st.orientation_wb.coeffs();  // Eigen stores xyzw
  position_setpoint_observation(st.position_w.data(), q.data(), v_b.data(), st.angvel_b.data(), target_w.data(), obs);
}

/// An observation built in float as the network's real type: `f` itself where real is float (no
/// copy: the M4F image is ~50 B smaller), else copied into `buf` (n values).
inline const real* observation_as_real(const float* f, real* buf, int n) {
  if constexpr (std::is_same<real, float>::value) {
    (void)buf;
    (void)n;
    return f;
  } else {
    for (int i = 0; i < n; ++i) buf[i] = static_cast<real>(f[i]);
    return buf;
  }
}

/// The same with the position error rotated about world z into the vehicle (yaw-only) frame, the
/// frame Lee velocity control reads its command in (the Python env's vehicle_frame_obs option):
/// [c s; -s c] e with (c, s) the yaw's cosine and sine taken from the observation's own quaternion
/// as the normalised (w^2 + x^2 - y^2 - z^2, 2 (w z + x y)) (no atan2: identical bits on every
/// target). A yaw-less attitude (both terms 0: pointing straight up or down) leaves e as it is.
inline void position_setpoint_observation_vehicle_frame(const RigidBodyState& st, const Vec3& target_w, float* obs) {
  position_setpoint_observation(st, target_w, obs);
  const float x = obs[3], y = obs[4], z = obs[5], w = obs[6];
  const float a = w * w + x * x - y * y - z * z, b = 2 * (w * z + x * y);
  const float n = std::sqrt(a * a + b * b);
  if (!(n > 0)) return;
  const float c = a / n, s = b / n, ex = obs[0], ey = obs[1];
  obs[0] = c * ex + s * ey;
  obs[1] = -s * ex + c * ey;
}

/// Aerial Gym's navigation_task: the state part of its observation (the image part follows it).
constexpr int kNavigationActionDim = 4;  // [vx, vy, vz, yaw_rate] after the task's scaling
constexpr int kNavigationStateObsDim = 17;

/// [unit goal direction (3), distance (m), roll, pitch, 0 (the reference zeroes the yaw slot),
/// body linear velocity (3), body angular velocity (3), the scaled actions (4)] from the
/// vehicle-frame position error `e_v`.
inline void navigation_state_observation(const float e_v[3], float roll, float pitch, const float v_b[3], const float w_b[3],
                                         const float action[kNavigationActionDim], float* o) {
  const float d = std::sqrt(e_v[0] * e_v[0] + e_v[1] * e_v[1] + e_v[2] * e_v[2]);
  for (int k = 0; k < 3; ++k) o[k] = d > 1e-6f ? e_v[k] / d : 0.0f;
  o[3] = d;
  o[4] = roll;
  o[5] = pitch;
  o[6] = 0.0f;
  for (int k = 0; k < 3; ++k) o[7 + k] = v_b[k];
  for (int k = 0; k < 3; ++k) o[10 + k] = w_b[k];
  for (int k = 0; k < kNavigationActionDim; ++k) o[13 + k] = action[k];
}

/// Cells of min_pool_ranges (each a range over max_range_m, in [0, 1]) rewritten in place as the
/// proximities 1 / (1 + r / scale_m) of their ranges r (navigation_task's image_encoding
/// proximity): 1 at contact, 0.5 at scale_m, 1 / (1 + max_range_m / scale_m) for no return.
inline void proximity_from_range_cells(float* cells, int n, float max_range_m, float scale_m) {
  const float k = max_range_m / scale_m;
  for (int i = 0; i < n; ++i) cells[i] = 1.0f / (1.0f + cells[i] * k);
}

/// A memory of earlier frames of an observation part (navigation_task's image history): a ring of
/// `span` slots of `cells` floats in caller storage (a static array on an MCU, one row per
/// environment in the simulator), slot `head` the newest. A feed-forward policy that sees the
/// image of now and of `lag`, 2 `lag`, ... env-steps before can tell an obstacle it is turning
/// away from from one it is approaching, which one image cannot (the frame stacking of Mnih et
/// al., "Human-level control through deep reinforcement learning", Nature 518, 2015, at a lag).
/// frame_history_span(frames, lag) slots keep `frames` earlier frames `lag` env-steps apart.
inline int frame_history_span(int frames, int lag) { return frames * lag + 1; }

/// Every slot set to `frame` (a new episode: its history is its first frame, repeated).
inline void frame_history_fill(float* ring, int span, int cells, const float* frame) {
  for (int s = 0; s < span; ++s)
    for (int c = 0; c < cells; ++c) ring[s * cells + c] = frame[c];
}

/// The slot that the next frame goes into (the oldest), to be written by the caller, and the new
/// head: head = frame_history_advance(span, head); then write cells at ring + head * cells.
inline int frame_history_advance(int span, int head) { return head + 1 < span ? head + 1 : 0; }

/// The frame `ago` env-steps before the newest (0 <= ago < span).
inline const float* frame_history_at(const float* ring, int span, int cells, int head, int ago) {
  const int s = head - ago;
  return ring + (s >= 0 ? s : s + span) * cells;
}

/// `frames` earlier frames, lag, 2 lag, ... frames x lag env-steps before the newest, one after
/// another into out (frames x cells floats).
inline void frame_history_write(const float* ring, int span, int cells, int head, int frames, int lag, float* out) {
  for (int j = 1; j <= frames; ++j) {
    const float* f = frame_history_at(ring, span, cells, head, j * lag);
    for (int c = 0; c < cells; ++c) out[(j - 1) * cells + c] = f[c];
  }
}

/// The image part: a range image (row r, column c at ranges[r * row_step + c * col_step]) min-pooled
/// into rows x cols cells, each the nearest valid range of its block over max_range_m, at most 1
/// (negative and NaN ranges are no return; an empty block reads 1). Aerial Gym pools its depth
/// image the same way before its VAE; a firmware pools its ToF zones with this.
inline void min_pool_ranges(const real* ranges, int height, int width, std::ptrdiff_t row_step, std::ptrdiff_t col_step,
                            real max_range_m, int rows, int cols, float* out) {
  for (int i = 0; i < rows; ++i) {
    const int r0 = i * height / rows, r1 = (i + 1) * height / rows;
    for (int j = 0; j < cols; ++j) {
      const int c0 = j * width / cols, c1 = (j + 1) * width / cols;
      real m = max_range_m;
      for (int r = r0; r < r1; ++r)
        for (int c = c0; c < c1; ++c) {
          const real v = ranges[r * row_step + c * col_step];
          if (v >= 0 && v < m) m = v;  // false for NaN: no return
        }
      out[i * cols + j] = static_cast<float>(max_range_m > 0 ? (m / max_range_m < 1 ? m / max_range_m : real(1)) : real(1));
    }
  }
}

}  // namespace kestrel::policy
