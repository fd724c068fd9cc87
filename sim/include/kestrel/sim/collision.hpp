// Narrow-phase collision of convex primitives without heap allocation.
//
// FCL's GJK/EPA path allocates on every query (its EPA polytope and libccd's ccdGJKPenetration
// both build heap lists), which the step must not do. So:
//  - pairs with an exact closed form are analytic: sphere-plane, sphere-sphere, sphere-box,
//    sphere-capsule, sphere-cylinder, capsule-capsule (segment-segment closest points, Ericson,
//    "Real-Time Collision Detection", 2005, sect. 5.1.9), any convex shape against the ground
//    plane (its support point along -z);
//  - every other convex pair (box/capsule/cylinder robots against box/cylinder obstacles) goes
//    to libccd's Minkowski Portal Refinement (G. Snethen, "XenoCollide", Game Programming Gems 7,
//    2008; libccd ccdMPRPenetration), whose simplex lives on the stack, with support functions
//    over the stack-allocated Shape below.
// FCL itself is the oracle: tests/sim/engine/collision_test.cpp checks these answers against
// fcl::collide on known geometry.
//
// Convention: a Contact between shape A (the robot) and B (an obstacle / the ground) has its
// normal_w pointing from B into A (the direction A must move to separate), depth_m > 0 when
// penetrating, point_w on the contact region.
#pragma once

#include "kestrel/kernel/types.hpp"
#include "kestrel/sim/config.hpp"

namespace kestrel::sim {

/// A posed convex primitive (capsule / cylinder axis = local z).
struct Shape {
  ShapeType type = ShapeType::sphere;
  real radius_m = 0;
  real half_length_m = 0;
  Vec3 half_extents_m = Vec3::Zero();
  Vec3 position_w = Vec3::Zero();
  Quat orientation_wb = Quat::Identity();
  const Vec3* vertices = nullptr;  // convex_hull: body-frame vertices, owned by the World
  int num_vertices = 0;
};

struct Contact {
  bool hit = false;
  real depth_m = 0;
  Vec3 normal_w = Vec3::UnitZ();
  Vec3 point_w = Vec3::Zero();
};

Shape make_shape(const ShapeSpec& spec, const Vec3& position_w, const Quat& orientation_wb);

/// World-frame axis-aligned bounding box of a posed shape.
void shape_aabb(const Shape& s, Vec3& min_w, Vec3& max_w);

/// Furthest point of the shape along world direction dir_w (dir need not be unit).
Vec3 support_point(const Shape& s, const Vec3& dir_w);

/// A against the horizontal plane z = plane_z_m (solid below).
Contact collide_plane(const Shape& a, real plane_z_m);
/// A against B (any pair of primitives). Never allocates.
Contact collide(const Shape& a, const Shape& b);

}  // namespace kestrel::sim
