// Binned SAH BVH build (Wald 2007), see bvh.hpp.
#include "kestrel/sensors/bvh.hpp"

namespace kestrel::sensors {

namespace {

constexpr int kBins = 16;

struct BuildTask {
  std::uint32_t node, begin, end;
  int depth;
};

struct Bin {
  Aabb box;
  std::uint32_t count = 0;
};

}  // namespace

Status bvh_build(const Aabb* prim_boxes, std::uint32_t n, const BvhBuildParams& params, Bvh& bvh) {
  bvh.node_count = 0;
  bvh.prim_count = 0;
  if (bvh.nodes == nullptr || bvh.node_capacity < bvh_node_capacity(n) || (n > 0 && bvh.prim_index == nullptr) ||
      bvh.prim_capacity < n)
    return Status::capacity_exceeded;
  if (params.max_leaf_size == 0 || (n > 0 && prim_boxes == nullptr)) return Status::invalid_argument;
  for (std::uint32_t i = 0; i < n; ++i) bvh.prim_index[i] = i;
  bvh.prim_count = n;

  BuildTask stack[kBvhMaxDepth];
  int sp = 0;
  bvh.node_count = 1;
  stack[sp++] = BuildTask{0, 0, n, 1};
  while (sp > 0) {
    const BuildTask task = stack[--sp];
    BvhNode& node = bvh.nodes[task.node];
    Aabb box, cbox;
    for (std::uint32_t i = task.begin; i < task.end; ++i) {
      const Aabb& b = prim_boxes[bvh.prim_index[i]];
      box.grow(b);
      const real c[3] = {b.centroid(0), b.centroid(1), b.centroid(2)};
      cbox.grow(c);
    }
    if (box.empty()) box = Aabb{{0, 0, 0}, {0, 0, 0}};  // empty scene: a degenerate box nothing hits
    for (int k = 0; k < 3; ++k) {
      node.lo[k] = box.lo[k];
      node.hi[k] = box.hi[k];
    }
    const std::uint32_t count = task.end - task.begin;
    node.first = task.begin;
    node.count = count;
    if (count <= 1) continue;

    // Axis of largest centroid extent.
    int axis = 0;
    real extent = cbox.hi[0] - cbox.lo[0];
    for (int k = 1; k < 3; ++k) {
      const real e = cbox.hi[k] - cbox.lo[k];
      if (e > extent) {
        extent = e;
        axis = k;
      }
    }

    std::uint32_t mid = task.begin;
    if (extent > 0) {
      Bin bins[kBins];
      const real scale = static_cast<real>(kBins) / extent;
      auto bin_of = [&](std::uint32_t prim) {
        // Compared in floating point before the conversion: a denormal extent makes scale inf and
        // 0 * inf NaN, whose conversion to int is undefined (fuzz_mesh); NaN goes to bin 0.
        const real t = (prim_boxes[prim].centroid(axis) - cbox.lo[axis]) * scale;
        return t >= static_cast<real>(kBins) ? kBins - 1 : (t > 0 ? static_cast<int>(t) : 0);
      };
      for (std::uint32_t i = task.begin; i < task.end; ++i) {
        Bin& b = bins[bin_of(bvh.prim_index[i])];
        b.box.grow(prim_boxes[bvh.prim_index[i]]);
        ++b.count;
      }
      // Sweep: right-side areas from the right, then evaluate each split from the left.
      real right_area[kBins];
      std::uint32_t right_count[kBins];
      Aabb acc;
      std::uint32_t cnt = 0;
      for (int b = kBins - 1; b > 0; --b) {
        acc.grow(bins[b].box);
        cnt += bins[b].count;
        right_area[b] = acc.half_area();
        right_count[b] = cnt;
      }
      Aabb left;
      std::uint32_t lcount = 0;
      real best_cost = 0;
      int best_split = -1;
      for (int b = 1; b < kBins; ++b) {
        left.grow(bins[b - 1].box);
        lcount += bins[b - 1].count;
        if (lcount == 0 || right_count[b] == 0) continue;
        const real cost = left.half_area() * static_cast<real>(lcount) + right_area[b] * static_cast<real>(right_count[b]);
        if (best_split < 0 || cost < best_cost) {  // strict: the first of equal costs wins
          best_cost = cost;
          best_split = b;
        }
      }
      const real leaf_cost = params.intersection_cost * static_cast<real>(count);
      const real split_cost =
          params.traversal_cost + params.intersection_cost * best_cost / (box.half_area() > 0 ? box.half_area() : 1_r);
      if (best_split < 0 || (count <= params.max_leaf_size && leaf_cost <= split_cost)) {
        if (count <= params.max_leaf_size) continue;  // leaf
        mid = task.begin + count / 2;                 // forced split below
      } else {
        // In-place partition (stable enough for determinism: depends only on the input order).
        std::uint32_t i = task.begin, j = task.end;
        while (i < j) {
          if (bin_of(bvh.prim_index[i]) < best_split) {
            ++i;
          } else {
            --j;
            const std::uint32_t tmp = bvh.prim_index[i];
            bvh.prim_index[i] = bvh.prim_index[j];
            bvh.prim_index[j] = tmp;
          }
        }
        mid = i;
      }
    } else {
      if (count <= params.max_leaf_size) continue;
      mid = task.begin + count / 2;  // coincident centroids: split by index
    }
    if (mid == task.begin || mid == task.end) mid = task.begin + count / 2;
    if (task.depth + 1 > kBvhMaxDepth || sp + 2 > kBvhMaxDepth) {
      bvh.node_count = 0;
      return Status::capacity_exceeded;
    }
    const std::uint32_t left_index = bvh.node_count;
    bvh.node_count += 2;
    node.first = left_index;
    node.count = 0;
    stack[sp++] = BuildTask{left_index + 1, mid, task.end, task.depth + 1};
    stack[sp++] = BuildTask{left_index, task.begin, mid, task.depth + 1};
  }
  return Status::ok;
}

}  // namespace kestrel::sensors
