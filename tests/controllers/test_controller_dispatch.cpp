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
      "rov_fully_actuated_control", "direct_motor_control", "velocity_steering_control",
      "joint_pd_control",
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

// The one table: every kind through control_update gives exactly its own update's result (the
// multirotor kinds update_controller's, velocity steering update_velocity_steering's, joint PD
// update_joint_pd's), each family reads only its own storage, and a missing pointer, input or a
// too-short action is refused with nothing written.
KTEST(ControllerDispatch, EveryKindThroughOneTable) {
  KEXPECT_TRUE(controller_family(ControllerKind::lee_rates) == ControlFamily::multirotor);
  KEXPECT_TRUE(controller_family(ControllerKind::direct_motor) == ControlFamily::multirotor);
  KEXPECT_TRUE(controller_family(ControllerKind::velocity_steering) == ControlFamily::ground_vehicle);
  KEXPECT_TRUE(controller_family(ControllerKind::joint_pd) == ControlFamily::articulated);
  KEXPECT_FALSE(controller_outputs_wrench(ControllerKind::velocity_steering));

  // Multirotor: the same wrench as update_controller.
  ControllerParams mp;
  mp.lee = lee_params_base_quadrotor();
  ControllerState ms, ms_direct;
  ControllerParamsRef mpr;
  mpr.multirotor = &mp;
  ControllerStateRef msr;
  msr.multirotor = &ms;
  KEXPECT_TRUE(control_reset(ControllerKind::lee_velocity, mpr, msr, nullptr) == Status::ok);
  controller_reset(ControllerKind::lee_velocity, mp, ms_direct);
  RigidBodyState body;
  body.linvel_w = Vec3(0.3_r, -0.2_r, 0.1_r);
  ControllerInput in;
  in.body = &body;
  const real a4[4] = {1, -0.5_r, 0.2_r, 0.3_r};
  ControlOutput out;
  ControllerOutput direct;
  KEXPECT_TRUE(control_update(ControllerKind::lee_velocity, mpr, msr, in, a4, 4, out) == Status::ok);
  KEXPECT_TRUE(update_controller(ControllerKind::lee_velocity, mp, ms_direct, body, a4, 4, direct) == Status::ok);
  KEXPECT_TRUE(out.family == ControlFamily::multirotor);
  KEXPECT_TRUE(out.multirotor.wrench_b.force_b == direct.wrench_b.force_b);
  KEXPECT_TRUE(out.multirotor.wrench_b.torque_b == direct.wrench_b.torque_b);
  KEXPECT_EQ(controller_action_dim(ControllerKind::lee_velocity, mpr), 4u);
  // update_controller is the multirotor slice: the other families' kinds are not its.
  KEXPECT_TRUE(update_controller(ControllerKind::velocity_steering, mp, ms, body, a4, 4, direct) == Status::invalid_argument);
  KEXPECT_EQ(controller_action_dim(ControllerKind::joint_pd, mp), 0u);

  // Ground vehicle: the same drive command as update_velocity_steering, over two steps.
  VelocitySteeringParams vp;
  VelocitySteeringState vs, vs_direct;
  vs.gain_scale = 1.25_r;
  ControllerParamsRef vpr;
  vpr.steering = &vp;
  ControllerStateRef vsr;
  vsr.steering = &vs;
  KEXPECT_TRUE(control_reset(ControllerKind::velocity_steering, vpr, vsr, nullptr) == Status::ok);
  KEXPECT_EQ(vs.gain_scale, 1.25_r);  // the caller's gain draw is kept
  velocity_steering_reset(vs_direct, 1.25_r);
  ControllerInput vin;
  vin.speed_m_s = 0.4_r;
  vin.dt_s = 0.02_r;
  const real drive[2] = {1.5_r, 0.3_r};
  for (int k = 0; k < 2; ++k) {
    VelocitySteeringOutput d;
    KEXPECT_TRUE(control_update(ControllerKind::velocity_steering, vpr, vsr, vin, drive, 2, out) == Status::ok);
    KEXPECT_TRUE(update_velocity_steering(vp, vs_direct, vin.speed_m_s, drive, vin.dt_s, d) == Status::ok);
    KEXPECT_TRUE(out.family == ControlFamily::ground_vehicle);
    KEXPECT_EQ(out.drive.accel_m_s2, d.accel_m_s2);
    KEXPECT_EQ(out.drive.steering_rad, d.steering_rad);
    KEXPECT_EQ(out.drive.yaw_rate_radps, d.yaw_rate_radps);
  }
  KEXPECT_EQ(controller_action_dim(ControllerKind::velocity_steering, vpr), 2u);
  const real nan_drive[2] = {std::numeric_limits<real>::quiet_NaN(), 0};
  KEXPECT_TRUE(control_update(ControllerKind::velocity_steering, vpr, vsr, vin, nan_drive, 2, out) == Status::non_finite_input);
  KEXPECT_TRUE((control_faults(ControllerKind::velocity_steering, vsr) & kFaultNonFiniteCommand) != 0);

  // Articulated: the same torques as update_joint_pd, with its delay line.
  JointPdControlParams jp;
  jp.num_joints = 3;
  for (std::size_t j = 0; j < 3; ++j) {
    jp.kp[j] = 20;
    jp.kd[j] = 0.5_r;
    jp.torque_limit_Nm[j] = 5;
  }
  jp.delay_steps = 1;
  KEXPECT_TRUE(validate_joint_pd_params(jp) == Status::ok);
  JointPdControlState js, js_direct;
  ControllerParamsRef jpr;
  jpr.joints = &jp;
  ControllerStateRef jsr;
  jsr.joints = &js;
  KEXPECT_TRUE(control_reset(ControllerKind::joint_pd, jpr, jsr, nullptr) == Status::ok);
  joint_pd_reset(jp, js_direct);
  const real q[3] = {0.1_r, -0.2_r, 0.05_r}, qd[3] = {0.5_r, 0, -1};
  ControllerInput jin;
  jin.joint_pos_rad = q;
  jin.joint_vel_radps = qd;
  const real ja[2][3] = {{0.3_r, 0.1_r, -0.4_r}, {0.2_r, 0.2_r, 0.2_r}};
  for (int k = 0; k < 2; ++k) {
    real tau[kMaxControlJoints] = {};
    KEXPECT_TRUE(control_update(ControllerKind::joint_pd, jpr, jsr, jin, ja[k], 3, out) == Status::ok);
    KEXPECT_TRUE(update_joint_pd(jp, js_direct, q, qd, ja[k], tau) == Status::ok);
    KEXPECT_TRUE(out.family == ControlFamily::articulated);
    KEXPECT_EQ(out.num_joints, 3u);
    for (std::size_t j = 0; j < 3; ++j) KEXPECT_EQ(out.joint_torque_Nm[j], tau[j]);
  }
  KEXPECT_EQ(controller_action_dim(ControllerKind::joint_pd, jpr), 3u);

  // Refusals: nothing written.
  out.drive.accel_m_s2 = 42;
  KEXPECT_TRUE(control_update(ControllerKind::velocity_steering, mpr, msr, vin, drive, 2, out) == Status::invalid_argument);
  KEXPECT_TRUE(control_update(ControllerKind::velocity_steering, vpr, vsr, vin, drive, 1, out) == Status::invalid_argument);
  KEXPECT_TRUE(control_update(ControllerKind::lee_velocity, mpr, msr, ControllerInput(), a4, 4, out) == Status::invalid_argument);
  KEXPECT_TRUE(control_update(ControllerKind::joint_pd, jpr, jsr, ControllerInput(), ja[0], 3, out) == Status::invalid_argument);
  KEXPECT_TRUE(control_update(ControllerKind::joint_pd, jpr, jsr, jin, ja[0], 2, out) == Status::invalid_argument);
  KEXPECT_TRUE(control_update(static_cast<ControllerKind>(77), vpr, vsr, vin, drive, 2, out) == Status::invalid_argument);
  KEXPECT_TRUE(control_reset(ControllerKind::joint_pd, vpr, vsr, nullptr) == Status::invalid_argument);
  KEXPECT_EQ(out.drive.accel_m_s2, 42);
  KEXPECT_EQ(controller_action_dim(ControllerKind::joint_pd, vpr), 0u);
}
