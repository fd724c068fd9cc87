// Full physics step of a legged robot standing on flat ground, Kestrel against MuJoCo, same model,
// same time step, in the same run (issue 12, "Measured": "Full physics step of a Go2 on flat ground
// with its four foot contacts, per core, against MuJoCo (same model, same dt) in the same run.
// Goal: <= 3 us per physics step per core, >= 15x MuJoCo per core").
//
// Per robot file (models/go2/go2.xml, models/anymal_c/anymal_c.xml):
//  - MuJoCo, double, two builds side by side (mujoco_runner.hpp): Debian's libmujoco 2.2.2 C library
//    (the one the loader links) and the PyPI wheel's (python/requirements.txt's `mujoco`, the build
//    the issue names; its library loaded with dlopen, --mujoco-pypi, found in .venv by the build).
//    Per build: a small wrapper MJCF written to a
//    temporary file <include>s the robot file and adds a floor plane z = 0 (the robot files have
//    none). One physics step = the joint PD below into d->ctrl (the files' motors, gear 1, ctrlrange
//    = the effort limits) and mj_step. Two solver settings, each timed: the file's own (it sets none:
//    MuJoCo's defaults, Newton, pyramidal cone, impratio 1; its soft friction lets the feet creep
//    apart under a standing robot, ANYmal C sinking ~6 mm/s) and the MuJoCo Menagerie Go2's
//    (elliptic cone, impratio 100, "to reduce slippage"; Kestrel's cone is isotropic too), against
//    which the heights are checked.
//  - Kestrel: the same file through the sim library's loader (sim/articulated_robot.hpp, which reads
//    it with the same MuJoCo compiler and translates it once into the core's MultibodyModel), in the
//    project's default `real` (float, as kestrel_sim is built). Every collision geom of the robot
//    that the core's half-space collider takes (sphere, capsule, box: feet, calves, thighs, trunk)
//    becomes a dynamics::CollisionShape. One physics step = the joint PD below, forward_kinematics,
//    collide_halfspace against HalfSpace() (z = 0) and step_constrained(..., drive_kp, drive_kd) (reusing
//    that forward kinematics, ConstraintParams::poses_current, as the simulator does)
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
#include <unistd.h>

#include <climits>
#include <cstdint>

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
#include "kestrel/sim/aligned_scratch.hpp"
#include "kestrel/sim/articulated_robot.hpp"
#include "kestrel/sim/progress.hpp"
#include "backends/articulated_batch.hpp"
#include "mujoco_runner.hpp"

#ifndef KESTREL_BENCH_MODELS_DIR
#define KESTREL_BENCH_MODELS_DIR "models"
#endif
#ifndef KESTREL_BENCH_CXX_FLAGS
#define KESTREL_BENCH_CXX_FLAGS "?"
#endif
#ifndef KESTREL_BENCH_MUJOCO_PYPI_LIB
#define KESTREL_BENCH_MUJOCO_PYPI_LIB ""
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

// One simulator's figures for one robot.
struct SimFigures {
  double ns = 1e300;  // best rep, ns per physics step
  // Means over the last 0.2 s of the settling:
  double height = 0;    // base z (m)
  double fn = 0;        // contact normal forces summed (N)
  double iters = 0;     // Kestrel: PGS sweeps (cd.iterations_used); MuJoCo: d->solver_iter
  int iters_max = 0;
  double contacts = 0;  // Kestrel: contact points from collide_halfspace; MuJoCo: d->ncon
  double rows = 0;      // constraint rows (Kestrel: cd.num_rows; MuJoCo: d->nefc)
  double settle_drift = 0;  // base x-y distance moved during the settling (m)
  double rep_drift = 0;     // ... during the first timed rep (m)
  double rep_dz = 0;        // base height change during the first timed rep (m)
};

// MuJoCo's sides, each a build and solver settings: the file's own (MuJoCo's defaults: pyramidal
// cone, impratio 1) and those of the MuJoCo Menagerie's Go2 (elliptic cone, impratio 100:
// "increased impratio to reduce slippage"; Kestrel's cone is isotropic, as an elliptic one), for
// Debian's libmujoco and, where its library loads, the PyPI wheel's (mujoco_runner.hpp).
struct MujocoConfig {
  std::string name;  // the CSV's mujoco_config
  bool pypi;
  bool menagerie_cone;
};
std::vector<MujocoConfig> g_configs;
std::string g_pypi_lib;

struct Result {
  std::string robot;
  double mass_kg = 0;
  int kestrel_shapes = 0;
  SimFigures k;
  double batch_ns = 1e300;  // Kestrel's batched step: best rep, ns per robot per physics step
  int batch_lanes = 0;
  bool batch_same_bits = false;  // its robots end each rep with the scalar step's state, bit for bit
  std::vector<SimFigures> mj;
  std::vector<std::string> mj_desc, mj_version;
  bool ok = true;
  std::string problem;
};

// ---------------------------------------------------------------- Kestrel's side
struct KestrelSide {
  ks::ArticulatedRobot robot;
  dy::MultibodyData<ks::kMaxRobotBodies> data;
  dy::ConstraintData<ks::kMaxRobotBodies, kMaxContacts> cd;
  dy::WarmStart<96> warm;  // the previous step's impulses, as the simulator keeps per robot
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

  // The joint PD (tau, and the gains taken implicitly), forward_kinematics (unless poses_ready:
  // cd.X_world already at q) and the contacts into `contacts`: everything of a physics step before
  // the constrained step. Returns the count.
  int prepare(dy::ContactPoint* contacts, bool poses_ready = false) {
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
    if (!poses_ready) dy::forward_kinematics(m, data, q.data(), cd.X_world);
    int n = dy::collide_halfspace(shapes.data(), static_cast<int>(shapes.size()), cd.X_world, ground, real(0.01), contacts,
                                  kMaxContacts);
    if (n > kMaxContacts) {
      overflow = true;
      n = kMaxContacts;
    }
    contacts_last = n;
    return n;
  }

  kestrel::Status step() {
    const auto& m = robot.multibody;
    dy::ContactPoint contacts[kMaxContacts];
    const int n = prepare(contacts);
    dy::ConstraintParams params;
    params.poses_current = true;  // forward_kinematics just above, as the simulator's physics step
    return dy::step_constrained(m, data, cd, q.data(), qd.data(), tau.data(), static_cast<real>(kDt), contacts, n, params,
                                kp_step.data(), kd_step.data(), &warm);
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

// ---------------------------------------------------------------- Kestrel's batched step
// The simulator's batched constrained step (sim/src/backends/articulated_batch.hpp): L robots
// (the kernel copy's lanes) from the same settled state, each prepared as KestrelSide::step
// does, then one batched step for all of them. Its time is per robot: a batch's time / L.
struct KestrelBatchSide {
  std::vector<std::unique_ptr<KestrelSide>> robots;
  std::vector<std::vector<dy::ContactPoint>> contacts;
  std::vector<std::vector<kestrel::Vec3>> forces;
  ks::AlignedScratch scratch;
  void* mem = nullptr;

  void init(const KestrelSide& k, int lanes) {
    robots.clear();
    for (int l = 0; l < lanes; ++l) robots.push_back(std::make_unique<KestrelSide>(k));
    contacts.assign(static_cast<std::size_t>(lanes), std::vector<dy::ContactPoint>(kMaxContacts));
    forces.assign(static_cast<std::size_t>(lanes), std::vector<kestrel::Vec3>(kMaxContacts));
    scratch.resize(ks::legged_batch::scratch_bytes());
    mem = scratch.data();
  }
  // True when every robot was stepped.
  bool step() {
    const int L = static_cast<int>(robots.size());
    ks::legged_batch::Lane lanes[ks::legged_batch::kMaxLanes];
    // The kinematics in the lanes (the simulator's order: they pose the collisions, then the step
    // reuses them).
    const real* qs[ks::legged_batch::kMaxLanes] = {};
    dy::Transform* Xs[ks::legged_batch::kMaxLanes] = {};
    for (int l = 0; l < L; ++l) {
      qs[l] = robots[static_cast<std::size_t>(l)]->q.data();
      Xs[l] = robots[static_cast<std::size_t>(l)]->cd.X_world;
    }
    const auto& m = robots[0]->robot.multibody;
    ks::legged_batch::kinematics(m, qs, L, Xs, mem);
    for (int l = 0; l < L; ++l) {
      KestrelSide& r = *robots[static_cast<std::size_t>(l)];
      ks::legged_batch::Lane& ln = lanes[l];
      ln.num_contacts = r.prepare(contacts[static_cast<std::size_t>(l)].data(), true);
      ln.q = r.q.data();
      ln.qd = r.qd.data();
      ln.tau = r.tau.data();
      ln.kp = r.kp_step.data();
      ln.kd = r.kd_step.data();
      ln.contacts = contacts[static_cast<std::size_t>(l)].data();
      ln.warm = &r.warm;
      ln.contact_force_w = forces[static_cast<std::size_t>(l)].data();
    }
    dy::ConstraintParams params;
    params.poses_current = true;
    const unsigned done = ks::legged_batch::step(m, params, static_cast<real>(kDt), lanes, L, mem);
    return done == (1u << L) - 1u;
  }
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

// Physics steps of every side (settling and timed reps) on one progress line (issue 15; a terminal
// only, off with --quiet): the default run is tens of seconds of silent loops. Updated between
// loops, never inside a timed one.
kestrel::sim::ProgressLine* g_progress = nullptr;
double g_steps_done = 0;
void progress_add(double n) {
  g_steps_done += n;
  if (g_progress != nullptr) g_progress->update(g_steps_done);
}

bool run_case(const Case& c, const std::string& models, long steps, int reps, Result& out) {
  const std::string path = models + "/" + c.file;
  out.robot = c.name;
  std::string err;
  const auto ks_side = std::make_unique<KestrelSide>();  // large scratch (ConstraintData): on the heap
  const int nm = static_cast<int>(g_configs.size());
  std::vector<std::unique_ptr<kestrel_bench::MujocoRunner>> mjs;
  out.mj.assign(g_configs.size(), SimFigures());
  out.mj_desc.assign(g_configs.size(), std::string());
  out.mj_version.assign(g_configs.size(), std::string());
  bool loaded = ks_side->init(path, c.kp, c.kd, err);
  for (int i = 0; i < nm && loaded; ++i) {
    const MujocoConfig& mc = g_configs[static_cast<std::size_t>(i)];
    mjs.push_back(mc.pypi ? kestrel_bench::make_mujoco_pypi(g_pypi_lib, err) : kestrel_bench::make_mujoco_debian());
    loaded = mjs.back() != nullptr && mjs.back()->init(path, mc.menagerie_cone, c.kp, c.kd, kDt, err);
  }
  if (!loaded) {
    std::fprintf(stderr, "kestrel_bench_legged_step: %s\n", err.c_str());
    return false;
  }
  KestrelSide& k = *ks_side;
  out.mass_kg = static_cast<double>(k.robot.total_mass_kg);
  out.kestrel_shapes = static_cast<int>(k.shapes.size());
  for (std::size_t i = 0; i < mjs.size(); ++i) {
    out.mj_desc[i] = mjs[i]->describe();
    out.mj_version[i] = mjs[i]->version();
    if (std::fabs(mjs[i]->total_mass() - out.mass_kg) > 1e-3 * out.mass_kg) {
      out.ok = false;
      out.problem += " masses differ (Kestrel " + std::to_string(out.mass_kg) + ", MuJoCo " +
                     std::to_string(mjs[i]->total_mass()) + ");";
    }
  }

  // Settle 2 s on every side.
  const int settle = static_cast<int>(std::lround(kSettleS / kDt));
  const double kx0 = k.x(), ky0 = k.y();
  for (int s = 0; s < settle; ++s) {
    const kestrel::Status st = k.step();
    if (st != kestrel::Status::ok) {
      out.ok = false;
      out.problem += " Kestrel's step " + std::to_string(s) + " refused (status " + std::to_string(static_cast<int>(st)) + ");";
      return true;
    }
    if (s >= settle - kAverageSteps) {
      SimFigures& f = out.k;
      f.height += k.z() / kAverageSteps;
      f.fn += k.normal_force() / kAverageSteps;
      f.iters += static_cast<double>(k.cd.iterations_used) / kAverageSteps;
      f.iters_max = std::max(f.iters_max, k.cd.iterations_used);
      f.contacts += static_cast<double>(k.contacts_last) / kAverageSteps;
      f.rows += static_cast<double>(k.cd.num_rows) / kAverageSteps;
    }
  }
  out.k.settle_drift = std::hypot(k.x() - kx0, k.y() - ky0);
  progress_add(settle);
  for (std::size_t i = 0; i < mjs.size(); ++i) {
    kestrel_bench::MujocoRunner& mj = *mjs[i];
    SimFigures& f = out.mj[i];
    const double x0 = mj.x(), y0 = mj.y();
    for (int s = 0; s < settle; ++s) {
      mj.step();
      if (s >= settle - kAverageSteps) {
        f.height += mj.z() / kAverageSteps;
        f.fn += mj.normal_force() / kAverageSteps;
        f.iters += static_cast<double>(mj.solver_iterations()) / kAverageSteps;
        f.iters_max = std::max(f.iters_max, mj.solver_iterations());
        f.contacts += static_cast<double>(mj.contacts()) / kAverageSteps;
        f.rows += static_cast<double>(mj.rows()) / kAverageSteps;
      }
    }
    f.settle_drift = std::hypot(mj.x() - x0, mj.y() - y0);
    progress_add(settle);
  }
  if (k.overflow) {
    out.ok = false;
    out.problem += " more than " + std::to_string(kMaxContacts) + " Kestrel contacts;";
  }

  // The timed reps, from the settled state each time, the sides interleaved.
  const std::vector<real> q_settled = k.q, qd_settled = k.qd;
  std::vector<double> mj_x0, mj_y0, mj_z0;
  for (const auto& mj : mjs) {
    mj->save();
    mj_x0.push_back(mj->x());
    mj_y0.push_back(mj->y());
    mj_z0.push_back(mj->z());
  }
  bool k_ok = true;
  const KestrelSide k_settled = k;
  KestrelBatchSide kb;
  const int L = ks::legged_batch::eligible(k.robot.multibody) ? ks::legged_batch::lanes() : 0;
  out.batch_lanes = L;
  out.batch_same_bits = L > 0;
  for (int r = 0; r < reps; ++r) {
    k = k_settled;
    const auto t0 = Clock::now();
    for (long i = 0; i < steps; ++i) k_ok = (k.step() == kestrel::Status::ok) && k_ok;
    const double kns = std::chrono::duration<double, std::nano>(Clock::now() - t0).count() / static_cast<double>(steps);
    out.k.ns = std::min(out.k.ns, kns);
    progress_add(static_cast<double>(steps));
    if (L > 0) {
      kb.init(k_settled, L);
      const auto tb = Clock::now();
      for (long i = 0; i < steps; ++i) k_ok = kb.step() && k_ok;
      const double bns = std::chrono::duration<double, std::nano>(Clock::now() - tb).count() / static_cast<double>(steps * L);
      out.batch_ns = std::min(out.batch_ns, bns);
      for (const auto& rb : kb.robots)
        out.batch_same_bits = out.batch_same_bits && std::memcmp(rb->q.data(), k.q.data(), k.q.size() * sizeof(real)) == 0 &&
                              std::memcmp(rb->qd.data(), k.qd.data(), k.qd.size() * sizeof(real)) == 0;
    }
    g_sink = g_sink + k.z();
    if (r == 0) {
      out.k.rep_drift = std::hypot(k.x() - static_cast<double>(q_settled[0]), k.y() - static_cast<double>(q_settled[1]));
      out.k.rep_dz = k.z() - static_cast<double>(q_settled[2]);
    }
    for (std::size_t c2 = 0; c2 < mjs.size(); ++c2) {
      kestrel_bench::MujocoRunner& mj = *mjs[c2];
      mj.restore();
      const auto t1 = Clock::now();
      for (long i = 0; i < steps; ++i) mj.step();
      const double mns = std::chrono::duration<double, std::nano>(Clock::now() - t1).count() / static_cast<double>(steps);
      out.mj[c2].ns = std::min(out.mj[c2].ns, mns);
      progress_add(static_cast<double>(steps));
      g_sink = g_sink + mj.z();
      if (r == 0) {
        out.mj[c2].rep_drift = std::hypot(mj.x() - mj_x0[c2], mj.y() - mj_y0[c2]);
        out.mj[c2].rep_dz = mj.z() - mj_z0[c2];
      }
    }
  }
  if (!k_ok) {
    out.ok = false;
    out.problem += " a timed Kestrel step refused (or a batched robot left to the scalar step);";
  }
  if (L > 0 && !out.batch_same_bits) {
    out.ok = false;
    out.problem += " the batched step's robots differ from the scalar step's;";
  }

  // Do both stand? Heights against Debian's MuJoCo with the Menagerie's cone (with the file's
  // pyramidal cone at impratio 1, MuJoCo's soft friction lets the feet creep apart: reported, not
  // checked; the PyPI build's heights are reported beside it).
  const double mg = out.mass_kg * kG;
  if (!(std::fabs(out.k.height - out.mj[1].height) < 0.03)) {
    out.ok = false;
    out.problem += " base heights differ by more than 3 cm from MuJoCo's (elliptic cone);";
  }
  if (!(std::fabs(out.k.fn - mg) < 0.1 * mg)) {
    out.ok = false;
    out.problem += " Kestrel's normal force is not within 10% of m g;";
  }
  for (std::size_t i = 0; i < out.mj.size(); ++i)
    if (!(std::fabs(out.mj[i].fn - mg) < 0.1 * mg)) {
      out.ok = false;
      out.problem += " MuJoCo's normal force (" + g_configs[i].name + ") is not within 10% of m g;";
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
  // The PyPI wheel's libmujoco.so (the one the build found in .venv), "none" to leave it out.
  std::string mujoco_pypi = KESTREL_BENCH_MUJOCO_PYPI_LIB;
  bool quiet = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quiet")) quiet = true;
    else if (!std::strcmp(argv[i], "--steps") && i + 1 < argc) steps = std::atol(argv[++i]);
    else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--csv") && i + 1 < argc) csv = argv[++i];
    else if (!std::strcmp(argv[i], "--models") && i + 1 < argc) models = argv[++i];
    else if (!std::strcmp(argv[i], "--machine") && i + 1 < argc) machine = argv[++i];
    else if (!std::strcmp(argv[i], "--mujoco-pypi") && i + 1 < argc) mujoco_pypi = argv[++i];
    else {
      std::fprintf(stderr,
                   "usage: kestrel_bench_legged_step [--steps N] [--reps R] [--csv PATH] [--models DIR] [--machine LABEL] "
                   "[--mujoco-pypi LIB|none] [--quiet]\n");
      return 2;
    }
  }
  if (steps < 1 || reps < 1) {
    std::fprintf(stderr, "kestrel_bench_legged_step: --steps and --reps must be positive\n");
    return 2;
  }
  g_configs = {{"file_defaults", false, false}, {"elliptic_impratio100", false, true}};
  if (!mujoco_pypi.empty() && mujoco_pypi != "none") {
    std::string err;
    if (kestrel_bench::make_mujoco_pypi(mujoco_pypi, err) == nullptr) {
      std::fprintf(stderr, "kestrel_bench_legged_step: --mujoco-pypi %s: %s\n", mujoco_pypi.c_str(), err.c_str());
      return 1;
    }
    g_pypi_lib = mujoco_pypi;
    g_configs.push_back({"pypi_file_defaults", true, false});
    g_configs.push_back({"pypi_elliptic_impratio100", true, true});
  }
  const int nm = static_cast<int>(g_configs.size());
  const Case cases[] = {{"go2", "go2/go2.xml", 20, 0.5}, {"anymal_c", "anymal_c/anymal_c.xml", 80, 2}};
  std::vector<Result> results;
  const double settle_steps = std::round(kSettleS / kDt);
  kestrel::sim::ProgressLine progress(stderr, kestrel::sim::ProgressLine::enabled_for(quiet),
                                      static_cast<double>(sizeof cases / sizeof cases[0]) * (1 + nm) * (settle_steps + static_cast<double>(reps) * static_cast<double>(steps)),
                                      "steps");
  g_progress = &progress;
  for (const Case& c : cases) {
    Result r;
    if (!run_case(c, models, steps, reps, r)) return 1;
    results.push_back(r);
  }
  progress.finish();
  g_progress = nullptr;

  std::string sides;
  for (std::size_t i = 0; i < g_configs.size(); ++i)
    sides += (i > 0 ? " / MuJoCo " : "MuJoCo ") + results[0].mj_version[i] + (g_configs[i].pypi ? " (PyPI wheel, dlopen)" : " (Debian)") +
             " in double, " + results[0].mj_desc[i] + " (" + g_configs[i].name + ")";
  char header[2400];
  std::snprintf(header, sizeof header,
                "machine %s (%s, %ld logical CPUs), one thread; compiler GCC-compatible %s, flags %s; Kestrel real = %s "
                "(the project's default build, kestrel_sim's loader), PGS defaults (ConstraintParams(), poses_current: the step reuses the collision's forward kinematics), contact margin "
                "0.01 m; %s; dt %g s, settle %g s, "
                "best of %d reps x %ld steps, interleaved; sanity figures: means over the last 0.2 s of the settling",
                machine.c_str(), cpu_model().c_str(), sysconf(_SC_NPROCESSORS_ONLN), __VERSION__, KESTREL_BENCH_CXX_FLAGS,
                sizeof(real) == 8 ? "double" : "float", sides.c_str(), kDt, kSettleS, reps, steps);
  std::printf("legged physics step on flat ground, PD to home (Go2 kp 20 kd 0.5, ANYmal C kp 80 kd 2)\n# %s\n", header);
  FILE* f = csv != nullptr ? std::fopen(csv, "w") : nullptr;
  if (csv != nullptr && f == nullptr) {
    std::fprintf(stderr, "kestrel_bench_legged_step: cannot write --csv %s\n", csv);
    return 1;
  }
  if (f != nullptr)
    std::fprintf(f,
                 "# %s\nrobot,mujoco_config,mass_kg,m_g_n,kestrel_ns_per_step,mujoco_ns_per_step,mujoco_over_kestrel,"
                 "kestrel_base_z_m,mujoco_base_z_m,kestrel_normal_force_n,mujoco_normal_force_n,kestrel_pgs_sweeps_mean,"
                 "kestrel_pgs_sweeps_max,mujoco_solver_iter_mean,kestrel_contacts,mujoco_ncon,kestrel_rows,mujoco_nefc,"
                 "kestrel_shapes,kestrel_settle_drift_xy_m,mujoco_settle_drift_xy_m,kestrel_rep_drift_xy_m,"
                 "mujoco_rep_drift_xy_m,kestrel_rep_dz_m,mujoco_rep_dz_m,stands,kestrel_batch_lanes,"
                 "kestrel_batch_ns_per_step,mujoco_over_kestrel_batch,kestrel_batch_same_bits,mujoco_version\n",
                 header);
  bool all_ok = true;
  for (const Result& r : results) {
    const SimFigures& k = r.k;
    std::printf("\n%s: %.3f kg, m g %.2f N; Kestrel %d collision shapes; first timed rep %.1f s\n", r.robot.c_str(), r.mass_kg,
                r.mass_kg * kG, r.kestrel_shapes, static_cast<double>(steps) * kDt);
    std::printf("  %-42s %11s %7s %8s %8s %11s %7s %7s %10s %14s %10s\n", "side", "ns/step", "MuJoCo/K", "base z", "Fn N",
                "iters mean/max", "contacts", "rows", "settle mm", "rep drift mm", "rep dz mm");
    auto line = [&](const char* name, const SimFigures& s, double ratio) {
      std::printf("  %-42s %11.1f %7.2f %8.4f %8.2f %7.1f/%-6d %7.1f %7.1f %10.2f %14.2f %+10.2f\n", name, s.ns, ratio, s.height,
                  s.fn, s.iters, s.iters_max, s.contacts, s.rows, 1e3 * s.settle_drift, 1e3 * s.rep_drift, 1e3 * s.rep_dz);
    };
    line("kestrel (float)", k, 1.0);
    if (r.batch_lanes > 0)
      std::printf("  %-42s %11.1f  (per robot, %d robots per step; the scalar step's bits: %s)\n", "kestrel batched (float)",
                  r.batch_ns, r.batch_lanes, r.batch_same_bits ? "yes" : "NO");
    for (std::size_t i = 0; i < r.mj.size(); ++i) {
      const SimFigures& m = r.mj[i];
      const std::string name = "mujoco " + r.mj_version[i] + " " + g_configs[i].name;
      line(name.c_str(), m, m.ns / k.ns);
      if (r.batch_lanes > 0) std::printf("  %-42s %11s %7.2f\n", "  MuJoCo / Kestrel batched", "", m.ns / r.batch_ns);
      if (f != nullptr)
        std::fprintf(f,
                     "%s,%s,%.3f,%.3f,%.1f,%.1f,%.3f,%.5f,%.5f,%.3f,%.3f,%.2f,%d,%.2f,%.2f,%.2f,%.2f,%.2f,%d,%.3g,%.3g,%.3g,%.3g,"
                     "%.3g,%.3g,%d,%d,%.1f,%.3f,%d,%s\n",
                     r.robot.c_str(), g_configs[i].name.c_str(), r.mass_kg, r.mass_kg * kG, k.ns, m.ns, m.ns / k.ns, k.height,
                     m.height, k.fn, m.fn, k.iters, k.iters_max, m.iters, k.contacts, m.contacts, k.rows, m.rows,
                     r.kestrel_shapes, k.settle_drift, m.settle_drift, k.rep_drift, m.rep_drift, k.rep_dz, m.rep_dz,
                     r.ok ? 1 : 0, r.batch_lanes, r.batch_lanes > 0 ? r.batch_ns : 0.0,
                     r.batch_lanes > 0 ? m.ns / r.batch_ns : 0.0, r.batch_same_bits ? 1 : 0, r.mj_version[i].c_str());
    }
    if (!r.ok) {
      std::fprintf(stderr, "kestrel_bench_legged_step: %s does not stand on every side:%s\n", r.robot.c_str(), r.problem.c_str());
      all_ok = false;
    }
  }
  if (f != nullptr) std::fclose(f);
  return all_ok ? 0 : 1;
}
