// The planar (Box2D) backend: the ground vehicle follows the kinematic bicycle model (circle of
// radius L / tan(delta)), the 2-D lidar against analytic circle/box/wall distances, a collision
// stops the car, the fixed-altitude multirotor reaches its targets, domain randomisation draws,
// and bit-identical results for 1, 2 and 3 threads.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/simulator.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {

// An asset class at a fixed place and size (ratios of the bounds -10..10 on x and y).
AssetClass fixed(const char* name, AssetKind kind, real x, real y, real size, real yaw = 0) {
  AssetClass c;
  c.name = name;
  c.kind = kind;
  c.num_assets = c.min_num_assets = 1;
  c.keep_in_env = true;
  c.min_position_ratio = c.max_position_ratio = Vec3((x + 10) / 20, (y + 10) / 20, 0.5_r);
  c.min_size_m = c.max_size_m = Vec3::Constant(size);
  c.min_euler_rad = c.max_euler_rad = Vec3(0, 0, yaw);
  return c;
}

WorldConfig yard(bool car, std::vector<AssetClass> assets, int envs = 1) {
  WorldConfig c;
  c.simulator.backend = "planar";
  if (car) {
    EXPECT_TRUE(registries().robots.make("ground_vehicle", c.robot));
  }
  c.env.name = "test_yard";
  c.env.num_envs = envs;
  c.env.lower_bound_min_m = c.env.lower_bound_max_m = Vec3(-10, -10, 0);
  c.env.upper_bound_min_m = c.env.upper_bound_max_m = Vec3(10, 10, 2);
  c.env.assets = std::move(assets);
  c.task.episode_len_env_steps = 1000000;
  c.task.placement_attempts = 64;
  c.num_threads = 1;
  return c;
}

bool place(Simulator& s, int env, real x, real y, real yaw, real z = 0) {
  const Quat q = quat_from_euler_xyz(0, 0, yaw);
  const real pos[3] = {x, y, z}, quat[4] = {q.x(), q.y(), q.z(), q.w()}, zero[3] = {0, 0, 0};
  const int id[1] = {env};
  return s.reset_root_states(id, 1, pos, quat, zero, zero);
}

// Distance along a ray from o in direction d to a circle (centre c, radius r); inf if missed.
double ray_circle(double ox, double oy, double dx, double dy, double cx, double cy, double r) {
  const double fx = ox - cx, fy = oy - cy;
  const double b = fx * dx + fy * dy, c = fx * fx + fy * fy - r * r;
  const double disc = b * b - c;
  if (disc < 0) return INFINITY;
  const double t = -b - std::sqrt(disc);
  return t >= 0 ? t : INFINITY;
}
// Distance to an oriented box (centre, half extents, yaw) by the slab method in the box frame.
double ray_box(double ox, double oy, double dx, double dy, double cx, double cy, double hx, double hy, double yaw) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  const double lx = c * (ox - cx) + s * (oy - cy), ly = -s * (ox - cx) + c * (oy - cy);
  const double ldx = c * dx + s * dy, ldy = -s * dx + c * dy;
  double t0 = -INFINITY, t1 = INFINITY;
  const double o[2] = {lx, ly}, d[2] = {ldx, ldy}, h[2] = {hx, hy};
  for (int k = 0; k < 2; ++k) {
    if (std::fabs(d[k]) < 1e-12) {
      if (std::fabs(o[k]) > h[k]) return INFINITY;
      continue;
    }
    double a = (-h[k] - o[k]) / d[k], b = (h[k] - o[k]) / d[k];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  return (t0 <= t1 && t0 >= 0) ? t0 : INFINITY;
}

}  // namespace

TEST(Planar, GroundVehicleDrivesTheBicycleCircle) {
  std::string err;
  WorldConfig cfg = yard(true, {});
  cfg.simulator.wheelbase_m = 0.5_r;
  std::unique_ptr<Simulator> sim = make_simulator(cfg, err);
  ASSERT_TRUE(sim) << err;
  ASSERT_TRUE(sim->ground_vehicle());
  ASSERT_EQ(sim->action_dim(), 2);
  ASSERT_TRUE(place(*sim, 0, -3, 0, 0)) << sim->last_error();
  const real delta = 0.3_r, speed = 1;
  const real act[2] = {speed, delta};
  for (int s = 0; s < 500; ++s) sim->step(act);  // speed and steering settle (5 s)
  const double radius = 0.5 / std::tan(0.3);
  // Yaw rate of the bicycle model at the commanded speed and steering angle.
  EXPECT_NEAR(sim->base_lin_vel_b()[0], speed, 2e-3);
  EXPECT_NEAR(sim->base_lin_vel_b()[1], 0, 1e-4);  // no slip at the rear axle
  EXPECT_NEAR(sim->base_ang_vel_b()[2], speed / radius, 2e-3);
  // Centre of the circle to the left of the heading; the rear axle stays on it for 6 s (> 1 lap).
  const double psi = sim->base_euler_xyz()[2];
  const double cx = sim->base_pos_w()[0] - radius * std::sin(psi), cy = sim->base_pos_w()[1] + radius * std::cos(psi);
  double max_dev = 0;
  for (int s = 0; s < 600; ++s) {
    sim->step(act);
    const double dx = sim->base_pos_w()[0] - cx, dy = sim->base_pos_w()[1] - cy;
    max_dev = std::max(max_dev, std::fabs(std::sqrt(dx * dx + dy * dy) - radius));
  }
  EXPECT_LT(max_dev, 0.01 * radius) << "radius " << radius;
  EXPECT_EQ(sim->crashed()[0], 0);
}

TEST(Planar, LidarMatchesAnalyticGeometry) {
  std::string err;
  // A pillar (circle r 0.5 at (3, 0)), a box 1.2 m wide rotated 30 deg at (0, 4), walls at +-10.
  std::vector<AssetClass> a;
  AssetClass walls = fixed("walls", AssetKind::wall, 0, 0, 0);
  a.push_back(walls);
  a.push_back(fixed("pillar", AssetKind::thin, 3, 0, 0.5_r));
  a.push_back(fixed("box", AssetKind::cube, 0, 4, 1.2_r, 0.5235988_r));
  WorldConfig cfg = yard(false, a);
  cfg.simulator.lidar_beams = 73;  // 360/73 deg apart all around
  cfg.simulator.lidar_fov_rad = 2 * kPi * 72 / 73;
  cfg.simulator.lidar_max_range_m = 30;
  cfg.simulator.altitude_m = 1;
  std::unique_ptr<Simulator> sim = make_simulator(cfg, err);
  ASSERT_TRUE(sim) << err;
  const real x0 = -0.5_r, y0 = 0.25_r, yaw = 0.2_r;
  ASSERT_TRUE(place(*sim, 0, x0, y0, yaw, 1)) << sim->last_error();
  sim->update_sensors();
  int hits_pillar = 0, hits_box = 0;
  for (int k = 0; k < sim->lidar_beams(); ++k) {
    const double ang = yaw + sim->lidar_beam_angle(k);
    const double dx = std::cos(ang), dy = std::sin(ang);
    const double tc = ray_circle(x0, y0, dx, dy, 3, 0, 0.5);
    const double tb = ray_box(x0, y0, dx, dy, 0, 4, 0.6, 0.6, 0.5235988);
    // Walls: thin boxes whose inner faces are the bounds.
    double tw = INFINITY;
    if (dx > 1e-9) tw = std::min(tw, (10 - x0) / dx);
    if (dx < -1e-9) tw = std::min(tw, (-10 - x0) / dx);
    if (dy > 1e-9) tw = std::min(tw, (10 - y0) / dy);
    if (dy < -1e-9) tw = std::min(tw, (-10 - y0) / dy);
    const double expect = std::min(std::min(tc, tb), std::min(tw, 30.0));
    hits_pillar += tc < std::min(tb, tw) ? 1 : 0;
    hits_box += tb < std::min(tc, tw) ? 1 : 0;
    EXPECT_NEAR(sim->lidar_ranges_m()[k], expect, 2e-3) << "beam " << k << " angle " << ang;
  }
  EXPECT_GE(hits_pillar, 2);
  EXPECT_GE(hits_box, 2);
}

TEST(Planar, CollisionStopsTheVehicle) {
  std::string err;
  // A wall-like box whose near face is at x = 2 (cube 2 m wide centred at x = 3).
  WorldConfig cfg = yard(true, {fixed("block", AssetKind::cube, 3, 0, 2)});
  cfg.env.reset_on_collision = false;
  cfg.env.collision_force_threshold_N = 1;
  std::unique_ptr<Simulator> sim = make_simulator(cfg, err);
  ASSERT_TRUE(sim) << err;
  ASSERT_TRUE(place(*sim, 0, -2, 0, 0)) << sim->last_error();
  const real act[2] = {1.5_r, 0};
  bool crashed = false;
  real max_push_x = 0;
  for (int s = 0; s < 600; ++s) {
    sim->step(act);
    crashed = crashed || sim->crashed()[0] != 0;
    max_push_x = std::min(max_push_x, sim->contact_forces_w()[0]);
  }
  // The front of the car (rear axle + L/2 + half length = 0.415 m ahead) rests on the face x = 2.
  const real front = sim->base_pos_w()[0] + 0.33_r / 2 + 0.25_r;
  EXPECT_NEAR(front, 2, 0.03);
  EXPECT_NEAR(sim->base_pos_w()[1], 0, 1e-3);
  EXPECT_LT(std::fabs(sim->base_lin_vel_b()[0]), 0.2_r);  // pressed against the block, not moving on
  EXPECT_TRUE(crashed);
  EXPECT_LT(max_push_x, -1);  // the contact force pushes back along -x
  EXPECT_EQ(sim->reset_buf()[0], 0);
  // A later position is still at the block (no tunnelling through it).
  for (int s = 0; s < 200; ++s) sim->step(act);
  EXPECT_LT(sim->base_pos_w()[0] + 0.415_r, 2.03_r);
}

TEST(Planar, MultirotorReachesTargets) {
  std::string err;
  WorldConfig cfg = yard(false, {}, 8);
  cfg.simulator.altitude_m = 1.5_r;
  cfg.task.episode_len_env_steps = 700;
  std::unique_ptr<Simulator> sim = make_simulator(cfg, err);
  ASSERT_TRUE(sim) << err;
  EXPECT_FALSE(sim->ground_vehicle());
  std::vector<real> a(static_cast<std::size_t>(sim->num_robots() * sim->action_dim()));
  double start_dist = 0;
  for (int e = 0; e < 8; ++e) {
    start_dist += std::hypot(sim->target_w()[3 * e] - sim->base_pos_w()[3 * e], sim->target_w()[3 * e + 1] - sim->base_pos_w()[3 * e + 1]);
    EXPECT_EQ(sim->base_pos_w()[3 * e + 2], 1.5_r);
  }
  EXPECT_GT(start_dist / 8, 3);
  for (int s = 0; s < 690; ++s) {
    scripted_setpoint_actions(*sim, a.data());
    sim->step(a.data());
  }
  for (int e = 0; e < 8; ++e) {
    const double d = std::hypot(sim->target_w()[3 * e] - sim->base_pos_w()[3 * e], sim->target_w()[3 * e + 1] - sim->base_pos_w()[3 * e + 1]);
    EXPECT_LT(d, 0.1) << "env " << e;
    // Quasi-static reduced model: the thrust holds the weight (0.25 kg) at hover.
    EXPECT_NEAR(sim->applied_wrench_b()[6 * e + 2], 0.25 * 9.81, 0.05);
  }
  for (int s = 0; s < 20; ++s) sim->step(nullptr);  // timeout at 700 -> success counted
  const WorldSummary sum = sim->summary();
  EXPECT_EQ(sum.timeouts, 8u);
  EXPECT_EQ(sum.successes, 8u);
  EXPECT_EQ(sum.crashes, 0u);
}

TEST(Planar, DomainRandomisationDraws) {
  std::string err;
  WorldConfig cfg = yard(true, {}, 16);
  cfg.simulator.added_mass_min_kg = 0.2_r;
  cfg.simulator.added_mass_max_kg = 0.8_r;
  cfg.simulator.com_bias_max_m = 0.03_r;
  cfg.simulator.motor_scale_min = 0.7_r;
  cfg.simulator.motor_scale_max = 1.3_r;
  cfg.simulator.gain_scale_min = 0.5_r;
  cfg.simulator.gain_scale_max = 1.5_r;
  std::unique_ptr<Simulator> a = make_simulator(cfg, err), b = make_simulator(cfg, err);
  ASSERT_TRUE(a && b) << err;
  real lo = 1e9, hi = -1e9;
  for (int i = 0; i < 16; ++i) {
    EXPECT_GE(a->added_mass_kg()[i], 0.2_r);
    EXPECT_LE(a->added_mass_kg()[i], 0.8_r);
    EXPECT_LE(std::fabs(a->com_bias_b_m()[3 * i]), 0.03_r);
    EXPECT_LE(std::fabs(a->com_bias_b_m()[3 * i + 1]), 0.03_r);
    EXPECT_GE(a->motor_constant_scale()[i], 0.7_r);
    EXPECT_LE(a->motor_constant_scale()[i], 1.3_r);
    EXPECT_GE(a->controller_gain_scale()[i], 0.5_r);
    EXPECT_LE(a->controller_gain_scale()[i], 1.5_r);
    EXPECT_EQ(a->added_mass_kg()[i], b->added_mass_kg()[i]);
    lo = std::min(lo, a->added_mass_kg()[i]);
    hi = std::max(hi, a->added_mass_kg()[i]);
  }
  EXPECT_GT(hi - lo, 0.2_r);
  // The drive scale limits the acceleration: from rest at full throttle, the speed after 0.1 s is
  // motor_scale * max_accel * 0.05 s (the speed loop saturates for every gain scale drawn).
  const real act[2] = {3, 0};
  std::vector<real> acts(32);
  for (int i = 0; i < 16; ++i) {
    acts[static_cast<std::size_t>(2 * i)] = act[0];
    acts[static_cast<std::size_t>(2 * i + 1)] = act[1];
  }
  for (int s = 0; s < 5; ++s) a->step(acts.data());
  for (int i = 0; i < 16; ++i) EXPECT_NEAR(a->base_lin_vel_b()[3 * i], a->motor_constant_scale()[i] * 4 * 0.05_r, 1e-4) << i;
}

TEST(Planar, BitIdenticalForAnyThreadCount) {
  std::uint64_t hashes[3] = {};
  WorldSummary sums[3];
  for (int t = 1; t <= 3; ++t) {
    std::string err;
    WorldConfig cfg;
    ASSERT_TRUE(registries().envs.make("planar_obstacles", cfg.env));
    ASSERT_TRUE(registries().robots.make("ground_vehicle", cfg.robot));
    cfg.simulator.backend = "planar";
    cfg.simulator.lidar_beams = 31;
    cfg.env.num_envs = 13;
    cfg.env.collision_force_threshold_N = 1;
    cfg.task.episode_len_env_steps = 150;
    cfg.seed = 3;
    cfg.num_threads = t;
    std::unique_ptr<Simulator> sim = make_simulator(cfg, err);
    ASSERT_TRUE(sim) << err;
    ASSERT_EQ(sim->num_threads(), t);
    std::vector<real> a(static_cast<std::size_t>(sim->num_robots() * sim->action_dim()));
    for (int s = 0; s < 400; ++s) {
      scripted_setpoint_actions(*sim, a.data());
      sim->step(a.data());
      if (s % 97 == 0) sim->push_robots();
    }
    hashes[t - 1] = sim->state_hash();
    sums[t - 1] = sim->summary();
  }
  EXPECT_EQ(hashes[0], hashes[1]);
  EXPECT_EQ(hashes[0], hashes[2]);
  EXPECT_EQ(sums[0].resets, sums[2].resets);
  EXPECT_GE(sums[0].episodes_done, 13u);  // resets happened inside the workers
}

TEST(Planar, ResetRootStatesAndPushes) {
  std::string err;
  WorldConfig cfg = yard(false, {}, 6);
  cfg.simulator.altitude_m = 2;
  cfg.simulator.max_push_vel_xy_m_s = 0.5_r;
  std::unique_ptr<Simulator> a = make_simulator(cfg, err), b = make_simulator(cfg, err);
  ASSERT_TRUE(a && b) << err;
  // Exact root states (yaw-only quaternion, z at the flight altitude).
  const int ids[2] = {2, 4};
  const Quat q0 = quat_from_euler_xyz(0, 0, 1.25_r), q1 = quat_from_euler_xyz(0, 0, -2.5_r);
  const real pos[6] = {1.5_r, -2.25_r, 2, -4, 3, 2};
  const real quat[8] = {q0.x(), q0.y(), q0.z(), q0.w(), q1.x(), q1.y(), q1.z(), q1.w()};
  const real lin[6] = {0.3_r, -0.2_r, 0, 0, 1, 0};
  const real ang[6] = {0, 0, 0.5_r, 0, 0, -1};
  ASSERT_TRUE(a->reset_root_states(ids, 2, pos, quat, lin, ang)) << a->last_error();
  ASSERT_TRUE(b->reset_root_states(ids, 2, pos, quat, lin, ang)) << b->last_error();
  for (int k = 0; k < 2; ++k) {
    const int i = ids[k];
    for (int j = 0; j < 3; ++j) EXPECT_EQ(a->base_pos_w()[3 * i + j], pos[3 * k + j]);
    EXPECT_NEAR(a->base_euler_xyz()[3 * i + 2], k == 0 ? 1.25 : -2.5, 1e-6);
    for (int j = 0; j < 4; ++j) EXPECT_NEAR(a->base_quat_xyzw()[4 * i + j], quat[4 * k + j], 1e-6);
    const Quat q = quat_from_xyzw(&a->base_quat_xyzw()[4 * i]);
    const Vec3 vw = rotate(q, Vec3(a->base_lin_vel_b()[3 * i], a->base_lin_vel_b()[3 * i + 1], a->base_lin_vel_b()[3 * i + 2]));
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(vw[j], lin[3 * k + j], 1e-6);
    EXPECT_NEAR(a->base_ang_vel_b()[3 * i + 2], ang[3 * k + 2], 1e-6);
  }
  // Pushes: world v_x, v_y in [-max, max], the same for the same seed, not all alike.
  for (int round = 0; round < 3; ++round) {
    a->push_robots();
    b->push_robots();
    for (int i = 0; i < a->num_robots(); ++i) {
      const Quat q = quat_from_xyzw(&a->base_quat_xyzw()[4 * i]);
      const Vec3 vw = rotate(q, Vec3(a->base_lin_vel_b()[3 * i], a->base_lin_vel_b()[3 * i + 1], 0));
      EXPECT_LE(std::fabs(vw[0]), 0.5_r + 1e-6_r);
      EXPECT_LE(std::fabs(vw[1]), 0.5_r + 1e-6_r);
      EXPECT_EQ(a->base_lin_vel_b()[3 * i], b->base_lin_vel_b()[3 * i]);
    }
    EXPECT_NE(a->base_lin_vel_b()[0], a->base_lin_vel_b()[3]);
    a->step(nullptr);
    b->step(nullptr);
  }
  EXPECT_EQ(a->state_hash(), b->state_hash());
}

TEST(Planar, NonFiniteActionsNeverReachTheState) {
  for (int car = 0; car < 2; ++car) {
    std::string err;
    std::unique_ptr<Simulator> sim = make_simulator(yard(car != 0, {}, 2), err);
    ASSERT_TRUE(sim) << err;
    std::vector<real> a(static_cast<std::size_t>(sim->num_robots() * sim->action_dim()), std::nanf(""));
    for (int s = 0; s < 50; ++s) sim->step(a.data());
    for (int i = 0; i < sim->num_robots(); ++i)
      for (int k = 0; k < 3; ++k) {
        EXPECT_TRUE(std::isfinite(sim->base_pos_w()[3 * i + k]));
        EXPECT_TRUE(std::isfinite(sim->base_lin_vel_b()[3 * i + k]));
      }
  }
}
