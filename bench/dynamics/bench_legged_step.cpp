// Full physics step of a legged robot standing on flat ground, Kestrel against MuJoCo, same model,
// same time step, in the same run (issue 12, "Measured": "Full physics step of a Go2 on flat ground
// with its four foot contacts, per core, against MuJoCo (same model, same dt) in the same run.
// Goal: <= 3 us per physics step per core, >= 15x MuJoCo per core").
//
// Per robot file (models/go2/go2.xml, models/anymal_c/anymal_c.xml):
//  - MuJoCo (Debian's libmujoco 2.2.2 C library, double, its own defaults for the solver: the file
//    sets none): a small wrapper MJCF written to a temporary file <include>s the robot file and adds
//    a floor plane z = 0 (the robot files have none). One physics step = the joint PD below into
//    d->ctrl (the files' motors, gear 1, ctrlrange = the effort limits) and mj_step.
//  - Kestrel: the same file through the sim library's loader (sim/articulated_robot.hpp, which reads
//    it with the same MuJoCo compiler and translates it once into the core's MultibodyModel), in the
//    project's default `real` (float, as kestrel_sim is built). Every collision geom of the robot
//    that the core's half-space collider takes (sphere, capsule, box: feet, calves, thighs, trunk)
//    becomes a dynamics::CollisionShape. One physics step = the joint PD below, forward_kinematics,
//    collide_halfspace against HalfSpace() (z = 0) and step_constrained(..., drive_kp, drive_kd)
//    (the PD's gains taken implicitly; a joint whose torque is clipped gets none that step).
//  - The PD on every leg joint toward the `home` keyframe's angles, legged_gym's gains (Go2: kp 20
//    N m/rad, kd 0.5 N m s/rad; ANYmal C: 80 / 2), clipped at the joint's effort limit.
// Both start at `home` and settle for 2 s; then, per rep (both sides restored to the settled state,
// Kestrel's and MuJoCo's reps interleaved), STEPS physics steps are timed; the best rep is reported
// in ns per physics step. Sanity figures, averaged over the last 0.2 s of the settling: base height,
// the contacts' normal forces summed (standing still they carry m g), Kestrel's PGS sweeps
// (cd.iterations_used), MuJoCo's contacts (d->ncon) and solver iterations; the base's horizontal
// drift over the settling and over one timed rep.
//
// Timings are figures, never assertions. The exit status checks only that both sides stand: base
// heights within 3 cm of each other, summed normal force within 10% of m g on both, no step
// refused (the smoke ctest). bench/dynamics/run_legged.sh runs it pinned to one core and writes
// bench/results/host/legged_step_side_by_side.csv.
#include <mujoco/mujoco.h>
#include <unistd.h>

#include <climits>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "kestrel/dynamics/contact.hpp"
#include "kestrel/dynamics/multibody.hpp"
#include "kestrel/sim/articulated_robot.hpp"

#ifndef KESTREL_BENCH_MODELS_DIR
#define KESTREL_BENCH_MODELS_DIR "models"
#endif
#ifndef KESTREL_BENCH_CXX_FLAGS
#define KESTREL_BENCH_CXX_FLAGS "?"
#endif

namespace {
namespace dy = kestrel::dynamics;
namespace ks = kestrel::sim;
using kestrel::real;
using Clock = std::chrono::steady_clock;

constexpr double kDt = 0.005;
constexpr double kSettleS = 2.0;
constexpr int kAverageSteps = 40;  // the last 0.2 s of the settling
constexpr int kMaxContacts = 32;   // Go2: 8 box corners + 16 capsule ends + 4 feet at most
constexpr double kG = 9.81;

volatile double g_sink = 0;

struct Case {
  const char* name;
  const char* file;  // under the models directory
  double kp, kd;
};

struct Result {
  std::string robot;
  double mass_kg = 0;
  int kestrel_shapes = 0;
  double kestrel_ns = 0, mujoco_ns = 0;
  double kestrel_height = 0, mujoco_height = 0;
  double kestrel_fn = 0, mujoco_fn = 0;
  double kestrel_iters = 0;
  int kestrel_iters_max = 0;
  double kestrel_contacts = 0, mujoco_ncon = 0, mujoco_solver_iter = 0;
  double kestrel_settle_drift = 0, mujoco_settle_drift = 0;  // base x-y distance moved during the settling (m)
  double kestrel_run_drift = 0, mujoco_run_drift = 0;        // ... during one timed rep (m)
  double kestrel_run_dz = 0, mujoco_run_dz = 0;              // base height change during one timed rep (m)
  bool ok = true;
  std::string problem;
};

// ---------------------------------------------------------------- Kestrel's side
struct KestrelSide {
  ks::ArticulatedRobot robot;
  dy::MultibodyData<ks::kMaxRobotBodies> data;
  dy::ConstraintData<ks::kMaxRobotBodies, kMaxContacts> cd;
  std::vector<dy::CollisionShape> shapes;
  dy::HalfSpace ground;
  std::vector<real> q, qd, tau, kp, kd, q_home;
  std::vector<real> kp_step, kd_step;
  int contacts_last = 0;
  bool overflow = false;

  bool init(const std::string& path, double gain_p, double gain_d, std::string& err) {
    if (!ks::load_robot_model(path, robot, err)) return false;
    const auto& m = robot.multibody;
    if (!robot.has_home) {
      err = path + ": no 'home' keyframe";
      return false;
    }
    for (const ks::RobotGeom& g : robot.geoms) {
      if (g.body < 0) continue;  // world geoms: none in these files
      dy::CollisionShape s;
      s.body = g.body;
      switch (g.type) {
        case ks::RobotGeomType::sphere: s.type = dy::ShapeType::sphere; break;
        case ks::RobotGeomType::capsule: s.type = dy::ShapeType::capsule; break;
        case ks::RobotGeomType::box: s.type = dy::ShapeType::box; break;
        default: continue;  // plane, ellipsoid, cylinder: not in the half-space collider
      }
      const Eigen::Quaternion<real> qr(g.quat_xyzw_b[3], g.quat_xyzw_b[0], g.quat_xyzw_b[1], g.quat_xyzw_b[2]);
      s.R_b = qr.normalized().toRotationMatrix();
      s.p_b = g.pos_b;
      s.size = g.size;
      s.friction = g.friction;
      shapes.push_back(s);
    }
    ground.friction = 1;  // MuJoCo's floor below has friction 1 too (MuJoCo combines by max, Kestrel by mean)
    q = robot.home_q;
    q_home = robot.home_q;
    qd.assign(static_cast<std::size_t>(m.num_dofs), 0);
    tau.assign(qd.size(), 0);
    kp.assign(qd.size(), 0);
    kd.assign(qd.size(), 0);
    for (int i = 0; i < m.num_bodies; ++i)
      if (m.joint[i] == dy::JointType::revolute || m.joint[i] == dy::JointType::prismatic) {
        kp[static_cast<std::size_t>(m.dof_index[i])] = static_cast<real>(gain_p);
        kd[static_cast<std::size_t>(m.dof_index[i])] = static_cast<real>(gain_d);
      }
    kp_step = kp;
    kd_step = kd;
    return true;
  }

  kestrel::Status step() {
    const auto& m = robot.multibody;
    for (int i = 0; i < m.num_bodies; ++i) {
      if (m.joint[i] != dy::JointType::revolute && m.joint[i] != dy::JointType::prismatic) continue;
      const auto k = static_cast<std::size_t>(m.dof_index[i]);
      const auto j = static_cast<std::size_t>(m.q_index[i]);
      const real t = kp[k] * (q_home[j] - q[j]) - kd[k] * qd[k];
      const real lim = m.effort_limit[i];
      const bool clipped = lim > 0 && std::fabs(t) > lim;
      tau[k] = clipped ? std::copysign(lim, t) : t;
      kp_step[k] = clipped ? real(0) : kp[k];
      kd_step[k] = clipped ? real(0) : kd[k];
    }
    dy::ContactPoint contacts[kMaxContacts];
    dy::forward_kinematics(m, data, q.data(), cd.X_world);
    int n = dy::collide_halfspace(shapes.data(), static_cast<int>(shapes.size()), cd.X_world, ground, real(0.01), contacts,
                                  kMaxContacts);
    if (n > kMaxContacts) {
      overflow = true;
      n = kMaxContacts;
    }
    contacts_last = n;
    return dy::step_constrained(m, data, cd, q.data(), qd.data(), tau.data(), static_cast<real>(kDt), contacts, n,
                                dy::ConstraintParams(), kp_step.data(), kd_step.data());
  }

  double normal_force() const {
    double f = 0;
    for (int c = 0; c < contacts_last; ++c) f += static_cast<double>(cd.contact_force_w[c].dot(ground.normal_w));
    return f;
  }
  double x() const { return static_cast<double>(q[0]); }
  double y() const { return static_cast<double>(q[1]); }
  double z() const { return static_cast<double>(q[2]); }
};

// ---------------------------------------------------------------- MuJoCo's side
struct MujocoSide {
  mjModel* m = nullptr;
  mjData* d = nullptr;
  std::vector<int> act_q, act_v;  // per actuator: the joint's qpos and qvel addresses
  std::vector<double> q_home, lim;
  double kp = 0, kd = 0;

  ~MujocoSide() {
    if (d != nullptr) mj_deleteData(d);
    if (m != nullptr) mj_deleteModel(m);
  }

  bool init(const std::string& robot_path, double gain_p, double gain_d, std::string& err) {
    // The robot file with a floor: a wrapper that includes it (absolute path) and adds a plane.
    char tmp[] = "/tmp/kestrel_bench_legged_XXXXXX.xml";
    const int fd = mkstemps(tmp, 4);
    if (fd < 0) {
      err = "cannot create a temporary file for the wrapper MJCF";
      return false;
    }
    close(fd);
    // MuJoCo 2.2 resolves an include against the including file's folder (it prefixes it even to an
    // absolute path): climb from /tmp to the root first.
    char abs_path[PATH_MAX];
    if (realpath(robot_path.c_str(), abs_path) == nullptr) {
      std::remove(tmp);
      err = robot_path + ": no such file";
      return false;
    }
    {
      std::ofstream w(tmp);
      w << "<mujoco model=\"floor_and_robot\">\n  <include file=\".." << abs_path
        << "\"/>\n  <worldbody>\n    <geom name=\"floor\" type=\"plane\" size=\"0 0 1\" pos=\"0 0 0\" "
           "contype=\"1\" conaffinity=\"1\" friction=\"1 0.005 0.0001\"/>\n  </worldbody>\n</mujoco>\n";
    }
    char msg[1000] = "";
    m = mj_loadXML(tmp, nullptr, msg, sizeof msg);
    std::remove(tmp);
    if (m == nullptr) {
      err = robot_path + " (MuJoCo, with a floor): " + msg;
      return false;
    }
    if (std::fabs(m->opt.timestep - kDt) > 1e-12) {
      err = robot_path + ": MuJoCo's timestep is not 0.005 s";
      return false;
    }
    d = mj_makeData(m);
    const int key = mj_name2id(m, mjOBJ_KEY, "home");
    if (key < 0) {
      err = robot_path + ": no 'home' keyframe in MuJoCo's model";
      return false;
    }
    mj_resetDataKeyframe(m, d, key);
    for (int a = 0; a < m->nu; ++a) {
      if (m->actuator_trntype[a] != mjTRN_JOINT) {
        err = robot_path + ": an actuator not on a joint";
        return false;
      }
      const int j = m->actuator_trnid[2 * a];
      act_q.push_back(m->jnt_qposadr[j]);
      act_v.push_back(m->jnt_dofadr[j]);
      q_home.push_back(m->key_qpos[key * m->nq + m->jnt_qposadr[j]]);
      lim.push_back(m->actuator_ctrllimited[a] ? std::min(std::fabs(m->actuator_ctrlrange[2 * a]),
                                                          std::fabs(m->actuator_ctrlrange[2 * a + 1]))
                                               : 1e300);
    }
    kp = gain_p;
    kd = gain_d;
    mj_forward(m, d);
    return true;
  }

  void step() {
    for (int a = 0; a < m->nu; ++a) {
      const double t = kp * (q_home[static_cast<std::size_t>(a)] - d->qpos[act_q[static_cast<std::size_t>(a)]]) -
                       kd * d->qvel[act_v[static_cast<std::size_t>(a)]];
      const double l = lim[static_cast<std::size_t>(a)];
      d->ctrl[a] = std::max(-l, std::min(l, t));
    }
    mj_step(m, d);
  }

  double normal_force() const {
    double f = 0;
    for (int c = 0; c < d->ncon; ++c) {
      mjtNum r[6];
      mj_contactForce(m, d, c, r);
      f += r[0];
    }
    return f;
  }
  double x() const { return d->qpos[0]; }
  double y() const { return d->qpos[1]; }
  double z() const { return d->qpos[2]; }
};

std::string cpu_model() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) {
      const auto p = line.find(':');
      return p == std::string::npos ? line : line.substr(p + 2);
    }
  return "unknown CPU";
}

const char* integrator_name(int i) {
  switch (i) {
    case mjINT_EULER: return "Euler";
    case mjINT_RK4: return "RK4";
    default: return "implicit";
  }
}

bool run_case(const Case& c, const std::string& models, long steps, int reps, Result& out, std::string& mj_desc) {
  const std::string path = models + "/" + c.file;
  out.robot = c.name;
  std::string err;
  const auto ks_side = std::make_unique<KestrelSide>();  // large scratch (ConstraintData): on the heap
  MujocoSide mj;
  if (!ks_side->init(path, c.kp, c.kd, err) || !mj.init(path, c.kp, c.kd, err)) {
    std::fprintf(stderr, "kestrel_bench_legged_step: %s\n", err.c_str());
    return false;
  }
  KestrelSide& k = *ks_side;
  out.mass_kg = static_cast<double>(k.robot.total_mass_kg);
  out.kestrel_shapes = static_cast<int>(k.shapes.size());
  if (std::fabs(mj_getTotalmass(mj.m) - out.mass_kg) > 1e-3 * out.mass_kg) {
    out.ok = false;
    out.problem += " masses differ (Kestrel " + std::to_string(out.mass_kg) + ", MuJoCo " +
                   std::to_string(mj_getTotalmass(mj.m)) + ");";
  }
  char buf[256];
  std::snprintf(buf, sizeof buf, "integrator %s, cone %s, solver %s, iterations %d, tolerance %g",
                integrator_name(mj.m->opt.integrator), mj.m->opt.cone == mjCONE_ELLIPTIC ? "elliptic" : "pyramidal",
                mj.m->opt.solver == mjSOL_NEWTON ? "Newton" : mj.m->opt.solver == mjSOL_CG ? "CG" : "PGS",
                mj.m->opt.iterations, mj.m->opt.tolerance);
  mj_desc = buf;

  // Settle 2 s on both sides.
  const int settle = static_cast<int>(std::lround(kSettleS / kDt));
  const double kx0 = k.x(), ky0 = k.y(), mx0 = mj.x(), my0 = mj.y();
  for (int s = 0; s < settle; ++s) {
    const kestrel::Status st = k.step();
    if (st != kestrel::Status::ok) {
      out.ok = false;
      out.problem += " Kestrel's step " + std::to_string(s) + " refused (status " + std::to_string(static_cast<int>(st)) + ");";
      return true;
    }
    mj.step();
    if (s >= settle - kAverageSteps) {
      out.kestrel_height += k.z() / kAverageSteps;
      out.mujoco_height += mj.z() / kAverageSteps;
      out.kestrel_fn += k.normal_force() / kAverageSteps;
      out.mujoco_fn += mj.normal_force() / kAverageSteps;
      out.kestrel_iters += static_cast<double>(k.cd.iterations_used) / kAverageSteps;
      out.kestrel_iters_max = std::max(out.kestrel_iters_max, k.cd.iterations_used);
      out.kestrel_contacts += static_cast<double>(k.contacts_last) / kAverageSteps;
      out.mujoco_ncon += static_cast<double>(mj.d->ncon) / kAverageSteps;
      out.mujoco_solver_iter += static_cast<double>(mj.d->solver_iter) / kAverageSteps;
    }
  }
  out.kestrel_settle_drift = std::hypot(k.x() - kx0, k.y() - ky0);
  out.mujoco_settle_drift = std::hypot(mj.x() - mx0, mj.y() - my0);
  if (k.overflow) {
    out.ok = false;
    out.problem += " more than " + std::to_string(kMaxContacts) + " Kestrel contacts;";
  }

  // The timed reps, from the settled state each time, interleaved.
  const std::vector<real> q_settled = k.q, qd_settled = k.qd;
  mjData* settled = mj_makeData(mj.m);
  mj_copyData(settled, mj.m, mj.d);
  out.kestrel_ns = out.mujoco_ns = 1e300;
  bool k_ok = true;
  for (int r = 0; r < reps; ++r) {
    k.q = q_settled;
    k.qd = qd_settled;
    const auto t0 = Clock::now();
    for (long i = 0; i < steps; ++i) k_ok = (k.step() == kestrel::Status::ok) && k_ok;
    const double kns = std::chrono::duration<double, std::nano>(Clock::now() - t0).count() / static_cast<double>(steps);
    out.kestrel_ns = std::min(out.kestrel_ns, kns);
    g_sink = g_sink + k.z();
    if (r == 0) {
      out.kestrel_run_drift = std::hypot(k.x() - static_cast<double>(q_settled[0]), k.y() - static_cast<double>(q_settled[1]));
      out.kestrel_run_dz = k.z() - static_cast<double>(q_settled[2]);
    }
    mj_copyData(mj.d, mj.m, settled);
    const auto t1 = Clock::now();
    for (long i = 0; i < steps; ++i) mj.step();
    const double mns = std::chrono::duration<double, std::nano>(Clock::now() - t1).count() / static_cast<double>(steps);
    out.mujoco_ns = std::min(out.mujoco_ns, mns);
    g_sink = g_sink + mj.z();
    if (r == 0) {
      out.mujoco_run_drift = std::hypot(mj.x() - settled->qpos[0], mj.y() - settled->qpos[1]);
      out.mujoco_run_dz = mj.z() - settled->qpos[2];
    }
  }
  mj_deleteData(settled);
  if (!k_ok) {
    out.ok = false;
    out.problem += " a timed Kestrel step refused;";
  }

  // Do both stand?
  const double mg = out.mass_kg * kG;
  if (!(std::fabs(out.kestrel_height - out.mujoco_height) < 0.03)) {
    out.ok = false;
    out.problem += " base heights differ by more than 3 cm;";
  }
  if (!(std::fabs(out.kestrel_fn - mg) < 0.1 * mg)) {
    out.ok = false;
    out.problem += " Kestrel's normal force is not within 10% of m g;";
  }
  if (!(std::fabs(out.mujoco_fn - mg) < 0.1 * mg)) {
    out.ok = false;
    out.problem += " MuJoCo's normal force is not within 10% of m g;";
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  long steps = 5000;
  int reps = 7;
  const char* csv = nullptr;
  std::string models = KESTREL_BENCH_MODELS_DIR;
  std::string machine = "host";
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--steps") && i + 1 < argc) steps = std::atol(argv[++i]);
    else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--csv") && i + 1 < argc) csv = argv[++i];
    else if (!std::strcmp(argv[i], "--models") && i + 1 < argc) models = argv[++i];
    else if (!std::strcmp(argv[i], "--machine") && i + 1 < argc) machine = argv[++i];
    else {
      std::fprintf(stderr,
                   "usage: kestrel_bench_legged_step [--steps N] [--reps R] [--csv PATH] [--models DIR] [--machine LABEL]\n");
      return 2;
    }
  }
  if (steps < 1 || reps < 1) {
    std::fprintf(stderr, "kestrel_bench_legged_step: --steps and --reps must be positive\n");
    return 2;
  }
  const Case cases[] = {{"go2", "go2/go2.xml", 20, 0.5}, {"anymal_c", "anymal_c/anymal_c.xml", 80, 2}};
  std::vector<Result> results;
  std::string mj_desc;
  for (const Case& c : cases) {
    Result r;
    if (!run_case(c, models, steps, reps, r, mj_desc)) return 1;
    results.push_back(r);
  }

  char header[1024];
  std::snprintf(header, sizeof header,
                "machine %s (%s, %ld logical CPUs), one thread; compiler %s, flags %s; Kestrel real = %s (the project's "
                "default build, kestrel_sim's loader), MuJoCo %s in double (%s); dt %g s, settle %g s, best of %d reps "
                "x %ld steps, interleaved",
                machine.c_str(), cpu_model().c_str(), sysconf(_SC_NPROCESSORS_ONLN), __VERSION__, KESTREL_BENCH_CXX_FLAGS,
                sizeof(real) == 8 ? "double" : "float", mj_versionString(), mj_desc.c_str(), kDt, kSettleS, reps, steps);
  std::printf("legged physics step on flat ground, PD to home (Go2 kp 20 kd 0.5, ANYmal C kp 80 kd 2)\n# %s\n", header);
  std::printf("  %-9s %7s %11s %11s %7s %9s %9s %9s %9s %8s %6s %6s %7s %11s %11s\n", "robot", "mass kg", "kestrel ns",
              "mujoco ns", "ratio", "k z m", "mj z m", "k Fn N", "mj Fn N", "m g N", "k it", "k con", "mj con",
              "k drift mm", "mj drift mm");
  FILE* f = csv != nullptr ? std::fopen(csv, "w") : nullptr;
  if (csv != nullptr && f == nullptr) {
    std::fprintf(stderr, "kestrel_bench_legged_step: cannot write --csv %s\n", csv);
    return 1;
  }
  if (f != nullptr)
    std::fprintf(f,
                 "# %s\nrobot,mass_kg,kestrel_ns_per_step,mujoco_ns_per_step,mujoco_over_kestrel,kestrel_base_z_m,"
                 "mujoco_base_z_m,kestrel_normal_force_n,mujoco_normal_force_n,m_g_n,kestrel_pgs_iterations_mean,"
                 "kestrel_pgs_iterations_max,kestrel_contacts,mujoco_ncon,mujoco_solver_iter,kestrel_shapes,"
                 "kestrel_settle_drift_xy_m,mujoco_settle_drift_xy_m,kestrel_rep_drift_xy_m,mujoco_rep_drift_xy_m,"
                 "kestrel_rep_dz_m,mujoco_rep_dz_m,stands\n",
                 header);
  bool all_ok = true;
  for (const Result& r : results) {
    const double ratio = r.mujoco_ns / r.kestrel_ns;
    std::printf("  %-9s %7.3f %11.1f %11.1f %7.2f %9.4f %9.4f %9.2f %9.2f %8.2f %6.1f %6.1f %7.1f %11.2f %11.2f\n",
                r.robot.c_str(), r.mass_kg, r.kestrel_ns, r.mujoco_ns, ratio, r.kestrel_height, r.mujoco_height, r.kestrel_fn,
                r.mujoco_fn, r.mass_kg * kG, r.kestrel_iters, r.kestrel_contacts, r.mujoco_ncon,
                1e3 * r.kestrel_settle_drift, 1e3 * r.mujoco_settle_drift);
    std::printf("            Kestrel: %d shapes, PGS sweeps max %d; MuJoCo solver iterations %.1f; one timed rep (%.1f s): "
                "drift Kestrel %.2f mm (dz %+.2f mm), MuJoCo %.2f mm (dz %+.2f mm)\n",
                r.kestrel_shapes, r.kestrel_iters_max, r.mujoco_solver_iter, static_cast<double>(steps) * kDt,
                1e3 * r.kestrel_run_drift, 1e3 * r.kestrel_run_dz, 1e3 * r.mujoco_run_drift, 1e3 * r.mujoco_run_dz);
    if (f != nullptr)
      std::fprintf(f, "%s,%.3f,%.1f,%.1f,%.3f,%.5f,%.5f,%.3f,%.3f,%.3f,%.2f,%d,%.2f,%.2f,%.2f,%d,%.3g,%.3g,%.3g,%.3g,%.3g,%.3g,%d\n",
                   r.robot.c_str(), r.mass_kg, r.kestrel_ns, r.mujoco_ns, ratio, r.kestrel_height, r.mujoco_height,
                   r.kestrel_fn, r.mujoco_fn, r.mass_kg * kG, r.kestrel_iters, r.kestrel_iters_max, r.kestrel_contacts,
                   r.mujoco_ncon, r.mujoco_solver_iter, r.kestrel_shapes, r.kestrel_settle_drift, r.mujoco_settle_drift,
                   r.kestrel_run_drift, r.mujoco_run_drift, r.kestrel_run_dz, r.mujoco_run_dz, r.ok ? 1 : 0);
    if (!r.ok) {
      std::fprintf(stderr, "kestrel_bench_legged_step: %s does not stand on both sides:%s\n", r.robot.c_str(), r.problem.c_str());
      all_ok = false;
    }
  }
  if (f != nullptr) std::fclose(f);
  return all_ok ? 0 : 1;
}
