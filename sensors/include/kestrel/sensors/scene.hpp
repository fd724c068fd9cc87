// A scene: shape instances with rigid poses and segmentation ids, and the instance-level BVH (the
// second level of the two-level scheme; mesh assets carry the first level, see mesh.hpp).
//
// Moving obstacles: set_pose() marks the scene dirty and intersect()/render refuse a dirty scene
// (Status::invalid_argument from the sensors) until build() has re-run, so a render never sees a
// stale hierarchy. build() over a few hundred instances costs microseconds (binned SAH over
// instance boxes), so it is simply re-run whenever anything moved; Aerial Gym's Warp path only
// refits at reset and cannot show moving obstacles.
//
// Determinism: equal-distance hits resolve to the lowest (object id, primitive id). Object ids are
// the order of add() calls, independent of the BVH layout.
#pragma once

#include <cstdint>

#include "kestrel/kernel/status.hpp"
#include "kestrel/kernel/types.hpp"
#include "kestrel/sensors/bvh.hpp"
#include "kestrel/sensors/geometry.hpp"
#include "kestrel/sensors/mesh.hpp"

namespace kestrel::sensors {

enum class ShapeType : std::uint8_t { box, sphere, capsule, cylinder, plane, mesh, height_field };

/// A shape in its local frame. Capsules and cylinders are along local z.
struct Shape {
  ShapeType type = ShapeType::box;
  real size[3] = {0.5_r, 0.5_r, 0.5_r};  // box: half extents; sphere: radius; capsule/cylinder: radius, half length
  const TriangleMesh* mesh = nullptr;         // type mesh (built with mesh_build)
  const HeightField* height_field = nullptr;  // type height_field (prepared)

  static Shape box(real hx, real hy, real hz) { return Shape{ShapeType::box, {hx, hy, hz}, nullptr, nullptr}; }
  static Shape sphere(real r) { return Shape{ShapeType::sphere, {r, 0, 0}, nullptr, nullptr}; }
  static Shape capsule(real r, real half_length) { return Shape{ShapeType::capsule, {r, half_length, 0}, nullptr, nullptr}; }
  static Shape cylinder(real r, real half_length) { return Shape{ShapeType::cylinder, {r, half_length, 0}, nullptr, nullptr}; }
  static Shape plane() { return Shape{ShapeType::plane, {0, 0, 0}, nullptr, nullptr}; }
  static Shape triangle_mesh(const TriangleMesh* m) { return Shape{ShapeType::mesh, {0, 0, 0}, m, nullptr}; }
  static Shape heights(const HeightField* h) { return Shape{ShapeType::height_field, {0, 0, 0}, nullptr, h}; }
};

/// One instance. r_wl is the local-to-world rotation, row-major.
struct SceneObject {
  Shape shape;
  real p_w[3] = {0, 0, 0};
  real r_wl[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  Aabb box_w;
  std::uint32_t seg_id = 0;
};

struct SceneHit {
  real t = 0;                          // range along the unit ray, m
  Vec3 normal_w = Vec3::Zero();        // unit, facing the ray for meshes/height fields, outward for solids
  std::uint32_t seg_id = 0;            // object's id, or the mesh part id
  std::uint32_t object = 0;            // object id (add order)
  std::uint32_t prim = 0;              // triangle / cell triangle, 0 for analytic shapes
};

/// Objects that rays sharing one origin and lying within one cone of directions may hit, ordered
/// by a lower bound of their hit range (Scene::gather_cone). A sensor's rays share the sensor
/// origin, so a tile of neighbouring rays is such a bundle: the instance BVH is then replaced by a
/// short list walked nearest-first that stops once the lower bound passes the best hit, and the
/// origin is moved into each candidate's local frame once per tile instead of once per ray.
struct ConeCandidates {
  static constexpr std::uint32_t kMax = 64;
  std::uint32_t count = 0;
  bool overflow = false;  // more than kMax candidates: intersect() falls back to the BVH walk
  real origin_w[3] = {0, 0, 0};
  std::uint32_t id[kMax];
  real lower[kMax];    // lower bound of the range of any hit on the object (conservative)
  real o_l[kMax][3];   // origin_w in the object's local frame, computed as the single-ray path does
};

/// Caller-provided storage for up to N objects.
template <std::uint32_t N>
struct SceneStorage {
  SceneObject objects[N];
  BvhNode nodes[bvh_node_capacity(N)];
  std::uint32_t prim_index[N];
  Aabb boxes[N];
  std::uint32_t bvh_objects[N];
};

class Scene {
 public:
  static constexpr std::uint32_t kMaxUnbounded = 8;  // planes (cannot live in a BVH)

  Scene() = default;
  Scene(SceneObject* objects, std::uint32_t capacity, BvhNode* nodes, std::uint32_t node_capacity,
        std::uint32_t* prim_index, Aabb* boxes, std::uint32_t* bvh_objects);
  template <std::uint32_t N>
  explicit Scene(SceneStorage<N>& s)
      : Scene(s.objects, N, s.nodes, bvh_node_capacity(N), s.prim_index, s.boxes, s.bvh_objects) {}

  void clear();
  /// Adds an object; its id (add order) goes to *id. Full -> capacity_exceeded; a mesh without a
  /// built BVH, a non-positive size or too many planes -> invalid_argument / capacity_exceeded.
  [[nodiscard]] Status add(const Shape& shape, const Vec3& position_w, const Quat& orientation_wl, std::uint32_t seg_id,
                           std::uint32_t* id = nullptr);
  [[nodiscard]] Status set_pose(std::uint32_t id, const Vec3& position_w, const Quat& orientation_wl);
  /// Rebuilds the instance BVH from the current poses.
  [[nodiscard]] Status build(const BvhBuildParams& params = {});
  bool dirty() const { return dirty_; }
  std::uint32_t size() const { return count_; }
  const SceneObject& object(std::uint32_t id) const { return objects_[id]; }

  /// Closest hit of the world ray (o_w, unit d_w) in [tmin, tmax]. False on a dirty scene.
  bool intersect(const Vec3& o_w, const Vec3& d_w, real tmin, real tmax, SceneHit& hit) const;
  bool intersect(const Ray& ray_w, real tmin, real tmax, SceneHit& hit) const;

  /// Collects the bounded objects that a ray from origin_w with a unit direction d,
  /// dot(d, axis_w) >= cos_half_angle, can hit within range tmax (axis_w unit; cos_half_angle <= -1:
  /// any direction). Conservative: it never leaves out an object such a ray hits.
  void gather_cone(const real origin_w[3], const real axis_w[3], real cos_half_angle, real tmax,
                   ConeCandidates& c) const;
  /// Closest hit of ray_w (origin exactly c.origin_w, direction within the gathered cone). Same
  /// result as intersect(ray_w, ...): the same (t, object, prim) minimum over the same tests.
  bool intersect(const ConeCandidates& c, const Ray& ray_w, real tmin, real tmax, SceneHit& hit) const;
  /// Rays i < n (n <= kMaxTileRays) from c.origin_w with world directions d_w[i] (within the
  /// gathered cone), cast together: found[i] and hits[i] are what intersect(c, make_ray(c.origin_w,
  /// d_w[i]), tmin, tmax[i], hit) returns, bit for bit. Mesh candidates are walked once for all
  /// the rays that reach them (mesh_intersect_packet); other shapes ray by ray.
  static constexpr std::uint32_t kMaxTileRays = MeshRayPacket::kMax;
  void intersect_tile(const ConeCandidates& c, const real (*d_w)[3], std::uint32_t n, real tmin, const real* tmax,
                      SceneHit* hits, bool* found) const;

 private:
  SceneObject* objects_ = nullptr;
  std::uint32_t capacity_ = 0;
  std::uint32_t count_ = 0;
  Bvh bvh_;
  Aabb* boxes_ = nullptr;
  std::uint32_t* bvh_objects_ = nullptr;  // BVH primitive -> object id (planes are not in the BVH)
  std::uint32_t unbounded_[kMaxUnbounded] = {};
  std::uint32_t unbounded_count_ = 0;
  bool dirty_ = true;
};

}  // namespace kestrel::sensors
