// Tasks on the planar backend (Box2D, sim/src/planar.cpp), through the Simulator interface only:
// base_pos_w, base_quat_xyzw, base_euler_xyz, base_lin_vel_b, base_ang_vel_b, crashed, target_w,
// lidar_ranges_m, env_bounds, step, reset_idx, set_auto_reset, set_curriculum_level.
//
// Why a second implementation next to the World ones (navigation_task.cpp, task.cpp): those are
// pinned bit for bit by golden rewards and state hashes and read World state the interface does
// not carry (sensor images of the 3-D ray sensors, per-env episode steps). What the two share is
// one code path, not a copy: the rewards (navigation_reward, position_setpoint_reward,
// vehicle_frame_error), the navigation action transform, state observations, scripted policy and
// episode / curriculum bookkeeping (tasks/navigation_common.hpp), and the range pooling
// (min_pool_ranges).
//
// Where the tasks apply on planar: the multirotor held at simulator.altitude_m (the issue's
// "multirotor at fixed altitude for fast 2-D navigation"), one robot per environment.
//   - navigation_task: lee_velocity_control. The image part of the observations is the 2-D
//     lidar (simulator.lidar_beams; 128 beams if the scenario gives none) min-pooled into
//     pool_rows * pool_cols sectors, so the observation size is the same 17 + pool_rows *
//     pool_cols as on rigid (81 by default). The sectors form one image row, column 0 leftmost
//     (the most counter-clockwise beam, body +y side, as the rigid image's column 0). The vertical
//     velocity action is dropped (set to 0 before the controller and in the actions the reward and
//     the observations see): the altitude is held. Roll and pitch observations are 0. The
//     obstacle curriculum works as on rigid (Simulator::set_curriculum_level scales each asset
//     class's obstacle count at the next layout). The robot's 3-D ray sensors (the task's
//     default VL53L5CX) are not built: the planar backend renders 2-D lidar only.
//   - position_setpoint_task: 13 observations as on rigid with a z error of 0 (the target is at
//     the flight altitude); the reward is position_setpoint_reward on the horizontal error (tilt
//     0, so its uprightness term is constant). Actions: lee_position_control [dx, dy, dz, yaw]
//     relative as on rigid with dz dropped; lee_velocity_control / lee_acceleration_control
//     passed through with the vertical component dropped.
//   - Terminations as on rigid: contact crash (force above the env's threshold), out of the bounds
//     (0.5 m margin; x and y only, z is the fixed altitude), the tasks' own rules; truncation at
//     episode_len_env_steps.
//   - custom tasks (goal_box_through_gap; PlanarCustomTask below): lee_position_control or
//     lee_velocity_control; the spec's solid objects are task-owned box slots (one asset class
//     each, reserved at creation) that on_reset moves with Simulator::set_obstacle_box after the
//     randomisation terms (the same functions and per-env stream as on rigid,
//     custom_task_terms.hpp); the terms see the objects at the flight altitude, so position errors
//     have z 0, distances are horizontal and inside_box checks x / y only (a height threshold
//     cannot apply at a fixed altitude); image_pool pools the 2-D lidar into one row of
//     rows * cols sectors (the same observation size as on rigid).
// Not here: the ground vehicle (actions [speed, steering], not the tasks' multirotor actions):
// make_planar_task refuses it naming the backend and the alternative.
#include <algorithm>
#include <cmath>
#include <limits>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/episode.hpp"
#include "kestrel/sim/custom_task.hpp"
#include "kestrel/sim/navigation_task.hpp"
#include "kestrel/sim/simulator.hpp"
#include "kestrel/sim/task.hpp"
#include "custom_task_terms.hpp"
#include "navigation_common.hpp"
#include "task_access.hpp"

namespace kestrel::sim {

namespace {

constexpr int kPlanarDefaultLidarBeams = 128;

/// Base of the planar tasks: one robot per env, episode steps counted here (the Simulator's
/// auto-reset is off, the task resets what ended after computing its reward on the final state).
class PlanarTaskBase : public Task {
 protected:
  PlanarTaskBase(std::unique_ptr<Simulator> s, int obs_dim, int action_dim)
      : Task(std::move(s), obs_dim, action_dim),
        episode_step_(static_cast<std::size_t>(num_envs_), 0),
        episode_reward_(static_cast<std::size_t>(num_envs_), 0.0),
        ended_(static_cast<std::size_t>(num_envs_), 0),
        reset_ids_(static_cast<std::size_t>(num_envs_), 0),
        sim_actions_(static_cast<std::size_t>(sim_->num_robots()) * static_cast<std::size_t>(sim_->action_dim()), 0) {
    sim_->set_auto_reset(false);
    len_ = sim_->config().task.episode_len_env_steps;
  }

  /// Contact crash or exit from the bounds (0.5 m margin on x and y, as World::env_step).
  bool crash_or_out(int env) const {
    if (sim_->crashed()[env] != 0) return true;
    Vec3 lo, hi;
    sim_->env_bounds(env, lo, hi);
    const real* p = sim_->base_pos_w() + 3 * env;
    return out_of_bounds(p, lo.data(), hi.data(), 2);
  }

  void quat(int env, float q[4]) const {
    for (int k = 0; k < 4; ++k) q[k] = static_cast<float>(sim_->base_quat_xyzw()[4 * env + k]);
  }
  /// target - position (world frame).
  void error_world(int env, float e_w[3]) const {
    for (int k = 0; k < 3; ++k) e_w[k] = static_cast<float>(sim_->target_w()[3 * env + k] - sim_->base_pos_w()[3 * env + k]);
  }
  void error_vehicle(int env, float e_v[3]) const {
    float q[4], e_w[3];
    quat(env, q);
    error_world(env, e_w);
    vehicle_frame_error(q, e_w, e_v);
  }

  /// Resets the environments flagged in ended_ (one reset_idx call), then on_reset for each.
  void reset_ended() {
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

  // The Simulator resets in batches (one reset_idx call for every id), so the planar tasks
  // override the per-environment defaults of Task.
 public:
  void reset() override {
    std::vector<int> all(static_cast<std::size_t>(num_envs_));  // set-up / explicit reset only, not inside step
    for (int env = 0; env < num_envs_; ++env) all[static_cast<std::size_t>(env)] = env;
    reset_envs(all.data(), num_envs_);
  }
  void reset_idx(const int* env_ids, int count) override { reset_envs(env_ids, count); }

 protected:
  void reset_one(int env) override { reset_envs(&env, 1); }

  void reset_envs(const int* env_ids, int count) {
    for (int env = 0; env < num_envs_; ++env) ended_[static_cast<std::size_t>(env)] = 0;
    for (int k = 0; k < count; ++k)
      if (env_ids[k] >= 0 && env_ids[k] < num_envs_) ended_[static_cast<std::size_t>(env_ids[k])] = 1;
    reset_ended();
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      if (!ended_[i]) continue;
      rewards_[i] = 0;
      terminations_[i] = truncations_[i] = 0;
      write_obs(env);
    }
  }

  virtual void on_reset(int env) = 0;

  int len_ = 0;
  std::vector<int> episode_step_;
  std::vector<double> episode_reward_;
  std::vector<std::uint8_t> ended_;
  std::vector<int> reset_ids_;
  std::vector<real> sim_actions_;  // (robots x simulator action_dim)
};

// ---- navigation_task ----------------------------------------------------------------------------

class PlanarNavigationTask final : public PlanarTaskBase {
 public:
  PlanarNavigationTask(std::unique_ptr<Simulator> s, const NavigationParams& p)
      : PlanarTaskBase(std::move(s), navigation_obs_dim(p), nav::kActionDim), p_(p) {
    const std::size_t n = static_cast<std::size_t>(num_envs_);
    err_prev_.assign(n * 3, 0.0f);
    action_.assign(n * nav::kActionDim, 0.0f);
    action_prev_.assign(n * nav::kActionDim, 0.0f);
    cells_ = p_.pool_rows * p_.pool_cols;
    beams_ = sim_->lidar_beams();
    left_to_right_.assign(static_cast<std::size_t>(beams_), 0);
    max_range_m_ = sim_->config().simulator.lidar_max_range_m;
    // The scripted policy looks at the sectors within +-90 deg of the heading (all of them for a
    // field of view up to 180 deg): its "ahead" is then the central +-45 deg, its sides the
    // left and right quarter-circles, whatever the lidar's field of view.
    const real fov = sim_->config().simulator.lidar_fov_rad;
    const int margin = fov > kPi ? static_cast<int>(std::floor(static_cast<real>(cells_) * (fov - kPi) / (2 * fov) + 0.5_r)) : 0;
    view_begin_ = std::min(margin, (cells_ - 1) / 2);
    view_end_ = cells_ - view_begin_;
    success_radius_m_ = static_cast<float>(sim_->config().task.success_radius_m);
    book_.level = std::min(std::max(p_.curriculum.start_level, p_.curriculum.min_level), p_.curriculum.max_level);
    infos_.curriculum_level = book_.level;
    reset();
  }

  const char* name() const override { return "navigation_task"; }

  void step(const float* actions) override {
    const int ad = sim_->action_dim();
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      float* cur = &action_[i * nav::kActionDim];
      float* prev = &action_prev_[i * nav::kActionDim];
      for (int k = 0; k < nav::kActionDim; ++k) prev[k] = cur[k];
      nav::transform_action(actions + i * nav::kActionDim, p_, cur);
      cur[2] = 0.0f;  // the altitude is held: no vertical command (nor its penalty)
      for (int k = 0; k < nav::kActionDim && k < ad; ++k) sim_actions_[i * static_cast<std::size_t>(ad) + static_cast<std::size_t>(k)] = static_cast<real>(cur[k]);
    }
    sim_->step(sim_actions_.data());
    ++infos_.steps;
    const float progress = book_.progress(p_.curriculum);
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      float e_v[3];
      error_vehicle(env, e_v);
      const bool crash = crash_or_out(env);
      const float r = navigation_reward(e_v, &err_prev_[i * 3], crash, &action_[i * nav::kActionDim],
                                        &action_prev_[i * nav::kActionDim], progress, p_.reward);
      for (int k = 0; k < 3; ++k) err_prev_[i * 3 + k] = e_v[k];
      const bool success = !crash && nav::norm3(e_v) < success_radius_m_;
      const bool trunc = !crash && !success && ++episode_step_[i] >= len_;
      rewards_[i] = r;
      terminations_[i] = (crash || success) ? 1 : 0;
      truncations_[i] = trunc ? 1 : 0;
      episode_reward_[i] += static_cast<double>(r);
      ended_[i] = (crash || success || trunc) ? 1 : 0;
      if (ended_[i]) book_.count(crash, success, episode_reward_[i], infos_);
    }
    // Curriculum before the resets (as on rigid): the environments ending now get the new level.
    if (book_.update_curriculum(p_.curriculum, infos_)) sim_->set_curriculum_level(static_cast<real>(book_.progress(p_.curriculum)));
    reset_ended();
    for (int env = 0; env < num_envs_; ++env) write_obs(env);
  }

  bool scripted_actions(float* actions) const override {
    for (int env = 0; env < num_envs_; ++env) {
      float* a = actions + static_cast<std::size_t>(env) * nav::kActionDim;
      const float* o = &obs_[static_cast<std::size_t>(env) * static_cast<std::size_t>(obs_dim_)];
      nav::scripted_action(o, o + nav::kStateObs + view_begin_, 1, view_end_ - view_begin_, false, a);
      a[2] = 0.0f;
    }
    return true;
  }

 private:
  void on_reset(int env) override {
    const std::size_t i = static_cast<std::size_t>(env);
    for (int k = 0; k < nav::kActionDim; ++k) action_[i * nav::kActionDim + k] = action_prev_[i * nav::kActionDim + k] = 0;
    error_vehicle(env, &err_prev_[i * 3]);  // the first "getting closer" of an episode is from its start
  }

  void write_obs(int env) override {
    const std::size_t i = static_cast<std::size_t>(env);
    float* o = &obs_[i * static_cast<std::size_t>(obs_dim_)];
    float e_v[3], v_b[3], w_b[3];
    error_vehicle(env, e_v);
    for (int k = 0; k < 3; ++k) v_b[k] = static_cast<float>(sim_->base_lin_vel_b()[3 * i + k]);
    for (int k = 0; k < 3; ++k) w_b[k] = static_cast<float>(sim_->base_ang_vel_b()[3 * i + k]);
    const real* eul = sim_->base_euler_xyz() + 3 * i;
    nav::write_state_obs(e_v, static_cast<float>(eul[0]), static_cast<float>(eul[1]), v_b, w_b, &action_[i * nav::kActionDim], o);
    // Beam k is at -fov/2 + k fov/(beams-1) (clockwise first): reversed, column 0 is the leftmost.
    const real* ranges = sim_->lidar_ranges_m() + i * static_cast<std::size_t>(beams_);
    for (int k = 0; k < beams_; ++k) left_to_right_[static_cast<std::size_t>(k)] = ranges[beams_ - 1 - k];
    min_pool_ranges(left_to_right_.data(), 1, beams_, max_range_m_, 1, cells_, o + nav::kStateObs);
  }

  NavigationParams p_;
  int cells_ = 0, beams_ = 0;
  int view_begin_ = 0, view_end_ = 0;  // sectors the scripted policy reads
  real max_range_m_ = 1;
  float success_radius_m_ = 1.0f;
  nav::EpisodeBook book_;
  std::vector<float> err_prev_, action_, action_prev_;
  std::vector<real> left_to_right_;
};

// ---- position_setpoint_task ---------------------------------------------------------------------

constexpr int kPsObsDim = 13;
constexpr int kPsActionDim = 4;
constexpr float kPsActionClip = 10.0f;  // as on rigid (Aerial Gym's robot clips to +-10)

class PlanarPositionSetpointTask final : public PlanarTaskBase {
 public:
  explicit PlanarPositionSetpointTask(std::unique_ptr<Simulator> s) : PlanarTaskBase(std::move(s), kPsObsDim, kPsActionDim) {
    kind_ = sim_->config().controller.kind;
    altitude_m_ = sim_->config().simulator.altitude_m;
    reset();
  }

  const char* name() const override { return "position_setpoint_task"; }

  void step(const float* actions) override {
    const int ad = sim_->action_dim();
    for (int env = 0; env < num_envs_; ++env) {
      const float* in = actions + static_cast<std::size_t>(env) * kPsActionDim;
      real* a = &sim_actions_[static_cast<std::size_t>(env) * static_cast<std::size_t>(ad)];
      float c[kPsActionDim];
      for (int k = 0; k < kPsActionDim; ++k) c[k] = std::min(kPsActionClip, std::max(-kPsActionClip, in[k]));
      for (int k = 0; k < ad && k < kPsActionDim; ++k) a[k] = static_cast<real>(c[k]);
      if (kind_ == ControllerKind::lee_position) {  // relative setpoint, as on rigid; z held
        const real* p = sim_->base_pos_w() + 3 * env;
        a[0] = p[0] + static_cast<real>(c[0]);
        a[1] = p[1] + static_cast<real>(c[1]);
        a[2] = altitude_m_;
      } else {
        a[2] = 0;  // no vertical velocity / acceleration at a fixed altitude
      }
    }
    sim_->step(sim_actions_.data());
    ++infos_.steps;
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      std::uint8_t crash = crash_or_out(env) ? 1 : 0;
      float q[4], e_w[3], e_v[3], w[3];
      quat(env, q);
      error_world(env, e_w);
      for (int k = 0; k < 3; ++k) w[k] = static_cast<float>(sim_->base_ang_vel_b()[3 * i + k]);
      vehicle_frame_error(q, e_w, e_v);
      const float r = position_setpoint_reward(e_v, q, w, 1.0f, crash);
      rewards_[i] = r;
      terminations_[i] = crash;
      const std::uint8_t trunc = ++episode_step_[i] >= len_ ? 1 : 0;
      truncations_[i] = trunc;
      episode_reward_[i] += static_cast<double>(r);
      ended_[i] = (crash || trunc) ? 1 : 0;
      if (!ended_[i]) continue;
      ++infos_.episodes;
      if (crash) {
        ++infos_.terminations;
        ++infos_.crashes;
      } else {
        ++infos_.truncations;
      }
      infos_.episode_reward_sum += episode_reward_[i];
    }
    reset_ended();
    for (int env = 0; env < num_envs_; ++env) write_obs(env);
  }

  // Fly to the target: lee_position_control gets the observed error as its relative setpoint and
  // keeps its yaw; lee_velocity_control a velocity along the error (1 /s, at most 2 m/s), as on rigid.
  bool scripted_actions(float* actions) const override {
    if (kind_ != ControllerKind::lee_position && kind_ != ControllerKind::lee_velocity) return false;
    for (int env = 0; env < num_envs_; ++env) {
      const float* o = &obs_[static_cast<std::size_t>(env) * kPsObsDim];
      float* a = actions + static_cast<std::size_t>(env) * kPsActionDim;
      const Quat q(static_cast<real>(o[6]), static_cast<real>(o[3]), static_cast<real>(o[4]), static_cast<real>(o[5]));  // wxyz ctor
      if (kind_ == ControllerKind::lee_position) {
        for (int k = 0; k < 3; ++k) a[k] = o[k];
        a[3] = static_cast<float>(task_access::yaw_of(q));
      } else {
        Vec3 v = task_access::world_to_vehicle(q, Vec3(o[0], o[1], o[2]));
        if (v.norm() > 2) v *= 2 / v.norm();
        for (int k = 0; k < 3; ++k) a[k] = static_cast<float>(v[k]);
        a[3] = 0;
      }
    }
    return true;
  }

 private:
  void on_reset(int) override {}

  // [target - position (world; z 0 at the flight altitude), quaternion xyzw, body linvel, body angvel].
  void write_obs(int env) override {
    const std::size_t i = static_cast<std::size_t>(env);
    float* o = &obs_[i * kPsObsDim];
    error_world(env, o);
    quat(env, o + 3);
    for (int k = 0; k < 3; ++k) o[7 + k] = static_cast<float>(sim_->base_lin_vel_b()[3 * i + k]);
    for (int k = 0; k < 3; ++k) o[10 + k] = static_cast<float>(sim_->base_ang_vel_b()[3 * i + k]);
  }

  ControllerKind kind_ = ControllerKind::lee_position;
  real altitude_m_ = 1;
};

// ---- custom tasks (goal_box_through_gap) ---------------------------------------------------------

/// A custom task on the fixed-altitude multirotor: the spec's terms evaluated by the same
/// functions as on the World (custom_task_terms.hpp), its solid objects in task-owned box slots
/// (Simulator::set_obstacle_box, one asset class per object), its randomisation drawn from the
/// same per-env stream RngStream(seed, env, kPurposeTaskRandomise). The terms see the objects at
/// the flight altitude (their z replaced by simulator.altitude_m): position errors have z 0,
/// distances are horizontal, and inside_box checks x / y only (the height threshold does not
/// apply: the robot cannot descend into the box). object_centre() reports the drawn 3-D centres.
class PlanarCustomTask final : public PlanarTaskBase, public CustomTaskView {
 public:
  PlanarCustomTask(std::unique_ptr<Simulator> s, const CustomTaskSpec& spec, std::vector<int> slot_class)
      : PlanarTaskBase(std::move(s), custom_terms::obs_dim(spec), custom_terms::kActionDim),
        spec_(spec),
        res_(spec_),
        slot_class_(std::move(slot_class)) {
    const std::size_t n = static_cast<std::size_t>(num_envs_), no = spec_.objects.size();
    centres_.assign(n * no, Vec3::Zero());
    flat_.assign(n * no, Vec3::Zero());
    prev_dist_.assign(n * spec_.rewards.size(), 0.0f);
    action_.assign(n * kAd, 0.0f);
    action_prev_.assign(n * kAd, 0.0f);
    rng_.resize(n);
    for (std::size_t e = 0; e < n; ++e) rng_[e] = RngStream(sim_->config().seed, static_cast<std::uint32_t>(e), kPurposeTaskRandomise);
    kind_ = sim_->config().controller.kind;
    altitude_m_ = sim_->config().simulator.altitude_m;
    beams_ = sim_->lidar_beams();
    left_to_right_.assign(static_cast<std::size_t>(beams_), 0);
    max_range_m_ = sim_->config().simulator.lidar_max_range_m;
    reset();
  }

  const char* name() const override { return spec_.id.c_str(); }

  void step(const float* actions) override {
    const int ad = sim_->action_dim();
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      float* cur = &action_[i * kAd];
      float* prev = &action_prev_[i * kAd];
      for (int k = 0; k < kAd; ++k) prev[k] = cur[k];
      custom_terms::clip_action(spec_, kind_, actions + i * kAd, cur);
      cur[2] = 0.0f;  // the altitude is held: no vertical command (nor its action-rate penalty)
      real* a = &sim_actions_[i * static_cast<std::size_t>(ad)];
      const real* p = sim_->base_pos_w() + 3 * env;
      if (kind_ == ControllerKind::lee_position) {  // offsets from the current position, as on rigid
        a[0] = p[0] + static_cast<real>(cur[0]);
        a[1] = p[1] + static_cast<real>(cur[1]);
        a[2] = altitude_m_;
        a[3] = static_cast<real>(cur[3]);
      } else {  // lee_velocity
        a[0] = static_cast<real>(cur[0] * spec_.max_speed_m_s);
        a[1] = static_cast<real>(cur[1] * spec_.max_speed_m_s);
        a[2] = 0;
        a[3] = static_cast<real>(cur[3] * spec_.max_yaw_rate_rad_s);
      }
    }
    sim_->step(sim_actions_.data());
    ++infos_.steps;
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      ++episode_step_[i];
      const int why = evaluate_terminations(env);
      const bool success = why == 1, crash = why == 2, timeout = why == 3;
      const float r = custom_terms::reward(spec_, res_, flat(env), position(env), success, crash, &action_[i * kAd],
                                           &action_prev_[i * kAd], &prev_dist_[i * spec_.rewards.size()]);
      rewards_[i] = r;
      terminations_[i] = (success || crash) ? 1 : 0;
      truncations_[i] = timeout ? 1 : 0;
      episode_reward_[i] += static_cast<double>(r);
      ended_[i] = why != 0 ? 1 : 0;
      if (ended_[i]) custom_terms::count_episode(why, episode_reward_[i], infos_);
    }
    reset_ended();
    for (int env = 0; env < num_envs_; ++env) write_obs(env);
  }

  bool scripted_actions(float* actions) const override {
    if (!spec_.scripted) return false;
    for (int env = 0; env < num_envs_; ++env) {
      float* a = actions + static_cast<std::size_t>(env) * kAd;
      spec_.scripted(spec_, position(env), flat(env), a);
      a[2] = 0.0f;
    }
    return true;
  }

  Vec3 object_centre(int env, const std::string& name) const override {
    return custom_terms::object_centre(spec_, centres_, num_envs_, env, name);
  }

  int evaluate_terminations(int env) const override {
    return custom_terms::evaluate_terminations(spec_, res_, flat(env), position(env), false, crash_or_out(env),
                                               episode_step_[static_cast<std::size_t>(env)] >= len_);
  }

 private:
  static constexpr int kAd = custom_terms::kActionDim;

  Vec3 position(int env) const {
    const real* p = sim_->base_pos_w() + 3 * env;
    return Vec3(p[0], p[1], p[2]);
  }
  const Vec3* flat(int env) const {
    return spec_.objects.empty() ? nullptr : &flat_[static_cast<std::size_t>(env) * spec_.objects.size()];
  }

  // After the Simulator's reset of env: the randomisation terms move the objects and the solid
  // ones are written into their box slots (the lidar is re-rendered by set_obstacle_box).
  void on_reset(int env) override {
    const std::size_t i = static_cast<std::size_t>(env), no = spec_.objects.size();
    Vec3* c = no ? &centres_[i * no] : nullptr;
    custom_terms::randomize_objects(spec_, res_, rng_[i], c);
    for (std::size_t k = 0; k < no; ++k) {
      flat_[i * no + k] = Vec3(c[k][0], c[k][1], altitude_m_);
      if (slot_class_[k] < 0) continue;
      const Vec3& h = spec_.objects[k].half_extents_m;
      // Checked at creation (positive finite extents, finite centres, box slots), so this holds.
      const bool ok = sim_->set_obstacle_box(env, slot_class_[k], c[k][0], c[k][1], h[0], h[1], 0);
      (void)ok;
    }
    custom_terms::reset_progress(spec_, res_, flat(env), position(env), &prev_dist_[i * spec_.rewards.size()]);
    for (int a = 0; a < kAd; ++a) action_[i * kAd + a] = action_prev_[i * kAd + a] = 0;
  }

  void write_obs(int env) override {
    const std::size_t i = static_cast<std::size_t>(env);
    custom_terms::ObsInput in;
    in.position_w = position(env);
    const real* q = sim_->base_quat_xyzw() + 4 * env;
    in.orientation_wb = Quat(q[3], q[0], q[1], q[2]);  // wxyz constructor
    for (int k = 0; k < 3; ++k) in.linvel_b[k] = sim_->base_lin_vel_b()[3 * i + k];
    for (int k = 0; k < 3; ++k) in.angvel_b[k] = sim_->base_ang_vel_b()[3 * i + k];
    in.action = &action_[i * kAd];
    if (beams_ > 0) {
      // Beam k is at -fov/2 + k fov/(beams-1) (clockwise first): reversed, column 0 is the leftmost.
      const real* ranges = sim_->lidar_ranges_m() + i * static_cast<std::size_t>(beams_);
      for (int k = 0; k < beams_; ++k) left_to_right_[static_cast<std::size_t>(k)] = ranges[beams_ - 1 - k];
      in.ranges = left_to_right_.data();
      in.height = 1;
      in.width = beams_;
    }
    in.max_range_m = max_range_m_;
    custom_terms::write_obs(spec_, res_, flat(env), in, &obs_[i * static_cast<std::size_t>(obs_dim_)]);
  }

  CustomTaskSpec spec_;
  custom_terms::Resolved res_;
  std::vector<int> slot_class_;  // per object: its asset class index (solid), -1 (region)
  ControllerKind kind_ = ControllerKind::lee_position;
  real altitude_m_ = 1, max_range_m_ = 1;
  int beams_ = 0;
  std::vector<Vec3> centres_, flat_;  // envs x objects: drawn centres, and at the flight altitude
  std::vector<float> prev_dist_;      // envs x reward terms (progress_to)
  std::vector<float> action_, action_prev_;
  std::vector<RngStream> rng_;
  std::vector<real> left_to_right_;
};

/// Checks what every planar task needs and builds the Simulator (3-D sensors dropped, the 2-D
/// lidar as given).
std::unique_ptr<Simulator> planar_task_simulator(const WorldConfig& config, const std::string& id, WorldConfig& wc,
                                                 std::string& error) {
  const std::string pre = "simulator planar: task " + id + ": ";
  if (config.robot.robots_per_env != 1) {
    error = pre + "needs robots_per_env = 1";
    return nullptr;
  }
  if (config.task.kind != TaskKind::position_setpoint && !custom_tasks().has(id)) {
    error = pre + "needs a position_setpoint task kind (a goal per episode)";
    return nullptr;
  }
  const bool ground = config.simulator.vehicle == PlanarVehicle::ground_vehicle ||
                      (config.simulator.vehicle == PlanarVehicle::automatic && config.robot.kind == robots::RobotKind::ground_vehicle);
  if (ground) {
    error = pre + "flies the fixed-altitude multirotor; the ground vehicle's actions are [speed, steering] (use a "
                  "multirotor robot, e.g. base_quadrotor, or simulator: rigid)";
    return nullptr;
  }
  wc = config;
  wc.simulator.backend = "planar";
  wc.simulator.vehicle = PlanarVehicle::multirotor;
  wc.robot.sensors.clear();  // 3-D ray sensors: the planar backend has the 2-D lidar instead
  std::unique_ptr<Simulator> s = make_simulator(wc, Backend::planar, error);
  return s;
}

}  // namespace

std::unique_ptr<Task> make_planar_navigation_task(const WorldConfig& config, const NavigationParams& params, std::string& error) {
  const std::string pre = "simulator planar: task navigation_task: ";
  if (config.controller.kind != ControllerKind::lee_velocity) {
    error = pre + "needs controller lee_velocity_control (got " + config.controller.name + ")";
    return nullptr;
  }
  const NavigationCurriculum& c = params.curriculum;
  if (c.min_level > c.max_level || c.check_after_episodes < 1 || c.increase_step < 0 || c.decrease_step < 0) {
    error = pre + "curriculum: expected min_level <= max_level, check_after_episodes >= 1, steps >= 0";
    return nullptr;
  }
  if (!(params.max_speed_m_s > 0) || !(params.max_yaw_rate_rad_s >= 0) || params.pool_rows < 1 || params.pool_cols < 1) {
    error = pre + "expected max_speed_m_s > 0, max_yaw_rate_rad_s >= 0, pool_rows and pool_cols >= 1";
    return nullptr;
  }
  WorldConfig in = config;
  const int cells = params.pool_rows * params.pool_cols;
  if (in.simulator.lidar_beams == 0) in.simulator.lidar_beams = std::max(kPlanarDefaultLidarBeams, cells);
  if (in.simulator.lidar_beams < cells) {
    error = pre + "simulator.lidar_beams (" + std::to_string(in.simulator.lidar_beams) + ") must be at least the " +
            std::to_string(cells) + " pooled sectors of the observation (pool_rows x pool_cols)";
    return nullptr;
  }
  const int span = c.max_level - c.min_level;
  const int start = std::min(std::max(c.start_level, c.min_level), c.max_level);
  in.env.curriculum_level = span > 0 ? static_cast<real>(start - c.min_level) / static_cast<real>(span) : 0;
  WorldConfig wc;
  std::unique_ptr<Simulator> s = planar_task_simulator(in, "navigation_task", wc, error);
  if (!s) return nullptr;
  return std::unique_ptr<Task>(new PlanarNavigationTask(std::move(s), params));
}

std::unique_ptr<Task> make_planar_custom_task(const WorldConfig& config, const CustomTaskSpec& spec, std::string& error) {
  if (!custom_terms::check_spec(spec, error)) return nullptr;
  const std::string where = "simulator planar: custom task " + spec.id + ": ";
  WorldConfig wc;
  std::vector<int> slot_class;
  if (!custom_terms::prepare_config(config, spec, {ControllerKind::lee_position, ControllerKind::lee_velocity},
                                    "lee_position_control or lee_velocity_control (the fixed-altitude multirotor), or use "
                                    "simulator: rigid",
                                    where, wc, slot_class, error))
    return nullptr;
  int cells = 0;
  for (const ObservationTerm& t : spec.observations)
    if (t.kind == ObsTermKind::image_pool) cells = std::max(cells, t.rows * t.cols);
  if (cells > 0 && wc.simulator.lidar_beams == 0) wc.simulator.lidar_beams = std::max(kPlanarDefaultLidarBeams, cells);
  if (wc.simulator.lidar_beams < cells) {
    error = where + "simulator.lidar_beams (" + std::to_string(wc.simulator.lidar_beams) + ") must be at least the " +
            std::to_string(cells) + " pooled sectors of the image_pool observation (rows x cols)";
    return nullptr;
  }
  WorldConfig built;
  std::unique_ptr<Simulator> s = planar_task_simulator(wc, spec.id, built, error);
  if (!s) return nullptr;
  return std::unique_ptr<Task>(new PlanarCustomTask(std::move(s), spec, std::move(slot_class)));
}

std::unique_ptr<Task> make_planar_task(const WorldConfig& config, std::string& error) {
  const std::string& id = config.task.name;
  if (id == "navigation_task") return make_planar_navigation_task(config, NavigationParams(), error);
  if (id == "position_setpoint_task") {
    const ControllerKind k = config.controller.kind;
    if (k != ControllerKind::lee_position && k != ControllerKind::lee_velocity && k != ControllerKind::lee_acceleration) {
      error = "simulator planar: task position_setpoint_task: controller " + config.controller.name +
              " is not available on the fixed-altitude multirotor; allowed: lee_position_control, lee_velocity_control, "
              "lee_acceleration_control (or use simulator: rigid)";
      return nullptr;
    }
    WorldConfig wc;
    std::unique_ptr<Simulator> s = planar_task_simulator(config, id, wc, error);
    if (!s) return nullptr;
    return std::unique_ptr<Task>(new PlanarPositionSetpointTask(std::move(s)));
  }
  if (custom_tasks().has(id)) {
    CustomTaskSpec spec;
    custom_tasks().make(id, spec);
    return make_planar_custom_task(config, spec, error);
  }
  error = "unknown task '" + id + "'; registered task ids: " + rl_task_ids_joined();
  return nullptr;
}

}  // namespace kestrel::sim
