// Parity of the control stack across rotor capacities: the same program is built with the default
// allocation library (KESTREL_MAX_ROTORS = 12) and with the quad build (KESTREL_MAX_ROTORS = 4,
// bench/control/mcu/CMakeLists.txt), runs the quadrotor cascade (Lee position -> sequential
// desaturation -> motor model) over 400 steps of pseudo-random states and setpoints — hover,
// large errors that saturate the motors and drive the desaturation passes, and a NaN input every
// 50 steps for the hold paths — and prints a hash of the bits of every output. The ctest
// kestrel_cascade_capacity_parity passes only if both builds print the same hash (and a
// non-trivial number of both saturated and feasible steps ran), i.e. the smaller capacity is
// bit-identical.
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

}  // namespace

int main() {
  Stack& s = g_stack;
  s.lee = lee_params_base_quadrotor();
  lee_reset(s.lee, s.lee_state);
  al::Airframe airframe;
  if (al::make_airframe(al::kBaseQuadrotor, airframe) != Status::ok) return 1;
  if (al::build_allocation_model(airframe, s.model) == Status::invalid_argument) return 1;
  al::reset_allocator(s.alloc_state);
  RngStream motor_rng(1, 0, kPurposeMotors);
  const real idle[al::kMaxRotors] = {};
  if (al::motor_model_reset(al::kBaseQuadrotorMotors, s.motors, motor_rng, idle) != Status::ok) return 1;

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
