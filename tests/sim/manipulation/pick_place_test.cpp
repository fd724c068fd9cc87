// The SO-101 pick-and-place scene (sim/pick_place.hpp): the cube rests on the table without
// creeping; LeIsaac's cube_in_box against placements set by hand; randomize_object_uniform within
// its range and reproducible per seed and environment; the scripted pick and place lifts the cube
// to the commanded height, carries it without slipping and leaves it in the box, by friction
// alone (with a gripper too weak to squeeze, the same script leaves the cube behind); no heap in
// a step; several worlds stepped at once (step_batch) get the bits of their own steps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "heap_counter.hpp"
#include "kestrel/sim/aligned_scratch.hpp"
#include "kestrel/sim/batch_step.hpp"
#include "kestrel/sim/pick_place.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {

void init_or_fail(PickPlaceWorld& w, const PickPlaceConfig& c, std::uint64_t seed = 1, std::uint32_t env = 0) {
  std::string err;
  ASSERT_TRUE(w.init(c, seed, env, err)) << err;
}

struct EpisodeLog {
  bool success = false;
  real max_cube_z = 0;
  real lifted_z = 0;        // the cube's centre height when the lift ends
  real carried_slip_m = 0;  // largest change of the cube's offset from the tool while carried
  int steps = 0;
};

EpisodeLog run_script(PickPlaceWorld& w) {
  ScriptedPickPlace s(w);
  EpisodeLog log;
  real a[PickPlaceWorld::kJoints];
  bool have_offset = false;
  Vec3 offset = Vec3::Zero();
  while (!s.done() && log.steps < 400) {
    s.act(a);
    EXPECT_EQ(w.step(a), Status::ok);
    ++log.steps;
    log.max_cube_z = std::max(log.max_cube_z, w.state().cube_pos_w[2]);
    if (s.phase() == 3) log.lifted_z = w.state().cube_pos_w[2];
    if (s.phase() == 4) {  // carrying
      const Vec3 off = w.state().cube_pos_w - w.state().tcp_pos_w;
      if (!have_offset) offset = off, have_offset = true;
      log.carried_slip_m = std::max(log.carried_slip_m, (off - offset).norm());
    }
  }
  for (int k = 0; k < 25; ++k) {  // half a second to settle
    s.act(a);
    EXPECT_EQ(w.step(a), Status::ok);
  }
  log.success = w.cube_in_box();
  return log;
}

}  // namespace

TEST(PickPlace, CubeRestsOnTheTableWithoutCreeping) {
  PickPlaceWorld w;
  init_or_fail(w, PickPlaceConfig());
  const Vec3 start = w.state().cube_pos_w;
  EXPECT_NEAR(start[2], w.config().cube_half_m, 1e-6);
  for (int k = 0; k < 100; ++k) ASSERT_EQ(w.step(w.home()), Status::ok);  // 2 s at home
  EXPECT_LT((w.state().cube_pos_w - start).norm(), 1e-4);
  for (int a = 0; a < 6; ++a) EXPECT_LT(std::fabs(w.joint_vel()[6 + a]), 1e-3);  // the cube at rest
  // The arm holds its home pose under gravity (stiff servos: within a few mrad).
  for (int j = 0; j < 5; ++j) EXPECT_NEAR(w.joint_pos()[j], w.home()[j], 5e-3);
}

TEST(PickPlace, CubeInBoxAgainstPlacementsSetByHand) {
  PickPlaceConfig c;
  c.randomize_xy_m = 0;
  PickPlaceWorld w;
  init_or_fail(w, c);
  const Vec3 box = w.state().box_pos_w;
  EXPECT_NEAR(box[0], c.box_pos_w[0], 1e-6);
  EXPECT_NEAR(box[1], c.box_pos_w[1], 1e-6);
  const Vec4 level(0, 0, 0, 1);
  w.set_cube_pose(box + Vec3(0, 0, 0.02_r), level);
  EXPECT_TRUE(w.cube_in_box());
  w.set_cube_pose(box + Vec3(0.049_r, -0.049_r, 0.02_r), level);
  EXPECT_TRUE(w.cube_in_box());
  w.set_cube_pose(box + Vec3(0.051_r, 0, 0.02_r), level);  // x beyond 0.05
  EXPECT_FALSE(w.cube_in_box());
  w.set_cube_pose(box + Vec3(0, -0.051_r, 0.02_r), level);  // y beyond 0.05
  EXPECT_FALSE(w.cube_in_box());
  w.set_cube_pose(box + Vec3(0, 0, 0.101_r), level);  // above the height threshold
  EXPECT_FALSE(w.cube_in_box());
  w.reset();
  EXPECT_FALSE(w.cube_in_box());  // the cube starts on the table beside the box
}

TEST(PickPlace, ResetsRandomiseObjectsUniformlyAndReproducibly) {
  PickPlaceConfig c;
  PickPlaceWorld w, same, other;
  init_or_fail(w, c, 7, 3);
  init_or_fail(same, c, 7, 3);
  init_or_fail(other, c, 7, 4);
  real lo[4] = {1, 1, 1, 1}, hi[4] = {-1, -1, -1, -1};
  bool differs = false;
  for (int k = 0; k < 200; ++k) {
    w.reset();
    same.reset();
    other.reset();
    EXPECT_EQ(w.state_hash(), same.state_hash());
    differs = differs || w.state_hash() != other.state_hash();
    const real d[4] = {w.state().cube_pos_w[0] - c.cube_pos_w[0], w.state().cube_pos_w[1] - c.cube_pos_w[1],
                       w.state().box_pos_w[0] - c.box_pos_w[0], w.state().box_pos_w[1] - c.box_pos_w[1]};
    for (int i = 0; i < 4; ++i) {
      EXPECT_LE(std::fabs(d[i]), c.randomize_xy_m + 1e-6);
      lo[i] = std::min(lo[i], d[i]);
      hi[i] = std::max(hi[i], d[i]);
    }
    EXPECT_NEAR(w.state().cube_pos_w[2], c.cube_half_m, 1e-6);
  }
  EXPECT_TRUE(differs);
  for (int i = 0; i < 4; ++i) {  // 200 uniform draws cover most of +-5 cm
    EXPECT_LT(lo[i], -0.04);
    EXPECT_GT(hi[i], 0.04);
  }
}

TEST(PickPlace, ScriptedPickAndPlaceByFrictionAlone) {
  PickPlaceWorld w;
  init_or_fail(w, PickPlaceConfig(), 11);
  ScriptedPickPlace probe(w);
  int successes = 0;
  const int episodes = 20;
  for (int e = 0; e < episodes; ++e) {
    w.reset();
    const EpisodeLog log = run_script(w);
    successes += log.success ? 1 : 0;
    // Lifted to the commanded carry height (the cube's centre), within 5 mm.
    EXPECT_NEAR(log.lifted_z, probe.lift_height_m, 5e-3) << "episode " << e;
    EXPECT_LT(log.carried_slip_m, 2e-3) << "episode " << e;  // no slip while carried
    // At rest in the box: no jitter.
    const Vec3 rest = w.state().cube_pos_w;
    real a[PickPlaceWorld::kJoints];
    for (int j = 0; j < PickPlaceWorld::kJoints; ++j) a[j] = w.joint_targets()[j];
    for (int k = 0; k < 25; ++k) ASSERT_EQ(w.step(a), Status::ok);
    if (log.success) {
      EXPECT_LT((w.state().cube_pos_w - rest).norm(), 2e-4) << "episode " << e;
    }
  }
  EXPECT_EQ(successes, episodes);
}

TEST(PickPlace, AGripperTooWeakToSqueezeLeavesTheCube) {
  PickPlaceConfig c;
  c.gripper_kp_Nm_rad = 0.02_r;  // 1000x softer: a few mN at the pads against 0.11 N of weight
  PickPlaceWorld w;
  init_or_fail(w, c, 11);
  const EpisodeLog log = run_script(w);
  EXPECT_FALSE(log.success);
  EXPECT_LT(log.max_cube_z, c.cube_half_m + 0.01_r);
}

TEST(PickPlace, AStepNeitherAllocatesNorAcceptsNonFiniteTargets) {
  PickPlaceWorld w;
  init_or_fail(w, PickPlaceConfig());
  real a[PickPlaceWorld::kJoints];
  for (int j = 0; j < PickPlaceWorld::kJoints; ++j) a[j] = w.home()[j];
  a[1] += 0.2_r;
  {
    kestrel::test::HeapCounter heap;
    for (int k = 0; k < 20; ++k) ASSERT_EQ(w.step(a), Status::ok);
    w.reset();
    EXPECT_EQ(heap.allocations(), 0u);
  }
  const real before = w.joint_targets()[2];
  a[2] = NAN;
  ASSERT_EQ(w.step(a), Status::ok);
  EXPECT_EQ(w.joint_targets()[2], before);  // a non-finite target holds the previous one
  for (int j = 0; j < PickPlaceWorld::kJoints; ++j) EXPECT_TRUE(std::isfinite(w.joint_pos()[j])) << j;
  EXPECT_TRUE(all_finite(w.state().cube_pos_w));
  // A bad configuration is refused with the field's name.
  PickPlaceConfig bad;
  bad.cube_half_m = -1;
  PickPlaceWorld w2;
  std::string err;
  EXPECT_FALSE(w2.init(bad, 1, 0, err));
  EXPECT_NE(err.find("cube_half_m"), std::string::npos) << err;
  bad = PickPlaceConfig();
  bad.robot_file = "/nonexistent/so101.xml";
  EXPECT_FALSE(w2.init(bad, 1, 0, err));
  EXPECT_NE(err.find("/nonexistent/so101.xml"), std::string::npos) << err;
}

// step_batch (one world per SIMD lane of the batched articulated step) gives every world the bits
// its own step() gives it: worlds in different phases of the script, some pushed off it by noise
// (into the table, the box, the cube), a NaN target, fewer worlds than lanes, on every kernel copy
// this CPU runs; and no heap inside it.
TEST(PickPlace, StepBatchGivesEveryWorldItsOwnStepsBits) {
  PickPlaceWorld probe;
  init_or_fail(probe, PickPlaceConfig());
  if (probe.batch_lanes() == 0) GTEST_SKIP() << "double build: nothing is batched";
  AlignedScratch mem(PickPlaceWorld::batch_scratch_bytes());
  void* scratch = mem.data();
  for (batch::KernelCopy copy : {batch::KernelCopy::baseline, batch::KernelCopy::avx2, batch::KernelCopy::avx512}) {
    if (!batch::use_kernel(copy)) continue;
    SCOPED_TRACE(batch::kernel_name());
    const int L = probe.batch_lanes();
    std::vector<std::unique_ptr<PickPlaceWorld>> alone, batched;
    std::vector<std::unique_ptr<ScriptedPickPlace>> script;
    for (int l = 0; l < L; ++l) {
      alone.push_back(std::make_unique<PickPlaceWorld>());
      batched.push_back(std::make_unique<PickPlaceWorld>());
      init_or_fail(*alone.back(), PickPlaceConfig(), 7, static_cast<std::uint32_t>(l));
      init_or_fail(*batched.back(), PickPlaceConfig(), 7, static_cast<std::uint32_t>(l));
      script.push_back(std::make_unique<ScriptedPickPlace>(*batched.back()));
    }
    std::mt19937 rng(11);
    std::normal_distribution<float> noise(0.f, 0.25f);
    std::vector<std::vector<real>> a(static_cast<std::size_t>(L), std::vector<real>(PickPlaceWorld::kJoints));
    std::vector<PickPlaceWorld*> ptr(static_cast<std::size_t>(L));
    std::vector<const real*> tgt(static_cast<std::size_t>(L));
    std::vector<Status> status(static_cast<std::size_t>(L));
    int batched_steps = 0, physics_steps = 0, contacts = 0;
    std::uint64_t heap_allocations = 0;
    for (int t = 0; t < 150; ++t) {
      // World 3 sits the first 20 actions out (fewer worlds than lanes in those calls).
      int n = 0;
      for (int l = 0; l < L; ++l) {
        if (l == 3 && t < 20) continue;
        std::vector<real>& al = a[static_cast<std::size_t>(l)];
        script[static_cast<std::size_t>(l)]->act(al.data());
        if (l % 3 == 1)
          for (real& v : al) v += noise(rng);
        if (l == 5 && t == 40) al[2] = NAN;
        ptr[static_cast<std::size_t>(n)] = batched[static_cast<std::size_t>(l)].get();
        tgt[static_cast<std::size_t>(n)] = al.data();
        ++n;
      }
      for (int l = 0; l < L; ++l) {
        if (l == 3 && t < 20) continue;
        ASSERT_EQ(alone[static_cast<std::size_t>(l)]->step(a[static_cast<std::size_t>(l)].data()), Status::ok);
      }
      {
        kestrel::test::HeapCounter heap;
        batched_steps += PickPlaceWorld::step_batch(ptr.data(), tgt.data(), n, status.data(), scratch);
        heap_allocations += heap.allocations();
      }
      physics_steps += n * PickPlaceConfig().decimation;
      for (int i = 0; i < n; ++i) ASSERT_EQ(status[static_cast<std::size_t>(i)], Status::ok);
      for (int l = 0; l < L; ++l) {
        const PickPlaceWorld& x = *alone[static_cast<std::size_t>(l)];
        const PickPlaceWorld& y = *batched[static_cast<std::size_t>(l)];
        ASSERT_EQ(x.state_hash(), y.state_hash()) << "world " << l << " action " << t;
        ASSERT_EQ(x.contacts(), y.contacts()) << "world " << l << " action " << t;
        ASSERT_EQ(x.grip_force_N(), y.grip_force_N()) << "world " << l << " action " << t;
        for (int j = 0; j < PickPlaceWorld::kJoints; ++j) ASSERT_EQ(x.joint_targets()[j], y.joint_targets()[j]);
        contacts += y.contacts();
      }
    }
    // One world: fewer than a third of the lanes step one at a time, with the same bits.
    {
      PickPlaceWorld* one = batched[0].get();
      const real* t0 = a[0].data();
      EXPECT_EQ(PickPlaceWorld::step_batch(&one, &t0, 1, status.data(), scratch), 0);
      ASSERT_EQ(alone[0]->step(a[0].data()), Status::ok);
      EXPECT_EQ(status[0], Status::ok);
      EXPECT_EQ(alone[0]->state_hash(), batched[0]->state_hash());
    }
    EXPECT_EQ(heap_allocations, 0u);
    // 98.8 % with 16 lanes (84 % before a call whose contacts overflow the slots retried by halves).
    EXPECT_GT(batched_steps, physics_steps * 95 / 100) << "the batch takes nearly every physics step";
    EXPECT_GT(contacts, 150 * L * 3) << "the worlds touch the table, the cube and the box";
    bool lifted = false;
    for (int l = 0; l < L; l += 3) lifted = lifted || batched[static_cast<std::size_t>(l)]->state().cube_pos_w[2] > 0.05_r;
    EXPECT_TRUE(lifted) << "a scripted world carries its cube: the grasp contacts are in the batch";
  }
  batch::use_default_kernel();
}
