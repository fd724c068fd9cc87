// Articulated robots (robot kind articulated) behind the Simulator interface, on the rigid
// backend: a robot file (sim/articulated_robot.hpp: MJCF or URDF through MuJoCo's compiler) as the
// core's kinematic tree, stepped by the core's constrained step (dynamics/contact.hpp: contacts
// with friction against the terrain, joint limits, joint dry friction) under legged_gym's joint PD.
//
// One physics step of an environment (legged_gym's LeggedRobot.step, per physics step):
//   tau = clip(kp (action_scale a + q_home - q) - kd qd, +-effort)      (recomputed every physics step
//     by the core's joint PD, controllers/joint_pd.hpp: legged_gym's _compute_torques, 'P' mode)
//   contacts: each collision primitive of the robot (spheres, capsules as their two end spheres,
//     boxes as their corners) against the terrain's local plane under it (Terrain::height_at and
//     its slope by central differences: a plane, a height field or a mesh alike)
//   step_constrained with the drives' kp and kd taken implicitly where the torque is not clipped
//     (legged_gym's explicit PD diverges on Go2's calf at dt = 5 ms otherwise; see contact.hpp).
// Episodes end on a base contact (legged_gym's termination_contact_names = base) when
// env.reset_on_collision, and on timeout (task.episode_len_env_steps); auto-reset puts the robot
// back at its `home` keyframe over its environment's origin. Environment origins lie on a square
// grid 3 m apart (legged_gym's env_spacing), centred on the terrain.
//
// Determinism: environments never read each other; each worker has its own scratch (dynamics data
// and the constraint solver's arrays), so the results are bit-identical for any thread count. No
// heap inside a step: every array is sized at set-up.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include "kestrel/controllers/joint_pd.hpp"
#include "kestrel/dynamics/contact.hpp"
#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/aligned_scratch.hpp"
#include "kestrel/sim/articulated_robot.hpp"
#include "kestrel/sim/collision.hpp"
#include "kestrel/sim/simulator.hpp"
#include "kestrel/sim/state_hash.hpp"
#include "kestrel/sim/terrain.hpp"
#include "kestrel/sim/thread_pool.hpp"
#include "articulated_batch.hpp"

namespace kestrel::sim {

namespace dy = kestrel::dynamics;

namespace {

constexpr int kMaxContacts = legged_batch::kMaxContacts;  // per robot per physics step
using Scratch = dy::ConstraintData<kMaxRobotBodies, kMaxContacts>;
constexpr real kEnvSpacing_m = 3;          // legged_gym's env_spacing
constexpr real kContactMargin_m = 0.01_r;  // speculative contacts (contact.hpp)
constexpr real kActionClip = 100;          // legged_gym's clip_actions
constexpr std::size_t kMaxJoints = kMaxRobotBodies;
constexpr std::size_t kMaxDelay = 4;       // physics steps of action delay the drive can hold
using Drive = JointPdParams<kMaxJoints, kMaxDelay>;
using DriveState = JointPdState<kMaxJoints, kMaxDelay>;
constexpr real kBaseContactThreshold_N = 1;
constexpr int kWarmRows = legged_batch::kWarmRows;  // rows of the previous step kept per robot (contact.hpp's WarmStart)
constexpr int kMaxSelfShapes = 64;  // collision geoms of a robot with self-collisions on

// One batch's per-robot inputs and outputs (physics_step_group, articulated_batch.hpp).
struct Group {
  static constexpr int kDofs = dy::max_dofs<kMaxRobotBodies>();
  real tau[legged_batch::kMaxLanes][kDofs], kp[legged_batch::kMaxLanes][kDofs], kd[legged_batch::kMaxLanes][kDofs];
  dy::ContactPoint contacts[legged_batch::kMaxLanes][kMaxContacts];
  Vec3 force[legged_batch::kMaxLanes][kMaxContacts];
  dy::Transform X_world[legged_batch::kMaxLanes][kMaxRobotBodies];
  int found[legged_batch::kMaxLanes] = {};
};

struct Worker {
  // The batched step's per-robot arrays and its scratch (set up when the batch is used).
  std::unique_ptr<Group> group;
  AlignedScratch batch_mem;
  void* batch_scratch() { return batch_mem.data(); }
  // The robot's model with one environment's randomised root-body inertia and joint armatures
  // written in before its physics step (only when those are randomised): one copy per worker, so
  // the environments share one model otherwise and never read each other's.
  RobotMultibody model;
  dy::MultibodyData<kMaxRobotBodies> data;
  Scratch scratch;
  dy::ContactPoint contacts[kMaxContacts];
};

class ArticulatedSimulator final : public Simulator {
 public:
  ArticulatedSimulator() : Simulator(Backend::rigid) {}

  bool init(const WorldConfig& c, std::string& error) {
    const std::string pre = "simulator rigid, robot " + c.robot.name + ": ";
    if (c.robot.model_file.empty()) {
      error = pre + "robot.model: an articulated robot needs a robot file (MJCF or URDF)";
      return false;
    }
    if (c.robot.robots_per_env != 1) {
      error = pre + "robot.robots_per_env: articulated robots run one per environment (got " + std::to_string(c.robot.robots_per_env) + ")";
      return false;
    }
    if (!c.env.assets.empty()) {
      error = pre + "env: articulated robots collide with the terrain only; use an environment without obstacles (e.g. env: empty)";
      return false;
    }
    if (!c.robot.sensors.empty()) {
      error = pre + "robot.sensors: articulated robots carry no sensors yet; remove `sensors`";
      return false;
    }
    if (!load_robot_model(c.robot.model_file, robot_, error)) return false;
    for (int b = 0; b < robot_.multibody.num_bodies; ++b) {
      // The scenario's passive joint dynamics replace the file's (legged_gym's assets have none).
      RobotMultibody& mm = robot_.multibody;
      if (mm.dof_index[b] < 0 || mm.joint[b] == dy::JointType::free) continue;
      if (c.robot.joint_damping_Nms_rad >= 0) mm.damping[b] = c.robot.joint_damping_Nms_rad;
      if (c.robot.joint_friction_loss_Nm >= 0) mm.friction_loss[b] = c.robot.joint_friction_loss_Nm;
      if (c.robot.joint_armature_kg_m2 >= 0) mm.armature[b] = c.robot.joint_armature_kg_m2;
    }
    const RobotMultibody& m = robot_.multibody;
    if (!robot_.has_home) {
      error = pre + c.robot.model_file + ": no keyframe named \"home\" (the joint PD's default pose)";
      return false;
    }
    floating_ = m.joint[0] == dy::JointType::free;
    for (int b = 0; b < m.num_bodies; ++b) {
      if (m.dof_index[b] < 0 || m.joint[b] == dy::JointType::free) continue;
      dof_v_.push_back(m.dof_index[b]);
      dof_q_.push_back(m.q_index[b]);
      dof_body_.push_back(b);
      effort_.push_back(m.effort_limit[b]);
      home_.push_back(robot_.home_q[static_cast<std::size_t>(m.q_index[b])]);
    }
    if (dof_v_.empty()) {
      error = pre + c.robot.model_file + ": the robot has no revolute or prismatic joint to drive";
      return false;
    }
    if (dof_v_.size() > kMaxJoints) {
      error = pre + c.robot.model_file + ": more than " + std::to_string(kMaxJoints) + " driven joints";
      return false;
    }
    drive_.num_joints = dof_v_.size();
    drive_.mode = c.robot.joint_control_mode;
    drive_.delay_steps = static_cast<std::size_t>(std::max(0, c.robot.joint_delay_steps));
    drive_.gain_scale_ranges = {c.robot.joint_kp_scale_min, c.robot.joint_kp_scale_max, c.robot.joint_kd_scale_min,
                                c.robot.joint_kd_scale_max};
    drive_.randomize_gain_scales =
        c.robot.joint_kp_scale_min != c.robot.joint_kp_scale_max || c.robot.joint_kd_scale_min != c.robot.joint_kd_scale_max;
    drive_.action_scale = c.robot.action_scale;
    drive_.action_clip = kActionClip;
    drive_.dt_s = c.sim.dt_s;
    for (std::size_t j = 0; j < dof_v_.size(); ++j) {
      drive_.kp[j] = c.robot.joint_kp_Nm_rad;
      drive_.kd[j] = c.robot.joint_kd_Nms_rad;
      drive_.default_pos_rad[j] = home_[j];
      // The file's effort limit; none (0) leaves the drive unclipped.
      drive_.torque_limit_Nm[j] = effort_[j] > 0 ? effort_[j] : std::numeric_limits<real>::max();
    }
    if (validate_joint_pd_params(drive_) != Status::ok) {
      error = pre + "robot.joint_kp_Nm_rad / joint_kd_Nms_rad / action_scale / joint_delay_steps (<= " + std::to_string(kMaxDelay) +
              ") / joint_kp_scale / joint_kd_scale (min <= max): the joint drive was refused";
      return false;
    }
    if (!check_randomisation(c, pre, error)) return false;
    for (const RobotGeom& g : robot_.geoms) {
      if (g.body < 0) continue;  // world geometry of the file: the terrain stands for the ground
      dy::CollisionShape s;
      if (!to_collision_shape(g, s)) {
        error = pre + c.robot.model_file + ": a plane geom on a moving body (" + robot_.body_names[static_cast<std::size_t>(g.body)] +
                ") cannot collide with the terrain";
        return false;
      }
      shapes_.push_back(s);
      shape_bits_.push_back({g.contype, g.conaffinity});
    }
    if (c.robot.self_collisions && !build_self_pairs(pre, error)) return false;
    if (!Terrain::build(c.env.terrain, c.seed, terrain_, error)) return false;
    params_.iterations = c.sim.solver_iterations;
    params_.poses_current = true;  // step() runs forward_kinematics into the step's own scratch for its collisions

    allocate_views(c, static_cast<int>(dof_v_.size()), 0);
    num_dofs_ = static_cast<int>(dof_v_.size());
    layout_.link_names = robot_.body_names;
    layout_.foot_links = robot_.foot_bodies;
    for (int b = 0; b < m.num_bodies; ++b) {
      if (m.dof_index[b] < 0 || m.joint[b] == dy::JointType::free) continue;
      layout_.dof_names.push_back(robot_.joint_names[static_cast<std::size_t>(b)]);
      layout_.dof_pos_lower.push_back(m.has_limit[b] ? m.q_min[b] : -std::numeric_limits<real>::infinity());
      layout_.dof_pos_upper.push_back(m.has_limit[b] ? m.q_max[b] : std::numeric_limits<real>::infinity());
      layout_.torque_limits.push_back(m.effort_limit[b] > 0 ? m.effort_limit[b] : std::numeric_limits<real>::infinity());
    }
    layout_.default_dof_pos = home_;
    num_feet_ = static_cast<int>(robot_.foot_bodies.size());
    num_links_ = m.num_bodies;
    const std::size_t n = static_cast<std::size_t>(num_robots());
    dof_pos_.assign(n * dof_v_.size(), 0);
    dof_vel_.assign(n * dof_v_.size(), 0);
    torques_.assign(n * dof_v_.size(), 0);
    feet_pos_w_.assign(n * robot_.foot_bodies.size() * 3, 0);
    link_forces_w_.assign(n * static_cast<std::size_t>(m.num_bodies) * 3, 0);
    nq_ = m.num_q;
    nv_ = m.num_dofs;
    q_.assign(n * static_cast<std::size_t>(nq_), 0);
    qd_.assign(n * static_cast<std::size_t>(nv_), 0);
    episode_step_.assign(static_cast<std::size_t>(num_envs_), 0);
    warm_.assign(static_cast<std::size_t>(num_envs_), dy::WarmStart<kWarmRows>{});
    drive_state_.assign(static_cast<std::size_t>(num_envs_), DriveState{});
    dr_kp_scale_.assign(n, 1);
    dr_kd_scale_.assign(n, 1);
    for (int e = 0; e < num_envs_; ++e) rng_gains_.emplace_back(c.seed, c.env.global_env(e), kPurposeJointGains);
    const SimulatorConfig& sc = c.simulator;
    dr_friction_.assign(n, sc.friction_min == -1 ? -1_r : sc.friction_min);
    dr_restitution_.assign(n, sc.restitution_min == -1 ? -1_r : sc.restitution_min);
    dr_armature_.assign(n * dof_v_.size(), 0);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < dof_v_.size(); ++j) dr_armature_[i * dof_v_.size() + j] = m.armature[dof_body_[j]];
    randomise_inertia_ = sc.added_mass_min_kg != 0 || sc.added_mass_max_kg != 0 || sc.com_bias_max_m != 0 ||
                         sc.joint_armature_min_kg_m2 != -1;
    randomise_contacts_ = sc.friction_min != -1 || sc.restitution_min != -1;
    for (int e = 0; e < num_envs_; ++e) {
      rng_dr_.emplace_back(c.seed, c.env.global_env(e), kPurposeDomainRand);
      rng_link_push_.emplace_back(c.seed, c.env.global_env(e), kPurposeLinkPush);
    }
    link_push_w_.assign(n * static_cast<std::size_t>(m.num_bodies) * 3, 0);
    link_push_due_.assign(n, 0);
    stats_.assign(static_cast<std::size_t>(num_envs_), EnvStats{});
    step_errors_.assign(static_cast<std::size_t>(num_envs_), 0);
    origins_.resize(static_cast<std::size_t>(num_envs_));
    for (int e = 0; e < num_envs_; ++e) rng_terrain_.emplace_back(c.seed, c.env.global_env(e), kPurposeTerrainLevel);
    place_origins();
    if (c.env.terrain.measure_heights) {
      // legged_gym's height points: the x list times the y list, x-major (as the World's).
      const std::vector<real>& px = c.env.terrain.measured_points_x_m;
      const std::vector<real>& py = c.env.terrain.measured_points_y_m;
      if (px.empty() || py.empty()) {
        error = pre + "env.terrain.measured_points_x/y: expected non-empty lists";
        return false;
      }
      for (real x : px)
        for (real y : py) {
          height_x_b_.push_back(x);
          height_y_b_.push_back(y);
        }
      num_height_points_ = static_cast<int>(height_x_b_.size());
      heights_.assign(n * height_x_b_.size(), 0);
    }
    const int threads = std::max(1, std::min(c.num_threads, num_envs_));
    pool_ = std::make_unique<ThreadPool>(threads);
    for (int w = 0; w < threads; ++w) {
      workers_.push_back(std::make_unique<Worker>());
      workers_.back()->model = robot_.multibody;
    }
    // The batched constrained step (articulated_batch.hpp) where the robots share one model;
    // KESTREL_LEGGED_BATCH=off keeps every robot on the scalar step (the same bits; for A/B runs).
    const char* batch_env = std::getenv("KESTREL_LEGGED_BATCH");
    const bool batch_off = batch_env != nullptr && std::strcmp(batch_env, "off") == 0;
    batch_lanes_ = !batch_off && !randomise_inertia_ && legged_batch::eligible(m) ? legged_batch::lanes() : 0;
    if (batch_lanes_ > 1)
      for (auto& w : workers_) {
        w->group = std::make_unique<Group>();
        w->batch_mem.resize(legged_batch::scratch_bytes());
      }
    for (int e = 0; e < num_envs_; ++e) reset_env(e, false);
    for (int e = 0; e < num_envs_; ++e) refresh(e, *workers_[0]);
    return true;
  }

  int num_threads() const override { return pool_->size(); }
  const real* measured_heights() const override { return num_height_points_ > 0 ? heights_.data() : nullptr; }
  const char* controller_name() const override { return "joint_pd"; }

  void post_physics_step() override {
    for (int e = 0; e < num_envs_; ++e) {
      const std::size_t ei = static_cast<std::size_t>(e);
      EnvStats& st = stats_[ei];
      ++st.env_steps;
      ++episode_step_[ei];
      const bool crash = crashed_[ei] != 0;
      if (crash) ++st.crashes;
      const bool timeout = episode_step_[ei] >= cfg_.task.episode_len_env_steps;
      const bool ended = (crash && cfg_.env.reset_on_collision) || timeout;
      reset_buf_[ei] = ended ? 1 : 0;
      if (!ended) continue;
      ++st.episodes_done;
      if (timeout && !(crash && cfg_.env.reset_on_collision)) ++st.timeouts;
      if (auto_reset_) {
        reset_env(e, true);
        refresh(e, *workers_[0]);
      }
    }
  }

  void reset_idx(const int* env_ids, int count) override {
    for (int k = 0; k < count; ++k) {
      if (env_ids[k] < 0 || env_ids[k] >= num_envs_) continue;
      reset_env(env_ids[k], true);
      refresh(env_ids[k], *workers_[0]);
    }
  }

  bool reset_dofs(const int* env_ids, int count, const real* dof_pos, const real* dof_vel) override {
    // The message is built only on a refusal (a string in the good path would allocate).
    const char* pre = "simulator rigid: reset_dofs: ";
    const int nd = num_dofs_;
    for (int k = 0; k < count; ++k)
      if (env_ids[k] < 0 || env_ids[k] >= num_envs_)
        return fail(pre + ("env id " + std::to_string(env_ids[k]) + " out of range [0, " + std::to_string(num_envs_) + ")"));
    if (!all_finite(dof_pos, count * nd) || !all_finite(dof_vel, count * nd))
      return fail(std::string(pre) + "non-finite dof_pos or dof_vel");
    for (int k = 0; k < count; ++k) {
      const std::size_t e = static_cast<std::size_t>(env_ids[k]);
      for (int j = 0; j < nd; ++j) {
        q_[e * static_cast<std::size_t>(nq_) + static_cast<std::size_t>(dof_q_[static_cast<std::size_t>(j)])] = dof_pos[k * nd + j];
        qd_[e * static_cast<std::size_t>(nv_) + static_cast<std::size_t>(dof_v_[static_cast<std::size_t>(j)])] = dof_vel[k * nd + j];
      }
      refresh(env_ids[k], *workers_[0]);
    }
    return true;
  }

  bool push_links() override {
    const real f = cfg_.simulator.max_push_force_N;
    const std::size_t nb = static_cast<std::size_t>(robot_.multibody.num_bodies);
    for (int e = 0; e < num_envs_; ++e) {
      const std::size_t ei = static_cast<std::size_t>(e);
      RngStream& rng = rng_link_push_[ei];
      // Three draws per link always, so the stream's position does not depend on the values.
      for (std::size_t k = 0; k < 3 * nb; ++k) link_push_w_[ei * 3 * nb + k] = rng.uniform(-f, f);
      link_push_due_[ei] = 1;
    }
    return true;
  }

  bool update_terrain_curriculum(const int* env_ids, int count, const std::uint8_t* move_up, const std::uint8_t* move_down) override {
    if (num_terrain_levels_ == 0) return Simulator::update_terrain_curriculum(env_ids, count, move_up, move_down);
    for (int k = 0; k < count; ++k)
      if (env_ids[k] < 0 || env_ids[k] >= num_envs_)
        return fail("simulator rigid: update_terrain_curriculum: env id " + std::to_string(env_ids[k]) + " out of range [0, " +
                    std::to_string(num_envs_) + ")");
    for (int k = 0; k < count; ++k) {
      const std::size_t e = static_cast<std::size_t>(env_ids[k]);
      int level = terrain_levels_[e] + (move_up[k] != 0 ? 1 : 0) - (move_down[k] != 0 && move_up[k] == 0 ? 1 : 0);
      // legged_gym: robots that solve the last level are sent to a random one; the lowest is 0.
      if (level >= num_terrain_levels_) level = static_cast<int>(rng_terrain_[e].next_u32() % static_cast<std::uint32_t>(num_terrain_levels_));
      terrain_levels_[e] = std::max(0, level);
      set_origin(e, terrain_->tile_origin(terrain_levels_[e], terrain_types_[e]));
    }
    return true;
  }

  void update_sensors() override {}
  void set_auto_reset(bool on) override { auto_reset_ = on; }
  // The obstacle curriculum's level: articulated robots have no obstacle slots, so nothing reads
  // it (legged_gym's terrain curriculum is a separate call, not built yet).
  void set_curriculum_level(real level) override { (void)level; }
  void env_bounds(int env, Vec3& lower_w, Vec3& upper_w) const override {
    const Vec3& o = origins_[static_cast<std::size_t>(env)];
    lower_w = o - Vec3(kEnvSpacing_m / 2, kEnvSpacing_m / 2, 1);
    upper_w = o + Vec3(kEnvSpacing_m / 2, kEnvSpacing_m / 2, 2);
  }
  RangeImage range_image(int robot, int k) const override {
    (void)robot, (void)k;
    return RangeImage{};
  }
  bool set_obstacle_boxes(int env, const ObstacleBox* boxes, int count) override {
    (void)env, (void)boxes, (void)count;
    return fail("simulator rigid: set_obstacle_boxes: articulated robots have no obstacle slots (they collide with the terrain only)");
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
    // FNV-1a over every environment's configuration and velocities, in environment order.
    Fnv1a f;
    f.bytes(q_.data(), q_.size() * sizeof(real));
    f.bytes(qd_.data(), qd_.size() * sizeof(real));
    return f.h;
  }

  /// Environment e's physics step up to the constrained step: its drive torques and gains (in),
  /// its contacts (into `contacts`, returns how many), a due link push added to tau. The body poses
  /// at e's q in X_world: computed here (forward_kinematics, which leaves the kinematics in w.data
  /// too, for the scalar step's poses_current) unless poses_ready (the batch's kinematics).
  int prepare(int e, const RobotMultibody& m, Worker& w, dy::Transform* X_world, bool poses_ready, real* tau, real* kp, real* kd,
              dy::ContactPoint* contacts) {
    const std::size_t ei = static_cast<std::size_t>(e);
    const real* q = &q_[ei * static_cast<std::size_t>(nq_)];
    const real* qd = &qd_[ei * static_cast<std::size_t>(nv_)];
    const real* a = &actions_[ei * static_cast<std::size_t>(action_dim_)];
    for (int k = 0; k < m.num_dofs; ++k) tau[k] = kp[k] = kd[k] = 0;
    real qj[kMaxJoints], qdj[kMaxJoints], tj[kMaxJoints];
    const std::size_t nj = dof_v_.size();
    for (std::size_t j = 0; j < nj; ++j) {
      qj[j] = q[dof_q_[j]];
      qdj[j] = qd[dof_v_[j]];
    }
    // A rejected update (non-finite action) holds the last safe torques (joint_pd.hpp's contract).
    DriveState& ds = drive_state_[ei];
    (void)update_joint_pd(drive_, ds, qj, qdj, a, tj);
    for (std::size_t j = 0; j < nj; ++j) {
      const int k = dof_v_[j];
      tau[k] = tj[j];
      torques_[ei * nj + j] = tj[j];
      // The drive's gains act on this step's motion unless it saturated: taken implicitly. 'P':
      // d tau / d q = -kp, d tau / d qd = -kd; 'V': d tau / d qd = -(kp + kd / dt); 'T': none.
      if (std::fabs(tj[j]) < drive_.torque_limit_Nm[j]) {
        const real gp = drive_.kp[j] * ds.scales.kp_scale, gd = drive_.kd[j] * ds.scales.kd_scale;
        if (drive_.mode == JointControlMode::position) {
          kp[k] = gp;
          kd[k] = gd;
        } else if (drive_.mode == JointControlMode::velocity) {
          kd[k] = gp + gd / drive_.dt_s;
        }
      }
    }
    if (!poses_ready) dy::forward_kinematics(m, w.data, q, X_world);
    int found = 0;
    for (std::size_t si = 0; si < shapes_.size(); ++si) {
      const dy::CollisionShape& s = shapes_[si];
      // The terrain's local plane under the shape's centre.
      const dy::Transform& X = X_world[s.body];
      const Vec3 c = X.r + X.E.transpose() * s.p_b;
      dy::HalfSpace ground;
      terrain_plane(c[0], c[1], ground);
      const int room = kMaxContacts - found;
      if (room <= 0) break;
      const int k = dy::collide_halfspace(&s, 1, X_world, ground, kContactMargin_m, contacts + found, room,
                                          static_cast<int>(si));
      found += std::min(k, room);
    }
    // Self-collision (robot.self_collisions): each allowed pair of the robot's own shapes, both
    // bodies pushed apart (two-body rows, contact.hpp). Keys after the terrain's (8 per shape).
    // A bounding sphere per shape first, so most pairs cost one distance test.
    const int self_key0 = 16 * static_cast<int>(shapes_.size());
    Vec3 centre_w[kMaxSelfShapes];
    if (!self_pairs_.empty())
      for (std::size_t si = 0; si < shapes_.size(); ++si) {
        const dy::Transform& X = X_world[shapes_[si].body];
        centre_w[si] = X.r + X.E.transpose() * shapes_[si].p_b;
      }
    for (std::size_t p = 0; p < self_pairs_.size() && found < kMaxContacts; ++p) {
      const std::size_t ia = static_cast<std::size_t>(self_pairs_[p].first), ib = static_cast<std::size_t>(self_pairs_[p].second);
      if ((centre_w[ia] - centre_w[ib]).norm() > bound_r_[ia] + bound_r_[ib] + kContactMargin_m) continue;
      const dy::CollisionShape& sa = shapes_[ia];
      const dy::CollisionShape& sb = shapes_[ib];
      if (sa.type == dy::ShapeType::convex || sb.type == dy::ShapeType::convex) {
        // A collision mesh (its hull) against another shape: libccd's MPR through the rigid
        // world's narrow phase (sim/collision.hpp), one contact at the deepest point, none while
        // apart (MPR measures penetration only: no speculative margin here).
        const Contact kc = collide(sim_shape(sa, X_world[sa.body]), sim_shape(sb, X_world[sb.body]));
        if (!kc.hit) continue;
        dy::ContactPoint& c = contacts[found++];
        c.body = sa.body;
        c.body_b = sb.body;
        c.point_w = kc.point_w;
        c.normal_w = kc.normal_w;  // from b into a: pushes a along it, b against it
        c.separation_m = -kc.depth_m;
        c.friction = real(0.5) * (sa.friction + sb.friction);
        c.restitution = real(0.5) * (sa.restitution + sb.restitution);
        c.key = self_key0 + 16 * static_cast<int>(p);
        continue;
      }
      const int room = kMaxContacts - found;
      const int k = dy::collide_shapes(sa, X_world[sa.body], sb, X_world[sb.body], kContactMargin_m,
                                       contacts + found, room, self_key0 + 16 * static_cast<int>(p));
      found += std::min(k, room);
    }
    if (randomise_contacts_)
      for (int k = 0; k < found; ++k) {
        if (dr_friction_[ei] >= 0) contacts[k].friction = dr_friction_[ei];
        if (dr_restitution_[ei] >= 0) contacts[k].restitution = dr_restitution_[ei];
      }
    if (link_push_due_[ei] != 0) {
      add_link_push(ei, m, X_world, tau);
      link_push_due_[ei] = 0;
    }
    return found;
  }

  /// The per-physics-step work of one environment (workers run slices of environments).
  void physics_step(int e, Worker& w) {
    const std::size_t ei = static_cast<std::size_t>(e);
    const RobotMultibody& m = randomise_inertia_ ? env_model(ei, w) : robot_.multibody;
    real tau[dy::max_dofs<kMaxRobotBodies>()], kp[dy::max_dofs<kMaxRobotBodies>()], kd[dy::max_dofs<kMaxRobotBodies>()];
    const int found = prepare(e, m, w, w.scratch.X_world, false, tau, kp, kd, w.contacts);
    constrained_step(e, m, w, tau, kp, kd, found);
  }

  /// The scalar constrained step of environment e after prepare() (w's kinematics at its q), and
  /// its per-link contact forces.
  void constrained_step(int e, const RobotMultibody& m, Worker& w, const real* tau, const real* kp, const real* kd, int found) {
    const std::size_t ei = static_cast<std::size_t>(e);
    real* q = &q_[ei * static_cast<std::size_t>(nq_)];
    real* qd = &qd_[ei * static_cast<std::size_t>(nv_)];
    const Status st = dy::step_constrained(m, w.data, w.scratch, q, qd, tau, cfg_.sim.dt_s, w.contacts, found,
                                           params_, kp, kd, &warm_[ei]);
    real* lf = &link_forces_w_[ei * static_cast<std::size_t>(m.num_bodies) * 3];
    for (int b = 0; b < 3 * m.num_bodies; ++b) lf[b] = 0;
    if (st != Status::ok) {
      ++step_errors_[ei];  // refused: the state is held (the core's contract)
      return;
    }
    add_link_forces(w.contacts, w.scratch.contact_force_w, found, lf);
  }

  /// Per-link contact forces (lf: 3 per body, zeroed); a self contact pushes its second body the other way.
  static void add_link_forces(const dy::ContactPoint* contacts, const Vec3* force_w, int found, real* lf) {
    for (int k = 0; k < found; ++k) {
      const dy::ContactPoint& ck = contacts[k];
      for (int c = 0; c < 3; ++c) lf[3 * ck.body + c] += force_w[k][c];
      if (ck.body_b >= 0)
        for (int c = 0; c < 3; ++c) lf[3 * ck.body_b + c] -= force_w[k][c];
    }
  }

  /// The physics step of environments e0 .. e0 + count - 1 (count <= the batch's lanes) with one
  /// batched constrained step (articulated_batch.hpp: each robot's bits are the scalar step's);
  /// a robot the batch leaves (see there) takes the scalar step.
  void physics_step_group(int e0, int count, Worker& w) {
    const RobotMultibody& m = robot_.multibody;
    Group& g = *w.group;
    legged_batch::Lane lanes[legged_batch::kMaxLanes];
    // The robots' kinematics in the batch's lanes (kept there for its step: poses_current), their
    // poses for the collisions.
    const real* qs[legged_batch::kMaxLanes] = {};
    dy::Transform* Xs[legged_batch::kMaxLanes] = {};
    for (int l = 0; l < count; ++l) {
      qs[l] = &q_[static_cast<std::size_t>(e0 + l) * static_cast<std::size_t>(nq_)];
      Xs[l] = g.X_world[l];
    }
    legged_batch::kinematics(m, qs, count, Xs, w.batch_scratch());
    for (int l = 0; l < count; ++l) {
      const std::size_t ei = static_cast<std::size_t>(e0 + l);
      g.found[l] = prepare(e0 + l, m, w, g.X_world[l], true, g.tau[l], g.kp[l], g.kd[l], g.contacts[l]);
      legged_batch::Lane& ln = lanes[l];
      ln.q = &q_[ei * static_cast<std::size_t>(nq_)];
      ln.qd = &qd_[ei * static_cast<std::size_t>(nv_)];
      ln.tau = g.tau[l];
      ln.kp = g.kp[l];
      ln.kd = g.kd[l];
      ln.contacts = g.contacts[l];
      ln.num_contacts = g.found[l];
      ln.warm = &warm_[ei];
      ln.contact_force_w = g.force[l];
    }
    const unsigned done = legged_batch::step(m, params_, cfg_.sim.dt_s, lanes, count, w.batch_scratch());
    for (int l = 0; l < count; ++l) {
      const int e = e0 + l;
      const std::size_t ei = static_cast<std::size_t>(e);
      if ((done >> l) & 1u) {
        real* lf = &link_forces_w_[ei * static_cast<std::size_t>(m.num_bodies) * 3];
        for (int b = 0; b < 3 * m.num_bodies; ++b) lf[b] = 0;
        add_link_forces(g.contacts[l], g.force[l], g.found[l], lf);
        continue;
      }
      // The scalar step, with the kinematics of this robot (prepare() left the last one's).
      dy::forward_kinematics(m, w.data, &q_[ei * static_cast<std::size_t>(nq_)], w.scratch.X_world);
      for (int k = 0; k < g.found[l]; ++k) w.contacts[k] = g.contacts[l][k];
      constrained_step(e, m, w, g.tau[l], g.kp[l], g.kd[l], g.found[l]);
    }
  }

  /// refresh() of environments e0 .. e0 + count - 1 with their poses from the batch's kinematics.
  void refresh_group(int e0, int count, Worker& w) {
    Group& g = *w.group;
    const real* qs[legged_batch::kMaxLanes] = {};
    dy::Transform* Xs[legged_batch::kMaxLanes] = {};
    for (int l = 0; l < count; ++l) {
      qs[l] = &q_[static_cast<std::size_t>(e0 + l) * static_cast<std::size_t>(nq_)];
      Xs[l] = g.X_world[l];
    }
    legged_batch::kinematics(robot_.multibody, qs, count, Xs, w.batch_scratch());
    for (int l = 0; l < count; ++l) refresh(e0 + l, w, g.X_world[l]);
  }

  /// The views of environment e from its state (and its feet by forward kinematics; X_world: the
  /// body poses at its q when the caller has them).
  void refresh(int e, Worker& w, const dy::Transform* X_world = nullptr) {
    const RobotMultibody& m = robot_.multibody;
    const std::size_t ei = static_cast<std::size_t>(e);
    const real* q = &q_[ei * static_cast<std::size_t>(nq_)];
    const real* qd = &qd_[ei * static_cast<std::size_t>(nv_)];
    if (X_world == nullptr) {
      dy::forward_kinematics(m, w.data, q, w.scratch.X_world);
      X_world = w.scratch.X_world;
    }
    RigidBodyState s;
    const dy::Transform& X0 = X_world[0];
    s.position_w = X0.r;
    s.orientation_wb = quat_from_rotation_matrix(X0.E.transpose());
    if (floating_) {
      s.orientation_wb = quat_from_xyzw(q + 3);
      s.linvel_w = rotate(s.orientation_wb, Vec3(qd[0], qd[1], qd[2]));
      s.angvel_b = Vec3(qd[3], qd[4], qd[5]);
    } else {
      s.linvel_w = Vec3::Zero();
      s.angvel_b = Vec3::Zero();
    }
    write_state_view(ei, s);
    for (std::size_t j = 0; j < dof_v_.size(); ++j) {
      dof_pos_[ei * dof_v_.size() + j] = q[dof_q_[j]];
      dof_vel_[ei * dof_v_.size() + j] = qd[dof_v_[j]];
    }
    for (std::size_t f = 0; f < robot_.foot_bodies.size(); ++f) {
      const dy::Transform& X = X_world[robot_.foot_bodies[f]];
      for (int c = 0; c < 3; ++c) feet_pos_w_[(ei * robot_.foot_bodies.size() + f) * 3 + c] = X.r[c];
    }
    const real* lf = &link_forces_w_[ei * static_cast<std::size_t>(m.num_bodies) * 3];
    Vec3 total = Vec3::Zero();
    for (int b = 0; b < m.num_bodies; ++b) total += Vec3(lf[3 * b], lf[3 * b + 1], lf[3 * b + 2]);
    for (int c = 0; c < 3; ++c) contact_w_[3 * ei + c] = total[c];
    crashed_[ei] = Vec3(lf[0], lf[1], lf[2]).norm() > kBaseContactThreshold_N ? 1 : 0;
    for (int c = 0; c < 3; ++c) target_w_[3 * ei + c] = origins_[ei][c];
    if (num_height_points_ > 0) {
      // legged_gym's _get_heights: the points turned by the base's yaw about the base.
      const Vec3 fwd = rotate(s.orientation_wb, Vec3::UnitX());
      const real fn = std::sqrt(fwd[0] * fwd[0] + fwd[1] * fwd[1]);
      const real cy = fn > 1e-6_r ? fwd[0] / fn : 1_r, sy = fn > 1e-6_r ? fwd[1] / fn : 0_r;
      real* out = &heights_[ei * height_x_b_.size()];
      for (std::size_t k = 0; k < height_x_b_.size(); ++k) {
        const real px = height_x_b_[k], py = height_y_b_[k];
        out[k] = terrain_->height_at(s.position_w[0] + cy * px - sy * py, s.position_w[1] + sy * px + cy * py);
      }
    }
  }

 protected:
  void advance() override {
    pool_->run(&ArticulatedSimulator::run_slice, this);
  }

  bool set_root_states(const int* env_ids, int count, const real* pos_w, const real* quat_xyzw, const real* lin_vel_w,
                       const real* ang_vel_w) override {
    if (!floating_) return fail("simulator rigid: reset_root_states: the robot's base is fixed to the world (no free joint)");
    for (int k = 0; k < count; ++k) {
      const std::size_t e = static_cast<std::size_t>(env_ids[k]);
      real* q = &q_[e * static_cast<std::size_t>(nq_)];
      real* qd = &qd_[e * static_cast<std::size_t>(nv_)];
      for (int c = 0; c < 3; ++c) q[c] = pos_w[3 * k + c];
      const Quat Q = quat_from_xyzw(quat_xyzw + 4 * k).normalized();
      const Vec4 qn = to_xyzw(Q);
      for (int c = 0; c < 4; ++c) q[3 + c] = qn[c];
      const Vec3 vb = rotate_inverse(Q, Vec3(lin_vel_w[3 * k], lin_vel_w[3 * k + 1], lin_vel_w[3 * k + 2]));
      const Vec3 wb = rotate_inverse(Q, Vec3(ang_vel_w[3 * k], ang_vel_w[3 * k + 1], ang_vel_w[3 * k + 2]));
      for (int c = 0; c < 3; ++c) {
        qd[c] = vb[c];
        qd[3 + c] = wb[c];
      }
      refresh(env_ids[k], *workers_[0]);
    }
    return true;
  }

  void set_velocity_xy(int env, int robot, real vx_w, real vy_w) override {
    (void)robot;
    if (!floating_) return;
    const std::size_t e = static_cast<std::size_t>(env);
    const real* q = &q_[e * static_cast<std::size_t>(nq_)];
    real* qd = &qd_[e * static_cast<std::size_t>(nv_)];
    const Quat Q = quat_from_xyzw(q + 3);
    Vec3 vw = rotate(Q, Vec3(qd[0], qd[1], qd[2]));
    vw[0] = vx_w;
    vw[1] = vy_w;
    const Vec3 vb = rotate_inverse(Q, vw);
    for (int c = 0; c < 3; ++c) qd[c] = vb[c];
    refresh(env, *workers_[0]);
  }

 private:
  static void run_slice(void* self_v, int worker) {
    auto* self = static_cast<ArticulatedSimulator*>(self_v);
    const int threads = self->pool_->size();
    // A static partition into contiguous slices; each environment's result depends on it alone.
    const int begin = static_cast<int>(static_cast<long long>(self->num_envs_) * worker / threads);
    const int end = static_cast<int>(static_cast<long long>(self->num_envs_) * (worker + 1) / threads);
    Worker& w = *self->workers_[static_cast<std::size_t>(worker)];
    const int L = self->batch_lanes_;
    if (L > 1) {
      for (int e0 = begin; e0 < end; e0 += L) {
        const int count = std::min(L, end - e0);
        for (int s = 0; s < self->decimation_; ++s) self->physics_step_group(e0, count, w);
        self->refresh_group(e0, count, w);
      }
      return;
    }
    for (int e = begin; e < end; ++e) {
      for (int s = 0; s < self->decimation_; ++s) self->physics_step(e, w);
      self->refresh(e, w);
    }
  }

  /// A shape posed by its body's transform, as the rigid world's narrow phase takes it.
  static Shape sim_shape(const dy::CollisionShape& s, const dy::Transform& X) {
    Shape out;
    Mat3 R_w;
    dy::shape_pose(s, X, out.position_w, R_w);
    out.orientation_wb = quat_from_rotation_matrix(R_w);
    switch (s.type) {
      case dy::ShapeType::sphere:
        out.type = ShapeType::sphere;
        out.radius_m = s.size[0];
        break;
      case dy::ShapeType::capsule:
        out.type = ShapeType::capsule;
        out.radius_m = s.size[0];
        out.half_length_m = s.size[1];
        break;
      case dy::ShapeType::box:
        out.type = ShapeType::box;
        out.half_extents_m = s.size;
        break;
      case dy::ShapeType::convex:
        out.type = ShapeType::convex_hull;
        out.vertices = s.points;
        out.num_vertices = s.num_points;
        break;
    }
    return out;
  }

  /// Height and unit normal of the terrain at (x, y): its local plane as a half-space.
  void terrain_plane(real x, real y, dy::HalfSpace& g) const {
    const real h = terrain_->height_at(x, y);
    Vec3 n(0, 0, 1);
    if (terrain_->type() != TerrainType::plane) {
      const real d = terrain_->type() == TerrainType::heightfield ? terrain_->spacing_m() / 2 : 0.02_r;
      const real dhdx = (terrain_->height_at(x + d, y) - terrain_->height_at(x - d, y)) / (2 * d);
      const real dhdy = (terrain_->height_at(x, y + d) - terrain_->height_at(x, y - d)) / (2 * d);
      n = Vec3(-dhdx, -dhdy, 1);
      n /= n.norm();
    }
    g.normal_w = n;
    g.offset_m = n.dot(Vec3(x, y, h));
    g.friction = 1;  // legged_gym's ground static friction
    g.restitution = 0;
  }

  /// The randomisation ranges (simulator.*) an articulated robot takes: a range is off (-1, -1) or
  /// 0 <= min <= max (restitution <= 1); the root body keeps a positive mass.
  bool check_randomisation(const WorldConfig& c, const std::string& pre, std::string& error) const {
    const SimulatorConfig& sc = c.simulator;
    const auto range = [&](const char* key, real lo, real hi, real cap) {
      if (lo == -1 && hi == -1) return true;
      if (lo >= 0 && lo <= hi && hi <= cap) return true;
      error = pre + "simulator." + key + ": expected [-1, -1] (not randomised) or [min, max] with 0 <= min <= max <= " +
              std::to_string(static_cast<double>(cap)) + ", got [" + std::to_string(static_cast<double>(lo)) + ", " +
              std::to_string(static_cast<double>(hi)) + "]";
      return false;
    };
    if (!range("friction", sc.friction_min, sc.friction_max, 100) || !range("restitution", sc.restitution_min, sc.restitution_max, 1) ||
        !range("joint_armature_kg_m2", sc.joint_armature_min_kg_m2, sc.joint_armature_max_kg_m2, 1e4))
      return false;
    const real m0 = robot_.multibody.body[0].mass;
    if (!(sc.added_mass_min_kg <= sc.added_mass_max_kg) || !(m0 + sc.added_mass_min_kg > 0)) {
      error = pre + "simulator.added_mass_kg: expected min <= max and a positive root-body mass (" +
              std::to_string(static_cast<double>(m0)) + " kg + min)";
      return false;
    }
    if (!(sc.max_push_force_N >= 0) || !std::isfinite(sc.max_push_force_N) || !(sc.com_bias_max_m >= 0)) {
      error = pre + "simulator.max_push_force_N and com_bias_max_m: expected finite values >= 0";
      return false;
    }
    return true;
  }

  /// Draws environment ei's randomised values (simulator.*) from its stream, a fixed number of
  /// draws per kind that is on, so that one kind's values never shift another's.
  void draw_randomisation(std::size_t ei) {
    const SimulatorConfig& sc = cfg_.simulator;
    RngStream& rng = rng_dr_[ei];
    if (sc.friction_min != -1) dr_friction_[ei] = rng.uniform(sc.friction_min, sc.friction_max);
    if (sc.restitution_min != -1) dr_restitution_[ei] = rng.uniform(sc.restitution_min, sc.restitution_max);
    if (sc.added_mass_min_kg != 0 || sc.added_mass_max_kg != 0) added_mass_kg_[ei] = rng.uniform(sc.added_mass_min_kg, sc.added_mass_max_kg);
    if (sc.com_bias_max_m != 0)
      for (int k = 0; k < 3; ++k) com_bias_b_m_[3 * ei + static_cast<std::size_t>(k)] = rng.uniform(-sc.com_bias_max_m, sc.com_bias_max_m);
    if (sc.joint_armature_min_kg_m2 != -1)
      for (std::size_t j = 0; j < dof_v_.size(); ++j)
        dr_armature_[ei * dof_v_.size() + j] = rng.uniform(sc.joint_armature_min_kg_m2, sc.joint_armature_max_kg_m2);
  }

  /// The worker's model with environment ei's root-body mass and centre of mass and joint armatures.
  const RobotMultibody& env_model(std::size_t ei, Worker& w) const {
    const RobotMultibody& base = robot_.multibody;
    w.model.body[0].mass = base.body[0].mass + added_mass_kg_[ei];
    for (int k = 0; k < 3; ++k) w.model.body[0].com[k] = base.body[0].com[k] + com_bias_b_m_[3 * ei + static_cast<std::size_t>(k)];
    for (std::size_t j = 0; j < dof_v_.size(); ++j) w.model.armature[dof_body_[j]] = dr_armature_[ei * dof_v_.size() + j];
    return w.model;
  }

  /// push_links' forces as joint-space forces: tau += J_b(c_b)^T f_b for every body b, J_b the
  /// Jacobian of its centre of mass c_b (its linear rows, 0-2), f_b its world-frame force. w.data
  /// and X_world hold this physics step's kinematics (physics_step computed them for collision).
  void add_link_push(std::size_t ei, const RobotMultibody& m, const dy::Transform* X_world, real* tau) const {
    constexpr int kDofs = dy::max_dofs<kMaxRobotBodies>();
    real J[6 * kDofs];
    const real* f = &link_push_w_[ei * 3 * static_cast<std::size_t>(m.num_bodies)];
    for (int b = 0; b < m.num_bodies; ++b) {
      dy::point_jacobian(m, X_world, b, m.body[b].com, J, kDofs);
      for (int c = 0; c < m.num_dofs; ++c)
        tau[c] += J[c] * f[3 * b] + J[kDofs + c] * f[3 * b + 1] + J[2 * kDofs + c] * f[3 * b + 2];
    }
  }

  void set_origin(std::size_t e, const Vec3& o) {
    origins_[e] = o;
    for (int k = 0; k < 3; ++k) env_origins_w_[3 * e + static_cast<std::size_t>(k)] = o[k];
  }

  void place_origins() {
    if (terrain_->tile_rows() > 0) {
      // legged_gym's custom origins: environment e on terrain type (column) e * cols / envs (global
      // index over the whole run), at a level drawn in [0, max_init_terrain_level] (below the top row).
      const int rows = terrain_->tile_rows(), cols = terrain_->tile_cols();
      num_terrain_levels_ = rows;
      const int top = std::min(rows - 1, std::max(0, cfg_.env.terrain.max_init_terrain_level));
      for (int e = 0; e < num_envs_; ++e) {
        const std::size_t ei = static_cast<std::size_t>(e);
        terrain_types_[ei] = static_cast<int>(static_cast<long long>(cfg_.env.global_env(e)) * cols / cfg_.env.run_num_envs());
        terrain_levels_[ei] = static_cast<int>(rng_terrain_[ei].next_u32() % static_cast<std::uint32_t>(top + 1));
        set_origin(ei, terrain_->tile_origin(terrain_levels_[ei], terrain_types_[ei]));
      }
      return;
    }
    // A square grid of environments, kEnvSpacing_m apart, centred on the height field (or the origin);
    // the grid of the whole run (env.total_num_envs), a slice taking its own global cells.
    const int cols = std::max(1, static_cast<int>(std::ceil(std::sqrt(static_cast<double>(cfg_.env.run_num_envs())))));
    Vec3 centre = Vec3::Zero();
    if (terrain_->type() == TerrainType::heightfield)
      centre = terrain_->corner_w() + Vec3(terrain_->spacing_m() * static_cast<real>(terrain_->nx() - 1) / 2,
                                           terrain_->spacing_m() * static_cast<real>(terrain_->ny() - 1) / 2, 0);
    for (int e = 0; e < num_envs_; ++e) {
      const int g = static_cast<int>(cfg_.env.global_env(e));
      const real x = (static_cast<real>(g % cols) - static_cast<real>(cols - 1) / 2) * kEnvSpacing_m;
      const real y = (static_cast<real>(g / cols) - static_cast<real>(cols - 1) / 2) * kEnvSpacing_m;
      Vec3 o(centre[0] + x, centre[1] + y, 0);
      o[2] = terrain_->height_at(o[0], o[1]);
      set_origin(static_cast<std::size_t>(e), o);
    }
  }

  /// The robot at its home keyframe over env's origin (the keyframe's base height above the
  /// terrain there), at rest.
  void reset_env(int e, bool count) {
    const std::size_t ei = static_cast<std::size_t>(e);
    real* q = &q_[ei * static_cast<std::size_t>(nq_)];
    real* qd = &qd_[ei * static_cast<std::size_t>(nv_)];
    for (int k = 0; k < nq_; ++k) q[k] = robot_.home_q[static_cast<std::size_t>(k)];
    for (int k = 0; k < nv_; ++k) qd[k] = 0;
    if (floating_) {
      q[0] += origins_[ei][0];
      q[1] += origins_[ei][1];
      q[2] += origins_[ei][2];
      if (num_terrain_levels_ > 0) {
        // legged_gym's _reset_root_states with custom origins: x and y within +-1 m of the tile's
        // centre (its central 2 m x 2 m, whose highest point the origin's height is).
        q[0] += rng_terrain_[ei].uniform(-1, 1);
        q[1] += rng_terrain_[ei].uniform(-1, 1);
      }
    }
    episode_step_[ei] = 0;
    warm_[ei].count = 0;
    joint_pd_reset(drive_, drive_state_[ei], rng_gains_[ei]);
    dr_kp_scale_[ei] = drive_state_[ei].scales.kp_scale;
    dr_kd_scale_[ei] = drive_state_[ei].scales.kd_scale;
    draw_randomisation(ei);
    link_push_due_[ei] = 0;
    std::fill(link_forces_w_.begin() + static_cast<long>(ei * static_cast<std::size_t>(robot_.multibody.num_bodies) * 3),
              link_forces_w_.begin() + static_cast<long>((ei + 1) * static_cast<std::size_t>(robot_.multibody.num_bodies) * 3), 0_r);
    std::fill(torques_.begin() + static_cast<long>(ei * dof_v_.size()), torques_.begin() + static_cast<long>((ei + 1) * dof_v_.size()), 0_r);
    EnvStats& st = stats_[ei];
    ++st.placements;
    if (count) ++st.resets;
  }

  ArticulatedRobot robot_;
  bool floating_ = false;
  std::vector<int> dof_v_, dof_q_;  // per actuated joint: its velocity and configuration coordinate
  std::vector<int> dof_body_;       // per actuated joint: its body
  int batch_lanes_ = 0;  // robots per batched constrained step (0: the scalar step for every robot)
  bool randomise_inertia_ = false;  // added base mass, centre-of-mass bias or joint armature drawn
  bool randomise_contacts_ = false; // friction or restitution drawn
  std::vector<RngStream> rng_dr_, rng_link_push_, rng_terrain_;  // (envs)
  std::vector<real> link_push_w_;         // (envs x links x 3) N: push_links' pending forces
  std::vector<std::uint8_t> link_push_due_;  // (envs) pending forces to apply at the next physics step
  std::vector<real> effort_, home_;
  Drive drive_;                          // the core's joint PD, one parameter set for every robot
  std::vector<DriveState> drive_state_;  // (envs) its delay line, gain scales, held torques
  std::vector<RngStream> rng_gains_;      // (envs) the gain scales' draws
  std::vector<real> height_x_b_, height_y_b_;  // measured_heights points, base-yaw frame
  std::vector<real> heights_;                  // (envs x points)
  std::vector<dy::CollisionShape> shapes_;
  std::vector<std::pair<int, int>> shape_bits_;  // per shape: the file's contype, conaffinity
  std::vector<std::pair<int, int>> self_pairs_;  // shape index pairs that may touch (robot.self_collisions)
  std::vector<real> bound_r_;                    // per shape: its bounding radius about its centre

  // The shape pairs of robot.self_collisions: two shapes on different bodies that no joint
  // connects directly (a joint's two links overlap at the joint by construction, and PhysX's
  // articulations, legged_gym's, never collide them either), and whose collision bits let them
  // touch as MuJoCo's filter does: (contype_a & conaffinity_b) || (contype_b & conaffinity_a).
  bool build_self_pairs(const std::string& pre, std::string& error) {
    const RobotMultibody& m = robot_.multibody;
    if (shapes_.size() > static_cast<std::size_t>(kMaxSelfShapes)) {
      error = pre + "robot.self_collisions: the robot has " + std::to_string(shapes_.size()) + " collision geoms, at most " +
              std::to_string(kMaxSelfShapes) + " with self-collisions on";
      return false;
    }
    for (const dy::CollisionShape& sh : shapes_) bound_r_.push_back(dy::bounding_radius(sh));
    for (std::size_t i = 0; i < shapes_.size(); ++i)
      for (std::size_t j = i + 1; j < shapes_.size(); ++j) {
        const int a = shapes_[i].body, b = shapes_[j].body;
        if (a == b || m.parent[a] == b || m.parent[b] == a) continue;
        const auto& ba = shape_bits_[i];
        const auto& bb = shape_bits_[j];
        if ((ba.first & bb.second) == 0 && (bb.first & ba.second) == 0) continue;
        self_pairs_.push_back({static_cast<int>(i), static_cast<int>(j)});
      }
    return true;
  }
  std::unique_ptr<Terrain> terrain_;
  std::vector<Vec3> origins_;
  int nq_ = 0, nv_ = 0;
  std::vector<real> q_, qd_;  // (envs x nq), (envs x nv)
  std::vector<int> episode_step_;
  std::vector<EnvStats> stats_;
  std::vector<std::uint64_t> step_errors_;
  std::unique_ptr<ThreadPool> pool_;
  std::vector<std::unique_ptr<Worker>> workers_;
  bool auto_reset_ = true;
  dy::ConstraintParams params_;
  std::vector<dy::WarmStart<kWarmRows>> warm_;  // (envs)
};

}  // namespace

std::unique_ptr<Simulator> make_articulated_simulator(const WorldConfig& config, std::string& error) {
  auto sim = std::make_unique<ArticulatedSimulator>();
  if (!sim->init(config, error)) return nullptr;
  return sim;
}

}  // namespace kestrel::sim
