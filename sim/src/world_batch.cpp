// World's batched path: groups of batch::kLanes consecutive environments step their robots through
// the batched twin of World::robot_dynamics (sim/batch_step.hpp) in lockstep; the rest of each
// env-step (setpoints, IMUs, obstacles, collision, statistics, resets, sensors) is the scalar code
// of world.cpp, run per environment in the same order as env_step. Environments never read each
// other's state and the twin is bit-identical to the scalar robot step, so the result does not
// depend on the grouping, on the thread partition or on whether the batched path is on
// (tests/sim/batch_step_test.cpp).
#include <cstring>

#include "kestrel/sim/batch_step.hpp"
#include "kestrel/sim/world.hpp"

namespace kestrel::sim {

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
}  // namespace

bool World::batch_eligible() const {
  // One robot per environment (lanes are environments); the observation noise and the random
  // disturbance draw from the environment's stream inside the robot step, which the twin leaves
  // to the scalar path.
  return robots_per_env_ == 1 && !cfg_.env.perturb_observations && !cfg_.env.enable_disturbance &&
         batch::chain_eligible(mr_) && batch::eligible(batch::models_of(mr_, body_model_, cfg_.sim.dt_s, cfg_.sim.substeps));
}

bool World::set_batched(bool on) {
  batch_ = on && batch_eligible();
  return batch_;
}

void World::robot_dynamics_batch(int env0, unsigned new_action_mask, const batch::Models& m) {
  batch::Lane lanes[batch::kLanes];
  for (int l = 0; l < batch::kLanes; ++l) {
    const std::size_t i = index(env0 + l, 0);
    real* applied = &applied_actions_[i * kMaxActionDim];
    if ((new_action_mask >> l) & 1u) std::memcpy(applied, &actions_[i * kMaxActionDim], sizeof(real) * kMaxActionDim);
    lanes[l].state = &state_[i];
    lanes[l].ctrl = &mr_state_[i].ctrl;
    lanes[l].alloc = &mr_state_[i].allocator;
    lanes[l].motors = &mr_state_[i].motors;
    lanes[l].action = applied;
    lanes[l].contact_force_w = &contact_force_w_[i];
    lanes[l].contact_torque_b = &contact_torque_b_[i];
  }
  batch::robot_step(m, lanes);
}

int World::env_steps_batched(int begin, int end) {
  constexpr int kL = batch::kLanes;
  constexpr int kAhead = 2 * kL;  // prefetch distance: two groups (~a microsecond of work)
  const batch::Models m = batch::models_of(mr_, body_model_, cfg_.sim.dt_s, cfg_.sim.substeps);
  int env = begin;
  for (; env + kL <= end; env += kL) {
    for (int l = 0; l < kL && env + kAhead + l < end; ++l) {
      const std::size_t i = index(env + kAhead + l, 0);
      prefetch(&mr_state_[i].motors);
      prefetch(&mr_state_[i].ctrl.lee);
      prefetch(&mr_state_[i].allocator);
      prefetch(&state_[i]);
    }
    // Lockstep needs the same number of physics steps in every lane (always, unless
    // num_physics_steps_per_env_step_std > 0); the latency may differ per lane.
    const int n = phys_steps_[env];
    bool same = true;
    for (int l = 1; l < kL; ++l) same = same && phys_steps_[env + l] == n;
    if (!same) {
      for (int l = 0; l < kL; ++l) env_step(env + l);
      continue;
    }
    for (int l = 0; l < kL; ++l) env_step_begin(env + l);
    for (int s = 0; s < n; ++s) {
      unsigned new_action = 0;
      Vec3 v0[kL];
      for (int l = 0; l < kL; ++l) {
        if (s == latency_[env + l]) new_action |= 1u << l;
        v0[l] = state_[index(env + l, 0)].linvel_w;
      }
      robot_dynamics_batch(env, new_action, m);
      for (int l = 0; l < kL; ++l) {
        if (any_imu_) update_imus(env + l, 0, v0[l]);
        physics_step_tail(env + l);
      }
    }
    for (int l = 0; l < kL; ++l) env_step_end(env + l);
  }
  return env;
}

}  // namespace kestrel::sim
