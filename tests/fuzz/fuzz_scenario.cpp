// Fuzz target: scenario text -> load_scenario_file, then the `kestrel run` path of sim/cli/main.cpp
// for a few env-steps: resolve_backend; an RL task (make_task, scripted or zero actions), the
// planar backend (make_simulator + scripted_setpoint_actions) or the rigid World (World::create,
// enable_trace, step), then summary() and state_hash().
//
// Contract checked: no crash, no sanitizer report, no assert; after every env-step every robot
// state (rigid: position, orientation, velocities; planar: the state views), every observation and
// reward is finite. A scenario that fails to load or to build is fine (that is its error message).
//
// Caps after loading (so one input runs in milliseconds; the limits themselves are unit-tested):
// num_envs <= 2, robots_per_env <= 3, substeps <= 4, physics steps per env-step <= 4, latency <= 16,
// <= 32 assets per class, <= 256 lidar beams, procedural grids <= 2e5 samples, <= 4096 measured
// height points, <= 2 sensors, threads = 1. Inputs naming /dev, /proc, /sys, `..` or `//` are skipped.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "kestrel/sim/scenario.hpp"
#include "kestrel/sim/simulator.hpp"
#include "kestrel/sim/task.hpp"
#include "kestrel/sim/world.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {

constexpr int kEnvSteps = 8;

void cap(WorldConfig& c) {
  c.num_threads = 1;
  c.env.num_envs = std::min(c.env.num_envs, 2);
  c.robot.robots_per_env = std::min(c.robot.robots_per_env, 3);
  c.sim.substeps = std::min(c.sim.substeps, 4);
  c.env.num_physics_steps_per_env_step_mean = std::min<real>(c.env.num_physics_steps_per_env_step_mean, 4);
  c.env.num_physics_steps_per_env_step_std = std::min<real>(c.env.num_physics_steps_per_env_step_std, 1);
  c.env.max_latency_physics_steps = std::min(c.env.max_latency_physics_steps, 16);
  for (AssetClass& a : c.env.assets) {
    a.num_assets = std::min(a.num_assets, 32);
    a.min_num_assets = std::min(a.min_num_assets, a.num_assets);
  }
  c.simulator.lidar_beams = std::min(c.simulator.lidar_beams, 256);
  TerrainConfig& t = c.env.terrain;
  if (!t.procedural.empty()) {
    const double h = static_cast<double>(t.horizontal_scale_m);
    const double samples = (static_cast<double>(t.length_x_m) / h + 1) * (static_cast<double>(t.width_y_m) / h + 1);
    if (!(samples <= 2e5)) t.horizontal_scale_m = static_cast<real>(std::sqrt(
        static_cast<double>(t.length_x_m) * static_cast<double>(t.width_y_m) / 1e5));
  }
  while (t.measured_points_x_m.size() * t.measured_points_y_m.size() > 4096) {
    t.measured_points_x_m.resize(t.measured_points_x_m.size() / 2 + 1);
    t.measured_points_y_m.resize(t.measured_points_y_m.size() / 2 + 1);
  }
  if (c.robot.sensors.size() > 2) c.robot.sensors.resize(2);
}

bool state_finite(const RigidBodyState& s) {
  return s.position_w.allFinite() && s.orientation_wb.coeffs().allFinite() && s.linvel_w.allFinite() && s.angvel_b.allFinite();
}

void run_task(const WorldConfig& cfg, Backend backend) {
  std::string err;
  std::unique_ptr<Task> task = make_task(cfg, backend, err);
  if (!task) return;
  const std::size_t n = static_cast<std::size_t>(task->num_envs());
  const std::size_t od = static_cast<std::size_t>(task->obs_dim()), ad = static_cast<std::size_t>(task->action_dim());
  std::vector<float> actions(n * ad, 0.0f);
  const bool scripted = task->scripted_actions(actions.data());
  KFUZZ_CHECK(kfuzz::all_finite(task->observations(), n * od), "task %s: initial observation not finite", task->name());
  for (int s = 0; s < kEnvSteps; ++s) {
    if (scripted) {
      (void)task->scripted_actions(actions.data());
      KFUZZ_CHECK(kfuzz::all_finite(actions.data(), actions.size()), "task %s: scripted action not finite (step %d)",
                  task->name(), s);
    }
    task->step(actions.data());
    KFUZZ_CHECK(kfuzz::all_finite(task->observations(), n * od), "task %s: observation not finite (step %d)", task->name(), s);
    KFUZZ_CHECK(kfuzz::all_finite(task->rewards(), n), "task %s: reward not finite (step %d)", task->name(), s);
  }
  (void)task->infos().mean_episode_reward();
  (void)task->state_hash();
}

void run_planar(const WorldConfig& cfg) {
  std::string err;
  std::unique_ptr<Simulator> sim = make_simulator(cfg, Backend::planar, err);
  if (!sim) return;
  const std::size_t r = static_cast<std::size_t>(sim->num_robots());
  std::vector<real> actions(r * static_cast<std::size_t>(sim->action_dim()), 0);
  for (int s = 0; s < kEnvSteps; ++s) {
    scripted_setpoint_actions(*sim, actions.data());
    sim->step(actions.data());
    KFUZZ_CHECK(kfuzz::all_finite(sim->base_pos_w(), 3 * r) && kfuzz::all_finite(sim->base_quat_xyzw(), 4 * r) &&
                    kfuzz::all_finite(sim->base_lin_vel_b(), 3 * r) && kfuzz::all_finite(sim->base_ang_vel_b(), 3 * r),
                "planar: state view not finite (step %d)", s);
    KFUZZ_CHECK(kfuzz::all_finite(sim->lidar_ranges_m(), r * static_cast<std::size_t>(sim->lidar_beams())),
                "planar: lidar range not finite (step %d)", s);
  }
  (void)sim->summary();
  (void)sim->state_hash();
}

void run_rigid(const WorldConfig& cfg) {
  std::string err;
  std::unique_ptr<World> world = World::create(cfg, err);
  if (!world) return;
  world->enable_trace(6, kEnvSteps);
  for (int s = 0; s < kEnvSteps; ++s) {
    world->step(1);
    for (int e = 0; e < world->num_envs(); ++e)
      for (int k = 0; k < cfg.robot.robots_per_env; ++k)
        KFUZZ_CHECK(state_finite(world->robot_state(e, k)), "rigid: env %d robot %d state not finite (step %d)", e, k, s);
  }
  (void)world->summary();
  (void)world->state_hash();
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  (void)kfuzz::work_dir();
  ::unsetenv("KESTREL_SIMULATOR");  // the scenario's own `simulator:` decides
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  for (const char* bad : {"/dev", "/proc", "/sys", "..", "//"})
    if (text.find(bad) != std::string::npos) return -1;
  if (text.find('\0') != std::string::npos) return -1;
  const std::string path = kfuzz::write_input("scenario.yaml", data, size);
  WorldConfig cfg;
  std::string err;
  if (!load_scenario_file(path, cfg, err)) return 0;
  cap(cfg);
  Backend backend = Backend::rigid;
  if (!resolve_backend(cfg, backend, err)) return 0;
  if (is_rl_task(cfg.task.name)) {
    run_task(cfg, backend);
  } else if (backend == Backend::planar) {
    run_planar(cfg);
  } else if (cfg.robot.kind != robots::RobotKind::ground_vehicle) {
    run_rigid(cfg);
  }
  return 0;
}
