// Controller dispatch table (see controller.hpp).
#include "kestrel/controllers/controller.hpp"

#include <cstring>

namespace kestrel {
namespace {

using LeeUpdateFn = Wrench (*)(const LeeParams&, LeeState&, const RigidBodyState&, const real*);

constexpr std::uint32_t kRejectedBits = kFaultNonFiniteCommand | kFaultNonFiniteState | kFaultNonFiniteOutput;

// Registry names, indexed by ControllerKind (no code referenced: naming a kind links nothing).
constexpr const char* kNames[kNumControllerKinds] = {
    "lee_position_control",     "lee_velocity_control", "lee_acceleration_control",
    "lee_attitude_control",     "lee_rates_control",    "lee_velocity_steering_angle_control",
    "rov_fully_actuated_control", "direct_motor_control", "velocity_steering_control",
    "joint_pd_control",
};

// The multirotor family's slice, indexed by ControllerKind: what update_controller dispatches on.
// Kept apart from the full table so that a firmware calling update_controller links the Lee laws
// and direct motor commands only, not the steering and joint code the full table references.
struct MultirotorEntry {
  std::uint8_t action_dim;  // 0: one per motor
  LeeUpdateFn lee_update;   // nullptr: direct motor commands
};
constexpr MultirotorEntry kMultirotor[kNumMultirotorControllerKinds] = {
    {kLeeActionDim, &update_lee_position},     {kLeeActionDim, &update_lee_velocity},
    {kLeeActionDim, &update_lee_acceleration}, {kLeeActionDim, &update_lee_attitude},
    {kLeeActionDim, &update_lee_rates},        {kLeeActionDim, &update_lee_velocity_steering_angle},
    {kPoseActionDim, &update_rov_fully_actuated}, {0, nullptr},
};

inline const MultirotorEntry* multirotor_entry(ControllerKind kind) {
  const std::size_t i = static_cast<std::size_t>(kind);
  return i < kNumMultirotorControllerKinds ? &kMultirotor[i] : nullptr;
}

// Every kind's update and reset share one signature (the refs carry the family's storage).
using UpdateFn = Status (*)(ControllerKind, const ControllerParamsRef&, const ControllerStateRef&, const ControllerInput&,
                            const real*, std::size_t, ControlOutput&);
using ResetFn = Status (*)(ControllerKind, const ControllerParamsRef&, const ControllerStateRef&, RngStream*);

// ---- the multirotor family: update_controller, reached with the refs -------------------------
Status multirotor_update(ControllerKind kind, const ControllerParamsRef& p, const ControllerStateRef& s,
                         const ControllerInput& in, const real* action, std::size_t len, ControlOutput& out) {
  if (p.multirotor == nullptr || s.multirotor == nullptr || in.body == nullptr) return Status::invalid_argument;
  out.family = ControlFamily::multirotor;
  return update_controller(kind, *p.multirotor, *s.multirotor, *in.body, action, len, out.multirotor);
}
Status multirotor_reset(ControllerKind kind, const ControllerParamsRef& p, const ControllerStateRef& s, RngStream* rng) {
  if (p.multirotor == nullptr || s.multirotor == nullptr) return Status::invalid_argument;
  if (rng != nullptr) controller_reset(kind, *p.multirotor, *s.multirotor, *rng);
  else controller_reset(kind, *p.multirotor, *s.multirotor);
  return Status::ok;
}

// ---- ground vehicle: velocity + steering angle (velocity_steering.hpp) ----------------------
Status steering_update(ControllerKind, const ControllerParamsRef& p, const ControllerStateRef& s, const ControllerInput& in,
                       const real* action, std::size_t len, ControlOutput& out) {
  if (p.steering == nullptr || s.steering == nullptr || len < kVelocitySteeringActionDim) return Status::invalid_argument;
  out.family = ControlFamily::ground_vehicle;
  return update_velocity_steering(*p.steering, *s.steering, in.speed_m_s, action, in.dt_s, out.drive);
}
// The state's gain_scale is kept: it is the caller's draw (domain randomisation of the gains).
Status steering_reset(ControllerKind, const ControllerParamsRef& p, const ControllerStateRef& s, RngStream*) {
  if (p.steering == nullptr || s.steering == nullptr) return Status::invalid_argument;
  velocity_steering_reset(*s.steering, s.steering->gain_scale);
  return Status::ok;
}

// ---- articulated: joint PD with action delay (joint_pd.hpp) ---------------------------------
Status joint_update(ControllerKind, const ControllerParamsRef& p, const ControllerStateRef& s, const ControllerInput& in,
                    const real* action, std::size_t len, ControlOutput& out) {
  if (p.joints == nullptr || s.joints == nullptr || in.joint_pos_rad == nullptr || in.joint_vel_radps == nullptr ||
      p.joints->num_joints > kMaxControlJoints || len < p.joints->num_joints)
    return Status::invalid_argument;
  out.family = ControlFamily::articulated;
  out.num_joints = p.joints->num_joints;
  return update_joint_pd(*p.joints, *s.joints, in.joint_pos_rad, in.joint_vel_radps, action, out.joint_torque_Nm);
}
Status joint_reset(ControllerKind, const ControllerParamsRef& p, const ControllerStateRef& s, RngStream* rng) {
  if (p.joints == nullptr || s.joints == nullptr) return Status::invalid_argument;
  if (rng != nullptr) joint_pd_reset(*p.joints, *s.joints, *rng);
  else joint_pd_reset(*p.joints, *s.joints);
  return Status::ok;
}

// The table: every kind, indexed by ControllerKind.
struct Entry {
  ControlFamily family;
  UpdateFn update;
  ResetFn reset;
};
constexpr Entry kMr = {ControlFamily::multirotor, &multirotor_update, &multirotor_reset};
constexpr Entry kTable[kNumControllerKinds] = {
    kMr, kMr, kMr, kMr, kMr, kMr, kMr, kMr,
    {ControlFamily::ground_vehicle, &steering_update, &steering_reset},
    {ControlFamily::articulated, &joint_update, &joint_reset},
};

inline const Entry* entry(ControllerKind kind) {
  const std::size_t i = static_cast<std::size_t>(kind);
  return i < kNumControllerKinds ? &kTable[i] : nullptr;
}

}  // namespace

const char* controller_name(ControllerKind kind) {
  const std::size_t i = static_cast<std::size_t>(kind);
  return i < kNumControllerKinds ? kNames[i] : "unknown";
}

bool controller_kind_from_name(const char* name, ControllerKind& kind) {
  if (name == nullptr) return false;
  for (std::size_t i = 0; i < kNumControllerKinds; ++i) {
    if (std::strcmp(name, kNames[i]) == 0) {
      kind = static_cast<ControllerKind>(i);
      return true;
    }
  }
  return false;
}

ControlFamily controller_family(ControllerKind kind) {
  const Entry* e = entry(kind);
  return e != nullptr ? e->family : ControlFamily::multirotor;
}

std::size_t controller_action_dim(ControllerKind kind, const ControllerParams& params) {
  const MultirotorEntry* e = multirotor_entry(kind);
  if (e == nullptr) return 0;
  return e->lee_update != nullptr ? e->action_dim : params.motors.num_motors;
}

std::size_t controller_action_dim(ControllerKind kind, const ControllerParamsRef& params) {
  const Entry* e = entry(kind);
  if (e == nullptr) return 0;
  switch (e->family) {
    case ControlFamily::multirotor: return params.multirotor != nullptr ? controller_action_dim(kind, *params.multirotor) : 0;
    case ControlFamily::ground_vehicle: return params.steering != nullptr ? kVelocitySteeringActionDim : 0;
    case ControlFamily::articulated: return params.joints != nullptr ? params.joints->num_joints : 0;
  }
  return 0;
}

bool controller_outputs_wrench(ControllerKind kind) {
  const MultirotorEntry* e = multirotor_entry(kind);
  return e != nullptr && e->lee_update != nullptr;
}

// The resets decide by kind, not through the table: a firmware image that resets and runs one
// controller directly then links only that one (the table references all seven Lee updates, ~14 KB
// of flash on the M4F).
void controller_reset(ControllerKind kind, const ControllerParams& params, ControllerState& state) {
  if (static_cast<std::size_t>(kind) >= kNumMultirotorControllerKinds) return;
  if (kind != ControllerKind::direct_motor) {
    lee_reset(params.lee, state.lee);
  } else {
    direct_motor_reset(params.motors, state.motors);
  }
}

void controller_reset(ControllerKind kind, const ControllerParams& params, ControllerState& state, RngStream& rng) {
  if (static_cast<std::size_t>(kind) >= kNumMultirotorControllerKinds) return;
  if (kind != ControllerKind::direct_motor) {
    lee_reset(params.lee, state.lee, rng);
  } else {
    direct_motor_reset(params.motors, state.motors);
  }
}

Status update_controller(ControllerKind kind, const ControllerParams& params, ControllerState& state,
                         const RigidBodyState& body, const real* action, std::size_t action_len,
                         ControllerOutput& out) {
  const MultirotorEntry* e = multirotor_entry(kind);
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

Status control_update(ControllerKind kind, const ControllerParamsRef& params, const ControllerStateRef& state,
                      const ControllerInput& in, const real* action, std::size_t action_len, ControlOutput& out) {
  const Entry* e = entry(kind);
  if (e == nullptr || action == nullptr) return Status::invalid_argument;
  return e->update(kind, params, state, in, action, action_len, out);
}

Status control_reset(ControllerKind kind, const ControllerParamsRef& params, const ControllerStateRef& state, RngStream* rng) {
  const Entry* e = entry(kind);
  return e != nullptr ? e->reset(kind, params, state, rng) : Status::invalid_argument;
}

std::uint32_t control_faults(ControllerKind kind, const ControllerStateRef& state) {
  const Entry* e = entry(kind);
  if (e == nullptr) return 0;
  switch (e->family) {
    case ControlFamily::multirotor:
      if (state.multirotor == nullptr) return 0;
      return kind == ControllerKind::direct_motor ? state.multirotor->motors.faults.bits : state.multirotor->lee.faults.bits;
    case ControlFamily::ground_vehicle: return state.steering != nullptr ? state.steering->faults.bits : 0;
    case ControlFamily::articulated: return state.joints != nullptr ? state.joints->faults.bits : 0;
  }
  return 0;
}

}  // namespace kestrel
