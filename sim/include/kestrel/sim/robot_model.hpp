// Robot configuration -> the core's robot model, compiled once for every backend (MuJoCo's
// user/ compiler step: the only writer of a robots::MultirotorModel in sim/). Before this, the
// World and the planar backend each compiled the airframe, allocation, motors and Lee gains, and
// the planar copy had drifted (no URDF rotors, no ROV gains).
#pragma once

#include <string>

#include "kestrel/robots/multirotor.hpp"
#include "kestrel/sim/config.hpp"

namespace kestrel::sim {

/// Airframe (preset, or rotor geometry from a URDF), allocation model, motor model, controller
/// parameters (Lee preset for the airframe, the robot's mass and inertia, the sim's gravity,
/// direct-motor limits from the airframe) and the allocator choice. False with a message naming
/// the field on a bad configuration; `out` is then unspecified.
[[nodiscard]] bool compile_multirotor(const WorldConfig& config, robots::MultirotorModel& out, std::string& error);

/// What a compiled multirotor can lift: max thrust = the sum over rotors of thrust_max x the body-z
/// share of the rotor's axis; weight = mass x |gravity|; thrust_to_weight = their ratio (0 without gravity).
struct RobotFigures {
  double mass_kg = 0, weight_N = 0, max_thrust_N = 0, thrust_to_weight = 0;
  int num_rotors = 0;
};
RobotFigures robot_figures(const WorldConfig& config, const robots::MultirotorModel& m);
/// One line naming the robot actually flown: mass, inertia, rotors (preset or URDF), their thrust
/// limits, max thrust, weight and thrust-to-weight (compile_multirotor refuses T/W < 1).
std::string describe_robot(const WorldConfig& config, const robots::MultirotorModel& m);
/// The same, compiling the robot of `config` (a ground vehicle: its name and mass; a robot that
/// does not compile: the compile error).
std::string describe_robot(const WorldConfig& config);

}  // namespace kestrel::sim
