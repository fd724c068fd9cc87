// Sequential desaturation ("airmode") allocator for multirotors.
//
// The allocation is the pseudo-inverse f = A+ w, then saturation is removed one control axis at a
// time by sliding f along a column of A+ (which changes that axis of the realized wrench only):
// PX4's ControlAllocationSequentialDesaturation (R. Bapst, B. Kueng; PX4-Autopilot
// src/modules/control_allocator), itself the vector form of the airmode mixer of M. Faessler,
// D. Falanga, D. Scaramuzza, "Thrust mixing, saturation, and body-rate control for accurate
// aggressive quadrotor flight", IEEE RA-L 2(2), 2017 (collective thrust is the first thing given
// up, roll/pitch the last). Here the columns are in physical units (N per N or per N m), so no
// normalisation of A+ is needed; limits are per motor and may be health-scaled.
//
// First, f = A+ w: if every motor is within its limits the command is feasible and returned as
// is (the common case; about 330 Cortex-M4F instructions for a quadrotor, result included).
// PX4 always runs the sequence below, which differs only when adding yaw brings an otherwise
// out-of-range motor back in range; Kestrel keeps the exact answer there.
// Otherwise, priorities (airmode = roll_pitch, the default):
//   1. mix roll, pitch and collective thrust (and fx, fy for frames that can make them);
//   2. shift collective thrust up or down to fit roll/pitch in the limits (airmode);
//   3. add yaw and reduce the yaw command to fit, allowing `yaw_headroom` of the thrust range
//      above the max so some yaw remains at full thrust;
//   4. reduce collective thrust (only reduce) to remove what the yaw headroom pushed above max.
// airmode = disabled never increases thrust, then reduces roll, then pitch, then does 3-4.
// airmode = roll_pitch_yaw mixes everything, shifts thrust, then reduces yaw.
// Each "fit" is PX4's two-pass gain: the gain that removes the largest violation, then half of
// the remaining one (which centres the outputs when both limits are exceeded).
//
// Roll/pitch torque is kept exactly (to round-off) whenever only thrust or yaw are adjusted: a step
// along column k of A+ changes A f by e_k only, because A A+ e_k = e_k for k in the range of A.
// Cost for a quadrotor, measured on the emulated Cortex-M4F (tests/allocation/test_alloc_cost.cpp):
// see the numbers there; no iteration, one division per violating motor and pass.
#pragma once

#include <cstdint>

#include "kestrel/allocation/allocation_model.hpp"

namespace kestrel::allocation {

enum class Airmode : std::uint8_t {
  disabled,        // PX4 MC_AIRMODE 0
  roll_pitch,      // PX4 MC_AIRMODE 1
  roll_pitch_yaw,  // PX4 MC_AIRMODE 2
};

struct SequentialDesaturationParams {
  Airmode airmode = Airmode::roll_pitch;
  /// Fraction of each motor's thrust range the yaw desaturation may exceed its max by (PX4: 0.15);
  /// the excess is then removed by reducing collective thrust.
  real yaw_headroom = 0.15_r;
};

/// Saturation bit i: motor i ended at (within 1e-5 of its range) or beyond a limit. Motors whose
/// limits are equal (dead) are never flagged. Returns ok, non_finite_input (last output held,
/// unallocated = 0), non_finite_output (a finite command so large that the solution overflowed to
/// NaN: last finite output held, kFaultNonFiniteOutput latched, unallocated = 0) or invalid_argument (empty model; in a KESTREL_MAX_ROTORS=4 build, which keeps
/// only the unrolled quadrotor path, also any rotor count other than 4).
[[nodiscard]] Status allocate_sequential_desaturation(const AllocationModel& model,
                                                      const SequentialDesaturationParams& params, AllocatorState& state,
                                                      const Vec6& wrench_cmd, AllocationResult& out);
[[nodiscard]] inline Status allocate_sequential_desaturation(const AllocationModel& model,
                                                             const SequentialDesaturationParams& params,
                                                             AllocatorState& state, const Wrench& wrench_cmd,
                                                             AllocationResult& out) {
  return allocate_sequential_desaturation(model, params, state, wrench_cmd.as_vec6(), out);
}

}  // namespace kestrel::allocation
