// Task base and position_setpoint_task (see task.hpp for the API and the reference it follows).
#include "kestrel/policy/observations.hpp"
#include "kestrel/sim/episode.hpp"
#include "kestrel/sim/task.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/custom_task.hpp"
#include "kestrel/sim/navigation_task.hpp"
#include "kestrel/sim/simulator.hpp"
#include "tasks/task_access.hpp"

namespace kestrel::sim {

Task::~Task() = default;

void Task::reset() {
  for (int env = 0; env < num_envs_; ++env) reset_one(env);
}

void Task::reset_idx(const int* env_ids, int count) {
  for (int k = 0; k < count; ++k)
    if (env_ids[k] >= 0 && env_ids[k] < num_envs_) reset_one(env_ids[k]);
}

Task::Task(std::unique_ptr<World> world, int obs_dim, int action_dim)
    : world_(std::move(world)), num_envs_(world_->num_envs()), obs_dim_(obs_dim), action_dim_(action_dim) {
  const std::size_t n = static_cast<std::size_t>(num_envs_);
  obs_.assign(n * static_cast<std::size_t>(obs_dim_), 0.0f);
  rewards_.assign(n, 0.0f);
  terminations_.assign(n, 0);
  truncations_.assign(n, 0);
}

Task::Task(std::unique_ptr<Simulator> sim, int obs_dim, int action_dim)
    : sim_(std::move(sim)), num_envs_(sim_->num_envs()), obs_dim_(obs_dim), action_dim_(action_dim) {
  const std::size_t n = static_cast<std::size_t>(num_envs_);
  obs_.assign(n * static_cast<std::size_t>(obs_dim_), 0.0f);
  rewards_.assign(n, 0.0f);
  terminations_.assign(n, 0);
  truncations_.assign(n, 0);
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

const char* Task::backend_name() const { return sim_ ? sim_->backend_name() : "rigid"; }
int Task::num_threads() const { return sim_ ? sim_->num_threads() : world_->num_threads(); }
std::uint64_t Task::state_hash() const { return sim_ ? sim_->state_hash() : world_->state_hash(); }

// The arithmetic below follows the reference's float32 TorchScript expression order
// (position_setpoint_task.py compute_reward / exp_func, utils/math.py quat_rotate), built with
// -ffp-contract=off so no fused multiply-add changes a rounding.
float position_setpoint_reward(const float e[3], const float q[4], const float w[3], float multiplier,
                               std::uint8_t& crash) {
  const float d = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
  // exp_func(x, gain, exp) = gain * exp(-exp * x * x)
  const float pos = 3.0f * std::exp(-8.0f * d * d) + 2.0f * std::exp(-4.0f * d * d);
  const float dist = (20.0f - d) / 40.0f;
  // quat_axis(q, 2)[2] via quat_rotate(q, e_z): a + b + c with a = v (2 w^2 - 1),
  // b = 2 w (q_vec x v) (zero z component for v = e_z), c = 2 q_vec (q_vec . v).
  const float qw = q[3];
  const float up_z = (2.0f * qw * qw - 1.0f) + 0.0f + q[2] * q[2] * 2.0f;
  const float tilt = std::fabs(1.0f - up_z);
  const float up = 0.2f / (0.1f + tilt * tilt);
  const float s = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
  const float spin = 3.0f / (1.0f + s * s);
  float reward = multiplier * (pos + dist + pos * (up + spin));
  if (d > 8.0f) crash = 1;  // in place; an existing crash stays
  if (crash > 0) reward = -20.0f;
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

namespace {

constexpr int kPsObsDim = policy::kPositionSetpointObsDim;
constexpr int kPsActionDim = 4;
constexpr float kActionClip = 10.0f;  // Aerial Gym robot: actions clipped to +-10 (quirk 7)

class PositionSetpointTask final : public Task {
 public:
  explicit PositionSetpointTask(std::unique_ptr<World> w)
      : Task(std::move(w), kPsObsDim, kPsActionDim), episode_reward_(static_cast<std::size_t>(num_envs_), 0.0) {
    // The task decides when an episode ends (its d > 8 m rule is not the World's), so the World
    // only flags; the reward must see the state before the reset.
    world_->set_auto_reset(false);
    relative_ = world_->config().controller.kind == ControllerKind::lee_position;
    len_ = world_->config().task.episode_len_env_steps;
    reset();
  }

  const char* name() const override { return "position_setpoint_task"; }

  // Fly to the target: lee_position_control gets the observed error as its (relative) setpoint;
  // lee_velocity_control a velocity along the error (gain 1 /s, at most 2 m/s); lee_attitude_control
  // (Aerial Gym's shipped controller for this task) a PD acceleration turned into collective
  // thrust and roll/pitch as that controller reads them (fz = (a0 + 1) m |g|, R_d = Euler(roll,
  // pitch, current yaw), see golden/README.md). Direct motor commands have none.
  bool scripted_actions(float* actions) const override {
    const ControllerKind kind = world_->config().controller.kind;
    if (kind != ControllerKind::lee_position && kind != ControllerKind::lee_velocity && kind != ControllerKind::lee_attitude)
      return false;
    const real g = world_->config().sim.gravity_w.norm();
    for (int env = 0; env < num_envs_; ++env) {
      const float* o = &obs_[static_cast<std::size_t>(env) * kPsObsDim];
      float* a = actions + static_cast<std::size_t>(env) * kPsActionDim;
      const task_access::RobotView r = task_access::robot(*world_, env);
      const Vec3 e_w(o[0], o[1], o[2]);
      if (kind == ControllerKind::lee_position) {
        for (int k = 0; k < 3; ++k) a[k] = o[k];
        a[3] = static_cast<float>(task_access::yaw_of(r.orientation_wb));  // absolute yaw: keep it
      } else if (kind == ControllerKind::lee_velocity) {
        Vec3 v = task_access::world_to_vehicle(r.orientation_wb, e_w);
        if (v.norm() > 2) v *= 2 / v.norm();
        for (int k = 0; k < 3; ++k) a[k] = static_cast<float>(v[k]);
        a[3] = 0;
      } else {
        // a_des = kp e - kd v (kp 2 /s^2, kd 2.5 /s: damped), horizontal part capped at 3 m/s^2.
        Vec3 acc = 2 * e_w - 2.5_r * r.linvel_w;
        const real h = std::sqrt(acc[0] * acc[0] + acc[1] * acc[1]);
        if (h > 3) {
          acc[0] *= 3 / h;
          acc[1] *= 3 / h;
        }
        acc[2] = std::max(-0.5_r * g, std::min(0.5_r * g, acc[2]));
        const Vec3 acc_v = task_access::world_to_vehicle(r.orientation_wb, acc);
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
    for (int env = 0; env < num_envs_; ++env) {
      const float* in = actions + static_cast<std::size_t>(env) * kPsActionDim;
      real* a = world_->action(env, 0);
      float c[kPsActionDim];
      for (int k = 0; k < kPsActionDim; ++k) c[k] = std::min(kActionClip, std::max(-kActionClip, in[k]));
      if (relative_) {
        const Vec3& p = world_->robot_state(env, 0).position_w;
        for (int k = 0; k < 3; ++k) a[k] = p[k] + static_cast<real>(c[k]);
        a[3] = static_cast<real>(c[3]);
      } else {
        for (int k = 0; k < kPsActionDim; ++k) a[k] = static_cast<real>(c[k]);
      }
    }
    world_->step(1);
    ++infos_.steps;
    for (int env = 0; env < num_envs_; ++env) {
      const RigidBodyState& st = world_->robot_state(env, 0);
      Vec3 lo, hi;
      world_->lower_upper_bounds(env, lo, hi);
      const bool out = out_of_bounds(st.position_w, lo, hi);
      std::uint8_t crash = (world_->crashed(env, 0) || out) ? 1 : 0;
      float q[4], e_w[3], e_v[3], w[3];
      state_inputs(env, q, e_w, w);
      vehicle_frame_error(q, e_w, e_v);
      const float r = position_setpoint_reward(e_v, q, w, 1.0f, crash);  // multiplier 1.0 as the task passes
      rewards_[static_cast<std::size_t>(env)] = r;
      terminations_[static_cast<std::size_t>(env)] = crash;
      const std::uint8_t trunc = world_->episode_step(env) >= len_ ? 1 : 0;
      truncations_[static_cast<std::size_t>(env)] = trunc;
      episode_reward_[static_cast<std::size_t>(env)] += static_cast<double>(r);
      if (crash || trunc) {
        ++infos_.episodes;
        if (crash) {
          ++infos_.terminations;
          ++infos_.crashes;
        } else {
          ++infos_.truncations;
        }
        infos_.episode_reward_sum += episode_reward_[static_cast<std::size_t>(env)];
        episode_reward_[static_cast<std::size_t>(env)] = 0;
        keep_final_obs(env);
        world_->reset_env(env);  // auto-reset: the row below is the new episode's first observation
      }
      write_obs(env);
    }
  }

 private:
  void reset_one(int env) override {
    world_->reset_env(env);
    const std::size_t i = static_cast<std::size_t>(env);
    rewards_[i] = 0;
    terminations_[i] = 0;
    truncations_[i] = 0;
    episode_reward_[i] = 0;
    write_obs(env);
  }

  void state_inputs(int env, float q[4], float e_w[3], float w[3]) const {
    const RigidBodyState& st = world_->robot_state(env, 0);
    const Vec3 e = world_->target(env, 0) - st.position_w;
    const auto& qc = st.orientation_wb.coeffs();  // Eigen stores xyzw
    for (int k = 0; k < 4; ++k) q[k] = static_cast<float>(qc[k]);
    for (int k = 0; k < 3; ++k) e_w[k] = static_cast<float>(e[k]);
    for (int k = 0; k < 3; ++k) w[k] = static_cast<float>(st.angvel_b[k]);
  }

  // Aerial Gym process_obs_for_task: [target - position, quaternion xyzw, body linvel, body angvel].
  // (policy/observations.hpp: the same builder the firmware uses.)
  void write_obs(int env) override {
    policy::position_setpoint_observation(world_->robot_state(env, 0), world_->target(env, 0),
                                          &obs_[static_cast<std::size_t>(env) * kPsObsDim]);
  }

  std::vector<double> episode_reward_;
  bool relative_ = false;
  int len_ = 0;
};

}  // namespace

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

void min_pool_ranges(const real* ranges, int height, int width, real max_range_m, int rows, int cols, float* out) {
  for (int i = 0; i < rows; ++i) {
    const int r0 = i * height / rows, r1 = (i + 1) * height / rows;
    for (int j = 0; j < cols; ++j) {
      const int c0 = j * width / cols, c1 = (j + 1) * width / cols;
      real m = max_range_m;
      for (int r = r0; r < r1; ++r)
        for (int c = c0; c < c1; ++c) {
          const real v = ranges[static_cast<std::size_t>(r) * static_cast<std::size_t>(width) + static_cast<std::size_t>(c)];
          if (v >= 0 && v < m) m = v;  // false for NaN: no return
        }
      out[i * cols + j] = static_cast<float>(max_range_m > 0 ? std::min(1.0_r, m / max_range_m) : 1.0_r);
    }
  }
}

std::vector<std::string> rl_task_ids() {
  std::vector<std::string> ids = {"navigation_task", "position_setpoint_task"};
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
  return task_name == "position_setpoint_task" || task_name == "navigation_task" || custom_tasks().has(task_name);
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
  CustomTaskSpec spec;
  if (!custom_tasks().make(task_name, spec)) return false;
  out = spec.defaults;
  return true;
}

std::unique_ptr<Task> make_position_setpoint_task(const WorldConfig& config, std::string& error) {
  if (config.robot.robots_per_env != 1) {
    error = "position_setpoint_task needs robots_per_env = 1";
    return nullptr;
  }
  if (config.task.kind != TaskKind::position_setpoint) {
    error = "position_setpoint_task needs a position_setpoint task kind (per-episode targets)";
    return nullptr;
  }
  std::unique_ptr<World> w = World::create(config, error);
  if (!w) return nullptr;
  return std::unique_ptr<Task>(new PositionSetpointTask(std::move(w)));
}

std::unique_ptr<Task> make_task(const WorldConfig& config, std::string& error) {
  const std::string& id = config.task.name;
  if (id == "position_setpoint_task") return make_position_setpoint_task(config, error);
  if (id == "navigation_task") return make_navigation_task(config, NavigationParams(), error);
  if (custom_tasks().has(id)) return make_custom_task(config, error);
  error = "unknown task '" + id + "'; registered task ids: " + rl_task_ids_joined();
  return nullptr;
}

std::unique_ptr<Task> make_planar_task(const WorldConfig& config, std::string& error);  // tasks/planar_tasks.cpp

std::unique_ptr<Task> make_task(const WorldConfig& config, Backend backend, std::string& error) {
  return backend == Backend::planar ? make_planar_task(config, error) : make_task(config, error);
}

}  // namespace kestrel::sim
