// locomotion_task (sim/locomotion_task.hpp): legged_gym's reward terms on hand-computed inputs,
// the only-positive clip with the termination term after it, feet_air_time's bookkeeping, the
// heading command's wrap and clip, the command resampling rule; then the task on Go2: the
// observation layout against the Simulator's views (noise off) and the noise bound (on), base
// contact terminates and the time limit truncates, pushes, bit-identical results for 1 and 2
// threads, no heap inside step, the scenario keys and the refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

#include "heap_counter.hpp"
#include "legged_config.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/locomotion_task.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/scenario.hpp"
#include "kestrel/sim/terrain.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {

float term(const float* t, LocoTerm k) { return t[static_cast<int>(k)]; }

struct TwoJoints {
  float q[2] = {0.3f, -1.2f}, qd[2] = {2.0f, -1.0f}, last_qd[2] = {1.0f, 0.0f}, home[2] = {0.1f, -1.0f};
  float lo[2] = {-0.5f, -1.1f}, hi[2] = {0.5f, 0.0f};  // joint 1 is 0.1 below its lower limit
  float tau[2] = {10.0f, -30.0f}, tlim[2] = {20.0f, 25.0f};  // joint 1 is 5 N m over
  float a[2] = {0.5f, -0.5f}, last_a[2] = {0.0f, 0.5f};
  float feet[6] = {3.0f, 4.0f, 0.5f, 0.0f, 0.0f, 120.0f};  // foot 0 stumbles (5 > 5 x 0.5); foot 1 pushes 120 N
  LocoTermInputs in() {
    LocoTermInputs x;
    x.num_dofs = 2;
    x.num_feet = 2;
    x.dt_s = 0.02f;
    x.commands[0] = 1.0f, x.commands[1] = 0.5f, x.commands[2] = -0.4f;
    x.lin_vel_b[0] = 0.8f, x.lin_vel_b[1] = 0.2f, x.lin_vel_b[2] = 0.3f;
    x.ang_vel_b[0] = 0.1f, x.ang_vel_b[1] = -0.2f, x.ang_vel_b[2] = 0.1f;
    x.projected_gravity[0] = 0.1f, x.projected_gravity[1] = -0.2f, x.projected_gravity[2] = -0.97f;
    x.base_height_m = 0.3f;
    x.dof_pos = q, x.dof_vel = qd, x.last_dof_vel = last_qd, x.default_dof_pos = home;
    x.dof_pos_lower = lo, x.dof_pos_upper = hi, x.torques = tau, x.torque_limits = tlim;
    x.actions = a, x.last_actions = last_a, x.foot_forces_w = feet;
    x.feet_air_time_sum = 0.25f;
    x.penalized_contacts = 2;
    x.terminated = true;
    return x;
  }
};

TEST(LocomotionTask, RewardTermsByHand) {
  TwoJoints j;
  LocomotionConfig c;
  c.base_height_target_m = 0.36_r;
  float t[kNumLocoTerms];
  locomotion_reward_terms(j.in(), c, t);
  // exp(-((1 - 0.8)^2 + (0.5 - 0.2)^2) / 0.25) = exp(-0.52)
  EXPECT_NEAR(term(t, LocoTerm::tracking_lin_vel), std::exp(-0.52), 1e-6);
  EXPECT_NEAR(term(t, LocoTerm::tracking_ang_vel), std::exp(-0.25 / 0.25), 1e-6);  // (-0.4 - 0.1)^2
  EXPECT_NEAR(term(t, LocoTerm::lin_vel_z), 0.09, 1e-6);
  EXPECT_NEAR(term(t, LocoTerm::ang_vel_xy), 0.05, 1e-6);
  EXPECT_NEAR(term(t, LocoTerm::orientation), 0.05, 1e-6);
  EXPECT_NEAR(term(t, LocoTerm::torques), 1000.0, 1e-3);
  EXPECT_NEAR(term(t, LocoTerm::dof_vel), 5.0, 1e-6);
  EXPECT_NEAR(term(t, LocoTerm::dof_acc), (2500.0 + 2500.0), 1e-2);  // ((1 - 2) / 0.02)^2 + ((0 + 1) / 0.02)^2
  EXPECT_NEAR(term(t, LocoTerm::base_height), 0.0036, 1e-6);          // (0.3 - 0.36)^2
  EXPECT_NEAR(term(t, LocoTerm::feet_air_time), 0.25, 1e-7);          // |cmd_xy| > 0.1: the sum as given
  EXPECT_EQ(term(t, LocoTerm::collision), 2.0f);
  EXPECT_EQ(term(t, LocoTerm::feet_stumble), 1.0f);
  EXPECT_NEAR(term(t, LocoTerm::action_rate), 0.25 + 1.0, 1e-6);
  EXPECT_EQ(term(t, LocoTerm::stand_still), 0.0f);                     // a command: not standing
  EXPECT_NEAR(term(t, LocoTerm::dof_pos_limits), 0.1, 1e-6);          // -(-1.2 - -1.1)
  EXPECT_NEAR(term(t, LocoTerm::torque_limits), 5.0, 1e-5);
  EXPECT_NEAR(term(t, LocoTerm::feet_contact_forces), 20.0, 1e-4);    // 120 - 100
  EXPECT_EQ(term(t, LocoTerm::termination), 1.0f);
  // A zero command: no air-time reward, and stand_still counts |q - home|.
  LocoTermInputs z = j.in();
  z.commands[0] = z.commands[1] = 0;
  locomotion_reward_terms(z, c, t);
  EXPECT_EQ(term(t, LocoTerm::feet_air_time), 0.0f);
  EXPECT_NEAR(term(t, LocoTerm::stand_still), 0.2 + 0.2, 1e-6);
  EXPECT_STREQ(loco_term_name(static_cast<int>(LocoTerm::feet_air_time)), "feet_air_time");
  EXPECT_EQ(loco_term_scale(c.scales, static_cast<int>(LocoTerm::lin_vel_z)), -2.0_r);  // legged_gym's default
}

TEST(LocomotionTask, OnlyPositiveClipsBeforeTermination) {
  float terms[kNumLocoTerms] = {}, scaled[kNumLocoTerms] = {};
  terms[static_cast<int>(LocoTerm::tracking_lin_vel)] = 0.5f;
  scaled[static_cast<int>(LocoTerm::tracking_lin_vel)] = 0.02f;  // 1.0 x dt
  terms[static_cast<int>(LocoTerm::lin_vel_z)] = 1.0f;
  scaled[static_cast<int>(LocoTerm::lin_vel_z)] = -0.04f;        // -2 x dt
  terms[static_cast<int>(LocoTerm::termination)] = 1.0f;
  scaled[static_cast<int>(LocoTerm::termination)] = -0.1f;
  EXPECT_NEAR(locomotion_total_reward(terms, scaled, false), 0.01f - 0.04f - 0.1f, 1e-7);
  EXPECT_NEAR(locomotion_total_reward(terms, scaled, true), -0.1f, 1e-7);  // max(-0.03, 0) - 0.1
  terms[static_cast<int>(LocoTerm::lin_vel_z)] = 0.1f;
  EXPECT_NEAR(locomotion_total_reward(terms, scaled, true), 0.01f - 0.004f - 0.1f, 1e-7);
}

TEST(LocomotionTask, FeetAirTime) {
  float air[1] = {0};
  std::uint8_t last[1] = {0};
  const float up[3] = {0, 0, 0}, down[3] = {0, 0, 50};
  const float dt = 0.1f;
  float got = 0;
  for (int s = 0; s < 7; ++s) got += update_feet_air_time(up, 1, dt, air, last);  // 0.7 s in the air
  EXPECT_EQ(got, 0.0f);
  EXPECT_NEAR(air[0], 0.7f, 1e-6);
  EXPECT_NEAR(update_feet_air_time(down, 1, dt, air, last), 0.8f - 0.5f, 1e-6);  // first contact: air time incl. this step
  EXPECT_EQ(air[0], 0.0f);
  EXPECT_EQ(update_feet_air_time(down, 1, dt, air, last), 0.0f);  // still down: no reward
  // Lifted for one step: the filter (contact last step) holds the air time at 0, then it counts.
  EXPECT_EQ(update_feet_air_time(up, 1, dt, air, last), 0.0f);
  EXPECT_EQ(air[0], 0.0f);
  EXPECT_EQ(update_feet_air_time(up, 1, dt, air, last), 0.0f);
  EXPECT_NEAR(air[0], 0.1f, 1e-7);
  EXPECT_NEAR(update_feet_air_time(down, 1, dt, air, last), 0.2f - 0.5f, 1e-6);  // a short step is penalised
}

TEST(LocomotionTask, HeadingCommand) {
  EXPECT_NEAR(heading_yaw_rate_command(0.5f, 0.1f), 0.2f, 1e-6);
  EXPECT_EQ(heading_yaw_rate_command(3.0f, 0.0f), 1.0f);   // clipped
  EXPECT_EQ(heading_yaw_rate_command(-3.0f, 0.0f), -1.0f);
  // Across +-pi: 3.0 - (-3.0) = 6.0 wraps to 6.0 - 2 pi.
  EXPECT_NEAR(heading_yaw_rate_command(3.0f, -3.0f), 0.5f * (6.0f - 2.0f * 3.14159265f), 1e-5);
}

TEST(LocomotionTask, ResampleCommands) {
  LocomotionConfig c;
  RngStream rng(3, 0, kPurposeLocoCommands);
  int zeroed = 0;
  for (int k = 0; k < 2000; ++k) {
    float cmd[4] = {9, 9, 9, 9};
    const std::uint64_t pos = rng.position();
    resample_locomotion_commands(c, rng, cmd);
    EXPECT_EQ(rng.position() - pos, 3u * (sizeof(real) == 8 ? 2u : 1u)) << "three draws whatever the values";
    const float n = std::sqrt(cmd[0] * cmd[0] + cmd[1] * cmd[1]);
    if (n == 0) ++zeroed;
    else EXPECT_GT(n, 0.2f);
    EXPECT_LE(std::fabs(cmd[0]), 1.0f);
    EXPECT_LE(std::fabs(cmd[1]), 1.0f);
    EXPECT_EQ(cmd[2], 9.0f) << "heading mode: the yaw rate comes from the heading";
    EXPECT_LE(std::fabs(cmd[3]), 3.14f);
  }
  // P(|(x, y)| <= 0.2) for x, y ~ U(-1, 1) is pi 0.04 / 4 = 3.1 %.
  EXPECT_GT(zeroed, 20);
  EXPECT_LT(zeroed, 110);
}

WorldConfig go2_task(int envs, int threads = 1) {
  WorldConfig c;
  std::string err;
  EXPECT_TRUE(load_scenario_string("task: locomotion_task\nrobot: go2\n", "loco.yaml", c, err)) << err;
  c.env.num_envs = envs;
  c.num_threads = threads;
  c.seed = 5;
  return c;
}

std::unique_ptr<Task> build(const WorldConfig& c) {
  std::string err;
  std::unique_ptr<Task> t = make_task(c, err);
  EXPECT_TRUE(t) << err;
  return t;
}

TEST(LocomotionTask, ObservationLayoutAgainstTheViews) {
  WorldConfig c = go2_task(3);
  c.task.locomotion.add_noise = false;
  auto t = build(c);
  ASSERT_TRUE(t);
  ASSERT_EQ(t->obs_dim(), 48);
  ASSERT_EQ(t->action_dim(), 12);
  std::vector<float> a(3 * 12);
  for (std::size_t k = 0; k < a.size(); ++k) a[k] = 0.1f * static_cast<float>(static_cast<int>(k % 7) - 3);
  a[5] = 250.0f;  // clipped to 100
  for (int s = 0; s < 5; ++s) t->step(a.data());
  const Simulator& sim = t->simulator();
  const RobotLayout& L = sim.robot_layout();
  for (int e = 0; e < 3; ++e) {
    const float* o = t->observations() + e * 48;
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(o[k], static_cast<float>(sim.base_lin_vel_b()[3 * e + k]) * 2.0f);
      EXPECT_EQ(o[3 + k], static_cast<float>(sim.base_ang_vel_b()[3 * e + k]) * 0.25f);
    }
    const Vec3 g = rotate_inverse(quat_from_xyzw(sim.base_quat_xyzw() + 4 * e), Vec3(0, 0, -1));
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(o[6 + k], g[k], 1e-6);
    EXPECT_LE(std::fabs(o[9]), 2.0f);     // lin_vel_x in [-1, 1] x 2
    EXPECT_LE(std::fabs(o[11]), 0.25f);   // the heading's yaw rate in [-1, 1] x 0.25
    for (int j = 0; j < 12; ++j) {
      EXPECT_EQ(o[12 + j], static_cast<float>(sim.dof_pos()[12 * e + j]) - static_cast<float>(L.default_dof_pos[static_cast<std::size_t>(j)]));
      EXPECT_EQ(o[24 + j], static_cast<float>(sim.dof_vel()[12 * e + j]) * 0.05f);
      EXPECT_EQ(o[36 + j], e == 0 && j == 5 ? 100.0f : a[static_cast<std::size_t>(12 * e + j)]);
    }
  }
  EXPECT_EQ(L.default_dof_pos.size(), 12u);
  EXPECT_EQ(L.foot_links.size(), 4u);
  // With noise: every noisy observation is within its bound of the noise-free one.
  WorldConfig n = c;
  n.task.locomotion.add_noise = true;
  auto tn = build(n);
  for (int s = 0; s < 5; ++s) tn->step(a.data());
  int differ = 0;
  for (int e = 0; e < 3; ++e)
    for (int k = 0; k < 48; ++k) {
      const float clean = t->observations()[e * 48 + k], noisy = tn->observations()[e * 48 + k];
      const float bound = k < 3 ? 0.2f : k < 6 ? 0.05f : k < 9 ? 0.05f : k < 12 ? 0.0f : k < 24 ? 0.01f : k < 36 ? 0.075f : 0.0f;
      EXPECT_LE(std::fabs(noisy - clean), bound + 1e-6f) << "obs " << k;
      if (noisy != clean) ++differ;
    }
  EXPECT_GT(differ, 3 * 30);
}

TEST(LocomotionTask, BaseContactTerminatesAndTimeLimitTruncates) {
  WorldConfig c = go2_task(2);
  c.task.episode_len_env_steps = 6;
  c.task.locomotion.push_robots = false;
  auto t = build(c);
  ASSERT_TRUE(t);
  std::vector<float> a(2 * 12, 0.0f);
  // Env 1 upside down on the ground: its base touches at once.
  const int ids[1] = {1};
  const Vec3 p(t->simulator().base_pos_w()[3], t->simulator().base_pos_w()[4], 0.05_r);  // the trunk box (half-height 0.057 m) 7 mm into the ground
  const real pos[3] = {p[0], p[1], p[2]}, quat[4] = {1, 0, 0, 0}, zero[3] = {0, 0, 0};  // 180 deg about x
  ASSERT_TRUE(t->simulator().reset_root_states(ids, 1, pos, quat, zero, zero));
  t->step(a.data());
  EXPECT_EQ(t->terminations()[1], 1);
  EXPECT_EQ(t->truncations()[1], 0);
  EXPECT_EQ(t->terminations()[0], 0);
  EXPECT_EQ(t->infos().crashes, 1u);
  EXPECT_EQ(t->episode_step(1), 0) << "reset inside the step";
  for (int s = 2; s <= 6; ++s) t->step(a.data());
  EXPECT_EQ(t->truncations()[0], 1) << "the time limit after 6 steps";
  EXPECT_EQ(t->terminations()[0], 0);
  EXPECT_EQ(t->infos().truncations, 1u);
}

TEST(LocomotionTask, PushesEveryInterval) {
  WorldConfig c = go2_task(8);
  c.task.locomotion.push_interval_s = 0.06_r;  // every 3 policy steps (0.02 s each)
  c.task.locomotion.reset_base_vel_max = 0;
  c.task.locomotion.reset_dof_pos_scale_min = c.task.locomotion.reset_dof_pos_scale_max = 1;
  auto t = build(c);
  ASSERT_TRUE(t);
  std::vector<float> a(8 * 12, 0.0f);
  auto mean_speed = [&] {
    double s = 0;
    for (int e = 0; e < 8; ++e) s += std::hypot(t->simulator().base_lin_vel_w()[3 * e], t->simulator().base_lin_vel_w()[3 * e + 1]);
    return s / 8;
  };
  t->step(a.data());
  t->step(a.data());
  const double before = mean_speed();
  t->step(a.data());  // the push
  const double after = mean_speed();
  EXPECT_LT(before, 0.1);
  EXPECT_GT(after, 0.25);  // |U(-1, 1)^2| averages 0.77 m/s, less one step of friction
}

TEST(LocomotionTask, TerrainCurriculumMovesLevelsByTheDistanceWalked) {
  // On a tiled terrain, at each episode's end: up a level past half a tile (4 m) from the origin,
  // down when closer than half of what the command asked over the episode (|cmd| x 20 s x 0.5).
  WorldConfig c = go2_task(4);
  kestrel::test::tiled_terrain(c.env.terrain, 5, 2, 4);
  c.task.episode_len_env_steps = 1000;  // 20 s
  c.task.locomotion.push_robots = false;
  c.task.locomotion.add_noise = false;
  auto t = build(c);
  ASSERT_TRUE(t);
  Simulator& sim = t->simulator();
  ASSERT_EQ(sim.num_terrain_levels(), 5);
  double start_mean = 0;
  for (int e = 0; e < 4; ++e) start_mean += sim.terrain_levels()[e] / 4.0;
  EXPECT_DOUBLE_EQ(t->infos().mean_terrain_level, start_mean);  // reported from the start
  std::vector<float> a(4 * 12, 0.0f);
  t->step(a.data());
  std::vector<int> before(sim.terrain_levels(), sim.terrain_levels() + 4);
  // Env 0 carried 5 m from its origin, env 1 put back on its origin: then both episodes end (a
  // base contact: upside down, half in the ground).
  std::vector<float> cmd(4);
  for (int e = 0; e < 4; ++e) cmd[static_cast<std::size_t>(e)] = std::hypot(t->observations()[48 * e + 9], t->observations()[48 * e + 10]) / 2;
  const int ids[2] = {0, 1};
  const real* o = sim.env_origins_w();
  std::unique_ptr<Terrain> ground;
  std::string err;
  ASSERT_TRUE(Terrain::build(c.env.terrain, c.seed, ground, err)) << err;
  const real pos[6] = {o[0] + 5, o[1], ground->height_at(o[0] + 5, o[1]), o[3], o[4], ground->height_at(o[3], o[4])};
  const real quat[8] = {1, 0, 0, 0, 1, 0, 0, 0}, zero[6] = {0, 0, 0, 0, 0, 0};
  ASSERT_TRUE(sim.reset_root_states(ids, 2, pos, quat, zero, zero));
  t->step(a.data());
  ASSERT_EQ(t->terminations()[0], 1);
  ASSERT_EQ(t->terminations()[1], 1);
  // Env 0: up (from the top, a random level below it).
  if (before[0] < 4) {
    EXPECT_EQ(sim.terrain_levels()[0], before[0] + 1);
  } else {
    EXPECT_LT(sim.terrain_levels()[0], 5);
  }
  // Env 1: down where its command asked to walk at all, else kept.
  EXPECT_EQ(sim.terrain_levels()[1], cmd[1] > 0 ? std::max(0, before[1] - 1) : before[1]) << cmd[1];
  EXPECT_EQ(sim.terrain_levels()[2], before[2]);  // episodes not ended: kept
  EXPECT_EQ(sim.terrain_levels()[3], before[3]);
  double mean = 0;
  for (int e = 0; e < 4; ++e) mean += sim.terrain_levels()[e] / 4.0;
  EXPECT_DOUBLE_EQ(t->infos().mean_terrain_level, mean);
  // The robots were reset onto their new tiles.
  for (int e = 0; e < 2; ++e) {
    EXPECT_LE(std::fabs(sim.base_pos_w()[3 * e] - sim.env_origins_w()[3 * e]), 1);
    EXPECT_LE(std::fabs(sim.base_pos_w()[3 * e + 1] - sim.env_origins_w()[3 * e + 1]), 1);
  }
  // Off: the levels never move.
  c.task.locomotion.terrain_curriculum = false;
  auto t2 = build(c);
  ASSERT_TRUE(t2);
  std::vector<int> b2(t2->simulator().terrain_levels(), t2->simulator().terrain_levels() + 4);
  const real* o2 = t2->simulator().env_origins_w();
  const real pos2[3] = {o2[0] + 5, o2[1], ground->height_at(o2[0] + 5, o2[1])};
  ASSERT_TRUE(t2->simulator().reset_root_states(ids, 1, pos2, quat, zero, zero));
  t2->step(a.data());
  EXPECT_EQ(t2->simulator().terrain_levels()[0], b2[0]);
}

std::vector<float> run(int threads, std::uint64_t* hash) {
  WorldConfig c = go2_task(6, threads);
  c.task.episode_len_env_steps = 15;
  c.task.locomotion.push_interval_s = 0.1_r;
  auto t = build(c);
  RngStream rng(9, 0, kPurposeUser);
  std::vector<float> a(6 * 12), out;
  for (int s = 0; s < 40; ++s) {
    for (float& v : a) v = static_cast<float>(rng.uniform(-2, 2));
    t->step(a.data());
    out.insert(out.end(), t->observations(), t->observations() + 6 * 48);
    out.insert(out.end(), t->rewards(), t->rewards() + 6);
  }
  *hash = t->state_hash();
  return out;
}

TEST(LocomotionTask, BitIdenticalForAnyThreadCount) {
  std::uint64_t h1 = 0, h2 = 0, h3 = 0;
  const std::vector<float> a = run(1, &h1), b = run(2, &h2), c = run(3, &h3);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float)));
  EXPECT_EQ(0, std::memcmp(a.data(), c.data(), a.size() * sizeof(float)));
  EXPECT_EQ(h1, h2);
  EXPECT_EQ(h1, h3);
  bool finite = true;
  for (float v : a) finite = finite && std::isfinite(v);
  EXPECT_TRUE(finite);
}

TEST(LocomotionTask, NoHeapInsideStep) {
  for (int tiled = 0; tiled < 2; ++tiled) {
    WorldConfig c = go2_task(4);
    c.task.episode_len_env_steps = 5;  // resets inside the counted steps
    c.task.locomotion.push_interval_s = 0.04_r;
    if (tiled) {  // the terrain curriculum, link pushes and the randomisation in the counted steps too
      kestrel::test::tiled_terrain(c.env.terrain, 3, 2, 2, 1);
      kestrel::test::randomise_all_articulated(c);
      c.task.locomotion.push_links_interval_s = 0.04_r;
      c.robot.self_collisions = true;  // and the self-collision pairs
    }
    auto t = build(c);
    std::vector<float> a(4 * 12, 0.3f);
    t->step(a.data());
    kestrel::test::HeapCounter counter;
    for (int s = 0; s < 20; ++s) t->step(a.data());
    EXPECT_EQ(counter.allocations(), 0u) << tiled;
    EXPECT_GE(t->infos().episodes, 4u);
  }
}

TEST(LocomotionTask, ScenarioKeysAndRefusals) {
  WorldConfig c;
  std::string err;
  ASSERT_TRUE(load_scenario_string("task: {name: locomotion_task, locomotion: {tracking_sigma: 0.5, lin_vel_x_m_s: [-0.5, 2],\n"
                                   "  scales: {orientation: -5, torques: -2.5e-5}, penalize_contacts_on: [THIGH]}}\nrobot: anymal_c\n",
                                   "loco.yaml", c, err))
      << err;
  EXPECT_EQ(c.task.locomotion.tracking_sigma, 0.5_r);
  EXPECT_EQ(c.task.locomotion.lin_vel_x_max_m_s, 2.0_r);
  EXPECT_EQ(c.task.locomotion.scales.orientation, -5.0_r);
  EXPECT_EQ(c.task.locomotion.scales.tracking_lin_vel, 1.0_r) << "unset scales keep legged_gym's";
  ASSERT_EQ(c.task.locomotion.penalize_contacts_on.size(), 1u);
  EXPECT_EQ(c.task.episode_len_env_steps, 1000);
  EXPECT_EQ(c.sim.solver_iterations, 10) << "the task's sim: legged_sim";
  EXPECT_EQ(c.env.num_physics_steps_per_env_step_mean, 4.0_r) << "the task's env: legged_flat";
  EXPECT_FALSE(load_scenario_string("task: {name: locomotion_task, locomotion: {scales: {tracking_lin: 1}}}\n", "loco.yaml", c, err));
  EXPECT_NE(err.find("task.locomotion.scales.tracking_lin"), std::string::npos) << err;
  EXPECT_NE(err.find("tracking_lin_vel"), std::string::npos) << err;
  EXPECT_FALSE(load_scenario_string("task: {name: locomotion_task, locomotion: {tracking_sigma: -1}}\n", "loco.yaml", c, err));
  EXPECT_NE(err.find("task.locomotion.tracking_sigma"), std::string::npos) << err;
  // A multirotor is refused by name.
  ASSERT_TRUE(load_scenario_string("task: locomotion_task\nrobot: base_quadrotor\n", "loco.yaml", c, err)) << err;
  EXPECT_FALSE(make_task(c, err));
  EXPECT_NE(err.find("articulated"), std::string::npos) << err;
}

}  // namespace
