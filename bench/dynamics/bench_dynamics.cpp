// Host speed of the core's articulated-body dynamics (dynamics/multibody.hpp) side by side with
// Pinocchio (issue 12: "Kestrel's forward dynamics per call against Pinocchio's on the same
// quadruped model; goal <= 1.0 us for an 18-DoF floating-base quadruped in double on one core").
//
// The model is bench/dynamics/quadruped_tree.hpp's (the MCU bench's too), built once as the core's
// tree and once as a pinocchio::Model from the same numbers (each movable joint a revolute joint
// about the tree's axis at X_tree, the floating base a free flyer, inertias at each body's
// centre of mass). Both sides run in double: this translation unit is compiled with
// KESTREL_USE_DOUBLE=1 and links no Kestrel library (the dynamics are header-only templates), so
// no float build of the core is mixed in. Pinocchio comes from the `pin` wheel of the project's
// .venv (its cmeel prefix: headers and libpinocchio_default); without it (KESTREL_BENCH_PINOCCHIO
// off, the default, as its headers take about 90 s of one core to compile) only Kestrel's rows are
// printed.
//
// Per algorithm (ABA, RNEA, CRBA) and base (fixed 12 dofs, floating 18): the best of REPS runs of
// CALLS calls, ns per call, and, with Pinocchio, the largest difference of the results (they must
// agree to ~1e-12: the same model). Timings are figures, never assertions; run pinned to one core
// (bench/dynamics/run.sh writes bench/results/host/dynamics_side_by_side.csv).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "kestrel/dynamics/multibody.hpp"
#include "kestrel/sim/progress.hpp"
#include "quadruped_tree.hpp"

#if defined(KESTREL_BENCH_WITH_PINOCCHIO)
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody.hpp>
#endif

#if defined(KESTREL_BENCH_WITH_PINOCCHIO)
static_assert(sizeof(kestrel::real) == 8, "the side by side is in double: build with KESTREL_USE_DOUBLE=1");
#endif

namespace {
namespace dy = kestrel::dynamics;
using kestrel::real;
using Clock = std::chrono::steady_clock;

volatile double g_sink = 0;
// The whole program's calls on one progress line (issue 15; a terminal only, off with --quiet):
// the default run is several seconds of silent loops. Updated between reps, outside the timing.
kestrel::sim::ProgressLine* g_progress = nullptr;
double g_calls_done = 0;

template <class F>
double best_ns_per_call(F&& f, long calls, int reps) {
  double best = 1e300;
  for (int r = 0; r < reps; ++r) {
    const auto t0 = Clock::now();
    for (long i = 0; i < calls; ++i) f();
    const double ns = std::chrono::duration<double, std::nano>(Clock::now() - t0).count() / static_cast<double>(calls);
    best = std::min(best, ns);
    g_calls_done += static_cast<double>(calls);
    if (g_progress != nullptr) g_progress->update(g_calls_done);
  }
  return best;
}

#if defined(KESTREL_BENCH_WITH_PINOCCHIO)
// The same tree in Pinocchio. Kestrel's X_tree (E, r) maps parent coordinates to joint
// coordinates with the joint origin at r in the parent; Pinocchio's joint placement is the
// joint frame in the parent: SE3(E^T, r). Body inertias at their centre of mass, in the body frame.
pinocchio::Model to_pinocchio(const dy::MultibodyModel<13>& m) {
  pinocchio::Model pm;
  pm.gravity.linear(m.gravity_w);
  int joint_of[13] = {};
  for (int i = 0; i < m.num_bodies; ++i) {
    const int parent_joint = m.parent[i] < 0 ? 0 : joint_of[m.parent[i]];
    const pinocchio::SE3 place(m.X_tree[i].E.transpose(), m.X_tree[i].r);
    const pinocchio::Inertia inertia(m.body[i].mass, m.body[i].com, m.body[i].inertia_com);
    pinocchio::JointIndex j = 0;
    switch (m.joint[i]) {
      case dy::JointType::free: j = pm.addJoint(parent_joint, pinocchio::JointModelFreeFlyer(), place, "j" + std::to_string(i)); break;
      case dy::JointType::revolute:
        j = pm.addJoint(parent_joint, pinocchio::JointModelRevoluteUnaligned(m.axis[i]), place, "j" + std::to_string(i));
        break;
      case dy::JointType::prismatic:
        j = pm.addJoint(parent_joint, pinocchio::JointModelPrismaticUnaligned(m.axis[i]), place, "j" + std::to_string(i));
        break;
      case dy::JointType::fixed: break;
    }
    if (m.joint[i] == dy::JointType::fixed) {
      // A trunk welded to the world (the fixed-base tree): its inertia moves nothing.
      pm.appendBodyToJoint(parent_joint, inertia, place);
      joint_of[i] = parent_joint;
    } else {
      pm.appendBodyToJoint(j, inertia, pinocchio::SE3::Identity());
      joint_of[i] = static_cast<int>(j);
    }
  }
  return pm;
}
#endif

struct Row {
  const char* algorithm;  // aba_batch4: ns per robot of one aba_batch call over 4 lanes (the call / 4)
  const char* base;
  double kestrel_ns;
  double pinocchio_ns;  // < 0: not measured
  double max_abs_diff;
};

}  // namespace

int main(int argc, char** argv) {
  long calls = 200000;
  int reps = 7;
  const char* csv = nullptr;
  bool quiet = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quiet")) quiet = true;
    else if (!std::strcmp(argv[i], "--calls") && i + 1 < argc) calls = std::atol(argv[++i]);
    else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--csv") && i + 1 < argc) csv = argv[++i];
    else {
      std::fprintf(stderr, "usage: kestrel_bench_dynamics [--calls N] [--reps R] [--csv PATH] [--quiet]\n");
      return 2;
    }
  }
  if (calls < 1 || reps < 1) {
    std::fprintf(stderr, "kestrel_bench_dynamics: --calls and --reps must be positive\n");
    return 2;
  }
  Row rows[8];
  int n_rows = 0;
#if defined(KESTREL_BENCH_WITH_PINOCCHIO)
  const int sides = 2;
#else
  const int sides = 1;
#endif
  // 2 bases x (3 algorithms x the sides + the batched ABA), reps x calls each.
  kestrel::sim::ProgressLine progress(stderr, kestrel::sim::ProgressLine::enabled_for(quiet),
                                      (6.0 * sides + 2.0) * static_cast<double>(reps) * static_cast<double>(calls), "calls");
  g_progress = &progress;
  for (int fl = 0; fl < 2; ++fl) {
    const bool floating = fl == 1;
    static dy::MultibodyModel<13> m;
    static dy::MultibodyData<13> d;
    if (kestrel::bench_trees::make_quadruped_tree(m, floating) != kestrel::Status::ok) {
      std::fprintf(stderr, "kestrel_bench_dynamics: the quadruped tree was refused\n");
      return 1;
    }
    const int nq = m.num_q, nv = m.num_dofs;
    real q[19], qd[18], qdd[18], tau[18], out[18], H[18 * 18];
    kestrel::bench_trees::quadruped_state(floating, q, qd, qdd);
    dy::rnea(m, d, q, qd, qdd, tau);
    const char* base = floating ? "floating_18dof" : "fixed_12dof";
    const double k_aba = best_ns_per_call([&] { g_sink = g_sink + static_cast<double>(dy::aba(m, d, q, qd, tau, out)); }, calls, reps);
    real aba_out[18];
    (void)dy::aba(m, d, q, qd, tau, aba_out);
    // The 4-lane batched ABA (dynamics/lanes.hpp): four robots in four states (the joints and
    // joint velocities moved per lane), each lane checked bit for bit against the scalar aba.
    using T4 = dy::Lanes<4>;
    static dy::MultibodyBatchData<13, 4> bd;
    T4 q4[19] = {}, qd4[18] = {}, tau4[18] = {}, out4[18] = {};
    real ql[4][19], qdl[4][18];
    const int first_joint_q = floating ? 7 : 0, first_joint_v = floating ? 6 : 0;
    for (int l = 0; l < 4; ++l) {
      for (int k = 0; k < nq; ++k) ql[l][k] = q[k] + (k >= first_joint_q ? real(0.05) * static_cast<real>(l) : real(0));
      for (int k = 0; k < nv; ++k) qdl[l][k] = qd[k] + (k >= first_joint_v ? real(0.1) * static_cast<real>(l) : real(0));
      for (int k = 0; k < nq; ++k) q4[k][l] = ql[l][k];
      for (int k = 0; k < nv; ++k) {
        qd4[k][l] = qdl[l][k];
        tau4[k][l] = tau[k];
      }
    }
    const double k_aba4 = best_ns_per_call([&] { g_sink = g_sink + static_cast<double>(dy::aba_batch(m, bd, q4, qd4, tau4, out4)); },
                                           calls, reps) / 4;
    for (int l = 0; l < 4; ++l) {
      real want[18];
      if (dy::aba(m, d, ql[l], qdl[l], tau, want) != kestrel::Status::ok) {
        std::fprintf(stderr, "kestrel_bench_dynamics: aba refused lane %d's state\n", l);
        return 1;
      }
      for (int k = 0; k < nv; ++k)
        if (std::memcmp(&want[k], &out4[k][l], sizeof(real)) != 0) {
          std::fprintf(stderr, "kestrel_bench_dynamics: aba_batch lane %d coordinate %d differs from aba: %.17g vs %.17g\n", l, k,
                       static_cast<double>(out4[k][l]), static_cast<double>(want[k]));
          return 1;
        }
    }
    const double k_rnea = best_ns_per_call([&] { dy::rnea(m, d, q, qd, qdd, out); g_sink = g_sink + out[0]; }, calls, reps);
    const double k_crba = best_ns_per_call([&] { dy::crba(m, d, q, H, nv); g_sink = g_sink + H[0]; }, calls, reps);
    double p_aba = -1, p_rnea = -1, p_crba = -1, d_aba = 0, d_rnea = 0, d_crba = 0;
#if defined(KESTREL_BENCH_WITH_PINOCCHIO)
    const pinocchio::Model pm = to_pinocchio(m);
    pinocchio::Data pd(pm);
    if (pm.nq != nq || pm.nv != nv) {
      std::fprintf(stderr, "kestrel_bench_dynamics: Pinocchio's model has nq %d nv %d, Kestrel's %d %d\n", pm.nq, pm.nv, nq, nv);
      return 1;
    }
    const Eigen::Map<const Eigen::VectorXd> pq(q, nq), pv(qd, nv), pa(qdd, nv), pt(tau, nv);
    p_aba = best_ns_per_call([&] { g_sink = g_sink + pinocchio::aba(pm, pd, pq, pv, pt, pinocchio::Convention::LOCAL)[0]; }, calls, reps);
    for (int k = 0; k < nv; ++k) d_aba = std::max(d_aba, std::fabs(pd.ddq[k] - aba_out[k]));
    p_rnea = best_ns_per_call([&] { g_sink = g_sink + pinocchio::rnea(pm, pd, pq, pv, pa)[0]; }, calls, reps);
    for (int k = 0; k < nv; ++k) d_rnea = std::max(d_rnea, std::fabs(pd.tau[k] - tau[k]));
    p_crba = best_ns_per_call([&] { g_sink = g_sink + pinocchio::crba(pm, pd, pq, pinocchio::Convention::LOCAL)(0, 0); }, calls, reps);
    for (int r = 0; r < nv; ++r)
      for (int c = r; c < nv; ++c) d_crba = std::max(d_crba, std::fabs(pd.M(r, c) - H[r * nv + c]));
#endif
    (void)nq;
    rows[n_rows++] = {"aba", base, k_aba, p_aba, d_aba};
    rows[n_rows++] = {"aba_batch4", base, k_aba4, p_aba, d_aba};
    rows[n_rows++] = {"rnea", base, k_rnea, p_rnea, d_rnea};
    rows[n_rows++] = {"crba", base, k_crba, p_crba, d_crba};
  }
  progress.finish();
  g_progress = nullptr;
  const char* precision = sizeof(real) == 8 ? "double" : "float";
  std::printf("quadruped tree (bench/dynamics/quadruped_tree.hpp), %s, one thread, best of %d x %ld calls "
              "(aba_batch4: per robot of a 4-lane call, its lanes bit-identical to aba; ratio against Pinocchio's aba)\n",
              precision, reps, calls);
  std::printf("  %-5s %-15s %12s %14s %10s %14s\n", "algo", "base", "kestrel ns", "pinocchio ns", "ratio", "max |diff|");
  FILE* f = csv != nullptr ? std::fopen(csv, "w") : nullptr;
  if (csv != nullptr && f == nullptr) {
    std::fprintf(stderr, "kestrel_bench_dynamics: cannot write --csv %s\n", csv);
    return 1;
  }
  if (f != nullptr) std::fprintf(f, "precision,algorithm,base,kestrel_ns,pinocchio_ns,pinocchio_over_kestrel,max_abs_diff\n");
  for (int i = 0; i < n_rows; ++i) {
    const Row& r = rows[i];
    const double ratio = r.pinocchio_ns > 0 ? r.pinocchio_ns / r.kestrel_ns : 0;
    std::printf("  %-5s %-15s %12.1f %14.1f %10.2f %14.3g\n", r.algorithm, r.base, r.kestrel_ns, r.pinocchio_ns, ratio, r.max_abs_diff);
    if (f != nullptr)
      std::fprintf(f, "%s,%s,%s,%.1f,%.1f,%.3f,%.3g\n", precision, r.algorithm, r.base, r.kestrel_ns, r.pinocchio_ns, ratio,
                   r.max_abs_diff);
  }
  if (f != nullptr) std::fclose(f);
#if defined(KESTREL_BENCH_WITH_PINOCCHIO)
  for (int i = 0; i < n_rows; ++i)
    if (!(rows[i].max_abs_diff < 1e-9)) {
      std::fprintf(stderr, "kestrel_bench_dynamics: %s %s differs from Pinocchio by %g: not the same model\n",
                   rows[i].algorithm, rows[i].base, rows[i].max_abs_diff);
      return 1;
    }
#endif
  return 0;
}
