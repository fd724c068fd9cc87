// The second firmware example: a hexarotor flight controller loop as it would run on a real board,
// closed with the core's rigid-body plant on the target itself (host and emulated Cortex-M4F).
//
// One 1 kHz tick drives a rate scheduler:
//   every tick       rate loop: gyro (IMU model) -> body-rate controller -> allocation -> motors
//   every 2nd tick   attitude loop (500 Hz): attitude error -> body-rate setpoint
//   every 10th tick  position loop (100 Hz): position error -> desired attitude + collective thrust
//   every 67th tick  8x8 ToF frame (VL53L5CX, ~15 Hz, its 8x8 maximum rate) -> obstacle stop
// How Lee's cascade is split: update_lee_position runs at 100 Hz and gives the collective thrust
// and the desired attitude R_d (LeeState::desired_quat_xyzw) and feed-forward rate w_ff. The
// 500 Hz attitude loop turns R_d into a rate setpoint w_cmd = w_ff - (k_R / k_w) e_R with Lee's
// e_R = 1/2 vee(R_d^T R - R^T R_d); the 1 kHz rate loop is update_lee_rates, whose torque is
// -k_w (w - w_cmd) + w x J w. Run at one rate, the three give exactly Lee's torque
// -k_R e_R - k_w (w - w_ff) + w x J w; split, the inner loops see fresher attitude and gyro.
//
// Estimation: the rate loop uses the IMU model's gyro (BMI088 noise and bias, sampled every tick);
// attitude, position and velocity are taken from the plant (a perfect estimator: this example
// exercises control, allocation and sensing, not a filter). The accelerometer is sampled too, as an
// estimator would, and its mean is reported as a sanity check (about +g on z in hover).
//
// Scenario (12 s): the vehicle starts in hover at (0, 0, 1.5) m, motors spun up (the hand-off from
// a take-off phase, which with Aerial Gym's slow z gains takes ~5 s and is the first example's
// subject); from t = 2 s a setpoint carrot moves at
// 1 m/s along +x toward a wall whose face is at x = 6 m; at t = 4 s motor 0 dies (scheduled in
// the motor model; the ESC telemetry, here the motor model's health, reports it and the allocator
// is rebuilt with MotorHealth on the next tick); once the ToF's nearest valid zone reads < 1.0 m
// the carrot freezes where the vehicle is and it holds position there.
#pragma once

#include <cstdint>

#include "kestrel/allocation/airframe.hpp"
#include "kestrel/allocation/allocation_model.hpp"
#include "kestrel/allocation/motor_model.hpp"
#include "kestrel/allocation/sequential_desaturation.hpp"
#include "kestrel/controllers/lee.hpp"
#include "kestrel/kernel/rigid_body.hpp"
#include "kestrel/robots/multirotor.hpp"
#include "kestrel/kernel/rng.hpp"
#include "kestrel/kernel/status.hpp"
#include "kestrel/sensors/imu.hpp"
#include "kestrel/sensors/ray_sensor.hpp"
#include "kestrel/sensors/scene.hpp"

namespace kestrel::firmware {

/// Scheduler and scenario constants: plain constexpr data, nothing read at run time.
struct HexaConfig {
  real tick_hz = 1000;
  int attitude_divider = 2;   // 500 Hz
  int position_divider = 10;  // 100 Hz
  int tof_divider = 67;       // ~14.9 Hz (VL53L5CX 8x8 mode: at most 15 Hz)
  real duration_s = 12;
  real hover_z_m = 1.5_r;
  real cruise_start_s = 2;
  real cruise_speed_m_s = 1;
  real cruise_target_x_m = 10;  // beyond the wall: only the ToF stops the vehicle
  real wall_face_x_m = 6;
  real stop_range_m = 1.0_r;    // hold position once the nearest ToF zone is closer than this
  real failure_time_s = 4;
  int failed_motor = 0;
  real hold_window_s = 2;       // the final-hold error is measured over the last 2 s
};
inline constexpr HexaConfig kHexaConfig{};

constexpr int kTofZones = 64;

struct HexaStack {
  // The core chain (robots/multirotor.hpp): Lee gains, airframe, allocation model (rebuilt after
  // a motor failure), motor constants; controller, allocator and motor state; last outputs.
  robots::MultirotorModel model;
  robots::MultirotorState state;
  robots::MultirotorOutput out;
  allocation::MotorHealth health;  // what the allocator was last told
  sensors::ImuParams imu;
  sensors::ImuState imu_state;
  RngStream imu_rng{2, 0, kPurposeSensorNoise};
  sensors::LidarParams tof;
  sensors::Mount tof_mount;
  real tof_dirs[3 * kTofZones] = {};
  real tof_scale[kTofZones] = {};
  real tof_range[kTofZones] = {};
  // Loop outputs held between the scheduled stages.
  real collective_N = 0;              // from the position loop
  Quat desired_wb = Quat::Identity();  // from the position loop
  Vec3 rate_ff_b = Vec3::Zero();      // from the position loop
  Vec3 rate_cmd_b = Vec3::Zero();     // from the attitude loop
  real motor_norm[allocation::kMaxRotors] = {};  // 0..1 throttle per motor
  std::uint16_t motor_pwm_us[allocation::kMaxRotors] = {};
};

struct HexaPlant {
  RigidBodyModel body;
  RigidBodyState state;
  sensors::SceneStorage<4> scene_storage;
  sensors::Scene scene;
};

struct HexaReport {
  int ticks = 0;
  real hover_rms_error_m = 0;     // last 1 s before the cruise
  // From the failure to the stop. Lee position has no velocity feed-forward, so a carrot moving
  // at v is followed with a steady along-track lag of v k_vel / k_pos (1 m here): reported apart
  // from the cross-track (y, z) error, which is what the failure disturbs.
  real cruise_cross_rms_m = 0;
  real cruise_cross_max_m = 0;
  real cruise_lag_max_m = 0;
  real hold_rms_error_m = 0;      // final hold window
  real hold_max_error_m = 0;
  real final_yaw_error_rad = 0;
  real min_wall_distance_m = 1e9_r;  // vehicle centre to the wall face
  real min_tof_range_m = -1;         // nearest valid ToF zone ever read
  real stop_time_s = -1;
  real failure_detected_s = -1;
  real min_z_after_failure_m = 1e9_r;
  real mean_accel_z_hover = 0;       // accelerometer z over the hover window (m/s^2)
  real motor_norm_before[allocation::kMaxRotors] = {};  // throttle just before the failure
  real motor_norm_after[allocation::kMaxRotors] = {};   // throttle at the end
  std::uint16_t pwm_after_us[allocation::kMaxRotors] = {};
  int imu_rejected = 0;  // imu_update() statuses other than ok
  bool stopped = false;
  bool finite = true;
  std::uint32_t faults = 0;
  // Costs in clock units (host ns, MCU SysTick ticks): scheduled work of one tick (sensors,
  // controller stages, allocation, motor model; not the plant).
  std::uint64_t tick_cost_total = 0;
  std::uint64_t tick_cost_max = 0;
  std::uint64_t tof_cost_total = 0;
  int tof_frames = 0;
  std::uint64_t rebuild_cost = 0;  // build_allocation_model after the failure
};

using HexaClockFn = std::uint64_t (*)();
using HexaWaitFn = void (*)();

[[nodiscard]] Status hexa_init(const HexaConfig& config, HexaStack& stack, HexaPlant& plant);
[[nodiscard]] Status hexa_fly(const HexaConfig& config, HexaStack& stack, HexaPlant& plant, HexaClockFn clock,
                              HexaWaitFn wait, HexaReport& report);
void hexa_print_report(const HexaConfig& config, const HexaReport& report, const char* target, const char* cost_unit,
                       double cost_scale);
/// The pass criteria (documented in the .cpp): stopped before the wall, airborne after the failure,
/// bounded tracking error, finite throughout.
bool hexa_pass(const HexaConfig& config, const HexaReport& report);

}  // namespace kestrel::firmware
