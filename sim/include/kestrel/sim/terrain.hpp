// Terrain of the `rigid` world: plane, height field or triangle mesh (TerrainConfig in config.hpp),
// shared read-only by every environment of a world (one terrain, built once at World::create).
//
// Tiled terrains (procedural curriculum / randomized): legged_gym's Terrain class (terrain.py:
// curiculum() and randomized_terrain() over make_terrain's smooth and rough pyramid slopes,
// pyramid stairs up and down and discrete obstacles, with its difficulty formulas); heights stay
// float metres as below, and each tile's generators work on the tile's samples alone.
//
// Generators: the height-field terrains of legged_gym (N. Rudin et al., "Learning to walk in
// minutes using massively parallel deep reinforcement learning", CoRL 2021; leggedrobotics/
// legged_gym legged_gym/utils/terrain.py, which calls isaacgym's terrain_utils: sloped_terrain,
// pyramid_sloped_terrain, stairs_terrain, pyramid_stairs_terrain, random_uniform_terrain,
// wave_terrain). Differences, on purpose: heights stay float metres (terrain_utils rounds them to
// int16 multiples of vertical_scale), so a slope is an exact plane; random_uniform interpolates
// its coarse grid bilinearly (terrain_utils: scipy interp2d, kind 'linear', the same thing).
//
// Surface: a height-field cell (i, j) is split along its (i, j)-(i+1, j+1) diagonal into the two
// triangles the ray caster uses (sensors/mesh.hpp), so contact, measured heights and sensor rays
// all see one surface.
//
// Contact (no heap; called from World::collide_robots):
//  - every triangle near the robot's bounding box (height field: the cells under the box; mesh:
//    an overlap walk of the mesh BVH) is a one-sided face with solid behind it (height field:
//    solid below, unbounded; mesh: up to the robot's bounding radius behind the face);
//  - sphere robots: exact sphere-triangle contact through the closest point on the triangle
//    (C. Ericson, "Real-Time Collision Detection", 2005, sect. 5.1.5); other convex shapes: the
//    deepest point of the shape along the face normal (support point, as the ground plane does),
//    when it lies over the face. Edge-edge contacts of boxes/cylinders with ridges are not
//    modelled (the built-in robots collide as spheres);
//  - contacts whose normals differ by less than ~18 deg (cos >= 0.95) are one contact (the deepest),
//    so a robot resting across many coplanar cells gets one spring, not one per triangle, while a
//    robot in a corner (floor + step face) gets one per face. At most kMaxTerrainContacts.
//
// measured_heights: legged_gym's _get_heights samples the height samples grid and takes the
// minimum of three neighbouring samples; Kestrel returns the height of the surface itself (the
// triangle the point lies over; outside the grid the nearest edge point, as legged_gym clips its
// indices; a mesh: the highest surface under the point, the mesh's lowest z if none).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "kestrel/kernel/rng.hpp"
#include "kestrel/kernel/types.hpp"
#include "kestrel/sensors/mesh.hpp"
#include "kestrel/sensors/scene.hpp"
#include "kestrel/sim/collision.hpp"
#include "kestrel/sim/config.hpp"

namespace kestrel::sim {

constexpr std::uint32_t kPurposeTerrain = kPurposeUser + 1;  // procedural terrain stream (env 0)
constexpr int kMaxTerrainContacts = 8;

struct TriangleMesh;

/// A triangle mesh with its ray-cast BVH in owned storage (sensors::mesh_build), for the sensors'
/// scenes: the mesh terrain and mesh obstacles. Built at set-up, read-only afterwards; not
/// copyable (the sensors mesh points into the vectors).
struct SceneMesh {
  std::vector<real> vertices;  // (n x 3), offset applied
  std::vector<std::uint32_t> indices;
  std::vector<sensors::BvhNode> nodes;
  std::vector<std::uint32_t> prim_index;
  std::vector<real> triangle_cache;
  sensors::TriangleMesh mesh;

  SceneMesh() = default;
  SceneMesh(const SceneMesh&) = delete;
  SceneMesh& operator=(const SceneMesh&) = delete;
  [[nodiscard]] bool build(const TriangleMesh& m, const Vec3& offset);
};

class Terrain {
 public:
  /// Builds the terrain (generators, files, mesh BVH). False with a message naming the file
  /// (config.source_file), the `env.terrain.*` field and the allowed values; `out` is then unusable.
  [[nodiscard]] static bool build(const TerrainConfig& config, std::uint64_t seed, std::unique_ptr<Terrain>& out,
                                  std::string& error);

  TerrainType type() const { return type_; }

  /// Height (world z) of the surface under (x, y); see the file comment.
  real height_at(real x_w, real y_w) const;

  /// Contacts of a posed robot shape (Contact convention of collision.hpp: normal from the
  /// terrain into the robot). bound_radius_m: the shape's bounding sphere (mesh back-face depth).
  /// Writes at most kMaxTerrainContacts; returns the count. Never allocates.
  int collide(const Shape& shape, real bound_radius_m, Contact* out) const;

  /// What World::update_scene adds to a ray-cast scene (segmentation 0, as the ground plane).
  sensors::Shape scene_shape() const;
  Vec3 scene_position_w() const { return scene_position_w_; }

  // Height field views (tests, plots): samples (ny x nx), sample (i, j) at
  // corner_w + (i dx, j dy, heights[j nx + i]).
  int nx() const { return static_cast<int>(hf_.nx); }
  int ny() const { return static_cast<int>(hf_.ny); }
  real spacing_m() const { return hf_.dx; }
  const Vec3& corner_w() const { return scene_position_w_; }
  const std::vector<real>& heights() const { return heights_; }
  // Tiled terrains (procedural curriculum / randomized): tile_rows() difficulty levels along x by
  // tile_cols() terrain types along y; tile_origin(level, type) is the world position of the
  // tile's centre at the highest surface of its central 2 m x 2 m (legged_gym's env_origins).
  // 0 rows and 0 columns for every other terrain.
  int tile_rows() const { return tile_rows_; }
  int tile_cols() const { return tile_cols_; }
  const Vec3& tile_origin(int level, int type) const { return tile_origins_[static_cast<std::size_t>(level * tile_cols_ + type)]; }

  Terrain() = default;
  Terrain(const Terrain&) = delete;
  Terrain& operator=(const Terrain&) = delete;

 private:
  bool build_heightfield(const TerrainConfig& c, std::uint64_t seed, std::string& error);
  bool build_trimesh(const TerrainConfig& c, std::string& error);
  real hf_local_height(real x_l, real y_l) const;

  TerrainType type_ = TerrainType::plane;
  Vec3 scene_position_w_ = Vec3::Zero();  // height field: world position of sample (0, 0), z offset
  // Height field.
  std::vector<real> heights_;
  int tile_rows_ = 0, tile_cols_ = 0;
  std::vector<Vec3> tile_origins_;  // (rows x cols)
  sensors::HeightField hf_;
  // Triangle mesh (world-frame vertices) and its BVH.
  SceneMesh trimesh_;
};

/// Procedural generator names accepted by TerrainConfig::procedural.
const char* terrain_procedural_names();

}  // namespace kestrel::sim
