// Whole-system bench of the batched world: the full physics step (controller -> allocation ->
// motor model -> rigid-body integration -> ground/obstacle collision, plus the task's reset and
// statistics) over N environments, against
//  - the torch CPU baseline of Aerial Gym's own control step (tests/golden/reference/torch_baseline.md),
//    reproduced here as constants, and
//  - the same quadrotor stepped in MuJoCo (free body, the same Kestrel controller + allocation +
//    motor model computing the wrench each step, applied through xfrc_applied), one core.
//
// World::step takes the batched twin of the robot step (sim/batch_step.hpp) where the config allows
// it; the empty_scalar_path rows time the same worlds with World::set_batched(false) (same bits),
// and the per-stage split is printed for both the scalar core functions and the batched twin.
//
// Method: each figure is the median of several repetitions (std::chrono::steady_clock around
// World::step(k), k chosen so a repetition is a few million env-steps), after one untimed warm-up
// repetition. Timings are printed and optionally written as CSV; nothing is asserted (the smoke
// test only checks the exit code).
//
// Usage: kestrel_bench_sim [--quick] [--csv PATH] [--reps N] [--quiet]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "kestrel/allocation/presets.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/batch_step.hpp"
#include "kestrel/sim/progress.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/world.hpp"

#ifdef KESTREL_BENCH_MUJOCO
#include <mujoco/mujoco.h>
#endif

using namespace kestrel;
using namespace kestrel::sim;
namespace al = kestrel::allocation;
using Clock = std::chrono::steady_clock;

namespace {

// tests/golden/reference/torch_baseline.md, "controller + allocation + motor model (no_grad)": Aerial
// Gym's own control step with PyTorch on this 2-vCPU machine. The issue quotes ~1.1 M env-steps/s
// at 4096 environments (the table: 0.97 M with 1 thread, 1.21 M with 2) and 840 env-steps/s at one
// environment (1 thread). The full robot step of that file is slower still (0.72 M / 621).
constexpr double kTorch4096EnvStepsPerS = 1.1e6;
constexpr double kTorch1EnvStepsPerS = 840;
// Issue targets (bench, not tests).
constexpr double kTargetEmpty4096x2 = 20e6;
// Issue 18's goal for the 2-core machine: 4096 environments on 2 threads.
constexpr double kTargetEmpty4096x2Issue18 = 50e6;
constexpr double kTargetObstacles4096x2 = 1e6;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct Options {
  bool quick = false;
  bool quiet = false;  // --quiet: no progress line (it is off anyway unless stderr is a terminal)
  int reps = 5;
  double env_steps_per_rep = 4e6;
  std::string csv;
};

struct Row {
  std::string name;
  int envs = 0, threads = 0;
  double env_steps_per_s = 0;
  double ns_per_env_step = 0;
  std::string note;
};
std::vector<Row> g_rows;

void record(const std::string& name, int envs, int threads, double rate, const std::string& note = "") {
  Row r;
  r.name = name;
  r.envs = envs;
  r.threads = threads;
  r.env_steps_per_s = rate;
  r.ns_per_env_step = rate > 0 ? 1e9 / rate : 0;
  r.note = note;
  g_rows.push_back(r);
}

WorldConfig make_config(const char* env, int envs, int threads) {
  WorldConfig c;
  if (!registries().envs.make(env, c.env)) {
    std::fprintf(stderr, "unknown env %s\n", env);
    std::exit(1);
  }
  c.env.num_envs = envs;
  c.num_threads = threads;
  c.seed = 1;
  return c;  // base_sim, base_quadrotor, lee_position_control, position_setpoint (the defaults)
}

/// Median env-steps/s of World::step over `reps` repetitions. batched = false forces the scalar
/// robot step (World::set_batched; same bits, for the before/after comparison); fused = false the
/// batched step env-step by env-step (World::set_fused; same bits).
double time_world(const Options& o, const char* env, int envs, int threads, bool batched = true, bool fused = true,
                  bool one_per_call = false) {
  std::string err;
  std::unique_ptr<World> w = World::create(make_config(env, envs, threads), err);
  if (!w) {
    std::fprintf(stderr, "World::create: %s\n", err.c_str());
    std::exit(1);
  }
  w->set_batched(batched);
  if (!fused) w->set_fused(false);
  const int k = std::max(1, static_cast<int>(o.env_steps_per_rep / envs));
  const int warm = std::max(1, k / 4);
  // This case's progress (issue 15): one case is up to tens of seconds of silence (1 env: 21M
  // env-steps at ~1 us). Updated between reps, outside the timing; erased before its row prints.
  ProgressLine progress(stderr, ProgressLine::enabled_for(o.quiet), (static_cast<double>(warm) + o.reps * static_cast<double>(k)) * envs);
  w->step(warm);  // warm-up: caches, page faults, branch predictors
  std::vector<double> rates;
  for (int r = 0; r < o.reps; ++r) {
    progress.update((warm + static_cast<double>(r) * k) * envs);
    const auto t0 = Clock::now();
    if (one_per_call) {
      for (int j = 0; j < k; ++j) w->step(1);  // a learner's pattern: one env-step per call
    } else {
      w->step(k);
    }
    rates.push_back(static_cast<double>(k) * envs / seconds_since(t0));
  }
  progress.clear();
  return median(rates);
}

// ---- Split of the per-robot step: the same core calls World::robot_dynamics makes, one stage at
// a time over arrays of 4096 robots (1 thread), so each stage's cost per env-step is visible.
struct Stack {
  RigidBodyModel body;
  ControllerParams ctrl;
  al::Airframe airframe;
  al::AllocationModel alloc;
  al::SequentialDesaturationParams desat;
  al::MotorModelConfig motor_cfg;
};

Stack make_stack() {
  Stack s;
  const al::AirframePreset p = al::AirframePreset::base_quadrotor;
  (void)al::make_airframe(al::airframe_spec(p), s.airframe);
  (void)al::build_allocation_model(s.airframe, s.alloc);
  s.motor_cfg = al::motor_model_preset(p);
  RigidBodyParams bp;
  bp.integrator = Integrator::semi_implicit_euler;
  (void)make_rigid_body_model(bp, s.body);
  s.ctrl.lee = lee_params_base_quadrotor();
  s.ctrl.motors.num_motors = static_cast<std::size_t>(s.airframe.num_rotors);
  return s;
}

struct Robots {
  std::vector<RigidBodyState> state;
  std::vector<ControllerState> ctrl;
  std::vector<al::AllocatorState> alloc;
  std::vector<al::MotorModelState> motors;
  std::vector<ControllerOutput> out;
  std::vector<al::AllocationResult> res;
  std::vector<Wrench> wrench;
  std::vector<real> action;
};

Robots make_robots(const Stack& s, int n) {
  Robots r;
  r.state.resize(n);
  r.ctrl.resize(n);
  r.alloc.resize(n);
  r.motors.resize(n);
  r.out.resize(n);
  r.res.resize(n);
  r.wrench.resize(n);
  r.action.assign(static_cast<std::size_t>(n) * kMaxActionDim, 0);
  for (int i = 0; i < n; ++i) {
    RngStream rng(7, static_cast<std::uint32_t>(i), kPurposeReset);
    r.state[i].position_w = Vec3(rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(1, 4));
    r.state[i].orientation_wb = quat_from_euler_xyz(0, 0, rng.uniform(-kPi, kPi));
    for (int k = 0; k < 3; ++k) r.action[i * kMaxActionDim + k] = rng.uniform(-4, 4);
    r.action[i * kMaxActionDim + 2] = rng.uniform(1, 4);
    controller_reset(ControllerKind::lee_position, s.ctrl, r.ctrl[i], rng);
    al::reset_allocator(r.alloc[i]);
    real hover[al::kMaxRotors] = {};
    for (int m = 0; m < 4; ++m) hover[m] = 0.25_r * kStandardGravity / 4;
    (void)al::motor_model_reset(s.motor_cfg, r.motors[i], rng, hover);
  }
  return r;
}

void bench_split(const Options& o) {
  const Stack s = make_stack();
  const int n = 4096;
  Robots r = make_robots(s, n);
  const int k = std::max(1, static_cast<int>(o.env_steps_per_rep / 4 / n));
  const real dt = 0.01_r;
  auto stage = [&](auto&& body) {
    std::vector<double> ns;
    for (int rep = 0; rep < o.reps; ++rep) {
      const auto t0 = Clock::now();
      for (int j = 0; j < k; ++j)
        for (int i = 0; i < n; ++i) body(i);
      ns.push_back(seconds_since(t0) * 1e9 / (static_cast<double>(k) * n));
    }
    return median(ns);
  };
  // Stages run in pipeline order on the same arrays, so each sees realistic inputs.
  const double ns_ctrl = stage([&](int i) {
    (void)update_controller(ControllerKind::lee_position, s.ctrl, r.ctrl[i], r.state[i], &r.action[i * kMaxActionDim],
                            kMaxActionDim, r.out[i]);
  });
  const double ns_alloc = stage([&](int i) {
    (void)al::allocate_sequential_desaturation(s.alloc, s.desat, r.alloc[i], r.out[i].wrench_b, r.res[i]);
  });
  const double ns_motor = stage([&](int i) {
    (void)al::motor_model_step(s.motor_cfg, r.motors[i], r.res[i].thrust_N, dt);
    r.wrench[i] = Wrench::from_vec6(al::wrench_from_thrusts(s.airframe.effectiveness, 4, r.motors[i].thrust_N));
  });
  const double ns_dyn = stage([&](int i) { (void)step_rigid_body(s.body, r.state[i], r.wrench[i], dt); });
  const double total = ns_ctrl + ns_alloc + ns_motor + ns_dyn;
  std::printf("\nSplit of the per-robot physics step (4096 robots, 1 thread, ns per env-step; stages timed one at a time;\n"
              "scalar core functions, as the firmware and World::robot_dynamics call them):\n");
  std::printf("  controller (lee_position)          %7.1f ns  (%4.1f%%)\n", ns_ctrl, 100 * ns_ctrl / total);
  std::printf("  allocation (sequential desat.)     %7.1f ns  (%4.1f%%)\n", ns_alloc, 100 * ns_alloc / total);
  std::printf("  motor model (RK4) + wrench A f      %7.1f ns  (%4.1f%%)\n", ns_motor, 100 * ns_motor / total);
  std::printf("  rigid body (semi-implicit Euler)   %7.1f ns  (%4.1f%%)\n", ns_dyn, 100 * ns_dyn / total);
  std::printf("  sum                                %7.1f ns  (%.3g env-steps/s per core)\n", total, 1e9 / total);
  record("split_controller", n, 1, 1e9 / ns_ctrl, "ns/env-step of the stage alone");
  record("split_allocation", n, 1, 1e9 / ns_alloc, "ns/env-step of the stage alone");
  record("split_motor_model", n, 1, 1e9 / ns_motor, "ns/env-step of the stage alone");
  record("split_rigid_body", n, 1, 1e9 / ns_dyn, "ns/env-step of the stage alone");

  // The same stages through the batched twin (sim/batch_step.hpp: batch::lanes() robots per call, the path
  // World::step takes for this robot), on fresh robots so both splits start from the same states.
  Robots b = make_robots(s, n);
  batch::Models m;
  m.controller = ControllerKind::lee_position;
  m.ctrl = &s.ctrl;
  m.alloc = &s.alloc;
  m.desat = &s.desat;
  m.motor = &s.motor_cfg;
  m.airframe = &s.airframe;
  m.body = &s.body;
  m.dt_s = dt;
  m.substeps = 1;
  if (!batch::eligible(m)) {
    std::printf("  (batched twin not eligible for this build: skipped)\n");
    return;
  }
  const int group_lanes = batch::lanes();
  const int groups = n / group_lanes;
  std::vector<Vec3> zero3(static_cast<std::size_t>(n), Vec3::Zero());
  struct Group {
    batch::Lane l[batch::kMaxLanes];
  };
  std::vector<Group> lanes(static_cast<std::size_t>(groups));
  for (int g = 0; g < groups; ++g)
    for (int l = 0; l < group_lanes; ++l) {
      const int i = g * group_lanes + l;
      batch::Lane& ln = lanes[static_cast<std::size_t>(g)].l[l];
      ln.state = &b.state[i];
      ln.ctrl = &b.ctrl[i];
      ln.alloc = &b.alloc[i];
      ln.motors = &b.motors[i];
      ln.action = &b.action[i * kMaxActionDim];
      ln.contact_force_w = &zero3[i];
      ln.contact_torque_b = &zero3[i];
    }
  struct GroupIo {
    real wrench[6][batch::kMaxLanes];
    real thrust[4][batch::kMaxLanes];
    real body[6][batch::kMaxLanes];
  };
  std::vector<GroupIo> io(static_cast<std::size_t>(groups));
  auto lane_ref = [&](int g) -> const batch::Lane* { return lanes[static_cast<std::size_t>(g)].l; };
  auto bstage = [&](auto&& body) {
    std::vector<double> ns;
    for (int rep = 0; rep < o.reps; ++rep) {
      const auto t0 = Clock::now();
      for (int j = 0; j < k; ++j)
        for (int g = 0; g < groups; ++g) body(g);
      ns.push_back(seconds_since(t0) * 1e9 / (static_cast<double>(k) * groups * group_lanes));
    }
    return median(ns);
  };
  const double b_ctrl = bstage([&](int g) { batch::controller_stage(m, lane_ref(g), io[static_cast<std::size_t>(g)].wrench); });
  const double b_alloc = bstage([&](int g) {
    GroupIo& x = io[static_cast<std::size_t>(g)];
    batch::allocation_stage(m, lane_ref(g), x.wrench, x.thrust);
  });
  const double b_motor = bstage([&](int g) {
    GroupIo& x = io[static_cast<std::size_t>(g)];
    batch::motor_stage(m, lane_ref(g), x.thrust, x.body);
  });
  const double b_dyn = bstage([&](int g) { batch::rigid_body_stage(m, lane_ref(g), io[static_cast<std::size_t>(g)].body); });
  const double b_total = b_ctrl + b_alloc + b_motor + b_dyn;
  std::printf("\nThe same stages through the batched twin (%s, the path World::step takes):\n", batch::kernel_name());
  std::printf("  controller (lee_position)          %7.1f ns  (%4.1f%%)\n", b_ctrl, 100 * b_ctrl / b_total);
  std::printf("  allocation (sequential desat.)     %7.1f ns  (%4.1f%%)\n", b_alloc, 100 * b_alloc / b_total);
  std::printf("  motor model (RK4) + wrench A f      %7.1f ns  (%4.1f%%)\n", b_motor, 100 * b_motor / b_total);
  std::printf("  rigid body (semi-implicit Euler)   %7.1f ns  (%4.1f%%)\n", b_dyn, 100 * b_dyn / b_total);
  std::printf("  sum                                %7.1f ns  (%.3g env-steps/s per core)\n", b_total, 1e9 / b_total);
  record("split_batched_controller", n, 1, 1e9 / b_ctrl, "batched twin; ns/env-step of the stage alone");
  record("split_batched_allocation", n, 1, 1e9 / b_alloc, "batched twin; ns/env-step of the stage alone");
  record("split_batched_motor_model", n, 1, 1e9 / b_motor, "batched twin; ns/env-step of the stage alone");
  record("split_batched_rigid_body", n, 1, 1e9 / b_dyn, "batched twin; ns/env-step of the stage alone");
}

#ifdef KESTREL_BENCH_MUJOCO
// The base quadrotor as MJCF: a free body of 0.25 kg, inertia diag(8.45e-4, 8.45e-4, 1.69e-3),
// a 0.2 m collision sphere (Kestrel's robot shape) over a ground plane (the empty env has one),
// no actuators: the rotor wrench (A f from the Kestrel motor model) goes through xfrc_applied, in
// the world frame at the centre of mass. Euler is MuJoCo's semi-implicit Euler, like Kestrel's.
const char* kQuadMjcf = R"(<mujoco model="base_quadrotor">
  <option timestep="0.01" integrator="Euler" gravity="0 0 -9.81"/>
  <worldbody>
    <geom name="ground" type="plane" size="50 50 0.1"/>
    <body name="quad" pos="0 0 2">
      <freejoint/>
      <inertial pos="0 0 0" mass="0.25" diaginertia="8.45e-4 8.45e-4 1.69e-3"/>
      <geom type="sphere" size="0.2" mass="0" contype="1" conaffinity="1"/>
    </body>
  </worldbody>
</mujoco>)";

mjModel* load_quad_model() {
  // MuJoCo 2.2 loads MJCF from a (virtual) file: put the string into a VFS.
  std::unique_ptr<mjVFS> vfs(new mjVFS);
  mj_defaultVFS(vfs.get());
  const int len = static_cast<int>(std::strlen(kQuadMjcf));
  if (mj_makeEmptyFileVFS(vfs.get(), "quad.xml", len) != 0) return nullptr;
  const int idx = mj_findFileVFS(vfs.get(), "quad.xml");
  std::memcpy(vfs->filedata[idx], kQuadMjcf, static_cast<std::size_t>(len));
  char err[1000] = "";
  mjModel* m = mj_loadXML("quad.xml", vfs.get(), err, sizeof(err));
  mj_deleteVFS(vfs.get());
  if (!m) std::fprintf(stderr, "MuJoCo: %s\n", err);
  return m;
}

/// Env-steps/s of the same quadrotor in MuJoCo on one core: `n` mjData stepped round-robin (as a
/// batched CPU user would), each step = Kestrel control stack from MuJoCo's state, then mj_step.
/// physics_only: mj_step with a fixed wrench (no control) to show MuJoCo's own share.
double time_mujoco(const Options& o, int n, bool physics_only) {
  mjModel* m = load_quad_model();
  if (!m) return 0;
  m->opt.timestep = 0.01;
  const Stack s = make_stack();
  Robots r = make_robots(s, n);
  std::vector<mjData*> d(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    d[i] = mj_makeData(m);
    const RigidBodyState& st = r.state[i];
    for (int k = 0; k < 3; ++k) d[i]->qpos[k] = st.position_w[k];
    d[i]->qpos[3] = st.orientation_wb.w();
    d[i]->qpos[4] = st.orientation_wb.x();
    d[i]->qpos[5] = st.orientation_wb.y();
    d[i]->qpos[6] = st.orientation_wb.z();
    mj_forward(m, d[i]);
  }
  const int body = 1;
  auto one = [&](int i) {
    mjData* di = d[i];
    if (!physics_only) {
      RigidBodyState& st = r.state[i];
      st.position_w = Vec3(static_cast<real>(di->qpos[0]), static_cast<real>(di->qpos[1]), static_cast<real>(di->qpos[2]));
      st.orientation_wb = Quat(static_cast<real>(di->qpos[3]), static_cast<real>(di->qpos[4]), static_cast<real>(di->qpos[5]),
                               static_cast<real>(di->qpos[6]));
      st.linvel_w = Vec3(static_cast<real>(di->qvel[0]), static_cast<real>(di->qvel[1]), static_cast<real>(di->qvel[2]));
      // Free joint: qvel[3..5] is the angular velocity in the body frame (Kestrel's angvel_b).
      st.angvel_b = Vec3(static_cast<real>(di->qvel[3]), static_cast<real>(di->qvel[4]), static_cast<real>(di->qvel[5]));
      ControllerOutput out;
      (void)update_controller(ControllerKind::lee_position, s.ctrl, r.ctrl[i], st, &r.action[i * kMaxActionDim],
                              kMaxActionDim, out);
      al::AllocationResult res;
      (void)al::allocate_sequential_desaturation(s.alloc, s.desat, r.alloc[i], out.wrench_b, res);
      (void)al::motor_model_step(s.motor_cfg, r.motors[i], res.thrust_N, 0.01_r);
      const Wrench w = Wrench::from_vec6(al::wrench_from_thrusts(s.airframe.effectiveness, 4, r.motors[i].thrust_N));
      const Vec3 f_w = rotate(st.orientation_wb, w.force_b), t_w = rotate(st.orientation_wb, w.torque_b);
      for (int k = 0; k < 3; ++k) {
        di->xfrc_applied[6 * body + k] = f_w[k];
        di->xfrc_applied[6 * body + 3 + k] = t_w[k];
      }
    } else {
      di->xfrc_applied[6 * body + 2] = 0.25 * 9.81;
    }
    mj_step(m, di);
  };
  const int k = std::max(1, static_cast<int>(o.env_steps_per_rep / 8 / n));
  const int warm = std::max(1, k / 4);
  ProgressLine progress(stderr, ProgressLine::enabled_for(o.quiet), (static_cast<double>(warm) + o.reps * static_cast<double>(k)) * n);
  for (int j = 0; j < warm; ++j)
    for (int i = 0; i < n; ++i) one(i);
  std::vector<double> rates;
  for (int rep = 0; rep < o.reps; ++rep) {
    progress.update((warm + static_cast<double>(rep) * k) * n);
    const auto t0 = Clock::now();
    for (int j = 0; j < k; ++j)
      for (int i = 0; i < n; ++i) one(i);
    rates.push_back(static_cast<double>(k) * n / seconds_since(t0));
  }
  progress.clear();
  // Sanity: the controlled quads should be near their setpoints (same controller, same dt).
  double dist = 0;
  if (!physics_only) {
    for (int i = 0; i < n; ++i) {
      const Vec3 tgt(r.action[i * kMaxActionDim], r.action[i * kMaxActionDim + 1], r.action[i * kMaxActionDim + 2]);
      dist += static_cast<double>((tgt - r.state[i].position_w).norm());
    }
    std::printf("  (MuJoCo run: mean distance to setpoint after %d steps: %.3f m)\n", k * o.reps + k / 4, dist / n);
  }
  for (mjData* di : d) mj_deleteData(di);
  mj_deleteModel(m);
  return median(rates);
}
#endif

void write_csv(const std::string& path) {
  FILE* f = std::fopen(path.c_str(), "w");
  if (!f) {
    std::fprintf(stderr, "cannot write %s\n", path.c_str());
    std::exit(1);
  }
  std::fprintf(f, "case,envs,threads,env_steps_per_s,ns_per_env_step,note\n");
  for (const Row& r : g_rows) {
    // The note is quoted (it may hold commas: "AVX2 copy, 8 lanes"), its quotes doubled (RFC 4180).
    std::string note;
    for (char ch : r.note) note += ch == '"' ? std::string("\"\"") : std::string(1, ch);
    std::fprintf(f, "%s,%d,%d,%.6g,%.6g,\"%s\"\n", r.name.c_str(), r.envs, r.threads, r.env_steps_per_s, r.ns_per_env_step,
                 note.c_str());
  }
  std::fclose(f);
  std::printf("\nwrote %s\n", path.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") o.quick = true;
    else if (a == "--quiet") o.quiet = true;
    else if (a == "--csv" && i + 1 < argc) o.csv = argv[++i];
    else if (a == "--reps" && i + 1 < argc) o.reps = std::max(1, std::atoi(argv[++i]));
    else {
      std::fprintf(stderr, "usage: kestrel_bench_sim [--quick] [--csv PATH] [--reps N] [--quiet]\n");
      return 2;
    }
  }
  if (o.quick) {
    o.reps = 1;
    o.env_steps_per_rep = 2e4;
  }
  const std::vector<int> sizes = o.quick ? std::vector<int>{1, 256, 1024} : std::vector<int>{1, 256, 1024, 4096, 16384, 65536};
  const int big = o.quick ? 1024 : 4096;

  std::printf("kestrel_bench_sim: full physics step (controller, allocation, motors, dynamics, ground collision,\n"
              "task reset/statistics), base quadrotor, lee_position_control, position setpoints, dt 0.01 s, float32.\n"
              "Median of %d repetitions of ~%.3g env-steps each.\n\n",
              o.reps, o.env_steps_per_rep);
  std::printf("empty env:\n  %8s %14s %14s %12s %12s\n", "envs", "1 thr steps/s", "2 thr steps/s", "1 thr ns/st", "2 thr ns/st");
  std::vector<double> r1(sizes.size()), r2(sizes.size());
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    r1[i] = time_world(o, "empty", sizes[i], 1);
    r2[i] = sizes[i] > 1 ? time_world(o, "empty", sizes[i], 2) : r1[i];
    record("empty", sizes[i], 1, r1[i]);
    if (sizes[i] > 1) record("empty", sizes[i], 2, r2[i]);
    std::printf("  %8d %14.4g %14.4g %12.1f %12.1f\n", sizes[i], r1[i], r2[i], 1e9 / r1[i], 1e9 / r2[i]);
  }
  std::printf("  (1 env: one pool thread whatever the count asked for)\n");
  {
    // Before/after: the same worlds with the scalar robot step (World::set_batched(false)).
    const double s1 = time_world(o, "empty", big, 1, false), s2 = time_world(o, "empty", big, 2, false);
    record("empty_scalar_path", big, 1, s1, "World::set_batched(false)");
    record("empty_scalar_path", big, 2, s2, "World::set_batched(false)");
    std::printf("  %8d %14.4g %14.4g %12.1f %12.1f   <- scalar robot step (set_batched(false)), for comparison\n", big, s1,
                s2, 1e9 / s1, 1e9 / s2);
    // The batched step env-step by env-step (World::set_fused(false)): what every env-step cost
    // before the fused env-steps, and what a world that cannot fuse (obstacles, IMU) still pays.
    const double f1 = time_world(o, "empty", big, 1, true, false), f2 = time_world(o, "empty", big, 2, true, false);
    record("empty_step_by_step", big, 1, f1, "World::set_fused(false)");
    record("empty_step_by_step", big, 2, f2, "World::set_fused(false)");
    std::printf("  %8d %14.4g %14.4g %12.1f %12.1f   <- batched, env-step by env-step (set_fused(false))\n", big, f1, f2,
                1e9 / f1, 1e9 / f2);
    // One env-step per World::step call (what a learner's loop does): fused and not.
    const double c1 = time_world(o, "empty", big, 1, true, true, true), c2 = time_world(o, "empty", big, 2, true, true, true);
    const double d1 = time_world(o, "empty", big, 1, true, false, true), d2 = time_world(o, "empty", big, 2, true, false, true);
    record("empty_one_step_per_call", big, 1, c1, "World::step(1) calls, fused");
    record("empty_one_step_per_call", big, 2, c2, "World::step(1) calls, fused");
    record("empty_one_step_per_call_step_by_step", big, 1, d1, "World::step(1) calls, set_fused(false)");
    record("empty_one_step_per_call_step_by_step", big, 2, d2, "World::step(1) calls, set_fused(false)");
    std::printf("  %8d %14.4g %14.4g %12.1f %12.1f   <- one env-step per step() call, fused\n", big, c1, c2, 1e9 / c1, 1e9 / c2);
    std::printf("  %8d %14.4g %14.4g %12.1f %12.1f   <- one env-step per step() call, set_fused(false)\n", big, d1, d2, 1e9 / d1,
                1e9 / d2);
  }
  {
    // The kernel copies side by side (issue 18): the same worlds with the 4-lane (SSE2), 8-lane
    // (AVX2) and 16-lane (AVX-512) robot step, each that this CPU runs; same bits.
    std::printf("  kernel copies at %d envs (same bits; 1 thr / 2 thr env-steps/s):\n", big);
    double base1 = 0, base2 = 0;
    for (batch::KernelCopy c : {batch::KernelCopy::baseline, batch::KernelCopy::avx2, batch::KernelCopy::avx512}) {
      if (!batch::use_kernel(c)) continue;
      const double k1 = time_world(o, "empty", big, 1), k2 = time_world(o, "empty", big, 2);
      const double u1 = time_world(o, "empty", big, 1, true, false), u2 = time_world(o, "empty", big, 2, true, false);
      const int nl = batch::lanes();
      record(std::string("empty_step_by_step_lanes_") + std::to_string(nl), big, 1, u1, batch::kernel_name());
      record(std::string("empty_step_by_step_lanes_") + std::to_string(nl), big, 2, u2, batch::kernel_name());
      std::printf("    %-24s %12.4g %12.4g  (env-step by env-step)\n", batch::kernel_name(), u1, u2);
      if (c == batch::KernelCopy::baseline) base1 = k1, base2 = k2;
      const std::string name = std::string("empty_lanes_") + std::to_string(nl);
      record(name, big, 1, k1, batch::kernel_name());
      record(name, big, 2, k2, batch::kernel_name());
      std::printf("    %-24s %12.4g %12.4g  (%.2fx / %.2fx the 4-lane copy)\n", batch::kernel_name(), k1, k2, k1 / base1, k2 / base2);
      if (c != batch::KernelCopy::baseline) {
        record("ratio_lanes_" + std::to_string(nl) + "_vs_4", big, 1, k1 / base1, "ratio (not a rate), same run");
        record("ratio_lanes_" + std::to_string(nl) + "_vs_4", big, 2, k2 / base2, "ratio (not a rate), same run");
      }
    }
    batch::use_default_kernel();
  }
  const double one_env_us = 1e6 / r1[0];
  std::size_t i_big = 0;
  for (std::size_t i = 0; i < sizes.size(); ++i)
    if (sizes[i] == big) i_big = i;

  // Flatness of the cost per env-step from 256 up to the largest size.
  std::printf("\ncost per env-step, 256 -> %d envs (relative to the mean over those sizes):\n", sizes.back());
  for (int t = 1; t <= 2; ++t) {
    const std::vector<double>& r = t == 1 ? r1 : r2;
    double mean = 0;
    int cnt = 0;
    for (std::size_t i = 0; i < sizes.size(); ++i)
      if (sizes[i] >= 256) mean += 1e9 / r[i], ++cnt;
    mean /= cnt;
    double worst = 0;
    std::printf("  %d thread(s):", t);
    for (std::size_t i = 0; i < sizes.size(); ++i) {
      if (sizes[i] < 256) continue;
      const double dev = (1e9 / r[i]) / mean - 1;
      worst = std::max(worst, std::fabs(dev));
      std::printf("  %d: %.1f ns (%+.0f%%)", sizes[i], 1e9 / r[i], 100 * dev);
    }
    std::printf("\n    -> within +-%.0f%% (target +-20%%)\n", 100 * worst);
    record("flatness", sizes.back(), t, 0, "max deviation " + std::to_string(static_cast<int>(std::lround(100 * worst))) + "%");
  }

  std::printf("\nwith obstacles (%d envs, 2 threads, collision on):\n", big);
  const double obst = time_world(o, "env_with_obstacles", big, 2);
  const double forest = time_world(o, "forest", big, 2);
  record("env_with_obstacles", big, 2, obst, "~45 obstacles/env");
  record("forest", big, 2, forest, "10 trees x 4 capsules");
  std::printf("  env_with_obstacles (~45 obstacles/env): %.4g env-steps/s (%.1f ns/env-step)\n", obst, 1e9 / obst);
  std::printf("  forest (40 capsules/env):              %.4g env-steps/s (%.1f ns/env-step)\n", forest, 1e9 / forest);

  bench_split(o);

  std::printf("\nvs torch baseline (tests/golden/reference/torch_baseline.md; Aerial Gym's controller+allocation+motor model,\n"
              "PyTorch CPU, this machine; Kestrel's figure also includes dynamics, collision and the task):\n");
  std::printf("  %d envs, 2 threads: Kestrel %.4g vs torch %.3g env-steps/s -> %.1fx   (target: Kestrel >= %.3g: %s)\n", big,
              r2[i_big], kTorch4096EnvStepsPerS, r2[i_big] / kTorch4096EnvStepsPerS, kTargetEmpty4096x2,
              r2[i_big] >= kTargetEmpty4096x2 ? "met" : "NOT met");
  std::printf("  1 env:              Kestrel %.4g vs torch %.3g env-steps/s -> %.0fx    (%.3f us/step; target < 1 us: %s)\n",
              r1[0], kTorch1EnvStepsPerS, r1[0] / kTorch1EnvStepsPerS, one_env_us, one_env_us < 1 ? "met" : "NOT met");
  std::printf("  env_with_obstacles %d envs, 2 threads: %.4g env-steps/s -> %.1fx torch (target >= %.3g: %s)\n", big, obst,
              obst / kTorch4096EnvStepsPerS, kTargetObstacles4096x2, obst >= kTargetObstacles4096x2 ? "met" : "NOT met");
  std::printf("  %d envs, 2 threads: %.4g env-steps/s (issue 18 target on 2 cores: >= %.3g: %s)\n", big, r2[i_big],
              kTargetEmpty4096x2Issue18, r2[i_big] >= kTargetEmpty4096x2Issue18 ? "met" : "NOT met");
  record("ratio_vs_torch_4096x2", big, 2, r2[i_big] / kTorch4096EnvStepsPerS, "ratio (not a rate)");
  record("ratio_vs_torch_1env", 1, 1, r1[0] / kTorch1EnvStepsPerS, "ratio (not a rate)");

#ifdef KESTREL_BENCH_MUJOCO
  std::printf("\nMuJoCo %s (same quadrotor: free body + ground plane, same Kestrel controller/allocation/motor model,\n"
              "dt 0.01 s, Euler; one core):\n",
              mj_versionString());
  const int nm = o.quick ? 16 : 256;
  const double mj = time_mujoco(o, nm, false);
  const double mj_phys = time_mujoco(o, nm, true);
  const double mj1 = time_mujoco(o, 1, false);
  record("mujoco_full", nm, 1, mj, "Kestrel control + mj_step");
  record("mujoco_mj_step_only", nm, 1, mj_phys, "mj_step with a fixed wrench");
  record("mujoco_full", 1, 1, mj1, "Kestrel control + mj_step");
  // Per core: Kestrel 1 thread at the nearest batch size vs MuJoCo on one core.
  std::size_t i_nm = 0;
  for (std::size_t i = 0; i < sizes.size(); ++i)
    if (sizes[i] <= nm) i_nm = i;
  std::printf("  %d envs round-robin: %.4g env-steps/s (%.0f ns/env-step); mj_step alone %.4g env-steps/s (%.0f ns)\n", nm, mj,
              1e9 / mj, mj_phys, 1e9 / mj_phys);
  std::printf("  1 env:               %.4g env-steps/s (%.0f ns/env-step)\n", mj1, 1e9 / mj1);
  std::printf("  per core: Kestrel %d envs 1 thread %.4g / MuJoCo %.4g = %.1fx; 1 env: %.1fx   (target >= 10x: %s)\n",
              sizes[i_nm], r1[i_nm], mj, r1[i_nm] / mj, r1[0] / mj1, r1[i_nm] / mj >= 10 ? "met" : "NOT met");
  record("ratio_vs_mujoco_per_core", sizes[i_nm], 1, r1[i_nm] / mj, "ratio (not a rate)");
  record("ratio_vs_mujoco_per_core", 1, 1, r1[0] / mj1, "ratio (not a rate)");
#else
  std::printf("\nMuJoCo comparison skipped (built without libmujoco-dev)\n");
#endif
  if (!o.csv.empty()) write_csv(o.csv);
  return 0;
}
