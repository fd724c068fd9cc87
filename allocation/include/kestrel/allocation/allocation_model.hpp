// What every allocator shares: the allocation model (effectiveness matrix with motor health
// applied, its pseudo-inverse, per-motor limits), the allocator's small mutable state, the result
// type, and the plain pseudo-inverse allocator of the reference.
//
// Shape (docs/design.md): AllocationModel is built once per geometry or motor-health change
// (build_allocation_model runs the Jacobi pseudo-inverse) and is read-only in the hot path;
// AllocatorState holds what an allocator remembers between steps (last output for the
// non-finite-input hold, the CLS active set for warm starts); AllocationResult is the output.
//
// Motor health: a dead motor (scale 0) gets bounds [0, 0] and its column is removed (zeroed)
// before the pseudo-inverse, so the pseudo-inverse based allocators redistribute its share to the
// remaining motors; a weak motor (0 < scale < 1) keeps its column and has its limits scaled
// (for a unidirectional rotor that is the max thrust). All allocators read the model's limits, so
// telling the allocator about a failure is one build_allocation_model() call.
#pragma once

#include <cstdint>
#include <utility>

#include "kestrel/allocation/airframe.hpp"
#include "kestrel/allocation/pinv.hpp"
#include "kestrel/kernel/status.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel::allocation {

/// Per-motor health: thrust_scale 1 healthy, 0 dead, in between weak (limits scaled).
struct MotorHealth {
  real thrust_scale[kMaxRotors];
  constexpr MotorHealth() : MotorHealth(std::make_integer_sequence<int, kMaxRotors>()) {}

 private:
  // {1, 1, ..., 1} for any KESTREL_MAX_ROTORS, as one array initialiser (constant data, no loop).
  template <int... kI>
  constexpr explicit MotorHealth(std::integer_sequence<int, kI...>) : thrust_scale{((void)kI, real(1))...} {}
};

/// Read-only allocation data derived from an airframe and the motor health.
struct AllocationModel {
  int num_rotors = 0;
  // Plain arrays (PlainMat, kernel/types.hpp: use .map() in expressions) so that a model baked at
  // build time is constant-initialised into flash.
  PlainMat<6, kMaxRotors> effectiveness = {};  // A, dead columns zeroed
  PlainMat<kMaxRotors, 6> pinv = {};           // A+ of `effectiveness`
  real pinv_col_abs_max[6] = {};       // largest |entry| of each A+ column (desaturation thresholds)
  // Bit i of entry k: |A+(i, k)| > 1e-6 pinv_col_abs_max[k], i.e. motor i can be moved along
  // wrench axis k (the desaturation test, precomputed so the hot path tests a bit).
  std::uint16_t pinv_col_movable_mask[6] = {};
  real thrust_min_N[kMaxRotors] = {};  // health-scaled limits
  real thrust_max_N[kMaxRotors] = {};
  std::uint16_t dead_mask = 0;  // bit i: motor i is dead
  std::uint16_t weak_mask = 0;  // bit i: motor i is weak
  // Bit k: row k of `effectiveness` has a non-zero entry. A zero row's part of A f is exactly +0
  // for finite thrusts (e.g. fx, fy of a quadrotor), so the allocators skip it.
  std::uint8_t wrench_row_mask = 0;
  PinvInfo pinv_info;           // rank, sweeps, singular values
  FaultFlags faults;            // kFaultSingular (rank < 6), kFaultMotorFailure, kFaultNotConverged
};

/// Builds the model. Returns invalid_argument (model left empty, num_rotors 0) for an empty
/// airframe or a health scale outside [0, 1]; otherwise the pseudo-inverse's status:
/// ok, singular (rank < 6: a warning like the reference's, the model is usable — the quadrotor is
/// always rank 4) or not_converged (usable).
[[nodiscard]] Status build_allocation_model(const Airframe& airframe, const MotorHealth& health, AllocationModel& model,
                                            const PinvOptions& options = PinvOptions());
[[nodiscard]] Status build_allocation_model(const Airframe& airframe, AllocationModel& model);

/// Allocator output.
struct AllocationResult {
  real thrust_N[kMaxRotors] = {};          // per-motor thrust command, within the model's limits
                                           // (entries >= num_rotors are left untouched)
  std::uint16_t saturated_low_mask = 0;    // bit i: motor i wanted less than its min
  std::uint16_t saturated_high_mask = 0;   // bit i: motor i wanted more than its max
  Vec6 wrench_realized = Vec6::Zero();     // A f (body frame, [fx, fy, fz, tx, ty, tz])
  Vec6 wrench_unallocated = Vec6::Zero();  // command - realized (0 where the command was non-finite)
  int iterations = 0;                      // CLS: active-set iterations; others 0
  std::uint16_t saturated_mask() const { return static_cast<std::uint16_t>(saturated_low_mask | saturated_high_mask); }
  bool any_saturated() const { return saturated_mask() != 0; }
  bool saturated(int motor) const { return (saturated_mask() & (1u << motor)) != 0; }
};

/// What an allocator remembers between calls.
struct AllocatorState {
  int num_rotors = 0;                   // 0: nothing remembered yet (cold)
  real last_thrust_N[kMaxRotors] = {};  // last output, held when a command is non-finite
  std::int8_t active[kMaxRotors] = {};  // CLS working set: -1 at min, +1 at max, 0 free
  FaultFlags faults;                    // kFaultNonFiniteCommand, kFaultSaturated, kFaultNotConverged
};

/// Forgets the warm start and the held output (the next non-finite command holds zero thrust).
void reset_allocator(AllocatorState& state);

/// f = A+ w (the reference's unclamped reference thrust, allocation.json `f_ref_N`).
void apply_pinv(const AllocationModel& model, const Vec6& wrench_cmd, real* thrust_N);

/// Plain pseudo-inverse allocation, as the reference: f = clamp(A+ w, min, max) (the clamp the
/// reference's motor model applies to its reference). Saturation bit i: A+ w was strictly outside
/// motor i's limits. Returns ok, or non_finite_input (command had NaN/inf: the last output is
/// held, kFaultNonFiniteCommand latched in state.faults, unallocated = 0), non_finite_output
/// (a finite command so large that A+ w overflowed: the last output is held, kFaultNonFiniteOutput
/// latched), or invalid_argument for an empty model.
[[nodiscard]] Status allocate_pinv(const AllocationModel& model, AllocatorState& state, const Vec6& wrench_cmd,
                                   AllocationResult& out);
[[nodiscard]] inline Status allocate_pinv(const AllocationModel& model, AllocatorState& state, const Wrench& wrench_cmd,
                                          AllocationResult& out) {
  return allocate_pinv(model, state, wrench_cmd.as_vec6(), out);
}

namespace detail {
/// A f (the realized wrench).
Vec6 realized_wrench(const AllocationModel& model, const real* thrust_N);
/// Shared tail of every allocator: clamps thrust_N into the limits, fills realized/unallocated,
/// stores the output in the state and latches kFaultSaturated. Entries >= num_rotors of
/// out.thrust_N are not written (they stay as the result was constructed: zero). A non-finite
/// thrust (finite command that overflowed) goes to hold_nonfinite_result() instead: returns ok
/// or non_finite_output.
[[nodiscard]] Status finish_allocation(const AllocationModel& model, AllocatorState& state, const Vec6& wrench_cmd,
                                       AllocationResult& out);
/// Shared non-finite-command path: holds state.last_thrust_N (clamped to the current limits),
/// latches kFaultNonFiniteCommand, returns non_finite_input.
Status hold_allocation(const AllocationModel& model, AllocatorState& state, AllocationResult& out);
/// Same hold for a finite command whose solution overflowed (NaN/inf inside the allocator):
/// latches kFaultNonFiniteOutput, returns non_finite_output. The held value is always finite.
Status hold_nonfinite_result(const AllocationModel& model, AllocatorState& state, AllocationResult& out);
}  // namespace detail

}  // namespace kestrel::allocation
