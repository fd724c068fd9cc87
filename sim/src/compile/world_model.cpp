// Compiling a WorldConfig into the rigid World's model (validation, rigid-body model, control
// chain, terrain, meshes, sensor tables) and sizing its data: everything set-up allocates.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include "kestrel/sim/limits.hpp"
#include "kestrel/sim/mesh.hpp"
#include "kestrel/sim/robot_model.hpp"
#include "kestrel/sim/schema.hpp"
#include "kestrel/sim/terrain.hpp"
#include "kestrel/sim/world_data.hpp"
#include "kestrel/sim/world_model.hpp"

namespace kestrel::sim {

WorldModel::WorldModel() = default;
WorldModel::~WorldModel() = default;

int asset_class_slots(const AssetClass& c) {
  if (c.kind == AssetKind::wall) return 5;  // four side walls and a ceiling around the bounds
  // In 64 bits and saturated: a tree class of 6e8 assets overflowed int here (fuzz F5), giving a
  // negative capacity. check_config_limits bounds num_assets long before this matters.
  const long long n = static_cast<long long>(c.num_assets) * (c.kind == AssetKind::tree ? 1 + kTreeBranches : 1);
  return static_cast<int>(std::min<long long>(n, std::numeric_limits<int>::max()));
}

std::size_t world_bytes_per_env(const WorldConfig& cfg, int obstacle_capacity, int height_points) {
  const std::size_t per_robot = sizeof(RigidBodyState) + sizeof(robots::MultirotorState) +
                                2 * kMaxActionDim * sizeof(real) + 3 * sizeof(Vec3) + 1;
  const std::size_t per_env = 2 * sizeof(RngStream) + 2 * sizeof(Vec3) + 6 * sizeof(int) + sizeof(std::uint32_t) +
                              sizeof(EnvStats) + static_cast<std::size_t>(obstacle_capacity) * sizeof(Obstacle);
  std::size_t sensor_per_robot = 0;
  bool any_ray = false;
  for (const SensorConfig& c : cfg.robot.sensors) {
    if (c.kind == SensorKind::imu) {
      sensor_per_robot += sizeof(sensors::ImuState) + sizeof(sensors::ImuSample);
      continue;
    }
    any_ray = true;
    const bool cam = c.kind == SensorKind::camera;
    const std::size_t pixels = static_cast<std::size_t>(cam ? c.camera.height : c.lidar.height) * (cam ? c.camera.width : c.lidar.width);
    sensor_per_robot += pixels * (sizeof(real) + sizeof(std::int32_t)) + sizeof(sensors::Mount);
  }
  const std::uint32_t scene_capacity = static_cast<std::uint32_t>(obstacle_capacity) + 1;
  const std::size_t scene = any_ray ? sizeof(sensors::Scene) + static_cast<std::size_t>(scene_capacity) *
                                          (sizeof(sensors::SceneObject) + 2 * sizeof(std::uint32_t) + sizeof(sensors::Aabb)) +
                                          sensors::bvh_node_capacity(scene_capacity) * sizeof(sensors::BvhNode)
                                    : 0;
  sensor_per_robot += static_cast<std::size_t>(height_points) * sizeof(real);  // measured_heights
  return per_env + scene + (per_robot + sensor_per_robot) * static_cast<std::size_t>(cfg.robot.robots_per_env);
}

double estimate_world_bytes(const WorldConfig& config) {
  int cap = 0;
  for (const AssetClass& c : config.env.assets) cap += asset_class_slots(c);
  const TerrainConfig& t = config.env.terrain;
  const int points = t.measure_heights ? static_cast<int>(t.measured_points_x_m.size() * t.measured_points_y_m.size()) : 0;
  // In double: the product of a bad config's counts must not wrap before it is compared.
  return static_cast<double>(world_bytes_per_env(config, cap, points)) * static_cast<double>(config.env.num_envs);
}

namespace {

/// The checks of every field a model needs, each a message naming the field and what is allowed.
bool validate(const WorldConfig& config, std::string& error);

/// The sensors' constant part: ray tables and output parameters (per robot.sensors entry).
bool compile_sensors(const WorldConfig& cfg, WorldModel& m, std::string& error) {
  m.sensors.resize(cfg.robot.sensors.size());
  for (std::size_t k = 0; k < m.sensors.size(); ++k) {
    const SensorConfig& c = cfg.robot.sensors[k];
    SensorModel& s = m.sensors[k];
    s.kind = c.kind;
    s.every = c.every_env_steps;
    if (c.every_env_steps < 1) {
      error = "robot.sensors." + c.name + ": every must be a positive integer";
      return false;
    }
    if (c.kind == SensorKind::imu) {
      m.any_imu = true;
      continue;
    }
    m.any_ray_sensor = true;
    const bool cam = c.kind == SensorKind::camera;
    const std::uint32_t h = cam ? c.camera.height : c.lidar.height, wd = cam ? c.camera.width : c.lidar.width;
    s.pixels = static_cast<std::size_t>(h) * wd;
    s.dirs_s.assign(3 * s.pixels, 0);
    s.depth_scale.assign(s.pixels, 1);
    s.table.dirs_s = s.dirs_s.data();
    s.table.depth_scale = s.depth_scale.data();
    s.table.capacity = static_cast<std::uint32_t>(s.pixels);
    const Status st = cam ? sensors::camera_rays(c.camera, s.table) : sensors::lidar_rays(c.lidar, s.table);
    if (st != Status::ok || s.pixels == 0) {
      error = "robot.sensors." + c.name + ": invalid ray pattern";
      return false;
    }
    s.depth = cam && c.camera.calculate_depth;
    s.range = cam ? c.camera.range : c.lidar.range;
    s.noise = cam ? c.camera.noise : c.lidar.noise;
    s.mount = cam ? c.camera.mount : c.lidar.mount;
  }
  // Every obstacle slot plus the ground plane.
  if (m.any_ray_sensor) m.scene_capacity = static_cast<std::uint32_t>(m.obstacle_capacity) + 1;
  return true;
}

}  // namespace

bool compile_world_model(const WorldConfig& config, WorldModel& m, std::string& error) {
  auto fail = [&](const std::string& msg) {
    error = msg;
    return false;
  };
  if (!validate(config, error)) return false;
  const EnvConfig& e = config.env;
  m.cfg = config;
  m.num_envs = e.num_envs;
  m.robots_per_env = config.robot.robots_per_env;

  // Robot models (validated by the core's own checks).
  RigidBodyParams bp;
  bp.mass_kg = config.robot.mass_kg;
  bp.inertia_b = config.robot.inertia_diag_kg_m2.asDiagonal();
  bp.gravity_w = config.sim.gravity_w;
  bp.linear_drag_b = config.robot.linear_drag_b;
  bp.quadratic_drag_b = config.robot.quadratic_drag_b;
  bp.angular_drag_b = config.robot.angular_drag_b;
  bp.quadratic_angular_drag_b = config.robot.quadratic_angular_drag_b;
  bp.integrator = config.sim.integrator;
  if (make_rigid_body_model(bp, m.body) != Status::ok)
    return fail("robot: mass_kg must be positive and inertia_diag_kg_m2 positive definite");
  if (!compile_multirotor(config, m.mr, error)) return false;
  m.action_dim = controller_action_dim(config.controller.kind, m.mr.ctrl);
  {
    const ShapeSpec& sh = config.robot.shape;
    switch (sh.type) {
      case ShapeType::sphere: m.robot_bound_radius_m = sh.radius_m; break;
      case ShapeType::box: m.robot_bound_radius_m = sh.half_extents_m.norm(); break;
      case ShapeType::capsule: m.robot_bound_radius_m = sh.radius_m + sh.half_length_m; break;
      case ShapeType::cylinder: m.robot_bound_radius_m = std::sqrt(sh.radius_m * sh.radius_m + sh.half_length_m * sh.half_length_m); break;
      case ShapeType::convex_hull: return fail("robot.collision_shape: a mesh hull is for obstacles only");
    }
  }

  // Mesh obstacles: loaded once here; shapes point into this storage, which never reallocates.
  m.mesh_vertices.resize(e.assets.size());
  m.render_meshes.resize(e.assets.size());
  for (std::size_t ci = 0; ci < e.assets.size(); ++ci) {
    if (e.assets[ci].kind != AssetKind::mesh) continue;
    TriangleMesh mesh;
    std::string merr;
    if (!load_mesh(e.assets[ci].mesh_file, mesh, merr)) return fail("env.assets." + e.assets[ci].name + ": " + merr);
    m.render_meshes[ci].reset(new SceneMesh());
    if (!m.render_meshes[ci]->build(mesh, Vec3::Zero()))
      return fail("env.assets." + e.assets[ci].name + ": " + e.assets[ci].mesh_file + ": mesh BVH build failed");
    m.mesh_vertices[ci] = std::move(mesh.vertices);
  }
  for (const AssetClass& c : e.assets) {
    if (!(c.max_angular_speed_rad_s >= 0)) return fail("env.assets." + c.name + ".max_angular_speed_rad_s: expected a number >= 0");
    m.obstacles_rotate = m.obstacles_rotate || (c.max_angular_speed_rad_s > 0 && c.kind != AssetKind::wall);
  }
  // Terrain (shared by every environment) and the measured_heights points.
  if (!Terrain::build(e.terrain, config.seed, m.terrain, error)) return false;
  if (e.terrain.measure_heights) {
    const std::vector<real>& px = e.terrain.measured_points_x_m;
    const std::vector<real>& py = e.terrain.measured_points_y_m;
    if (px.empty() || py.empty()) return fail("env.terrain.measured_points_x/y: expected non-empty lists");
    for (real x : px)
      for (real y : py) {
        m.height_points_x_b.push_back(x);
        m.height_points_y_b.push_back(y);
      }
    m.height_points = static_cast<int>(m.height_points_x_b.size());
  }
  int cap = 0;
  for (const AssetClass& c : e.assets) cap += asset_class_slots(c);
  m.obstacle_capacity = cap;
  return compile_sensors(config, m, error);
}

void make_world_data(const WorldModel& m, WorldData& d) {
  const WorldConfig& cfg = m.cfg;
  const std::size_t nr = static_cast<std::size_t>(m.num_envs) * static_cast<std::size_t>(m.robots_per_env);
  const std::size_t ne = static_cast<std::size_t>(m.num_envs);
  d.state.assign(nr, RigidBodyState());
  d.mr_state.assign(nr, robots::MultirotorState());
  d.actions.assign(nr * kMaxActionDim, 0);
  d.applied_actions.assign(nr * kMaxActionDim, 0);
  d.target_w.assign(nr, Vec3::Zero());
  d.setpoint_w.assign(nr, Vec3::Zero());
  d.contact_force_w.assign(nr, Vec3::Zero());
  d.contact_torque_b.assign(nr, Vec3::Zero());
  d.crashed.assign(nr, 0);
  d.status_count.assign(ne, 0);
  d.rng_reset.resize(ne);
  d.rng_step.resize(ne);
  d.rng_place.resize(ne);
  d.rng_sensor.resize(ne);
  for (std::size_t i = 0; i < ne; ++i) {
    const std::uint32_t env = cfg.env.global_env(static_cast<int>(i));
    d.rng_reset[i] = RngStream(cfg.seed, env, kPurposeReset);
    d.rng_step[i] = RngStream(cfg.seed, env, kPurposeDisturbance);
    d.rng_place[i] = RngStream(cfg.seed, env, kPurposePlacement);
    d.rng_sensor[i] = RngStream(cfg.seed, env, kPurposeSensorNoise);
  }
  d.lower_w.assign(ne, Vec3::Zero());
  d.upper_w.assign(ne, Vec3::Zero());
  d.phys_steps.assign(ne, 1);
  d.latency.assign(ne, 0);
  d.episode_step.assign(ne, 0);
  d.episode_ended.assign(ne, 0);
  d.episode_fallback.assign(ne, 0);
  d.num_obstacles.assign(ne, 0);
  d.episodes_since_layout.assign(ne, 0);
  d.layout_generation.assign(ne, 0);
  d.stats.assign(ne, EnvStats());
  d.obstacles.assign(ne * static_cast<std::size_t>(m.obstacle_capacity), Obstacle());
  d.measured_heights.assign(nr * static_cast<std::size_t>(m.height_points), 0);
  d.sensors.resize(m.sensors.size());
  for (std::size_t k = 0; k < m.sensors.size(); ++k) {
    const SensorModel& s = m.sensors[k];
    SensorData& sd = d.sensors[k];
    if (s.kind == SensorKind::imu) {
      sd.imu_state.assign(nr, sensors::ImuState());
      sd.imu.assign(nr, sensors::ImuSample());
      continue;
    }
    sd.ranges.assign(nr * s.pixels, 0);
    sd.segmentation.assign(nr * s.pixels, sensors::kNoHitSegment);
    sd.mounts.assign(nr, sensors::Mount());
  }
  if (m.any_ray_sensor) {
    // Scenes over caller storage that never reallocates after this.
    const std::uint32_t cap = m.scene_capacity;
    const std::size_t nodes = sensors::bvh_node_capacity(cap);
    d.scene_objects.assign(ne * cap, sensors::SceneObject());
    d.scene_nodes.assign(ne * nodes, sensors::BvhNode());
    d.scene_prim_index.assign(ne * cap, 0);
    d.scene_bvh_objects.assign(ne * cap, 0);
    d.scene_boxes.assign(ne * cap, sensors::Aabb());
    d.scenes.clear();
    d.scenes.reserve(ne);
    for (std::size_t e = 0; e < ne; ++e) {
      const std::size_t o = e * cap;
      d.scenes.emplace_back(&d.scene_objects[o], cap, &d.scene_nodes[e * nodes], static_cast<std::uint32_t>(nodes),
                            &d.scene_prim_index[o], &d.scene_boxes[o], &d.scene_bvh_objects[o]);
    }
  }
  d.curriculum_level = cfg.env.curriculum_level;
  d.auto_reset = true;
}

namespace {
bool validate(const WorldConfig& config, std::string& error) {
  auto fail = [&](const std::string& m) {
    error = m;
    return false;
  };
  const EnvConfig& e = config.env;
  if (e.num_envs < 1) return fail("env.num_envs: expected a positive integer");
  if (config.robot.robots_per_env < 1) return fail("robot.robots_per_env: expected a positive integer");
  if (!(config.sim.dt_s > 0)) return fail("sim.dt_s: expected a positive number");
  if (config.sim.substeps < 1) return fail("sim.substeps: expected a positive integer");
  if (!(e.num_physics_steps_per_env_step_mean >= 1)) return fail("env.num_physics_steps_per_env_step_mean: expected >= 1");
  if (!(e.num_physics_steps_per_env_step_std >= 0)) return fail("env.num_physics_steps_per_env_step_std: expected >= 0");
  if (e.keep_same_env_for_num_episodes < 1) return fail("env.keep_same_env_for_num_episodes: expected >= 1");
  if (e.max_latency_physics_steps < 0) return fail("env.max_latency_physics_steps: expected >= 0");
  if (!(e.curriculum_level >= 0 && e.curriculum_level <= 1)) return fail("env.curriculum_level: expected a number in [0, 1]");
  for (int i = 0; i < 3; ++i) {
    if (!(e.lower_bound_min_m[i] <= e.lower_bound_max_m[i] && e.upper_bound_min_m[i] <= e.upper_bound_max_m[i] &&
          e.lower_bound_max_m[i] < e.upper_bound_min_m[i]))
      return fail("env bounds: expected lower_bound_min <= lower_bound_max < upper_bound_min <= upper_bound_max per axis");
  }
  for (const AssetClass& c : e.assets) {
    if (c.num_assets < 0 || c.min_num_assets < 0 || c.min_num_assets > c.num_assets)
      return fail("env.assets." + c.name + ": expected 0 <= min_num_assets <= num_assets");
  }
  if (config.num_threads < 1) return fail("threads: expected a positive integer");
  if (config.task.episode_len_env_steps < 1) return fail("task.episode_len_env_steps: expected a positive integer");
  if (config.task.placement_attempts < 1 || config.task.placement_attempts > kMaxPlacementAttempts)
    return fail("task.placement_attempts: expected an integer in [1, " + std::to_string(kMaxPlacementAttempts) + "]");
  if (!(config.task.clearance_m >= 0)) return fail("task.clearance_m: expected a number >= 0");
  if (!(config.task.setpoint_speed_m_s >= 0)) return fail("task.setpoint_speed_m_s: expected a number >= 0");
  // Every field within the range its schema allows (sim/schema.hpp): what a scenario file could
  // not hold cannot arrive through a config built in code either.
  if (!check_config_fields(config, error)) return false;
  // Upper bounds of every count (sim/limits.hpp), then the memory the world will need, before
  // any of it is allocated: a bad count is a message naming the field, not std::bad_alloc.
  {
    std::string lerr;
    if (!check_config_limits(config, lerr)) return fail(lerr);
    const double need = estimate_world_bytes(config), gib = 1024.0 * 1024.0 * 1024.0;
    if (need > config.max_memory_gib * gib) {
      char buf[512];
      std::snprintf(buf, sizeof buf,
                    "memory: this world needs about %.3g GiB (%d envs x %.4g MiB each: robots_per_env, obstacle slots, "
                    "sensors), more than max_memory_gib = %.4g GiB; allowed: up to max_memory_gib (scenario "
                    "`max_memory_gib` or kestrel run --max-memory-gib, (0, %.0f]); reduce env.num_envs or the counts",
                    need / gib, e.num_envs, need / e.num_envs / (1024.0 * 1024.0), config.max_memory_gib, kMaxMemoryGiBSetting);
      return fail(buf);
    }
  }
  return true;
}
}  // namespace

}  // namespace kestrel::sim
