// Backend `planar`: Box2D 2.4 (Debian libbox2d-dev) for robots that move in a plane.
//
// One b2World per environment (zero gravity: the plane is horizontal), stepped by the thread pool
// over a static partition of environments. Box2D is deterministic for a single-threaded world
// (same inputs, same order of calls -> same bits), and no environment touches another's world, so
// results are bit-identical for any thread count (tests/sim/backends/planar_test.cpp hashes them).
// (Box2D 2.4 keeps a few global profiling counters, b2_gjkCalls / b2_toiCalls ..., that every
// world increments without synchronisation; they are statistics only and never read back.)
//
// Robots:
//  - ground_vehicle: a box on a dynamic body whose origin is the rear axle. Every physics step
//    the velocity + steering-angle controller (controllers/velocity_steering.hpp) turns the
//    command [speed, steering] and the measured speed along the heading into the next speed and
//    steering angle, and the body gets the kinematic bicycle model's velocity (rear axle moving at
//    v along the heading, yaw rate v tan(delta) / L; Rajamani 2012, sec. 2.2) before
//    b2World::Step. Box2D's contact solver then removes any velocity into an obstacle, so a
//    collision stops the car, and the next step starts from that measured speed.
//  - multirotor at a fixed altitude (a reduced model, documented here): the Lee controller
//    (position / velocity / acceleration / velocity-steering) runs on the planar state lifted to
//    3-D (z = altitude, level attitude with the body's yaw). Attitude is assumed to track
//    instantly (quasi-static: the attitude loop is far faster than the translation), so the
//    desired force m (a_cmd - g) is what the tilted thrust delivers: its norm and the Lee yaw
//    torque go through the same allocation (sequential desaturation) and motor model as the rigid
//    World; the horizontal force is m a_cmd,xy, bounded by the horizontal thrust the realised
//    collective thrust T leaves after holding the weight, sqrt(T^2 - (m g)^2); the yaw torque is
//    the realised motor torque. Roll/pitch dynamics and altitude changes are not modelled.
//
// Obstacles: the shared layout (sim/layout.hpp) of the env config's asset classes, its upright
// obstacles as circles (thin poles, rods, trees' trunks, spheres)
// and yaw-rotated boxes (cubes, panels, small walls, bounding walls), one static body per slot,
// created at set-up; a reset edits the slots' shapes in place, moves them and enables the used
// ones, so no Box2D object is created inside a step. Roll and pitch ranges of 3-D asset classes
// are ignored (the plane cuts their vertical extrusion); mesh obstacles are refused (rigid only).
//
// Sensors: a 2-D lidar of N beams over a field of view, through b2World::RayCast with a callback
// that keeps the closest hit (it returns the hit's fraction, which clips the ray).
//
// Heap: Box2D allocates its contacts from a block allocator (16 KiB chunks, reused through free
// lists) and grows its broad-phase buffers and tree node pool on demand, all through
// b2Alloc_Default / b2Free_Default (malloc/free), which libbox2d.so calls through its PLT. Measured
// with a process-wide malloc counter, that made a few calls in every thousand steps even after a
// long warm-up (each new peak of contacts or proxies in some environment). So this file defines
// both functions (they interpose on the library's; sim/CMakeLists.txt exports them from every
// executable that links kestrel_sim): outside a step they are malloc/free; inside a step (a
// thread-local arena is set while an environment steps or resets) they bump-allocate from that
// environment's arena, sized at set-up (kStepArenaBytes). Arena memory freed by Box2D is not
// reused (growth is rare and geometric); a full arena falls back to malloc and is counted
// (Simulator::step_heap_fallbacks), never silent. tests/sim/backends/planar_heap_test.cpp checks zero
// malloc calls inside steps.
#include <box2d/box2d.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <cstdio>

#include "kestrel/allocation/allocation_model.hpp"
#include "kestrel/allocation/presets.hpp"
#include "kestrel/allocation/sequential_desaturation.hpp"
#include "kestrel/controllers/velocity_steering.hpp"
#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/episode.hpp"
#include "kestrel/sim/layout.hpp"
#include "kestrel/sim/schema.hpp"
#include "../scene/episode_draw.hpp"
#include "kestrel/sim/limits.hpp"
#include "kestrel/sim/robot_model.hpp"
#include "kestrel/sim/simulator.hpp"
#include "kestrel/sim/state_hash.hpp"
#include "kestrel/sim/thread_pool.hpp"

namespace kestrel::sim {

namespace al = kestrel::allocation;

namespace {

constexpr std::size_t kStepArenaBytes = 96 * 1024;  // per environment: ~5 block-allocator chunks

/// One environment's in-step allocation arena (bump allocator over set-up storage).
struct StepArena {
  unsigned char* base = nullptr;
  std::size_t size = 0, used = 0;
  std::uint64_t fallbacks = 0;  // allocations that did not fit and went to malloc
};
thread_local StepArena* t_arena = nullptr;

/// Sets the calling thread's arena for a scope (the worker stepping an environment).
struct ArenaScope {
  StepArena* saved;
  explicit ArenaScope(StepArena* a) : saved(t_arena) { t_arena = a; }
  ~ArenaScope() { t_arena = saved; }
  ArenaScope(const ArenaScope&) = delete;
  ArenaScope& operator=(const ArenaScope&) = delete;
};

// Every block carries a 16-byte header saying where it came from, so b2Free_Default needs no
// lookup: malloc'd blocks are freed, arena blocks are left to their arena.
constexpr std::uint32_t kFromMalloc = 0x4d414c43u, kFromArena = 0x4152454eu;
constexpr std::size_t kHeader = 16;

}  // namespace
}  // namespace kestrel::sim

// Box2D's allocation hooks (b2_settings.h), interposed on libbox2d.so's definitions.
void* b2Alloc_Default(int32 size) {
  using kestrel::sim::t_arena;
  const std::size_t n = (static_cast<std::size_t>(size > 0 ? size : 1) + kestrel::sim::kHeader + 15) & ~static_cast<std::size_t>(15);
  unsigned char* p = nullptr;
  std::uint32_t tag = kestrel::sim::kFromMalloc;
  if (t_arena != nullptr && t_arena->used + n <= t_arena->size) {
    p = t_arena->base + t_arena->used;
    t_arena->used += n;
    tag = kestrel::sim::kFromArena;
  } else {
    if (t_arena != nullptr) ++t_arena->fallbacks;
    p = static_cast<unsigned char*>(std::malloc(n));
    if (p == nullptr) return nullptr;
  }
  std::memcpy(p, &tag, sizeof(tag));
  return p + kestrel::sim::kHeader;
}

void b2Free_Default(void* mem) {
  if (mem == nullptr) return;
  unsigned char* p = static_cast<unsigned char*>(mem) - kestrel::sim::kHeader;
  std::uint32_t tag = 0;
  std::memcpy(&tag, p, sizeof(tag));
  if (tag == kestrel::sim::kFromMalloc) std::free(p);
}

namespace kestrel::sim {
namespace {

constexpr int kVelocityIterations = 8;  // Box2D's recommended defaults
constexpr int kPositionIterations = 3;

enum class SlotShape : std::uint8_t { circle, box };

struct Slot {
  b2Body* body = nullptr;
  SlotShape shape = SlotShape::circle;
  std::uint8_t class_index = 0;
  bool used = false;
  real x = 0, y = 0, yaw = 0, radius = 0, hx = 0, hy = 0;  // current geometry
};

/// Collects the normal impulses on robot bodies (user data = robot index + 1).
class ContactForces final : public b2ContactListener {
 public:
  real* force_xy = nullptr;      // (robots_per_env x 2) N, world frame, last physics step
  real* normal_sum_N = nullptr;  // (robots_per_env) sum of normal force magnitudes
  float inv_dt = 0;
  void PostSolve(b2Contact* c, const b2ContactImpulse* imp) override {
    const std::uintptr_t ua = c->GetFixtureA()->GetBody()->GetUserData().pointer;
    const std::uintptr_t ub = c->GetFixtureB()->GetBody()->GetUserData().pointer;
    if (ua == 0 && ub == 0) return;
    b2WorldManifold wm;
    c->GetWorldManifold(&wm);  // normal points from A to B
    float p = 0;
    for (int k = 0; k < imp->count; ++k) p += imp->normalImpulses[k];
    const float f = p * inv_dt;
    if (ub != 0) add(ub - 1, wm.normal.x * f, wm.normal.y * f, f);
    if (ua != 0) add(ua - 1, -wm.normal.x * f, -wm.normal.y * f, f);
  }

 private:
  void add(std::uintptr_t r, float fx, float fy, float f) {
    force_xy[2 * r] += static_cast<real>(fx);
    force_xy[2 * r + 1] += static_cast<real>(fy);
    normal_sum_N[r] += static_cast<real>(f);
  }
};

/// Closest hit along a ray, ignoring one body (the robot carrying the lidar).
class ClosestHit final : public b2RayCastCallback {
 public:
  const b2Body* ignore = nullptr;
  float fraction = 1;
  bool hit = false;
  float ReportFixture(b2Fixture* f, const b2Vec2&, const b2Vec2&, float frac) override {
    if (f->GetBody() == ignore) return -1;  // filter: continue as if not there
    hit = true;
    fraction = frac;
    return frac;  // clip the ray here: only closer hits are reported from now on
  }
};

struct Env {
  StepArena arena;  // in-step Box2D allocations (before the world: it outlives nothing it serves)
  std::unique_ptr<b2World> world;
  ContactForces contacts;
  std::vector<b2Body*> robots;
  std::vector<Slot> slots;
  std::vector<int> next_slot;  // per asset class: its next free slot while a layout is mapped
  RngStream rng_reset, rng_step;
  Vec3 lower = Vec3::Zero(), upper = Vec3::Zero();
  int episode_step = 0, episodes_since_layout = 0;
  std::uint32_t layout_generation = 0;
  bool episode_fallback = false;  // a robot of this episode was placed by a fallback (never a success)
  EnvStats stats;
};

real clearance_to_slot(const Slot& s, real x, real y) {
  if (s.shape == SlotShape::circle) return std::sqrt((x - s.x) * (x - s.x) + (y - s.y) * (y - s.y)) - s.radius;
  real sn = 0, cs = 1;
  sin_cos(s.yaw, sn, cs);
  const real dx = x - s.x, dy = y - s.y;
  const real lx = cs * dx + sn * dy, ly = -sn * dx + cs * dy;  // point in the box frame
  const real qx = std::fabs(lx) - s.hx, qy = std::fabs(ly) - s.hy;
  const real ox = std::max(qx, 0_r), oy = std::max(qy, 0_r);
  return std::sqrt(ox * ox + oy * oy) + std::min(std::max(qx, qy), 0_r);  // signed distance to a box
}

/// What the plane can carry, checked before anything is built: the counts and ranges every
/// backend checks, the planar backend's own limits (2-D sensors and terrain, no spinning, moving or
/// mesh obstacles, randomisation ranges), and the memory estimate. False and the message (without
/// the "simulator planar: " prefix) for the first problem.
bool validate_planar_config(const WorldConfig& c, std::string& error) {
  auto fail = [&](const std::string& m) {
    error = m;
    return false;
  };
  const SimulatorConfig& sc = c.simulator;
  const EnvConfig& e = c.env;
  if (e.num_envs < 1) return fail("env.num_envs: expected a positive integer");
  if (c.robot.robots_per_env < 1) return fail("robot.robots_per_env: expected a positive integer");
  if (!(c.sim.dt_s > 0)) return fail("sim.dt_s: expected a positive number");
  if (c.num_threads < 1) return fail("threads: expected a positive integer");
  if (c.task.episode_len_env_steps < 1) return fail("task.episode_len_env_steps: expected a positive integer");
  if (!(e.num_physics_steps_per_env_step_mean >= 1)) return fail("env.num_physics_steps_per_env_step_mean: expected >= 1");
  if (c.task.placement_attempts < 1 || c.task.placement_attempts > kMaxPlacementAttempts)
    return fail("task.placement_attempts: expected an integer in [1, " + std::to_string(kMaxPlacementAttempts) + "]");
  if (!c.robot.sensors.empty())
    return fail("robot sensors (" + c.robot.sensors.front().name +
               ") render 3-D scenes; planar has a 2-D lidar (simulator.lidar_beams); use simulator: rigid for 3-D sensors");
  if (e.sample_timestep_for_latency || e.num_physics_steps_per_env_step_std != 0 || e.perturb_observations || e.enable_disturbance)
    return fail("latency sampling, random physics-step counts, observation noise and disturbances are rigid-only; use simulator: rigid");
  if (!(sc.max_push_vel_xy_m_s >= 0) || !(sc.added_mass_min_kg <= sc.added_mass_max_kg) || !(sc.motor_scale_min > 0) ||
      !(sc.motor_scale_min <= sc.motor_scale_max) || !(sc.gain_scale_min > 0) || !(sc.gain_scale_min <= sc.gain_scale_max) ||
      !(sc.com_bias_max_m >= 0) || !(c.robot.mass_kg + sc.added_mass_min_kg > 0))
    return fail("simulator: randomisation ranges need min <= max, scales > 0, com_bias_max_m >= 0 and a positive total mass");
  if (articulated_only_randomisation(sc))
    return fail("simulator.friction, restitution, joint_armature_kg_m2 and max_push_force_N randomise articulated robots; "
                "use simulator: rigid with an articulated robot (robot: go2)");
  if (sc.lidar_beams < 0 || sc.lidar_beams > 4096 || !(sc.lidar_max_range_m > 0) || !(sc.lidar_fov_rad > 0 && sc.lidar_fov_rad <= kTwoPi))
    return fail("simulator.lidar_*: expected 0..4096 beams, a positive range and a field of view in (0, 2 pi]");
  // Upper bounds of every count (sim/limits.hpp) and the memory estimate, before allocating.
  {
    std::string lerr;
    if (!check_config_limits(c, lerr)) return fail(lerr);
    if (!check_config_fields(c, lerr)) return fail(lerr);  // the schema's ranges (sim/schema.hpp)
    long long slots = 0;
    for (const AssetClass& a : e.assets) slots += asset_class_slots(a);
    // Per environment: the step arena, ~1 KiB of Box2D body and fixture per obstacle and robot
    // (generous), per robot the controller/allocator/motor state, the views and the lidar.
    const double per_robot = sizeof(ControllerState) + sizeof(VelocitySteeringState) + sizeof(al::AllocatorState) +
                             sizeof(al::MotorModelState) + 1024.0 + 64.0 * sizeof(real) + 4.0 * sc.lidar_beams;
    const double per_env = static_cast<double>(kStepArenaBytes) + 1024.0 * static_cast<double>(slots) +
                           per_robot * c.robot.robots_per_env;
    const double need = per_env * e.num_envs, gib = 1024.0 * 1024.0 * 1024.0;
    if (need > c.max_memory_gib * gib) {
      char buf[400];
      std::snprintf(buf, sizeof buf,
                    "memory: this world needs about %.3g GiB (%d envs), more than max_memory_gib = %.4g GiB; allowed: up to "
                    "max_memory_gib (scenario `max_memory_gib` or kestrel run --max-memory-gib); reduce env.num_envs or the counts",
                    need / gib, e.num_envs, c.max_memory_gib);
      return fail(buf);
    }
  }
  if (e.terrain.type == TerrainType::heightfield)
    return fail("env.terrain: a height field is 3-D ground the plane cannot represent; use simulator: rigid");
  if (e.terrain.type == TerrainType::trimesh)
    return fail("env.terrain: triangle-mesh terrain is 3-D ground the plane cannot represent; use simulator: rigid");
  if (e.terrain.measure_heights) return fail("env.terrain.measure_heights: no heights on a plane; use simulator: rigid");
  for (const AssetClass& a : e.assets) {
    if (a.max_angular_speed_rad_s > 0)
      return fail("env.assets." + a.name + ": spinning obstacles are rigid-only; use simulator: rigid");
    if (a.kind == AssetKind::mesh)
      return fail("env.assets." + a.name + ": 3-D mesh obstacles are not supported (circles and boxes only); use simulator: rigid");
    if (a.max_speed_m_s > 0) return fail("env.assets." + a.name + ": moving obstacles are rigid-only; use simulator: rigid");
    if (a.num_assets < 0 || a.min_num_assets < 0 || a.min_num_assets > a.num_assets)
      return fail("env.assets." + a.name + ": expected 0 <= min_num_assets <= num_assets");
  }
  for (int i = 0; i < 2; ++i)
    if (!(e.lower_bound_min_m[i] <= e.lower_bound_max_m[i] && e.upper_bound_min_m[i] <= e.upper_bound_max_m[i] &&
          e.lower_bound_max_m[i] < e.upper_bound_min_m[i]))
      return fail("env bounds: expected lower_bound_min <= lower_bound_max < upper_bound_min <= upper_bound_max on x and y");
  return true;
}

class PlanarSimulator final : public Simulator {
 public:
  PlanarSimulator() : Simulator(Backend::planar) {}

  bool init(const WorldConfig& c, std::string& error) {
    auto bad = [&](const std::string& m) {
      error = "simulator planar: " + m;
      return false;
    };
    if (std::string why; !validate_planar_config(c, why)) return bad(why);
    const SimulatorConfig& sc = c.simulator;

    ground_ = sc.vehicle == PlanarVehicle::ground_vehicle || (sc.vehicle == PlanarVehicle::automatic && c.robot.kind == robots::RobotKind::ground_vehicle);
    ground_vehicle_ = ground_;
    int adim = 0;
    if (ground_) {
      vs_.wheelbase_m = sc.wheelbase_m;
      vs_.mass_kg = c.robot.mass_kg;
      vs_.max_speed_m_s = sc.max_speed_m_s;
      vs_.max_steering_rad = sc.max_steering_rad;
      if (validate_velocity_steering_params(vs_) != Status::ok)
        return bad("simulator.wheelbase_m / max_speed_m_s / max_steering_rad: expected positive values, steering < 1.5 rad");
      adim = static_cast<int>(kVelocitySteeringActionDim);
      // The ground vehicle's own controller (the table's velocity_steering kind). A multirotor
      // controller named in the scenario (a task's default) stands for it, as before the table
      // had the kind; another family's is refused.
      if (controller_family(c.controller.kind) == ControlFamily::articulated)
        return bad("controller " + c.controller.name + " drives joints; a ground vehicle takes velocity_steering_control");
      controller_ = kestrel::controller_name(ControllerKind::velocity_steering);
    } else {
      const ControllerKind k = c.controller.kind;
      if (k != ControllerKind::lee_position && k != ControllerKind::lee_velocity && k != ControllerKind::lee_acceleration &&
          k != ControllerKind::lee_velocity_steering_angle)
        return bad("controller " + c.controller.name +
                   " needs roll/pitch dynamics; the planar multirotor takes lee_position_control, lee_velocity_control, "
                   "lee_acceleration_control or lee_velocity_steering_angle_control; use simulator: rigid");
      if (c.robot.kind == robots::RobotKind::ground_vehicle) return bad("robot ground_vehicle with simulator.vehicle multirotor; pick a multirotor robot");
      // The same robot compile as the rigid World (URDF rotors, the ROV's gains, the allocator choice).
      std::string robot_error;
      if (!compile_multirotor(c, mr_, robot_error)) return bad(robot_error);
      // The plane carries the vehicle's weight at standard gravity (the altitude is held), so the
      // controller's feed-forward uses it whatever sim.gravity_w says.
      mr_.ctrl.lee.gravity_w = Vec3(0, 0, -kStandardGravity);
      adim = static_cast<int>(controller_action_dim(k, mr_.ctrl));
      controller_ = c.controller.name;
    }
    // Robot footprint.
    const ShapeSpec& sh = c.robot.shape;
    if (ground_) {
      half_x_ = sh.type == ShapeType::box ? sh.half_extents_m[0] : 0.25_r;
      half_y_ = sh.type == ShapeType::box ? sh.half_extents_m[1] : 0.15_r;
      // The origin is the rear axle and the box centre half a wheelbase ahead: the disc about the
      // origin that covers the box (placement clearance is measured from the origin).
      bound_r_ = std::sqrt((std::fabs(sc.wheelbase_m / 2) + half_x_) * (std::fabs(sc.wheelbase_m / 2) + half_x_) + half_y_ * half_y_);
    } else {
      radius_ = sh.type == ShapeType::box ? std::sqrt(sh.half_extents_m[0] * sh.half_extents_m[0] + sh.half_extents_m[1] * sh.half_extents_m[1])
                                          : sh.radius_m;
      bound_r_ = radius_;
    }
    allocate_views(c, adim, sc.lidar_beams);
    plane_z_ = ground_ ? 0_r : sc.altitude_m;
    holds_altitude_ = !ground_;  // the multirotor flies in the plane z = simulator.altitude_m
    altitude_m_ = ground_ ? 0_r : sc.altitude_m;
    num_range_images_ = sc.lidar_beams > 0 ? 1 : 0;
    const std::size_t nr = static_cast<std::size_t>(num_robots());
    steer_.assign(nr, VelocitySteeringState());
    mr_state_.assign(nr, robots::MultirotorState());
    force_xy_.assign(2 * nr, 0);
    normal_sum_.assign(nr, 0);
    prev_omega_.assign(nr, 0);
    kin_.assign(5 * nr, 0);
    envs_.resize(static_cast<std::size_t>(num_envs_));
    arena_storage_.reset(new unsigned char[kStepArenaBytes * static_cast<std::size_t>(num_envs_)]);
    for (int ei = 0; ei < num_envs_; ++ei) {
      StepArena& a = envs_[static_cast<std::size_t>(ei)].arena;
      a.base = arena_storage_.get() + kStepArenaBytes * static_cast<std::size_t>(ei);
      a.size = kStepArenaBytes;
    }
    for (int ei = 0; ei < num_envs_; ++ei) build_env(ei);
    for (int ei = 0; ei < num_envs_; ++ei) {
      reset_env(ei);
      envs_[static_cast<std::size_t>(ei)].stats.resets = 0;  // the initial reset is not counted
    }
    pool_.reset(new ThreadPool(std::min(c.num_threads, num_envs_)));
    refresh_all();
    return true;
  }

  int num_threads() const override { return pool_->size(); }
  const char* controller_name() const override { return controller_.c_str(); }

  void post_physics_step() override {
    phase_ = Phase::post;
    pool_->run(&PlanarSimulator::trampoline, this);
    refresh_all();
  }

  void reset_idx(const int* env_ids, int count) override {
    for (int k = 0; k < count; ++k)
      if (env_ids[k] >= 0 && env_ids[k] < num_envs_) {
        ArenaScope arena(&envs_[static_cast<std::size_t>(env_ids[k])].arena);
        reset_env(env_ids[k]);
      }
    refresh_all();
  }

  // After the common checks (Simulator::reset_root_states): only states the plane can hold.
  bool set_root_states(const int* env_ids, int count, const real* pos_w, const real* quat_xyzw, const real* lin_vel_w,
                       const real* ang_vel_w) override {
    const int rows = count * robots_per_env_;
    for (int j = 0; j < rows; ++j) {
      const std::string row = " (row " + std::to_string(j) + ")";
      const real* q = quat_xyzw + 4 * j;
      if (std::fabs(q[0]) > 1e-4_r || std::fabs(q[1]) > 1e-4_r || std::fabs(ang_vel_w[3 * j]) > 1e-6_r ||
          std::fabs(ang_vel_w[3 * j + 1]) > 1e-6_r)
        return fail("simulator planar: reset_root_states: roll/pitch (a non-yaw orientation or x/y angular velocity) cannot "
                    "be represented in the plane" + row + "; use simulator: rigid");
      if (std::fabs(pos_w[3 * j + 2] - plane_z_) > 1e-4_r || std::fabs(lin_vel_w[3 * j + 2]) > 1e-6_r)
        return fail("simulator planar: reset_root_states: z must be the plane height " + std::to_string(plane_z_) +
                    " with zero vertical velocity" + row + "; use simulator: rigid for 3-D states");
    }
    for (int k = 0; k < count; ++k) {
      Env& ev = envs_[static_cast<std::size_t>(env_ids[k])];
      ArenaScope arena(&ev.arena);
      for (int r = 0; r < robots_per_env_; ++r) {
        const int j = k * robots_per_env_ + r;
        const std::size_t i = static_cast<std::size_t>(env_ids[k] * robots_per_env_ + r);
        const real* q = quat_xyzw + 4 * j;
        const real yaw = 2 * std::atan2(q[2], q[3]);
        place_body(ev.robots[static_cast<std::size_t>(r)], i, pos_w[3 * j], pos_w[3 * j + 1], wrap_pi(yaw), lin_vel_w[3 * j],
                   lin_vel_w[3 * j + 1], ang_vel_w[3 * j + 2]);
        reset_controller(i, ev.rng_reset, false);
        crashed_[i] = 0;
        force_xy_[2 * i] = force_xy_[2 * i + 1] = normal_sum_[i] = 0;
        refresh_robot(env_ids[k], r);
      }
    }
    return true;
  }

  void update_sensors() override {
    for (int ei = 0; ei < num_envs_; ++ei) {
      ArenaScope arena(&envs_[static_cast<std::size_t>(ei)].arena);
      render_lidar(ei);
    }
  }

  void set_auto_reset(bool on) override { auto_reset_ = on; }
  void set_curriculum_level(real level) override {
    if (std::isfinite(level)) cfg_.env.curriculum_level = std::min(std::max(level, 0_r), 1_r);  // read by generate_layout
  }
  void env_bounds(int env, Vec3& lower_w, Vec3& upper_w) const override {
    const Env& ev = envs_[static_cast<std::size_t>(env)];
    lower_w = ev.lower;
    upper_w = ev.upper;
  }

  // The 2-D lidar as one image row. Beam k is at -fov/2 + k fov/(beams-1) (clockwise first), so
  // column 0, the leftmost (body +y side, as the rigid images), is the last beam: read backwards.
  RangeImage range_image(int robot, int k) const override {
    RangeImage img;
    if (robot < 0 || robot >= num_robots() || k != 0 || lidar_beams_ == 0) return img;
    img.ranges = lidar_.data() + static_cast<std::size_t>(robot) * static_cast<std::size_t>(lidar_beams_) +
                 static_cast<std::size_t>(lidar_beams_ - 1);
    img.height = 1;
    img.width = lidar_beams_;
    img.row_step = 0;
    img.col_step = -1;
    img.max_range_m = cfg_.simulator.lidar_max_range_m;
    img.horizontal_fov_rad = cfg_.simulator.lidar_fov_rad;
    return img;
  }

  static Slot* first_slot(Env& ev, int asset_class) {
    for (Slot& sl : ev.slots)
      if (static_cast<int>(sl.class_index) == asset_class) return &sl;
    return nullptr;
  }

  // A box's x / y footprint and yaw (its z centre and half height do not apply in the plane).
  bool set_obstacle_boxes(int env, const ObstacleBox* boxes, int count) override {
    const char* pre = "simulator planar: set_obstacle_boxes: ";  // a string only on a refusal: no heap in a step
    if (env < 0 || env >= num_envs_) return fail(std::string(pre) + "env " + std::to_string(env) + " out of range");
    Env& ev = envs_[static_cast<std::size_t>(env)];
    for (int b = 0; b < count; ++b) {  // checked first: nothing changes on a refusal (and no heap)
      const ObstacleBox& x = boxes[b];
      const real hx = x.half_extents_m[0], hy = x.half_extents_m[1];
      if (!(std::isfinite(x.center_w[0]) && std::isfinite(x.center_w[1]) && std::isfinite(x.yaw_rad) && hx > 0 && hy > 0 &&
            std::isfinite(hx) && std::isfinite(hy)))
        return fail(std::string(pre) + "expected a finite centre and yaw and positive finite half extents");
      const Slot* sl = first_slot(ev, x.asset_class);
      if (sl == nullptr)
        return fail(std::string(pre) + "asset class " + std::to_string(x.asset_class) + " has no obstacle slot (" +
                    std::to_string(cfg_.env.assets.size()) + " asset classes)");
      if (sl->shape != SlotShape::box)
        return fail(std::string(pre) + "asset class " + std::to_string(x.asset_class) + " has circle slots, not boxes");
    }
    ArenaScope arena(&ev.arena);  // broad-phase buffer growth, if any, goes to the env's arena
    for (int b = 0; b < count; ++b) {
      const ObstacleBox& x = boxes[b];
      set_slot(*first_slot(ev, x.asset_class), x.center_w[0], x.center_w[1], x.yaw_rad, 0, x.half_extents_m[0], x.half_extents_m[1]);
    }
    if (count > 0) render_lidar(env);
    return true;
  }

  std::uint64_t step_heap_fallbacks() const override {
    std::uint64_t n = 0;
    for (const Env& ev : envs_) n += ev.arena.fallbacks;
    return n;
  }

  bool placement_fallback(int env) const override {
    return env >= 0 && env < num_envs_ && envs_[static_cast<std::size_t>(env)].episode_fallback;
  }

  WorldSummary summary() const override {
    WorldSummary s;
    double err = 0, end_dist = 0, final_dist = 0;
    for (int ei = 0; ei < num_envs_; ++ei) {
      const EnvStats& st = envs_[static_cast<std::size_t>(ei)].stats;
      add_env_counters(s, st);
      err += st.tracking_error_sum_m;
      end_dist += st.final_distance_sum_m;
      for (int r = 0; r < robots_per_env_; ++r) final_dist += static_cast<double>(distance_to_target(ei, r));
    }
    s.mean_tracking_error_m = s.env_steps > 0 ? err / (static_cast<double>(s.env_steps) * robots_per_env_) : 0;
    s.final_mean_distance_m = final_dist / static_cast<double>(num_robots());
    s.episode_end_distance_m = s.episodes_done > 0 ? end_dist / static_cast<double>(s.episodes_done) : 0;
    // As the rigid World: the union of every robot's latched controller / chain faults (the
    // non-ok statuses met while resetting come with the per-environment counters above).
    for (std::size_t i = 0; i < static_cast<std::size_t>(num_robots()); ++i)
      s.fault_bits |= ground_ ? steer_[i].faults.bits : robots::multirotor_faults(mr_state_[i]);
    return s;
  }

  std::uint64_t state_hash() const override {
    Fnv1a f;  // as World::state_hash
    auto bytes = [&f](const void* p, std::size_t n) { f.bytes(p, n); };
    for (int ei = 0; ei < num_envs_; ++ei) {
      const Env& ev = envs_[static_cast<std::size_t>(ei)];
      for (int r = 0; r < robots_per_env_; ++r) {
        const b2Body* b = ev.robots[static_cast<std::size_t>(r)];
        const b2Vec2 p = b->GetPosition(), v = b->GetLinearVelocity();
        const float a = b->GetAngle(), w = b->GetAngularVelocity();
        bytes(&p, sizeof(p));
        bytes(&a, sizeof(a));
        bytes(&v, sizeof(v));
        bytes(&w, sizeof(w));
        const std::size_t i = static_cast<std::size_t>(ei * robots_per_env_ + r);
        if (ground_) bytes(&steer_[i].steering_rad, sizeof(real));
        else bytes(mr_state_[i].motors.thrust_N, sizeof(real) * static_cast<std::size_t>(mr_.airframe.num_rotors));
        bytes(&crashed_[i], 1);
        if (lidar_beams_ > 0) bytes(&lidar_[i * static_cast<std::size_t>(lidar_beams_)], sizeof(real) * static_cast<std::size_t>(lidar_beams_));
      }
      for (const Slot& s : ev.slots)
        if (s.used) {
          bytes(&s.x, sizeof(real));
          bytes(&s.y, sizeof(real));
        }
      bytes(&ev.episode_step, sizeof(int));
      bytes(&ev.stats.resets, sizeof(ev.stats.resets));
      bytes(&ev.stats.crashes, sizeof(ev.stats.crashes));
    }
    return f.h;
  }

  static void trampoline(void* ctx, int worker) { static_cast<PlanarSimulator*>(ctx)->run_slice(worker); }

 protected:
  void advance() override {
    phase_ = Phase::physics;
    pool_->run(&PlanarSimulator::trampoline, this);
  }

  void set_velocity_xy(int env, int robot, real vx, real vy) override {
    ArenaScope arena(&envs_[static_cast<std::size_t>(env)].arena);
    b2Body* b = envs_[static_cast<std::size_t>(env)].robots[static_cast<std::size_t>(robot)];
    // The interface's velocity is the robot origin's (rear axle / centre); Box2D keeps the centre
    // of mass's: add w x (c - origin).
    const b2Vec2 o = b->GetPosition(), c = b->GetWorldCenter();
    const float w = b->GetAngularVelocity();
    b->SetLinearVelocity(b2Vec2(static_cast<float>(vx) - w * (c.y - o.y), static_cast<float>(vy) + w * (c.x - o.x)));
    refresh_robot(env, robot);
  }

 private:
  enum class Phase { physics, post };

  void run_slice(int worker) {
    const int t = pool_->size();
    const int begin = static_cast<int>(static_cast<long long>(num_envs_) * worker / t);
    const int end = static_cast<int>(static_cast<long long>(num_envs_) * (worker + 1) / t);
    for (int ei = begin; ei < end; ++ei) {
      ArenaScope arena(&envs_[static_cast<std::size_t>(ei)].arena);
      if (phase_ == Phase::physics) env_physics(ei);
      else env_post(ei);
    }
  }

  // ---- set-up ------------------------------------------------------------------------------
  void build_env(int ei) {
    Env& ev = envs_[static_cast<std::size_t>(ei)];
    ev.world.reset(new b2World(b2Vec2(0, 0)));
    ev.world->SetAllowSleeping(false);  // a parked robot must still see new velocity commands
    ev.contacts.force_xy = &force_xy_[static_cast<std::size_t>(2 * ei * robots_per_env_)];
    ev.contacts.normal_sum_N = &normal_sum_[static_cast<std::size_t>(ei * robots_per_env_)];
    ev.contacts.inv_dt = 1.0f / static_cast<float>(cfg_.sim.dt_s);
    ev.world->SetContactListener(&ev.contacts);
    ev.rng_reset = RngStream(cfg_.seed, cfg_.env.global_env(static_cast<int>(ei)), kPurposeReset);
    ev.rng_step = RngStream(cfg_.seed, cfg_.env.global_env(static_cast<int>(ei)), kPurposeDisturbance);
    for (int r = 0; r < robots_per_env_; ++r) {
      b2BodyDef bd;
      bd.type = b2_dynamicBody;
      bd.bullet = false;
      bd.userData.pointer = static_cast<std::uintptr_t>(r + 1);
      b2Body* b = ev.world->CreateBody(&bd);
      b2FixtureDef fd;
      b2PolygonShape box;
      b2CircleShape circle;
      if (ground_) {
        // Origin at the rear axle; the box centre sits half a wheelbase ahead of it.
        box.SetAsBox(static_cast<float>(half_x_), static_cast<float>(half_y_), b2Vec2(static_cast<float>(vs_.wheelbase_m / 2), 0), 0);
        fd.shape = &box;
      } else {
        circle.m_radius = static_cast<float>(radius_);
        fd.shape = &circle;
      }
      fd.density = 1;
      fd.friction = 0.3f;
      fd.restitution = 0;
      b->CreateFixture(&fd);
      ev.robots.push_back(b);
    }
    // Obstacle slots: one static body per upright obstacle a class's layout can hold (the four side
    // walls; a tree's trunk), disabled until used.
    ev.next_slot.assign(cfg_.env.assets.size(), 0);
    class_first_slot_.assign(cfg_.env.assets.size(), 0);
    for (std::size_t ci = 0; ci < cfg_.env.assets.size(); ++ci) {
      const AssetClass& a = cfg_.env.assets[ci];
      const bool is_box = a.kind == AssetKind::cube || a.kind == AssetKind::panel || a.kind == AssetKind::small_wall || a.kind == AssetKind::wall;
      const int n = a.kind == AssetKind::wall ? 4 : a.num_assets;
      class_first_slot_[ci] = static_cast<int>(ev.slots.size());
      for (int k = 0; k < n; ++k) {
        b2BodyDef bd;
        bd.type = b2_staticBody;
        bd.enabled = false;
        Slot s;
        s.body = ev.world->CreateBody(&bd);
        s.shape = is_box ? SlotShape::box : SlotShape::circle;
        s.class_index = static_cast<std::uint8_t>(ci);
        b2FixtureDef fd;
        b2PolygonShape box;
        b2CircleShape circle;
        box.SetAsBox(0.5f, 0.5f);
        circle.m_radius = 0.5f;
        fd.shape = is_box ? static_cast<b2Shape*>(&box) : static_cast<b2Shape*>(&circle);
        fd.friction = 0.3f;
        s.body->CreateFixture(&fd);
        ev.slots.push_back(s);
      }
    }
  }

  // ---- reset -------------------------------------------------------------------------------

  void set_slot(Slot& s, real x, real y, real yaw, real radius, real hx, real hy) {
    s.x = x;
    s.y = y;
    s.yaw = yaw;
    s.radius = radius;
    s.hx = hx;
    s.hy = hy;
    s.used = true;
    b2Shape* shape = s.body->GetFixtureList()->GetShape();
    if (s.shape == SlotShape::circle) static_cast<b2CircleShape*>(shape)->m_radius = static_cast<float>(radius);
    else static_cast<b2PolygonShape*>(shape)->SetAsBox(static_cast<float>(hx), static_cast<float>(hy));
    // SetTransform re-synchronises the broad-phase proxy with the edited shape when enabled;
    // SetEnabled(true) creates it from the edited shape otherwise.
    s.body->SetTransform(b2Vec2(static_cast<float>(x), static_cast<float>(y)), static_cast<float>(yaw));
    if (!s.body->IsEnabled()) s.body->SetEnabled(true);
  }

  /// The shared layout (sim/layout.hpp) in the plane: each upright obstacle becomes its class's
  /// next slot, a box as its yaw-rotated footprint, a sphere, capsule or cylinder as a circle of
  /// its radius (the plane cuts their vertical extrusion); tree branches and the walls' ceiling
  /// have no footprint and are left out.
  void generate_layout(Env& ev) {
    for (Slot& s : ev.slots) s.used = false;
    for (std::size_t ci = 0; ci < ev.next_slot.size(); ++ci) ev.next_slot[ci] = class_first_slot_[ci];
    struct Fill {
      PlanarSimulator* self;
      Env* ev;
      static void put(void* context, const Obstacle& o) {
        Fill& f = *static_cast<Fill*>(context);
        if (!o.upright) return;
        Slot& s = f.ev->slots[static_cast<std::size_t>(f.ev->next_slot[o.class_index]++)];
        const Shape& sh = o.shape;
        if (s.shape == SlotShape::box) {
          const Vec3 ex = rotate(sh.orientation_wb, Vec3::UnitX());
          f.self->set_slot(s, sh.position_w[0], sh.position_w[1], std::atan2(ex[1], ex[0]), 0, sh.half_extents_m[0], sh.half_extents_m[1]);
        } else {
          f.self->set_slot(s, sh.position_w[0], sh.position_w[1], 0, sh.radius_m, 0, 0);
        }
      }
    } fill{this, &ev};
    (void)sim::generate_layout(cfg_, cfg_.env.curriculum_level, ev.lower, ev.upper, ev.rng_reset, nullptr, &Fill::put, &fill);
    for (Slot& s : ev.slots)
      if (!s.used && s.body->IsEnabled()) s.body->SetEnabled(false);
  }

  bool clear_point(const Env& ev, real x, real y) const {
    const real need = bound_r_ + cfg_.task.clearance_m;
    for (const Slot& s : ev.slots)
      if (s.used && clearance_to_slot(s, x, y) < need) return false;
    return true;
  }

  bool clear_segment(const Env& ev, real x0, real y0, real x1, real y1) const {
    const real len = std::sqrt((x1 - x0) * (x1 - x0) + (y1 - y0) * (y1 - y0));
    const int n = 1 + static_cast<int>(len / 0.1_r);
    for (int k = 0; k <= n; ++k) {
      const real t = static_cast<real>(k) / static_cast<real>(n);
      if (!clear_point(ev, x0 + t * (x1 - x0), y0 + t * (y1 - y0))) return false;
    }
    return true;
  }

  void place_body(b2Body* b, std::size_t i, real x, real y, real yaw, real vx, real vy, real w) {
    b->SetTransform(b2Vec2(static_cast<float>(x), static_cast<float>(y)), static_cast<float>(yaw));
    b->SetAngularVelocity(static_cast<float>(w));
    const b2Vec2 o = b->GetPosition(), c = b->GetWorldCenter();
    const float wf = static_cast<float>(w);
    b->SetLinearVelocity(b2Vec2(static_cast<float>(vx) - wf * (c.y - o.y), static_cast<float>(vy) + wf * (c.x - o.x)));
    real sn = 0, cs = 1;
    sin_cos(static_cast<real>(b->GetAngle()), sn, cs);
    remember_kinematics(b, i, vx * cs + vy * sn, cs, sn);
  }

  /// Controller/motor state of robot i; with draw, also the domain randomisation draws.
  void reset_controller(std::size_t i, RngStream& rng, bool draw) {
    if (draw) {
      const SimulatorConfig& sc = cfg_.simulator;
      // Always five draws, in this order: added mass, CoM bias x, y, motor scale, gain scale.
      added_mass_kg_[i] = rng.uniform(sc.added_mass_min_kg, sc.added_mass_max_kg);
      com_bias_b_m_[3 * i] = rng.uniform(-sc.com_bias_max_m, sc.com_bias_max_m);
      com_bias_b_m_[3 * i + 1] = rng.uniform(-sc.com_bias_max_m, sc.com_bias_max_m);
      com_bias_b_m_[3 * i + 2] = 0;
      motor_scale_[i] = rng.uniform(sc.motor_scale_min, sc.motor_scale_max);
      gain_scale_[i] = rng.uniform(sc.gain_scale_min, sc.gain_scale_max);
    }
    prev_omega_[i] = 0;
    if (ground_) {
      steer_[i].gain_scale = gain_scale_[i];  // the table's reset keeps the caller's gain draw
      if (control_reset(ControllerKind::velocity_steering, steering_params(vs_), steering_state(i), nullptr) != Status::ok)
        ++env_of(i).stats.reset_errors;
      return;
    }
    real hover[al::kMaxRotors] = {};
    const real per_motor = mass(i) * kStandardGravity / static_cast<real>(mr_.airframe.num_rotors);
    for (int m = 0; m < mr_.airframe.num_rotors; ++m) hover[m] = per_motor;
    robots::MultirotorState& mr = mr_state_[i];
    // Valid model and hover: none expected. Counted per environment (resets run on the workers).
    if (robots::multirotor_reset(mr_, mr, &rng, rng, hover) != Status::ok) ++env_of(i).stats.reset_errors;
    // Domain randomisation over the drawn state: controller gains and motor time constants.
    LeeGains& g = mr.ctrl.lee.gains;
    g.k_pos *= gain_scale_[i];
    g.k_vel *= gain_scale_[i];
    g.k_rot *= gain_scale_[i];
    g.k_angvel *= gain_scale_[i];
    for (int m = 0; m < mr_.airframe.num_rotors; ++m) {
      mr.motors.time_constant_increasing_s[m] *= motor_scale_[i];
      mr.motors.time_constant_decreasing_s[m] *= motor_scale_[i];
    }
  }

  real mass(std::size_t i) const { return cfg_.robot.mass_kg + added_mass_kg_[i]; }

  void apply_mass(b2Body* b, std::size_t i) {
    b2MassData md;
    md.mass = static_cast<float>(mass(i));
    const real cx = (ground_ ? vs_.wheelbase_m / 2 : 0_r) + com_bias_b_m_[3 * i], cy = com_bias_b_m_[3 * i + 1];
    md.center = b2Vec2(static_cast<float>(cx), static_cast<float>(cy));
    // Box2D's I is about the body origin: I_com (yaw inertia scaled with the mass) + m |c|^2.
    const real izz = cfg_.robot.inertia_diag_kg_m2[2] * mass(i) / cfg_.robot.mass_kg;
    md.I = static_cast<float>(izz + mass(i) * (cx * cx + cy * cy));
    b->SetMassData(&md);
  }

  void reset_env(int ei) {
    Env& ev = envs_[static_cast<std::size_t>(ei)];
    RngStream& rng = ev.rng_reset;
    const EnvConfig& e = cfg_.env;
    scene::draw_bounds(e, rng, ev.lower, ev.upper);
    if (scene::layout_due(e, ev.layout_generation, ev.episodes_since_layout)) {
      generate_layout(ev);
      scene::layout_drawn(ev.layout_generation, ev.episodes_since_layout);
    }
    ev.episode_step = 0;
    ev.episode_fallback = false;
    for (int r = 0; r < robots_per_env_; ++r) {
      const std::size_t i = static_cast<std::size_t>(ei * robots_per_env_ + r);
      // Clearance in the plane: x and y of each candidate against the used slots.
      const scene::Placement place = scene::place_robot(
          cfg_, ev.lower, ev.upper, rng, [&](const Vec3& p) { return clear_point(ev, p[0], p[1]); },
          [&](const Vec3& a, const Vec3& b) { return clear_segment(ev, a[0], a[1], b[0], b[1]); });
      ++ev.stats.placements;
      if (place.fallback) {
        ++ev.stats.placement_fallbacks;
        ev.episode_fallback = true;
      }
      const real yaw = rng.uniform(-cfg_.robot.max_init_yaw_rad, cfg_.robot.max_init_yaw_rad);
      // The rigid World's start-velocity draws (three each), of which the plane keeps x, y and the yaw rate.
      const real v0 = cfg_.robot.max_init_linvel_m_s, w0 = cfg_.robot.max_init_angvel_rad_s;
      const Vec3 v_w = v0 > 0 ? scene::uniform_vec(rng, Vec3::Constant(-v0), Vec3::Constant(v0)) : Vec3::Zero();
      const Vec3 w_w = w0 > 0 ? scene::uniform_vec(rng, Vec3::Constant(-w0), Vec3::Constant(w0)) : Vec3::Zero();
      const Vec3& start = place.start_w;
      const Vec3& target = place.target_w;
      target_w_[3 * i] = target[0];
      target_w_[3 * i + 1] = target[1];
      target_w_[3 * i + 2] = plane_z_;
      reset_controller(i, rng, true);
      b2Body* b = ev.robots[static_cast<std::size_t>(r)];
      apply_mass(b, i);
      place_body(b, i, start[0], start[1], yaw, v_w[0], v_w[1], w_w[2]);
      crashed_[i] = 0;
      force_xy_[2 * i] = force_xy_[2 * i + 1] = normal_sum_[i] = 0;
      real* a = &actions_[i * static_cast<std::size_t>(action_dim_)];
      for (int k = 0; k < action_dim_; ++k) a[k] = 0;
      if (!ground_ && cfg_.controller.kind == ControllerKind::lee_position) {
        a[0] = target[0];
        a[1] = target[1];
        a[2] = plane_z_;
      }
    }
    ++ev.stats.resets;
    render_lidar(ei);
  }

  // ---- step --------------------------------------------------------------------------------
  void env_physics(int ei) {
    Env& ev = envs_[static_cast<std::size_t>(ei)];
    const real dt = cfg_.sim.dt_s;
    for (int r = 0; r < robots_per_env_; ++r) crashed_[static_cast<std::size_t>(ei * robots_per_env_ + r)] = 0;
    for (int s = 0; s < decimation_; ++s) {
      for (int r = 0; r < robots_per_env_; ++r) {
        const std::size_t i = static_cast<std::size_t>(ei * robots_per_env_ + r);
        if (ground_) drive(ev.robots[static_cast<std::size_t>(r)], i, dt);
        else fly(ev.robots[static_cast<std::size_t>(r)], i, dt);
        force_xy_[2 * i] = force_xy_[2 * i + 1] = normal_sum_[i] = 0;
      }
      ev.world->Step(static_cast<float>(dt), kVelocityIterations, kPositionIterations);
      for (int r = 0; r < robots_per_env_; ++r) {
        const std::size_t i = static_cast<std::size_t>(ei * robots_per_env_ + r);
        if (normal_sum_[i] > cfg_.env.collision_force_threshold_N) crashed_[i] = 1;
      }
    }
  }

  /// Speed of the rear axle along the heading. Box2D integrates the centre of mass linearly while
  /// the body turns, so reading the rear axle's velocity after a free step would add an O(dt)
  /// artefact (w^2 |c - o| dt forwards, v w dt sideways) that the speed loop would fight. Instead:
  /// the speed set last plus the change of the centre-of-mass velocity since it was set (zero in
  /// free motion; what a contact or a push did otherwise), along the heading it was set with.
  real measured_speed(const b2Body* b, std::size_t i) const {
    const b2Vec2 v = b->GetLinearVelocity();
    const real dvx = static_cast<real>(v.x) - kin_[5 * i + 1], dvy = static_cast<real>(v.y) - kin_[5 * i + 2];
    return kin_[5 * i] + dvx * kin_[5 * i + 3] + dvy * kin_[5 * i + 4];
  }
  void remember_kinematics(const b2Body* b, std::size_t i, real speed, real c, real s) {
    const b2Vec2 v = b->GetLinearVelocity();
    kin_[5 * i] = speed;
    kin_[5 * i + 1] = static_cast<real>(v.x);
    kin_[5 * i + 2] = static_cast<real>(v.y);
    kin_[5 * i + 3] = c;
    kin_[5 * i + 4] = s;
  }

  void drive(b2Body* b, std::size_t i, real dt) {
    const b2Vec2 o = b->GetPosition();
    const float psi = b->GetAngle();
    const real c = static_cast<real>(std::cos(psi)), s = static_cast<real>(std::sin(psi));
    const real speed = measured_speed(b, i);
    VelocitySteeringParams p = vs_;
    p.max_accel_m_s2 *= motor_scale_[i];  // drive constant randomisation scales the available force
    p.max_decel_m_s2 *= motor_scale_[i];
    p.mass_kg = mass(i);
    // Through the controller table; a rejected update holds the last safe output and latches its
    // fault bits in steer_[i] (summary().fault_bits reports them).
    ControllerInput in;
    in.speed_m_s = speed;
    in.dt_s = dt;
    ControlOutput co;
    (void)control_update(ControllerKind::velocity_steering, steering_params(p), steering_state(i), in,
                         &actions_[i * static_cast<std::size_t>(action_dim_)], kVelocitySteeringActionDim, co);
    const VelocitySteeringOutput& out = co.drive;
    const real w = out.yaw_rate_radps;
    // Kinematic bicycle: the rear axle moves at v along the heading, the body turns at w; Box2D
    // takes the centre of mass's velocity, v_o + w x (c - o).
    const b2Vec2 cw = b->GetWorldCenter();
    const real vx = out.speed_m_s * c - w * static_cast<real>(cw.y - o.y);
    const real vy = out.speed_m_s * s + w * static_cast<real>(cw.x - o.x);
    b->SetLinearVelocity(b2Vec2(static_cast<float>(vx), static_cast<float>(vy)));
    b->SetAngularVelocity(static_cast<float>(w));
    remember_kinematics(b, i, out.speed_m_s, c, s);
    // Applied wrench in the body frame: drive force, the lateral force that keeps the car on its
    // arc (m v w), and the yaw torque of the change of yaw rate.
    wrench_b_[6 * i] = out.force_N;
    wrench_b_[6 * i + 1] = mass(i) * out.speed_m_s * w;
    wrench_b_[6 * i + 2] = wrench_b_[6 * i + 3] = wrench_b_[6 * i + 4] = 0;
    wrench_b_[6 * i + 5] = static_cast<real>(b->GetInertia()) * (w - prev_omega_[i]) / dt;
    prev_omega_[i] = w;
  }

  void fly(b2Body* b, std::size_t i, real dt) {
    const b2Vec2 p = b->GetPosition(), v = b->GetLinearVelocity();
    const float psi = b->GetAngle();
    RigidBodyState st;  // the planar state lifted to 3-D at the flight altitude
    st.position_w = Vec3(static_cast<real>(p.x), static_cast<real>(p.y), plane_z_);
    st.orientation_wb = quat_from_euler_xyz(0, 0, static_cast<real>(psi));
    st.linvel_w = Vec3(static_cast<real>(v.x), static_cast<real>(v.y), 0);
    st.angvel_b = Vec3(0, 0, static_cast<real>(b->GetAngularVelocity()));
    real action[kMaxActionDim] = {};
    for (int k = 0; k < action_dim_; ++k) action[k] = actions_[i * static_cast<std::size_t>(action_dim_) + static_cast<std::size_t>(k)];
    // The core chain with the controller's wrench reduced to the plane: collective thrust |f_des|
    // and the yaw torque (roll and pitch are not simulated). Statuses are latched as fault bits.
    robots::MultirotorState& mr = mr_state_[i];
    robots::MultirotorOutput out;
    (void)robots::multirotor_control(mr_, mr_.controller, mr, st, action, kMaxActionDim, out.command);
    const real m = mass(i);
    const Vec3 a_cmd = mr.ctrl.lee.accel_command_w;
    const Vec3 f_des = m * (a_cmd - mr_.ctrl.lee.gravity_w.map());
    const real yaw_torque = out.command.wrench_b.torque_b[2];
    out.command.is_wrench = true;
    out.command.wrench_b.force_b = Vec3(0, 0, f_des.norm());
    out.command.wrench_b.torque_b = Vec3(0, 0, yaw_torque);
    (void)robots::multirotor_actuate(mr_, mr, dt, out);
    const Vec6 w = robots::multirotor_wrench(mr_, mr).as_vec6();
    const real thrust = w[2], weight = m * kStandardGravity;
    const real h_avail = thrust > weight ? std::sqrt(thrust * thrust - weight * weight) : 0_r;
    real fx = m * a_cmd[0], fy = m * a_cmd[1];
    const real fh = std::sqrt(fx * fx + fy * fy);
    if (fh > h_avail && fh > 0) {
      fx *= h_avail / fh;
      fy *= h_avail / fh;
    }
    b->ApplyForceToCenter(b2Vec2(static_cast<float>(fx), static_cast<float>(fy)), true);
    b->ApplyTorque(static_cast<float>(w[5]), true);
    const Vec3 fb = rotate_inverse(st.orientation_wb, Vec3(fx, fy, 0));
    wrench_b_[6 * i] = fb[0];
    wrench_b_[6 * i + 1] = fb[1];
    wrench_b_[6 * i + 2] = thrust;
    wrench_b_[6 * i + 3] = w[3];
    wrench_b_[6 * i + 4] = w[4];
    wrench_b_[6 * i + 5] = w[5];
  }

  real distance_to_target(int ei, int r) const {
    const b2Vec2 p = envs_[static_cast<std::size_t>(ei)].robots[static_cast<std::size_t>(r)]->GetPosition();
    const std::size_t i = static_cast<std::size_t>(ei * robots_per_env_ + r);
    const real dx = target_w_[3 * i] - static_cast<real>(p.x), dy = target_w_[3 * i + 1] - static_cast<real>(p.y);
    return std::sqrt(dx * dx + dy * dy);
  }

  /// Episode bookkeeping after the physics (World::env_step's rules): crash, exit, timeout,
  /// success at timeout; auto-reset of an ended episode.
  void env_post(int ei) {
    Env& ev = envs_[static_cast<std::size_t>(ei)];
    EnvStats& es = ev.stats;
    ++es.env_steps;
    bool any_crash = false, out = false;
    real err = 0;
    for (int r = 0; r < robots_per_env_; ++r) {
      const std::size_t i = static_cast<std::size_t>(ei * robots_per_env_ + r);
      any_crash = any_crash || crashed_[i] != 0;
      const b2Vec2 p = ev.robots[static_cast<std::size_t>(r)]->GetPosition();
      const real px = static_cast<real>(p.x), py = static_cast<real>(p.y);
      const real p_w[2] = {px, py};
      out = out || out_of_bounds(p_w, ev.lower.data(), ev.upper.data(), 2);
      err += distance_to_target(ei, r);
    }
    es.tracking_error_sum_m += static_cast<double>(err);
    if (any_crash) ++es.crashes;
    const bool timeout = ++ev.episode_step >= cfg_.task.episode_len_env_steps;
    if (timeout) {
      ++es.timeouts;
      bool ok = true;
      for (int r = 0; r < robots_per_env_; ++r) ok = ok && within_success_radius(distance_to_target(ei, r), cfg_.task.success_radius_m);
      es.successes += ok && !ev.episode_fallback ? 1u : 0u;  // a fallback episode hovers: never a success
    }
    if (out) ++es.out_of_bounds;
    const bool done = timeout || out || (any_crash && cfg_.env.reset_on_collision);
    reset_buf_[static_cast<std::size_t>(ei)] = done ? 1 : 0;
    if (done) {
      ++es.episodes_done;
      if (ev.episode_fallback) ++es.fallback_episodes;
      real d = 0;
      for (int r = 0; r < robots_per_env_; ++r) d += distance_to_target(ei, r);
      es.final_distance_sum_m += static_cast<double>(d) / robots_per_env_;
      if (auto_reset_) {
        reset_env(ei);  // renders the new episode's first scan
        return;
      }
      // Auto-reset off (a task owns the episode): keep the final state and scan; the owner calls reset_idx.
    }
    render_lidar(ei);
  }

  void render_lidar(int ei) {
    if (lidar_beams_ == 0) return;
    Env& ev = envs_[static_cast<std::size_t>(ei)];
    const real range = cfg_.simulator.lidar_max_range_m;
    for (int r = 0; r < robots_per_env_; ++r) {
      const b2Body* b = ev.robots[static_cast<std::size_t>(r)];
      const std::size_t i = static_cast<std::size_t>(ei * robots_per_env_ + r);
      // The lidar sits at the footprint's centre (the box centre of the car, the multirotor's centre).
      const b2Vec2 origin = b->GetWorldPoint(b2Vec2(ground_ ? static_cast<float>(vs_.wheelbase_m / 2) : 0.0f, 0.0f));
      const real psi = static_cast<real>(b->GetAngle());
      for (int k = 0; k < lidar_beams_; ++k) {
        real s = 0, c = 1;
        sin_cos(psi + lidar_beam_angle(k), s, c);
        const b2Vec2 end(origin.x + static_cast<float>(range * c), origin.y + static_cast<float>(range * s));
        ClosestHit cb;
        cb.ignore = b;
        ev.world->RayCast(&cb, origin, end);
        lidar_[i * static_cast<std::size_t>(lidar_beams_) + static_cast<std::size_t>(k)] = cb.hit ? static_cast<real>(cb.fraction) * range : range;
      }
    }
  }

  void refresh_robot(int ei, int r) {
    const std::size_t i = static_cast<std::size_t>(ei * robots_per_env_ + r);
    const b2Body* b = envs_[static_cast<std::size_t>(ei)].robots[static_cast<std::size_t>(r)];
    RigidBodyState s;
    const b2Vec2 p = b->GetPosition();
    s.position_w = Vec3(static_cast<real>(p.x), static_cast<real>(p.y), plane_z_);
    s.orientation_wb = quat_from_euler_xyz(0, 0, static_cast<real>(b->GetAngle()));
    if (ground_) {
      // No-slip kinematic model: the rear axle moves along the heading (measured_speed).
      real sn = 0, cs = 1;
      sin_cos(static_cast<real>(b->GetAngle()), sn, cs);
      const real v = measured_speed(b, i);
      s.linvel_w = Vec3(v * cs, v * sn, 0);
    } else {
      const b2Vec2 v = b->GetLinearVelocityFromLocalPoint(b2Vec2(0, 0));  // the body origin (CoM bias aside)
      s.linvel_w = Vec3(static_cast<real>(v.x), static_cast<real>(v.y), 0);
    }
    s.angvel_b = Vec3(0, 0, static_cast<real>(b->GetAngularVelocity()));
    write_state_view(i, s);
    contact_w_[3 * i] = force_xy_[2 * i];
    contact_w_[3 * i + 1] = force_xy_[2 * i + 1];
    contact_w_[3 * i + 2] = 0;
  }

  void refresh_all() {
    for (int ei = 0; ei < num_envs_; ++ei)
      for (int r = 0; r < robots_per_env_; ++r) refresh_robot(ei, r);
  }

  bool ground_ = true;
  bool auto_reset_ = true;
  std::string controller_;
  VelocitySteeringParams vs_;
  robots::MultirotorModel mr_;  // the multirotor's chain (robots/multirotor.hpp), compiled as on rigid
  real half_x_ = 0, half_y_ = 0, radius_ = 0, bound_r_ = 0, plane_z_ = 0;
  std::vector<int> class_first_slot_;  // per asset class: its first slot in Env::slots
  std::vector<VelocitySteeringState> steer_;
  Env& env_of(std::size_t robot) { return envs_[robot / static_cast<std::size_t>(robots_per_env_)]; }
  static ControllerParamsRef steering_params(const VelocitySteeringParams& p) {
    ControllerParamsRef r;
    r.steering = &p;
    return r;
  }
  ControllerStateRef steering_state(std::size_t i) {
    ControllerStateRef r;
    r.steering = &steer_[i];
    return r;
  }
  std::vector<robots::MultirotorState> mr_state_;
  std::vector<real> force_xy_, normal_sum_, prev_omega_;
  std::vector<real> kin_;  // (robots x 5) ground vehicle: speed set, COM velocity set (x, y), heading (cos, sin)
  std::unique_ptr<unsigned char[]> arena_storage_;  // declared before envs_: destroyed after the worlds
  std::vector<Env> envs_;
  std::unique_ptr<ThreadPool> pool_;
  Phase phase_ = Phase::physics;
};

}  // namespace

std::unique_ptr<Simulator> make_planar_simulator(const WorldConfig& config, std::string& error) {
  std::unique_ptr<PlanarSimulator> s(new PlanarSimulator());
  if (!s->init(config, error)) return nullptr;
  return s;
}

}  // namespace kestrel::sim
