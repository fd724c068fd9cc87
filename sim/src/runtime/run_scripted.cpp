// `kestrel run` through the Simulator interface: the scripted position-setpoint policy (targets
// for Lee position control, pure pursuit for the ground vehicle), a summary and the state hash.
#include <sys/stat.h>

#include <chrono>
#include <cinttypes>
#include <cstdio>

#include "kestrel/sim/output.hpp"
#include "kestrel/sim/simulator.hpp"

namespace kestrel::sim {

int run_scripted(Simulator& sim, const std::string& label, long long steps, const std::string& out_dir, bool quiet) {
  const WorldConfig& cfg = sim.config();
  RunReport rep;  // what is printed, also written to out_dir/summary.txt
  rep.say("kestrel run: %s\n", label.c_str());
  rep.say("  simulator %s, vehicle %s, controller %s (%d actions), env %s, robot %s x%d, dt %.4g s x %d\n",
              sim.backend_name(),
              sim.backend() == Backend::planar
                  ? (sim.ground_vehicle() ? "ground_vehicle" : "multirotor at fixed altitude")
                  : (sim.num_dofs() > 0 ? "articulated" : "3-D"),
              sim.controller_name(), sim.action_dim(), cfg.env.name.c_str(), cfg.robot.name.c_str(), sim.robots_per_env(),
              static_cast<double>(sim.dt_s()), sim.decimation());
  rep.say("  envs %d, threads %d, seed %" PRIu64 ", steps %lld", sim.num_envs(), sim.num_threads(), cfg.seed, steps);
  if (sim.lidar_beams() > 0) rep.say(", 2-D lidar %d beams", sim.lidar_beams());
  rep.say("\n");
  std::vector<real> actions(static_cast<std::size_t>(sim.num_robots()) * static_cast<std::size_t>(sim.action_dim()), 0);
  // Trajectory of robot 0 of the first environments (x, y, yaw per env-step).
  const int trace_envs = std::min(6, sim.num_envs());
  std::vector<real> trace(static_cast<std::size_t>(trace_envs) * static_cast<std::size_t>(steps) * 3, 0);
  ProgressLine progress(stderr, !quiet && ProgressLine::stderr_is_terminal(), static_cast<double>(steps) * sim.num_envs());
  const auto t0 = std::chrono::steady_clock::now();
  // Articulated robots: random joint targets, uniform in [-1, 1] actions (x robot.action_scale
  // about the home pose), redrawn every 25 env-steps from each robot's own stream.
  const int nd = sim.num_dofs();
  std::vector<RngStream> target_rng;
  for (int i = 0; nd > 0 && i < sim.num_robots(); ++i) target_rng.emplace_back(cfg.seed, static_cast<std::uint32_t>(cfg.env.first_env_index * sim.robots_per_env() + i), kPurposeScriptedTargets);
  if (nd > 0)
    rep.say("  articulated: %d joints, %d feet, %d links; random joint targets every 25 env-steps\n", nd, sim.num_feet(), sim.num_links());
  for (long long s = 0; s < steps; ++s) {
    if (nd > 0) {
      if (s % 25 == 0)
        for (int i = 0; i < sim.num_robots(); ++i)
          for (int j = 0; j < nd; ++j) actions[static_cast<std::size_t>(i * nd + j)] = target_rng[static_cast<std::size_t>(i)].uniform(-1, 1);
    } else {
      scripted_setpoint_actions(sim, actions.data());
    }
    sim.step(actions.data());
    for (int e = 0; e < trace_envs; ++e) {
      const std::size_t i = static_cast<std::size_t>(e * sim.robots_per_env());
      real* t = &trace[(static_cast<std::size_t>(e) * static_cast<std::size_t>(steps) + static_cast<std::size_t>(s)) * 3];
      t[0] = sim.base_pos_w()[3 * i];
      t[1] = sim.base_pos_w()[3 * i + 1];
      t[2] = sim.base_euler_xyz()[3 * i + 2];
    }
    progress.update(static_cast<double>(s + 1) * sim.num_envs());
  }
  progress.finish();
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const WorldSummary s = sim.summary();
  std::printf("  wall time %.3f s, %.3g env-steps/s\n", secs, static_cast<double>(s.env_steps) / secs);
  report_episodes(rep, s, cfg.task.success_radius_m);
  rep.say("  distance to target: mean over env-steps %.3f m; at episode end %.3f m; final mean %.3f m\n",
          s.mean_tracking_error_m, s.episode_end_distance_m, s.final_mean_distance_m);
  if (sim.backend() == Backend::planar)
    rep.say("  Box2D allocations inside steps that overflowed the per-env arenas to the heap: %" PRIu64 "\n",
            sim.step_heap_fallbacks());
  const std::string fb = placement_fallback_text(
      cfg.env.name, s.placement_fallbacks,
      s.placements, -1.0,
      cfg.task.line_of_sight);
  if (!fb.empty()) rep.say("  %s\n", fb.c_str());
  ::mkdir(out_dir.c_str(), 0755);
  const std::string path = out_dir + "/trajectory.csv";
  std::string err;
  if (!write_trace_csv(path, "x_m,y_m,yaw_rad", trace.data(), trace_envs, steps, err)) {
    std::fprintf(stderr, "kestrel: %s\n", err.c_str());
    return 1;
  }
  std::printf("  wrote %s\n", path.c_str());
  print_plot_hint(out_dir);
  if (!rep.finish(out_dir, sim.state_hash(), err)) {
    std::fprintf(stderr, "kestrel: %s\n", err.c_str());
    return 1;
  }
  return 0;
}

}  // namespace kestrel::sim
