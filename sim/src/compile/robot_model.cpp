#include "kestrel/sim/robot_model.hpp"

#include "kestrel/allocation/presets.hpp"

namespace kestrel::sim {

namespace al = kestrel::allocation;

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
  m.ctrl.lee = rc.airframe == al::AirframePreset::base_rov ? lee_params_rov() : lee_params_base_quadrotor();
  m.ctrl.lee.mass_kg = rc.mass_kg;
  m.ctrl.lee.inertia_b = rc.inertia_diag_kg_m2.asDiagonal();
  m.ctrl.lee.gravity_w = config.sim.gravity_w;
  m.ctrl.lee.randomize_gains = config.controller.randomize_gains;
  // Lee parameters are checked for every kind (a direct-motor world still reports them).
  if (validate_lee_params(m.ctrl.lee) != Status::ok) return fail("controller: invalid Lee parameters");
  if (robots::finish_multirotor_model(m) != Status::ok)
    return fail("robot: the airframe, motor model and controller " + config.controller.name + " do not fit together");
  return true;
}

}  // namespace kestrel::sim
