// The multirotor's control chain, written once: controller -> allocation -> motor model -> body
// wrench. Every place that flies a multirotor calls it: the desktop World (sim/engine), the planar
// backend, the firmware examples and the C API. The 4-lane SIMD twin in sim/ (batch_step.hpp) is
// tested bit-identical against it (tests/sim/engine/batch_step_test.cpp).
//
// Shape: Pinocchio's model/data split and PX4's library-vs-module split (PX4
// src/lib/control_allocation: one interface, the module is glue). MultirotorModel is constant after
// set-up (what a World compiles once per robot type, or what firmware bakes into flash);
// MultirotorState is what one vehicle remembers between steps. Every function is allocation-free,
// exception-free and builds for every MCU preset.
//
// The chain is split where callers need to step in between:
//   multirotor_control  (controller table: any ControllerKind -> ControllerOutput)
//   multirotor_actuate  (ControllerOutput -> thrust setpoints -> motor model), and
//   multirotor_wrench   (motor thrusts -> body wrench, what the plant receives).
// The planar backend reshapes the controller's wrench between the first two (fixed altitude);
// firmware measures its control cost over the first two and leaves the third to its plant.
// multirotor_step runs the first two.
#pragma once

#include <cstddef>
#include <cstdint>

#include "kestrel/allocation/airframe.hpp"
#include "kestrel/allocation/allocation_model.hpp"
#include "kestrel/allocation/motor_model.hpp"
#include "kestrel/allocation/sequential_desaturation.hpp"
#include "kestrel/controllers/controller.hpp"
#include "kestrel/kernel/rigid_body.hpp"
#include "kestrel/kernel/rng.hpp"
#include "kestrel/kernel/status.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel::robots {

/// The kinds of robot Kestrel composes a chain for. A kind is a type, never a string compare:
/// registries and scenario files map names to it once (sim/), everything else switches on it.
enum class RobotKind : std::uint8_t {
  multirotor = 0,      // rotors through an allocator (quadrotor, hexarotor, octarotor, ROV)
  ground_vehicle = 1,  // car-like, velocity + steering angle (controllers/velocity_steering.hpp)
  articulated = 2,     // a tree of jointed bodies from a robot file (dynamics/), joint PD targets
};
constexpr std::size_t kNumRobotKinds = 3;
/// "multirotor" / "ground_vehicle" / "articulated" ("unknown" outside the enum).
const char* robot_kind_name(RobotKind kind);
/// False (kind untouched) for any other name.
[[nodiscard]] bool robot_kind_from_name(const char* name, RobotKind& kind);

/// How a wrench becomes thrust setpoints.
enum class AllocatorKind : std::uint8_t {
  sequential_desaturation = 0,  // PX4's sequential desaturation (allocation/sequential_desaturation.hpp)
  pseudo_inverse = 1,           // clamp(A+ w), Aerial Gym's reference allocation
};

/// Constant after set-up.
struct MultirotorModel {
  ControllerKind controller = ControllerKind::lee_position;
  ControllerParams ctrl;                   // the controller table's parameters (Lee, direct motors)
  allocation::Airframe airframe;           // geometry, limits, effectiveness A (wrench = A f)
  allocation::AllocationModel allocation;  // A+, masks and limits the allocators read
  AllocatorKind allocator = AllocatorKind::sequential_desaturation;
  allocation::SequentialDesaturationParams desat;
  allocation::MotorModelConfig motors;
  /// Off: the thrust setpoints are applied as they are (the C API's option for firmware that has
  /// its own ESC model); the motor state then mirrors the setpoints.
  bool use_motor_model = true;
};

/// What one vehicle remembers between steps.
struct MultirotorState {
  ControllerState ctrl;
  allocation::AllocatorState allocator;
  allocation::MotorModelState motors;
};

/// Outputs of one actuation, kept by the caller (firmware reports them, the C API copies them).
struct MultirotorOutput {
  ControllerOutput command;                 // the controller's wrench (or direct thrusts)
  allocation::AllocationResult allocation;  // thrust setpoints (wrench controllers; else the direct thrusts)
};

/// Sizes and limits the direct-motor parameters from the airframe (what every caller did by hand)
/// and checks the controller and motor parameters. invalid_argument for a bad model.
[[nodiscard]] Status finish_multirotor_model(MultirotorModel& model);

/// Resets a vehicle: controller (gains drawn from `gain_rng` where the params randomise them; null:
/// nominal gains), allocator warm start, motors (constants drawn from `motor_rng`, thrust
/// `initial_thrust_N` or, if null, the reference's uniform draw). The draw order is the one the
/// World has always used (controller, then motors, from one stream when both are the same).
[[nodiscard]] Status multirotor_reset(const MultirotorModel& model, MultirotorState& state, RngStream* gain_rng,
                                      RngStream& motor_rng, const real* initial_thrust_N);

/// The controller stage through the controller table, with an explicit kind (the C API switches
/// modes per call) or the model's.
[[nodiscard]] Status multirotor_control(const MultirotorModel& model, ControllerKind kind, MultirotorState& state,
                                        const RigidBodyState& estimate, const real* action, std::size_t action_len,
                                        ControllerOutput& command);

/// Allocation (wrench commands) and the motor model over `out.command`, writing
/// out.allocation and state.motors. Returns the first non-ok status of the stages (each stage
/// also latches its fault bits in `state`); the chain always leaves finite setpoints and thrusts.
[[nodiscard]] Status multirotor_actuate(const MultirotorModel& model, MultirotorState& state, real dt_s,
                                        MultirotorOutput& out);

/// multirotor_control with the model's controller, then multirotor_actuate; the first non-ok status.
[[nodiscard]] Status multirotor_step(const MultirotorModel& model, MultirotorState& state,
                                     const RigidBodyState& estimate, const real* action, std::size_t action_len,
                                     real dt_s, MultirotorOutput& out);

/// The rotor wrench on the body, [fx fy fz tx ty tz] in the body frame, from the motors' thrusts.
inline Wrench multirotor_wrench(const MultirotorModel& model, const MultirotorState& state) {
  return Wrench::from_vec6(
      allocation::wrench_from_thrusts(model.airframe.effectiveness, model.airframe.num_rotors, state.motors.thrust_N));
}

/// Every latched fault bit of the chain (controller, allocator, motors).
std::uint32_t multirotor_faults(const MultirotorState& state);

}  // namespace kestrel::robots
