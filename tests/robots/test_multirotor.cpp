// The multirotor chain: equal bit for bit to the stages composed by hand (what the World, the
// firmware and the C API each wrote before), statuses surfaced rather than dropped, finite outputs
// for any input, no heap, and robot kinds by type.
#include <cmath>
#include <cstring>
#include <limits>

#include "kestrel/allocation/presets.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/robots/multirotor.hpp"
#include "ktest.hpp"

using namespace kestrel;
namespace al = kestrel::allocation;
namespace rb = kestrel::robots;

namespace {

bool make_quad(rb::MultirotorModel& m, ControllerKind kind, rb::AllocatorKind allocator) {
  m.controller = kind;
  m.ctrl.lee = lee_params_base_quadrotor();
  m.allocator = allocator;
  if (al::make_airframe(al::kBaseQuadrotor, m.airframe) != Status::ok) return false;
  const Status am = al::build_allocation_model(m.airframe, m.allocation);
  if (am != Status::ok && am != Status::singular) return false;
  m.motors = al::kBaseQuadrotorMotors;
  return rb::finish_multirotor_model(m) == Status::ok;
}

RigidBodyState off_hover_state(int k) {
  RigidBodyState s;
  const real t = static_cast<real>(k) * 0.01_r;
  s.position_w = Vec3(0.3_r * std::sin(t), -0.2_r, 1 + 0.1_r * std::cos(2 * t));
  s.orientation_wb = quat_from_euler_xyz(0.1_r * std::sin(t), -0.05_r, 0.7_r + t);
  s.linvel_w = Vec3(0.3_r, -0.2_r * std::cos(t), 0.1_r);
  s.angvel_b = Vec3(0.2_r, 0.1_r, -0.4_r * std::sin(3 * t));
  return s;
}

bool bits_equal(const real* a, const real* b, int n) {
  return std::memcmp(a, b, sizeof(real) * static_cast<std::size_t>(n)) == 0;
}

}  // namespace

KTEST(RobotsMultirotor, KindNames) {
  rb::RobotKind k = rb::RobotKind::multirotor;
  KEXPECT_TRUE(rb::robot_kind_from_name("ground_vehicle", k));
  KEXPECT_TRUE(k == rb::RobotKind::ground_vehicle);
  KEXPECT_TRUE(rb::robot_kind_from_name("multirotor", k));
  KEXPECT_TRUE(k == rb::RobotKind::multirotor);
  KEXPECT_FALSE(rb::robot_kind_from_name("car", k));
  KEXPECT_FALSE(rb::robot_kind_from_name(nullptr, k));
  KEXPECT_TRUE(k == rb::RobotKind::multirotor);
  KEXPECT_EQ(std::strcmp(rb::robot_kind_name(static_cast<rb::RobotKind>(9)), "unknown"), 0);
}

KTEST(RobotsMultirotor, EqualsTheStagesComposedByHand) {
  // Every wrench controller through both allocators, and direct motor commands: 300 steps each,
  // compared by memcmp against controller -> allocator -> motor model -> wrench written out.
  for (int kind_i = 0; kind_i < 8; ++kind_i) {
    const ControllerKind kind = static_cast<ControllerKind>(kind_i);
    for (int alloc_i = 0; alloc_i < 2; ++alloc_i) {
      const rb::AllocatorKind allocator = static_cast<rb::AllocatorKind>(alloc_i);
      rb::MultirotorModel m;
      KEXPECT_TRUE(make_quad(m, kind, allocator));
      rb::MultirotorState s;
      RngStream r1(7, 3, kPurposeMotors), r2(7, 3, kPurposeMotors);
      RngStream g1(7, 3, kPurposeGains), g2(7, 3, kPurposeGains);
      const real hover[al::kMaxRotors] = {0.7_r, 0.7_r, 0.7_r, 0.7_r};
      KEXPECT_NO_HEAP(KEXPECT_TRUE(rb::multirotor_reset(m, s, &g1, r1, hover) == Status::ok));
      // The same stages by hand.
      ControllerState cs;
      al::AllocatorState as;
      al::MotorModelState ms;
      controller_reset(kind, m.ctrl, cs, g2);
      al::reset_allocator(as);
      KEXPECT_TRUE(al::motor_model_reset(m.motors, ms, r2, hover) == Status::ok);
      rb::MultirotorOutput out;
      bool same = true;
      int non_ok = 0;
      for (int k = 0; k < 300; ++k) {
        const RigidBodyState x = off_hover_state(k);
        real action[kMaxActionDim] = {0.5_r, -0.3_r, 1.2_r, 0.4_r, 0, 0, 1, 0};
        if (kind == ControllerKind::direct_motor)
          for (int i = 0; i < 4; ++i) action[i] = 0.2_r * static_cast<real>(i + (k % 5));
        if (k == 150) action[0] = std::numeric_limits<real>::quiet_NaN();  // a rejected command
        Status st = Status::invalid_argument;
        KEXPECT_NO_HEAP(st = rb::multirotor_step(m, s, x, action, kMaxActionDim, 0.01_r, out));
        if (st != Status::ok) ++non_ok;

        ControllerOutput co;
        (void)update_controller(kind, m.ctrl, cs, x, action, kMaxActionDim, co);
        al::AllocationResult ar;
        const real* ref = co.motor_thrust_N;
        if (co.is_wrench) {
          if (allocator == rb::AllocatorKind::sequential_desaturation)
            (void)al::allocate_sequential_desaturation(m.allocation, m.desat, as, co.wrench_b, ar);
          else
            (void)al::allocate_pinv(m.allocation, as, co.wrench_b, ar);
          ref = ar.thrust_N;
        }
        (void)al::motor_model_step(m.motors, ms, ref, 0.01_r);
        const Vec6 w = al::wrench_from_thrusts(m.airframe.effectiveness, 4, ms.thrust_N);
        const Vec6 wc = rb::multirotor_wrench(m, s).as_vec6();
        same = same && bits_equal(s.motors.thrust_N, ms.thrust_N, 4) && bits_equal(out.allocation.thrust_N, ref, 4) &&
               bits_equal(wc.data(), w.data(), 6);
      }
      KEXPECT_TRUE(same);
      KEXPECT_GE(non_ok, 1);  // the NaN command came back as a status, not silently
      KEXPECT_TRUE((rb::multirotor_faults(s) & kFaultNonFiniteCommand) != 0);
    }
  }
}

KTEST(RobotsMultirotor, MotorModelOffAppliesSetpoints) {
  rb::MultirotorModel m;
  KEXPECT_TRUE(make_quad(m, ControllerKind::lee_position, rb::AllocatorKind::sequential_desaturation));
  m.use_motor_model = false;
  rb::MultirotorState s;
  RngStream r(1, 0, kPurposeMotors);
  KEXPECT_TRUE(rb::multirotor_reset(m, s, nullptr, r, nullptr) == Status::ok);
  rb::MultirotorOutput out;
  const real action[4] = {0, 0, 1, 0};
  KEXPECT_TRUE(rb::multirotor_step(m, s, off_hover_state(0), action, 4, 0.01_r, out) == Status::ok);
  KEXPECT_TRUE(bits_equal(s.motors.thrust_N, out.allocation.thrust_N, 4));
  real sum = 0;
  for (int i = 0; i < 4; ++i) sum += out.allocation.thrust_N[i];
  KEXPECT_GT(sum, 0);
}

KTEST(RobotsMultirotor, RefusesBadModelsAndShortActions) {
  rb::MultirotorModel m;
  KEXPECT_TRUE(make_quad(m, ControllerKind::lee_position, rb::AllocatorKind::sequential_desaturation));
  rb::MultirotorModel bad = m;
  bad.airframe.num_rotors = 0;
  KEXPECT_TRUE(rb::finish_multirotor_model(bad) == Status::invalid_argument);
  bad = m;
  bad.motors.num_motors = 6;  // motors that do not match the airframe
  KEXPECT_TRUE(rb::finish_multirotor_model(bad) == Status::invalid_argument);
  bad = m;
  bad.ctrl.lee.mass_kg = -1;
  KEXPECT_TRUE(rb::finish_multirotor_model(bad) == Status::invalid_argument);
  rb::MultirotorState s;
  RngStream r(1, 0, kPurposeMotors);
  KEXPECT_TRUE(rb::multirotor_reset(m, s, nullptr, r, nullptr) == Status::ok);
  rb::MultirotorOutput out;
  const real action[2] = {0, 0};
  const rb::MultirotorState before = s;
  KEXPECT_TRUE(rb::multirotor_step(m, s, off_hover_state(0), action, 2, 0.01_r, out) == Status::invalid_argument);
  KEXPECT_TRUE(bits_equal(before.motors.thrust_N, s.motors.thrust_N, 4));  // nothing actuated
}
