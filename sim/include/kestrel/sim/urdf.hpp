// URDF robot files (ROS URDF XML, parsed with tinyxml2) as input for a robot's mass, inertia,
// collision shape and rotor geometry. Read at set-up only.
//
// What is read, and the conventions:
//  - The base link is the one link that is no joint's child. Every link attached to it through
//    any joints is treated as rigid (rotors do spin, but their inertia is lumped as PhysX does for
//    Aerial Gym's robots): mass = the sum of the links' <inertial><mass>; inertia = their
//    <inertia> tensors moved to the composite centre of mass (parallel-axis theorem) and rotated
//    into the base frame.
//  - Kestrel's body frame is the centre of mass with principal axes: a composite centre of mass
//    more than 1e-6 m from the base link origin, or products of inertia above 1e-6 of the largest
//    moment, are errors (move the base link origin / align the base frame in the file).
//  - Collision: the base link's first <collision> with a <box size>, <sphere radius> or
//    <cylinder radius length> (local z axis), at the base origin (zero <origin>). No <collision>:
//    the robot keeps its configured shape. Meshes are refused (robots collide as primitives).
//  - Rotors: links named rotor_<N> or prop_<N>, N = 0, 1, ... without gaps (rotor N = motor N of
//    the allocation). Hub position = the link origin in the base frame; thrust axis = the link's
//    +z axis in the base frame; spin direction = the sign of the z component of the <axis> of the
//    continuous/revolute joint whose child the link is (axis 0 0 1: +1, counter-clockwise seen
//    from above, reaction torque about -z; axis 0 0 -1: -1), as allocation/airframe.hpp defines it.
//    No rotor links: the airframe preset's rotors stay.
// Errors name the file, the element path (e.g. link[base_link]/inertial/mass) and what is allowed.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "kestrel/allocation/airframe.hpp"
#include "kestrel/kernel/types.hpp"
#include "kestrel/sim/config.hpp"

namespace kestrel::sim {

struct UrdfRobot {
  std::string name;             // <robot name>
  std::string base_link;
  real mass_kg = 0;
  Vec3 inertia_diag_kg_m2 = Vec3::Zero();
  bool has_shape = false;
  ShapeSpec shape;
  std::vector<allocation::RotorSpec> rotors;  // rotor N at index N
  std::vector<std::int8_t> rotor_directions;
};

/// Parses a URDF file. False with a message naming the file and element; `out` untouched then.
[[nodiscard]] bool load_urdf(const std::string& path, UrdfRobot& out, std::string& error);

/// Loads `path` and writes mass, inertia, collision shape (if any) and rotors (if any) into robot.
[[nodiscard]] bool apply_urdf(const std::string& path, RobotConfig& robot, std::string& error);

}  // namespace kestrel::sim
