// The SO-101 pick-and-place (sim/pick_place.hpp) on one core: the scripted pick and place
// (ScriptedPickPlace) over N randomised resets (LeIsaac's randomize_object_uniform, +-5 cm for cube
// and box), its success rate by LeIsaac's cube_in_box, the physics steps per second with the grasp
// contacts (the whole step: servos, collision, constrained solve; timed over the episodes, IK
// excluded), the contacts and solver sweeps per step, and the cube's drift at rest in the box.
//
// W worlds (default: the batched step's lanes, 16 with AVX-512) run the episodes side by side, each
// taking the next episode when its own ends. Two copies of those worlds run in the same loop, one
// action apart: one copy steps each world alone (PickPlaceWorld::step), the other steps them all
// at once (PickPlaceWorld::step_batch, one world per SIMD lane); both are timed, and after every
// action their states are compared: the bench stops with an error if they ever differ.
//
//   kestrel_bench_pick_place [episodes=1000] [seed=1] [csv path|-] [actions csv path|-] [worlds]
// prints a summary line and, with a path, writes one CSV row per episode; with an actions path, the
// first episode's joint targets and the cube's position per action (what
// bench/manipulation/mujoco_side_by_side.py replays in MuJoCo).
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "kestrel/sim/aligned_scratch.hpp"
#include "kestrel/sim/pick_place.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {

// One world's run through its episodes: the script, then 25 actions more of it, then 25 actions
// holding the last targets (the cube's drift at rest in the box).
struct Slot {
  std::unique_ptr<PickPlaceWorld> alone, batched;  // the same world, stepped the two ways
  std::unique_ptr<ScriptedPickPlace> script;
  int episode = -1, stage = 0, count = 0, actions = 0;
  real a[PickPlaceWorld::kJoints] = {};
  Vec3 cube0, box0, offset, rest;
  bool have = false;
  real lifted = 0, slip = 0;
};

}  // namespace

int main(int argc, char** argv) {
  const int episodes = argc > 1 ? std::atoi(argv[1]) : 1000;
  const std::uint64_t seed = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 1;
  auto path = [&](int i) -> const char* { return argc > i && std::strcmp(argv[i], "-") != 0 ? argv[i] : nullptr; };
  const char* csv_path = path(3);
  std::FILE* trace = path(4) != nullptr ? std::fopen(argv[4], "w") : nullptr;
  if (path(4) != nullptr && trace == nullptr) {
    std::fprintf(stderr, "bench_pick_place: cannot write %s\n", argv[4]);
    return 1;
  }
  if (trace != nullptr) std::fprintf(trace, "t_s,phase,q0,q1,q2,q3,q4,q5,cube_x,cube_y,cube_z,box_x,box_y\n");
  PickPlaceConfig cfg;
  std::string err;
  std::vector<Slot> slots;
  {
    PickPlaceWorld probe;
    if (!probe.init(cfg, seed, 0, err)) {
      std::fprintf(stderr, "%s\n", err.c_str());
      return 1;
    }
    const int lanes = probe.batch_lanes();
    const int worlds = argc > 5 ? std::atoi(argv[5]) : std::max(1, lanes);
    if (worlds < 1 || (lanes > 0 && worlds > lanes)) {
      std::fprintf(stderr, "bench_pick_place: worlds: expected 1 .. %d (the batched step's lanes), got %s\n", std::max(1, lanes),
                   argv[5]);
      return 1;
    }
    slots.resize(static_cast<std::size_t>(std::min(worlds, std::max(1, episodes))));
  }
  for (std::size_t l = 0; l < slots.size(); ++l) {
    slots[l].alone = std::make_unique<PickPlaceWorld>();
    slots[l].batched = std::make_unique<PickPlaceWorld>();
    if (!slots[l].alone->init(cfg, seed, static_cast<std::uint32_t>(l), err) ||
        !slots[l].batched->init(cfg, seed, static_cast<std::uint32_t>(l), err)) {
      std::fprintf(stderr, "%s\n", err.c_str());
      return 1;
    }
  }
  std::FILE* csv = csv_path != nullptr ? std::fopen(csv_path, "w") : nullptr;
  if (csv_path != nullptr && csv == nullptr) {
    std::fprintf(stderr, "bench_pick_place: cannot write %s\n", csv_path);
    return 1;
  }
  if (csv != nullptr) std::fprintf(csv, "episode,world,success,lifted_z_m,carried_slip_m,rest_drift_m,actions,cube_x,cube_y,box_x,box_y\n");
  struct Row {
    int world = 0, ok = 0, actions = 0;
    double lifted = 0, slip = 0, drift = 0, cx = 0, cy = 0, bx = 0, by = 0;
  };
  std::vector<Row> rows(static_cast<std::size_t>(std::max(episodes, 0)));
  AlignedScratch scratch_mem(PickPlaceWorld::batch_scratch_bytes());
  void* scratch = scratch_mem.data();

  int next_episode = 0;
  auto start = [&](Slot& s) {
    if (next_episode >= episodes) {
      s.episode = -1;
      return;
    }
    s.episode = next_episode++;
    s.alone->reset();
    s.batched->reset();
    s.cube0 = s.batched->state().cube_pos_w;
    s.box0 = s.batched->state().box_pos_w;
    s.script = std::make_unique<ScriptedPickPlace>(*s.batched);
    s.stage = s.count = s.actions = 0;
    s.have = false;
    s.lifted = s.slip = 0;
  };
  for (Slot& s : slots) start(s);

  int successes = 0, errors = 0;
  long world_steps = 0, batched_steps = 0, contacts = 0, sweeps = 0;
  double alone_s = 0, batch_s = 0, worst_slip = 0, worst_drift = 0;
  using clock = std::chrono::steady_clock;
  const int W = static_cast<int>(slots.size());
  std::vector<PickPlaceWorld*> live(static_cast<std::size_t>(W));
  std::vector<const real*> targets(static_cast<std::size_t>(W));
  std::vector<Status> status(static_cast<std::size_t>(W));
  for (;;) {
    int n = 0;
    for (Slot& s : slots) {
      if (s.episode < 0) continue;
      if (s.stage < 2) s.script->act(s.a);  // stage 2 holds the last targets
      live[static_cast<std::size_t>(n)] = s.batched.get();
      targets[static_cast<std::size_t>(n)] = s.a;
      ++n;
    }
    if (n == 0) break;
    // The same action both ways: each world alone, then all of them at once.
    auto t0 = clock::now();
    for (Slot& s : slots)
      if (s.episode >= 0 && s.alone->step(s.a) != Status::ok) ++errors;
    auto t1 = clock::now();
    batched_steps += PickPlaceWorld::step_batch(live.data(), targets.data(), n, status.data(), scratch);
    auto t2 = clock::now();
    alone_s += std::chrono::duration<double>(t1 - t0).count();
    batch_s += std::chrono::duration<double>(t2 - t1).count();
    world_steps += static_cast<long>(n) * cfg.decimation;
    for (int i = 0; i < n; ++i)
      if (status[static_cast<std::size_t>(i)] != Status::ok) ++errors;
    for (std::size_t l = 0; l < slots.size(); ++l) {
      Slot& s = slots[l];
      if (s.episode < 0) continue;
      PickPlaceWorld& w = *s.batched;
      if (w.state_hash() != s.alone->state_hash()) {
        std::fprintf(stderr, "bench_pick_place: world %zu, episode %d: the batched step's state differs from the world's own step()\n", l,
                     s.episode);
        return 2;
      }
      contacts += w.contacts();
      sweeps += s.alone->solver_iterations_used();
      if (s.stage == 0) {
        ++s.actions;
        if (trace != nullptr && s.episode == 0) {
          const Vec3 c = w.state().cube_pos_w, b = w.state().box_pos_w;
          std::fprintf(trace, "%.3f,%d", static_cast<double>(s.actions) * cfg.dt_s * cfg.decimation, s.script->phase());
          for (int j = 0; j < PickPlaceWorld::kJoints; ++j) std::fprintf(trace, ",%.7f", static_cast<double>(s.a[j]));
          std::fprintf(trace, ",%.5f,%.5f,%.5f,%.5f,%.5f\n", static_cast<double>(c[0]), static_cast<double>(c[1]), static_cast<double>(c[2]),
                       static_cast<double>(b[0]), static_cast<double>(b[1]));
        }
        if (s.script->phase() == 3) s.lifted = w.state().cube_pos_w[2];
        if (s.script->phase() == 4) {
          const Vec3 off = w.state().cube_pos_w - w.state().tcp_pos_w;
          if (!s.have) s.offset = off, s.have = true;
          s.slip = std::max(s.slip, (off - s.offset).norm());
        }
        if (s.script->done() || s.actions >= 400) s.stage = 1, s.count = 0;
      } else if (s.stage == 1) {
        if (++s.count == 25) {
          s.rest = w.state().cube_pos_w;
          s.stage = 2, s.count = 0;
        }
      } else if (++s.count == 25) {
        const real drift = (w.state().cube_pos_w - s.rest).norm();
        const bool ok = w.cube_in_box();
        successes += ok ? 1 : 0;
        worst_slip = std::max(worst_slip, static_cast<double>(s.slip));
        if (ok) worst_drift = std::max(worst_drift, static_cast<double>(drift));
        Row& r = rows[static_cast<std::size_t>(s.episode)];
        r = Row{static_cast<int>(l), ok ? 1 : 0, s.actions, s.lifted, s.slip, drift, s.cube0[0], s.cube0[1], s.box0[0], s.box0[1]};
        if (trace != nullptr && s.episode == 0) {
          std::fclose(trace);
          trace = nullptr;
        }
        start(s);
      }
    }
  }
  if (csv != nullptr) {
    for (std::size_t e = 0; e < rows.size(); ++e) {
      const Row& r = rows[e];
      std::fprintf(csv, "%zu,%d,%d,%.5f,%.6f,%.7f,%d,%.5f,%.5f,%.5f,%.5f\n", e, r.world, r.ok, r.lifted, r.slip, r.drift, r.actions, r.cx, r.cy,
                   r.bx, r.by);
    }
    std::fclose(csv);
  }
  if (trace != nullptr) std::fclose(trace);
  const double actions = static_cast<double>(world_steps) / cfg.decimation;
  std::printf(
      "pick_place: %d/%d successes (%.1f %%), %d step errors; physics %.0f steps/s on one core batched (%d worlds, %.1f %% of their "
      "steps in the batch; %.2f us/step), %.0f steps/s one world at a time (%.2f us/step), batched %.2fx; the two bit-identical; "
      "%.1f contacts and %.1f solver sweeps per step; worst slip while carried %.2f mm, worst drift at rest in the box over 0.5 s "
      "%.3f mm\n",
      successes, episodes, 100.0 * successes / std::max(episodes, 1), errors, world_steps / batch_s, W,
      100.0 * static_cast<double>(batched_steps) / static_cast<double>(std::max(world_steps, 1L)), 1e6 * batch_s / world_steps,
      world_steps / alone_s, 1e6 * alone_s / world_steps, alone_s / batch_s, static_cast<double>(contacts) / actions,
      static_cast<double>(sweeps) / actions, 1e3 * worst_slip, 1e3 * worst_drift);
  return 0;
}
