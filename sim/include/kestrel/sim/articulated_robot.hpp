// Robot files (MJCF or URDF) as the core's articulated-body model (dynamics/multibody.hpp). Read at
// set-up only, through MuJoCo's own compiler (mj_loadXML of the C library, Debian's libmujoco 2.2),
// so that a file means here exactly what it means to MuJoCo: defaults, classes, URDF conversion,
// the principal-axis inertias and quaternions its compiler computes. The MuJoCo model is then
// translated once into a dynamics::MultibodyModel and freed; nothing of MuJoCo is used in a step.
//
// The translation, and what it refuses (an error naming the file, the element and the problem):
//  - Bodies in MuJoCo's order (parents before children), body 0 = the first body under the world.
//    A body welded to the world (no joint on it or its ancestors) is part of the world: its geoms
//    are world geoms (body -1) and its children hang from the world.
//  - Joints: one per body at most (several: refused), free (only the first body's, from the
//    world), hinge -> revolute, slide -> prismatic, none -> fixed; ball joints are refused (the
//    core has none). The free joint's position in MuJoCo is the base's world pose, so the base's
//    X_tree is the identity.
//  - A joint placed off its body's origin (MJCF <joint pos>) moves that body's frame to the joint
//    (same orientation): its centre of mass, its geoms and its children's placements are
//    re-expressed there, which leaves the dynamics unchanged (the core's joint frame is its body's
//    frame at zero angle).
//  - X_tree from the body's pos and quat (MuJoCo's quaternions are w x y z, child -> parent):
//    E = R^T, r = the joint origin in the parent's frame.
//  - Inertia: body_mass, body_ipos (centre of mass) and the principal moments body_inertia about
//    the axes body_iquat, turned into the full tensor in the body frame. Every body needs a
//    positive mass and inertia (the core's rule; MuJoCo allows massless bodies).
//  - Per joint: dof_armature, dof_damping, dof_frictionloss, jnt_range where jnt_limited, and the
//    effort limit: an actuator on the joint with a force range (|gear| x the range) or, for a
//    plain motor with no force range, its control range (|gear x gain| x the range); a URDF
//    joint's <limit effort> when no actuator names one (MuJoCo 2.2 reads no effort from URDF).
//    Asymmetric ranges and several actuators on one joint are refused (the core's limit is one
//    number).
//  - Gravity: opt.gravity.
//  - Geoms that collide (contype or conaffinity non-zero): plane, sphere, capsule, ellipsoid,
//    cylinder, box with MuJoCo's sizes (half-sizes, radius, half-length) and pose in the body frame;
//    height fields and meshes are refused (the sim's robots collide as primitives). Visual-only
//    geoms are skipped.
//  - Feet: bodies whose name contains "foot" (any case), and the bodies of geoms so named; a foot's
//    geom is the first sphere on it (-1: none).
//  - The keyframe named "home", if any, as a configuration in the core's coordinates (the free
//    joint's quaternion turned from MuJoCo's w x y z to x y z w).
//  - Tendons, equality constraints and mocap bodies (which the core's open chains cannot hold) are
//    refused; actuators (but for the effort limits), sensors, sites, cameras and lights are ignored.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "kestrel/dynamics/contact.hpp"
#include "kestrel/dynamics/multibody.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel::sim {

/// Bodies a robot file may have (Go2 and ANYmal C: 17, feet included).
inline constexpr int kMaxRobotBodies = 32;
using RobotMultibody = dynamics::MultibodyModel<kMaxRobotBodies>;

enum class RobotGeomType : std::uint8_t { plane = 0, sphere = 1, capsule = 2, ellipsoid = 3, cylinder = 4, box = 5, mesh = 6 };

/// A collision mesh keeps at most this many vertices: its convex hull's (MuJoCo's compiler builds
/// the hull), reduced further to the hull's extreme points along a fixed set of directions when
/// there are more. The robot collides with the ground through them (dynamics::ShapeType::convex).
constexpr int kMaxMeshCollisionPoints = 64;

/// A collision primitive fixed on a body (or the world: body -1).
struct RobotGeom {
  std::string name;  // "" when the file gives none (MuJoCo 2.2 does not read URDF collision names)
  int body = -1;
  RobotGeomType type = RobotGeomType::sphere;
  Vec3 size = Vec3::Zero();   // MuJoCo's: sphere [r], capsule/cylinder [r, half-length], box half-sizes, ellipsoid radii
  Vec3 pos_b = Vec3::Zero();  // in the body's frame (the world's for body -1)
  Vec4 quat_xyzw_b = Vec4(0, 0, 0, 1);
  real friction = 1;  // sliding friction coefficient
  int contype = 1, conaffinity = 1;  // MuJoCo's collision bits (a URDF's collision geoms: 1, 1)
  std::vector<Vec3> points;  // mesh: its collision vertices in the geom's frame (m)
};

struct ArticulatedRobot {
  std::string path;
  std::string name;  // <mujoco model> / <robot name>
  RobotMultibody multibody;  // finished (finish_model ok)
  std::vector<std::string> body_names;   // per body
  std::vector<std::string> joint_names;  // per body, "" for a fixed one
  std::vector<RobotGeom> geoms;
  std::vector<int> foot_bodies;  // ascending body indices
  std::vector<int> foot_geoms;   // per foot: index into geoms of its sphere, -1 if none
  bool has_home = false;
  std::vector<real> home_q;  // num_q entries when has_home
  real total_mass_kg = 0;
};

/// Loads an MJCF or URDF file (MuJoCo decides by its root element). False with a message naming
/// the file, the element and the problem; `out` is untouched then.
[[nodiscard]] bool load_robot_model(const std::string& path, ArticulatedRobot& out, std::string& error);

/// The folder of Kestrel's robot files (models/ of the source tree, where the registry's `go2` and
/// `anymal_c` point): the KESTREL_MODELS_DIR environment variable if set, else the source tree's.
std::string models_dir();

/// The body index of `name`, -1 if none.
int find_body(const ArticulatedRobot& robot, const std::string& name);

/// A geom of the file as the core's collision primitive (dynamics/contact.hpp) on its body: a
/// sphere, capsule or box as itself; a cylinder as the capsule of its radius and half-length (its
/// end discs' rims become end spheres); an ellipsoid as its bounding box; a mesh as a convex shape
/// over g.points (which `out` points into: g must outlive it). False for a plane (no primitive of
/// the core's is a plane on a body).
bool to_collision_shape(const RobotGeom& g, dynamics::CollisionShape& out);

}  // namespace kestrel::sim
