// Dispatch table: registry names, action widths, and that it routes to the same functions.
#include <cstring>
#include <limits>

#include "kestrel/controllers/controller.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "ktest.hpp"

using namespace kestrel;

KTEST(ControllerDispatch, NamesMatchAerialGymRegistry) {
  const char* names[kNumControllerKinds] = {
      "lee_position_control",       "lee_velocity_control", "lee_acceleration_control",
      "lee_attitude_control",       "lee_rates_control",    "lee_velocity_steering_angle_control",
      "rov_fully_actuated_control", "direct_motor_control",
  };
  for (std::size_t i = 0; i < kNumControllerKinds; ++i) {
    const ControllerKind kind = static_cast<ControllerKind>(i);
    KEXPECT_EQ(std::strcmp(controller_name(kind), names[i]), 0);
    ControllerKind back = ControllerKind::direct_motor;
    KEXPECT_TRUE(controller_kind_from_name(names[i], back));
    KEXPECT_TRUE(back == kind);
  }
  ControllerKind k = ControllerKind::lee_rates;
  KEXPECT_FALSE(controller_kind_from_name("lee_controller", k));
  KEXPECT_FALSE(controller_kind_from_name(nullptr, k));
  KEXPECT_TRUE(k == ControllerKind::lee_rates);  // untouched
  KEXPECT_EQ(std::strcmp(controller_name(static_cast<ControllerKind>(200)), "unknown"), 0);
}

KTEST(ControllerDispatch, ActionDimensions) {
  ControllerParams p;
  p.motors = direct_motor_params(8, -6.25_r, 6.25_r);
  KEXPECT_EQ(controller_action_dim(ControllerKind::lee_position, p), 4u);
  KEXPECT_EQ(controller_action_dim(ControllerKind::lee_rates, p), 4u);
  KEXPECT_EQ(controller_action_dim(ControllerKind::rov_fully_actuated, p), 7u);
  KEXPECT_EQ(controller_action_dim(ControllerKind::direct_motor, p), 8u);
  KEXPECT_EQ(controller_action_dim(static_cast<ControllerKind>(99), p), 0u);
  KEXPECT_LE(controller_action_dim(ControllerKind::direct_motor, p), kMaxActionDim);
  KEXPECT_TRUE(controller_outputs_wrench(ControllerKind::lee_attitude));
  KEXPECT_FALSE(controller_outputs_wrench(ControllerKind::direct_motor));
}

KTEST(ControllerDispatch, RoutesToTheSameControllers) {
  ControllerParams p;
  p.lee = lee_params_base_quadrotor();
  RigidBodyState body;
  body.orientation_wb = quat_from_euler_xyz(0.1_r, -0.05_r, 0.7_r);
  body.linvel_w = Vec3(0.3_r, -0.2_r, 0.1_r);
  body.angvel_b = Vec3(0.2_r, 0.1_r, -0.4_r);
  const real action[kMaxActionDim] = {0.5_r, -0.3_r, 1.2_r, 0.4_r, 0, 0, 1, 0};
  using Fn = Wrench (*)(const LeeParams&, LeeState&, const RigidBodyState&, const real*);
  const Fn direct[7] = {&update_lee_position, &update_lee_velocity, &update_lee_acceleration, &update_lee_attitude,
                        &update_lee_rates, &update_lee_velocity_steering_angle, &update_rov_fully_actuated};
  for (std::size_t i = 0; i < 7; ++i) {
    const ControllerKind kind = static_cast<ControllerKind>(i);
    ControllerState s;
    KEXPECT_NO_HEAP(controller_reset(kind, p, s));
    ControllerOutput out;
    Status st = Status::invalid_argument;
    // The whole uniform array is handed over; the controller reads what it needs.
    KEXPECT_NO_HEAP(st = update_controller(kind, p, s, body, action, kMaxActionDim, out));
    KEXPECT_TRUE(st == Status::ok);
    KEXPECT_TRUE(out.is_wrench);
    LeeState ls;
    lee_reset(p.lee, ls);
    const Wrench w = direct[i](p.lee, ls, body, action);
    KEXPECT_TRUE(w.force_b == out.wrench_b.force_b);
    KEXPECT_TRUE(w.torque_b == out.wrench_b.torque_b);
  }
}

KTEST(ControllerDispatch, DirectMotorThroughTheTable) {
  ControllerParams p;
  p.motors = direct_motor_params(4, 0, 2);
  ControllerState s;
  controller_reset(ControllerKind::direct_motor, p, s);
  const real action[4] = {0.5_r, 3, -1, 1};
  ControllerOutput out;
  Status st = Status::invalid_argument;
  KEXPECT_NO_HEAP(st = update_controller(ControllerKind::direct_motor, p, s, RigidBodyState(), action, 4, out));
  KEXPECT_TRUE(st == Status::ok);
  KEXPECT_FALSE(out.is_wrench);
  KEXPECT_EQ(out.num_motors, 4u);
  KEXPECT_EQ(out.motor_thrust_N[0], 0.5_r);
  KEXPECT_EQ(out.motor_thrust_N[1], 2);
  KEXPECT_EQ(out.motor_thrust_N[2], 0);
  KEXPECT_TRUE(s.motors.step_faults & kFaultSaturated);
}

KTEST(ControllerDispatch, BadArgumentsAndRejectedInputs) {
  ControllerParams p;
  p.lee = lee_params_base_quadrotor();
  p.motors = direct_motor_params(4, 0, 2);
  ControllerState s;
  controller_reset(ControllerKind::lee_position, p, s);
  const real action[7] = {0, 0, 0, 0, 0, 0, 1};
  ControllerOutput out;
  out.wrench_b.force_b = Vec3(1, 2, 3);
  KEXPECT_TRUE(update_controller(static_cast<ControllerKind>(42), p, s, RigidBodyState(), action, 7, out) ==
               Status::invalid_argument);
  KEXPECT_TRUE(update_controller(ControllerKind::lee_position, p, s, RigidBodyState(), action, 3, out) ==
               Status::invalid_argument);
  KEXPECT_TRUE(update_controller(ControllerKind::rov_fully_actuated, p, s, RigidBodyState(), action, 6, out) ==
               Status::invalid_argument);
  KEXPECT_TRUE(update_controller(ControllerKind::direct_motor, p, s, RigidBodyState(), action, 3, out) ==
               Status::invalid_argument);
  KEXPECT_TRUE(update_controller(ControllerKind::lee_position, p, s, RigidBodyState(), nullptr, 4, out) ==
               Status::invalid_argument);
  KEXPECT_TRUE(out.wrench_b.force_b == Vec3(1, 2, 3));  // nothing written
  const real nan_action[4] = {0, std::numeric_limits<real>::quiet_NaN(), 0, 0};
  KEXPECT_TRUE(update_controller(ControllerKind::lee_position, p, s, RigidBodyState(), nan_action, 4, out) ==
               Status::non_finite_input);
  KEXPECT_TRUE(out.wrench_b.force_b == Vec3::Zero());
  KEXPECT_TRUE(update_controller(ControllerKind::direct_motor, p, s, RigidBodyState(), nan_action, 4, out) ==
               Status::non_finite_input);
  // Clipping is not a rejection.
  const real big[4] = {20, 0, 0, 0};
  KEXPECT_TRUE(update_controller(ControllerKind::lee_position, p, s, RigidBodyState(), big, 4, out) == Status::ok);
  KEXPECT_TRUE(s.lee.step_faults & kFaultCommandOutOfRange);
}
