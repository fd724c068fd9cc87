// navigation_task (see navigation_task.hpp for what follows Aerial Gym's navigation_task.py and
// what differs).
#include "kestrel/sim/navigation_task.hpp"

#include <algorithm>
#include <cmath>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/policy/observations.hpp"
#include "navigation_common.hpp"
#include "task_support.hpp"

namespace kestrel::sim {

namespace {

constexpr int kNavActionDim = nav::kActionDim;
constexpr int kNavStateObs = nav::kStateObs;
using nav::norm3;

// The reference's exponential_reward_function / exponential_penalty_function.
float exp_reward(float magnitude, float exponent, float v) { return magnitude * std::exp(-(v * v) * exponent); }
float exp_penalty(float magnitude, float exponent, float v) { return magnitude * (std::exp(-(v * v) * exponent) - 1.0f); }

}  // namespace

float navigation_reward(const float e[3], const float e_prev[3], bool crash, const float a[4], const float a_prev[4],
                        float progress, const NavigationRewardParams& p) {
  // The constants in float32, as the reference computes (the same bits in a double build).
  const auto f = [](real v) { return static_cast<float>(v); };
  if (crash) return f(p.collision_penalty);
  const float mult = 1.0f + 2.0f * progress;
  const float dist = norm3(e), prev_dist = norm3(e_prev);
  const float pos_reward = exp_reward(f(p.pos_reward_magnitude), f(p.pos_reward_exponent), dist);
  const float very_close = exp_reward(f(p.very_close_to_goal_reward_magnitude), f(p.very_close_to_goal_reward_exponent), dist);
  const float closer = prev_dist - dist;
  const float closer_reward = closer > 0 ? f(p.getting_closer_reward_multiplier) * closer
                                         : 2.0f * f(p.getting_closer_reward_multiplier) * closer;
  const float distance_reward = (20.0f - dist) / 20.0f;
  const float dx = a[0] - a_prev[0], dz = a[2] - a_prev[2], dyaw = a[3] - a_prev[3];
  const float diff_penalty = exp_penalty(f(p.x_action_diff_penalty_magnitude), f(p.x_action_diff_penalty_exponent), dx) +
                             exp_penalty(f(p.z_action_diff_penalty_magnitude), f(p.z_action_diff_penalty_exponent), dz) +
                             exp_penalty(f(p.yawrate_action_diff_penalty_magnitude), f(p.yawrate_action_diff_penalty_exponent), dyaw);
  const float abs_penalty =
      progress * exp_penalty(f(p.x_absolute_action_penalty_magnitude), f(p.x_absolute_action_penalty_exponent), a[0]) +
      progress * exp_penalty(f(p.z_absolute_action_penalty_magnitude), f(p.z_absolute_action_penalty_exponent), a[2]) +
      progress * exp_penalty(f(p.yawrate_absolute_action_penalty_magnitude), f(p.yawrate_absolute_action_penalty_exponent), a[3]);
  return mult * (pos_reward + very_close + closer_reward + distance_reward) + (diff_penalty + abs_penalty);
}

float navigation_clearance_reward(float nearest_m, const NavigationRewardParams& p) {
  const float pen = static_cast<float>(p.clearance_penalty), d0 = static_cast<float>(p.clearance_m);
  if (pen == 0.0f || !(nearest_m < d0)) return 0.0f;  // off, clear (or a NaN range: no penalty)
  return pen * (1.0f - std::max(nearest_m, 0.0f) / d0);
}

float navigation_sideslip_reward(float lateral_speed_m_s, const NavigationRewardParams& p) {
  const float pen = static_cast<float>(p.sideslip_penalty);
  if (pen == 0.0f || !std::isfinite(lateral_speed_m_s)) return 0.0f;
  return pen * std::fabs(lateral_speed_m_s);
}

int next_curriculum_level(const NavigationCurriculum& c, double success_rate, int level) {
  // Compared in float32, as the reference's tensor comparison is.
  const float rate = static_cast<float>(success_rate);
  if (rate > c.success_rate_for_increase) level += c.increase_step;
  else if (rate < c.success_rate_for_decrease) level -= c.decrease_step;
  return std::min(std::max(level, c.min_level), c.max_level);
}

int navigation_obs_dim(const NavigationParams& p) {
  return kNavStateObs + (1 + p.image_history_frames) * p.pool_rows * p.pool_cols;
}

int navigation_action_dim(const NavigationParams& p) { return p.action_space == NavigationActionSpace::velocity ? 4 : 3; }

namespace nav {

namespace {
// clamp(-1, 1); a NaN action becomes 0 (never reaches the controller).
float clamp_unit(float x) { return x >= -1.0f && x <= 1.0f ? x : (x > 1.0f ? 1.0f : (x < -1.0f ? -1.0f : 0.0f)); }
}  // namespace

void transform_action(const float* in, const NavigationParams& p, float out[kActionDim]) {
  if (p.action_space == NavigationActionSpace::velocity) {
    for (int k = 0; k < kActionDim; ++k) out[k] = clamp_unit(in[k]) * (k < 3 ? p.max_speed_m_s : p.max_yaw_rate_rad_s);
    return;
  }
  // The reference's expression order in float32: (a0 + 1) x cos / sin(max_inclination x a1) x
  // max_speed / 2; the climb angle tilts the forward speed, it never adds a sideways component.
  const float fwd = clamp_unit(in[0]) + 1.0f, incl = p.max_inclination_rad * clamp_unit(in[1]);
  out[0] = fwd * std::cos(incl) * p.max_speed_m_s / 2.0f;
  out[1] = 0.0f;
  out[2] = fwd * std::sin(incl) * p.max_speed_m_s / 2.0f;
  out[3] = clamp_unit(in[2]) * p.max_yaw_rate_rad_s;
}

void command_to_action(const float cmd[kActionDim], const NavigationParams& p, float* action) {
  if (p.action_space == NavigationActionSpace::velocity) {
    for (int k = 0; k < kActionDim; ++k) action[k] = clamp_unit(cmd[k]);
    return;
  }
  const float vx = std::max(cmd[0], 0.0f), vz = clamp_unit(cmd[2]);
  const float speed = std::min(1.0f, std::sqrt(vx * vx + vz * vz));
  const float climb = speed > 0.0f && p.max_inclination_rad > 0.0f ? std::atan2(vz, vx) / p.max_inclination_rad : 0.0f;
  action[0] = 2.0f * speed - 1.0f;
  action[1] = clamp_unit(climb);
  action[2] = clamp_unit(cmd[3] + 2.0f * cmd[1]);  // a sideways wish (+y, left) turns that way (+yaw)
}

void write_state_obs(const float e_v[3], float roll, float pitch, const float v_b[3], const float w_b[3],
                     const float action[kActionDim], float* o) {
  policy::navigation_state_observation(e_v, roll, pitch, v_b, w_b, action, o);  // the firmware's builder too
}

// Velocity towards the goal, at full speed until 2 m from it and then proportionally less (an
// episode succeeds only if it ends within the radius: arrive and stay), yawing to face it (so a
// forward sensor looks along the path), with a reactive dodge read from the pooled image: when
// the central half of the image sees something closer than 0.65 of the sensor's range, the
// command blends towards the clearest side (left / right / up / down half of the image's central
// band) and slows down.
void scripted_action(const float* o, const float* img, int rows, int cols, bool vertical, float* a) {
  const int r0 = rows / 4, r1 = std::max(r0 + 1, rows - rows / 4), c0 = cols / 4, c1 = std::max(c0 + 1, cols - cols / 4);
  const float approach = std::min(1.0f, o[3] / 2.0f);  // o[3]: the distance to the goal, m
  for (int k = 0; k < 3; ++k) a[k] = o[k] * approach;
  const float heading = std::atan2(o[1], o[0]);
  a[3] = std::min(1.0f, std::max(-1.0f, heading));
  float ahead = 1.0f;
  for (int r = r0; r < r1; ++r)
    for (int c = c0; c < c1; ++c) ahead = std::min(ahead, img[r * cols + c]);
  constexpr float kClear = 0.65f;
  if (!(ahead < kClear) || std::fabs(heading) > 0.5f) return;  // clear, or not yet facing the goal
  float side[4] = {0, 0, 0, 0};  // left, right, up, down: mean clearance of that half
  for (int r = r0; r < r1; ++r)
    for (int c = 0; c < cols; ++c) side[c < cols / 2 ? 0 : 1] += img[r * cols + c];
  for (int r = 0; r < rows; ++r)
    for (int c = c0; c < c1; ++c) side[r < rows / 2 ? 2 : 3] += img[r * cols + c];
  const float lr_norm = static_cast<float>((r1 - r0) * (cols / 2)), ud_norm = static_cast<float>((rows / 2) * (c1 - c0));
  const float mean[4] = {side[0] / lr_norm, side[1] / lr_norm, side[2] / ud_norm, side[3] / ud_norm};
  const int sides = vertical ? 4 : 2;  // one image row (planar): no up / down halves
  int best = 0;
  for (int k = 1; k < sides; ++k)
    if (mean[k] > mean[best]) best = k;
  const float dodge[4][3] = {{0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  const float s = (kClear - ahead) / kClear;  // 0 at the threshold, 1 touching
  for (int k = 0; k < 3; ++k) a[k] = (1.0f - s) * a[k] + s * dodge[best][k];
}

void EpisodeBook::count(bool crash, bool success, bool fallback, double episode_reward, TaskInfos& infos) {
  ++infos.episodes;
  infos.episode_reward_sum += episode_reward;
  if (fallback) {
    ++infos.fallback_episodes;
    if (crash) {
      ++infos.terminations;
      ++infos.crashes;
    } else {
      ++infos.truncations;
    }
  } else if (crash) {
    ++infos.terminations;
    ++infos.crashes;
    ++window_crashes;
  } else if (success) {
    ++infos.truncations;  // a success is a truncation within the radius (the reference's rule)
    ++infos.successes;
    ++window_successes;
  } else {
    ++infos.truncations;
    ++window_timeouts;
  }
}

bool EpisodeBook::update_curriculum(const NavigationCurriculum& c, TaskInfos& infos) {
  const int instances = window_successes + window_crashes + window_timeouts;
  if (instances < c.check_after_episodes) return false;
  const int next = next_curriculum_level(c, static_cast<double>(window_successes) / instances, level);
  window_successes = window_crashes = window_timeouts = 0;
  if (next == level) return false;
  level = next;
  ++infos.curriculum_changes;
  infos.curriculum_level = level;
  return true;
}

float EpisodeBook::progress(const NavigationCurriculum& c) const {
  const int span = c.max_level - c.min_level;
  return span > 0 ? static_cast<float>(level - c.min_level) / static_cast<float>(span) : 0.0f;
}

}  // namespace nav

namespace {

// One class for every backend. The image part of the observations is the robot's first range
// image pooled to pool_rows x pool_cols (rigid: the ray sensor's image; planar: the 2-D lidar,
// one row, pooled into pool_rows * pool_cols sectors, so obs_dim is the same). Where the backend
// holds the altitude (planar multirotor) the vertical velocity action is dropped (set to 0 before
// the controller and in the actions the reward and observations see) and the bounds rule reads
// x and y.
class NavigationTask final : public Task {
 public:
  NavigationTask(std::unique_ptr<Simulator> s, const NavigationParams& p)
      : Task(std::move(s), navigation_obs_dim(p), navigation_action_dim(p)), p_(p) {
    const std::size_t n = static_cast<std::size_t>(num_envs_);
    err_prev_.assign(n * 3, 0.0f);
    action_.assign(n * kNavActionDim, 0.0f);
    action_prev_.assign(n * kNavActionDim, 0.0f);
    range_cells_.assign(static_cast<std::size_t>(p_.pool_rows * p_.pool_cols), 0.0f);
    // The image memory: one ring of span frames per environment (span 1 without a history, the
    // current image only), written once per env-step in step() and at a reset, read by write_obs.
    cells_ = p_.pool_rows * p_.pool_cols;
    span_ = p_.image_history_frames > 0 ? policy::frame_history_span(p_.image_history_frames, p_.image_history_lag_env_steps) : 1;
    frames_.assign(n * static_cast<std::size_t>(span_) * static_cast<std::size_t>(cells_), 0.0f);
    head_.assign(n, 0);
    flat_ = sim_->holds_altitude();
    const RangeImage img = sim_->range_image(0, 0);
    scan_ = img.height == 1;
    if (scan_) {
      // A one-row scan: the scripted policy looks at the sectors within +-90 deg of the heading
      // (all of them for a field of view up to 180 deg): its "ahead" is then the central +-45 deg,
      // its sides the left and right quarter-circles, whatever the scan's field of view.
      const int cells = p_.pool_rows * p_.pool_cols;
      const real fov = img.horizontal_fov_rad;
      const int margin = fov > kPi ? static_cast<int>(std::floor(static_cast<real>(cells) * (fov - kPi) / (2 * fov) + 0.5_r)) : 0;
      view_begin_ = std::min(margin, (cells - 1) / 2);
      view_end_ = cells - view_begin_;
    }
    success_radius_m_ = static_cast<float>(sim_->config().task.success_radius_m);
    book_.level = std::min(std::max(p_.curriculum.start_level, p_.curriculum.min_level), p_.curriculum.max_level);
    apply_level();
    reset();
  }

  const char* name() const override { return "navigation_task"; }

  void step(const float* actions) override {
    const int ad = sim_->action_dim();
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      float* cur = &action_[i * kNavActionDim];
      float* prev = &action_prev_[i * kNavActionDim];
      for (int k = 0; k < kNavActionDim; ++k) prev[k] = cur[k];
      nav::transform_action(actions + i * static_cast<std::size_t>(action_dim_), p_, cur);
      if (flat_) cur[2] = 0.0f;  // the altitude is held: no vertical command (nor its penalty)
      for (int k = 0; k < kNavActionDim && k < ad; ++k)
        sim_actions_[i * static_cast<std::size_t>(ad) + static_cast<std::size_t>(k)] = static_cast<real>(cur[k]);
    }
    sim_->step(sim_actions_.data());
    ++infos_.steps;
    const float progress = book_.progress(p_.curriculum);
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      ++episode_step_[i];
      head_[i] = policy::frame_history_advance(span_, head_[i]);
      encode_image(env, ring(env) + static_cast<std::size_t>(head_[i]) * static_cast<std::size_t>(cells_));
      float e_v[3];
      error_vehicle(env, e_v);
      const bool crash = crash_or_out(env);
      float r = navigation_reward(e_v, &err_prev_[i * 3], crash, &action_[i * kNavActionDim],
                                  &action_prev_[i * kNavActionDim], progress, p_.reward);
      if (p_.reward.clearance_penalty != 0 && !crash) r += navigation_clearance_reward(nearest_range_m(env), p_.reward);
      if (p_.reward.sideslip_penalty != 0 && !crash)
        r += navigation_sideslip_reward(static_cast<float>(sim_->base_lin_vel_b()[i * 3 + 1]), p_.reward);
      for (int k = 0; k < 3; ++k) err_prev_[i * 3 + k] = e_v[k];
      // The reference's episode end: a crash terminates; the time limit truncates, a success
      // when within the radius of the goal then (arriving does not end the episode).
      const bool trunc = !crash && episode_step_[i] >= len_;
      const bool success = trunc && norm3(e_v) < success_radius_m_;
      rewards_[i] = r;
      terminations_[i] = crash ? 1 : 0;
      truncations_[i] = trunc ? 1 : 0;
      episode_reward_[i] += static_cast<double>(r);
      ended_[i] = (crash || trunc) ? 1 : 0;
      if (ended_[i]) book_.count(crash, success, sim_->placement_fallback(env), episode_reward_[i], infos_);
    }
    // Curriculum before the resets, as the reference updates it before post_reward_calculation_step:
    // the environments ending now get their next layout at the new level.
    if (book_.update_curriculum(p_.curriculum, infos_)) apply_level();
    reset_ended();  // auto-reset: the rows below are the new episodes' first observations
    for (int env = 0; env < num_envs_; ++env) write_obs(env);
  }

  // nav::scripted_action on every environment's observation row (a scan: its forward sectors).
  // Its thresholds are fractions of the sensor's range: under the proximity encoding it reads the
  // image pooled again in range cells.
  bool scripted_actions(float* actions) const override {
    const bool pooled_again = p_.image_encoding != NavigationImageEncoding::range;
    for (int env = 0; env < num_envs_; ++env) {
      const float* o = &obs_[static_cast<std::size_t>(env) * static_cast<std::size_t>(obs_dim_)];
      const float* img = o + kNavStateObs;
      if (pooled_again) {
        task_support::pool_image(sim_->range_image(env, 0), p_.pool_rows, p_.pool_cols, range_cells_.data());
        img = range_cells_.data();
      }
      float cmd[kNavActionDim];
      if (scan_) nav::scripted_action(o, img + view_begin_, 1, view_end_ - view_begin_, false, cmd);
      else nav::scripted_action(o, img, p_.pool_rows, p_.pool_cols, !flat_, cmd);
      if (flat_) cmd[2] = 0.0f;
      nav::command_to_action(cmd, p_, actions + static_cast<std::size_t>(env) * static_cast<std::size_t>(action_dim_));
    }
    return true;
  }

 private:
  // The nearest range (m) of the robot's first range image: every ray (the whole image min-pooled
  // to one cell, with the observation's rule for no-return rays), not the observation's cells.
  float nearest_range_m(int env) const {
    const RangeImage img = sim_->range_image(env, 0);
    float nearest = 1.0f;
    min_pool_image(img, 1, 1, &nearest);
    return nearest * static_cast<float>(img.max_range_m);
  }

  void apply_level() {
    sim_->set_curriculum_level(static_cast<real>(book_.progress(p_.curriculum)));
    infos_.curriculum_level = book_.level;
  }

  void on_reset(int env) override {
    const std::size_t i = static_cast<std::size_t>(env);
    for (int k = 0; k < kNavActionDim; ++k) action_[i * kNavActionDim + k] = action_prev_[i * kNavActionDim + k] = 0;
    error_vehicle(env, &err_prev_[i * 3]);  // the first "getting closer" of an episode is from its start
    // A new episode's image history is its first image (nothing of the last episode's).
    float* r = ring(env);
    head_[i] = 0;
    encode_image(env, r);
    policy::frame_history_fill(r, span_, cells_, r);
  }

  float* ring(int env) { return &frames_[static_cast<std::size_t>(env) * static_cast<std::size_t>(span_) * static_cast<std::size_t>(cells_)]; }

  // The observation's image cells of the robot's first range image now: min-pooled, then encoded.
  void encode_image(int env, float* cells) const {
    const RangeImage img = sim_->range_image(env, 0);
    task_support::pool_image(img, p_.pool_rows, p_.pool_cols, cells);
    if (p_.image_encoding == NavigationImageEncoding::proximity)
      policy::proximity_from_range_cells(cells, cells_, static_cast<float>(img.max_range_m), p_.proximity_scale_m);
  }

  void write_obs(int env) override {
    const std::size_t i = static_cast<std::size_t>(env);
    float* o = &obs_[i * static_cast<std::size_t>(obs_dim_)];
    float e_v[3], v_b[3], w_b[3];
    error_vehicle(env, e_v);
    for (int k = 0; k < 3; ++k) v_b[k] = static_cast<float>(sim_->base_lin_vel_b()[3 * i + k]);
    for (int k = 0; k < 3; ++k) w_b[k] = static_cast<float>(sim_->base_ang_vel_b()[3 * i + k]);
    const real* eul = sim_->base_euler_xyz() + 3 * i;  // ssa: wrapped to [-pi, pi)
    nav::write_state_obs(e_v, static_cast<float>(eul[0]), static_cast<float>(eul[1]), v_b, w_b, &action_[i * kNavActionDim], o);
    // The image of the last env-step (or of the reset), then the earlier ones.
    const float* r = ring(env);
    const float* now = policy::frame_history_at(r, span_, cells_, head_[i], 0);
    std::copy(now, now + cells_, o + kNavStateObs);
    policy::frame_history_write(r, span_, cells_, head_[i], p_.image_history_frames, p_.image_history_lag_env_steps,
                                o + kNavStateObs + cells_);
  }

  NavigationParams p_;
  bool flat_ = false, scan_ = false;
  int view_begin_ = 0, view_end_ = 0;  // a scan's sectors the scripted policy reads
  float success_radius_m_ = 1.0f;
  nav::EpisodeBook book_;
  std::vector<float> err_prev_, action_, action_prev_;
  mutable std::vector<float> range_cells_;  // scripted_actions' scratch (the image in range cells)
  int cells_ = 0, span_ = 1;
  std::vector<float> frames_;  // per environment: span_ frames of cells_ (policy::frame_history_*)
  std::vector<int> head_;      // per environment: the newest frame's slot
};

}  // namespace

std::unique_ptr<Task> make_navigation_task(const WorldConfig& config, const NavigationParams& params, Backend backend,
                                           std::string& error) {
  const std::string pre = backend == Backend::planar ? "simulator planar: task navigation_task: " : "navigation_task ";
  if (config.controller.kind != ControllerKind::lee_velocity) {
    error = pre + "needs controller lee_velocity_control (got " + config.controller.name + ")";
    return nullptr;
  }
  if (config.task.kind != TaskKind::position_setpoint) {
    error = pre + "needs a position_setpoint task kind (a goal per episode)";
    return nullptr;
  }
  const NavigationCurriculum& c = params.curriculum;
  if (c.min_level > c.max_level || c.check_after_episodes < 1 || c.increase_step < 0 || c.decrease_step < 0) {
    error = pre + "task.curriculum: expected min_level <= max_level, check_after_episodes >= 1, increase_step and "
                  "decrease_step >= 0, got min_level " + std::to_string(c.min_level) + ", max_level " +
            std::to_string(c.max_level) + ", check_after_episodes " + std::to_string(c.check_after_episodes) +
            ", increase_step " + std::to_string(c.increase_step) + ", decrease_step " + std::to_string(c.decrease_step);
    return nullptr;
  }
  if (!(params.max_speed_m_s > 0) || !(params.max_yaw_rate_rad_s >= 0) || !(params.max_inclination_rad >= 0) ||
      params.pool_rows < 1 || params.pool_cols < 1 || !(params.proximity_scale_m > 0) || params.image_history_frames < 0 ||
      params.image_history_frames > 16 || params.image_history_lag_env_steps < 1 || params.image_history_lag_env_steps > 1000) {
    error = pre + "expected max_speed_m_s > 0, max_yaw_rate_rad_s >= 0, max_inclination_rad >= 0, pool_rows and pool_cols >= 1, "
                  "proximity_scale_m > 0, image_history_frames 0-16, image_history_lag_env_steps 1-1000";
    return nullptr;
  }
  WorldConfig wc = config;
  const int span = c.max_level - c.min_level;
  const int start = std::min(std::max(c.start_level, c.min_level), c.max_level);
  wc.env.curriculum_level = span > 0 ? static_cast<real>(start - c.min_level) / static_cast<real>(span) : 0;
  task_support::TaskNeeds needs;
  needs.id = "navigation_task";
  needs.prefix = "navigation_task ";
  needs.image = true;
  needs.image_rows = params.pool_rows;
  needs.image_cols = params.pool_cols;
  std::unique_ptr<Simulator> s = task_support::make_task_simulator(wc, backend, needs, error);
  if (!s) return nullptr;
  return std::unique_ptr<Task>(new NavigationTask(std::move(s), params));
}

TaskConfig navigation_task_config() {
  TaskConfig t;
  t.name = "navigation_task";
  t.kind = TaskKind::position_setpoint;
  t.episode_len_env_steps = 1000;  // 10 s of 10 ms env-steps
  t.min_target_ratio = Vec3(0.90_r, 0.1_r, 0.1_r);  // navigation_task_config.target_min/max_ratio
  t.max_target_ratio = Vec3(0.94_r, 0.9_r, 0.9_r);
  t.success_radius_m = 1.0_r;  // the reference's success check radius
  t.line_of_sight = false;     // obstacles between start and goal are the point
  t.clearance_m = 0.3_r;
  t.placement_attempts = 16;
  t.setpoint_speed_m_s = 0;
  return t;
}

TaskDefaults navigation_task_defaults() {
  TaskDefaults d;
  d.env = "env_with_obstacles";
  // The reference's start (the robot config's init_config, base_quad_config.py and lmf2_config.py
  // alike; robot_asset.min/max_state_ratio is not read for the robot): within x 0.1-0.2, y and z
  // 0.15-0.85 of the bounds, facing the goal's end of the environment within +-pi/6, each
  // velocity component in +-0.2 m/s and each angular rate in +-0.2 rad/s. The registered
  // base_quadrotor starts anywhere in y and z 0.1-0.9, facing any way, at rest.
  d.robot =
      "{name: base_quadrotor, min_init_position_ratio: [0.1, 0.15, 0.15], max_init_position_ratio: [0.2, 0.85, 0.85], "
      "max_init_yaw_rad: 0.5235987755982988, max_init_linvel_m_s: 0.2, max_init_angvel_rad_s: 0.2}";
  d.controller = "lee_velocity_control";
  d.sensors = {{"vl53l5cx", 1}};
  return d;
}

}  // namespace kestrel::sim
