// navigation_task: reward against hand-computed values of Aerial Gym's compute_reward, the
// curriculum rule, min-pooling, success / crash / truncation terminations with auto-reset, the
// curriculum moving with the success rate, no heap in step, thread-count independence.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "heap_counter.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/navigation_task.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/scenario.hpp"
#include "task_world.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {

// Empty 10 x 10 x 5 m env (or env_with_obstacles), base quad, lee_velocity_control, ToF 8 x 8.
WorldConfig nav_config(int num_envs, std::uint64_t seed, const char* env = "empty", int threads = 2) {
  WorldConfig c;
  EXPECT_TRUE(registries().envs.make(env, c.env));
  EXPECT_TRUE(registries().tasks.make("navigation_task", c.task));
  EXPECT_TRUE(registries().controllers.make("lee_velocity_control", c.controller));
  SensorConfig tof;
  EXPECT_TRUE(registries().sensors.make("vl53l5cx", tof));
  c.robot.sensors.push_back(tof);
  c.env.num_envs = num_envs;
  c.num_threads = threads;
  c.seed = seed;
  return c;
}

std::unique_ptr<Task> build(const WorldConfig& c, const NavigationParams& p = NavigationParams()) {
  std::string err;
  auto t = make_navigation_task(c, p, err);
  EXPECT_TRUE(t) << err;
  return t;
}

float dist_obs(const Task& t, int env) { return t.observations()[env * t.obs_dim() + 3]; }

}  // namespace

TEST(NavigationReward, HandComputedValues) {
  const NavigationRewardParams p;
  const float e[3] = {3, 4, 0}, e_prev[3] = {3, 4, 1};  // d = 5 from sqrt(26): 0.0990 m closer
  const float a[4] = {1, 0, 0.5f, 0.2f}, a0[4] = {0, 0, 0, 0};
  // pos 5 exp(-25/3.5) = 0.0039525, very close ~0, closer 10 * 0.0990195, (20 - 5)/20 = 0.75;
  // action differences 0.8 (exp(-3.333) - 1) + 0.8 (exp(-0.25 * 5) - 1) + 0.8 (exp(-0.04 * 3.33) - 1) = -1.4420154.
  EXPECT_NEAR(navigation_reward(e, e_prev, false, a, a0, 0.0f, p), 0.30213215f, 2e-5f);
  // progress 0.5: multiplier 2, absolute penalties 0.5 (0.1 (e^-0.3 - 1) + 1.5 (e^-0.25 - 1) + 1.5 (e^-0.08 - 1)).
  EXPECT_NEAR(navigation_reward(e, e_prev, false, a, a0, 0.5f, p), 1.8097585f, 2e-5f);
  // Moving away is punished twice as hard: 20 * (5 - sqrt(26)).
  EXPECT_NEAR(navigation_reward(e_prev, e, false, a0, a0, 0.0f, p), -1.2323711f, 2e-5f);
  // Near the goal, still: 5 exp(-0.25/3.5) + 5 exp(-0.5) + 0.975.
  const float n[3] = {0.3f, 0.4f, 0};
  EXPECT_NEAR(navigation_reward(n, n, false, a0, a0, 0.0f, p), 8.6629672f, 2e-5f);
  EXPECT_EQ(navigation_reward(n, n, true, a0, a0, 0.0f, p), -100.0f);
}

// The clearance term (not the reference's, off by default): -4 at range 0, 0 from clearance_m on.
TEST(NavigationReward, ClearanceTerm) {
  NavigationRewardParams p;
  EXPECT_EQ(navigation_clearance_reward(0.1f, p), 0.0f);  // off by default: the reference's reward
  p.clearance_penalty = -4.0f;
  p.clearance_m = 2.0f;
  EXPECT_FLOAT_EQ(navigation_clearance_reward(0.5f, p), -3.0f);
  EXPECT_FLOAT_EQ(navigation_clearance_reward(0.0f, p), -4.0f);
  EXPECT_FLOAT_EQ(navigation_clearance_reward(1.5f, p), -1.0f);
  EXPECT_EQ(navigation_clearance_reward(2.0f, p), 0.0f);
  EXPECT_EQ(navigation_clearance_reward(7.0f, p), 0.0f);
  EXPECT_EQ(navigation_clearance_reward(std::nanf(""), p), 0.0f);
}

// The sideslip term (not the reference's, off by default): sideslip_penalty x |v_y|.
TEST(NavigationReward, SideslipTerm) {
  NavigationRewardParams p;
  EXPECT_EQ(navigation_sideslip_reward(0.7f, p), 0.0f);  // off by default: the reference's reward
  p.sideslip_penalty = -2.0f;
  EXPECT_FLOAT_EQ(navigation_sideslip_reward(0.5f, p), -1.0f);
  EXPECT_FLOAT_EQ(navigation_sideslip_reward(-0.5f, p), -1.0f);  // either side
  EXPECT_EQ(navigation_sideslip_reward(0.0f, p), 0.0f);
  EXPECT_EQ(navigation_sideslip_reward(std::nanf(""), p), 0.0f);
}

TEST(NavigationReward, CurriculumRule) {
  NavigationCurriculum c;  // 0..10, +2 above 0.7, -1 below 0.6
  EXPECT_EQ(next_curriculum_level(c, 0.71, 3), 5);
  EXPECT_EQ(next_curriculum_level(c, 0.70, 3), 3);  // strictly above
  EXPECT_EQ(next_curriculum_level(c, 0.65, 3), 3);
  EXPECT_EQ(next_curriculum_level(c, 0.59, 3), 2);
  EXPECT_EQ(next_curriculum_level(c, 1.0, 9), 10);   // clamped
  EXPECT_EQ(next_curriculum_level(c, 0.0, 0), 0);
}

TEST(NavigationTask, MinPoolRanges) {
  // 4 x 4 image, max range 4 m: blocks of 2 x 2; -1 (no return) and NaN count as max range.
  const real nan = std::numeric_limits<real>::quiet_NaN();
  const real img[16] = {1, 2, 4, 4,   //
                        3, 0.5_r, -1, 3,  //
                        -1, -1, 8, nan,   //
                        -1, -1, 2, 2};
  float out[4];
  min_pool_ranges(img, 4, 4, 4, 2, 2, out);
  EXPECT_FLOAT_EQ(out[0], 0.125f);  // 0.5 / 4
  EXPECT_FLOAT_EQ(out[1], 0.75f);   // 3 / 4
  EXPECT_FLOAT_EQ(out[2], 1.0f);    // nothing seen
  EXPECT_FLOAT_EQ(out[3], 0.5f);    // 2 / 4 (8 is beyond range)
  // Uneven split: 3 rows into 2 cells -> rows {0}, {1, 2}.
  const real col[3] = {2, 1, 3};
  float o2[2];
  min_pool_ranges(col, 3, 1, 4, 2, 1, o2);
  EXPECT_FLOAT_EQ(o2[0], 0.5f);
  EXPECT_FLOAT_EQ(o2[1], 0.25f);
}

TEST(NavigationTask, ShapesAndFirstObservation) {
  auto t = build(nav_config(4, 3));
  ASSERT_TRUE(t);
  EXPECT_STREQ(t->name(), "navigation_task");
  EXPECT_EQ(t->obs_dim(), 17 + 64);
  EXPECT_EQ(t->action_dim(), 3);  // forward_inclination, the reference's action space
  for (int e = 0; e < 4; ++e) {
    const float* o = t->observations() + e * t->obs_dim();
    const RigidBodyState& st = world_of(*t).robot_state(e, 0);
    const real d = (world_of(*t).target(e, 0) - st.position_w).norm();
    EXPECT_NEAR(o[3], static_cast<float>(d), 1e-4f);
    EXPECT_NEAR(std::sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]), 1.0f, 1e-5f);
    EXPECT_GT(d, 5.0_r);  // goal ratio x 0.90..0.94, start 0.1..0.2 of 10 m
    for (int k = 13; k < 17; ++k) EXPECT_EQ(o[k], 0.0f);
    for (int k = 17; k < t->obs_dim(); ++k) EXPECT_TRUE(o[k] >= 0.0f && o[k] <= 1.0f);
    // Goal inside the bounds' ratio box.
    Vec3 lo, hi;
    world_of(*t).lower_upper_bounds(e, lo, hi);
    const Vec3 r = (world_of(*t).target(e, 0) - lo).cwiseQuotient(hi - lo);
    EXPECT_TRUE(r[0] >= 0.9_r - 1e-5_r && r[0] <= 0.94_r + 1e-5_r) << r.transpose();
    EXPECT_TRUE(r[1] >= 0.1_r - 1e-5_r && r[1] <= 0.9_r + 1e-5_r);
  }
}

TEST(NavigationTask, ImageSeesTheGroundWhenPitchedDown) {
  // The ToF looks along body x; pitched 80 deg nose-down 1 m above the floor the centre cells see
  // the ground at ~1 m (0.25 of its 4 m range); level at 4.5 m it sees nothing (1.0).
  auto t = build(nav_config(1, 5));
  ASSERT_TRUE(t);
  RigidBodyState& st = world_of(*t).robot_state(0, 0);
  st.position_w = Vec3(0, 0, 1);
  st.orientation_wb = quat_from_euler_xyz(0, 80 * kPi / 180, 0);
  world_of(*t).render_sensors(0);
  std::vector<float> pool(64);
  min_pool_ranges(world_of(*t).sensor_ranges(0, 0), world_of(*t).sensor_height(0), world_of(*t).sensor_width(0), 4, 8, 8, pool.data());
  float mn = 1;
  for (float v : pool) mn = std::min(mn, v);
  EXPECT_NEAR(mn, 0.25f, 0.05f);
  st.orientation_wb = Quat::Identity();
  st.position_w = Vec3(0, 0, 4.5_r);  // level, high: the 45 deg lower edge meets the floor 6.4 m away
  world_of(*t).render_sensors(0);
  min_pool_ranges(world_of(*t).sensor_ranges(0, 0), world_of(*t).sensor_height(0), world_of(*t).sensor_width(0), 4, 8, 8, pool.data());
  for (float v : pool) EXPECT_EQ(v, 1.0f);
}

// With clearance_penalty set, a robot whose ToF sees the floor 1 m away gets the clearance term
// of its nearest ray on top of the reference's reward; the same step without it does not.
TEST(NavigationTask, ClearancePenaltyFromTheNearestRay) {
  NavigationParams with;
  with.reward.clearance_penalty = -4;
  with.reward.clearance_m = 4;
  auto a = build(nav_config(2, 5));
  auto b = build(nav_config(2, 5), with);
  ASSERT_TRUE(a && b);
  for (Task* t : {a.get(), b.get()}) {
    RigidBodyState& st = world_of(*t).robot_state(0, 0);
    st.position_w = Vec3(0, 0, 1);
    st.orientation_wb = quat_from_euler_xyz(0, 80 * kPi / 180, 0);  // nose down: the floor ~1 m ahead
  }
  const std::vector<float> zero(2 * 3, 0.0f);
  a->step(zero.data());
  b->step(zero.data());
  ASSERT_EQ(a->terminations()[0], 0);
  const real* ranges = world_of(*b).sensor_ranges(0, 0);
  real nearest = 4;
  for (int k = 0; k < world_of(*b).sensor_height(0) * world_of(*b).sensor_width(0); ++k)
    if (ranges[k] >= 0) nearest = std::min(nearest, ranges[k]);
  EXPECT_LT(nearest, 1.5_r);
  EXPECT_GT(nearest, 0.5_r);
  const float term = navigation_clearance_reward(static_cast<float>(nearest), with.reward);
  EXPECT_LT(term, -2.0f);
  EXPECT_FLOAT_EQ(b->rewards()[0], a->rewards()[0] + term);  // the task's range went through the image's normalisation
}

// With sideslip_penalty set, a robot drifting sideways gets the sideslip term of its body-frame
// v_y after the step on top of the reference's reward; the same step without it does not.
TEST(NavigationTask, SideslipPenaltyFromTheBodyVelocity) {
  NavigationParams with;
  with.reward.sideslip_penalty = -3;
  auto a = build(nav_config(2, 5));
  auto b = build(nav_config(2, 5), with);
  ASSERT_TRUE(a && b);
  for (Task* t : {a.get(), b.get()}) {
    RigidBodyState& st = world_of(*t).robot_state(0, 0);
    st.position_w = Vec3(0, 0, 1.5_r);
    st.orientation_wb = Quat::Identity();
    st.linvel_w = Vec3(0, 1.2_r, 0);  // sideways (body +y)
  }
  const std::vector<float> zero(2 * 3, 0.0f);
  a->step(zero.data());
  b->step(zero.data());
  ASSERT_EQ(a->terminations()[0], 0);
  const real v_y = b->simulator().base_lin_vel_b()[1];  // body frame, after the step
  EXPECT_GT(v_y, 0.5_r);  // still drifting one env-step later
  const float term = navigation_sideslip_reward(static_cast<float>(v_y), with.reward);
  EXPECT_LT(term, -1.5f);
  EXPECT_FLOAT_EQ(b->rewards()[0], a->rewards()[0] + term);
}

// The reference's episode end: arriving does not end the episode; at the time limit an episode
// within the success radius is a success, the others time out; the ended rows auto-reset.
TEST(NavigationTask, SuccessIsCountedAtTheTimeLimit) {
  WorldConfig c = nav_config(2, 7);
  c.task.episode_len_env_steps = 5;
  auto t = build(c);
  ASSERT_TRUE(t);
  const Vec3 goal = world_of(*t).target(0, 0);
  world_of(*t).robot_state(0, 0).position_w = goal + Vec3(0.3_r, 0, 0);  // inside the 1 m radius
  const std::vector<float> zero(2 * 4, 0.0f);
  for (int k = 1; k <= 4; ++k) {
    t->step(zero.data());
    EXPECT_EQ(t->terminations()[0], 0) << k;  // at the goal, still flying
    EXPECT_EQ(t->truncations()[0], 0) << k;
    EXPECT_GT(t->rewards()[0], 5.0f);  // the proximity terms keep paying
  }
  EXPECT_EQ(t->infos().episodes, 0u);
  t->step(zero.data());
  EXPECT_EQ(t->terminations()[0], 0);
  EXPECT_EQ(t->truncations()[0], 1);
  EXPECT_EQ(t->truncations()[1], 1);
  EXPECT_EQ(t->infos().successes, 1u);  // env 0 within the radius at the limit; env 1 timed out
  EXPECT_EQ(t->infos().crashes, 0u);
  EXPECT_EQ(t->infos().truncations, 2u);
  EXPECT_EQ(t->infos().terminations, 0u);
  EXPECT_EQ(t->infos().episodes, 2u);
  EXPECT_DOUBLE_EQ(t->infos().success_rate(), 0.5);
  // The returned row is the new episode's first observation.
  EXPECT_EQ(world_of(*t).episode_step(0), 0);
  const real d_new = (world_of(*t).target(0, 0) - world_of(*t).robot_state(0, 0).position_w).norm();
  EXPECT_NEAR(dist_obs(*t, 0), static_cast<float>(d_new), 1e-4f);
  EXPECT_GT(d_new, 5.0_r);
}

TEST(NavigationTask, CrashGivesCollisionPenalty) {
  auto t = build(nav_config(2, 8));
  ASSERT_TRUE(t);
  world_of(*t).robot_state(1, 0).position_w[2] = 0.05_r;  // into the ground plane
  const std::vector<float> zero(2 * 4, 0.0f);
  t->step(zero.data());
  EXPECT_EQ(t->terminations()[1], 1);
  EXPECT_EQ(t->rewards()[1], -100.0f);
  EXPECT_EQ(t->terminations()[0], 0);
  EXPECT_EQ(t->infos().crashes, 1u);
  EXPECT_EQ(t->infos().successes, 0u);
  EXPECT_EQ(world_of(*t).episode_step(1), 0);
  EXPECT_EQ(world_of(*t).episode_step(0), 1);
}

TEST(NavigationTask, TruncationAtEpisodeLength) {
  WorldConfig c = nav_config(3, 9);
  c.task.episode_len_env_steps = 15;
  auto t = build(c);
  ASSERT_TRUE(t);
  const std::vector<float> zero(3 * 4, 0.0f);
  for (int s = 1; s <= 15; ++s) {
    t->step(zero.data());
    for (int e = 0; e < 3; ++e) {
      EXPECT_EQ(t->terminations()[e], 0);
      EXPECT_EQ(t->truncations()[e], s == 15 ? 1 : 0) << "step " << s;
    }
  }
  EXPECT_EQ(t->infos().truncations, 3u);
  EXPECT_EQ(t->infos().successes, 0u);
}

// The reference's action_transformation_function: speed (a0 + 1) / 2 x max along the heading,
// tilted by a1 x pi/4, yaw rate a2 x pi/3; never sideways. A NaN action is 0 (half speed level).
TEST(NavigationTask, ForwardInclinationActions) {
  auto t = build(nav_config(1, 10));
  ASSERT_TRUE(t);
  ASSERT_EQ(t->action_dim(), 3);
  const float a[3] = {1.0f, 0.5f, -2.0f};  // yaw clamped to -1
  t->step(a);
  const real* w = world_of(*t).action(0, 0);
  const float climb = 0.78539816f * 0.5f;
  EXPECT_FLOAT_EQ(static_cast<float>(w[0]), 2.0f * std::cos(climb) * 2.0f / 2.0f);
  EXPECT_EQ(w[1], 0_r);
  EXPECT_FLOAT_EQ(static_cast<float>(w[2]), 2.0f * std::sin(climb) * 2.0f / 2.0f);
  EXPECT_FLOAT_EQ(static_cast<float>(w[3]), -1.0471976f);
  EXPECT_NEAR(static_cast<float>(w[0] * w[0] + w[2] * w[2]), 4.0f, 1e-5f);  // the top speed, 2 m/s
  EXPECT_FLOAT_EQ(t->observations()[13], static_cast<float>(w[0]));  // the command in the observation
  const float stop[3] = {-1.0f, 1.0f, 0.0f};
  t->step(stop);
  EXPECT_EQ(world_of(*t).action(0, 0)[0], 0_r);
  EXPECT_EQ(world_of(*t).action(0, 0)[2], 0_r);
  const float bad[3] = {std::nanf(""), std::nanf(""), std::nanf("")};
  t->step(bad);
  EXPECT_FLOAT_EQ(static_cast<float>(world_of(*t).action(0, 0)[0]), 1.0f);
  EXPECT_EQ(world_of(*t).action(0, 0)[2], 0_r);
  EXPECT_EQ(world_of(*t).action(0, 0)[3], 0_r);
}

TEST(NavigationTask, ActionsAreScaledVelocityCommands) {
  NavigationParams p;
  p.action_space = NavigationActionSpace::velocity;
  auto t = build(nav_config(1, 10), p);
  ASSERT_TRUE(t);
  ASSERT_EQ(t->action_dim(), 4);
  const float a[4] = {3.0f, -0.25f, 0.5f, 0.5f};  // x clamped to 1
  t->step(a);
  const real* w = world_of(*t).action(0, 0);
  EXPECT_FLOAT_EQ(static_cast<float>(w[0]), 2.0f);
  EXPECT_FLOAT_EQ(static_cast<float>(w[1]), -0.5f);
  EXPECT_FLOAT_EQ(static_cast<float>(w[2]), 1.0f);
  EXPECT_NEAR(static_cast<float>(w[3]), 0.5f * 1.0471976f, 1e-6f);
  const float* o = t->observations();
  EXPECT_FLOAT_EQ(o[13], 2.0f);  // the robot's (transformed) actions
  EXPECT_FLOAT_EQ(o[14], -0.5f);
  const float bad[4] = {std::nanf(""), 0, 0, 0};
  t->step(bad);
  EXPECT_EQ(world_of(*t).action(0, 0)[0], 0_r);
}

TEST(NavigationTask, CurriculumFollowsSuccessRate) {
  // Zero actions never succeed: every window of 6 timeouts lowers the level by 1.
  {
    WorldConfig c = nav_config(6, 11, "env_with_obstacles");
    c.task.episode_len_env_steps = 10;
    NavigationParams p;
    p.curriculum.start_level = 5;
    p.curriculum.check_after_episodes = 6;
    auto t = build(c, p);
    ASSERT_TRUE(t);
    EXPECT_FLOAT_EQ(static_cast<float>(world_of(*t).data().curriculum_level), 0.5f);
    const std::vector<float> zero(6 * 4, 0.0f);
    for (int s = 0; s < 30; ++s) t->step(zero.data());
    EXPECT_EQ(t->infos().curriculum_level, 2);  // three windows
    EXPECT_EQ(t->infos().curriculum_changes, 3u);
    EXPECT_FLOAT_EQ(static_cast<float>(world_of(*t).data().curriculum_level), 0.2f);
  }
  // The scripted policy in the empty env succeeds: the level rises by 2 per window.
  {
    WorldConfig c = nav_config(8, 12);
    c.task.episode_len_env_steps = 800;
    NavigationParams p;
    p.curriculum.check_after_episodes = 8;
    auto t = build(c, p);
    ASSERT_TRUE(t);
    std::vector<float> a(8 * 4);
    while (t->infos().episodes < 8) {
      ASSERT_TRUE(t->scripted_actions(a.data()));
      t->step(a.data());
      ASSERT_LT(t->infos().steps, 2000u);
    }
    EXPECT_EQ(t->infos().successes, 8u);
    EXPECT_EQ(t->infos().curriculum_level, 2);
    EXPECT_FLOAT_EQ(static_cast<float>(world_of(*t).data().curriculum_level), 0.2f);
  }
}

TEST(NavigationTask, ScriptedBeatsZeroInObstacles) {
  WorldConfig c = nav_config(16, 13, "env_with_obstacles");
  c.task.episode_len_env_steps = 1000;  // the default: successes are counted at the limit
  auto scripted = build(c);
  auto zero = build(c);
  ASSERT_TRUE(scripted && zero);
  std::vector<float> a(16 * 4, 0.0f);
  const std::vector<float> z(16 * 4, 0.0f);
  for (int s = 0; s < 1000; ++s) {
    ASSERT_TRUE(scripted->scripted_actions(a.data()));
    scripted->step(a.data());
    zero->step(z.data());
  }
  std::printf("navigation scripted: %llu episodes, %llu successes, %llu crashes; zero: %llu successes\n",
              static_cast<unsigned long long>(scripted->infos().episodes),
              static_cast<unsigned long long>(scripted->infos().successes),
              static_cast<unsigned long long>(scripted->infos().crashes),
              static_cast<unsigned long long>(zero->infos().successes));
  EXPECT_GE(scripted->infos().successes, 6u);
  EXPECT_EQ(zero->infos().successes, 0u);
}

TEST(NavigationTask, NoHeapInsideStep) {
  WorldConfig c = nav_config(8, 14, "env_with_obstacles", 1);
  c.task.episode_len_env_steps = 60;  // resets (truncations at least) inside the counted steps
  auto t = build(c);
  ASSERT_TRUE(t);
  std::vector<float> a(8 * 4, 0.0f);
  for (int s = 0; s < 5; ++s) {
    ASSERT_TRUE(t->scripted_actions(a.data()));
    t->step(a.data());
  }
  kestrel::test::HeapCounter counter;
  for (int s = 0; s < 200; ++s) {
    (void)t->scripted_actions(a.data());
    t->step(a.data());
  }
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_GE(t->infos().episodes, 16u);
}

TEST(NavigationTask, SameResultForAnyThreadCount) {
  auto t1 = build(nav_config(6, 15, "env_with_obstacles", 1));
  auto t3 = build(nav_config(6, 15, "env_with_obstacles", 3));
  ASSERT_TRUE(t1 && t3);
  std::vector<float> a(6 * 4);
  for (int s = 0; s < 300; ++s) {
    ASSERT_TRUE(t1->scripted_actions(a.data()));
    t1->step(a.data());
    t3->step(a.data());
  }
  EXPECT_EQ(world_of(*t1).state_hash(), world_of(*t3).state_hash());
  for (int i = 0; i < 6 * t1->obs_dim(); ++i) ASSERT_EQ(t1->observations()[i], t3->observations()[i]) << i;
  EXPECT_EQ(t1->infos().episodes, t3->infos().episodes);
}

TEST(NavigationTask, ErrorsAndScenario) {
  std::string err;
  WorldConfig c = nav_config(2, 1);
  c.robot.sensors.clear();
  EXPECT_FALSE(make_navigation_task(c, NavigationParams(), err));
  EXPECT_NE(err.find("ray sensor"), std::string::npos) << err;
  c = nav_config(2, 1);
  EXPECT_TRUE(registries().controllers.make("lee_position_control", c.controller));
  EXPECT_FALSE(make_task(c, err));
  EXPECT_NE(err.find("lee_velocity_control"), std::string::npos) << err;
  // A scenario naming only the task gets the task's scene (env_with_obstacles, velocity control, ToF).
  WorldConfig s;
  ASSERT_TRUE(load_scenario_string("task: navigation_task\nenv: {name: env_with_obstacles, num_envs: 3}\n", "nav.yaml", s, err)) << err;
  EXPECT_EQ(s.controller.name, "lee_velocity_control");
  ASSERT_EQ(s.robot.sensors.size(), 1u);
  EXPECT_EQ(s.robot.sensors[0].name, "vl53l5cx");
  auto t = make_task(s, err);
  ASSERT_TRUE(t) << err;
  EXPECT_STREQ(t->name(), "navigation_task");
  EXPECT_EQ(t->num_envs(), 3);
}

// A scenario naming only the task starts its robots as the reference does (the init_config of
// Aerial Gym's robot configs): x 0.1-0.2 and y, z 0.15-0.85 of the bounds, yaw within +-pi/6,
// each world-frame velocity component and angular rate within +-0.2. A robot section of the
// scenario's own replaces that start: the registered base_quadrotor faces any way, at rest.
TEST(NavigationTask, StartsAsTheReferenceUnlessTheScenarioNamesARobot) {
  constexpr int kEnvs = 64;
  const std::string env = "env: {name: env_with_obstacles, num_envs: 64}\n";
  for (const bool own_robot : {false, true}) {
    std::string err;
    WorldConfig s;
    ASSERT_TRUE(load_scenario_string(std::string("task: navigation_task\n") + (own_robot ? "robot: base_quadrotor\n" : "") + env,
                                     "nav.yaml", s, err))
        << err;
    auto t = make_task(s, err);
    ASSERT_TRUE(t) << err;
    const World& w = world_of(*t);
    real max_yaw = 0, max_v = 0, max_w = 0;
    int checked = 0;
    for (int e = 0; e < kEnvs; ++e) {
      const RigidBodyState& st = w.robot_state(e, 0);
      const Quat& q = st.orientation_wb;
      max_yaw = std::max(max_yaw, std::fabs(std::atan2(2 * (q.w() * q.z() + q.x() * q.y()), 1 - 2 * (q.y() * q.y() + q.z() * q.z()))));
      const Vec3 w_w = rotate(q, st.angvel_b);
      max_v = std::max(max_v, st.linvel_w.cwiseAbs().maxCoeff());
      max_w = std::max(max_w, w_w.cwiseAbs().maxCoeff());
      if (own_robot || w.data().episode_fallback[static_cast<std::size_t>(e)] != 0) continue;
      const Vec3 lo = w.data().lower_w[e], hi = w.data().upper_w[e];
      const Vec3 ratio = (st.position_w - lo).cwiseQuotient(hi - lo);
      EXPECT_GE(ratio[0], 0.1_r - 1e-5_r) << e;
      EXPECT_LE(ratio[0], 0.2_r + 1e-5_r) << e;
      for (int k = 1; k < 3; ++k) {
        EXPECT_GE(ratio[k], 0.15_r - 1e-5_r) << e << " axis " << k;
        EXPECT_LE(ratio[k], 0.85_r + 1e-5_r) << e << " axis " << k;
      }
      ++checked;
    }
    if (own_robot) {
      EXPECT_GT(max_yaw, 1.5_r);  // 64 draws in +-pi
      EXPECT_EQ(max_v, 0_r);
      EXPECT_EQ(max_w, 0_r);
    } else {
      EXPECT_EQ(s.robot.name, "base_quadrotor");
      EXPECT_GT(checked, kEnvs / 2);
      EXPECT_GT(max_yaw, 0.4_r);
      EXPECT_LE(max_yaw, static_cast<real>(kPi / 6) + 1e-5_r);
      EXPECT_GT(max_v, 0.15_r);
      EXPECT_LE(max_v, 0.2_r);
      EXPECT_GT(max_w, 0.15_r);
      EXPECT_LE(max_w, 0.2_r + 1e-5_r);
    }
  }
  std::string err;
  WorldConfig s;
  EXPECT_FALSE(load_scenario_string("robot: {name: base_quadrotor, max_init_linvel_m_s: -0.2}\n", "nav.yaml", s, err));
  EXPECT_NE(err.find("robot.max_init_linvel_m_s"), std::string::npos) << err;
}

// task.navigation.image_encoding proximity: the same run as the range encoding (the state, the
// rewards, the scripted actions, which read range cells either way), each image cell the
// proximity 1 / (1 + r / scale) of the range cell's r; an unknown encoding is refused by name.
TEST(NavigationTask, ProximityEncodingOfTheImage) {
  std::string err;
  std::unique_ptr<Task> t[2];
  for (int k = 0; k < 2; ++k) {
    WorldConfig s;
    ASSERT_TRUE(load_scenario_string(std::string("task: {name: navigation_task, navigation: {image_encoding: ") + (k ? "proximity" : "range") +
                                         ", proximity_scale_m: 0.4}}\nenv: {name: env_with_obstacles, num_envs: 4}\n",
                                     "nav.yaml", s, err))
        << err;
    t[k] = make_task(s, err);
    ASSERT_TRUE(t[k]) << err;
  }
  const int od = t[0]->obs_dim(), n = t[0]->num_envs();
  ASSERT_EQ(t[1]->obs_dim(), od);
  const float max_range = static_cast<float>(t[0]->simulator().range_image(0, 0).max_range_m);
  std::vector<float> a0(static_cast<std::size_t>(n * t[0]->action_dim())), a1(a0.size());
  int near_cells = 0;
  for (int step = 0; step < 40; ++step) {
    ASSERT_TRUE(t[0]->scripted_actions(a0.data()));
    ASSERT_TRUE(t[1]->scripted_actions(a1.data()));
    ASSERT_EQ(a0, a1) << step;
    for (int e = 0; e < n; ++e) {
      const float* o0 = t[0]->observations() + e * od;
      const float* o1 = t[1]->observations() + e * od;
      for (int c = 0; c < 17; ++c) ASSERT_EQ(o0[c], o1[c]) << step << " " << e << " " << c;
      for (int c = 17; c < od; ++c) {
        const float want = 1.0f / (1.0f + o0[c] * (max_range / 0.4f));
        ASSERT_NEAR(o1[c], want, 1e-6f) << step << " " << e << " " << c;
        near_cells += o1[c] > 0.2f;  // nearer than 1.6 m
      }
      ASSERT_EQ(t[0]->rewards()[e], t[1]->rewards()[e]);
    }
    t[0]->step(a0.data());
    t[1]->step(a1.data());
  }
  EXPECT_GT(near_cells, 0);
  WorldConfig s;
  EXPECT_FALSE(load_scenario_string("task: {name: navigation_task, navigation: {image_encoding: inverse}}\n", "nav.yaml", s, err));
  EXPECT_NE(err.find("task.navigation.image_encoding"), std::string::npos) << err;
  EXPECT_NE(err.find("range, proximity"), std::string::npos) << err;
}

// task.navigation.image_history_frames: after the task's own observation (the same bits as without
// a history, which changes nothing else), the image cells of lag and 2 lag env-steps before, the
// episode's first image where the episode is younger; a reset environment's history is its new
// first image. Checked against the observations recorded along the way, across auto-resets.
TEST(NavigationTask, ImageHistoryOfEarlierFrames) {
  constexpr int kFrames = 2, kLag = 3;
  std::string err;
  std::unique_ptr<Task> t[2];
  for (int k = 0; k < 2; ++k) {
    WorldConfig s;
    ASSERT_TRUE(load_scenario_string(std::string("task: {name: navigation_task, episode_len_env_steps: 25, navigation: {image_encoding: proximity") +
                                         (k ? ", image_history_frames: 2, image_history_lag_env_steps: 3" : "") +
                                         "}}\nenv: {name: env_with_obstacles, num_envs: 4}\n",
                                     "nav.yaml", s, err))
        << err;
    EXPECT_EQ(s.task.navigation.image_history_frames, k ? kFrames : 0);
    t[k] = make_task(s, err);
    ASSERT_TRUE(t[k]) << err;
  }
  const int od = t[0]->obs_dim(), n = t[0]->num_envs(), cells = od - 17;
  ASSERT_EQ(cells, 64);
  ASSERT_EQ(t[1]->obs_dim(), od + kFrames * cells);
  const int hd = t[1]->obs_dim();
  std::vector<std::vector<float>> images;  // per env-step: every environment's current image
  std::vector<int> start(static_cast<std::size_t>(n), 0);  // the env-step each env's episode began
  std::vector<float> a0(static_cast<std::size_t>(n * t[0]->action_dim())), a1(a0.size());
  int resets = 0, moved = 0;
  for (int step = 0; step < 60; ++step) {
    std::vector<float> now(static_cast<std::size_t>(n * cells));
    for (int e = 0; e < n; ++e) {
      const float* o0 = t[0]->observations() + e * od;
      const float* o1 = t[1]->observations() + e * hd;
      for (int c = 0; c < od; ++c) ASSERT_EQ(o0[c], o1[c]) << step << " " << e << " " << c;
      std::copy(o1 + 17, o1 + od, now.begin() + e * cells);
    }
    images.push_back(now);
    for (int e = 0; e < n; ++e) {
      const float* o1 = t[1]->observations() + e * hd;
      for (int j = 1; j <= kFrames; ++j) {
        const int then = std::max(step - j * kLag, start[static_cast<std::size_t>(e)]);
        // Counts the comparisons that would catch a history that only repeats the current image.
        moved += !std::equal(now.begin() + e * cells, now.begin() + (e + 1) * cells,
                             images[static_cast<std::size_t>(then)].begin() + e * cells);
        for (int c = 0; c < cells; ++c)
          ASSERT_EQ(o1[od + (j - 1) * cells + c], images[static_cast<std::size_t>(then)][static_cast<std::size_t>(e * cells + c)])
              << step << " " << e << " " << j << " " << c;
      }
    }
    ASSERT_TRUE(t[0]->scripted_actions(a0.data()));
    ASSERT_TRUE(t[1]->scripted_actions(a1.data()));
    ASSERT_EQ(a0, a1) << step;
    t[0]->step(a0.data());
    t[1]->step(a1.data());
    for (int e = 0; e < n; ++e) {
      ASSERT_EQ(t[0]->rewards()[e], t[1]->rewards()[e]);
      if (t[1]->terminations()[e] || t[1]->truncations()[e]) {
        start[static_cast<std::size_t>(e)] = step + 1;
        ++resets;
      }
    }
  }
  EXPECT_GT(resets, 2);
  EXPECT_GT(moved, 0);
  // The images differ along the way: the comparison above could tell frames apart.
  EXPECT_NE(images[1], images[20]);
  WorldConfig s;
  EXPECT_FALSE(load_scenario_string("task: {name: navigation_task, navigation: {image_history_frames: 17}}\n", "nav.yaml", s, err));
  EXPECT_NE(err.find("task.navigation.image_history_frames"), std::string::npos) << err;
}

// task.curriculum from a scenario file: a level held fixed at the top (an evaluation there), and a
// curriculum that cannot hold refused with the section, the fields and the values.
TEST(NavigationTask, CurriculumFromTheScenario) {
  std::string err;
  WorldConfig s;
  ASSERT_TRUE(load_scenario_string("task: {name: navigation_task, episode_len_env_steps: 5,\n"
                                   "       curriculum: {start_level: 10, increase_step: 0, decrease_step: 0,\n"
                                   "                    check_after_episodes: 2}}\n"
                                   "env: {name: env_with_obstacles, num_envs: 2}\n",
                                   "nav.yaml", s, err))
      << err;
  EXPECT_EQ(s.task.curriculum.start_level, 10);
  EXPECT_EQ(s.task.curriculum.max_level, 10);
  EXPECT_EQ(s.task.curriculum.decrease_step, 0);
  EXPECT_EQ(s.task.curriculum.check_after_episodes, 2);
  auto t = make_task(s, err);
  ASSERT_TRUE(t) << err;
  EXPECT_EQ(t->infos().curriculum_level, 10);
  EXPECT_FLOAT_EQ(static_cast<float>(world_of(*t).data().curriculum_level), 1.0f);  // every obstacle
  const std::vector<float> zero(2 * 4, 0.0f);
  for (int k = 0; k < 20; ++k) t->step(zero.data());  // timeouts only: would lower a free curriculum
  EXPECT_GE(t->infos().episodes, 4u);
  EXPECT_EQ(t->infos().curriculum_level, 10);
  EXPECT_EQ(t->infos().curriculum_changes, 0u);

  EXPECT_FALSE(load_scenario_string("task: {name: navigation_task, curriculum: {increase_stp: 1}}\n", "nav.yaml", s, err));
  EXPECT_NE(err.find("task.curriculum.increase_stp"), std::string::npos) << err;
  EXPECT_FALSE(load_scenario_string("task: {name: navigation_task, curriculum: {success_rate_for_increase: 2}}\n", "nav.yaml", s, err));
  EXPECT_NE(err.find("task.curriculum.success_rate_for_increase"), std::string::npos) << err;
  ASSERT_TRUE(load_scenario_string("task: {name: navigation_task, curriculum: {min_level: 5, max_level: 2}}\n", "nav.yaml", s, err)) << err;
  EXPECT_FALSE(make_task(s, err));
  EXPECT_NE(err.find("task.curriculum: expected min_level <= max_level"), std::string::npos) << err;
  EXPECT_NE(err.find("min_level 5, max_level 2"), std::string::npos) << err;
}

// task.navigation from a scenario reaches the task: the action scaling, the pool grid (and so the
// observation size) and the reward constants.
TEST(NavigationTask, NavigationSectionFromTheScenario) {
  std::string err;
  WorldConfig s;
  ASSERT_TRUE(load_scenario_string("task: {name: navigation_task, navigation: {action_space: velocity, max_speed_m_s: 1.5, max_yaw_rate_rad_s: 0.5,\n"
                                   "       pool_rows: 4, pool_cols: 2, reward: {collision_penalty: -50}}}\n"
                                   "env: {name: env_with_obstacles, num_envs: 2}\n",
                                   "nav.yaml", s, err))
      << err;
  auto t = make_task(s, err);
  ASSERT_TRUE(t) << err;
  EXPECT_EQ(t->obs_dim(), 17 + 8);
  EXPECT_EQ(t->action_dim(), 4);
  const float a[8] = {1, 0, 0, 1, 0, 0, 0, 0};
  t->step(a);
  EXPECT_FLOAT_EQ(t->observations()[13], 1.5f);  // the scaled actions in the observation
  EXPECT_FLOAT_EQ(t->observations()[16], 0.5f);
  world_of(*t).robot_state(1, 0).position_w[2] = 0.05_r;  // into the ground: a crash
  t->step(a);
  EXPECT_EQ(t->terminations()[1], 1);
  EXPECT_EQ(t->rewards()[1], -50.0f);
}
