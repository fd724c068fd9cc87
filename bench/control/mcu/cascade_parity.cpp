// Parity of the control stack across rotor capacities: the same program is built with the default
// allocation library (KESTREL_MAX_ROTORS = 12) and with the quad build (KESTREL_MAX_ROTORS = 4,
// bench/control/mcu/CMakeLists.txt), runs the quadrotor cascade (Lee position -> sequential
// desaturation -> motor model) over 400 steps of pseudo-random states and setpoints — hover,
// large errors that saturate the motors and drive the desaturation passes, and a NaN input every
// 50 steps for the hold paths — and prints a hash of the bits of every output. The ctest
// kestrel_cascade_capacity_parity passes only if both builds print the same hash (and a
// non-trivial number of both saturated and feasible steps ran), i.e. the smaller capacity is
// bit-identical.
// Built a third time with KESTREL_CASCADE_BAKED (kestrel_cascade_parity_baked, quad capacity):
// the cascade then runs on the parameters, allocation model and initial state generated on the
// host at build time (baked_cascade.hpp, kestrel_baked_cascade_quad.hpp). Before running, the
// image also sets them up on board exactly as the other builds do and requires every field to
// have the same bits (the claim that host and MCU compute the same floats for the set-up code),
// then must print the same hash as the other two.
#include <cstdint>
#include <cstring>
#include <limits>

#include "kestrel/allocation/airframe.hpp"
#include "kestrel/allocation/allocation_model.hpp"
#include "kestrel/allocation/motor_model.hpp"
#include "kestrel/allocation/presets.hpp"
#include "kestrel/allocation/sequential_desaturation.hpp"
#include "kestrel/controllers/lee.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/platform/console.hpp"
#if defined(KESTREL_CASCADE_BAKED)
#include "kestrel_baked_cascade_quad.hpp"
#endif

namespace al = kestrel::allocation;
using namespace kestrel;

namespace {

struct Stack {
  LeeParams lee;
  LeeState lee_state;
  al::AllocationModel model;
  al::AllocatorState alloc_state;
  al::SequentialDesaturationParams desat;
  al::MotorModelState motors;
};
Stack g_stack;

// FNV-1a over the bit patterns of the outputs.
std::uint32_t g_hash = 2166136261u;
void mix(real v) {
  std::uint32_t bits;
  static_assert(sizeof(real) == sizeof(bits), "float build");
  std::memcpy(&bits, &v, sizeof(bits));
  for (int b = 0; b < 4; ++b) {
    g_hash ^= (bits >> (8 * b)) & 0xFFu;
    g_hash *= 16777619u;
  }
}

#if defined(KESTREL_CASCADE_BAKED)
// Bit comparison of two objects' numbers (fields listed one by one: padding is not compared).
int g_compared = 0, g_mismatched = 0;
template <typename T>
void same_bits(const T* a, const T* b, int n, const char* field) {
  for (int i = 0; i < n; ++i) {
    ++g_compared;
    if (std::memcmp(&a[i], &b[i], sizeof(T)) != 0) {
      ++g_mismatched;
      platform::print("baked model: MISMATCH in ");
      platform::print(field);
      platform::print("[");
      platform::print_int(i);
      platform::print("]");
      platform::println();
    }
  }
}
void same_gains(const LeeGains& a, const LeeGains& b) {
  same_bits(a.k_pos.data(), b.k_pos.data(), 3, "k_pos");
  same_bits(a.k_vel.data(), b.k_vel.data(), 3, "k_vel");
  same_bits(a.k_rot.data(), b.k_rot.data(), 3, "k_rot");
  same_bits(a.k_angvel.data(), b.k_angvel.data(), 3, "k_angvel");
}
bool baked_matches_on_board(const Stack& on_board, const Stack& b) {
  const LeeParams& lee = on_board.lee;
  const LeeParams& blee = b.lee;
  const al::AllocationModel& m = on_board.model;
  const al::AllocationModel& bm = b.model;
  same_bits(&lee.mass_kg, &blee.mass_kg, 1, "mass_kg");
  same_bits(lee.inertia_b.data(), blee.inertia_b.data(), 9, "inertia_b");
  same_bits(lee.gravity_w.data(), blee.gravity_w.data(), 3, "gravity_w");
  same_bits(&lee.max_yaw_rate_radps, &blee.max_yaw_rate_radps, 1, "max_yaw_rate_radps");
  same_gains(lee.gain_ranges.min, blee.gain_ranges.min);
  same_gains(lee.gain_ranges.max, blee.gain_ranges.max);
  same_bits(&lee.randomize_gains, &blee.randomize_gains, 1, "randomize_gains");
  same_bits(&lee.action_min, &blee.action_min, 1, "action_min");
  same_bits(&lee.action_max, &blee.action_max, 1, "action_max");
  same_bits(&m.num_rotors, &bm.num_rotors, 1, "num_rotors");
  same_bits(m.effectiveness.data(), bm.effectiveness.data(), 6 * al::kMaxRotors, "effectiveness");
  same_bits(m.pinv.data(), bm.pinv.data(), 6 * al::kMaxRotors, "pinv");
  same_bits(m.pinv_col_abs_max, bm.pinv_col_abs_max, 6, "pinv_col_abs_max");
  same_bits(m.pinv_col_movable_mask, bm.pinv_col_movable_mask, 6, "pinv_col_movable_mask");
  same_bits(m.thrust_min_N, bm.thrust_min_N, al::kMaxRotors, "thrust_min_N");
  same_bits(m.thrust_max_N, bm.thrust_max_N, al::kMaxRotors, "thrust_max_N");
  same_bits(&m.dead_mask, &bm.dead_mask, 1, "dead_mask");
  same_bits(&m.weak_mask, &bm.weak_mask, 1, "weak_mask");
  same_bits(&m.wrench_row_mask, &bm.wrench_row_mask, 1, "wrench_row_mask");
  same_bits(&m.pinv_info.rank, &bm.pinv_info.rank, 1, "pinv_info.rank");
  same_bits(&m.pinv_info.sweeps, &bm.pinv_info.sweeps, 1, "pinv_info.sweeps");
  same_bits(&m.pinv_info.rotations, &bm.pinv_info.rotations, 1, "pinv_info.rotations");
  same_bits(&m.pinv_info.converged, &bm.pinv_info.converged, 1, "pinv_info.converged");
  same_bits(&m.pinv_info.sigma_max, &bm.pinv_info.sigma_max, 1, "pinv_info.sigma_max");
  same_bits(&m.pinv_info.sigma_min_kept, &bm.pinv_info.sigma_min_kept, 1, "pinv_info.sigma_min_kept");
  same_bits(&m.faults.bits, &bm.faults.bits, 1, "faults");
  same_bits(&on_board.desat.airmode, &b.desat.airmode, 1, "airmode");
  same_bits(&on_board.desat.yaw_headroom, &b.desat.yaw_headroom, 1, "yaw_headroom");
  // Initial state (lee_reset, reset_allocator, motor_model_reset).
  const LeeState& ls = on_board.lee_state;
  const LeeState& bls = b.lee_state;
  same_gains(ls.gains, bls.gains);
  same_bits(ls.last_safe_wrench_b.force_b.data(), bls.last_safe_wrench_b.force_b.data(), 3, "last_safe_wrench_b");
  same_bits(ls.last_safe_wrench_b.torque_b.data(), bls.last_safe_wrench_b.torque_b.data(), 3, "last_safe_wrench_b");
  same_bits(&ls.faults.bits, &bls.faults.bits, 1, "lee faults");
  same_bits(&ls.step_faults, &bls.step_faults, 1, "step_faults");
  same_bits(ls.accel_command_w.data(), bls.accel_command_w.data(), 3, "accel_command_w");
  same_bits(ls.desired_quat_xyzw.data(), bls.desired_quat_xyzw.data(), 4, "desired_quat_xyzw");
  same_bits(ls.desired_angvel_b.data(), bls.desired_angvel_b.data(), 3, "desired_angvel_b");
  same_bits(&ls.inertia_diagonal, &bls.inertia_diagonal, 1, "inertia_diagonal");
  const al::AllocatorState& as = on_board.alloc_state;
  const al::AllocatorState& bas = b.alloc_state;
  same_bits(&as.num_rotors, &bas.num_rotors, 1, "alloc num_rotors");
  same_bits(as.last_thrust_N, bas.last_thrust_N, al::kMaxRotors, "last_thrust_N");
  same_bits(as.active, bas.active, al::kMaxRotors, "active");
  same_bits(&as.faults.bits, &bas.faults.bits, 1, "alloc faults");
  const al::MotorModelState& ms = on_board.motors;
  const al::MotorModelState& bms = b.motors;
  constexpr int n = al::kMaxRotors;
  same_bits(&ms.num_motors, &bms.num_motors, 1, "num_motors");
  same_bits(ms.thrust_N, bms.thrust_N, n, "thrust_N");
  same_bits(ms.axial_torque_Nm, bms.axial_torque_Nm, n, "axial_torque_Nm");
  same_bits(ms.time_constant_increasing_s, bms.time_constant_increasing_s, n, "time_constant_increasing_s");
  same_bits(ms.time_constant_decreasing_s, bms.time_constant_decreasing_s, n, "time_constant_decreasing_s");
  same_bits(ms.thrust_constant, bms.thrust_constant, n, "thrust_constant");
  same_bits(ms.health_scale, bms.health_scale, n, "health_scale");
  same_bits(ms.pending_scale, bms.pending_scale, n, "pending_scale");
  same_bits(ms.failure_time_s, bms.failure_time_s, n, "failure_time_s");
  same_bits(ms.last_reference_N, bms.last_reference_N, n, "last_reference_N");
  same_bits(&ms.pending_mask, &bms.pending_mask, 1, "pending_mask");
  same_bits(&ms.elapsed_s, &bms.elapsed_s, 1, "elapsed_s");
  same_bits(&ms.faults.bits, &bms.faults.bits, 1, "motor faults");
  platform::print("baked model: ");
  platform::print_int(g_compared);
  platform::print(" fields compared with the on-board set-up, ");
  platform::print_int(g_mismatched);
  platform::print(" differ");
  platform::println();
  return g_mismatched == 0 && g_compared > 0;
}
#endif

}  // namespace

int main() {
  Stack& s = g_stack;
  s.lee = lee_params_base_quadrotor();
  al::Airframe airframe;
  if (al::make_airframe(al::kBaseQuadrotor, airframe) != Status::ok) return 1;
  if (al::build_allocation_model(airframe, s.model) == Status::invalid_argument) return 1;
  lee_reset(s.lee, s.lee_state);
  al::reset_allocator(s.alloc_state);
  RngStream motor_rng(1, 0, kPurposeMotors);
  const real idle[al::kMaxRotors] = {};
  if (al::motor_model_reset(al::kBaseQuadrotorMotors, s.motors, motor_rng, idle) != Status::ok) return 1;
#if defined(KESTREL_CASCADE_BAKED)
  {
    // The on-board set-up above is only the reference; the cascade below runs on the baked data.
    static Stack baked;
    baked.lee = baked::kLeeBaseQuadrotor;
    baked::load(baked::kLeeStateInitial, baked.lee_state);
    baked.model = baked::kModelBaseQuadrotor;
    baked.desat = baked::kDesat;
    baked.motors = baked::kMotorsInitial;
    if (!baked_matches_on_board(s, baked)) return 1;
    s = Stack();  // nothing of the on-board result can leak into the run below
    s.lee = baked::kLeeBaseQuadrotor;
    baked::load(baked::kLeeStateInitial, s.lee_state);
    s.model = baked::kModelBaseQuadrotor;
    s.desat = baked::kDesat;
    s.motors = baked::kMotorsInitial;
  }
#endif

  RngStream rng(7, 0, 1);
  int saturated_steps = 0, feasible_steps = 0;
  for (int k = 0; k < 400; ++k) {
    // Every fourth step far from the setpoint (saturates), the others near hover.
    const real spread = (k % 4 == 0) ? 3.0_r : 0.2_r;
    RigidBodyState b;
    b.position_w = Vec3(rng.uniform(-spread, spread), rng.uniform(-spread, spread), 1 + rng.uniform(-spread, spread));
    b.linvel_w = Vec3(rng.uniform(-spread, spread), rng.uniform(-spread, spread), rng.uniform(-spread, spread));
    b.orientation_wb = quat_from_euler_xyz(rng.uniform(-0.1_r, 0.1_r) * spread, rng.uniform(-0.1_r, 0.1_r) * spread,
                                           rng.uniform(-spread, spread));
    b.angvel_b = Vec3(rng.uniform(-spread, spread), rng.uniform(-spread, spread), rng.uniform(-spread, spread));
    if (k % 50 == 49) b.position_w[0] = std::numeric_limits<real>::quiet_NaN();
    const real cmd[4] = {0, 0, 1, rng.uniform(-0.1_r, 0.1_r) * spread};
    const Wrench w = update_lee_position(s.lee, s.lee_state, b, cmd);
    al::AllocationResult out;
    (void)al::allocate_sequential_desaturation(s.model, s.desat, s.alloc_state, w, out);
    (void)al::motor_model_step(al::kBaseQuadrotorMotors, s.motors, out.thrust_N, 0.002_r);
    if (out.any_saturated()) {
      ++saturated_steps;
    } else {
      ++feasible_steps;
    }
    for (int i = 0; i < 6; ++i) mix(w.as_vec6()[i]);
    for (int i = 0; i < 4; ++i) {
      mix(out.thrust_N[i]);
      mix(s.motors.thrust_N[i]);
      mix(s.motors.axial_torque_Nm[i]);
    }
    for (int i = 0; i < 6; ++i) mix(out.wrench_unallocated[i]);
    mix(static_cast<real>(out.saturated_mask()));
  }
  // The quad build (KESTREL_MAX_ROTORS=4) keeps only the unrolled 4-rotor desaturation path and
  // refuses other rotor counts; the default build runs them on the generic path.
  {
    al::AllocationModel three = s.model;
    three.num_rotors = 3;
    al::AllocatorState st;
    al::AllocationResult r;
    Vec6 hover = Vec6::Zero();
    hover(2) = 2;
    const Status got = al::allocate_sequential_desaturation(three, s.desat, st, hover, r);
    const Status want = al::kMaxRotors == 4 ? Status::invalid_argument : Status::ok;
    if (got != want) {
      platform::print("cascade parity: FAIL: 3-rotor model gave status ");
      platform::print_int(static_cast<int>(got));
      platform::println();
      return 1;
    }
  }
  platform::print("cascade parity: capacity ");
  platform::print_int(al::kMaxRotors);
  platform::print(", saturated steps ");
  platform::print_int(saturated_steps);
  platform::print(", feasible ");
  platform::print_int(feasible_steps);
  platform::print(", hash ");
  platform::print_hex32(g_hash);
  platform::println();
  // Both allocator paths must have run often enough for the hash to mean something.
  return saturated_steps >= 50 && feasible_steps >= 50 ? 0 : 1;
}
