// The batched twin of the robot step (sim/batch_step.hpp) against the scalar core functions it
// mirrors: bit-equal states after many steps from random (and deliberately awkward) states, and
// whole worlds stepped with and without the batched path giving identical bits, for any thread
// count, without heap allocation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include "heap_counter.hpp"
#include "kestrel/allocation/presets.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/kernel/rng.hpp"
#include "kestrel/sim/batch_step.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/world.hpp"

using namespace kestrel;
using namespace kestrel::sim;
namespace al = kestrel::allocation;

namespace {

// The twin reproduces the float build's Eigen SSE orders; in the double build batch::eligible() is
// false and World keeps the scalar path (these tests then check only that).
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
constexpr bool kTwinBuild = false;
#else
constexpr bool kTwinBuild = true;
#endif

bool same_bits(const real* a, const real* b, int n) { return std::memcmp(a, b, sizeof(real) * static_cast<std::size_t>(n)) == 0; }

::testing::AssertionResult same_body(const RigidBodyState& a, const RigidBodyState& b) {
  if (same_bits(a.position_w.data(), b.position_w.data(), 3) && same_bits(a.linvel_w.data(), b.linvel_w.data(), 3) &&
      same_bits(a.angvel_b.data(), b.angvel_b.data(), 3) &&
      same_bits(a.orientation_wb.coeffs().data(), b.orientation_wb.coeffs().data(), 4))
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "body state differs: p " << a.position_w.transpose() << " vs "
                                       << b.position_w.transpose() << ", q " << a.orientation_wb.coeffs().transpose()
                                       << " vs " << b.orientation_wb.coeffs().transpose();
}

::testing::AssertionResult same_lee(const LeeState& a, const LeeState& b) {
  const bool ok = same_bits(a.last_safe_wrench_b.force_b.data(), b.last_safe_wrench_b.force_b.data(), 3) &&
                  same_bits(a.last_safe_wrench_b.torque_b.data(), b.last_safe_wrench_b.torque_b.data(), 3) &&
                  same_bits(a.accel_command_w.data(), b.accel_command_w.data(), 3) &&
                  same_bits(a.desired_quat_xyzw.data(), b.desired_quat_xyzw.data(), 4) &&
                  same_bits(a.desired_angvel_b.data(), b.desired_angvel_b.data(), 3) && a.step_faults == b.step_faults &&
                  a.faults.bits == b.faults.bits;
  if (ok) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "controller state differs (faults " << a.faults.bits << " vs " << b.faults.bits << ")";
}

::testing::AssertionResult same_alloc(const al::AllocatorState& a, const al::AllocatorState& b) {
  if (a.num_rotors == b.num_rotors && same_bits(a.last_thrust_N, b.last_thrust_N, al::kMaxRotors) &&
      a.faults.bits == b.faults.bits && std::memcmp(a.active, b.active, sizeof(a.active)) == 0)
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "allocator state differs";
}

::testing::AssertionResult same_motors(const al::MotorModelState& a, const al::MotorModelState& b) {
  constexpr int n = al::kMaxRotors;
  const bool ok = a.num_motors == b.num_motors && same_bits(a.thrust_N, b.thrust_N, n) &&
                  same_bits(a.axial_torque_Nm, b.axial_torque_Nm, n) && same_bits(a.health_scale, b.health_scale, n) &&
                  same_bits(a.last_reference_N, b.last_reference_N, n) && a.pending_mask == b.pending_mask &&
                  same_bits(&a.elapsed_s, &b.elapsed_s, 1) && a.faults.bits == b.faults.bits;
  if (ok) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "motor state differs: thrust " << a.thrust_N[0] << " " << a.thrust_N[1] << " "
                                       << a.thrust_N[2] << " " << a.thrust_N[3] << " vs " << b.thrust_N[0] << " "
                                       << b.thrust_N[1] << " " << b.thrust_N[2] << " " << b.thrust_N[3];
}

// An environment's statistics, the double sums bit for bit.
::testing::AssertionResult same_stats(const EnvStats& x, const EnvStats& y) {
  if (x.env_steps == y.env_steps && x.crashes == y.crashes && x.resets == y.resets && x.timeouts == y.timeouts &&
      x.out_of_bounds == y.out_of_bounds && x.successes == y.successes &&
      std::memcmp(&x.tracking_error_sum_m, &y.tracking_error_sum_m, sizeof(double)) == 0 &&
      std::memcmp(&x.final_distance_sum_m, &y.final_distance_sum_m, sizeof(double)) == 0)
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "statistics differ: env-steps " << x.env_steps << " vs " << y.env_steps << ", crashes "
                                       << x.crashes << " vs " << y.crashes << ", resets " << x.resets << " vs " << y.resets
                                       << ", timeouts " << x.timeouts << " vs " << y.timeouts << ", out of bounds "
                                       << x.out_of_bounds << " vs " << y.out_of_bounds << ", tracking error sum "
                                       << x.tracking_error_sum_m << " vs " << y.tracking_error_sum_m;
}

// The constant models of the default robot (World::create's), with a settable integrator setup.
struct Stack {
  ControllerParams ctrl;
  al::Airframe airframe;
  al::AllocationModel alloc;
  al::SequentialDesaturationParams desat;
  al::MotorModelConfig motor;
  RigidBodyModel body;
  batch::Models models(real dt, int substeps) const {
    batch::Models m;
    m.controller = ControllerKind::lee_position;
    m.ctrl = &ctrl;
    m.alloc = &alloc;
    m.desat = &desat;
    m.motor = &motor;
    m.airframe = &airframe;
    m.body = &body;
    m.dt_s = dt;
    m.substeps = substeps;
    return m;
  }
};

Stack make_stack(bool rps, bool drag) {
  Stack s;
  const al::AirframePreset p = al::AirframePreset::base_quadrotor;
  EXPECT_EQ(al::make_airframe(al::airframe_spec(p), s.airframe), Status::ok);
  EXPECT_NE(al::build_allocation_model(s.airframe, s.alloc), Status::invalid_argument);
  s.motor = al::motor_model_preset(p);
  s.motor.use_rps = rps;
  RigidBodyParams bp;
  bp.integrator = Integrator::semi_implicit_euler;
  if (drag) {
    bp.linear_drag_b = Vec3(0.01_r, 0.02_r, 0.03_r);
    bp.quadratic_drag_b = Vec3(0.001_r, 0.002_r, 0.004_r);
    bp.angular_drag_b = Vec3(1e-4_r, 2e-4_r, 3e-4_r);
    bp.quadratic_angular_drag_b = Vec3(1e-5_r, 1e-5_r, 2e-5_r);
  }
  EXPECT_EQ(make_rigid_body_model(bp, s.body), Status::ok);
  s.ctrl.lee = lee_params_base_quadrotor();
  s.ctrl.lee.randomize_gains = true;  // per-lane gains
  s.ctrl.motors.num_motors = 4;
  return s;
}

struct Robot {
  RigidBodyState state;
  ControllerState ctrl;
  al::AllocatorState alloc;
  al::MotorModelState motors;
  real action[kMaxActionDim] = {};
  Vec3 contact_force_w = Vec3::Zero();
  Vec3 contact_torque_b = Vec3::Zero();
};

// World::robot_dynamics for one robot, written out from the scalar core functions.
void scalar_step(const Stack& s, Robot& r, real dt, int substeps) {
  ControllerOutput out;
  (void)update_controller(ControllerKind::lee_position, s.ctrl, r.ctrl, r.state, r.action, kMaxActionDim, out);
  al::AllocationResult res;
  (void)al::allocate_sequential_desaturation(s.alloc, s.desat, r.alloc, out.wrench_b, res);
  (void)al::motor_model_step(s.motor, r.motors, res.thrust_N, dt);
  Wrench w = Wrench::from_vec6(al::wrench_from_thrusts(s.airframe.effectiveness, 4, r.motors.thrust_N));
  w.torque_b += r.contact_torque_b;
  const real h = dt / static_cast<real>(substeps);
  for (int k = 0; k < substeps; ++k) (void)step_rigid_body(s.body, r.state, w, h, r.contact_force_w);
}

// A random robot, with a share of awkward cases: commands outside the action range or non-finite,
// yaw setpoints near +-pi (desired rotation with trace <= 0), large errors (saturated allocation),
// zero velocities and rates (signed zeros), weak / dead / scheduled motor failures, contact
// wrenches, and a non-finite contact force now and then.
Robot random_robot(const Stack& s, RngStream& rng, int k) {
  Robot r;
  r.state.position_w = Vec3(rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(0, 5));
  r.state.orientation_wb = quat_from_euler_xyz(rng.uniform(-0.6_r, 0.6_r), rng.uniform(-0.6_r, 0.6_r), rng.uniform(-kPi, kPi));
  if (k % 7 != 0) {
    r.state.linvel_w = Vec3(rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-3, 3));
    r.state.angvel_b = Vec3(rng.uniform(-4, 4), rng.uniform(-4, 4), rng.uniform(-2, 2));
  }
  controller_reset(ControllerKind::lee_position, s.ctrl, r.ctrl, rng);
  al::reset_allocator(r.alloc);
  real hover[al::kMaxRotors] = {};
  for (int m = 0; m < 4; ++m) hover[m] = rng.uniform(0, 1.2_r);
  EXPECT_EQ(al::motor_model_reset(s.motor, r.motors, rng, hover), Status::ok);
  for (int i = 0; i < 3; ++i) r.action[i] = r.state.position_w[i] + rng.uniform(-(k % 3 == 0 ? 12 : 1), k % 3 == 0 ? 12 : 1);
  // Headings near pi, within +-1 rad, and (every 7th) over the whole action range: the kernel's
  // lane-wise sine and cosine must match sin_cos in every octant.
  r.action[3] = k % 5 == 0 ? kPi - rng.uniform(0, 0.1_r) : (k % 7 == 3 ? rng.uniform(-9.9_r, 9.9_r) : rng.uniform(-1, 1));
  switch (k % 23) {
    case 1: r.action[0] = 1e6_r; break;  // outside the action range: clipped by the controller
    case 2: r.action[1] = std::numeric_limits<real>::quiet_NaN(); break;
    case 3: EXPECT_EQ(al::inject_motor_failure(r.motors, 2, 0.5_r), Status::ok); break;
    case 4: EXPECT_EQ(al::inject_motor_failure(r.motors, 1, 0), Status::ok); break;
    case 5: EXPECT_EQ(al::schedule_motor_failure(r.motors, 3, 0.3_r, 0.05_r), Status::ok); break;
    case 6: r.contact_force_w = Vec3(0.5_r, -0.2_r, 3); r.contact_torque_b = Vec3(0.001_r, 0, -0.002_r); break;
    case 7: r.contact_force_w[2] = std::numeric_limits<real>::infinity(); break;
    case 8: r.state.orientation_wb = quat_from_euler_xyz(3.0_r, 0.1_r, 0.2_r); break;  // upside down
    // Fuzz F1: finite body rates whose Lee torque overflows the allocation to NaN; the scalar
    // allocator holds the last finite thrust, and the twin must send such a lane to it.
    case 11: r.state.angvel_b = Vec3(0, 0, 3.4e38_r); break;
    case 12: r.state.angvel_b = Vec3(-1e37_r, 2e37_r, 0); break;
    default: break;
  }
  return r;
}

void run_twin(bool rps, bool drag, int substeps) {
  if (!kTwinBuild) GTEST_SKIP() << "the batched twin covers the float build only";
  const Stack s = make_stack(rps, drag);
  const real dt = 0.01_r;
  const batch::Models m = s.models(dt, substeps);
  ASSERT_TRUE(batch::eligible(m));
  constexpr int kRobots = 16 * 15;  // whole groups of 4, 8 and 16
  std::vector<Robot> a, b;
  RngStream rng(11, 0, kPurposeReset);
  for (int k = 0; k < kRobots; ++k) a.push_back(random_robot(s, rng, k));
  b = a;
  const Vec3 p10 = a[10].state.position_w;
  for (int step = 0; step < 150; ++step) {
    const int group = batch::lanes();
    for (int g = 0; g < kRobots; g += group) {
      batch::Lane lanes[batch::kMaxLanes];
      for (int l = 0; l < group; ++l) {
        Robot& r = a[static_cast<std::size_t>(g + l)];
        lanes[l].state = &r.state;
        lanes[l].ctrl = &r.ctrl;
        lanes[l].alloc = &r.alloc;
        lanes[l].motors = &r.motors;
        lanes[l].action = r.action;
        lanes[l].contact_force_w = &r.contact_force_w;
        lanes[l].contact_torque_b = &r.contact_torque_b;
      }
      batch::robot_step(m, lanes);
    }
    for (Robot& r : b) scalar_step(s, r, dt, substeps);
    for (int k = 0; k < kRobots; ++k) {
      const Robot &x = a[static_cast<std::size_t>(k)], &y = b[static_cast<std::size_t>(k)];
      ASSERT_TRUE(same_body(x.state, y.state)) << "robot " << k << " step " << step;
      ASSERT_TRUE(same_lee(x.ctrl.lee, y.ctrl.lee)) << "robot " << k << " step " << step;
      ASSERT_TRUE(same_alloc(x.alloc, y.alloc)) << "robot " << k << " step " << step;
      ASSERT_TRUE(same_motors(x.motors, y.motors)) << "robot " << k << " step " << step;
    }
  }
  // The run must have gone somewhere: robots moved, motors spun, some allocations saturated.
  int saturated = 0;
  for (const Robot& r : a) saturated += r.alloc.faults.has(kFaultSaturated) ? 1 : 0;
  EXPECT_GT(saturated, 0);
  EXPECT_GT((a[10].state.position_w - p10).norm(), 0);
}

WorldConfig world_config(const char* env, int num_envs, int threads) {
  WorldConfig c;
  EXPECT_TRUE(registries().envs.make(env, c.env));
  c.env.num_envs = num_envs;
  c.num_threads = threads;
  c.seed = 7;
  return c;
}

std::unique_ptr<World> build(const WorldConfig& c, bool batched) {
  std::string err;
  auto w = World::create(c, err);
  EXPECT_TRUE(w) << err;
  if (w) w->set_batched(batched);
  return w;
}

}  // namespace

// Every copy of the kernel this CPU runs (baseline 4 lanes, AVX2 8, AVX-512 16), each made the one
// in use in turn; the default copy is restored afterwards.
std::vector<batch::KernelCopy> runnable_copies() {
  std::vector<batch::KernelCopy> v;
  for (batch::KernelCopy c : {batch::KernelCopy::baseline, batch::KernelCopy::avx2, batch::KernelCopy::avx512})
    if (batch::use_kernel(c)) v.push_back(c);
  batch::use_default_kernel();
  return v;
}

TEST(SimBatchStep, BitEqualToScalarRotorSpeedMotors) { run_twin(true, false, 1); }
TEST(SimBatchStep, BitEqualToScalarThrustStateMotorsWithDragAndSubsteps) { run_twin(false, true, 3); }
TEST(SimBatchStep, EveryKernelCopyBitEqualToScalar) {
  const std::vector<batch::KernelCopy> copies = runnable_copies();
  ASSERT_FALSE(copies.empty());
  EXPECT_EQ(copies.front(), batch::KernelCopy::baseline);
  for (batch::KernelCopy c : copies) {
    ASSERT_TRUE(batch::use_kernel(c));
    EXPECT_EQ(batch::lanes(), c == batch::KernelCopy::baseline ? 4 : c == batch::KernelCopy::avx2 ? 8 : 16);
    SCOPED_TRACE(batch::kernel_name());
    run_twin(true, false, 1);
    run_twin(false, true, 2);
  }
  batch::use_default_kernel();
  // The default (unless KESTREL_BATCH_KERNEL asks for another): the widest copy this CPU runs.
  if (std::getenv("KESTREL_BATCH_KERNEL") == nullptr) {
    EXPECT_EQ(batch::kernel_copy(), copies.back());
    EXPECT_EQ(batch::kernel_copy(), batch::widest_kernel_copy());
  }
}

TEST(SimBatchStep, EligibilityFollowsTheConfiguration) {
  const Stack s = make_stack(true, false);
  batch::Models m = s.models(0.01_r, 1);
  EXPECT_EQ(batch::eligible(m), kTwinBuild);
  m.controller = ControllerKind::lee_velocity;
  EXPECT_FALSE(batch::eligible(m));
  Stack t = make_stack(true, false);
  t.motor.integrator = al::MotorIntegrator::euler;
  EXPECT_FALSE(batch::eligible(t.models(0.01_r, 1)));
  t = make_stack(true, false);
  t.body.params.integrator = Integrator::rk4;
  EXPECT_FALSE(batch::eligible(t.models(0.01_r, 1)));

  // The world uses the batched path for the default robot and falls back where it must.
  WorldConfig c = world_config("empty", 8, 1);
  EXPECT_EQ(build(c, true)->batched(), kTwinBuild);
  EXPECT_FALSE(build(c, false)->batched());
  c.env.perturb_observations = true;
  EXPECT_FALSE(build(c, true)->batched());
  c = world_config("empty", 8, 1);
  c.robot.robots_per_env = 2;
  EXPECT_FALSE(build(c, true)->batched());
}

// Whole worlds: the batched path changes no bit of any environment (robots, controllers, motors,
// allocators, obstacles, statistics), with resets, crashes, per-env latency, a random number of
// physics steps per env-step (mixed lockstep groups), substeps, IMUs and randomised gains.
TEST(SimBatchStep, WorldBitIdenticalWithAndWithoutBatchedPath) {
  struct Case {
    const char* env;
    int envs;
    bool variety;
  };
  for (batch::KernelCopy copy : runnable_copies())
  for (const Case& k : {Case{"empty", 37, false}, Case{"forest", 41, false}, Case{"env_with_obstacles", 21, true},
                        Case{"dynamic", 19, true}, Case{"empty", 70, true}}) {
    ASSERT_TRUE(batch::use_kernel(copy));
    SCOPED_TRACE(batch::kernel_name());
    WorldConfig c = world_config(k.env, k.envs, 2);
    c.controller.randomize_gains = true;
    c.task.episode_len_env_steps = 150;
    if (k.variety) {
      c.env.sample_timestep_for_latency = true;
      c.env.num_physics_steps_per_env_step_mean = 2;
      c.env.num_physics_steps_per_env_step_std = 0.6_r;
      c.sim.substeps = 2;
      SensorConfig imu;
      imu.name = "imu";
      imu.kind = SensorKind::imu;
      c.robot.sensors.push_back(imu);
    }
    auto a = build(c, true), b = build(c, false);
    ASSERT_EQ(a->batched(), kTwinBuild) << k.env;
    ASSERT_FALSE(b->batched()) << k.env;
    for (int s = 0; s < 400; s += 50) {
      a->step(50);
      b->step(50);
      for (int e = 0; e < k.envs; ++e) {
        ASSERT_TRUE(same_body(a->robot_state(e, 0), b->robot_state(e, 0))) << k.env << " env " << e << " step " << s;
        ASSERT_TRUE(same_lee(a->controller_state(e, 0).lee, b->controller_state(e, 0).lee)) << k.env << " env " << e;
        ASSERT_TRUE(same_motors(a->motor_state(e, 0), b->motor_state(e, 0))) << k.env << " env " << e;
        ASSERT_EQ(a->stats(e).resets, b->stats(e).resets) << k.env << " env " << e;
        ASSERT_EQ(a->stats(e).crashes, b->stats(e).crashes) << k.env << " env " << e;
      }
    }
    EXPECT_EQ(a->state_hash(), b->state_hash()) << k.env;
    EXPECT_GT(a->summary().resets, 0u) << k.env;
  }
  batch::use_default_kernel();
}

// The batched path's own short forms (step_batched.cpp): the collision pass of robots clear of the
// ground done in the kernel (batch::Models::ground_tail), and the env-step's start and end inline
// for the common case. Every statistic, contact force and state must match the scalar path's bits
// while robots start and fly at the floor with random velocities (contacts, crashes, resets), leave
// the bounds where there is no ground plane, time out, and are traced.
TEST(SimBatchStep, GroundTailAndInlineEnvStepEndsBitIdentical) {
  struct Case {
    const char* what;
    bool at_floor;
    bool ground_plane;
    int trace_envs;
  };
  for (batch::KernelCopy copy : runnable_copies())
    for (const Case& k : {Case{"at the floor", true, true, 0}, Case{"at the floor, no ground plane", true, false, 0},
                          Case{"in the air, timeouts, traced", false, true, 5}}) {
      ASSERT_TRUE(batch::use_kernel(copy));
      SCOPED_TRACE(batch::kernel_name());
      SCOPED_TRACE(k.what);
      WorldConfig c = world_config("empty", 45, 2);
      if (k.at_floor) {
        c.robot.min_init_position_ratio[2] = 0;
        c.robot.max_init_position_ratio[2] = 0.05_r;
        c.robot.max_init_linvel_m_s = 4;
        c.task.min_target_ratio[2] = 0;
        c.task.max_target_ratio[2] = 0.05_r;
      }
      c.env.create_ground_plane = k.ground_plane;
      c.task.episode_len_env_steps = 90;
      auto a = build(c, true), b = build(c, false);
      ASSERT_EQ(a->batched(), kTwinBuild);
      if (k.trace_envs > 0) {
        a->enable_trace(k.trace_envs, 400);
        b->enable_trace(k.trace_envs, 400);
      }
      for (int s = 0; s < 400; s += 25) {
        a->step(25);
        b->step(25);
        for (int e = 0; e < 45; ++e) {
          ASSERT_TRUE(same_body(a->robot_state(e, 0), b->robot_state(e, 0))) << "env " << e << " step " << s;
          ASSERT_TRUE(same_bits(a->contact_force_w(e, 0).data(), b->contact_force_w(e, 0).data(), 3)) << "env " << e << " step " << s;
          ASSERT_TRUE(same_stats(a->stats(e), b->stats(e))) << "env " << e << " step " << s;
        }
      }
      EXPECT_EQ(a->state_hash(), b->state_hash());
      const WorldSummary sa = a->summary();
      EXPECT_GT(sa.resets, 0u);
      if (k.at_floor && k.ground_plane) {
        EXPECT_GT(sa.crashes, 0u) << "the robots must reach the ground";
      }
      if (!k.ground_plane) {
        EXPECT_GT(sa.out_of_bounds, 0u) << "the robots must fall out of the bounds";
      }
      if (k.trace_envs > 0) {
        EXPECT_GT(sa.timeouts, 0u);
        for (int e = 0; e < k.trace_envs; ++e)
          for (int t = 0; t < a->trace_length(); ++t) ASSERT_TRUE(same_bits(a->trace_point(e, t).data(), b->trace_point(e, t).data(), 3));
      }
    }
  batch::use_default_kernel();
}

// The fused env-steps (World::set_fused, batch::robot_env_steps: a lane group's robots held in
// registers through the quiet env-steps of a step() call) against the step by step batched path
// and the scalar path: every stored field of every robot equal bit for bit after calls of 1, 7
// and 25 env-steps, through what interrupts a fused run (the ground, leaving the bounds,
// timeouts, traced environments, sampled latencies, out-of-range and non-finite actions written
// between calls, several physics steps per env-step and integrator substeps).
TEST(SimBatchStep, FusedEnvStepsBitIdenticalToStepByStepAndScalar) {
  struct Case {
    const char* what;
    bool at_floor;
    int trace_envs;
    bool latency;
    int physics_steps;
    int substeps;
    bool random_actions;
  };
  const Case cases[] = {
      {"in the air", false, 0, false, 1, 1, false},
      {"at the floor, traced", true, 3, false, 1, 1, false},
      {"sampled latency, 3 physics steps, 2 substeps", false, 0, true, 3, 2, false},
      {"random actions between calls", false, 0, false, 2, 1, true},
  };
  for (batch::KernelCopy copy : runnable_copies())
    for (const Case& k : cases) {
      ASSERT_TRUE(batch::use_kernel(copy));
      SCOPED_TRACE(batch::kernel_name());
      SCOPED_TRACE(k.what);
      WorldConfig c = world_config("empty", 53, 2);  // 53: a ragged last group on each thread
      if (k.at_floor) {
        c.robot.min_init_position_ratio[2] = 0;
        c.robot.max_init_position_ratio[2] = 0.05_r;
        c.task.min_target_ratio[2] = 0;
        c.task.max_target_ratio[2] = 0.05_r;
      }
      c.env.sample_timestep_for_latency = k.latency;
      c.env.num_physics_steps_per_env_step_mean = static_cast<real>(k.physics_steps);
      c.sim.substeps = k.substeps;
      c.task.episode_len_env_steps = 70;
      auto fused = build(c, true), steps = build(c, true), scalar = build(c, false);
      ASSERT_EQ(fused->fused(), kTwinBuild) << "the empty world takes the fused env-steps by default";
      EXPECT_FALSE(steps->set_fused(false));
      EXPECT_FALSE(scalar->fused());
      // set_batched turns the fused path off and back on, and keeps a set_fused(false).
      EXPECT_FALSE(fused->set_batched(false) || fused->fused());
      EXPECT_EQ(fused->set_batched(true) && fused->fused(), kTwinBuild);
      steps->set_batched(true);
      EXPECT_FALSE(steps->fused());
      World* w[3] = {fused.get(), steps.get(), scalar.get()};
      if (k.trace_envs > 0)
        for (World* x : w) x->enable_trace(k.trace_envs, 300);
      RngStream rng(5, 0, kPurposeReset);
      int total = 0;
      for (int call = 0; total < 300; ++call) {
        const int n = call % 3 == 0 ? 1 : (call % 3 == 1 ? 7 : 25);
        if (k.random_actions && call % 2 == 1) {
          for (int e = 0; e < 53; ++e) {
            real a[4];
            for (real& v : a) v = rng.uniform(-3, 3);  // sometimes outside the action range
            if (e == 11 && call % 4 == 1) a[2] = std::numeric_limits<real>::quiet_NaN();
            for (World* x : w) std::memcpy(x->action(e, 0), a, sizeof a);
          }
        }
        for (World* x : w) x->step(n);
        total += n;
        for (int e = 0; e < 53; ++e) {
          for (int side = 1; side < 3; ++side) {
            const World& a = *w[0];
            const World& b = *w[side];
            const std::size_t i = static_cast<std::size_t>(e);
            ASSERT_TRUE(same_body(a.robot_state(e, 0), b.robot_state(e, 0))) << "env " << e << " after " << total << ", side " << side;
            ASSERT_TRUE(same_lee(a.data().mr_state[i].ctrl.lee, b.data().mr_state[i].ctrl.lee)) << "env " << e << " after " << total;
            ASSERT_TRUE(same_alloc(a.data().mr_state[i].allocator, b.data().mr_state[i].allocator)) << "env " << e << " after " << total;
            ASSERT_TRUE(same_motors(a.data().mr_state[i].motors, b.data().mr_state[i].motors)) << "env " << e << " after " << total;
            ASSERT_TRUE(same_bits(a.contact_force_w(e, 0).data(), b.contact_force_w(e, 0).data(), 3)) << "env " << e;
            ASSERT_TRUE(same_bits(a.contact_torque_b(e, 0).data(), b.contact_torque_b(e, 0).data(), 3)) << "env " << e;
            ASSERT_TRUE(same_bits(&a.data().applied_actions[i * kMaxActionDim], &b.data().applied_actions[i * kMaxActionDim], 4));
            ASSERT_EQ(a.crashed(e, 0), b.crashed(e, 0)) << "env " << e;
            ASSERT_EQ(a.episode_step(e), b.episode_step(e)) << "env " << e;
            ASSERT_EQ(a.data().episode_ended[i], b.data().episode_ended[i]) << "env " << e;
            ASSERT_TRUE(same_stats(a.stats(e), b.stats(e))) << "env " << e << " after " << total;
          }
        }
      }
      EXPECT_EQ(fused->state_hash(), scalar->state_hash());
      const WorldSummary sa = fused->summary();
      EXPECT_GT(sa.resets, 53u);
      if (k.at_floor) {
        EXPECT_GT(sa.crashes, 0u) << "the robots must reach the ground";
      }
      if (k.trace_envs > 0) {
        for (int e = 0; e < k.trace_envs; ++e)
          for (int t = 0; t < fused->trace_length(); ++t)
            ASSERT_TRUE(same_bits(fused->trace_point(e, t).data(), scalar->trace_point(e, t).data(), 3));
      }
    }
  batch::use_default_kernel();
}

TEST(SimBatchStep, BatchedWorldHashIdenticalFor1_2_3ThreadsAndEveryCopy) {
  WorldConfig c = world_config("forest", 101, 1);  // 101: groups of 4, 8 or 16 split unevenly over threads
  std::vector<std::uint64_t> h;
  for (batch::KernelCopy copy : runnable_copies()) {
    ASSERT_TRUE(batch::use_kernel(copy));
    for (int t = 1; t <= 3; ++t) {
      c.num_threads = t;
      auto w = build(c, true);
      ASSERT_EQ(w->batched(), kTwinBuild);
      w->step(300);
      h.push_back(w->state_hash());
    }
  }
  batch::use_default_kernel();
  for (std::size_t i = 1; i < h.size(); ++i) EXPECT_EQ(h[0], h[i]) << "run " << i;
}

TEST(SimBatchStep, NoHeapInsideBatchedStep) {
  for (const char* env : {"empty", "forest"}) {
    WorldConfig c = world_config(env, 16, 1);  // one thread: the step runs on this (counted) thread
    auto w = build(c, true);
    ASSERT_EQ(w->batched(), kTwinBuild);
    kestrel::test::HeapCounter counter;
    w->step(600);  // includes crashes and resets
    EXPECT_EQ(counter.allocations(), 0u) << env;
    EXPECT_GT(w->summary().resets, 0u) << env;
  }
}
