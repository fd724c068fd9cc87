// The batched world: N environments, each with one or more robots and its own obstacles, stepped
// in parallel by a fixed thread pool that hands out blocks of environments (World::run_slice).
//
// A World owns a WorldModel (sim/world_model.hpp: compiled once, read-only) and a WorldData
// (sim/world_data.hpp: every array a step writes, sized once), MuJoCo's mjModel / mjData split,
// and steps them through the stage functions of sim/world_stages.hpp. The accessors below are
// conveniences over those two; model() and data() give the whole of each (what a binding or a
// viewer reads in place). step() never allocates (tests/sim/engine/world_test.cpp proves it with a heap
// counter).
//
// Determinism: every environment owns its random streams RngStream(seed, env, purpose) and no
// environment reads another's state, so a worker can advance its whole slice of environments by
// several env-steps without synchronising, and the result is bit-identical for any thread count
// (golden-hash test in tests/sim/engine/world_test.cpp).
#pragma once

#include <atomic>
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
#include "kestrel/sim/world_data.hpp"
#include "kestrel/sim/world_model.hpp"
#include "kestrel/sim/world_stages.hpp"
#include "kestrel/sensors/imu.hpp"
#include "kestrel/sensors/ray_sensor.hpp"
#include "kestrel/sensors/scene.hpp"

namespace kestrel::sim {


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

  const WorldConfig& config() const { return model_.cfg; }
  /// The compiled model and the data a step writes (sim/world_model.hpp, sim/world_data.hpp).
  /// data() is writable between steps (what the rigid Simulator's resets and a task's object
  /// placement do); a stage function run on it must keep each environment's rows to itself.
  const WorldModel& model() const { return model_; }
  WorldData& data() { return data_; }
  const WorldData& data() const { return data_; }
  int num_envs() const { return model_.num_envs; }
  int robots_per_env() const { return model_.robots_per_env; }
  int num_threads() const { return pool_ ? pool_->size() : 1; }

  RigidBodyState& robot_state(int env, int robot) { return data_.state[index(env, robot)]; }
  const RigidBodyState& robot_state(int env, int robot) const { return data_.state[index(env, robot)]; }
  /// The action array the controller reads (kMaxActionDim values; the task writes it at reset).
  real* action(int env, int robot) { return &data_.actions[index(env, robot) * kMaxActionDim]; }
  const Vec3& target(int env, int robot) const { return data_.target_w[index(env, robot)]; }
  bool crashed(int env, int robot) const { return data_.crashed[index(env, robot)] != 0; }
  const Vec3& contact_force_w(int env, int robot) const { return data_.contact_force_w[index(env, robot)]; }
  int num_obstacles(int env) const { return data_.num_obstacles[env]; }
  Obstacle& obstacle(int env, int i) { return data_.env_obstacles(env, model_.obstacle_capacity)[i]; }
  const Obstacle& obstacle(int env, int i) const {
    return data_.env_obstacles(env, model_.obstacle_capacity)[i];
  }
  int obstacle_capacity() const { return model_.obstacle_capacity; }
  void lower_upper_bounds(int env, Vec3& lower_w, Vec3& upper_w) const {
    lower_w = data_.lower_w[env];
    upper_w = data_.upper_w[env];
  }
  int physics_steps_per_env_step(int env) const { return data_.phys_steps[env]; }
  int latency_physics_steps(int env) const { return data_.latency[env]; }
  int episode_step(int env) const { return data_.episode_step[env]; }
  std::uint32_t layout_generation(int env) const { return data_.layout_generation[env]; }
  const EnvStats& stats(int env) const { return data_.stats[env]; }

  /// Resets one environment now (what a crash, timeout or out-of-bounds does at step end).
  void reset_env(int env);
  /// false: step() still flags crashes and counts timeouts/exits but never resets an environment;
  /// the owner (a Task, sim/task.hpp) resets after computing its reward on the final state.
  void set_auto_reset(bool on) { data_.auto_reset = on; }
  /// Obstacle-count curriculum level in [0, 1]; takes effect at each environment's next layout.
  void set_curriculum_level(real level) { data_.curriculum_level = level; }

  WorldSummary summary() const;
  /// FNV-1a (64-bit) over every environment's final state, in environment order.
  std::uint64_t state_hash() const;
  /// Bytes of world storage per environment (robots, obstacles, streams, counters).
  std::size_t bytes_per_env() const;

  /// Records robot 0's position of the first num_envs environments for max_env_steps env-steps
  /// (allocated here, written by step() without allocation).
  void enable_trace(int num_envs, int max_env_steps);
  int trace_envs() const { return data_.trace_envs; }
  int trace_length() const { return data_.trace_len; }
  const Vec3& trace_point(int env, int k) const { return data_.trace[trace_index(env, k)]; }
  /// The target of robot 0 and the episode number (resets of the environment before it) at point k.
  const Vec3& trace_target(int env, int k) const { return data_.trace_target[trace_index(env, k)]; }
  std::uint32_t trace_episode(int env, int k) const { return data_.trace_episode[trace_index(env, k)]; }

  // Sensors in the loop (config().robot.sensors; sensor index = position in that list). Ray
  // sensors (lidar, ToF, camera) render against the environment's obstacles every `every_env_steps`
  // env-steps and at every reset; IMUs update every physics step. Read-only views, valid until
  // the next step(); per robot, row-major images (row 0 = top).
  int num_sensors() const { return static_cast<int>(model_.sensors.size()); }
  const SensorConfig& sensor_config(int sensor) const { return model_.cfg.robot.sensors[static_cast<std::size_t>(sensor)]; }
  /// Image size of a ray sensor (0 x 0 for an IMU).
  int sensor_height(int sensor) const { return static_cast<int>(model_.sensors[static_cast<std::size_t>(sensor)].table.height); }
  int sensor_width(int sensor) const { return static_cast<int>(model_.sensors[static_cast<std::size_t>(sensor)].table.width); }
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
  /// Runs fn(context, begin, end) on the worker of step() that stepped chunk [begin, end), right
  /// after the chunk has taken its last env-step (no extra dispatch; chunks of 64 environments,
  /// each once per call, so the rows are still in cache): the rigid Simulator
  /// refreshes its flat views there, in parallel. nullptr: nothing.
  using SliceHook = void (*)(void* context, int begin, int end);
  void set_after_step(SliceHook fn, void* context) {
    after_step_ = fn;
    after_step_context_ = context;
  }

  /// Worker entry (public for the thread pool's trampoline): takes blocks of environments from a
  /// shared counter until none is left.
  void run_slice(int worker);

  /// Batched twin of the robot step (sim/batch_step.hpp), on by default where the configuration
  /// allows it and bit-identical to the scalar path. set_batched(false) forces the scalar path
  /// (tests, bench); returns whether the batched path is in use afterwards.
  bool set_batched(bool on);
  bool batched() const { return batch_; }
  /// Environments per temporal block of step() (the env-step by env-step path; the fused path
  /// blocks by lane group): a worker takes a block through all of a call's env-steps before it
  /// takes the next (rows stay in cache; no result changes). The block is also the unit the
  /// workers take from the shared counter, so a value >= num_envs gives the whole world to one
  /// worker. Default: about 256 KB of rows; set_block_envs(0) restores it. For benches and tests.
  void set_block_envs(int envs);
  /// Fused env-steps (stage::env_steps_fused, batch::robot_env_steps): a lane group's robots stay
  /// in registers through the quiet env-steps of a step() call. On by default with the batched
  /// path where the world allows it; the same bits either way. set_fused(false) turns it off
  /// (tests, bench); returns whether it is in use afterwards. It needs the batched path: off while
  /// set_batched(false) holds, back (unless set_fused(false) was asked) with set_batched(true).
  bool set_fused(bool on);
  bool fused() const { return fused_; }
  int block_envs() const { return block_envs_; }

  // Terrain (config().env.terrain, sim/terrain.hpp): shared by every environment.
  const Terrain* terrain() const { return model_.terrain.get(); }
  /// measured_heights (legged_gym): world z of the terrain under each robot's height points
  /// (measured_points_x/y rotated by the robot's yaw, x-major: point k = ix * ny + iy), updated at
  /// every env-step end and reset. Shape (num_envs x robots_per_env x num_height_points()); 0
  /// points unless env.terrain.measure_heights. Plane terrain: the ground plane's z (-1e30 with
  /// create_ground_plane false); heights outside a height field: its nearest edge.
  int num_height_points() const { return model_.height_points; }
  const real* measured_heights() const { return data_.measured_heights.data(); }
  const real* measured_heights(int env, int robot) const {
    return data_.measured_heights.data() + index(env, robot) * static_cast<std::size_t>(model_.height_points);
  }

  // Used by the rigid backend of the Simulator interface (sim/simulator.hpp).
  /// Puts an exact root state and clears the pending contact wrench and the crash flag.
  void set_root_state(int env, int robot, const RigidBodyState& s) {
    data_.state[index(env, robot)] = s;
    data_.contact_force_w[index(env, robot)] = Vec3::Zero();
    data_.contact_torque_b[index(env, robot)] = Vec3::Zero();
    data_.crashed[index(env, robot)] = 0;
  }
  const Vec3& contact_torque_b(int env, int robot) const { return data_.contact_torque_b[index(env, robot)]; }
  const ControllerState& controller_state(int env, int robot) const { return data_.mr_state[index(env, robot)].ctrl; }
  const allocation::MotorModelState& motor_state(int env, int robot) const { return data_.mr_state[index(env, robot)].motors; }
  const allocation::Airframe& airframe() const { return model_.mr.airframe; }
  const allocation::MotorModelConfig& motor_config() const { return model_.mr.motors; }
  const ControllerParams& controller_params() const { return model_.mr.ctrl; }
  /// The robots' control chain (robots/multirotor.hpp), compiled once for the world.
  const robots::MultirotorModel& robot_model() const { return model_.mr; }
  /// Non-ok statuses returned by the core while resetting this environment's robots, summed since
  /// set-up (reported in the summary; statuses inside a step are latched as fault bits instead).
  std::uint64_t reset_status_count(int env) const { return data_.status_count[static_cast<std::size_t>(env)]; }

 private:
  World() = default;
  std::size_t index(int env, int robot) const { return model_.index(env, robot); }
  std::size_t trace_index(int env, int k) const {
    return static_cast<std::size_t>(env) * static_cast<std::size_t>(data_.trace_cap) + static_cast<std::size_t>(k);
  }

  WorldModel model_;  // compiled once by create(); never written by a step
  WorldData data_;    // everything a step writes

  // Threads: pending env-steps and the block counter for run_slice.
  SliceHook after_step_ = nullptr;
  void* after_step_context_ = nullptr;
  std::unique_ptr<ThreadPool> pool_;
  int pending_steps_ = 0;
  std::atomic<int> next_env_{0};  // the next block's first environment (run_slice hands out blocks)
  int block_envs_ = 0;            // set by create()
  bool batch_ = false;
  bool fused_ = false;
  bool fused_wanted_ = true;  // set_fused's last request
};


}  // namespace kestrel::sim
