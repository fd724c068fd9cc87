// Articulated robots behind the Simulator interface (sim/src/backends/articulated.cpp): Go2 and
// ANYmal C from their model files stand under the joint PD at their home pose for 10 s on flat
// ground and on a slope within the friction limit (the base drifts less than 1 mm once settled and
// does not jitter; the feet carry the weight); random joint targets at the torque limits and a
// spawn partly in the ground stay finite; the views (dof_pos, dof_vel, torques, feet, link forces)
// agree with each other; results are bit-identical for 1, 2 and 3 threads; reset_dofs and
// reset_root_states write exactly; the planar backend refuses an articulated robot by name.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "kestrel/kernel/rng.hpp"
#include "kestrel/sim/articulated_robot.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/simulator.hpp"

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
      EXPECT_LT(s.drift_m, 1e-3);   // the bound, once settled
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
