// Backend `rigid`: the 3-D batched World (sim/world.hpp) behind the Simulator interface. The World
// keeps its own episode logic (auto-reset on timeout, exit or crash, task targets); this class
// copies actions in, steps it, and exposes its state as the interface's flat views.
#include <algorithm>
#include <cmath>

#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/rigid_backend.hpp"
#include "kestrel/sim/simulator.hpp"

namespace kestrel::sim {

namespace al = kestrel::allocation;

namespace {

class RigidSimulator final : public Simulator {
 public:
  RigidSimulator() : Simulator(Backend::rigid) {}

  bool init(const WorldConfig& config, std::string& error) {
    if (config.robot.kind == robots::RobotKind::ground_vehicle) {
      error = "simulator rigid: robot ground_vehicle drives on the planar backend only; use simulator: planar";
      return false;
    }
    if (config.simulator.added_mass_max_kg != 0 || config.simulator.added_mass_min_kg != 0 || config.simulator.com_bias_max_m != 0 ||
        config.simulator.motor_scale_min != 1 || config.simulator.motor_scale_max != 1 || config.simulator.gain_scale_min != 1 ||
        config.simulator.gain_scale_max != 1) {
      error = "simulator rigid: added-mass, centre-of-mass, motor and gain-scale randomisation ranges are planar-only (the "
              "World has one body model per world; it randomises motors through the motor model and gains through "
              "controller.randomize_gains); use simulator: planar";
      return false;
    }
    if (articulated_only_randomisation(config.simulator)) {
      error = "simulator rigid: simulator.friction, restitution, joint_armature_kg_m2 and max_push_force_N randomise "
              "articulated robots (robot kind articulated); the multirotor's contacts take sim.friction_coefficient";
      return false;
    }
    if (config.simulator.lidar_beams != 0) {
      error = "simulator rigid: simulator.lidar_beams is the planar 2-D lidar; on rigid attach a lidar through `sensors:`";
      return false;
    }
    world_ = World::create(config, error);
    if (!world_) return false;
    allocate_views(config, static_cast<int>(controller_action_dim(config.controller.kind, world_->controller_params())), 0);
    nominal_ = lee_nominal_gains(world_->controller_params().lee.gain_ranges);
    for (int k = 0; k < world_->num_sensors(); ++k)
      if (world_->sensor_config(k).kind != SensorKind::imu) ray_sensors_.push_back(k);
    num_range_images_ = static_cast<int>(ray_sensors_.size());
    num_height_points_ = world_->num_height_points();
    // The views are refreshed by the World's workers right after their slice of environments
    // stepped (in parallel, in the same dispatch), not by a serial pass afterwards.
    world_->set_after_step(&RigidSimulator::refresh_slice, this);
    // The actions the World set at its first reset (target setpoints) are the initial actions.
    for (int i = 0; i < num_robots(); ++i)
      for (int k = 0; k < action_dim_; ++k)
        actions_[static_cast<std::size_t>(i * action_dim_ + k)] = world_->action(i / robots_per_env_, i % robots_per_env_)[k];
    refresh(0, num_envs_);
    mark_derived_stale();
    return true;
  }

  int num_threads() const override { return world_->num_threads(); }
  const real* measured_heights() const override { return num_height_points_ > 0 ? world_->measured_heights() : nullptr; }
  const char* controller_name() const override { return cfg_.controller.name.c_str(); }
  World* world() { return world_.get(); }

  void post_physics_step() override {
    const std::vector<std::uint8_t>& ended = world_->data().episode_ended;  // the World's own end rule, once
    for (int e = 0; e < num_envs_; ++e) {
      const bool reset = ended[static_cast<std::size_t>(e)] != 0;
      reset_buf_[static_cast<std::size_t>(e)] = reset ? 1 : 0;
      if (!reset || !auto_reset_) continue;
      // The World reset the ended episode inside its step (auto-reset): the new episode's actions
      // (its target setpoint) become the current ones.
      for (int r = 0; r < robots_per_env_; ++r) {
        const std::size_t i = static_cast<std::size_t>(e * robots_per_env_ + r);
        for (int j = 0; j < action_dim_; ++j)
          actions_[i * static_cast<std::size_t>(action_dim_) + static_cast<std::size_t>(j)] = world_->action(e, r)[j];
      }
    }
  }

  void reset_idx(const int* env_ids, int count) override {
    for (int k = 0; k < count; ++k) {
      const int e = env_ids[k];
      if (e < 0 || e >= num_envs_) continue;
      world_->reset_env(e);
      for (int r = 0; r < robots_per_env_; ++r) {
        const std::size_t i = static_cast<std::size_t>(e * robots_per_env_ + r);
        for (int j = 0; j < action_dim_; ++j) actions_[i * static_cast<std::size_t>(action_dim_) + static_cast<std::size_t>(j)] = world_->action(e, r)[j];
      }
      refresh(e, e + 1);
    }
    mark_derived_stale();
  }

  // After the common checks (Simulator::reset_root_states): every 3-D state is representable.
  bool set_root_states(const int* env_ids, int count, const real* pos_w, const real* quat_xyzw, const real* lin_vel_w,
                       const real* ang_vel_w) override {
    for (int k = 0; k < count; ++k) {
      for (int r = 0; r < robots_per_env_; ++r) {
        const int j = k * robots_per_env_ + r;
        RigidBodyState s;
        s.position_w = Vec3(pos_w[3 * j], pos_w[3 * j + 1], pos_w[3 * j + 2]);
        s.orientation_wb = quat_from_xyzw(quat_xyzw[4 * j], quat_xyzw[4 * j + 1], quat_xyzw[4 * j + 2], quat_xyzw[4 * j + 3]);
        s.linvel_w = Vec3(lin_vel_w[3 * j], lin_vel_w[3 * j + 1], lin_vel_w[3 * j + 2]);
        // The interface takes the world-frame angular velocity (legged_gym's root state); the
        // World keeps it in the body frame.
        s.angvel_b = rotate_inverse(s.orientation_wb, Vec3(ang_vel_w[3 * j], ang_vel_w[3 * j + 1], ang_vel_w[3 * j + 2]));
        world_->set_root_state(env_ids[k], r, s);
      }
      refresh(env_ids[k], env_ids[k] + 1);
    }
    mark_derived_stale();
    return true;
  }

  void update_sensors() override {
    for (int e = 0; e < num_envs_; ++e) world_->render_sensors(e);
  }

  RangeImage range_image(int robot, int k) const override {
    RangeImage img;
    if (robot < 0 || robot >= num_robots() || k < 0 || k >= num_range_images_) return img;
    const int sensor = ray_sensors_[static_cast<std::size_t>(k)];
    const SensorConfig& sc = world_->sensor_config(sensor);
    const sensors::RangeOutputParams& rp = sc.kind == SensorKind::camera ? sc.camera.range : sc.lidar.range;
    img.ranges = world_->sensor_ranges(robot / robots_per_env_, sensor, robot % robots_per_env_);
    img.height = world_->sensor_height(sensor);
    img.width = world_->sensor_width(sensor);
    img.row_step = img.width;
    img.col_step = 1;
    img.max_range_m = rp.normalize_range ? 1 : rp.max_range;  // normalised images are already in [0, 1]
    img.horizontal_fov_rad = sc.kind == SensorKind::camera ? sc.camera.horizontal_fov_deg * (kPi / 180)
                                                           : (sc.lidar.horizontal_fov_deg_max - sc.lidar.horizontal_fov_deg_min) * (kPi / 180);
    return img;
  }

  bool set_obstacle_boxes(int env, const ObstacleBox* boxes, int count) override {
    const char* pre = "simulator rigid: set_obstacle_boxes: ";  // a string only on a refusal: no heap in a step
    if (env < 0 || env >= num_envs_) return fail(std::string(pre) + "env " + std::to_string(env) + " out of range");
    // Check every box before changing anything.
    for (int b = 0; b < count; ++b) {
      const ObstacleBox& x = boxes[b];
      if (!(all_finite(x.center_w.data(), 3) && std::isfinite(x.yaw_rad) && all_finite(x.half_extents_m.data(), 3) &&
            x.half_extents_m.minCoeff() > 0))
        return fail(std::string(pre) + "expected a finite centre and yaw and positive finite half extents");
      bool found = false;
      for (int s = 0; s < world_->num_obstacles(env) && !found; ++s) found = world_->obstacle(env, s).class_index == x.asset_class;
      if (!found)
        return fail(std::string(pre) + "asset class " + std::to_string(x.asset_class) + " has no obstacle slot in env " + std::to_string(env) +
                    " (" + std::to_string(cfg_.env.assets.size()) + " asset classes)");
    }
    for (int b = 0; b < count; ++b) {
      const ObstacleBox& x = boxes[b];
      for (int s = 0; s < world_->num_obstacles(env); ++s) {
        Obstacle& o = world_->obstacle(env, s);
        if (o.class_index != x.asset_class) continue;
        o.shape = Shape();
        o.shape.type = ShapeType::box;
        o.shape.half_extents_m = x.half_extents_m;
        o.shape.position_w = x.center_w;
        if (x.yaw_rad != 0) o.shape.orientation_wb = quat_from_euler_xyz(0, 0, x.yaw_rad);
        break;  // the class's first slot
      }
    }
    if (count > 0) world_->obstacles_changed(env);  // sweep order and sensor images see the moved boxes
    return true;
  }

  void set_auto_reset(bool on) override {
    auto_reset_ = on;
    world_->set_auto_reset(on);
  }
  void set_curriculum_level(real level) override {
    if (std::isfinite(level)) world_->set_curriculum_level(std::min(std::max(level, 0_r), 1_r));
  }
  void env_bounds(int env, Vec3& lower_w, Vec3& upper_w) const override { world_->lower_upper_bounds(env, lower_w, upper_w); }

  WorldSummary summary() const override { return world_->summary(); }
  bool placement_fallback(int env) const override {
    return env >= 0 && env < num_envs() && world_->data().episode_fallback[static_cast<std::size_t>(env)] != 0;
  }

  std::uint64_t state_hash() const override { return world_->state_hash(); }

 protected:
  void advance() override {
    mark_derived_stale();  // the World's workers refresh the other views as they step (refresh_slice)
    if (!actions_given_) {
      world_->step(1);
      return;
    }
    for (int i = 0; i < num_robots(); ++i) {
      real* a = world_->action(i / robots_per_env_, i % robots_per_env_);
      for (int k = 0; k < action_dim_; ++k) a[k] = actions_[static_cast<std::size_t>(i * action_dim_ + k)];
    }
    world_->step(1);
  }

  void set_velocity_xy(int env, int robot, real vx, real vy) override {
    RigidBodyState s = world_->robot_state(env, robot);
    s.linvel_w[0] = vx;
    s.linvel_w[1] = vy;
    world_->robot_state(env, robot) = s;  // contact state kept: a push is not a teleport
    refresh(env, env + 1);
    mark_derived_stale();
  }

 private:
  static void refresh_slice(void* self, int begin, int end) { static_cast<RigidSimulator*>(self)->refresh(begin, end); }

  /// Writes the views of environments [begin, end) from the World's state; the derived views
  /// (Euler, applied wrench, scales) are flagged and filled when read (fill_lazy_views).
  void refresh(int begin, int end) {
    for (int e = begin; e < end; ++e) {
      for (int r = 0; r < robots_per_env_; ++r) {
        const std::size_t i = static_cast<std::size_t>(e * robots_per_env_ + r);
        write_state_view(i, world_->robot_state(e, r), false);
        const Vec3& f = world_->contact_force_w(e, r);
        for (int k = 0; k < 3; ++k) contact_w_[3 * i + k] = f[k];
        const Vec3& t = world_->target(e, r);
        for (int k = 0; k < 3; ++k) target_w_[3 * i + k] = t[k];
        crashed_[i] = world_->crashed(e, r) ? 1 : 0;
      }
    }
  }
  void mark_derived_stale() { lazy_ = kLazyEuler | kLazyWrench | kLazyScales; }

  void fill_lazy_views(std::uint8_t which) const override {
    const al::Airframe& af = world_->airframe();
    const al::MotorModelConfig& mc = world_->motor_config();
    const real tau_nominal = (mc.time_constant_increasing_min_s + mc.time_constant_increasing_max_s) / 2;
    for (int e = 0; e < num_envs_; ++e) {
      for (int r = 0; r < robots_per_env_; ++r) {
        const std::size_t i = static_cast<std::size_t>(e * robots_per_env_ + r);
        if (which & kLazyEuler) write_euler_view(i);
        const al::MotorModelState& m = world_->motor_state(e, r);
        if (which & kLazyWrench) {
          // Applied wrench: motor thrusts through the effectiveness matrix plus the contact wrench
          // the next physics step applies (the random disturbance, when enabled, is not included).
          const Vec6 w = al::wrench_from_thrusts(af.effectiveness, af.num_rotors, m.thrust_N);
          const Vec3 fb = rotate_inverse(world_->robot_state(e, r).orientation_wb, world_->contact_force_w(e, r));
          const Vec3& tb = world_->contact_torque_b(e, r);
          for (int k = 0; k < 3; ++k) {
            wrench_b_[6 * i + k] = w[k] + fb[k];
            wrench_b_[6 * i + 3 + k] = w[3 + k] + tb[k];
          }
        }
        if (which & kLazyScales) {
          // Domain randomisation the World does: motor time constants (motor model reset) and Lee
          // gains (controller.randomize_gains). Mass and centre of mass are fixed per world.
          real tau = 0;
          for (int k = 0; k < af.num_rotors; ++k) tau += m.time_constant_increasing_s[k];
          motor_scale_[i] = af.num_rotors > 0 && tau_nominal > 0 ? tau / static_cast<real>(af.num_rotors) / tau_nominal : 1;
          gain_scale_[i] = gain_ratio(world_->controller_state(e, r).lee.gains);
        }
      }
    }
  }

  real gain_ratio(const LeeGains& g) const {
    real sum = 0;
    int n = 0;
    const PlainVec3* a[4] = {&g.k_pos, &g.k_vel, &g.k_rot, &g.k_angvel};
    const PlainVec3* b[4] = {&nominal_.k_pos, &nominal_.k_vel, &nominal_.k_rot, &nominal_.k_angvel};
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 3; ++k)
        if ((*b[j])[k] != 0) {
          sum += (*a[j])[k] / (*b[j])[k];
          ++n;
        }
    return n > 0 ? sum / static_cast<real>(n) : 1;
  }

  std::unique_ptr<World> world_;
  std::vector<int> ray_sensors_;  // robot.sensors indices of the ray sensors (range images)
  bool auto_reset_ = true;
  LeeGains nominal_;
};

}  // namespace

std::unique_ptr<Simulator> make_rigid_simulator(const WorldConfig& config, std::string& error) {
  std::unique_ptr<RigidSimulator> s(new RigidSimulator());
  if (!s->init(config, error)) return nullptr;
  return s;
}

World* rigid_world(Simulator& sim) {
  // Articulated robots run on the rigid backend too, but not in a World (backends/articulated.cpp).
  const bool world = sim.backend() == Backend::rigid && sim.config().robot.kind != robots::RobotKind::articulated;
  return world ? static_cast<RigidSimulator&>(sim).world() : nullptr;
}
const World* rigid_world(const Simulator& sim) { return rigid_world(const_cast<Simulator&>(sim)); }

}  // namespace kestrel::sim
