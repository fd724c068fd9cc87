// The Simulator interface (sim/simulator.hpp): the rigid backend's views against the World state,
// exact reset_root_states, bounded and deterministic pushes, backend selection through
// KESTREL_SIMULATOR and the scenario file, and the errors naming the backend and the alternative.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <vector>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/rigid_backend.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/scenario.hpp"
#include "kestrel/sim/simulator.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {

// Restores KESTREL_SIMULATOR after a test sets it.
struct EnvVarGuard {
  std::string old;
  bool had = false;
  EnvVarGuard() {
    if (const char* v = std::getenv("KESTREL_SIMULATOR")) {
      had = true;
      old = v;
    }
    unsetenv("KESTREL_SIMULATOR");
  }
  ~EnvVarGuard() {
    if (had) setenv("KESTREL_SIMULATOR", old.c_str(), 1);
    else unsetenv("KESTREL_SIMULATOR");
  }
};

WorldConfig rigid_config(int envs = 8) {
  WorldConfig c;
  EXPECT_TRUE(registries().envs.make("env_with_obstacles", c.env));
  c.env.num_envs = envs;
  c.task.episode_len_env_steps = 60;  // a few auto-resets inside the test
  c.seed = 7;
  c.num_threads = 2;
  return c;
}

}  // namespace

TEST(SimulatorRigid, ViewsAgreeWithWorldState) {
  EnvVarGuard g;
  std::string err;
  const WorldConfig cfg = rigid_config();
  std::unique_ptr<Simulator> sim = make_simulator(cfg, Backend::rigid, err);
  ASSERT_TRUE(sim) << err;
  std::unique_ptr<World> twin = World::create(cfg, err);
  ASSERT_TRUE(twin) << err;
  EXPECT_EQ(sim->backend(), Backend::rigid);
  EXPECT_STREQ(sim->backend_name(), "rigid");
  EXPECT_EQ(sim->action_dim(), 4);
  bool saw_reset = false, saw_contact = false;
  for (int s = 0; s < 120; ++s) {
    sim->step(nullptr);  // the World's own setpoint actions
    twin->step(1);
    World& w = *rigid_world(*sim);
    for (int e = 0; e < sim->num_envs(); ++e) {
      saw_reset = saw_reset || sim->reset_buf()[e] != 0;
      const std::size_t i = static_cast<std::size_t>(e);
      const RigidBodyState& st = w.robot_state(e, 0);
      for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(sim->base_pos_w()[3 * i + k], st.position_w[k]);
        ASSERT_EQ(sim->contact_forces_w()[3 * i + k], w.contact_force_w(e, 0)[k]);
        ASSERT_EQ(sim->target_w()[3 * i + k], w.target(e, 0)[k]);
        ASSERT_EQ(sim->base_ang_vel_b()[3 * i + k], st.angvel_b[k]);
      }
      for (int k = 0; k < 4; ++k) ASSERT_EQ(sim->base_quat_xyzw()[4 * i + k], st.orientation_wb.coeffs()[k]);
      const Vec3 vb = rotate_inverse(st.orientation_wb, st.linvel_w);
      for (int k = 0; k < 3; ++k) ASSERT_EQ(sim->base_lin_vel_b()[3 * i + k], vb[k]);
      // Euler XYZ view reproduces the quaternion.
      const real* eu = &sim->base_euler_xyz()[3 * i];
      const Quat q = quat_from_euler_xyz(eu[0], eu[1], eu[2]);
      EXPECT_NEAR(std::fabs(q.dot(st.orientation_wb)), 1, 1e-5);
      // Applied wrench: thrust along body z equals the motor thrust sum (no contact -> exact).
      if (w.contact_force_w(e, 0).isZero()) {
        real sum = 0;
        for (int m = 0; m < w.airframe().num_rotors; ++m) sum += w.motor_state(e, 0).thrust_N[m];
        EXPECT_NEAR(sim->applied_wrench_b()[6 * i + 2], sum, 1e-5);
      } else {
        saw_contact = true;
      }
      EXPECT_EQ(sim->crashed()[i], w.crashed(e, 0) ? 1 : 0);
      EXPECT_GT(sim->motor_constant_scale()[i], 0);
      EXPECT_EQ(sim->controller_gain_scale()[i], 1);  // randomize_gains off: nominal gains
      EXPECT_EQ(sim->added_mass_kg()[i], 0);
    }
  }
  EXPECT_TRUE(saw_reset);
  (void)saw_contact;
  // The interface adds nothing to the dynamics: same bits as the World stepped directly.
  EXPECT_EQ(sim->state_hash(), twin->state_hash());
}

TEST(SimulatorRigid, ActionsReachTheController) {
  EnvVarGuard g;
  std::string err;
  WorldConfig cfg = rigid_config(2);
  cfg.env.assets.clear();
  cfg.task.episode_len_env_steps = 100000;
  std::unique_ptr<Simulator> sim = make_simulator(cfg, Backend::rigid, err);
  ASSERT_TRUE(sim) << err;
  // Command both robots to an explicit point: they fly there.
  std::vector<real> a(static_cast<std::size_t>(sim->num_robots() * sim->action_dim()), 0);
  for (int i = 0; i < sim->num_robots(); ++i) {
    a[static_cast<std::size_t>(4 * i)] = 1;
    a[static_cast<std::size_t>(4 * i + 1)] = -1;
    a[static_cast<std::size_t>(4 * i + 2)] = 2;
  }
  for (int s = 0; s < 800; ++s) sim->step(a.data());
  for (int i = 0; i < sim->num_robots(); ++i) {
    EXPECT_NEAR(sim->base_pos_w()[3 * i], 1, 0.05);
    EXPECT_NEAR(sim->base_pos_w()[3 * i + 1], -1, 0.05);
    EXPECT_NEAR(sim->base_pos_w()[3 * i + 2], 2, 0.05);
  }
}

TEST(SimulatorRigid, ResetRootStatesPutsExactStates) {
  EnvVarGuard g;
  std::string err;
  std::unique_ptr<Simulator> sim = make_simulator(rigid_config(4), Backend::rigid, err);
  ASSERT_TRUE(sim) << err;
  const int ids[2] = {1, 3};
  const Quat q1 = quat_from_euler_xyz(0.1_r, -0.2_r, 0.7_r), q3 = quat_from_euler_xyz(0, 0, -2);
  const real pos[6] = {1, 2, 3, -1.5_r, 0.25_r, 1};
  const real quat[8] = {q1.x(), q1.y(), q1.z(), q1.w(), q3.x(), q3.y(), q3.z(), q3.w()};
  const real lin[6] = {0.5_r, -0.25_r, 0.1_r, 0, 0, 0};
  const real ang[6] = {0.2_r, 0, -0.3_r, 0, 0, 1};
  ASSERT_TRUE(sim->reset_root_states(ids, 2, pos, quat, lin, ang)) << sim->last_error();
  for (int k = 0; k < 2; ++k) {
    const std::size_t i = static_cast<std::size_t>(ids[k]);
    const RigidBodyState& st = rigid_world(*sim)->robot_state(ids[k], 0);
    for (int j = 0; j < 3; ++j) {
      EXPECT_EQ(sim->base_pos_w()[3 * i + j], pos[3 * k + j]);
      EXPECT_EQ(st.position_w[j], pos[3 * k + j]);
      EXPECT_EQ(st.linvel_w[j], lin[3 * k + j]);
    }
    for (int j = 0; j < 4; ++j) EXPECT_EQ(sim->base_quat_xyzw()[4 * i + j], quat[4 * k + j]);
    const Vec3 w_w = rotate(st.orientation_wb, st.angvel_b);  // stored in the body frame
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(w_w[j], ang[3 * k + j], 1e-6);
    EXPECT_TRUE(rigid_world(*sim)->contact_force_w(ids[k], 0).isZero());
  }
  // Bad input: nothing written.
  const RigidBodyState before = rigid_world(*sim)->robot_state(1, 0);
  const real bad_quat[8] = {0, 0, 0, 2, 0, 0, 0, 1};
  EXPECT_FALSE(sim->reset_root_states(ids, 2, pos, bad_quat, lin, ang));
  EXPECT_NE(sim->last_error().find("unit length"), std::string::npos);
  const int bad_id[1] = {9};
  EXPECT_FALSE(sim->reset_root_states(bad_id, 1, pos, quat, lin, ang));
  EXPECT_NE(sim->last_error().find("out of range"), std::string::npos);
  EXPECT_EQ(rigid_world(*sim)->robot_state(1, 0).position_w, before.position_w);
}

TEST(SimulatorRigid, PushRobotsBoundedAndDeterministic) {
  EnvVarGuard g;
  std::string err;
  WorldConfig cfg = rigid_config(16);
  cfg.simulator.max_push_vel_xy_m_s = 0.75_r;
  std::unique_ptr<Simulator> a = make_simulator(cfg, Backend::rigid, err), b = make_simulator(cfg, Backend::rigid, err);
  ASSERT_TRUE(a && b) << err;
  for (int round = 0; round < 3; ++round) {
    const Vec3 vz_before(0, 0, rigid_world(*a)->robot_state(0, 0).linvel_w[2]);
    a->push_robots();
    b->push_robots();
    real max_abs = 0;
    for (int e = 0; e < a->num_envs(); ++e) {
      const RigidBodyState& s = rigid_world(*a)->robot_state(e, 0);
      EXPECT_LE(std::fabs(s.linvel_w[0]), 0.75_r);
      EXPECT_LE(std::fabs(s.linvel_w[1]), 0.75_r);
      max_abs = std::max(max_abs, std::max(std::fabs(s.linvel_w[0]), std::fabs(s.linvel_w[1])));
      EXPECT_EQ(s.linvel_w, rigid_world(*b)->robot_state(e, 0).linvel_w);  // same seed, same kicks
      // The view is refreshed: body-frame velocity rotated back is the pushed world velocity.
      const Vec3 vb(a->base_lin_vel_b()[3 * e], a->base_lin_vel_b()[3 * e + 1], a->base_lin_vel_b()[3 * e + 2]);
      EXPECT_LT((rotate(s.orientation_wb, vb) - s.linvel_w).norm(), 1e-5);
    }
    EXPECT_EQ(rigid_world(*a)->robot_state(0, 0).linvel_w[2], vz_before[2]);  // z untouched
    EXPECT_GT(max_abs, 0.3_r);  // 16 robots x 2 draws in +-0.75: not all tiny
    a->step(nullptr);
    b->step(nullptr);
  }
  EXPECT_NE(rigid_world(*a)->robot_state(0, 0).linvel_w, rigid_world(*a)->robot_state(1, 0).linvel_w);
  EXPECT_EQ(a->state_hash(), b->state_hash());
}

// LeggedGym-Ex's set_viewer_camera / draw_debug_vis: the request is kept, refused with its reason
// when bad (nothing changed), handed to an attached viewer at once and to one attached later.
TEST(SimulatorViewerHooks, RequestsReachTheAttachedViewer) {
  EnvVarGuard g;
  std::string err;
  std::unique_ptr<Simulator> sim = make_simulator(rigid_config(2), Backend::rigid, err);
  ASSERT_TRUE(sim) << err;
  struct Recorder : Simulator::ViewerHooks {
    std::vector<Simulator::ViewerRequest> got;
    void on_viewer_request(const Simulator::ViewerRequest& r) override { got.push_back(r); }
  } rec;
  EXPECT_FALSE(sim->viewer_request().camera_set);
  ASSERT_TRUE(sim->set_viewer_camera(Vec3(0, -8, 6), Vec3(0, 0, 1)));  // before any viewer: kept
  EXPECT_FALSE(sim->set_viewer_camera(Vec3(1, 1, 1), Vec3(1, 1, 1)));
  EXPECT_NE(sim->last_error().find("must differ"), std::string::npos) << sim->last_error();
  EXPECT_FALSE(sim->set_viewer_camera(Vec3(std::numeric_limits<real>::quiet_NaN(), 0, 0), Vec3::Zero()));
  EXPECT_NE(sim->last_error().find("finite"), std::string::npos) << sim->last_error();
  EXPECT_EQ(sim->viewer_request().camera_position_w, Vec3(0, -8, 6));  // the refused calls changed nothing
  sim->set_viewer(&rec);
  ASSERT_EQ(rec.got.size(), 1u);
  EXPECT_TRUE(rec.got[0].camera_set);
  EXPECT_EQ(rec.got[0].camera_lookat_w, Vec3(0, 0, 1));
  EXPECT_FALSE(rec.got[0].debug_contacts);
  sim->draw_debug_vis(true, false);
  ASSERT_EQ(rec.got.size(), 2u);
  EXPECT_TRUE(rec.got[1].debug_height_samples);
  EXPECT_FALSE(rec.got[1].debug_contacts);
  sim->set_viewer(nullptr);
  sim->draw_debug_vis(true, true);  // detached: kept, not sent
  EXPECT_EQ(rec.got.size(), 2u);
  EXPECT_TRUE(sim->viewer_request().debug_contacts);
}

TEST(SimulatorSelect, EnvironmentVariableAndScenario) {
  EnvVarGuard g;
  std::string err;
  WorldConfig cfg;
  ASSERT_TRUE(load_scenario_string("env: {name: planar_obstacles, num_envs: 2}\nsimulator: planar\n", "t.yaml", cfg, err)) << err;
  EXPECT_EQ(cfg.simulator.backend, "planar");
  Backend b = Backend::rigid;
  ASSERT_TRUE(resolve_backend(cfg, b, err));
  EXPECT_EQ(b, Backend::planar);
  std::unique_ptr<Simulator> s = make_simulator(cfg, err);
  ASSERT_TRUE(s) << err;
  EXPECT_EQ(s->backend(), Backend::planar);
  EXPECT_FALSE(s->ground_vehicle());  // automatic: base_quadrotor -> multirotor
  // KESTREL_SIMULATOR wins over the file.
  setenv("KESTREL_SIMULATOR", "rigid", 1);
  ASSERT_TRUE(resolve_backend(cfg, b, err));
  EXPECT_EQ(b, Backend::rigid);
  s = make_simulator(cfg, err);
  ASSERT_TRUE(s) << err;
  EXPECT_EQ(s->backend(), Backend::rigid);
  setenv("KESTREL_SIMULATOR", "planar", 1);
  WorldConfig plain;
  plain.env.num_envs = 2;
  ASSERT_TRUE(resolve_backend(plain, b, err));
  EXPECT_EQ(b, Backend::planar);
  setenv("KESTREL_SIMULATOR", "mujoco", 1);
  EXPECT_FALSE(resolve_backend(plain, b, err));
  EXPECT_NE(err.find("KESTREL_SIMULATOR"), std::string::npos);
  EXPECT_NE(err.find("rigid, planar"), std::string::npos);
  EXPECT_FALSE(make_simulator(plain, err));
  unsetenv("KESTREL_SIMULATOR");
  // No variable, no field: rigid.
  ASSERT_TRUE(resolve_backend(plain, b, err));
  EXPECT_EQ(b, Backend::rigid);
  // Scenario errors name the field and the allowed values.
  EXPECT_FALSE(load_scenario_string("simulator: bullet\n", "s.yaml", cfg, err));
  EXPECT_NE(err.find("s.yaml: simulator"), std::string::npos) << err;
  EXPECT_NE(err.find("planar, rigid"), std::string::npos) << err;
  EXPECT_FALSE(load_scenario_string("simulator: {name: planar, vehicle: boat}\n", "s.yaml", cfg, err));
  EXPECT_NE(err.find("simulator.vehicle"), std::string::npos) << err;
  EXPECT_FALSE(load_scenario_string("simulator: {name: planar, wheel: 1}\n", "s.yaml", cfg, err));
  EXPECT_NE(err.find("unknown field"), std::string::npos) << err;
  ASSERT_TRUE(load_scenario_string("simulator: {name: planar, vehicle: ground_vehicle, added_mass_kg: [0.1, 0.2], "
                                   "gain_scale: [0.9, 1.1], lidar_beams: 16, max_push_vel_xy_m_s: 0.4}\n",
                                   "s.yaml", cfg, err))
      << err;
  EXPECT_EQ(cfg.simulator.vehicle, PlanarVehicle::ground_vehicle);
  EXPECT_EQ(cfg.simulator.added_mass_min_kg, 0.1_r);
  EXPECT_EQ(cfg.simulator.added_mass_max_kg, 0.2_r);
  EXPECT_EQ(cfg.simulator.gain_scale_max, 1.1_r);
  EXPECT_EQ(cfg.simulator.lidar_beams, 16);
  EXPECT_EQ(cfg.simulator.max_push_vel_xy_m_s, 0.4_r);
  EXPECT_FALSE(load_scenario_string("simulator: {name: planar, added_mass_kg: [0.3, 0.1]}\n", "s.yaml", cfg, err));
  EXPECT_NE(err.find("simulator.added_mass_kg: expected min <= max"), std::string::npos) << err;
  // The registry lists both.
  EXPECT_TRUE(registries().simulators.has("rigid"));
  EXPECT_TRUE(registries().simulators.has("planar"));
}

TEST(SimulatorSelect, UnsupportedOperationsNameBackendAndAlternative) {
  EnvVarGuard g;
  std::string err;
  // Planar: a mesh obstacle.
  WorldConfig c;
  c.env.num_envs = 1;
  AssetClass mesh;
  mesh.name = "statues";
  mesh.kind = AssetKind::mesh;
  mesh.mesh_file = "statue.obj";
  c.env.assets.push_back(mesh);
  EXPECT_FALSE(make_simulator(c, Backend::planar, err));
  EXPECT_NE(err.find("simulator planar"), std::string::npos) << err;
  EXPECT_NE(err.find("mesh"), std::string::npos) << err;
  EXPECT_NE(err.find("use simulator: rigid"), std::string::npos) << err;
  // Planar: a height field (the example) and mesh terrain.
  WorldConfig hf;
  hf.env.num_envs = 1;
  hf.env.terrain.type = TerrainType::heightfield;
  EXPECT_FALSE(make_simulator(hf, Backend::planar, err));
  EXPECT_NE(err.find("simulator planar: env.terrain: a height field"), std::string::npos) << err;
  EXPECT_NE(err.find("use simulator: rigid"), std::string::npos) << err;
  hf.env.terrain.type = TerrainType::trimesh;
  EXPECT_FALSE(make_simulator(hf, Backend::planar, err));
  EXPECT_NE(err.find("use simulator: rigid"), std::string::npos) << err;
  // Planar: 3-D sensors; attitude-level controllers.
  WorldConfig s;
  s.env.num_envs = 1;
  ASSERT_TRUE(load_scenario_string("env: {name: empty, num_envs: 1}\nsensors: [base_depth_camera]\n", "x", s, err)) << err;
  EXPECT_FALSE(make_simulator(s, Backend::planar, err));
  EXPECT_NE(err.find("use simulator: rigid"), std::string::npos) << err;
  WorldConfig att;
  att.env.num_envs = 1;
  ASSERT_TRUE(registries().controllers.make("lee_attitude_control", att.controller));
  EXPECT_FALSE(make_simulator(att, Backend::planar, err));
  EXPECT_NE(err.find("roll/pitch"), std::string::npos) << err;
  // Rigid: the planar-only car and planar-only randomisation.
  WorldConfig car;
  car.env.num_envs = 1;
  ASSERT_TRUE(registries().robots.make("ground_vehicle", car.robot));
  EXPECT_FALSE(make_simulator(car, Backend::rigid, err));
  EXPECT_NE(err.find("simulator rigid"), std::string::npos) << err;
  EXPECT_NE(err.find("use simulator: planar"), std::string::npos) << err;
  WorldConfig dr;
  dr.env.num_envs = 1;
  dr.simulator.added_mass_max_kg = 0.1_r;
  EXPECT_FALSE(make_simulator(dr, Backend::rigid, err));
  EXPECT_NE(err.find("use simulator: planar"), std::string::npos) << err;
  // Planar: a reset with roll/pitch.
  WorldConfig p;
  p.env.num_envs = 1;
  std::unique_ptr<Simulator> sim = make_simulator(p, Backend::planar, err);
  ASSERT_TRUE(sim) << err;
  const int id[1] = {0};
  const Quat tilted = quat_from_euler_xyz(0.3_r, 0, 0);
  const real pos[3] = {0, 0, 1}, q[4] = {tilted.x(), tilted.y(), tilted.z(), tilted.w()}, zero[3] = {0, 0, 0};
  EXPECT_FALSE(sim->reset_root_states(id, 1, pos, q, zero, zero));
  EXPECT_NE(sim->last_error().find("simulator planar"), std::string::npos) << sim->last_error();
  EXPECT_NE(sim->last_error().find("use simulator: rigid"), std::string::npos) << sim->last_error();
  const real flat_q[4] = {0, 0, 0, 1}, off_plane[3] = {0, 0, 3};
  EXPECT_FALSE(sim->reset_root_states(id, 1, off_plane, flat_q, zero, zero));
  EXPECT_NE(sim->last_error().find("plane height"), std::string::npos) << sim->last_error();
}

// The controller table on the backends: velocity_steering_control is the ground vehicle's kind
// (named by the Simulator, accepted from a scenario), refused by name on a multirotor; both
// backends report latched faults in summary().fault_bits (a NaN command is held, not dropped).
TEST(Simulator, ControllerFamiliesAndFaultBits) {
  std::string err;
  WorldConfig car;
  ASSERT_TRUE(load_scenario_string("simulator: {name: planar, vehicle: ground_vehicle}\nrobot: ground_vehicle\n"
                                   "controller: velocity_steering_control\nenv: {name: planar_obstacles, num_envs: 2}\n",
                                   "car.yaml", car, err))
      << err;
  EXPECT_EQ(car.controller.kind, ControllerKind::velocity_steering);
  std::unique_ptr<Simulator> sim = make_simulator(car, Backend::planar, err);
  ASSERT_TRUE(sim) << err;
  EXPECT_STREQ(sim->controller_name(), "velocity_steering_control");
  EXPECT_EQ(sim->summary().fault_bits, 0u);
  std::vector<real> a(static_cast<std::size_t>(sim->num_robots() * sim->action_dim()), 0.5_r);
  sim->step(a.data());
  EXPECT_EQ(sim->summary().fault_bits & kFaultNonFiniteCommand, 0u);
  a[0] = std::numeric_limits<real>::quiet_NaN();
  sim->step(a.data());
  EXPECT_NE(sim->summary().fault_bits & kFaultNonFiniteCommand, 0u);
  EXPECT_EQ(sim->summary().reset_errors, 0u);

  // A multirotor (rigid or planar) refuses the ground vehicle's controller, naming what it takes.
  WorldConfig quad;
  quad.env.num_envs = 1;
  ASSERT_TRUE(registries().controllers.make("velocity_steering_control", quad.controller));
  EXPECT_FALSE(make_simulator(quad, Backend::rigid, err));
  EXPECT_NE(err.find("controller velocity_steering_control drives a ground vehicle"), std::string::npos) << err;
  EXPECT_NE(err.find("lee_position_control"), std::string::npos) << err;
  EXPECT_FALSE(make_simulator(quad, Backend::planar, err));
  EXPECT_NE(err.find("velocity_steering_control"), std::string::npos) << err;
  // joint_pd_control has no robot yet: not a scenario's controller.
  EXPECT_FALSE(registries().controllers.has("joint_pd_control"));

  // Rigid: a NaN action is held and latched too.
  WorldConfig r;
  r.env.num_envs = 1;
  std::unique_ptr<Simulator> rigid = make_simulator(r, Backend::rigid, err);
  ASSERT_TRUE(rigid) << err;
  std::vector<real> ra(static_cast<std::size_t>(rigid->action_dim()), 0);
  ra[1] = std::numeric_limits<real>::quiet_NaN();
  rigid->step(ra.data());
  EXPECT_NE(rigid->summary().fault_bits & kFaultNonFiniteCommand, 0u);
}

TEST(SimulatorRigid, MeasuredHeightsAreTheWorlds) {
  // The interface's measured_heights on rigid is the World's own array (legged_gym's height points).
  WorldConfig c = rigid_config(4);
  c.env.terrain.type = TerrainType::heightfield;
  c.env.terrain.procedural = "random_uniform";
  c.env.terrain.measure_heights = true;
  std::string err;
  std::unique_ptr<Simulator> sim = make_simulator(c, Backend::rigid, err);
  ASSERT_TRUE(sim) << err;
  sim->step(nullptr);
  const World* w = rigid_world(*sim);
  ASSERT_NE(w, nullptr);
  EXPECT_EQ(sim->num_height_points(), w->num_height_points());
  EXPECT_EQ(sim->num_height_points(), 17 * 11);
  EXPECT_EQ(sim->measured_heights(), w->measured_heights());
  c.env.terrain.measure_heights = false;
  std::unique_ptr<Simulator> none = make_simulator(c, Backend::rigid, err);
  ASSERT_TRUE(none) << err;
  EXPECT_EQ(none->num_height_points(), 0);
  EXPECT_EQ(none->measured_heights(), nullptr);
}
