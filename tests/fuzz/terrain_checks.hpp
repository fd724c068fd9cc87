// Probes of a built Terrain shared by fuzz_mesh and fuzz_heightmap: height_at and collide() of a
// sphere and a box at a few places over and around it; every result must be finite and the
// contact count within [0, kMaxTerrainContacts].
#pragma once

#include "fuzz_common.hpp"
#include "kestrel/sim/collision.hpp"
#include "kestrel/sim/terrain.hpp"

namespace kfuzz {

inline void probe_terrain(const kestrel::sim::Terrain& t, std::uint8_t salt) {
  using namespace kestrel;
  using namespace kestrel::sim;
  const real xs[] = {0, 0.05_r, -1.3_r, 2.7_r, static_cast<real>(salt) * 0.01_r, 1e4_r};
  for (real x : xs)
    for (real y : xs) {
      const real h = t.height_at(x, y);
      KFUZZ_CHECK(std::isfinite(h), "height_at(%g, %g) = %g", static_cast<double>(x), static_cast<double>(y),
                  static_cast<double>(h));
      for (int kind = 0; kind < 2; ++kind) {
        Shape s;
        s.type = kind == 0 ? ShapeType::sphere : ShapeType::box;
        s.radius_m = 0.2_r;
        s.half_extents_m = Vec3(0.2_r, 0.1_r, 0.05_r);
        s.position_w = Vec3(x, y, h + 0.1_r);
        s.orientation_wb = Quat(Eigen::AngleAxis<real>(0.3_r * static_cast<real>(salt % 7), Vec3(0.6_r, 0.8_r, 0)));
        Contact c[kMaxTerrainContacts];
        const int n = t.collide(s, 0.25_r, c);
        KFUZZ_CHECK(n >= 0 && n <= kMaxTerrainContacts, "collide returned %d contacts", n);
        for (int i = 0; i < n; ++i)
          KFUZZ_CHECK(std::isfinite(c[i].depth_m) && c[i].normal_w.allFinite() && c[i].point_w.allFinite(),
                      "contact %d of %d not finite", i, n);
      }
    }
}

}  // namespace kfuzz
