// The batched legged step (sim/src/backends/articulated_batch.hpp) against the core's scalar
// constrained step (dynamics/contact.hpp), lane by lane and bit for bit: Go2 and ANYmal C in random
// states (joints near and past their limits, fast joints, a tilted and moving base), each lane
// with its own subset of foot and leg contacts (penetrating, touching, speculative, tilted
// normals, restitution), its own drive gains and warm start; every kernel copy this CPU runs
// (4, 8, 16 lanes) and batches of fewer robots than lanes. A lane with an input the scalar step
// refuses is left untouched and reported so.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstring>
#include <memory>
#include <vector>

#include "backends/articulated_batch.hpp"
#include "kestrel/dynamics/contact.hpp"
#include "kestrel/kernel/rng.hpp"
#include "kestrel/sim/aligned_scratch.hpp"
#include "kestrel/sim/articulated_robot.hpp"
#include "kestrel/sim/batch_step.hpp"

using namespace kestrel;
using namespace kestrel::sim;
namespace dy = kestrel::dynamics;
namespace lb = kestrel::sim::legged_batch;

namespace {

using Model = lb::Model;
using CD = dy::ConstraintData<kMaxRobotBodies, lb::kMaxContacts>;

struct Robot {
  real q[dy::max_dofs<kMaxRobotBodies>() + 1] = {};
  real qd[dy::max_dofs<kMaxRobotBodies>()] = {};
  real tau[dy::max_dofs<kMaxRobotBodies>()] = {};
  real kp[dy::max_dofs<kMaxRobotBodies>()] = {};
  real kd[dy::max_dofs<kMaxRobotBodies>()] = {};
  dy::ContactPoint contacts[lb::kMaxContacts];
  int num_contacts = 0;
  lb::Warm warm;
  Vec3 force[lb::kMaxContacts];
};

real uniform(RngStream& r, real lo, real hi) { return r.uniform(lo, hi); }

// A random state near the robot's home pose, with contacts of its own (a subset of the feet and
// some leg bodies, keys ascending as the simulator writes them).
void random_robot(const ArticulatedRobot& ar, RngStream& rng, Robot& rb, bool near_limits, bool two_body) {
  const Model& m = ar.multibody;
  for (int k = 0; k < m.num_q; ++k) rb.q[k] = ar.home_q[static_cast<std::size_t>(k)];
  rb.q[2] += uniform(rng, -0.05_r, 0.05_r);
  Vec4 qa(uniform(rng, -0.2_r, 0.2_r), uniform(rng, -0.2_r, 0.2_r), uniform(rng, -0.5_r, 0.5_r), 1);
  qa /= qa.norm();
  for (int c = 0; c < 4; ++c) rb.q[3 + c] = qa[c];
  for (int i = 0; i < m.num_bodies; ++i) {
    if (m.dof_index[i] < 0 || m.joint[i] == dy::JointType::free) continue;
    real& qi = rb.q[m.q_index[i]];
    if (near_limits && m.has_limit[i] && rng.uniform() < 0.4) {
      const bool lower = rng.uniform() < 0.5;
      qi = (lower ? m.q_min[i] : m.q_max[i]) + uniform(rng, -0.03_r, 0.03_r);
    } else {
      qi += uniform(rng, -0.3_r, 0.3_r);
    }
  }
  for (int k = 0; k < m.num_dofs; ++k) {
    rb.qd[k] = uniform(rng, -3, 3);
    rb.tau[k] = k < 6 ? 0_r : uniform(rng, -30, 30);
    const real g = rng.uniform() < 0.2 ? 0_r : uniform(rng, 10, 60);
    rb.kp[k] = k < 6 ? 0_r : g;
    rb.kd[k] = k < 6 ? 0_r : (rng.uniform() < 0.2 ? 0_r : uniform(rng, 0.2_r, 2));
  }
  dy::MultibodyData<kMaxRobotBodies> d;
  dy::Transform X[kMaxRobotBodies];
  dy::forward_kinematics(m, d, rb.q, X);
  rb.num_contacts = 0;
  for (int b = 1; b < m.num_bodies; ++b) {
    const bool foot = std::find(ar.foot_bodies.begin(), ar.foot_bodies.end(), b) != ar.foot_bodies.end();
    if (rng.uniform() > (foot ? 0.75 : 0.12)) continue;
    const int corners = foot ? 1 : (rng.uniform() < 0.5 ? 2 : 1);
    for (int c = 0; c < corners; ++c) {
      dy::ContactPoint& ct = rb.contacts[rb.num_contacts++];
      ct.body = b;
      ct.key = 8 * b + c;
      ct.point_w = X[b].r + Vec3(uniform(rng, -0.02_r, 0.02_r), uniform(rng, -0.02_r, 0.02_r), uniform(rng, -0.03_r, 0.0_r));
      Vec3 nrm(uniform(rng, -0.3_r, 0.3_r), uniform(rng, -0.3_r, 0.3_r), 1);
      if (rng.uniform() < 0.1) nrm = Vec3(1, 0, uniform(rng, -0.05_r, 0.05_r));  // a wall: the other tangent basis
      ct.normal_w = nrm / nrm.norm();
      ct.separation_m = uniform(rng, -0.012_r, 0.01_r);
      ct.friction = uniform(rng, 0.2_r, 1.25_r);
      ct.restitution = rng.uniform() < 0.5 ? 0_r : uniform(rng, 0, 0.5_r);
    }
  }
  // Two-body contacts (self-collision, as the simulator keys them: after the terrain's), each key
  // on the same pair of bodies in every lane: a leg body against another leg's or the trunk. Three
  // pairs, so that the lanes' union (up to 26 terrain keys) stays within the batch's capacity.
  if (two_body)
    for (int b = 1; b < m.num_bodies; b += 4) {
      if (rng.uniform() > 0.5 || rb.num_contacts >= lb::kMaxContacts) continue;
      const int other = (b * 5) % m.num_bodies != b ? (b * 5) % m.num_bodies : 0;
      dy::ContactPoint& ct = rb.contacts[rb.num_contacts++];
      ct.body = b;
      ct.body_b = other;
      ct.key = 1000 + 16 * b;
      ct.point_w = real(0.5) * (X[b].r + X[other].r) + Vec3(uniform(rng, -0.02_r, 0.02_r), uniform(rng, -0.02_r, 0.02_r), 0);
      Vec3 nrm(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
      ct.normal_w = nrm / nrm.norm();
      ct.separation_m = uniform(rng, -0.008_r, 0.005_r);
      ct.friction = uniform(rng, 0.2_r, 1.0_r);
      ct.restitution = 0;
    }
}

// Bits of a value (a NaN compares by its bits too).
bool same_bits(real a, real b) { return std::memcmp(&a, &b, sizeof(real)) == 0; }

// Every mismatch counts (the test checks the count at its end); the first 20 of a test are
// reported one by one.
int g_mismatches = 0;
void expect_same(const real* a, const real* b, int n, const char* what, int lane) {
  for (int k = 0; k < n; ++k)
    if (!same_bits(a[k], b[k])) {
      if (g_mismatches++ < 20)
        ADD_FAILURE() << what << "[" << k << "] lane " << lane << ": scalar " << a[k] << " batch " << b[k];
      return;
    }
}

// Steps `count` random robots once with the scalar step and once with the batch (starting from
// the same warm start, itself from one earlier scalar step), and compares everything written.
// Returns the lanes the batch took.
unsigned compare_batch(const ArticulatedRobot& ar, std::uint64_t seed, int count, bool near_limits, int bad_lane = -1,
                       bool two_body = false) {
  const Model& m = ar.multibody;
  dy::ConstraintParams p;
  p.iterations = 30;
  const real dt = 0.005_r;
  std::vector<Robot> a(static_cast<std::size_t>(count)), b;
  auto cd = std::make_unique<CD>();
  dy::MultibodyData<kMaxRobotBodies> d;
  for (int l = 0; l < count; ++l) {
    RngStream rng(seed, static_cast<std::uint32_t>(l), kPurposeUser);
    Robot& r = a[static_cast<std::size_t>(l)];
    random_robot(ar, rng, r, near_limits, two_body);
    // One scalar step first, for a warm start to begin from (then a fresh state around it).
    Robot warm_src = r;
    (void)dy::step_constrained(m, d, *cd, warm_src.q, warm_src.qd, warm_src.tau, dt, warm_src.contacts, warm_src.num_contacts, p,
                               warm_src.kp, warm_src.kd, &r.warm);
    if (l == bad_lane) r.tau[7] = std::numeric_limits<real>::quiet_NaN();
  }
  b = a;
  unsigned scalar_ok = 0;
  for (int l = 0; l < count; ++l) {
    Robot& r = a[static_cast<std::size_t>(l)];
    const Status st = dy::step_constrained(m, d, *cd, r.q, r.qd, r.tau, dt, r.contacts, r.num_contacts, p, r.kp, r.kd, &r.warm);
    if (st == Status::ok) {
      scalar_ok |= 1u << l;
      for (int c = 0; c < r.num_contacts; ++c) r.force[c] = cd->contact_force_w[c];
    }
  }
  std::vector<lb::Lane> lanes(static_cast<std::size_t>(count));
  for (int l = 0; l < count; ++l) {
    Robot& r = b[static_cast<std::size_t>(l)];
    lb::Lane& ln = lanes[static_cast<std::size_t>(l)];
    ln.q = r.q;
    ln.qd = r.qd;
    ln.tau = r.tau;
    ln.kp = r.kp;
    ln.kd = r.kd;
    ln.contacts = r.contacts;
    ln.num_contacts = r.num_contacts;
    ln.warm = &r.warm;
    ln.contact_force_w = r.force;
  }
  AlignedScratch scratch(lb::scratch_bytes());
  void* mem = scratch.data();
  const unsigned done = lb::step(m, p, dt, lanes.data(), count, mem);
  EXPECT_EQ(done, scalar_ok) << "the batch takes exactly the lanes the scalar step takes";
  for (int l = 0; l < count; ++l) {
    const Robot& x = a[static_cast<std::size_t>(l)];
    const Robot& y = b[static_cast<std::size_t>(l)];
    expect_same(x.q, y.q, m.num_q, "q", l);
    expect_same(x.qd, y.qd, m.num_dofs, "qd", l);
    EXPECT_EQ(x.warm.count, y.warm.count) << "lane " << l;
    for (int k = 0; k < std::min(x.warm.count, y.warm.count); ++k) EXPECT_EQ(x.warm.key[k], y.warm.key[k]) << "lane " << l;
    expect_same(x.warm.lambda, y.warm.lambda, std::min(x.warm.count, y.warm.count), "warm lambda", l);
    if ((done >> l) & 1u)
      for (int c = 0; c < x.num_contacts; ++c) expect_same(x.force[c].data(), y.force[c].data(), 3, "contact force", l);
  }
  return done;
}

class ArticulatedBatch : public ::testing::TestWithParam<const char*> {};

TEST_P(ArticulatedBatch, EveryLaneHasTheScalarStepsBits) {
  if (lb::lanes() == 0) GTEST_SKIP() << "double build: nothing is batched";
  ArticulatedRobot ar;
  std::string err;
  ASSERT_TRUE(load_robot_model(models_dir() + "/" + GetParam(), ar, err)) << err;
  ASSERT_TRUE(lb::eligible(ar.multibody));
  g_mismatches = 0;
  for (batch::KernelCopy c : {batch::KernelCopy::baseline, batch::KernelCopy::avx2, batch::KernelCopy::avx512}) {
    if (!batch::use_kernel(c)) continue;
    const int L = lb::lanes();
    SCOPED_TRACE(batch::kernel_name());
    int stepped = 0;
    for (std::uint64_t seed = 1; seed <= 24; ++seed) {
      const unsigned done = compare_batch(ar, 1000 * seed + static_cast<std::uint64_t>(L), L, seed % 2 == 0);
      stepped += __builtin_popcount(done);
    }
    EXPECT_GT(stepped, 24 * L * 3 / 4) << "most random lanes are stepped by the batch";
    // With two-body (self-collision) contacts among them.
    int stepped_two = 0;
    for (std::uint64_t seed = 1; seed <= 12; ++seed)
      stepped_two += __builtin_popcount(compare_batch(ar, 5000 + 1000 * seed + static_cast<std::uint64_t>(L), L, seed % 2 == 0, -1, true));
    EXPECT_GT(stepped_two, 12 * L * 3 / 4) << "lanes with two-body contacts are stepped by the batch too";
    // Fewer robots than lanes, and a lane the scalar step refuses (a NaN torque): left untouched.
    const unsigned part = compare_batch(ar, 77, L - 1, true, 1);
    EXPECT_EQ(part & 2u, 0u);
  }
  batch::use_default_kernel();
  EXPECT_EQ(g_mismatches, 0) << "values whose bits differ from the scalar step's (the first 20 are reported above)";
}

INSTANTIATE_TEST_SUITE_P(Robots, ArticulatedBatch, ::testing::Values("go2/go2.xml", "anymal_c/anymal_c.xml"));

}  // namespace
