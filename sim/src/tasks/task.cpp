// Task base and position_setpoint_task (see task.hpp for the API and the reference it follows).
#include "kestrel/policy/observations.hpp"
#include "kestrel/sim/episode.hpp"
#include "kestrel/sim/task.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/custom_task.hpp"
#include "kestrel/sim/locomotion_task.hpp"
#include "kestrel/sim/navigation_task.hpp"
#include "kestrel/sim/pick_place_task.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/simulator.hpp"

namespace kestrel::sim {

Task::~Task() = default;

Task::Task(std::unique_ptr<Simulator> sim, int obs_dim, int action_dim)
    : sim_(std::move(sim)), num_envs_(sim_->num_envs()), obs_dim_(obs_dim), action_dim_(action_dim) {
  const std::size_t n = static_cast<std::size_t>(num_envs_);
  obs_.assign(n * static_cast<std::size_t>(obs_dim_), 0.0f);
  rewards_.assign(n, 0.0f);
  terminations_.assign(n, 0);
  truncations_.assign(n, 0);
  episode_step_.assign(n, 0);
  episode_reward_.assign(n, 0.0);
  ended_.assign(n, 0);
  reset_ids_.assign(n, 0);
  sim_actions_.assign(static_cast<std::size_t>(sim_->num_robots()) * static_cast<std::size_t>(sim_->action_dim()), 0);
  // The task decides when an episode ends (its own rules, not only the Simulator's) and computes
  // the reward on the final state before resetting, so the Simulator only flags.
  sim_->set_auto_reset(false);
  len_ = sim_->config().task.episode_len_env_steps;
}

void Task::reset() {
  for (int env = 0; env < num_envs_; ++env) reset_ids_[static_cast<std::size_t>(env)] = env;
  reset_envs(reset_ids_.data(), num_envs_);
}

void Task::reset_idx(const int* env_ids, int count) { reset_envs(env_ids, count); }

void Task::reset_envs(const int* env_ids, int count) {
  // Through ended_ so that a repeated id resets once and reset_ids_ (which env_ids may be) is
  // rebuilt before use.
  for (int env = 0; env < num_envs_; ++env) ended_[static_cast<std::size_t>(env)] = 0;
  for (int k = 0; k < count; ++k)
    if (env_ids[k] >= 0 && env_ids[k] < num_envs_) ended_[static_cast<std::size_t>(env_ids[k])] = 1;
  int n = 0;
  for (int env = 0; env < num_envs_; ++env)
    if (ended_[static_cast<std::size_t>(env)]) reset_ids_[static_cast<std::size_t>(n++)] = env;
  if (n > 0) sim_->reset_idx(reset_ids_.data(), n);
  for (int k = 0; k < n; ++k) {
    const int env = reset_ids_[static_cast<std::size_t>(k)];
    const std::size_t i = static_cast<std::size_t>(env);
    episode_step_[i] = 0;
    episode_reward_[i] = 0;
    on_reset(env);
    rewards_[i] = 0;
    terminations_[i] = truncations_[i] = 0;
    write_obs(env);
  }
}

void Task::reset_ended() {
  int n = 0;
  for (int env = 0; env < num_envs_; ++env)
    if (ended_[static_cast<std::size_t>(env)]) reset_ids_[static_cast<std::size_t>(n++)] = env;
  for (int k = 0; k < n; ++k) keep_final_obs(reset_ids_[static_cast<std::size_t>(k)]);  // before the reset
  if (n > 0) sim_->reset_idx(reset_ids_.data(), n);
  for (int k = 0; k < n; ++k) {
    const int env = reset_ids_[static_cast<std::size_t>(k)];
    episode_step_[static_cast<std::size_t>(env)] = 0;
    episode_reward_[static_cast<std::size_t>(env)] = 0;
    on_reset(env);
  }
}

void Task::set_keep_final_observations(bool on) {
  if (on) final_obs_.assign(obs_.size(), 0.0f);
  else std::vector<float>().swap(final_obs_);
}

void Task::keep_final_obs(int env) {
  if (final_obs_.empty()) return;
  write_obs(env);
  const std::size_t row = static_cast<std::size_t>(env) * static_cast<std::size_t>(obs_dim_);
  std::memcpy(&final_obs_[row], &obs_[row], static_cast<std::size_t>(obs_dim_) * sizeof(float));
}

const char* Task::backend_name() const { return sim_->backend_name(); }
int Task::num_threads() const { return sim_->num_threads(); }
std::uint64_t Task::state_hash() const { return sim_->state_hash(); }

Vec3 Task::position(int env) const {
  const real* p = sim_->base_pos_w() + 3 * static_cast<std::size_t>(env) * static_cast<std::size_t>(sim_->robots_per_env());
  return Vec3(p[0], p[1], p[2]);
}

void Task::quat_xyzw(int env, float q[4]) const {
  const real* s = sim_->base_quat_xyzw() + 4 * static_cast<std::size_t>(env) * static_cast<std::size_t>(sim_->robots_per_env());
  for (int k = 0; k < 4; ++k) q[k] = static_cast<float>(s[k]);
}

void Task::error_world(int env, float e_w[3]) const {
  const std::size_t i = static_cast<std::size_t>(env) * static_cast<std::size_t>(sim_->robots_per_env());
  for (int k = 0; k < 3; ++k) e_w[k] = static_cast<float>(sim_->target_w()[3 * i + k] - sim_->base_pos_w()[3 * i + k]);
}

void Task::error_vehicle(int env, float e_v[3]) const {
  float q[4], e_w[3];
  quat_xyzw(env, q);
  error_world(env, e_w);
  vehicle_frame_error(q, e_w, e_v);
}

bool Task::crash_or_out(int env) const {
  const std::size_t i = static_cast<std::size_t>(env) * static_cast<std::size_t>(sim_->robots_per_env());
  if (sim_->crashed()[i] != 0) return true;
  Vec3 lo, hi;
  sim_->env_bounds(env, lo, hi);
  return out_of_bounds(sim_->base_pos_w() + 3 * i, lo.data(), hi.data(), sim_->holds_altitude() ? 2 : 3);
}

// The arithmetic below follows the reference's float32 TorchScript expression order
// (position_setpoint_task.py compute_reward / exp_func, utils/math.py quat_rotate), built with
// -ffp-contract=off so no fused multiply-add changes a rounding.
float position_setpoint_reward(const float e[3], const float q[4], const float w[3], float multiplier,
                               std::uint8_t& crash) {
  return position_setpoint_reward(e, q, w, multiplier, crash, PositionSetpointRewardParams());
}

float position_setpoint_reward(const float e[3], const float q[4], const float w[3], float multiplier,
                               std::uint8_t& crash, const PositionSetpointRewardParams& p) {
  // The constants as float32 (exact for the defaults: the same bits as the reference's literals).
  const auto f = [](real v) { return static_cast<float>(v); };
  const float d = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
  // exp_func(x, gain, exp) = gain * exp(-exp * x * x)
  const float pos = f(p.pos_reward_magnitude_1) * std::exp(-f(p.pos_reward_exponent_1) * d * d) +
                    f(p.pos_reward_magnitude_2) * std::exp(-f(p.pos_reward_exponent_2) * d * d);
  const float dist = (f(p.distance_reward_offset_m) - d) / f(p.distance_reward_divisor_m);
  // quat_axis(q, 2)[2] via quat_rotate(q, e_z): a + b + c with a = v (2 w^2 - 1),
  // b = 2 w (q_vec x v) (zero z component for v = e_z), c = 2 q_vec (q_vec . v).
  const float qw = q[3];
  const float up_z = (2.0f * qw * qw - 1.0f) + 0.0f + q[2] * q[2] * 2.0f;
  const float tilt = std::fabs(1.0f - up_z);
  const float up = f(p.up_reward_magnitude) / (f(p.up_reward_offset) + tilt * tilt);
  const float s = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
  const float spin = f(p.spin_reward_magnitude) / (1.0f + s * s);
  float reward = multiplier * (pos + dist + pos * (up + spin));
  if (d > f(p.crash_distance_m)) crash = 1;  // in place; an existing crash stays
  if (crash > 0) reward = f(p.crash_reward);
  return reward;
}

void vehicle_frame_error(const float q[4], const float err[3], float out[3]) {
  // Yaw as the reference's get_euler_xyz: atan2(2(wz + xy), w^2 + x^2 - y^2 - z^2); the vehicle
  // frame is the rotation about world z by that yaw, so its inverse rotation is Rz(-yaw).
  const float x = q[0], y = q[1], z = q[2], w = q[3];
  const float yaw = std::atan2(2.0f * (w * z + x * y), w * w + x * x - y * y - z * z);
  const float c = std::cos(yaw), s = std::sin(yaw);
  out[0] = c * err[0] + s * err[1];
  out[1] = -s * err[0] + c * err[1];
  out[2] = err[2];
}

TaskConfig position_setpoint_task_config() {
  TaskConfig t;
  t.name = "position_setpoint_task";
  t.kind = TaskKind::position_setpoint;
  t.episode_len_env_steps = 500;  // Aerial Gym position_setpoint_task_config.episode_len_steps
  // Aerial Gym's target is the world origin, the middle of its empty env in x and y; here the
  // target is the centre of the (per-reset) bounds, so starts drawn in the robot's ratio box stay
  // well inside the reward's 8 m crash radius.
  t.min_target_ratio = Vec3(0.5_r, 0.5_r, 0.5_r);
  t.max_target_ratio = Vec3(0.5_r, 0.5_r, 0.5_r);
  t.setpoint_speed_m_s = 0;  // the policy's action is the setpoint
  return t;
}

// The core's pooling (policy/observations.hpp), so a firmware pools its image with the same code.
void min_pool_image(const RangeImage& img, int rows, int cols, float* out) {
  policy::min_pool_ranges(img.ranges, img.height, img.width, img.row_step, img.col_step, img.max_range_m, rows, cols, out);
}

void min_pool_ranges(const real* ranges, int height, int width, real max_range_m, int rows, int cols, float* out) {
  RangeImage img;
  img.ranges = ranges;
  img.height = height;
  img.width = width;
  img.row_step = width;
  img.col_step = 1;
  img.max_range_m = max_range_m;
  min_pool_image(img, rows, cols, out);
}

std::vector<std::string> rl_task_ids() {
  std::vector<std::string> ids = {"locomotion_task", "navigation_task", "position_setpoint_task", "so101_pick_place"};
  for (const std::string& c : custom_tasks().names()) ids.push_back(c);
  std::sort(ids.begin(), ids.end());
  return ids;
}

std::string rl_task_ids_joined() {
  std::string s;
  for (const std::string& id : rl_task_ids()) s += (s.empty() ? "" : ", ") + id;
  return s;
}

bool is_rl_task(const std::string& task_name) {
  return task_name == "position_setpoint_task" || task_name == "navigation_task" || task_name == "locomotion_task" ||
         task_name == "so101_pick_place" || custom_tasks().has(task_name);
}

bool task_defaults(const std::string& task_name, TaskDefaults& out) {
  if (task_name == "position_setpoint_task") {
    out = TaskDefaults();
    return true;
  }
  if (task_name == "navigation_task") {
    out = navigation_task_defaults();
    return true;
  }
  if (task_name == "locomotion_task") {
    out = locomotion_task_defaults();
    return true;
  }
  if (task_name == "so101_pick_place") {  // its scene is task.pick_place's; the other sections are not read
    out = TaskDefaults();
    return true;
  }
  CustomTaskSpec spec;
  if (custom_tasks().make(task_name, spec)) {
    out = spec.defaults;
    return true;
  }
  // A registered preset of an RL task (locomotion_go2: locomotion_task with Go2's rewards) brings
  // that task's scene.
  TaskConfig preset;
  if (registries().tasks.make(task_name, preset) && preset.name != task_name) return task_defaults(preset.name, out);
  return false;
}

std::unique_ptr<Task> make_task(const WorldConfig& config, Backend backend, std::string& error) {
  const std::string& id = config.task.name;
  if (id == "position_setpoint_task") return make_position_setpoint_task(config, backend, error);
  if (id == "navigation_task") {
    NavigationParams p;
    const NavigationConfig& nc = config.task.navigation;
    p.action_space = nc.action_space;
    p.max_speed_m_s = static_cast<float>(nc.max_speed_m_s);
    p.max_inclination_rad = static_cast<float>(nc.max_inclination_rad);
    p.max_yaw_rate_rad_s = static_cast<float>(nc.max_yaw_rate_rad_s);
    p.pool_rows = nc.pool_rows;
    p.pool_cols = nc.pool_cols;
    p.image_encoding = nc.image_encoding;
    p.proximity_scale_m = static_cast<float>(nc.proximity_scale_m);
    p.image_history_frames = nc.image_history_frames;
    p.image_history_lag_env_steps = nc.image_history_lag_env_steps;
    p.reward = nc.reward;
    p.curriculum = config.task.curriculum;
    return make_navigation_task(config, p, backend, error);
  }
  if (id == "locomotion_task") return make_locomotion_task(config, backend, error);
  if (id == "so101_pick_place") {
    if (backend == Backend::planar) {
      error = "simulator planar: task so101_pick_place runs its own articulated scene (the SO-101 arm, cube and box); "
              "use simulator: rigid";
      return nullptr;
    }
    return make_pick_place_task(config, error);
  }
  if (custom_tasks().has(id)) {
    CustomTaskSpec spec;
    custom_tasks().make(id, spec);
    return make_custom_task(config, spec, backend, error);
  }
  error = "unknown task '" + id + "'; registered task ids: " + rl_task_ids_joined();
  return nullptr;
}

std::unique_ptr<Task> make_task(const WorldConfig& config, std::string& error) { return make_task(config, Backend::rigid, error); }

}  // namespace kestrel::sim
