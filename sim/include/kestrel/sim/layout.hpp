// The obstacle layout of an environment, generated once for every backend (issue 10: the rigid
// World and the planar backend each had their own generator, and they had drifted: the planar
// one drew every asset whatever the curriculum level and had no tree branches). The rigid World
// keeps the layout's 3-D shapes as they are; the planar backend keeps the footprints of the
// upright ones (sim/src/backends/planar.cpp).
#pragma once

#include <cstdint>
#include <vector>

#include "kestrel/kernel/rng.hpp"
#include "kestrel/sim/collision.hpp"
#include "kestrel/sim/config.hpp"

namespace kestrel::sim {

/// One obstacle slot. Obstacles of an environment are kept sorted by aabb_min_w.x (the sweep
/// order of the rigid World's broad phase); a moving obstacle may change its index after a step.
struct Obstacle {
  Shape shape;
  Vec3 linvel_w = Vec3::Zero();   // dynamic environment: set per reset or by set_obstacle_velocity
  Vec3 angvel_w = Vec3::Zero();   // dynamic environment: world-frame angular velocity, set per reset
  Vec3 aabb_min_w = Vec3::Zero();
  Vec3 aabb_max_w = Vec3::Zero();
  std::int16_t semantic_id = 0;
  AssetKind kind = AssetKind::cube;
  std::uint8_t class_index = 0;
  /// Stands on the ground with a vertical axis, so its cross-section at any height is its
  /// footprint (pillars, trunks, boxes, side walls): what a planar backend keeps. False for a
  /// tree's branches and the walls' ceiling.
  bool upright = true;
};

/// Draws a layout for the bounds [lower_w, upper_w] at curriculum level in [0, 1] into slots
/// (capacity: the sum of asset_class_slots over cfg.env.assets), in asset-class order, with each
/// obstacle's bounding box set; returns how many it wrote. mesh_vertices: per asset class, the
/// hull vertices of AssetKind::mesh classes (nullptr where no class is a mesh). No heap.
/// Draws per asset: position ratio, Euler angles, size, then the kind's own draws (tree branches),
/// then velocities for moving or spinning classes; a class draws only for the assets the level
/// asks for.
int generate_layout(const WorldConfig& cfg, real curriculum_level, const Vec3& lower_w, const Vec3& upper_w, RngStream& rng,
                    const std::vector<std::vector<Vec3>>* mesh_vertices, Obstacle* slots);

/// The same, handing each obstacle to sink(context, obstacle) in order instead of storing it (what
/// a backend with its own obstacle storage uses: the planar backend maps each upright one to its
/// Box2D slot). Returns how many it handed over.
using LayoutSink = void (*)(void* context, const Obstacle& obstacle);
int generate_layout(const WorldConfig& cfg, real curriculum_level, const Vec3& lower_w, const Vec3& upper_w, RngStream& rng,
                    const std::vector<std::vector<Vec3>>* mesh_vertices, LayoutSink sink, void* context);

}  // namespace kestrel::sim
