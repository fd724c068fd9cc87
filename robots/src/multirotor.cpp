#include "kestrel/robots/multirotor.hpp"

#include <cstring>

namespace kestrel::robots {

namespace al = kestrel::allocation;

const char* robot_kind_name(RobotKind kind) {
  switch (kind) {
    case RobotKind::multirotor:
      return "multirotor";
    case RobotKind::ground_vehicle:
      return "ground_vehicle";
    case RobotKind::articulated:
      return "articulated";
  }
  return "unknown";
}

bool robot_kind_from_name(const char* name, RobotKind& kind) {
  if (name == nullptr) return false;
  for (std::size_t k = 0; k < kNumRobotKinds; ++k) {
    const RobotKind candidate = static_cast<RobotKind>(k);
    if (std::strcmp(name, robot_kind_name(candidate)) == 0) {
      kind = candidate;
      return true;
    }
  }
  return false;
}

Status finish_multirotor_model(MultirotorModel& m) {
  const int n = m.airframe.num_rotors;
  if (n < 1 || n > al::kMaxRotors || static_cast<std::size_t>(n) > kMaxMotors) return Status::invalid_argument;
  // Direct motor commands are clamped to the airframe's own limits.
  m.ctrl.motors.num_motors = static_cast<std::size_t>(n);
  for (int i = 0; i < n; ++i) {
    m.ctrl.motors.min_thrust_N[i] = m.airframe.thrust_min_N[i];
    m.ctrl.motors.max_thrust_N[i] = m.airframe.thrust_max_N[i];
  }
  if (m.controller == ControllerKind::direct_motor) {
    if (validate_direct_motor_params(m.ctrl.motors) != Status::ok) return Status::invalid_argument;
  } else if (validate_lee_params(m.ctrl.lee) != Status::ok) {
    return Status::invalid_argument;
  }
  if (m.allocation.num_rotors != n) return Status::invalid_argument;
  if (m.use_motor_model && (al::validate(m.motors) != Status::ok || m.motors.num_motors != n))
    return Status::invalid_argument;
  return Status::ok;
}

Status multirotor_reset(const MultirotorModel& model, MultirotorState& state, RngStream* gain_rng, RngStream& motor_rng,
                        const real* initial_thrust_N) {
  if (gain_rng != nullptr) {
    controller_reset(model.controller, model.ctrl, state.ctrl, *gain_rng);
  } else {
    controller_reset(model.controller, model.ctrl, state.ctrl);
  }
  al::reset_allocator(state.allocator);
  return al::motor_model_reset(model.motors, state.motors, motor_rng, initial_thrust_N);
}

Status multirotor_control(const MultirotorModel& model, ControllerKind kind, MultirotorState& state,
                          const RigidBodyState& estimate, const real* action, std::size_t action_len,
                          ControllerOutput& command) {
  return update_controller(kind, model.ctrl, state.ctrl, estimate, action, action_len, command);
}

Status multirotor_actuate(const MultirotorModel& model, MultirotorState& state, real dt_s, MultirotorOutput& out) {
  Status worst = Status::ok;
  const real* reference = out.command.motor_thrust_N;
  if (out.command.is_wrench) {
    // A rejected controller input still yields its held safe wrench, which is allocated as usual.
    const Status sa = model.allocator == AllocatorKind::sequential_desaturation
                          ? al::allocate_sequential_desaturation(model.allocation, model.desat, state.allocator,
                                                                 out.command.wrench_b, out.allocation)
                          : al::allocate_pinv(model.allocation, state.allocator, out.command.wrench_b, out.allocation);
    worst = sa;
    reference = out.allocation.thrust_N;
  } else {
    const int n = model.airframe.num_rotors;
    for (int i = 0; i < n; ++i) out.allocation.thrust_N[i] = out.command.motor_thrust_N[i];
  }
  if (model.use_motor_model) {
    const Status sm = al::motor_model_step(model.motors, state.motors, reference, dt_s);
    if (worst == Status::ok) worst = sm;
  } else {
    // No motor dynamics: the setpoints act at once (the state mirrors them for multirotor_wrench).
    state.motors.num_motors = model.airframe.num_rotors;
    for (int i = 0; i < model.airframe.num_rotors; ++i) state.motors.thrust_N[i] = reference[i];
  }
  return worst;
}

Status multirotor_step(const MultirotorModel& model, MultirotorState& state, const RigidBodyState& estimate,
                       const real* action, std::size_t action_len, real dt_s, MultirotorOutput& out) {
  const Status sc = multirotor_control(model, model.controller, state, estimate, action, action_len, out.command);
  if (sc == Status::invalid_argument) return sc;  // nothing was written: nothing to actuate
  const Status sa = multirotor_actuate(model, state, dt_s, out);
  return sc != Status::ok ? sc : sa;
}

std::uint32_t multirotor_faults(const MultirotorState& state) {
  return state.ctrl.lee.faults.bits | state.ctrl.motors.faults.bits | state.allocator.faults.bits |
         state.motors.faults.bits;
}

}  // namespace kestrel::robots
