// Heap use inside the planar (Box2D) step (Box2D's own allocations go to per-environment arenas
// inside a step: see sim/src/backends/planar.cpp). Box2D lives in a shared library (libbox2d.so), whose
// calls to malloc the linker's --wrap cannot see; this executable defines malloc & co. itself,
// which interposes on every caller in the process (libbox2d.so and libstdc++ included), and
// counts calls on all threads with one atomic counter. The real allocator is glibc's __libc_*.
#include <gtest/gtest.h>

#include "legged_config.hpp"

#include <atomic>
#include <cstdio>
#include <cstdlib>

#include "kestrel/kernel/rng.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/simulator.hpp"

extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
}

namespace {
std::atomic<std::size_t> g_allocations{0};
}

extern "C" {
void* malloc(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(n);
}
void* calloc(std::size_t a, std::size_t b) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_calloc(a, b);
}
void* realloc(void* p, std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_realloc(p, n);
}
void* aligned_alloc(std::size_t a, std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_memalign(a, n);
}
int posix_memalign(void** out, std::size_t a, std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  void* p = __libc_memalign(a, n);
  if (p == nullptr) return 12;  // ENOMEM
  *out = p;
  return 0;
}
}

using namespace kestrel;
using namespace kestrel::sim;

namespace {

std::size_t count_in_steps(bool car, int threads, int warm_steps, int steps, std::size_t* warm_allocs) {
  std::string err;
  WorldConfig cfg;
  EXPECT_TRUE(registries().envs.make("planar_obstacles", cfg.env));
  if (car) {
    EXPECT_TRUE(registries().robots.make("ground_vehicle", cfg.robot));
  }
  cfg.simulator.backend = "planar";
  cfg.simulator.lidar_beams = 64;
  cfg.env.num_envs = 16;
  cfg.env.collision_force_threshold_N = 1;
  cfg.task.episode_len_env_steps = 120;  // many resets (layouts, placements) in the measured window
  cfg.simulator.added_mass_max_kg = 0.5_r;
  cfg.num_threads = threads;
  std::unique_ptr<Simulator> sim = make_simulator(cfg, err);
  EXPECT_TRUE(sim) << err;
  if (!sim) return 1;
  std::vector<real> a(static_cast<std::size_t>(sim->num_robots() * sim->action_dim()));
  const std::size_t w0 = g_allocations.load();
  for (int s = 0; s < warm_steps; ++s) {
    scripted_setpoint_actions(*sim, a.data());
    sim->step(a.data());
  }
  *warm_allocs = g_allocations.load() - w0;
  const int ids[3] = {0, 5, 11};
  const std::size_t before = g_allocations.load();
  for (int s = 0; s < steps; ++s) {
    scripted_setpoint_actions(*sim, a.data());
    sim->step(a.data());
    if (s % 50 == 0) sim->push_robots();
    if (s % 77 == 0) sim->reset_idx(ids, 3);
  }
  const std::size_t n = g_allocations.load() - before;
  EXPECT_GT(sim->summary().episodes_done, 16u);
  EXPECT_EQ(sim->step_heap_fallbacks(), 0u);  // Box2D's in-step growth fit the per-env arenas
  return n;
}

}  // namespace

TEST(PlanarHeap, CounterSeesBox2DAllocations) {
  // The interposed malloc sees Box2D's own allocations: building a world allocates.
  const std::size_t before = g_allocations.load();
  std::string err;
  WorldConfig cfg;
  cfg.simulator.backend = "planar";
  cfg.env.num_envs = 1;
  std::unique_ptr<Simulator> sim = make_simulator(cfg, err);
  ASSERT_TRUE(sim) << err;
  EXPECT_GT(g_allocations.load() - before, 0u);
}

TEST(PlanarHeap, NoAllocationInStepAfterWarmUp) {
  for (int car = 0; car < 2; ++car) {
    for (int threads = 1; threads <= 2; ++threads) {
      std::size_t warm = 0;
      const std::size_t n = count_in_steps(car != 0, threads, 300, 2000, &warm);
      std::printf("planar %s, %d thread(s): %zu allocations in the first 300 steps, %zu in the next 2000 "
                  "(with resets, pushes, reset_idx)\n",
                  car ? "ground vehicle" : "multirotor", threads, warm, n);
      EXPECT_EQ(n, 0u) << (car ? "ground vehicle" : "multirotor") << ", threads " << threads;
    }
  }
}

TEST(ArticulatedHeap, NoAllocationInStepsResetsAndPushes) {
  // Articulated robots (sim/src/backends/articulated.cpp): every array is sized at set-up, so not
  // even the first step allocates; measured over steps with random joint targets, auto-resets
  // (short episodes), reset_idx, reset_dofs, push_robots and push_links, with every randomisation
  // of simulator.* on, on 1 and 2 threads.
  for (int threads = 1; threads <= 2; ++threads) {
    std::string err;
    WorldConfig cfg;
    ASSERT_TRUE(registries().robots.make("go2", cfg.robot));
    ASSERT_TRUE(registries().sims.make("fast_sim", cfg.sim));
    ASSERT_TRUE(registries().tasks.make("joint_targets", cfg.task));
    cfg.task.episode_len_env_steps = 30;
    cfg.env.num_envs = 4;
    cfg.env.num_physics_steps_per_env_step_mean = 4;
    cfg.num_threads = threads;
    // Every randomisation on, so that their draws and the per-environment model are in the count.
    kestrel::test::randomise_all_articulated(cfg);
    std::unique_ptr<Simulator> sim = make_simulator(cfg, err);
    ASSERT_TRUE(sim) << err;
    std::vector<real> a(static_cast<std::size_t>(sim->num_robots() * sim->action_dim()));
    std::vector<real> dp(static_cast<std::size_t>(sim->num_dofs()), 0.1_r), dv(dp.size(), 0);
    RngStream rng(3, 0, kPurposeUser + 41);
    const int ids[2] = {1, 3};
    const std::size_t before = g_allocations.load();
    for (int s = 0; s < 200; ++s) {
      for (real& v : a) v = rng.uniform(-1, 1);
      sim->step(a.data());
      if (s % 40 == 0) sim->push_robots();
      if (s % 30 == 0) {
        EXPECT_TRUE(sim->push_links());
      }
      if (s % 55 == 0) sim->reset_idx(ids, 2);
      if (s % 70 == 0) {
        EXPECT_TRUE(sim->reset_dofs(ids, 1, dp.data(), dv.data()));
      }
    }
    const std::size_t n = g_allocations.load() - before;
    EXPECT_GT(sim->summary().episodes_done, 8u);
    EXPECT_EQ(n, 0u) << "threads " << threads;
  }
}
