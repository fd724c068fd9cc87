// position_setpoint_task: reward parity with Aerial Gym (golden/rewards.json, every case), the task
// API (shapes, auto-reset, truncation, reset_idx, no heap in step), the reward trend under a
// scripted policy vs zero actions, and the registry entry.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "golden_tol.hpp"
#include "heap_counter.hpp"
#include "json_pull.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/task.hpp"
#include "task_world.hpp"
#include "test_io.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {

struct RewardCase {
  int id = -1;
  float pos[3] = {}, target[3] = {}, quat[4] = {}, angvel[3] = {}, err_v[3] = {};
  float crashes_in = 0, multiplier = 0, reward = 0, crashes_out = 0;
};

bool read_vec(ktest::JsonReader& r, float* v, int n) { return r.read_numbers(v, n) == n; }

// The cases of rewards.json and the reward tolerance its conventions declare (kept if it does not).
std::vector<RewardCase> load_cases(ktest::GoldenTol& tol) {
  std::vector<RewardCase> cases;
  ktest::JsonReader r;
  const char* path = ktest::golden_path("rewards.json");
  if (!r.open(path)) {
    ADD_FAILURE() << "cannot open " << path;
    return cases;
  }
  static const char* const kNames[] = {"reward"};
  ktest::GoldenTol* const out[] = {&tol};
  EXPECT_TRUE(r.begin_object() && r.find_key("conventions") &&  // listed first
              ktest::read_conventions_tolerance(r, [&](ktest::JsonReader& t) { return ktest::read_named_tolerances(t, kNames, out, 1); }))
      << r.error();
  EXPECT_TRUE(r.find_key("cases") && r.begin_array()) << r.error();
  while (r.next_element()) {
    RewardCase c;
    if (!r.begin_object()) break;
    char key[64];
    bool ok = true;
    while (ok && r.next_key(key, sizeof key)) {
      if (!std::strcmp(key, "id")) ok = r.read_int(c.id);
      else if (!std::strcmp(key, "robot_position_world")) ok = read_vec(r, c.pos, 3);
      else if (!std::strcmp(key, "target_position_world")) ok = read_vec(r, c.target, 3);
      else if (!std::strcmp(key, "robot_orientation_xyzw")) ok = read_vec(r, c.quat, 4);
      else if (!std::strcmp(key, "robot_body_angvel")) ok = read_vec(r, c.angvel, 3);
      else if (!std::strcmp(key, "pos_error_vehicle_frame")) ok = read_vec(r, c.err_v, 3);
      else if (!std::strcmp(key, "crashes_in")) ok = r.read_float(c.crashes_in);
      else if (!std::strcmp(key, "curriculum_level_multiplier")) ok = r.read_float(c.multiplier);
      else if (!std::strcmp(key, "reward")) ok = r.read_float(c.reward);
      else if (!std::strcmp(key, "crashes_out")) ok = r.read_float(c.crashes_out);
      else ok = r.skip_value();
    }
    EXPECT_TRUE(ok && r.ok()) << "case " << c.id << ": " << r.error();
    cases.push_back(c);
  }
  EXPECT_TRUE(r.ok()) << r.error();
  return cases;
}

bool close(float mine, float golden, float abs_tol, float rel_tol) {
  return std::fabs(mine - golden) <= abs_tol + rel_tol * std::fabs(golden);
}

WorldConfig task_config(int num_envs, std::uint64_t seed) {
  WorldConfig c;
  EXPECT_TRUE(registries().envs.make("empty", c.env));
  EXPECT_TRUE(registries().tasks.make("position_setpoint_task", c.task));
  c.env.num_envs = num_envs;
  c.num_threads = 2;
  c.seed = seed;
  return c;
}

std::unique_ptr<Task> build(const WorldConfig& c) {
  std::string err;
  auto t = make_task(c, err);
  EXPECT_TRUE(t) << err;
  return t;
}

// Mean reward per step over [from, to) for a policy: scripted = fly to the target (action =
// obs[0:3], the position error, since lee_position actions are offsets from the robot), or zero.
std::vector<double> reward_curve(Task& t, bool scripted, int steps) {
  const int n = t.num_envs();
  std::vector<float> a(static_cast<std::size_t>(n) * 4, 0.0f);
  std::vector<double> curve;
  for (int s = 0; s < steps; ++s) {
    if (scripted)
      for (int e = 0; e < n; ++e)
        for (int k = 0; k < 3; ++k) a[static_cast<std::size_t>(e) * 4 + k] = t.observations()[e * t.obs_dim() + k];
    t.step(a.data());
    double m = 0;
    for (int e = 0; e < n; ++e) m += t.rewards()[e];
    curve.push_back(m / n);
  }
  return curve;
}

double mean(const std::vector<double>& v, int from, int to) {
  double s = 0;
  for (int i = from; i < to; ++i) s += v[static_cast<std::size_t>(i)];
  return s / (to - from);
}

}  // namespace

TEST(RewardParity, EveryGoldenCase) {
  ktest::GoldenTol tol = {1e-5, 1e-5};
  const std::vector<RewardCase> cases = load_cases(tol);
  const float abs_tol = static_cast<float>(tol.abs), rel_tol = static_cast<float>(tol.rel);
  int checked = 0, crashed = 0;
  float worst = 0;  // largest |mine - golden| / (abs + rel |golden|): < 1 passes
  for (const RewardCase& c : cases) {
    std::uint8_t crash = c.crashes_in > 0 ? 1 : 0;
    const float r = position_setpoint_reward(c.err_v, c.quat, c.angvel, c.multiplier, crash);
    EXPECT_TRUE(close(r, c.reward, abs_tol, rel_tol)) << "case " << c.id << ": reward " << r << " vs " << c.reward;
    EXPECT_EQ(crash, c.crashes_out > 0 ? 1 : 0) << "case " << c.id;
    worst = std::max(worst, std::fabs(r - c.reward) / (abs_tol + rel_tol * std::fabs(c.reward)));
    crashed += crash;
    // The task's own vehicle-frame error from world position/target/orientation (what step() feeds).
    const float e_w[3] = {c.target[0] - c.pos[0], c.target[1] - c.pos[1], c.target[2] - c.pos[2]};
    float e_v[3];
    vehicle_frame_error(c.quat, e_w, e_v);
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(close(e_v[k], c.err_v[k], 1e-5f, 1e-5f)) << "case " << c.id << " axis " << k;
    std::uint8_t crash2 = c.crashes_in > 0 ? 1 : 0;
    const float r2 = position_setpoint_reward(e_v, c.quat, c.angvel, c.multiplier, crash2);
    EXPECT_TRUE(close(r2, c.reward, abs_tol, rel_tol)) << "case " << c.id << " (from world inputs)";
    EXPECT_EQ(crash2, crash);
    // What the task passes: the world-frame error (only its length enters the reward).
    std::uint8_t crash3 = c.crashes_in > 0 ? 1 : 0;
    const float r3 = position_setpoint_reward(e_w, c.quat, c.angvel, c.multiplier, crash3);
    EXPECT_TRUE(close(r3, c.reward, abs_tol, rel_tol)) << "case " << c.id << " (world-frame error)";
    EXPECT_EQ(crash3, crash);
    ++checked;
  }
  // Any number of cases, but all of them checked, and both outcomes (crash, no crash) present.
  EXPECT_EQ(checked, static_cast<int>(cases.size()));
  EXPECT_GE(crashed, 1);
  EXPECT_GE(checked - crashed, 1);
  std::printf("reward parity: %d cases, %d crashed, worst error %.3f of the tolerance\n", checked, crashed,
              static_cast<double>(worst));
}

TEST(RewardParity, CrashRulesAndConstants) {
  const float q[4] = {0, 0, 0, 1}, w[3] = {0, 0, 0};
  const float at[3] = {0, 0, 0}, far[3] = {8.5f, 0, 0};
  std::uint8_t crash = 0;
  // d = 0, level, still: pos 5, dist 0.5, up 2, spin 3 -> 5 + 0.5 + 5 * 5 = 30.5
  EXPECT_NEAR(position_setpoint_reward(at, q, w, 1.0f, crash), 30.5f, 1e-5f);
  EXPECT_EQ(crash, 0);
  EXPECT_EQ(position_setpoint_reward(far, q, w, 1.0f, crash), -20.0f);
  EXPECT_EQ(crash, 1);
  crash = 1;  // an existing crash stays and forces -20 even at the target
  EXPECT_EQ(position_setpoint_reward(at, q, w, 1.0f, crash), -20.0f);
  EXPECT_EQ(crash, 1);
}

TEST(SimTask, ShapesAndFirstObservation) {
  auto t = build(task_config(8, 3));
  ASSERT_TRUE(t);
  EXPECT_STREQ(t->name(), "position_setpoint_task");
  EXPECT_EQ(t->num_envs(), 8);
  EXPECT_EQ(t->obs_dim(), 13);
  EXPECT_EQ(t->action_dim(), 4);
  for (int e = 0; e < 8; ++e) {
    const float* o = t->observations() + e * 13;
    const RigidBodyState& st = world_of(*t).robot_state(e, 0);
    const Vec3 err = world_of(*t).target(e, 0) - st.position_w;
    for (int k = 0; k < 3; ++k) EXPECT_FLOAT_EQ(o[k], static_cast<float>(err[k]));
    EXPECT_FLOAT_EQ(o[6], static_cast<float>(st.orientation_wb.w()));  // xyzw: w last
    EXPECT_GT(err.norm(), 0.5_r);  // the start is not the target
    EXPECT_LT(err.norm(), 8.0_r);  // inside the crash radius
    EXPECT_EQ(t->rewards()[e], 0.0f);
  }
}

TEST(SimTask, NoHeapInsideStep) {
  WorldConfig c = task_config(16, 5);
  c.task.episode_len_env_steps = 8;  // truncations and their resets inside the counted steps
  auto t = build(c);
  ASSERT_TRUE(t);
  std::vector<float> a(16 * 4, 0.0f);
  t->step(a.data());  // warm-up
  kestrel::test::HeapCounter counter;
  for (int s = 0; s < 20; ++s) t->step(a.data());
  EXPECT_EQ(counter.allocations(), 0u);
}

TEST(SimTask, TruncationAutoResetAndReset) {
  WorldConfig c = task_config(4, 7);
  c.task.episode_len_env_steps = 10;
  auto t = build(c);
  ASSERT_TRUE(t);
  std::vector<float> a(4 * 4, 0.0f);
  std::vector<float> before(t->observations(), t->observations() + 4 * 13);
  for (int s = 1; s <= 10; ++s) {
    t->step(a.data());
    for (int e = 0; e < 4; ++e) {
      EXPECT_EQ(t->terminations()[e], 0) << "hovering in an empty env must not crash";
      EXPECT_EQ(t->truncations()[e], s == 10 ? 1 : 0) << "step " << s;
    }
  }
  // Auto-reset: the returned observation is the new episode's first (a new start, episode step 0).
  for (int e = 0; e < 4; ++e) {
    EXPECT_EQ(world_of(*t).episode_step(e), 0);
    EXPECT_NE(t->observations()[e * 13], before[static_cast<std::size_t>(e) * 13]);
  }
  EXPECT_EQ(t->infos().episodes, 4u);
  EXPECT_EQ(t->infos().truncations, 4u);
  t->step(a.data());
  const int ids[1] = {2};
  t->reset_idx(ids, 1);
  EXPECT_EQ(world_of(*t).episode_step(2), 0);
  EXPECT_EQ(world_of(*t).episode_step(1), 1);
  t->reset();
  for (int e = 0; e < 4; ++e) EXPECT_EQ(world_of(*t).episode_step(e), 0);
}

TEST(SimTask, FarFromTargetTerminatesWithMinus20) {
  auto t = build(task_config(2, 9));
  ASSERT_TRUE(t);
  // Command 10 m away in x every step (clipped offset): the robot leaves the 8 m radius (or the
  // bounds) and the episode terminates with reward -20.
  std::vector<float> a = {10, 0, 0, 0, -10, 0, 0, 0};
  bool seen[2] = {false, false};
  for (int s = 0; s < 400 && !(seen[0] && seen[1]); ++s) {
    t->step(a.data());
    for (int e = 0; e < 2; ++e)
      if (t->terminations()[e]) {
        EXPECT_EQ(t->rewards()[e], -20.0f);
        seen[e] = true;
      }
  }
  EXPECT_TRUE(seen[0] && seen[1]);
  EXPECT_GE(t->infos().terminations, 2u);
}

TEST(SimTask, RewardRisesUnderScriptedPolicyNotUnderZeroActions) {
  // 3 s of flight (300 env-steps of 10 ms) from starts 3-6 m away; episodes (500 steps) do not end.
  auto scripted = build(task_config(32, 11));
  auto zero = build(task_config(32, 11));
  ASSERT_TRUE(scripted && zero);
  const std::vector<double> rs = reward_curve(*scripted, true, 300);
  const std::vector<double> rz = reward_curve(*zero, false, 300);
  const double s_start = mean(rs, 0, 10), s_end = mean(rs, 250, 300);
  const double z_start = mean(rz, 0, 10), z_end = mean(rz, 250, 300);
  // Far from the target the reward is ~(20 - d)/40 < 0.5; at the target, level and still, 30.5.
  std::printf("mean reward, steps 0-9 -> 250-299: scripted %.3f -> %.3f, zero actions %.3f -> %.3f\n", s_start, s_end,
              z_start, z_end);
  EXPECT_GT(s_end, s_start + 10.0) << "scripted: " << s_start << " -> " << s_end;
  EXPECT_LT(z_end, z_start + 0.5) << "zero actions: " << z_start << " -> " << z_end;
  EXPECT_GT(s_end, z_end + 10.0);
  EXPECT_EQ(scripted->infos().terminations, 0u);
}

// Successes are counted as the scripted harness and the Python evaluation count them: an episode
// that runs to its time limit within task.success_radius_m of the target. The scripted policy
// reaches the targets of 300-step episodes; hovering where it starts (zero actions) reaches none.
TEST(SimTask, SuccessesCountTruncationsWithinTheRadius) {
  WorldConfig c = task_config(32, 11);
  c.task.episode_len_env_steps = 300;
  auto scripted = build(c);
  auto zero = build(c);
  ASSERT_TRUE(scripted && zero);
  (void)reward_curve(*scripted, true, 300);
  (void)reward_curve(*zero, false, 300);
  EXPECT_EQ(scripted->infos().episodes, 32u);
  EXPECT_GE(scripted->infos().successes, 24u) << "of 32";
  EXPECT_LE(scripted->infos().successes, scripted->infos().truncations);
  EXPECT_EQ(zero->infos().successes, 0u);
}

// Issue 19: position_setpoint_task's target (the bounds' centre) lies in env_with_obstacles'
// obstacle field; forced to fall back everywhere (no point clears 100 m), the hovering robots end
// every episode at their "target" and none counts as a success; the episodes are counted apart.
TEST(SimTask, FallbackEpisodesAreNeverSuccesses) {
  WorldConfig c = task_config(8, 5);
  EXPECT_TRUE(registries().envs.make("env_with_obstacles", c.env));
  c.env.num_envs = 8;
  c.task.clearance_m = 100;
  c.task.episode_len_env_steps = 50;
  auto t = build(c);
  ASSERT_TRUE(t);
  for (int e = 0; e < 8; ++e) EXPECT_TRUE(t->simulator().placement_fallback(e));
  (void)reward_curve(*t, true, 120);
  const TaskInfos& in = t->infos();
  EXPECT_GT(in.truncations, 0u);
  EXPECT_EQ(in.fallback_episodes, in.episodes);
  EXPECT_EQ(in.real_episodes(), 0u);
  EXPECT_EQ(in.successes, 0u);
  EXPECT_EQ(in.success_rate(), 0.0);
  // The empty environment: every placement is real, the rate is over every episode.
  auto real = build(task_config(8, 5));
  ASSERT_TRUE(real);
  (void)reward_curve(*real, true, 520);
  EXPECT_EQ(real->infos().fallback_episodes, 0u);
  EXPECT_EQ(real->infos().real_episodes(), real->infos().episodes);
  EXPECT_FALSE(real->simulator().placement_fallback(0));
}

// The "reward falls under zero actions". Under lee_position_control a zero action is a
// zero offset ("hold here"), so the reward above stays flat. What a zero action means depends on
// the controller configuration, as in Aerial Gym:
//  - direct_motor_control (Aerial Gym's motor-command configurations, controller "no_control",
//    action = motor thrusts): zero = motors off; the robot falls, hits the floor (crash, -20,
//    auto-reset) and falls again, so the reward falls;
//  - lee_attitude_control (the shipped position_setpoint_task_config): zero = hover thrust
//    (fz = (0 + 1) m |g|), level, zero yaw rate, with no position feedback: from a still start it
//    holds where it is and the reward stays flat, while the task's scripted attitude controller
//    raises it.
static WorldConfig with_controller(WorldConfig c, const char* controller) {
  EXPECT_TRUE(registries().controllers.make(controller, c.controller));
  return c;
}

TEST(SimTask, RewardFallsUnderZeroMotorCommands) {
  auto t = build(with_controller(task_config(32, 11), "direct_motor_control"));
  ASSERT_TRUE(t);
  std::vector<double> z0(32);
  for (int e = 0; e < 32; ++e) z0[static_cast<std::size_t>(e)] = static_cast<double>(world_of(*t).robot_state(e, 0).position_w[2]);
  std::vector<float> scripted(32 * 4);
  EXPECT_FALSE(t->scripted_actions(scripted.data())) << "no scripted controller for motor commands";
  const std::vector<double> r = reward_curve(*t, false, 20);
  // 0.2 s of free fall from rest: every robot has dropped ~0.196 m (none has reached the floor:
  // starts are >= 0.5 m up, contact at 0.2 m).
  for (int e = 0; e < 32; ++e)
    EXPECT_LT(static_cast<double>(world_of(*t).robot_state(e, 0).position_w[2]), z0[static_cast<std::size_t>(e)] - 0.15) << e;
  const std::vector<double> rest = reward_curve(*t, false, 180);
  std::vector<double> all = r;
  all.insert(all.end(), rest.begin(), rest.end());
  const double first = mean(all, 0, 50), last = mean(all, 150, 200);
  std::printf("direct motor commands, zero actions: mean reward first quarter %.4f -> last quarter %.4f, %llu crashes\n", first,
              last, static_cast<unsigned long long>(t->infos().crashes));
  EXPECT_LT(last, first - 0.1) << first << " -> " << last;
  EXPECT_GT(t->infos().crashes, 32u) << "every robot reaches the floor, most more than once";
}

TEST(SimTask, ShippedAttitudeConfigScriptedRisesZeroHovers) {
  auto scripted = build(with_controller(task_config(32, 12), "lee_attitude_control"));
  auto zero = build(with_controller(task_config(32, 12), "lee_attitude_control"));
  ASSERT_TRUE(scripted && zero);
  const std::vector<double> rz = reward_curve(*zero, false, 400);
  std::vector<double> rs;
  std::vector<float> a(32 * 4);
  for (int s = 0; s < 400; ++s) {
    ASSERT_TRUE(scripted->scripted_actions(a.data()));
    scripted->step(a.data());
    double m = 0;
    for (int e = 0; e < 32; ++e) m += scripted->rewards()[e];
    rs.push_back(m / 32);
  }
  const double s_first = mean(rs, 0, 100), s_last = mean(rs, 300, 400);
  const double z_first = mean(rz, 0, 100), z_last = mean(rz, 300, 400);
  std::printf("lee_attitude_control: scripted %.4f -> %.4f, zero actions %.4f -> %.4f (first -> last quarter)\n", s_first,
              s_last, z_first, z_last);
  EXPECT_GT(s_last, s_first + 10.0);
  EXPECT_NEAR(z_last, z_first, 0.01) << "hover thrust, level: the robot stays where it started";
  EXPECT_EQ(zero->infos().terminations, 0u);
  EXPECT_EQ(scripted->infos().terminations, 0u);
}

TEST(SimTask, RegisteredAndUnknownRejected) {
  EXPECT_TRUE(registries().tasks.has("position_setpoint_task"));
  EXPECT_TRUE(is_rl_task("position_setpoint_task"));
  EXPECT_FALSE(is_rl_task("position_setpoint"));
  WorldConfig c = task_config(2, 1);
  c.task.name = "no_such_task";
  std::string err;
  EXPECT_FALSE(make_task(c, err));
  EXPECT_FALSE(err.empty());
  c = task_config(2, 1);
  c.robot.robots_per_env = 2;
  EXPECT_FALSE(make_task(c, err));
}
