// Build-time ("baked") parameters of the quadrotor control stack: LeeParams and the allocation
// model as plain constant data, generated on the host from the same presets and set-up code that
// the start-up-built images run (bench/control/bake/bake_cascade.cpp writes
// kestrel_baked_cascade_quad.hpp with every float as a hex-float literal), as PX4 generated its
// mixer tables at build time (px_generate_mixers.py).
//
// Why plain mirrors and not `constexpr LeeParams` / `constexpr AllocationModel`: those structs
// hold Eigen fixed-size matrices, and Eigen 3.4's constructors are not constexpr, so an object of
// them can never be constant-initialised: GCC places it in .bss and fills it at start-up
// whatever its initialiser. The mirrors below (arrays only) are constant-initialised into
// .rodata; load() copies them element by element into the core structs (no type punning: the
// core's per-step functions read real LeeParams / AllocationModel objects, which therefore stay
// in RAM). The copy replaces the presets, airframe and pseudo-inverse set-up code.
//
// The initial state is baked too: what lee_reset leaves in a LeeState (nominal gains, the
// diagonal-inertia flag; the rest is LeeState()'s defaults) and the MotorModelState that
// motor_model_reset draws (RngStream(1, 0, kPurposeMotors), idle thrust). MotorModelState holds
// arrays only, so the generated kMotorsInitial constant-initialises a state object in .data; a
// re-arm on board is a copy of these constants again, not a call of the reset functions.
#pragma once

#include <cstdint>

#include "kestrel/allocation/allocation_model.hpp"
#include "kestrel/allocation/motor_model.hpp"
#include "kestrel/controllers/lee.hpp"

namespace kestrel::baked {

/// LeeParams as arrays (matrices in Eigen's storage order, column-major).
struct LeeParamsData {
  real mass_kg;
  real inertia_b[9];
  real gravity_w[3];
  real max_yaw_rate_radps;
  real gains_min[12];  // k_pos xyz, k_vel xyz, k_rot xyz, k_angvel xyz
  real gains_max[12];
  bool randomize_gains;
  real action_min;
  real action_max;
};

/// AllocationModel as arrays (matrices column-major, as Eigen stores them).
struct AllocationModelData {
  int num_rotors;
  real effectiveness[6 * allocation::kMaxRotors];
  real pinv[allocation::kMaxRotors * 6];
  real pinv_col_abs_max[6];
  std::uint16_t pinv_col_movable_mask[6];
  real thrust_min_N[allocation::kMaxRotors];
  real thrust_max_N[allocation::kMaxRotors];
  std::uint16_t dead_mask;
  std::uint16_t weak_mask;
  std::uint8_t wrench_row_mask;
  allocation::PinvInfo pinv_info;
  std::uint32_t fault_bits;
};

/// What lee_reset(params, state) computes: the nominal gains and the diagonal-inertia flag.
struct LeeStateData {
  real gains[12];  // k_pos xyz, k_vel xyz, k_rot xyz, k_angvel xyz
  bool inertia_diagonal;
};

namespace detail {
template <typename T, int N>
inline void copy_n(const T (&from)[N], T* to) {
  for (int i = 0; i < N; ++i) to[i] = from[i];
}
}  // namespace detail

inline void load(const LeeParamsData& d, LeeParams& p) {
  p.mass_kg = d.mass_kg;
  detail::copy_n(d.inertia_b, p.inertia_b.data());
  detail::copy_n(d.gravity_w, p.gravity_w.data());
  p.max_yaw_rate_radps = d.max_yaw_rate_radps;
  LeeGains* const g[2] = {&p.gain_ranges.min, &p.gain_ranges.max};
  const real* const src[2] = {d.gains_min, d.gains_max};
  for (int r = 0; r < 2; ++r) {
    Vec3* const v[4] = {&g[r]->k_pos, &g[r]->k_vel, &g[r]->k_rot, &g[r]->k_angvel};
    for (int k = 0; k < 4; ++k)
      for (int i = 0; i < 3; ++i) (*v[k])(i) = src[r][3 * k + i];
  }
  p.randomize_gains = d.randomize_gains;
  p.action_min = d.action_min;
  p.action_max = d.action_max;
}

/// lee_reset's result: LeeState() with the baked gains and flag.
inline void load(const LeeStateData& d, LeeState& s) {
  s = LeeState();
  Vec3* const v[4] = {&s.gains.k_pos, &s.gains.k_vel, &s.gains.k_rot, &s.gains.k_angvel};
  for (int k = 0; k < 4; ++k)
    for (int i = 0; i < 3; ++i) (*v[k])(i) = d.gains[3 * k + i];
  s.inertia_diagonal = d.inertia_diagonal;
}

inline void load(const AllocationModelData& d, allocation::AllocationModel& m) {
  m.num_rotors = d.num_rotors;
  detail::copy_n(d.effectiveness, m.effectiveness.data());
  detail::copy_n(d.pinv, m.pinv.data());
  detail::copy_n(d.pinv_col_abs_max, m.pinv_col_abs_max);
  detail::copy_n(d.pinv_col_movable_mask, m.pinv_col_movable_mask);
  detail::copy_n(d.thrust_min_N, m.thrust_min_N);
  detail::copy_n(d.thrust_max_N, m.thrust_max_N);
  m.dead_mask = d.dead_mask;
  m.weak_mask = d.weak_mask;
  m.wrench_row_mask = d.wrench_row_mask;
  m.pinv_info = d.pinv_info;
  m.faults.bits = d.fault_bits;
}

}  // namespace kestrel::baked
