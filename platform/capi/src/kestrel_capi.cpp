// C API over the control stack (kestrel/kestrel.h). Thin glue: every number comes from the core;
// this file only converts between the C structs and the core types and lays the stack out in the
// caller's storage (placement new into kestrel_storage, no heap).
#include "kestrel/kestrel.h"

#include <cmath>
#include <cstddef>
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
  std::uint32_t latched;        // latched faults (KESTREL_LATCHED_FAULTS bits): kestrel_faults()
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
static_assert(KESTREL_FAULT_COMMAND_OUT_OF_RANGE == kFaultCommandOutOfRange && KESTREL_FAULT_SINGULAR == kFaultSingular &&
                  KESTREL_FAULT_NON_FINITE_COMMAND == kFaultNonFiniteCommand &&
                  KESTREL_FAULT_NON_FINITE_STATE == kFaultNonFiniteState,
              "fault bits are kestrel::Fault values");
// conditions (uint16_t) took the padding after saturated_mask: the struct's size and every
// earlier field's offset are those of the previous header (firmware built against it still works).
static_assert(sizeof(kestrel_output) == 4 + 3 * 4 * KESTREL_MAX_MOTORS + 6 * 4 + 4 + 2 + 2, "kestrel_output layout");
static_assert(offsetof(kestrel_output, conditions) == offsetof(kestrel_output, saturated_mask) + 2,
              "conditions fills the old padding");
static_assert(static_cast<int>(KESTREL_CLIPPED) > static_cast<int>(Status::non_finite_output),
              "C-only status values follow kestrel::Status's");
static_assert(static_cast<float>(KESTREL_SETPOINT_MAX) == 10.0f && static_cast<float>(KESTREL_SETPOINT_MIN) == -10.0f,
              "the setpoint range is LeeParams' default action range");

constexpr std::uint32_t kLatched = KESTREL_LATCHED_FAULTS;
constexpr float kMaxRotorPositionM = 100.0f;  // |rotor position component| (m)
constexpr float kMaxThrustN = 1e6f;           // |rotor thrust limit| (N)
constexpr float kMaxTimeConstantS = 10.0f;    // motor time constants (s)
constexpr real kIndependence = 1e-4_r;        // controllability check, see build_stack
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


// A refused init leaves the storage unusable (kestrel.h): only the magic word is cleared.
void unusable(kestrel_storage* storage) {
  if (storage != nullptr) std::launder(reinterpret_cast<CapiStack*>(storage->u.bytes))->magic = 0;
}

bool in_range(float v, float lo, float hi) { return v >= lo && v <= hi; }  // false for NaN
bool in_range3(const float* v, float lo, float hi) {
  return in_range(v[0], lo, hi) && in_range(v[1], lo, hi) && in_range(v[2], lo, hi);
}

// kestrel_params' ranges (kestrel.h) beyond what validate_lee_params checks: gains >= 0, inertia > 0.
bool params_ok(const kestrel_params& p) {
  const float kmax = static_cast<float>(kLeeMaxGain);
  if (!in_range(p.mass_kg, 0.0f, static_cast<float>(kLeeMaxMassKg)) || !(p.mass_kg > 0.0f)) return false;
  for (int i = 0; i < 3; ++i) {
    if (!in_range(p.inertia_diag_kgm2[i], 0.0f, static_cast<float>(kLeeMaxInertiaKgm2)) || !(p.inertia_diag_kgm2[i] > 0.0f))
      return false;
  }
  return in_range3(p.k_pos, 0.0f, kmax) && in_range3(p.k_vel, 0.0f, kmax) && in_range3(p.k_rot, 0.0f, kmax) &&
         in_range3(p.k_angvel, 0.0f, kmax) && in_range(p.max_yaw_rate_radps, 0.0f, 1e6f) &&
         in_range(p.yaw_headroom, 0.0f, 1e6f);
}

// kestrel_airframe's ranges (kestrel.h).
bool airframe_ok(const kestrel_airframe& a, bool motors_on) {
  if (a.num_rotors < 1 || a.num_rotors > KESTREL_MAX_MOTORS) return false;
  if (!in_range(a.torque_to_thrust_m, 0.0f, 1.0f) || !in_range(a.thrust_constant, 0.0f, 1.0f)) return false;
  if (motors_on && (!in_range(a.time_constant_up_s, 0.0f, kMaxTimeConstantS) || !(a.time_constant_up_s > 0.0f) ||
                    !in_range(a.time_constant_down_s, 0.0f, kMaxTimeConstantS) || !(a.time_constant_down_s > 0.0f)))
    return false;
  for (int i = 0; i < a.num_rotors; ++i) {
    const kestrel_rotor& r = a.rotor[i];
    if (!in_range3(r.position_b_m, -kMaxRotorPositionM, kMaxRotorPositionM)) return false;
    // Components bounded so the squared norm neither overflows nor underflows to zero.
    if (!in_range3(r.axis_b, -1e6f, 1e6f)) return false;
    const float n2 = r.axis_b[0] * r.axis_b[0] + r.axis_b[1] * r.axis_b[1] + r.axis_b[2] * r.axis_b[2];
    if (!(n2 >= 1e-12f)) return false;
    if (r.direction != 1 && r.direction != -1) return false;
    if (!in_range(r.thrust_min_N, -kMaxThrustN, kMaxThrustN) || !in_range(r.thrust_max_N, -kMaxThrustN, kMaxThrustN) ||
        !(r.thrust_min_N < r.thrust_max_N))
      return false;
    // The rotor-speed model takes sqrt(thrust / kf): no negative thrust (motor_model.hpp, quirk 9).
    if (motors_on && a.thrust_constant > 0.0f && r.thrust_min_N < 0.0f) return false;
  }
  return true;
}

// Builds the stack in the storage from checked-here parameters, an airframe spec (per-rotor limits
// lo/hi replacing the spec's scalar ones where given) and a motor model. Every refusal leaves the
// storage unusable (magic 0).
kestrel_status build_stack(kestrel_storage* storage, const kestrel_params* p, const al::AirframeSpec& spec,
                           const real* lo, const real* hi, const al::MotorModelConfig& motors) {
  if (storage == nullptr) return KESTREL_INVALID_ARGUMENT;
  if (p == nullptr || !params_ok(*p)) {
    unusable(storage);
    return KESTREL_INVALID_ARGUMENT;
  }
  CapiStack* s = new (storage->u.bytes) CapiStack();  // value-initialised; magic 0 until the end

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

  s->mr.desat.yaw_headroom = static_cast<real>(p->yaw_headroom);
  if (const Status st = al::make_airframe(spec, s->mr.airframe); st != Status::ok) return to_c(st);
  al::Airframe& af = s->mr.airframe;
  const int n = af.num_rotors;
  if (lo != nullptr && hi != nullptr) {
    for (int i = 0; i < n; ++i) {
      af.thrust_min_N[i] = lo[i];
      af.thrust_max_N[i] = hi[i];
    }
  }
  // Flat multirotors have rank 4 (no lateral force): Status::singular is expected and harmless.
  const Status am = al::build_allocation_model(af, s->health, s->mr.allocation);
  if (am != Status::ok && am != Status::singular) return to_c(am);
  // Controllability: the collective thrust fz and the three torques must be producible
  // independently (lateral forces may come along, as on a quad with tilted rotors): the rows
  // fz, tx, ty, tz of A must be linearly independent. Checked scale-free on their correlation
  // matrix (Gram matrix with unit diagonal) by Cholesky: a pivot below kIndependence means a row
  // is (nearly) a combination of the others, e.g. every rotor on one line (no torque about it) or
  // a flat frame with torque_to_thrust_m 0 (no yaw torque).
  {
    real gram[4][4], chol[4][4] = {};
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) {
        real dot = 0;
        for (int i = 0; i < n; ++i) dot += af.effectiveness(2 + a, i) * af.effectiveness(2 + b, i);
        gram[a][b] = dot;
      }
    }
    for (int a = 0; a < 4; ++a) {
      if (!(gram[a][a] > 0)) return KESTREL_SINGULAR;
    }
    for (int j = 0; j < 4; ++j) {
      for (int i = j; i < 4; ++i) {
        real c = gram[i][j] / std::sqrt(gram[i][i] * gram[j][j]);
        for (int k = 0; k < j; ++k) c -= chol[i][k] * chol[j][k];
        if (i == j) {
          if (!(c > kIndependence)) return KESTREL_SINGULAR;
          chol[j][j] = std::sqrt(c);
        } else {
          chol[i][j] = c / chol[j][j];
        }
      }
    }
  }
  // Thrust-to-weight >= 1: the largest total thrust along body +z (each rotor at whichever limit
  // pushes up more) must lift the mass.
  real fz_max = 0;
  for (int i = 0; i < n; ++i) {
    const real az = af.effectiveness(2, i);
    const real a = az * af.thrust_min_N[i], b = az * af.thrust_max_N[i];
    fz_max += a > b ? a : b;
  }
  if (!(fz_max >= lee.mass_kg * kStandardGravity)) return KESTREL_INSUFFICIENT_THRUST;

  al::reset_allocator(s->st.allocator);
  s->mr.motors = motors;
  RngStream rng(1, 0, kPurposeMotors);
  const real idle[al::kMaxRotors] = {};
  if (const Status st = al::motor_model_reset(s->mr.motors, s->st.motors, rng, idle); st != Status::ok) return to_c(st);
  s->mr.use_motor_model = p->use_motor_model != 0;
  s->mr.controller = ControllerKind::lee_position;  // the default mode; kestrel_step picks per call
  s->mr.allocator = robots::AllocatorKind::sequential_desaturation;
  if (const Status st = robots::finish_multirotor_model(s->mr); st != Status::ok) return to_c(st);
  s->latched = 0;
  s->magic = kMagic;
  return KESTREL_OK;
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
  set3(p->k_pos, g.k_pos.map());
  set3(p->k_vel, g.k_vel.map());
  set3(p->k_rot, g.k_rot.map() * inertia_scale);
  set3(p->k_angvel, g.k_angvel.map() * inertia_scale);
  p->max_yaw_rate_radps = static_cast<float>(q.max_yaw_rate_radps);
  p->yaw_headroom = static_cast<float>(al::SequentialDesaturationParams().yaw_headroom);
  p->use_motor_model = 1;
  return KESTREL_OK;
}

kestrel_status kestrel_init(kestrel_storage* storage, std::int32_t preset) {
  kestrel_params p;
  if (const kestrel_status st = kestrel_default_params(preset, &p); st != KESTREL_OK) {
    unusable(storage);
    return st;
  }
  return kestrel_init_params(storage, &p);
}

kestrel_status kestrel_init_params(kestrel_storage* storage, const kestrel_params* p) {
  if (p == nullptr || !supported(p->preset)) {
    unusable(storage);
    return KESTREL_INVALID_ARGUMENT;
  }
  const auto preset = static_cast<al::AirframePreset>(p->preset);
  return build_stack(storage, p, al::airframe_spec(preset), nullptr, nullptr, al::motor_model_preset(preset));
}

kestrel_status kestrel_airframe_from_preset(std::int32_t preset, kestrel_airframe* a) {
  if (a == nullptr || !supported(preset)) return KESTREL_INVALID_ARGUMENT;
  const al::AirframeSpec& spec = al::airframe_spec(static_cast<al::AirframePreset>(preset));
  const al::MotorModelConfig& m = al::motor_model_preset(static_cast<al::AirframePreset>(preset));
  *a = kestrel_airframe();
  a->num_rotors = spec.num_rotors;
  for (int i = 0; i < spec.num_rotors; ++i) {
    kestrel_rotor& r = a->rotor[i];
    for (int k = 0; k < 3; ++k) {
      r.position_b_m[k] = static_cast<float>(spec.rotors[i].position_b_m[k]);
      r.axis_b[k] = static_cast<float>(spec.rotors[i].axis_b[k]);
    }
    r.direction = spec.direction[i];
    r.thrust_min_N = static_cast<float>(spec.thrust_min_N);
    r.thrust_max_N = static_cast<float>(spec.thrust_max_N);
  }
  a->torque_to_thrust_m = static_cast<float>(spec.thrust_to_torque_m);
  // The nominal constants (min = max for the hexarotor and the X500: the same values).
  a->thrust_constant = m.use_rps ? static_cast<float>((m.thrust_constant_min + m.thrust_constant_max) / 2) : 0.0f;
  a->time_constant_up_s = static_cast<float>((m.time_constant_increasing_min_s + m.time_constant_increasing_max_s) / 2);
  a->time_constant_down_s = static_cast<float>((m.time_constant_decreasing_min_s + m.time_constant_decreasing_max_s) / 2);
  return KESTREL_OK;
}

kestrel_status kestrel_init_airframe(kestrel_storage* storage, const kestrel_airframe* a, const kestrel_params* p) {
  const bool motors_on = p != nullptr && p->use_motor_model != 0;
  if (p == nullptr || a == nullptr || !airframe_ok(*a, motors_on)) {
    unusable(storage);
    return KESTREL_INVALID_ARGUMENT;
  }
  const int n = a->num_rotors;
  // The spec (scalar limits: the envelope of the rotors'; the per-rotor limits go into the built
  // airframe) and the motor model, as the PX4-class presets build theirs (presets.hpp).
  al::AirframeSpec spec{};
  spec.name = "custom";
  spec.num_rotors = n;
  spec.source = al::AirframeSource::rotor_geometry;
  spec.thrust_to_torque_m = static_cast<real>(a->torque_to_thrust_m);
  spec.mass_kg = static_cast<real>(p->mass_kg);
  real lo[al::kMaxRotors] = {}, hi[al::kMaxRotors] = {};
  for (int i = 0; i < n; ++i) {
    const kestrel_rotor& r = a->rotor[i];
    for (int k = 0; k < 3; ++k) {
      spec.rotors[i].position_b_m[k] = static_cast<real>(r.position_b_m[k]);
      spec.rotors[i].axis_b[k] = static_cast<real>(r.axis_b[k]);
    }
    spec.direction[i] = static_cast<std::int8_t>(r.direction);
    lo[i] = static_cast<real>(r.thrust_min_N);
    hi[i] = static_cast<real>(r.thrust_max_N);
    spec.thrust_min_N = i == 0 || lo[i] < spec.thrust_min_N ? lo[i] : spec.thrust_min_N;
    spec.thrust_max_N = i == 0 || hi[i] > spec.thrust_max_N ? hi[i] : spec.thrust_max_N;
  }
  al::MotorModelConfig m = al::presets::motors_from(spec);
  m.integrator = al::MotorIntegrator::rk4;
  m.use_discrete_approximation = false;
  m.max_rate = 100000;
  // Off: the model is never stepped, but its reset still validates it (sane constants).
  const real kf = motors_on ? static_cast<real>(a->thrust_constant) : 0;
  const real up = motors_on ? static_cast<real>(a->time_constant_up_s) : 0.04_r;
  const real down = motors_on ? static_cast<real>(a->time_constant_down_s) : 0.04_r;
  m.use_rps = kf > 0;
  m.thrust_constant_min = m.thrust_constant_max = kf;
  m.time_constant_increasing_min_s = m.time_constant_increasing_max_s = up;
  m.time_constant_decreasing_min_s = m.time_constant_decreasing_max_s = down;
  return build_stack(storage, p, spec, lo, hi, m);
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

  // The stages' fault flags hold this step's bits only (cleared here; the C API latches its own
  // mask of faults below, so saturation and the like stay per-step conditions).
  s->st.ctrl.lee.faults.bits = 0;
  s->st.allocator.faults.bits = 0;
  s->st.motors.faults.bits = 0;

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
  std::uint32_t cond = s->st.ctrl.lee.faults.bits | s->st.allocator.faults.bits | s->st.motors.faults.bits;
  if ((s->mr.allocation.dead_mask | s->mr.allocation.weak_mask) != 0) cond |= kFaultMotorFailure;
  s->latched |= cond & kLatched;
  out->saturated_mask = s->out.allocation.saturated_mask();
  out->conditions = static_cast<std::uint16_t>(cond);
  out->faults = s->latched;
  if (worst != Status::ok) return to_c(worst);
  // Finite, but not the controller's answer to the setpoint as given: not OK (kestrel.h).
  if ((cond & kFaultCommandOutOfRange) != 0) return KESTREL_CLIPPED;
  if ((cond & kFaultSingular) != 0) return KESTREL_SINGULAR;
  return KESTREL_OK;
}

uint32_t kestrel_faults(const kestrel_storage* storage) {
  const CapiStack* s = stack_of(storage);
  if (s == nullptr) return 0;
  // The model's kFaultSingular is the rank deficiency of a flat frame, not a fault.
  return s->latched;
}

void kestrel_clear_faults(kestrel_storage* storage) {
  CapiStack* s = stack_of(storage);
  if (s == nullptr) return;
  s->st.ctrl.lee.faults.clear();
  s->st.allocator.faults.clear();
  s->st.motors.faults.clear();
  s->latched = 0;
}

kestrel_status kestrel_inject_motor_failure(kestrel_storage* storage, std::int32_t motor, float thrust_scale) {
  CapiStack* s = stack_of(storage);
  if (s == nullptr || motor < 0 || motor >= s->mr.allocation.num_rotors || !(thrust_scale >= 0.0f) || !(thrust_scale <= 1.0f)) {
    return KESTREL_INVALID_ARGUMENT;
  }
  const real scale = static_cast<real>(thrust_scale);
  if (const Status st = al::inject_motor_failure(s->st.motors, motor, scale); st != Status::ok) return to_c(st);
  s->health.thrust_scale[motor] = scale;
  if (scale < 1) s->latched |= kFaultMotorFailure;
  const Status am = al::build_allocation_model(s->mr.airframe, s->health, s->mr.allocation);
  return am == Status::singular ? KESTREL_OK : to_c(am);
}

float kestrel_command_to_throttle(float command, float thr_mdl_fac) {
  const float t = command > 0.0f ? (command < 1.0f ? command : 1.0f) : 0.0f;  // NaN -> 0
  const float k = thr_mdl_fac > 0.0f ? (thr_mdl_fac < 1.0f ? thr_mdl_fac : 1.0f) : 0.0f;
  if (!(t > 0.0f)) return 0.0f;
  // Root of k u^2 + (1 - k) u - t = 0 in the form without cancellation (exact u = t at k = 0).
  const float b = 1.0f - k;
  const float u = 2.0f * t / (b + std::sqrt(b * b + 4.0f * k * t));
  return u < 1.0f ? u : 1.0f;
}

float kestrel_thrust_to_pwm_us(float command, float thr_mdl_fac, float min_us, float max_us) {
  return min_us + kestrel_command_to_throttle(command, thr_mdl_fac) * (max_us - min_us);
}

float kestrel_command_to_pwm_us(float command, float min_us, float max_us) {
  const float c = command < 0.0f ? 0.0f : (command > 1.0f ? 1.0f : command);  // NaN -> min (motors idle)
  return c == c ? min_us + c * (max_us - min_us) : min_us;
}

}  // extern "C"
