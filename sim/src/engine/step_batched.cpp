// The rigid World's batched path: groups of batch::lanes() (4, 8 or 16) consecutive environments step their
// robots through the batched twin of stage::robot_dynamics (sim/batch_step.hpp) in lockstep; the
// rest of each env-step (setpoints, IMUs, obstacles, collision, statistics, resets, sensors) is the
// scalar stages of step.cpp, run per environment in the same order as env_step (where a stage's
// common case has a short form here, the ground-only collision pass done by the kernel,
// batch::Models::ground_tail, and the env-step's start and end inline, begin_quiet / end_quiet,
// it does the same operations: together they took the empty environment from ~990 to ~770
// instructions per env-step, callgrind, 4096 environments, one thread). Environments never
// read each other's state and the twin is bit-identical to the scalar robot step, so the result
// does not depend on the grouping, on the thread partition or on whether the batched path is on
// (tests/sim/engine/batch_step_test.cpp).
#include <algorithm>
#include <cstring>
#include <limits>

#include "kestrel/sim/batch_step.hpp"
#include "kestrel/sim/episode.hpp"
#include "kestrel/sim/terrain.hpp"
#include "kestrel/sim/world_stages.hpp"

namespace kestrel::sim::stage {

namespace {
// Software prefetch of one robot's per-step storage: at 4096+ environments a worker's robots no
// longer fit in L2, and the motor state alone (448 bytes, six of its seven lines touched per step)
// would otherwise miss on first touch. No effect on results.
template <typename T>
inline void prefetch(const T* p) {
  const char* c = reinterpret_cast<const char*>(p);
  for (std::size_t o = 0; o < sizeof(T); o += 64) __builtin_prefetch(c + o, 1);
  __builtin_prefetch(c + sizeof(T) - 1, 1);
}

// A lane's pointers into robot i's rows (the applied action at `applied`).
inline void point_lane(WorldData& d, std::size_t i, const real* applied, batch::Lane& lane) {
  lane.state = &d.state[i];
  lane.ctrl = &d.mr_state[i].ctrl;
  lane.alloc = &d.mr_state[i].allocator;
  lane.motors = &d.mr_state[i].motors;
  lane.action = applied;
  lane.contact_force_w = &d.contact_force_w[i];
  lane.contact_torque_b = &d.contact_torque_b[i];
}

// `lanes` is the caller's scratch (num_lanes entries), every field rewritten here: an array of
// batch::Lane declared per call would be zero-filled per call (its members have initialisers).
// Returns the lanes whose collision pass the kernel did (batch::robot_step).
unsigned robot_dynamics_batch(const WorldModel& m, WorldData& d, int env0, int num_lanes, unsigned new_action_mask,
                              const batch::Models& models, batch::Lane* lanes) {
  for (int l = 0; l < num_lanes; ++l) {
    const int env = env0 + l;
    const std::size_t i = m.index(env, 0);
    real* applied = &d.applied_actions[i * kMaxActionDim];
    if ((new_action_mask >> l) & 1u) std::memcpy(applied, &d.actions[i * kMaxActionDim], sizeof(real) * kMaxActionDim);
    point_lane(d, i, applied, lanes[l]);
    if (models.ground_tail) {
      const real plane_z = m.cfg.env.create_ground_plane ? ground_plane_z(d, env) : -std::numeric_limits<real>::infinity();
      lanes[l].ground_z = d.num_obstacles[env] == 0 ? plane_z : std::numeric_limits<real>::quiet_NaN();
    }
  }
  return batch::robot_step(models, lanes);
}

// env_step_begin / env_step_end of one environment of a group, for its common case, inline
// (they were a call each, ~150 instructions per env-step together, most of it the checks for
// what rarely happens). `quiet` (per world): no moving setpoint, no height samples, no ray
// sensor. The end's short form is for an env-step after which the episode goes on and nothing is
// counted but the step and the tracking error: no crash, in bounds, not at the time limit, not
// traced; anything else is env_step_end's, which then does exactly what it always did. The same
// operations in the same order, so the same bits.
inline void begin_quiet(const WorldModel& m, WorldData& d, int env) {
  d.crashed[m.index(env, 0)] = 0;
  d.episode_ended[static_cast<std::size_t>(env)] = 0;
}
inline void end_quiet(const WorldModel& m, WorldData& d, int env) {
  const std::size_t i = m.index(env, 0);
  const Vec3& p = d.state[i].position_w;
  if (env < d.trace_envs || d.crashed[i] != 0 || d.episode_step[static_cast<std::size_t>(env)] + 1 >= m.cfg.task.episode_len_env_steps ||
      out_of_bounds(p, d.lower_w[env], d.upper_w[env])) {
    env_step_end(m, d, env);
    return;
  }
  EnvStats& es = d.stats[env];
  ++es.env_steps;
  real err_sum = 0;
  err_sum += (d.setpoint_w[i] - p).norm();
  es.tracking_error_sum_m += static_cast<double>(err_sum);
  ++d.episode_step[static_cast<std::size_t>(env)];
}
bool quiet_eligible(const WorldModel& m) {
  return m.robots_per_env == 1 && !moves_setpoint(m) && m.height_points == 0 && !m.any_ray_sensor;
}

// Where the kernel may do the collision pass itself (batch::Models::ground_tail): collide_robots'
// fast path covers the robot alone (one sphere per environment, plane terrain), and nothing
// between the dynamics and that pass reads what it writes (no IMU) or is raised by a zero normal
// force (a crash threshold >= 0). Which environments have obstacles is decided per lane.
bool ground_tail_eligible(const WorldModel& m) {
  return m.robots_per_env == 1 && m.cfg.robot.shape.type == ShapeType::sphere && m.terrain->type() == TerrainType::plane &&
         !m.any_imu && !(0_r > m.cfg.env.collision_force_threshold_N);
}
}  // namespace

bool batch_eligible(const WorldModel& m) {
  // One robot per environment (lanes are environments); the observation noise and the random
  // disturbance draw from the environment's stream inside the robot step, which the twin leaves
  // to the scalar path.
  return m.robots_per_env == 1 && !m.cfg.env.perturb_observations && !m.cfg.env.enable_disturbance &&
         batch::chain_eligible(m.mr) && batch::eligible(batch::models_of(m.mr, m.body, m.cfg.sim.dt_s, m.cfg.sim.substeps));
}

int env_steps_batched(const WorldModel& m, WorldData& d, int begin, int end) {
  const int group = batch::lanes();
  // Software prefetch of the robots `ahead` environments on, one robot per lane of each per-lane
  // loop below, so that the prefetches spread over the group's work: issued all at once (8 robots
  // x 16 lines for the 8-lane copy) they overran the core's outstanding-miss slots, and the 8-lane
  // copy ran 25 % slower than the 4-lane one at 65,536 environments on the 2-core machine.
  const int ahead = std::max(group, 8);  // measured best: 8 robots for 4 and 8 lanes
  batch::Models models = batch::models_of(m.mr, m.body, m.cfg.sim.dt_s, m.cfg.sim.substeps);
  models.ground_tail = ground_tail_eligible(m);
  models.ground_radius_m = m.cfg.robot.shape.radius_m;
  const bool quiet = quiet_eligible(m);
  batch::Lane lanes[batch::kMaxLanes];
  int env = begin;
  for (; env + group <= end; env += group) {
    // Lockstep needs the same number of physics steps in every lane (always, unless
    // num_physics_steps_per_env_step_std > 0); the latency may differ per lane.
    const int n = d.phys_steps[env];
    bool same = true;
    for (int l = 1; l < group; ++l) same = same && d.phys_steps[env + l] == n;
    if (!same) {
      for (int l = 0; l < group; ++l) env_step(m, d, env + l);
      continue;
    }
    const int pf_end = std::min(group, end - env - ahead);  // robots env + ahead + l, l < pf_end
    for (int l = 0; l < group; ++l) {
      if (l < pf_end) prefetch(&d.mr_state[m.index(env + ahead + l, 0)].motors);
      if (quiet) {
        begin_quiet(m, d, env + l);
      } else {
        env_step_begin(m, d, env + l);
      }
    }
    for (int s = 0; s < n; ++s) {
      unsigned new_action = 0;
      Vec3 v0[batch::kMaxLanes];
      for (int l = 0; l < group; ++l) {
        if (s == d.latency[env + l]) new_action |= 1u << l;
        v0[l] = d.state[m.index(env + l, 0)].linvel_w;
      }
      const unsigned tail_done = robot_dynamics_batch(m, d, env, group, new_action, models, lanes);
      for (int l = 0; l < group; ++l) {
        if (s == 0 && l < pf_end) {
          const std::size_t i = m.index(env + ahead + l, 0);
          prefetch(&d.mr_state[i].ctrl.lee);
          prefetch(&d.mr_state[i].allocator);
        }
        if (m.any_imu) update_imus(m, d, env + l, 0, v0[l]);
        if (((tail_done >> l) & 1u) == 0) physics_step_tail(m, d, env + l);
      }
    }
    for (int l = 0; l < group; ++l) {
      if (l < pf_end) prefetch(&d.state[m.index(env + ahead + l, 0)]);
      if (quiet) {
        end_quiet(m, d, env + l);
      } else {
        env_step_end(m, d, env + l);
      }
    }
  }
  return env;
}

bool fused_eligible(const WorldModel& m) { return batch_eligible(m) && quiet_eligible(m) && ground_tail_eligible(m); }

namespace {
// One group's fused run: at most max_env_steps env-steps of environments env .. env + lanes() - 1,
// the ones batch::robot_env_steps completes. Only where every environment's env-steps have the
// quiet shape: not traced, the same physics steps per env-step, the new action at physics step 0
// (no latency: the applied action is then the action throughout, copied here once as every
// env-step's first physics step would copy it), no obstacles, and an episode that does not reach
// its time limit within the run (the run stops one env-step before the first lane's limit).
int fused_group(const WorldModel& m, WorldData& d, const batch::Models& models, int env, int max_env_steps) {
  const int group = batch::lanes();
  const int n = d.phys_steps[env];
  int max_steps = max_env_steps;
  for (int l = 0; l < group; ++l) {
    const int e = env + l;
    if (e < d.trace_envs || d.phys_steps[e] != n || d.latency[e] != 0 || d.num_obstacles[e] != 0) return 0;
    max_steps = std::min(max_steps, m.cfg.task.episode_len_env_steps - 1 - d.episode_step[static_cast<std::size_t>(e)]);
  }
  if (max_steps <= 0) return 0;
  batch::Lane lanes[batch::kMaxLanes];
  batch::QuietEnv envs[batch::kMaxLanes];
  for (int l = 0; l < group; ++l) {
    const int e = env + l;
    const std::size_t i = m.index(e, 0);
    real* applied = &d.applied_actions[i * kMaxActionDim];
    std::memcpy(applied, &d.actions[i * kMaxActionDim], sizeof(real) * kMaxActionDim);
    point_lane(d, i, applied, lanes[l]);
    lanes[l].ground_z = m.cfg.env.create_ground_plane ? ground_plane_z(d, e) : -std::numeric_limits<real>::infinity();
    envs[l].setpoint_w = &d.setpoint_w[i];
    envs[l].lower_w = &d.lower_w[e];
    envs[l].upper_w = &d.upper_w[e];
    envs[l].tracking_error_sum_m = &d.stats[e].tracking_error_sum_m;
  }
  const int done = batch::robot_env_steps(models, lanes, envs, n, max_steps);
  if (done == 0) return 0;
  for (int l = 0; l < group; ++l) {
    const int e = env + l;
    // What begin_quiet / end_quiet leave after `done` quiet env-steps.
    d.crashed[m.index(e, 0)] = 0;
    d.episode_ended[static_cast<std::size_t>(e)] = 0;
    d.stats[e].env_steps += static_cast<std::uint64_t>(done);
    d.episode_step[static_cast<std::size_t>(e)] += done;
  }
  return done;
}
}  // namespace

void env_steps_fused(const WorldModel& m, WorldData& d, int begin, int end, int num_env_steps) {
  const int group = batch::lanes();
  batch::Models models = batch::models_of(m.mr, m.body, m.cfg.sim.dt_s, m.cfg.sim.substeps);
  models.ground_tail = true;
  models.ground_radius_m = m.cfg.robot.shape.radius_m;
  // After a fused run that could not take a single env-step (a robot on the ground, say), the
  // group goes step by step for a while before it tries again, so a group that stays unfused
  // pays for the failed try once per kRetryEnvSteps env-steps, not at every one.
  constexpr int kRetryEnvSteps = 16;
  int env = begin;
  for (; env + group <= end; env += group) {
    int s = 0;
    while (s < num_env_steps) {
      const int k = fused_group(m, d, models, env, num_env_steps - s);
      s += k;
      const int single = k == 0 ? std::min(kRetryEnvSteps, num_env_steps - s) : std::min(1, num_env_steps - s);
      for (int j = 0; j < single; ++j) (void)env_steps_batched(m, d, env, env + group);
      s += single;
    }
  }
  for (; env < end; ++env)
    for (int s = 0; s < num_env_steps; ++s) env_step(m, d, env);
}

}  // namespace kestrel::sim::stage
