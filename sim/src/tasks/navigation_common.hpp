// Pieces of navigation_task (navigation_task.cpp, one class over the Simulator for every
// backend) kept as free functions so tests and other tasks can call them: the action transform,
// the state observations, the scripted policy and the episode / curriculum bookkeeping (the reward is navigation_reward, navigation_task.hpp). Defined in navigation_task.cpp.
#pragma once

#include <cmath>

#include "kestrel/policy/observations.hpp"
#include "kestrel/sim/navigation_task.hpp"

namespace kestrel::sim::nav {

constexpr int kActionDim = policy::kNavigationActionDim;
constexpr int kStateObs = policy::kNavigationStateObsDim;  // policy/observations.hpp builds them

inline float norm3(const float v[3]) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

/// The policy's navigation_action_dim(p) actions (each clamped to [-1, 1]; NaN becomes 0) to the
/// velocity command [vx, vy, vz, yaw_rate] (vehicle frame) of p.action_space.
void transform_action(const float* in, const NavigationParams& p, float out[kActionDim]);

/// The inverse for the scripted policy: a wanted command in [-1, 1] units of the velocity space
/// ([vx, vy, vz, yaw_rate] / maxima) to p.action_space's actions. forward_inclination cannot move
/// sideways or backwards: vy becomes a turn towards that side, vx < 0 a stop.
void command_to_action(const float cmd[kActionDim], const NavigationParams& p, float* action);

/// The first kStateObs observations: unit goal direction and distance from the vehicle-frame
/// error, roll, pitch, 0, body linear and angular velocity, the transformed actions.
void write_state_obs(const float e_v[3], float roll, float pitch, const float v_b[3], const float w_b[3],
                     const float action[kActionDim], float* o);

/// The scripted policy for one environment from its observation row: the state part of `obs` and
/// an image of rows x cols (row 0 top, column 0 left = body +y; on rigid obs + kStateObs, on planar
/// the sectors of the pooled lidar row within +-90 deg of the heading). `vertical` allows dodging
/// up/down (3-D); the planar multirotor has one row and dodges left/right only.
void scripted_action(const float* obs, const float* img, int rows, int cols, bool vertical, float* a);

/// Episode statistics and the curriculum window.
struct EpisodeBook {
  int level = 0;
  int window_successes = 0, window_crashes = 0, window_timeouts = 0;
  /// Counts one ended episode (crash, else success, else timeout) in the infos and the window.
  /// A fallback episode (target = start) is counted in infos.fallback_episodes, never as a success,
  /// and stays out of the curriculum's window.
  void count(bool crash, bool success, bool fallback, double episode_reward, TaskInfos& infos);
  /// After a window of check_after_episodes episodes: the next level (the reference's
  /// check_and_update_curriculum_level). True if the level moved.
  bool update_curriculum(const NavigationCurriculum& c, TaskInfos& infos);
  /// Curriculum progress in [0, 1].
  float progress(const NavigationCurriculum& c) const;
};

}  // namespace kestrel::sim::nav
