// Plain configuration structs of the simulation harness, with documented defaults (Box2D's
// b2DefaultWorldDef habit): one source of truth per preset, validated once, read-only while the
// world steps. Field names follow Aerial Gym's env/sim/robot configs (ntnu-arl/aerial_gym_simulator,
// commit f0d0f05: aerial_gym/config/{sim,env,robot}_config) where a field has an Aerial Gym twin.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "kestrel/controllers/joint_pd.hpp"
#include "kestrel/robots/multirotor.hpp"
#include "kestrel/allocation/presets.hpp"
#include "kestrel/controllers/controller.hpp"
#include "kestrel/controllers/lee.hpp"
#include "kestrel/kernel/rigid_body.hpp"
#include "kestrel/kernel/types.hpp"
#include "kestrel/sensors/imu.hpp"
#include "kestrel/sensors/ray_sensor.hpp"
#include "kestrel/sim/limits.hpp"

namespace kestrel::sim {

/// Physics parameters (Aerial Gym's sim config: dt, substeps, gravity).
struct SimParams {
  std::string name = "base_sim";
  real dt_s = 0.01_r;           // physics step (Aerial Gym base_sim dt = 0.01 s)
  int substeps = 1;             // integrator sub-steps per physics step (dynamics only)
  Vec3 gravity_w = Vec3(0, 0, -kStandardGravity);  // m/s^2
  Integrator integrator = Integrator::semi_implicit_euler;  // PhysX (Isaac Gym) is semi-implicit
  // Penalty contact (spring-damper along the normal, clamped Coulomb friction).
  real contact_stiffness_N_m = 2000;  // a 0.25 kg quad resting sinks mg/k = 1.2 mm
  real contact_damping_N_s_m = 10;    // damping ratio ~0.2 for the base quadrotor
  real friction_coefficient = 0.5_r;
  real friction_damping_N_s_m = 10;   // viscous regularisation of Coulomb friction below the cone
  // Articulated robots' constraint solver (dynamics/contact.hpp): projected Gauss-Seidel sweeps at
  // most per physics step (warm-started; PhysX in legged_gym runs 4 position iterations).
  int solver_iterations = 60;
};

// convex_hull: a loaded mesh's vertices (obstacles only; see mesh.hpp).
enum class ShapeType : std::uint8_t { sphere = 0, box, capsule, cylinder, convex_hull };

/// Collision shape in the owner's frame (capsule/cylinder axis = local z).
struct ShapeSpec {
  ShapeType type = ShapeType::sphere;
  real radius_m = 0.2_r;                     // sphere / capsule / cylinder
  real half_length_m = 0;                    // capsule / cylinder: half length of the axis segment
  Vec3 half_extents_m = Vec3(0.1_r, 0.1_r, 0.1_r);  // box
};

/// One asset class (Aerial Gym asset config): how many, where (as ratios of the env bounds),
/// how oriented, which semantic id, whether the curriculum may remove it.
enum class AssetKind : std::uint8_t { tree = 0, panel, cube, rod, small_wall, wall, thin, sphere, mesh };
struct AssetClass {
  std::string name;
  AssetKind kind = AssetKind::cube;
  int num_assets = 1;            // maximum count (curriculum level 1)
  int min_num_assets = 1;        // count at curriculum level 0
  Vec3 min_position_ratio = Vec3(0.1_r, 0.1_r, 0.1_r);  // of (upper - lower) from lower bound
  Vec3 max_position_ratio = Vec3(0.9_r, 0.9_r, 0.9_r);
  Vec3 min_euler_rad = Vec3::Zero();  // orientation drawn uniformly in [min, max] (Euler XYZ)
  Vec3 max_euler_rad = Vec3::Zero();
  Vec3 min_size_m = Vec3(0.3_r, 0.3_r, 0.3_r);  // kind-specific (see sim/src/scene/layout.cpp)
  Vec3 max_size_m = Vec3(0.6_r, 0.6_r, 0.6_r);
  bool keep_in_env = false;      // true: the curriculum never removes it
  int semantic_id = 1;
  real max_speed_m_s = 0;        // dynamic environment: velocity drawn per reset in +-max
  real max_angular_speed_rad_s = 0;  // dynamic environment: world-frame angular velocity per reset in +-max
  std::string mesh_file;         // AssetKind::mesh: .obj/.stl loaded at World::create (size unused)
};

/// Terrain: the ground of every environment of a world (legged_gym's cfg.terrain; see
/// sim/terrain.hpp for the generators, the contact model and measured_heights).
///  plane:       the ground plane (create_ground_plane), as without terrain;
///  heightfield: a grid of heights from `heights_m` (YAML list), an image (PGM/PNG, pixel value x
///               vertical_scale_m) or a procedural generator; it replaces the ground plane;
///  trimesh:     triangles of an OBJ/STL file (outward = right-hand winding); replaces the plane.
enum class TerrainType : std::uint8_t { plane = 0, heightfield, trimesh };
struct TerrainConfig {
  TerrainType type = TerrainType::plane;
  std::string source_file;          // scenario file the terrain came from (error messages)
  // Heightfield grid: nx samples along x, ny along y, spacing horizontal_scale_m (legged_gym's
  // horizontal_scale). origin_m: world x-y of the grid centre and a z offset added to every height
  // (trimesh: a translation added to every vertex).
  real horizontal_scale_m = 0.1_r;
  real vertical_scale_m = 0.005_r;  // image pixel value -> metres (legged_gym's vertical_scale)
  Vec3 origin_m = Vec3::Zero();
  int nx = 0, ny = 0;
  std::vector<real> heights_m;      // (ny x nx), row j = y index j, from the YAML list
  std::string image_file;           // .pgm / .png heightmap (row 0 = largest y)
  std::string procedural;           // flat, slope, pyramid_slope, stairs, pyramid_stairs, random_uniform, wave
  real length_x_m = 8, width_y_m = 8;  // procedural grid size
  real slope = 0.2_r;               // slope, pyramid_slope: rise per metre (negative: down)
  real platform_size_m = 1;         // pyramid_*: flat top of this width
  real step_width_m = 0.3_r, step_height_m = 0.1_r;  // stairs, pyramid_stairs
  real min_height_m = -0.05_r, max_height_m = 0.05_r, height_step_m = 0.005_r, downsampled_scale_m = 0.2_r;  // random_uniform
  int num_waves = 2;                // wave
  real amplitude_m = 0.2_r;         // wave
  // curriculum / randomized (legged_gym's terrain.py curiculum() / randomized_terrain()): a grid of
  // num_rows x num_cols tiles of tile_length_m x tile_width_m inside a flat border; row i (along x)
  // is difficulty level i (curriculum: i / num_rows; randomized: drawn per tile), column j the
  // terrain type by the cumulative terrain_proportions of [smooth slope, rough slope, stairs up,
  // stairs down, discrete obstacles]. Robots start on a tile's centre (env_origins) at a level in
  // [0, max_init_terrain_level] and move between levels by Simulator::update_terrain_curriculum.
  int num_rows = 10, num_cols = 20;
  real tile_length_m = 8, tile_width_m = 8;
  std::vector<real> terrain_proportions = {0.1_r, 0.1_r, 0.35_r, 0.25_r, 0.2_r};
  real border_size_m = 25;
  int max_init_terrain_level = 5;
  std::string mesh_file;            // trimesh
  // measured_heights (legged_gym): heights sampled at these body-yaw-frame offsets around each robot.
  bool measure_heights = false;
  std::vector<real> measured_points_x_m = {-0.8_r, -0.7_r, -0.6_r, -0.5_r, -0.4_r, -0.3_r, -0.2_r, -0.1_r, 0,
                                           0.1_r,  0.2_r,  0.3_r,  0.4_r,  0.5_r,  0.6_r,  0.7_r,  0.8_r};
  std::vector<real> measured_points_y_m = {-0.5_r, -0.4_r, -0.3_r, -0.2_r, -0.1_r, 0, 0.1_r, 0.2_r, 0.3_r, 0.4_r, 0.5_r};
};

/// Environment config (Aerial Gym env config fields).
struct EnvConfig {
  std::string name = "empty";
  int num_envs = 1024;
  // A world that is one slice of a larger run (kestrel.cluster's rollout actors): its environment k
  // is global environment first_env_index + k of a run of total_num_envs (0: num_envs), so that its
  // random streams RngStream(seed, global index, purpose) and its place in an environment grid (the
  // articulated backend's origins) are those of the single-process run, whatever the split.
  int first_env_index = 0;
  int total_num_envs = 0;
  /// The global index of local environment `local` (the env key of every per-environment stream).
  std::uint32_t global_env(int local) const { return static_cast<std::uint32_t>(first_env_index + local); }
  /// Environments of the whole run this world is a slice of.
  int run_num_envs() const { return total_num_envs > 0 ? total_num_envs : num_envs; }
  real num_physics_steps_per_env_step_mean = 1;
  real num_physics_steps_per_env_step_std = 0;
  // Bounds, re-sampled per reset: lower in [lower_min, lower_max], upper in [upper_min, upper_max].
  Vec3 lower_bound_min_m = Vec3(-5, -5, 0);
  Vec3 lower_bound_max_m = Vec3(-5, -5, 0);
  Vec3 upper_bound_min_m = Vec3(5, 5, 5);
  Vec3 upper_bound_max_m = Vec3(5, 5, 5);
  bool reset_on_collision = true;
  real collision_force_threshold_N = 0.05_r;
  bool create_ground_plane = true;
  int keep_same_env_for_num_episodes = 1;   // obstacles re-sampled every k-th reset of an env
  bool sample_timestep_for_latency = false; // per-env action latency in physics steps, per reset
  int max_latency_physics_steps = 2;
  bool perturb_observations = false;        // Gaussian noise on what the controller sees
  real observation_noise_position_m = 0.01_r;
  real observation_noise_velocity_m_s = 0.01_r;
  // Random force/torque disturbances (Aerial Gym robot config `disturbance`).
  bool enable_disturbance = false;
  real prob_apply_disturbance = 0.05_r;
  Vec3 max_force_disturbance_N = Vec3(0.75_r, 0.75_r, 0.75_r);
  Vec3 max_torque_disturbance_Nm = Vec3(0.004_r, 0.004_r, 0.004_r);
  real curriculum_level = 1;   // 0..1: obstacle count between min_num_assets and num_assets
  std::vector<AssetClass> assets;   // include_asset_type: the classes present
  TerrainConfig terrain;            // `terrain:` (default: the ground plane)
};

/// One sensor attached to the robot (sensors registry entry; Aerial Gym's robot config
/// sensor_config: enable_camera / camera_config, enable_lidar / lidar_config, enable_imu / imu_config).
/// The ToF (VL53L5CX) is a small lidar grid, so it is a lidar here too.
enum class SensorKind : std::uint8_t { lidar = 0, camera, imu };
struct SensorConfig {
  std::string name;
  SensorKind kind = SensorKind::camera;
  sensors::LidarParams lidar;    // kind lidar
  sensors::CameraParams camera;  // kind camera
  sensors::ImuParams imu;        // kind imu
  // Ray sensors render every `every_env_steps` env-steps (a 30 Hz camera on a 100 Hz env-step
  // loop); the IMU updates every physics step whatever this says (it integrates the dynamics).
  int every_env_steps = 1;
};

/// Robot config: dynamics, airframe, motors, controller, collision shape.
struct RobotConfig {
  std::string name = "base_quadrotor";
  // What chain drives it (set by the robot preset; a type, never a name compare).
  robots::RobotKind kind = robots::RobotKind::multirotor;
  int robots_per_env = 1;
  allocation::AirframePreset airframe = allocation::AirframePreset::base_quadrotor;
  real mass_kg = 0.25_r;
  Vec3 inertia_diag_kg_m2 = Vec3(8.45e-4_r, 8.45e-4_r, 1.69e-3_r);
  Vec3 linear_drag_b = Vec3::Zero();
  Vec3 quadratic_drag_b = Vec3::Zero();
  Vec3 angular_drag_b = Vec3::Zero();
  Vec3 quadratic_angular_drag_b = Vec3::Zero();
  ShapeSpec shape;  // default: sphere of 0.2 m radius around the base quadrotor
  // Rotor geometry read from a URDF (sim/urdf.hpp). Non-empty: replaces the airframe preset's
  // rotors (count, hub positions, thrust axes, spin directions); the thrust limits, reaction-torque
  // ratio and motor model constants stay the preset's.
  std::vector<allocation::RotorSpec> rotors;
  std::vector<std::int8_t> rotor_directions;  // +1 / -1 per rotor (see airframe.hpp)
  // Start state as ratios of the env bounds (Aerial Gym robot config min/max_init_state ratios).
  Vec3 min_init_position_ratio = Vec3(0.1_r, 0.1_r, 0.1_r);
  Vec3 max_init_position_ratio = Vec3(0.2_r, 0.9_r, 0.9_r);
  real max_init_yaw_rad = kPi;
  // Start velocities: each world-frame velocity component drawn in [-max, max] m/s and each
  // world-frame angular rate in [-max, max] rad/s (Aerial Gym's init_config draws both in +-0.2).
  // 0: a start at rest and no draws, so the reset streams of other scenes are unchanged.
  real max_init_linvel_m_s = 0;
  real max_init_angvel_rad_s = 0;
  bool use_desaturation = true;  // sequential desaturation; false: Aerial Gym's clamped pinv
  std::vector<SensorConfig> sensors;  // none by default: the default run renders nothing
  // kind articulated: the robot file (MJCF or URDF, sim/articulated_robot.hpp) and its joint drive,
  // legged_gym's P mode: tau = joint_kp (action_scale a + q_home - q) - joint_kd qd, clipped at the
  // file's effort limits, recomputed every physics step (the home pose is the file's `home` keyframe).
  std::string model_file;
  real joint_kp_Nm_rad = 20;      // legged_gym's Go2 stiffness
  real joint_kd_Nms_rad = 0.5_r;  // and damping
  real action_scale = 0.25_r;     // rad per unit of action
  JointControlMode joint_control_mode = JointControlMode::position;  // legged_gym's control_type P, V or T
  int joint_delay_steps = 0;      // physics steps between an action and its torques (the PD's delay line)
  // legged_gym's Kp / Kd randomisation: per reset, the gains x a scale drawn in [min, max].
  real joint_kp_scale_min = 1, joint_kp_scale_max = 1;
  real joint_kd_scale_min = 1, joint_kd_scale_max = 1;
  // The actuated joints' passive dynamics, replacing the robot file's where >= 0 (-1: the file's).
  // legged_gym's assets have none (URDF <dynamics> zero, asset.armature 0); the MJCF files carry
  // MuJoCo Menagerie's (Go2: damping 2 N m s/rad, frictionloss 0.2 N m, armature 0.01 kg m^2).
  real joint_damping_Nms_rad = -1;
  real joint_friction_loss_Nm = -1;
  real joint_armature_kg_m2 = -1;
  // Contacts between the robot's own links (legged_gym's asset.self_collisions; off by default as
  // the issue and legged_gym's ANYmal configuration have it): every pair of collision geoms on two
  // links that no joint connects directly, filtered by the file's contype / conaffinity bits as
  // MuJoCo filters them.
  bool self_collisions = false;
};

/// Controller config: registry name -> kind, and the Lee family's parameters (LeeParams: gain
/// ranges, yaw-rate limit, action clip; mass, inertia and gravity come from the robot and the sim).
/// Defaults: Aerial Gym's lee_controller_config (lee_params_base_quadrotor). The nominal gain of
/// each axis is the midpoint of [min, max] (what flies unless randomize_gains draws per reset); a
/// scenario's `k_pos: [x, y, z]` sets min = max (a fixed gain). A base_rov airframe keeps the ROV
/// preset (lee_params_rov).
struct ControllerConfig {
  std::string name = "lee_position_control";
  ControllerKind kind = ControllerKind::lee_position;
  bool randomize_gains = false;
  Vec3 k_pos_min = lee_gain_ranges_default().min.k_pos.map(), k_pos_max = lee_gain_ranges_default().max.k_pos.map();  // (m/s^2) per m
  Vec3 k_vel_min = lee_gain_ranges_default().min.k_vel.map(), k_vel_max = lee_gain_ranges_default().max.k_vel.map();  // (m/s^2) per m/s
  Vec3 k_rot_min = lee_gain_ranges_default().min.k_rot.map(), k_rot_max = lee_gain_ranges_default().max.k_rot.map();  // N m per unit of e_R
  Vec3 k_angvel_min = lee_gain_ranges_default().min.k_angvel.map(), k_angvel_max = lee_gain_ranges_default().max.k_angvel.map();  // N m per rad/s
  real max_yaw_rate_rad_s = kPi / 3;  // LeeParams::max_yaw_rate_radps
  real action_min = -10, action_max = 10;  // every action component clipped to [min, max]
};

/// Task: what actions the robots get and how success is measured.
enum class TaskKind : std::uint8_t { hover = 0, position_setpoint };
/// A curriculum over the obstacle count (task.curriculum): Aerial Gym's
/// navigation_task_config.curriculum. Every check_after_episodes ended episodes the level moves up
/// by increase_step when the success rate over them exceeds success_rate_for_increase, down by
/// decrease_step below success_rate_for_decrease, within [min_level, max_level]; the level maps
/// linearly onto env.curriculum_level (min_level -> 0, max_level -> 1). increase_step =
/// decrease_step = 0 holds it (an evaluation at the top level: start_level = max_level).
struct CurriculumConfig {
  int min_level = 0, max_level = 10;
  int start_level = 0;            // the reference starts at min_level
  int check_after_episodes = 64;  // check_after_log_instances (2048 for 1024 GPU envs)
  int increase_step = 2, decrease_step = 1;
  real success_rate_for_increase = 0.7_r, success_rate_for_decrease = 0.6_r;
};

/// navigation_task's reward constants (task.navigation.reward): Aerial Gym's
/// navigation_task_config.reward_parameters, evaluated in float32 in its expression order.
struct NavigationRewardParams {
  real pos_reward_magnitude = 5.0f, pos_reward_exponent = 1.0f / 3.5f;
  real very_close_to_goal_reward_magnitude = 5.0f, very_close_to_goal_reward_exponent = 2.0f;
  real getting_closer_reward_multiplier = 10.0f;
  real x_action_diff_penalty_magnitude = 0.8f, x_action_diff_penalty_exponent = 3.333f;
  real z_action_diff_penalty_magnitude = 0.8f, z_action_diff_penalty_exponent = 5.0f;
  real yawrate_action_diff_penalty_magnitude = 0.8f, yawrate_action_diff_penalty_exponent = 3.33f;
  real x_absolute_action_penalty_magnitude = 0.1f, x_absolute_action_penalty_exponent = 0.3f;
  real z_absolute_action_penalty_magnitude = 1.5f, z_absolute_action_penalty_exponent = 1.0f;
  real yawrate_absolute_action_penalty_magnitude = 1.5f, yawrate_absolute_action_penalty_exponent = 2.0f;
  real collision_penalty = -100.0f;
  // Not in the reference (0 turns it off, the default): a penalty per env-step while the nearest
  // range of the robot's range image is within clearance_m, growing linearly from 0 there to
  // clearance_penalty at range 0 (training shaping: it teaches a margin from obstacles the forward
  // view is about to lose at its edge, where most crashes of trained policies happen).
  real clearance_penalty = 0.0f;
  real clearance_m = 1.0f;
  // Not in the reference (0 turns it off, the default): the reward per env-step per m/s of the
  // vehicle's sideways speed |v_y| (body frame) after the step (training shaping: with
  // forward-only commands the velocity lags the heading while the vehicle turns, and trained
  // policies skid into obstacles their view has already passed; stop 43's crash geometry in
  // bench/results/python/README.md).
  real sideslip_penalty = 0.0f;
};

/// How navigation_task's actions become the velocity controller's [vx, vy, vz, yaw_rate] command.
/// forward_inclination (Aerial Gym's navigation_task_config.action_transformation_function): 3
/// actions in [-1, 1]: speed (a0 + 1) / 2 x max_speed_m_s along the body's heading, tilted up or
/// down by a1 x max_inclination_rad, and a2 x max_yaw_rate_rad_s; never sideways or backwards, so
/// the vehicle moves where its forward sensor looks. velocity: 4 actions, each x its maximum.
enum class NavigationActionSpace : std::uint8_t { forward_inclination = 0, velocity };
/// What each image cell of navigation_task's observation holds for the nearest range r (m) of its
/// block. range: r / max_range_m in [0, 1] (1: nothing within range). proximity: 1 / (1 + r /
/// proximity_scale_m), 1 at contact and falling off with distance, so that the ranges an
/// avoidance decision turns on (a few tenths of a metre to two metres) span most of [0, 1]
/// instead of its bottom fifth (the reference feeds its depth image through a VAE instead).
enum class NavigationImageEncoding : std::uint8_t { range = 0, proximity };
/// navigation_task's action scaling, image pooling and reward (task.navigation).
struct NavigationConfig {
  NavigationActionSpace action_space = NavigationActionSpace::forward_inclination;
  real max_speed_m_s = 2.0f;              // forward_inclination: the top speed; velocity: per axis
  real max_inclination_rad = 0.78539816f; // pi / 4 (forward_inclination)
  real max_yaw_rate_rad_s = 1.0471976f;   // pi / 3
  int pool_rows = 8, pool_cols = 8;       // the range image min-pooled to rows x cols cells
  NavigationImageEncoding image_encoding = NavigationImageEncoding::range;
  real proximity_scale_m = 0.5f;          // proximity: the range that reads 0.5
  // The image cells of image_history_frames earlier moments, image_history_lag_env_steps apart,
  // appended after the current image (0: none, the reference's observation).
  int image_history_frames = 0, image_history_lag_env_steps = 10;
  NavigationRewardParams reward;
};

/// position_setpoint_task's reward constants (task.reward): Aerial Gym's position_setpoint_task
/// compute_reward, d = |target - position|, tilt = |1 - up_z|, s = |body rates|:
///   pos = pos_reward_magnitude_1 exp(-pos_reward_exponent_1 d^2) + pos_reward_magnitude_2 exp(-pos_reward_exponent_2 d^2)
///   dist = (distance_reward_offset_m - d) / distance_reward_divisor_m
///   up = up_reward_magnitude / (up_reward_offset + tilt^2), spin = spin_reward_magnitude / (1 + s^2)
///   reward = pos + dist + pos (up + spin); crash_reward where crashed or d > crash_distance_m.
/// Evaluated in float32; the defaults reproduce the reference bit for bit.
struct PositionSetpointRewardParams {
  real pos_reward_magnitude_1 = 3.0f, pos_reward_exponent_1 = 8.0f;
  real pos_reward_magnitude_2 = 2.0f, pos_reward_exponent_2 = 4.0f;
  real distance_reward_offset_m = 20.0f, distance_reward_divisor_m = 40.0f;
  real up_reward_magnitude = 0.2f, up_reward_offset = 0.1f;
  real spin_reward_magnitude = 3.0f;
  real crash_distance_m = 8.0f;
  real crash_reward = -20.0f;
};

/// locomotion_task's reward scales (task.locomotion.scales): legged_gym's LeggedRobotCfg.rewards.scales
/// (per second: each is multiplied by the policy step, sim dt x decimation, as legged_gym's
/// _prepare_reward_function does; a zero scale leaves its term out). Defaults: legged_gym's.
struct LocomotionRewardScales {
  real termination = 0, tracking_lin_vel = 1, tracking_ang_vel = 0.5_r, lin_vel_z = -2, ang_vel_xy = -0.05_r;
  real orientation = 0, torques = -1e-5_r, dof_vel = 0, dof_acc = -2.5e-7_r, base_height = 0;
  real feet_air_time = 1, collision = -1, feet_stumble = 0, action_rate = -0.01_r, stand_still = 0;
  real dof_pos_limits = 0, torque_limits = 0, feet_contact_forces = 0;
};

/// locomotion_task (legged_gym's LeggedRobot task over an articulated robot, task.locomotion):
/// velocity commands, observation scales and noise, reward parameters and pushes. Defaults:
/// legged_gym's LeggedRobotCfg (legged_robot_config.py).
struct LocomotionConfig {
  // commands: lin_vel_x, lin_vel_y (m/s, body frame), ang_vel_yaw (rad/s), heading (rad)
  real resampling_time_s = 10;
  bool heading_command = true;  // the yaw-rate command is 0.5 x the heading error, clipped to +-1
  real lin_vel_x_min_m_s = -1, lin_vel_x_max_m_s = 1;
  real lin_vel_y_min_m_s = -1, lin_vel_y_max_m_s = 1;
  real ang_vel_yaw_min_rad_s = -1, ang_vel_yaw_max_rad_s = 1;
  real heading_min_rad = -3.14_r, heading_max_rad = 3.14_r;
  // normalization
  real obs_scale_lin_vel = 2, obs_scale_ang_vel = 0.25_r, obs_scale_dof_pos = 1, obs_scale_dof_vel = 0.05_r;
  real obs_scale_height = 5;
  real clip_observations = 100;
  // noise: uniform in +-(scale x noise_level x the observation's scale)
  bool add_noise = true;
  real noise_level = 1;
  real noise_lin_vel = 0.1_r, noise_ang_vel = 0.2_r, noise_gravity = 0.05_r, noise_dof_pos = 0.01_r, noise_dof_vel = 1.5_r;
  real noise_height = 0.1_r;
  // rewards
  bool only_positive_rewards = true;
  real tracking_sigma = 0.25_r;
  real soft_dof_pos_limit = 1, soft_torque_limit = 1;
  real base_height_target_m = 1;
  real max_contact_force_N = 100;
  LocomotionRewardScales scales;
  // body-name fragments (case-insensitive) whose ground contact the collision term counts
  std::vector<std::string> penalize_contacts_on = {"thigh", "calf", "shank"};
  // domain randomisation of the task (the robot's own: robot.joint_kp_scale, ...)
  bool push_robots = true;
  real push_interval_s = 15;  // every robot pushed (simulator.max_push_vel_xy_m_s) this often
  real reset_dof_pos_scale_min = 0.5_r, reset_dof_pos_scale_max = 1.5_r;  // dof_pos = home x U(min, max)
  real reset_base_vel_max = 0.5_r;  // base linear and angular velocity components U(-max, max) at reset
  // legged_gym's terrain curriculum (terrain.curriculum, on a tiled terrain: env.terrain.procedural
  // curriculum / randomized): at each episode's end the robot moves a level up if it walked farther
  // than half a tile from its origin, down if less than half of what its command asked over the
  // episode (Simulator::update_terrain_curriculum); ignored on other terrains.
  bool terrain_curriculum = true;
  // LeggedGym-Ex's push_links: every link pushed (simulator.max_push_force_N) this often (0: never).
  real push_links_interval_s = 0;
};

/// so101_pick_place's action space (task.pick_place.action_mode).
enum class PickPlaceActionMode : std::uint8_t {
  joint_position = 0,  // 6 absolute joint targets (rad): LeIsaac's joint position action
  ee_delta = 1,        // tool-centre-point delta x, y, z (m), yaw delta (rad), gripper target (rad): teleoperation
};

/// so101_pick_place (sim/pick_place_task.hpp, task.pick_place): the scene's parameters (the
/// defaults are sim/pick_place.hpp's PickPlaceConfig), the action mode and the shaped reward's
/// weights. The episode length is task.episode_len_env_steps (1000 = 20 s at the 50 Hz action rate).
struct PickPlaceTaskConfig {
  PickPlaceActionMode action_mode = PickPlaceActionMode::joint_position;
  // physics
  real dt_s = 0.005_r;
  int decimation = 4;
  int solver_iterations = 60;
  real arm_kp_Nm_rad = 998.22_r, arm_kd_Nms_rad = 2.73_r;
  real gripper_kp_Nm_rad = 20, gripper_kd_Nms_rad = 0.5_r;
  // objects
  real cube_half_m = 0.0125_r, cube_mass_kg = 0.011_r, cube_friction = 1;
  Vec3 cube_pos_w = Vec3(0.20_r, 0, 0);
  Vec3 box_pos_w = Vec3(0.20_r, 0.15_r, 0);
  real box_inner_half_m = 0.05_r, box_wall_m = 0.005_r, box_height_m = 0.04_r;
  real box_friction = 0.6_r, table_friction = 0.5_r;
  // The arm's robot file ("" = models/so101/so101.xml); a USD scene's kestrel:robotFile
  // (kestrel.pick_place_scene maps a scene file onto these keys).
  std::string robot_file;
  real randomize_xy_m = 0.05_r;
  real success_xy_m = 0.05_r, success_height_m = 0.10_r;
  // success: cube_in_box with the pads' force on the cube below release_force_N, held this many
  // consecutive action steps
  int success_hold_steps = 10;
  real release_force_N = 0.1_r;
  // false: success neither ends nor pays (the bonus) an episode: a caller's own terms decide
  // (kestrel.SceneTask, LeIsaac's way of writing terminations in Python)
  bool end_on_success = true;
  // ee_delta: per-action clips of the deltas
  real ee_max_delta_m = 0.02_r;
  real ee_max_yaw_delta_rad = 0.2_r;
  // shaped reward (per action step): reach, grasp, lift, place, success (see pick_place_task.hpp)
  real reach_weight = 1, reach_scale_m = 0.05_r;
  real grasp_weight = 1, grasp_force_N = 0.5_r;
  real lift_weight = 2, lift_height_m = 0.05_r;
  real place_weight = 2, place_scale_m = 0.05_r;
  real success_reward = 50;
};

struct TaskConfig {
  std::string name = "position_setpoint";
  TaskKind kind = TaskKind::position_setpoint;
  int episode_len_env_steps = 500;
  Vec3 min_target_ratio = Vec3(0.7_r, 0.1_r, 0.2_r);  // targets as ratios of the bounds
  Vec3 max_target_ratio = Vec3(0.9_r, 0.9_r, 0.8_r);
  real success_radius_m = 0.3_r;
  // Placement of the start and the target (Aerial Gym draws both uniformly in their ratio boxes;
  // with a straight-line position controller that puts targets inside or behind trees, so nearly
  // every episode of the forest ended in a crash). Each reset draws placement_attempts candidate
  // (start, target) pairs and keeps the first whose start and target clear every obstacle by
  // clearance_m (beyond the robot's bounding sphere) and, with line_of_sight, whose straight
  // segment between them does too. See World::reset_env.
  real clearance_m = 0.3_r;
  bool line_of_sight = true;
  int placement_attempts = 16;   // 1..kMaxPlacementAttempts
  // 0: the action is the target itself from the first step (Aerial Gym's position setpoint). > 0:
  // the setpoint given to lee_position_control moves from the start towards the target along the
  // straight (line-of-sight) path at this speed, so the robot follows the checked path instead of
  // the saturated, curved response to a step of several metres (up to ~2 m off the line for a
  // 10 m step with the default Lee gains).
  real setpoint_speed_m_s = 0;
  CurriculumConfig curriculum;  // read by the tasks with a curriculum (navigation_task)
  NavigationConfig navigation;  // read by navigation_task
  LocomotionConfig locomotion;  // read by locomotion_task
  PickPlaceTaskConfig pick_place;  // read by so101_pick_place
  PositionSetpointRewardParams reward;  // read by position_setpoint_task (navigation_task: navigation.reward)
};
constexpr int kMaxPlacementAttempts = 64;  // candidates live on the stack of reset_env

/// The physics backend behind sim/simulator.hpp and its options (scenario `simulator:`).
/// backend: "rigid" (the 3-D World) or "planar" (Box2D); empty = the KESTREL_SIMULATOR environment
/// variable, else rigid (resolved once, by make_simulator). The planar fields are read by the
/// planar backend only (sim/src/planar*.cpp).
/// automatic: ground_vehicle for the robot "ground_vehicle", multirotor for any other robot.
enum class PlanarVehicle : std::uint8_t { automatic = 0, ground_vehicle, multirotor };
struct SimulatorConfig {
  std::string backend;               // "", "rigid" or "planar"
  real max_push_vel_xy_m_s = 1;      // push_robots: v_x, v_y drawn in [-max, max] (legged_gym)
  PlanarVehicle vehicle = PlanarVehicle::automatic;
  real wheelbase_m = 0.33_r;         // ground vehicle (VelocitySteeringParams)
  real max_speed_m_s = 3;
  real max_steering_rad = 0.4_r;
  real altitude_m = 1;               // multirotor: fixed flight height
  int lidar_beams = 0;               // 2-D lidar: 0 = none
  real lidar_fov_rad = 4.71238898_r; // 270 deg, centred on body x
  real lidar_max_range_m = 10;
  // Domain randomisation per reset (planar and articulated robots): uniform in [min, max].
  // Planar: the body's mass and its centre of mass in x and y. Articulated (legged_gym's
  // randomize_base_mass / LeggedGym-Ex's randomize_com_displacement): the root body's mass and
  // its centre of mass in x, y and z, the rest of its inertia kept (as legged_gym does).
  real added_mass_min_kg = 0, added_mass_max_kg = 0;
  real com_bias_max_m = 0;           // centre-of-mass offset in [-max, max] per axis (body frame)
  // Articulated robots only (legged_gym's randomize_friction / restitution, LeggedGym-Ex's
  // randomize_joint_armature), drawn per robot at each reset; -1 (both ends): not randomised.
  // friction: every contact of the robot with the ground gets this Coulomb coefficient (else the
  // mean of the shape's and the ground's); restitution: likewise, in [0, 1] (else the mean);
  // joint_armature: each actuated joint's rotor inertia, drawn per joint (kg m^2; else the file's
  // or robot.joint_armature_kg_m2).
  real friction_min = -1, friction_max = -1;
  real restitution_min = -1, restitution_max = -1;
  real joint_armature_min_kg_m2 = -1, joint_armature_max_kg_m2 = -1;
  // push_links (LeggedGym-Ex): every link of every robot gets a force with components drawn in
  // [-max, max] at its centre of mass during the next physics step.
  real max_push_force_N = 0;
  real motor_scale_min = 1, motor_scale_max = 1;  // motor/drive constant scale
  real gain_scale_min = 1, gain_scale_max = 1;    // controller gain scale
};

/// Everything a world is built from.
struct WorldConfig {
  SimParams sim;
  EnvConfig env;
  RobotConfig robot;
  ControllerConfig controller;
  TaskConfig task;
  SimulatorConfig simulator;  // backend selection (sim/simulator.hpp)
  std::uint64_t seed = 0;
  int num_threads = 1;
  // Set-up refuses a world whose estimated memory exceeds this (scenario `max_memory_gib`,
  // kestrel run --max-memory-gib; see sim/limits.hpp).
  double max_memory_gib = kDefaultMaxMemoryGiB;
};

/// Robots per asset link: a tree is a trunk and this many branches (one obstacle slot each).
constexpr int kTreeBranches = 3;
/// Obstacle slots an asset class needs at most (scene layout of every backend).
int asset_class_slots(const AssetClass& c);

}  // namespace kestrel::sim
