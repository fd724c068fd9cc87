// kestrel: the desktop harness's command line.
//   kestrel run [SCENARIO] --envs N --steps S --threads T --seed X --out DIR [--image-env E] [--max-memory-gib G]
//   Every run (scenario, --task, either backend) writes to DIR (default kestrel_out): summary.txt
//   (the printed summary) and trajectory.csv (the first 6 environments' robot 0 per env-step); on
//   the rigid simulator also envs.csv (per-environment final state, counters and bounds),
//   obstacles.csv (the traced environments' last obstacle layouts) and, with sensors in the
//   scenario, env E's sensor images: sensor_<name>_*.png (libpng). The plots are matplotlib's,
//   drawn from these CSVs by the Python package (`kestrel run` through the console script, or
//   `kestrel plot DIR`: python/kestrel/plots.py); this program cannot import matplotlib.
//   On a terminal, a progress line on stderr (env-steps, rate, time left) unless --quiet.
//   kestrel list
// With no scenario, `run` uses the embedded default (1024 quadrotors, position setpoints, forest).
#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <thread>
#include <vector>

#include "kestrel/sim/batch_step.hpp"
#include "kestrel/sim/limits.hpp"
#include "kestrel/sim/output.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/rigid_backend.hpp"
#include "kestrel/sim/robot_model.hpp"
#include "kestrel/sim/schema.hpp"
#include "kestrel/sim/scenario.hpp"
#include "kestrel/sim/simulator.hpp"
#include "kestrel/sim/task.hpp"
#include "kestrel/sim/world.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {

// What `run` is working on (the scenario file, --task ID or the embedded default), for main()'s
// last-resort error messages.
std::string g_label = "kestrel";

int usage() {
  std::fprintf(stderr,
               "usage: kestrel run [SCENARIO.yaml] [--envs N] [--steps S] [--threads T] [--seed X] [--out DIR] [--image-env E] [--quiet]\n"
               "                   [--task ID] [--policy scripted|zero] [--max-memory-gib G]\n"
               "         --out DIR (default kestrel_out), every run: summary.txt, trajectory.csv; rigid simulator also\n"
               "                   envs.csv, obstacles.csv and env E's sensor images (sensor_<name>_*.png); plots:\n"
               "                   `kestrel plot DIR` (the Python package; its `kestrel run` plots by itself)\n"
               "         --quiet   no progress line (it is shown only when stderr is a terminal)\n"
               "       kestrel list\n"
               "       kestrel schema      (the scenario reference: every key, unit, range and default)\n");
  return 2;
}

template <class T>
void list_one(const char* title, const Registry<T>& r) {
  std::printf("%s:\n", title);
  if (r.names().empty()) std::printf("  (none registered)\n");
  for (const auto& n : r.names()) std::printf("  %-36s %s\n", n.c_str(), r.description(n).c_str());
}

bool parse_long(const char* s, long long lo, long long hi, long long& out) {
  char* end = nullptr;
  out = std::strtoll(s, &end, 10);
  return end != s && *end == '\0' && out >= lo && out <= hi;
}

// An RL task (sim/task.hpp) runs through its step() under the task's built-in scripted
// controller (position_setpoint_task: fly to the target; navigation_task: velocity towards the
// goal, dodging what its pooled image sees; goal_box_through_gap: waypoints through the gap) or
// zero actions; the summary reports the episodes, their terminations, the success rate, the mean
// episode reward and the reward trend (mean step reward over the first and the last quarter).
int run_task(const WorldConfig& cfg, Backend backend, const std::string& label, long long steps, bool scripted,
             const std::string& out_dir, long long image_env, bool quiet) {
  std::string err;
  std::unique_ptr<Task> task = make_task(cfg, backend, err);
  if (!task) {
    std::fprintf(stderr, "kestrel: %s: %s\n", label.c_str(), err.c_str());
    return 1;
  }
  const int n = task->num_envs(), od = task->obs_dim(), ad = task->action_dim();
  std::vector<float> actions(static_cast<std::size_t>(n) * static_cast<std::size_t>(ad), 0.0f);
  if (scripted && !task->scripted_actions(actions.data())) {
    std::fprintf(stderr, "kestrel: %s: task %s has no scripted controller for controller %s; use --policy zero\n",
                 label.c_str(), task->name(), cfg.controller.name.c_str());
    return 1;
  }
  World* world = rigid_world(task->simulator());  // nullptr on planar
  if (world != nullptr) world->enable_trace(6, static_cast<int>(std::min<long long>(steps, 0x7fffffff)));
  // Trajectory of robot 0 of the first environments (x, y, z per task step), on every backend.
  const Simulator& sim = task->simulator();
  const int trace_envs = std::min(6, n);
  std::vector<real> trace(static_cast<std::size_t>(trace_envs) * static_cast<std::size_t>(steps) * 3, 0);
  RunReport rep;
  rep.say("kestrel run: %s\n", label.c_str());
  rep.say("  task %s: %d envs x (%d obs, %d actions), simulator %s, controller %s, env %s, threads %d, seed %" PRIu64
          ", steps %lld, policy %s\n", task->name(), n, od, ad, task->backend_name(), task->simulator().controller_name(),
          cfg.env.name.c_str(), task->num_threads(), cfg.seed, steps, scripted ? "scripted" : "zero");
  if (std::string(task->name()) == "so101_pick_place")
    rep.say("  scene: SO-101 arm (models/so101/so101.xml), %.0f mm cube, box; actions %s; scripted policy: ScriptedPickPlace "
            "(DLS IK pick and place)\n", static_cast<double>(2000 * cfg.task.pick_place.cube_half_m),
            cfg.task.pick_place.action_mode == PickPlaceActionMode::ee_delta ? "ee_delta" : "joint_position");
  else if (cfg.robot.kind == robots::RobotKind::articulated)
    rep.say("  robot: %s (%s), %d joints, %d feet; scripted policy: every joint held at home\n", cfg.robot.name.c_str(),
            cfg.robot.model_file.c_str(), task->simulator().num_dofs(), task->simulator().num_feet());
  else
    rep.say("  robot flown: %s\n", describe_robot(cfg).c_str());  // mass, inertia, rotors, max thrust, T/W
  double reward_sum = 0, first_quarter = 0, last_quarter = 0;
  const long long quarter = std::max(1LL, steps / 4);
  ProgressLine progress(stderr, !quiet && ProgressLine::stderr_is_terminal(), static_cast<double>(steps) * n);
  const auto t0 = std::chrono::steady_clock::now();
  for (long long s = 0; s < steps; ++s) {
    if (scripted) (void)task->scripted_actions(actions.data());
    task->step(actions.data());
    double r = 0;
    for (int e = 0; e < n; ++e) r += static_cast<double>(task->rewards()[e]);
    reward_sum += r;
    if (s < quarter) first_quarter += r;
    if (s >= steps - quarter) last_quarter += r;
    for (int e = 0; e < trace_envs; ++e) {
      const std::size_t i = static_cast<std::size_t>(e) * static_cast<std::size_t>(sim.robots_per_env());
      real* t = &trace[(static_cast<std::size_t>(e) * static_cast<std::size_t>(steps) + static_cast<std::size_t>(s)) * 3];
      for (int k = 0; k < 3; ++k) t[k] = sim.base_pos_w()[3 * i + static_cast<std::size_t>(k)];
    }
    progress.update(static_cast<double>(s + 1) * n);
  }
  progress.finish();
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const TaskInfos& in = task->infos();
  std::printf("  wall time %.3f s, %.3g env-steps/s\n", secs, static_cast<double>(steps) * n / secs);  // not in summary.txt: varies
  rep.say("  episodes %" PRIu64 " (terminated %" PRIu64 ", truncated %" PRIu64 "), mean episode reward %.3f, "
          "mean step reward %.4f\n", in.episodes, in.terminations, in.truncations, in.mean_episode_reward(),
          reward_sum / (static_cast<double>(steps) * n));
  rep.say("  terminations: crashes %" PRIu64 ", successes %" PRIu64 "; %s\n", in.crashes, in.successes,
          success_rate_text(in.episodes, in.fallback_episodes, in.successes).c_str());
  const WorldSummary ss = sim.summary();
  const std::string fb = placement_fallback_text(
      cfg.env.name, ss.placement_fallbacks, ss.placements,
      world != nullptr ? static_cast<double>(world->model().robot_bound_radius_m + cfg.task.clearance_m) : -1.0, cfg.task.line_of_sight);
  if (!fb.empty()) rep.say("  %s\n", fb.c_str());
  rep.say("  reward trend: mean step reward %.4f over the first quarter -> %.4f over the last quarter (%s)\n",
          first_quarter / (static_cast<double>(quarter) * n), last_quarter / (static_cast<double>(quarter) * n),
          // A change under 0.1 % of the first quarter's magnitude (or 1e-3 per step) is called flat.
          std::fabs(last_quarter - first_quarter) <= 1e-3 * std::max(std::fabs(first_quarter), static_cast<double>(quarter) * n)
              ? "flat"
              : last_quarter > first_quarter ? "rising" : "falling");
  if (std::string(task->name()) == "navigation_task")
    rep.say("  curriculum level %d (%" PRIu64 " changes)\n", in.curriculum_level, in.curriculum_changes);
  // --out: the same files as a scripted run of the same backend (see the usage).
  ::mkdir(out_dir.c_str(), 0755);
  std::vector<std::string> wrote;
  const std::string tpath = out_dir + "/trajectory.csv";
  if (world != nullptr) {
    if (!write_trajectory_csv(*world, tpath, err) || !write_env_csv(*world, out_dir + "/envs.csv", err) ||
        !write_obstacles_csv(*world, world->trace_envs(), out_dir + "/obstacles.csv", err) ||
        (world->num_sensors() > 0 && !write_sensor_pngs(*world, static_cast<int>(std::min<long long>(image_env, n - 1)), out_dir, wrote, err))) {
      std::fprintf(stderr, "kestrel: %s\n", err.c_str());
      return 1;
    }
    wrote.insert(wrote.begin(), {tpath, out_dir + "/envs.csv", out_dir + "/obstacles.csv"});
  } else {
    if (!write_trace_csv(tpath, "x_m,y_m,z_m", trace.data(), trace_envs, steps, err)) {
      std::fprintf(stderr, "kestrel: %s\n", err.c_str());
      return 1;
    }
    wrote.insert(wrote.begin(), tpath);
  }
  for (const std::string& p : wrote) std::printf("  wrote %s\n", p.c_str());
  print_plot_hint(out_dir);
  if (!rep.finish(out_dir, task->state_hash(), err)) {
    std::fprintf(stderr, "kestrel: %s\n", err.c_str());
    return 1;
  }
  return 0;
}

// `kestrel run`'s options.
struct RunArgs {
  std::string scenario, out_dir = "kestrel_out", task_id;
  long long envs = -1, steps = 1000, threads = -1, seed = -1, image_env = 0;
  double max_memory_gib = -1;
  bool quiet = false, scripted = true;
};

constexpr long long kNoMax = 0x7fffffffffffffffLL;

/// argv[2..] into `r`; false with the exit code in `code` (2: a bad option, after its message).
bool parse_run_args(int argc, char** argv, RunArgs& r, int& code) {
  code = 2;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](long long lo, long long hi, long long& v) {
      if (i + 1 >= argc || !parse_long(argv[i + 1], lo, hi, v)) {
        if (hi == kNoMax) std::fprintf(stderr, "kestrel run: %s expects an integer >= %lld\n", a.c_str(), lo);
        else std::fprintf(stderr, "kestrel run: %s expects an integer in [%lld, %lld]\n", a.c_str(), lo, hi);
        std::exit(2);
      }
      ++i;
    };
    if (a == "--envs") value(1, kMaxNumEnvs, r.envs);
    else if (a == "--steps") value(1, kNoMax, r.steps);
    else if (a == "--threads") value(1, kMaxThreads, r.threads);
    else if (a == "--seed") value(0, kNoMax, r.seed);
    else if (a == "--image-env") value(0, kMaxNumEnvs - 1, r.image_env);
    else if (a == "--max-memory-gib") {
      char* end = nullptr;
      r.max_memory_gib = i + 1 < argc ? std::strtod(argv[i + 1], &end) : -1;
      if (i + 1 >= argc || end == argv[i + 1] || *end != '\0' || !(r.max_memory_gib > 0) || !(r.max_memory_gib <= kMaxMemoryGiBSetting)) {
        std::fprintf(stderr, "kestrel run: --max-memory-gib expects a number in (0, %.0f] (GiB)\n", kMaxMemoryGiBSetting);
        return false;
      }
      ++i;
    }
    else if (a == "--out" && i + 1 < argc) r.out_dir = argv[++i];
    else if (a == "--quiet") r.quiet = true;
    else if (a == "--task" && i + 1 < argc) r.task_id = argv[++i];
    else if (a == "--policy" && i + 1 < argc) {
      const std::string p = argv[++i];
      if (p != "scripted" && p != "zero") {
        std::fprintf(stderr, "kestrel run: --policy expects scripted or zero, got \"%s\"\n", p.c_str());
        return false;
      }
      r.scripted = p == "scripted";
    }
    else if (!a.empty() && a[0] != '-' && r.scenario.empty()) r.scenario = a;
    else {
      code = usage();
      return false;
    }
  }
  return true;
}

/// The scenario (file, --task's own scene or the embedded default) with the options applied;
/// false after printing the error. `label` names what runs, for messages.
bool load_run_config(const RunArgs& r, WorldConfig& cfg, std::string& label) {
  std::string err;
  if (!r.task_id.empty() && !is_rl_task(r.task_id) && !registries().tasks.has(r.task_id)) {
    std::fprintf(stderr, "kestrel: --task: unknown task \"%s\"; registered task ids: %s\n", r.task_id.c_str(),
                 rl_task_ids_joined().c_str());
    return false;
  }
  // --task alone: the task's own scene (as a scenario `task: ID` with no other section); with a
  // scenario: the scenario's scene with its task replaced.
  label = !r.scenario.empty() ? r.scenario : !r.task_id.empty() ? "--task " + r.task_id : "<embedded default>";
  g_label = label;  // main()'s last-resort messages, from here on
  const bool ok = !r.scenario.empty()    ? load_scenario_file(r.scenario, cfg, err)
                  : !r.task_id.empty() ? load_scenario_string("task: " + r.task_id + "\n", label, cfg, err)
                                       : load_scenario_string(default_scenario_yaml(), label, cfg, err);
  if (!ok) {
    std::fprintf(stderr, "kestrel: %s\n", err.c_str());
    return false;
  }
  if (!r.task_id.empty() && !r.scenario.empty() && !registries().tasks.make(r.task_id, cfg.task)) return false;
  if (r.envs > 0) cfg.env.num_envs = static_cast<int>(r.envs);
  if (r.seed >= 0) cfg.seed = static_cast<std::uint64_t>(r.seed);
  // Default: every hardware thread, within kMaxThreads.
  cfg.num_threads = r.threads > 0 ? static_cast<int>(r.threads)
                                : static_cast<int>(std::min<unsigned>(kMaxThreads, std::max(1u, std::thread::hardware_concurrency())));
  if (r.max_memory_gib > 0) cfg.max_memory_gib = r.max_memory_gib;
  return true;
}

/// A scripted run of the rigid World: the header, the steps (a progress bar on long runs), the
/// summary, the trajectory files and sensor images, the state hash.
int run_world(const WorldConfig& cfg, const RunArgs& r, const std::string& label) {
  std::string err;
  std::unique_ptr<World> world = World::create(cfg, err);
  if (!world) {
    std::fprintf(stderr, "kestrel: %s: %s\n", label.c_str(), err.c_str());
    return 1;
  }
  world->enable_trace(6, static_cast<int>(r.steps));
  RunReport rep;
  rep.say("kestrel run: %s\n", label.c_str());
  rep.say("  sim %s (dt %.4g s), env %s, robot %s x%d, controller %s, task %s\n", cfg.sim.name.c_str(),
              static_cast<double>(cfg.sim.dt_s), cfg.env.name.c_str(), cfg.robot.name.c_str(), cfg.robot.robots_per_env,
              cfg.controller.name.c_str(), cfg.task.name.c_str());
  rep.say("  robot flown: %s\n", describe_robot(cfg).c_str());  // mass, inertia, rotors, max thrust, T/W
  rep.say("  envs %d, obstacles/env <= %d, threads %d, seed %" PRIu64 ", steps %lld\n", world->num_envs(),
              world->obstacle_capacity(), world->num_threads(), cfg.seed, r.steps);
  for (int k = 0; k < world->num_sensors(); ++k) {
    const SensorConfig& sc = world->sensor_config(k);
    if (sc.kind == SensorKind::imu) rep.say("  sensor %s: IMU, every physics step\n", sc.name.c_str());
    else rep.say("  sensor %s: %s %d x %d, every %d env-step(s)\n", sc.name.c_str(), sc.kind == SensorKind::camera ? "camera" : "lidar",
                     world->sensor_height(k), world->sensor_width(k), sc.every_env_steps);
  }
  rep.say("  robot step: %s\n", world->batched() ? (std::string("batched, ") + batch::kernel_name()).c_str() : "scalar (one robot at a time)");
  rep.say("  memory: %zu bytes per env (%.1f MiB total)\n", world->bytes_per_env(),
              static_cast<double>(world->bytes_per_env()) * world->num_envs() / (1024.0 * 1024.0));
  // Progress line on a terminal (stderr, so the summary on stdout stays clean to compare). The
  // steps go in chunks that start at about 8 M env-steps and double while a World::step call takes
  // under 0.1 s, so the line moves at least every second or so at 10 M env-steps/s, while each
  // call gives every worker enough to do that waking the pool's threads costs little (64k-env-step
  // chunks were 16 env-steps at 4,096 environments: ~0.25 ms per thread at 16 threads), and the
  // fused env-steps (World::set_fused) load and store a robot once per call (fixed 8 M env-step
  // chunks were 8 env-steps at 1 M environments: each robot's ~1 KB read and written every 8, which
  // took memory bandwidth the 16 cores share). Chunking does not change the result (a step is the
  // same however it is batched: tests/sim/engine/world_test.cpp, batch_step_test.cpp).
  const double total = static_cast<double>(r.steps) * world->num_envs();
  ProgressLine progress(stderr, !r.quiet && ProgressLine::stderr_is_terminal(), total);
  // (Starting at 1 M env-steps, a 1-thread run of 1 M environments stayed at one env-step per call,
  // each 0.2 s, memory-bound at 5 M env-steps/s against 20 M with 8.)
  long long chunk = std::max(1LL, std::min(r.steps, (1LL << 23) / world->num_envs()));
  constexpr long long kMaxChunk = 1LL << 30;  // env-steps per call (World::step takes an int count)
  const auto t0 = std::chrono::steady_clock::now();
  for (long long done = 0; done < r.steps;) {
    const long long n = std::min(chunk, r.steps - done);
    const auto c0 = std::chrono::steady_clock::now();
    world->step(static_cast<int>(n));
    done += n;
    progress.update(static_cast<double>(done) * world->num_envs());
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - c0).count() < 0.1 &&
        chunk * 2 * world->num_envs() <= kMaxChunk)
      chunk *= 2;
  }
  progress.finish();
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const WorldSummary s = world->summary();
  std::printf("  wall time %.3f s, %.3g env-steps/s\n", secs, static_cast<double>(s.env_steps) / secs);
  report_episodes(rep, s, cfg.task.success_radius_m);
  rep.say("  tracking error (|setpoint - position|): mean %.3f m; distance to target at episode end %.3f m; "
          "final mean distance to target %.3f m\n",
          s.mean_tracking_error_m, s.episode_end_distance_m, s.final_mean_distance_m);
  const std::string fb = placement_fallback_text(
      cfg.env.name, s.placement_fallbacks,
      s.placements,
      static_cast<double>(world->model().robot_bound_radius_m + cfg.task.clearance_m), cfg.task.line_of_sight);
  if (!fb.empty()) rep.say("  %s\n", fb.c_str());
  const std::string& out_dir = r.out_dir;
  ::mkdir(out_dir.c_str(), 0755);
  if (!write_trajectory_csv(*world, out_dir + "/trajectory.csv", err) || !write_env_csv(*world, out_dir + "/envs.csv", err) ||
      !write_obstacles_csv(*world, world->trace_envs(), out_dir + "/obstacles.csv", err)) {
    std::fprintf(stderr, "kestrel: %s\n", err.c_str());
    return 1;
  }
  std::printf("  wrote %s/trajectory.csv, %s/envs.csv, %s/obstacles.csv\n", out_dir.c_str(), out_dir.c_str(), out_dir.c_str());
  if (world->num_sensors() > 0) {
    std::vector<std::string> images;
    if (!write_sensor_pngs(*world, static_cast<int>(r.image_env), out_dir, images, err)) {
      std::fprintf(stderr, "kestrel: %s\n", err.c_str());
      return 1;
    }
    for (const std::string& p : images) std::printf("  wrote %s (env %lld)\n", p.c_str(), r.image_env);
  }
  print_plot_hint(out_dir);
  if (!rep.finish(out_dir, world->state_hash(), err)) {
    std::fprintf(stderr, "kestrel: %s\n", err.c_str());
    return 1;
  }
  return 0;
}

int run(int argc, char** argv) {
  RunArgs r;
  int code = 0;
  if (!parse_run_args(argc, argv, r, code)) return code;
  WorldConfig cfg;
  std::string label;
  if (!load_run_config(r, cfg, label)) return 1;
  std::string err;
  // Physics backend (sim/simulator.hpp): KESTREL_SIMULATOR, else the scenario's `simulator:`, else rigid.
  Backend backend = Backend::rigid;
  if (!resolve_backend(cfg, backend, err)) {
    std::fprintf(stderr, "kestrel: %s: %s\n", label.c_str(), err.c_str());
    return 1;
  }
  if (cfg.robot.kind == robots::RobotKind::articulated) {
    // Legged robots and arms (sim/src/backends/articulated.cpp): random joint targets (run_scripted).
    if (cfg.task.name == "locomotion_task") return run_task(cfg, backend, label, r.steps, r.scripted, r.out_dir, r.image_env, r.quiet);
    if (is_rl_task(cfg.task.name)) {
      std::fprintf(stderr, "kestrel: %s: task %s: drives multirotors; an articulated robot (%s) runs locomotion_task, or `kestrel run` with no task\n",
                   label.c_str(), cfg.task.name.c_str(), cfg.robot.name.c_str());
      return 1;
    }
    std::unique_ptr<Simulator> sim = make_simulator(cfg, backend, err);
    if (!sim) {
      std::fprintf(stderr, "kestrel: %s: %s\n", label.c_str(), err.c_str());
      return 1;
    }
    return run_scripted(*sim, label, r.steps, r.out_dir, r.quiet);
  }
  if (backend == Backend::planar) {
    if (is_rl_task(cfg.task.name)) return run_task(cfg, backend, label, r.steps, r.scripted, r.out_dir, r.image_env, r.quiet);
    std::unique_ptr<Simulator> sim = make_simulator(cfg, backend, err);
    if (!sim) {
      std::fprintf(stderr, "kestrel: %s: %s\n", label.c_str(), err.c_str());
      return 1;
    }
    return run_scripted(*sim, label, r.steps, r.out_dir, r.quiet);
  }
  if (cfg.robot.kind == robots::RobotKind::ground_vehicle) {
    std::fprintf(stderr, "kestrel: %s: simulator rigid: robot ground_vehicle drives on the planar backend only; use simulator: planar\n",
                 label.c_str());
    return 1;
  }
  if (is_rl_task(cfg.task.name)) return run_task(cfg, backend, label, r.steps, r.scripted, r.out_dir, r.image_env, r.quiet);
  return run_world(cfg, r, label);
}

int run_main(int argc, char** argv);

}  // namespace

int main(int argc, char** argv) {
  // Set-up may allocate (sim/ allocates while it is set up); the checks (sim/limits.hpp, the
  // memory estimate) refuse what they can foresee with a message naming the field, and this is the
  // last line for what they cannot: a clear message and exit 1 instead of an uncaught-exception abort.
  try {
    return run_main(argc, argv);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr,
                 "kestrel: %s: out of memory while setting up or running it; reduce env.num_envs, robot.robots_per_env, "
                 "env.assets.*.num_assets or the sensor sizes (or lower --max-memory-gib, default %.0f GiB, so set-up refuses "
                 "it up front)\n",
                 g_label.c_str(), kDefaultMaxMemoryGiB);
  } catch (const std::exception& ex) {
    std::fprintf(stderr, "kestrel: %s: error: %s\n", g_label.c_str(), ex.what());
  }
  return 1;
}

namespace {
int run_main(int argc, char** argv) {
  if (argc < 2) return usage();
  const std::string cmd = argv[1];
  if (cmd == "list") {
    Registries& r = registries();
    list_one("sims", r.sims);
    list_one("envs", r.envs);
    list_one("robots", r.robots);
    list_one("controllers", r.controllers);
    list_one("sensors", r.sensors);
    list_one("tasks", r.tasks);
    list_one("simulators", r.simulators);
    return 0;
  }
  if (cmd == "run") return run(argc, argv);
  if (cmd == "schema") {
    std::fputs(scenario_reference_markdown().c_str(), stdout);
    return 0;
  }
  return usage();
}
}  // namespace
