// navigation_task: reach a goal through obstacles with velocity commands and an in-loop range
// image, after Aerial Gym's navigation_task (ntnu-arl/aerial_gym_simulator,
// aerial_gym/task/navigation_task/navigation_task.py and config/task_config/
// navigation_task_config.py).
//
// What is mirrored:
//   - goal drawn at every reset in the target ratio box of the environment's (per-reset) bounds
//     (task_config.target_min/max_ratio, default [0.90, 0.1, 0.1] .. [0.94, 0.9, 0.9]);
//   - observations: unit vector to the goal in the vehicle frame, distance, roll, pitch, 0 (the
//     reference zeroes the yaw slot), body linear and angular velocity, the robot's actions, then
//     the image part (the reference's 64 VAE latents of its depth image; here the range image of
//     the robot's first ray sensor min-pooled to pool_rows x pool_cols, 8 x 8 = 64 by default);
//   - reward = compute_reward(): (1 + 2 p) (pos + very_close + getting_closer + (20 - d)/20)
//     + action-difference penalties + p * absolute-action penalties, collision -> -100, with p the
//     curriculum progress fraction and the reference's constants (NavigationRewardParams);
//   - episode end: a crash terminates; the time limit truncates, and an episode truncated within
//     success_radius_m of the goal (TaskConfig::success_radius_m, the reference's 1 m) is a
//     success (infos.successes), else a timeout. Reaching the goal does not end the episode: the
//     reward stays positive near it, so the robot is paid to get there and stay (a version that
//     ended the episode on arrival taught PPO to hover just outside the radius, where the reward
//     kept coming: bench/results/python/README.md);
//   - obstacle curriculum: success / crash / timeout counts aggregated until check_after_episodes
//     episodes ended, then level +increase_step if the success rate > success_rate_for_increase,
//     -decrease_step if < success_rate_for_decrease, clamped to [min_level, max_level]
//     (check_and_update_curriculum_level); the level goes to World::set_curriculum_level as
//     (level - min_level) / (max_level - min_level) and takes effect at each environment's next
//     layout.
// Differences (why):
//   - actions (task.navigation.action_space): forward_inclination, the default, is the reference's
//     active action_transformation_function (3 actions in [-1, 1]: speed (a0 + 1) / 2 x
//     max_speed_m_s along the heading, climb angle a1 x max_inclination_rad, yaw rate a2 x
//     max_yaw_rate_rad_s; vy = 0), sent to lee_velocity_control as [vx, 0, vz, yaw_rate] in the
//     vehicle frame; velocity is its commented-out one ([vx, vy, vz, yaw_rate] each x its maximum);
//   - the goal is placed clear of obstacles (World placement, TaskConfig::clearance_m; no line of
//     sight needed): the reference's uniform draw may put it inside an obstacle;
//   - no observation noise (the reference adds uniform noise to the goal vector and the angles
//     with torch.rand, which is not reproducible per environment);
//   - the previous-error memory is reset with the episode (the reference keeps the last episode's
//     error, so its first "getting closer" term of an episode compares with the old goal);
//   - out of bounds (World's 0.5 m margin) counts as a crash as a contact does;
//   - curriculum levels are 0..10 steps of the obstacle-count range of the environment's asset
//     classes (the reference counts obstacles, 15..50);
//   - an optional image history, off by default (task.navigation.image_history_frames): the
//     cells of the image lag, 2 lag, ... env-steps before, after the current image's; the
//     reference's VAE latents of one depth image carry no motion, and a feed-forward policy with
//     one image cannot tell an obstacle it turns away from from one it approaches;
//   - an optional clearance term, off by default (NavigationRewardParams::clearance_penalty): a
//     penalty per env-step growing as the nearest ray of the range image falls within clearance_m,
//     for training (navigation_clearance_reward);
//   - an optional sideslip term, off by default (NavigationRewardParams::sideslip_penalty): a
//     penalty per env-step on the body-frame sideways speed, for training (navigation_sideslip_reward).
#pragma once

#include <memory>
#include <string>

#include "kestrel/sim/task.hpp"

namespace kestrel::sim {

/// navigation_task_config.reward_parameters: NavigationRewardParams (sim/config.hpp, the scenario's
/// task.navigation.reward).

/// navigation_task_config.curriculum (levels rescaled, see above): the scenario's task.curriculum.
using NavigationCurriculum = CurriculumConfig;

struct NavigationParams {
  NavigationActionSpace action_space = NavigationActionSpace::forward_inclination;
  float max_speed_m_s = 2.0f;
  float max_inclination_rad = 0.78539816f;  // pi / 4
  float max_yaw_rate_rad_s = 1.0471976f;  // pi / 3
  int pool_rows = 8, pool_cols = 8;
  NavigationImageEncoding image_encoding = NavigationImageEncoding::range;  // sim/config.hpp
  float proximity_scale_m = 0.5f;
  // Earlier images appended after the current one (policy::frame_history_*): frames, lag apart.
  int image_history_frames = 0, image_history_lag_env_steps = 10;
  NavigationRewardParams reward;
  NavigationCurriculum curriculum;
};

/// compute_reward of the reference for one environment (float32, its expression order).
/// `action` / `prev_action` are the transformed actions [vx, vy, vz, yaw_rate] the robot got;
/// `progress` the curriculum progress fraction in [0, 1]; crash > 0 gives the collision penalty.
float navigation_reward(const float pos_error[3], const float prev_pos_error[3], bool crash, const float action[4],
                        const float prev_action[4], float progress, const NavigationRewardParams& p);

/// The clearance term (not the reference's; p.clearance_penalty 0 turns it off): the penalty per
/// env-step for the nearest range nearest_m (m) of the robot's range image,
/// clearance_penalty x (1 - nearest_m / clearance_m) within clearance_m, else 0.
float navigation_clearance_reward(float nearest_m, const NavigationRewardParams& p);

/// The sideslip term (not the reference's; p.sideslip_penalty 0 turns it off): sideslip_penalty x
/// |v_y| for the body-frame sideways speed v_y (m/s) after the step; 0 for a non-finite v_y.
float navigation_sideslip_reward(float lateral_speed_m_s, const NavigationRewardParams& p);

/// The reference's update_curriculim_level: the next level after a window with this success rate.
int next_curriculum_level(const NavigationCurriculum& c, double success_rate, int level);

/// Observation size: 17 + (1 + image_history_frames) x pool_rows x pool_cols.
int navigation_obs_dim(const NavigationParams& p);

/// Actions per environment: 3 (forward_inclination) or 4 (velocity).
int navigation_action_dim(const NavigationParams& p);

/// Its scripted_actions() (not a reference feature; for `kestrel run --policy scripted`): velocity
/// towards the goal at full speed, yaw towards it, and a reactive dodge to the clearest side of
/// the pooled image when its central half sees something within 0.65 of the sensor's range (with
/// forward_inclination, a sideways dodge is a turn).
/// Builds the task on `backend`: needs robots_per_env = 1, controller lee_velocity_control and a
/// range image: on rigid a ray sensor (lidar, ToF or camera) on the robot; on planar the
/// fixed-altitude multirotor's 2-D lidar (simulator.lidar_beams, 128 if 0) pooled into pool_rows *
/// pool_cols sectors as one image row (same obs_dim), vertical velocity dropped. nullptr and a
/// message otherwise. make_task(config, backend, error) calls it for "navigation_task".
std::unique_ptr<Task> make_navigation_task(const WorldConfig& config, const NavigationParams& params, Backend backend,
                                           std::string& error);
inline std::unique_ptr<Task> make_navigation_task(const WorldConfig& config, const NavigationParams& params, std::string& error) {
  return make_navigation_task(config, params, Backend::rigid, error);
}

/// The registered TaskConfig (registries().tasks "navigation_task").
TaskConfig navigation_task_config();
/// Default scene: env_with_obstacles, base quadrotor, lee_velocity_control, the 8 x 8 VL53L5CX
/// ToF (its image is already the 8 x 8 pool; a camera pools the same way).
TaskDefaults navigation_task_defaults();

}  // namespace kestrel::sim
