// Build-time ("baked") quadrotor control stack: LeeParams and the allocation model as constant
// objects of the core's own types, generated on the host from the same presets and set-up code
// that the start-up-built images run (bench/control/bake/bake_cascade.cpp writes
// kestrel_baked_cascade_quad.hpp with every float as a hex-float literal), as PX4 generated its
// mixer tables at build time (px_generate_mixers.py).
//
// LeeParams and AllocationModel hold their matrices as plain arrays (kestrel::PlainMat,
// kernel/types.hpp), so `constexpr LeeParams` / `constexpr AllocationModel` objects are
// constant-initialised: they live in flash (.rodata) and the per-step functions read them there.
// Only the mutable state takes RAM.
//
// The initial state is baked too: what lee_reset leaves in a LeeState (nominal gains, the
// diagonal-inertia flag; the rest is LeeState()'s defaults) and the MotorModelState that
// motor_model_reset draws (RngStream(1, 0, kPurposeMotors), idle thrust). MotorModelState holds
// arrays only, so the generated kMotorsInitial constant-initialises a state object in .data; a
// re-arm on board is a copy of these constants again, not a call of the reset functions.
// LeeState keeps Eigen members (it is written every step and lives in RAM anyway), so its
// initial value is a small table copied by load().
#pragma once

#include "kestrel/allocation/allocation_model.hpp"
#include "kestrel/allocation/motor_model.hpp"
#include "kestrel/controllers/lee.hpp"

namespace kestrel::baked {

/// What lee_reset(params, state) computes: the nominal gains and the diagonal-inertia flag.
struct LeeStateData {
  LeeGains gains;
  bool inertia_diagonal;
};

/// lee_reset's result: LeeState() with the baked gains and flag.
inline void load(const LeeStateData& d, LeeState& s) {
  s = LeeState();
  s.gains = d.gains;
  s.inertia_diagonal = d.inertia_diagonal;
}

}  // namespace kestrel::baked
