// The rigid World's batched path: groups of batch::lanes() (4, 8 or 16) consecutive environments step their
// robots through the batched twin of stage::robot_dynamics (sim/batch_step.hpp) in lockstep; the
// rest of each env-step (setpoints, IMUs, obstacles, collision, statistics, resets, sensors) is the
// scalar stages of step.cpp, run per environment in the same order as env_step. Environments never
// read each other's state and the twin is bit-identical to the scalar robot step, so the result
// does not depend on the grouping, on the thread partition or on whether the batched path is on
// (tests/sim/engine/batch_step_test.cpp).
#include <algorithm>
#include <cstring>

#include "kestrel/sim/batch_step.hpp"
#include "kestrel/sim/world_stages.hpp"

namespace kestrel::sim::stage {

namespace {
// Software prefetch of one robot's per-step storage: at 4096+ environments a worker's robots no
// longer fit in L2, and the motor state alone (448 bytes, six of its seven lines touched per step)
// would otherwise miss on first touch. No effect on results.
template <typename T>
inline void prefetch(const T* p) {
  const char* c = reinterpret_cast<const char*>(p);
  for (std::size_t o = 0; o < sizeof(T); o += 64) __builtin_prefetch(c + o, 1);
  __builtin_prefetch(c + sizeof(T) - 1, 1);
}

// `lanes` is the caller's scratch (num_lanes entries), every field rewritten here: an array of
// batch::Lane declared per call would be zero-filled per call (its members have initialisers).
void robot_dynamics_batch(const WorldModel& m, WorldData& d, int env0, int num_lanes, unsigned new_action_mask,
                          const batch::Models& models, batch::Lane* lanes) {
  for (int l = 0; l < num_lanes; ++l) {
    const std::size_t i = m.index(env0 + l, 0);
    real* applied = &d.applied_actions[i * kMaxActionDim];
    if ((new_action_mask >> l) & 1u) std::memcpy(applied, &d.actions[i * kMaxActionDim], sizeof(real) * kMaxActionDim);
    lanes[l].state = &d.state[i];
    lanes[l].ctrl = &d.mr_state[i].ctrl;
    lanes[l].alloc = &d.mr_state[i].allocator;
    lanes[l].motors = &d.mr_state[i].motors;
    lanes[l].action = applied;
    lanes[l].contact_force_w = &d.contact_force_w[i];
    lanes[l].contact_torque_b = &d.contact_torque_b[i];
  }
  batch::robot_step(models, lanes);
}
}  // namespace

bool batch_eligible(const WorldModel& m) {
  // One robot per environment (lanes are environments); the observation noise and the random
  // disturbance draw from the environment's stream inside the robot step, which the twin leaves
  // to the scalar path.
  return m.robots_per_env == 1 && !m.cfg.env.perturb_observations && !m.cfg.env.enable_disturbance &&
         batch::chain_eligible(m.mr) && batch::eligible(batch::models_of(m.mr, m.body, m.cfg.sim.dt_s, m.cfg.sim.substeps));
}

int env_steps_batched(const WorldModel& m, WorldData& d, int begin, int end) {
  const int group = batch::lanes();
  // Software prefetch of the robots `ahead` environments on, one robot per lane of each per-lane
  // loop below, so that the prefetches spread over the group's work: issued all at once (8 robots
  // x 16 lines for the 8-lane copy) they overran the core's outstanding-miss slots, and the 8-lane
  // copy ran 25 % slower than the 4-lane one at 65,536 environments on the 2-core machine.
  const int ahead = std::max(group, 8);  // measured best: 8 robots for 4 and 8 lanes
  const batch::Models models = batch::models_of(m.mr, m.body, m.cfg.sim.dt_s, m.cfg.sim.substeps);
  batch::Lane lanes[batch::kMaxLanes];
  int env = begin;
  for (; env + group <= end; env += group) {
    // Lockstep needs the same number of physics steps in every lane (always, unless
    // num_physics_steps_per_env_step_std > 0); the latency may differ per lane.
    const int n = d.phys_steps[env];
    bool same = true;
    for (int l = 1; l < group; ++l) same = same && d.phys_steps[env + l] == n;
    if (!same) {
      for (int l = 0; l < group; ++l) env_step(m, d, env + l);
      continue;
    }
    const int pf_end = std::min(group, end - env - ahead);  // robots env + ahead + l, l < pf_end
    for (int l = 0; l < group; ++l) {
      if (l < pf_end) prefetch(&d.mr_state[m.index(env + ahead + l, 0)].motors);
      env_step_begin(m, d, env + l);
    }
    for (int s = 0; s < n; ++s) {
      unsigned new_action = 0;
      Vec3 v0[batch::kMaxLanes];
      for (int l = 0; l < group; ++l) {
        if (s == d.latency[env + l]) new_action |= 1u << l;
        v0[l] = d.state[m.index(env + l, 0)].linvel_w;
      }
      robot_dynamics_batch(m, d, env, group, new_action, models, lanes);
      for (int l = 0; l < group; ++l) {
        if (s == 0 && l < pf_end) {
          const std::size_t i = m.index(env + ahead + l, 0);
          prefetch(&d.mr_state[i].ctrl.lee);
          prefetch(&d.mr_state[i].allocator);
        }
        if (m.any_imu) update_imus(m, d, env + l, 0, v0[l]);
        physics_step_tail(m, d, env + l);
      }
    }
    for (int l = 0; l < group; ++l) {
      if (l < pf_end) prefetch(&d.state[m.index(env + ahead + l, 0)]);
      env_step_end(m, d, env + l);
    }
  }
  return env;
}

}  // namespace kestrel::sim::stage
