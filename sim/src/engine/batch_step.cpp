// Batched twin of the per-robot physics step; see batch_step.hpp for the contract. The kernel is in
// batch_kernel.inc (compiled three times here: baseline 4 lanes, AVX2 8, AVX-512 16; chosen at run
// time); each block there
// names the scalar function it mirrors; the operation order is that function's (Eigen
// expressions resolved to the order Eigen 3.4 evaluates them: Vec3 reductions a0 + (a1 + a2),
// Vec4 reductions (a0 + a2) + (a1 + a3) on SSE, cross products and Quaternion::_transformVector
// as written in Eigen's sources, the quaternion product of Eigen's SSE path).
#include "kestrel/sim/batch_step.hpp"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "kestrel/kernel/math.hpp"
#include "kestrel/sim/episode.hpp"

#if defined(__SSE__) && !(defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE)
#include <immintrin.h>
#define KESTREL_BATCH_SSE 1
#endif

namespace kestrel::sim::batch {

namespace al = kestrel::allocation;

// The kernel's three copies (4, 8, 16 lanes). In the double build eligible() is false, so World
// never uses them.
#define KESTREL_KERNEL_FILE "batch_kernel.inc"
#include "kernel_copies.inc"
#undef KESTREL_KERNEL_FILE

namespace {
// The widest copy this CPU and build run (libgcc's CPU model, which checks the OS saves the wide
// registers too).
KernelCopy widest_copy() {
#ifdef KESTREL_BATCH_WIDE
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq")) return KernelCopy::avx512;
  if (__builtin_cpu_supports("avx2")) return KernelCopy::avx2;
#endif
  return KernelCopy::baseline;
}
// The start-up choice: the widest copy the CPU runs, or the copy KESTREL_BATCH_KERNEL asks for,
// where the CPU runs it. (Until the fused env-steps it was the AVX2 copy: the lanes' gathers and
// per-lane stores, not the arithmetic, bound the step, and 16 lanes were no faster. With the
// robots in registers through a call's env-steps, the AVX-512 copy takes 1.6-1.8x the AVX2 one's
// env-steps per second on the 2-core Zen 5 and on the 16-core Xeon, and 1.25x env-step by
// env-step: bench/results/device/fused_*.)
KernelCopy default_copy() {
  const KernelCopy widest = widest_copy();
  const KernelCopy preferred = widest;
  const char* e = std::getenv("KESTREL_BATCH_KERNEL");
  if (e == nullptr) return preferred;
  KernelCopy want = preferred;
  if (std::strcmp(e, "baseline") == 0 || std::strcmp(e, "sse2") == 0) want = KernelCopy::baseline;
  if (std::strcmp(e, "avx2") == 0) want = KernelCopy::avx2;
  if (std::strcmp(e, "avx512") == 0) want = KernelCopy::avx512;
  return static_cast<int>(want) <= static_cast<int>(widest) ? want : widest;
}
const KernelCopy g_default = default_copy();
KernelCopy g_copy = g_default;  // changed by use_kernel() only (tests, benches), before stepping
const bool g_env_chosen = std::getenv("KESTREL_BATCH_KERNEL") != nullptr;
bool g_chosen = g_env_chosen;
}  // namespace

// The kernel moves RigidBodyState as 13 packed floats (position, quaternion x y z w, linear
// velocity, body rate): true when the types are laid out that way (Eigen's DontAlign types are).
static bool state_layout_ok() {
  const RigidBodyState s;
  const real* b = reinterpret_cast<const real*>(&s);
  return sizeof(RigidBodyState) == 13 * sizeof(real) && s.position_w.data() == b && s.orientation_wb.coeffs().data() == b + 3 &&
         s.linvel_w.data() == b + 7 && s.angvel_b.data() == b + 10;
}

KernelCopy kernel_copy() { return g_copy; }

bool use_kernel(KernelCopy c) {
  if (static_cast<int>(c) > static_cast<int>(widest_copy())) return false;
  g_copy = c;
  g_chosen = true;
  return true;
}

void use_default_kernel() {
  g_copy = g_default;
  g_chosen = g_env_chosen;
}

bool kernel_copy_chosen() { return g_chosen; }

KernelCopy widest_kernel_copy() { return widest_copy(); }

int lanes() {
  switch (g_copy) {
    case KernelCopy::avx512: return 16;
    case KernelCopy::avx2: return 8;
    default: return 4;
  }
}

const char* kernel_name() {
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  return "none (double build: scalar robot step)";
#elif defined(KESTREL_BATCH_SSE)
  switch (g_copy) {
    case KernelCopy::avx512: return "AVX-512 copy, 16 lanes";
    case KernelCopy::avx2: return "AVX2 copy, 8 lanes";
    default: return "SSE2 copy, 4 lanes";
  }
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

#ifdef KESTREL_BATCH_WIDE
#define KESTREL_BATCH_DISPATCH(call)         \
  do {                                       \
    switch (g_copy) {                        \
      case KernelCopy::avx512: avx512::call; \
        break;                               \
      case KernelCopy::avx2: avx2::call;     \
        break;                               \
      default: base::call;                   \
    }                                        \
  } while (false)
#else
#define KESTREL_BATCH_DISPATCH(call) base::call
#endif

void controller_stage(const Models& m, const Lane* lanes, real (&wrench)[6][kMaxLanes]) {
  KESTREL_BATCH_DISPATCH(controller_stage_k(m, lanes, wrench));
}
void allocation_stage(const Models& m, const Lane* lanes, const real (&wrench)[6][kMaxLanes],
                      real (&thrust)[4][kMaxLanes]) {
  KESTREL_BATCH_DISPATCH(allocation_stage_k(m, lanes, wrench, thrust));
}
void motor_stage(const Models& m, const Lane* lanes, const real (&thrust)[4][kMaxLanes],
                 real (&body_wrench)[6][kMaxLanes]) {
  KESTREL_BATCH_DISPATCH(motor_stage_k(m, lanes, thrust, body_wrench));
}
void rigid_body_stage(const Models& m, const Lane* lanes, const real (&body_wrench)[6][kMaxLanes]) {
  KESTREL_BATCH_DISPATCH(rigid_body_stage_k(m, lanes, body_wrench));
}
int robot_env_steps(const Models& m, const Lane* lanes, const QuietEnv* envs, int physics_steps, int max_env_steps) {
  int done = 0;
  KESTREL_BATCH_DISPATCH(env_steps_k(m, lanes, envs, physics_steps, max_env_steps, done));
  return done;
}
unsigned robot_step(const Models& m, const Lane* lanes) {
  unsigned done = 0;
  KESTREL_BATCH_DISPATCH(robot_step_k(m, lanes, done));
  return done;
}

}  // namespace kestrel::sim::batch
