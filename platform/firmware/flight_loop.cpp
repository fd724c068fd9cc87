#include "flight_loop.hpp"

#include <cmath>

#include "kestrel/allocation/presets.hpp"
#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/platform/console.hpp"

namespace kestrel::firmware {

namespace al = kestrel::allocation;

Status flight_init(FlightStack& s, Plant& p) {
  robots::MultirotorModel& m = s.model;
  m.controller = ControllerKind::lee_position;
  m.ctrl.lee = lee_params_base_quadrotor();
  if (const Status st = al::make_airframe(al::kBaseQuadrotor, m.airframe); st != Status::ok) return st;
  // The quad's effectiveness matrix has rank 4 (no lateral force): build_allocation_model reports
  // that as Status::singular, which is expected and harmless for a quadrotor.
  const Status am = al::build_allocation_model(m.airframe, m.allocation);
  if (am != Status::ok && am != Status::singular) return am;
  m.allocator = robots::AllocatorKind::sequential_desaturation;
  m.desat = al::SequentialDesaturationParams();
  m.motors = al::kBaseQuadrotorMotors;
  m.use_motor_model = true;
  if (const Status st = robots::finish_multirotor_model(m); st != Status::ok) return st;
  RngStream rng(1, 0, kPurposeMotors);
  const real idle[al::kMaxRotors] = {};
  if (const Status st = robots::multirotor_reset(m, s.state, nullptr, rng, idle); st != Status::ok) return st;

  RigidBodyParams bp;
  bp.mass_kg = m.ctrl.lee.mass_kg;
  bp.inertia_b = m.ctrl.lee.inertia_b.map();
  bp.gravity_w = m.ctrl.lee.gravity_w.map();
  bp.integrator = Integrator::rk4;
  if (const Status st = make_rigid_body_model(bp, p.body); st != Status::ok) return st;
  p.state = RigidBodyState();
  return Status::ok;
}

void control_step(FlightStack& s, const RigidBodyState& estimate, const real* command, real dt_s) {
  // The controller this firmware flies, called directly rather than through the controller table
  // (robots::multirotor_control): a flight controller that runs one controller need not link the
  // other six, and the call inlines (1,170 instead of 1,246 instructions per step on the M4F, 43.5
  // instead of 58.7 KB of flash). From its output on, the core chain (robots::multirotor_actuate).
  // Every stage's status is also latched in its fault flags, which fly() reports.
  s.out.command.is_wrench = true;
  s.out.command.wrench_b = update_lee_position(s.model.ctrl.lee, s.state.ctrl.lee, estimate, command);
  (void)robots::multirotor_actuate(s.model, s.state, dt_s, s.out);
}

void plant_step(const FlightStack& s, Plant& p, real dt_s) {
  (void)step_rigid_body(p.body, p.state, robots::multirotor_wrench(s.model, s.state), dt_s);
  // Ground: a rigid floor at z = 0. Resting on it, the vehicle keeps its attitude and stops.
  if (p.state.position_w[2] < 0) {
    p.state.position_w[2] = 0;
    if (p.state.linvel_w[2] < 0) p.state.linvel_w = Vec3::Zero();
    p.state.angvel_b = Vec3::Zero();
  }
}

Status fly(const FlightConfig& c, FlightStack& s, Plant& p, ClockFn clock, WaitFn wait, FlightReport& r) {
  if (const Status st = flight_init(s, p); st != Status::ok) return st;
  r = FlightReport();
  const real dt = 1 / c.control_rate_hz;
  const int steps = static_cast<int>(c.duration_s * c.control_rate_hz + 0.5_r);
  int seg = 0;
  real sum_sq[4] = {};
  int count[4] = {};
  for (int k = 0; k < steps; ++k) {
    const real t = static_cast<real>(k) * dt;
    while (seg + 1 < c.num_waypoints && t >= c.waypoints[seg + 1].t_s) ++seg;
    const Waypoint& wp = c.waypoints[seg];
    const real command[4] = {wp.position_w[0], wp.position_w[1], wp.position_w[2], wp.yaw_rad};
    if (wait != nullptr) wait();

    const std::uint64_t t0 = clock();
    control_step(s, p.state, command, dt);  // the estimate is the true state in this example
    const std::uint64_t t1 = clock();
    plant_step(s, p, dt);
    const std::uint64_t t2 = clock();
    r.control_cost_total += t1 - t0;
    r.plant_cost_total += t2 - t1;

    const Vec3 err = Vec3(wp.position_w[0], wp.position_w[1], wp.position_w[2]) - p.state.position_w;
    const real e = err.norm();
    if (!is_finite(e)) r.finite = false;
    if (seg == 0 && r.takeoff_time_s < 0 && e < 0.1_r) r.takeoff_time_s = t + dt;
    const real seg_end = seg + 1 < c.num_waypoints ? c.waypoints[seg + 1].t_s : c.duration_s;
    if (t + dt > seg_end - c.hold_window_s) {
      sum_sq[seg] += e * e;
      ++count[seg];
      if (e > r.hold_max_error_m[seg]) r.hold_max_error_m[seg] = e;
      r.hold_yaw_error_rad[seg] = std::fabs(wrap_pi(wp.yaw_rad - euler_xyz(p.state.orientation_wb)[2]));
    }
    r.final_error_m = e;
    ++r.steps;
  }
  for (int i = 0; i < c.num_waypoints; ++i) {
    r.hold_rms_error_m[i] = count[i] > 0 ? std::sqrt(sum_sq[i] / static_cast<real>(count[i])) : 0;
  }
  r.faults = robots::multirotor_faults(s.state);
  return Status::ok;
}

bool flight_pass(const FlightReport& r) { return r.finite && r.takeoff_time_s > 0 && r.final_error_m < 0.05_r; }

void print_report(const FlightConfig& c, const FlightReport& r, const char* target, const char* cost_unit,
                  double cost_scale) {
  using namespace kestrel::platform;
  print("kestrel firmware example [");
  print(target);
  println("]: Lee position -> sequential desaturation -> motor model (RK4, rotor speed) -> rigid body, base quadrotor");
  print("  control rate ");
  print_fixed(static_cast<double>(c.control_rate_hz), 0);
  print(" Hz, ");
  print_int(r.steps);
  print(" steps (");
  print_fixed(static_cast<double>(c.duration_s), 1);
  println(" s flight)");
  print("  takeoff: within 0.1 m of the first setpoint after ");
  print_fixed(static_cast<double>(r.takeoff_time_s), 3);
  println(" s");
  for (int i = 0; i < c.num_waypoints; ++i) {
    const Waypoint& w = c.waypoints[i];
    print("  setpoint ");
    print_int(i + 1);
    print(" (");
    print_fixed(static_cast<double>(w.position_w[0]), 2);
    print(", ");
    print_fixed(static_cast<double>(w.position_w[1]), 2);
    print(", ");
    print_fixed(static_cast<double>(w.position_w[2]), 2);
    print(") m yaw ");
    print_fixed(static_cast<double>(w.yaw_rad), 2);
    print(" rad: hold error RMS ");
    print_fixed(static_cast<double>(r.hold_rms_error_m[i]) * 1000.0, 2);
    print(" mm, max ");
    print_fixed(static_cast<double>(r.hold_max_error_m[i]) * 1000.0, 2);
    print(" mm, yaw error ");
    print_sci(static_cast<double>(r.hold_yaw_error_rad[i]), 2);
    println(" rad");
  }
  print("  tracking error: final ");
  print_fixed(static_cast<double>(r.final_error_m) * 1000.0, 3);
  print(" mm, all states finite: ");
  println(r.finite ? "yes" : "NO");
  print("  fault flags: ");
  print_hex32(r.faults);
  println("");
  const double n = r.steps > 0 ? static_cast<double>(r.steps) : 1.0;
  print("  cost per control step (controller + allocation + motor model): ");
  print_fixed(static_cast<double>(r.control_cost_total) * cost_scale / n, 1);
  print(" ");
  println(cost_unit);
  print("  cost per plant step (rigid body RK4 + ground): ");
  print_fixed(static_cast<double>(r.plant_cost_total) * cost_scale / n, 1);
  print(" ");
  println(cost_unit);
}

}  // namespace kestrel::firmware

namespace kestrel::firmware {
std::uint64_t time_control_steps(FlightStack& s, int n, ClockFn clock) {
  RigidBodyState hover;
  hover.position_w = Vec3(0.2_r, -0.1_r, 0.9_r);  // slightly off the setpoint: a non-trivial step
  hover.orientation_wb = quat_from_euler_xyz(0.05_r, -0.03_r, 0.2_r);
  hover.linvel_w = Vec3(0.1_r, 0.05_r, -0.02_r);
  hover.angvel_b = Vec3(0.1_r, -0.2_r, 0.05_r);
  const real command[4] = {0, 0, 1, 0};
  const real dt = 0.002_r;
  const std::uint64_t c0 = clock();
  const std::uint64_t overhead = clock() - c0;
  const std::uint64_t t0 = clock();
  for (int i = 0; i < n; ++i) control_step(s, hover, command, dt);
  const std::uint64_t total = clock() - t0;
  return total > overhead ? total - overhead : 0;
}
}  // namespace kestrel::firmware
