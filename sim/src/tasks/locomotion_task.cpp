// locomotion_task (see locomotion_task.hpp for what follows legged_gym and what differs).
#include "kestrel/sim/locomotion_task.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>

#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/registry.hpp"
#include "task_support.hpp"

namespace kestrel::sim {

namespace {

constexpr float kClipActions = 100.0f;        // legged_gym's normalization.clip_actions
constexpr float kContactThreshold_N = 1.0f;   // feet_air_time's contact
constexpr float kCollisionThreshold_N = 0.1f; // _reward_collision
constexpr float kPi_f = 3.14159265358979f;

float sq(float v) { return v * v; }

float wrap_to_pi(float a) {
  // legged_gym's wrap_to_pi: a % (2 pi), then minus 2 pi above pi (torch's % has the divisor's sign).
  const float two_pi = 2.0f * kPi_f;
  float m = std::fmod(a, two_pi);
  if (m < 0) m += two_pi;
  return m > kPi_f ? m - two_pi : m;
}

std::string lower(std::string s) {
  for (char& ch : s) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return s;
}

}  // namespace

const char* loco_term_name(int term) {
  static const char* const kNames[kNumLocoTerms] = {
      "tracking_lin_vel", "tracking_ang_vel", "lin_vel_z",    "ang_vel_xy",   "orientation",    "torques",
      "dof_vel",          "dof_acc",          "base_height",  "feet_air_time", "collision",     "feet_stumble",
      "action_rate",      "stand_still",      "dof_pos_limits", "torque_limits", "feet_contact_forces", "termination"};
  return term >= 0 && term < kNumLocoTerms ? kNames[term] : "";
}

real loco_term_scale(const LocomotionRewardScales& s, int term) {
  switch (static_cast<LocoTerm>(term)) {
    case LocoTerm::tracking_lin_vel: return s.tracking_lin_vel;
    case LocoTerm::tracking_ang_vel: return s.tracking_ang_vel;
    case LocoTerm::lin_vel_z: return s.lin_vel_z;
    case LocoTerm::ang_vel_xy: return s.ang_vel_xy;
    case LocoTerm::orientation: return s.orientation;
    case LocoTerm::torques: return s.torques;
    case LocoTerm::dof_vel: return s.dof_vel;
    case LocoTerm::dof_acc: return s.dof_acc;
    case LocoTerm::base_height: return s.base_height;
    case LocoTerm::feet_air_time: return s.feet_air_time;
    case LocoTerm::collision: return s.collision;
    case LocoTerm::feet_stumble: return s.feet_stumble;
    case LocoTerm::action_rate: return s.action_rate;
    case LocoTerm::stand_still: return s.stand_still;
    case LocoTerm::dof_pos_limits: return s.dof_pos_limits;
    case LocoTerm::torque_limits: return s.torque_limits;
    case LocoTerm::feet_contact_forces: return s.feet_contact_forces;
    case LocoTerm::termination: return s.termination;
    case LocoTerm::count: break;
  }
  return 0;
}

void locomotion_reward_terms(const LocoTermInputs& in, const LocomotionConfig& c, float* out) {
  const int nd = in.num_dofs, nf = in.num_feet;
  const float sigma = static_cast<float>(c.tracking_sigma);
  auto at = [out](LocoTerm t) -> float& { return out[static_cast<int>(t)]; };
  at(LocoTerm::tracking_lin_vel) =
      std::exp(-(sq(in.commands[0] - in.lin_vel_b[0]) + sq(in.commands[1] - in.lin_vel_b[1])) / sigma);
  at(LocoTerm::tracking_ang_vel) = std::exp(-sq(in.commands[2] - in.ang_vel_b[2]) / sigma);
  at(LocoTerm::lin_vel_z) = sq(in.lin_vel_b[2]);
  at(LocoTerm::ang_vel_xy) = sq(in.ang_vel_b[0]) + sq(in.ang_vel_b[1]);
  at(LocoTerm::orientation) = sq(in.projected_gravity[0]) + sq(in.projected_gravity[1]);
  float torques = 0, dof_vel = 0, dof_acc = 0, action_rate = 0, still = 0, limits = 0, torque_limits = 0;
  for (int j = 0; j < nd; ++j) {
    torques += sq(in.torques[j]);
    dof_vel += sq(in.dof_vel[j]);
    dof_acc += sq((in.last_dof_vel[j] - in.dof_vel[j]) / in.dt_s);
    action_rate += sq(in.last_actions[j] - in.actions[j]);
    still += std::fabs(in.dof_pos[j] - in.default_dof_pos[j]);
    limits += -std::min(in.dof_pos[j] - in.dof_pos_lower[j], 0.0f) + std::max(in.dof_pos[j] - in.dof_pos_upper[j], 0.0f);
    torque_limits += std::max(std::fabs(in.torques[j]) - in.torque_limits[j], 0.0f);
  }
  at(LocoTerm::torques) = torques;
  at(LocoTerm::dof_vel) = dof_vel;
  at(LocoTerm::dof_acc) = dof_acc;
  at(LocoTerm::base_height) = sq(in.base_height_m - static_cast<float>(c.base_height_target_m));
  const float cmd_xy = std::sqrt(sq(in.commands[0]) + sq(in.commands[1]));
  at(LocoTerm::feet_air_time) = cmd_xy > 0.1f ? in.feet_air_time_sum : 0.0f;  // no reward for zero command
  at(LocoTerm::collision) = static_cast<float>(in.penalized_contacts);
  bool stumble = false;
  float over = 0;
  for (int f = 0; f < nf; ++f) {
    const float* F = in.foot_forces_w + 3 * f;
    const float fxy = std::sqrt(sq(F[0]) + sq(F[1]));
    if (fxy > 5.0f * std::fabs(F[2])) stumble = true;
    over += std::max(std::sqrt(sq(F[0]) + sq(F[1]) + sq(F[2])) - static_cast<float>(c.max_contact_force_N), 0.0f);
  }
  at(LocoTerm::feet_stumble) = stumble ? 1.0f : 0.0f;
  at(LocoTerm::action_rate) = action_rate;
  at(LocoTerm::stand_still) = cmd_xy < 0.1f ? still : 0.0f;
  at(LocoTerm::dof_pos_limits) = limits;
  at(LocoTerm::torque_limits) = torque_limits;
  at(LocoTerm::feet_contact_forces) = over;
  at(LocoTerm::termination) = in.terminated ? 1.0f : 0.0f;
}

float locomotion_total_reward(const float* terms, const float* scaled, bool only_positive) {
  float r = 0;
  const int term = static_cast<int>(LocoTerm::termination);
  for (int k = 0; k < kNumLocoTerms; ++k)
    if (k != term && scaled[k] != 0) r += terms[k] * scaled[k];
  if (only_positive) r = std::max(r, 0.0f);
  if (scaled[term] != 0) r += terms[term] * scaled[term];
  return r;
}

float update_feet_air_time(const float* foot_forces_w, int num_feet, float dt_s, float* air_time, std::uint8_t* last_contact) {
  float sum = 0;
  for (int f = 0; f < num_feet; ++f) {
    const bool contact = foot_forces_w[3 * f + 2] > kContactThreshold_N;
    const bool filt = contact || last_contact[f] != 0;  // PhysX reports foot contacts unreliably on meshes
    last_contact[f] = contact ? 1 : 0;
    const bool first = air_time[f] > 0 && filt;
    air_time[f] += dt_s;
    if (first) sum += air_time[f] - 0.5f;
    if (filt) air_time[f] = 0;
  }
  return sum;
}

float heading_yaw_rate_command(float heading_target_rad, float heading_rad) {
  return std::min(1.0f, std::max(-1.0f, 0.5f * wrap_to_pi(heading_target_rad - heading_rad)));
}

void resample_locomotion_commands(const LocomotionConfig& c, RngStream& rng, float cmd[4]) {
  cmd[0] = static_cast<float>(rng.uniform(c.lin_vel_x_min_m_s, c.lin_vel_x_max_m_s));
  cmd[1] = static_cast<float>(rng.uniform(c.lin_vel_y_min_m_s, c.lin_vel_y_max_m_s));
  if (c.heading_command) cmd[3] = static_cast<float>(rng.uniform(c.heading_min_rad, c.heading_max_rad));
  else cmd[2] = static_cast<float>(rng.uniform(c.ang_vel_yaw_min_rad_s, c.ang_vel_yaw_max_rad_s));
  if (!(std::sqrt(cmd[0] * cmd[0] + cmd[1] * cmd[1]) > 0.2f)) cmd[0] = cmd[1] = 0;  // small commands -> 0
}

int locomotion_obs_dim(int num_dofs, int num_height_points) { return 9 + 3 + 3 * num_dofs + num_height_points; }

namespace {

class LocomotionTask final : public Task {
 public:
  // obs_dim and dofs are read from the Simulator by the caller (an argument list may move `s`
  // before it reads it).
  LocomotionTask(std::unique_ptr<Simulator> s, int obs_dim, int dofs, const LocomotionConfig& c)
      : Task(std::move(s), obs_dim, dofs), c_(c) {
    const Simulator& sim = *sim_;
    nd_ = sim.num_dofs();
    nf_ = sim.num_feet();
    nh_ = sim.num_height_points();
    dt_ = static_cast<float>(sim.dt_s() * static_cast<real>(sim.decimation()));
    const RobotLayout& L = sim.robot_layout();
    const std::size_t n = static_cast<std::size_t>(num_envs_), nd = static_cast<std::size_t>(nd_);
    default_.resize(nd);
    lower_.resize(nd);
    upper_.resize(nd);
    tlim_.resize(nd);
    for (std::size_t j = 0; j < nd; ++j) {
      default_[j] = static_cast<float>(L.default_dof_pos[j]);
      // legged_gym's soft limits: the middle of the range +- half of it x soft_dof_pos_limit.
      const real lo = L.dof_pos_lower[j], hi = L.dof_pos_upper[j];
      if (std::isfinite(lo) && std::isfinite(hi)) {
        const real m = (lo + hi) / 2, r = hi - lo;
        lower_[j] = static_cast<float>(m - 0.5_r * r * c.soft_dof_pos_limit);
        upper_[j] = static_cast<float>(m + 0.5_r * r * c.soft_dof_pos_limit);
      } else {
        lower_[j] = -std::numeric_limits<float>::infinity();
        upper_[j] = std::numeric_limits<float>::infinity();
      }
      tlim_[j] = static_cast<float>(L.torque_limits[j] * c.soft_torque_limit);
    }
    for (std::size_t b = 0; b < L.link_names.size(); ++b) {
      const std::string name = lower(L.link_names[b]);
      for (const std::string& frag : c.penalize_contacts_on)
        if (!frag.empty() && name.find(lower(frag)) != std::string::npos) {
          penalized_.push_back(static_cast<int>(b));
          break;
        }
    }
    for (int k = 0; k < kNumLocoTerms; ++k) scaled_[k] = static_cast<float>(loco_term_scale(c.scales, k)) * dt_;
    const std::size_t od = static_cast<std::size_t>(obs_dim_);
    noise_.assign(od, 0.0f);
    if (c.add_noise) {
      const float lvl = static_cast<float>(c.noise_level);
      for (int k = 0; k < 3; ++k) {
        noise_[static_cast<std::size_t>(k)] = static_cast<float>(c.noise_lin_vel * c.obs_scale_lin_vel) * lvl;
        noise_[static_cast<std::size_t>(3 + k)] = static_cast<float>(c.noise_ang_vel * c.obs_scale_ang_vel) * lvl;
        noise_[static_cast<std::size_t>(6 + k)] = static_cast<float>(c.noise_gravity) * lvl;
      }
      for (std::size_t j = 0; j < nd; ++j) {
        noise_[12 + j] = static_cast<float>(c.noise_dof_pos * c.obs_scale_dof_pos) * lvl;
        noise_[12 + nd + j] = static_cast<float>(c.noise_dof_vel * c.obs_scale_dof_vel) * lvl;
      }
      for (std::size_t k = 12 + 3 * nd; k < od; ++k) noise_[k] = static_cast<float>(c.noise_height * c.obs_scale_height) * lvl;
    }
    resample_steps_ = std::max(1, static_cast<int>(c.resampling_time_s / static_cast<real>(dt_)));
    push_steps_ = std::max(1, static_cast<int>(std::ceil(c.push_interval_s / static_cast<real>(dt_))));
    link_push_steps_ = c.push_links_interval_s > 0 ? std::max(1, static_cast<int>(std::ceil(c.push_links_interval_s / static_cast<real>(dt_)))) : 0;
    curriculum_ = c.terrain_curriculum && sim.num_terrain_levels() > 0;
    if (sim.num_terrain_levels() > 0) {  // the start levels, before any episode has ended
      double sum = 0;
      for (int e = 0; e < num_envs_; ++e) sum += sim.terrain_levels()[e];
      infos_.mean_terrain_level = sum / num_envs_;
    }
    half_tile_m_ = static_cast<float>(sim.config().env.terrain.tile_length_m) / 2;
    episode_s_ = static_cast<float>(len_) * dt_;
    commands_.assign(n * 4, 0.0f);
    actions_.assign(n * nd, 0.0f);
    last_actions_.assign(n * nd, 0.0f);
    last_dof_vel_.assign(n * nd, 0.0f);
    air_time_.assign(n * static_cast<std::size_t>(nf_), 0.0f);
    last_contact_.assign(n * static_cast<std::size_t>(nf_), 0);
    episode_terms_.assign(n * kNumLocoTerms, 0.0);
    term_sums_.assign(kNumLocoTerms, 0.0);
    scratch_.assign(4 * nd + 3 * static_cast<std::size_t>(nf_), 0.0f);
    reset_pos_.assign(nd, 0);
    reset_vel_.assign(nd, 0);
    const std::uint64_t seed = sim.config().seed;
    for (int e = 0; e < num_envs_; ++e) {
      const std::uint32_t g = sim.config().env.global_env(e);
      rng_cmd_.emplace_back(seed, g, kPurposeLocoCommands);
      rng_noise_.emplace_back(seed, g, kPurposeLocoNoise);
      rng_reset_.emplace_back(seed, g, kPurposeLocoReset);
    }
    reset();
  }

  const char* name() const override { return "locomotion_task"; }

  int num_reward_terms() const override { return kNumLocoTerms; }
  const char* reward_term_name(int k) const override { return loco_term_name(k); }
  double reward_term_sum(int k) const override { return k >= 0 && k < kNumLocoTerms ? term_sums_[static_cast<std::size_t>(k)] : 0.0; }

  void step(const float* actions) override {
    const std::size_t nd = static_cast<std::size_t>(nd_);
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      for (std::size_t j = 0; j < nd; ++j) {
        float a = actions[i * nd + j];
        a = a >= -kClipActions && a <= kClipActions ? a : (a > kClipActions ? kClipActions : (a < -kClipActions ? -kClipActions : 0.0f));
        actions_[i * nd + j] = a;
        sim_actions_[i * nd + j] = static_cast<real>(a);
      }
    }
    sim_->step(sim_actions_.data());
    ++infos_.steps;
    ++common_step_;
    const bool push = c_.push_robots && common_step_ % static_cast<std::uint64_t>(push_steps_) == 0;
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      ++episode_step_[i];
      float* cmd = &commands_[i * 4];
      if (episode_step_[i] % resample_steps_ == 0) resample_locomotion_commands(c_, rng_cmd_[i], cmd);
      if (c_.heading_command) cmd[2] = heading_yaw_rate_command(cmd[3], heading(env));
    }
    // legged_gym pushes in _post_physics_step_callback, before the rewards read the velocities.
    if (push) sim_->push_robots();
    // LeggedGym-Ex's push_links: the forces act during the next step's first physics step.
    if (link_push_steps_ > 0 && common_step_ % static_cast<std::uint64_t>(link_push_steps_) == 0) (void)sim_->push_links();
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      const bool crash = sim_->crashed()[i] != 0;
      const bool timeout = episode_step_[i] >= len_;
      float terms[kNumLocoTerms];
      compute_terms(env, crash, terms);
      const float r = locomotion_total_reward(terms, scaled_, c_.only_positive_rewards);
      for (int k = 0; k < kNumLocoTerms; ++k) episode_terms_[i * kNumLocoTerms + static_cast<std::size_t>(k)] += terms[k] * scaled_[k];
      rewards_[i] = r;
      episode_reward_[i] += static_cast<double>(r);
      terminations_[i] = crash ? 1 : 0;
      truncations_[i] = !crash && timeout ? 1 : 0;
      ended_[i] = crash || timeout ? 1 : 0;
      for (std::size_t j = 0; j < nd; ++j) {
        last_actions_[i * nd + j] = actions_[i * nd + j];
        last_dof_vel_[i * nd + j] = static_cast<float>(sim_->dof_vel()[i * nd + j]);
      }
      if (ended_[i]) {
        ++infos_.episodes;
        infos_.episode_reward_sum += episode_reward_[i];
        if (crash) {
          ++infos_.terminations;
          ++infos_.crashes;
        } else {
          ++infos_.truncations;
        }
        for (int k = 0; k < kNumLocoTerms; ++k) term_sums_[static_cast<std::size_t>(k)] += episode_terms_[i * kNumLocoTerms + static_cast<std::size_t>(k)];
      }
    }
    if (curriculum_) update_curriculum();
    reset_ended();
    for (int env = 0; env < num_envs_; ++env) write_obs(env);
  }

  bool scripted_actions(float* actions) const override {
    // Zero actions: every joint held at its home position (legged_gym has no scripted gait).
    std::fill(actions, actions + static_cast<std::size_t>(num_envs_) * static_cast<std::size_t>(nd_), 0.0f);
    return true;
  }

 private:
  /// legged_gym's _update_terrain_curriculum for the environments whose episode ended: up a level
  /// after walking farther than half a tile from the origin, down after walking less than half of
  /// what the command asked over a whole episode (and not up).
  void update_curriculum() {
    const real* p = sim_->base_pos_w();
    const real* o = sim_->env_origins_w();
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      if (!ended_[i]) continue;
      const float dx = static_cast<float>(p[3 * i] - o[3 * i]), dy = static_cast<float>(p[3 * i + 1] - o[3 * i + 1]);
      const float dist = std::sqrt(dx * dx + dy * dy);
      const float* cmd = &commands_[i * 4];
      const std::uint8_t up = dist > half_tile_m_ ? 1 : 0;
      const std::uint8_t down = up == 0 && dist < std::sqrt(cmd[0] * cmd[0] + cmd[1] * cmd[1]) * episode_s_ * 0.5f ? 1 : 0;
      (void)sim_->update_terrain_curriculum(&env, 1, &up, &down);
    }
    double sum = 0;
    for (int env = 0; env < num_envs_; ++env) sum += sim_->terrain_levels()[env];
    infos_.mean_terrain_level = sum / num_envs_;
  }

  float heading(int env) const {
    const real* q = sim_->base_quat_xyzw() + 4 * static_cast<std::size_t>(env);
    const Vec3 fwd = rotate(quat_from_xyzw(q), Vec3::UnitX());
    return static_cast<float>(std::atan2(fwd[1], fwd[0]));
  }

  void projected_gravity(int env, float g[3]) const {
    const real* q = sim_->base_quat_xyzw() + 4 * static_cast<std::size_t>(env);
    const Vec3 gb = rotate_inverse(quat_from_xyzw(q), Vec3(0, 0, -1));
    for (int k = 0; k < 3; ++k) g[k] = static_cast<float>(gb[k]);
  }

  /// Base z over the terrain: the mean of the measured heights (legged_gym's base_height), or the
  /// environment origin's height without height points.
  float base_height(int env) const {
    const std::size_t i = static_cast<std::size_t>(env);
    const real z = sim_->base_pos_w()[3 * i + 2];
    real ground = sim_->target_w()[3 * i + 2];
    if (nh_ > 0) {
      const real* h = sim_->measured_heights() + i * static_cast<std::size_t>(nh_);
      real s = 0;
      for (int k = 0; k < nh_; ++k) s += h[k];
      ground = s / static_cast<real>(nh_);
    }
    return static_cast<float>(z - ground);
  }

  void compute_terms(int env, bool crash, float* terms) {
    const std::size_t i = static_cast<std::size_t>(env), nd = static_cast<std::size_t>(nd_), nf = static_cast<std::size_t>(nf_);
    float* q = scratch_.data();
    float* qd = q + nd;
    float* tau = qd + nd;
    float* feet = tau + nd;
    const real* dp = sim_->dof_pos() + i * nd;
    const real* dv = sim_->dof_vel() + i * nd;
    const real* tq = sim_->torques() + i * nd;
    for (std::size_t j = 0; j < nd; ++j) {
      q[j] = static_cast<float>(dp[j]);
      qd[j] = static_cast<float>(dv[j]);
      tau[j] = static_cast<float>(tq[j]);
    }
    const RobotLayout& L = sim_->robot_layout();
    const std::size_t links = static_cast<std::size_t>(sim_->num_links());
    const real* lf = sim_->link_contact_forces_w() + i * links * 3;
    for (std::size_t f = 0; f < nf; ++f)
      for (int c = 0; c < 3; ++c) feet[3 * f + static_cast<std::size_t>(c)] = static_cast<float>(lf[3 * static_cast<std::size_t>(L.foot_links[f]) + static_cast<std::size_t>(c)]);
    int penalized = 0;
    for (int b : penalized_) {
      const real* F = lf + 3 * static_cast<std::size_t>(b);
      if (std::sqrt(F[0] * F[0] + F[1] * F[1] + F[2] * F[2]) > static_cast<real>(kCollisionThreshold_N)) ++penalized;
    }
    LocoTermInputs in;
    in.num_dofs = nd_;
    in.num_feet = nf_;
    in.dt_s = dt_;
    for (int k = 0; k < 3; ++k) {
      in.commands[k] = commands_[i * 4 + static_cast<std::size_t>(k)];
      in.lin_vel_b[k] = static_cast<float>(sim_->base_lin_vel_b()[3 * i + static_cast<std::size_t>(k)]);
      in.ang_vel_b[k] = static_cast<float>(sim_->base_ang_vel_b()[3 * i + static_cast<std::size_t>(k)]);
    }
    projected_gravity(env, in.projected_gravity);
    in.base_height_m = base_height(env);
    in.dof_pos = q;
    in.dof_vel = qd;
    in.last_dof_vel = &last_dof_vel_[i * nd];
    in.default_dof_pos = default_.data();
    in.dof_pos_lower = lower_.data();
    in.dof_pos_upper = upper_.data();
    in.torques = tau;
    in.torque_limits = tlim_.data();
    in.actions = &actions_[i * nd];
    in.last_actions = &last_actions_[i * nd];
    in.foot_forces_w = feet;
    in.feet_air_time_sum = update_feet_air_time(feet, nf_, dt_, &air_time_[i * nf], &last_contact_[i * nf]);
    in.penalized_contacts = penalized;
    in.terminated = crash;
    locomotion_reward_terms(in, c_, terms);
  }

  void on_reset(int env) override {
    const std::size_t i = static_cast<std::size_t>(env), nd = static_cast<std::size_t>(nd_), nf = static_cast<std::size_t>(nf_);
    RngStream& rng = rng_reset_[i];
    // legged_gym's _reset_dofs: home x U(0.5, 1.5), at rest; _reset_root_states: base velocities
    // U(-0.5, 0.5) per component (world frame). The draws are made whatever the values.
    for (std::size_t j = 0; j < nd; ++j) {
      reset_pos_[j] = static_cast<real>(default_[j]) * rng.uniform(c_.reset_dof_pos_scale_min, c_.reset_dof_pos_scale_max);
      reset_vel_[j] = 0;
    }
    real vel[6];
    for (real& v : vel) v = rng.uniform(-c_.reset_base_vel_max, c_.reset_base_vel_max);
    (void)sim_->reset_dofs(&env, 1, reset_pos_.data(), reset_vel_.data());
    if (c_.reset_base_vel_max > 0) {
      real pos[3], quat[4];
      for (int k = 0; k < 3; ++k) pos[k] = sim_->base_pos_w()[3 * i + static_cast<std::size_t>(k)];
      for (int k = 0; k < 4; ++k) quat[k] = sim_->base_quat_xyzw()[4 * i + static_cast<std::size_t>(k)];
      (void)sim_->reset_root_states(&env, 1, pos, quat, vel, vel + 3);
    }
    resample_locomotion_commands(c_, rng_cmd_[i], &commands_[i * 4]);
    if (c_.heading_command) commands_[i * 4 + 2] = heading_yaw_rate_command(commands_[i * 4 + 3], heading(env));
    for (std::size_t j = 0; j < nd; ++j) actions_[i * nd + j] = last_actions_[i * nd + j] = last_dof_vel_[i * nd + j] = 0;
    for (std::size_t f = 0; f < nf; ++f) {
      air_time_[i * nf + f] = 0;
      last_contact_[i * nf + f] = 0;
    }
    for (int k = 0; k < kNumLocoTerms; ++k) episode_terms_[i * kNumLocoTerms + static_cast<std::size_t>(k)] = 0;
  }

  void write_obs(int env) override {
    const std::size_t i = static_cast<std::size_t>(env), nd = static_cast<std::size_t>(nd_);
    float* o = &obs_[i * static_cast<std::size_t>(obs_dim_)];
    const float sl = static_cast<float>(c_.obs_scale_lin_vel), sa = static_cast<float>(c_.obs_scale_ang_vel);
    for (int k = 0; k < 3; ++k) {
      o[k] = static_cast<float>(sim_->base_lin_vel_b()[3 * i + static_cast<std::size_t>(k)]) * sl;
      o[3 + k] = static_cast<float>(sim_->base_ang_vel_b()[3 * i + static_cast<std::size_t>(k)]) * sa;
    }
    projected_gravity(env, o + 6);
    o[9] = commands_[i * 4] * sl;
    o[10] = commands_[i * 4 + 1] * sl;
    o[11] = commands_[i * 4 + 2] * sa;
    const float sp = static_cast<float>(c_.obs_scale_dof_pos), sv = static_cast<float>(c_.obs_scale_dof_vel);
    for (std::size_t j = 0; j < nd; ++j) {
      o[12 + j] = (static_cast<float>(sim_->dof_pos()[i * nd + j]) - default_[j]) * sp;
      o[12 + nd + j] = static_cast<float>(sim_->dof_vel()[i * nd + j]) * sv;
      o[12 + 2 * nd + j] = actions_[i * nd + j];
    }
    if (nh_ > 0) {
      const real z = sim_->base_pos_w()[3 * i + 2];
      const real* h = sim_->measured_heights() + i * static_cast<std::size_t>(nh_);
      const float sh = static_cast<float>(c_.obs_scale_height);
      for (int k = 0; k < nh_; ++k)
        o[12 + 3 * nd + static_cast<std::size_t>(k)] = std::min(1.0f, std::max(-1.0f, static_cast<float>(z - 0.5_r - h[k]))) * sh;
    }
    const float clip = static_cast<float>(c_.clip_observations);
    RngStream& rng = rng_noise_[i];
    for (int k = 0; k < obs_dim_; ++k) {
      const std::size_t kk = static_cast<std::size_t>(k);
      if (c_.add_noise && noise_[kk] != 0) o[k] += (2.0f * static_cast<float>(rng.uniform()) - 1.0f) * noise_[kk];
      o[k] = std::min(clip, std::max(-clip, o[k]));
    }
  }

  LocomotionConfig c_;
  int nd_ = 0, nf_ = 0, nh_ = 0;
  float dt_ = 0.02f;
  int resample_steps_ = 500, push_steps_ = 750, link_push_steps_ = 0;
  bool curriculum_ = false;        // terrain curriculum on (task.locomotion.terrain_curriculum and a tiled terrain)
  float half_tile_m_ = 4, episode_s_ = 20;
  std::uint64_t common_step_ = 0;
  std::vector<float> default_, lower_, upper_, tlim_, noise_;
  std::vector<int> penalized_;
  float scaled_[kNumLocoTerms] = {};
  std::vector<float> commands_, actions_, last_actions_, last_dof_vel_, air_time_, scratch_;
  std::vector<std::uint8_t> last_contact_;
  std::vector<double> episode_terms_, term_sums_;
  std::vector<real> reset_pos_, reset_vel_;
  std::vector<RngStream> rng_cmd_, rng_noise_, rng_reset_;
};

}  // namespace

std::unique_ptr<Task> make_locomotion_task(const WorldConfig& config, Backend backend, std::string& error) {
  const std::string pre = "locomotion_task: ";
  if (backend != Backend::rigid) {
    error = pre + "needs the rigid backend (articulated robots); got " + backend_name(backend);
    return nullptr;
  }
  if (config.robot.kind != robots::RobotKind::articulated) {
    error = pre + "needs an articulated robot (robot: go2 or anymal_c, or a robot with robot.model); got " + config.robot.name;
    return nullptr;
  }
  const LocomotionConfig& c = config.task.locomotion;
  if (!(c.resampling_time_s > 0) || !(c.push_interval_s > 0) || !(c.tracking_sigma > 0) ||
      !(c.lin_vel_x_min_m_s <= c.lin_vel_x_max_m_s) || !(c.lin_vel_y_min_m_s <= c.lin_vel_y_max_m_s) ||
      !(c.ang_vel_yaw_min_rad_s <= c.ang_vel_yaw_max_rad_s) || !(c.heading_min_rad <= c.heading_max_rad) ||
      !(c.reset_dof_pos_scale_min <= c.reset_dof_pos_scale_max)) {
    error = pre + "task.locomotion: expected resampling_time_s, push_interval_s and tracking_sigma > 0 and every min <= its max";
    return nullptr;
  }
  WorldConfig wc = config;
  wc.robot.sensors.clear();
  std::unique_ptr<Simulator> s = make_simulator(wc, backend, error);
  if (!s) return nullptr;
  if (s->num_dofs() == 0) {
    error = pre + "the robot " + config.robot.name + " has no driven joint";
    return nullptr;
  }
  const int dofs = s->num_dofs(), obs_dim = locomotion_obs_dim(dofs, s->num_height_points());
  return std::unique_ptr<Task>(new LocomotionTask(std::move(s), obs_dim, dofs, c));
}

TaskConfig locomotion_task_config() {
  TaskConfig t;
  t.name = "locomotion_task";
  t.kind = TaskKind::hover;
  t.episode_len_env_steps = 1000;  // legged_gym's episode_length_s 20 at dt 0.005 x decimation 4
  return t;
}

void register_locomotion_builtins(Registries& r) {
  r.tasks.add("locomotion_task",
              "legged_gym's locomotion RL task: joint targets, velocity commands, 48 obs (+ height points), legged_gym's "
              "reward terms, base-contact termination, pushes",
              [] { return locomotion_task_config(); });
  // locomotion_task with each robot's reward configuration (scenario `task: locomotion_go2`, the
  // gymnasium ids Kestrel-Go2-*-v0 / Kestrel-AnymalC-*-v0).
  r.tasks.add("locomotion_go2",
              "locomotion_task with LeggedGym-Ex's Go2 rewards (go2_config.py; its action_smoothness and foot_clearance "
              "terms are not legged_gym's and are left out) over legged_gym's command ranges",
              [] {
                TaskConfig t = locomotion_task_config();
                LocomotionConfig& l = t.locomotion;
                l.soft_dof_pos_limit = 0.9_r;
                l.base_height_target_m = 0.36_r;
                LocomotionRewardScales& s = l.scales;
                s.dof_pos_limits = -1;
                s.collision = -1;
                s.tracking_lin_vel = 1;
                s.tracking_ang_vel = 0.5_r;
                s.lin_vel_z = -0.5_r;
                s.base_height = -2;
                s.ang_vel_xy = -0.05_r;
                s.orientation = -1;
                s.dof_vel = -5e-4_r;
                s.dof_acc = -2e-7_r;
                s.action_rate = -0.01_r;
                s.torques = -2e-4_r;
                s.feet_air_time = 1;
                return t;
              });
  r.tasks.add("locomotion_anymal_c_rough", "locomotion_task with legged_gym's anymal_c_rough_config rewards", [] {
    TaskConfig t = locomotion_task_config();
    t.locomotion.base_height_target_m = 0.5_r;
    t.locomotion.max_contact_force_N = 500;
    return t;
  });
  r.tasks.add("locomotion_anymal_c_flat",
              "locomotion_task with legged_gym's anymal_c_flat_config: rewards, no heading command, yaw rate +-1.5 rad/s "
              "resampled every 4 s",
              [] {
                TaskConfig t = locomotion_task_config();
                LocomotionConfig& l = t.locomotion;
                l.base_height_target_m = 0.5_r;
                l.max_contact_force_N = 350;
                l.heading_command = false;
                l.resampling_time_s = 4;
                l.ang_vel_yaw_min_rad_s = -1.5_r;
                l.ang_vel_yaw_max_rad_s = 1.5_r;
                l.scales.orientation = -5;
                l.scales.torques = -2.5e-5_r;
                l.scales.feet_air_time = 2;
                return t;
              });
  // legged_gym's dt 5 ms with 10 constraint-solver sweeps at most (PhysX there: 4 position
  // iterations). A jittering random policy on Go2: 34k env-steps/s on 2 threads against 13k at the
  // default 60 sweeps, with the same falls and mean base speed (warm-started rows converge in a
  // few sweeps; the cap only cuts the rest short).
  r.sims.add("legged_sim", "dt 0.005 s, 10 constraint-solver sweeps (articulated robots)", [] {
    SimParams s;
    s.name = "legged_sim";
    s.dt_s = 0.005_r;
    s.solver_iterations = 10;
    return s;
  });
  // legged_gym's ground for locomotion_task: dt 5 ms (legged_sim) x decimation 4 = a 50 Hz policy.
  r.envs.add("legged_flat", "legged_gym's flat ground: plane, decimation 4 (50 Hz policy at fast_sim's 5 ms)", [] {
    EnvConfig e;
    e.name = "legged_flat";
    e.num_physics_steps_per_env_step_mean = 4;
    return e;
  });
  // legged_gym's rough terrain (terrain.py with LeggedRobotCfg.terrain: curriculum over 10 levels x
  // 20 types of 8 m x 8 m tiles in a 25 m border, start levels up to 5, the 187 height points).
  r.envs.add("legged_rough",
             "legged_gym's rough terrain: 10 levels x 20 types of 8 m tiles (slopes, rough slopes, stairs up/down, discrete "
             "obstacles) with the terrain curriculum, decimation 4, the 187 height points",
             [] {
               EnvConfig e;
               e.name = "legged_rough";
               e.num_physics_steps_per_env_step_mean = 4;
               e.terrain.type = TerrainType::heightfield;
               e.terrain.procedural = "curriculum";
               e.terrain.horizontal_scale_m = 0.1_r;
               e.terrain.measure_heights = true;
               return e;
             });
}

TaskDefaults locomotion_task_defaults() {
  TaskDefaults d;
  d.sim = "legged_sim";
  d.env = "legged_flat";
  d.robot = "go2";
  d.controller = "lee_position_control";  // not read: the robot's joint PD drives it
  return d;
}

}  // namespace kestrel::sim
