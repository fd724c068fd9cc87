// World behaviour: determinism over thread counts, no heap in step, contacts/crash/reset, bounds,
// curriculum, layouts, latency, physics steps per env step, dynamic obstacles, registries.
#include <gtest/gtest.h>

#include "heap_counter.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/world.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {
WorldConfig config(const char* env, int num_envs, int threads) {
  WorldConfig c;
  EXPECT_TRUE(registries().envs.make(env, c.env));
  c.env.num_envs = num_envs;
  c.num_threads = threads;
  c.seed = 42;
  return c;
}
std::unique_ptr<World> build(const WorldConfig& c) {
  std::string err;
  auto w = World::create(c, err);
  EXPECT_TRUE(w) << err;
  return w;
}
std::uint64_t run_hash(WorldConfig c, int threads, int steps) {
  c.num_threads = threads;
  auto w = build(c);
  for (int i = 0; i < steps; i += 25) w->step(25);
  return w->state_hash();
}
}  // namespace

TEST(SimWorld, HashIdenticalFor1_2_4ThreadsAndRuns) {
  for (const char* env : {"empty", "forest", "dynamic"}) {
    WorldConfig c = config(env, 37, 1);  // odd count: uneven partitions
    c.env.enable_disturbance = true;
    c.env.perturb_observations = true;
    c.env.sample_timestep_for_latency = true;
    const std::uint64_t h1 = run_hash(c, 1, 300);
    EXPECT_EQ(h1, run_hash(c, 2, 300)) << env;
    EXPECT_EQ(h1, run_hash(c, 4, 300)) << env;
    EXPECT_EQ(h1, run_hash(c, 1, 300)) << env;
    c.seed = 43;
    EXPECT_NE(h1, run_hash(c, 1, 300)) << env;
  }
}

TEST(SimWorld, ChunkedStepsEqualSingleSteps) {
  WorldConfig c = config("env_with_obstacles", 16, 2);
  auto a = build(c), b = build(c);
  a->step(100);
  for (int i = 0; i < 100; ++i) b->step(1);
  EXPECT_EQ(a->state_hash(), b->state_hash());
}

// Temporal blocking (World::set_block_envs) changes the order in which environments take their
// env-steps, never an environment's own order: every block size (one lane group, a few groups
// with a ragged last block, the default, none) gives the same state hash, summary and trace, on
// the batched path and the scalar one, with resets and crashes inside the blocked calls.
TEST(SimWorld, TemporalBlocksChangeNoResult) {
  for (const char* env : {"empty", "env_with_obstacles"}) {
    for (const bool batched : {true, false}) {
      std::uint64_t first_hash = 0;
      std::uint64_t first_resets = 0;
      double first_error = 0;
      Vec3 first_trace = Vec3::Zero();
      for (const int block : {64, 192, 0, 1 << 20}) {
        WorldConfig c = config(env, 301, 2);  // 301: a ragged last block and lane group
        c.task.episode_len_env_steps = 120;   // resets inside the calls
        auto w = build(c);
        w->set_batched(batched);
        w->set_block_envs(block);
        if (block == 0) {
          EXPECT_GE(w->block_envs(), 64);
          EXPECT_EQ(w->block_envs() % 64, 0);
        }
        w->enable_trace(3, 400);
        w->step(250);
        w->step(150);
        const WorldSummary s = w->summary();
        if (block == 64) {
          first_hash = w->state_hash();
          first_resets = s.resets;
          first_error = s.mean_tracking_error_m;
          first_trace = w->trace_point(2, 399);
          EXPECT_GT(s.resets, 301u) << env;
          continue;
        }
        EXPECT_EQ(w->state_hash(), first_hash) << env << " batched " << batched << " block " << block;
        EXPECT_EQ(s.resets, first_resets) << env << " block " << block;
        EXPECT_EQ(s.mean_tracking_error_m, first_error) << env << " block " << block;
        EXPECT_EQ(w->trace_point(2, 399), first_trace) << env << " block " << block;
      }
    }
  }
}

TEST(SimWorld, NoHeapInsideStep) {
  for (const char* env : {"empty", "env_with_obstacles", "forest", "dynamic"}) {
    WorldConfig c = config(env, 8, 1);  // one thread: the step runs on this (counted) thread
    c.env.enable_disturbance = true;
    c.env.perturb_observations = true;
    c.robot.robots_per_env = 2;
    auto w = build(c);
    w->enable_trace(2, 600);
    kestrel::test::HeapCounter counter;
    w->step(600);  // includes crashes, resets and new layouts
    EXPECT_EQ(counter.allocations(), 0u) << env;
    EXPECT_GT(w->summary().resets, 0u) << env;
  }
}

TEST(SimWorld, HoverIsStableInEmptyEnv) {
  WorldConfig c = config("empty", 16, 2);
  c.task.kind = TaskKind::hover;
  auto w = build(c);
  w->step(400);
  const WorldSummary s = w->summary();
  EXPECT_EQ(s.crashes, 0u);
  EXPECT_LT(s.final_mean_distance_m, 0.05);
}

TEST(SimWorld, PositionSetpointReachesTargets) {
  WorldConfig c = config("empty", 32, 2);
  c.task.episode_len_env_steps = 1000;
  auto w = build(c);
  w->step(900);
  EXPECT_LT(w->summary().final_mean_distance_m, 0.1);
}

TEST(SimWorld, RestsOnGroundPlaneWithPenaltyContact) {
  WorldConfig c = config("empty", 1, 1);
  c.controller.kind = ControllerKind::direct_motor;
  c.env.collision_force_threshold_N = 100;  // resting is not a crash here
  c.env.reset_on_collision = false;         // (the landing impact may be)
  c.task.kind = TaskKind::hover;
  c.task.episode_len_env_steps = 100000;
  auto w = build(c);
  real* a = w->action(0, 0);
  for (int m = 0; m < 4; ++m) a[m] = 0;  // motors off: it falls and lands
  w->step(400);
  const RigidBodyState& s = w->robot_state(0, 0);
  const double sink = 0.25 * 9.81 / 2000.0;  // m g / k
  EXPECT_NEAR(s.position_w[2], 0.2 - sink, 2e-4);
  EXPECT_NEAR(w->contact_force_w(0, 0)[2], 0.25 * 9.81, 0.02);
  EXPECT_LT(s.linvel_w.norm(), 0.05);  // viscous-regularised friction leaves a slow creep
  EXPECT_FALSE(w->crashed(0, 0));
}

TEST(SimWorld, CrashOnObstacleAndResetOnCollision) {
  for (bool reset : {true, false}) {
    WorldConfig c = config("env_with_obstacles", 1, 1);
    c.env.reset_on_collision = reset;
    c.task.kind = TaskKind::hover;
    auto w = build(c);
    // Put the robot inside the first cube-like obstacle that is a box.
    int box = -1;
    for (int i = 0; i < w->num_obstacles(0); ++i)
      if (w->obstacle(0, i).kind == AssetKind::cube) box = i;
    ASSERT_GE(box, 0);
    w->robot_state(0, 0).position_w = w->obstacle(0, box).shape.position_w;
    w->step(1);  // the collision pass of the step marks the crash at the end of the env-step
    EXPECT_EQ(w->stats(0).crashes, 1u);
    EXPECT_EQ(w->stats(0).resets, reset ? 1u : 0u);
    EXPECT_EQ(w->stats(0).episodes_done, reset ? 1u : 0u);
    if (!reset) {
      EXPECT_TRUE(w->crashed(0, 0));
      EXPECT_GT(w->contact_force_w(0, 0).norm(), 0.05);
    }
  }
}

TEST(SimWorld, RobotRobotContact) {
  WorldConfig c = config("empty", 1, 1);
  c.robot.robots_per_env = 2;
  c.env.reset_on_collision = false;
  c.task.kind = TaskKind::hover;
  auto w = build(c);
  w->robot_state(0, 1).position_w = w->robot_state(0, 0).position_w + Vec3(0.3_r, 0, 0);
  w->step(1);
  EXPECT_TRUE(w->crashed(0, 0));
  EXPECT_TRUE(w->crashed(0, 1));
  EXPECT_LT(w->contact_force_w(0, 0)[0], 0);  // pushed apart along x
  EXPECT_GT(w->contact_force_w(0, 1)[0], 0);
}

TEST(SimWorld, BoundsResampledWithinRangesPerReset) {
  WorldConfig c = config("env_with_obstacles", 64, 2);
  auto w = build(c);
  bool differ = false;
  Vec3 lo0, hi0;
  w->lower_upper_bounds(0, lo0, hi0);
  for (int e = 0; e < 64; ++e) {
    Vec3 lo, hi;
    w->lower_upper_bounds(e, lo, hi);
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(lo[k], c.env.lower_bound_min_m[k]);
      EXPECT_LE(lo[k], c.env.lower_bound_max_m[k]);
      EXPECT_GE(hi[k], c.env.upper_bound_min_m[k]);
      EXPECT_LE(hi[k], c.env.upper_bound_max_m[k]);
    }
    differ = differ || lo != lo0;
    // Robots start inside the bounds.
    const Vec3 p = w->robot_state(e, 0).position_w;
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(p[k] >= lo[k] && p[k] <= hi[k]);
  }
  EXPECT_TRUE(differ);
  Vec3 before, after, unused;
  w->lower_upper_bounds(3, before, unused);
  w->reset_env(3);
  w->lower_upper_bounds(3, after, unused);
  EXPECT_NE(before, after);
}

TEST(SimWorld, ObstacleCountCurriculumAndKeepInEnv) {
  WorldConfig c = config("env_with_obstacles", 4, 1);
  c.env.curriculum_level = 0;
  auto w = build(c);
  int min_total = 0, max_total = 0;
  for (const AssetClass& a : c.env.assets) {
    min_total += a.kind == AssetKind::wall ? 5 : a.keep_in_env ? a.num_assets : a.min_num_assets;
    max_total += asset_class_slots(a);
  }
  EXPECT_EQ(w->num_obstacles(0), min_total);
  w->set_curriculum_level(1);
  w->reset_env(0);
  EXPECT_EQ(w->num_obstacles(0), max_total);
  EXPECT_GE(max_total, 40);  // ~45 obstacles, as Aerial Gym's env_with_obstacles
  w->set_curriculum_level(0.5_r);
  w->reset_env(1);
  EXPECT_GT(w->num_obstacles(1), min_total);
  EXPECT_LT(w->num_obstacles(1), max_total);
  // Walls are keep_in_env: present at every level.
  int walls = 0;
  for (int i = 0; i < w->num_obstacles(2); ++i) walls += w->obstacle(2, i).kind == AssetKind::wall;
  EXPECT_EQ(walls, 5);
}

TEST(SimWorld, ForestTreesAreMultiLinkCapsules) {
  auto w = build(config("forest", 2, 1));
  EXPECT_EQ(w->num_obstacles(0), 10 * (1 + kTreeBranches));
  for (int i = 0; i < w->num_obstacles(0); ++i) {
    EXPECT_EQ(w->obstacle(0, i).shape.type, ShapeType::capsule);
    EXPECT_EQ(w->obstacle(0, i).semantic_id, 5);
    if (i > 0) {
      EXPECT_LE(w->obstacle(0, i - 1).aabb_min_w[0], w->obstacle(0, i).aabb_min_w[0]);  // sweep order
    }
  }
}

TEST(SimWorld, KeepSameEnvForNumEpisodes) {
  WorldConfig c = config("env_with_obstacles", 1, 1);
  c.env.keep_same_env_for_num_episodes = 3;
  auto w = build(c);
  EXPECT_EQ(w->layout_generation(0), 1u);
  const Vec3 p = w->obstacle(0, 7).shape.position_w;
  w->reset_env(0);
  w->reset_env(0);
  EXPECT_EQ(w->layout_generation(0), 1u);
  EXPECT_EQ(w->obstacle(0, 7).shape.position_w, p);
  w->reset_env(0);
  EXPECT_EQ(w->layout_generation(0), 2u);
}

TEST(SimWorld, PhysicsStepsPerEnvStepAndLatencySampled) {
  WorldConfig c = config("empty", 200, 1);
  c.env.num_physics_steps_per_env_step_mean = 3;
  c.env.num_physics_steps_per_env_step_std = 1;
  c.env.sample_timestep_for_latency = true;
  c.env.max_latency_physics_steps = 2;
  auto w = build(c);
  int mn = 1000, mx = 0, lat_mx = 0, lat_mn = 10;
  for (int e = 0; e < 200; ++e) {
    mn = std::min(mn, w->physics_steps_per_env_step(e));
    mx = std::max(mx, w->physics_steps_per_env_step(e));
    lat_mn = std::min(lat_mn, w->latency_physics_steps(e));
    lat_mx = std::max(lat_mx, w->latency_physics_steps(e));
  }
  EXPECT_GE(mn, 1);
  EXPECT_LT(mn, 3);
  EXPECT_GT(mx, 3);
  EXPECT_EQ(lat_mn, 0);
  EXPECT_EQ(lat_mx, 2);
}

TEST(SimWorld, DynamicObstaclesMove) {
  auto w = build(config("dynamic", 1, 1));
  Vec3 before = Vec3::Zero(), after = Vec3::Zero();
  for (int i = 0; i < w->num_obstacles(0); ++i) before += w->obstacle(0, i).shape.position_w;
  w->obstacle(0, 0).linvel_w = Vec3(1, 0, 0);  // a per-environment obstacle action
  w->step(10);
  for (int i = 0; i < w->num_obstacles(0); ++i) after += w->obstacle(0, i).shape.position_w;
  EXPECT_GT((after - before).norm(), 0.05);
}

TEST(SimWorld, MemoryPerEnvReported) {
  auto w = build(config("env_with_obstacles", 4, 1));
  EXPECT_GT(w->bytes_per_env(), static_cast<std::size_t>(w->obstacle_capacity()) * sizeof(Obstacle));
  EXPECT_LT(w->bytes_per_env(), 64u * 1024u);
}

TEST(SimRegistry, BuiltinsAndUserEntries) {
  Registries r;
  register_builtins(r);
  for (const char* e : {"empty", "env_with_obstacles", "forest", "lidar_navigation", "dynamic"}) EXPECT_TRUE(r.envs.has(e)) << e;
  EXPECT_TRUE(r.sims.has("falling_forwards"));
  EXPECT_TRUE(r.robots.has("base_quadrotor"));
  EXPECT_TRUE(r.controllers.has("lee_position_control"));
  EXPECT_TRUE(r.tasks.has("position_setpoint"));
  EXPECT_TRUE(r.envs.add("my_env", "user env", [] {
    EnvConfig e;
    e.name = "my_env";
    e.num_envs = 3;
    return e;
  }));
  EXPECT_FALSE(r.envs.add("forest", "duplicate", [] { return EnvConfig(); }));
  EnvConfig e;
  ASSERT_TRUE(r.envs.make("my_env", e));
  EXPECT_EQ(e.num_envs, 3);
  EXPECT_FALSE(r.envs.make("nope", e));
  EXPECT_EQ(e.num_envs, 3);
  SimParams s;
  ASSERT_TRUE(r.sims.make("falling_forwards", s));
  EXPECT_GT(s.gravity_w[0], 4.0f);
}

TEST(SimWorld, InvalidConfigIsRejected) {
  WorldConfig c = config("empty", 0, 1);
  std::string err;
  EXPECT_FALSE(World::create(c, err));
  EXPECT_NE(err.find("env.num_envs"), std::string::npos);
}
