// The World: owner of a WorldModel and a WorldData, and the thread pool that runs the stages of
// sim/world_stages.hpp over a static partition of environments. Summary, state hash, trace and
// sensor accessors.
#include "kestrel/sim/world.hpp"

#include <algorithm>

#include "kestrel/sim/state_hash.hpp"
#include "kestrel/sim/terrain.hpp"

namespace kestrel::sim {

namespace {
constexpr int kHookChunkEnvs = 64;  // a multiple of every batch::lanes(); ~40 KB of robot rows
void world_task(void* context, int worker) { static_cast<World*>(context)->run_slice(worker); }
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
  w->pool_.reset(new ThreadPool(std::min(config.num_threads, w->model_.num_envs)));
  return w;
}

World::~World() = default;

void World::reset_env(int env) { stage::reset_env(model_, data_, env); }

void World::render_sensors(int env) {
  if (model_.any_ray_sensor) stage::render_ray_sensors(model_, data_, env, true);
}

void World::obstacles_changed(int env) { stage::obstacles_changed(model_, data_, env); }

bool World::set_batched(bool on) {
  batch_ = on && stage::batch_eligible(model_);
  return batch_;
}

void World::run_slice(int worker) {
  const int t = pool_ ? pool_->size() : 1;
  const int n = model_.num_envs;
  const int begin = static_cast<int>(static_cast<long long>(n) * worker / t);
  const int end = static_cast<int>(static_cast<long long>(n) * (worker + 1) / t);
  for (int s = 0; s < pending_steps_; ++s) {
    // With an after-step hook, the last env-step runs in chunks of kHookChunkEnvs and the hook
    // reads each chunk's rows right after they were written, while they are still in cache (a
    // worker's slice of 4096 robots does not fit in L2). Environments are independent, so the
    // chunking changes no result.
    const bool hook = after_step_ != nullptr && s + 1 == pending_steps_;
    const int chunk = hook ? kHookChunkEnvs : end - begin;
    for (int b = begin; b < end; b += chunk) {
      const int e = std::min(end, b + chunk);
      // Batched twin (step_batched.cpp): whole groups of batch::lanes() environments, bit-identical.
      int env = batch_ ? stage::env_steps_batched(model_, data_, b, e) : b;
      for (; env < e; ++env) stage::env_step(model_, data_, env);
      if (hook) after_step_(after_step_context_, b, e);
    }
  }
  if (after_step_ != nullptr && pending_steps_ == 0) after_step_(after_step_context_, begin, end);
}

void World::step(int num_env_steps) {
  pending_steps_ = num_env_steps;
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
