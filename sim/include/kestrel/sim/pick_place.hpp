// LeIsaac's SO-101 task, "pick up the red cube and place it into the box", as one environment: the
// arm (a robot file, models/so101/so101.xml) and the cube as one forest of the core's articulated
// dynamics (dynamics/multibody.hpp: the arm on its fixed base, the cube a free body of its own),
// stepped by the core's constrained step with contacts between them (dynamics/contact.hpp): the
// cube is held by the pads' contact forces and Coulomb friction alone, no weld, no attachment.
//
// The scene (models/so101/pick_place_scene.usda, read by kestrel.usd_scene; its numbers are the
// defaults below): the table top is the plane z = 0, the robot's base at the origin reaching along
// +x, the cube on the table and an open box (a floor and four walls, static boxes) beside it.
//
// One physics step: the servos' torques tau = clip(kp (q* - q) - kd qd, +-effort) on the six
// joints (kp, kd taken implicitly while unclipped, as the articulated backend), then contacts:
// every collision primitive of the arm against the cube (two-body contacts), the table and the
// box's parts; the cube against the table and the box's parts. Actions are absolute joint targets
// (LeIsaac's "joint position" action), held over `decimation` physics steps.
//
// LeIsaac's terms: cube_in_box (the cube's centre within +-0.05 m of the box's centre in x and y
// and below 0.10 m above the table) and randomize_object_uniform (cube and box positions uniform
// within +-0.05 m in x and y at every reset, from the environment's own random stream).
//
// Determinism: one environment's state is a function of its seed, its index and its actions. No
// heap inside reset or step: every array is sized by init.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "kestrel/dynamics/contact.hpp"
#include "kestrel/dynamics/ik.hpp"
#include "kestrel/kernel/rng.hpp"
#include "kestrel/sim/articulated_robot.hpp"

namespace kestrel::sim {

/// Random stream purpose of the pick-and-place object poses (above kPurposeUser; distinct from
/// simulator.hpp's and the tasks').
constexpr std::uint32_t kPurposeObjectPose = kPurposeUser + 20;

struct PickPlaceConfig {
  std::string robot_file;  // "" = models_dir() + "/so101/so101.xml"
  real dt_s = 0.005_r;     // physics step
  int decimation = 4;      // physics steps per action (30 Hz control at dt 1/120 s is LeIsaac's; 50 Hz here)
  int solver_iterations = 60;
  // The servos (STS3215, position mode): the file's effort limit; the gains per joint, arm then
  // gripper. kp: the file's 998 N m/rad (Menagerie) is stiff; kd: Menagerie's kv 2.73 N m s/rad.
  real arm_kp_Nm_rad = 998.22_r;
  real arm_kd_Nms_rad = 2.73_r;
  // The gripper softer, so that closing on the cube squeezes it by kp x the remaining angle
  // rather than by the full effort limit.
  real gripper_kp_Nm_rad = 20;
  real gripper_kd_Nms_rad = 0.5_r;
  // The cube: 25 mm, 11 g (beech or PLA), rubbery enough to grip.
  real cube_half_m = 0.0125_r;
  real cube_mass_kg = 0.011_r;
  real cube_friction = 1;
  Vec3 cube_pos_w = Vec3(0.20_r, 0, 0);  // centre x, y (z: resting on the table)
  // The box: inner 10 x 10 cm, walls 5 mm thick and 4 cm tall, a 5 mm floor.
  Vec3 box_pos_w = Vec3(0.20_r, 0.15_r, 0);  // centre of its floor's bottom face
  real box_inner_half_m = 0.05_r;
  real box_wall_m = 0.005_r;
  real box_height_m = 0.04_r;
  real box_friction = 0.6_r;
  real table_friction = 0.5_r;
  real randomize_xy_m = 0.05_r;  // randomize_object_uniform's +- range in x and y (0: none)
  // cube_in_box: LeIsaac's thresholds.
  real success_xy_m = 0.05_r;
  real success_height_m = 0.10_r;
};

/// What a scene shape belongs to (its colour in a camera image, its name in a segmentation).
enum class PickPlaceEntity : std::uint8_t { table = 0, robot = 1, cube = 2, box = 3 };

/// A collision shape of the scene in the world at the current state: the primitive (its p_b, R_b
/// in its body's frame, or the world's for the box's parts) and its body's pose (world -> body,
/// forward_kinematics's; the identity for a world shape). The table is the plane z = 0.
struct PickPlaceShape {
  dynamics::CollisionShape shape;
  dynamics::Transform X_body;
  PickPlaceEntity entity = PickPlaceEntity::robot;
  int index = 0;  // within its entity (the arm's shapes in file order, the box's parts 0-4)
};

/// Tool-centre-point pose of the arm and the cube's pose, the task's observations beside q, qd.
struct PickPlaceState {
  Vec3 tcp_pos_w = Vec3::Zero();
  Mat3 tcp_R_w = Mat3::Identity();
  Vec3 cube_pos_w = Vec3::Zero();
  Vec4 cube_quat_xyzw = Vec4(0, 0, 0, 1);
  Vec3 box_pos_w = Vec3::Zero();
};

class PickPlaceWorld {
 public:
  static constexpr int kJoints = 6;  // shoulder_pan, shoulder_lift, elbow_flex, wrist_flex, wrist_roll, gripper
  static constexpr int kMaxContacts = 48;

  PickPlaceWorld();
  ~PickPlaceWorld();
  PickPlaceWorld(const PickPlaceWorld&) = delete;
  PickPlaceWorld& operator=(const PickPlaceWorld&) = delete;

  /// Loads the robot file and builds the scene. False with a message naming the file or the field.
  [[nodiscard]] bool init(const PickPlaceConfig& c, std::uint64_t seed, std::uint32_t env_index, std::string& error);

  /// A new episode: the arm at its `home` keyframe at rest, the cube and the box at their
  /// randomised positions (randomize_object_uniform), the cube resting on the table.
  void reset();
  /// One action: absolute joint targets (rad) for the six joints, clamped into the joints'
  /// ranges, held for `decimation` physics steps. A non-finite target holds the previous one.
  /// Status of the last physics step (ok, or the core's refusal, which leaves the state alone).
  Status step(const real* joint_targets_rad);

  bool cube_in_box() const;
  const PickPlaceState& state() const { return state_; }
  const real* joint_pos() const { return q_; }   // the arm's six, q order
  const real* joint_vel() const { return qd_; }
  const real* joint_targets() const { return target_; }
  const real* home() const { return home_; }
  const real* joint_lower() const { return lower_; }
  const real* joint_upper() const { return upper_; }
  /// The contact forces' sum on the cube from the two pads (N), the last physics step.
  real grip_force_N() const { return grip_force_N_; }
  int contacts() const { return num_contacts_; }
  int solver_iterations_used() const;
  const PickPlaceConfig& config() const { return cfg_; }
  const ArticulatedRobot& robot() const { return robot_; }
  /// The arm's joint angles that put the tool centre point at p_w pointing straight down, its
  /// pads' faces normal to the world's x (yaw 0) or y (yaw pi/2) as `yaw_rad` says: damped least
  /// squares (dynamics/ik.hpp) from `q_start` (six angles). Returns the position error (m).
  real solve_tcp(const Vec3& p_w, real yaw_rad, const real* q_start, real* q_out) const;
  /// The scene's shapes at the current state (the arm's, the cube, the box's five parts; the table
  /// is the plane z = 0): writes at most `capacity`, returns how many there are.
  int scene_shapes(PickPlaceShape* out, int capacity) const;
  /// A body's pose at the current state (world -> body; -1: the identity). The tool centre point's
  /// body is tcp_body().
  dynamics::Transform body_pose(int body) const;
  int tcp_body() const { return tcp_body_; }
  /// Places the cube at p_w (centre) with orientation quat_xyzw, at rest: for tests.
  void set_cube_pose(const Vec3& p_w, const Vec4& quat_xyzw);
  /// Moves the box (its floor and four walls together) so that its floor's bottom-face centre is
  /// at p_w (z 0: standing on the table), as randomize_object_uniform does for the box; the cube,
  /// the arm and their velocities are left alone (a cube inside the box stays where it is). A
  /// non-finite p_w is ignored. state().box_pos_w and cube_in_box() follow at once.
  void set_box_position(const Vec3& p_w);
  std::uint64_t state_hash() const;

  /// step() for several worlds at once: at each physics step their constrained steps go through
  /// the batched articulated step, one world per SIMD lane (sim/src/backends/articulated_batch.hpp;
  /// 16 lanes with AVX-512, 8 with AVX2, 4 otherwise), which gives every world the bits its own
  /// step() gives it. A world the batch cannot take at a physics step (more than its 32 contacts)
  /// takes the scalar step there; worlds whose contacts together overflow the batch's 32 slots go
  /// as two halves. The worlds come from one PickPlaceConfig. They step one at a time where
  /// count > batch_lanes(), where count is under a third of the lanes (faster so: a batch does its
  /// whole width's work) or without scratch. scratch: batch_scratch_bytes() (AlignedScratch), one
  /// per thread. status[i]: what step() returns. Returns the physics steps the batch took (the
  /// rest were scalar).
  static int step_batch(PickPlaceWorld* const* worlds, const real* const* joint_targets_rad, int count, Status* status, void* scratch);
  /// Worlds step_batch() takes at once (0: none: the double build).
  int batch_lanes() const;
  static std::size_t batch_scratch_bytes();

 private:
  static constexpr int kDofs = dynamics::max_dofs<kMaxRobotBodies>();
  void set_targets(const real* joint_targets_rad);
  // The servos' torques and, where unclipped, their implicit gains, per velocity coordinate.
  void servo_torques(real* tau, real* kp, real* kd) const;
  // The contacts at the poses in the solver's X_world, ascending keys; returns how many.
  int collide();
  void physics_step_done(int num_contacts);
  void refresh();
  void place_box(const Vec3& box_c);
  struct Impl;
  PickPlaceConfig cfg_;
  ArticulatedRobot robot_;
  std::unique_ptr<Impl> impl_;
  PickPlaceState state_;
  RngStream rng_;
  real q_[kJoints + 7] = {};   // the arm's 6 angles, then the cube's free joint (x y z, x y z w)
  real qd_[kJoints + 6] = {};  // the arm's 6 rates, then the cube's (linear, angular; its frame)
  real target_[kJoints] = {};
  real home_[kJoints] = {}, lower_[kJoints] = {}, upper_[kJoints] = {}, effort_[kJoints] = {};
  real kp_[kJoints] = {}, kd_[kJoints] = {};
  real grip_force_N_ = 0;
  int num_contacts_ = 0;
  int tcp_body_ = -1, pad_body_[2] = {-1, -1}, cube_body_ = -1;
  bool batch_ok_ = false;  // the model's joints suit the batched step
};

/// LeIsaac-style scripted pick and place over PickPlaceWorld (the seed's demonstrations are
/// teleoperated; this is the automatic one the issue asks for): above the cube with the gripper
/// open, down to the grasp height, close, lift, carry above the box, lower, open, up. Each phase
/// moves the tool-centre-point target in a straight line with a smooth (cubic) time law and turns
/// it into joint targets by damped least squares every action.
class ScriptedPickPlace {
 public:
  explicit ScriptedPickPlace(const PickPlaceWorld& world);
  /// Restarts at the world's current state (after reset).
  void reset();
  /// The next action's six joint targets. done() once the cube has been released and the arm
  /// raised.
  void act(real* joint_targets_rad);
  bool done() const { return phase_ >= kDone; }
  int phase() const { return phase_; }
  real lift_height_m = 0.10_r;      // cube centre above the table while carried
  real grasp_depth_m = 0.0;         // tcp below the cube's centre when closing (0: at its centre)
  real gripper_open_rad = 0.7_r;
  real gripper_close_rad = 0.0_r;   // below the cube's 0.2 rad: the squeeze is kp x the difference
  real fixed_jaw_clearance_m = 0.004_r;  // the fixed pad's gap to the cube while the gripper comes down

 private:
  enum { kApproach = 0, kDescend, kClose, kLift, kCarry, kLower, kOpen, kRetreat, kDone };
  void start_phase(int phase);
  const PickPlaceWorld& w_;
  int phase_ = kApproach;
  int tick_ = 0, ticks_ = 1;
  Vec3 from_w_ = Vec3::Zero(), to_w_ = Vec3::Zero();
  real grip_ = 0, yaw_ = 0;
  real q_ik_[PickPlaceWorld::kJoints] = {};
};

}  // namespace kestrel::sim
