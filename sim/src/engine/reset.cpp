// Episode set-up of the rigid World: bounds, obstacle layout, placement of starts and targets,
// physics-step count and latency, the control chain's reset, sensor mounts.
#include <algorithm>
#include <cmath>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/terrain.hpp"
#include "kestrel/sim/world_stages.hpp"
#include "../scene/episode_draw.hpp"

namespace kestrel::sim::stage {

namespace al = kestrel::allocation;
using scene::uniform_vec;

namespace {
bool overlaps_obstacle(const WorldModel& m, const WorldData& d, int env, const Shape& s) {
  Vec3 mn, mx;
  shape_aabb(s, mn, mx);
  const Obstacle* o = d.env_obstacles(env, m.obstacle_capacity);
  for (int i = 0; i < d.num_obstacles[env]; ++i) {
    // AABB rejection first: placement tests many candidates against every obstacle at each reset.
    if ((o[i].aabb_max_w.array() < mn.array()).any() || (o[i].aabb_min_w.array() > mx.array()).any()) continue;
    if (collide(s, o[i].shape).hit) return true;
  }
  return false;
}
}  // namespace

void generate_layout(const WorldModel& m, WorldData& d, int env, RngStream& rng) {
  // data() + offset, not &v[i]: the empty environment has no obstacle slots (capacity 0).
  Obstacle* slots = d.env_obstacles(env, m.obstacle_capacity);
  const int n = sim::generate_layout(m.cfg, d.curriculum_level, d.lower_w[env], d.upper_w[env], rng, &m.mesh_vertices, slots);
  d.num_obstacles[env] = n;
  sort_sweep_order(slots, n);
}

bool clear_point(const WorldModel& m, const WorldData& d, int env, const Vec3& p) {
  // Above the terrain by the bounding sphere and the clearance (heightfield / mesh terrain only:
  // the ground plane lies under the bounds by construction).
  if (m.terrain->type() != TerrainType::plane &&
      !(p[2] - m.terrain->height_at(p[0], p[1]) > m.robot_bound_radius_m + m.cfg.task.clearance_m))
    return false;
  Shape s;
  s.type = ShapeType::sphere;
  s.radius_m = m.robot_bound_radius_m + m.cfg.task.clearance_m;
  s.position_w = p;
  return !overlaps_obstacle(m, d, env, s);
}

bool clear_segment(const WorldModel& m, const WorldData& d, int env, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const real len = ab.norm();
  if (!(len > 1e-6_r)) return clear_point(m, d, env, a);
  if (m.terrain->type() != TerrainType::plane) {
    // The path over the terrain, checked every 0.1 m.
    const int steps = static_cast<int>(len / 0.1_r) + 1;
    for (int k = 0; k <= steps; ++k) {
      const Vec3 p = a + ab * (static_cast<real>(k) / static_cast<real>(steps));
      if (!(p[2] - m.terrain->height_at(p[0], p[1]) > m.robot_bound_radius_m + m.cfg.task.clearance_m)) return false;
    }
  }
  // The swept bounding sphere: a capsule from a to b (local z along the segment).
  Shape s;
  s.type = ShapeType::capsule;
  s.radius_m = m.robot_bound_radius_m + m.cfg.task.clearance_m;
  s.half_length_m = len / 2;
  s.position_w = (a + b) / 2;
  s.orientation_wb = Quat::FromTwoVectors(Vec3::UnitZ(), ab / len);
  return !overlaps_obstacle(m, d, env, s);
}

void reset_env(const WorldModel& m, WorldData& d, int env) {
  RngStream& rng = d.rng_reset[env];
  const EnvConfig& e = m.cfg.env;
  scene::draw_bounds(e, rng, d.lower_w[env], d.upper_w[env]);
  if (scene::layout_due(e, d.layout_generation[env], d.episodes_since_layout[env])) {
    generate_layout(m, d, env, rng);
    scene::layout_drawn(d.layout_generation[env], d.episodes_since_layout[env]);
  }
  const int ps = static_cast<int>(std::floor(
      e.num_physics_steps_per_env_step_mean + e.num_physics_steps_per_env_step_std * rng.normal() + 0.5_r));
  d.phys_steps[env] = std::max(1, ps);
  d.latency[env] = e.sample_timestep_for_latency
                      ? std::min(d.phys_steps[env], static_cast<int>(rng.next_u32() % static_cast<std::uint32_t>(e.max_latency_physics_steps + 1)))
                      : 0;
  d.episode_step[env] = 0;
  const bool hover_task = m.cfg.task.kind == TaskKind::hover;
  d.episode_fallback[static_cast<std::size_t>(env)] = 0;
  for (int r = 0; r < m.robots_per_env; ++r) {
    const std::size_t i = m.index(env, r);
    const scene::Placement place = scene::place_robot(
        m.cfg, d.lower_w[env], d.upper_w[env], rng, [&](const Vec3& p) { return clear_point(m, d, env, p); },
        [&](const Vec3& a, const Vec3& b) { return clear_segment(m, d, env, a, b); });
    ++d.stats[env].placements;
    if (place.fallback) {  // hovers at a clear start rather than fly into an obstacle: not a real episode
      ++d.stats[env].placement_fallbacks;
      d.episode_fallback[static_cast<std::size_t>(env)] = 1;
    }
    RigidBodyState st;
    st.position_w = place.start_w;
    const real yaw = rng.uniform(-m.cfg.robot.max_init_yaw_rad, m.cfg.robot.max_init_yaw_rad);
    st.orientation_wb = quat_from_euler_xyz(0, 0, yaw);
    const real v0 = m.cfg.robot.max_init_linvel_m_s, w0 = m.cfg.robot.max_init_angvel_rad_s;
    if (v0 > 0) st.linvel_w = uniform_vec(rng, Vec3::Constant(-v0), Vec3::Constant(v0));
    if (w0 > 0) st.angvel_b = rotate_inverse(st.orientation_wb, uniform_vec(rng, Vec3::Constant(-w0), Vec3::Constant(w0)));
    d.state[i] = st;
    real hover[al::kMaxRotors] = {};
    const real per_motor = m.body.params.mass_kg * kStandardGravity / static_cast<real>(m.mr.airframe.num_rotors);
    for (int j = 0; j < m.mr.airframe.num_rotors; ++j) hover[j] = per_motor;
    // One stream for the gain and the motor draws, in that order (the World's order since the start).
    if (robots::multirotor_reset(m.mr, d.mr_state[i], &rng, rng, hover) != Status::ok) ++d.status_count[static_cast<std::size_t>(env)];
    // Task: the position setpoint (or the start point for hover) is the action of the episode.
    d.target_w[i] = place.target_w;
    real* a = &d.actions[i * kMaxActionDim];
    std::fill(a, a + kMaxActionDim, 0_r);
    const bool moving = m.cfg.task.setpoint_speed_m_s > 0 && !hover_task;
    d.setpoint_w[i] = moving ? st.position_w : d.target_w[i];
    if (m.cfg.controller.kind == ControllerKind::lee_position) {
      a[0] = d.setpoint_w[i][0];
      a[1] = d.setpoint_w[i][1];
      a[2] = d.setpoint_w[i][2];
      a[3] = 0;
    } else if (m.cfg.controller.kind == ControllerKind::direct_motor) {
      for (int j = 0; j < m.mr.airframe.num_rotors; ++j) a[j] = per_motor;
    }
    std::copy(a, a + kMaxActionDim, &d.applied_actions[i * kMaxActionDim]);
    d.contact_force_w[i] = Vec3::Zero();
    d.contact_torque_b[i] = Vec3::Zero();
    d.crashed[i] = 0;
  }
  // Sensor placement per reset (Aerial Gym's randomize_placement) from the placement stream, so
  // the reset stream (layout, start, target) is the same with or without sensors.
  for (int r = 0; r < m.robots_per_env; ++r) {
    const std::size_t i = m.index(env, r);
    for (std::size_t k = 0; k < m.sensors.size(); ++k) {
      const SensorModel& s = m.sensors[k];
      SensorData& sd = d.sensors[k];
      if (s.kind == SensorKind::imu) {
        sensors::imu_reset(m.cfg.robot.sensors[k].imu, sd.imu_state[i], d.rng_sensor[static_cast<std::size_t>(env)]);
        sd.imu[i] = sensors::ImuSample();
      } else {
        sd.mounts[i] = sensors::sample_mount(s.mount, d.rng_place[static_cast<std::size_t>(env)]);
      }
    }
  }
  ++d.stats[env].resets;
  // The new episode's first observation sees the new layout and start.
  if (m.any_ray_sensor) render_ray_sensors(m, d, env, true);
  if (m.height_points > 0) update_measured_heights(m, d, env);
}

}  // namespace kestrel::sim::stage
