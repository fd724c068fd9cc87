// Reinforcement-learning tasks over the Simulator interface (any backend), shaped like Aerial Gym's task API
// (ntnu-arl/aerial_gym_simulator, commit f0d0f05: aerial_gym/task/base_task.py and
// task/position_setpoint_task/position_setpoint_task.py): reset(), reset_idx(env_ids) and
// step(actions) -> (observations, rewards, terminations, truncations, infos), with the auto-reset
// inside step: an environment that ends is reset before step() returns and its row of the
// observations holds the first observation of the new episode (Aerial Gym's
// return_state_before_reset = False), while its reward and flags describe the step that ended it.
//
// The results live in flat, row-major buffers owned by the task and rewritten in place by every
// call (Aerial Gym's task_obs dict tensors are updated in place too), so a caller reads them
// without copies: observations() is num_envs x obs_dim floats, rewards() num_envs floats,
// terminations()/truncations() num_envs bytes (0/1). step() does not allocate
// (tests/sim/tasks/task_test.cpp checks it with the heap counter).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "kestrel/kernel/types.hpp"
#include "kestrel/sim/config.hpp"
#include "kestrel/sim/simulator.hpp"

namespace kestrel::sim {

/// Aerial Gym's `infos` is an empty dict in this task; here it carries the running episode
/// statistics instead (summed over every episode finished since the task was built).
struct TaskInfos {
  std::uint64_t steps = 0;          // task steps taken
  std::uint64_t episodes = 0;       // episodes finished (terminated or truncated)
  std::uint64_t terminations = 0;   // of which terminated (crash, or success where the task ends on it)
  std::uint64_t truncations = 0;    // of which truncated only (episode length reached)
  std::uint64_t crashes = 0;        // episodes ended by a crash (contact, out of bounds, task rule)
  std::uint64_t successes = 0;      // real episodes ended by reaching the goal (tasks that have one)
  std::uint64_t fallback_episodes = 0;  // of episodes: placed by a fallback (no clear start/target pair,
                                        // target = start), never successes (Simulator::placement_fallback)
  double episode_reward_sum = 0;    // sum over finished episodes of the episode's summed reward
  int curriculum_level = 0;         // obstacle curriculum level now (navigation_task)
  double mean_terrain_level = 0;    // mean terrain level of the environments now (locomotion_task on tiled terrain)
  std::uint64_t curriculum_changes = 0;  // times the curriculum level moved
  double mean_episode_reward() const { return episodes > 0 ? episode_reward_sum / static_cast<double>(episodes) : 0; }
  /// Finished episodes with a real (start, target) pair: the success rate's denominator.
  std::uint64_t real_episodes() const { return episodes - fallback_episodes; }
  /// Successes over real episodes; 0 when there are none (check real_episodes() before printing it).
  double success_rate() const {
    return real_episodes() > 0 ? static_cast<double>(successes) / static_cast<double>(real_episodes()) : 0;
  }
};

class Task {
 public:
  virtual ~Task();
  Task(const Task&) = delete;
  Task& operator=(const Task&) = delete;

  virtual const char* name() const = 0;
  int num_envs() const { return num_envs_; }
  int obs_dim() const { return obs_dim_; }
  int action_dim() const { return action_dim_; }

  /// Resets every environment; observations() then holds the first observations, rewards and
  /// flags are zero (Aerial Gym's reset() returning the tuple).
  void reset();
  /// Resets the listed environments only (their observation rows are rewritten); ids outside
  /// [0, num_envs) are ignored.
  void reset_idx(const int* env_ids, int count);
  /// One task step: `actions` is num_envs x action_dim floats (row-major).
  virtual void step(const float* actions) = 0;
  /// The task's built-in scripted controller (what `kestrel run --policy scripted` drives):
  /// writes num_envs x action_dim actions computed from the current observations and state.
  /// False (nothing written) when the task has none for its controller configuration.
  virtual bool scripted_actions(float* actions) const = 0;

  /// The box the task clamps each action component to (action_dim values each), where the task
  /// has per-component bounds (so101_pick_place: the joint ranges); false (nothing written) for
  /// tasks whose bounds are one number for every component (kestrel.vector_env's _action_bound).
  virtual bool action_bounds(float* low, float* high) const {
    (void)low, (void)high;
    return false;
  }

  const float* observations() const { return obs_.data(); }
  const float* rewards() const { return rewards_.data(); }
  const std::uint8_t* terminations() const { return terminations_.data(); }
  const std::uint8_t* truncations() const { return truncations_.data(); }
  const TaskInfos& infos() const { return infos_; }
  /// Reward terms the task sums (locomotion_task: legged_gym's, scaled; others: none): their
  /// names and each one's sum over every finished episode (legged_gym's episode_sums; per episode:
  /// divide by infos().episodes).
  virtual int num_reward_terms() const { return 0; }
  virtual const char* reward_term_name(int k) const {
    (void)k;
    return "";
  }
  virtual double reward_term_sum(int k) const {
    (void)k;
    return 0;
  }

  /// Final observations (gymnasium's same-step autoreset `final_obs`): off by default; once on,
  /// every step() writes, for each environment whose episode ended in that step, the observation
  /// of the state that ended it (before the auto-reset) into that environment's row of
  /// final_observations() (num_envs x obs_dim floats; other rows keep older values). Turning it on
  /// allocates the buffer (here, never in step); nullptr while off.
  void set_keep_final_observations(bool on);
  const float* final_observations() const { return final_obs_.empty() ? nullptr : final_obs_.data(); }

  /// The Simulator the task runs on (whichever backend; a task reads and writes nothing else).
  Simulator& simulator() { return *sim_; }
  const Simulator& simulator() const { return *sim_; }
  /// "rigid" or "planar".
  const char* backend_name() const;
  int num_threads() const;
  std::uint64_t state_hash() const;
  /// Environment env's env-steps in its current episode (0 right after a reset).
  int episode_step(int env) const { return episode_step_[static_cast<std::size_t>(env)]; }

 protected:
  /// Takes the Simulator (its auto-reset is turned off: the task decides when an episode ends
  /// and reads the final state before resetting it).
  Task(std::unique_ptr<Simulator> sim, int obs_dim, int action_dim);

  /// Resets one environment (a valid id): new episode, its observation row rewritten.
  void reset_one(int env) { reset_envs(&env, 1); }
  /// Resets the listed environments in one Simulator::reset_idx call, then on_reset and the
  /// observation row of each, with rewards and flags cleared.
  void reset_envs(const int* env_ids, int count);
  /// After step(): the environments flagged in ended_ keep their final observation (when asked)
  /// and are reset in one Simulator::reset_idx call, then on_reset for each.
  void reset_ended();
  /// The task's own reset of env after the Simulator's (its memory, its objects).
  virtual void on_reset(int env) = 0;
  /// Writes environment env's observation row from the current state (every task has one).
  virtual void write_obs(int env) = 0;
  /// Called for an environment that ended, before its reset: with final observations on, writes
  /// its observation row and copies it to final_observations(); else nothing.
  void keep_final_obs(int env);

  // Robot 0 of env as the tasks read it, from the Simulator's views.
  Vec3 position(int env) const;
  void quat_xyzw(int env, float q[4]) const;
  /// target - position (world frame) and the same in the vehicle (yaw-only) frame.
  void error_world(int env, float e_w[3]) const;
  void error_vehicle(int env, float e_v[3]) const;
  /// Contact crash (force above the env's threshold) or exit from the bounds (episode.hpp's
  /// margin; x and y only where the backend holds the altitude).
  bool crash_or_out(int env) const;

  std::unique_ptr<Simulator> sim_;
  int num_envs_ = 0, obs_dim_ = 0, action_dim_ = 0;
  int len_ = 0;  // task.episode_len_env_steps
  std::vector<float> obs_, rewards_;
  std::vector<std::uint8_t> terminations_, truncations_;
  std::vector<float> final_obs_;  // empty unless set_keep_final_observations(true)
  std::vector<int> episode_step_;
  std::vector<double> episode_reward_;
  std::vector<std::uint8_t> ended_;
  std::vector<int> reset_ids_;
  std::vector<real> sim_actions_;  // (robots x Simulator::action_dim)
  TaskInfos infos_;
};

/// Builds the task named by config.task.name: "position_setpoint_task", "navigation_task"
/// (navigation_task.hpp) or a custom task id (custom_task.hpp), on the rigid backend whatever
/// config.simulator says (the backend overload below takes resolve_backend's choice, as `kestrel
/// run` does). Returns nullptr and a message (listing the task ids) for an unknown task or a bad config.
std::unique_ptr<Task> make_task(const WorldConfig& config, std::string& error);
/// The same on an explicit backend. Each task is one class over the Simulator (sim/src/tasks/);
/// on planar it flies the fixed-altitude multirotor (navigation_task, position_setpoint_task and
/// the custom tasks such as goal_box_through_gap), or nullptr and a
/// message naming the backend and the alternative for a task that does not apply there (the
/// ground vehicle, attitude or rate controllers).
std::unique_ptr<Task> make_task(const WorldConfig& config, Backend backend, std::string& error);
/// True if config.task.name names a Task (rather than the World's built-in scripted tasks).
bool is_rl_task(const std::string& task_name);
/// Every id make_task accepts, sorted ("a, b, c" for messages).
std::vector<std::string> rl_task_ids();
std::string rl_task_ids_joined();

/// Registry names a scenario (or `kestrel run --task ID`) uses for the sections it does not give,
/// when its task is an RL task: the task's own sim, env, robot, controller and sensors.
struct TaskDefaults {
  // robot: a registered robot's name, or a YAML map of one with fields set (`{name: base_quadrotor,
  // max_init_yaw_rad: 0.52}`), as a scenario's robot section reads.
  std::string sim = "base_sim", env = "empty", robot = "base_quadrotor", controller = "lee_position_control";
  std::vector<std::pair<std::string, int>> sensors;  // (sensor registry name, every_env_steps)
};
/// False if `task_name` is not an RL task id.
bool task_defaults(const std::string& task_name, TaskDefaults& out);

/// Min-pools a ray sensor's range image (height x width, row-major) to rows x cols cells: each
/// cell is the smallest valid range of its pixel block (blocks split at floor(i * height / rows))
/// divided by max_range_m and clamped to [0, 1]; pixels with no valid return (negative,
/// non-finite, beyond max_range_m) count as max_range_m. Needs rows <= height, cols <= width.
void min_pool_ranges(const real* ranges, int height, int width, real max_range_m, int rows, int cols, float* out);
/// The same over a Simulator range image (any row / column step).
void min_pool_image(const RangeImage& img, int rows, int cols, float* out);

// ---- position_setpoint_task ---------------------------------------------------------------------

/// Aerial Gym's position_setpoint_task reward (compute_reward in position_setpoint_task.py at
/// commit f0d0f05; golden/README.md section rewards.json), as a pure float32 function of one
/// environment's inputs:
///   d = |pos_error|; pos = 3 exp(-8 d^2) + 2 exp(-4 d^2); dist = (20 - d)/40;
///   tilt = |1 - (world-z component of the body z axis)|, up = 0.2/(0.1 + tilt^2);
///   s = |body angular velocity|, spin = 3/(1 + s^2);
///   reward = multiplier (pos + dist + pos (up + spin)).
/// Then crash becomes 1 where d > 8 (written in place, existing 1s stay) and the reward is -20
/// wherever crash > 0. The reference takes the task config's reward parameters, linear velocity
/// and the actions but uses none of them (golden/README.md quirk 15), so they are not parameters.
/// pos_error = target - position. The reference rotates it into the yaw-only vehicle frame first
/// (vehicle_frame_error below), but only its length d enters the reward and a rotation keeps the
/// length: the task passes the world-frame error and saves the atan2, sin and cos per step (the
/// reward moves by at most an ulp of d; tests/sim/tasks/task_test.cpp checks both within 1e-5).
float position_setpoint_reward(const float pos_error[3], const float quat_xyzw[4], const float body_angvel[3],
                               float curriculum_multiplier, std::uint8_t& crash);
/// The same with the constants of `p` (task.reward; the defaults give the same bits as above).
float position_setpoint_reward(const float pos_error[3], const float quat_xyzw[4], const float body_angvel[3],
                               float curriculum_multiplier, std::uint8_t& crash, const PositionSetpointRewardParams& p);

/// target - position (world frame) rotated into the vehicle frame (inverse rotation by the yaw-only
/// quaternion of `quat_xyzw`), as the reference does before calling the reward.
void vehicle_frame_error(const float quat_xyzw[4], const float err_world[3], float out[3]);

/// Position setpoint task: one robot per environment flies to the target the World drew at reset.
///   observations (13): [target - position (world), orientation quaternion xyzw,
///                       body-frame linear velocity, body-frame angular velocity]
///     (Aerial Gym's process_obs_for_task; its target is the world origin, ours the per-episode
///     target, placed at the centre of the bounds by the registered config).
///   actions (4): clipped to +-10 as Aerial Gym's robot does (no scaling, quirk 7), then
///     - lee_position_control: [dx, dy, dz, yaw] -> setpoint = current position + (dx, dy, dz),
///       yaw absolute. Aerial Gym's position setpoint is absolute with the target at the origin;
///       a setpoint relative to the robot keeps a zero action meaning "hold here" wherever the
///       target is, and the scripted policy "fly to the target" is simply action = obs[0:3].
///     - any other controller: passed through unchanged (Aerial Gym's semantics; its shipped
///       config uses lee_attitude_control, where a zero action is hover thrust, level, zero yaw
///       rate; with direct_motor_control, as Aerial Gym's motor-command configs, a zero action
///       is motors off and the robot falls: sim/scenarios/position_setpoint_*.yaml).
///   scripted_actions(): fly to the target for lee_position_control (action = obs[0:3]),
///     lee_velocity_control and lee_attitude_control (a PD position loop); none for motor commands.
///   terminations: contact crash (World, force > threshold), out of bounds (World's 0.5 m margin)
///     or d > 8 m (the reward's crash rule); truncations: episode_len_env_steps env-steps reached
///     (Aerial Gym truncates at sim_steps > episode_len_steps, i.e. one step later).
std::unique_ptr<Task> make_position_setpoint_task(const WorldConfig& config, Backend backend, std::string& error);
inline std::unique_ptr<Task> make_position_setpoint_task(const WorldConfig& config, std::string& error) {
  return make_position_setpoint_task(config, Backend::rigid, error);
}

/// The registered config of position_setpoint_task (registries().tasks "position_setpoint_task").
TaskConfig position_setpoint_task_config();

}  // namespace kestrel::sim
