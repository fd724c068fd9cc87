// so101_pick_place (see sim/pick_place_task.hpp for the observations, actions, reward and the
// design: a Task over its own small Simulator of PickPlaceWorlds).
#include "kestrel/sim/pick_place_task.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/aligned_scratch.hpp"
#include "kestrel/sim/schema.hpp"
#include "kestrel/sim/state_hash.hpp"
#include "kestrel/sim/summary.hpp"
#include "kestrel/sim/thread_pool.hpp"

namespace kestrel::sim {

namespace {

constexpr int kJ = PickPlaceWorld::kJoints;
// ee_delta: the tool-centre-point target stays in this box (m, world): above the table, within reach.
constexpr real kEeMinZ_m = 0.0_r, kEeMaxZ_m = 0.45_r, kEeMaxXY_m = 0.5_r;

float clipf(float v, float lo, float hi) { return v < lo ? lo : (v > hi ? hi : v); }

// The Simulator the task runs on: N PickPlaceWorlds (one per environment) stepped in a thread
// pool; action = the six joint targets per environment; views = the arm's joints and the tool
// centre point (base_pos_w / base_quat_xyzw). Not a backend of make_simulator: only the task
// builds it.
class PickPlaceSimulator final : public Simulator {
 public:
  PickPlaceSimulator() : Simulator(Backend::rigid) {}

  bool init(const WorldConfig& config, std::string& error) {
    WorldConfig c = config;
    c.robot.robots_per_env = 1;
    // The arm is an articulated robot (so rigid_world() and the callers that look for a World
    // see none here); the robot section of the scenario is not read.
    c.robot.kind = robots::RobotKind::articulated;
    c.robot.name = "so101";
    c.robot.model_file = c.task.pick_place.robot_file.empty() ? models_dir() + "/so101/so101.xml" : c.task.pick_place.robot_file;
    c.robot.sensors.clear();
    c.sim.dt_s = c.task.pick_place.dt_s;
    allocate_views(c, kJ, 0);
    decimation_ = c.task.pick_place.decimation;
    const PickPlaceConfig pc = pick_place_world_config(c.task.pick_place);
    const std::size_t n = static_cast<std::size_t>(num_envs_);
    worlds_.reserve(n);
    for (int e = 0; e < num_envs_; ++e) {
      worlds_.push_back(std::make_unique<PickPlaceWorld>());
      if (!worlds_.back()->init(pc, c.seed, c.env.global_env(e), error)) return false;
    }
    num_dofs_ = kJ;
    num_links_ = 0;
    dof_pos_.assign(n * kJ, 0);
    dof_vel_.assign(n * kJ, 0);
    torques_.assign(n * kJ, 0);
    dr_kp_scale_.assign(n, 1);
    dr_kd_scale_.assign(n, 1);
    dr_armature_.assign(n * kJ, 0);
    const PickPlaceWorld& w0 = *worlds_[0];
    static const char* const kNames[kJ] = {"shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex", "wrist_roll", "gripper"};
    for (int j = 0; j < kJ; ++j) {
      layout_.dof_names.push_back(kNames[j]);
      layout_.default_dof_pos.push_back(w0.home()[j]);
      layout_.dof_pos_lower.push_back(w0.joint_lower()[j]);
      layout_.dof_pos_upper.push_back(w0.joint_upper()[j]);
      layout_.torque_limits.push_back(std::numeric_limits<real>::infinity());
    }
    stats_.assign(n, EnvStats());
    step_errors_.assign(n, 0);
    episode_step_.assign(n, 0);
    const int threads = std::max(1, std::min(c.num_threads, num_envs_));
    pool_ = std::make_unique<ThreadPool>(threads);
    // KESTREL_LEGGED_BATCH=off steps every world alone, as it keeps the legged robots on the
    // scalar step (the same bits; for A/B runs).
    const char* batch_env = std::getenv("KESTREL_LEGGED_BATCH");
    const bool batch_off = batch_env != nullptr && std::strcmp(batch_env, "off") == 0;
    lanes_ = batch_off ? 0 : std::min(w0.batch_lanes(), 64);
    if (lanes_ > 0)  // one batch scratch per worker
      scratch_.assign(static_cast<std::size_t>(threads), AlignedScratch(PickPlaceWorld::batch_scratch_bytes()));
    for (int e = 0; e < num_envs_; ++e) refresh(e);
    return true;
  }

  PickPlaceWorld& world(int env) { return *worlds_[static_cast<std::size_t>(env)]; }
  /// The views of env after its world was changed from outside a step (an object moved).
  void refresh_env(int env) { refresh(env); }
  const PickPlaceWorld& world(int env) const { return *worlds_[static_cast<std::size_t>(env)]; }

  /// Runs fn(ctx, env) for every environment, slices of environments on the pool's workers.
  void for_each_env(void (*fn)(void*, int), void* ctx) const {
    Job job{fn, ctx, num_envs_, pool_->size()};
    pool_->run(&PickPlaceSimulator::run_job, &job);
  }

  /// The task's episode bookkeeping (the summary `kestrel run` prints).
  void record_episode(int env, bool success) {
    EnvStats& st = stats_[static_cast<std::size_t>(env)];
    ++st.episodes_done;
    if (success) ++st.successes;
    else ++st.timeouts;
  }

  int num_threads() const override { return pool_->size(); }
  const char* controller_name() const override { return "so101_servo_pd"; }

  void post_physics_step() override {
    for (int e = 0; e < num_envs_; ++e) {
      const std::size_t i = static_cast<std::size_t>(e);
      ++stats_[i].env_steps;
      ++episode_step_[i];
      refresh(e);
      const bool timeout = episode_step_[i] >= cfg_.task.episode_len_env_steps;
      reset_buf_[i] = timeout ? 1 : 0;
      if (timeout && auto_reset_) {
        record_episode(e, false);
        reset_env(e);
      }
    }
  }

  void reset_idx(const int* env_ids, int count) override {
    for (int k = 0; k < count; ++k)
      if (env_ids[k] >= 0 && env_ids[k] < num_envs_) reset_env(env_ids[k]);
  }

  void update_sensors() override {}
  void set_auto_reset(bool on) override { auto_reset_ = on; }
  void set_curriculum_level(real level) override { (void)level; }
  void env_bounds(int env, Vec3& lower_w, Vec3& upper_w) const override {
    (void)env;
    lower_w = Vec3(-0.5_r, -0.5_r, 0);
    upper_w = Vec3(0.5_r, 0.5_r, 0.5_r);
  }
  RangeImage range_image(int robot, int k) const override {
    (void)robot, (void)k;
    return RangeImage{};
  }
  bool set_obstacle_boxes(int env, const ObstacleBox* boxes, int count) override {
    (void)env, (void)boxes, (void)count;
    return fail("simulator so101_pick_place: set_obstacle_boxes: the scene's objects are the task's (cube, box)");
  }
  WorldSummary summary() const override {
    WorldSummary s;
    for (const EnvStats& e : stats_) add_env_counters(s, e);
    for (std::uint64_t k : step_errors_) s.reset_errors += k;
    return s;
  }
  bool placement_fallback(int env) const override {
    (void)env;
    return false;
  }
  std::uint64_t state_hash() const override {
    // FNV-1a over the environments' hashes, in environment order.
    Fnv1a f;
    for (const auto& w : worlds_) f.u64_le(w->state_hash());
    return f.h;
  }

 protected:
  // The worlds in blocks of the batched step's lanes on each worker (PickPlaceWorld::step_batch:
  // every world gets the bits of its own step(), so the partition changes no result).
  void advance() override {
    if (lanes_ <= 0) {
      for_each_env(&PickPlaceSimulator::step_env, this);
      return;
    }
    Job job{nullptr, this, num_envs_, pool_->size()};
    pool_->run(&PickPlaceSimulator::step_blocks, &job);
  }
  bool set_root_states(const int* env_ids, int count, const real* pos_w, const real* quat_xyzw, const real* lin_vel_w,
                       const real* ang_vel_w) override {
    (void)env_ids, (void)count, (void)pos_w, (void)quat_xyzw, (void)lin_vel_w, (void)ang_vel_w;
    return fail("simulator so101_pick_place: reset_root_states: the arm stands on a fixed base");
  }
  void set_velocity_xy(int env, int robot, real vx_w, real vy_w) override { (void)env, (void)robot, (void)vx_w, (void)vy_w; }

 private:
  struct Job {
    void (*fn)(void*, int);
    void* ctx;
    int n, threads;
  };
  static void run_job(void* job_v, int worker) {
    const Job& job = *static_cast<const Job*>(job_v);
    const int begin = static_cast<int>(static_cast<long long>(job.n) * worker / job.threads);
    const int end = static_cast<int>(static_cast<long long>(job.n) * (worker + 1) / job.threads);
    for (int e = begin; e < end; ++e) job.fn(job.ctx, e);
  }
  static void step_blocks(void* job_v, int worker) {
    const Job& job = *static_cast<const Job*>(job_v);
    PickPlaceSimulator& self = *static_cast<PickPlaceSimulator*>(job.ctx);
    const int begin = static_cast<int>(static_cast<long long>(job.n) * worker / job.threads);
    const int end = static_cast<int>(static_cast<long long>(job.n) * (worker + 1) / job.threads);
    void* scratch = self.scratch_[static_cast<std::size_t>(worker)].data();
    PickPlaceWorld* worlds[64];
    const real* targets[64];
    Status status[64];
    for (int e0 = begin; e0 < end; e0 += self.lanes_) {
      const int count = std::min(self.lanes_, end - e0);
      for (int l = 0; l < count; ++l) {
        worlds[l] = &self.world(e0 + l);
        targets[l] = &self.actions_[static_cast<std::size_t>(e0 + l) * kJ];
      }
      (void)PickPlaceWorld::step_batch(worlds, targets, count, status, scratch);
      for (int l = 0; l < count; ++l)
        if (status[l] != Status::ok) ++self.step_errors_[static_cast<std::size_t>(e0 + l)];
    }
  }
  static void step_env(void* self_v, int env) {
    PickPlaceSimulator& self = *static_cast<PickPlaceSimulator*>(self_v);
    const std::size_t i = static_cast<std::size_t>(env);
    if (self.world(env).step(&self.actions_[i * kJ]) != Status::ok) ++self.step_errors_[i];
  }
  void reset_env(int env) {
    const std::size_t i = static_cast<std::size_t>(env);
    world(env).reset();
    episode_step_[i] = 0;
    ++stats_[i].resets;
    refresh(env);
  }
  void refresh(int env) {
    const std::size_t i = static_cast<std::size_t>(env);
    const PickPlaceWorld& w = world(env);
    for (int j = 0; j < kJ; ++j) {
      dof_pos_[i * kJ + static_cast<std::size_t>(j)] = w.joint_pos()[j];
      dof_vel_[i * kJ + static_cast<std::size_t>(j)] = w.joint_vel()[j];
    }
    const PickPlaceState& s = w.state();
    const Vec4 q = to_xyzw(quat_from_rotation_matrix(s.tcp_R_w));
    for (int k = 0; k < 3; ++k) {
      pos_w_[3 * i + static_cast<std::size_t>(k)] = s.tcp_pos_w[k];
      target_w_[3 * i + static_cast<std::size_t>(k)] = s.box_pos_w[k];
    }
    for (int k = 0; k < 4; ++k) quat_xyzw_[4 * i + static_cast<std::size_t>(k)] = q[k];
    lazy_ = kLazyEuler;
  }
  void fill_lazy_views(std::uint8_t which) const override {
    if ((which & kLazyEuler) != 0)
      for (int i = 0; i < num_envs_; ++i) write_euler_view(static_cast<std::size_t>(i));
  }

  std::vector<std::unique_ptr<PickPlaceWorld>> worlds_;
  std::unique_ptr<ThreadPool> pool_;
  int lanes_ = 0;  // worlds per step_batch call (0: one at a time)
  std::vector<AlignedScratch> scratch_;
  std::vector<EnvStats> stats_;
  std::vector<std::uint64_t> step_errors_;
  std::vector<int> episode_step_;
  bool auto_reset_ = true;
};

class PickPlaceTask final : public Task {
 public:
  PickPlaceTask(std::unique_ptr<Simulator> s, PickPlaceSimulator* ps, int action_dim, const PickPlaceTaskConfig& c)
      : Task(std::move(s), kPickPlaceObsDim, action_dim), ps_(ps), c_(c) {
    const std::size_t n = static_cast<std::size_t>(num_envs_);
    ee_mode_ = c.action_mode == PickPlaceActionMode::ee_delta;
    scripts_.reserve(n);
    for (int e = 0; e < num_envs_; ++e) scripts_.push_back(std::make_unique<ScriptedPickPlace>(ps_->world(e)));
    scripted_.assign(n * kJ, 0.0f);
    scripted_fresh_.assign(n, 0);
    hold_.assign(n, 0);
    ee_target_w_.assign(n * 3, 0);
    ee_yaw_.assign(n, 0);
    ee_grip_.assign(n, 0);
    actions_in_ = nullptr;
    episode_terms_.assign(n * kNumPickPlaceTerms, 0.0);
    term_sums_.assign(kNumPickPlaceTerms, 0.0);
    reset();
  }

  const char* name() const override { return "so101_pick_place"; }
  int num_reward_terms() const override { return kNumPickPlaceTerms; }
  const char* reward_term_name(int k) const override { return pick_place_term_name(k); }
  double reward_term_sum(int k) const override { return k >= 0 && k < kNumPickPlaceTerms ? term_sums_[static_cast<std::size_t>(k)] : 0.0; }

  bool action_bounds(float* low, float* high) const override {
    const PickPlaceWorld& w = ps_->world(0);
    if (!ee_mode_) {
      for (int j = 0; j < kJ; ++j) {
        low[j] = static_cast<float>(w.joint_lower()[j]);
        high[j] = static_cast<float>(w.joint_upper()[j]);
      }
      return true;
    }
    const float d = static_cast<float>(c_.ee_max_delta_m), y = static_cast<float>(c_.ee_max_yaw_delta_rad);
    for (int k = 0; k < 3; ++k) {
      low[k] = -d;
      high[k] = d;
    }
    low[3] = -y;
    high[3] = y;
    low[4] = static_cast<float>(w.joint_lower()[kJ - 1]);
    high[4] = static_cast<float>(w.joint_upper()[kJ - 1]);
    return true;
  }

  void step(const float* actions) override {
    const std::size_t n = static_cast<std::size_t>(num_envs_);
    if (ee_mode_) {
      actions_in_ = actions;
      ps_->for_each_env(&PickPlaceTask::ee_to_joints, this);
      actions_in_ = nullptr;
    } else {
      for (std::size_t k = 0; k < n * kJ; ++k) sim_actions_[k] = static_cast<real>(actions[k]);
    }
    sim_->step(sim_actions_.data());
    ++infos_.steps;
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      scripted_fresh_[i] = 0;
      ++episode_step_[i];
      const PickPlaceWorld& w = ps_->world(env);
      const bool in_box = w.cube_in_box();
      const bool released = w.grip_force_N() < c_.release_force_N;
      hold_[i] = in_box && released ? hold_[i] + 1 : 0;
      const bool success = c_.end_on_success && hold_[i] >= c_.success_hold_steps;
      const bool timeout = episode_step_[i] >= len_;
      float terms[kNumPickPlaceTerms];
      const float r = pick_place_reward(reward_inputs(w, in_box, success), c_, terms);
      for (int k = 0; k < kNumPickPlaceTerms; ++k) episode_terms_[i * kNumPickPlaceTerms + static_cast<std::size_t>(k)] += terms[k];
      rewards_[i] = r;
      episode_reward_[i] += static_cast<double>(r);
      terminations_[i] = success ? 1 : 0;
      truncations_[i] = !success && timeout ? 1 : 0;
      ended_[i] = success || timeout ? 1 : 0;
      if (ended_[i]) {
        ++infos_.episodes;
        infos_.episode_reward_sum += episode_reward_[i];
        if (success) {
          ++infos_.terminations;
          ++infos_.successes;
        } else {
          ++infos_.truncations;
        }
        for (int k = 0; k < kNumPickPlaceTerms; ++k)
          term_sums_[static_cast<std::size_t>(k)] += episode_terms_[i * kNumPickPlaceTerms + static_cast<std::size_t>(k)];
        ps_->record_episode(env, success);
      }
    }
    reset_ended();
    for (int env = 0; env < num_envs_; ++env) write_obs(env);
  }

  bool scripted_actions(float* actions) const override {
    if (ee_mode_) return false;  // the script gives joint targets (joint_position mode)
    ps_->for_each_env(&PickPlaceTask::run_script, const_cast<PickPlaceTask*>(this));
    std::memcpy(actions, scripted_.data(), scripted_.size() * sizeof(float));
    return true;
  }

  const PickPlaceWorld& world(int env) const { return ps_->world(env); }

  // An object of env moved between steps (an event term): the views, the observation row, the
  // scripted controller (it plans from the objects' positions) and the success counter follow.
  void set_object_pose(int env, bool cube, const Vec3& p_w, const Vec4& quat_xyzw) {
    const std::size_t i = static_cast<std::size_t>(env);
    PickPlaceWorld& w = ps_->world(env);
    if (cube) w.set_cube_pose(p_w, quat_xyzw);
    else w.set_box_position(p_w);
    ps_->refresh_env(env);
    hold_[i] = 0;
    scripted_fresh_[i] = 0;
    scripts_[i]->reset();
    write_obs(env);
  }

 protected:
  void on_reset(int env) override {
    const std::size_t i = static_cast<std::size_t>(env);
    hold_[i] = 0;
    scripted_fresh_[i] = 0;
    for (std::size_t k = 0; k < kNumPickPlaceTerms; ++k) episode_terms_[i * kNumPickPlaceTerms + k] = 0;
    const PickPlaceWorld& w = ps_->world(env);
    scripts_[i]->reset();
    const PickPlaceState& s = w.state();
    for (int k = 0; k < 3; ++k) ee_target_w_[3 * i + static_cast<std::size_t>(k)] = s.tcp_pos_w[k];
    const Vec3 x = s.tcp_R_w.col(0);
    ee_yaw_[i] = std::atan2(x[1], x[0]);
    ee_grip_[i] = w.joint_targets()[kJ - 1];
  }

  void write_obs(int env) override {
    const PickPlaceWorld& w = ps_->world(env);
    float* o = &obs_[static_cast<std::size_t>(env) * static_cast<std::size_t>(obs_dim_)];
    for (int j = 0; j < kJ; ++j) {
      o[j] = static_cast<float>(w.joint_pos()[j]);
      o[6 + j] = static_cast<float>(w.joint_vel()[j]);
      o[12 + j] = static_cast<float>(w.joint_targets()[j]);
    }
    const PickPlaceState& s = w.state();
    Vec4 q = to_xyzw(quat_from_rotation_matrix(s.tcp_R_w));
    if (q[3] < 0) q = -q;
    for (int k = 0; k < 3; ++k) {
      o[18 + k] = static_cast<float>(s.tcp_pos_w[k]);
      o[25 + k] = static_cast<float>(s.cube_pos_w[k] - s.tcp_pos_w[k]);
      o[28 + k] = static_cast<float>(s.box_pos_w[k] - s.cube_pos_w[k]);
    }
    for (int k = 0; k < 4; ++k) o[21 + k] = static_cast<float>(q[k]);
  }

 private:
  static PickPlaceRewardInputs reward_inputs(const PickPlaceWorld& w, bool in_box, bool success) {
    PickPlaceRewardInputs in;
    const PickPlaceState& s = w.state();
    for (int k = 0; k < 3; ++k) {
      in.tcp_w[k] = static_cast<float>(s.tcp_pos_w[k]);
      in.cube_w[k] = static_cast<float>(s.cube_pos_w[k]);
      in.box_w[k] = static_cast<float>(s.box_pos_w[k]);
    }
    in.grip_force_N = static_cast<float>(w.grip_force_N());
    in.in_box = in_box;
    in.success = success;
    return in;
  }

  // ee_delta: the tcp target moved by the clipped deltas, solved to joint targets (one env).
  static void ee_to_joints(void* self_v, int env) {
    PickPlaceTask& t = *static_cast<PickPlaceTask*>(self_v);
    const std::size_t i = static_cast<std::size_t>(env);
    const float* a = t.actions_in_ + i * kPickPlaceEeActionDim;
    const float d = static_cast<float>(t.c_.ee_max_delta_m), yd = static_cast<float>(t.c_.ee_max_yaw_delta_rad);
    auto finite_or_zero = [](float v) { return std::isfinite(v) ? v : 0.0f; };
    real* p = &t.ee_target_w_[3 * i];
    for (int k = 0; k < 3; ++k) p[k] += static_cast<real>(clipf(finite_or_zero(a[k]), -d, d));
    p[0] = std::min(std::max(p[0], -kEeMaxXY_m), kEeMaxXY_m);
    p[1] = std::min(std::max(p[1], -kEeMaxXY_m), kEeMaxXY_m);
    p[2] = std::min(std::max(p[2], kEeMinZ_m), kEeMaxZ_m);
    t.ee_yaw_[i] = wrap_pi(t.ee_yaw_[i] + static_cast<real>(clipf(finite_or_zero(a[3]), -yd, yd)));
    if (std::isfinite(a[4])) t.ee_grip_[i] = static_cast<real>(a[4]);
    const PickPlaceWorld& w = t.ps_->world(env);
    real q[kJ];
    (void)w.solve_tcp(Vec3(p[0], p[1], p[2]), t.ee_yaw_[i], w.joint_targets(), q);
    q[kJ - 1] = t.ee_grip_[i];
    for (int j = 0; j < kJ; ++j) t.sim_actions_[i * kJ + static_cast<std::size_t>(j)] = q[j];
  }

  // The scripted controller of one env, advanced once per task step.
  static void run_script(void* self_v, int env) {
    PickPlaceTask& t = *static_cast<PickPlaceTask*>(self_v);
    const std::size_t i = static_cast<std::size_t>(env);
    if (t.scripted_fresh_[i] != 0) return;
    real a[kJ];
    t.scripts_[i]->act(a);
    for (int j = 0; j < kJ; ++j) t.scripted_[i * kJ + static_cast<std::size_t>(j)] = static_cast<float>(a[j]);
    t.scripted_fresh_[i] = 1;
  }

  PickPlaceSimulator* ps_;
  PickPlaceTaskConfig c_;
  bool ee_mode_ = false;
  std::vector<std::unique_ptr<ScriptedPickPlace>> scripts_;
  std::vector<float> scripted_;              // (envs x 6) the scripts' actions this step
  std::vector<std::uint8_t> scripted_fresh_;  // scripted_ computed since the last step / reset
  std::vector<int> hold_;                     // consecutive steps with the cube in the box, released
  std::vector<real> ee_target_w_, ee_yaw_, ee_grip_;  // ee_delta: each env's tcp target
  const float* actions_in_ = nullptr;         // ee_delta: the step's actions while converting
  std::vector<double> episode_terms_, term_sums_;
};

}  // namespace

const char* pick_place_term_name(int term) {
  static const char* const kNames[kNumPickPlaceTerms] = {"reach", "grasp", "lift", "place", "success"};
  return term >= 0 && term < kNumPickPlaceTerms ? kNames[term] : "";
}

float pick_place_reward(const PickPlaceRewardInputs& in, const PickPlaceTaskConfig& c, float* terms) {
  const auto f = [](real v) { return static_cast<float>(v); };
  float d2 = 0, xy2 = 0;
  for (int k = 0; k < 3; ++k) d2 += (in.cube_w[k] - in.tcp_w[k]) * (in.cube_w[k] - in.tcp_w[k]);
  for (int k = 0; k < 2; ++k) xy2 += (in.cube_w[k] - in.box_w[k]) * (in.cube_w[k] - in.box_w[k]);
  const bool grasped = in.grip_force_N > f(c.grasp_force_N);
  const float h = in.cube_w[2] - f(c.cube_half_m);  // height above resting on the table
  terms[static_cast<int>(PickPlaceTerm::reach)] = f(c.reach_weight) * (1.0f - std::tanh(std::sqrt(d2) / f(c.reach_scale_m)));
  terms[static_cast<int>(PickPlaceTerm::grasp)] = grasped ? f(c.grasp_weight) : 0.0f;
  terms[static_cast<int>(PickPlaceTerm::lift)] = grasped ? f(c.lift_weight) * clipf(h / f(c.lift_height_m), 0.0f, 1.0f) : 0.0f;
  terms[static_cast<int>(PickPlaceTerm::place)] =
      (grasped && h > 0.01f) || in.in_box ? f(c.place_weight) * (1.0f - std::tanh(std::sqrt(xy2) / f(c.place_scale_m))) : 0.0f;
  terms[static_cast<int>(PickPlaceTerm::success)] = in.success ? f(c.success_reward) : 0.0f;
  float r = 0;
  for (int k = 0; k < kNumPickPlaceTerms; ++k) r += terms[k];
  return r;
}

PickPlaceConfig pick_place_world_config(const PickPlaceTaskConfig& t) {
  PickPlaceConfig c;
  c.dt_s = t.dt_s;
  c.decimation = t.decimation;
  c.solver_iterations = t.solver_iterations;
  c.arm_kp_Nm_rad = t.arm_kp_Nm_rad;
  c.arm_kd_Nms_rad = t.arm_kd_Nms_rad;
  c.gripper_kp_Nm_rad = t.gripper_kp_Nm_rad;
  c.gripper_kd_Nms_rad = t.gripper_kd_Nms_rad;
  c.cube_half_m = t.cube_half_m;
  c.cube_mass_kg = t.cube_mass_kg;
  c.cube_friction = t.cube_friction;
  c.cube_pos_w = Vec3(t.cube_pos_w[0], t.cube_pos_w[1], 0);
  c.box_pos_w = Vec3(t.box_pos_w[0], t.box_pos_w[1], 0);
  c.box_inner_half_m = t.box_inner_half_m;
  c.box_wall_m = t.box_wall_m;
  c.box_height_m = t.box_height_m;
  c.robot_file = t.robot_file;
  c.box_friction = t.box_friction;
  c.table_friction = t.table_friction;
  c.randomize_xy_m = t.randomize_xy_m;
  c.success_xy_m = t.success_xy_m;
  c.success_height_m = t.success_height_m;
  return c;
}

std::unique_ptr<Task> make_pick_place_task(const WorldConfig& config, std::string& error) {
  const std::string pre = "so101_pick_place: ";
  std::string err;
  if (!check_config_fields(config, err)) {
    error = pre + err;
    return nullptr;
  }
  if (config.env.num_envs < 1) {
    error = pre + "env.num_envs: expected >= 1";
    return nullptr;
  }
  auto sim = std::make_unique<PickPlaceSimulator>();
  PickPlaceSimulator* raw = sim.get();
  if (!raw->init(config, err)) {
    error = pre + err;
    return nullptr;
  }
  const int ad = config.task.pick_place.action_mode == PickPlaceActionMode::ee_delta ? kPickPlaceEeActionDim : kPickPlaceJointActionDim;
  return std::make_unique<PickPlaceTask>(std::move(sim), raw, ad, config.task.pick_place);
}

TaskConfig pick_place_task_config() {
  TaskConfig t;
  t.name = "so101_pick_place";
  t.kind = TaskKind::hover;               // not read: the task's own rules end its episodes
  t.episode_len_env_steps = 1000;         // 20 s at the 50 Hz action rate
  return t;
}

bool pick_place_set_object_pose(Task& task, int env, PickPlaceObject object, const Vec3& p_w, const Vec4& quat_xyzw,
                                std::string& error) {
  if (std::strcmp(task.name(), "so101_pick_place") != 0) {
    error = std::string("task ") + task.name() + ": set_object_pose is so101_pick_place's";
    return false;
  }
  if (env < 0 || env >= task.num_envs()) {
    error = "env: expected 0.." + std::to_string(task.num_envs() - 1) + " (got " + std::to_string(env) + ")";
    return false;
  }
  if (!all_finite(p_w) || !all_finite(quat_xyzw)) {
    error = "pos, quat: expected finite numbers";
    return false;
  }
  if (object == PickPlaceObject::cube && !(quat_xyzw.norm() > real(1e-6))) {
    error = "quat: expected a non-zero quaternion (x, y, z, w)";
    return false;
  }
  static_cast<PickPlaceTask&>(task).set_object_pose(env, object == PickPlaceObject::cube, p_w, quat_xyzw);
  return true;
}

const PickPlaceWorld* pick_place_world(const Task& task, int env) {
  if (std::strcmp(task.name(), "so101_pick_place") != 0 || env < 0 || env >= task.num_envs()) return nullptr;
  return &static_cast<const PickPlaceTask&>(task).world(env);
}

}  // namespace kestrel::sim
