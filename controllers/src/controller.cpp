// Controller dispatch table (see controller.hpp).
#include "kestrel/controllers/controller.hpp"

#include <cstring>

namespace kestrel {
namespace {

using LeeUpdateFn = Wrench (*)(const LeeParams&, LeeState&, const RigidBodyState&, const real*);

struct Entry {
  const char* name;
  std::uint8_t action_dim;  // 0: one per motor
  LeeUpdateFn lee_update;   // nullptr: direct motor path
};

// Indexed by ControllerKind.
constexpr Entry kTable[kNumControllerKinds] = {
    {"lee_position_control", kLeeActionDim, &update_lee_position},
    {"lee_velocity_control", kLeeActionDim, &update_lee_velocity},
    {"lee_acceleration_control", kLeeActionDim, &update_lee_acceleration},
    {"lee_attitude_control", kLeeActionDim, &update_lee_attitude},
    {"lee_rates_control", kLeeActionDim, &update_lee_rates},
    {"lee_velocity_steering_angle_control", kLeeActionDim, &update_lee_velocity_steering_angle},
    {"rov_fully_actuated_control", kPoseActionDim, &update_rov_fully_actuated},
    {"direct_motor_control", 0, nullptr},
};

inline const Entry* entry(ControllerKind kind) {
  const std::size_t i = static_cast<std::size_t>(kind);
  return i < kNumControllerKinds ? &kTable[i] : nullptr;
}

constexpr std::uint32_t kRejectedBits = kFaultNonFiniteCommand | kFaultNonFiniteState | kFaultNonFiniteOutput;

}  // namespace

const char* controller_name(ControllerKind kind) {
  const Entry* e = entry(kind);
  return e != nullptr ? e->name : "unknown";
}

bool controller_kind_from_name(const char* name, ControllerKind& kind) {
  if (name == nullptr) return false;
  for (std::size_t i = 0; i < kNumControllerKinds; ++i) {
    if (std::strcmp(name, kTable[i].name) == 0) {
      kind = static_cast<ControllerKind>(i);
      return true;
    }
  }
  return false;
}

std::size_t controller_action_dim(ControllerKind kind, const ControllerParams& params) {
  const Entry* e = entry(kind);
  if (e == nullptr) return 0;
  return e->lee_update != nullptr ? e->action_dim : params.motors.num_motors;
}

bool controller_outputs_wrench(ControllerKind kind) {
  const Entry* e = entry(kind);
  return e != nullptr && e->lee_update != nullptr;
}

// The resets decide by kind, not through the table: a firmware image that resets and runs one
// controller directly then links only that one (the table references all seven Lee updates, ~14 KB
// of flash on the M4F).
void controller_reset(ControllerKind kind, const ControllerParams& params, ControllerState& state) {
  if (static_cast<std::size_t>(kind) >= kNumControllerKinds) return;
  if (kind != ControllerKind::direct_motor) {
    lee_reset(params.lee, state.lee);
  } else {
    direct_motor_reset(params.motors, state.motors);
  }
}

void controller_reset(ControllerKind kind, const ControllerParams& params, ControllerState& state, RngStream& rng) {
  if (static_cast<std::size_t>(kind) >= kNumControllerKinds) return;
  if (kind != ControllerKind::direct_motor) {
    lee_reset(params.lee, state.lee, rng);
  } else {
    direct_motor_reset(params.motors, state.motors);
  }
}

Status update_controller(ControllerKind kind, const ControllerParams& params, ControllerState& state,
                         const RigidBodyState& body, const real* action, std::size_t action_len,
                         ControllerOutput& out) {
  const Entry* e = entry(kind);
  if (e == nullptr || action == nullptr) return Status::invalid_argument;
  if (e->lee_update != nullptr) {
    if (action_len < e->action_dim) return Status::invalid_argument;
    out.is_wrench = true;
    out.wrench_b = e->lee_update(params.lee, state.lee, body, action);
    out.num_motors = 0;
    return (state.lee.step_faults & kRejectedBits) != 0 ? Status::non_finite_input : Status::ok;
  }
  const std::size_t n = params.motors.num_motors;
  if (n > kMaxMotors || action_len < n) return Status::invalid_argument;
  out.is_wrench = false;
  out.wrench_b = Wrench();
  out.num_motors = n;
  update_direct_motor(params.motors, state.motors, action, out.motor_thrust_N);
  return (state.motors.step_faults & kRejectedBits) != 0 ? Status::non_finite_input : Status::ok;
}

}  // namespace kestrel
