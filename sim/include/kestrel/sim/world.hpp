// The batched world: N environments, each with one or more robots and its own obstacles, stepped
// in parallel by a fixed thread pool over a static partition of environment indices.
//
// Storage is structure-of-arrays over robots (index env * robots_per_env + r) and over obstacle
// slots (index env * obstacle_capacity + i), all sized when the world is built (MuJoCo's
// mjModel/mjData split: WorldConfig is the constant model, the arrays are the data). step()
// never allocates (tests/sim/world_test.cpp proves it with a heap counter).
//
// Determinism: every environment owns its random streams RngStream(seed, env, purpose) and no
// environment reads another's state, so a worker can advance its whole slice of environments by
// several env-steps without synchronising, and the result is bit-identical for any thread count
// (golden-hash test in tests/sim/world_test.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "kestrel/allocation/airframe.hpp"
#include "kestrel/allocation/allocation_model.hpp"
#include "kestrel/allocation/motor_model.hpp"
#include "kestrel/allocation/sequential_desaturation.hpp"
#include "kestrel/controllers/controller.hpp"
#include "kestrel/kernel/rigid_body.hpp"
#include "kestrel/kernel/rng.hpp"
#include "kestrel/robots/multirotor.hpp"
#include "kestrel/sim/collision.hpp"
#include "kestrel/sim/config.hpp"
#include "kestrel/sim/limits.hpp"
#include "kestrel/sim/summary.hpp"
#include "kestrel/sim/thread_pool.hpp"
#include "kestrel/sensors/imu.hpp"
#include "kestrel/sensors/ray_sensor.hpp"
#include "kestrel/sensors/scene.hpp"

namespace kestrel::sim {

class Terrain;
namespace batch {
struct Models;
}
struct SceneMesh;

/// One obstacle slot. Obstacles of an environment are kept sorted by aabb_min_w.x (the sweep
/// order of the broad phase); a moving obstacle may change its index after a step.
struct Obstacle {
  Shape shape;
  Vec3 linvel_w = Vec3::Zero();   // dynamic environment: set per reset or by set_obstacle_velocity
  Vec3 angvel_w = Vec3::Zero();   // dynamic environment: world-frame angular velocity, set per reset
  Vec3 aabb_min_w = Vec3::Zero();
  Vec3 aabb_max_w = Vec3::Zero();
  std::int16_t semantic_id = 0;
  AssetKind kind = AssetKind::cube;
  std::uint8_t class_index = 0;
};

class World {
 public:
  /// Builds a world from a validated config. Returns nullptr and a message on bad parameters;
  /// nothing is half-built. Every environment is reset once (episode 0).
  static std::unique_ptr<World> create(const WorldConfig& config, std::string& error);
  /// Bytes the world's per-environment storage will take (what bytes_per_env() x num_envs reports
  /// once built), from the config alone: create() refuses a config above max_memory_gib with it,
  /// before allocating. Double: a bad config's product must not wrap.
  static double estimate_bytes(const WorldConfig& config);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  /// Advances every environment by num_env_steps env-steps (each: several physics steps).
  void step(int num_env_steps = 1);

  const WorldConfig& config() const { return cfg_; }
  int num_envs() const { return num_envs_; }
  int robots_per_env() const { return robots_per_env_; }
  int num_threads() const { return pool_ ? pool_->size() : 1; }

  RigidBodyState& robot_state(int env, int robot) { return state_[index(env, robot)]; }
  const RigidBodyState& robot_state(int env, int robot) const { return state_[index(env, robot)]; }
  /// The action array the controller reads (kMaxActionDim values; the task writes it at reset).
  real* action(int env, int robot) { return &actions_[index(env, robot) * kMaxActionDim]; }
  const Vec3& target(int env, int robot) const { return target_w_[index(env, robot)]; }
  bool crashed(int env, int robot) const { return crashed_[index(env, robot)] != 0; }
  const Vec3& contact_force_w(int env, int robot) const { return contact_force_w_[index(env, robot)]; }
  int num_obstacles(int env) const { return num_obstacles_[env]; }
  Obstacle& obstacle(int env, int i) { return obstacles_[static_cast<std::size_t>(env) * obstacle_capacity_ + i]; }
  const Obstacle& obstacle(int env, int i) const {
    return obstacles_[static_cast<std::size_t>(env) * obstacle_capacity_ + i];
  }
  int obstacle_capacity() const { return obstacle_capacity_; }
  void lower_upper_bounds(int env, Vec3& lower_w, Vec3& upper_w) const {
    lower_w = lower_w_[env];
    upper_w = upper_w_[env];
  }
  int physics_steps_per_env_step(int env) const { return phys_steps_[env]; }
  int latency_physics_steps(int env) const { return latency_[env]; }
  int episode_step(int env) const { return episode_step_[env]; }
  std::uint32_t layout_generation(int env) const { return layout_generation_[env]; }
  const EnvStats& stats(int env) const { return stats_[env]; }

  /// Resets one environment now (what a crash, timeout or out-of-bounds does at step end).
  void reset_env(int env);
  /// false: step() still flags crashes and counts timeouts/exits but never resets an environment;
  /// the owner (a Task, sim/task.hpp) resets after computing its reward on the final state.
  void set_auto_reset(bool on) { auto_reset_ = on; }
  /// Obstacle-count curriculum level in [0, 1]; takes effect at each environment's next layout.
  void set_curriculum_level(real level) { cfg_.env.curriculum_level = level; }

  WorldSummary summary() const;
  /// FNV-1a (64-bit) over every environment's final state, in environment order.
  std::uint64_t state_hash() const;
  /// Bytes of world storage per environment (robots, obstacles, streams, counters).
  std::size_t bytes_per_env() const;

  /// Records robot 0's position of the first num_envs environments for max_env_steps env-steps
  /// (allocated here, written by step() without allocation).
  void enable_trace(int num_envs, int max_env_steps);
  int trace_envs() const { return trace_envs_; }
  int trace_length() const { return trace_len_; }
  const Vec3& trace_point(int env, int k) const { return trace_[static_cast<std::size_t>(env) * trace_cap_ + k]; }

  // Sensors in the loop (config().robot.sensors; sensor index = position in that list). Ray
  // sensors (lidar, ToF, camera) render against the environment's obstacles every `every_env_steps`
  // env-steps and at every reset; IMUs update every physics step. Read-only views, valid until
  // the next step(); per robot, row-major images (row 0 = top).
  int num_sensors() const { return static_cast<int>(sensors_.size()); }
  const SensorConfig& sensor_config(int sensor) const { return cfg_.robot.sensors[static_cast<std::size_t>(sensor)]; }
  /// Image size of a ray sensor (0 x 0 for an IMU).
  int sensor_height(int sensor) const { return static_cast<int>(sensors_[static_cast<std::size_t>(sensor)].table.height); }
  int sensor_width(int sensor) const { return static_cast<int>(sensors_[static_cast<std::size_t>(sensor)].table.width); }
  /// Range image (depth for a depth camera), post-processed as the sensor config says; null for an IMU.
  const real* sensor_ranges(int env, int sensor, int robot = 0) const;
  /// Segmentation image (obstacle semantic id, 0 ground, -1 no hit); null for an IMU.
  const std::int32_t* sensor_segmentation(int env, int sensor, int robot = 0) const;
  /// Latest IMU measurement (zero sample for a ray sensor).
  const sensors::ImuSample& imu_sample(int env, int sensor, int robot = 0) const;
  /// Mount drawn at the environment's last reset.
  const sensors::Mount& sensor_mount(int env, int sensor, int robot = 0) const;
  /// Rebuilds the environment's scene from its obstacles and renders every ray sensor now
  /// (what step() does; no heap). For tests and owners that move robots or obstacles by hand.
  void render_sensors(int env);
  /// After an owner (a Task's randomisation terms, sim/task.hpp) rewrote obstacle shapes of an
  /// environment through obstacle(): recomputes their bounding boxes, restores the sweep order
  /// and re-renders the ray sensors (no heap).
  void obstacles_changed(int env);
  /// Runs fn(context, begin, end) on each worker of step() right after that worker's slice
  /// [begin, end) of environments has stepped (same static partition, no extra dispatch): the
  /// rigid Simulator refreshes its flat views there, in parallel. nullptr: nothing.
  using SliceHook = void (*)(void* context, int begin, int end);
  void set_after_step(SliceHook fn, void* context) {
    after_step_ = fn;
    after_step_context_ = context;
  }

  /// Worker entry (public for the thread pool's trampoline).
  void run_slice(int worker);

  /// Batched twin of the robot step (sim/batch_step.hpp), on by default where the configuration
  /// allows it and bit-identical to the scalar path. set_batched(false) forces the scalar path
  /// (tests, bench); returns whether the batched path is in use afterwards.
  bool set_batched(bool on);
  bool batched() const { return batch_; }

  // Terrain (config().env.terrain, sim/terrain.hpp): shared by every environment.
  const Terrain* terrain() const { return terrain_.get(); }
  /// measured_heights (legged_gym): world z of the terrain under each robot's height points
  /// (measured_points_x/y rotated by the robot's yaw, x-major: point k = ix * ny + iy), updated at
  /// every env-step end and reset. Shape (num_envs x robots_per_env x num_height_points()); 0
  /// points unless env.terrain.measure_heights. Plane terrain: the ground plane's z (-1e30 with
  /// create_ground_plane false); heights outside a height field: its nearest edge.
  int num_height_points() const { return height_points_; }
  const real* measured_heights() const { return measured_heights_.data(); }
  const real* measured_heights(int env, int robot) const {
    return measured_heights_.data() + index(env, robot) * static_cast<std::size_t>(height_points_);
  }

  // Used by the rigid backend of the Simulator interface (sim/simulator.hpp).
  /// Puts an exact root state and clears the pending contact wrench and the crash flag.
  void set_root_state(int env, int robot, const RigidBodyState& s) {
    state_[index(env, robot)] = s;
    contact_force_w_[index(env, robot)] = Vec3::Zero();
    contact_torque_b_[index(env, robot)] = Vec3::Zero();
    crashed_[index(env, robot)] = 0;
  }
  const Vec3& contact_torque_b(int env, int robot) const { return contact_torque_b_[index(env, robot)]; }
  const ControllerState& controller_state(int env, int robot) const { return mr_state_[index(env, robot)].ctrl; }
  const allocation::MotorModelState& motor_state(int env, int robot) const { return mr_state_[index(env, robot)].motors; }
  const allocation::Airframe& airframe() const { return mr_.airframe; }
  const allocation::MotorModelConfig& motor_config() const { return mr_.motors; }
  const ControllerParams& controller_params() const { return mr_.ctrl; }
  /// The robots' control chain (robots/multirotor.hpp), compiled once for the world.
  const robots::MultirotorModel& robot_model() const { return mr_; }
  /// Non-ok statuses returned by the core while resetting this environment's robots, summed since
  /// set-up (reported in the summary; statuses inside a step are latched as fault bits instead).
  std::uint64_t reset_status_count(int env) const { return status_count_[static_cast<std::size_t>(env)]; }

 private:
  World() = default;
  std::size_t index(int env, int robot) const { return static_cast<std::size_t>(env) * robots_per_env_ + robot; }
  void env_step(int env);
  void env_step_begin(int env);
  void env_step_end(int env);
  void physics_step(int env, bool use_new_action);
  void physics_step_tail(int env);
  // Batched path (world_batch.cpp).
  bool batch_eligible() const;
  int env_steps_batched(int begin, int end);  // returns the first environment it left to the caller
  void robot_dynamics_batch(int env0, unsigned new_action_mask, const batch::Models& models);
  void robot_dynamics(int env, int robot, std::size_t i, bool use_new_action);
  void move_obstacles(int env);
  void collide_robots(int env);
  void generate_layout(int env, RngStream& rng);
  bool overlaps_obstacle(int env, const Shape& s) const;
  bool clear_point(int env, const Vec3& p) const;
  bool clear_segment(int env, const Vec3& a, const Vec3& b) const;
  void update_scene(int env);
  void update_measured_heights(int env);
  real ground_height(real x_w, real y_w, int env) const;
  void render_ray_sensors(int env, bool all);
  void update_imus(int env, int robot, const Vec3& linvel_before_w);
  bool setup_sensors(std::string& error);

  // One attached sensor: constant ray table plus per-robot outputs, mounts and IMU state (all
  // sized at set-up; indexed by robot index env * robots_per_env + r).
  struct SensorSlot {
    SensorKind kind = SensorKind::camera;
    int every = 1;
    bool depth = false;
    sensors::RangeOutputParams range;
    sensors::NoiseParams noise;
    sensors::MountParams mount;
    std::vector<real> dirs_s, depth_scale;
    sensors::RayTable table;
    std::size_t pixels = 0;
    std::vector<real> ranges;                 // robots x pixels
    std::vector<std::int32_t> segmentation;   // robots x pixels
    std::vector<sensors::Mount> mounts;       // robots
    std::vector<sensors::ImuState> imu_state; // robots (IMU)
    std::vector<sensors::ImuSample> imu;      // robots (IMU)
  };

  WorldConfig cfg_;
  int num_envs_ = 0, robots_per_env_ = 0, obstacle_capacity_ = 0;
  std::size_t action_dim_ = 0;
  real robot_bound_radius_m_ = 0;  // bounding sphere of the robot's collision shape

  // Constant per-world models (robots are identical within a world).
  RigidBodyModel body_model_;
  robots::MultirotorModel mr_;  // controller -> allocation -> motors (robots/multirotor.hpp)

  // Per robot (num_envs * robots_per_env).
  std::vector<RigidBodyState> state_;
  std::vector<robots::MultirotorState> mr_state_;  // controller, allocator and motor state
  std::vector<real> actions_;          // (robots x kMaxActionDim): latest action
  std::vector<real> applied_actions_;  // (robots x kMaxActionDim): what the controller uses now
  std::vector<Vec3> target_w_;
  std::vector<Vec3> setpoint_w_;       // moving setpoint (TaskConfig::setpoint_speed_m_s > 0)
  std::vector<Vec3> contact_force_w_;  // from the last collision pass, applied at the next step
  std::vector<Vec3> contact_torque_b_;
  std::vector<std::uint8_t> crashed_;

  // Per environment.
  std::vector<std::uint64_t> status_count_;  // non-ok core statuses (step_status_count)
  void count_status(int env, Status st) {
    if (st != Status::ok) ++status_count_[static_cast<std::size_t>(env)];
  }
  std::vector<RngStream> rng_reset_, rng_step_;  // placement/reset draws; per-step noise/disturbance
  std::vector<Vec3> lower_w_, upper_w_;
  std::vector<int> phys_steps_, latency_, episode_step_, num_obstacles_, episodes_since_layout_;
  std::vector<std::uint32_t> layout_generation_;
  std::vector<EnvStats> stats_;

  std::vector<Obstacle> obstacles_;  // (num_envs x obstacle_capacity)
  bool obstacles_rotate_ = false;    // some asset class has max_angular_speed_rad_s > 0

  // Terrain and measured heights (num_envs x robots x height_points_).
  std::unique_ptr<Terrain> terrain_;
  int height_points_ = 0;
  std::vector<real> height_points_x_b_, height_points_y_b_;  // (height_points_) body-yaw-frame offsets
  std::vector<real> measured_heights_;
  std::vector<std::vector<Vec3>> mesh_vertices_;  // per asset class (AssetKind::mesh), set-up only
  std::vector<std::unique_ptr<SceneMesh>> render_meshes_;  // per asset class (AssetKind::mesh): what sensors see

  // Sensors: per-environment scenes over caller storage (scene_capacity_ objects each: the
  // obstacle slots plus the ground plane), the streams of placement and sensor noise.
  std::vector<SensorSlot> sensors_;
  bool any_ray_sensor_ = false, any_imu_ = false;
  std::uint32_t scene_capacity_ = 0;
  std::vector<sensors::SceneObject> scene_objects_;
  std::vector<sensors::BvhNode> scene_nodes_;
  std::vector<std::uint32_t> scene_prim_index_, scene_bvh_objects_;
  std::vector<sensors::Aabb> scene_boxes_;
  std::vector<sensors::Scene> scenes_;
  std::vector<RngStream> rng_place_, rng_sensor_;

  // Trace.
  std::vector<Vec3> trace_;
  int trace_envs_ = 0, trace_cap_ = 0, trace_len_ = 0;
  std::uint64_t trace_base_ = 0;

  // Threads: static partition, pending env-steps for run_slice.
  SliceHook after_step_ = nullptr;
  void* after_step_context_ = nullptr;
  std::unique_ptr<ThreadPool> pool_;
  int pending_steps_ = 0;
  bool auto_reset_ = true;
  bool batch_ = false;
};


}  // namespace kestrel::sim
