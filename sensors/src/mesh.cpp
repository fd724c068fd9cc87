// Mesh BVH build/traversal and height-field grid traversal (see mesh.hpp).
#include "kestrel/sensors/mesh.hpp"

#include <cmath>

namespace kestrel::sensors {

Status mesh_build(TriangleMesh& mesh, const MeshStorage& st, const BvhBuildParams& params) {
  mesh.bvh = Bvh{};
  mesh.triangle_cache = nullptr;
  mesh.bounds = Aabb{};
  const std::uint32_t n = mesh.triangle_count;
  if (n > 0 && (mesh.vertices == nullptr || mesh.indices == nullptr)) return Status::invalid_argument;
  if (st.triangle_capacity < n || (n > 0 && (st.prim_index == nullptr || st.triangle_cache == nullptr ||
                                             st.scratch_boxes == nullptr)))
    return Status::capacity_exceeded;
  for (std::uint32_t t = 0; t < n; ++t) {
    Aabb b;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t vi = mesh.indices[3 * t + static_cast<std::uint32_t>(k)];
      if (vi >= mesh.vertex_count) return Status::invalid_argument;
      b.grow(&mesh.vertices[3 * vi]);
    }
    st.scratch_boxes[t] = b;
    mesh.bounds.grow(b);
  }
  Bvh bvh;
  bvh.nodes = st.nodes;
  bvh.node_capacity = st.node_capacity;
  bvh.prim_index = st.prim_index;
  bvh.prim_capacity = st.triangle_capacity;
  const Status s = bvh_build(st.scratch_boxes, n, params, bvh);
  if (s != Status::ok) return s;
  // Gather triangles in leaf order as (v0, e1, e2).
  for (std::uint32_t slot = 0; slot < n; ++slot) {
    const std::uint32_t t = bvh.prim_index[slot];
    const real* v0 = &mesh.vertices[3 * mesh.indices[3 * t]];
    const real* v1 = &mesh.vertices[3 * mesh.indices[3 * t + 1]];
    const real* v2 = &mesh.vertices[3 * mesh.indices[3 * t + 2]];
    real* c = &st.triangle_cache[kTriangleCacheStride * slot];
    for (int k = 0; k < 3; ++k) {
      c[k] = v0[k];
      c[3 + k] = v1[k] - v0[k];
      c[6 + k] = v2[k] - v0[k];
    }
  }
  mesh.bvh = bvh;
  mesh.triangle_cache = st.triangle_cache;
  return Status::ok;
}

namespace {

// Möller–Trumbore on a pre-gathered (v0, e1, e2) triangle.
inline bool mt_cached(const real* c, const Ray& r, real tmin, real tmax, real& t_out) {
  const real* e1 = c + 3;
  const real* e2 = c + 6;
  const real* d = r.d;
  const real p0 = d[1] * e2[2] - d[2] * e2[1], p1 = d[2] * e2[0] - d[0] * e2[2], p2 = d[0] * e2[1] - d[1] * e2[0];
  const real det = e1[0] * p0 + e1[1] * p1 + e1[2] * p2;
  if (std::fabs(det) < 1e-12_r) return false;
  const real inv = 1 / det;
  const real s0 = r.o[0] - c[0], s1 = r.o[1] - c[1], s2 = r.o[2] - c[2];
  const real u = (s0 * p0 + s1 * p1 + s2 * p2) * inv;
  if (u < 0 || u > 1) return false;
  const real q0 = s1 * e1[2] - s2 * e1[1], q1 = s2 * e1[0] - s0 * e1[2], q2 = s0 * e1[1] - s1 * e1[0];
  const real v = (d[0] * q0 + d[1] * q1 + d[2] * q2) * inv;
  if (v < 0 || u + v > 1) return false;
  const real t = (e2[0] * q0 + e2[1] * q1 + e2[2] * q2) * inv;
  if (t < tmin || t > tmax) return false;
  t_out = t;
  return true;
}

}  // namespace

bool mesh_intersect(const TriangleMesh& mesh, const Ray& ray, real tmin, real& tmax, std::uint32_t& tri) {
  if (mesh.triangle_cache == nullptr) return false;
  bool found = false;
  std::uint32_t best = 0;
  // Own traversal loop (not bvh_traverse): leaves are read by slot so the cache is contiguous.
  const std::uint32_t* ids = mesh.bvh.prim_index;
  if (mesh.bvh.node_count == 0) return false;
  std::uint32_t stack[kBvhMaxDepth];
  int sp = 0;
  std::uint32_t ni = 0;
  real tn;
  const BvhNode* nodes = mesh.bvh.nodes;
  if (!ray_box(ray, nodes[0].lo, nodes[0].hi, tmin, tmax, tn)) return false;
  for (;;) {
    const BvhNode& node = nodes[ni];
    if (node.count > 0) {
      for (std::uint32_t s = node.first; s < node.first + node.count; ++s) {
        real t;
        if (mt_cached(&mesh.triangle_cache[kTriangleCacheStride * s], ray, tmin, tmax, t)) {
          const std::uint32_t id = ids[s];
          if (!found || t < tmax || id < best) {
            tmax = t;
            best = id;
            found = true;
          }
        }
      }
    } else {
      const std::uint32_t l = node.first, r = node.first + 1;
      real tl, tr;
      const bool hl = ray_box(ray, nodes[l].lo, nodes[l].hi, tmin, tmax, tl);
      const bool hr = ray_box(ray, nodes[r].lo, nodes[r].hi, tmin, tmax, tr);
      if (hl && hr) {
        if (tr < tl) {
          stack[sp++] = l;
          ni = r;
        } else {
          stack[sp++] = r;
          ni = l;
        }
        continue;
      }
      if (hl || hr) {
        ni = hl ? l : r;
        continue;
      }
    }
    for (;;) {
      if (sp == 0) {
        if (found) tri = best;
        return found;
      }
      ni = stack[--sp];
      if (ray_box(ray, nodes[ni].lo, nodes[ni].hi, tmin, tmax, tn)) break;
    }
  }
}

// ---- Packets of rays with a shared origin (sensor tiles) ----
//
// Traversal: the large-packet BVH walk of I. Wald, S. Boulos, P. Shirley, "Ray tracing deformable
// scenes using dynamic bounding volume hierarchies", ACM TOG 26(1), 2007: the packet descends
// together, carrying the index of its first active ray; a node is entered when that ray hits its
// box (the early-hit test: one slab test for a coherent packet), is skipped when an interval-
// arithmetic bound over all rays misses it, and otherwise the first ray that hits it is searched.
// Leaves test the rays from the first to the last one that hits the leaf's box.
//
// Why the result is the single-ray one: each ray's answer is the (t, triangle id) minimum over
// the triangles it hits within [tmin, tmax] (mesh_intersect's rule), computed with the same
// Möller–Trumbore arithmetic below. Any walk that tests every triangle whose box the ray enters
// before its current best t gives that minimum, in any order: a box is only skipped when its
// entry is beyond the ray's best t so far, and a triangle's t is never before its box's entry,
// the assumption the single-ray walk makes too (bvh.hpp). Extra tests (rays of the packet that
// miss a leaf's box) only find hits that the box test would have allowed anyway, or none.
//
// Shared origin: in Möller–Trumbore (Möller & Trumbore 1997) s = o - v0, q = s x e1 and the t
// numerator e2 . q depend on the triangle and the origin only, so they are formed once per
// triangle for the whole packet with the single-ray expressions (the same bits).

namespace {

constexpr std::uint32_t kPacketMax = MeshRayPacket::kMax;

// Interval-arithmetic bounds of the packet's inverse directions (conservative for any sign mix:
// (lo - o) inv_d is monotonic in inv_d, rounding included).
struct PacketBounds {
  real inv_lo[3], inv_hi[3];
  real tmax;  // largest tmax of any ray
};

// Can any ray of the packet hit the box within [tmin, b.tmax]? False only when none can.
inline bool packet_may_hit(const BvhNode& node, const real o[3], const PacketBounds& b, real tmin) {
  real tn = tmin, tf = b.tmax;
  for (int k = 0; k < 3; ++k) {
    const real a = node.lo[k] - o[k], c = node.hi[k] - o[k];
    const real t0 = a * b.inv_lo[k], t1 = a * b.inv_hi[k], t2 = c * b.inv_lo[k], t3 = c * b.inv_hi[k];
    const real lo01 = t0 < t1 ? t0 : t1, lo23 = t2 < t3 ? t2 : t3;
    const real hi01 = t0 < t1 ? t1 : t0, hi23 = t2 < t3 ? t3 : t2;
    const real near_lo = lo01 < lo23 ? lo01 : lo23, far_hi = hi01 < hi23 ? hi23 : hi01;
    tn = near_lo > tn ? near_lo : tn;
    tf = far_hi < tf ? far_hi : tf;
  }
  return tn <= tf;
}

// ray_box for ray i of the packet (the same slab arithmetic).
inline bool packet_ray_box(const BvhNode& node, const MeshRayPacket& p, std::uint32_t i, real tmin, real& tn_out) {
  const real inv_d[3] = {p.inv_d[0][i], p.inv_d[1][i], p.inv_d[2][i]};
  return slab_box(p.o, inv_d, node.lo, node.hi, tmin, p.tmax[i], tn_out);
}

// First ray >= from that hits the node's box (p.count: none); its entry distance in tn.
inline std::uint32_t packet_first_hit(const BvhNode& node, const MeshRayPacket& p, const PacketBounds& b,
                                      std::uint32_t from, real tmin, real& tn) {
  if (!packet_may_hit(node, p.o, b, tmin)) return p.count;
  for (std::uint32_t i = from; i < p.count; ++i)
    if (packet_ray_box(node, p, i, tmin, tn)) return i;
  return p.count;
}

// All rays [first, last] against one pre-gathered triangle; the per-ray loop is branch free so
// that it vectorises. The arithmetic is mt_cached's, expression for expression.
inline void packet_triangle(const real* c, std::uint32_t id, MeshRayPacket& p, std::uint32_t first, std::uint32_t last,
                            real tmin) {
  const real* e1 = c + 3;
  const real* e2 = c + 6;
  const real s0 = p.o[0] - c[0], s1 = p.o[1] - c[1], s2 = p.o[2] - c[2];
  const real q0 = s1 * e1[2] - s2 * e1[1], q1 = s2 * e1[0] - s0 * e1[2], q2 = s0 * e1[1] - s1 * e1[0];
  const real tnum = e2[0] * q0 + e2[1] * q1 + e2[2] * q2;
  const real e10 = e1[0], e11 = e1[1], e12 = e1[2], e20 = e2[0], e21 = e2[1], e22 = e2[2];
  real* __restrict tmax = p.tmax;
  std::uint32_t* __restrict tri = p.tri;
  const real* __restrict dx = p.d[0];
  const real* __restrict dy = p.d[1];
  const real* __restrict dz = p.d[2];
  for (std::uint32_t i = first; i <= last; ++i) {
    const real d0 = dx[i], d1 = dy[i], d2 = dz[i];
    const real p0 = d1 * e22 - d2 * e21, p1 = d2 * e20 - d0 * e22, p2 = d0 * e21 - d1 * e20;
    const real det = e10 * p0 + e11 * p1 + e12 * p2;
    const real inv = 1 / det;
    const real u = (s0 * p0 + s1 * p1 + s2 * p2) * inv;
    const real v = (d0 * q0 + d1 * q1 + d2 * q2) * inv;
    const real t = tnum * inv;
    const real tm = tmax[i];
    // mt_cached's rejections as one mask (no short circuit: NaN compares false there too).
    const bool reject = (std::fabs(det) < 1e-12_r) | (u < 0) | (u > 1) | (v < 0) | (u + v > 1) | (t < tmin) | (t > tm);
    const bool take = (!reject) & ((t < tm) | (id < tri[i]));
    tmax[i] = take ? t : tm;
    tri[i] = take ? id : tri[i];
  }
}

}  // namespace

void mesh_intersect_packet(const TriangleMesh& mesh, MeshRayPacket& p, real tmin) {
  const std::uint32_t n = p.count < kPacketMax ? p.count : kPacketMax;
  p.count = n;
  for (std::uint32_t i = 0; i < n; ++i) p.tri[i] = MeshRayPacket::kNoTriangle;
  if (mesh.triangle_cache == nullptr || mesh.bvh.node_count == 0 || n == 0) return;
  PacketBounds b;
  for (int k = 0; k < 3; ++k) {
    b.inv_lo[k] = p.inv_d[k][0];
    b.inv_hi[k] = p.inv_d[k][0];
    for (std::uint32_t i = 1; i < n; ++i) {
      b.inv_lo[k] = p.inv_d[k][i] < b.inv_lo[k] ? p.inv_d[k][i] : b.inv_lo[k];
      b.inv_hi[k] = p.inv_d[k][i] > b.inv_hi[k] ? p.inv_d[k][i] : b.inv_hi[k];
    }
  }
  auto update_tmax = [&] {
    b.tmax = p.tmax[0];
    for (std::uint32_t i = 1; i < n; ++i) b.tmax = p.tmax[i] > b.tmax ? p.tmax[i] : b.tmax;
  };
  update_tmax();
  const BvhNode* nodes = mesh.bvh.nodes;
  const std::uint32_t* ids = mesh.bvh.prim_index;
  struct Entry {
    std::uint32_t node, first;
  };
  Entry stack[kBvhMaxDepth];
  int sp = 0;
  real tn;
  std::uint32_t ni = 0;
  std::uint32_t first = packet_first_hit(nodes[0], p, b, 0, tmin, tn);
  if (first == n) return;
  for (;;) {
    const BvhNode& node = nodes[ni];
    if (node.count > 0) {
      // Last ray that hits the leaf's box (the first one does).
      std::uint32_t last = n - 1;
      while (last > first && !packet_ray_box(node, p, last, tmin, tn)) --last;
      for (std::uint32_t s = node.first; s < node.first + node.count; ++s)
        packet_triangle(&mesh.triangle_cache[kTriangleCacheStride * s], ids[s], p, first, last, tmin);
      update_tmax();
    } else {
      const std::uint32_t l = node.first, r = node.first + 1;
      real tl = 0, tr = 0;
      const std::uint32_t fl = packet_first_hit(nodes[l], p, b, first, tmin, tl);
      const std::uint32_t fr = packet_first_hit(nodes[r], p, b, first, tmin, tr);
      if (fl < n && fr < n) {
        // Nearer child first (by the entry distances of the two first rays: a speed choice only).
        if (tr < tl) {
          stack[sp++] = Entry{l, fl};
          ni = r;
          first = fr;
        } else {
          stack[sp++] = Entry{r, fr};
          ni = l;
          first = fl;
        }
        continue;
      }
      if (fl < n || fr < n) {
        ni = fl < n ? l : r;
        first = fl < n ? fl : fr;
        continue;
      }
    }
    // Pop, skipping nodes that the rays' best hits have since made irrelevant.
    for (;;) {
      if (sp == 0) return;
      const Entry e = stack[--sp];
      ni = e.node;
      first = packet_first_hit(nodes[ni], p, b, e.first, tmin, tn);
      if (first < n) break;
    }
  }
}

void mesh_triangle_normal(const TriangleMesh& mesh, std::uint32_t tri, real n[3]) {
  triangle_normal(&mesh.vertices[3 * mesh.indices[3 * tri]], &mesh.vertices[3 * mesh.indices[3 * tri + 1]],
                  &mesh.vertices[3 * mesh.indices[3 * tri + 2]], n);
}

Status height_field_prepare(HeightField& hf) {
  hf.bounds = Aabb{};
  if (hf.heights == nullptr || hf.nx < 2 || hf.ny < 2 || !(hf.dx > 0) || !(hf.dy > 0)) return Status::invalid_argument;
  real lo = hf.heights[0], hi = hf.heights[0];
  for (std::uint32_t i = 0; i < hf.nx * hf.ny; ++i) {
    const real h = hf.heights[i];
    if (!std::isfinite(h)) return Status::non_finite_input;
    lo = h < lo ? h : lo;
    hi = h > hi ? h : hi;
  }
  const real a[3] = {0, 0, lo};
  const real b[3] = {static_cast<real>(hf.nx - 1) * hf.dx, static_cast<real>(hf.ny - 1) * hf.dy, hi};
  hf.bounds.grow(a);
  hf.bounds.grow(b);
  return Status::ok;
}

namespace {

inline void hf_vertex(const HeightField& hf, std::uint32_t i, std::uint32_t j, real v[3]) {
  v[0] = static_cast<real>(i) * hf.dx;
  v[1] = static_cast<real>(j) * hf.dy;
  v[2] = hf.heights[j * hf.nx + i];
}

inline void hf_triangle(const HeightField& hf, std::uint32_t prim, real a[3], real b[3], real c[3]) {
  const std::uint32_t cell = prim / 2, i = cell % (hf.nx - 1), j = cell / (hf.nx - 1);
  hf_vertex(hf, i, j, a);
  if (prim % 2 == 0) {
    hf_vertex(hf, i + 1, j, b);
    hf_vertex(hf, i + 1, j + 1, c);
  } else {
    hf_vertex(hf, i + 1, j + 1, b);
    hf_vertex(hf, i, j + 1, c);
  }
}

}  // namespace

bool height_field_intersect(const HeightField& hf, const Ray& ray, real tmin, real& tmax, std::uint32_t& prim) {
  real t0;
  if (hf.heights == nullptr || !ray_box(ray, hf.bounds.lo, hf.bounds.hi, tmin, tmax, t0)) return false;
  // Exit distance of the grid box bounds the walk.
  real t1 = tmax;
  for (int k = 0; k < 3; ++k) {
    const real ta = (hf.bounds.lo[k] - ray.o[k]) * ray.inv_d[k], tb = (hf.bounds.hi[k] - ray.o[k]) * ray.inv_d[k];
    const real f = ta > tb ? ta : tb;
    t1 = f < t1 ? f : t1;
  }
  const int ncx = static_cast<int>(hf.nx) - 1, ncy = static_cast<int>(hf.ny) - 1;
  const real px = ray.o[0] + t0 * ray.d[0], py = ray.o[1] + t0 * ray.d[1];
  int ix = static_cast<int>(std::floor(px / hf.dx)), iy = static_cast<int>(std::floor(py / hf.dy));
  ix = ix < 0 ? 0 : (ix >= ncx ? ncx - 1 : ix);
  iy = iy < 0 ? 0 : (iy >= ncy ? ncy - 1 : iy);
  const int step_x = ray.d[0] >= 0 ? 1 : -1, step_y = ray.d[1] >= 0 ? 1 : -1;
  // Distances to the next cell boundary on each axis, and per-cell increments (Amanatides & Woo).
  const real next_x = static_cast<real>(ix + (step_x > 0 ? 1 : 0)) * hf.dx;
  const real next_y = static_cast<real>(iy + (step_y > 0 ? 1 : 0)) * hf.dy;
  real tmax_x = (next_x - ray.o[0]) * ray.inv_d[0];
  real tmax_y = (next_y - ray.o[1]) * ray.inv_d[1];
  const real tdelta_x = hf.dx * std::fabs(ray.inv_d[0]), tdelta_y = hf.dy * std::fabs(ray.inv_d[1]);
  for (;;) {
    const std::uint32_t cell = static_cast<std::uint32_t>(iy) * (hf.nx - 1) + static_cast<std::uint32_t>(ix);
    bool found = false;
    for (std::uint32_t k = 0; k < 2; ++k) {
      real a[3], b[3], c[3], t;
      hf_triangle(hf, 2 * cell + k, a, b, c);
      if (intersect_triangle(ray.o, ray.d, a, b, c, tmin, tmax, t) && (!found || t < tmax)) {
        tmax = t;
        prim = 2 * cell + k;
        found = true;
      }
    }
    if (found) return true;
    // Step to the neighbouring cell through the nearer boundary (x first on a tie: deterministic).
    if (tmax_x <= tmax_y) {
      if (tmax_x > t1) return false;
      ix += step_x;
      tmax_x += tdelta_x;
    } else {
      if (tmax_y > t1) return false;
      iy += step_y;
      tmax_y += tdelta_y;
    }
    if (ix < 0 || ix >= ncx || iy < 0 || iy >= ncy) return false;
  }
}

void height_field_triangle_normal(const HeightField& hf, std::uint32_t prim, real n[3]) {
  real a[3], b[3], c[3];
  hf_triangle(hf, prim, a, b, c);
  triangle_normal(a, b, c, n);
}

}  // namespace kestrel::sensors
