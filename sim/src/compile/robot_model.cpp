#include "kestrel/sim/robot_model.hpp"

#include "kestrel/allocation/presets.hpp"

#include <cstdio>
#include <utility>

namespace kestrel::sim {

namespace al = kestrel::allocation;

namespace {
std::string fixed(double v, int digits) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}
std::string general(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.4g", v);
  return b;
}
}  // namespace

RobotFigures robot_figures(const WorldConfig& config, const robots::MultirotorModel& m) {
  RobotFigures f;
  f.mass_kg = static_cast<double>(config.robot.mass_kg);
  f.weight_N = f.mass_kg * static_cast<double>(config.sim.gravity_w.norm());
  f.num_rotors = m.airframe.num_rotors;
  for (int k = 0; k < m.airframe.num_rotors; ++k) {
    // Force along body z at full thrust (a tilted or downward rotor counts by its z share).
    const double z = static_cast<double>(m.airframe.effectiveness(2, k)) * static_cast<double>(m.airframe.thrust_max_N[k]);
    if (z > 0) f.max_thrust_N += z;
  }
  f.thrust_to_weight = f.weight_N > 0 ? f.max_thrust_N / f.weight_N : 0;
  return f;
}

std::string describe_robot(const WorldConfig& config, const robots::MultirotorModel& m) {
  const RobotConfig& rc = config.robot;
  const RobotFigures f = robot_figures(config, m);
  std::string s = rc.name + ": mass " + general(f.mass_kg) + " kg, inertia diag [" + general(rc.inertia_diag_kg_m2[0]) + ", " +
                  general(rc.inertia_diag_kg_m2[1]) + ", " + general(rc.inertia_diag_kg_m2[2]) + "] kg m^2, " +
                  std::to_string(f.num_rotors) + " rotors (" + (rc.rotors.empty() ? "airframe preset" : "URDF geometry") + ", ";
  bool same = true;
  for (int k = 1; k < m.airframe.num_rotors; ++k) same = same && m.airframe.thrust_max_N[k] == m.airframe.thrust_max_N[0];
  s += same && f.num_rotors > 0 ? std::to_string(f.num_rotors) + " x " + general(m.airframe.thrust_max_N[0]) + " N"
                                : std::string("per-rotor limits");
  s += "), max thrust " + general(f.max_thrust_N) + " N, weight " + general(f.weight_N) + " N, T/W " +
       (f.weight_N > 0 ? fixed(f.thrust_to_weight, 2) : std::string("n/a (no gravity)"));
  return s;
}

std::string describe_robot(const WorldConfig& config) {
  robots::MultirotorModel m;
  std::string err;
  if (config.robot.kind != robots::RobotKind::multirotor) return config.robot.name + ": mass " + general(config.robot.mass_kg) + " kg";
  if (!compile_multirotor(config, m, err)) return config.robot.name + ": " + err;
  return describe_robot(config, m);
}

bool compile_multirotor(const WorldConfig& config, robots::MultirotorModel& m, std::string& error) {
  auto fail = [&error](const std::string& msg) {
    error = msg;
    return false;
  };
  const RobotConfig& rc = config.robot;
  al::AirframeSpec spec = al::airframe_spec(rc.airframe);
  const std::size_t n_urdf_rotors = rc.rotors.size();
  if (n_urdf_rotors > 0) {
    // Rotor geometry from a URDF (sim/urdf.hpp) over the preset's limits and motor constants.
    if (n_urdf_rotors > static_cast<std::size_t>(al::kMaxRotors) || rc.rotor_directions.size() != n_urdf_rotors)
      return fail("robot.rotors: expected 1.." + std::to_string(al::kMaxRotors) + " rotors, each with a direction");
    spec.num_rotors = static_cast<int>(n_urdf_rotors);
    spec.source = al::AirframeSource::rotor_geometry;
    for (std::size_t k = 0; k < n_urdf_rotors; ++k) {
      spec.rotors[k] = rc.rotors[k];
      spec.direction[k] = rc.rotor_directions[k];
    }
  }
  if (al::make_airframe(spec, m.airframe) != Status::ok) return fail("robot.airframe: invalid airframe");
  const Status am = al::build_allocation_model(m.airframe, m.allocation);
  if (am != Status::ok && am != Status::singular)
    return fail("robot.airframe: allocation model failed");  // quads: rank 4
  m.motors = al::motor_model_preset(rc.airframe);
  if (n_urdf_rotors > 0) {
    m.motors.num_motors = spec.num_rotors;
    for (int k = 0; k < al::kMaxRotors; ++k) m.motors.direction[k] = k < spec.num_rotors ? spec.direction[k] : 0;
  }
  if (al::validate(m.motors) != Status::ok) return fail("robot.motor_model: invalid motor model");
  m.use_motor_model = true;
  m.desat = al::SequentialDesaturationParams();
  m.allocator =
      rc.use_desaturation ? robots::AllocatorKind::sequential_desaturation : robots::AllocatorKind::pseudo_inverse;
  if (controller_family(config.controller.kind) != ControlFamily::multirotor)
    return fail("controller " + config.controller.name + " drives a " +
                (controller_family(config.controller.kind) == ControlFamily::ground_vehicle ? "ground vehicle (robot ground_vehicle, simulator: planar)"
                                                                                            : "robot with joints") +
                "; a multirotor takes lee_position_control, lee_velocity_control, lee_acceleration_control, "
                "lee_attitude_control, lee_rates_control, lee_velocity_steering_angle_control, rov_fully_actuated_control or "
                "direct_motor_control");
  m.controller = config.controller.kind;
  const ControllerConfig& cc = config.controller;
  if (rc.airframe == al::AirframePreset::base_rov) {
    m.ctrl.lee = lee_params_rov();
  } else {
    // The controller section's parameters (sim/config.hpp ControllerConfig; defaults = the preset).
    m.ctrl.lee = lee_params_base_quadrotor();
    LeeGainRanges& g = m.ctrl.lee.gain_ranges;
    const std::pair<const char*, std::pair<Vec3, Vec3>> ranges[4] = {{"k_pos", {cc.k_pos_min, cc.k_pos_max}},
                                                                      {"k_vel", {cc.k_vel_min, cc.k_vel_max}},
                                                                      {"k_rot", {cc.k_rot_min, cc.k_rot_max}},
                                                                      {"k_angvel", {cc.k_angvel_min, cc.k_angvel_max}}};
    for (const auto& r : ranges)
      for (int k = 0; k < 3; ++k)
        if (!(r.second.first[k] <= r.second.second[k]))
          return fail(std::string("controller.") + r.first + "_min: expected <= " + r.first + "_max on every axis, got " +
                      std::to_string(r.second.first[k]) + " > " + std::to_string(r.second.second[k]) + " at [" + std::to_string(k) + "]");
    g.min = LeeGains{cc.k_pos_min, cc.k_vel_min, cc.k_rot_min, cc.k_angvel_min};
    g.max = LeeGains{cc.k_pos_max, cc.k_vel_max, cc.k_rot_max, cc.k_angvel_max};
    m.ctrl.lee.max_yaw_rate_radps = cc.max_yaw_rate_rad_s;
    if (!(cc.action_min < cc.action_max))
      return fail("controller.action_min: expected < action_max, got " + std::to_string(cc.action_min) + " >= " +
                  std::to_string(cc.action_max));
    m.ctrl.lee.action_min = cc.action_min;
    m.ctrl.lee.action_max = cc.action_max;
  }
  m.ctrl.lee.mass_kg = rc.mass_kg;
  m.ctrl.lee.inertia_b = Mat3(rc.inertia_diag_kg_m2.asDiagonal());
  m.ctrl.lee.gravity_w = config.sim.gravity_w;
  m.ctrl.lee.randomize_gains = cc.randomize_gains;
  // Lee parameters are checked for every kind (a direct-motor world still reports them).
  if (validate_lee_params(m.ctrl.lee) != Status::ok)
    return fail("controller: invalid Lee parameters (gains within [0, " + std::to_string(kLeeMaxGain) + "], min <= max; robot.mass_kg in (0, " +
                std::to_string(kLeeMaxMassKg) + "])");
  // Thrust-to-weight (as the C API's KESTREL_INSUFFICIENT_THRUST): below 1 the multirotor cannot
  // leave the ground and every episode ends in a crash, so the world is refused with its figures.
  if (rc.airframe != al::AirframePreset::base_rov) {
    const RobotFigures f = robot_figures(config, m);
    if (f.weight_N > 0 && f.thrust_to_weight < 1)
      return fail("robot: thrust-to-weight ratio " + fixed(f.thrust_to_weight, 2) + " < 1: " + describe_robot(config, m) +
                  "; it cannot take off. Lower robot.mass_kg or pick motors for it (robot.airframe: " +
                  "base_quadrotor 4 x 2 N, x500 4 x 10 N, hexarotor 6 x 8 N)");
  }
  if (robots::finish_multirotor_model(m) != Status::ok)
    return fail("robot: the airframe, motor model and controller " + config.controller.name + " do not fit together");
  return true;
}

}  // namespace kestrel::sim
