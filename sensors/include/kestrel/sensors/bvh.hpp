// Fixed-memory bounding volume hierarchy.
//
// Build: binned surface-area heuristic, I. Wald, "On fast construction of SAH-based bounding
// volume hierarchies", IEEE Symposium on Interactive Ray Tracing 2007 (16 bins along the axis of
// largest centroid extent, in-place partition of the primitive index array, explicit stack: no
// recursion, so the MCU stack use is bounded). Binary nodes of 32 bytes (float build).
//
// Memory: the caller provides node storage for bvh_node_capacity(n) = 2n - 1 nodes (the most a
// binary tree with non-empty leaves can have) and n primitive slots. Too little storage is a
// Status::capacity_exceeded before anything is written, never a crash.
//
// Determinism: the build is sequential and depends only on the primitive boxes and their order;
// traversal visits a node only when its entry distance is <= the best hit so far, so a later
// primitive at exactly the same distance is still seen and the caller's (t, id) tie break decides.
#pragma once

#include <cstdint>

#include "kestrel/kernel/status.hpp"
#include "kestrel/sensors/geometry.hpp"

namespace kestrel::sensors {

struct BvhNode {
  real lo[3];
  std::uint32_t first;  // interior: index of the left child (right child = first + 1); leaf: first primitive slot
  real hi[3];
  std::uint32_t count;  // 0: interior node; > 0: number of primitives in the leaf
};
#if !(defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE)
static_assert(sizeof(BvhNode) == 32, "BvhNode is one half cache line");
#endif

/// Nodes needed for n primitives.
constexpr std::uint32_t bvh_node_capacity(std::uint32_t n) { return n == 0 ? 1u : 2u * n - 1u; }

/// Traversal stack depth. The build refuses trees deeper than this (Status::capacity_exceeded).
constexpr int kBvhMaxDepth = 64;

/// A built hierarchy: views into the caller's storage.
struct Bvh {
  BvhNode* nodes = nullptr;
  std::uint32_t node_capacity = 0;
  std::uint32_t node_count = 0;
  std::uint32_t* prim_index = nullptr;  // leaf slots -> primitive ids
  std::uint32_t prim_capacity = 0;
  std::uint32_t prim_count = 0;
};

struct BvhBuildParams {
  std::uint32_t max_leaf_size = 4;
  real traversal_cost = 1;     // SAH cost of one node visit, relative to one primitive test
  real intersection_cost = 1;
};

/// Builds over prim_boxes[0..n) into bvh's storage (nodes, node_capacity, prim_index,
/// prim_capacity must be set). Empty input gives a single empty leaf.
[[nodiscard]] Status bvh_build(const Aabb* prim_boxes, std::uint32_t n, const BvhBuildParams& params, Bvh& bvh);

/// Closest-hit traversal. leaf(prim_id, tmax) tests one primitive and returns the new (smaller or
/// equal) best distance, or tmax unchanged. Near child first.
template <typename LeafFn>
inline void bvh_traverse(const Bvh& bvh, const Ray& ray, real tmin, real& tmax, LeafFn&& leaf) {
  if (bvh.node_count == 0) return;
  std::uint32_t stack[kBvhMaxDepth];
  int sp = 0;
  std::uint32_t ni = 0;
  real tn;
  if (!ray_box(ray, bvh.nodes[0].lo, bvh.nodes[0].hi, tmin, tmax, tn)) return;
  for (;;) {
    const BvhNode& node = bvh.nodes[ni];
    if (node.count > 0) {
      for (std::uint32_t k = 0; k < node.count; ++k) tmax = leaf(bvh.prim_index[node.first + k], tmax);
    } else {
      const std::uint32_t l = node.first, r = node.first + 1;
      real tl, tr;
      const bool hl = ray_box(ray, bvh.nodes[l].lo, bvh.nodes[l].hi, tmin, tmax, tl);
      const bool hr = ray_box(ray, bvh.nodes[r].lo, bvh.nodes[r].hi, tmin, tmax, tr);
      if (hl && hr) {
        // Ties go to the left child: deterministic order.
        if (tr < tl) {
          stack[sp++] = l;
          ni = r;
        } else {
          stack[sp++] = r;
          ni = l;
        }
        continue;
      }
      if (hl) {
        ni = l;
        continue;
      }
      if (hr) {
        ni = r;
        continue;
      }
    }
    // Pop, skipping nodes that the current best hit has since made irrelevant.
    for (;;) {
      if (sp == 0) return;
      ni = stack[--sp];
      if (ray_box(ray, bvh.nodes[ni].lo, bvh.nodes[ni].hi, tmin, tmax, tn)) break;
    }
  }
}

}  // namespace kestrel::sensors
