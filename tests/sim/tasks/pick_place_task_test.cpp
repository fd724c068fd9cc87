// so101_pick_place (sim/pick_place_task.hpp): the shaped reward's terms on hand-computed inputs;
// the observation layout at reset against the world (home pose, tool-centre-point pose, relative
// positions); the reward of a step equals the terms on the world's state; success (cube in the box,
// released, held) terminates with the bonus and resets; the episode length truncates; the
// scripted controller succeeds; bit-identical results for 1 and 2 threads; no heap inside step
// (joint and ee_delta modes, resets included); the scenario keys and the registry.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <random>
#include <cstring>
#include <memory>
#include <vector>

#include "heap_counter.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/pick_place_task.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/scenario.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {

WorldConfig config(int envs, int threads, const char* extra = "") {
  WorldConfig c;
  std::string err;
  const std::string text = std::string("task: {name: so101_pick_place") + extra + "}\n";
  EXPECT_TRUE(load_scenario_string(text, "pp.yaml", c, err)) << err;
  c.env.num_envs = envs;
  c.num_threads = threads;
  c.seed = 7;
  return c;
}

std::unique_ptr<Task> build(const WorldConfig& c) {
  std::string err;
  std::unique_ptr<Task> t = make_task(c, err);
  EXPECT_TRUE(t != nullptr) << err;
  return t;
}

PickPlaceWorld& world(Task& t, int env) { return const_cast<PickPlaceWorld&>(*pick_place_world(t, env)); }

// Environment env's cube resting on its box's floor (5 mm thick), the cube's centre 12.5 mm above.
void put_cube_in_box(Task& t, int env) {
  PickPlaceWorld& w = world(t, env);
  const Vec3 b = w.state().box_pos_w;
  w.set_cube_pose(Vec3(b[0], b[1], 0.005 + 0.0125), Vec4(0, 0, 0, 1));
}

std::vector<float> home_actions(Task& t) {
  std::vector<float> a(static_cast<std::size_t>(t.num_envs()) * 6);
  for (int e = 0; e < t.num_envs(); ++e)
    for (int j = 0; j < 6; ++j) a[static_cast<std::size_t>(e) * 6 + static_cast<std::size_t>(j)] = static_cast<float>(world(t, e).home()[j]);
  return a;
}

float term(const float* t, PickPlaceTerm k) { return t[static_cast<int>(k)]; }

}  // namespace

TEST(PickPlaceTask, RewardTermsByHand) {
  PickPlaceTaskConfig c;
  PickPlaceRewardInputs in;
  in.tcp_w[0] = 0.2f, in.tcp_w[1] = 0.0f, in.tcp_w[2] = 0.1f;
  in.cube_w[0] = 0.2f, in.cube_w[1] = 0.03f, in.cube_w[2] = 0.0125f + 0.04f;  // lifted 4 cm
  in.box_w[0] = 0.2f, in.box_w[1] = 0.15f, in.box_w[2] = 0.0f;
  in.grip_force_N = 2.0f;  // grasped
  float t[kNumPickPlaceTerms];
  float r = pick_place_reward(in, c, t);
  const float d = std::sqrt(0.03f * 0.03f + 0.0475f * 0.0475f);
  EXPECT_NEAR(term(t, PickPlaceTerm::reach), 1.0f - std::tanh(d / 0.05f), 1e-6f);
  EXPECT_EQ(term(t, PickPlaceTerm::grasp), 1.0f);
  EXPECT_NEAR(term(t, PickPlaceTerm::lift), 2.0f * 0.8f, 1e-5f);
  EXPECT_NEAR(term(t, PickPlaceTerm::place), 2.0f * (1.0f - std::tanh(0.12f / 0.05f)), 1e-5f);
  EXPECT_EQ(term(t, PickPlaceTerm::success), 0.0f);
  EXPECT_NEAR(r, t[0] + t[1] + t[2] + t[3] + t[4], 1e-6f);
  // Not grasped: no grasp, lift or place (not in the box); success adds the bonus.
  in.grip_force_N = 0.1f;
  in.success = true;
  r = pick_place_reward(in, c, t);
  EXPECT_EQ(term(t, PickPlaceTerm::grasp), 0.0f);
  EXPECT_EQ(term(t, PickPlaceTerm::lift), 0.0f);
  EXPECT_EQ(term(t, PickPlaceTerm::place), 0.0f);
  EXPECT_EQ(term(t, PickPlaceTerm::success), 50.0f);
  // In the box, released: the place term at the box's centre is its full weight.
  in.cube_w[0] = 0.2f, in.cube_w[1] = 0.15f, in.cube_w[2] = 0.0175f;
  in.in_box = true;
  (void)pick_place_reward(in, c, t);
  EXPECT_EQ(term(t, PickPlaceTerm::place), 2.0f);
  EXPECT_STREQ(pick_place_term_name(0), "reach");
  EXPECT_STREQ(pick_place_term_name(4), "success");
}

TEST(PickPlaceTask, ObservationsAtResetAndReward) {
  auto t = build(config(3, 1));
  ASSERT_TRUE(t);
  EXPECT_STREQ(t->name(), "so101_pick_place");
  EXPECT_EQ(t->obs_dim(), kPickPlaceObsDim);
  EXPECT_EQ(t->action_dim(), 6);
  float lo[6], hi[6];
  ASSERT_TRUE(t->action_bounds(lo, hi));
  for (int e = 0; e < 3; ++e) {
    const PickPlaceWorld& w = world(*t, e);
    const float* o = t->observations() + e * kPickPlaceObsDim;
    for (int j = 0; j < 6; ++j) {
      EXPECT_EQ(o[j], static_cast<float>(w.home()[j]));
      EXPECT_EQ(o[6 + j], 0.0f);
      EXPECT_EQ(o[12 + j], static_cast<float>(w.home()[j]));
      EXPECT_EQ(lo[j], static_cast<float>(w.joint_lower()[j]));
      EXPECT_EQ(hi[j], static_cast<float>(w.joint_upper()[j]));
    }
    const PickPlaceState& s = w.state();
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(o[18 + k], static_cast<float>(s.tcp_pos_w[k]));
      EXPECT_NEAR(o[25 + k], s.cube_pos_w[k] - s.tcp_pos_w[k], 1e-6);
      EXPECT_NEAR(o[28 + k], s.box_pos_w[k] - s.cube_pos_w[k], 1e-6);
    }
    // The quaternion is the tool's rotation (w >= 0).
    const Quat q = quat_from_xyzw(o[21], o[22], o[23], o[24]);
    EXPECT_NEAR(q.norm(), 1.0, 1e-5);
    EXPECT_GE(o[24], 0.0f);
    EXPECT_LT((rotation_matrix(q) - s.tcp_R_w).cwiseAbs().maxCoeff(), 1e-5);
    // The cube rests on the table at its randomised place, the box within its range.
    EXPECT_NEAR(s.cube_pos_w[2], 0.0125, 1e-9);
    EXPECT_LE(std::fabs(s.cube_pos_w[0] - 0.20), 0.05 + 1e-9);
    EXPECT_LE(std::fabs(s.box_pos_w[1] - 0.15), 0.05 + 1e-9);
  }
  // The reward of a step is the terms on the world's state after it.
  std::vector<float> a = home_actions(*t);
  t->step(a.data());
  for (int e = 0; e < 3; ++e) {
    const PickPlaceWorld& w = world(*t, e);
    PickPlaceRewardInputs in;
    for (int k = 0; k < 3; ++k) {
      in.tcp_w[k] = static_cast<float>(w.state().tcp_pos_w[k]);
      in.cube_w[k] = static_cast<float>(w.state().cube_pos_w[k]);
      in.box_w[k] = static_cast<float>(w.state().box_pos_w[k]);
    }
    in.grip_force_N = static_cast<float>(w.grip_force_N());
    float terms[kNumPickPlaceTerms];
    EXPECT_EQ(t->rewards()[e], pick_place_reward(in, PickPlaceTaskConfig(), terms));
    EXPECT_GT(t->rewards()[e], 0.0f);  // the reach term
    EXPECT_LT(t->rewards()[e], 1.0f);
  }
}

TEST(PickPlaceTask, SuccessTerminatesTruncationAtLength) {
  WorldConfig c = config(2, 1);
  c.task.episode_len_env_steps = 30;
  auto t = build(c);
  ASSERT_TRUE(t);
  // Env 0: the cube put into the box (resting on its floor), the arm at home: after
  // success_hold_steps (10) steps it succeeds; env 1 runs to the time limit.
  put_cube_in_box(*t, 0);
  std::vector<float> a = home_actions(*t);
  for (int s = 1; s <= 10; ++s) {
    t->step(a.data());
    if (s < 10) {
      EXPECT_EQ(t->terminations()[0], 0) << s;
    }
  }
  EXPECT_EQ(t->terminations()[0], 1);
  EXPECT_EQ(t->truncations()[0], 0);
  EXPECT_GT(t->rewards()[0], 50.0f);
  EXPECT_EQ(t->infos().successes, 1u);
  EXPECT_EQ(t->infos().terminations, 1u);
  EXPECT_EQ(t->episode_step(0), 0);  // reset inside step
  EXPECT_FALSE(world(*t, 0).cube_in_box());
  for (int s = 11; s <= 30; ++s) t->step(a.data());
  EXPECT_EQ(t->truncations()[1], 1);
  EXPECT_EQ(t->terminations()[1], 0);
  EXPECT_EQ(t->infos().truncations, 1u);
  EXPECT_EQ(t->infos().episodes, 2u);
  EXPECT_EQ(t->simulator().summary().successes, 1u);
}

// end_on_success: false (kestrel.SceneTask's setting): the same placement neither ends the
// episode nor pays the bonus; the cube stays in the box.
TEST(PickPlaceTask, SuccessOffLeavesTheEpisodeToTheCaller) {
  WorldConfig c = config(1, 1, ", pick_place: {end_on_success: false}");
  ASSERT_FALSE(c.task.pick_place.end_on_success);
  auto t = build(c);
  ASSERT_TRUE(t);
  put_cube_in_box(*t, 0);
  std::vector<float> a = home_actions(*t);
  for (int s = 1; s <= 20; ++s) {
    t->step(a.data());
    EXPECT_EQ(t->terminations()[0], 0) << s;
    EXPECT_LT(t->rewards()[0], 50.0f) << s;
  }
  EXPECT_TRUE(world(*t, 0).cube_in_box());
  EXPECT_EQ(t->infos().successes, 0u);
}

TEST(PickPlaceTask, ScriptedSucceedsAndThreadsAgree) {
  const int n = 4;
  std::unique_ptr<Task> t1 = build(config(n, 1)), t2 = build(config(n, 2));
  ASSERT_TRUE(t1 && t2);
  EXPECT_EQ(t2->num_threads(), 2);
  std::vector<float> a1(n * 6), a2(n * 6), again(n * 6);
  std::vector<std::uint8_t> done(n, 0);
  for (int s = 0; s < 350; ++s) {
    ASSERT_TRUE(t1->scripted_actions(a1.data()));
    ASSERT_TRUE(t1->scripted_actions(again.data()));  // idempotent within a step
    ASSERT_EQ(std::memcmp(a1.data(), again.data(), a1.size() * sizeof(float)), 0);
    ASSERT_TRUE(t2->scripted_actions(a2.data()));
    t1->step(a1.data());
    t2->step(a2.data());
    ASSERT_EQ(std::memcmp(t1->observations(), t2->observations(), n * kPickPlaceObsDim * sizeof(float)), 0) << s;
    ASSERT_EQ(std::memcmp(t1->rewards(), t2->rewards(), n * sizeof(float)), 0) << s;
    for (int e = 0; e < n; ++e) done[e] = done[e] || t1->terminations()[e];
  }
  EXPECT_EQ(t1->state_hash(), t2->state_hash());
  int successes = 0;
  for (int e = 0; e < n; ++e) successes += done[e];
  EXPECT_GE(successes, n - 1);
  EXPECT_EQ(t1->infos().successes, static_cast<std::uint64_t>(successes));
  EXPECT_GT(t1->reward_term_sum(static_cast<int>(PickPlaceTerm::lift)), 0.0);
}

// The task steps its worlds in blocks through the batched step (PickPlaceWorld::step_batch): the
// same observations, rewards and state hash as every world stepped alone (KESTREL_LEGGED_BATCH=off),
// on 1 and 2 threads, with the scripted actions pushed off by noise (arms on the table and the box).
TEST(PickPlaceTask, BatchedWorldsGiveTheBitsOfWorldsAlone) {
  const int n = 24;  // 1 thread: blocks of 16 and 8 with AVX-512; 2 threads: 12 each
  setenv("KESTREL_LEGGED_BATCH", "off", 1);
  std::unique_ptr<Task> alone = build(config(n, 1));
  unsetenv("KESTREL_LEGGED_BATCH");
  std::unique_ptr<Task> b1 = build(config(n, 1)), b2 = build(config(n, 2));
  ASSERT_TRUE(alone && b1 && b2);
  std::vector<float> a(n * 6);
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.f, 0.3f);
  for (int s = 0; s < 120; ++s) {
    ASSERT_TRUE(alone->scripted_actions(a.data()));
    for (int e = 0; e < n; e += 2)
      for (int j = 0; j < 6; ++j) a[static_cast<std::size_t>(e * 6 + j)] += noise(rng);
    alone->step(a.data());
    b1->step(a.data());
    b2->step(a.data());
    ASSERT_EQ(std::memcmp(alone->observations(), b1->observations(), n * kPickPlaceObsDim * sizeof(float)), 0) << s;
    ASSERT_EQ(std::memcmp(alone->observations(), b2->observations(), n * kPickPlaceObsDim * sizeof(float)), 0) << s;
    ASSERT_EQ(std::memcmp(alone->rewards(), b1->rewards(), n * sizeof(float)), 0) << s;
  }
  EXPECT_EQ(alone->state_hash(), b1->state_hash());
  EXPECT_EQ(alone->state_hash(), b2->state_hash());
}

TEST(PickPlaceTask, EeDeltaMode) {
  auto t = build(config(2, 1, ", pick_place: {action_mode: ee_delta, randomize_xy_m: 0}"));
  ASSERT_TRUE(t);
  EXPECT_EQ(t->action_dim(), 5);
  float lo[5], hi[5];
  ASSERT_TRUE(t->action_bounds(lo, hi));
  EXPECT_FLOAT_EQ(hi[0], 0.02f);
  float none[10];
  EXPECT_FALSE(t->scripted_actions(none));
  const Vec3 p0 = world(*t, 0).state().tcp_pos_w;
  const float g = static_cast<float>(world(*t, 0).home()[5]);
  // Env 0 goes down 1 cm per action for 3 actions (a delta beyond the clip counts as the clip),
  // env 1 holds (zero deltas).
  std::vector<float> a = {0, 0, -0.01f, 0, g, 0, 0, 0, 0, g};
  for (int s = 0; s < 2; ++s) t->step(a.data());
  a[2] = -0.5f;  // clipped to -0.02
  t->step(a.data());
  a[2] = 0;
  for (int s = 0; s < 40; ++s) t->step(a.data());
  const Vec3 p = world(*t, 0).state().tcp_pos_w;
  EXPECT_NEAR(p[2] - p0[2], -0.04, 0.01);
  EXPECT_NEAR(p[0], p0[0], 0.01);
  EXPECT_LT((world(*t, 1).state().tcp_pos_w - p0).norm(), 0.01);
}

TEST(PickPlaceTask, NoHeapInStep) {
  for (const char* extra : {"", ", pick_place: {action_mode: ee_delta}"}) {
    WorldConfig c = config(3, 1, extra);  // one thread: the counter sees the caller's thread only
    c.task.episode_len_env_steps = 6;  // resets inside the counted steps
    auto t = build(c);
    ASSERT_TRUE(t);
    const bool ee = t->action_dim() == 5;
    std::vector<float> a(static_cast<std::size_t>(3 * t->action_dim()), 0.0f);
    if (!ee) {
      a = home_actions(*t);
      ASSERT_TRUE(t->scripted_actions(a.data()));
    }
    t->step(a.data());
    kestrel::test::HeapCounter counter;
    for (int s = 0; s < 15; ++s) {
      if (!ee) (void)t->scripted_actions(a.data());
      t->step(a.data());
    }
    EXPECT_EQ(counter.allocations(), 0u) << extra;
    EXPECT_GE(t->infos().episodes, 6u);
  }
}

TEST(PickPlaceTask, ScenarioKeysAndRegistry) {
  WorldConfig c;
  std::string err;
  ASSERT_TRUE(load_scenario_string("task: {name: so101_pick_place, episode_len_env_steps: 500, pick_place: {action_mode: ee_delta,\n"
                                   "  randomize_xy_m: 0.02, cube_mass_kg: 0.02, arm_kp_Nm_rad: 500, box_pos_w: [0.2, -0.15, 0]}}\n",
                                   "pp.yaml", c, err))
      << err;
  EXPECT_EQ(c.task.pick_place.action_mode, PickPlaceActionMode::ee_delta);
  EXPECT_EQ(c.task.pick_place.randomize_xy_m, 0.02_r);
  EXPECT_EQ(c.task.pick_place.cube_mass_kg, 0.02_r);
  EXPECT_EQ(c.task.pick_place.arm_kp_Nm_rad, 500.0_r);
  EXPECT_EQ(c.task.pick_place.box_pos_w[1], -0.15_r);
  EXPECT_EQ(c.task.episode_len_env_steps, 500);
  EXPECT_FALSE(load_scenario_string("task: {name: so101_pick_place, pick_place: {action_mode: torque}}\n", "bad.yaml", c, err));
  EXPECT_NE(err.find("action_mode"), std::string::npos) << err;
  EXPECT_FALSE(load_scenario_string("task: {name: so101_pick_place, pick_place: {cube_mass_kg: -1}}\n", "bad.yaml", c, err));
  EXPECT_NE(err.find("cube_mass_kg"), std::string::npos) << err;
  EXPECT_TRUE(registries().tasks.has("so101_pick_place"));
  EXPECT_TRUE(is_rl_task("so101_pick_place"));
  TaskConfig tc;
  ASSERT_TRUE(registries().tasks.make("so101_pick_place", tc));
  EXPECT_EQ(tc.episode_len_env_steps, 1000);
  // Planar has no joint trees.
  ASSERT_TRUE(load_scenario_string("task: so101_pick_place\n", "pp.yaml", c, err)) << err;
  c.env.num_envs = 1;
  EXPECT_EQ(make_task(c, Backend::planar, err), nullptr);
  EXPECT_NE(err.find("rigid"), std::string::npos);
}

// PickPlaceWorld::set_box_position: the box's five parts move together (the world's shapes),
// cube_in_box follows the box, the cube's state is left alone; and the task-level setter
// (pick_place_set_object_pose) rewrites the observation row and refuses bad input.
TEST(PickPlaceTask, SetBoxPositionMovesThePartsAndCubeInBoxFollows) {
  WorldConfig c = config(1, 1, ", pick_place: {randomize_xy_m: 0}");
  std::unique_ptr<Task> t = build(c);
  PickPlaceWorld& w = world(*t, 0);
  PickPlaceShape before[64], after[64];
  const int n = w.scene_shapes(before, 64);
  const Vec3 cube0 = w.state().cube_pos_w;
  const std::uint64_t h0 = w.state_hash();
  EXPECT_FALSE(w.cube_in_box());
  const Vec3 d(-0.03_r, -0.12_r, 0);  // box centre (0.2, 0.15) -> (0.17, 0.03): the cube (0.2, 0) inside
  w.set_box_position(w.state().box_pos_w + d);
  ASSERT_EQ(w.scene_shapes(after, 64), n);
  int box_parts = 0;
  for (int i = 0; i < n; ++i) {
    if (before[i].entity == PickPlaceEntity::box) {
      ++box_parts;
      EXPECT_NEAR((after[i].shape.p_b - before[i].shape.p_b - d).norm(), 0, 1e-6) << "part " << before[i].index;
      EXPECT_NEAR((after[i].shape.size - before[i].shape.size).norm(), 0, 1e-9);
    } else {
      EXPECT_NEAR((after[i].shape.p_b - before[i].shape.p_b).norm(), 0, 1e-9);
    }
  }
  EXPECT_EQ(box_parts, 5);
  EXPECT_NEAR((w.state().box_pos_w - Vec3(0.17_r, 0.03_r, 0)).norm(), 0, 1e-6);
  EXPECT_EQ(w.state_hash(), h0);  // q, qd (the arm and the cube) untouched
  EXPECT_NEAR((w.state().cube_pos_w - cube0).norm(), 0, 0);
  EXPECT_TRUE(w.cube_in_box());
  w.set_box_position(Vec3(0.20_r, 0.15_r, 0));
  EXPECT_FALSE(w.cube_in_box());
  w.set_box_position(Vec3(std::nan(""), 0, 0));  // ignored
  EXPECT_NEAR((w.state().box_pos_w - Vec3(0.20_r, 0.15_r, 0)).norm(), 0, 1e-9);

  // The task's setter: the observation's box - cube (28..31) follows; the cube is set at rest.
  std::string err;
  ASSERT_TRUE(pick_place_set_object_pose(*t, 0, PickPlaceObject::box, Vec3(0.1_r, -0.2_r, 0), Vec4(0, 0, 0, 1), err)) << err;
  ASSERT_TRUE(pick_place_set_object_pose(*t, 0, PickPlaceObject::cube, Vec3(0.12_r, -0.19_r, 0.0125_r), Vec4(0, 0, 0, 1), err)) << err;
  const float* o = t->observations();
  EXPECT_NEAR(o[28], -0.02f, 1e-5f);
  EXPECT_NEAR(o[29], -0.01f, 1e-5f);
  EXPECT_NEAR(o[30], -0.0125f, 1e-5f);
  EXPECT_TRUE(w.cube_in_box());
  EXPECT_FALSE(pick_place_set_object_pose(*t, 1, PickPlaceObject::box, Vec3::Zero(), Vec4(0, 0, 0, 1), err));
  EXPECT_NE(err.find("env"), std::string::npos) << err;
  EXPECT_FALSE(pick_place_set_object_pose(*t, 0, PickPlaceObject::cube, Vec3::Zero(), Vec4(0, 0, 0, 0), err));
  EXPECT_NE(err.find("quat"), std::string::npos) << err;
  // The box stays where it was put over steps; the cube, released in it, counts towards success:
  // after success_hold_steps (10) actions the episode ends in success and the reset draws again.
  std::vector<float> a = home_actions(*t);
  for (int k = 0; k < 9; ++k) t->step(a.data());
  EXPECT_NEAR((w.state().box_pos_w - Vec3(0.1_r, -0.2_r, 0)).norm(), 0, 1e-9);
  EXPECT_EQ(t->infos().successes, 0u);
  t->step(a.data());
  EXPECT_EQ(t->infos().successes, 1u);
  EXPECT_NEAR((w.state().box_pos_w - Vec3(0.2_r, 0.15_r, 0)).norm(), 0, 1e-9);
}

TEST(PickPlaceTask, BoxGeometryAndRobotFileKeys) {
  WorldConfig c;
  std::string err;
  ASSERT_TRUE(load_scenario_string("task: {name: so101_pick_place, pick_place: {box_inner_half_m: 0.07, box_wall_m: 0.004,\n"
                                   "  box_height_m: 0.05, robot_file: " KESTREL_MODELS_SO101_XML "}}\n",
                                   "pp.yaml", c, err))
      << err;
  EXPECT_EQ(c.task.pick_place.box_inner_half_m, 0.07_r);
  EXPECT_EQ(c.task.pick_place.box_wall_m, 0.004_r);
  EXPECT_EQ(c.task.pick_place.box_height_m, 0.05_r);
  EXPECT_EQ(c.task.pick_place.robot_file, KESTREL_MODELS_SO101_XML);
  const PickPlaceConfig pc = pick_place_world_config(c.task.pick_place);
  EXPECT_EQ(pc.box_inner_half_m, 0.07_r);
  EXPECT_EQ(pc.box_wall_m, 0.004_r);
  EXPECT_EQ(pc.box_height_m, 0.05_r);
  EXPECT_EQ(pc.robot_file, KESTREL_MODELS_SO101_XML);
  c.env.num_envs = 1;
  std::unique_ptr<Task> t = build(c);
  PickPlaceShape s[64];
  const int n = world(*t, 0).scene_shapes(s, 64);
  for (int i = 0; i < n; ++i)
    if (s[i].entity == PickPlaceEntity::box && s[i].index == 2) {  // the +x wall
      EXPECT_NEAR(s[i].shape.size[0], 0.002, 1e-7);
      EXPECT_NEAR(s[i].shape.size[2], 0.025, 1e-7);
      EXPECT_NEAR(s[i].shape.p_b[0] - world(*t, 0).state().box_pos_w[0], 0.072, 1e-6);
    }
  ASSERT_TRUE(load_scenario_string("task: {name: so101_pick_place, pick_place: {robot_file: /nonexistent/arm.xml}}\n", "pp.yaml", c, err));
  c.env.num_envs = 1;
  EXPECT_EQ(make_task(c, err), nullptr);
  EXPECT_NE(err.find("/nonexistent/arm.xml"), std::string::npos) << err;
}
