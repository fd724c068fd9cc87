// Batched twin of the per-robot physics step; see batch_step.hpp for the contract. The kernel is in
// batch_kernel.inc (compiled twice here: baseline and AVX2, chosen at run time); each block there
// names the scalar function it mirrors; the operation order is that function's (Eigen
// expressions resolved to the order Eigen 3.4 evaluates them: Vec3 reductions a0 + (a1 + a2),
// Vec4 reductions (a0 + a2) + (a1 + a3) on SSE, cross products and Quaternion::_transformVector
// as written in Eigen's sources, the quaternion product of Eigen's SSE path).
#include "kestrel/sim/batch_step.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>

#include "kestrel/kernel/math.hpp"

#if defined(__SSE__) && !(defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE)
#include <xmmintrin.h>
#define KESTREL_BATCH_SSE 1
#endif

namespace kestrel::sim::batch {

namespace al = kestrel::allocation;

// Baseline copy of the kernel (SSE2: every x86-64; plain C++ element loops elsewhere). In the
// double build the lanes are 32-byte vectors passed between the kernel's own inline helpers
// (GCC's -Wpsabi note about their calling convention does not concern them); eligible() is false
// there, so World never uses this copy.
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"
#endif
namespace base {
#include "batch_kernel.inc"
}  // namespace base
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
#pragma GCC diagnostic pop
#endif

#if defined(KESTREL_BATCH_SSE) && defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define KESTREL_BATCH_AVX2 1
// The same kernel compiled for AVX2 machines. Every header is included above, so only the
// kernel's own functions get the target; the core functions it calls are the baseline ones.
#pragma GCC push_options
#pragma GCC target("avx2")
namespace avx2 {
#include "batch_kernel.inc"
}  // namespace avx2
#pragma GCC pop_options
#endif

namespace {
bool g_force_baseline = false;  // set by tests only, before stepping
// Chosen per call (a load and a test of libgcc's CPU model, initialised before main).
inline bool have_avx2() {
#ifdef KESTREL_BATCH_AVX2
  return !g_force_baseline && __builtin_cpu_supports("avx2");
#else
  return false;
#endif
}
}  // namespace

// The kernel moves RigidBodyState as 13 packed floats (position, quaternion x y z w, linear
// velocity, body rate): true when the types are laid out that way (Eigen's DontAlign types are).
static bool state_layout_ok() {
  const RigidBodyState s;
  const real* b = reinterpret_cast<const real*>(&s);
  return sizeof(RigidBodyState) == 13 * sizeof(real) && s.position_w.data() == b && s.orientation_wb.coeffs().data() == b + 3 &&
         s.linvel_w.data() == b + 7 && s.angvel_b.data() == b + 10;
}

bool force_baseline_kernel(bool on) {
  g_force_baseline = on;
  return have_avx2();
}

const char* kernel_name() {
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  return "none (double build: scalar robot step)";
#elif defined(KESTREL_BATCH_SSE)
  return have_avx2() ? "AVX2 copy, 4 lanes" : "SSE2 copy, 4 lanes";
#else
  return "plain C++ copy, 4 lanes";
#endif
}


bool eligible(const Models& m) {
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  (void)m;
  return false;  // the twin reproduces Eigen's float SSE quaternion product only
#else
  if (m.ctrl == nullptr || m.alloc == nullptr || m.desat == nullptr || m.motor == nullptr || m.airframe == nullptr ||
      m.body == nullptr)
    return false;
  const LeeParams& lp = m.ctrl->lee;
  const PlainMat3& j = lp.inertia_b;
  const bool diag = j(0, 1) == 0 && j(0, 2) == 0 && j(1, 0) == 0 && j(1, 2) == 0 && j(2, 0) == 0 && j(2, 1) == 0;
  const al::MotorModelConfig& mc = *m.motor;
  return state_layout_ok() && m.controller == ControllerKind::lee_position && diag && m.alloc->num_rotors == 4 &&
         m.airframe->num_rotors == 4 && mc.num_motors == 4 && mc.integrator == al::MotorIntegrator::rk4 &&
         mc.use_discrete_approximation && m.body->params.integrator == Integrator::semi_implicit_euler &&
         m.substeps >= 1 && std::isfinite(m.dt_s) && m.dt_s > 0;
#endif
}

#ifdef KESTREL_BATCH_AVX2
#define KESTREL_BATCH_DISPATCH(call) \
  do {                               \
    if (have_avx2()) {               \
      avx2::call;                    \
    } else {                         \
      base::call;                    \
    }                                \
  } while (false)
#else
#define KESTREL_BATCH_DISPATCH(call) base::call
#endif

void controller_stage(const Models& m, const Lane (&lanes)[kLanes], real (&wrench)[6][kLanes]) {
  KESTREL_BATCH_DISPATCH(controller_stage_k(m, lanes, wrench));
}
void allocation_stage(const Models& m, const Lane (&lanes)[kLanes], const real (&wrench)[6][kLanes],
                      real (&thrust)[4][kLanes]) {
  KESTREL_BATCH_DISPATCH(allocation_stage_k(m, lanes, wrench, thrust));
}
void motor_stage(const Models& m, const Lane (&lanes)[kLanes], const real (&thrust)[4][kLanes],
                 real (&body_wrench)[6][kLanes]) {
  KESTREL_BATCH_DISPATCH(motor_stage_k(m, lanes, thrust, body_wrench));
}
void rigid_body_stage(const Models& m, const Lane (&lanes)[kLanes], const real (&body_wrench)[6][kLanes]) {
  KESTREL_BATCH_DISPATCH(rigid_body_stage_k(m, lanes, body_wrench));
}
void robot_step(const Models& m, const Lane (&lanes)[kLanes]) { KESTREL_BATCH_DISPATCH(robot_step_k(m, lanes)); }

}  // namespace kestrel::sim::batch
