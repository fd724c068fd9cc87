// Scene instances, instance BVH and the two-level closest-hit query (see scene.hpp).
#include "kestrel/sensors/scene.hpp"

#include <cmath>

#include "kestrel/kernel/quaternion.hpp"

namespace kestrel::sensors {

Scene::Scene(SceneObject* objects, std::uint32_t capacity, BvhNode* nodes, std::uint32_t node_capacity,
             std::uint32_t* prim_index, Aabb* boxes, std::uint32_t* bvh_objects)
    : objects_(objects), capacity_(capacity), boxes_(boxes), bvh_objects_(bvh_objects) {
  bvh_.nodes = nodes;
  bvh_.node_capacity = node_capacity;
  bvh_.prim_index = prim_index;
  bvh_.prim_capacity = capacity;
}

void Scene::clear() {
  count_ = 0;
  unbounded_count_ = 0;
  dirty_ = true;
}

namespace {

// Local-frame bounds of a shape.
Aabb local_bounds(const Shape& s) {
  Aabb b;
  real h[3] = {0, 0, 0};
  switch (s.type) {
    case ShapeType::box: h[0] = s.size[0]; h[1] = s.size[1]; h[2] = s.size[2]; break;
    case ShapeType::sphere: h[0] = h[1] = h[2] = s.size[0]; break;
    case ShapeType::capsule: h[0] = h[1] = s.size[0]; h[2] = s.size[1] + s.size[0]; break;
    case ShapeType::cylinder: h[0] = h[1] = s.size[0]; h[2] = s.size[1]; break;
    case ShapeType::mesh: return s.mesh->bounds;
    case ShapeType::height_field: return s.height_field->bounds;
    case ShapeType::plane: return b;
  }
  for (int k = 0; k < 3; ++k) {
    b.lo[k] = -h[k];
    b.hi[k] = h[k];
  }
  return b;
}

void update_world(SceneObject& o, const Vec3& p, const Quat& q_in) {
  const Quat q = q_in.normalized();
  const Mat3 r = rotation_matrix(q);
  for (int i = 0; i < 3; ++i) {
    o.p_w[i] = p[i];
    for (int j = 0; j < 3; ++j) o.r_wl[3 * i + j] = r(i, j);
  }
  // World box of a rotated box: centre moves, half extents become |R| h (Arvo 1990).
  o.box_w = Aabb{};
  if (o.shape.type == ShapeType::plane) return;
  const Aabb lb = local_bounds(o.shape);
  for (int i = 0; i < 3; ++i) {
    real c = o.p_w[i], e = 0;
    for (int j = 0; j < 3; ++j) {
      const real rij = o.r_wl[3 * i + j];
      c += rij * lb.centroid(j);
      e += std::fabs(rij) * (lb.hi[j] - lb.lo[j]) * 0.5_r;
    }
    o.box_w.lo[i] = c - e;
    o.box_w.hi[i] = c + e;
  }
}

bool shape_valid(const Shape& s) {
  switch (s.type) {
    case ShapeType::box: return s.size[0] > 0 && s.size[1] > 0 && s.size[2] > 0;
    case ShapeType::sphere: return s.size[0] > 0;
    case ShapeType::capsule:
    case ShapeType::cylinder: return s.size[0] > 0 && s.size[1] >= 0;
    case ShapeType::plane: return true;
    case ShapeType::mesh: return s.mesh != nullptr && (s.mesh->triangle_count == 0 || s.mesh->bvh.node_count > 0);
    case ShapeType::height_field: return s.height_field != nullptr && !s.height_field->bounds.empty();
  }
  return false;
}

}  // namespace

Status Scene::add(const Shape& shape, const Vec3& position_w, const Quat& orientation_wl, std::uint32_t seg_id,
                  std::uint32_t* id) {
  if (count_ >= capacity_) return Status::capacity_exceeded;
  if (!shape_valid(shape) || !position_w.allFinite() || !orientation_wl.coeffs().allFinite() ||
      orientation_wl.norm() < 1e-6_r)
    return Status::invalid_argument;
  if (shape.type == ShapeType::plane) {
    if (unbounded_count_ >= kMaxUnbounded) return Status::capacity_exceeded;
    unbounded_[unbounded_count_++] = count_;
  }
  SceneObject& o = objects_[count_];
  o.shape = shape;
  o.seg_id = seg_id;
  update_world(o, position_w, orientation_wl);
  if (id != nullptr) *id = count_;
  ++count_;
  dirty_ = true;
  return Status::ok;
}

Status Scene::set_pose(std::uint32_t id, const Vec3& position_w, const Quat& orientation_wl) {
  if (id >= count_ || !position_w.allFinite() || !orientation_wl.coeffs().allFinite() || orientation_wl.norm() < 1e-6_r)
    return Status::invalid_argument;
  update_world(objects_[id], position_w, orientation_wl);
  dirty_ = true;
  return Status::ok;
}

Status Scene::build(const BvhBuildParams& params) {
  std::uint32_t n = 0;
  for (std::uint32_t i = 0; i < count_; ++i) {
    if (objects_[i].shape.type == ShapeType::plane) continue;
    boxes_[n] = objects_[i].box_w;
    bvh_objects_[n] = i;
    ++n;
  }
  const Status s = bvh_build(boxes_, n, params, bvh_);
  dirty_ = s != Status::ok;
  return s;
}

namespace {

struct Best {
  real t;
  std::uint32_t object;
  std::uint32_t prim;
  real n_l[3];
  bool found;
};

// (t, object, prim) lexicographic: the stable tie break.
inline bool better(const Best& b, real t, std::uint32_t object, std::uint32_t prim) {
  if (!b.found || t < b.t) return true;
  if (t > b.t) return false;
  return object < b.object || (object == b.object && prim < b.prim);
}

// The world point ow in the object's local frame: R^T (ow - p).
inline void to_local_origin(const SceneObject& ob, const real ow[3], real o[3]) {
  const real* r = ob.r_wl;
  const real v[3] = {ow[0] - ob.p_w[0], ow[1] - ob.p_w[1], ow[2] - ob.p_w[2]};
  o[0] = r[0] * v[0] + r[3] * v[1] + r[6] * v[2];
  o[1] = r[1] * v[0] + r[4] * v[1] + r[7] * v[2];
  o[2] = r[2] * v[0] + r[5] * v[1] + r[8] * v[2];
}

// R^T d_w: a world direction in the object's frame (rigid: ranges are the same in both frames).
inline void local_direction(const SceneObject& ob, const real dw[3], real d[3]) {
  const real* r = ob.r_wl;
  d[0] = r[0] * dw[0] + r[3] * dw[1] + r[6] * dw[2];
  d[1] = r[1] * dw[0] + r[4] * dw[1] + r[7] * dw[2];
  d[2] = r[2] * dw[0] + r[5] * dw[1] + r[8] * dw[2];
}

inline void commit(const SceneObject& ob, std::uint32_t id, const real d[3], const LocalHit& h, std::uint32_t prim,
                   Best& best);

// Tests one object with the world ray moved into its local frame; o is the ray origin already in
// that frame (R^T (o_w - p); computed per ray, or once per sensor tile for shared-origin rays).
inline void test_object_local(const SceneObject& ob, std::uint32_t id, const real o[3], const Ray& rw, real tmin,
                              Best& best, real tmax) {
  real d[3];
  LocalHit h;
  bool hit = false;
  std::uint32_t prim = 0;
  local_direction(ob, rw.d, d);
  switch (ob.shape.type) {
    case ShapeType::box: hit = intersect_box(o, d, ob.shape.size, tmin, tmax, h); break;
    case ShapeType::sphere: hit = intersect_sphere(o, d, ob.shape.size[0], tmin, tmax, h); break;
    case ShapeType::capsule: hit = intersect_capsule(o, d, ob.shape.size[0], ob.shape.size[1], tmin, tmax, h); break;
    case ShapeType::cylinder: hit = intersect_cylinder(o, d, ob.shape.size[0], ob.shape.size[1], tmin, tmax, h); break;
    case ShapeType::plane: hit = intersect_plane(o, d, tmin, tmax, h); break;
    case ShapeType::mesh: {
      const Ray rl = make_ray(o, d);
      real t = tmax;
      if (mesh_intersect(*ob.shape.mesh, rl, tmin, t, prim)) {
        hit = true;
        h.t = t;
        mesh_triangle_normal(*ob.shape.mesh, prim, h.n);
      }
      break;
    }
    case ShapeType::height_field: {
      const Ray rl = make_ray(o, d);
      real t = tmax;
      if (height_field_intersect(*ob.shape.height_field, rl, tmin, t, prim)) {
        hit = true;
        h.t = t;
        height_field_triangle_normal(*ob.shape.height_field, prim, h.n);
      }
      break;
    }
  }
  if (hit) commit(ob, id, d, h, prim, best);
}

// Keeps the local hit h (object id, primitive prim, local ray direction d) if it beats best.
inline void commit(const SceneObject& ob, std::uint32_t id, const real d[3], const LocalHit& h, std::uint32_t prim,
                   Best& best) {
  if (!better(best, h.t, id, prim)) return;
  best.t = h.t;
  best.object = id;
  best.prim = prim;
  real n[3] = {h.n[0], h.n[1], h.n[2]};
  if (ob.shape.type == ShapeType::mesh || ob.shape.type == ShapeType::height_field) {
    // Surfaces without an inside: report the face the sensor sees.
    if (n[0] * d[0] + n[1] * d[1] + n[2] * d[2] > 0) {
      n[0] = -n[0];
      n[1] = -n[1];
      n[2] = -n[2];
    }
  }
  best.n_l[0] = n[0];
  best.n_l[1] = n[1];
  best.n_l[2] = n[2];
  best.found = true;
}

inline void test_object(const SceneObject& ob, std::uint32_t id, const Ray& rw, real tmin, Best& best, real tmax) {
  real o[3];
  to_local_origin(ob, rw.o, o);
  test_object_local(ob, id, o, rw, tmin, best, tmax);
}

// World-frame hit record of the best local hit.
inline bool finish(const SceneObject* objects, const Best& best, SceneHit& hit) {
  if (!best.found) return false;
  const SceneObject& ob = objects[best.object];
  const real* r = ob.r_wl;
  hit.t = best.t;
  for (int i = 0; i < 3; ++i) hit.normal_w[i] = r[3 * i] * best.n_l[0] + r[3 * i + 1] * best.n_l[1] + r[3 * i + 2] * best.n_l[2];
  hit.object = best.object;
  hit.prim = best.prim;
  hit.seg_id = ob.seg_id;
  if (ob.shape.type == ShapeType::mesh && ob.shape.mesh->part_ids != nullptr) hit.seg_id = ob.shape.mesh->part_ids[best.prim];
  return true;
}

}  // namespace

bool Scene::intersect(const Vec3& o_w, const Vec3& d_w, real tmin, real tmax, SceneHit& hit) const {
  const real o[3] = {o_w[0], o_w[1], o_w[2]};
  const real d[3] = {d_w[0], d_w[1], d_w[2]};
  return intersect(make_ray(o, d), tmin, tmax, hit);
}

bool Scene::intersect(const Ray& ray, real tmin, real tmax, SceneHit& hit) const {
  if (dirty_) return false;
  Best best{tmax, 0, 0, {0, 0, 0}, false};
  for (std::uint32_t k = 0; k < unbounded_count_; ++k)
    test_object(objects_[unbounded_[k]], unbounded_[k], ray, tmin, best, best.t);
  real t = best.t;
  bvh_traverse(bvh_, ray, tmin, t, [&](std::uint32_t prim, real tcur) {
    const std::uint32_t id = bvh_objects_[prim];
    test_object(objects_[id], id, ray, tmin, best, tcur);
    return best.found ? best.t : tcur;
  });
  return finish(objects_, best, hit);
}


namespace {

// Can a ray from o with a unit direction inside the cone (axis, cos_t, sin_t) reach box within
// range tmax? On true, lower is a conservative lower bound of the range of any point of the box.
// Margins: boxes are float bounds and directions are unit only to rounding, so the lower bound is
// shrunk by 1e-4 relative + 0.1 mm and the box's bounding sphere grown by ~1e-3 rad + 0.1 mm.
inline bool cone_reaches(const real lo[3], const real hi[3], const real o[3], const real axis[3], bool any_dir,
                         real cos_t, real sin_t, real tmax, real& lower) {
  real dist2 = 0, diag2 = 0, v[3];
  for (int k = 0; k < 3; ++k) {
    const real out = o[k] < lo[k] ? lo[k] - o[k] : (o[k] > hi[k] ? o[k] - hi[k] : 0_r);
    dist2 += out * out;
    const real e = (hi[k] - lo[k]) * 0.5_r;
    diag2 += e * e;
    v[k] = (lo[k] + hi[k]) * 0.5_r - o[k];
  }
  lower = std::sqrt(dist2) * (1 - 1e-4_r) - 1e-4_r;
  if (lower > tmax) return false;
  if (any_dir) return true;
  // Bounding sphere of the box against the cone: out when the angle between the axis and the
  // centre exceeds the cone half angle plus the sphere's angular radius.
  const real vn = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  const real rad = std::sqrt(diag2) + 1e-3_r * vn + 1e-4_r;
  if (vn <= rad) return true;  // origin inside the sphere
  const real cos_a = (v[0] * axis[0] + v[1] * axis[1] + v[2] * axis[2]) / vn;
  const real sin_b = rad / vn;
  const real cos_b = std::sqrt(1 - sin_b * sin_b);
  if (cos_t < -cos_b) return true;  // half angle + angular radius >= pi
  return cos_a >= cos_t * cos_b - sin_t * sin_b - 1e-6_r;
}

}  // namespace

void Scene::gather_cone(const real origin_w[3], const real axis_w[3], real cos_half_angle, real tmax,
                        ConeCandidates& c) const {
  c.count = 0;
  c.overflow = false;
  for (int k = 0; k < 3; ++k) c.origin_w[k] = origin_w[k];
  if (bvh_.node_count == 0 || bvh_.prim_count == 0) return;
  const bool any_dir = cos_half_angle <= -1;
  const real cos_t = cos_half_angle < -1 ? -1_r : (cos_half_angle > 1 ? 1_r : cos_half_angle);
  const real sin_t = std::sqrt(1 - cos_t * cos_t);
  // Cone walk of the instance BVH (a node outside the cone or beyond tmax holds no candidate).
  std::uint32_t stack[kBvhMaxDepth + 2];  // one pending sibling per level, depth <= kBvhMaxDepth
  int sp = 0;
  stack[sp++] = 0;
  while (sp > 0) {
    const BvhNode& node = bvh_.nodes[stack[--sp]];
    real lower;
    if (!cone_reaches(node.lo, node.hi, origin_w, axis_w, any_dir, cos_t, sin_t, tmax, lower)) continue;
    if (node.count == 0) {
      stack[sp++] = node.first + 1;
      stack[sp++] = node.first;
      continue;
    }
    for (std::uint32_t s = node.first; s < node.first + node.count; ++s) {
      const std::uint32_t id = bvh_objects_[bvh_.prim_index[s]];
      const SceneObject& ob = objects_[id];
      if (node.count > 1 && !cone_reaches(ob.box_w.lo, ob.box_w.hi, origin_w, axis_w, any_dir, cos_t, sin_t, tmax, lower))
        continue;
      if (c.count == ConeCandidates::kMax) {
        c.overflow = true;
        return;
      }
      // Insertion by lower bound, then id (the order only affects speed, not results).
      std::uint32_t j = c.count++;
      while (j > 0 && (c.lower[j - 1] > lower || (c.lower[j - 1] == lower && c.id[j - 1] > id))) {
        c.id[j] = c.id[j - 1];
        c.lower[j] = c.lower[j - 1];
        for (int k = 0; k < 3; ++k) c.o_l[j][k] = c.o_l[j - 1][k];
        --j;
      }
      c.id[j] = id;
      c.lower[j] = lower;
      to_local_origin(ob, origin_w, c.o_l[j]);
    }
  }
}

bool Scene::intersect(const ConeCandidates& c, const Ray& ray, real tmin, real tmax, SceneHit& hit) const {
  if (c.overflow) return intersect(ray, tmin, tmax, hit);
  if (dirty_) return false;
  Best best{tmax, 0, 0, {0, 0, 0}, false};
  for (std::uint32_t k = 0; k < unbounded_count_; ++k)
    test_object(objects_[unbounded_[k]], unbounded_[k], ray, tmin, best, best.t);
  // Every hit on candidate k is at range >= lower[k]; visiting in that order, the walk ends once
  // the bound passes the best hit (equal ranges are still tested for the (t, id) tie break).
  real t = best.t;
  for (std::uint32_t k = 0; k < c.count; ++k) {
    if (c.lower[k] > t) break;
    const std::uint32_t id = c.id[k];
    const SceneObject& ob = objects_[id];
    real tn;
    if (!ray_box(ray, ob.box_w.lo, ob.box_w.hi, tmin, t, tn)) continue;
    test_object_local(ob, id, c.o_l[k], ray, tmin, best, t);
    if (best.found) t = best.t;
  }
  return finish(objects_, best, hit);
}

void Scene::intersect_tile(const ConeCandidates& c, const real (*d_w)[3], std::uint32_t n, real tmin, const real* tmax,
                           SceneHit* hits, bool* found) const {
  if (c.overflow || dirty_ || n > kMaxTileRays) {
    for (std::uint32_t i = 0; i < n; ++i) found[i] = intersect(c, make_ray(c.origin_w, d_w[i]), tmin, tmax[i], hits[i]);
    return;
  }
  // Per ray, the same steps as intersect(c, ...): unbounded objects, then the candidates in order
  // with the same culls (lower bound, world box) against that ray's running best t. Candidates
  // are taken one at a time for all rays instead of rays one at a time: every ray still sees the
  // same objects in the same order with the same t, so its result is unchanged.
  Ray rays[kMaxTileRays];
  Best best[kMaxTileRays];
  real t[kMaxTileRays];
  for (std::uint32_t i = 0; i < n; ++i) {
    rays[i] = make_ray(c.origin_w, d_w[i]);
    best[i] = Best{tmax[i], 0, 0, {0, 0, 0}, false};
    for (std::uint32_t k = 0; k < unbounded_count_; ++k)
      test_object(objects_[unbounded_[k]], unbounded_[k], rays[i], tmin, best[i], best[i].t);
    t[i] = best[i].t;
  }
  MeshRayPacket packet;
  std::uint32_t lane_ray[kMaxTileRays];
  for (std::uint32_t k = 0; k < c.count; ++k) {
    const std::uint32_t id = c.id[k];
    const SceneObject& ob = objects_[id];
    // intersect(c, ...) stops a ray's walk at the first lower bound beyond its best t; the bounds
    // are sorted and t only shrinks, so skipping this candidate for that ray is the same.
    std::uint32_t live = 0;
    for (std::uint32_t i = 0; i < n; ++i) {
      real tn;
      if (c.lower[k] > t[i] || !ray_box(rays[i], ob.box_w.lo, ob.box_w.hi, tmin, t[i], tn)) continue;
      lane_ray[live++] = i;
    }
    if (live == 0) continue;
    if (ob.shape.type == ShapeType::mesh && live > 1) {
      packet.count = live;
      for (int a = 0; a < 3; ++a) packet.o[a] = c.o_l[k][a];
      for (std::uint32_t j = 0; j < live; ++j) {
        real d[3];
        local_direction(ob, rays[lane_ray[j]].d, d);
        const Ray rl = make_ray(c.o_l[k], d);
        for (int a = 0; a < 3; ++a) {
          packet.d[a][j] = rl.d[a];
          packet.inv_d[a][j] = rl.inv_d[a];
        }
        packet.tmax[j] = t[lane_ray[j]];
      }
      mesh_intersect_packet(*ob.shape.mesh, packet, tmin);
      for (std::uint32_t j = 0; j < live; ++j) {
        if (packet.tri[j] == MeshRayPacket::kNoTriangle) continue;
        const std::uint32_t i = lane_ray[j];
        const real d[3] = {packet.d[0][j], packet.d[1][j], packet.d[2][j]};
        LocalHit h;
        h.t = packet.tmax[j];
        mesh_triangle_normal(*ob.shape.mesh, packet.tri[j], h.n);
        commit(ob, id, d, h, packet.tri[j], best[i]);
        if (best[i].found) t[i] = best[i].t;
      }
    } else {
      for (std::uint32_t j = 0; j < live; ++j) {
        const std::uint32_t i = lane_ray[j];
        test_object_local(ob, id, c.o_l[k], rays[i], tmin, best[i], t[i]);
        if (best[i].found) t[i] = best[i].t;
      }
    }
  }
  for (std::uint32_t i = 0; i < n; ++i) found[i] = finish(objects_, best[i], hits[i]);
}

}  // namespace kestrel::sensors
