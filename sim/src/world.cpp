// Batched world: set-up, reset/layout generation and the per-environment step.
//
// One physics step of a robot (the batched twin of platform/firmware/flight_loop.cpp):
//   controller (ControllerKind dispatch) -> allocation (sequential desaturation or Aerial Gym's
//   clamped pseudo-inverse) -> motor model -> body wrench A f + random disturbance + contact
//   wrench of the previous step -> rigid-body integration -> collision against the ground plane,
//   the environment's obstacles (sweep-and-prune broad phase on x over the sorted obstacle list)
//   and the other robots -> penalty contact wrench for the next step, crash flag.
// The contact response is explicit (forces from the post-integration penetration act during the
// next step), the usual choice for penalty methods with a small dt.
#include "kestrel/sim/episode.hpp"
#include "kestrel/sim/world.hpp"
#include "kestrel/sim/robot_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include "kestrel/allocation/presets.hpp"
#include "kestrel/sim/mesh.hpp"
#include "kestrel/sim/terrain.hpp"
#include "kestrel/kernel/quaternion.hpp"

namespace kestrel::sim {

namespace al = kestrel::allocation;

namespace {
Vec3 uniform_vec(RngStream& rng, const Vec3& lo, const Vec3& hi) {
  Vec3 v;
  for (int i = 0; i < 3; ++i) v[i] = lo[i] < hi[i] ? rng.uniform(lo[i], hi[i]) : lo[i];
  return v;
}

void world_task(void* context, int worker) { static_cast<World*>(context)->run_slice(worker); }

/// Puts an environment's obstacles in the broad phase's sweep order (aabb_min_w.x) by insertion
/// sort: stable, so equal keys keep generation order; O(n) for the nearly sorted list a step
/// leaves; and unlike std::stable_sort it never allocates a buffer (resets run inside the step).
void sort_sweep_order(Obstacle* o, int n) {
  for (int i = 1; i < n; ++i) {
    Obstacle key = o[i];
    int j = i - 1;
    while (j >= 0 && o[j].aabb_min_w[0] > key.aabb_min_w[0]) {
      o[j + 1] = o[j];
      --j;
    }
    o[j + 1] = key;
  }
}
}  // namespace

int asset_class_slots(const AssetClass& c) {
  if (c.kind == AssetKind::wall) return 5;  // four side walls and a ceiling around the bounds
  // In 64 bits and saturated: a tree class of 6e8 assets overflowed int here (fuzz F5), giving a
  // negative capacity. check_config_limits bounds num_assets long before this matters.
  const long long n = static_cast<long long>(c.num_assets) * (c.kind == AssetKind::tree ? 1 + kTreeBranches : 1);
  return static_cast<int>(std::min<long long>(n, std::numeric_limits<int>::max()));
}

namespace {
/// Bytes one environment's storage takes (World::bytes_per_env, and the estimate made before
/// anything is allocated: both are computed here so they cannot drift apart).
std::size_t env_bytes(const WorldConfig& cfg, int obstacle_capacity, int height_points) {
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
}  // namespace

double World::estimate_bytes(const WorldConfig& config) {
  int cap = 0;
  for (const AssetClass& c : config.env.assets) cap += asset_class_slots(c);
  const TerrainConfig& t = config.env.terrain;
  const int points = t.measure_heights ? static_cast<int>(t.measured_points_x_m.size() * t.measured_points_y_m.size()) : 0;
  // In double: the product of a bad config's counts must not wrap before it is compared.
  return static_cast<double>(env_bytes(config, cap, points)) * static_cast<double>(config.env.num_envs);
}

std::unique_ptr<World> World::create(const WorldConfig& config, std::string& error) {
  auto fail = [&](const std::string& m) {
    error = m;
    return std::unique_ptr<World>();
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
  // Upper bounds of every count (sim/limits.hpp), then the memory the world will need, before
  // any of it is allocated: a bad count is a message naming the field, not std::bad_alloc.
  {
    std::string lerr;
    if (!check_config_limits(config, lerr)) return fail(lerr);
    const double need = estimate_bytes(config), gib = 1024.0 * 1024.0 * 1024.0;
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

  std::unique_ptr<World> w(new World());
  w->cfg_ = config;
  w->num_envs_ = e.num_envs;
  w->robots_per_env_ = config.robot.robots_per_env;

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
  if (make_rigid_body_model(bp, w->body_model_) != Status::ok)
    return fail("robot: mass_kg must be positive and inertia_diag_kg_m2 positive definite");
  {
    std::string robot_error;
    if (!compile_multirotor(config, w->mr_, robot_error)) return fail(robot_error);
  }
  w->action_dim_ = controller_action_dim(config.controller.kind, w->mr_.ctrl);
  {
    const ShapeSpec& sh = config.robot.shape;
    switch (sh.type) {
      case ShapeType::sphere: w->robot_bound_radius_m_ = sh.radius_m; break;
      case ShapeType::box: w->robot_bound_radius_m_ = sh.half_extents_m.norm(); break;
      case ShapeType::capsule: w->robot_bound_radius_m_ = sh.radius_m + sh.half_length_m; break;
      case ShapeType::cylinder: w->robot_bound_radius_m_ = std::sqrt(sh.radius_m * sh.radius_m + sh.half_length_m * sh.half_length_m); break;
      case ShapeType::convex_hull: return fail("robot.collision_shape: a mesh hull is for obstacles only");
    }
  }

  // Mesh obstacles: loaded once here; shapes point into this storage, which never reallocates.
  w->mesh_vertices_.resize(e.assets.size());
  w->render_meshes_.resize(e.assets.size());
  for (std::size_t ci = 0; ci < e.assets.size(); ++ci) {
    if (e.assets[ci].kind != AssetKind::mesh) continue;
    TriangleMesh mesh;
    std::string merr;
    if (!load_mesh(e.assets[ci].mesh_file, mesh, merr)) return fail("env.assets." + e.assets[ci].name + ": " + merr);
    w->render_meshes_[ci].reset(new SceneMesh());
    if (!w->render_meshes_[ci]->build(mesh, Vec3::Zero()))
      return fail("env.assets." + e.assets[ci].name + ": " + e.assets[ci].mesh_file + ": mesh BVH build failed");
    w->mesh_vertices_[ci] = std::move(mesh.vertices);
  }
  for (const AssetClass& c : e.assets) {
    if (!(c.max_angular_speed_rad_s >= 0)) return fail("env.assets." + c.name + ".max_angular_speed_rad_s: expected a number >= 0");
    w->obstacles_rotate_ = w->obstacles_rotate_ || (c.max_angular_speed_rad_s > 0 && c.kind != AssetKind::wall);
  }
  // Terrain (shared by every environment) and the measured_heights storage.
  if (!Terrain::build(e.terrain, config.seed, w->terrain_, error)) return std::unique_ptr<World>();
  if (e.terrain.measure_heights) {
    const std::vector<real>& px = e.terrain.measured_points_x_m;
    const std::vector<real>& py = e.terrain.measured_points_y_m;
    if (px.empty() || py.empty()) return fail("env.terrain.measured_points_x/y: expected non-empty lists");
    for (real x : px)
      for (real y : py) {
        w->height_points_x_b_.push_back(x);
        w->height_points_y_b_.push_back(y);
      }
    w->height_points_ = static_cast<int>(w->height_points_x_b_.size());
    w->measured_heights_.assign(static_cast<std::size_t>(e.num_envs) * static_cast<std::size_t>(config.robot.robots_per_env) *
                                    static_cast<std::size_t>(w->height_points_),
                                0);
  }
  int cap = 0;
  for (const AssetClass& c : e.assets) cap += asset_class_slots(c);
  w->obstacle_capacity_ = cap;

  const std::size_t nr = static_cast<std::size_t>(w->num_envs_) * w->robots_per_env_;
  const std::size_t ne = static_cast<std::size_t>(w->num_envs_);
  w->state_.assign(nr, RigidBodyState());
  w->mr_state_.assign(nr, robots::MultirotorState());
  w->actions_.assign(nr * kMaxActionDim, 0);
  w->applied_actions_.assign(nr * kMaxActionDim, 0);
  w->target_w_.assign(nr, Vec3::Zero());
  w->setpoint_w_.assign(nr, Vec3::Zero());
  w->contact_force_w_.assign(nr, Vec3::Zero());
  w->contact_torque_b_.assign(nr, Vec3::Zero());
  w->crashed_.assign(nr, 0);
  w->rng_reset_.resize(ne);
  w->status_count_.assign(ne, 0);
  w->rng_step_.resize(ne);
  for (std::size_t i = 0; i < ne; ++i) {
    w->rng_reset_[i] = RngStream(config.seed, static_cast<std::uint32_t>(i), kPurposeReset);
    w->rng_step_[i] = RngStream(config.seed, static_cast<std::uint32_t>(i), kPurposeDisturbance);
  }
  w->lower_w_.assign(ne, Vec3::Zero());
  w->upper_w_.assign(ne, Vec3::Zero());
  w->phys_steps_.assign(ne, 1);
  w->latency_.assign(ne, 0);
  w->episode_step_.assign(ne, 0);
  w->num_obstacles_.assign(ne, 0);
  w->episodes_since_layout_.assign(ne, 0);
  w->layout_generation_.assign(ne, 0);
  w->stats_.assign(ne, EnvStats());
  w->obstacles_.assign(ne * static_cast<std::size_t>(cap), Obstacle());
  {
    std::string serr;
    if (!w->setup_sensors(serr)) return fail(serr);
  }
  for (int env = 0; env < w->num_envs_; ++env) {
    w->reset_env(env);
    w->stats_[env].resets = 0;  // the initial reset is not counted
  }
  w->batch_ = w->batch_eligible();
  w->pool_.reset(new ThreadPool(std::min(config.num_threads, w->num_envs_)));
  return w;
}

World::~World() = default;

void World::generate_layout(int env, RngStream& rng) {
  const Vec3 lo = lower_w_[env], hi = upper_w_[env], span = hi - lo;
  // data() + offset, not &v[i]: the empty environment has no obstacle slots (capacity 0).
  Obstacle* slots = obstacles_.data() + static_cast<std::size_t>(env) * obstacle_capacity_;
  int n = 0;
  const real level = cfg_.env.curriculum_level;
  for (std::size_t ci = 0; ci < cfg_.env.assets.size(); ++ci) {
    const AssetClass& c = cfg_.env.assets[ci];
    auto emit = [&](const Shape& s) {
      Obstacle& o = slots[n++];
      o.shape = s;
      o.semantic_id = static_cast<std::int16_t>(c.semantic_id);
      o.kind = c.kind;
      o.class_index = static_cast<std::uint8_t>(ci);
      o.linvel_w = Vec3::Zero();
      if (c.max_speed_m_s > 0) o.linvel_w = uniform_vec(rng, Vec3::Constant(-c.max_speed_m_s), Vec3::Constant(c.max_speed_m_s));
      // Drawn only for rotating classes, so layouts without rotation keep their stream positions.
      o.angvel_w = Vec3::Zero();
      if (c.max_angular_speed_rad_s > 0 && c.kind != AssetKind::wall)
        o.angvel_w = uniform_vec(rng, Vec3::Constant(-c.max_angular_speed_rad_s), Vec3::Constant(c.max_angular_speed_rad_s));
    };
    if (c.kind == AssetKind::wall) {
      // Thin boxes just outside the bounds (they bound the flight volume, Aerial Gym's walls).
      const real t = 0.05_r;
      const Vec3 mid = (lo + hi) / 2;
      Shape s;
      s.type = ShapeType::box;
      s.half_extents_m = Vec3(t, span[1] / 2 + t, span[2] / 2);
      s.position_w = Vec3(lo[0] - t, mid[1], mid[2]);
      emit(s);
      s.position_w = Vec3(hi[0] + t, mid[1], mid[2]);
      emit(s);
      s.half_extents_m = Vec3(span[0] / 2 + t, t, span[2] / 2);
      s.position_w = Vec3(mid[0], lo[1] - t, mid[2]);
      emit(s);
      s.position_w = Vec3(mid[0], hi[1] + t, mid[2]);
      emit(s);
      s.half_extents_m = Vec3(span[0] / 2 + t, span[1] / 2 + t, t);
      s.position_w = Vec3(mid[0], mid[1], hi[2] + t);
      emit(s);
      continue;
    }
    const int count = c.keep_in_env ? c.num_assets
                                    : c.min_num_assets + static_cast<int>(std::floor(
                                          level * static_cast<real>(c.num_assets - c.min_num_assets) + 0.5_r));
    for (int k = 0; k < count; ++k) {
      const Vec3 ratio = uniform_vec(rng, c.min_position_ratio, c.max_position_ratio);
      const Vec3 e = uniform_vec(rng, c.min_euler_rad, c.max_euler_rad);
      const Vec3 size = uniform_vec(rng, c.min_size_m, c.max_size_m);
      const Vec3 p = lo + ratio.cwiseProduct(span);
      const Quat q = quat_from_euler_xyz(e[0], e[1], e[2]);
      Shape s;
      s.position_w = p;
      s.orientation_wb = q;
      switch (c.kind) {
        case AssetKind::tree: {
          // Procedural tree: trunk (size x = radius, z = height) standing on the ground, and
          // kTreeBranches capsules leaving it at random heights, azimuths and tilts (size y =
          // branch length). Parametric and randomised as Aerial Gym's generated forest URDFs.
          const real r = size[0], h = size[2];
          s.type = ShapeType::capsule;
          s.radius_m = r;
          s.half_length_m = h / 2;
          s.orientation_wb = Quat::Identity();
          s.position_w = Vec3(p[0], p[1], lo[2] + h / 2);
          emit(s);
          for (int b = 0; b < kTreeBranches; ++b) {
            const real at = rng.uniform(0.4_r, 0.9_r) * h;
            const real az = rng.uniform(0, kTwoPi);
            const real tilt = rng.uniform(0.5_r, 1.1_r);  // rad from vertical
            const real len = size[1] * rng.uniform(0.6_r, 1.0_r);
            const Quat qb = quat_from_euler_xyz(0, tilt, az);
            Shape br;
            br.type = ShapeType::capsule;
            br.radius_m = r * 0.5_r;
            br.half_length_m = len / 2;
            br.orientation_wb = qb;
            br.position_w = Vec3(p[0], p[1], lo[2] + at) + rotate(qb, Vec3(0, 0, len / 2));
            emit(br);
          }
          break;
        }
        case AssetKind::panel:  // thin plate: x thickness, y width, z height
          s.type = ShapeType::box;
          s.half_extents_m = Vec3(0.025_r, size[1] / 2, size[2] / 2);
          emit(s);
          break;
        case AssetKind::cube:
          s.type = ShapeType::box;
          s.half_extents_m = Vec3::Constant(size[0] / 2);
          emit(s);
          break;
        case AssetKind::small_wall:
          s.type = ShapeType::box;
          s.half_extents_m = Vec3(0.05_r, size[1] / 2, size[2] / 2);
          emit(s);
          break;
        case AssetKind::rod:
          s.type = ShapeType::capsule;
          s.radius_m = size[0];
          s.half_length_m = size[2] / 2;
          emit(s);
          break;
        case AssetKind::thin:
          s.type = ShapeType::cylinder;
          s.radius_m = size[0];
          s.half_length_m = size[2] / 2;
          emit(s);
          break;
        case AssetKind::sphere:
          s.type = ShapeType::sphere;
          s.radius_m = size[0];
          emit(s);
          break;
        case AssetKind::mesh:
          s.type = ShapeType::convex_hull;
          s.vertices = mesh_vertices_[ci].data();
          s.num_vertices = static_cast<int>(mesh_vertices_[ci].size());
          emit(s);
          break;
        case AssetKind::wall:
          break;
      }
    }
  }
  num_obstacles_[env] = n;
  for (int i = 0; i < n; ++i) shape_aabb(slots[i].shape, slots[i].aabb_min_w, slots[i].aabb_max_w);
  sort_sweep_order(slots, n);
}

bool World::overlaps_obstacle(int env, const Shape& s) const {
  Vec3 mn, mx;
  shape_aabb(s, mn, mx);
  for (int i = 0; i < num_obstacles_[env]; ++i) {
    const Obstacle& o = obstacle(env, i);
    // AABB rejection first: placement tests many candidates against every obstacle at each reset.
    if ((o.aabb_max_w.array() < mn.array()).any() || (o.aabb_min_w.array() > mx.array()).any()) continue;
    if (collide(s, o.shape).hit) return true;
  }
  return false;
}

bool World::clear_point(int env, const Vec3& p) const {
  // Above the terrain by the bounding sphere and the clearance (heightfield / mesh terrain only:
  // the ground plane lies under the bounds by construction).
  if (terrain_->type() != TerrainType::plane &&
      !(p[2] - terrain_->height_at(p[0], p[1]) > robot_bound_radius_m_ + cfg_.task.clearance_m))
    return false;
  Shape s;
  s.type = ShapeType::sphere;
  s.radius_m = robot_bound_radius_m_ + cfg_.task.clearance_m;
  s.position_w = p;
  return !overlaps_obstacle(env, s);
}

bool World::clear_segment(int env, const Vec3& a, const Vec3& b) const {
  const Vec3 d = b - a;
  const real len = d.norm();
  if (!(len > 1e-6_r)) return clear_point(env, a);
  if (terrain_->type() != TerrainType::plane) {
    // The path over the terrain, checked every 0.1 m.
    const int steps = static_cast<int>(len / 0.1_r) + 1;
    for (int k = 0; k <= steps; ++k) {
      const Vec3 p = a + d * (static_cast<real>(k) / static_cast<real>(steps));
      if (!(p[2] - terrain_->height_at(p[0], p[1]) > robot_bound_radius_m_ + cfg_.task.clearance_m)) return false;
    }
  }
  // The swept bounding sphere: a capsule from a to b (local z along the segment).
  Shape s;
  s.type = ShapeType::capsule;
  s.radius_m = robot_bound_radius_m_ + cfg_.task.clearance_m;
  s.half_length_m = len / 2;
  s.position_w = (a + b) / 2;
  s.orientation_wb = Quat::FromTwoVectors(Vec3::UnitZ(), d / len);
  return !overlaps_obstacle(env, s);
}

void World::reset_env(int env) {
  RngStream& rng = rng_reset_[env];
  const EnvConfig& e = cfg_.env;
  lower_w_[env] = uniform_vec(rng, e.lower_bound_min_m, e.lower_bound_max_m);
  upper_w_[env] = uniform_vec(rng, e.upper_bound_min_m, e.upper_bound_max_m);
  if (layout_generation_[env] == 0 || ++episodes_since_layout_[env] >= e.keep_same_env_for_num_episodes) {
    generate_layout(env, rng);
    episodes_since_layout_[env] = 0;
    ++layout_generation_[env];
  }
  const int ps = static_cast<int>(std::floor(
      e.num_physics_steps_per_env_step_mean + e.num_physics_steps_per_env_step_std * rng.normal() + 0.5_r));
  phys_steps_[env] = std::max(1, ps);
  latency_[env] = e.sample_timestep_for_latency
                      ? std::min(phys_steps_[env], static_cast<int>(rng.next_u32() % static_cast<std::uint32_t>(e.max_latency_physics_steps + 1)))
                      : 0;
  episode_step_[env] = 0;
  const Vec3 lo = lower_w_[env], span = upper_w_[env] - lower_w_[env];
  for (int r = 0; r < robots_per_env_; ++r) {
    const std::size_t i = index(env, r);
    RigidBodyState st;
    // Start and target (TaskConfig::placement_attempts): all candidates are drawn first, always
    // the same number, so the stream position after a reset does not depend on the layout; then
    // the first candidate pair whose start and target clear the obstacles (and, with
    // line_of_sight, the straight path between them) is kept. Fallbacks: the first pair with a
    // clear start, else the first pair (a layout with no free space still resets).
    const int attempts = cfg_.task.placement_attempts;
    Vec3 starts[kMaxPlacementAttempts], targets[kMaxPlacementAttempts];
    for (int k = 0; k < attempts; ++k) {
      starts[k] = lo + uniform_vec(rng, cfg_.robot.min_init_position_ratio, cfg_.robot.max_init_position_ratio).cwiseProduct(span);
      targets[k] = lo + uniform_vec(rng, cfg_.task.min_target_ratio, cfg_.task.max_target_ratio).cwiseProduct(span);
    }
    const bool hover_task = cfg_.task.kind == TaskKind::hover;
    int chosen = -1, clear_start = -1;
    for (int k = 0; k < attempts && chosen < 0; ++k) {
      if (!clear_point(env, starts[k])) continue;
      if (clear_start < 0) clear_start = k;
      if (hover_task || (clear_point(env, targets[k]) && (!cfg_.task.line_of_sight || clear_segment(env, starts[k], targets[k]))))
        chosen = k;
    }
    // No clear pair: hover at the first clear start rather than fly into an obstacle.
    const bool fallback = chosen < 0;
    if (fallback) {
      chosen = clear_start >= 0 ? clear_start : 0;
      ++stats_[env].placement_fallbacks;
    }
    st.position_w = starts[chosen];
    const real yaw = rng.uniform(-cfg_.robot.max_init_yaw_rad, cfg_.robot.max_init_yaw_rad);
    st.orientation_wb = quat_from_euler_xyz(0, 0, yaw);
    state_[i] = st;
    real hover[al::kMaxRotors] = {};
    const real per_motor = body_model_.params.mass_kg * kStandardGravity / static_cast<real>(mr_.airframe.num_rotors);
    for (int m = 0; m < mr_.airframe.num_rotors; ++m) hover[m] = per_motor;
    // One stream for the gain and the motor draws, in that order (the World's order since the start).
    count_status(env, robots::multirotor_reset(mr_, mr_state_[i], &rng, rng, hover));
    // Task: the position setpoint (or the start point for hover) is the action of the episode.
    target_w_[i] = (hover_task || fallback) ? st.position_w : targets[chosen];
    real* a = &actions_[i * kMaxActionDim];
    std::fill(a, a + kMaxActionDim, 0_r);
    const bool moving = cfg_.task.setpoint_speed_m_s > 0 && !hover_task;
    setpoint_w_[i] = moving ? st.position_w : target_w_[i];
    if (cfg_.controller.kind == ControllerKind::lee_position) {
      a[0] = setpoint_w_[i][0];
      a[1] = setpoint_w_[i][1];
      a[2] = setpoint_w_[i][2];
      a[3] = 0;
    } else if (cfg_.controller.kind == ControllerKind::direct_motor) {
      for (int m = 0; m < mr_.airframe.num_rotors; ++m) a[m] = per_motor;
    }
    std::copy(a, a + kMaxActionDim, &applied_actions_[i * kMaxActionDim]);
    contact_force_w_[i] = Vec3::Zero();
    contact_torque_b_[i] = Vec3::Zero();
    crashed_[i] = 0;
  }
  // Sensor placement per reset (Aerial Gym's randomize_placement) from the placement stream, so
  // the reset stream (layout, start, target) is the same with or without sensors.
  for (int r = 0; r < robots_per_env_; ++r) {
    const std::size_t i = index(env, r);
    for (std::size_t k = 0; k < sensors_.size(); ++k) {
      SensorSlot& s = sensors_[k];
      if (s.kind == SensorKind::imu) {
        sensors::imu_reset(cfg_.robot.sensors[k].imu, s.imu_state[i], rng_sensor_[static_cast<std::size_t>(env)]);
        s.imu[i] = sensors::ImuSample();
      } else {
        s.mounts[i] = sensors::sample_mount(s.mount, rng_place_[static_cast<std::size_t>(env)]);
      }
    }
  }
  ++stats_[env].resets;
  // The new episode's first observation sees the new layout and start.
  if (any_ray_sensor_) render_ray_sensors(env, true);
  if (height_points_ > 0) update_measured_heights(env);
}

real World::ground_height(real x_w, real y_w, int env) const {
  if (terrain_->type() != TerrainType::plane) return terrain_->height_at(x_w, y_w);
  if (!cfg_.env.create_ground_plane) return -1e30_r;
  return lower_w_[env][2] < 0 ? lower_w_[env][2] : 0_r;
}

void World::update_measured_heights(int env) {
  // legged_gym _get_heights: the points rotated by the base yaw (quat_apply_yaw) around the base.
  for (int r = 0; r < robots_per_env_; ++r) {
    const std::size_t i = index(env, r);
    const RigidBodyState& st = state_[i];
    const Vec3 fwd = rotate(st.orientation_wb, Vec3::UnitX());
    const real fn = std::sqrt(fwd[0] * fwd[0] + fwd[1] * fwd[1]);
    const real c = fn > 1e-6_r ? fwd[0] / fn : 1_r, s = fn > 1e-6_r ? fwd[1] / fn : 0_r;
    real* out = &measured_heights_[i * static_cast<std::size_t>(height_points_)];
    for (int k = 0; k < height_points_; ++k) {
      const real px = height_points_x_b_[static_cast<std::size_t>(k)], py = height_points_y_b_[static_cast<std::size_t>(k)];
      out[k] = ground_height(st.position_w[0] + c * px - s * py, st.position_w[1] + s * px + c * py, env);
    }
  }
}

void World::robot_dynamics(int env, int robot, std::size_t i, bool use_new_action) {
  (void)robot;
  const real dt = cfg_.sim.dt_s;
  real* applied = &applied_actions_[i * kMaxActionDim];
  if (use_new_action) std::memcpy(applied, &actions_[i * kMaxActionDim], sizeof(real) * kMaxActionDim);
  RigidBodyState& st = state_[i];
  RngStream& rng = rng_step_[env];
  // The controller reads the true state unless observation noise is on (no copy on that path).
  RigidBodyState noisy;
  const RigidBodyState* observed = &st;
  if (cfg_.env.perturb_observations) {
    noisy = st;
    for (int k = 0; k < 3; ++k) noisy.position_w[k] += cfg_.env.observation_noise_position_m * rng.normal();
    for (int k = 0; k < 3; ++k) noisy.linvel_w[k] += cfg_.env.observation_noise_velocity_m_s * rng.normal();
    observed = &noisy;
  }
  robots::MultirotorOutput out;
  // Every non-ok status of the chain is also latched as fault bits in mr_state_[i] (the batched
  // twin reproduces them bit for bit), which summary() reports; the status itself adds nothing.
  (void)robots::multirotor_step(mr_, mr_state_[i], *observed, applied, kMaxActionDim, dt, out);
  Wrench w = robots::multirotor_wrench(mr_, mr_state_[i]);
  Vec3 extra_force_w = contact_force_w_[i];
  w.torque_b += contact_torque_b_[i];
  if (cfg_.env.enable_disturbance) {
    // Aerial Gym's disturbance: with probability p per step, a uniform random force and torque
    // within +-max (its robot config `disturbance`). Always three draws so streams stay aligned.
    const real u = rng.uniform();
    const Vec3 f = uniform_vec(rng, -cfg_.env.max_force_disturbance_N, cfg_.env.max_force_disturbance_N);
    const Vec3 t = uniform_vec(rng, -cfg_.env.max_torque_disturbance_Nm, cfg_.env.max_torque_disturbance_Nm);
    if (u < cfg_.env.prob_apply_disturbance) {
      w.force_b += f;
      w.torque_b += t;
    }
  }
  const real h = dt / static_cast<real>(cfg_.sim.substeps);
  // A non-finite input is refused and the state held (step_rigid_body's contract).
  for (int s = 0; s < cfg_.sim.substeps; ++s) (void)step_rigid_body(body_model_, st, w, h, extra_force_w);
}

void World::move_obstacles(int env) {
  Obstacle* o = obstacles_.data() + static_cast<std::size_t>(env) * obstacle_capacity_;
  const int n = num_obstacles_[env];
  if (n == 0) return;  // the empty environment: nothing to move (hot path)
  const real dt = cfg_.sim.dt_s;
  const Vec3 lo = lower_w_[env], hi = upper_w_[env];
  bool moved = false;
  for (int i = 0; i < n; ++i) {
    if (o[i].linvel_w.isZero() && o[i].angvel_w.isZero()) continue;
    moved = true;
    if (!o[i].angvel_w.isZero()) {
      // Constant world-frame angular velocity: q <- exp(w dt) q, the exact rotation of one step
      // (axis-angle to quaternion), renormalised against round-off drift.
      const Vec3 rot = dt * o[i].angvel_w;
      const real angle = rot.norm();
      if (angle > 0) {
        const real half = angle / 2;
        const Vec3 axis = rot / angle;
        const real sh = std::sin(half);
        const Quat dq = quat_from_xyzw(axis[0] * sh, axis[1] * sh, axis[2] * sh, std::cos(half));
        o[i].shape.orientation_wb = (dq * o[i].shape.orientation_wb).normalized();
      }
    }
    o[i].shape.position_w += dt * o[i].linvel_w;
    for (int k = 0; k < 3; ++k) {  // bounce off the env bounds
      if ((o[i].shape.position_w[k] < lo[k] && o[i].linvel_w[k] < 0) || (o[i].shape.position_w[k] > hi[k] && o[i].linvel_w[k] > 0))
        o[i].linvel_w[k] = -o[i].linvel_w[k];
    }
    shape_aabb(o[i].shape, o[i].aabb_min_w, o[i].aabb_max_w);
  }
  if (!moved) return;
  sort_sweep_order(o, n);
}

void World::collide_robots(int env) {
  const SimParams& sp = cfg_.sim;
  const Obstacle* o = obstacles_.data() + static_cast<std::size_t>(env) * obstacle_capacity_;
  const int n = num_obstacles_[env];
  if (n == 0 && robots_per_env_ == 1 && cfg_.robot.shape.type == ShapeType::sphere && terrain_->type() == TerrainType::plane) {
    // Fast path, the empty environment's common case: one sphere robot, no obstacles, and the
    // sphere clear of the ground plane (collide_plane's own test). Nothing touches it, so this
    // stores what the pass below would: zero force, the zero torque rotated into the body frame
    // (its signed zeros), and a crash only if the threshold were negative.
    const std::size_t i = index(env, 0);
    const RigidBodyState& st = state_[i];
    const real plane_z = lower_w_[env][2] < 0 ? lower_w_[env][2] : 0_r;
    if (!cfg_.env.create_ground_plane || st.position_w[2] - cfg_.robot.shape.radius_m >= plane_z) {
      contact_force_w_[i] = Vec3::Zero();
      contact_torque_b_[i] = rotate_inverse(st.orientation_wb, Vec3::Zero());
      if (0_r > cfg_.env.collision_force_threshold_N) crashed_[i] = 1;
      return;
    }
  }
  for (int r = 0; r < robots_per_env_; ++r) {
    const std::size_t i = index(env, r);
    const RigidBodyState& st = state_[i];
    const Shape me = make_shape(cfg_.robot.shape, st.position_w, st.orientation_wb);
    Vec3 mn, mx;
    shape_aabb(me, mn, mx);
    Vec3 force = Vec3::Zero(), torque_w = Vec3::Zero();
    real normal_force_sum = 0;
    auto respond = [&](const Contact& k, const Vec3& other_vel_w) {
      if (!k.hit) return;
      const Vec3 arm = k.point_w - st.position_w;
      const Vec3 v = st.linvel_w + rotate(st.orientation_wb, st.angvel_b).cross(arm) - other_vel_w;
      const real vn = v.dot(k.normal_w);
      const real fn = std::max(0_r, sp.contact_stiffness_N_m * k.depth_m - sp.contact_damping_N_s_m * vn);
      const Vec3 vt = v - vn * k.normal_w;
      Vec3 ft = -sp.friction_damping_N_s_m * vt;  // viscous inside the cone, clamped to mu fn
      const real ftn = ft.norm(), lim = sp.friction_coefficient * fn;
      if (ftn > lim) ft *= lim / ftn;
      const Vec3 f = fn * k.normal_w + ft;
      force += f;
      torque_w += arm.cross(f);
      normal_force_sum += fn;
    };
    if (terrain_->type() != TerrainType::plane) {
      // Height-field / mesh terrain replaces the ground plane (sim/terrain.hpp).
      Contact tk[kMaxTerrainContacts];
      const int nt = terrain_->collide(me, robot_bound_radius_m_, tk);
      for (int c = 0; c < nt; ++c) respond(tk[c], Vec3::Zero());
    } else if (cfg_.env.create_ground_plane) {
      respond(collide_plane(me, lower_w_[env][2] < 0 ? lower_w_[env][2] : 0_r), Vec3::Zero());
    }
    for (int k = 0; k < n && o[k].aabb_min_w[0] <= mx[0]; ++k) {
      if (o[k].aabb_max_w[0] < mn[0] || o[k].aabb_max_w[1] < mn[1] || o[k].aabb_min_w[1] > mx[1] ||
          o[k].aabb_max_w[2] < mn[2] || o[k].aabb_min_w[2] > mx[2])
        continue;
      const Contact ok = collide(me, o[k].shape);
      // A rotating obstacle's surface moves at v + w x r at the contact point.
      respond(ok, ok.hit && !o[k].angvel_w.isZero() ? Vec3(o[k].linvel_w + o[k].angvel_w.cross(ok.point_w - o[k].shape.position_w))
                                                    : o[k].linvel_w);
    }
    for (int q = 0; q < robots_per_env_; ++q) {
      if (q == r) continue;
      const RigidBodyState& other = state_[index(env, q)];
      respond(collide(me, make_shape(cfg_.robot.shape, other.position_w, other.orientation_wb)), other.linvel_w);
    }
    contact_force_w_[i] = force;
    contact_torque_b_[i] = rotate_inverse(st.orientation_wb, torque_w);
    if (normal_force_sum > cfg_.env.collision_force_threshold_N) crashed_[i] = 1;
  }
}

void World::physics_step(int env, bool use_new_action) {
  for (int r = 0; r < robots_per_env_; ++r) {
    const Vec3 v0 = state_[index(env, r)].linvel_w;
    robot_dynamics(env, r, index(env, r), use_new_action);
    if (any_imu_) update_imus(env, r, v0);
  }
  physics_step_tail(env);
}

// What a physics step does after the robots' dynamics (shared with the batched path).
void World::physics_step_tail(int env) {
  move_obstacles(env);
  collide_robots(env);
}

void World::env_step(int env) {
  env_step_begin(env);
  for (int s = 0; s < phys_steps_[env]; ++s) physics_step(env, s == latency_[env]);
  env_step_end(env);
}

// The parts of an env-step before and after its physics steps (the batched path, world_batch.cpp,
// runs the same two around its lockstep physics steps).
void World::env_step_begin(int env) {
  const int n = phys_steps_[env];
  for (int r = 0; r < robots_per_env_; ++r) crashed_[index(env, r)] = 0;  // per env-step flag
  if (cfg_.task.setpoint_speed_m_s > 0 && cfg_.task.kind == TaskKind::position_setpoint &&
      cfg_.controller.kind == ControllerKind::lee_position) {
    // Moving setpoint: advance it by at most speed * (env-step duration) towards the target.
    const real max_move = cfg_.task.setpoint_speed_m_s * cfg_.sim.dt_s * static_cast<real>(n);
    for (int r = 0; r < robots_per_env_; ++r) {
      const std::size_t i = index(env, r);
      const Vec3 d = target_w_[i] - setpoint_w_[i];
      const real len = d.norm();
      setpoint_w_[i] = len <= max_move ? target_w_[i] : Vec3(setpoint_w_[i] + d * (max_move / len));
      real* a = &actions_[i * kMaxActionDim];
      for (int k = 0; k < 3; ++k) a[k] = setpoint_w_[i][k];
    }
  }
}

void World::env_step_end(int env) {
  EnvStats& es = stats_[env];
  ++es.env_steps;
  if (env < trace_envs_) {
    const std::uint64_t k = es.env_steps - 1 - trace_base_;
    if (k < static_cast<std::uint64_t>(trace_cap_)) trace_[static_cast<std::size_t>(env) * trace_cap_ + k] = state_[index(env, 0)].position_w;
  }
  bool any_crash = false, out = false;
  real err_sum = 0;
  for (int r = 0; r < robots_per_env_; ++r) {
    const std::size_t i = index(env, r);
    any_crash = any_crash || crashed_[i] != 0;
    const Vec3& p = state_[i].position_w;
    // Out of bounds (with a margin for a robot resting on the ground plane) ends the episode.
    out = out || out_of_bounds(p, lower_w_[env], upper_w_[env]);
    err_sum += (setpoint_w_[i] - p).norm();  // the controller's tracking error (setpoint = target unless it moves)
  }
  es.tracking_error_sum_m += static_cast<double>(err_sum);
  if (any_crash) ++es.crashes;
  const bool timeout = ++episode_step_[env] >= cfg_.task.episode_len_env_steps;
  if (timeout) {
    ++es.timeouts;
    bool ok = true;
    for (int r = 0; r < robots_per_env_; ++r)
      ok = ok && (target_w_[index(env, r)] - state_[index(env, r)].position_w).norm() <= cfg_.task.success_radius_m;
    es.successes += ok ? 1u : 0u;
  }
  if (out) ++es.out_of_bounds;
  if (timeout || out || (any_crash && cfg_.env.reset_on_collision)) {
    ++es.episodes_done;
    real d = 0;
    for (int r = 0; r < robots_per_env_; ++r) d += (target_w_[index(env, r)] - state_[index(env, r)].position_w).norm();
    es.final_distance_sum_m += static_cast<double>(d) / robots_per_env_;
    if (auto_reset_) {
      reset_env(env);  // renders the new episode's first images
      return;
    }
  }
  if (height_points_ > 0) update_measured_heights(env);
  if (any_ray_sensor_) render_ray_sensors(env, false);
}

void World::run_slice(int worker) {
  const int t = pool_ ? pool_->size() : 1;
  const int begin = static_cast<int>(static_cast<long long>(num_envs_) * worker / t);
  const int end = static_cast<int>(static_cast<long long>(num_envs_) * (worker + 1) / t);
  for (int s = 0; s < pending_steps_; ++s) {
    // Batched twin (world_batch.cpp): whole groups of batch::kLanes environments, bit-identical.
    int env = batch_ ? env_steps_batched(begin, end) : begin;
    for (; env < end; ++env) env_step(env);
  }
  if (after_step_ != nullptr) after_step_(after_step_context_, begin, end);
}

void World::step(int num_env_steps) {
  pending_steps_ = num_env_steps;
  pool_->run(world_task, this);
  trace_len_ = std::min(trace_cap_, trace_len_ + num_env_steps);
}

void World::enable_trace(int num_envs, int max_env_steps) {
  trace_envs_ = std::min(num_envs, num_envs_);
  trace_cap_ = max_env_steps;
  trace_len_ = 0;
  trace_base_ = num_envs_ > 0 ? stats_[0].env_steps : 0;
  trace_.assign(static_cast<std::size_t>(trace_envs_) * trace_cap_, Vec3::Zero());
}

WorldSummary World::summary() const {
  WorldSummary s;
  double err = 0, final_dist = 0, end_dist = 0;
  for (int env = 0; env < num_envs_; ++env) {
    const EnvStats& e = stats_[env];
    add_env_counters(s, e);
    err += e.tracking_error_sum_m;
    end_dist += e.final_distance_sum_m;
    for (int r = 0; r < robots_per_env_; ++r) {
      final_dist += static_cast<double>((target_w_[index(env, r)] - state_[index(env, r)].position_w).norm());
      s.fault_bits |= robots::multirotor_faults(mr_state_[index(env, r)]);
    }
    s.reset_errors += status_count_[static_cast<std::size_t>(env)];
  }
  const double nr = static_cast<double>(num_envs_) * robots_per_env_;
  s.mean_tracking_error_m = s.env_steps > 0 ? err / (static_cast<double>(s.env_steps) * robots_per_env_) : 0;
  s.final_mean_distance_m = final_dist / nr;
  s.episode_end_distance_m = s.episodes_done > 0 ? end_dist / static_cast<double>(s.episodes_done) : 0;
  return s;
}

namespace {
struct Fnv {
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a 64 offset basis (Fowler, Noll, Vo)
  void bytes(const void* p, std::size_t n) {
    const unsigned char* c = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) {
      h ^= c[i];
      h *= 1099511628211ull;
    }
  }
  void v3(const Vec3& v) { bytes(v.data(), sizeof(real) * 3); }
  template <class T>
  void pod(const T& v) { bytes(&v, sizeof(T)); }
};
}  // namespace

std::uint64_t World::state_hash() const {
  Fnv f;
  for (int env = 0; env < num_envs_; ++env) {
    for (int r = 0; r < robots_per_env_; ++r) {
      const std::size_t i = index(env, r);
      const RigidBodyState& s = state_[i];
      f.v3(s.position_w);
      f.bytes(s.orientation_wb.coeffs().data(), sizeof(real) * 4);
      f.v3(s.linvel_w);
      f.v3(s.angvel_b);
      f.bytes(mr_state_[i].motors.thrust_N, sizeof(real) * static_cast<std::size_t>(mr_.airframe.num_rotors));
      f.pod(crashed_[i]);
    }
    for (int k = 0; k < num_obstacles_[env]; ++k) f.v3(obstacle(env, k).shape.position_w);
    if (obstacles_rotate_)  // (absent otherwise, so hashes of worlds without rotation are unchanged)
      for (int k = 0; k < num_obstacles_[env]; ++k) f.bytes(obstacle(env, k).shape.orientation_wb.coeffs().data(), sizeof(real) * 4);
    // Sensor outputs (absent without sensors, so sensor-free hashes are unchanged).
    for (const SensorSlot& sl : sensors_) {
      for (int r = 0; r < robots_per_env_; ++r) {
        const std::size_t i = index(env, r);
        if (sl.kind == SensorKind::imu) {
          f.v3(sl.imu[i].accel_s);
          f.v3(sl.imu[i].gyro_s);
        } else {
          f.bytes(&sl.ranges[i * sl.pixels], sizeof(real) * sl.pixels);
          f.bytes(&sl.segmentation[i * sl.pixels], sizeof(std::int32_t) * sl.pixels);
        }
      }
    }
    f.pod(episode_step_[env]);
    f.pod(stats_[env].resets);
    f.pod(stats_[env].crashes);
  }
  return f.h;
}

bool World::setup_sensors(std::string& error) {
  const std::size_t nr = static_cast<std::size_t>(num_envs_) * static_cast<std::size_t>(robots_per_env_);
  const std::size_t ne = static_cast<std::size_t>(num_envs_);
  sensors_.resize(cfg_.robot.sensors.size());
  for (std::size_t k = 0; k < sensors_.size(); ++k) {
    const SensorConfig& c = cfg_.robot.sensors[k];
    SensorSlot& s = sensors_[k];
    s.kind = c.kind;
    s.every = c.every_env_steps;
    if (c.every_env_steps < 1) {
      error = "robot.sensors." + c.name + ": every must be a positive integer";
      return false;
    }
    if (c.kind == SensorKind::imu) {
      any_imu_ = true;
      s.imu_state.assign(nr, sensors::ImuState());
      s.imu.assign(nr, sensors::ImuSample());
      continue;
    }
    any_ray_sensor_ = true;
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
    s.ranges.assign(nr * s.pixels, 0);
    s.segmentation.assign(nr * s.pixels, sensors::kNoHitSegment);
    s.mounts.assign(nr, sensors::Mount());
  }
  if (any_ray_sensor_) {
    // Every obstacle slot plus the ground plane; storage never reallocates after this.
    scene_capacity_ = static_cast<std::uint32_t>(obstacle_capacity_) + 1;
    const std::size_t nodes = sensors::bvh_node_capacity(scene_capacity_);
    scene_objects_.assign(ne * scene_capacity_, sensors::SceneObject());
    scene_nodes_.assign(ne * nodes, sensors::BvhNode());
    scene_prim_index_.assign(ne * scene_capacity_, 0);
    scene_bvh_objects_.assign(ne * scene_capacity_, 0);
    scene_boxes_.assign(ne * scene_capacity_, sensors::Aabb());
    scenes_.reserve(ne);
    for (std::size_t e = 0; e < ne; ++e) {
      const std::size_t o = e * scene_capacity_;
      scenes_.emplace_back(&scene_objects_[o], scene_capacity_, &scene_nodes_[e * nodes], static_cast<std::uint32_t>(nodes),
                           &scene_prim_index_[o], &scene_boxes_[o], &scene_bvh_objects_[o]);
    }
  }
  rng_place_.resize(ne);
  rng_sensor_.resize(ne);
  for (std::size_t i = 0; i < ne; ++i) {
    rng_place_[i] = RngStream(cfg_.seed, static_cast<std::uint32_t>(i), kPurposePlacement);
    rng_sensor_[i] = RngStream(cfg_.seed, static_cast<std::uint32_t>(i), kPurposeSensorNoise);
  }
  return true;
}

void World::update_scene(int env) {
  // Rebuilt from the obstacle slots rather than moved with set_pose: a reset may change the
  // layout (other shapes, other count) and move_obstacles re-sorts the slots, so slot i is not
  // always the same object. clear/add/build write only the caller storage (no heap) and cost
  // microseconds for tens of obstacles, far below one image.
  sensors::Scene& sc = scenes_[static_cast<std::size_t>(env)];
  sc.clear();
  if (terrain_->type() != TerrainType::plane) {
    // The terrain takes the ground plane's slot (segmentation 0, as the ground).
    (void)sc.add(terrain_->scene_shape(), terrain_->scene_position_w(), Quat::Identity(), 0);
  } else if (cfg_.env.create_ground_plane) {
    const real gz = lower_w_[env][2] < 0 ? lower_w_[env][2] : 0_r;  // the plane collide_robots uses
    (void)sc.add(sensors::Shape::plane(), Vec3(0, 0, gz), Quat::Identity(), 0);
  }
  for (int k = 0; k < num_obstacles_[env]; ++k) {
    const Obstacle& o = obstacle(env, k);
    const Shape& s = o.shape;
    sensors::Shape rs;
    Vec3 p = s.position_w;
    switch (s.type) {
      case ShapeType::sphere: rs = sensors::Shape::sphere(s.radius_m); break;
      case ShapeType::box: rs = sensors::Shape::box(s.half_extents_m[0], s.half_extents_m[1], s.half_extents_m[2]); break;
      case ShapeType::capsule: rs = sensors::Shape::capsule(s.radius_m, s.half_length_m); break;
      case ShapeType::cylinder: rs = sensors::Shape::cylinder(s.radius_m, s.half_length_m); break;
      case ShapeType::convex_hull: {
        // Mesh obstacles render as their triangles (the file's surface; they collide as its
        // convex hull); a hull without a mesh as the box of its body-frame bounds.
        const std::size_t ci = o.class_index;
        if (ci < render_meshes_.size() && render_meshes_[ci]) {
          rs = sensors::Shape::triangle_mesh(&render_meshes_[ci]->mesh);
          break;
        }
        Vec3 mn = Vec3::Constant(1e30_r), mx = Vec3::Constant(-1e30_r);
        for (int v = 0; v < s.num_vertices; ++v) {
          mn = mn.cwiseMin(s.vertices[v]);
          mx = mx.cwiseMax(s.vertices[v]);
        }
        if (s.num_vertices == 0) continue;
        const Vec3 half = ((mx - mn) / 2).cwiseMax(Vec3::Constant(1e-4_r));
        rs = sensors::Shape::box(half[0], half[1], half[2]);
        p += rotate(s.orientation_wb, Vec3((mn + mx) / 2));
        break;
      }
    }
    (void)sc.add(rs, p, s.orientation_wb, static_cast<std::uint32_t>(o.semantic_id));
  }
  (void)sc.build();
}

void World::render_ray_sensors(int env, bool all) {
  const std::uint64_t n = stats_[env].env_steps;
  bool any = false;
  for (const SensorSlot& s : sensors_)
    any = any || (s.kind != SensorKind::imu && (all || n % static_cast<std::uint64_t>(s.every) == 0));
  if (!any) return;
  update_scene(env);
  const sensors::Scene& sc = scenes_[static_cast<std::size_t>(env)];
  for (SensorSlot& s : sensors_) {
    if (s.kind == SensorKind::imu || !(all || n % static_cast<std::uint64_t>(s.every) == 0)) continue;
    for (int r = 0; r < robots_per_env_; ++r) {
      const std::size_t i = index(env, r);
      const sensors::SensorPose pose = sensors::sensor_pose(state_[i], s.mounts[i]);
      sensors::SensorOutput out;
      out.range = &s.ranges[i * s.pixels];
      out.segmentation = &s.segmentation[i * s.pixels];
      (void)sensors::render(sc, pose, s.table, s.range, s.depth, out, &s.noise, &rng_sensor_[static_cast<std::size_t>(env)]);
    }
  }
}

void World::render_sensors(int env) {
  if (any_ray_sensor_) render_ray_sensors(env, true);
}

void World::obstacles_changed(int env) {
  Obstacle* o = obstacles_.data() + static_cast<std::size_t>(env) * obstacle_capacity_;
  const int n = num_obstacles_[env];
  for (int i = 0; i < n; ++i) shape_aabb(o[i].shape, o[i].aabb_min_w, o[i].aabb_max_w);
  sort_sweep_order(o, n);
  if (any_ray_sensor_) render_ray_sensors(env, true);
}

void World::update_imus(int env, int robot, const Vec3& linvel_before_w) {
  const std::size_t i = index(env, robot);
  const RigidBodyState& st = state_[i];
  const real dt = cfg_.sim.dt_s;
  // Acceleration over the physics step from the velocity change: it contains every force the
  // integrator applied (thrust, drag, contact, disturbance, gravity), as a force sensor would.
  const Vec3 acc_w = (st.linvel_w - linvel_before_w) / dt;
  for (std::size_t k = 0; k < sensors_.size(); ++k) {
    SensorSlot& s = sensors_[k];
    if (s.kind != SensorKind::imu) continue;
    (void)sensors::imu_update(cfg_.robot.sensors[k].imu, s.imu_state[i], st.orientation_wb, acc_w, st.angvel_b, Quat::Identity(), dt,
                              rng_sensor_[static_cast<std::size_t>(env)], s.imu[i]);
  }
}

const real* World::sensor_ranges(int env, int sensor, int robot) const {
  const SensorSlot& s = sensors_[static_cast<std::size_t>(sensor)];
  return s.kind == SensorKind::imu ? nullptr : &s.ranges[index(env, robot) * s.pixels];
}
const std::int32_t* World::sensor_segmentation(int env, int sensor, int robot) const {
  const SensorSlot& s = sensors_[static_cast<std::size_t>(sensor)];
  return s.kind == SensorKind::imu ? nullptr : &s.segmentation[index(env, robot) * s.pixels];
}
const sensors::ImuSample& World::imu_sample(int env, int sensor, int robot) const {
  static const sensors::ImuSample kZero{};
  const SensorSlot& s = sensors_[static_cast<std::size_t>(sensor)];
  return s.kind == SensorKind::imu ? s.imu[index(env, robot)] : kZero;
}
const sensors::Mount& World::sensor_mount(int env, int sensor, int robot) const {
  static const sensors::Mount kIdentity{};
  const SensorSlot& s = sensors_[static_cast<std::size_t>(sensor)];
  return s.kind == SensorKind::imu ? kIdentity : s.mounts[index(env, robot)];
}

std::size_t World::bytes_per_env() const { return env_bytes(cfg_, obstacle_capacity_, height_points_); }

}  // namespace kestrel::sim
