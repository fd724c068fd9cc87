// URDF robot files (ROS URDF XML, parsed with tinyxml2) as input for a robot's mass, inertia,
// collision shape and rotor geometry. Read at set-up only.
//
// What is read, and the conventions:
//  - The base link is the one link that is no joint's child. Every link attached to it through
//    any joints is treated as rigid (rotors do spin, but their inertia is lumped as PhysX does for
//    Aerial Gym's robots): mass = the sum of the links' <inertial><mass>; inertia = their
//    <inertia> tensors moved to the composite centre of mass (parallel-axis theorem) and rotated
//    into the base frame.
//  - Kestrel's body frame is the centre of mass with principal axes. A composite centre of mass
//    off the base link origin (most real URDFs) is supported by re-expressing the body about it:
//    the body frame is the centre of mass with the base link's axes, rotor hub positions are taken
//    relative to it (so the allocation sees the true moment arms and balances the offset), and the
//    inertia is about it (parallel-axis theorem). The robot's position (state, logs, targets) is
//    then that of the centre of mass. UrdfRobot::com_offset_m says where it is in the base frame.
//    Products of inertia above 1e-6 of the largest moment are errors (align the base frame).
//  - The collision primitive stays centred on the body frame (the centre of mass): with an offset
//    centre of mass it is shifted by com_offset_m from where the file puts it (the shape has no
//    offset of its own).
//  - Collision: the base link's first <collision> with a <box size>, <sphere radius> or
//    <cylinder radius length> (local z axis), at the base origin (zero <origin>). No <collision>:
//    the robot keeps its configured shape. Meshes are refused (robots collide as primitives).
//  - Rotors: links named rotor_<N> or prop_<N>, N = 0, 1, ... without gaps (rotor N = motor N of
//    the allocation). Hub position = the link origin relative to the centre of mass; thrust axis = the link's
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
  Vec3 inertia_diag_kg_m2 = Vec3::Zero();  // about the centre of mass
  Vec3 com_offset_m = Vec3::Zero();        // composite centre of mass in the base link frame
  bool has_shape = false;
  ShapeSpec shape;
  std::vector<allocation::RotorSpec> rotors;  // rotor N at index N
  std::vector<std::int8_t> rotor_directions;
};

/// Parses a URDF file. False with a message naming the file and element; `out` untouched then.
[[nodiscard]] bool load_urdf(const std::string& path, UrdfRobot& out, std::string& error);

/// Loads `path` and writes mass, inertia, collision shape (if any) and rotors (if any) into robot;
/// `urdf_name` (if given) receives the file's <robot name>.
[[nodiscard]] bool apply_urdf(const std::string& path, RobotConfig& robot, std::string& error, std::string* urdf_name = nullptr);

}  // namespace kestrel::sim
