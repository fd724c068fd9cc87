// Articulated robots behind the Simulator interface (sim/src/backends/articulated.cpp): Go2 and
// ANYmal C from their model files stand under the joint PD at their home pose for 10 s on flat
// ground and on a slope within the friction limit (the base drifts less than 1 mm once settled and
// does not jitter; the feet carry the weight); random joint targets at the torque limits and a
// spawn partly in the ground stay finite; the views (dof_pos, dof_vel, torques, feet, link forces)
// agree with each other; results are bit-identical for 1, 2 and 3 threads; reset_dofs and
// reset_root_states write exactly; the planar backend refuses an articulated robot by name.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/kernel/rng.hpp"
#include "kestrel/sim/articulated_robot.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/simulator.hpp"
#include "kestrel/sim/terrain.hpp"
#include "legged_config.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {

WorldConfig legged(const char* robot, int envs, int threads = 1) {
  WorldConfig c;
  EXPECT_TRUE(registries().robots.make(robot, c.robot));
  EXPECT_TRUE(registries().sims.make("fast_sim", c.sim));  // dt 5 ms
  EXPECT_TRUE(registries().tasks.make("joint_targets", c.task));
  c.env.name = "flat";
  c.env.num_envs = envs;
  c.env.num_physics_steps_per_env_step_mean = 4;  // legged_gym's decimation
  c.num_threads = threads;
  c.seed = 11;
  return c;
}

double total_mass(const char* robot) {
  WorldConfig c = legged(robot, 1);
  ArticulatedRobot r;
  std::string err;
  EXPECT_TRUE(load_robot_model(c.robot.model_file, r, err)) << err;
  return r.total_mass_kg;
}

// Stands the robot for 10 s with zero actions (the home pose, dropped from legged_gym's spawn
// height): the base's drift over the last 5 s (after 5 s of settling), its height's peak-to-peak
// over the last 2 s, and the ground's force at the end.
struct Standing {
  double drift_m = 0, jitter_m = 0, height_m = 0, foot_share = 0, tilt_rad = 0;
  Vec3 force_N = Vec3::Zero();
  std::uint64_t crashes = 0;
};

Standing stand(const WorldConfig& c) {
  std::string err;
  std::unique_ptr<Simulator> sim = make_simulator(c, err);
  EXPECT_TRUE(sim) << err;
  Standing out;
  if (!sim) return out;
  std::vector<real> zero(static_cast<std::size_t>(sim->num_robots() * sim->action_dim()), 0);
  const int steps = 500, settle = 250;  // 10 s at 50 Hz
  Vec3 settled = Vec3::Zero();
  double zmin = 1e9, zmax = -1e9;
  for (int s = 0; s < steps; ++s) {
    sim->step(zero.data());
    const real* p = sim->base_pos_w();
    if (s == settle - 1) settled = Vec3(p[0], p[1], p[2]);
    if (s >= settle) out.drift_m = std::max(out.drift_m, static_cast<double>((Vec3(p[0], p[1], p[2]) - settled).norm()));
    if (s >= steps - 100) {
      zmin = std::min(zmin, static_cast<double>(p[2]));
      zmax = std::max(zmax, static_cast<double>(p[2]));
    }
  }
  out.jitter_m = zmax - zmin;
  out.height_m = sim->base_pos_w()[2];
  const real* e = sim->base_euler_xyz();
  out.tilt_rad = std::sqrt(e[0] * e[0] + e[1] * e[1]);
  const real* lf = sim->link_contact_forces_w();
  double feet = 0;
  for (int b = 0; b < sim->num_links(); ++b) out.force_N += Vec3(lf[3 * b], lf[3 * b + 1], lf[3 * b + 2]);
  ArticulatedRobot r;
  EXPECT_TRUE(load_robot_model(c.robot.model_file, r, err));
  for (int f : r.foot_bodies) feet += lf[3 * f + 2];
  out.foot_share = out.force_N[2] > 0 ? feet / out.force_N[2] : 0;
  out.crashes = sim->summary().crashes;
  return out;
}

}  // namespace

TEST(Articulated, Go2AndAnymalStandAtHomeOnFlatGroundAndOnASlope) {
  for (const char* robot : {"go2", "anymal_c"}) {
    const double weight = total_mass(robot) * 9.81;
    for (int slope = 0; slope < 2; ++slope) {
      WorldConfig c = legged(robot, 2);
      if (slope) {
        // legged_gym's sloped terrain: rise 0.2 per metre (11.3 deg), well inside the friction
        // cone of the feet on the ground (mu about 1: 45 deg).
        c.env.terrain.type = TerrainType::heightfield;
        c.env.terrain.procedural = "slope";
        c.env.terrain.slope = 0.2_r;
        c.env.terrain.length_x_m = 8;
        c.env.terrain.width_y_m = 8;
      }
      const Standing s = stand(c);
      const std::string what = std::string(robot) + (slope ? "_slope" : "_flat");
      SCOPED_TRACE(what);
      RecordProperty(what + "_drift_um", static_cast<int>(s.drift_m * 1e6));
      RecordProperty(what + "_tilt_mrad", static_cast<int>(s.tilt_rad * 1e3));
      EXPECT_EQ(s.crashes, 0u);     // the base never touched the ground
      EXPECT_LT(s.drift_m, 1e-3);   // the issue's bound, once settled
      EXPECT_LT(s.jitter_m, 1e-4);  // no jitter above 0.1 mm over the last 2 s
      // At rest the ground's force balances the weight: all of it vertical, none sideways (the
      // friction holds the feet on the slope).
      EXPECT_NEAR(s.force_N[2], weight, 0.02 * weight);
      EXPECT_LT(std::hypot(s.force_N[0], s.force_N[1]), 0.02 * weight);
      if (!slope) {
        EXPECT_GT(s.height_m, 0.2);    // standing, not lying
        EXPECT_LT(s.tilt_rad, 0.05);   // level
        EXPECT_GT(s.foot_share, 0.99); // on its feet alone
      } else {
        EXPECT_LT(s.tilt_rad, 0.6);  // Go2's soft drives (kp 20) let it sit back on the slope
      }
    }
  }
}

namespace {

// Random joint targets far beyond the joint ranges (actions of +-50: the PD saturates at the
// effort limits), redrawn every env-step, on rough ground: the hash of 60 env-steps.
std::uint64_t random_run(int threads, int envs, std::vector<real>* torques_seen = nullptr, Simulator** keep = nullptr,
                         std::unique_ptr<Simulator>* owner = nullptr, bool self_collisions = false) {
  WorldConfig c = legged("go2", envs, threads);
  c.robot.self_collisions = self_collisions;
  c.env.terrain.type = TerrainType::heightfield;
  c.env.terrain.procedural = "random_uniform";
  c.env.terrain.min_height_m = -0.03_r;
  c.env.terrain.max_height_m = 0.03_r;
  std::string err;
  std::unique_ptr<Simulator> sim = make_simulator(c, err);
  EXPECT_TRUE(sim) << err;
  if (!sim) return 0;
  RngStream rng(5, 0, kPurposeUser + 40);
  std::vector<real> a(static_cast<std::size_t>(sim->num_robots() * sim->action_dim()));
  for (int s = 0; s < 60; ++s) {
    for (real& v : a) v = rng.uniform(-50, 50);
    sim->step(a.data());
    if (torques_seen != nullptr)
      torques_seen->insert(torques_seen->end(), sim->torques(), sim->torques() + sim->num_robots() * sim->num_dofs());
  }
  const std::uint64_t h = sim->state_hash();
  if (keep != nullptr) *keep = sim.get();
  if (owner != nullptr) *owner = std::move(sim);
  return h;
}

}  // namespace

TEST(Articulated, RandomTargetsAtTheTorqueLimitsAreFiniteAndThreadCountIndependent) {
  std::vector<real> torques;
  Simulator* sim = nullptr;
  std::unique_ptr<Simulator> owner;
  const std::uint64_t h1 = random_run(1, 5, &torques, &sim, &owner);
  EXPECT_EQ(random_run(2, 5), h1);  // slices of 2 and 3 environments
  EXPECT_EQ(random_run(3, 5), h1);
  ASSERT_NE(sim, nullptr);
  // The drive saturates: torques reach the effort limits and never pass them.
  ArticulatedRobot r;
  std::string err;
  ASSERT_TRUE(load_robot_model(sim->config().robot.model_file, r, err));
  std::vector<real> limit;
  for (int b = 0; b < r.multibody.num_bodies; ++b)
    if (r.multibody.dof_index[b] >= 0 && r.multibody.joint[b] != dynamics::JointType::free) limit.push_back(r.multibody.effort_limit[b]);
  ASSERT_EQ(static_cast<int>(limit.size()), sim->num_dofs());
  int at_limit = 0;
  for (std::size_t k = 0; k < torques.size(); ++k) {
    const real lim = limit[k % limit.size()];
    ASSERT_TRUE(std::isfinite(torques[k]));
    EXPECT_LE(std::fabs(torques[k]), lim * (1 + 1e-6));
    at_limit += std::fabs(torques[k]) >= lim * (1 - 1e-6) ? 1 : 0;
  }
  EXPECT_GT(at_limit, static_cast<int>(torques.size() / 4));
  // Every view finite, dof_pos within the joints' ranges (the limits hold) up to a small overshoot.
  const int n = sim->num_robots(), nd = sim->num_dofs();
  for (int i = 0; i < n * 3; ++i) ASSERT_TRUE(std::isfinite(sim->base_pos_w()[i]) && std::isfinite(sim->base_lin_vel_w()[i]));
  for (int i = 0; i < n * nd; ++i) ASSERT_TRUE(std::isfinite(sim->dof_pos()[i]) && std::isfinite(sim->dof_vel()[i]));
  for (int i = 0; i < n * sim->num_links() * 3; ++i) ASSERT_TRUE(std::isfinite(sim->link_contact_forces_w()[i]));
  int j = 0;
  for (int b = 0; b < r.multibody.num_bodies; ++b) {
    if (r.multibody.dof_index[b] < 0 || r.multibody.joint[b] == dynamics::JointType::free) continue;
    if (r.multibody.has_limit[b])
      for (int i = 0; i < n; ++i) {
        EXPECT_GE(sim->dof_pos()[i * nd + j], r.multibody.q_min[b] - 0.05);
        EXPECT_LE(sim->dof_pos()[i * nd + j], r.multibody.q_max[b] + 0.05);
      }
    ++j;
  }
  EXPECT_EQ(sim->summary().reset_errors, 0u);  // no step refused
}

// The batched constrained step (sim/src/backends/articulated_batch.hpp, several robots per SIMD
// step) against the scalar step for every robot (KESTREL_LEGGED_BATCH=off): the same state hash
// and views, bit for bit, with whole and partial batches (21 robots: 8 + 8 + 5 on one thread,
// slices of 10 and 11 on two), robots falling onto rough ground under random targets.
TEST(Articulated, TheBatchedStepGivesEveryRobotTheScalarStepsBits) {
  struct Views {
    std::uint64_t hash = 0;
    std::vector<real> dof_pos, dof_vel, forces, torques;
  };
  auto run = [](int threads, bool batched, bool self = false) {
    if (!batched) setenv("KESTREL_LEGGED_BATCH", "off", 1);
    Views v;
    Simulator* sim = nullptr;
    std::unique_ptr<Simulator> owner;
    v.hash = random_run(threads, 21, nullptr, &sim, &owner, self);
    unsetenv("KESTREL_LEGGED_BATCH");
    if (sim == nullptr) return v;
    const int n = sim->num_robots(), nd = sim->num_dofs();
    v.dof_pos.assign(sim->dof_pos(), sim->dof_pos() + n * nd);
    v.dof_vel.assign(sim->dof_vel(), sim->dof_vel() + n * nd);
    v.forces.assign(sim->link_contact_forces_w(), sim->link_contact_forces_w() + n * sim->num_links() * 3);
    v.torques.assign(sim->torques(), sim->torques() + n * nd);
    return v;
  };
  const Views scalar = run(1, false);
  ASSERT_NE(scalar.hash, 0u);
  for (int threads : {1, 2}) {
    const Views b = run(threads, true);
    EXPECT_EQ(b.hash, scalar.hash) << threads << " threads";
    // With robot.self_collisions the batch takes the two-body contacts too: the same bits.
    const Views sb = run(threads, true, true), ss = run(1, false, true);
    EXPECT_EQ(sb.hash, ss.hash) << threads << " threads, self-collisions";
    EXPECT_NE(ss.hash, scalar.hash) << "the legs touched each other (else self-collisions change nothing)";
    EXPECT_EQ(std::memcmp(sb.dof_vel.data(), ss.dof_vel.data(), ss.dof_vel.size() * sizeof(real)), 0);
    EXPECT_EQ(std::memcmp(sb.forces.data(), ss.forces.data(), ss.forces.size() * sizeof(real)), 0);
    EXPECT_EQ(std::memcmp(b.dof_pos.data(), scalar.dof_pos.data(), scalar.dof_pos.size() * sizeof(real)), 0);
    EXPECT_EQ(std::memcmp(b.dof_vel.data(), scalar.dof_vel.data(), scalar.dof_vel.size() * sizeof(real)), 0);
    ASSERT_EQ(b.forces.size(), scalar.forces.size());
    EXPECT_EQ(std::memcmp(b.forces.data(), scalar.forces.data(), scalar.forces.size() * sizeof(real)), 0);
    EXPECT_EQ(std::memcmp(b.torques.data(), scalar.torques.data(), scalar.torques.size() * sizeof(real)), 0);
  }
  // The robots did touch the ground with more than their feet (the batch's union of contacts).
  double force = 0;
  for (real f : scalar.forces) force += std::fabs(static_cast<double>(f));
  EXPECT_GT(force, 1.0);
}

TEST(Articulated, SpawnedHalfInTheGroundIsPushedOutAndResetsWriteExactly) {
  WorldConfig c = legged("anymal_c", 2);
  std::string err;
  std::unique_ptr<Simulator> sim = make_simulator(c, err);
  ASSERT_TRUE(sim) << err;
  EXPECT_EQ(sim->num_dofs(), 12);
  EXPECT_EQ(sim->num_feet(), 4);
  EXPECT_EQ(std::string(sim->controller_name()), "joint_pd");
  // Env 1's base 3 cm above the ground: legs and trunk partly below it.
  const int env = 1;
  const real pos[3] = {sim->base_pos_w()[3], sim->base_pos_w()[4], 0.03_r}, quat[4] = {0, 0, 0, 1}, zero3[3] = {0, 0, 0};
  ASSERT_TRUE(sim->reset_root_states(&env, 1, pos, quat, zero3, zero3)) << sim->last_error();
  EXPECT_EQ(sim->base_pos_w()[5], 0.03_r);
  // reset_dofs writes the joints exactly and the views show them at once.
  std::vector<real> dp(12), dv(12);
  for (int k = 0; k < 12; ++k) {
    dp[static_cast<std::size_t>(k)] = 0.01_r * static_cast<real>(k);
    dv[static_cast<std::size_t>(k)] = -0.02_r * static_cast<real>(k);
  }
  ASSERT_TRUE(sim->reset_dofs(&env, 1, dp.data(), dv.data())) << sim->last_error();
  for (int k = 0; k < 12; ++k) {
    EXPECT_EQ(sim->dof_pos()[12 + k], dp[static_cast<std::size_t>(k)]);
    EXPECT_EQ(sim->dof_vel()[12 + k], dv[static_cast<std::size_t>(k)]);
  }
  const int bad_env = 7;
  EXPECT_FALSE(sim->reset_dofs(&bad_env, 1, dp.data(), dv.data()));
  EXPECT_NE(sim->last_error().find("env id 7"), std::string::npos);
  dp[3] = std::numeric_limits<real>::quiet_NaN();
  EXPECT_FALSE(sim->reset_dofs(&env, 1, dp.data(), dv.data()));
  EXPECT_NE(sim->last_error().find("non-finite"), std::string::npos);
  sim->set_auto_reset(false);
  std::vector<real> a(static_cast<std::size_t>(sim->num_robots() * sim->action_dim()), 0);
  for (int s = 0; s < 50; ++s) sim->step(a.data());
  // Climbed out of the ground (at most max_push_mps, not launched) and finite; its first steps
  // count as base contacts (crashes).
  EXPECT_GT(sim->base_pos_w()[5], 0.2_r);
  EXPECT_LT(sim->base_pos_w()[5], 0.8_r);
  for (int k = 0; k < 6; ++k) EXPECT_TRUE(std::isfinite(sim->base_pos_w()[k]));
  EXPECT_GE(sim->summary().crashes, 1u);
  // The feet view is where the feet are: on the ground (their spheres' centres ~3 cm up).
  for (int f = 0; f < 4; ++f) EXPECT_NEAR(sim->feet_pos_w()[3 * f + 2], 0.03, 0.03);
}

TEST(Articulated, ThePlanarBackendAndObstaclesRefuseArticulatedRobotsByName) {
  WorldConfig c = legged("go2", 2);
  std::string err;
  EXPECT_FALSE(make_simulator(c, Backend::planar, err));
  EXPECT_NE(err.find("go2"), std::string::npos);
  EXPECT_NE(err.find("simulator: rigid"), std::string::npos);
  WorldConfig bad = legged("go2", 2);
  bad.robot.model_file = "/nonexistent/robot.xml";
  err.clear();
  EXPECT_FALSE(make_simulator(bad, err));
  EXPECT_NE(err.find("/nonexistent/robot.xml"), std::string::npos);
  WorldConfig two = legged("go2", 2);
  two.robot.robots_per_env = 2;
  err.clear();
  EXPECT_FALSE(make_simulator(two, err));
  EXPECT_NE(err.find("robots_per_env"), std::string::npos);
  std::unique_ptr<Simulator> sim = make_simulator(c, err);
  ASSERT_TRUE(sim) << err;
  ObstacleBox box;
  EXPECT_FALSE(sim->set_obstacle_box(0, box));
  EXPECT_NE(sim->last_error().find("articulated"), std::string::npos);
}

TEST(Articulated, JointGainScalesDelayAndModesFollowTheScenario) {
  // legged_gym's Kp/Kd randomisation: scales drawn per reset within the ranges, each robot its own,
  // and the torques they give; the delay line holds the action back; V and T modes drive too.
  WorldConfig c = legged("go2", 6);
  c.robot.joint_kp_scale_min = 0.8_r;
  c.robot.joint_kp_scale_max = 1.2_r;
  c.robot.joint_kd_scale_min = 0.5_r;
  c.robot.joint_kd_scale_max = 1.5_r;
  std::string err;
  std::unique_ptr<Simulator> sim = make_simulator(c, err);
  ASSERT_TRUE(sim) << err;
  std::vector<real> kp(sim->dr_kp_scale(), sim->dr_kp_scale() + 6), kd(sim->dr_kd_scale(), sim->dr_kd_scale() + 6);
  for (int i = 0; i < 6; ++i) {
    EXPECT_GE(kp[static_cast<std::size_t>(i)], 0.8_r);
    EXPECT_LE(kp[static_cast<std::size_t>(i)], 1.2_r);
    EXPECT_GE(kd[static_cast<std::size_t>(i)], 0.5_r);
    EXPECT_LE(kd[static_cast<std::size_t>(i)], 1.5_r);
  }
  EXPECT_NE(kp[0], kp[1]);  // drawn per robot
  std::vector<real> a(static_cast<std::size_t>(6 * 12), 0);
  sim->step(a.data());
  // Robots with a stiffer drive hold their home pose closer: the sag of the thigh joints falls
  // as the kp scale grows (the same weight on every robot).
  for (int k = 0; k < 100; ++k) sim->step(a.data());
  ArticulatedRobot r;
  ASSERT_TRUE(load_robot_model(c.robot.model_file, r, err));
  int stiff = 0, soft = 0;
  for (int i = 1; i < 6; ++i) {
    if (kp[static_cast<std::size_t>(i)] > kp[static_cast<std::size_t>(stiff)]) stiff = i;
    if (kp[static_cast<std::size_t>(i)] < kp[static_cast<std::size_t>(soft)]) soft = i;
  }
  auto sag = [&](int i) {
    double s = 0;
    for (int j = 0; j < 12; ++j) s += std::fabs(sim->dof_pos()[i * 12 + j] - r.home_q[static_cast<std::size_t>(7 + j)]);
    return s;
  };
  EXPECT_LT(sag(stiff), sag(soft));
  const int env = 2;
  sim->reset_idx(&env, 1);
  EXPECT_NE(sim->dr_kp_scale()[2], kp[2]);  // redrawn at the reset
  EXPECT_EQ(sim->dr_kp_scale()[3], kp[3]);  // the others kept

  // Delay: with 3 physics steps of delay, one env-step of 2 physics steps applies no action yet.
  for (int delay = 0; delay <= 3; delay += 3) {
    WorldConfig cd = legged("go2", 1);
    cd.env.num_physics_steps_per_env_step_mean = 2;
    cd.robot.joint_delay_steps = delay;
    std::unique_ptr<Simulator> s2 = make_simulator(cd, err);
    ASSERT_TRUE(s2) << err;
    std::vector<real> zero(12, 0), big(12, 2);
    for (int k = 0; k < 50; ++k) s2->step(zero.data());  // settle
    const real before = s2->torques()[2];
    s2->step(big.data());
    const real change = std::fabs(s2->torques()[2] - before);
    if (delay == 0) {
      EXPECT_GT(change, 5.0);  // 20 N m/rad x 0.5 rad of target
    } else {
      EXPECT_LT(change, 1.0);  // still the old target
    }
  }
  for (const JointControlMode mode : {JointControlMode::velocity, JointControlMode::torque}) {
    WorldConfig cm = legged("go2", 1);
    cm.robot.joint_control_mode = mode;
    std::unique_ptr<Simulator> s3 = make_simulator(cm, err);
    ASSERT_TRUE(s3) << err;
    std::vector<real> act(12, 0.1_r);
    for (int k = 0; k < 20; ++k) s3->step(act.data());
    for (int j = 0; j < 12; ++j) EXPECT_TRUE(std::isfinite(s3->dof_pos()[j]));
    if (mode == JointControlMode::torque) {
      EXPECT_NEAR(s3->torques()[0], 0.1 * cm.robot.action_scale, 1e-6);
    }
  }
}

TEST(Articulated, MeasuredHeightsFollowTheTerrainAroundTheBase) {
  // legged_gym's height points on the 0.2-per-metre slope (z rises along +x): points 1.6 m apart
  // along the base's x differ by 0.32 m while the robot faces +x, and by -0.32 m once it faces -x.
  WorldConfig c = legged("go2", 1);
  c.env.terrain.type = TerrainType::heightfield;
  c.env.terrain.procedural = "slope";
  c.env.terrain.slope = 0.2_r;
  c.env.terrain.measure_heights = true;  // the default 17 x 11 points, x in [-0.8, 0.8], y in [-0.5, 0.5]
  std::string err;
  std::unique_ptr<Simulator> sim = make_simulator(c, err);
  ASSERT_TRUE(sim) << err;
  ASSERT_EQ(sim->num_height_points(), 17 * 11);
  const real* h = sim->measured_heights();
  ASSERT_NE(h, nullptr);
  const int front = 16 * 11 + 5, back = 0 * 11 + 5;  // x = +0.8 and -0.8 at y = 0 (x-major)
  EXPECT_NEAR(h[front] - h[back], 0.32, 0.01);
  EXPECT_NEAR(h[16 * 11 + 0], h[16 * 11 + 10], 1e-4);  // across y: level
  // Turned to face -x (yaw pi) at the same place: the points swap sides.
  const int env = 0;
  const real pos[3] = {sim->base_pos_w()[0], sim->base_pos_w()[1], sim->base_pos_w()[2]}, quat[4] = {0, 0, 1, 0}, zero[3] = {};
  ASSERT_TRUE(sim->reset_root_states(&env, 1, pos, quat, zero, zero)) << sim->last_error();
  EXPECT_NEAR(sim->measured_heights()[front] - sim->measured_heights()[back], -0.32, 0.01);
  // Without measure_heights: none.
  std::unique_ptr<Simulator> flat = make_simulator(legged("go2", 1), err);
  ASSERT_TRUE(flat) << err;
  EXPECT_EQ(flat->num_height_points(), 0);
  EXPECT_EQ(flat->measured_heights(), nullptr);
}

namespace {

using kestrel::test::randomise_all_articulated;
using kestrel::test::tiled_terrain;

// Sum of the ground's vertical force on the feet that sit ahead of the base (body x > 0 at home),
// as a share of all the feet's.
double front_share(const Simulator& sim, int robot) {
  const RobotLayout& l = sim.robot_layout();
  const real* lf = sim.link_contact_forces_w() + static_cast<std::ptrdiff_t>(robot) * sim.num_links() * 3;
  const real* fp = sim.feet_pos_w() + static_cast<std::ptrdiff_t>(robot) * sim.num_feet() * 3;
  const real bx = sim.base_pos_w()[3 * robot];
  double front = 0, all = 0;
  for (int f = 0; f < sim.num_feet(); ++f) {
    const double fz = lf[3 * l.foot_links[static_cast<std::size_t>(f)] + 2];
    all += fz;
    if (fp[3 * f] > bx) front += fz;
  }
  return all > 0 ? front / all : 0;
}

}  // namespace

TEST(Articulated, DomainRandomisationViewsAreDrawnPerRobotWithinTheirRanges) {
  WorldConfig c = legged("go2", 6);
  randomise_all_articulated(c);
  std::string err;
  std::unique_ptr<Simulator> sim = make_simulator(c, err);
  ASSERT_TRUE(sim) << err;
  const int n = 6, nd = sim->num_dofs();
  auto in = [](real v, real lo, real hi) { return v >= lo && v <= hi; };
  for (int i = 0; i < n; ++i) {
    EXPECT_TRUE(in(sim->dr_friction_values()[i], 0.5_r, 1.25_r));
    EXPECT_TRUE(in(sim->dr_restitution_values()[i], 0, 0.5_r));
    EXPECT_TRUE(in(sim->added_mass_kg()[i], -1, 3));
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(in(sim->com_bias_b_m()[3 * i + k], -0.05_r, 0.05_r));
    for (int j = 0; j < nd; ++j) EXPECT_TRUE(in(sim->dr_joint_armature()[i * nd + j], 0.005_r, 0.02_r));
  }
  EXPECT_NE(sim->dr_friction_values()[0], sim->dr_friction_values()[1]);  // drawn per robot
  EXPECT_NE(sim->added_mass_kg()[0], sim->added_mass_kg()[1]);
  EXPECT_NE(sim->dr_joint_armature()[0], sim->dr_joint_armature()[1]);    // and per joint
  const std::vector<real> mu(sim->dr_friction_values(), sim->dr_friction_values() + n);
  const std::vector<real> dm(sim->added_mass_kg(), sim->added_mass_kg() + n);
  const int env = 2;
  sim->reset_idx(&env, 1);
  EXPECT_NE(sim->dr_friction_values()[2], mu[2]);  // redrawn at the reset
  EXPECT_NE(sim->added_mass_kg()[2], dm[2]);
  EXPECT_EQ(sim->dr_friction_values()[3], mu[3]);  // the others kept
  EXPECT_EQ(sim->added_mass_kg()[3], dm[3]);

  // Off by default: -1 for the contact values, no added mass or bias, the file's armature.
  std::unique_ptr<Simulator> plain = make_simulator(legged("go2", 2), err);
  ASSERT_TRUE(plain) << err;
  ArticulatedRobot r;
  ASSERT_TRUE(load_robot_model(plain->config().robot.model_file, r, err));
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(plain->dr_friction_values()[i], -1);
    EXPECT_EQ(plain->dr_restitution_values()[i], -1);
    EXPECT_EQ(plain->added_mass_kg()[i], 0);
    const real arm = plain->config().robot.joint_armature_kg_m2;
    for (int j = 0; j < nd; ++j) {
      if (arm >= 0) {
        EXPECT_EQ(plain->dr_joint_armature()[i * nd + j], arm);
      } else {
        EXPECT_GE(plain->dr_joint_armature()[i * nd + j], 0);
      }
    }
  }

  // Refusals name the field and the allowed values; other robots refuse the articulated-only ones.
  WorldConfig bad = legged("go2", 1);
  bad.simulator.restitution_min = 0.2_r;
  bad.simulator.restitution_max = 0.1_r;
  EXPECT_FALSE(make_simulator(bad, err));
  EXPECT_NE(err.find("simulator.restitution"), std::string::npos) << err;
  bad = legged("go2", 1);
  bad.simulator.added_mass_min_kg = -100;
  EXPECT_FALSE(make_simulator(bad, err));
  EXPECT_NE(err.find("simulator.added_mass_kg"), std::string::npos) << err;
  WorldConfig quad;
  quad.simulator.friction_min = quad.simulator.friction_max = 0.5_r;
  EXPECT_FALSE(make_simulator(quad, Backend::rigid, err));
  EXPECT_NE(err.find("simulator.friction"), std::string::npos) << err;
  EXPECT_FALSE(make_simulator(quad, Backend::planar, err));
  EXPECT_NE(err.find("simulator.friction"), std::string::npos) << err;
  std::unique_ptr<Simulator> quad_sim = make_simulator(WorldConfig{}, err);
  ASSERT_TRUE(quad_sim) << err;
  EXPECT_FALSE(quad_sim->push_links());
  EXPECT_NE(quad_sim->last_error().find("articulated only"), std::string::npos);
}

TEST(Articulated, RandomisedMassCentreOfMassFrictionRestitutionAndArmatureActOnTheRobot) {
  std::string err;
  // Added base mass: the ground carries the new weight at rest (within 2 %).
  const double mass = total_mass("go2");
  for (const real added : {-1.0_r, 3.0_r}) {
    WorldConfig c = legged("go2", 1);
    c.simulator.added_mass_min_kg = c.simulator.added_mass_max_kg = added;
    const Standing s = stand(c);
    EXPECT_NEAR(s.force_N[2], (mass + added) * 9.81, 0.02 * (mass + added) * 9.81) << added;
    EXPECT_LT(s.drift_m, 1e-3);
  }
  // Centre-of-mass bias: the robot whose base mass sits furthest forward puts the largest share of
  // its weight on its front feet, the one furthest back the least.
  {
    WorldConfig c = legged("go2", 8);
    c.simulator.com_bias_max_m = 0.06_r;
    std::unique_ptr<Simulator> sim = make_simulator(c, err);
    ASSERT_TRUE(sim) << err;
    std::vector<real> zero(static_cast<std::size_t>(sim->num_robots() * sim->action_dim()), 0);
    for (int s = 0; s < 150; ++s) sim->step(zero.data());
    int fwd = 0, back = 0;
    for (int i = 1; i < 8; ++i) {
      if (sim->com_bias_b_m()[3 * i] > sim->com_bias_b_m()[3 * fwd]) fwd = i;
      if (sim->com_bias_b_m()[3 * i] < sim->com_bias_b_m()[3 * back]) back = i;
    }
    ASSERT_GT(sim->com_bias_b_m()[3 * fwd] - sim->com_bias_b_m()[3 * back], 0.04_r);
    EXPECT_GT(front_share(*sim, fwd), front_share(*sim, back) + 0.05) << front_share(*sim, fwd) << " " << front_share(*sim, back);
  }
  // Friction: on legged_gym's 11-degree slope (rise 0.2) the robot holds at mu 1 and slides at
  // mu 0.05 < tan(11.3 deg).
  {
    double travel[2] = {0, 0};
    const real mus[2] = {1.0_r, 0.05_r};
    for (int k = 0; k < 2; ++k) {
      WorldConfig c = legged("go2", 1);
      c.env.terrain.type = TerrainType::heightfield;
      c.env.terrain.procedural = "slope";
      c.env.terrain.slope = 0.2_r;
      c.env.terrain.length_x_m = 8;
      c.env.terrain.width_y_m = 8;
      c.simulator.friction_min = c.simulator.friction_max = mus[k];
      std::unique_ptr<Simulator> sim = make_simulator(c, err);
      ASSERT_TRUE(sim) << err;
      EXPECT_EQ(sim->dr_friction_values()[0], mus[k]);
      std::vector<real> zero(12, 0);
      for (int s = 0; s < 100; ++s) sim->step(zero.data());
      const Vec3 p0(sim->base_pos_w()[0], sim->base_pos_w()[1], sim->base_pos_w()[2]);
      for (int s = 0; s < 100; ++s) sim->step(zero.data());
      travel[k] = (Vec3(sim->base_pos_w()[0], sim->base_pos_w()[1], sim->base_pos_w()[2]) - p0).norm();
    }
    EXPECT_LT(travel[0], 2e-3);
    EXPECT_GT(travel[1], 0.05);
  }
  // Restitution: dropped from 0.5 m above its standing height, the feet of the robot whose
  // contacts have restitution 1 bounce off the ground (they leave it upwards at about their impact
  // speed); with 0 they stay on it.
  {
    double rebound[2] = {0, 0};
    for (int k = 0; k < 2; ++k) {
      WorldConfig c = legged("go2", 1);
      c.env.num_physics_steps_per_env_step_mean = 1;
      c.simulator.restitution_min = c.simulator.restitution_max = static_cast<real>(1 - k);
      std::unique_ptr<Simulator> sim = make_simulator(c, err);
      ASSERT_TRUE(sim) << err;
      const int env = 0;
      const real pos[3] = {sim->base_pos_w()[0], sim->base_pos_w()[1], sim->base_pos_w()[2] + 0.5_r}, quat[4] = {0, 0, 0, 1},
                 zero3[3] = {0, 0, 0};
      ASSERT_TRUE(sim->reset_root_states(&env, 1, pos, quat, zero3, zero3));
      std::vector<real> zero(12, 0);
      real last = sim->feet_pos_w()[2];
      for (int s = 0; s < 100; ++s) {
        sim->step(zero.data());
        const real z = sim->feet_pos_w()[2];  // foot 0
        rebound[k] = std::max(rebound[k], static_cast<double>((z - last) / c.sim.dt_s));
        last = z;
      }
    }
    EXPECT_GT(rebound[0], 1.0) << rebound[0];  // impact at sqrt(2 g 0.5) = 3.1 m/s
    EXPECT_LT(rebound[1], 0.5) << rebound[1];
  }
  // Armature: a joint with a heavy rotor answers a step of its target more slowly.
  {
    double speed[2] = {0, 0};
    for (int k = 0; k < 2; ++k) {
      WorldConfig c = legged("go2", 1);
      c.env.num_physics_steps_per_env_step_mean = 1;
      c.simulator.joint_armature_min_kg_m2 = c.simulator.joint_armature_max_kg_m2 = k == 0 ? 0.001_r : 0.2_r;
      std::unique_ptr<Simulator> sim = make_simulator(c, err);
      ASSERT_TRUE(sim) << err;
      std::vector<real> zero(12, 0), step(12, 2);
      for (int s = 0; s < 100; ++s) sim->step(zero.data());
      sim->step(step.data());
      for (int j = 0; j < 12; ++j) speed[k] += std::fabs(sim->dof_vel()[j]);
    }
    EXPECT_LT(speed[1], 0.5 * speed[0]) << speed[0] << " " << speed[1];
  }
}

TEST(Articulated, PushLinksAppliesItsForcesForOnePhysicsStepAndKeepsResultsThreadIndependent) {
  std::string err;
  // In the air (no contact): after one physics step the base's velocity changes by about the
  // pushes' total impulse over the robot's mass, in its direction, against the same robot unpushed.
  WorldConfig c = legged("go2", 2);
  c.env.num_physics_steps_per_env_step_mean = 1;
  c.simulator.max_push_force_N = 100;
  std::unique_ptr<Simulator> sim = make_simulator(c, err);
  ASSERT_TRUE(sim) << err;
  const int ids[2] = {0, 1};
  real pos[6], quat[8] = {0, 0, 0, 1, 0, 0, 0, 1}, zero6[6] = {0, 0, 0, 0, 0, 0};
  for (int k = 0; k < 6; ++k) pos[k] = sim->base_pos_w()[k] + (k % 3 == 2 ? 2 : 0);
  ASSERT_TRUE(sim->reset_root_states(ids, 2, pos, quat, zero6, zero6));
  std::unique_ptr<Simulator> ref = make_simulator(c, err);
  ASSERT_TRUE(ref) << err;
  ASSERT_TRUE(ref->reset_root_states(ids, 2, pos, quat, zero6, zero6));
  ASSERT_TRUE(sim->push_links()) << sim->last_error();
  // The forces drawn: the same stream a second simulator would draw (they are not a view), so
  // recompute them here from the documented stream.
  const int nl = sim->num_links();
  std::vector<real> a(24, 0);
  sim->step(a.data());
  ref->step(a.data());
  const double mass = total_mass("go2");
  for (int e = 0; e < 2; ++e) {
    RngStream rng(c.seed, static_cast<std::uint32_t>(e), kPurposeLinkPush);
    Vec3 total = Vec3::Zero();
    for (int b = 0; b < nl; ++b)
      for (int k = 0; k < 3; ++k) total[k] += rng.uniform(-100, 100);
    const Vec3 dv_expected = total * c.sim.dt_s / static_cast<real>(mass);
    Vec3 dv;
    for (int k = 0; k < 3; ++k) dv[k] = sim->base_lin_vel_w()[3 * e + k] - ref->base_lin_vel_w()[3 * e + k];
    EXPECT_GT(dv.dot(dv_expected) / (dv.norm() * dv_expected.norm()), 0.9) << e;
    EXPECT_NEAR(dv.norm(), dv_expected.norm(), 0.35 * dv_expected.norm()) << e;
  }
  // Only for that one physics step: with 4 physics steps per env-step the change is still about one
  // step's impulse (4 steps' would be 4 times as large).
  c.env.num_physics_steps_per_env_step_mean = 4;
  std::unique_ptr<Simulator> sim4 = make_simulator(c, err), ref4 = make_simulator(c, err);
  ASSERT_TRUE(sim4 && ref4) << err;
  ASSERT_TRUE(sim4->reset_root_states(ids, 2, pos, quat, zero6, zero6));
  ASSERT_TRUE(ref4->reset_root_states(ids, 2, pos, quat, zero6, zero6));
  ASSERT_TRUE(sim4->push_links());
  sim4->step(a.data());
  ref4->step(a.data());
  for (int e = 0; e < 2; ++e) {
    RngStream rng(c.seed, static_cast<std::uint32_t>(e), kPurposeLinkPush);
    Vec3 total = Vec3::Zero();
    for (int b = 0; b < nl; ++b)
      for (int k = 0; k < 3; ++k) total[k] += rng.uniform(-100, 100);
    const double one_step = (total * c.sim.dt_s / static_cast<real>(mass)).norm();
    Vec3 dv;
    for (int k = 0; k < 3; ++k) dv[k] = sim4->base_lin_vel_w()[3 * e + k] - ref4->base_lin_vel_w()[3 * e + k];
    EXPECT_LT(dv.norm(), 2 * one_step) << e;
    EXPECT_GT(dv.norm(), 0.5 * one_step) << e;
  }

  // Every randomisation and push_links on: bit-identical for 1, 2 and 3 threads.
  std::uint64_t hashes[3] = {};
  for (int t = 1; t <= 3; ++t) {
    WorldConfig d = legged("go2", 5, t);
    d.task.episode_len_env_steps = 40;
    randomise_all_articulated(d);
    std::unique_ptr<Simulator> s = make_simulator(d, err);
    ASSERT_TRUE(s) << err;
    RngStream rng(5, 0, kPurposeUser + 40);
    std::vector<real> act(static_cast<std::size_t>(s->num_robots() * s->action_dim()));
    for (int k = 0; k < 120; ++k) {
      for (real& v : act) v = rng.uniform(-1, 1);
      if (k % 25 == 0) {
        EXPECT_TRUE(s->push_links());
      }
      s->step(act.data());
    }
    for (int k = 0; k < s->num_robots() * 3; ++k) EXPECT_TRUE(std::isfinite(s->base_pos_w()[k]));
    hashes[t - 1] = s->state_hash();
  }
  EXPECT_EQ(hashes[0], hashes[1]);
  EXPECT_EQ(hashes[0], hashes[2]);
}

TEST(Articulated, TerrainCurriculumPlacesRobotsOnTilesAndMovesTheirLevels) {
  WorldConfig c = legged("go2", 10);
  tiled_terrain(c.env.terrain, 4, 5, 1);
  std::string err;
  std::unique_ptr<Simulator> sim = make_simulator(c, err);
  ASSERT_TRUE(sim) << err;
  ASSERT_EQ(sim->num_terrain_levels(), 4);
  std::unique_ptr<Terrain> terrain;
  ASSERT_TRUE(Terrain::build(c.env.terrain, c.seed, terrain, err)) << err;
  for (int e = 0; e < 10; ++e) {
    EXPECT_EQ(sim->terrain_types()[e], e / 2);  // legged_gym: env e on type e * cols / envs
    EXPECT_GE(sim->terrain_levels()[e], 0);
    EXPECT_LE(sim->terrain_levels()[e], 1);  // max_init_terrain_level
    const Vec3& o = terrain->tile_origin(sim->terrain_levels()[e], sim->terrain_types()[e]);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(sim->env_origins_w()[3 * e + k], o[k]);
    // Spawned within 1 m of the tile's centre in x and y.
    EXPECT_LE(std::fabs(sim->base_pos_w()[3 * e] - o[0]), 1);
    EXPECT_LE(std::fabs(sim->base_pos_w()[3 * e + 1] - o[1]), 1);
  }
  // Up, down (not below 0), and past the top to a random level; the origin follows the level.
  const int ids[3] = {0, 1, 2};
  const int l0 = sim->terrain_levels()[0], l1 = sim->terrain_levels()[1];
  const std::uint8_t up[3] = {1, 0, 1}, down[3] = {0, 1, 0};
  ASSERT_TRUE(sim->update_terrain_curriculum(ids, 3, up, down)) << sim->last_error();
  EXPECT_EQ(sim->terrain_levels()[0], l0 + 1);
  EXPECT_EQ(sim->terrain_levels()[1], std::max(0, l1 - 1));
  const Vec3& o0 = terrain->tile_origin(l0 + 1, 0);
  EXPECT_EQ(sim->env_origins_w()[0], o0[0]);
  int seen_top = 0;
  for (int k = 0; k < 40; ++k) {
    const int env = 3;
    const std::uint8_t u = 1, d = 0;
    ASSERT_TRUE(sim->update_terrain_curriculum(&env, 1, &u, &d));
    EXPECT_LT(sim->terrain_levels()[3], 4);  // never past the top row
    seen_top += sim->terrain_levels()[3] == 3 ? 1 : 0;
  }
  EXPECT_GT(seen_top, 0);
  // The robot moves to its new tile at its next reset.
  const int env0 = 0;
  sim->reset_idx(&env0, 1);
  EXPECT_LE(std::fabs(sim->base_pos_w()[0] - o0[0]), 1);
  EXPECT_LE(std::fabs(sim->base_pos_w()[1] - o0[1]), 1);
  EXPECT_GT(sim->base_pos_w()[2], o0[2]);
  const int bad = 12;
  EXPECT_FALSE(sim->update_terrain_curriculum(&bad, 1, up, down));
  EXPECT_NE(sim->last_error().find("env id 12"), std::string::npos);
  // Without tiles: refused by name.
  std::unique_ptr<Simulator> flat = make_simulator(legged("go2", 2), err);
  ASSERT_TRUE(flat) << err;
  EXPECT_EQ(flat->num_terrain_levels(), 0);
  EXPECT_FALSE(flat->update_terrain_curriculum(ids, 1, up, down));
  EXPECT_NE(flat->last_error().find("tiled terrain"), std::string::npos);
}

// robot.self_collisions (off by default, as legged_gym's ANYmal has it): two arms on hinges from a
// fixed base, driven to swing their tips through each other. Off, the tips cross; on, the two-body
// contacts stop them at the tips' touching distance, and the link forces are equal and opposite.
// Go2 and ANYmal C standing at home are the same with it on (no pair touches at the home pose: a
// joint's two links, which overlap at the joint, are never a pair).
TEST(Articulated, SelfCollisionsStopTwoArmsFromPassingThroughEachOther) {
  const std::string path = ::testing::TempDir() + "kestrel_two_arms.xml";
  // Arms of length 0.3 m hanging at y = +-0.1 m, a tip at each end (a 0.03 m sphere, or a 0.06 m
  // cube given as a collision mesh); both hinges turn about x, so tip y = +-0.1 + 0.3 sin(q). The
  // base (body 0, whose contacts would end the joint_targets task's episode) has no collision
  // geometry and a stiff slide joint, held at 0.
  auto write = [&](bool mesh_tips) {
    std::FILE* f = std::fopen(path.c_str(), "w");
    ASSERT_NE(f, nullptr);
    const std::string tip = mesh_tips ? "type=\"mesh\" mesh=\"tip\"" : "type=\"sphere\" size=\"0.03\"";
    const std::string xml = std::string(R"(<mujoco model="two_arms">
  <compiler angle="radian"/>
  <asset><mesh name="tip" vertex="-0.03 -0.03 -0.03 0.03 -0.03 -0.03 -0.03 0.03 -0.03 0.03 0.03 -0.03 -0.03 -0.03 0.03 0.03 -0.03 0.03 -0.03 0.03 0.03 0.03 0.03 0.03"/></asset>
  <worldbody>
    <body name="base" pos="0 0 1">
      <joint name="slide" type="slide" axis="1 0 0" limited="true" range="-0.01 0.01"/>
      <geom type="box" size="0.05 0.15 0.02" mass="1" contype="0" conaffinity="0"/>
      <body name="arm_l" pos="0 0.1 0">
        <joint name="hinge_l" type="hinge" axis="1 0 0" limited="true" range="-1.2 1.2"/>
        <geom type="capsule" fromto="0 0 -0.05 0 0 -0.27" size="0.01" mass="0.1"/>
        <geom name="tip_l" pos="0 0 -0.3" mass="0.05" )") + tip + R"(/>
      </body>
      <body name="arm_r" pos="0 -0.1 0">
        <joint name="hinge_r" type="hinge" axis="1 0 0" limited="true" range="-1.2 1.2"/>
        <geom type="capsule" fromto="0 0 -0.05 0 0 -0.27" size="0.01" mass="0.1"/>
        <geom name="tip_r" pos="0 0 -0.3" mass="0.05" )" + tip + R"(/>
      </body>
    </body>
  </worldbody>
  <keyframe><key name="home" qpos="0 0 0"/></keyframe>
</mujoco>
)";
    std::fputs(xml.c_str(), f);
    std::fclose(f);
  };
  write(false);
  struct Run {
    double min_gap_m = 1e9, final_gap_m = 0, force_l_y = 0, force_r_y = 0;
  };
  auto run = [&](bool self) {
    WorldConfig c = legged("go2", 1);
    c.robot.model_file = path;
    c.robot.self_collisions = self;
    c.robot.action_scale = 0.25_r;
    std::string err;
    std::unique_ptr<Simulator> sim = make_simulator(c, err);
    Run r;
    EXPECT_TRUE(sim) << err;
    if (!sim) return r;
    EXPECT_EQ(sim->num_dofs(), 3);
    // Targets -0.5 rad (left) and +0.5 rad (right): the tips' targets are y = -+0.044 m, past
    // each other.
    const real a[3] = {0, -2, 2};
    for (int s = 0; s < 100; ++s) {
      sim->step(a);
      const real* q = sim->dof_pos();
      const double yl = 0.1 + 0.3 * std::sin(static_cast<double>(q[1])), yr = -0.1 + 0.3 * std::sin(static_cast<double>(q[2]));
      r.min_gap_m = std::min(r.min_gap_m, yl - yr);
      r.final_gap_m = yl - yr;
    }
    const real* lf = sim->link_contact_forces_w();
    r.force_l_y = lf[3 * 1 + 1];
    r.force_r_y = lf[3 * 2 + 1];
    EXPECT_EQ(sim->summary().resets, 0u);
    return r;
  };
  const Run off = run(false), on = run(true);
  EXPECT_LT(off.final_gap_m, -0.05);  // crossed: the targets are 0.088 m past each other
  EXPECT_EQ(off.force_l_y, 0);
  // On: the tips (0.03 m spheres) stop where they touch, 0.06 m apart, within the contact margin
  // and the solver's penetration.
  EXPECT_GT(on.min_gap_m, 0.06 - 0.005);
  EXPECT_LT(on.final_gap_m, 0.06 + 0.005);
  // The PD pushes each arm inwards; the contact pushes the left arm out (+y) and the right one out
  // (-y), equally.
  EXPECT_GT(on.force_l_y, 0.5);
  EXPECT_NEAR(on.force_r_y, -on.force_l_y, 1e-4 * on.force_l_y);
  // Mesh tips (libccd's MPR between the hulls: penetration only, no speculative margin): they
  // stop too, where the cubes touch, 0.06-0.072 m apart as they turn.
  write(true);
  const Run mesh_off = run(false), mesh_on = run(true);
  EXPECT_LT(mesh_off.final_gap_m, -0.05);
  EXPECT_GT(mesh_on.min_gap_m, 0.06 - 0.006);
  EXPECT_LT(mesh_on.final_gap_m, 0.072 + 0.005);
  EXPECT_GT(mesh_on.force_l_y, 0.5);
  EXPECT_NEAR(mesh_on.force_r_y, -mesh_on.force_l_y, 1e-4 * mesh_on.force_l_y);
  std::remove(path.c_str());

  for (const char* robot : {"go2", "anymal_c"}) {
    WorldConfig c = legged(robot, 1);
    const Standing a = stand(c);
    c.robot.self_collisions = true;
    const Standing b = stand(c);
    EXPECT_EQ(a.height_m, b.height_m) << robot;
    EXPECT_EQ(a.force_N, b.force_N) << robot;
  }
}

// A collision mesh collides with the ground through its hull's vertices (dynamics ShapeType::convex):
// a 0.2 m cube given as an 8-vertex mesh comes to rest where the same cube as a box primitive does,
// flat on a face. The cube hangs under a light root body by a hinge the PD holds (the root carries
// no collision geometry: its ground contact would end joint_targets' episode).
TEST(Articulated, ACollisionMeshRestsOnTheGroundLikeItsPrimitive) {
  auto write = [](const std::string& name, const std::string& geom) {
    const std::string path = ::testing::TempDir() + name;
    std::FILE* f = std::fopen(path.c_str(), "w");
    EXPECT_NE(f, nullptr);
    if (f == nullptr) return path;
    const std::string xml =
        "<mujoco><compiler angle=\"radian\"/><asset><mesh name=\"cube\" vertex=\"-0.1 -0.1 -0.1 0.1 -0.1 -0.1 -0.1 0.1 -0.1 "
        "0.1 0.1 -0.1 -0.1 -0.1 0.1 0.1 -0.1 0.1 -0.1 0.1 0.1 0.1 0.1 0.1\"/></asset><worldbody>"
        "<body name=\"base\" pos=\"0 0 0.5\"><freejoint/><inertial pos=\"0 0 0\" mass=\"0.1\" diaginertia=\"1e-4 1e-4 1e-4\"/>"
        "<body name=\"foot\" pos=\"0 0 -0.12\"><joint name=\"hinge\" type=\"hinge\" axis=\"1 0 0\" "
        "limited=\"true\" range=\"-0.5 0.5\"/>" + geom + "</body></body></worldbody>"
        "<keyframe><key name=\"home\" qpos=\"0 0 0.5 0.9938 0.0998 0.0497 0.005 0\"/></keyframe></mujoco>";
    std::fputs(xml.c_str(), f);
    std::fclose(f);
    return path;
  };
  const std::string mesh = write("kestrel_mesh_cube.xml", "<geom type=\"mesh\" mesh=\"cube\" mass=\"2\"/>");
  const std::string box = write("kestrel_box_cube.xml", "<geom type=\"box\" size=\"0.1 0.1 0.1\" mass=\"2\"/>");
  auto rest = [&](const std::string& path, Vec3& p, Vec4& q) {
    WorldConfig c = legged("go2", 1);
    c.robot.model_file = path;
    std::string err;
    std::unique_ptr<Simulator> sim = make_simulator(c, err);
    ASSERT_TRUE(sim) << err;
    const real a[1] = {0};
    for (int s = 0; s < 100; ++s) sim->step(a);  // 2 s: dropped 0.3 m, tilted, comes to rest
    p = Vec3(sim->base_pos_w()[0], sim->base_pos_w()[1], sim->base_pos_w()[2]);
    q = Vec4(sim->base_quat_xyzw()[0], sim->base_quat_xyzw()[1], sim->base_quat_xyzw()[2], sim->base_quat_xyzw()[3]);
    for (int i = 0; i < 3; ++i) EXPECT_TRUE(std::isfinite(p[i]));
  };
  Vec3 pm, pb;
  Vec4 qm, qb;
  rest(mesh, pm, qm);
  rest(box, pb, qb);
  EXPECT_NEAR(pm[2], 0.1 + 0.12, 3e-3);  // the cube on a face, the root 0.12 m above its centre
  EXPECT_NEAR(pb[2], 0.1 + 0.12, 3e-3);
  EXPECT_LT((pm - pb).norm(), 2e-3);
  // Dropped tilted (about 0.2 and 0.1 rad), it lands on a corner and settles flat: the root, which
  // the held hinge keeps aligned with the cube, upright.
  EXPECT_GT(rotation_matrix(quat_from_xyzw(qm))(2, 2), 0.999);
  EXPECT_GT(rotation_matrix(quat_from_xyzw(qb))(2, 2), 0.999);
  std::remove(mesh.c_str());
  std::remove(box.c_str());
}
