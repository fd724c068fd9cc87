// Tasks on the planar backend (the tasks of sim/src/tasks/, written once over the Simulator): navigation_task on the fixed-altitude
// multirotor (observation layout with the pooled 2-D lidar, dropped vertical action, success /
// crash / truncation with auto-reset, curriculum, scripted policy beating zero actions, no heap in
// step, thread-count independence), position_setpoint_task on planar, the errors for tasks that do
// not apply there, and make_task(config, Backend::rigid) being the World path.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "heap_counter.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/custom_task.hpp"
#include "kestrel/sim/navigation_task.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/scenario.hpp"
#include "kestrel/sim/simulator.hpp"
#include "task_world.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {

const std::string kScenario = std::string(KESTREL_SIM_TEST_DIR) + "/../../sim/scenarios/planar_navigation_task.yaml";

// The shipped planar navigation scenario (planar_obstacles yard, 128-beam lidar of 5 m).
WorldConfig planar_nav(int num_envs, std::uint64_t seed, int threads = 2) {
  WorldConfig c;
  std::string err;
  EXPECT_TRUE(load_scenario_file(kScenario, c, err)) << err;
  c.env.num_envs = num_envs;
  c.num_threads = threads;
  c.seed = seed;
  return c;
}

std::unique_ptr<Task> build(const WorldConfig& c) {
  std::string err;
  auto t = make_task(c, Backend::planar, err);
  EXPECT_TRUE(t) << err;
  return t;
}

// Puts env's robot at (x, y) at the flight altitude, yaw 0, at rest.
void place(Task& t, int env, real x, real y, real vx = 0) {
  Simulator* s = &t.simulator();
  const real pos[3] = {x, y, s->config().simulator.altitude_m}, q[4] = {0, 0, 0, 1}, v[3] = {vx, 0, 0}, w[3] = {0, 0, 0};
  ASSERT_TRUE(s->reset_root_states(&env, 1, pos, q, v, w)) << s->last_error();
}

float dist_obs(const Task& t, int env) { return t.observations()[env * t.obs_dim() + 3]; }

}  // namespace

TEST(PlanarNavigationTask, ShapesAndFirstObservation) {
  auto t = build(planar_nav(3, 1));
  ASSERT_TRUE(t);
  EXPECT_STREQ(t->name(), "navigation_task");
  EXPECT_STREQ(t->backend_name(), "planar");
  EXPECT_EQ(rigid_world(t->simulator()), nullptr);
  EXPECT_EQ(t->obs_dim(), 81);  // 17 + 8 x 8, as on rigid
  EXPECT_EQ(t->action_dim(), 3);  // forward_inclination
  const Simulator& s = t->simulator();
  ASSERT_EQ(s.lidar_beams(), 128);
  const real range = s.config().simulator.lidar_max_range_m;
  for (int e = 0; e < 3; ++e) {
    const float* o = t->observations() + e * t->obs_dim();
    const real dx = s.target_w()[3 * e] - s.base_pos_w()[3 * e], dy = s.target_w()[3 * e + 1] - s.base_pos_w()[3 * e + 1];
    EXPECT_NEAR(o[3], static_cast<float>(std::sqrt(dx * dx + dy * dy)), 1e-4f);
    EXPECT_GT(o[3], 3.0f);  // the goal is at the far end of the yard
    EXPECT_NEAR(o[0] * o[0] + o[1] * o[1], 1.0f, 1e-5f);
    EXPECT_EQ(o[2], 0.0f);  // at the goal's altitude
    EXPECT_EQ(o[4], 0.0f);  // roll, pitch, yaw slot
    EXPECT_EQ(o[5], 0.0f);
    EXPECT_EQ(o[6], 0.0f);
    for (int k = 13; k < 17; ++k) EXPECT_EQ(o[k], 0.0f);
    // Sector j (column 0 leftmost) is the min of beams 127 - 2j and 126 - 2j over the range.
    const real* r = s.lidar_ranges_m() + e * 128;
    bool some_hit = false;
    for (int j = 0; j < 64; ++j) {
      const real m = std::min(r[127 - 2 * j], r[126 - 2 * j]);
      EXPECT_FLOAT_EQ(o[17 + j], static_cast<float>(std::min(m, range) / range)) << "env " << e << " sector " << j;
      some_hit = some_hit || o[17 + j] < 1.0f;
    }
    EXPECT_TRUE(some_hit);  // the walls and obstacles of the yard are within 5 m somewhere
  }
}

TEST(PlanarNavigationTask, VerticalActionDroppedOthersScaled) {
  auto t = build(planar_nav(1, 2));
  ASSERT_TRUE(t);
  const float a[3] = {3.0f, 0.5f, 0.5f};  // speed clamped to the top; the climb's vertical part dropped
  t->step(a);
  const float* o = t->observations();
  EXPECT_FLOAT_EQ(o[13], 2.0f * std::cos(0.78539816f * 0.5f) * 2.0f / 2.0f);
  EXPECT_FLOAT_EQ(o[14], 0.0f);
  EXPECT_FLOAT_EQ(o[15], 0.0f);
  EXPECT_FLOAT_EQ(o[16], 0.5f * 1.0471976f);
  const Simulator& s = t->simulator();
  EXPECT_FLOAT_EQ(static_cast<float>(s.base_pos_w()[2]), static_cast<float>(s.config().simulator.altitude_m));
}

TEST(PlanarNavigationTask, SuccessCrashAndAutoReset) {
  WorldConfig c = planar_nav(3, 3);
  c.task.episode_len_env_steps = 3;
  auto t = build(c);
  ASSERT_TRUE(t);
  const Simulator& s = t->simulator();
  // env 0 inside the success radius; env 1 far outside the bounds (an exit counts as a crash).
  place(*t, 0, s.target_w()[0] + 0.3_r, s.target_w()[1]);
  place(*t, 1, 40, 40);
  const std::vector<float> zero(3 * 4, 0.0f);
  t->step(zero.data());
  EXPECT_EQ(t->terminations()[0], 0);  // at the goal: the episode goes on (success is counted at the limit)
  EXPECT_GT(t->rewards()[0], 5.0f);
  EXPECT_EQ(t->terminations()[1], 1);
  EXPECT_EQ(t->rewards()[1], -100.0f);
  EXPECT_EQ(t->terminations()[2], 0);
  EXPECT_EQ(t->infos().crashes, 1u);
  EXPECT_EQ(t->infos().episodes, 1u);
  t->step(zero.data());
  t->step(zero.data());  // the limit: env 0 within the radius succeeds, env 2 times out
  EXPECT_EQ(t->truncations()[0], 1);
  EXPECT_EQ(t->truncations()[2], 1);
  EXPECT_EQ(t->infos().successes, 1u);
  EXPECT_EQ(t->infos().crashes, 1u);
  EXPECT_EQ(t->infos().episodes, 3u);
  // The rows of the ended environments are their new episodes' first observations.
  for (int e = 0; e < 2; ++e) {
    const real dx = s.target_w()[3 * e] - s.base_pos_w()[3 * e], dy = s.target_w()[3 * e + 1] - s.base_pos_w()[3 * e + 1];
    EXPECT_NEAR(dist_obs(*t, e), static_cast<float>(std::sqrt(dx * dx + dy * dy)), 1e-4f);
    EXPECT_GT(dist_obs(*t, e), 3.0f);
    EXPECT_LT(std::fabs(s.base_pos_w()[3 * e]), 6.0_r);
  }
}

TEST(PlanarNavigationTask, TruncationAtEpisodeLength) {
  WorldConfig c = planar_nav(3, 4);
  c.task.episode_len_env_steps = 15;
  auto t = build(c);
  ASSERT_TRUE(t);
  const std::vector<float> zero(3 * 4, 0.0f);
  for (int k = 1; k <= 15; ++k) {
    t->step(zero.data());
    for (int e = 0; e < 3; ++e) {
      EXPECT_EQ(t->terminations()[e], 0);
      EXPECT_EQ(t->truncations()[e], k == 15 ? 1 : 0) << "step " << k;
    }
  }
  EXPECT_EQ(t->infos().truncations, 3u);
}

TEST(PlanarNavigationTask, CurriculumFollowsSuccessRate) {
  // Every episode a success (teleported onto the goal at its last step, the time limit): after
  // each window of 4 episodes the level rises by 2 and reaches the planar backend's layouts as the
  // obstacle-count fraction.
  std::string err;
  WorldConfig c = planar_nav(4, 5);
  c.task.episode_len_env_steps = 1;
  NavigationParams p;
  p.curriculum.check_after_episodes = 4;
  auto t = make_navigation_task(c, p, Backend::planar, err);
  ASSERT_TRUE(t) << err;
  const std::vector<float> zero(4 * 4, 0.0f);
  for (int round = 0; round < 2; ++round) {
    for (int e = 0; e < 4; ++e) place(*t, e, t->simulator().target_w()[3 * e], t->simulator().target_w()[3 * e + 1]);
    t->step(zero.data());
  }
  EXPECT_EQ(t->infos().successes, 8u);
  EXPECT_EQ(t->infos().curriculum_level, 4);
  EXPECT_EQ(t->infos().curriculum_changes, 2u);
  EXPECT_FLOAT_EQ(static_cast<float>(t->simulator().config().env.curriculum_level), 0.4f);
}

TEST(PlanarNavigationTask, ScriptedBeatsZero) {
  WorldConfig c = planar_nav(16, 13);
  auto scripted = build(c);
  auto zero = build(c);
  ASSERT_TRUE(scripted && zero);
  std::vector<float> a(16 * 4, 0.0f);
  const std::vector<float> z(16 * 4, 0.0f);
  for (int k = 0; k < 1500; ++k) {
    ASSERT_TRUE(scripted->scripted_actions(a.data()));
    scripted->step(a.data());
    zero->step(z.data());
  }
  std::printf("planar navigation scripted: %llu episodes, %llu successes, %llu crashes; zero: %llu episodes, %llu successes\n",
              static_cast<unsigned long long>(scripted->infos().episodes),
              static_cast<unsigned long long>(scripted->infos().successes),
              static_cast<unsigned long long>(scripted->infos().crashes),
              static_cast<unsigned long long>(zero->infos().episodes),
              static_cast<unsigned long long>(zero->infos().successes));
  EXPECT_GE(scripted->infos().successes, 10u);
  // Zero actions fly forward at 1 m/s; the start faces the goal's end within +-30 degrees, so a
  // straight line through the obstacles now and then arrives.
  EXPECT_LT(zero->infos().success_rate(), 0.25);
  EXPECT_GT(scripted->infos().success_rate(), 0.4);
  EXPECT_GT(scripted->infos().success_rate(), zero->infos().success_rate());
}

TEST(PlanarNavigationTask, NoHeapInsideStep) {
  WorldConfig c = planar_nav(8, 14, 1);
  c.task.episode_len_env_steps = 60;  // resets (truncations at least) inside the counted steps
  auto t = build(c);
  ASSERT_TRUE(t);
  std::vector<float> a(8 * 4, 0.0f);
  for (int k = 0; k < 300; ++k) {  // Box2D's contact and broad-phase pools warm up
    ASSERT_TRUE(t->scripted_actions(a.data()));
    t->step(a.data());
  }
  const std::uint64_t episodes = t->infos().episodes;
  kestrel::test::HeapCounter counter;
  for (int k = 0; k < 200; ++k) {
    (void)t->scripted_actions(a.data());
    t->step(a.data());
  }
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(t->simulator().step_heap_fallbacks(), 0u);
  EXPECT_GE(t->infos().episodes - episodes, 16u);
}

TEST(PlanarNavigationTask, SameResultForAnyThreadCount) {
  auto t1 = build(planar_nav(6, 15, 1));
  auto t2 = build(planar_nav(6, 15, 2));
  ASSERT_TRUE(t1 && t2);
  EXPECT_EQ(t1->num_threads(), 1);
  EXPECT_EQ(t2->num_threads(), 2);
  std::vector<float> a(6 * 4);
  for (int k = 0; k < 600; ++k) {
    ASSERT_TRUE(t1->scripted_actions(a.data()));
    t1->step(a.data());
    t2->step(a.data());
  }
  EXPECT_EQ(t1->state_hash(), t2->state_hash());
  for (int i = 0; i < 6 * t1->obs_dim(); ++i) ASSERT_EQ(t1->observations()[i], t2->observations()[i]) << i;
  EXPECT_EQ(t1->infos().episodes, t2->infos().episodes);
  EXPECT_GT(t1->infos().episodes, 0u);
}

TEST(PlanarPositionSetpointTask, RewardRisesUnderScriptedNotZero) {
  std::string err;
  WorldConfig c;
  ASSERT_TRUE(load_scenario_string("task: position_setpoint_task\nsimulator: planar\nenv: {name: empty, num_envs: 8}\n", "ps.yaml",
                                   c, err))
      << err;
  auto scripted = make_task(c, Backend::planar, err);
  ASSERT_TRUE(scripted) << err;
  auto zero = make_task(c, Backend::planar, err);
  ASSERT_TRUE(zero) << err;
  EXPECT_EQ(scripted->obs_dim(), 13);
  EXPECT_EQ(scripted->observations()[2], 0.0f);  // target at the flight altitude
  std::vector<float> a(8 * 4, 0.0f);
  const std::vector<float> z(8 * 4, 0.0f);
  double first_s = 0, last_s = 0, first_z = 0, last_z = 0;
  for (int k = 0; k < 400; ++k) {
    ASSERT_TRUE(scripted->scripted_actions(a.data()));
    scripted->step(a.data());
    zero->step(z.data());
    for (int e = 0; e < 8; ++e) {
      if (k < 50) first_s += scripted->rewards()[e], first_z += zero->rewards()[e];
      if (k >= 350) last_s += scripted->rewards()[e], last_z += zero->rewards()[e];
      ASSERT_EQ(scripted->observations()[e * 13 + 2], 0.0f);
    }
  }
  EXPECT_GT(last_s, 3 * first_s);           // approaching the target: the reward rises
  EXPECT_LT(last_z, 1.05 * first_z);        // hovering in place: it does not
  EXPECT_GT(last_s, 10 * last_z);
  EXPECT_EQ(scripted->infos().crashes, 0u);
}

TEST(PlanarTasks, ErrorsForTasksThatDoNotApply) {
  std::string err;
  // The worked custom task on the ground vehicle (its actions are [speed, steering]).
  WorldConfig c;
  ASSERT_TRUE(load_scenario_string("task: goal_box_through_gap\nsimulator: {name: planar, vehicle: ground_vehicle}\n", "gb.yaml", c, err)) << err;
  EXPECT_FALSE(make_task(c, Backend::planar, err));
  EXPECT_NE(err.find("simulator planar: task goal_box_through_gap"), std::string::npos) << err;
  EXPECT_NE(err.find("ground vehicle"), std::string::npos) << err;
  // ... and with a controller the fixed-altitude multirotor cannot run for it.
  ASSERT_TRUE(load_scenario_string("task: goal_box_through_gap\ncontroller: lee_attitude_control\n", "gb.yaml", c, err)) << err;
  EXPECT_FALSE(make_task(c, Backend::planar, err));
  EXPECT_NE(err.find("lee_attitude_control is not supported"), std::string::npos) << err;
  EXPECT_NE(err.find("use simulator: rigid"), std::string::npos) << err;
  // The ground vehicle.
  c = planar_nav(2, 1);
  c.simulator.vehicle = PlanarVehicle::ground_vehicle;
  EXPECT_FALSE(make_task(c, Backend::planar, err));
  EXPECT_NE(err.find("ground vehicle"), std::string::npos) << err;
  // navigation_task needs velocity control and enough beams for the 64 sectors.
  c = planar_nav(2, 1);
  ASSERT_TRUE(registries().controllers.make("lee_position_control", c.controller));
  EXPECT_FALSE(make_task(c, Backend::planar, err));
  EXPECT_NE(err.find("lee_velocity_control"), std::string::npos) << err;
  c = planar_nav(2, 1);
  c.simulator.lidar_beams = 32;
  EXPECT_FALSE(make_task(c, Backend::planar, err));
  EXPECT_NE(err.find("lidar_beams (32)"), std::string::npos) << err;
  // position_setpoint_task with a controller the fixed-altitude multirotor cannot run.
  ASSERT_TRUE(load_scenario_string("task: position_setpoint_task\ncontroller: lee_attitude_control\n", "ps.yaml", c, err)) << err;
  EXPECT_FALSE(make_task(c, Backend::planar, err));
  EXPECT_NE(err.find("lee_attitude_control"), std::string::npos) << err;
  // Unknown ids list the registered ones.
  c.task.name = "no_such_task";
  EXPECT_FALSE(make_task(c, Backend::planar, err));
  EXPECT_NE(err.find("registered task ids"), std::string::npos) << err;
}

TEST(PlanarTasks, RigidBackendIsTheWorldPath) {
  std::string err;
  WorldConfig c;
  ASSERT_TRUE(load_scenario_string("task: navigation_task\nenv: {name: env_with_obstacles, num_envs: 3}\n", "nav.yaml", c, err)) << err;
  auto a = make_task(c, err);
  auto b = make_task(c, Backend::rigid, err);
  ASSERT_TRUE(a && b) << err;
  EXPECT_NE(rigid_world(b->simulator()), nullptr);
  EXPECT_STREQ(b->backend_name(), "rigid");
  std::vector<float> act(3 * 4);
  for (int k = 0; k < 50; ++k) {
    ASSERT_TRUE(a->scripted_actions(act.data()));
    a->step(act.data());
    b->step(act.data());
  }
  EXPECT_EQ(a->state_hash(), b->state_hash());
  EXPECT_EQ(a->state_hash(), world_of(*a).state_hash());
}

TEST(PlanarTasks, SimulatorAutoResetOffFlagsButKeepsTheState) {
  // What the tasks rely on: with auto-reset off, an ended episode is flagged in reset_buf and left
  // as it is until reset_idx; env_bounds gives the episode's bounds. Both backends.
  for (const Backend b : {Backend::rigid, Backend::planar}) {
    std::string err;
    WorldConfig c;
    ASSERT_TRUE(load_scenario_string("env: {name: empty, num_envs: 2}\ncontroller: lee_velocity_control\n", "s.yaml", c, err)) << err;
    auto s = make_simulator(c, b, err);
    ASSERT_TRUE(s) << err;
    s->set_auto_reset(false);
    Vec3 lo, hi;
    s->env_bounds(1, lo, hi);
    EXPECT_LT(lo[0], hi[0]);
    const int env = 1;
    const real z = b == Backend::planar ? c.simulator.altitude_m : (lo[2] + hi[2]) / 2;
    const real pos[3] = {hi[0] + 5, (lo[1] + hi[1]) / 2, z}, q[4] = {0, 0, 0, 1}, v[3] = {0, 0, 0}, w[3] = {0, 0, 0};
    ASSERT_TRUE(s->reset_root_states(&env, 1, pos, q, v, w)) << s->last_error();
    std::vector<real> a(static_cast<std::size_t>(s->num_robots() * s->action_dim()), 0);
    s->step(a.data());
    EXPECT_EQ(s->reset_buf()[1], 1) << backend_name(b);
    EXPECT_EQ(s->reset_buf()[0], 0) << backend_name(b);
    EXPECT_GT(s->base_pos_w()[3], hi[0] + 4) << backend_name(b);  // not reset
    s->reset_idx(&env, 1);
    EXPECT_LT(s->base_pos_w()[3], hi[0]) << backend_name(b);
    s->set_auto_reset(true);
    ASSERT_TRUE(s->reset_root_states(&env, 1, pos, q, v, w)) << s->last_error();
    s->step(a.data());
    EXPECT_EQ(s->reset_buf()[1], 1) << backend_name(b);
    EXPECT_LT(s->base_pos_w()[3], hi[0]) << backend_name(b);  // reset inside the step
  }
}

// ---- goal_box_through_gap on planar -------------------------------------------------------------

namespace {

const std::string kGoalBoxScenario = std::string(KESTREL_SIM_TEST_DIR) + "/../../sim/scenarios/planar_goal_box_through_gap.yaml";

WorldConfig planar_goal_box(int num_envs, std::uint64_t seed, int threads = 2) {
  WorldConfig c;
  std::string err;
  EXPECT_TRUE(load_scenario_file(kGoalBoxScenario, c, err)) << err;
  c.env.num_envs = num_envs;
  c.num_threads = threads;
  c.seed = seed;
  return c;
}

// Flies env 0 from (x0, y) along +x with the relative setpoint (+1 m, 0) until x passes x_stop or
// the episode ends; returns the crashes counted.
std::uint64_t fly_along_x(Task& t, real x0, real y, real x_stop) {
  place(t, 0, x0, y);
  std::vector<float> a(static_cast<std::size_t>(t.num_envs()) * 4, 0.0f);
  a[0] = 1.0f;
  const std::uint64_t crashes = t.infos().crashes, episodes = t.infos().episodes;
  for (int k = 0; k < 400; ++k) {
    t.step(a.data());
    if (t.infos().episodes != episodes || t.simulator().base_pos_w()[0] > x_stop) break;
  }
  return t.infos().crashes - crashes;
}

}  // namespace

TEST(PlanarGoalBox, GapMovesWithinItsRangeDeterministically) {
  auto t = build(planar_goal_box(2, 21));
  auto u = build(planar_goal_box(2, 21));
  ASSERT_TRUE(t && u);
  EXPECT_STREQ(t->backend_name(), "planar");
  EXPECT_EQ(t->obs_dim(), 36);  // as on rigid: 3 + 3 + 4 + 3 + 3 + 4 + 4 x 4
  const CustomTaskView* v = custom_task_view(*t);
  const CustomTaskView* w = custom_task_view(*u);
  ASSERT_TRUE(v && w);
  std::vector<real> gaps;
  for (int k = 0; k < 12; ++k) {
    const Vec3 gap = v->object_centre(0, "gap");
    const Vec3 left = v->object_centre(0, "wall_left"), right = v->object_centre(0, "wall_right");
    EXPECT_GE(gap[1], -1.2_r);
    EXPECT_LE(gap[1], 1.2_r);
    EXPECT_EQ(gap[2], 1.2_r);  // the drawn 3-D centre is reported (the terms see it at the altitude)
    const real width = (right[1] - 4) - (left[1] + 4);  // inner edges of the two 8 m halves
    EXPECT_GE(width, 0.9_r - 1e-5_r);
    EXPECT_LE(width, 1.2_r + 1e-5_r);
    EXPECT_NEAR((left[1] + right[1]) / 2, gap[1], 1e-5_r);  // the gap marker is centred between the halves
    EXPECT_EQ(gap[1], w->object_centre(0, "gap")[1]);       // same seed, same draws
    EXPECT_NE(gap[1], v->object_centre(1, "gap")[1]);       // each env its own stream
    // The position error to the gap is horizontal (z 0 at the fixed altitude).
    EXPECT_EQ(t->observations()[2], 0.0f);
    gaps.push_back(gap[1]);
    const int env = 0;
    t->reset_idx(&env, 1);
    u->reset_idx(&env, 1);
  }
  std::sort(gaps.begin(), gaps.end());
  EXPECT_GT(gaps.back() - gaps.front(), 0.8_r);  // it moves between resets
}

TEST(PlanarGoalBox, WallIsSolidAndTheGapOpen) {
  auto t = build(planar_goal_box(1, 22));
  ASSERT_TRUE(t);
  const CustomTaskView* v = custom_task_view(*t);
  ASSERT_TRUE(v);
  // Through the gap: no crash up to 0.8 m behind the wall.
  Vec3 gap = v->object_centre(0, "gap");
  EXPECT_EQ(fly_along_x(*t, -1.0_r, gap[1], 0.8_r), 0u);
  EXPECT_GT(t->simulator().base_pos_w()[0], 0.8_r);
  // At a wall segment 1.8 m beside the gap's centre (at least 1.2 m from its edge): a crash.
  const int env = 0;
  t->reset_idx(&env, 1);
  gap = v->object_centre(0, "gap");
  const real y = gap[1] > 0 ? gap[1] - 1.8_r : gap[1] + 1.8_r;
  EXPECT_EQ(fly_along_x(*t, -1.0_r, y, 0.8_r), 1u);
  EXPECT_EQ(t->infos().crashes, 1u);
}

TEST(PlanarGoalBox, InsideBoxChecksXYOnly) {
  auto t = build(planar_goal_box(1, 23));
  ASSERT_TRUE(t);
  const CustomTaskView* v = custom_task_view(*t);
  ASSERT_TRUE(v);
  const Vec3 box = v->object_centre(0, "goal_box");
  // At 1.2 m the robot is 1.2 m above the box's floor, over the rigid height threshold (1 m): on
  // planar the x / y ranges alone decide.
  place(*t, 0, box[0] + 0.4_r, box[1] - 0.4_r);
  EXPECT_EQ(v->evaluate_terminations(0), 1);
  place(*t, 0, box[0] + 0.6_r, box[1]);
  EXPECT_EQ(v->evaluate_terminations(0), 0);
}

TEST(PlanarGoalBox, ScriptedReachesTheBoxZeroNever) {
  auto s = build(planar_goal_box(8, 24));
  auto z = build(planar_goal_box(8, 24));
  ASSERT_TRUE(s && z);
  std::vector<float> a(8 * 4, 0.0f), zero(8 * 4, 0.0f);
  for (int k = 0; k < 1500; ++k) {
    ASSERT_TRUE(s->scripted_actions(a.data()));
    s->step(a.data());
    z->step(zero.data());
  }
  EXPECT_GE(s->infos().episodes, 8u);
  EXPECT_GE(s->infos().successes * 10, s->infos().episodes * 8);  // most episodes
  EXPECT_GT(s->infos().mean_episode_reward(), 5.0);
  EXPECT_EQ(z->infos().successes, 0u);
  EXPECT_EQ(z->infos().truncations, 8u);  // hovering in front of the wall until the timeout
  EXPECT_EQ(z->infos().crashes, 0u);
}

TEST(PlanarGoalBox, NoHeapInsideStep) {
  WorldConfig c = planar_goal_box(8, 25, 1);
  c.task.episode_len_env_steps = 200;  // resets (wall moves) inside the counted steps
  auto t = build(c);
  ASSERT_TRUE(t);
  std::vector<float> a(8 * 4, 0.0f);
  for (int k = 0; k < 600; ++k) {
    ASSERT_TRUE(t->scripted_actions(a.data()));
    t->step(a.data());
  }
  const std::uint64_t episodes = t->infos().episodes;
  kestrel::test::HeapCounter counter;
  for (int k = 0; k < 400; ++k) {
    (void)t->scripted_actions(a.data());
    t->step(a.data());
  }
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(t->simulator().step_heap_fallbacks(), 0u);
  EXPECT_GE(t->infos().episodes - episodes, 8u);
}

TEST(PlanarGoalBox, SameResultForAnyThreadCount) {
  auto t1 = build(planar_goal_box(6, 26, 1));
  auto t2 = build(planar_goal_box(6, 26, 2));
  ASSERT_TRUE(t1 && t2);
  EXPECT_EQ(t1->num_threads(), 1);
  EXPECT_EQ(t2->num_threads(), 2);
  std::vector<float> a(6 * 4);
  for (int k = 0; k < 900; ++k) {
    ASSERT_TRUE(t1->scripted_actions(a.data()));
    t1->step(a.data());
    t2->step(a.data());
  }
  EXPECT_EQ(t1->state_hash(), t2->state_hash());
  for (int i = 0; i < 6 * t1->obs_dim(); ++i) ASSERT_EQ(t1->observations()[i], t2->observations()[i]) << i;
  EXPECT_EQ(t1->infos().successes, t2->infos().successes);
  EXPECT_GT(t1->infos().successes, 0u);
}

ObstacleBox box(int asset_class, real half_extent_m) {
  ObstacleBox b;
  b.asset_class = asset_class;
  b.half_extents_m = Vec3::Constant(half_extent_m);
  return b;
}

TEST(PlanarGoalBox, SetObstacleBoxRefusals) {
  auto t = build(planar_goal_box(1, 27));
  ASSERT_TRUE(t);
  Simulator* s = &t->simulator();
  EXPECT_FALSE(s->set_obstacle_box(1, box(0, 1)));
  EXPECT_NE(s->last_error().find("env 1 out of range"), std::string::npos) << s->last_error();
  EXPECT_FALSE(s->set_obstacle_box(0, box(0, -1)));
  EXPECT_NE(s->last_error().find("positive finite half extents"), std::string::npos) << s->last_error();
  EXPECT_FALSE(s->set_obstacle_box(0, box(99, 1)));
  EXPECT_NE(s->last_error().find("no obstacle slot"), std::string::npos) << s->last_error();
  std::string err;
  WorldConfig c = planar_goal_box(1, 27);
  c.simulator.lidar_beams = 0;
  auto rigid_task = make_task(c, Backend::rigid, err);  // reserves the objects' box classes
  ASSERT_TRUE(rigid_task) << err;
  Simulator* rigid = &rigid_task->simulator();
  EXPECT_FALSE(rigid->set_obstacle_box(0, box(99, 1)));
  EXPECT_NE(rigid->last_error().find("simulator rigid"), std::string::npos) << rigid->last_error();
  EXPECT_NE(rigid->last_error().find("no obstacle slot"), std::string::npos) << rigid->last_error();
  // On rigid the box is 3-D: the class's first slot gets the centre, the half extents and the yaw.
  World* w = rigid_world(*rigid);
  ASSERT_NE(w, nullptr);
  ASSERT_GT(w->num_obstacles(0), 0);
  const int cls = w->obstacle(0, 0).class_index;
  ObstacleBox b = box(cls, 0.25_r);
  b.center_w = Vec3(1, 2, 1.5_r);
  b.yaw_rad = 0.5_r;
  ASSERT_TRUE(rigid->set_obstacle_box(0, b)) << rigid->last_error();
  int moved = 0;
  for (int i = 0; i < w->num_obstacles(0); ++i) {
    const Obstacle& o = w->obstacle(0, i);
    if (o.class_index == cls && o.shape.type == ShapeType::box && o.shape.position_w == b.center_w &&
        o.shape.half_extents_m == b.half_extents_m && std::fabs(euler_xyz(o.shape.orientation_wb)[2] - 0.5_r) < 1e-5_r)
      ++moved;
  }
  EXPECT_EQ(moved, 1);
}
