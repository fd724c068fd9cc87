// Frozen golden state hash: a small fixed scenario (6 dynamic environments with moving and
// spinning obstacles, 2 robots each so robots also hit each other, disturbances on, 300 env-steps,
// 1 thread) whose final World::state_hash() must equal the value committed below. Any change of
// physics, collision, reset or random-stream results — intended or not — changes it. The
// thread-count and run-to-run determinism tests (world_test.cpp) compare runs with each other;
// this one compares with the past.
//
// Regenerating after an INTENDED change of results: run
//   kestrel_sim_tests --gtest_filter=SimGoldenHash.*
// read the "actual" hash in the failure message, and replace kGoldenStateHash with it in the same
// commit as the change, saying in the commit message why the results changed.
#include <gtest/gtest.h>

#include <cinttypes>
#include <cstdio>

#include <memory>
#include <vector>

#include "kestrel/kernel/rng.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/simulator.hpp"
#include "kestrel/sim/world.hpp"
#include "legged_config.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {
// Float build (the default); the double build (KESTREL_DOUBLE) has other bits and skips the check.
constexpr std::uint64_t kGoldenStateHash = 0xe95f8efa954452c3ull;
}  // namespace

TEST(SimGoldenHash, DynamicEnvWithCollisionsMatchesTheFrozenHash) {
  WorldConfig c;
  ASSERT_TRUE(registries().envs.make("dynamic", c.env));
  c.env.num_envs = 6;
  c.env.enable_disturbance = true;
  c.robot.robots_per_env = 2;
  c.task.episode_len_env_steps = 120;
  c.task.line_of_sight = false;  // straight flights through the moving obstacles: crashes
  c.task.clearance_m = 0;
  c.seed = 20261121;
  c.num_threads = 1;
  std::string err;
  auto w = World::create(c, err);
  ASSERT_TRUE(w) << err;
  w->step(300);
  const WorldSummary s = w->summary();
  // The scenario must keep exercising what it guards: collisions, crashes and resets.
  EXPECT_GT(s.crashes, 0u);
  EXPECT_GT(s.resets, 0u);
  char hex[32];
  std::snprintf(hex, sizeof hex, "0x%016" PRIx64, w->state_hash());
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  GTEST_SKIP() << "golden hash is recorded for the float build (this build: " << hex << ")";
#else
  EXPECT_EQ(w->state_hash(), kGoldenStateHash) << "actual " << hex << "; see the file comment before updating kGoldenStateHash";
#endif
}

// The same for articulated robots (issue 12): Go2 on legged_gym's tiled terrain with every
// randomisation of simulator.* on, random joint targets at the torque limits, pushes of the base
// and of every link, base-contact and timeout resets, 200 env-steps of 4 physics steps, 1 thread.
namespace {
// Re-frozen when projected Gauss-Seidel began keeping every row's residual in one vector (summed
// afresh per sweep, updated as impulses change) instead of summing W_r . lambda serially per row:
// same solver, other rounding.
constexpr std::uint64_t kGoldenLeggedHash = 0x07220a284e60532full;
}  // namespace

TEST(SimGoldenHash, LeggedRunWithContactsPushesAndResetsMatchesTheFrozenHash) {
  WorldConfig c;
  ASSERT_TRUE(registries().robots.make("go2", c.robot));
  ASSERT_TRUE(registries().sims.make("legged_sim", c.sim));
  ASSERT_TRUE(registries().tasks.make("joint_targets", c.task));
  c.task.episode_len_env_steps = 60;
  c.env.num_envs = 6;
  c.env.num_physics_steps_per_env_step_mean = 4;
  kestrel::test::tiled_terrain(c.env.terrain, 3, 3, 2);
  kestrel::test::randomise_all_articulated(c);
  c.seed = 20261127;
  c.num_threads = 1;
  std::string err;
  std::unique_ptr<Simulator> sim = make_simulator(c, err);
  ASSERT_TRUE(sim) << err;
  RngStream rng(c.seed, 0, kPurposeUser + 77);
  std::vector<real> a(static_cast<std::size_t>(sim->num_robots() * sim->action_dim()));
  for (int s = 0; s < 200; ++s) {
    for (real& v : a) v = rng.uniform(-4, 4);
    if (s % 25 == 0) sim->push_robots();
    if (s % 30 == 0) {
      ASSERT_TRUE(sim->push_links());
    }
    sim->step(a.data());
  }
  const WorldSummary s = sim->summary();
  EXPECT_GT(s.crashes, 0u);   // base contacts
  EXPECT_GT(s.timeouts, 0u);  // and timeouts, both resetting
  char hex[32];
  std::snprintf(hex, sizeof hex, "0x%016" PRIx64, sim->state_hash());
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  GTEST_SKIP() << "golden hash is recorded for the float build (this build: " << hex << ")";
#else
  EXPECT_EQ(sim->state_hash(), kGoldenLeggedHash) << "actual " << hex << "; see the file comment before updating kGoldenLeggedHash";
#endif
}
