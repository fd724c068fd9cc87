// The obstacle layout generator shared by every backend (sim/layout.hpp).
#include "kestrel/sim/layout.hpp"

#include <cmath>

#include "kestrel/kernel/quaternion.hpp"
#include "episode_draw.hpp"

namespace kestrel::sim {

using scene::uniform_vec;

// Long on purpose: one switch over the asset kinds, and the order of its draws is part of the
// determinism contract (every hash depends on it), so it reads top to bottom in one place.
int generate_layout(const WorldConfig& cfg, real level, const Vec3& lower_w, const Vec3& upper_w, RngStream& rng,
                    const std::vector<std::vector<Vec3>>* mesh_vertices, LayoutSink sink, void* context) {
  const Vec3 lo = lower_w, hi = upper_w, span = hi - lo;
  int n = 0;
  for (std::size_t ci = 0; ci < cfg.env.assets.size(); ++ci) {
    const AssetClass& c = cfg.env.assets[ci];
    auto emit = [&](const Shape& s, bool upright) {
      Obstacle o;
      o.shape = s;
      o.semantic_id = static_cast<std::int16_t>(c.semantic_id);
      o.kind = c.kind;
      o.class_index = static_cast<std::uint8_t>(ci);
      o.upright = upright;
      o.linvel_w = Vec3::Zero();
      if (c.max_speed_m_s > 0) o.linvel_w = uniform_vec(rng, Vec3::Constant(-c.max_speed_m_s), Vec3::Constant(c.max_speed_m_s));
      // Drawn only for rotating classes, so layouts without rotation keep their stream positions.
      o.angvel_w = Vec3::Zero();
      if (c.max_angular_speed_rad_s > 0 && c.kind != AssetKind::wall)
        o.angvel_w = uniform_vec(rng, Vec3::Constant(-c.max_angular_speed_rad_s), Vec3::Constant(c.max_angular_speed_rad_s));
      shape_aabb(o.shape, o.aabb_min_w, o.aabb_max_w);
      sink(context, o);
      ++n;
    };
    if (c.kind == AssetKind::wall) {
      // Thin boxes just outside the bounds (they bound the flight volume, Aerial Gym's walls).
      const real t = 0.05_r;
      const Vec3 mid = (lo + hi) / 2;
      Shape s;
      s.type = ShapeType::box;
      s.half_extents_m = Vec3(t, span[1] / 2 + t, span[2] / 2);
      s.position_w = Vec3(lo[0] - t, mid[1], mid[2]);
      emit(s, true);
      s.position_w = Vec3(hi[0] + t, mid[1], mid[2]);
      emit(s, true);
      s.half_extents_m = Vec3(span[0] / 2 + t, t, span[2] / 2);
      s.position_w = Vec3(mid[0], lo[1] - t, mid[2]);
      emit(s, true);
      s.position_w = Vec3(mid[0], hi[1] + t, mid[2]);
      emit(s, true);
      s.half_extents_m = Vec3(span[0] / 2 + t, span[1] / 2 + t, t);
      s.position_w = Vec3(mid[0], mid[1], hi[2] + t);
      emit(s, false);  // the ceiling
      continue;
    }
    const int count = scene::asset_count(c, level);
    for (int k = 0; k < count; ++k) {
      const Vec3 ratio = uniform_vec(rng, c.min_position_ratio, c.max_position_ratio);
      const Vec3 e = uniform_vec(rng, c.min_euler_rad, c.max_euler_rad);
      const Vec3 size = uniform_vec(rng, c.min_size_m, c.max_size_m);
      const Vec3 p = lo + ratio.cwiseProduct(span);
      const Quat q = quat_from_euler_xyz(e[0], e[1], e[2]);
      Shape s;
      s.position_w = p;
      s.orientation_wb = q;
      switch (c.kind) {
        case AssetKind::tree: {
          // Procedural tree: trunk (size x = radius, z = height) standing on the ground, and
          // kTreeBranches capsules leaving it at random heights, azimuths and tilts (size y =
          // branch length). Parametric and randomised as Aerial Gym's generated forest URDFs.
          const real r = size[0], h = size[2];
          s.type = ShapeType::capsule;
          s.radius_m = r;
          s.half_length_m = h / 2;
          s.orientation_wb = Quat::Identity();
          s.position_w = Vec3(p[0], p[1], lo[2] + h / 2);
          emit(s, true);
          for (int b = 0; b < kTreeBranches; ++b) {
            const real at = rng.uniform(0.4_r, 0.9_r) * h;
            const real az = rng.uniform(0, kTwoPi);
            const real tilt = rng.uniform(0.5_r, 1.1_r);  // rad from vertical
            const real len = size[1] * rng.uniform(0.6_r, 1.0_r);
            const Quat qb = quat_from_euler_xyz(0, tilt, az);
            Shape br;
            br.type = ShapeType::capsule;
            br.radius_m = r * 0.5_r;
            br.half_length_m = len / 2;
            br.orientation_wb = qb;
            br.position_w = Vec3(p[0], p[1], lo[2] + at) + rotate(qb, Vec3(0, 0, len / 2));
            emit(br, false);
          }
          break;
        }
        case AssetKind::panel:  // thin plate: x thickness, y width, z height
          s.type = ShapeType::box;
          s.half_extents_m = Vec3(0.025_r, size[1] / 2, size[2] / 2);
          emit(s, true);
          break;
        case AssetKind::cube:
          s.type = ShapeType::box;
          s.half_extents_m = Vec3::Constant(size[0] / 2);
          emit(s, true);
          break;
        case AssetKind::small_wall:
          s.type = ShapeType::box;
          s.half_extents_m = Vec3(0.05_r, size[1] / 2, size[2] / 2);
          emit(s, true);
          break;
        case AssetKind::rod:
          s.type = ShapeType::capsule;
          s.radius_m = size[0];
          s.half_length_m = size[2] / 2;
          emit(s, true);
          break;
        case AssetKind::thin:
          s.type = ShapeType::cylinder;
          s.radius_m = size[0];
          s.half_length_m = size[2] / 2;
          emit(s, true);
          break;
        case AssetKind::sphere:
          s.type = ShapeType::sphere;
          s.radius_m = size[0];
          emit(s, true);
          break;
        case AssetKind::mesh:
          s.type = ShapeType::convex_hull;
          if (mesh_vertices != nullptr && ci < mesh_vertices->size()) {
            s.vertices = (*mesh_vertices)[ci].data();
            s.num_vertices = static_cast<int>((*mesh_vertices)[ci].size());
          }
          emit(s, true);
          break;
        case AssetKind::wall:
          break;
      }
    }
  }
  return n;
}

int generate_layout(const WorldConfig& cfg, real level, const Vec3& lower_w, const Vec3& upper_w, RngStream& rng,
                    const std::vector<std::vector<Vec3>>* mesh_vertices, Obstacle* slots) {
  struct Fill {
    Obstacle* next;
    static void put(void* self, const Obstacle& o) { *static_cast<Fill*>(self)->next++ = o; }
  } fill{slots};
  return generate_layout(cfg, level, lower_w, upper_w, rng, mesh_vertices, &Fill::put, &fill);
}

}  // namespace kestrel::sim
