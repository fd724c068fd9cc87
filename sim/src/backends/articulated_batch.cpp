// The batched legged step (articulated_batch.hpp): its kernel, articulated_kernel.inc, compiled
// for baseline x86-64 (SSE2, 4 lanes), AVX2 (8) and AVX-512 (16), as engine/batch_step.cpp
// compiles the multirotor's, and run in the widest copy this CPU runs or the one asked for (copy() below).
#include "articulated_batch.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "kestrel/kernel/math.hpp"
#include "kestrel/sim/batch_step.hpp"

#if defined(__SSE__) && !(defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE)
#include <immintrin.h>
#define KESTREL_BATCH_SSE 1
#endif

namespace kestrel::sim::legged_batch {

#if !(defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE)
#define KESTREL_KERNEL_FILE "../backends/articulated_kernel.inc"
#include "../engine/kernel_copies.inc"
#undef KESTREL_KERNEL_FILE
#endif

#if !(defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE)
namespace {
// The copy this step runs: the one asked for, else the widest (see batch::kernel_copy_chosen).
batch::KernelCopy copy() { return batch::kernel_copy_chosen() ? batch::kernel_copy() : batch::widest_kernel_copy(); }
}  // namespace
#endif

int lanes() {
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  return 0;
#else
  switch (copy()) {
    case batch::KernelCopy::avx512: return 16;
    case batch::KernelCopy::avx2: return 8;
    default: return 4;
  }
#endif
}

bool eligible(const Model& m) {
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  (void)m;
  return false;  // the kernel reproduces Eigen's float evaluation order only
#else
  if (m.num_bodies <= 0 || m.num_dofs <= 0) return false;
  for (int i = 0; i < m.num_bodies; ++i) {
    const bool one_dof = m.joint[i] == dynamics::JointType::revolute || m.joint[i] == dynamics::JointType::prismatic;
    if (one_dof && m.unit_subspace[i] < 0) return false;
    if (m.joint[i] == dynamics::JointType::free && m.parent[i] >= 0) return false;
  }
  return true;
#endif
}

std::size_t scratch_bytes() {
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  return 0;
#elif defined(KESTREL_BATCH_WIDE)
  return std::max({sizeof(base::Scratch), sizeof(avx2::Scratch), sizeof(avx512::Scratch)});
#else
  return sizeof(base::Scratch);
#endif
}

void kinematics(const Model& m, const real* const* q, int count, dynamics::Transform* const* X_world, void* scratch) {
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  (void)m, (void)q, (void)count, (void)X_world, (void)scratch;
#else
#ifdef KESTREL_BATCH_WIDE
  switch (copy()) {
    case batch::KernelCopy::avx512: avx512::kinematics_k(m, q, count, X_world, scratch); return;
    case batch::KernelCopy::avx2: avx2::kinematics_k(m, q, count, X_world, scratch); return;
    default: break;
  }
#endif
  base::kinematics_k(m, q, count, X_world, scratch);
#endif
}

unsigned step(const Model& m, const dynamics::ConstraintParams& p, real dt_s, const Lane* lanes_in, int count, void* scratch) {
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  (void)m, (void)p, (void)dt_s, (void)lanes_in, (void)count, (void)scratch;
  return 0;
#else
  if (count > lanes()) return 0;
#ifdef KESTREL_BATCH_WIDE
  switch (copy()) {
    case batch::KernelCopy::avx512: return avx512::step_k(m, p, dt_s, lanes_in, count, scratch);
    case batch::KernelCopy::avx2: return avx2::step_k(m, p, dt_s, lanes_in, count, scratch);
    default: break;
  }
#endif
  return base::step_k(m, p, dt_s, lanes_in, count, scratch);
#endif
}

}  // namespace kestrel::sim::legged_batch
