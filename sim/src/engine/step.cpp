// One env-step of the rigid World as stages over (model, data, env) (sim/world_stages.hpp).
//
// One physics step of a robot (the batched twin of platform/firmware/flight_loop.cpp):
//   robots::multirotor_step (controller -> allocation -> motor model) -> body wrench A f + random
//   disturbance + contact wrench of the previous step -> rigid-body integration -> collision
//   against the ground plane, the environment's obstacles (sweep-and-prune broad phase on x over
//   the sorted obstacle list) and the other robots -> penalty contact wrench for the next step,
//   crash flag.
// The contact response is explicit (forces from the post-integration penetration act during the
// next step), the usual choice for penalty methods with a small dt.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/episode.hpp"
#include "kestrel/sim/terrain.hpp"
#include "kestrel/sim/world_stages.hpp"
#include "../scene/episode_draw.hpp"

namespace kestrel::sim::stage {

using scene::uniform_vec;

void sort_sweep_order(Obstacle* o, int n) {
  // Insertion sort: stable, so equal keys keep generation order; O(n) for the nearly sorted list
  // a step leaves; and unlike std::stable_sort it never allocates a buffer (resets run inside the
  // step).
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

void robot_dynamics(const WorldModel& m, WorldData& d, int env, std::size_t i, bool use_new_action) {
  const real dt = m.cfg.sim.dt_s;
  real* applied = &d.applied_actions[i * kMaxActionDim];
  if (use_new_action) std::memcpy(applied, &d.actions[i * kMaxActionDim], sizeof(real) * kMaxActionDim);
  RigidBodyState& st = d.state[i];
  RngStream& rng = d.rng_step[env];
  // The controller reads the true state unless observation noise is on (no copy on that path).
  RigidBodyState noisy;
  const RigidBodyState* observed = &st;
  if (m.cfg.env.perturb_observations) {
    noisy = st;
    for (int k = 0; k < 3; ++k) noisy.position_w[k] += m.cfg.env.observation_noise_position_m * rng.normal();
    for (int k = 0; k < 3; ++k) noisy.linvel_w[k] += m.cfg.env.observation_noise_velocity_m_s * rng.normal();
    observed = &noisy;
  }
  robots::MultirotorOutput out;
  // Every non-ok status of the chain is also latched as fault bits in d.mr_state[i] (the batched
  // twin reproduces them bit for bit), which summary() reports; the status itself adds nothing.
  (void)robots::multirotor_step(m.mr, d.mr_state[i], *observed, applied, kMaxActionDim, dt, out);
  Wrench w = robots::multirotor_wrench(m.mr, d.mr_state[i]);
  Vec3 extra_force_w = d.contact_force_w[i];
  w.torque_b += d.contact_torque_b[i];
  if (m.cfg.env.enable_disturbance) {
    // Aerial Gym's disturbance: with probability p per step, a uniform random force and torque
    // within +-max (its robot config `disturbance`). Always three draws so streams stay aligned.
    const real u = rng.uniform();
    const Vec3 f = uniform_vec(rng, -m.cfg.env.max_force_disturbance_N, m.cfg.env.max_force_disturbance_N);
    const Vec3 t = uniform_vec(rng, -m.cfg.env.max_torque_disturbance_Nm, m.cfg.env.max_torque_disturbance_Nm);
    if (u < m.cfg.env.prob_apply_disturbance) {
      w.force_b += f;
      w.torque_b += t;
    }
  }
  const real h = dt / static_cast<real>(m.cfg.sim.substeps);
  // A non-finite input is refused and the state held (step_rigid_body's contract).
  for (int s = 0; s < m.cfg.sim.substeps; ++s) (void)step_rigid_body(m.body, st, w, h, extra_force_w);
}

void move_obstacles(const WorldModel& m, WorldData& d, int env) {
  Obstacle* o = d.env_obstacles(env, m.obstacle_capacity);
  const int n = d.num_obstacles[env];
  if (n == 0) return;  // the empty environment: nothing to move (hot path)
  const real dt = m.cfg.sim.dt_s;
  const Vec3 lo = d.lower_w[env], hi = d.upper_w[env];
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

void collide_robots(const WorldModel& m, WorldData& d, int env) {
  const SimParams& sp = m.cfg.sim;
  const Obstacle* o = d.env_obstacles(env, m.obstacle_capacity);
  const int n = d.num_obstacles[env];
  if (n == 0 && m.robots_per_env == 1 && m.cfg.robot.shape.type == ShapeType::sphere && m.terrain->type() == TerrainType::plane) {
    // Fast path, the empty environment's common case: one sphere robot, no obstacles, and the
    // sphere clear of the ground plane (collide_plane's own test). Nothing touches it, so this
    // stores what the pass below would: zero force, the zero torque rotated into the body frame
    // (its signed zeros), and a crash only if the threshold were negative.
    const std::size_t i = m.index(env, 0);
    const RigidBodyState& st = d.state[i];
    const real plane_z = ground_plane_z(d, env);
    if (!m.cfg.env.create_ground_plane || st.position_w[2] - m.cfg.robot.shape.radius_m >= plane_z) {
      d.contact_force_w[i] = Vec3::Zero();
      d.contact_torque_b[i] = rotate_inverse(st.orientation_wb, Vec3::Zero());
      if (0_r > m.cfg.env.collision_force_threshold_N) d.crashed[i] = 1;
      return;
    }
  }
  for (int r = 0; r < m.robots_per_env; ++r) {
    const std::size_t i = m.index(env, r);
    const RigidBodyState& st = d.state[i];
    const Shape me = make_shape(m.cfg.robot.shape, st.position_w, st.orientation_wb);
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
    if (m.terrain->type() != TerrainType::plane) {
      // Height-field / mesh terrain replaces the ground plane (sim/terrain.hpp).
      Contact tk[kMaxTerrainContacts];
      const int nt = m.terrain->collide(me, m.robot_bound_radius_m, tk);
      for (int c = 0; c < nt; ++c) respond(tk[c], Vec3::Zero());
    } else if (m.cfg.env.create_ground_plane) {
      respond(collide_plane(me, ground_plane_z(d, env)), Vec3::Zero());
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
    for (int q = 0; q < m.robots_per_env; ++q) {
      if (q == r) continue;
      const RigidBodyState& other = d.state[m.index(env, q)];
      respond(collide(me, make_shape(m.cfg.robot.shape, other.position_w, other.orientation_wb)), other.linvel_w);
    }
    d.contact_force_w[i] = force;
    d.contact_torque_b[i] = rotate_inverse(st.orientation_wb, torque_w);
    if (normal_force_sum > m.cfg.env.collision_force_threshold_N) d.crashed[i] = 1;
  }
}

void physics_step(const WorldModel& m, WorldData& d, int env, bool use_new_action) {
  for (int r = 0; r < m.robots_per_env; ++r) {
    const Vec3 v0 = d.state[m.index(env, r)].linvel_w;
    robot_dynamics(m, d, env, m.index(env, r), use_new_action);
    if (m.any_imu) update_imus(m, d, env, r, v0);
  }
  physics_step_tail(m, d, env);
}

// What a physics step does after the robots' dynamics (shared with the batched path).
void physics_step_tail(const WorldModel& m, WorldData& d, int env) {
  move_obstacles(m, d, env);
  collide_robots(m, d, env);
}

void env_step(const WorldModel& m, WorldData& d, int env) {
  env_step_begin(m, d, env);
  for (int s = 0; s < d.phys_steps[env]; ++s) physics_step(m, d, env, s == d.latency[env]);
  env_step_end(m, d, env);
}

// The parts of an env-step before and after its physics steps (the batched path, step_batched.cpp,
// runs the same two around its lockstep physics steps).
void env_step_begin(const WorldModel& m, WorldData& d, int env) {
  const int n = d.phys_steps[env];
  for (int r = 0; r < m.robots_per_env; ++r) d.crashed[m.index(env, r)] = 0;  // per env-step flag
  d.episode_ended[static_cast<std::size_t>(env)] = 0;
  if (moves_setpoint(m)) {
    // Moving setpoint: advance it by at most speed * (env-step duration) towards the target.
    const real max_move = m.cfg.task.setpoint_speed_m_s * m.cfg.sim.dt_s * static_cast<real>(n);
    for (int r = 0; r < m.robots_per_env; ++r) {
      const std::size_t i = m.index(env, r);
      d.setpoint_w[i] = advance_setpoint(d.setpoint_w[i], d.target_w[i], max_move);
      real* a = &d.actions[i * kMaxActionDim];
      for (int k = 0; k < 3; ++k) a[k] = d.setpoint_w[i][k];
    }
  }
}

void env_step_end(const WorldModel& m, WorldData& d, int env) {
  EnvStats& es = d.stats[env];
  ++es.env_steps;
  if (env < d.trace_envs) {
    const std::uint64_t k = es.env_steps - 1 - d.trace_base;
    if (k < static_cast<std::uint64_t>(d.trace_cap)) {
      const std::size_t t = static_cast<std::size_t>(env) * static_cast<std::size_t>(d.trace_cap) + static_cast<std::size_t>(k);
      d.trace[t] = d.state[m.index(env, 0)].position_w;
      d.trace_target[t] = d.target_w[m.index(env, 0)];  // before this step's reset: the episode's own target
      d.trace_episode[t] = es.resets;
    }
  }
  bool any_crash = false, out = false;
  real err_sum = 0;
  for (int r = 0; r < m.robots_per_env; ++r) {
    const std::size_t i = m.index(env, r);
    any_crash = any_crash || d.crashed[i] != 0;
    const Vec3& p = d.state[i].position_w;
    // Out of bounds (with a margin for a robot resting on the ground plane) ends the episode.
    out = out || out_of_bounds(p, d.lower_w[env], d.upper_w[env]);
    err_sum += (d.setpoint_w[i] - p).norm();  // the controller's tracking error (setpoint = target unless it moves)
  }
  es.tracking_error_sum_m += static_cast<double>(err_sum);
  if (any_crash) ++es.crashes;
  const bool timeout = ++d.episode_step[env] >= m.cfg.task.episode_len_env_steps;
  if (timeout) {
    ++es.timeouts;
    bool ok = true;
    for (int r = 0; r < m.robots_per_env; ++r)
      ok = ok && within_success_radius((d.target_w[m.index(env, r)] - d.state[m.index(env, r)].position_w).norm(), m.cfg.task.success_radius_m);
    // A fallback episode (target = start) hovers: never a success (summary.hpp).
    es.successes += ok && d.episode_fallback[static_cast<std::size_t>(env)] == 0 ? 1u : 0u;
  }
  if (out) ++es.out_of_bounds;
  if (timeout || out || (any_crash && m.cfg.env.reset_on_collision)) {
    d.episode_ended[static_cast<std::size_t>(env)] = 1;  // what a Simulator's reset_buf reports
    ++es.episodes_done;
    if (d.episode_fallback[static_cast<std::size_t>(env)] != 0) ++es.fallback_episodes;
    real dist = 0;
    for (int r = 0; r < m.robots_per_env; ++r) dist += (d.target_w[m.index(env, r)] - d.state[m.index(env, r)].position_w).norm();
    es.final_distance_sum_m += static_cast<double>(dist) / m.robots_per_env;
    if (d.auto_reset) {
      reset_env(m, d, env);  // renders the new episode's first images
      return;
    }
  }
  if (m.height_points > 0) update_measured_heights(m, d, env);
  if (m.any_ray_sensor) render_ray_sensors(m, d, env, false);
}

}  // namespace kestrel::sim::stage
