#include "kestrel/allocation/allocation_model.hpp"

#include <cmath>

#include "kestrel/kernel/math.hpp"

namespace kestrel::allocation {

Status build_allocation_model(const Airframe& airframe, const MotorHealth& health, AllocationModel& model,
                              const PinvOptions& options) {
  model = AllocationModel();
  const int n = airframe.num_rotors;
  if (n < 1 || n > kMaxRotors) return Status::invalid_argument;
  for (int i = 0; i < n; ++i) {
    const real s = health.thrust_scale[i];
    if (!is_finite(s) || s < 0 || s > 1) return Status::invalid_argument;
  }
  AllocationModel m;
  m.num_rotors = n;
  for (int i = 0; i < n; ++i) {
    const real s = health.thrust_scale[i];
    if (s == 0) {
      // Dead: the column is removed so the pseudo-inverse gives this motor exactly zero thrust
      // and spreads its share over the others.
      m.dead_mask = static_cast<std::uint16_t>(m.dead_mask | (1u << i));
      m.thrust_min_N[i] = 0;
      m.thrust_max_N[i] = 0;
      continue;
    }
    if (s < 1) m.weak_mask = static_cast<std::uint16_t>(m.weak_mask | (1u << i));
    m.effectiveness.map().col(i) = airframe.effectiveness.col(i);
    m.thrust_min_N[i] = s * airframe.thrust_min_N[i];
    m.thrust_max_N[i] = s * airframe.thrust_max_N[i];
  }
  if ((m.dead_mask | m.weak_mask) != 0) m.faults.raise(kFaultMotorFailure);
  for (int k = 0; k < 6; ++k) {
    for (int i = 0; i < n; ++i) {
      if (m.effectiveness(k, i) != 0) m.wrench_row_mask = static_cast<std::uint8_t>(m.wrench_row_mask | (1u << k));
    }
  }
  PinvMatrix pinv;
  const Status st = pseudo_inverse(EffectivenessMatrix(m.effectiveness.map()), n, pinv, &m.pinv_info, options);
  m.pinv = pinv;
  if (st == Status::invalid_argument) return st;
  for (int k = 0; k < 6; ++k) {
    real mx = 0;
    for (int i = 0; i < n; ++i) mx = std::fabs(m.pinv(i, k)) > mx ? std::fabs(m.pinv(i, k)) : mx;
    m.pinv_col_abs_max[k] = mx;
    const real d_min = 1e-6_r * mx;
    for (int i = 0; i < n; ++i) {
      if (std::fabs(m.pinv(i, k)) > d_min)
        m.pinv_col_movable_mask[k] = static_cast<std::uint16_t>(m.pinv_col_movable_mask[k] | (1u << i));
    }
  }
  if (m.pinv_info.rank < 6) m.faults.raise(kFaultSingular);
  if (!m.pinv_info.converged) m.faults.raise(kFaultNotConverged);
  model = m;
  return st;
}

Status build_allocation_model(const Airframe& airframe, AllocationModel& model) {
  return build_allocation_model(airframe, MotorHealth(), model);
}

void reset_allocator(AllocatorState& state) { state = AllocatorState(); }

void apply_pinv(const AllocationModel& model, const Vec6& wrench_cmd, real* thrust_N) {
  // Row i of A+ dotted with w, summed in the order of the reference's batched product (k = 0..5).
  // Written out: with the six command values in registers this is 3 instructions per term on a
  // Cortex-M4F, where an indexed inner loop costs about 10.
  const real w0 = wrench_cmd(0), w1 = wrench_cmd(1), w2 = wrench_cmd(2);
  const real w3 = wrench_cmd(3), w4 = wrench_cmd(4), w5 = wrench_cmd(5);
  const PlainMat<kMaxRotors, 6>& p = model.pinv;
  for (int i = 0; i < model.num_rotors; ++i) {
    real f = p(i, 0) * w0;
    f += p(i, 1) * w1;
    f += p(i, 2) * w2;
    f += p(i, 3) * w3;
    f += p(i, 4) * w4;
    f += p(i, 5) * w5;
    thrust_N[i] = f;
  }
}

namespace detail {

Vec6 realized_wrench(const AllocationModel& model, const real* thrust_N) {
  // Six accumulators in registers, one contiguous column of A per motor (see apply_pinv).
  real w0 = 0, w1 = 0, w2 = 0, w3 = 0, w4 = 0, w5 = 0;
  const PlainMat<6, kMaxRotors>& a = model.effectiveness;
  for (int i = 0; i < model.num_rotors; ++i) {
    const real f = thrust_N[i];
    w0 += a(0, i) * f;
    w1 += a(1, i) * f;
    w2 += a(2, i) * f;
    w3 += a(3, i) * f;
    w4 += a(4, i) * f;
    w5 += a(5, i) * f;
  }
  Vec6 out;
  out << w0, w1, w2, w3, w4, w5;
  return out;
}

Status finish_allocation(const AllocationModel& model, AllocatorState& state, const Vec6& wrench_cmd,
                         AllocationResult& out) {
  const int n = model.num_rotors;
  // clamp() passes NaN through: a finite command near the float limit can overflow A+ w to inf
  // and the solvers' differences (inf - inf) to NaN. Checked before anything is stored, so the held
  // output (state.last_thrust_N) stays the last finite one. (+-inf alone clamps to the limit it
  // overflowed towards, which is the saturated answer.)
  for (int i = 0; i < n; ++i) {
    if (std::isnan(out.thrust_N[i])) return hold_nonfinite_result(model, state, out);
  }
  for (int i = 0; i < n; ++i) {
    out.thrust_N[i] = clamp(out.thrust_N[i], model.thrust_min_N[i], model.thrust_max_N[i]);
    state.last_thrust_N[i] = out.thrust_N[i];
  }
  state.num_rotors = n;
  out.wrench_realized = realized_wrench(model, out.thrust_N);
  out.wrench_unallocated = wrench_cmd - out.wrench_realized;
  if (out.any_saturated()) state.faults.raise(kFaultSaturated);
  return Status::ok;
}

namespace {
// Holds state.last_thrust_N (clamped into the current limits; a non-finite held value, which the
// allocators never store, would become the lower limit), latches `fault`.
void hold(const AllocationModel& model, AllocatorState& state, AllocationResult& out, std::uint32_t fault) {
  const int n = model.num_rotors;
  const bool have_last = state.num_rotors == n;
  for (int i = 0; i < n; ++i) {
    real held = have_last ? state.last_thrust_N[i] : real(0);
    if (!is_finite(held)) held = model.thrust_min_N[i];
    out.thrust_N[i] = clamp(held, model.thrust_min_N[i], model.thrust_max_N[i]);
    state.last_thrust_N[i] = out.thrust_N[i];
  }
  state.num_rotors = n;
  out.saturated_low_mask = 0;
  out.saturated_high_mask = 0;
  out.iterations = 0;
  out.wrench_realized = realized_wrench(model, out.thrust_N);
  out.wrench_unallocated.setZero();
  state.faults.raise(fault);
}
}  // namespace

Status hold_allocation(const AllocationModel& model, AllocatorState& state, AllocationResult& out) {
  hold(model, state, out, kFaultNonFiniteCommand);
  return Status::non_finite_input;
}

Status hold_nonfinite_result(const AllocationModel& model, AllocatorState& state, AllocationResult& out) {
  hold(model, state, out, kFaultNonFiniteOutput);
  return Status::non_finite_output;
}

}  // namespace detail

Status allocate_pinv(const AllocationModel& model, AllocatorState& state, const Vec6& wrench_cmd,
                     AllocationResult& out) {
  const int n = model.num_rotors;
  if (n < 1 || n > kMaxRotors) return Status::invalid_argument;
  if (!all_finite(wrench_cmd)) return detail::hold_allocation(model, state, out);
  apply_pinv(model, wrench_cmd, out.thrust_N);
  std::uint16_t low = 0, high = 0;
  for (int i = 0; i < n; ++i) {
    if (out.thrust_N[i] < model.thrust_min_N[i]) low = static_cast<std::uint16_t>(low | (1u << i));
    if (out.thrust_N[i] > model.thrust_max_N[i]) high = static_cast<std::uint16_t>(high | (1u << i));
  }
  out.saturated_low_mask = low;
  out.saturated_high_mask = high;
  out.iterations = 0;
  return detail::finish_allocation(model, state, wrench_cmd, out);
}

}  // namespace kestrel::allocation
