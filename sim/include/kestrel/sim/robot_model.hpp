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

}  // namespace kestrel::sim
