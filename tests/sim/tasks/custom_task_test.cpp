// Custom tasks from terms (goal_box_through_gap): terminations at hand-set states, the randomised
// gap (range, movement between resets, determinism per seed, the obstacles in the world), the
// scripted policy succeeding where zero actions and a gap-blind policy do not, observation and
// reward terms, spec errors, registration by id and the scenario path.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "heap_counter.hpp"
#include "kestrel/sim/custom_task.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/scenario.hpp"
#include "task_world.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {

WorldConfig gap_config(int num_envs, std::uint64_t seed, int threads = 2) {
  WorldConfig c;
  std::string err;
  EXPECT_TRUE(load_scenario_string("task: goal_box_through_gap\n", "test", c, err)) << err;
  c.env.num_envs = num_envs;
  c.seed = seed;
  c.num_threads = threads;
  return c;
}

std::unique_ptr<Task> build(const WorldConfig& c) {
  std::string err;
  auto t = make_task(c, err);
  EXPECT_TRUE(t) << err;
  return t;
}

// Puts env's robot at p, level and at rest, through the Simulator (its views follow).
void place(Task& t, int env, const Vec3& p) {
  const real pos[3] = {p[0], p[1], p[2]}, q[4] = {0, 0, 0, 1}, v[3] = {0, 0, 0}, w[3] = {0, 0, 0};
  ASSERT_TRUE(t.simulator().reset_root_states(&env, 1, pos, q, v, w)) << t.simulator().last_error();
}

// The wall halves as obstacles of the world (semantic ids 21 / 22).
bool wall_obstacle(const Task& t, int env, int semantic, Obstacle& out) {
  for (int i = 0; i < world_of(t).num_obstacles(env); ++i)
    if (world_of(t).obstacle(env, i).semantic_id == semantic) {
      out = world_of(t).obstacle(env, i);
      return true;
    }
  return false;
}

}  // namespace

TEST(CustomTask, RegisteredAndSceneFromTheTask) {
  EXPECT_TRUE(custom_tasks().has("goal_box_through_gap"));
  EXPECT_TRUE(registries().tasks.has("goal_box_through_gap"));
  EXPECT_TRUE(is_rl_task("goal_box_through_gap"));
  const WorldConfig c = gap_config(2, 0);
  EXPECT_EQ(c.env.name, "goal_box_room");
  EXPECT_EQ(c.controller.name, "lee_position_control");
  ASSERT_EQ(c.robot.sensors.size(), 1u);
  auto t = build(c);
  ASSERT_TRUE(t);
  EXPECT_STREQ(t->name(), "goal_box_through_gap");
  // gap error 3 + box error 3 + quaternion 4 + v 3 + w 3 + previous actions 4 + 4 x 4 image.
  EXPECT_EQ(t->obs_dim(), 36);
  EXPECT_EQ(t->action_dim(), 4);
  ASSERT_TRUE(custom_task_view(*t));
}

TEST(CustomTask, TerminationsFireExactlyInsideTheBox) {
  auto t = build(gap_config(2, 1));
  ASSERT_TRUE(t);
  const CustomTaskView& v = *custom_task_view(*t);
  const Vec3 box = v.object_centre(0, "goal_box");  // half extents 0.5, floor at z = 0
  EXPECT_NEAR(box[2], 0.5_r, 1e-6_r);
  place(*t, 0, box + Vec3(0, 0, 0.1_r));
  EXPECT_EQ(v.evaluate_terminations(0), 1);
  place(*t, 0, box + Vec3(0.49_r, -0.49_r, 0.49_r));  // corner, z 0.99 above the floor
  EXPECT_EQ(v.evaluate_terminations(0), 1);
  place(*t, 0, box + Vec3(0.51_r, 0, 0));  // x just outside
  EXPECT_EQ(v.evaluate_terminations(0), 0);
  place(*t, 0, box + Vec3(0, 0.51_r, 0));  // y just outside
  EXPECT_EQ(v.evaluate_terminations(0), 0);
  place(*t, 0, box + Vec3(0, 0, 0.51_r));  // 1.01 m above the floor: above the height threshold
  EXPECT_EQ(v.evaluate_terminations(0), 0);
  place(*t, 0, Vec3(0, 0, 6));  // far above the room: out of bounds
  EXPECT_EQ(v.evaluate_terminations(0), 2);

  // Stepped inside the box: success, terminated, reward has the +10 bonus, and auto-reset returns
  // the new episode's first observation.
  place(*t, 0, box + Vec3(0, 0, 0.1_r));
  const std::vector<float> zero(2 * 4, 0.0f);
  t->step(zero.data());
  EXPECT_EQ(t->terminations()[0], 1);
  EXPECT_EQ(t->truncations()[0], 0);
  EXPECT_EQ(t->terminations()[1], 0);
  EXPECT_GT(t->rewards()[0], 9.0f);
  EXPECT_EQ(t->infos().successes, 1u);
  EXPECT_EQ(world_of(*t).episode_step(0), 0);
  const Vec3 p = world_of(*t).robot_state(0, 0).position_w;
  EXPECT_LT(p[0], -2.0_r) << "new start in front of the wall";
  const Vec3 box_err = v.object_centre(0, "goal_box") - p;  // yaw-free start? compare the norm
  const float* o = t->observations();
  EXPECT_NEAR(std::sqrt(o[3] * o[3] + o[4] * o[4] + o[5] * o[5]), static_cast<float>(box_err.norm()), 1e-4f);
  EXPECT_NEAR(o[5], static_cast<float>(box_err[2]), 1e-5f);  // z is the same in the vehicle frame
}

TEST(CustomTask, CrashIntoTheWallAndTimeout) {
  WorldConfig c = gap_config(2, 2);
  c.task.episode_len_env_steps = 20;
  auto t = build(c);
  ASSERT_TRUE(t);
  const CustomTaskView& v = *custom_task_view(*t);
  Obstacle left;
  ASSERT_TRUE(wall_obstacle(*t, 0, 21, left));
  const real inner_edge = left.shape.position_w[1] + left.shape.half_extents_m[1];
  place(*t, 0, Vec3(0, inner_edge - 0.5_r, 1.2_r));  // in the left half of the wall
  EXPECT_EQ(v.evaluate_terminations(0), 0) << "contact is only known after a step";
  const std::vector<float> zero(2 * 4, 0.0f);
  t->step(zero.data());
  EXPECT_EQ(t->terminations()[0], 1);
  EXPECT_EQ(t->infos().crashes, 1u);
  EXPECT_LT(t->rewards()[0], -5.0f);  // the -10 crash term (+ the hand move's "progress", ~2 m)
  for (int s = 1; s < 20; ++s) t->step(zero.data());
  EXPECT_EQ(t->truncations()[1], 1);
  EXPECT_EQ(t->terminations()[1], 0);
  EXPECT_EQ(t->infos().truncations, 1u);
  EXPECT_EQ(t->infos().successes, 0u);
}

TEST(CustomTask, GapIsRandomisedWithinItsRangeAndDeterministic) {
  const int n = 8, resets = 6;
  auto a = build(gap_config(n, 21));
  auto b = build(gap_config(n, 21));
  auto other = build(gap_config(n, 22));
  ASSERT_TRUE(a && b && other);
  const CustomTaskView& va = *custom_task_view(*a);
  const CustomTaskView& vb = *custom_task_view(*b);
  const CustomTaskView& vo = *custom_task_view(*other);
  real min_gap = 10, max_gap = -10, min_w = 10, max_w = -10;
  int moved = 0, differs = 0;
  for (int r = 0; r < resets; ++r) {
    for (int e = 0; e < n; ++e) {
      const Vec3 g = va.object_centre(e, "gap");
      EXPECT_EQ(g, vb.object_centre(e, "gap")) << "same seed, same draws";
      differs += g != vo.object_centre(e, "gap") ? 1 : 0;
      EXPECT_TRUE(g[1] >= -1.2_r && g[1] <= 1.2_r) << g[1];
      EXPECT_EQ(g[0], 0_r);
      // The wall in the world: its halves' inner edges bound the gap, 0.9 .. 1.2 m wide around g.
      Obstacle l, rr;
      ASSERT_TRUE(wall_obstacle(*a, e, 21, l) && wall_obstacle(*a, e, 22, rr));
      const real lo = l.shape.position_w[1] + l.shape.half_extents_m[1];
      const real hi = rr.shape.position_w[1] - rr.shape.half_extents_m[1];
      const real w = hi - lo;
      EXPECT_TRUE(w >= 0.9_r - 1e-5_r && w <= 1.2_r + 1e-5_r) << w;
      EXPECT_NEAR((lo + hi) / 2, g[1], 1e-5_r);
      EXPECT_EQ(l.shape.type, ShapeType::box);
      min_gap = std::min(min_gap, g[1]);
      max_gap = std::max(max_gap, g[1]);
      min_w = std::min(min_w, w);
      max_w = std::max(max_w, w);
      const Vec3 box = va.object_centre(e, "goal_box");
      EXPECT_TRUE(box[1] >= -1.5_r && box[1] <= 1.5_r);
      EXPECT_EQ(box[0], 2.5_r);
    }
    std::vector<Vec3> before(n);
    for (int e = 0; e < n; ++e) before[static_cast<std::size_t>(e)] = va.object_centre(e, "gap");
    a->reset();
    b->reset();
    other->reset();
    for (int e = 0; e < n; ++e) moved += va.object_centre(e, "gap") != before[static_cast<std::size_t>(e)] ? 1 : 0;
  }
  EXPECT_EQ(moved, n * resets) << "every reset draws a new gap";
  EXPECT_GT(differs, n * resets - 2) << "another seed, other gaps";
  EXPECT_LT(min_gap, -0.6_r);  // 48 draws spread over the range
  EXPECT_GT(max_gap, 0.6_r);
  EXPECT_LT(min_w, 1.0_r);
  EXPECT_GT(max_w, 1.1_r);
}

namespace {

// Runs until every environment has finished at least one episode (or max_steps); returns the
// counters. policy: 0 zero, 1 the task's scripted waypoints, 2 straight at the box (ignores the gap).
TaskInfos run_policy(Task& t, int policy, int max_steps) {
  const int n = t.num_envs();
  std::vector<float> a(static_cast<std::size_t>(n) * 4, 0.0f);
  const CustomTaskView& v = *custom_task_view(t);
  for (int s = 0; s < max_steps && t.infos().episodes < static_cast<std::uint64_t>(n); ++s) {
    if (policy == 1) {
      EXPECT_TRUE(t.scripted_actions(a.data()));
    }
    if (policy == 2)
      for (int e = 0; e < n; ++e) {
        Vec3 d = v.object_centre(e, "goal_box") + Vec3(0, 0, 0.1_r) - world_of(t).robot_state(e, 0).position_w;
        if (d.norm() > 1) d /= d.norm();
        for (int k = 0; k < 3; ++k) a[static_cast<std::size_t>(e) * 4 + k] = static_cast<float>(d[k]);
      }
    t.step(a.data());
  }
  return t.infos();
}

}  // namespace

TEST(CustomTask, ScriptedPolicySucceedsZeroAndGapBlindDoNot) {
  const int n = 24;
  auto scripted = build(gap_config(n, 31));
  auto zero = build(gap_config(n, 31));
  auto blind = build(gap_config(n, 31));
  ASSERT_TRUE(scripted && zero && blind);
  const TaskInfos s = run_policy(*scripted, 1, 3000);
  const TaskInfos z = run_policy(*zero, 0, 1500);
  const TaskInfos b = run_policy(*blind, 2, 3000);
  std::printf("goal_box_through_gap: scripted %llu/%llu successes, zero %llu/%llu, gap-blind %llu/%llu (%llu crashes)\n",
              static_cast<unsigned long long>(s.successes), static_cast<unsigned long long>(s.episodes),
              static_cast<unsigned long long>(z.successes), static_cast<unsigned long long>(z.episodes),
              static_cast<unsigned long long>(b.successes), static_cast<unsigned long long>(b.episodes),
              static_cast<unsigned long long>(b.crashes));
  ASSERT_GE(s.episodes, static_cast<std::uint64_t>(n));
  EXPECT_GE(static_cast<double>(s.successes), 0.8 * static_cast<double>(s.episodes));
  EXPECT_GT(s.mean_episode_reward(), 10.0);
  EXPECT_EQ(z.successes, 0u);
  EXPECT_EQ(z.truncations, static_cast<std::uint64_t>(n));
  EXPECT_GT(b.crashes, b.successes) << "flying straight at the box hits the wall";
}

TEST(CustomTask, ObservationAndRewardTerms) {
  auto t = build(gap_config(1, 41));
  ASSERT_TRUE(t);
  const CustomTaskView& v = *custom_task_view(*t);
  place(*t, 0, Vec3(-2, 0.5_r, 1));
  // Hold still for a step (zero offset) and check the terms against the state after it.
  const float zero[4] = {0, 0, 0, 0};
  t->step(zero);
  const RigidBodyState& st = world_of(*t).robot_state(0, 0);
  const float* o = t->observations();
  const Vec3 eg = v.object_centre(0, "gap") - st.position_w;
  const real yaw = std::atan2(2 * (st.orientation_wb.w() * st.orientation_wb.z()), 1 - 2 * st.orientation_wb.z() * st.orientation_wb.z());
  EXPECT_NEAR(o[0], static_cast<float>(std::cos(yaw) * eg[0] + std::sin(yaw) * eg[1]), 1e-3f);
  EXPECT_NEAR(o[2], static_cast<float>(eg[2]), 1e-5f);
  for (int k = 0; k < 4; ++k) EXPECT_FLOAT_EQ(o[6 + k], static_cast<float>(st.orientation_wb.coeffs()[k]));
  for (int k = 16; k < 20; ++k) EXPECT_EQ(o[k], 0.0f);  // previous actions
  // Facing the wall 2 m ahead (yaw 0 at x = -2; the ToF reaches 4 m): some image cells see it.
  const real gy = v.object_centre(0, "gap")[1];
  place(*t, 0, Vec3(-2, gy > 0 ? gy - 2 : gy + 2, 1.2_r));  // in front of a wall half, inside the room
  const float ahead[4] = {0, 0, 0, 0};
  t->step(ahead);
  // The 4 x 4 pool's central cells (+-22.5 deg) see the wall 1.95 m ahead: 1.95 / 4 of the range
  // (the outer cells see the floor closer, 1.2 m below at 45 deg).
  for (int r = 1; r <= 2; ++r)
    for (int col = 1; col <= 2; ++col) EXPECT_NEAR(t->observations()[20 + r * 4 + col], 0.4875f, 0.03f) << r << "," << col;
  // Reward: progress towards the box (+1 per m) minus 0.01 (action change)^2.
  place(*t, 0, Vec3(1.0_r, v.object_centre(0, "goal_box")[1], 1.5_r));
  const float a1[4] = {0.5f, 0, 0, 0};
  t->step(a1);  // previous distance is from the last step (the hand move counts as progress)
  const float a2[4] = {0.5f, 0, 0, 0};
  const real d0 = (v.object_centre(0, "goal_box") - world_of(*t).robot_state(0, 0).position_w).norm();
  t->step(a2);
  const real d1 = (v.object_centre(0, "goal_box") - world_of(*t).robot_state(0, 0).position_w).norm();
  EXPECT_NEAR(t->rewards()[0], static_cast<float>(d0 - d1), 1e-5f);  // same action: no action-rate term
  EXPECT_GT(d0 - d1, 0.0_r);
  const float a3[4] = {0.5f, 0.3f, 0, 0};  // action change 0.3: -0.01 * 0.09
  t->step(a3);
  const real d2 = (v.object_centre(0, "goal_box") - world_of(*t).robot_state(0, 0).position_w).norm();
  EXPECT_NEAR(t->rewards()[0], static_cast<float>(d1 - d2) - 0.0009f, 1e-5f);
}

TEST(CustomTask, NoHeapInsideStep) {
  auto t = build(gap_config(8, 51, 1));
  ASSERT_TRUE(t);
  std::vector<float> a(8 * 4);
  ASSERT_TRUE(t->scripted_actions(a.data()));
  t->step(a.data());
  kestrel::test::HeapCounter counter;
  for (int s = 0; s < 1200; ++s) {  // includes successes and their resets
    (void)t->scripted_actions(a.data());
    t->step(a.data());
  }
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_GT(t->infos().successes, 0u);
}

TEST(CustomTask, SpecErrorsAndUserRegistration) {
  std::string err;
  CustomTaskSpec bad = goal_box_through_gap_spec();
  bad.id = "bad_gap";
  bad.terminations[0].object = "goal_bx";
  EXPECT_FALSE(register_custom_task(bad, err));
  EXPECT_NE(err.find("unknown object 'goal_bx'"), std::string::npos) << err;
  EXPECT_NE(err.find("wall_left, wall_right, gap, goal_box"), std::string::npos) << err;
  EXPECT_FALSE(custom_tasks().has("bad_gap"));
  bad = goal_box_through_gap_spec();
  bad.id = "bad_gap";
  bad.terminations.pop_back();
  EXPECT_FALSE(register_custom_task(bad, err));
  EXPECT_NE(err.find("timeout"), std::string::npos) << err;
  EXPECT_FALSE(register_custom_task(goal_box_through_gap_spec(), err));  // id taken
  EXPECT_NE(err.find("taken"), std::string::npos) << err;

  // A user task: the same scene, a narrower box, registered under a new id and run by id.
  CustomTaskSpec mine = goal_box_through_gap_spec();
  mine.id = "user_small_box";
  mine.objects[3].half_extents_m = Vec3(0.3_r, 0.3_r, 0.5_r);
  ASSERT_TRUE(register_custom_task(mine, err)) << err;
  EXPECT_TRUE(registries().tasks.has("user_small_box"));
  WorldConfig c;
  ASSERT_TRUE(load_scenario_string("task: user_small_box\nenv: {name: goal_box_room, num_envs: 2}\nseed: 3\n", "user.yaml", c, err)) << err;
  auto t = make_task(c, err);
  ASSERT_TRUE(t) << err;
  EXPECT_STREQ(t->name(), "user_small_box");
  EXPECT_NE(rl_task_ids_joined().find("user_small_box"), std::string::npos);

  // Unsupported controller and a missing sensor name the fix.
  WorldConfig d = gap_config(2, 0);
  EXPECT_TRUE(registries().controllers.make("direct_motor_control", d.controller));
  EXPECT_FALSE(make_task(d, err));
  EXPECT_NE(err.find("lee_position_control"), std::string::npos) << err;
  d = gap_config(2, 0);
  d.robot.sensors.clear();
  EXPECT_FALSE(make_task(d, err));
  EXPECT_NE(err.find("ray sensor"), std::string::npos) << err;
  d.task.name = "no_such_task";
  EXPECT_FALSE(make_task(d, err));
  EXPECT_NE(err.find("registered task ids: goal_box_through_gap, locomotion_task, navigation_task, position_setpoint_task"), std::string::npos) << err;
}

TEST(CustomTask, SameResultForAnyThreadCount) {
  auto t1 = build(gap_config(6, 61, 1));
  auto t3 = build(gap_config(6, 61, 3));
  ASSERT_TRUE(t1 && t3);
  std::vector<float> a(6 * 4);
  for (int s = 0; s < 1200; ++s) {
    ASSERT_TRUE(t1->scripted_actions(a.data()));
    t1->step(a.data());
    t3->step(a.data());
  }
  EXPECT_GT(t1->infos().successes, 0u);
  EXPECT_EQ(t1->infos().successes, t3->infos().successes);
  EXPECT_EQ(world_of(*t1).state_hash(), world_of(*t3).state_hash());
  for (int i = 0; i < 6 * t1->obs_dim(); ++i) ASSERT_EQ(t1->observations()[i], t3->observations()[i]) << i;
}
