// Run outputs (sim/output.hpp): the trajectory plot's line rasteriser with far coordinates.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "kestrel/sim/output.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/world.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {
constexpr int kW = 64, kH = 48;
std::size_t count_colour(const std::vector<unsigned char>& rgb, const unsigned char c[3]) {
  std::size_t n = 0;
  for (std::size_t i = 0; i + 2 < rgb.size(); i += 3) n += rgb[i] == c[0] && rgb[i + 1] == c[1] && rgb[i + 2] == c[2];
  return n;
}
}  // namespace

// Fuzz finding F2: pixel coordinates of obstacles ~1e9 m away overflowed int in the Bresenham
// rasteriser (2 * err, |x1 - x0|) and `kestrel run` crashed writing trajectory.png. Far segments
// are clipped in floating point first: only their on-canvas part is drawn, and quickly.
TEST(SimOutput, FarLineCoordinatesAreClippedNotOverflowed) {
  const unsigned char red[3] = {255, 0, 0};
  std::vector<unsigned char> rgb(static_cast<std::size_t>(kW) * kH * 3, 255);
  // A horizontal line through row 10 from -6e10 to +6e10 px: exactly the canvas width.
  EXPECT_EQ(draw_line_rgb(rgb.data(), kW, kH, -6e10, 10, 6e10, 10, red), static_cast<std::size_t>(kW));
  EXPECT_EQ(count_colour(rgb, red), static_cast<std::size_t>(kW));
  for (int x = 0; x < kW; ++x) EXPECT_EQ(rgb[(10 * kW + x) * 3 + 1], 0) << x;
  // A vertical one at the float limit, a diagonal through the canvas, and lines wholly off it.
  EXPECT_EQ(draw_line_rgb(rgb.data(), kW, kH, 5, -3.4e38, 5, 3.4e38, red), static_cast<std::size_t>(kH));
  EXPECT_GT(draw_line_rgb(rgb.data(), kW, kH, -1e12, -1e12, 1e12, 1e12, red), 40u);
  EXPECT_EQ(draw_line_rgb(rgb.data(), kW, kH, -1e12, -5, 1e12, -5, red), 0u);
  EXPECT_EQ(draw_line_rgb(rgb.data(), kW, kH, 1e9, 1e9, 2e9, 3e9, red), 0u);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(draw_line_rgb(rgb.data(), kW, kH, nan, 1, 5, 5, red), 0u);
  EXPECT_EQ(draw_line_rgb(rgb.data(), kW, kH, -inf, 1, inf, 1, red), 0u);
  // On the canvas: the plain Bresenham line, endpoints included.
  std::vector<unsigned char> small(static_cast<std::size_t>(kW) * kH * 3, 255);
  EXPECT_EQ(draw_line_rgb(small.data(), kW, kH, 2, 3, 12, 8, red), 11u);
  EXPECT_EQ(small[(3 * kW + 2) * 3 + 1], 0);
  EXPECT_EQ(small[(8 * kW + 12) * 3 + 1], 0);
}

// The fuzz report's scene, as obstacle bounding boxes 1e9 m (and 3.4e38 m) out: trajectory.png is
// written (the Release build crashed with SIGSEGV before the fix).
TEST(SimOutput, TrajectoryPngWithFarObstaclesIsWritten) {
  WorldConfig c;
  ASSERT_TRUE(registries().envs.make("empty", c.env));
  c.env.num_envs = 1;
  AssetClass a;
  a.name = "c";
  a.kind = AssetKind::cube;
  a.num_assets = a.min_num_assets = 3;
  c.env.assets.push_back(a);
  std::string err;
  auto w = World::create(c, err);
  ASSERT_TRUE(w) << err;
  w->enable_trace(1, 4);
  w->step(3);
  ASSERT_GE(w->num_obstacles(0), 3);
  w->obstacle(0, 0).aabb_min_w = Vec3(-1e9_r, -0.5_r, 0);
  w->obstacle(0, 0).aabb_max_w = Vec3(0.5_r, 5.5_r, 5);
  w->obstacle(0, 1).aabb_min_w = Vec3(-3.4e38_r, -3.4e38_r, 0);
  w->obstacle(0, 1).aabb_max_w = Vec3(3.4e38_r, 3.4e38_r, 1);
  w->obstacle(0, 2).aabb_min_w = Vec3(2e9_r, 2e9_r, 0);
  w->obstacle(0, 2).aabb_max_w = Vec3(3e9_r, 3e9_r, 1);
  const std::string path = std::string(::testing::TempDir()) + "kestrel_far_trajectory.png";
  ASSERT_TRUE(write_trajectory_png(*w, path, err)) << err;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  ASSERT_NE(f, nullptr);
  std::fclose(f);
  std::remove(path.c_str());
}
