// No heap inside World::step on the multi-threaded path. tests/support/heap_counter counts per
// thread (thread_local), which sees only the calling thread; the pool's workers run most of the
// step. This executable replaces the allocation functions with a process-wide atomic counter
// instead, so an allocation on any thread (workers included) between the two reads is caught.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/world.hpp"

namespace {
std::atomic<std::size_t> g_allocations{0};
void* counted(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  void* p = std::malloc(n == 0 ? 1 : n);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void* counted_aligned(std::size_t n, std::size_t a) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  void* p = nullptr;
  if (posix_memalign(&p, a < sizeof(void*) ? sizeof(void*) : a, n == 0 ? 1 : n) != 0) throw std::bad_alloc();
  return p;
}
}  // namespace

// malloc/calloc/realloc are wrapped by the linker (--wrap, see tests/sim/CMakeLists.txt).
extern "C" {
void* __real_malloc(std::size_t);
void* __real_calloc(std::size_t, std::size_t);
void* __real_realloc(void*, std::size_t);
void* __wrap_malloc(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __real_malloc(n);
}
void* __wrap_calloc(std::size_t a, std::size_t b) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __real_calloc(a, b);
}
void* __wrap_realloc(void* p, std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __real_realloc(p, n);
}
}

void* operator new(std::size_t n) { return counted(n); }
void* operator new[](std::size_t n) { return counted(n); }
void* operator new(std::size_t n, std::align_val_t a) { return counted_aligned(n, static_cast<std::size_t>(a)); }
void* operator new[](std::size_t n, std::align_val_t a) { return counted_aligned(n, static_cast<std::size_t>(a)); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

using namespace kestrel;
using namespace kestrel::sim;

TEST(SimWorldMultiThread, CounterSeesWorkerThreadAllocations) {
  // The counter itself must see an allocation made on another thread.
  const std::size_t before = g_allocations.load();
  std::thread t([] { delete new int(3); });
  t.join();
  EXPECT_GT(g_allocations.load(), before);
}

TEST(SimWorldMultiThread, NoHeapInsideStepOnAnyThread) {
  for (const char* env : {"empty", "env_with_obstacles", "forest", "dynamic"}) {
    for (int threads : {2, 4}) {
      WorldConfig c;
      ASSERT_TRUE(registries().envs.make(env, c.env));
      c.env.num_envs = 37;  // uneven slices
      c.num_threads = threads;
      c.seed = 5;
      c.env.enable_disturbance = true;
      c.env.perturb_observations = true;
      c.env.sample_timestep_for_latency = true;
      c.robot.robots_per_env = 2;
      c.task.setpoint_speed_m_s = 2;
      c.task.episode_len_env_steps = 150;  // several resets (new layouts) inside the counted steps
      std::string err;
      auto w = World::create(c, err);
      ASSERT_TRUE(w) << err;
      w->enable_trace(4, 1000);
      w->step(1);  // workers have run once (thread start-up is set-up)
      const std::size_t before = g_allocations.load();
      w->step(400);
      for (int i = 0; i < 50; ++i) w->step(1);  // many pool hand-offs
      EXPECT_EQ(g_allocations.load() - before, 0u) << env << " threads " << threads;
      EXPECT_GT(w->summary().resets, 0u) << env;
    }
  }
}

TEST(SimWorldMultiThread, NoHeapInsideStepWithSensorsOnAnyThread) {
  // A depth camera, a ToF and an IMU on two robots per env: scenes rebuilt and images rendered
  // on the workers, resets re-drawing mounts, all without the heap.
  for (const char* env : {"forest", "dynamic"}) {
    WorldConfig c;
    ASSERT_TRUE(registries().envs.make(env, c.env));
    c.env.num_envs = 9;
    c.num_threads = 2;
    c.seed = 5;
    c.robot.robots_per_env = 2;
    c.task.episode_len_env_steps = 40;
    for (const char* s : {"base_depth_camera", "vl53l5cx", "bmi088"}) {
      SensorConfig sc;
      ASSERT_TRUE(registries().sensors.make(s, sc));
      c.robot.sensors.push_back(sc);
    }
    std::string err;
    auto w = World::create(c, err);
    ASSERT_TRUE(w) << err;
    w->step(1);
    const std::size_t before = g_allocations.load();
    w->step(60);
    EXPECT_EQ(g_allocations.load() - before, 0u) << env;
    EXPECT_GT(w->summary().resets, 0u) << env;
  }
}
