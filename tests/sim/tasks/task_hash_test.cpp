// Frozen results of every task on every backend that carries it: observations, rewards,
// terminations, truncations and the simulator's state hash over 300 steps of a fixed action
// sequence (a deterministic mix of the task's scripted policy and pseudo-random actions), hashed
// with FNV-1a. The constants were taken before the tasks moved onto the Simulator interface
// (issue 10) and hold bit for bit after it: a task is written once and runs on each backend with
// the results it had when it was written per backend.
//
// To regenerate after an intended change of results: run this test, read the printed hashes,
// replace the constants in one commit and say why in its message.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "kestrel/kernel/rng.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/scenario.hpp"
#include "kestrel/sim/simulator.hpp"
#include "kestrel/sim/task.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {

struct Fnv {
  std::uint64_t h = 1469598103934665603ull;
  void add(const void* p, std::size_t n) {
    const unsigned char* b = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  }
};

WorldConfig task_config(const std::string& task, const std::string& controller, int envs) {
  WorldConfig c;
  std::string err;
  std::string yaml = "task: " + task + "\n";
  if (!controller.empty()) yaml += "controller: " + controller + "\n";
  EXPECT_TRUE(load_scenario_string(yaml, "<task hash test>", c, err)) << err;
  c.env.num_envs = envs;
  c.num_threads = 2;
  c.seed = 11;
  return c;
}

std::uint64_t run_hash(const WorldConfig& c, Backend b, int steps) {
  std::string err;
  std::unique_ptr<Task> t = make_task(c, b, err);
  EXPECT_TRUE(t) << err;
  if (!t) return 0;
  t->set_keep_final_observations(true);
  const int n = t->num_envs(), ad = t->action_dim(), od = t->obs_dim();
  std::vector<float> a(static_cast<std::size_t>(n * ad), 0.0f);
  RngStream rng(5, 0, kPurposeUser);
  Fnv f;
  f.add(t->observations(), sizeof(float) * static_cast<std::size_t>(n * od));
  for (int s = 0; s < steps; ++s) {
    const bool scripted = (s / 25) % 2 == 0 && t->scripted_actions(a.data());
    if (!scripted)
      for (float& x : a) x = static_cast<float>(rng.uniform(-1, 1));
    t->step(a.data());
    f.add(t->observations(), sizeof(float) * static_cast<std::size_t>(n * od));
    f.add(t->final_observations(), sizeof(float) * static_cast<std::size_t>(n * od));
    f.add(t->rewards(), sizeof(float) * static_cast<std::size_t>(n));
    f.add(t->terminations(), static_cast<std::size_t>(n));
    f.add(t->truncations(), static_cast<std::size_t>(n));
  }
  const std::uint64_t sh = t->state_hash();
  f.add(&sh, sizeof sh);
  const TaskInfos& in = t->infos();
  f.add(&in.episodes, sizeof in.episodes);
  f.add(&in.successes, sizeof in.successes);
  f.add(&in.crashes, sizeof in.crashes);
  return f.h;
}

struct Case {
  const char* task;
  const char* controller;
  Backend backend;
  std::uint64_t frozen;
};

}  // namespace

TEST(TaskHashes, FrozenOnEveryBackend) {
  const Case cases[] = {
      {"position_setpoint_task", "lee_position_control", Backend::rigid, 8391189067952894450ull},
      {"position_setpoint_task", "lee_attitude_control", Backend::rigid, 9600798817189083350ull},
      {"position_setpoint_task", "lee_velocity_control", Backend::rigid, 7170106308769359274ull},  // re-frozen (these five): the reward reads |world-frame error|
      {"position_setpoint_task", "lee_position_control", Backend::planar, 257101743332984947ull},
      {"position_setpoint_task", "lee_velocity_control", Backend::planar, 2215116553741921012ull},
      {"navigation_task", "", Backend::rigid, 10602241566285191750ull},  // re-frozen: the reference's start (yaw, velocities)
      {"navigation_task", "", Backend::planar, 17525082069354197038ull},  // re-frozen: the reference's start (see git log)
      {"goal_box_through_gap", "", Backend::rigid, 5311961127904642832ull},
      {"goal_box_through_gap", "", Backend::planar, 11363323505176394179ull},
  };
  for (const Case& k : cases) {
    const std::uint64_t h = run_hash(task_config(k.task, k.controller, 12), k.backend, 300);
    std::printf("    {\"%s\", \"%s\", Backend::%s, %lluull},\n", k.task, k.controller, backend_name(k.backend),
                static_cast<unsigned long long>(h));
    EXPECT_EQ(h, k.frozen) << k.task << " " << k.controller << " on " << backend_name(k.backend);
  }
}
