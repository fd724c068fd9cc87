// Batched twin of the per-robot physics step (World::robot_dynamics): controller -> allocation ->
// motor model -> body wrench -> rigid-body integration for 4, 8 or 16 robots at once, one robot
// per SIMD lane (structure of arrays in registers, gathered from and scattered back to the
// world's per-robot storage).
//
// Bit-identical to the scalar path, by construction and by test (tests/sim/engine/batch_step_test.cpp):
// every lane performs the same IEEE operations in the same order as the scalar core functions
// (update_lee_position, allocate_sequential_desaturation<4>, motor_model_step, wrench_from_thrusts,
// step_rigid_body with Eigen 3.4's quaternion product / transformVector / reduction orders), and
// SIMD add, sub, mul, div and sqrt round exactly like their scalar forms (-ffp-contract=off keeps
// the compiler from fusing). The heading's sine and cosine are the core's own sin_cos (Cephes'
// polynomial, no libm) computed in every lane with its branches as selects, and so are the
// attitude update's (step_rigid_body uses the same sin_cos). The sequential desaturation of an infeasible command (airmode roll_pitch, the
// default) runs in the lanes too, its per-lane early exits as masks. Rare paths (a non-finite or
// out-of-range command, a singular force or heading, a desired rotation with trace <= 0, another
// airmode, a scheduled or dead motor, a clamped motor rate, a non-finite result) are detected per
// lane and that lane's stage is recomputed by the scalar core function itself, on the unmodified
// inputs, so the twin never has to reproduce them.
//
// Covered configuration (eligible()): lee_position controller, sequential desaturation with a
// 4-rotor allocation model, 4 motors with RK4 and the discrete approximation (thrust or rotor-speed
// state), semi-implicit Euler (any number of substeps), float build (the quaternion product order
// is Eigen's SSE path). World (sim/src/engine/step_batched.cpp) also needs one robot per environment, no
// observation noise and no random disturbance. Anything else runs the scalar path unchanged.
//
// Per-robot storage moves in and out as rows where it is laid out in rows (the state's 13 floats,
// the Lee gains' 12, the actions' and each per-motor array's first 4): one 16-byte load or store
// per lane and 4x4 transposes, not one scalar access per lane and value. Where World allows it
// (Models::ground_tail), the kernel also does the collision pass of the robots clear of the ground
// plane, which is all that pass does in an environment without obstacles.
#pragma once

#include "kestrel/allocation/airframe.hpp"
#include "kestrel/allocation/allocation_model.hpp"
#include "kestrel/allocation/motor_model.hpp"
#include "kestrel/allocation/sequential_desaturation.hpp"
#include "kestrel/controllers/controller.hpp"
#include "kestrel/kernel/rigid_body.hpp"
#include "kestrel/robots/multirotor.hpp"

namespace kestrel::sim::batch {

/// Robots stepped together, one per float lane: 4 in the baseline copy of the kernel (SSE2, which
/// every x86-64 has), 8 in the AVX2 copy, 16 in the AVX-512 copy; the copy is chosen at run time
/// (kernel_copy(), lanes()), and every copy gives the same bits.
constexpr int kMaxLanes = 16;

/// The copies of the kernel.
enum class KernelCopy : int { baseline = 0, avx2 = 1, avx512 = 2 };

/// The constant models of one robot type (all lanes share them).
struct Models {
  ControllerKind controller = ControllerKind::lee_position;
  const ControllerParams* ctrl = nullptr;
  const allocation::AllocationModel* alloc = nullptr;
  const allocation::SequentialDesaturationParams* desat = nullptr;
  const allocation::MotorModelConfig* motor = nullptr;
  const allocation::Airframe* airframe = nullptr;
  const RigidBodyModel* body = nullptr;
  real dt_s = 0;
  int substeps = 1;
  /// The ground tail (robot_step's return value): set by the caller where collide_robots' fast
  /// path is all a clear robot's collision pass does (one sphere robot per environment over the
  /// ground plane, no IMU, a crash threshold >= 0); then the kernel does that pass itself for the
  /// lanes whose Lane::ground_z says so. Radius of the robot's collision sphere.
  bool ground_tail = false;
  real ground_radius_m = 0;
};

/// The twin's view of the core chain's model (robots/multirotor.hpp) and the body model.
inline Models models_of(const robots::MultirotorModel& robot, const RigidBodyModel& body, real dt_s, int substeps) {
  Models m;
  m.controller = robot.controller;
  m.ctrl = &robot.ctrl;
  m.alloc = &robot.allocation;
  m.desat = &robot.desat;
  m.motor = &robot.motors;
  m.airframe = &robot.airframe;
  m.body = &body;
  m.dt_s = dt_s;
  m.substeps = substeps;
  return m;
}

/// Whether the twin can step this chain: the multirotor model must use the motor model and the
/// sequential desaturation (the rest is checked by eligible()).
inline bool chain_eligible(const robots::MultirotorModel& robot) {
  return robot.use_motor_model && robot.allocator == robots::AllocatorKind::sequential_desaturation;
}

/// One lane's robot: pointers into the owner's storage (read and written in place).
struct Lane {
  RigidBodyState* state = nullptr;
  ControllerState* ctrl = nullptr;
  allocation::AllocatorState* alloc = nullptr;
  allocation::MotorModelState* motors = nullptr;
  const real* action = nullptr;     // the applied action (kMaxActionDim values)
  Vec3* contact_force_w = nullptr;   // extra world force of the previous collision pass (the ground tail writes the next)
  Vec3* contact_torque_b = nullptr;  // added to the rotor torque (likewise)
  /// Models::ground_tail only: the height of the ground plane under this lane's robot (-inf
  /// without a plane; NaN where the environment has obstacles, which leaves its pass to the caller).
  real ground_z = 0;
};

/// Whether `m` is the configuration the twin covers (see the file comment).
bool eligible(const Models& m);

/// One physics step of lanes() robots (`lanes` points at that many); bit-identical to, per lane, update_controller ->
/// allocate_sequential_desaturation -> motor_model_step -> wrench_from_thrusts + contact ->
/// step_rigid_body (substeps times), as World::robot_dynamics does. Requires eligible(m).
/// Returns the lanes (bit l for lane l) whose collision pass it did too (Models::ground_tail: the
/// robot is clear of the ground, position z - radius >= ground_z; it stores what collide_robots'
/// fast path stores, a zero force and the zero torque rotated into the body frame); 0 otherwise.
unsigned robot_step(const Models& m, const Lane* lanes);

/// What the fused env-steps (robot_env_steps) read and write of each lane's environment besides
/// its robot: the setpoint the tracking error is measured to, the bounds, and that error's sum.
struct QuietEnv {
  const Vec3* setpoint_w = nullptr;
  const Vec3* lower_w = nullptr;
  const Vec3* upper_w = nullptr;
  double* tracking_error_sum_m = nullptr;
};

/// Up to max_env_steps whole env-steps (physics_steps physics steps each, one constant action) of
/// lanes() robots in one call, with the robots' state, motor thrusts and contact wrench kept in
/// registers from one step to the next and stored once at the end: what robot_step (with
/// Models::ground_tail) does physics step after physics step, and what an env-step's quiet end
/// does (the tracking error's sum; a robot out of bounds ends the run). It runs an env-step only
/// if every lane stays on every stage's fast path in all of its physics steps, stays clear of the
/// ground and in bounds; otherwise it stops before that env-step, leaving it untouched (computed
/// in registers, never stored) for the caller's step by step path. Returns the env-steps done
/// (0 .. max_env_steps); the caller counts them (episode step, statistics). Each lane's bits are
/// those of the same env-steps taken one by one. Requires eligible(m) and m.ground_tail.
int robot_env_steps(const Models& m, const Lane* lanes, const QuietEnv* envs, int physics_steps, int max_env_steps);

/// Robots per call of the copy in use: 4, 8 or 16.
int lanes();

/// The copy in use. By default the widest copy this CPU and build run (AVX-512, else AVX2, else
/// the baseline); the environment variable
/// KESTREL_BATCH_KERNEL=baseline|avx2|avx512, read once at start-up, asks for another (one the
/// CPU cannot run is ignored), for side-by-side timings.
KernelCopy kernel_copy();

/// Tests and benches: use copy `c` from now on; false (nothing changed) where this CPU or build
/// cannot run it. Not thread-safe: call it while nothing steps.
bool use_kernel(KernelCopy c);
/// Back to the copy chosen at start-up.
void use_default_kernel();
/// True where a copy was asked for (KESTREL_BATCH_KERNEL, or use_kernel() since the last
/// use_default_kernel()): the legged robots' batched step (sim/src/backends/articulated_batch.hpp)
/// then runs that copy too; otherwise it runs widest_kernel_copy(), its fastest (16 lanes on the
/// 16-core Xeon: 1.64 against 2.20 us per Go2 step with 8).
bool kernel_copy_chosen();
/// The widest copy this CPU and build run.
KernelCopy widest_kernel_copy();

/// Which copy of the kernel robot_step runs on this CPU ("AVX2 copy, 8 lanes", "SSE2 copy, 4
/// lanes", ...), for `kestrel run`'s header.
const char* kernel_name();

/// The stages alone (for the bench's per-stage split), on the same lanes; each writes what the
/// scalar stage writes, on lanes() robots. Arrays are structure-of-arrays: wrench[k][lane] with k
/// over [fx, fy, fz, tx, ty, tz] (body frame), thrust[motor][lane] (the first lanes() columns used).
void controller_stage(const Models& m, const Lane* lanes, real (&wrench)[6][kMaxLanes]);
void allocation_stage(const Models& m, const Lane* lanes, const real (&wrench)[6][kMaxLanes],
                      real (&thrust)[4][kMaxLanes]);
/// Motor model, then the body wrench A f plus the contact torque (what step_rigid_body receives).
void motor_stage(const Models& m, const Lane* lanes, const real (&thrust)[4][kMaxLanes],
                 real (&body_wrench)[6][kMaxLanes]);
void rigid_body_stage(const Models& m, const Lane* lanes, const real (&body_wrench)[6][kMaxLanes]);

}  // namespace kestrel::sim::batch
