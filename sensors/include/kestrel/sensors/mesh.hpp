// Triangle meshes and height fields: the two shapes with their own acceleration structure.
//
// A mesh asset is built once into caller storage (first level of the two-level scheme; the scene's
// instance BVH is the second level and may be rebuilt every frame). Its triangles are copied in
// leaf order as (v0, e1, e2) so the inner Möller–Trumbore loop reads contiguous memory with no
// index indirection (the "pre-gathered triangle" layout Embree uses for its Triangle4 leaves).
//
// A height field is a regular grid of samples; a ray walks its cells with the 2D grid traversal of
// J. Amanatides, A. Woo, "A fast voxel traversal algorithm for ray tracing", Eurographics 1987,
// testing the two triangles of each cell. No per-field structure is needed.
#pragma once

#include <cstdint>

#include "kestrel/kernel/status.hpp"
#include "kestrel/sensors/bvh.hpp"

namespace kestrel::sensors {

/// Number of reals of the pre-gathered triangle cache per triangle.
constexpr std::uint32_t kTriangleCacheStride = 9;

/// Storage a mesh build needs, all caller-provided (sizes: see mesh_build).
struct MeshStorage {
  BvhNode* nodes = nullptr;            // >= bvh_node_capacity(triangle_count)
  std::uint32_t node_capacity = 0;
  std::uint32_t* prim_index = nullptr;  // >= triangle_count
  real* triangle_cache = nullptr;       // >= kTriangleCacheStride * triangle_count
  Aabb* scratch_boxes = nullptr;        // >= triangle_count, only used during the build
  std::uint32_t triangle_capacity = 0;  // capacity of prim_index, triangle_cache and scratch_boxes
};

/// Triangle mesh asset in its own (local) frame. The vertex/index arrays stay the caller's.
struct TriangleMesh {
  const real* vertices = nullptr;        // (vertex_count x 3), m
  std::uint32_t vertex_count = 0;
  const std::uint32_t* indices = nullptr;  // (triangle_count x 3)
  std::uint32_t triangle_count = 0;
  const std::uint32_t* part_ids = nullptr;  // optional (triangle_count): per-part segmentation ids
  // Filled by mesh_build:
  Bvh bvh;
  const real* triangle_cache = nullptr;
  Aabb bounds;
};

/// Builds the mesh's BVH and triangle cache. Index out of range -> invalid_argument; storage too
/// small -> capacity_exceeded (nothing usable is left half-built: the mesh reports 0 nodes).
[[nodiscard]] Status mesh_build(TriangleMesh& mesh, const MeshStorage& storage, const BvhBuildParams& params = {});

/// Closest hit of a local-frame ray against the mesh within [tmin, tmax]. On a hit tmax becomes
/// the hit distance and tri the triangle id (equal distances: lowest triangle id).
bool mesh_intersect(const TriangleMesh& mesh, const Ray& ray, real tmin, real& tmax, std::uint32_t& tri);

/// Rays that share one origin (a sensor tile moved into the mesh's frame), cast together through
/// the mesh BVH by mesh_intersect_packet. Structure of arrays so the per-ray loops vectorise.
struct MeshRayPacket {
  static constexpr std::uint32_t kMax = 64;                 // one 8 x 8 sensor tile
  static constexpr std::uint32_t kNoTriangle = 0xffffffffu;  // tri[] of a ray without a hit
  std::uint32_t count = 0;
  real o[3] = {0, 0, 0};   // shared origin, local frame
  real d[3][kMax];         // unit directions, local frame (as make_ray stores them)
  real inv_d[3][kMax];     // make_ray's inverse directions
  real tmax[kMax];         // in: each ray's range limit; out: its hit distance where tri[] is set
  std::uint32_t tri[kMax];  // out: the hit triangle id or kNoTriangle (set by the call)
};

/// Closest hit of every ray of the packet: for each ray i exactly what mesh_intersect(mesh,
/// make_ray(o, d_i), tmin, tmax[i], tri[i]) returns, bit for bit (the same Möller–Trumbore
/// arithmetic and the same (t, triangle id) minimum; only the node visiting order differs, and the
/// result does not depend on it, see mesh.cpp).
void mesh_intersect_packet(const TriangleMesh& mesh, MeshRayPacket& p, real tmin);

/// Unit normal of triangle tri (local frame, right-hand winding).
void mesh_triangle_normal(const TriangleMesh& mesh, std::uint32_t tri, real n[3]);

/// Height field: sample (i, j) sits at (i dx, j dy, heights[j nx + i]) in the local frame.
struct HeightField {
  const real* heights = nullptr;  // (ny x nx), m
  std::uint32_t nx = 0, ny = 0;   // samples per axis, >= 2
  real dx = 1, dy = 1;            // sample spacing, m
  Aabb bounds;                    // filled by height_field_prepare
};

[[nodiscard]] Status height_field_prepare(HeightField& hf);

/// Closest hit within [tmin, tmax] (cells are visited front to back; the first cell with a hit
/// holds the closest one). prim = 2 (j (nx-1) + i) + {0, 1}.
bool height_field_intersect(const HeightField& hf, const Ray& ray, real tmin, real& tmax, std::uint32_t& prim);
void height_field_triangle_normal(const HeightField& hf, std::uint32_t prim, real n[3]);

}  // namespace kestrel::sensors
