// The rigid World's data: every array a step writes, sized once from a WorldModel
// (make_world_data) and never resized (MuJoCo's mjData). Plain std::vector storage of fixed size,
// structure-of-arrays over robots and environments, so a binding or a viewer can look at it in
// place. Shapes in the comments: E environments, R robots per environment, N = E * R robots
// (index env * R + r), C obstacle slots per environment, P pixels of a ray sensor, H height points.
//
// Determinism: every environment owns its random streams RngStream(seed, env, purpose) and no
// environment reads another's rows, which is what lets the World step slices of environments on
// different threads with bit-identical results for any thread count.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "kestrel/kernel/rigid_body.hpp"
#include "kestrel/kernel/rng.hpp"
#include "kestrel/robots/multirotor.hpp"
#include "kestrel/sensors/imu.hpp"
#include "kestrel/sensors/ray_sensor.hpp"
#include "kestrel/sensors/scene.hpp"
#include "kestrel/sim/collision.hpp"
#include "kestrel/sim/config.hpp"
#include "kestrel/sim/layout.hpp"
#include "kestrel/sim/summary.hpp"

namespace kestrel::sim {

struct WorldModel;

/// One sensor's per-robot outputs (the model's SensorModel holds its constant part).
struct SensorData {
  std::vector<real> ranges;                 // (N x P) ray sensor: range or depth image, row-major
  std::vector<std::int32_t> segmentation;   // (N x P) semantic id, 0 ground, -1 no hit
  std::vector<sensors::Mount> mounts;       // (N) drawn at each reset
  std::vector<sensors::ImuState> imu_state; // (N) IMU: bias and filter state
  std::vector<sensors::ImuSample> imu;      // (N) IMU: latest sample
};

struct WorldData {
  // Per robot.
  std::vector<RigidBodyState> state;               // (N) pose and twist
  std::vector<robots::MultirotorState> mr_state;   // (N) controller, allocator and motor state, fault bits
  std::vector<real> actions;                       // (N x kMaxActionDim) latest action
  std::vector<real> applied_actions;               // (N x kMaxActionDim) what the controller uses now (latency)
  std::vector<Vec3> target_w;                      // (N) episode target
  std::vector<Vec3> setpoint_w;                    // (N) moving setpoint (TaskConfig::setpoint_speed_m_s > 0)
  std::vector<Vec3> contact_force_w;               // (N) from the last collision pass, applied at the next step
  std::vector<Vec3> contact_torque_b;              // (N)
  std::vector<std::uint8_t> crashed;               // (N) contact above the force threshold this env-step

  // Per environment.
  std::vector<std::uint64_t> status_count;         // (E) non-ok core statuses at resets
  std::vector<RngStream> rng_reset, rng_step;      // (E) placement/reset draws; per-step noise/disturbance
  std::vector<RngStream> rng_place, rng_sensor;    // (E) sensor mounts; sensor and IMU noise
  std::vector<Vec3> lower_w, upper_w;              // (E) bounds of the current episode
  std::vector<int> phys_steps, latency;            // (E) physics steps per env-step; step the action arrives
  std::vector<int> episode_step;                   // (E)
  std::vector<std::uint8_t> episode_ended;         // (E) this env-step ended the episode (before any auto-reset)
  std::vector<std::uint8_t> episode_fallback;      // (E) a robot of this episode was placed by a fallback
  std::vector<int> num_obstacles;                  // (E) used slots (<= C)
  std::vector<int> episodes_since_layout;          // (E)
  std::vector<std::uint32_t> layout_generation;    // (E) layouts drawn so far
  std::vector<EnvStats> stats;                     // (E)
  std::vector<Obstacle> obstacles;                 // (E x C)

  std::vector<real> measured_heights;              // (N x H) terrain z under each robot's height points
  std::vector<SensorData> sensors;                 // (model.sensors.size())

  // Ray-sensor scenes over this storage (scene_capacity S objects per environment; no heap after set-up).
  std::vector<sensors::SceneObject> scene_objects;   // (E x S)
  std::vector<sensors::BvhNode> scene_nodes;         // (E x bvh_node_capacity(S))
  std::vector<std::uint32_t> scene_prim_index, scene_bvh_objects;  // (E x S)
  std::vector<sensors::Aabb> scene_boxes;            // (E x S)
  std::vector<sensors::Scene> scenes;                // (E)

  // Trace of robot 0's position (World::enable_trace): (trace_envs x trace_cap), with the target
  // and the episode number (the environment's resets so far) of each point, so a plot can split
  // the episodes and mark each one's start and target without guessing from jumps.
  std::vector<Vec3> trace;
  std::vector<Vec3> trace_target;
  std::vector<std::uint32_t> trace_episode;
  int trace_envs = 0, trace_cap = 0, trace_len = 0;
  std::uint64_t trace_base = 0;

  // Run-time settings a step reads.
  real curriculum_level = 1;  // obstacle-count level in [0, 1], from the next layout on
  bool auto_reset = true;     // false: an ended episode is flagged, its owner resets it

  Obstacle* env_obstacles(int env, int capacity) { return obstacles.data() + static_cast<std::size_t>(env) * static_cast<std::size_t>(capacity); }
  const Obstacle* env_obstacles(int env, int capacity) const {
    return obstacles.data() + static_cast<std::size_t>(env) * static_cast<std::size_t>(capacity);
  }
};

/// Sizes every array for the model and seeds every stream (no environment is reset yet).
void make_world_data(const WorldModel& model, WorldData& data);

/// Bytes one environment's data takes (robots, obstacles, streams, counters, sensors, heights),
/// from the config alone: the same figure before anything is allocated and once built.
std::size_t world_bytes_per_env(const WorldConfig& cfg, int obstacle_capacity, int height_points);
/// world_bytes_per_env x num_envs for a config not yet compiled (double: a bad config's product
/// must not wrap); compile_world_model refuses a config above max_memory_gib with it.
double estimate_world_bytes(const WorldConfig& config);

}  // namespace kestrel::sim
