// The legged robots' constrained physics step for several robots of one model at once, one robot
// per SIMD lane (4 lanes in the baseline x86-64 copy, 8 with AVX2, 16 with AVX-512: the widest the
// CPU runs, or the copy asked for, batch_step.hpp's kernel_copy_chosen()). Each lane performs the IEEE
// operations that dynamics::step_constrained performs for that robot alone, in the same order
// (Eigen's 3-term sums resolved to the order Eigen 3.4 evaluates them, a0 + (a1 + a2), as the
// multirotor's kernel does), so every lane's result has the bits of the scalar step:
// tests/sim/backends/articulated_batch_test.cpp compares them over random states, contacts,
// limits and warm starts. Internal to sim/src: its users are the articulated backend (articulated.cpp) and the SO-101
// pick-and-place worlds (manipulation/pick_place.cpp, PickPlaceWorld::step_batch).
//
// What the lanes share: the model (no per-robot inertia randomisation) and the solver's row layout.
// Robots whose contacts or active joint limits differ still share a step: the rows are the union
// over the lanes (contacts matched by key), and a row a lane does not have is a row of zeros
// there, which the solver skips as the scalar step skips a row nothing can move, and which adds
// only exact zeros to every other row's sums. Two-body contacts (self-collision; a contact on
// body and body_b, acting on their relative velocity) are batched too: their rows span both
// bodies' chains and are solved alone along the merged chain, as the scalar step solves them; a
// key must name the same two bodies in every lane that has it. What falls back to the scalar step
// (the caller's job: the returned mask leaves those lanes untouched): a key on other bodies in
// another lane, contacts without a key or out of key order, a union of more contacts than the capacity, joints
// whose motion subspace is not a unit vector (an axis other than +x, +y, +z), the double build,
// and any lane the scalar step would refuse (it is run alone, to give its status).
//
// No heap inside a step: the scratch is allocated once per worker (scratch_bytes()).
#pragma once

#include <cstddef>

#include "kestrel/dynamics/contact.hpp"
#include "kestrel/sim/articulated_robot.hpp"

namespace kestrel::sim::legged_batch {

constexpr int kMaxLanes = 16;
constexpr int kMaxContacts = 32;  // per robot per physics step (the scalar step's capacity too)
constexpr int kWarmRows = 96;     // rows of the previous step kept per robot (contact.hpp's WarmStart)
using Model = dynamics::MultibodyModel<kMaxRobotBodies>;
using Warm = dynamics::WarmStart<kWarmRows>;

/// One robot of a batch: its state (advanced in place when its lane is done), its joint torques
/// and drive gains (per velocity coordinate, as step_constrained's tau, drive_kp, drive_kd), its
/// contacts, its warm start, and where its contact forces go (num_contacts of them, world frame, N).
struct Lane {
  real* q = nullptr;
  real* qd = nullptr;
  const real* tau = nullptr;
  const real* kp = nullptr;
  const real* kd = nullptr;
  const dynamics::ContactPoint* contacts = nullptr;
  int num_contacts = 0;
  Warm* warm = nullptr;
  Vec3* contact_force_w = nullptr;
};

/// Lanes of the copy in use (4, 8 or 16; 0 in the double build, where nothing is batched).
int lanes();

/// True where the model's joints let the batch run it (see the file comment).
bool eligible(const Model& m);

/// Bytes of scratch one worker needs (aligned to 64 bytes by the caller).
std::size_t scratch_bytes();

/// forward_kinematics of count <= lanes() robots of model m at q[l] (num_q each), each robot's
/// world poses into X_world[l] (num_bodies each; the bits forward_kinematics gives), kept in the
/// scratch for a step() with p.poses_current at the same q (the simulator's collisions read them
/// first, as they read forward_kinematics's before the scalar step).
void kinematics(const Model& m, const real* const* q, int count, dynamics::Transform* const* X_world, void* scratch);

/// One constrained step of length dt_s for count <= lanes() robots of model m (eligible), with the
/// solver settings p. Returns the lanes (bit l: lanes[l]) whose step was taken, each with the bits
/// step_constrained gives that robot (its q, qd, warm start and contact forces written); the other
/// lanes are left untouched, for the scalar step. p.poses_current: the kinematics are kinematics()'s,
/// run on this scratch at the same q (else the step computes them).
unsigned step(const Model& m, const dynamics::ConstraintParams& p, real dt_s, const Lane* lanes, int count, void* scratch);

}  // namespace kestrel::sim::legged_batch
