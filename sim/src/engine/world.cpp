// The World: owner of a WorldModel and a WorldData, and the thread pool that runs the stages of
// sim/world_stages.hpp over blocks of environments. Summary, state hash, trace and
// sensor accessors.
#include "kestrel/sim/world.hpp"

#include <algorithm>

#include "kestrel/sim/state_hash.hpp"
#include "kestrel/sim/terrain.hpp"

namespace kestrel::sim {

namespace {
constexpr int kHookChunkEnvs = 64;  // a multiple of every batch::lanes(); ~40 KB of robot rows
void world_task(void* context, int worker) { static_cast<World*>(context)->run_slice(worker); }
// The temporal block's size: about kBlockBytes of environment rows, a multiple of kHookChunkEnvs
// (so of every lane count). 256 KB leaves room in a 1 MB L2 for the model, the stacks and the
// prefetches ahead of the block (bench/results/device/blocking_xeon16_runs.csv: 1.2-1.25x at
// 65,536 environments on 16 threads with it, before the fused env-steps; nothing at 4,096).
constexpr std::size_t kBlockBytes = 256 * 1024;
// The fused path's unit of hand-out: 64 environments (4 lane groups of the widest copy), so that
// 4,096 environments make 4 blocks per worker at 16 threads (256-environment blocks, one per
// worker there, left no room to even out the cores' speeds: 9.6-12.3x from 1 to 16 threads).
constexpr int kFusedBlockEnvs = 64;
int default_block_envs(std::size_t bytes_per_env) {
  const std::size_t envs = kBlockBytes / std::max<std::size_t>(bytes_per_env, 1);
  return static_cast<int>(std::max<std::size_t>(kHookChunkEnvs, envs / kHookChunkEnvs * kHookChunkEnvs));
}
}  // namespace

double World::estimate_bytes(const WorldConfig& config) { return estimate_world_bytes(config); }

std::unique_ptr<World> World::create(const WorldConfig& config, std::string& error) {
  std::unique_ptr<World> w(new World());
  if (!compile_world_model(config, w->model_, error)) return std::unique_ptr<World>();
  make_world_data(w->model_, w->data_);
  for (int env = 0; env < w->model_.num_envs; ++env) {
    stage::reset_env(w->model_, w->data_, env);
    w->data_.stats[static_cast<std::size_t>(env)].resets = 0;  // the initial reset is not counted
  }
  w->batch_ = stage::batch_eligible(w->model_);
  w->fused_ = w->batch_ && stage::fused_eligible(w->model_);
  w->block_envs_ = default_block_envs(w->bytes_per_env());
  w->pool_.reset(new ThreadPool(std::min(config.num_threads, w->model_.num_envs)));
  return w;
}

World::~World() = default;

void World::reset_env(int env) { stage::reset_env(model_, data_, env); }

void World::render_sensors(int env) {
  if (model_.any_ray_sensor) stage::render_ray_sensors(model_, data_, env, true);
}

void World::obstacles_changed(int env) { stage::obstacles_changed(model_, data_, env); }

void World::set_block_envs(int envs) { block_envs_ = envs > 0 ? envs : default_block_envs(bytes_per_env()); }

bool World::set_batched(bool on) {
  batch_ = on && stage::batch_eligible(model_);
  fused_ = fused_wanted_ && batch_ && stage::fused_eligible(model_);
  return batch_;
}

bool World::set_fused(bool on) {
  fused_wanted_ = on;
  fused_ = on && batch_ && stage::fused_eligible(model_);
  return fused_;
}

void World::run_slice(int /*worker*/) {
  const int n = model_.num_envs;
  // Work is handed out in blocks from a shared counter (dynamic scheduling), not as one fixed
  // slice per worker: on a machine whose cores run at different speeds (another tenant's thread
  // on the same physical core, bench/results/device/README.md) the fast workers take more blocks
  // instead of waiting for the slowest. Environments never read each other's rows and each one
  // takes its own env-steps in order, so which worker steps which block changes no result.
  //
  // Temporal blocking: each block takes all pending env-steps before its worker takes the next
  // block, so its rows stay in the core's L2 from one env-step to the next instead of coming back
  // from L3 or memory at every env-step (a slice of 2,048 robots at 1 KB each overflows a 1-2 MB
  // L2). The state hash is the same for every block size (tests/sim/engine/world_test.cpp).
  // Fused env-steps (step_batched.cpp): each lane group takes all of the call's env-steps before
  // the next, so the blocking is implicit and the block is only the unit of hand-out.
  // (At most n: the counter then stays below n + workers x n.)
  const int block = std::min(n, fused_ ? kFusedBlockEnvs : (block_envs_ > 0 ? block_envs_ : n));
  for (;;) {
    const int b0 = next_env_.fetch_add(block, std::memory_order_relaxed);
    if (b0 >= n) break;
    const int e0 = std::min(n, b0 + block);
    if (fused_) {
      // With an after-step hook, chunk by chunk: the hook reads each chunk's rows right after
      // they were written, while they are still in cache.
      const int chunk = after_step_ != nullptr ? kHookChunkEnvs : e0 - b0;
      for (int b = b0; b < e0; b += chunk) {
        const int e = std::min(e0, b + chunk);
        stage::env_steps_fused(model_, data_, b, e, pending_steps_);
        if (after_step_ != nullptr) after_step_(after_step_context_, b, e);
      }
      continue;
    }
    for (int s = 0; s < pending_steps_; ++s) {
      // With an after-step hook, the last env-step runs in chunks of kHookChunkEnvs and the hook
      // reads each chunk's rows right after they were written, while they are still in L1.
      const bool hook = after_step_ != nullptr && s + 1 == pending_steps_;
      const int chunk = hook ? kHookChunkEnvs : e0 - b0;
      for (int b = b0; b < e0; b += chunk) {
        const int e = std::min(e0, b + chunk);
        // Batched twin (step_batched.cpp): whole groups of batch::lanes() environments, bit-identical.
        int env = batch_ ? stage::env_steps_batched(model_, data_, b, e) : b;
        for (; env < e; ++env) stage::env_step(model_, data_, env);
        if (hook) after_step_(after_step_context_, b, e);
      }
    }
    if (after_step_ != nullptr && pending_steps_ == 0) after_step_(after_step_context_, b0, e0);
  }
}

void World::step(int num_env_steps) {
  pending_steps_ = num_env_steps;
  next_env_.store(0, std::memory_order_relaxed);
  pool_->run(world_task, this);
  data_.trace_len = std::min(data_.trace_cap, data_.trace_len + num_env_steps);
}

void World::enable_trace(int num_envs, int max_env_steps) {
  WorldData& d = data_;
  d.trace_envs = std::min(num_envs, model_.num_envs);
  d.trace_cap = max_env_steps;
  d.trace_len = 0;
  d.trace_base = model_.num_envs > 0 ? d.stats[0].env_steps : 0;
  const std::size_t n = static_cast<std::size_t>(d.trace_envs) * static_cast<std::size_t>(d.trace_cap);
  d.trace.assign(n, Vec3::Zero());
  d.trace_target.assign(n, Vec3::Zero());
  d.trace_episode.assign(n, 0);
}

WorldSummary World::summary() const {
  const WorldModel& m = model_;
  const WorldData& d = data_;
  WorldSummary s;
  double err = 0, final_dist = 0, end_dist = 0;
  for (int env = 0; env < m.num_envs; ++env) {
    const EnvStats& e = d.stats[env];
    add_env_counters(s, e);
    err += e.tracking_error_sum_m;
    end_dist += e.final_distance_sum_m;
    for (int r = 0; r < m.robots_per_env; ++r) {
      final_dist += static_cast<double>((d.target_w[m.index(env, r)] - d.state[m.index(env, r)].position_w).norm());
      s.fault_bits |= robots::multirotor_faults(d.mr_state[m.index(env, r)]);
    }
    s.reset_errors += d.status_count[static_cast<std::size_t>(env)];
  }
  const double nr = static_cast<double>(m.num_envs) * m.robots_per_env;
  s.mean_tracking_error_m = s.env_steps > 0 ? err / (static_cast<double>(s.env_steps) * m.robots_per_env) : 0;
  s.final_mean_distance_m = final_dist / nr;
  s.episode_end_distance_m = s.episodes_done > 0 ? end_dist / static_cast<double>(s.episodes_done) : 0;
  return s;
}

namespace {
/// The shared FNV-1a plus the World's own shorthand for a 3-vector.
struct Fnv : Fnv1a {
  void v3(const Vec3& v) { bytes(v.data(), sizeof(real) * 3); }
};
}  // namespace

std::uint64_t World::state_hash() const {
  const WorldModel& m = model_;
  const WorldData& d = data_;
  Fnv f;
  for (int env = 0; env < m.num_envs; ++env) {
    for (int r = 0; r < m.robots_per_env; ++r) {
      const std::size_t i = m.index(env, r);
      const RigidBodyState& s = d.state[i];
      f.v3(s.position_w);
      f.bytes(s.orientation_wb.coeffs().data(), sizeof(real) * 4);
      f.v3(s.linvel_w);
      f.v3(s.angvel_b);
      f.bytes(d.mr_state[i].motors.thrust_N, sizeof(real) * static_cast<std::size_t>(m.mr.airframe.num_rotors));
      f.pod(d.crashed[i]);
    }
    for (int k = 0; k < d.num_obstacles[env]; ++k) f.v3(obstacle(env, k).shape.position_w);
    if (m.obstacles_rotate)  // (absent otherwise, so hashes of worlds without rotation are unchanged)
      for (int k = 0; k < d.num_obstacles[env]; ++k) f.bytes(obstacle(env, k).shape.orientation_wb.coeffs().data(), sizeof(real) * 4);
    // Sensor outputs (absent without sensors, so sensor-free hashes are unchanged).
    for (std::size_t k = 0; k < m.sensors.size(); ++k) {
      const SensorModel& sl = m.sensors[k];
      const SensorData& sd = d.sensors[k];
      for (int r = 0; r < m.robots_per_env; ++r) {
        const std::size_t i = m.index(env, r);
        if (sl.kind == SensorKind::imu) {
          f.v3(sd.imu[i].accel_s);
          f.v3(sd.imu[i].gyro_s);
        } else {
          f.bytes(&sd.ranges[i * sl.pixels], sizeof(real) * sl.pixels);
          f.bytes(&sd.segmentation[i * sl.pixels], sizeof(std::int32_t) * sl.pixels);
        }
      }
    }
    f.pod(d.episode_step[env]);
    f.pod(d.stats[env].resets);
    f.pod(d.stats[env].crashes);
  }
  return f.h;
}
const real* World::sensor_ranges(int env, int sensor, int robot) const {
  const SensorModel& s = model_.sensors[static_cast<std::size_t>(sensor)];
  return s.kind == SensorKind::imu ? nullptr : &data_.sensors[static_cast<std::size_t>(sensor)].ranges[index(env, robot) * s.pixels];
}
const std::int32_t* World::sensor_segmentation(int env, int sensor, int robot) const {
  const SensorModel& s = model_.sensors[static_cast<std::size_t>(sensor)];
  return s.kind == SensorKind::imu ? nullptr : &data_.sensors[static_cast<std::size_t>(sensor)].segmentation[index(env, robot) * s.pixels];
}
const sensors::ImuSample& World::imu_sample(int env, int sensor, int robot) const {
  static const sensors::ImuSample kZero{};
  const SensorData& s = data_.sensors[static_cast<std::size_t>(sensor)];
  return model_.sensors[static_cast<std::size_t>(sensor)].kind == SensorKind::imu ? s.imu[index(env, robot)] : kZero;
}
const sensors::Mount& World::sensor_mount(int env, int sensor, int robot) const {
  static const sensors::Mount kIdentity{};
  const SensorData& s = data_.sensors[static_cast<std::size_t>(sensor)];
  return model_.sensors[static_cast<std::size_t>(sensor)].kind == SensorKind::imu ? kIdentity : s.mounts[index(env, robot)];
}

std::size_t World::bytes_per_env() const { return world_bytes_per_env(model_.cfg, model_.obstacle_capacity, model_.height_points); }

}  // namespace kestrel::sim
