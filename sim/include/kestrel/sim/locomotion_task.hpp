// locomotion_task: legged_gym's LeggedRobot task (leggedrobotics/legged_gym, commit 0548121:
// legged_gym/envs/base/legged_robot.py and legged_robot_config.py) over an articulated robot of the
// Simulator interface (robot kind articulated, rigid backend), term for term:
//   - actions: joint position targets, clipped to +-100 and given to the robot's joint PD
//     (target = action_scale x action + home; robot.joint_kp_Nm_rad, joint_kd_Nms_rad, action_scale);
//   - commands: lin_vel_x, lin_vel_y (m/s, body frame), ang_vel_yaw (rad/s) and heading (rad),
//     resampled every resampling_time_s and at each reset, |(x, y)| < 0.2 m/s set to zero; with
//     heading_command the yaw-rate command is clip(0.5 wrap(heading - yaw), -1, 1) every step;
//   - observations (48 + height points): base linear velocity x 2, angular velocity x 0.25,
//     projected gravity, commands x (2, 2, 0.25), (dof_pos - home) x 1, dof_vel x 0.05, the last
//     actions, and with env.terrain.measure_heights clip(base z - 0.5 - heights, -1, 1) x 5; plus
//     uniform noise (legged_gym's noise_scale_vec) and the +-100 clip;
//   - rewards: the terms of LocomotionRewardScales with a non-zero scale, each x scale x dt, summed,
//     clipped at 0 (only_positive_rewards), then the termination term;
//   - episode end: a base contact above 1 N terminates (legged_gym's termination_contact_names =
//     base; the Simulator's crashed view), the time limit (task.episode_len_env_steps, 1000 = 20 s)
//     truncates;
//   - resets: the robot at its home keyframe over its environment's origin, dof_pos = home x
//     U(0.5, 1.5), dof_vel 0, base velocities U(-0.5, 0.5) (world frame); every robot pushed every
//     push_interval_s (Simulator::push_robots).
// What differs: legged_gym's episode lasts max_episode_length + 1 steps (time_out is `>`), here
// episode_len_env_steps; the reset zeroes the last actions in the first observation (legged_gym
// keeps the ended step's); collision and feet terms read the Simulator's per-body contact forces
// (the foot bodies are their own links here, legged_gym merges them into the shank); body names
// match penalize_contacts_on case-insensitively.
//
// Random draws come from per-environment streams (commands, observation noise, resets), so results
// are bit-identical for any thread count. step() does not allocate.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "kestrel/kernel/rng.hpp"
#include "kestrel/sim/config.hpp"
#include "kestrel/sim/simulator.hpp"
#include "kestrel/sim/task.hpp"

namespace kestrel::sim {

/// Random stream purposes of locomotion_task (above kPurposeUser; distinct from simulator.hpp's).
constexpr std::uint32_t kPurposeLocoCommands = kPurposeUser + 8;
constexpr std::uint32_t kPurposeLocoNoise = kPurposeUser + 9;
constexpr std::uint32_t kPurposeLocoReset = kPurposeUser + 10;

/// The reward terms, in legged_gym's order of LeggedRobotCfg.rewards.scales (then the limit and
/// contact-force terms of legged_robot.py).
enum class LocoTerm : int {
  tracking_lin_vel = 0, tracking_ang_vel, lin_vel_z, ang_vel_xy, orientation, torques, dof_vel, dof_acc,
  base_height, feet_air_time, collision, feet_stumble, action_rate, stand_still, dof_pos_limits,
  torque_limits, feet_contact_forces, termination, count
};
constexpr int kNumLocoTerms = static_cast<int>(LocoTerm::count);
/// The term's name (legged_gym's _reward_<name>).
const char* loco_term_name(int term);
/// The term's scale in `s`.
real loco_term_scale(const LocomotionRewardScales& s, int term);

/// One environment's quantities the reward terms read (float32, as legged_gym's tensors).
struct LocoTermInputs {
  int num_dofs = 0, num_feet = 0;
  float dt_s = 0.02f;            // the policy step (sim dt x decimation)
  float commands[3] = {0, 0, 0}; // vx, vy (m/s), yaw rate (rad/s)
  float lin_vel_b[3] = {0, 0, 0}, ang_vel_b[3] = {0, 0, 0}, projected_gravity[3] = {0, 0, -1};
  float base_height_m = 0;       // base z minus the mean terrain height under it
  const float* dof_pos = nullptr;        // (dofs)
  const float* dof_vel = nullptr;        // (dofs)
  const float* last_dof_vel = nullptr;   // (dofs)
  const float* default_dof_pos = nullptr;
  const float* dof_pos_lower = nullptr;  // soft limits (soft_dof_pos_limit applied)
  const float* dof_pos_upper = nullptr;
  const float* torques = nullptr;        // (dofs) N m
  const float* torque_limits = nullptr;  // (dofs) soft_torque_limit x the effort limit
  const float* actions = nullptr;        // (dofs) clipped actions of this step
  const float* last_actions = nullptr;   // (dofs)
  const float* foot_forces_w = nullptr;  // (feet x 3) N
  float feet_air_time_sum = 0;  // update_feet_air_time's return value
  int penalized_contacts = 0;   // penalised bodies with |F| > 0.1 N
  bool terminated = false;      // ended by a contact, not by the time limit
};

/// legged_gym's _reward_<term> for every term (unscaled) of one environment: out[kNumLocoTerms].
void locomotion_reward_terms(const LocoTermInputs& in, const LocomotionConfig& c, float* out);
/// legged_gym's compute_reward: sum of scaled[k] x terms[k] over every term but termination,
/// clipped at 0 when only_positive, then + the termination term. scaled: scale x dt per term.
float locomotion_total_reward(const float* terms, const float* scaled, bool only_positive);
/// legged_gym's feet_air_time bookkeeping (_reward_feet_air_time): contact = F_z > 1 N; filtered
/// with the last step's contact; returns sum over feet of (air_time - 0.5) at a first contact, and
/// updates air_time (+dt, zeroed on contact) and last_contact. Call once per step.
float update_feet_air_time(const float* foot_forces_w, int num_feet, float dt_s, float* air_time, std::uint8_t* last_contact);
/// legged_gym's heading command: clip(0.5 x wrap_to_pi(heading_target - heading), -1, 1).
float heading_yaw_rate_command(float heading_target_rad, float heading_rad);
/// legged_gym's _resample_commands for one environment (3 draws from rng, always): vx, vy in
/// their ranges, then the heading (heading_command) or the yaw rate; |(vx, vy)| <= 0.2 -> 0.
void resample_locomotion_commands(const LocomotionConfig& c, RngStream& rng, float cmd[4]);
/// Observations per environment: 48 for 12 joints (9 + 3 + 3 x dofs) plus the height points.
int locomotion_obs_dim(int num_dofs, int num_height_points);

/// The task on `config` (its robot must be articulated; rigid backend). nullptr and a message on
/// bad input.
std::unique_ptr<Task> make_locomotion_task(const WorldConfig& config, Backend backend, std::string& error);
/// task: locomotion_task's TaskConfig (episode 1000 env-steps = 20 s at legged_gym's 50 Hz).
TaskConfig locomotion_task_config();
struct Registries;
/// Registers locomotion_task and its robot presets (locomotion_go2, locomotion_anymal_c_flat,
/// locomotion_anymal_c_rough), the sim legged_sim and the envs legged_flat and legged_rough.
void register_locomotion_builtins(Registries& r);
/// The scene a locomotion_task scenario gets for the sections it leaves out: legged_sim (dt 5 ms),
/// env legged_flat (plane, decimation 4), robot go2.
TaskDefaults locomotion_task_defaults();

}  // namespace kestrel::sim
