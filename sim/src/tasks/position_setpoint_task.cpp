// position_setpoint_task, written once over the Simulator interface (task.hpp has its contract and
// the reference it follows). On a backend that holds the altitude (planar multirotor) the
// vertical command is dropped, the target is at the flight altitude (z error 0) and the bounds
// rule reads x and y; everything else is the same code on every backend.
#include <algorithm>
#include <cmath>

#include "kestrel/policy/observations.hpp"
#include "kestrel/sim/task.hpp"
#include "kestrel/sim/episode.hpp"
#include "task_support.hpp"

namespace kestrel::sim {

namespace {

constexpr int kPsObsDim = policy::kPositionSetpointObsDim;
constexpr int kPsActionDim = 4;
constexpr float kActionClip = 10.0f;  // Aerial Gym robot: actions clipped to +-10 (quirk 7)

class PositionSetpointTask final : public Task {
 public:
  explicit PositionSetpointTask(std::unique_ptr<Simulator> s) : Task(std::move(s), kPsObsDim, kPsActionDim) {
    kind_ = sim_->config().controller.kind;
    relative_ = kind_ == ControllerKind::lee_position;
    reset();
  }

  const char* name() const override { return "position_setpoint_task"; }

  // Fly to the target: lee_position_control gets the observed error as its (relative) setpoint;
  // lee_velocity_control a velocity along the error (gain 1 /s, at most 2 m/s); lee_attitude_control
  // (Aerial Gym's shipped controller for this task) a PD acceleration turned into collective
  // thrust and roll/pitch as that controller reads them (fz = (a0 + 1) m |g|, R_d = Euler(roll,
  // pitch, current yaw), see golden/README.md). Direct motor commands have none.
  bool scripted_actions(float* actions) const override {
    if (kind_ != ControllerKind::lee_position && kind_ != ControllerKind::lee_velocity && kind_ != ControllerKind::lee_attitude)
      return false;
    const real g = sim_->config().sim.gravity_w.norm();
    for (int env = 0; env < num_envs_; ++env) {
      const float* o = &obs_[static_cast<std::size_t>(env) * kPsObsDim];
      float* a = actions + static_cast<std::size_t>(env) * kPsActionDim;
      const real* qv = sim_->base_quat_xyzw() + 4 * env;
      const Quat q(qv[3], qv[0], qv[1], qv[2]);  // wxyz constructor
      const Vec3 e_w(o[0], o[1], o[2]);
      if (kind_ == ControllerKind::lee_position) {
        for (int k = 0; k < 3; ++k) a[k] = o[k];
        a[3] = static_cast<float>(task_support::yaw_of(q));  // absolute yaw: keep it
      } else if (kind_ == ControllerKind::lee_velocity) {
        Vec3 v = task_support::world_to_vehicle(q, e_w);
        if (v.norm() > 2) v *= 2 / v.norm();
        for (int k = 0; k < 3; ++k) a[k] = static_cast<float>(v[k]);
        a[3] = 0;
      } else {
        // a_des = kp e - kd v (kp 2 /s^2, kd 2.5 /s: damped), horizontal part capped at 3 m/s^2.
        const real* vw = sim_->base_lin_vel_w() + 3 * env;
        Vec3 acc = 2 * e_w - 2.5_r * Vec3(vw[0], vw[1], vw[2]);
        const real h = std::sqrt(acc[0] * acc[0] + acc[1] * acc[1]);
        if (h > 3) {
          acc[0] *= 3 / h;
          acc[1] *= 3 / h;
        }
        acc[2] = std::max(-0.5_r * g, std::min(0.5_r * g, acc[2]));
        const Vec3 acc_v = task_support::world_to_vehicle(q, acc);
        const real up = g + acc_v[2];
        const real pitch = std::atan2(acc_v[0], up);
        const real roll = std::atan2(-acc_v[1], std::sqrt(acc_v[0] * acc_v[0] + up * up));
        const real f = std::sqrt(acc_v[0] * acc_v[0] + acc_v[1] * acc_v[1] + up * up);  // |F| / m
        a[0] = static_cast<float>(f / g - 1);  // the controller does not compensate tilt: ask for |F|
        a[1] = static_cast<float>(roll);
        a[2] = static_cast<float>(pitch);
        a[3] = 0;
      }
    }
    return true;
  }

  void step(const float* actions) override {
    const int ad = sim_->action_dim();
    const bool flat = sim_->holds_altitude();
    for (int env = 0; env < num_envs_; ++env) {
      const float* in = actions + static_cast<std::size_t>(env) * kPsActionDim;
      real* a = &sim_actions_[static_cast<std::size_t>(env) * static_cast<std::size_t>(ad)];
      float c[kPsActionDim];
      for (int k = 0; k < kPsActionDim; ++k) c[k] = std::min(kActionClip, std::max(-kActionClip, in[k]));
      for (int k = 0; k < ad && k < kPsActionDim; ++k) a[k] = static_cast<real>(c[k]);
      if (relative_) {
        const real* p = sim_->base_pos_w() + 3 * env;
        for (int k = 0; k < 3; ++k) a[k] = p[k] + static_cast<real>(c[k]);
      }
      // At a held altitude: the setpoint stays on it, and no vertical velocity or acceleration.
      if (flat) a[2] = relative_ ? sim_->altitude_m() : 0;
    }
    sim_->step(sim_actions_.data());
    ++infos_.steps;
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      ++episode_step_[i];
      std::uint8_t crash = crash_or_out(env) ? 1 : 0;
      float q[4], e_w[3], w[3];
      quat_xyzw(env, q);
      error_world(env, e_w);
      for (int k = 0; k < 3; ++k) w[k] = static_cast<float>(sim_->base_ang_vel_b()[3 * i + k]);
      // Only |error| enters the reward: the world-frame error, not the reference's vehicle-frame
      // copy of it (same length; task.hpp).
      const float r = position_setpoint_reward(e_w, q, w, 1.0f, crash, sim_->config().task.reward);  // multiplier 1.0 as the task passes
      rewards_[i] = r;
      terminations_[i] = crash;
      const std::uint8_t trunc = episode_step_[i] >= len_ ? 1 : 0;
      truncations_[i] = trunc;
      episode_reward_[i] += static_cast<double>(r);
      ended_[i] = (crash || trunc) ? 1 : 0;
      if (!ended_[i]) continue;
      ++infos_.episodes;
      // A fallback placement (target = start) hovers: counted apart, never a success.
      const bool fallback = sim_->placement_fallback(env);
      if (fallback) ++infos_.fallback_episodes;
      if (crash) {
        ++infos_.terminations;
        ++infos_.crashes;
      } else {
        ++infos_.truncations;
        // Success as Aerial Gym's evaluation and the scripted harness count it: the episode ran to
        // its time limit and ended within task.success_radius_m of the target (episode.hpp).
        const real d = std::sqrt(static_cast<real>(e_w[0] * e_w[0] + e_w[1] * e_w[1] + e_w[2] * e_w[2]));
        if (!fallback && within_success_radius(d, sim_->config().task.success_radius_m)) ++infos_.successes;
      }
      infos_.episode_reward_sum += episode_reward_[i];
    }
    reset_ended();  // auto-reset: the rows below are the new episodes' first observations
    for (int env = 0; env < num_envs_; ++env) write_obs(env);
  }

 private:
  void on_reset(int) override {}

  // Aerial Gym process_obs_for_task: [target - position, quaternion xyzw, body linvel, body angvel]
  // (policy/observations.hpp: the same builder the firmware uses).
  void write_obs(int env) override {
    const std::size_t i = static_cast<std::size_t>(env);
    policy::position_setpoint_observation(sim_->base_pos_w() + 3 * i, sim_->base_quat_xyzw() + 4 * i,
                                          sim_->base_lin_vel_b() + 3 * i, sim_->base_ang_vel_b() + 3 * i,
                                          sim_->target_w() + 3 * i, &obs_[i * kPsObsDim]);
  }

  ControllerKind kind_ = ControllerKind::lee_position;
  bool relative_ = false;
};

}  // namespace

std::unique_ptr<Task> make_position_setpoint_task(const WorldConfig& config, Backend backend, std::string& error) {
  if (config.task.kind != TaskKind::position_setpoint) {
    error = "position_setpoint_task needs a position_setpoint task kind (per-episode targets)";
    return nullptr;
  }
  if (backend == Backend::planar) {
    const ControllerKind k = config.controller.kind;
    if (k != ControllerKind::lee_position && k != ControllerKind::lee_velocity && k != ControllerKind::lee_acceleration) {
      error = "simulator planar: task position_setpoint_task: controller " + config.controller.name +
              " is not available on the fixed-altitude multirotor; allowed: lee_position_control, lee_velocity_control, "
              "lee_acceleration_control (or use simulator: rigid)";
      return nullptr;
    }
  }
  task_support::TaskNeeds needs;
  needs.id = "position_setpoint_task";
  needs.prefix = "position_setpoint_task ";
  std::unique_ptr<Simulator> s = task_support::make_task_simulator(config, backend, needs, error);
  if (!s) return nullptr;
  return std::unique_ptr<Task>(new PositionSetpointTask(std::move(s)));
}

}  // namespace kestrel::sim
