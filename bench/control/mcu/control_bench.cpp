// Deterministic MCU benchmark of the control stack: instructions per call of every controller,
// allocator and the motor model, of the whole cascade and of the 8x8 ToF scan, plus the
// painted-stack depth of each.
//
// Method: under `qemu -icount shift=0,sleep=off` every guest instruction is 1 ns of virtual time
// and SysTick counts the core clock (kestrel/platform/board.hpp: 40 instructions per tick on the
// 25 MHz MPS2 boards, 125 per 21 ticks on the 168 MHz netduinoplus2), so a tick count is an
// instruction count with one tick's resolution (RISC-V: mcycle, one tick per instruction). Each function runs `calls`
// times in one timed region that starts on a SysTick edge (sync_to_tick), which removes the
// phase of the 40-instruction tick from the measurement; an empty loop of the same length is
// subtracted. Each measurement is taken twice, from the same restored state, and must agree to
// the tick (the in-run check; the smaller is reported; run-mcu-bench.sh also runs the image twice and
// requires byte-identical output). Output: one CSV line per function after a "csv-begin" line.
//
// Stack: the region below the current stack pointer is painted with a pattern, the function runs
// once, and the deepest overwritten word gives its worst-case stack use for that input (the
// "painted stack" method; -fstack-usage would give a static bound per function but not the
// call-graph sum).
#include <cstddef>
#include <cstdint>

#include "kestrel/allocation/airframe.hpp"
#include "kestrel/allocation/allocation_model.hpp"
#include "kestrel/allocation/cls_allocator.hpp"
#include "kestrel/allocation/motor_model.hpp"
#include "kestrel/allocation/pinv.hpp"
#include "kestrel/allocation/presets.hpp"
#include "kestrel/allocation/sequential_desaturation.hpp"
#include "kestrel/controllers/controller.hpp"
#include "kestrel/dynamics/multibody.hpp"
#include "quadruped_tree.hpp"  // bench/dynamics: the tree the host side by side times too
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/kernel/rigid_body.hpp"
#include "kestrel/kestrel.h"
#include "kestrel/platform/board.hpp"
#include "kestrel/platform/console.hpp"
#include "kestrel/policy/mlp.hpp"
#include "kestrel/sensors/ray_sensor.hpp"
#include "go2_flat_policy.hpp"  // platform/firmware: the trained Go2 walking policy (issue 13)
#include "go2_flat_cases.hpp"   // tests/policy: observations recorded with it walking

namespace board = kestrel::platform::board;
namespace al = kestrel::allocation;
using namespace kestrel;
using kestrel::platform::print;
using kestrel::platform::println;

namespace {

// Everything the benchmarked calls touch lives in static storage, as on a flight controller.
struct Quad {
  al::Airframe airframe;
  al::AllocationModel model;
  al::AllocatorState alloc_state;
  al::SequentialDesaturationParams desat;
  al::ClsParams cls;
  al::AllocationResult out;
  al::MotorModelState motors;
  al::PinvMatrix pinv;
  LeeParams lee;
  LeeState lee_state;
};
Quad g_quad, g_hexa;
ControllerParams g_ctrl_params[kNumMultirotorControllerKinds];
ControllerState g_ctrl_state[kNumMultirotorControllerKinds];
ControllerOutput g_ctrl_out;
RigidBodyModel g_body_model;
RigidBodyState g_body, g_body_saved;
kestrel_storage g_capi, g_capi_saved;
volatile std::uint32_t g_sink;
int g_failures = 0;

// The ToF scene of tests/sensors/test_sensor_tof.cpp: floor plane, box wall, capsule post, sphere.
kestrel::sensors::SceneStorage<8> g_tof_storage;
real g_tof_dirs[3 * 64], g_tof_scale[64], g_tof_range[64];
std::int32_t g_tof_seg[64];

// A 64-64 policy network of the size Learning to Fly runs on the STM32F405 (13 position-setpoint
// observations in, 4 actions out), with PyTorch-scale random weights.
using BenchMlp = kestrel::policy::MlpParams<13, 64, 64, 4>;
BenchMlp g_mlp;
real g_mlp_obs[13], g_mlp_action[4];

void init_mlp(kestrel::policy::Activation a) {
  RngStream r(5, 0, kPurposeUser);
  g_mlp.activation = a;
  g_mlp.obs_clip = 5;
  for (int i = 0; i < 13; ++i) {
    g_mlp.obs_mean[i] = 0;
    g_mlp.obs_inv_std[i] = 1;
    g_mlp_obs[i] = r.uniform(-1, 1);
  }
  for (int o = 0; o < 64; ++o) {
    for (int i = 0; i < 13; ++i) g_mlp.hidden1.weight[o][i] = r.uniform(-0.27_r, 0.27_r);
    g_mlp.hidden1.bias[o] = r.uniform(-0.27_r, 0.27_r);
    for (int i = 0; i < 64; ++i) g_mlp.hidden2.weight[o][i] = r.uniform(-0.125_r, 0.125_r);
    g_mlp.hidden2.bias[o] = r.uniform(-0.125_r, 0.125_r);
  }
  for (int o = 0; o < 4; ++o) {
    for (int i = 0; i < 64; ++i) g_mlp.output.weight[o][i] = r.uniform(-0.125_r, 0.125_r);
    g_mlp.output.bias[o] = 0;
    g_mlp.action_low[o] = -1;
    g_mlp.action_high[o] = 1;
    g_mlp.action_scale[o] = 1;
    g_mlp.action_offset[o] = 0;
  }
}

Quad g_saved_quad, g_saved_hexa;  // state restored before every timed pass
ControllerState g_saved_ctrl[kNumMultirotorControllerKinds];

void restore() {
  g_quad = g_saved_quad;
  g_hexa = g_saved_hexa;
  for (std::size_t k = 0; k < kNumMultirotorControllerKinds; ++k) g_ctrl_state[k] = g_saved_ctrl[k];
  g_body = g_body_saved;
  g_capi = g_capi_saved;
}

// Waits for the next SysTick decrement so a region starts at a fixed phase of the tick.
inline void sync_to_tick() {
  const std::uint32_t v = board::systick_current();
  while (board::systick_current() == v) {
  }
}

template <typename F>
__attribute__((noinline)) std::uint64_t region_ticks(F& f, int calls) {
  sync_to_tick();
  const std::uint64_t t0 = board::systick_now();
  for (int k = 0; k < calls; ++k) f();
  return board::systick_now() - t0;
}

__attribute__((noinline)) std::uint64_t empty_ticks(int calls) {
  sync_to_tick();
  const std::uint64_t t0 = board::systick_now();
  for (int k = 0; k < calls; ++k) asm volatile("" ::: "memory");
  return board::systick_now() - t0;
}

constexpr std::uint32_t kPaint = 0xC0FFEE42u;
constexpr std::uint32_t kPaintBytes = 4096;  // deeper than any call measured here

// Deepest stack use of one call of f, by painting the stack below the caller's frame.
template <typename F>
__attribute__((noinline)) std::uint32_t stack_bytes(F& f) {
  std::uint32_t sp;
#if defined(__riscv)
  asm volatile("mv %0, sp" : "=r"(sp));
#else
  asm volatile("mov %0, sp" : "=r"(sp));
#endif
  // The 64 bytes just below sp are left alone: this function may still spill there.
  volatile std::uint32_t* lo = reinterpret_cast<volatile std::uint32_t*>(sp - kPaintBytes);
  volatile std::uint32_t* hi = reinterpret_cast<volatile std::uint32_t*>(sp - 64);
  for (volatile std::uint32_t* p = lo; p < hi; ++p) *p = kPaint;
  f();
  volatile std::uint32_t* p = lo;
  while (p < hi && *p == kPaint) ++p;
  return sp - reinterpret_cast<std::uint32_t>(p);
}

void print_row(const char* function, const char* airframe, std::uint64_t net_ticks, int calls, std::uint32_t stack) {
  // instructions per call with one decimal: ticks * 1e9 / core clock / calls, integer arithmetic.
  const std::uint64_t tenths = board::ticks_to_instructions(net_ticks, 10u) / static_cast<std::uint64_t>(calls);
  print(function);
  print(",");
  print(airframe);
  print(",");
  kestrel::platform::print_uint(tenths / 10u);
  print(".");
  kestrel::platform::print_uint(tenths % 10u);
  print(",");
  kestrel::platform::print_int(calls);
  print(",");
  kestrel::platform::print_uint(stack);
  println("");
}

template <typename F>
void bench(const char* function, const char* airframe, int calls, F f) {
  board::systick_start();
  const std::uint64_t empty = empty_ticks(calls);
  restore();
  const std::uint64_t a = region_ticks(f, calls);
  restore();
  const std::uint64_t b = region_ticks(f, calls);
  board::systick_stop();  // no interrupt frames in the painted region
  restore();
  const std::uint32_t stack = stack_bytes(f);
  // Both passes execute the same instructions; the tick edge can still fall one poll-loop
  // iteration (a few instructions) differently after sync_to_tick, hence the one-tick allowance.
  // Run to run the image is exactly repeatable: run-mcu-bench.sh compares two whole runs.
  if ((a > b ? a - b : b - a) > 1u) {
    print("# NOT DETERMINISTIC: ");
    print(function);
    print(" ");
    kestrel::platform::print_uint(a);
    print(" vs ");
    kestrel::platform::print_uint(b);
    println(" ticks");
    ++g_failures;
  }
  const std::uint64_t t = a < b ? a : b;
  print_row(function, airframe, t > empty ? t - empty : 0, calls, stack);
}

bool setup_frame(const al::AirframeSpec& spec, const al::MotorModelConfig& motors, Quad& q) {
  bool ok = al::make_airframe(spec, q.airframe) == Status::ok;
  const Status am = al::build_allocation_model(q.airframe, q.model);
  ok = ok && (am == Status::ok || am == Status::singular);
  al::reset_allocator(q.alloc_state);
  RngStream rng(1, 0, kPurposeMotors);
  real hover[al::kMaxRotors] = {};
  for (int i = 0; i < spec.num_rotors; ++i) hover[i] = spec.mass_kg * kStandardGravity / static_cast<real>(spec.num_rotors);
  ok = ok && al::motor_model_reset(motors, q.motors, rng, hover) == Status::ok;
  q.lee = lee_params_base_quadrotor();
  lee_reset(q.lee, q.lee_state);
  return ok;
}

}  // namespace

int main() {
  bool ok = setup_frame(al::kBaseQuadrotor, al::kBaseQuadrotorMotors, g_quad);
  ok = setup_frame(al::kHexarotor, al::kHexarotorMotors, g_hexa) && ok;
  // Every controller kind with the quad's Lee parameters; direct motor with the quad's limits.
  for (std::size_t k = 0; k < kNumMultirotorControllerKinds; ++k) {
    const auto kind = static_cast<ControllerKind>(k);
    g_ctrl_params[k].lee = kind == ControllerKind::rov_fully_actuated ? lee_params_rov() : lee_params_base_quadrotor();
    g_ctrl_params[k].motors.num_motors = 4;
    for (int i = 0; i < 4; ++i) {
      g_ctrl_params[k].motors.min_thrust_N[i] = 0;
      g_ctrl_params[k].motors.max_thrust_N[i] = 2;
    }
    controller_reset(kind, g_ctrl_params[k], g_ctrl_state[k]);
  }
  RigidBodyParams bp;
  bp.mass_kg = g_quad.lee.mass_kg;
  bp.inertia_b = g_quad.lee.inertia_b.map();
  bp.integrator = Integrator::rk4;
  ok = make_rigid_body_model(bp, g_body_model) == Status::ok && ok;
  ok = kestrel_init(&g_capi, KESTREL_PRESET_BASE_QUADROTOR) == KESTREL_OK && ok;
  // A state slightly off hover (non-trivial errors on every axis), as in the firmware example.
  g_body_saved.position_w = Vec3(0.2_r, -0.1_r, 0.9_r);
  g_body_saved.orientation_wb = quat_from_euler_xyz(0.05_r, -0.03_r, 0.2_r);
  g_body_saved.linvel_w = Vec3(0.1_r, 0.05_r, -0.02_r);
  g_body_saved.angvel_b = Vec3(0.1_r, -0.2_r, 0.05_r);
  g_capi_saved = g_capi;
  g_saved_quad = g_quad;
  g_saved_hexa = g_hexa;
  for (std::size_t k = 0; k < kNumMultirotorControllerKinds; ++k) g_saved_ctrl[k] = g_ctrl_state[k];
  restore();
  if (!ok) {
    println("control bench: setup failed");
    return 1;
  }

  print("# kestrel control bench: ");
  print(board::kCpuName);
  print(", QEMU ");
  print(board::kBoardName);
  println(", -icount shift=0, GCC -O2; instructions per call (exact to 40 / calls), painted stack bytes");
  println("csv-begin");
  println("function,airframe,instructions_per_call,calls,stack_bytes");

  constexpr int kCalls = 100;
  const real actions[kNumMultirotorControllerKinds][7] = {
      {0.0_r, 0.0_r, 1.0_r, 0.3_r},            // position [x y z yaw]
      {0.5_r, 0.2_r, -0.1_r, 0.1_r},           // velocity [vx vy vz yaw_rate]
      {0.5_r, 0.2_r, 0.3_r, 0.1_r},            // acceleration [ax ay az yaw_rate]
      {0.1_r, 0.05_r, -0.05_r, 0.1_r},         // attitude [thrust roll pitch yaw_rate]
      {0.1_r, 0.2_r, -0.1_r, 0.05_r},          // rates [thrust p q r]
      {0.5_r, 0.2_r, -0.1_r, 0.3_r},           // velocity + steering angle [vx vy vz yaw]
      {0.2_r, -0.1_r, 1.0_r, 0, 0, 0.0998334_r, 0.995004_r},  // ROV pose [x y z qx qy qz qw]
      {0.5_r, 0.6_r, 0.4_r, 0.5_r},            // direct motor thrusts
  };
  for (std::size_t k = 0; k < kNumMultirotorControllerKinds; ++k) {
    const auto kind = static_cast<ControllerKind>(k);
    bench(controller_name(kind), k == 6 ? "base_rov" : "base_quadrotor", kCalls, [k, kind, &actions] {
      g_sink = static_cast<std::uint32_t>(
          update_controller(kind, g_ctrl_params[k], g_ctrl_state[k], g_body, actions[k], 7, g_ctrl_out));
    });
  }
  const real pos_cmd[4] = {0, 0, 1, 0.3_r};
  bench("update_lee_position", "base_quadrotor", kCalls, [&pos_cmd] {
    const Wrench w = update_lee_position(g_quad.lee, g_quad.lee_state, g_body, pos_cmd);
    g_sink = static_cast<std::uint32_t>(w.force_b[2] > 0);
  });

  // Allocation. Saturating command: every desaturation pass runs; hover: the feasible fast path.
  const Vec6 sat = (Vec6() << 0, 0, 7.5_r, 0.1_r, -0.06_r, 0.01_r).finished();
  const Vec6 hover_q = (Vec6() << 0, 0, 0.25_r * kStandardGravity, 0.002_r, -0.001_r, 0.0005_r).finished();
  const Vec6 hover_h = (Vec6() << 0, 0, 2.4_r * kStandardGravity, 0.2_r, -0.1_r, 0.05_r).finished();
  bench("pseudo_inverse", "base_quadrotor", 4, [] {
    g_sink = static_cast<std::uint32_t>(al::pseudo_inverse(g_quad.airframe.effectiveness, 4, g_quad.pinv));
  });
  bench("pseudo_inverse", "hexarotor", 4, [] {
    g_sink = static_cast<std::uint32_t>(al::pseudo_inverse(g_hexa.airframe.effectiveness, 6, g_hexa.pinv));
  });
  bench("build_allocation_model", "base_quadrotor", 4, [] {
    g_sink = static_cast<std::uint32_t>(al::build_allocation_model(g_quad.airframe, g_quad.model));
  });
  bench("allocate_pinv", "base_quadrotor", kCalls, [&sat] {
    g_sink = static_cast<std::uint32_t>(al::allocate_pinv(g_quad.model, g_quad.alloc_state, sat, g_quad.out));
  });
  bench("allocate_sequential_desaturation_saturated", "base_quadrotor", kCalls, [&sat] {
    g_sink = static_cast<std::uint32_t>(
        al::allocate_sequential_desaturation(g_quad.model, g_quad.desat, g_quad.alloc_state, sat, g_quad.out));
  });
  bench("allocate_sequential_desaturation_feasible", "base_quadrotor", kCalls, [&hover_q] {
    g_sink = static_cast<std::uint32_t>(
        al::allocate_sequential_desaturation(g_quad.model, g_quad.desat, g_quad.alloc_state, hover_q, g_quad.out));
  });
  bench("allocate_sequential_desaturation_feasible", "hexarotor", kCalls, [&hover_h] {
    g_sink = static_cast<std::uint32_t>(
        al::allocate_sequential_desaturation(g_hexa.model, g_hexa.desat, g_hexa.alloc_state, hover_h, g_hexa.out));
  });
  bench("allocate_cls_warm", "base_quadrotor", kCalls, [&sat] {
    g_sink = static_cast<std::uint32_t>(al::allocate_cls(g_quad.model, g_quad.cls, g_quad.alloc_state, sat, g_quad.out));
  });
  bench("allocate_cls_warm", "hexarotor", kCalls, [&hover_h] {
    g_sink = static_cast<std::uint32_t>(al::allocate_cls(g_hexa.model, g_hexa.cls, g_hexa.alloc_state, hover_h, g_hexa.out));
  });

  // Motor model: references just off the hover thrust (the motors move every step).
  static const real ref_q[al::kMaxRotors] = {0.7_r, 0.55_r, 0.65_r, 0.6_r};
  static const real ref_h[al::kMaxRotors] = {4.1_r, 3.8_r, 4.0_r, 3.9_r, 4.2_r, 3.7_r};
  bench("motor_model_step_rk4_rps", "base_quadrotor", kCalls, [] {
    g_sink = static_cast<std::uint32_t>(al::motor_model_step(al::kBaseQuadrotorMotors, g_quad.motors, ref_q, 0.002_r));
  });
  bench("motor_model_step_rk4_rps", "hexarotor", kCalls, [] {
    g_sink = static_cast<std::uint32_t>(al::motor_model_step(al::kHexarotorMotors, g_hexa.motors, ref_h, 0.002_r));
  });

  // The whole cascade of the firmware example: Lee position -> sequential desaturation -> motor model.
  bench("cascade_lee_position_desat_motors", "base_quadrotor", kCalls, [&pos_cmd] {
    const Wrench w = update_lee_position(g_quad.lee, g_quad.lee_state, g_body, pos_cmd);
    (void)al::allocate_sequential_desaturation(g_quad.model, g_quad.desat, g_quad.alloc_state, w, g_quad.out);
    g_sink = static_cast<std::uint32_t>(al::motor_model_step(al::kBaseQuadrotorMotors, g_quad.motors, g_quad.out.thrust_N, 0.002_r));
  });
  // The same through the C API (state/setpoint conversion and the fault summary included).
  kestrel_state cs;
  for (int i = 0; i < 3; ++i) {
    cs.position_w[i] = static_cast<float>(g_body_saved.position_w[i]);
    cs.linvel_w[i] = static_cast<float>(g_body_saved.linvel_w[i]);
    cs.angvel_b[i] = static_cast<float>(g_body_saved.angvel_b[i]);
  }
  cs.orientation_xyzw[0] = static_cast<float>(g_body_saved.orientation_wb.x());
  cs.orientation_xyzw[1] = static_cast<float>(g_body_saved.orientation_wb.y());
  cs.orientation_xyzw[2] = static_cast<float>(g_body_saved.orientation_wb.z());
  cs.orientation_xyzw[3] = static_cast<float>(g_body_saved.orientation_wb.w());
  const kestrel_setpoint csp = {KESTREL_MODE_POSITION, {0.0f, 0.0f, 1.0f, 0.3f}};
  static kestrel_output cout;
  bench("kestrel_step_capi", "base_quadrotor", kCalls,
        [&cs, &csp] { g_sink = static_cast<std::uint32_t>(kestrel_step(&g_capi, &cs, &csp, 0.002f, &cout)); });
  // The 8x8 multizone ToF (VL53L5CX preset, 64 rays) against the 4-object scene of
  // tests/sensors/test_sensor_tof.cpp (its zones are checked there against analytic answers).
  {
    namespace se = kestrel::sensors;
    static se::Scene scene(g_tof_storage);
    const Quat id = Quat::Identity();
    bool tof_ok = scene.add(se::Shape::plane(), Vec3(0, 0, -0.6_r), id, 1) == Status::ok;
    tof_ok = tof_ok && scene.add(se::Shape::box(0.1_r, 2, 2), Vec3(2.1_r, 0, 0), id, 2) == Status::ok;
    tof_ok = tof_ok && scene.add(se::Shape::capsule(0.1_r, 0.5_r), Vec3(1, 0.3_r, 0), id, 3) == Status::ok;
    tof_ok = tof_ok && scene.add(se::Shape::sphere(0.15_r), Vec3(1.5_r, -0.4_r, 0.3_r), id, 4) == Status::ok;
    tof_ok = tof_ok && scene.build() == Status::ok;
    static const se::LidarParams tof = se::lidar_preset_vl53l5cx();
    static se::RayTable table{g_tof_dirs, g_tof_scale, 64, 0, 0};
    tof_ok = tof_ok && se::lidar_rays(tof, table) == Status::ok;
    static se::SensorPose pose;  // at the origin, looking along +x
    static se::SensorOutput out;
    out.range = g_tof_range;
    out.segmentation = g_tof_seg;
    tof_ok = tof_ok && se::render(scene, pose, table, tof.range, false, out) == Status::ok;
    int hits = 0;
    for (int i = 0; i < 64; ++i) hits += g_tof_seg[i] >= 0 ? 1 : 0;
    if (!tof_ok || hits == 0) {
      println("control bench: ToF scene setup failed");
      return 1;
    }
    bench("tof_scan_vl53l5cx_8x8", "scene_4_objects", 10,
          [] { g_sink = static_cast<std::uint32_t>(se::render(scene, pose, table, tof.range, false, out)); });
  }
  // The policy network (policy/mlp.hpp): one inference per call, tanh (SB3) and ELU (rsl_rl).
  init_mlp(kestrel::policy::Activation::tanh);
  bench("mlp_forward_13_64_64_4_tanh", "policy", 20,
        [] { g_sink = static_cast<std::uint32_t>(kestrel::policy::mlp_forward(g_mlp, g_mlp_obs, g_mlp_action)); });
  init_mlp(kestrel::policy::Activation::elu);
  bench("mlp_forward_13_64_64_4_elu", "policy", 20,
        [] { g_sink = static_cast<std::uint32_t>(kestrel::policy::mlp_forward(g_mlp, g_mlp_obs, g_mlp_action)); });
  // The trained Go2 walking policy (48 observations, 128-64 ELU, 12 joint targets; weights in
  // flash), one 50 Hz decision on an observation recorded with it walking.
  {
    static real obs[48], action[12];
    for (int i = 0; i < 48; ++i) obs[i] = static_cast<real>(kestrel::policy::generated::kGo2FlatObs[10][i]);
    bench("mlp_forward_go2_48_128_64_12_elu", "policy", 10, [] {
      g_sink = static_cast<std::uint32_t>(kestrel::policy::mlp_forward(kestrel::policy::generated::kGo2FlatPolicy, obs, action));
    });
  }
  // Articulated-body dynamics (dynamics/multibody.hpp): the legs of a 12-joint quadruped on a
  // fixed trunk (hip abduction about x, hip and knee flexion about y per leg; Go2-like masses),
  // one call each of RNEA, CRBA and ABA at a bent stance with joint velocities; then the same
  // quadruped on a floating trunk (free joint: 18 velocity, 19 configuration coordinates), as a
  // legged robot is simulated: trunk tilted and moving (bench/dynamics/quadruped_tree.hpp, the
  // model the host's side-by-side with Pinocchio times too).
  {
    namespace dy = kestrel::dynamics;
    static dy::MultibodyModel<13> legs;
    static dy::MultibodyData<13> dd;
    static real q[12], qd[12], qdd[12], tau[12], H[144];
    if (kestrel::bench_trees::make_quadruped_tree(legs, false) != Status::ok) {
      println("control bench: quadruped tree setup failed");
      return 1;
    }
    kestrel::bench_trees::quadruped_state(false, q, qd, qdd);
    dy::rnea(legs, dd, q, qd, qdd, tau);
    bench("rnea_quadruped_legs_12dof", "fixed_base_13_bodies", 10, [] { dy::rnea(legs, dd, q, qd, qdd, tau); });
    bench("crba_quadruped_legs_12dof", "fixed_base_13_bodies", 10, [] { dy::crba(legs, dd, q, H, 12); });
    bench("aba_quadruped_legs_12dof", "fixed_base_13_bodies", 10,
          [] { g_sink = static_cast<std::uint32_t>(dy::aba(legs, dd, q, qd, tau, qdd)); });
    static dy::MultibodyModel<13> robot;
    static real fq[19], fqd[18], fqdd[18], ftau[18], fH[18 * 18];
    if (kestrel::bench_trees::make_quadruped_tree(robot, true) != Status::ok || robot.num_q != 19) {
      println("control bench: floating quadruped setup failed");
      return 1;
    }
    kestrel::bench_trees::quadruped_state(true, fq, fqd, fqdd);
    dy::rnea(robot, dd, fq, fqd, fqdd, ftau);
    bench("rnea_quadruped_floating_18dof", "floating_base_13_bodies", 10, [] { dy::rnea(robot, dd, fq, fqd, fqdd, ftau); });
    bench("crba_quadruped_floating_18dof", "floating_base_13_bodies", 10, [] { dy::crba(robot, dd, fq, fH, 18); });
    bench("aba_quadruped_floating_18dof", "floating_base_13_bodies", 10,
          [] { g_sink = static_cast<std::uint32_t>(dy::aba(robot, dd, fq, fqd, ftau, fqdd)); });
    // One physics step of the same robot standing on the ground (dynamics/contact.hpp): the four
    // feet against the plane, then the constrained step (mass matrix, its factors, 12 contact rows,
    // projected Gauss-Seidel warm-started from the previous step's impulses, as the simulator
    // runs it). The state and the warm start are restored before each call, so every call does the same
    // work.
    static dy::ConstraintData<13, 4> cd;
    static dy::WarmStart<16> warm, warm0;
    static dy::CollisionShape feet[4];
    static real sq0[19], sqd0[18], sq[19], sqd[18], stau[18];
    kestrel::bench_trees::quadruped_feet(feet);
    kestrel::bench_trees::quadruped_standing_state(robot, dd, sq0, sqd0);
    auto standing_step = [] {
      for (int k = 0; k < 19; ++k) sq[k] = sq0[k];
      for (int k = 0; k < 18; ++k) sqd[k] = sqd0[k];
      warm = warm0;
      dy::ContactPoint contacts[4];
      dy::forward_kinematics(robot, dd, sq, cd.X_world);
      const int n = dy::collide_halfspace(feet, 4, cd.X_world, dy::HalfSpace(), 0.01_r, contacts, 4);
      g_sink = static_cast<std::uint32_t>(
          dy::step_constrained(robot, dd, cd, sq, sqd, stau, 0.005_r, contacts, n, dy::ConstraintParams(), nullptr, nullptr, &warm));
    };
    standing_step();  // primes the warm start; every timed call starts from these same impulses
    warm0 = warm;
    bench("step_constrained_quadruped_4_feet", "floating_base_13_bodies", 10, standing_step);
  }
  // The plant the firmware example closes the loop with (not part of the control stack).
  const Wrench hover_w = Wrench::from_vec6(hover_q);
  bench("step_rigid_body_rk4", "base_quadrotor", kCalls,
        [&hover_w] { g_sink = static_cast<std::uint32_t>(step_rigid_body(g_body_model, g_body, hover_w, 0.002_r)); });
  println("csv-end");
  print("# determinism: ");
  println(g_failures == 0 ? "every measurement repeated within one tick" : "FAILED");
  return g_failures == 0 ? 0 : 1;
}
