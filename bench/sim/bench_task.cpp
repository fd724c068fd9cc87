// Task throughput: Task::step (actions in, reward, flags, observations out, auto-reset) on each
// backend, in ns per env-step (one task step of one environment), best of `reps` runs. The
// figure a learner's rollout sees; bench_sim measures the World alone. Timings are reported,
// never asserted (the smoke test only checks that it runs).
//
//   kestrel_bench_task [--quick] [--reps N] [--only SUBSTRING]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "kestrel/kernel/rng.hpp"
#include "kestrel/sim/progress.hpp"
#include "kestrel/sim/scenario.hpp"
#include "kestrel/sim/simulator.hpp"
#include "kestrel/sim/task.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {

struct Case {
  const char* task;
  const char* controller;
  Backend backend;
  int envs;
  int steps;
};

double run_case(const Case& c, int threads, int reps, bool quick, bool quiet) {
  WorldConfig cfg;
  std::string err;
  std::string yaml = std::string("task: ") + c.task + "\n";
  if (c.controller[0] != '\0') yaml += std::string("controller: ") + c.controller + "\n";
  if (!load_scenario_string(yaml, "<bench_task>", cfg, err)) {
    std::fprintf(stderr, "bench_task: %s\n", err.c_str());
    return -1;
  }
  cfg.env.num_envs = quick ? 8 : c.envs;
  cfg.num_threads = threads;
  cfg.seed = 3;
  std::unique_ptr<Task> t = make_task(cfg, c.backend, err);
  if (!t) {
    std::fprintf(stderr, "bench_task: %s\n", err.c_str());
    return -1;
  }
  const int steps = quick ? 5 : c.steps;
  std::vector<float> a(static_cast<std::size_t>(t->num_envs() * t->action_dim()), 0.0f);
  RngStream rng(1, 0, kPurposeUser);
  for (float& x : a) x = static_cast<float>(rng.uniform(-0.5_r, 0.5_r));
  double best = 1e30;
  // This case's progress (issue 15), between reps and outside the timing; erased before its row.
  ProgressLine progress(stderr, ProgressLine::enabled_for(quiet), static_cast<double>(reps) * steps * t->num_envs());
  for (int r = 0; r < reps; ++r) {
    progress.update(static_cast<double>(r) * steps * t->num_envs());
    const auto t0 = std::chrono::steady_clock::now();
    for (int s = 0; s < steps; ++s) t->step(a.data());
    const double ns = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count();
    best = std::min(best, ns / (static_cast<double>(steps) * t->num_envs()));
  }
  progress.clear();
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, quiet = false;
  int reps = 3;
  const char* only = nullptr;  // run the cases whose "task,controller,backend" contains this
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) quick = true;
    else if (std::strcmp(argv[i], "--quiet") == 0) quiet = true;
    else if (std::strcmp(argv[i], "--reps") == 0 && i + 1 < argc) reps = std::max(1, std::atoi(argv[++i]));
    else if (std::strcmp(argv[i], "--only") == 0 && i + 1 < argc) only = argv[++i];
    else {
      std::fprintf(stderr, "usage: kestrel_bench_task [--quick] [--reps N] [--only SUBSTRING] [--quiet]\n");
      return 2;
    }
  }
  const Case cases[] = {
      {"position_setpoint_task", "lee_position_control", Backend::rigid, 4096, 200},
      {"position_setpoint_task", "lee_attitude_control", Backend::rigid, 4096, 200},
      {"navigation_task", "", Backend::rigid, 1024, 200},
      {"goal_box_through_gap", "", Backend::rigid, 1024, 200},
      {"position_setpoint_task", "lee_position_control", Backend::planar, 256, 100},
      {"navigation_task", "", Backend::planar, 256, 100},
  };
  std::printf("task,controller,backend,envs,threads,ns_per_env_step\n");
  for (const Case& c : cases)
    for (int threads : {1, 2}) {
      const std::string id = std::string(c.task) + "," + c.controller + "," + backend_name(c.backend);
      if (only != nullptr && id.find(only) == std::string::npos) continue;
      const double ns = run_case(c, threads, quick ? 1 : reps, quick, quiet);
      if (ns < 0) return 1;
      std::printf("%s,%s,%s,%d,%d,%.1f\n", c.task, c.controller, backend_name(c.backend), quick ? 8 : c.envs, threads, ns);
      std::fflush(stdout);
    }
  return 0;
}
