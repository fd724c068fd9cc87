// Fuzz target: a PGM or PNG height map -> Terrain::build (the public entry to read_pgm/read_png),
// height_at, sphere/box collide. Byte 0: bit 0 picks .pgm / .png, bits 1-3 the horizontal scale,
// bits 4-6 the vertical scale; the rest is the file.
// Contract: no crash, no sanitizer report, no allocation beyond sim/limits.hpp's height-map cap
// (the fuzzer's -rss_limit_mb catches one); every height of a built terrain finite; probes finite.
#include <cstdint>
#include <string>

#include "fuzz_common.hpp"
#include "kestrel/sim/limits.hpp"
#include "terrain_checks.hpp"

using namespace kestrel;
using namespace kestrel::sim;

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  (void)kfuzz::work_dir();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::string path = kfuzz::write_input((data[0] & 1) ? "map.png" : "map.pgm", data + 1, size - 1);
  static const real kHorizontal[8] = {0.1_r, 1e-3_r, 0.05_r, 1, 10, 1e3_r, 0.25_r, 1e-4_r};
  static const real kVertical[8] = {0.005_r, 1, 1e-6_r, 0.1_r, 100, 1e4_r, 0.02_r, 1e3_r};
  TerrainConfig tc;
  tc.type = TerrainType::heightfield;
  tc.image_file = path;
  tc.horizontal_scale_m = kHorizontal[(data[0] >> 1) & 7];
  tc.vertical_scale_m = kVertical[(data[0] >> 4) & 7];
  tc.origin_m = Vec3(-0.5_r, 0.25_r, (data[0] & 0x80) ? 3.0_r : 0.0_r);
  std::unique_ptr<Terrain> t;
  std::string err;
  if (!Terrain::build(tc, 7, t, err)) return 0;
  KFUZZ_CHECK(t->nx() >= 1 && t->ny() >= 1, "grid %d x %d", t->nx(), t->ny());
  KFUZZ_CHECK(static_cast<long long>(t->nx()) * t->ny() <= kMaxHeightmapSamples, "grid %d x %d over the cap", t->nx(), t->ny());
  KFUZZ_CHECK(kfuzz::all_finite(t->heights().data(), t->heights().size()), "height not finite");
  kfuzz::probe_terrain(*t, data[0]);
  return 0;
}
