// One entry point over every controller kind, in the manner of Crazyflie's controller.c (an enum,
// a constant table of {name, update function}, no virtual calls): the simulator, the C API and
// the firmware select a controller by kind or by registry name and update it through one table.
//
// Kinds come in families, one per robot kind's chain (robots/): the multirotor/ROV kinds (Lee
// family, direct motor commands) read the rigid-body state and output a body wrench or motor
// thrusts; velocity_steering (ground vehicle) reads the speed along the heading and outputs a
// drive command; joint_pd (articulated robots) reads joint positions and velocities and outputs
// joint torques. control_update() takes every kind with one signature: what the kind reads
// (ControllerInput), where its parameters and state live (ControllerParamsRef / ControllerStateRef,
// typed pointers into the caller's storage, so a robot keeps only its own family's state and a
// multirotor's RAM is what it was), and one output (ControlOutput).
//
// update_controller() is the multirotor family's typed slice of the same table, the path the
// world's step and the SIMD twin take (no per-call refs); a firmware that calls it, or one Lee
// update directly, links no steering or joint code.
//
// A trained policy is not a kind here: it is a command source upstream of this table
// (policy/mlp.hpp: observation -> network -> action -> a kind's update), so one policy drives
// lee_velocity on the MCU and in the simulator alike.
#pragma once

#include <cstddef>
#include <cstdint>

#include "kestrel/controllers/direct_motor.hpp"
#include "kestrel/controllers/joint_pd.hpp"
#include "kestrel/controllers/lee.hpp"
#include "kestrel/controllers/velocity_steering.hpp"
#include "kestrel/kernel/rng.hpp"
#include "kestrel/kernel/status.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel {

/// Kinds, in Aerial Gym's registry order; names from controller_name().
enum class ControllerKind : std::uint8_t {
  lee_position = 0,             // "lee_position_control"                 [x, y, z, yaw]
  lee_velocity = 1,             // "lee_velocity_control"                 [vx, vy, vz, yaw_rate]
  lee_acceleration = 2,         // "lee_acceleration_control"             [ax, ay, az, yaw_rate]
  lee_attitude = 3,             // "lee_attitude_control"                 [thrust, roll, pitch, yaw_rate]
  lee_rates = 4,                // "lee_rates_control"                    [thrust, p, q, r]
  lee_velocity_steering_angle = 5,  // "lee_velocity_steering_angle_control" [vx, vy, vz, yaw]
  rov_fully_actuated = 6,       // "rov_fully_actuated_control"           [x, y, z, qx, qy, qz, qw]
  direct_motor = 7,             // "direct_motor_control"                 [f_0 .. f_{n-1}] (N)
  velocity_steering = 8,        // "velocity_steering_control"            [speed_m_s, steering_rad]
  joint_pd = 9,                 // "joint_pd_control"                     [a_0 .. a_{n-1}] (joint_pd.hpp)
};
constexpr std::size_t kNumControllerKinds = 10;
/// The multirotor/ROV kinds are the first ones (lee_position .. direct_motor): update_controller's.
constexpr std::size_t kNumMultirotorControllerKinds = 8;

/// The robot family a kind drives (its chain in robots/; a robot kind accepts its family's kinds).
enum class ControlFamily : std::uint8_t { multirotor = 0, ground_vehicle = 1, articulated = 2 };

/// Width of the uniform action array: 7 for the pose command; direct motor commands take one
/// value per motor, up to kMaxMotors (8 for the octarotor/ROV airframes).
constexpr std::size_t kMaxActionDim = kMaxMotors > kPoseActionDim ? kMaxMotors : kPoseActionDim;

struct ControllerParams {
  LeeParams lee;              // every kind but direct_motor
  DirectMotorParams motors;   // direct_motor
};

struct ControllerState {
  LeeState lee;
  DirectMotorState motors;
};

/// The joint PD instance of the table: up to 12 joints (a quadruped; the SO-101 arm has 6) and 4
/// steps of action delay. Other capacities use joint_pd.hpp's templates directly.
constexpr std::size_t kMaxControlJoints = 12;
constexpr std::size_t kMaxControlDelaySteps = 4;
using JointPdControlParams = JointPdParams<kMaxControlJoints, kMaxControlDelaySteps>;
using JointPdControlState = JointPdState<kMaxControlJoints, kMaxControlDelaySteps>;

struct ControllerOutput {
  bool is_wrench = true;       // true: wrench_b is the output; false: motor_thrust_N
  Wrench wrench_b;
  std::size_t num_motors = 0;
  real motor_thrust_N[kMaxMotors] = {};
};

/// What a kind reads besides its action. Multirotor kinds: `body` (the state estimate); velocity
/// steering: `speed_m_s` (along the heading, negative in reverse) and `dt_s`; joint PD:
/// `joint_pos_rad` and `joint_vel_radps` (params.num_joints values each).
struct ControllerInput {
  const RigidBodyState* body = nullptr;
  real speed_m_s = 0;
  real dt_s = 0;
  const real* joint_pos_rad = nullptr;
  const real* joint_vel_radps = nullptr;
};

/// Where a robot's controller parameters and state live: the pointer of the kind's family is
/// set, the others stay null (the caller's storage; nothing is copied).
struct ControllerParamsRef {
  const ControllerParams* multirotor = nullptr;
  const VelocitySteeringParams* steering = nullptr;
  const JointPdControlParams* joints = nullptr;
};
struct ControllerStateRef {
  ControllerState* multirotor = nullptr;
  VelocitySteeringState* steering = nullptr;
  JointPdControlState* joints = nullptr;
};

/// One update's result, in the member of the kind's family: `multirotor` (a wrench or motor
/// thrusts), `drive` (velocity steering), `joint_torque_Nm` (joint PD, num_joints values).
struct ControlOutput {
  ControlFamily family = ControlFamily::multirotor;
  ControllerOutput multirotor;
  VelocitySteeringOutput drive;
  std::size_t num_joints = 0;
  real joint_torque_Nm[kMaxControlJoints] = {};
};

/// Registry name of a kind ("unknown" outside the enum).
const char* controller_name(ControllerKind kind);
/// Kind of a registry name; false (kind untouched) if the name is not one of them.
[[nodiscard]] bool controller_kind_from_name(const char* name, ControllerKind& kind);
/// The family a kind drives (multirotor for an unknown kind; check the kind with controller_name).
ControlFamily controller_family(ControllerKind kind);
/// Number of action values a multirotor kind reads: 4, 7, or params.motors.num_motors (0 for an
/// unknown or non-multirotor kind).
std::size_t controller_action_dim(ControllerKind kind, const ControllerParams& params);
/// Any kind: as above for the multirotor family, 2 for velocity steering, joints->num_joints for
/// joint PD; 0 for an unknown kind or a missing family pointer.
std::size_t controller_action_dim(ControllerKind kind, const ControllerParamsRef& params);
/// Whether the kind outputs a body wrench (the Lee family).
bool controller_outputs_wrench(ControllerKind kind);

/// Resets the part of `state` the kind uses (lee_reset / direct_motor_reset).
void controller_reset(ControllerKind kind, const ControllerParams& params, ControllerState& state);
/// As above, drawing randomised gains from `rng` where the params ask for it.
void controller_reset(ControllerKind kind, const ControllerParams& params, ControllerState& state, RngStream& rng);

/// One update of the selected controller. `action` holds at least controller_action_dim() values
/// (a wider uniform array is fine; the rest is ignored). Returns:
///  - Status::invalid_argument (nothing written) for an unknown kind or a too-short action;
///  - Status::non_finite_input when the controller rejected the input and held its last safe
///    output (see the fault bits in the kind's state);
///  - Status::ok otherwise (clipping/saturation/singular fallbacks show up as fault bits only).
[[nodiscard]] Status update_controller(ControllerKind kind, const ControllerParams& params, ControllerState& state,
                                       const RigidBodyState& body, const real* action, std::size_t action_len,
                                       ControllerOutput& out);

/// Any kind, through the one table. Status::invalid_argument (nothing written) for an unknown kind,
/// a missing family pointer or input (body, joint arrays), or a too-short action; otherwise the
/// kind's own status (non_finite_input: rejected, last safe output held and faults latched in its
/// state; ok). The multirotor kinds give exactly update_controller's results.
[[nodiscard]] Status control_update(ControllerKind kind, const ControllerParamsRef& params, const ControllerStateRef& state,
                                    const ControllerInput& in, const real* action, std::size_t action_len, ControlOutput& out);
/// Resets the kind's state (controller_reset, velocity_steering_reset, joint_pd_reset); rng (may
/// be null) draws randomised gains where the params ask for it. invalid_argument for an unknown
/// kind or a missing family pointer.
[[nodiscard]] Status control_reset(ControllerKind kind, const ControllerParamsRef& params, const ControllerStateRef& state,
                                   RngStream* rng);
/// The latched fault bits of the kind's state (kernel/status.hpp), 0 for a missing pointer.
std::uint32_t control_faults(ControllerKind kind, const ControllerStateRef& state);

}  // namespace kestrel
