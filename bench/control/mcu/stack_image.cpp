// Minimal images for the flash / static-RAM figures of the control stack (run-mcu-bench.sh takes
// arm-none-eabi-size of each and subtracts the empty image, which has the same startup code,
// vector table and runtime):
//   KESTREL_STACK_EMPTY    main() only;
//   KESTREL_STACK_CASCADE  Lee position -> sequential desaturation -> motor model of the quad,
//                          built at start-up (airframe, pseudo-inverse and presets included),
//                          stepped from volatile inputs: the control stack of the firmware
//                          example without its plant and printing. Static RAM holds what
//                          persists between steps (parameters, allocation model, stage states);
//                          set-up-only data and per-step outputs are on the stack.
//                          Built twice: with the default rotor capacity (kestrel_stack_cascade)
//                          and with the allocation library at KESTREL_MAX_ROTORS=4
//                          (kestrel_stack_cascade_quad), as a quadrotor's firmware would build it;
//   KESTREL_STACK_CASCADE + KESTREL_STACK_BAKED  (kestrel_stack_cascade_quad_baked) the quad
//                          build with LeeParams, the allocation model and the desaturation
//                          parameters generated at build time on the host (baked_cascade.hpp):
//                          no presets, airframe, pseudo-inverse or reset code on board, the
//                          desaturation parameters in flash, the allocator and motor states
//                          constant-initialised, LeeParams and the allocation model read in
//                          place from flash; only LeeState is copied from a table at start-up;
//   KESTREL_STACK_CAPI     the same through the C API (every controller kind reachable);
//   KESTREL_STACK_POLICY   the trained position policy as a command source, alone: what
//                          policy_loop.cpp runs before Lee velocity control (observation builder
//                          in the vehicle frame -> policy::mlp_forward over the exported
//                          13-64-64-4 ELU network of platform/firmware/position_policy.hpp, weights
//                          constexpr in flash -> the task's action clip, the last action held on a
//                          rejected inference; the network checked at compile time), stepped from
//                          volatile inputs. No Lee controller, allocation or plant: those are the
//                          cascade image's. Static RAM: the held action only (the activations
//                          are on the stack, control.csv's mlp_forward stack_bytes).
// Nothing is printed: the console and its number formatting would count as control stack.
#include <cstdint>

#if !defined(KESTREL_STACK_EMPTY) && !defined(KESTREL_STACK_POLICY)
#include "kestrel/allocation/airframe.hpp"
#include "kestrel/allocation/allocation_model.hpp"
#include "kestrel/allocation/motor_model.hpp"
#include "kestrel/allocation/presets.hpp"
#include "kestrel/allocation/sequential_desaturation.hpp"
#include "kestrel/controllers/lee.hpp"
#endif
#if defined(KESTREL_STACK_BAKED)
#include "kestrel_baked_cascade_quad.hpp"
#endif
#if defined(KESTREL_STACK_CAPI)
#include "kestrel/kestrel.h"
#endif
#if defined(KESTREL_STACK_POLICY)
#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/rigid_body.hpp"
#include "kestrel/policy/mlp.hpp"
#include "kestrel/policy/observations.hpp"
#include "position_policy.hpp"  // platform/firmware: the network the firmware example flies
#endif

namespace {
volatile float g_in[13];   // state estimate [p v q w] written by "the estimator"
volatile float g_out[12];  // motor thrusts read by "the ESC driver"
volatile std::uint32_t g_steps = 3;
}  // namespace

#if defined(KESTREL_STACK_CASCADE)
namespace {
namespace al = kestrel::allocation;
using kestrel::real;
// What a flight controller keeps between steps: parameters, the allocation model (rebuilt when a
// motor fails) and the state of each stage. The airframe description is needed only to build
// the model and the per-step allocation result is an output, so both live on the stack.
#if defined(KESTREL_STACK_BAKED)
// Baked: LeeParams, the allocation model and the desaturation parameters are constexpr objects in
// flash that the per-step functions read in place; the allocator and motor states hold no Eigen
// member, so they are constant-initialised (zero, and the baked motor_model_reset result in
// .data). Only LeeState, which holds Eigen members, is filled at start-up (from a flash table).
struct Stack {
  kestrel::LeeState lee_state;
};
Stack g_stack;
al::AllocatorState g_alloc_state;
al::MotorModelState g_motors = kestrel::baked::kMotorsInitial;
const kestrel::LeeParams& lee_params(const Stack&) { return kestrel::baked::kLeeBaseQuadrotor; }
const al::AllocationModel& model(const Stack&) { return kestrel::baked::kModelBaseQuadrotor; }
const al::SequentialDesaturationParams& desat_params(const Stack&) { return kestrel::baked::kDesat; }
al::AllocatorState& alloc_state(Stack&) { return g_alloc_state; }
al::MotorModelState& motors(Stack&) { return g_motors; }
#else
struct Stack {
  kestrel::LeeParams lee;
  kestrel::LeeState lee_state;
  al::AllocationModel model;
  al::AllocatorState alloc_state;
  al::SequentialDesaturationParams desat;
  al::MotorModelState motors;
};
Stack g_stack;
const kestrel::LeeParams& lee_params(const Stack& s) { return s.lee; }
const al::AllocationModel& model(const Stack& s) { return s.model; }
const al::SequentialDesaturationParams& desat_params(const Stack& s) { return s.desat; }
al::AllocatorState& alloc_state(Stack& s) { return s.alloc_state; }
al::MotorModelState& motors(Stack& s) { return s.motors; }
#endif

// One control step, the entry point of bench/control/stack_usage.py's static stack bound.
__attribute__((noinline)) void cascade_step(Stack& s, const real (&in)[13], bool first) {
  using namespace kestrel;
  RigidBodyState b;
  b.position_w = Vec3(in[0], in[1], in[2]);
  b.linvel_w = Vec3(in[3], in[4], in[5]);
  b.orientation_wb = Quat(in[9], in[6], in[7], in[8]);
  if (first) b.orientation_wb = Quat::Identity();
  b.angvel_b = Vec3(in[10], in[11], in[12]);
  const real cmd[4] = {0, 0, 1, 0};
  const Wrench w = update_lee_position(lee_params(s), s.lee_state, b, cmd);
  al::AllocationResult alloc_out;
  (void)al::allocate_sequential_desaturation(model(s), desat_params(s), alloc_state(s), w, alloc_out);
  (void)al::motor_model_step(al::kBaseQuadrotorMotors, motors(s), alloc_out.thrust_N, 0.002_r);
  for (int i = 0; i < 4; ++i) g_out[i] = motors(s).thrust_N[i];
}

__attribute__((noinline)) bool setup(Stack& s) {
  using namespace kestrel;
#if defined(KESTREL_STACK_BAKED)
  // The whole set-up: copies of build-time constants (a re-arm would copy them again).
  baked::load(baked::kLeeStateInitial, s.lee_state);
  return true;
#else
  s.lee = lee_params_base_quadrotor();
  lee_reset(s.lee, s.lee_state);
  al::Airframe airframe;
  if (al::make_airframe(al::kBaseQuadrotor, airframe) != Status::ok) return false;
  if (al::build_allocation_model(airframe, s.model) == Status::invalid_argument) return false;
  al::reset_allocator(s.alloc_state);
  RngStream rng(1, 0, kPurposeMotors);
  const real idle[al::kMaxRotors] = {};
  return al::motor_model_reset(al::kBaseQuadrotorMotors, s.motors, rng, idle) == Status::ok;
#endif
}
}  // namespace

int main() {
  if (!setup(g_stack)) return 1;
  for (std::uint32_t k = 0; k < g_steps; ++k) {
    real in[13];
    for (int i = 0; i < 13; ++i) in[i] = g_in[i];
    cascade_step(g_stack, in, k == 0);
  }
  return 0;
}
#elif defined(KESTREL_STACK_CAPI)
namespace {
kestrel_storage g_storage;
}
int main() {
  if (kestrel_init(&g_storage, KESTREL_PRESET_BASE_QUADROTOR) != KESTREL_OK) return 1;
  for (std::uint32_t k = 0; k < g_steps; ++k) {
    kestrel_state st;
    for (int i = 0; i < 3; ++i) {
      st.position_w[i] = g_in[i];
      st.linvel_w[i] = g_in[3 + i];
      st.angvel_b[i] = g_in[10 + i];
    }
    for (int i = 0; i < 4; ++i) st.orientation_xyzw[i] = g_in[6 + i];
    st.orientation_xyzw[3] = 1.0f;
    const kestrel_setpoint sp = {KESTREL_MODE_POSITION, {0.0f, 0.0f, 1.0f, 0.0f}};
    kestrel_output out;
    (void)kestrel_step(&g_storage, &st, &sp, 0.002f, &out);
    for (int i = 0; i < 4; ++i) g_out[i] = out.motor_command[i];
  }
  return 0;
}
#elif defined(KESTREL_STACK_POLICY)
namespace {
using kestrel::real;
using kestrel::policy::generated::kPositionPolicy;
constexpr real kTaskActionClip = 10;  // as policy_loop.cpp: position_setpoint_task's clip
real g_action[4];                     // the last accepted action, held on a rejected inference

// One inference as the firmware runs it every control period (policy_loop.cpp, pass 0), the root
// of memory_breakdown.py's per-step code.
// It takes the vehicle state as the firmware holds it (policy_loop.cpp's RigidBodyState).
__attribute__((noinline)) void policy_step(const kestrel::RigidBodyState& b, const real (&target)[3]) {
  using namespace kestrel;
  float obs_f[policy::kPositionSetpointObsDim];
  policy::position_setpoint_observation_vehicle_frame(b, Vec3(target[0], target[1], target[2]), obs_f);
  real obs_buf[policy::kPositionSetpointObsDim];
  const real* obs = policy::observation_as_real(obs_f, obs_buf, policy::kPositionSetpointObsDim);
  real a[4];
  if (policy::mlp_forward(kPositionPolicy, obs, a) == Status::ok) {
    if constexpr (policy::actions_within(kPositionPolicy, kTaskActionClip)) {  // as policy_loop.cpp
      for (int i = 0; i < 4; ++i) g_action[i] = a[i];
    } else {
      for (int i = 0; i < 4; ++i) g_action[i] = clamp(a[i], -kTaskActionClip, kTaskActionClip);
    }
  }
  for (int i = 0; i < 4; ++i) g_out[i] = g_action[i];
}

// No set-up code: the network is checked when it is compiled (position_policy.hpp's static_assert
// on the constexpr validate_mlp), as policy_loop.cpp relies on.
}  // namespace

int main() {
  for (std::uint32_t k = 0; k < g_steps; ++k) {
    real in[13];
    for (int i = 0; i < 13; ++i) in[i] = g_in[i];
    kestrel::RigidBodyState b;
    b.position_w = kestrel::Vec3(in[0], in[1], in[2]);
    b.linvel_w = kestrel::Vec3(in[3], in[4], in[5]);
    b.orientation_wb = kestrel::Quat(in[9], in[6], in[7], in[8]);
    b.angvel_b = kestrel::Vec3(in[10], in[11], in[12]);
    const real target[3] = {in[0], in[1], 1};
    policy_step(b, target);
  }
  return 0;
}
#else
int main() {
  for (std::uint32_t k = 0; k < g_steps; ++k) g_out[0] = g_in[0];
  return 0;
}
#endif
