// The obstacle layout generator both backends share (sim/layout.hpp): the curriculum level sets
// how many assets a class gets and how many draws it makes, the slot and sink forms agree, walls
// and trees mark which of their parts are upright (what the planar backend keeps), and the rigid
// World's layout is exactly the generator's.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "kestrel/sim/layout.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/world.hpp"

namespace kestrel::sim {
namespace {

WorldConfig forest_config() {
  WorldConfig c;
  AssetClass walls;
  walls.name = "walls";
  walls.kind = AssetKind::wall;
  walls.num_assets = walls.min_num_assets = 1;
  walls.keep_in_env = true;
  AssetClass trees;
  trees.name = "trees";
  trees.kind = AssetKind::tree;
  trees.num_assets = 6;
  trees.min_num_assets = 2;
  trees.min_size_m = Vec3(0.1_r, 0.5_r, 2);
  trees.max_size_m = Vec3(0.2_r, 1.0_r, 4);
  AssetClass cubes;
  cubes.name = "cubes";
  cubes.kind = AssetKind::cube;
  cubes.num_assets = 4;
  cubes.min_num_assets = 0;
  c.env.assets = {walls, trees, cubes};
  c.env.lower_bound_min_m = c.env.lower_bound_max_m = Vec3(-5, -5, 0);
  c.env.upper_bound_min_m = c.env.upper_bound_max_m = Vec3(5, 5, 4);
  return c;
}

int capacity(const WorldConfig& c) {
  int n = 0;
  for (const AssetClass& a : c.env.assets) n += asset_class_slots(a);
  return n;
}

TEST(SimLayout, CurriculumLevelSetsCountsAndDraws) {
  const WorldConfig c = forest_config();
  std::vector<Obstacle> slots(static_cast<std::size_t>(capacity(c)));
  const Vec3 lo(-5, -5, 0), hi(5, 5, 4);
  // Level 0: the walls (5) and the minimum of 2 trees (1 + kTreeBranches parts each), no cubes.
  RngStream a(7, 0, kPurposeReset), b(7, 0, kPurposeReset);
  const int n0 = generate_layout(c, 0, lo, hi, a, nullptr, slots.data());
  EXPECT_EQ(n0, 5 + 2 * (1 + kTreeBranches));
  // Level 1: every asset; and more draws, so the stream has moved further.
  const int n1 = generate_layout(c, 1, lo, hi, b, nullptr, slots.data());
  EXPECT_EQ(n1, 5 + 6 * (1 + kTreeBranches) + 4);
  EXPECT_NE(a.next_u32(), b.next_u32());
  // Upright parts: the four side walls (not the ceiling), each trunk (not its branches), every cube.
  int upright = 0;
  for (int i = 0; i < n1; ++i) upright += slots[static_cast<std::size_t>(i)].upright ? 1 : 0;
  EXPECT_EQ(upright, 4 + 6 + 4);
  EXPECT_FALSE(slots[4].upright);  // the ceiling
  EXPECT_GT(slots[4].shape.position_w[2], hi[2]);
  for (int i = 0; i < n1; ++i) {
    const Obstacle& o = slots[static_cast<std::size_t>(i)];
    EXPECT_TRUE((o.aabb_min_w.array() <= o.aabb_max_w.array()).all());  // bounding boxes are set
    // A trunk stands on the ground: its capsule reaches one radius below the lower bound.
    if (o.kind == AssetKind::tree && o.upright) {
      EXPECT_NEAR(o.aabb_min_w[2], lo[2] - o.shape.radius_m, 1e-5);
    }
  }
}

TEST(SimLayout, SinkAndSlotsAgree) {
  const WorldConfig c = forest_config();
  std::vector<Obstacle> slots(static_cast<std::size_t>(capacity(c))), seen;
  RngStream a(11, 3, kPurposeReset), b(11, 3, kPurposeReset);
  const int n = generate_layout(c, 0.5_r, Vec3(-5, -5, 0), Vec3(5, 5, 4), a, nullptr, slots.data());
  struct Collect {
    static void put(void* v, const Obstacle& o) { static_cast<std::vector<Obstacle>*>(v)->push_back(o); }
  };
  const int m = generate_layout(c, 0.5_r, Vec3(-5, -5, 0), Vec3(5, 5, 4), b, nullptr, &Collect::put, &seen);
  ASSERT_EQ(n, m);
  ASSERT_EQ(static_cast<int>(seen.size()), n);
  for (int i = 0; i < n; ++i) {
    EXPECT_EQ(std::memcmp(slots[static_cast<std::size_t>(i)].shape.position_w.data(), seen[static_cast<std::size_t>(i)].shape.position_w.data(),
                          sizeof(real) * 3),
              0);
    EXPECT_EQ(slots[static_cast<std::size_t>(i)].class_index, seen[static_cast<std::size_t>(i)].class_index);
  }
}

TEST(SimLayout, RigidWorldHoldsTheGeneratorsLayout) {
  WorldConfig c = forest_config();
  c.env.num_envs = 3;
  c.num_threads = 1;
  std::string err;
  auto w = World::create(c, err);
  ASSERT_TRUE(w) << err;
  for (int env = 0; env < 3; ++env) {
    // Replay the World's reset stream: fixed bounds (empty ranges draw nothing), then the layout.
    RngStream rng(c.seed, static_cast<std::uint32_t>(env), kPurposeReset);
    const Vec3 lo(-5, -5, 0), hi(5, 5, 4);
    std::vector<Obstacle> slots(static_cast<std::size_t>(capacity(c)));
    const int n = generate_layout(c, c.env.curriculum_level, lo, hi, rng, nullptr, slots.data());
    ASSERT_EQ(n, w->num_obstacles(env));
    // The World keeps them in sweep order; compare as multisets of positions.
    int matched = 0;
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < n; ++k)
        if (std::memcmp(slots[static_cast<std::size_t>(i)].shape.position_w.data(), w->obstacle(env, k).shape.position_w.data(),
                        sizeof(real) * 3) == 0) {
          ++matched;
          break;
        }
    EXPECT_EQ(matched, n) << "env " << env;
  }
}

}  // namespace
}  // namespace kestrel::sim
