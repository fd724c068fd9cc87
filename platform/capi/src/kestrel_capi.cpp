// C API over the control stack (kestrel/kestrel.h). Thin glue: every number comes from the core;
// this file only converts between the C structs and the core types and lays the stack out in the
// caller's storage (placement new into kestrel_storage, no heap).
#include "kestrel/kestrel.h"

#include <new>

#include "kestrel/allocation/airframe.hpp"
#include "kestrel/allocation/allocation_model.hpp"
#include "kestrel/allocation/motor_model.hpp"
#include "kestrel/allocation/presets.hpp"
#include "kestrel/allocation/sequential_desaturation.hpp"
#include "kestrel/controllers/controller.hpp"
#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/robots/multirotor.hpp"

namespace {

using namespace kestrel;
namespace al = kestrel::allocation;

constexpr std::uint32_t kMagic = 0x4b455354u;  // "KEST": the storage holds an initialised stack

struct CapiStack {
  std::uint32_t magic;
  robots::MultirotorModel mr;   // the core chain (robots/multirotor.hpp): Lee, airframe, allocation, motors
  robots::MultirotorState st;   // controller, allocator and motor state
  robots::MultirotorOutput out; // last controller wrench and thrust setpoints
  al::MotorHealth health;       // what the allocation model was last built with
};
static_assert(sizeof(CapiStack) <= KESTREL_STORAGE_BYTES, "raise KESTREL_STORAGE_BYTES in kestrel.h");
static_assert(alignof(CapiStack) <= alignof(kestrel_storage), "kestrel_storage is under-aligned");
static_assert(static_cast<int>(KESTREL_MODE_POSITION) == static_cast<int>(ControllerKind::lee_position) &&
                  static_cast<int>(KESTREL_MODE_VELOCITY) == static_cast<int>(ControllerKind::lee_velocity) &&
                  static_cast<int>(KESTREL_MODE_ATTITUDE) == static_cast<int>(ControllerKind::lee_attitude) &&
                  static_cast<int>(KESTREL_MODE_RATES) == static_cast<int>(ControllerKind::lee_rates),
              "kestrel_mode values are ControllerKind values");
static_assert(KESTREL_FAULT_NON_FINITE_OUTPUT == kFaultNonFiniteOutput && KESTREL_FAULT_MOTOR_FAILURE == kFaultMotorFailure &&
                  KESTREL_FAULT_SATURATED == kFaultSaturated,
              "fault bits are kestrel::Fault values");
static_assert(KESTREL_MAX_MOTORS == al::kMaxRotors, "KESTREL_MAX_MOTORS is kMaxRotors");
static_assert(static_cast<int>(KESTREL_NOT_CONVERGED) == static_cast<int>(Status::not_converged) &&
                  static_cast<int>(KESTREL_NON_FINITE_OUTPUT) == static_cast<int>(Status::non_finite_output),
              "status values");

kestrel_status to_c(Status s) { return static_cast<kestrel_status>(static_cast<int>(s)); }

CapiStack* stack_of(kestrel_storage* s) {
  if (s == nullptr) return nullptr;
  CapiStack* p = std::launder(reinterpret_cast<CapiStack*>(s->u.bytes));
  return p->magic == kMagic ? p : nullptr;
}
const CapiStack* stack_of(const kestrel_storage* s) {
  if (s == nullptr) return nullptr;
  const CapiStack* p = std::launder(reinterpret_cast<const CapiStack*>(s->u.bytes));
  return p->magic == kMagic ? p : nullptr;
}

bool supported(std::int32_t preset) {
  return preset == KESTREL_PRESET_BASE_QUADROTOR || preset == KESTREL_PRESET_HEXAROTOR || preset == KESTREL_PRESET_X500;
}

void set3(float* dst, const Vec3& v) {
  for (int i = 0; i < 3; ++i) dst[i] = static_cast<float>(v[i]);
}
Vec3 vec3(const float* v) { return Vec3(static_cast<real>(v[0]), static_cast<real>(v[1]), static_cast<real>(v[2])); }

// Last line of defence behind the allocator's own hold (kestrel_step's output check): replaces a
// non-finite or out-of-range output with the allocator's held thrust (finite by construction; the
// motor's lower limit if even that is not), a non-finite wrench with zero. Cold: never runs unless
// a stage broke its contract.
__attribute__((noinline, cold)) void repair_outputs(CapiStack* s, kestrel_output* out) {
  const int n = s->mr.allocation.num_rotors;
  for (int i = 0; i < n; ++i) {
    const real lo = s->mr.airframe.thrust_min_N[i], hi = s->mr.airframe.thrust_max_N[i];
    real f = s->st.allocator.last_thrust_N[i];
    if (!is_finite(f)) f = lo;
    const float cmd = out->motor_command[i];
    if (!(cmd >= 0.0f && cmd <= 1.0f)) out->motor_command[i] = static_cast<float>(hi > lo ? clamp((f - lo) / (hi - lo), 0_r, 1_r) : 0_r);
    if (!is_finite(static_cast<real>(out->thrust_setpoint_N[i]))) out->thrust_setpoint_N[i] = static_cast<float>(f);
    if (!is_finite(static_cast<real>(out->thrust_N[i]))) out->thrust_N[i] = static_cast<float>(f);
  }
  for (int i = 0; i < 6; ++i) {
    if (!is_finite(static_cast<real>(out->wrench_b[i]))) out->wrench_b[i] = 0.0f;
  }
  s->st.allocator.faults.raise(kFaultNonFiniteOutput);
}

}  // namespace

extern "C" {

size_t kestrel_storage_used(void) { return sizeof(CapiStack); }

kestrel_status kestrel_default_params(std::int32_t preset, kestrel_params* p) {
  if (p == nullptr || !supported(preset)) return KESTREL_INVALID_ARGUMENT;
  // The Lee gains and the quad's mass and inertia are Aerial Gym's (lee_params_base_quadrotor).
  // The heavier frames keep the same closed-loop dynamics: the position gains are accelerations
  // (mass-free), and the attitude gains are torques, so they scale with the inertia.
  const LeeParams q = lee_params_base_quadrotor();
  const LeeGains g = lee_nominal_gains(q.gain_ranges);
  const al::AirframeSpec& spec = al::airframe_spec(static_cast<al::AirframePreset>(preset));
  real inertia_scale = 1;
  real mass = q.mass_kg;
  if (preset != KESTREL_PRESET_BASE_QUADROTOR) {
    mass = spec.mass_kg;
    // Inertia ~ m r^2: mass ratio times the squared ratio of arm lengths (quad 0.13 m per axis,
    // hexarotor arm 0.25 m, X500 0.175 m per axis).
    const real arm = preset == KESTREL_PRESET_HEXAROTOR ? 0.25_r : 0.175_r * 1.41421356_r;
    const real arm_q = 0.13_r * 1.41421356_r;
    inertia_scale = (mass / q.mass_kg) * (arm / arm_q) * (arm / arm_q);
  }
  p->preset = preset;
  p->mass_kg = static_cast<float>(mass);
  for (int i = 0; i < 3; ++i) p->inertia_diag_kgm2[i] = static_cast<float>(q.inertia_b(i, i) * inertia_scale);
  set3(p->k_pos, g.k_pos);
  set3(p->k_vel, g.k_vel);
  set3(p->k_rot, g.k_rot * inertia_scale);
  set3(p->k_angvel, g.k_angvel * inertia_scale);
  p->max_yaw_rate_radps = static_cast<float>(q.max_yaw_rate_radps);
  p->yaw_headroom = static_cast<float>(al::SequentialDesaturationParams().yaw_headroom);
  p->use_motor_model = 1;
  return KESTREL_OK;
}

kestrel_status kestrel_init(kestrel_storage* storage, std::int32_t preset) {
  kestrel_params p;
  if (const kestrel_status st = kestrel_default_params(preset, &p); st != KESTREL_OK) return st;
  return kestrel_init_params(storage, &p);
}

kestrel_status kestrel_init_params(kestrel_storage* storage, const kestrel_params* p) {
  if (storage == nullptr || p == nullptr || !supported(p->preset)) return KESTREL_INVALID_ARGUMENT;
  CapiStack* s = new (storage->u.bytes) CapiStack();  // value-initialised; magic 0 until the end
  const auto preset = static_cast<al::AirframePreset>(p->preset);

  LeeParams& lee = s->mr.ctrl.lee;
  lee = lee_params_base_quadrotor();
  lee.mass_kg = static_cast<real>(p->mass_kg);
  lee.inertia_b = Mat3::Zero();
  for (int i = 0; i < 3; ++i) lee.inertia_b(i, i) = static_cast<real>(p->inertia_diag_kgm2[i]);
  LeeGains g;
  g.k_pos = vec3(p->k_pos);
  g.k_vel = vec3(p->k_vel);
  g.k_rot = vec3(p->k_rot);
  g.k_angvel = vec3(p->k_angvel);
  lee.gain_ranges.min = g;  // min = max fixes the gains
  lee.gain_ranges.max = g;
  lee.randomize_gains = false;
  lee.max_yaw_rate_radps = static_cast<real>(p->max_yaw_rate_radps);
  if (const Status st = validate_lee_params(lee); st != Status::ok) return to_c(st);
  controller_reset(ControllerKind::lee_position, s->mr.ctrl, s->st.ctrl);

  if (!is_finite(static_cast<real>(p->yaw_headroom)) || p->yaw_headroom < 0) return KESTREL_INVALID_ARGUMENT;
  s->mr.desat.yaw_headroom = static_cast<real>(p->yaw_headroom);
  if (const Status st = al::make_airframe(al::airframe_spec(preset), s->mr.airframe); st != Status::ok) return to_c(st);
  // Flat multirotors have rank 4 (no lateral force): Status::singular is expected and harmless.
  const Status am = al::build_allocation_model(s->mr.airframe, s->health, s->mr.allocation);
  if (am != Status::ok && am != Status::singular) return to_c(am);
  al::reset_allocator(s->st.allocator);
  s->mr.motors = al::motor_model_preset(preset);
  RngStream rng(1, 0, kPurposeMotors);
  const real idle[al::kMaxRotors] = {};
  if (const Status st = al::motor_model_reset(s->mr.motors, s->st.motors, rng, idle); st != Status::ok) return to_c(st);
  s->mr.use_motor_model = p->use_motor_model != 0;
  s->mr.controller = ControllerKind::lee_position;  // the default mode; kestrel_step picks per call
  s->mr.allocator = robots::AllocatorKind::sequential_desaturation;
  if (const Status st = robots::finish_multirotor_model(s->mr); st != Status::ok) return to_c(st);
  s->magic = kMagic;
  return KESTREL_OK;
}

kestrel_status kestrel_step(kestrel_storage* storage, const kestrel_state* st, const kestrel_setpoint* sp, float dt_s,
                            kestrel_output* out) {
  CapiStack* s = stack_of(storage);
  if (s == nullptr || st == nullptr || sp == nullptr || out == nullptr) return KESTREL_INVALID_ARGUMENT;
  const std::int32_t m = sp->mode;
  if (m != KESTREL_MODE_POSITION && m != KESTREL_MODE_VELOCITY && m != KESTREL_MODE_ATTITUDE && m != KESTREL_MODE_RATES) {
    return KESTREL_INVALID_ARGUMENT;
  }
  // dt_s in (0, KESTREL_MAX_DT_S]: a huge period (~1e16 s and up) overflows the motor model (F6).
  if (!(dt_s > 0.0f) || !(dt_s <= KESTREL_MAX_DT_S)) return KESTREL_INVALID_ARGUMENT;
  // A finite quaternion must be unit within KESTREL_QUAT_NORM_TOLERANCE (a zero or scaled one
  // gives finite but meaningless commands). Compared squared: no sqrt. A non-finite one is left to
  // the controller, which holds its output and reports NON_FINITE_INPUT.
  {
    const float* q = st->orientation_xyzw;
    const float n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
    constexpr float kLo = (1.0f - KESTREL_QUAT_NORM_TOLERANCE) * (1.0f - KESTREL_QUAT_NORM_TOLERANCE);
    constexpr float kHi = (1.0f + KESTREL_QUAT_NORM_TOLERANCE) * (1.0f + KESTREL_QUAT_NORM_TOLERANCE);
    const bool q_finite = q[0] * 0.0f + q[1] * 0.0f + q[2] * 0.0f + q[3] * 0.0f == 0.0f;
    if (q_finite && !(n2 >= kLo && n2 <= kHi)) return KESTREL_INVALID_ARGUMENT;
  }

  RigidBodyState body;
  body.position_w = vec3(st->position_w);
  body.orientation_wb = quat_from_xyzw(static_cast<real>(st->orientation_xyzw[0]), static_cast<real>(st->orientation_xyzw[1]),
                                       static_cast<real>(st->orientation_xyzw[2]), static_cast<real>(st->orientation_xyzw[3]));
  body.linvel_w = vec3(st->linvel_w);
  body.angvel_b = vec3(st->angvel_b);
  const real action[4] = {static_cast<real>(sp->value[0]), static_cast<real>(sp->value[1]),
                          static_cast<real>(sp->value[2]), static_cast<real>(sp->value[3])};

  // The core chain with the mode's controller; a rejected (non-finite) input still yields the held
  // safe wrench, which is allocated as usual. First non-ok status of the stages.
  const ControllerKind kind = static_cast<ControllerKind>(m);
  Status worst = robots::multirotor_control(s->mr, kind, s->st, body, action, 4, s->out.command);
  const Status sa = robots::multirotor_actuate(s->mr, s->st, static_cast<real>(dt_s), s->out);
  if (worst == Status::ok) worst = sa;
  const int n = s->mr.allocation.num_rotors;

  out->num_motors = n;
  for (int i = 0; i < KESTREL_MAX_MOTORS; ++i) {
    if (i >= n) {
      out->motor_command[i] = 0;
      out->thrust_setpoint_N[i] = 0;
      out->thrust_N[i] = 0;
      continue;
    }
    // Normalised against the airframe's nominal range: a weak motor's 1.0 stays its full throttle.
    const real lo = s->mr.airframe.thrust_min_N[i], hi = s->mr.airframe.thrust_max_N[i];
    const real f = s->out.allocation.thrust_N[i];
    out->motor_command[i] = static_cast<float>(hi > lo ? clamp((f - lo) / (hi - lo), 0_r, 1_r) : 0_r);
    out->thrust_setpoint_N[i] = static_cast<float>(f);
    out->thrust_N[i] = static_cast<float>(s->mr.use_motor_model ? s->st.motors.thrust_N[i] : f);
  }
  const Vec6 w = s->out.command.wrench_b.as_vec6();
  for (int i = 0; i < 6; ++i) out->wrench_b[i] = static_cast<float>(w[i]);
  // The contract of this API: every output finite, motor_command in [0, 1], whatever the input.
  // The stages guarantee it themselves; checked here once more (branch-free probe: v * 0 is +-0
  // for finite v, NaN otherwise) so a broken stage cannot reach the motors. A double core's
  // finite value beyond the float range also becomes inf in the conversion and is caught here.
  float probe = 0.0f;
  bool in_range = true;
  for (int i = 0; i < n; ++i) {
    probe += out->thrust_setpoint_N[i] * 0.0f + out->thrust_N[i] * 0.0f;
    in_range = in_range && out->motor_command[i] >= 0.0f && out->motor_command[i] <= 1.0f;
  }
  for (int i = 0; i < 6; ++i) probe += out->wrench_b[i] * 0.0f;
  if (!(probe == 0.0f) || !in_range) {
    repair_outputs(s, out);
    if (worst == Status::ok) worst = Status::non_finite_output;
  }
  out->saturated_mask = s->out.allocation.saturated_mask();
  out->faults = kestrel_faults(storage);
  return to_c(worst);
}

uint32_t kestrel_faults(const kestrel_storage* storage) {
  const CapiStack* s = stack_of(storage);
  if (s == nullptr) return 0;
  // The model's kFaultSingular is the rank deficiency of a flat frame, not a fault.
  return s->st.ctrl.lee.faults.bits | s->st.allocator.faults.bits | s->st.motors.faults.bits |
         (s->mr.allocation.faults.bits & ~static_cast<std::uint32_t>(kFaultSingular));
}

void kestrel_clear_faults(kestrel_storage* storage) {
  CapiStack* s = stack_of(storage);
  if (s == nullptr) return;
  s->st.ctrl.lee.faults.clear();
  s->st.allocator.faults.clear();
  s->st.motors.faults.clear();
}

kestrel_status kestrel_inject_motor_failure(kestrel_storage* storage, std::int32_t motor, float thrust_scale) {
  CapiStack* s = stack_of(storage);
  if (s == nullptr || motor < 0 || motor >= s->mr.allocation.num_rotors || !(thrust_scale >= 0.0f) || !(thrust_scale <= 1.0f)) {
    return KESTREL_INVALID_ARGUMENT;
  }
  const real scale = static_cast<real>(thrust_scale);
  if (const Status st = al::inject_motor_failure(s->st.motors, motor, scale); st != Status::ok) return to_c(st);
  s->health.thrust_scale[motor] = scale;
  const Status am = al::build_allocation_model(s->mr.airframe, s->health, s->mr.allocation);
  return am == Status::singular ? KESTREL_OK : to_c(am);
}

float kestrel_command_to_pwm_us(float command, float min_us, float max_us) {
  const float c = command < 0.0f ? 0.0f : (command > 1.0f ? 1.0f : command);  // NaN -> min (motors idle)
  return c == c ? min_us + c * (max_us - min_us) : min_us;
}

}  // extern "C"
