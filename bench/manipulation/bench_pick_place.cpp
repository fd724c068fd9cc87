// The SO-101 pick-and-place (sim/pick_place.hpp) on one core: the scripted pick and place
// (ScriptedPickPlace) over N randomised resets (LeIsaac's randomize_object_uniform, +-5 cm for cube
// and box), its success rate by LeIsaac's cube_in_box, the physics steps per second with the grasp
// contacts (the whole step: servos, collision, constrained solve; timed over the episodes, IK
// excluded), the contacts and solver sweeps per step, and the cube's drift at rest in the box.
//
//   kestrel_bench_pick_place [episodes=1000] [seed=1] [csv path] [actions csv path]
// prints a summary line and, with a path, writes one CSV row per episode; with an actions path, the
// first episode's joint targets and the cube's position per action (what
// bench/manipulation/mujoco_side_by_side.py replays in MuJoCo).
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "kestrel/sim/pick_place.hpp"

using namespace kestrel;
using namespace kestrel::sim;

int main(int argc, char** argv) {
  const int episodes = argc > 1 ? std::atoi(argv[1]) : 1000;
  const std::uint64_t seed = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 1;
  const char* csv_path = argc > 3 ? argv[3] : nullptr;
  std::FILE* trace = argc > 4 ? std::fopen(argv[4], "w") : nullptr;
  if (argc > 4 && trace == nullptr) {
    std::fprintf(stderr, "bench_pick_place: cannot write %s\n", argv[4]);
    return 1;
  }
  if (trace != nullptr) std::fprintf(trace, "t_s,phase,q0,q1,q2,q3,q4,q5,cube_x,cube_y,cube_z,box_x,box_y\n");
  PickPlaceConfig cfg;
  PickPlaceWorld w;
  std::string err;
  if (!w.init(cfg, seed, 0, err)) {
    std::fprintf(stderr, "%s\n", err.c_str());
    return 1;
  }
  std::FILE* csv = csv_path != nullptr ? std::fopen(csv_path, "w") : nullptr;
  if (csv_path != nullptr && csv == nullptr) {
    std::fprintf(stderr, "bench_pick_place: cannot write %s\n", csv_path);
    return 1;
  }
  if (csv != nullptr) std::fprintf(csv, "episode,success,lifted_z_m,carried_slip_m,rest_drift_m,actions,cube_x,cube_y,box_x,box_y\n");
  int successes = 0, errors = 0;
  long physics_steps = 0, contacts = 0, sweeps = 0;
  double step_seconds = 0, worst_slip = 0, worst_drift = 0;
  real a[PickPlaceWorld::kJoints];
  using clock = std::chrono::steady_clock;
  auto timed_step = [&](const real* act) {
    const auto t0 = clock::now();
    const Status st = w.step(act);
    step_seconds += std::chrono::duration<double>(clock::now() - t0).count();
    physics_steps += cfg.decimation;
    contacts += w.contacts();
    sweeps += w.solver_iterations_used();
    if (st != Status::ok) ++errors;
  };
  for (int e = 0; e < episodes; ++e) {
    w.reset();
    const Vec3 cube0 = w.state().cube_pos_w, box0 = w.state().box_pos_w;
    ScriptedPickPlace s(w);
    int actions = 0;
    real lifted = 0, slip = 0;
    bool have = false;
    Vec3 offset = Vec3::Zero();
    while (!s.done() && actions < 400) {
      s.act(a);
      timed_step(a);
      ++actions;
      if (trace != nullptr && e == 0) {
        const Vec3 c = w.state().cube_pos_w, b = w.state().box_pos_w;
        std::fprintf(trace, "%.3f,%d", static_cast<double>(actions) * cfg.dt_s * cfg.decimation, s.phase());
        for (int j = 0; j < PickPlaceWorld::kJoints; ++j) std::fprintf(trace, ",%.7f", static_cast<double>(a[j]));
        std::fprintf(trace, ",%.5f,%.5f,%.5f,%.5f,%.5f\n", static_cast<double>(c[0]), static_cast<double>(c[1]), static_cast<double>(c[2]),
                     static_cast<double>(b[0]), static_cast<double>(b[1]));
      }
      if (s.phase() == 3) lifted = w.state().cube_pos_w[2];
      if (s.phase() == 4) {
        const Vec3 off = w.state().cube_pos_w - w.state().tcp_pos_w;
        if (!have) offset = off, have = true;
        slip = std::max(slip, (off - offset).norm());
      }
    }
    for (int k = 0; k < 25; ++k) {
      s.act(a);
      timed_step(a);
    }
    const Vec3 rest = w.state().cube_pos_w;
    for (int k = 0; k < 25; ++k) timed_step(a);
    const real drift = (w.state().cube_pos_w - rest).norm();
    const bool ok = w.cube_in_box();
    successes += ok ? 1 : 0;
    worst_slip = std::max(worst_slip, static_cast<double>(slip));
    if (ok) worst_drift = std::max(worst_drift, static_cast<double>(drift));
    if (csv != nullptr)
      std::fprintf(csv, "%d,%d,%.5f,%.6f,%.7f,%d,%.5f,%.5f,%.5f,%.5f\n", e, ok ? 1 : 0, static_cast<double>(lifted),
                   static_cast<double>(slip), static_cast<double>(drift), actions, static_cast<double>(cube0[0]),
                   static_cast<double>(cube0[1]), static_cast<double>(box0[0]), static_cast<double>(box0[1]));
  }
  if (csv != nullptr) std::fclose(csv);
  if (trace != nullptr) std::fclose(trace);
  std::printf(
      "pick_place: %d/%d successes (%.1f %%), %d step errors; physics %.0f steps/s on one core (%.2f us/step), "
      "%.1f contacts and %.1f solver sweeps per step; worst slip while carried %.2f mm, worst drift at rest in the "
      "box over 0.5 s %.3f mm\n",
      successes, episodes, 100.0 * successes / episodes, errors, physics_steps / step_seconds, 1e6 * step_seconds / physics_steps,
      static_cast<double>(contacts) / (physics_steps / cfg.decimation), static_cast<double>(sweeps) / (physics_steps / cfg.decimation),
      1e3 * worst_slip, 1e3 * worst_drift);
  return 0;
}
