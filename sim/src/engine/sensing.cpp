// Sensing stages of the rigid World: IMUs every physics step, ray sensors against a per-environment
// scene rebuilt from the obstacle slots, and legged_gym's measured heights.
#include <algorithm>
#include <cmath>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/mesh.hpp"
#include "kestrel/sim/terrain.hpp"
#include "kestrel/sim/world_stages.hpp"

namespace kestrel::sim::stage {

namespace {
real ground_height(const WorldModel& m, const WorldData& d, real x_w, real y_w, int env) {
  if (m.terrain->type() != TerrainType::plane) return m.terrain->height_at(x_w, y_w);
  if (!m.cfg.env.create_ground_plane) return -1e30_r;
  return ground_plane_z(d, env);
}

}  // namespace

void update_measured_heights(const WorldModel& m, WorldData& d, int env) {
  // legged_gym _get_heights: the points rotated by the base yaw (quat_apply_yaw) around the base.
  for (int r = 0; r < m.robots_per_env; ++r) {
    const std::size_t i = m.index(env, r);
    const RigidBodyState& st = d.state[i];
    const Vec3 fwd = rotate(st.orientation_wb, Vec3::UnitX());
    const real fn = std::sqrt(fwd[0] * fwd[0] + fwd[1] * fwd[1]);
    const real c = fn > 1e-6_r ? fwd[0] / fn : 1_r, s = fn > 1e-6_r ? fwd[1] / fn : 0_r;
    real* out = &d.measured_heights[i * static_cast<std::size_t>(m.height_points)];
    for (int k = 0; k < m.height_points; ++k) {
      const real px = m.height_points_x_b[static_cast<std::size_t>(k)], py = m.height_points_y_b[static_cast<std::size_t>(k)];
      out[k] = ground_height(m, d, st.position_w[0] + c * px - s * py, st.position_w[1] + s * px + c * py, env);
    }
  }
}

void update_scene(const WorldModel& m, WorldData& d, int env) {
  // Rebuilt from the obstacle slots rather than moved with set_pose: a reset may change the
  // layout (other shapes, other count) and move_obstacles re-sorts the slots, so slot i is not
  // always the same object. clear/add/build write only the caller storage (no heap) and cost
  // microseconds for tens of obstacles, far below one image.
  sensors::Scene& sc = d.scenes[static_cast<std::size_t>(env)];
  sc.clear();
  if (m.terrain->type() != TerrainType::plane) {
    // The terrain takes the ground plane's slot (segmentation 0, as the ground).
    (void)sc.add(m.terrain->scene_shape(), m.terrain->scene_position_w(), Quat::Identity(), 0);
  } else if (m.cfg.env.create_ground_plane) {
    (void)sc.add(sensors::Shape::plane(), Vec3(0, 0, ground_plane_z(d, env)), Quat::Identity(), 0);  // the plane collide_robots uses
  }
  for (int k = 0; k < d.num_obstacles[env]; ++k) {
    const Obstacle& o = d.env_obstacles(env, m.obstacle_capacity)[k];
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
        if (ci < m.render_meshes.size() && m.render_meshes[ci]) {
          rs = sensors::Shape::triangle_mesh(&m.render_meshes[ci]->mesh);
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

void render_ray_sensors(const WorldModel& m, WorldData& d, int env, bool all) {
  const std::uint64_t n = d.stats[env].env_steps;
  bool any = false;
  for (const SensorModel& s : m.sensors)
    any = any || (s.kind != SensorKind::imu && (all || n % static_cast<std::uint64_t>(s.every) == 0));
  if (!any) return;
  update_scene(m, d, env);
  const sensors::Scene& sc = d.scenes[static_cast<std::size_t>(env)];
  for (std::size_t k = 0; k < m.sensors.size(); ++k) {
    const SensorModel& s = m.sensors[k];
    if (s.kind == SensorKind::imu || !(all || n % static_cast<std::uint64_t>(s.every) == 0)) continue;
    SensorData& sd = d.sensors[k];
    for (int r = 0; r < m.robots_per_env; ++r) {
      const std::size_t i = m.index(env, r);
      const sensors::SensorPose pose = sensors::sensor_pose(d.state[i], sd.mounts[i]);
      sensors::SensorOutput out;
      out.range = &sd.ranges[i * s.pixels];
      out.segmentation = &sd.segmentation[i * s.pixels];
      (void)sensors::render(sc, pose, s.table, s.range, s.depth, out, &s.noise, &d.rng_sensor[static_cast<std::size_t>(env)]);
    }
  }
}

void obstacles_changed(const WorldModel& m, WorldData& d, int env) {
  Obstacle* o = d.env_obstacles(env, m.obstacle_capacity);
  const int n = d.num_obstacles[env];
  for (int i = 0; i < n; ++i) shape_aabb(o[i].shape, o[i].aabb_min_w, o[i].aabb_max_w);
  sort_sweep_order(o, n);
  if (m.any_ray_sensor) render_ray_sensors(m, d, env, true);
}

void update_imus(const WorldModel& m, WorldData& d, int env, int robot, const Vec3& linvel_before_w) {
  const std::size_t i = m.index(env, robot);
  const RigidBodyState& st = d.state[i];
  const real dt = m.cfg.sim.dt_s;
  // Acceleration over the physics step from the velocity change: it contains every force the
  // integrator applied (thrust, drag, contact, disturbance, gravity), as a force sensor would.
  const Vec3 acc_w = (st.linvel_w - linvel_before_w) / dt;
  for (std::size_t k = 0; k < m.sensors.size(); ++k) {
    if (m.sensors[k].kind != SensorKind::imu) continue;
    SensorData& sd = d.sensors[k];
    (void)sensors::imu_update(m.cfg.robot.sensors[k].imu, sd.imu_state[i], st.orientation_wb, acc_w, st.angvel_b, Quat::Identity(), dt,
                              d.rng_sensor[static_cast<std::size_t>(env)], sd.imu[i]);
  }
}

}  // namespace kestrel::sim::stage
