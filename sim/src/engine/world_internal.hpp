// Helpers shared by the rigid World's stage files (sim/src/engine/); not part of any interface.
#pragma once

#include "kestrel/kernel/rng.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel::sim::stage {

/// Uniform per axis in [lo, hi); an empty range gives lo (and draws nothing).
inline Vec3 uniform_vec(RngStream& rng, const Vec3& lo, const Vec3& hi) {
  Vec3 v;
  for (int i = 0; i < 3; ++i) v[i] = lo[i] < hi[i] ? rng.uniform(lo[i], hi[i]) : lo[i];
  return v;
}

}  // namespace kestrel::sim::stage
