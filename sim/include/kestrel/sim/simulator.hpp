// One simulator interface over two physics backends.
//
// The shape is legged_gym-Ex's Simulator class (the Isaac Gym calls of legged_gym's LeggedRobot
// gathered behind one object: step with `decimation` physics steps, post_physics_step, reset_idx,
// reset_root_states, push_robots, refreshed state tensors and domain-randomisation buffers),
// adapted to flat float arrays and to Kestrel's robots:
//   - rigid:  the 3-D batched World (sim/world.hpp: Newton-Euler bodies, libccd/analytic collision
//             with penalty contact), every robot, environment and sensor it supports; articulated
//             robots (robot kind articulated: legged robots from MJCF/URDF files) on the core's
//             constrained step against the terrain (sim/src/backends/articulated.cpp);
//   - planar: Box2D 2.4 (sim/src/backends/planar.cpp), one b2World per environment, for robots that move in a
//             plane: a car-like ground vehicle on the velocity + steering-angle controller
//             (kinematic bicycle model) or a multirotor held at a fixed altitude; circles and boxes
//             as obstacles; a 2-D lidar through b2World::RayCast.
// The backend is chosen once, by make_simulator: the KESTREL_SIMULATOR environment variable if set,
// else the scenario's `simulator:` field, else rigid. What a backend cannot do fails with a message
// naming the backend and the alternative (e.g. a mesh obstacle on planar: "use simulator: rigid").
//
// Every view is a flat array over robots, robot index = env * robots_per_env + r, valid until the
// next call that changes state. Frames: positions and contact forces in the world frame (z up),
// quaternions xyzw (q_wb), Euler XYZ (roll, pitch, yaw) in [-pi, pi), linear and angular velocity
// in the body frame (legged_gym's base_lin_vel / base_ang_vel), wrench [fx fy fz tx ty tz] in the
// body frame.
//
// What a task sits on (the narrow API): num_envs/num_robots/action_dim, step(actions) with
// post_physics_step's reset_buf, reset_idx, reset_root_states, push_robots, the base_* views,
// contact_forces_w/crashed, target_w, range_image (rigid: the robot's ray sensors; planar: the 2-D
// lidar as one row), holds_altitude, env_bounds, set_obstacle_boxes (task-owned objects),
// set_auto_reset / set_curriculum_level (the task owns episode ends and the obstacle curriculum),
// and the domain-randomisation views for privileged observations. The tasks (sim/src/tasks/) are
// written once over exactly this and run on both backends; nothing else of either is reachable
// from them.
//
// Determinism: per-environment streams RngStream(seed, env, purpose); environments never read each
// other, so results are bit-identical for any thread count (tests/sim/backends/planar_test.cpp hashes it).
// No heap inside step/post_physics_step/push_robots/reset_idx after set-up (planar: after Box2D's
// block allocator and broad-phase buffers have warmed up; see sim/src/backends/planar.cpp and the heap test).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "kestrel/kernel/rigid_body.hpp"
#include "kestrel/kernel/rng.hpp"
#include "kestrel/sim/config.hpp"
#include "kestrel/sim/summary.hpp"

namespace kestrel::sim {

enum class Backend : std::uint8_t { rigid = 0, planar = 1 };
const char* backend_name(Backend b);
/// "rigid" / "planar"; false (out untouched) for anything else.
[[nodiscard]] bool backend_from_name(const std::string& name, Backend& out);
/// KESTREL_SIMULATOR (read now) if set and non-empty, else config.simulator.backend if non-empty,
/// else rigid. An unknown name gives false and a message naming where it came from.
[[nodiscard]] bool resolve_backend(const WorldConfig& config, Backend& out, std::string& error);

/// One ray-sensor range image as a task reads it: element (r, c), r in [0, height) from the top,
/// c in [0, width) from the left, is ranges[r * row_step + c * col_step] (metres; in [0, 1] when
/// the sensor normalises, then max_range_m is 1). Negative, non-finite or >= max_range_m: no return.
struct RangeImage {
  const real* ranges = nullptr;
  int height = 0, width = 0;
  std::ptrdiff_t row_step = 0, col_step = 1;
  real max_range_m = 1;
  real horizontal_fov_rad = 0;  // the columns' span
  real at(int r, int c) const { return ranges[r * row_step + c * col_step]; }
};

/// A task-owned box obstacle (Simulator::set_obstacle_boxes).
struct ObstacleBox {
  int asset_class = 0;
  Vec3 center_w = Vec3::Zero();
  Vec3 half_extents_m = Vec3::Constant(0.5_r);
  real yaw_rad = 0;
};

/// Random stream purpose of push_robots (above kPurposeUser, see kernel/rng.hpp).
constexpr std::uint32_t kPurposePush = kPurposeUser + 5;
/// Random stream purpose of run_scripted's joint targets for articulated robots.
constexpr std::uint32_t kPurposeScriptedTargets = kPurposeUser + 6;
/// Random stream purpose of the articulated robots' joint-gain scales (drawn at each reset).
constexpr std::uint32_t kPurposeJointGains = kPurposeUser + 7;
/// Random stream purpose of the articulated robots' other randomisation (friction, restitution,
/// added base mass, centre-of-mass bias, joint armature; drawn at each reset).
constexpr std::uint32_t kPurposeDomainRand = kPurposeUser + 8;
/// Random stream purpose of push_links' forces.
constexpr std::uint32_t kPurposeLinkPush = kPurposeUser + 9;
/// Random stream purpose of the terrain curriculum (start levels, levels past the top, spawn offsets).
constexpr std::uint32_t kPurposeTerrainLevel = kPurposeUser + 10;

/// True when the scenario asks for a randomisation only articulated robots have (simulator.friction,
/// restitution, joint_armature_kg_m2 or max_push_force_N set): the other robots' backends refuse it.
bool articulated_only_randomisation(const SimulatorConfig& sc);

/// What legged_gym reads from an articulated robot's asset (Simulator::robot_layout; empty for
/// other robots): the actuated joints in body order with their home (default) positions, position
/// limits (-inf / +inf where the joint has none) and effort limits (+inf where none), the bodies'
/// names, and the foot bodies (indices into the links of link_contact_forces_w, in feet_pos_w order).
struct RobotLayout {
  std::vector<std::string> dof_names, link_names;
  std::vector<real> default_dof_pos, dof_pos_lower, dof_pos_upper, torque_limits;
  std::vector<int> foot_links;
};

class Simulator {
 public:
  virtual ~Simulator();
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  Backend backend() const { return backend_; }
  const char* backend_name() const { return sim::backend_name(backend_); }
  const WorldConfig& config() const { return cfg_; }
  int num_envs() const { return num_envs_; }
  int robots_per_env() const { return robots_per_env_; }
  int num_robots() const { return num_envs_ * robots_per_env_; }
  /// Values per robot in the action array (4 for the Lee controllers, 2 for the ground vehicle).
  int action_dim() const { return action_dim_; }
  /// Nominal physics steps per step() (env.num_physics_steps_per_env_step_mean, legged_gym's decimation).
  int decimation() const { return decimation_; }
  real dt_s() const { return cfg_.sim.dt_s; }
  virtual int num_threads() const = 0;
  /// Name of what drives the robots: the controller kind ("lee_position_control", "velocity_steering_control", ...).
  virtual const char* controller_name() const = 0;
  /// True for the planar car (action [speed_m_s, steering_rad]); false for multirotors.
  bool ground_vehicle() const { return ground_vehicle_; }

  /// Copies the actions (num_robots x action_dim, row-major), runs every environment's physics
  /// steps in parallel, then post_physics_step(). nullptr keeps the current actions: on planar the
  /// last ones given (a reset sets them to the episode's target or zero); on rigid the World's own
  /// (the task's setpoints, moving ones included).
  void step(const real* actions);
  /// Refreshes the views, sets reset_buf for environments whose episode ended in this step
  /// (timeout, exit from the bounds, crash with reset_on_collision) and resets them (auto-reset).
  virtual void post_physics_step() = 0;
  /// Resets these environments now: new layout/start/target per the env config, as a timeout does.
  virtual void reset_idx(const int* env_ids, int count) = 0;
  /// Puts exact root states: for each listed env, robots_per_env rows of pos_w (3), quat_xyzw (4),
  /// lin_vel_w (3), ang_vel_w (3). Controller and contact state are cleared; nothing else changes.
  /// False (nothing written, last_error() says why) for a non-finite or non-unit quaternion, a bad
  /// env id, or a state the backend cannot represent (planar: roll/pitch, or z off the plane).
  /// The checks every backend makes are here; the backend's own (set_root_states) follow.
  [[nodiscard]] bool reset_root_states(const int* env_ids, int count, const real* pos_w, const real* quat_xyzw,
                                       const real* lin_vel_w, const real* ang_vel_w);
  /// Renders the sensors now (step() already renders them at the configured rate).
  virtual void update_sensors() = 0;
  /// With auto-reset off, post_physics_step only flags reset_buf and leaves the ended episodes
  /// as they are, so a task can read the final state (reward, terminations) and call reset_idx
  /// itself (World::set_auto_reset). On by default.
  virtual void set_auto_reset(bool on) = 0;
  /// Obstacle curriculum level in [0, 1] (clamped; non-finite ignored): the share of each asset
  /// class's [min_num_assets, num_assets] range used, from each environment's next layout on
  /// (World::set_curriculum_level).
  virtual void set_curriculum_level(real level) = 0;
  /// The environment's bounds for its current episode (drawn at each reset).
  virtual void env_bounds(int env, Vec3& lower_w, Vec3& upper_w) const = 0;
  /// LeggedGym-Ex's set_viewer_camera and draw_debug_vis: hooks that a viewer fills. The
  /// simulator keeps the latest request (viewer_request()) and hands it to the viewer attached with
  /// set_viewer (the Python Viewer through Simulator.attach_viewer), at once and again when a
  /// viewer attaches later; without one, nothing is drawn. Setting up, not stepping: may allocate.
  struct ViewerRequest {
    bool camera_set = false;
    Vec3 camera_position_w = Vec3::Zero(), camera_lookat_w = Vec3::Zero();  // m, world frame
    bool debug_height_samples = false, debug_contacts = false;  // measured_heights points; contacts and forces
  };
  class ViewerHooks {
   public:
    virtual ~ViewerHooks() = default;
    virtual void on_viewer_request(const ViewerRequest& request) = 0;
  };
  /// The viewer's camera at position_w looking at lookat_w. False (nothing changed, last_error()
  /// says why) for a non-finite point or two equal ones.
  [[nodiscard]] bool set_viewer_camera(const Vec3& position_w, const Vec3& lookat_w);
  /// From now on the viewer also draws the height samples and / or the contacts with their forces.
  void draw_debug_vis(bool height_samples, bool contacts);
  /// Attaches a viewer (not owned; nullptr detaches) and hands it the current request.
  void set_viewer(ViewerHooks* viewer);
  const ViewerRequest& viewer_request() const { return viewer_request_; }
  /// legged_gym's _push_robots: every robot's world-frame v_x and v_y are set to values drawn
  /// uniformly in [-max_push_vel_xy_m_s, max_push_vel_xy_m_s] from its environment's push stream.
  void push_robots();
  /// legged_gym's _update_terrain_curriculum on a tiled terrain (env.terrain.procedural curriculum
  /// or randomized): each listed environment's level moves up by one where move_up[k] and down by
  /// one where move_down[k] (not below 0); one that passes the top level goes to a level drawn
  /// uniformly in [0, levels) from its stream. Its origin becomes its tile's (terrain_levels,
  /// env_origins_w): the robot goes there at its next reset. False (nothing changed, last_error()
  /// says why) without a tiled terrain or for a bad env id.
  [[nodiscard]] virtual bool update_terrain_curriculum(const int* env_ids, int count, const std::uint8_t* move_up,
                                                       const std::uint8_t* move_down) {
    (void)env_ids, (void)count, (void)move_up, (void)move_down;
    return fail(std::string("simulator ") + backend_name() +
                ": update_terrain_curriculum: needs articulated robots on a tiled terrain (env.terrain.procedural curriculum or randomized)");
  }
  /// Tiled terrain: each environment's level (row of tiles) and type (column); 0 levels otherwise.
  int num_terrain_levels() const { return num_terrain_levels_; }
  const int* terrain_levels() const { return terrain_levels_.data(); }  // (envs)
  const int* terrain_types() const { return terrain_types_.data(); }    // (envs)
  /// (envs x 3) m: where each environment's robot starts (articulated: its grid or tile origin;
  /// zeros on other robots, whose starts are drawn per reset).
  const real* env_origins_w() const { return env_origins_w_.data(); }
  /// LeggedGym-Ex's push_links: every link of every robot gets a force (world frame, components
  /// drawn uniformly in [-simulator.max_push_force_N, max] from its environment's link-push stream)
  /// at its centre of mass during the next physics step. False (nothing drawn, last_error() says
  /// why) for robots without links (articulated robots only).
  [[nodiscard]] virtual bool push_links() {
    return fail(std::string("simulator ") + backend_name() + ": push_links: the robot has no links (robot kind articulated only)");
  }

  // State views (refreshed by post_physics_step, reset_idx, reset_root_states and push_robots).
  // The derived ones (Euler angles, applied wrench, motor and gain scales) may be computed when
  // their accessor is called rather than after every step (rigid: a task that does not read them
  // does not pay for them), so a caller holding one of those pointers across a step calls the
  // accessor again (Python: reads the property again).
  const real* base_pos_w() const { return pos_w_.data(); }            // (robots x 3) m
  const real* base_quat_xyzw() const { return quat_xyzw_.data(); }    // (robots x 4)
  const real* base_euler_xyz() const { return fresh(kLazyEuler, euler_xyz_); }  // (robots x 3) rad
  const real* base_lin_vel_b() const { return lin_vel_b_.data(); }    // (robots x 3) m/s, body
  const real* base_lin_vel_w() const { return lin_vel_w_.data(); }    // (robots x 3) m/s, world
  const real* base_ang_vel_b() const { return ang_vel_b_.data(); }    // (robots x 3) rad/s, body
  const real* contact_forces_w() const { return contact_w_.data(); }  // (robots x 3) N
  const real* applied_wrench_b() const { return fresh(kLazyWrench, wrench_b_); }  // (robots x 6) N, N m
  const real* target_w() const { return target_w_.data(); }           // (robots x 3) m
  const std::uint8_t* crashed() const { return crashed_.data(); }     // (robots)
  const std::uint8_t* reset_buf() const { return reset_buf_.data(); } // (envs) episode ended last step

  // Domain-randomisation views (drawn at each reset; robots). Articulated robots: added_mass_kg is
  // legged_gym's dr_added_base_mass (the root body's), com_bias_b_m its dr_base_com_bias.
  const real* added_mass_kg() const { return added_mass_kg_.data(); }
  const real* com_bias_b_m() const { return com_bias_b_m_.data(); }    // (robots x 3)
  /// Articulated robots: the ground contacts' friction coefficient and restitution of each robot
  /// (simulator.friction / restitution; -1 where not randomised: each contact then takes the mean
  /// of the shape's and the ground's), and each actuated joint's armature (robots x dofs, kg m^2 or
  /// kg: the value in effect, randomised or not). Empty views on other robots.
  const real* dr_friction_values() const { return dr_friction_.data(); }
  const real* dr_restitution_values() const { return dr_restitution_.data(); }
  const real* dr_joint_armature() const { return dr_armature_.data(); }
  /// Multirotor: motor time constant / its nominal value; ground vehicle: drive force scale.
  const real* motor_constant_scale() const { return fresh(kLazyScales, motor_scale_); }
  /// Active controller gains / nominal gains (Lee: mean over the 12 gain components).
  const real* controller_gain_scale() const { return fresh(kLazyScales, gain_scale_); }

  // Articulated robots (robot kind articulated, rigid backend; 0 and empty otherwise): legged_gym's
  // joint and link views. Joints are the robot file's actuated joints in body order.
  int num_dofs() const { return num_dofs_; }    // actuated joints per robot
  int num_feet() const { return num_feet_; }    // foot bodies per robot
  int num_links() const { return num_links_; }  // bodies per robot
  const real* dof_pos() const { return dof_pos_.data(); }    // (robots x dofs) rad or m
  const real* dof_vel() const { return dof_vel_.data(); }    // (robots x dofs) rad/s or m/s
  const real* torques() const { return torques_.data(); }    // (robots x dofs) N m or N: the last physics step's
  const real* feet_pos_w() const { return feet_pos_w_.data(); }  // (robots x feet x 3) m
  /// (robots x links x 3) N: the ground's force on each body at the last physics step.
  const real* link_contact_forces_w() const { return link_forces_w_.data(); }
  /// legged_gym's measured_heights: world z of the terrain under each robot's height points
  /// (env.terrain.measure_heights; measured_points_x_m x measured_points_y_m around the base, turned
  /// by its yaw, x-major), refreshed after every step and reset; (robots x num_height_points()).
  /// 0 points (and nullptr) without measure_heights or on planar.
  int num_height_points() const { return num_height_points_; }
  virtual const real* measured_heights() const { return nullptr; }
  /// legged_gym's dr_kp_scale / dr_kd_scale: each robot's joint-gain scales, drawn at its resets
  /// in robot.joint_kp_scale / joint_kd_scale (robots).
  const real* dr_kp_scale() const { return dr_kp_scale_.data(); }
  const real* dr_kd_scale() const { return dr_kd_scale_.data(); }
  const RobotLayout& robot_layout() const { return layout_; }
  /// legged_gym's reset_dofs: for each listed env, robots_per_env rows of dof_pos and dof_vel
  /// (num_dofs each). False (nothing written, last_error() says why) off articulated robots, for
  /// a bad env id or a non-finite value.
  [[nodiscard]] virtual bool reset_dofs(const int* env_ids, int count, const real* dof_pos, const real* dof_vel) {
    (void)env_ids, (void)count, (void)dof_pos, (void)dof_vel;
    return fail(std::string("simulator ") + backend_name() + ": reset_dofs: the robot has no joints (robot kind articulated only)");
  }

  /// 2-D lidar (planar; 0 beams on rigid, whose ray sensors are the World's, rigid_world(sim)->sensor_*).
  int lidar_beams() const { return lidar_beams_; }
  const real* lidar_ranges_m() const { return lidar_.data(); }  // (robots x beams), max range = no hit
  /// Beam k's angle in the body frame (rad, counter-clockwise from body x).
  real lidar_beam_angle(int k) const;

  /// Ray-sensor images a task reads (navigation_task's pooled depth, a custom task's image_pool),
  /// the same shape on every backend: rigid gives each robot's ray sensors (lidar, ToF, camera; in
  /// the order of robot.sensors, IMUs skipped) as rendered by the World; planar gives its 2-D lidar
  /// as one image row. Column 0 is the leftmost (body +y side), row 0 the top.
  int num_range_images() const { return num_range_images_; }
  /// Robot i's k-th image (0 <= k < num_range_images()), valid until the next state change.
  virtual RangeImage range_image(int robot, int k) const = 0;

  /// True where the backend holds the robots at a fixed altitude (planar multirotor): tasks then
  /// drop vertical commands and measure errors in x and y only.
  bool holds_altitude() const { return holds_altitude_; }
  /// The held altitude (simulator.altitude_m) when holds_altitude(), else 0.
  real altitude_m() const { return altitude_m_; }

  /// Task-owned box obstacles: each box goes to the first obstacle slot of its asset class in env
  /// (the task reserves one class per object at creation, e.g. a cube class with keep_in_env and
  /// one asset), from now on until the next call or the class's next layout draw, and env's sensor
  /// images are re-rendered once. Rigid: a 3-D box, yaw about z; planar: its x / y footprint (the
  /// pre-created Box2D fixture is edited: no heap). False (nothing changed, last_error() says
  /// why) for a bad env or class, a class without box slots, or non-finite or non-positive sizes.
  [[nodiscard]] virtual bool set_obstacle_boxes(int env, const ObstacleBox* boxes, int count) = 0;
  [[nodiscard]] bool set_obstacle_box(int env, const ObstacleBox& box) { return set_obstacle_boxes(env, &box, 1); }

  /// In-step allocations that found their environment's fixed arena full and went to the heap
  /// (planar: Box2D's growth; see sim/src/backends/planar.cpp). 0 on rigid, which never allocates in a step.
  virtual std::uint64_t step_heap_fallbacks() const { return 0; }

  virtual WorldSummary summary() const = 0;
  /// True when env's current episode was placed by a fallback (no clear start / target / path
  /// within task.placement_attempts: the target is the start, the robot hovers). Tasks count such
  /// an episode apart (TaskInfos::fallback_episodes), never as a success.
  virtual bool placement_fallback(int env) const = 0;
  /// FNV-1a over every environment's state, in environment order (as World::state_hash).
  virtual std::uint64_t state_hash() const = 0;
  const std::string& last_error() const { return error_; }

 protected:
  explicit Simulator(Backend b) : backend_(b) {}
  /// Sizes every view for the config's robots (called by the backends' set-up).
  void allocate_views(const WorldConfig& cfg, int action_dim, int lidar_beams);
  /// Writes the views of robot i from a 3-D state (with_euler false: the Euler view is left to
  /// fill_lazy_views).
  void write_state_view(std::size_t i, const RigidBodyState& s, bool with_euler = true);
  /// Euler view of robot i from its quaternion view (the same bits as write_state_view's).
  void write_euler_view(std::size_t i) const;
  /// Runs the physics steps of every environment with the current actions.
  virtual void advance() = 0;
  /// reset_root_states after the common checks (env ids in range, every value finite, unit
  /// quaternions): the backend's own checks, then the writes; false (nothing written) on a refusal.
  [[nodiscard]] virtual bool set_root_states(const int* env_ids, int count, const real* pos_w, const real* quat_xyzw,
                                             const real* lin_vel_w, const real* ang_vel_w) = 0;
  /// Sets robot i's world-frame linear velocity x and y (push_robots).
  virtual void set_velocity_xy(int env, int robot, real vx_w, real vy_w) = 0;
  /// Derived views a backend computes on demand: flag them in lazy_ when the state changes and
  /// fill them in fill_lazy_views (the accessor calls it once per change).
  enum : std::uint8_t { kLazyEuler = 1, kLazyWrench = 2, kLazyScales = 4 };
  virtual void fill_lazy_views(std::uint8_t which) const { (void)which; }
  const real* fresh(std::uint8_t which, const std::vector<real>& v) const {
    if ((lazy_ & which) != 0) {
      fill_lazy_views(which);
      lazy_ = static_cast<std::uint8_t>(lazy_ & ~which);
    }
    return v.data();
  }
  bool fail(const std::string& m) {
    error_ = m;
    return false;
  }

  WorldConfig cfg_;
  Backend backend_;
  bool ground_vehicle_ = false;
  bool holds_altitude_ = false;
  real altitude_m_ = 0;
  int num_range_images_ = 0;
  bool actions_given_ = false;  // the current step() got an action array (rigid: else the World's own)
  int num_envs_ = 0, robots_per_env_ = 0, action_dim_ = 0, decimation_ = 1, lidar_beams_ = 0;
  std::vector<real> actions_;  // (robots x action_dim)
  std::vector<real> pos_w_, quat_xyzw_, lin_vel_b_, lin_vel_w_, ang_vel_b_, contact_w_, target_w_;
  mutable std::vector<real> euler_xyz_, wrench_b_;  // derived: may be filled on demand (lazy_)
  std::vector<std::uint8_t> crashed_, reset_buf_;
  std::vector<real> added_mass_kg_, com_bias_b_m_;
  mutable std::vector<real> motor_scale_, gain_scale_;
  mutable std::uint8_t lazy_ = 0;
  std::vector<real> lidar_;
  int num_dofs_ = 0, num_feet_ = 0, num_links_ = 0, num_height_points_ = 0;
  std::vector<real> dof_pos_, dof_vel_, torques_, feet_pos_w_, link_forces_w_, dr_kp_scale_, dr_kd_scale_;
  std::vector<real> dr_friction_, dr_restitution_, dr_armature_;
  int num_terrain_levels_ = 0;
  std::vector<int> terrain_levels_, terrain_types_;  // (envs)
  std::vector<real> env_origins_w_;                  // (envs x 3)
  std::vector<RngStream> rng_push_;
  RobotLayout layout_;
  ViewerRequest viewer_request_;
  ViewerHooks* viewer_ = nullptr;
  std::string error_;
};

/// Builds the backend resolve_backend() picks. nullptr and a message on bad input (nothing half-built).
std::unique_ptr<Simulator> make_simulator(const WorldConfig& config, std::string& error);
/// The same with an explicit backend (ignores KESTREL_SIMULATOR and config.simulator.backend).
std::unique_ptr<Simulator> make_simulator(const WorldConfig& config, Backend backend, std::string& error);

/// The scripted position-setpoint policy `kestrel run` uses through this interface: Lee position
/// control gets the target (x, y, z or the planar altitude, yaw 0); the ground vehicle gets pure
/// pursuit to the target (R. C. Coulter, "Implementation of the pure pursuit path tracking
/// algorithm", CMU-RI-TR-92-01, 1992: delta = atan(2 L sin(alpha) / d)) at a speed that tapers
/// to zero at the target. Writes num_robots x action_dim values; no heap.
void scripted_setpoint_actions(const Simulator& sim, real* actions);

/// `kestrel run` through this interface (sim/src/runtime/run_scripted.cpp): `steps` env-steps of
/// scripted_setpoint_actions, a summary, DIR/trajectory.csv and the state hash. Returns the exit code.
int run_scripted(Simulator& sim, const std::string& label, long long steps, const std::string& out_dir, bool quiet);

}  // namespace kestrel::sim
