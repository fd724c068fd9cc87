#include "hexa_loop.hpp"

#include <cmath>

#include "kestrel/allocation/presets.hpp"
#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/platform/console.hpp"

namespace kestrel::firmware {

namespace al = kestrel::allocation;
namespace se = kestrel::sensors;

namespace {

// Lee parameters for the 2.4 kg hexarotor, derived from Aerial Gym's quadrotor ones as the C API
// does (kestrel_default_params): position gains are accelerations (mass-free) and stay; inertia
// and the attitude gains (torques) scale with m r^2 (mass ratio times squared arm ratio, hex arm
// 0.25 m against the quad's 0.13 * sqrt(2) m), so the closed-loop attitude dynamics are the quad's.
LeeParams hexa_lee_params() {
  LeeParams p = lee_params_base_quadrotor();
  const real arm_ratio = 0.25_r / (0.13_r * 1.41421356_r);
  const real scale = (al::kHexarotor.mass_kg / p.mass_kg) * arm_ratio * arm_ratio;
  p.mass_kg = al::kHexarotor.mass_kg;
  p.inertia_b *= scale;
  p.gain_ranges.min.k_rot *= scale;
  p.gain_ranges.max.k_rot *= scale;
  p.gain_ranges.min.k_angvel *= scale;
  p.gain_ranges.max.k_angvel *= scale;
  return p;
}

// Throttle of a motor: thrust ~ (rotor speed)^2 and an ESC's throttle sets rotor speed roughly
// linearly, so throttle = sqrt(thrust / max thrust). PWM: 1000 us idle/stop .. 2000 us full.
real throttle_of(real thrust_N, real max_N) {
  if (!(thrust_N > 0) || !(max_N > 0)) return 0;
  const real u = std::sqrt(thrust_N / max_N);
  return u > 1 ? 1 : u;
}

std::uint16_t pwm_us_of(real throttle) {
  return static_cast<std::uint16_t>(1000 + static_cast<int>(throttle * 1000 + 0.5_r));
}

// Lee's attitude error e_R = 1/2 vee(R_d^T R - R^T R_d).
Vec3 attitude_error(const Mat3& r_d, const Mat3& r) {
  const Mat3 e = r_d.transpose() * r - r.transpose() * r_d;
  return 0.5_r * vee(e);
}

}  // namespace

Status hexa_init(const HexaConfig& c, HexaStack& s, HexaPlant& p) {
  s.model.controller = ControllerKind::lee_rates;  // the rate loop; the outer loops call Lee position
  s.model.ctrl.lee = hexa_lee_params();
  if (const Status st = validate_lee_params(s.model.ctrl.lee); st != Status::ok) return st;
  lee_reset(s.model.ctrl.lee, s.state.ctrl.lee);
  if (const Status st = al::make_airframe(al::kHexarotor, s.model.airframe); st != Status::ok) return st;
  s.health = al::MotorHealth();
  // A flat hexarotor makes no lateral force: rank 4, reported as singular, expected.
  const Status am = al::build_allocation_model(s.model.airframe, s.health, s.model.allocation);
  if (am != Status::ok && am != Status::singular) return am;
  al::reset_allocator(s.state.allocator);
  s.model.desat = al::SequentialDesaturationParams();
  s.model.motors = al::kHexarotorMotors;
  s.model.allocator = robots::AllocatorKind::sequential_desaturation;
  s.model.use_motor_model = true;
  if (const Status st = robots::finish_multirotor_model(s.model); st != Status::ok) return st;
  RngStream motor_rng(2, 0, kPurposeMotors);
  // Motors start at hover thrust (mg / 6 each): the vehicle is handed over in hover.
  real hover[al::kMaxRotors] = {};
  for (int i = 0; i < al::kHexarotor.num_rotors; ++i)
    hover[i] = al::kHexarotor.mass_kg * kStandardGravity / static_cast<real>(al::kHexarotor.num_rotors);
  if (const Status st = al::motor_model_reset(s.model.motors, s.state.motors, motor_rng, hover); st != Status::ok) return st;
  if (const Status st = al::schedule_motor_failure(s.state.motors, c.failed_motor, 0, c.failure_time_s); st != Status::ok)
    return st;

  s.imu = se::imu_preset_bmi088();
  s.imu_rng = RngStream(2, 0, kPurposeSensorNoise);
  se::imu_reset(s.imu, s.imu_state, s.imu_rng);

  s.tof = se::lidar_preset_vl53l5cx();
  se::MountParams mp;
  mp.nominal_position_b = Vec3(0.15_r, 0, 0);  // on the front of the frame, looking along +x
  RngStream mount_rng(2, 0, kPurposePlacement);
  s.tof_mount = se::sample_mount(mp, mount_rng);
  se::RayTable table{s.tof_dirs, s.tof_scale, kTofZones, 0, 0};
  if (const Status st = se::lidar_rays(s.tof, table); st != Status::ok) return st;
  s.collective_N = 0;
  s.desired_wb = Quat::Identity();
  s.rate_ff_b = Vec3::Zero();
  s.rate_cmd_b = Vec3::Zero();

  RigidBodyParams bp;
  bp.mass_kg = s.model.ctrl.lee.mass_kg;
  bp.inertia_b = s.model.ctrl.lee.inertia_b.map();
  bp.gravity_w = s.model.ctrl.lee.gravity_w.map();
  bp.integrator = Integrator::rk4;
  if (const Status st = make_rigid_body_model(bp, p.body); st != Status::ok) return st;
  p.state = RigidBodyState();
  p.state.position_w = Vec3(0, 0, c.hover_z_m);

  // The world: a 0.2 m thick wall, 6 m wide and 4 m high, its near face at x = wall_face_x_m. No
  // floor in the scene: the ToF looks forward and the floor is the plant's business (z = 0).
  p.scene = se::Scene(p.scene_storage);
  const Quat id = Quat::Identity();
  if (const Status st = p.scene.add(se::Shape::box(0.1_r, 3, 2), Vec3(c.wall_face_x_m + 0.1_r, 0, 2), id, 1);
      st != Status::ok)
    return st;
  return p.scene.build();
}

Status hexa_fly(const HexaConfig& c, HexaStack& s, HexaPlant& p, HexaClockFn clock, HexaWaitFn wait, HexaReport& r) {
  if (const Status st = hexa_init(c, s, p); st != Status::ok) return st;
  r = HexaReport();
  const real dt = 1 / c.tick_hz;
  const int ticks = static_cast<int>(c.duration_s * c.tick_hz + 0.5_r);
  const real k_ratio_x = s.state.ctrl.lee.gains.k_rot[0] / s.state.ctrl.lee.gains.k_angvel[0];
  const real k_ratio_y = s.state.ctrl.lee.gains.k_rot[1] / s.state.ctrl.lee.gains.k_angvel[1];
  const real k_ratio_z = s.state.ctrl.lee.gains.k_rot[2] / s.state.ctrl.lee.gains.k_angvel[2];
  const real mg = s.model.ctrl.lee.mass_kg * s.model.ctrl.lee.gravity_w.map().norm();
  const Quat mount_nominal = Quat::Identity();

  real carrot_x = 0;
  bool stopped = false;
  real hold_x = 0;
  Vec3 prev_vel = Vec3::Zero();
  real hover_sq = 0, cross_sq = 0, hold_sq = 0, accel_z_sum = 0;
  int hover_n = 0, cruise_n = 0, hold_n = 0;
  bool failure_known = false;

  for (int k = 0; k < ticks; ++k) {
    const real t = static_cast<real>(k) * dt;
    if (wait != nullptr) wait();
    const std::uint64_t t0 = clock();

    // Setpoint: hover, then the cruise carrot, frozen once the ToF has stopped the vehicle.
    if (t >= c.cruise_start_s && !stopped) {
      carrot_x = (t - c.cruise_start_s) * c.cruise_speed_m_s;
      if (carrot_x > c.cruise_target_x_m) carrot_x = c.cruise_target_x_m;
    }
    const real sp_x = stopped ? hold_x : carrot_x;
    const real command[4] = {sp_x, 0, c.hover_z_m, 0};
    const RigidBodyState& truth = p.state;

    // ESC telemetry: a motor whose health dropped is reported on the next tick, and the allocator
    // is rebuilt without it (one pseudo-inverse, off the regular path).
    if (!failure_known) {
      for (int i = 0; i < s.state.motors.num_motors; ++i) {
        if (s.state.motors.health_scale[i] < s.health.thrust_scale[i]) {
          s.health.thrust_scale[i] = s.state.motors.health_scale[i];
          failure_known = true;
        }
      }
      if (failure_known) {
        const std::uint64_t b0 = clock();
        (void)al::build_allocation_model(s.model.airframe, s.health, s.model.allocation);  // singular: expected
        r.rebuild_cost = clock() - b0;
        r.failure_detected_s = t;
      }
    }

    // 100 Hz position loop: collective thrust and desired attitude (Lee position, full cascade;
    // only its thrust and R_d are used, the torque is the inner loops' job).
    if (k % c.position_divider == 0) {
      const Wrench w = update_lee_position(s.model.ctrl.lee, s.state.ctrl.lee, truth, command);
      s.collective_N = w.force_b[2];
      s.desired_wb = quat_from_xyzw(s.state.ctrl.lee.desired_quat_xyzw);
      s.rate_ff_b = s.state.ctrl.lee.desired_angvel_b;
    }
    // 500 Hz attitude loop: body-rate setpoint from the attitude error (see the header).
    if (k % c.attitude_divider == 0) {
      const Vec3 e_r = attitude_error(rotation_matrix(s.desired_wb), rotation_matrix(truth.orientation_wb));
      s.rate_cmd_b = s.rate_ff_b - Vec3(k_ratio_x * e_r[0], k_ratio_y * e_r[1], k_ratio_z * e_r[2]);
    }
    // 8x8 ToF frame: nearest valid zone (invalid zones read -1: no return within 4 m).
    if (k % c.tof_divider == 0) {
      const std::uint64_t f0 = clock();
      const se::SensorPose pose = se::sensor_pose(truth, s.tof_mount);
      const se::RayTable table{s.tof_dirs, s.tof_scale, kTofZones, s.tof.height, s.tof.width};
      se::SensorOutput out;
      out.range = s.tof_range;
      if (se::render(p.scene, pose, table, s.tof.range, false, out) == Status::ok) {
        real nearest = -1;
        for (int i = 0; i < kTofZones; ++i)
          if (s.tof_range[i] > 0 && (nearest < 0 || s.tof_range[i] < nearest)) nearest = s.tof_range[i];
        if (nearest > 0 && (r.min_tof_range_m < 0 || nearest < r.min_tof_range_m)) r.min_tof_range_m = nearest;
        if (!stopped && t >= c.cruise_start_s && nearest > 0 && nearest < c.stop_range_m) {
          stopped = true;
          hold_x = truth.position_w[0];
          r.stop_time_s = t;
        }
      }
      r.tof_cost_total += clock() - f0;
      ++r.tof_frames;
    }
    // 1 kHz rate loop on the gyro, then allocation and the motors.
    se::ImuSample imu;
    const Vec3 accel_w = (truth.linvel_w - prev_vel) / dt;
    const Status imu_st = se::imu_update(s.imu, s.imu_state, truth.orientation_wb, accel_w, truth.angvel_b,
                                         mount_nominal, dt, s.imu_rng, imu);
    RigidBodyState est = truth;
    // A rejected IMU sample is counted and reported; the rate loop then uses the true rates so a
    // sensor-model fault shows in the report instead of crashing the vehicle.
    if (imu_st == Status::ok) {
      est.angvel_b = imu.gyro_s;
    } else {
      ++r.imu_rejected;
    }
    const real rate_action[4] = {s.collective_N / mg - 1, s.rate_cmd_b[0], s.rate_cmd_b[1], s.rate_cmd_b[2]};
    // The core chain on the rate command: Lee rates -> sequential desaturation -> motor model
    // (statuses are latched as fault bits, which the report carries).
    (void)robots::multirotor_control(s.model, ControllerKind::lee_rates, s.state, est, rate_action, 4, s.out.command);
    (void)robots::multirotor_actuate(s.model, s.state, dt, s.out);
    for (int i = 0; i < s.model.airframe.num_rotors; ++i) {
      s.motor_norm[i] = throttle_of(s.out.allocation.thrust_N[i], s.model.motors.thrust_max_N);
      s.motor_pwm_us[i] = pwm_us_of(s.motor_norm[i]);
    }
    const std::uint64_t cost = clock() - t0;
    r.tick_cost_total += cost;
    if (cost > r.tick_cost_max) r.tick_cost_max = cost;

    // Plant (not part of the firmware's cost).
    prev_vel = p.state.linvel_w;
    (void)step_rigid_body(p.body, p.state, robots::multirotor_wrench(s.model, s.state), dt);
    if (p.state.position_w[2] < 0) {
      p.state.position_w[2] = 0;
      if (p.state.linvel_w[2] < 0) p.state.linvel_w = Vec3::Zero();
      p.state.angvel_b = Vec3::Zero();
    }

    // Bookkeeping.
    const Vec3 pos = p.state.position_w;
    const real e = (Vec3(sp_x, 0, c.hover_z_m) - pos).norm();
    if (!is_finite(e)) r.finite = false;
    if (t >= c.cruise_start_s - 1 && t < c.cruise_start_s) {
      hover_sq += e * e;
      ++hover_n;
      accel_z_sum += imu.accel_s[2];
    }
    if (t + dt <= c.failure_time_s) {
      for (int i = 0; i < s.model.airframe.num_rotors; ++i) r.motor_norm_before[i] = s.motor_norm[i];
    } else {
      if (pos[2] < r.min_z_after_failure_m) r.min_z_after_failure_m = pos[2];
      if (!stopped) {
        const real cross = Vec3(0, pos[1], pos[2] - c.hover_z_m).norm();
        const real lag = std::fabs(sp_x - pos[0]);
        cross_sq += cross * cross;
        ++cruise_n;
        if (cross > r.cruise_cross_max_m) r.cruise_cross_max_m = cross;
        if (lag > r.cruise_lag_max_m) r.cruise_lag_max_m = lag;
      }
    }
    if (t + dt > c.duration_s - c.hold_window_s) {
      hold_sq += e * e;
      ++hold_n;
      if (e > r.hold_max_error_m) r.hold_max_error_m = e;
    }
    const real wall_distance = c.wall_face_x_m - pos[0];
    if (wall_distance < r.min_wall_distance_m) r.min_wall_distance_m = wall_distance;
    ++r.ticks;
  }
  r.hover_rms_error_m = hover_n > 0 ? std::sqrt(hover_sq / static_cast<real>(hover_n)) : 0;
  r.cruise_cross_rms_m = cruise_n > 0 ? std::sqrt(cross_sq / static_cast<real>(cruise_n)) : 0;
  r.hold_rms_error_m = hold_n > 0 ? std::sqrt(hold_sq / static_cast<real>(hold_n)) : 0;
  r.mean_accel_z_hover = hover_n > 0 ? accel_z_sum / static_cast<real>(hover_n) : 0;
  r.final_yaw_error_rad = std::fabs(wrap_pi(euler_xyz(p.state.orientation_wb)[2]));
  for (int i = 0; i < s.model.airframe.num_rotors; ++i) {
    r.motor_norm_after[i] = s.motor_norm[i];
    r.pwm_after_us[i] = s.motor_pwm_us[i];
  }
  r.stopped = stopped;
  r.faults = robots::multirotor_faults(s.state);
  return Status::ok;
}

// Pass criteria, with margin over the measured values (see README/report):
//  - stopped by the ToF, and the vehicle centre never closer than 0.4 m to the wall face (the
//    hexarotor's 0.4 m collision sphere of sim/'s registry: no contact);
//  - the failure was seen and the vehicle stayed airborne: z > 1.0 m after it (setpoint 1.5 m);
//  - tracking error bounded: cross-track (y, z) error during the cruise with one motor out
//    max < 0.2 m, along-track lag < 1.3 m (the P-D lag is 1.0 m), final hold RMS < 0.05 m;
//  - every state finite.
bool hexa_pass(const HexaConfig& c, const HexaReport& r) {
  (void)c;
  return r.finite && r.stopped && r.min_wall_distance_m > 0.4_r && r.failure_detected_s > 0 &&
         r.min_z_after_failure_m > 1.0_r && r.cruise_cross_max_m < 0.2_r &&
         r.cruise_lag_max_m < 1.3_r && r.hold_rms_error_m < 0.05_r && r.imu_rejected == 0;
}

namespace {
void print_m(const char* label, real v_m, int decimals = 3) {
  using namespace kestrel::platform;
  print(label);
  print_fixed(static_cast<double>(v_m), decimals);
}
}  // namespace

void hexa_print_report(const HexaConfig& c, const HexaReport& r, const char* target, const char* cost_unit,
                       double cost_scale) {
  using namespace kestrel::platform;
  print("kestrel hexarotor firmware example [");
  print(target);
  println("]");
  println("  1 kHz tick: rates (gyro, IMU model) every tick, attitude every 2, position every 10, 8x8 ToF every 67");
  println("  Lee cascade split -> sequential desaturation -> motor model -> rigid body (RK4), hexarotor 2.4 kg");
  print("  ticks ");
  print_int(r.ticks);
  print_m(" (", c.duration_s, 1);
  println(" s), starting in hover at 1.5 m");
  print("  IMU samples rejected by the sensor model: ");
  print_int(r.imu_rejected);
  println("");
  print_m("  hover error RMS (1 s before cruise): ", r.hover_rms_error_m * 1000, 2);
  print_m(" mm; accelerometer z mean ", r.mean_accel_z_hover, 3);
  println(" m/s^2");
  print("  motor ");
  print_int(c.failed_motor);
  print_m(" dead at t = ", c.failure_time_s, 2);
  print_m(" s, allocator rebuilt at t = ", r.failure_detected_s, 3);
  println(" s");
  print("  throttle before failure:");
  for (int i = 0; i < 6; ++i) print_m(" ", r.motor_norm_before[i], 3);
  println("");
  print("  throttle at the end:    ");
  for (int i = 0; i < 6; ++i) print_m(" ", r.motor_norm_after[i], 3);
  println("");
  print("  PWM at the end (us):    ");
  for (int i = 0; i < 6; ++i) {
    print(" ");
    print_uint(r.pwm_after_us[i]);
  }
  println("");
  print_m("  cruise after failure (carrot 1 m/s): cross-track RMS ", r.cruise_cross_rms_m * 1000, 2);
  print_m(" mm, max ", r.cruise_cross_max_m * 1000, 2);
  print_m(" mm; along-track lag max ", r.cruise_lag_max_m, 3);
  println(" m");
  print_m("  min altitude after failure: ", r.min_z_after_failure_m, 3);
  println(" m");
  print("  ToF stop: ");
  print(r.stopped ? "yes" : "NO");
  print_m(" at t = ", r.stop_time_s, 3);
  print_m(" s; nearest ToF zone ", r.min_tof_range_m, 3);
  print_m(" m; min distance centre-to-wall ", r.min_wall_distance_m, 3);
  println(" m");
  print_m("  tracking error: final hold RMS ", r.hold_rms_error_m * 1000, 2);
  print_m(" mm, max ", r.hold_max_error_m * 1000, 2);
  print_m(" mm, yaw error ", r.final_yaw_error_rad, 4);
  print(" rad, all finite: ");
  println(r.finite ? "yes" : "NO");
  print("  fault flags: ");
  print_hex32(r.faults);
  println("");
  const double n = r.ticks > 0 ? static_cast<double>(r.ticks) : 1.0;
  print("  per scheduler tick (sensors + control + allocation + motors): mean ");
  print_fixed(static_cast<double>(r.tick_cost_total) * cost_scale / n, 0);
  print(", max ");
  print_fixed(static_cast<double>(r.tick_cost_max) * cost_scale, 0);
  print(" ");
  println(cost_unit);
  print("  per ToF frame (64 zones): ");
  print_fixed(static_cast<double>(r.tof_cost_total) * cost_scale / (r.tof_frames > 0 ? r.tof_frames : 1), 0);
  print(" ");
  print(cost_unit);
  print("; allocator rebuild: ");
  print_fixed(static_cast<double>(r.rebuild_cost) * cost_scale, 0);
  print(" ");
  println(cost_unit);
}

}  // namespace kestrel::firmware
