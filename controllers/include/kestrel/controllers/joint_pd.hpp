// Joint-space PD controller with an action-delay line, as legged_gym's _compute_torques()
// (N. Rudin, D. Hoeller, P. Reist, M. Hutter, "Learning to walk in minutes using massively parallel
// deep reinforcement learning", CoRL 2021):
//   a = action_scale * action (after clipping to +-action_clip)
//   'P' position: tau = kp (a + q_default - q) - kd qd
//   'V' velocity: tau = kp (a - qd) - kd (qd - qd_last) / dt
//   'T' torque:   tau = a
//   tau = clip(tau, -torque_limit, +torque_limit)
// with kp = kp_joint * kp_scale and kd = kd_joint * kd_scale, where the scales are per instance
// and may be redrawn at every reset (domain randomisation of actuator gains).
//
// The delay line holds delay_steps actions: the action applied at update t is the one given at
// update t - delay_steps. joint_pd_reset() fills it with zero actions (so the first delay_steps
// updates apply action 0: the default position in 'P' mode, zero velocity in 'V', zero torque in
// 'T'). The capacities (joints, delay steps) are template parameters: no heap.
//
// Rejected updates (non-finite action -> kFaultNonFiniteCommand, non-finite q or qd ->
// kFaultNonFiniteState, non-finite result -> kFaultNonFiniteOutput) output the last safe torques
// and change nothing else: the delay line does not advance and qd_last is kept.
// Clipped actions raise kFaultCommandOutOfRange, clipped torques kFaultSaturated.
#pragma once

#include <cstddef>
#include <cstdint>

#include "kestrel/kernel/assert.hpp"
#include "kestrel/kernel/containers.hpp"
#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/rng.hpp"
#include "kestrel/kernel/status.hpp"
#include "kestrel/kernel/types.hpp"

namespace kestrel {

enum class JointControlMode : std::uint8_t { position = 'P', velocity = 'V', torque = 'T' };

/// Per-instance multipliers on every joint's kp and kd.
struct JointGainScales {
  real kp_scale = 1;
  real kd_scale = 1;
};

/// Inclusive ranges of the scales (min = max fixes a scale).
struct JointGainScaleRanges {
  real kp_scale_min = 1;
  real kp_scale_max = 1;
  real kd_scale_min = 1;
  real kd_scale_max = 1;
};

/// Scales drawn uniformly in the ranges (two draws: kp then kd).
JointGainScales randomize_joint_gain_scales(const JointGainScaleRanges& ranges, RngStream& rng);
/// Midpoints of the ranges.
JointGainScales joint_nominal_gain_scales(const JointGainScaleRanges& ranges);

template <std::size_t MaxJoints, std::size_t MaxDelaySteps>
struct JointPdParams {
  static_assert(MaxJoints > 0, "JointPdParams needs at least one joint");
  static constexpr std::size_t kMaxJoints = MaxJoints;
  static constexpr std::size_t kMaxDelaySteps = MaxDelaySteps;

  std::size_t num_joints = 0;
  JointControlMode mode = JointControlMode::position;
  real kp[MaxJoints] = {};               // N m/rad ('P'), N m s/rad ('V')
  real kd[MaxJoints] = {};               // N m s/rad ('P'), N m s^2/rad ('V')
  real default_pos_rad[MaxJoints] = {};  // 'P' mode offset
  real torque_limit_Nm[MaxJoints] = {};  // symmetric clip
  real action_scale = 1;
  real action_clip = 100;     // legged_gym's clip_actions
  real dt_s = 0.005_r;        // time between updates ('V' mode derivative)
  std::size_t delay_steps = 0;  // 0 = no delay; at most MaxDelaySteps
  JointGainScaleRanges gain_scale_ranges;
  bool randomize_gain_scales = false;
};

template <std::size_t MaxJoints, std::size_t MaxDelaySteps>
struct JointPdState {
  struct Action {
    real v[MaxJoints];
  };
  JointGainScales scales;
  RingBuffer<Action, MaxDelaySteps + 1> delay_line;  // oldest first
  real last_qd_radps[MaxJoints] = {};
  real last_safe_torque_Nm[MaxJoints] = {};  // held while an update is rejected; starts at zero
  FaultFlags faults;                         // latched until cleared (reset clears them)
  std::uint32_t step_faults = 0;             // raised by the most recent update only
};

/// num_joints in [1, MaxJoints], delay_steps <= MaxDelaySteps, finite values, kp, kd,
/// torque limits >= 0, action_clip > 0, dt_s > 0 in 'V' mode, scale ranges finite with min <= max.
template <std::size_t J, std::size_t D>
[[nodiscard]] Status validate_joint_pd_params(const JointPdParams<J, D>& p) {
  if (p.num_joints < 1 || p.num_joints > J || p.delay_steps > D) return Status::invalid_argument;
  if (p.mode != JointControlMode::position && p.mode != JointControlMode::velocity &&
      p.mode != JointControlMode::torque) {
    return Status::invalid_argument;
  }
  for (std::size_t i = 0; i < p.num_joints; ++i) {
    if (!is_finite(p.kp[i]) || !is_finite(p.kd[i]) || !is_finite(p.default_pos_rad[i]) ||
        !is_finite(p.torque_limit_Nm[i])) {
      return Status::invalid_argument;
    }
    if (!(p.kp[i] >= 0) || !(p.kd[i] >= 0) || !(p.torque_limit_Nm[i] >= 0)) return Status::invalid_argument;
  }
  if (!is_finite(p.action_scale) || !is_finite(p.action_clip) || !(p.action_clip > 0)) return Status::invalid_argument;
  if (p.mode == JointControlMode::velocity && !(is_finite(p.dt_s) && p.dt_s > 0)) return Status::invalid_argument;
  const JointGainScaleRanges& r = p.gain_scale_ranges;
  const real v[4] = {r.kp_scale_min, r.kp_scale_max, r.kd_scale_min, r.kd_scale_max};
  if (!all_finite(v, 4) || !(r.kp_scale_min <= r.kp_scale_max) || !(r.kd_scale_min <= r.kd_scale_max)) {
    return Status::invalid_argument;
  }
  return Status::ok;
}

/// Start an instance: nominal (midpoint) gain scales, delay line filled with delay_steps zero
/// actions, qd_last = 0, zero held torques, faults cleared.
template <std::size_t J, std::size_t D>
void joint_pd_reset(const JointPdParams<J, D>& p, JointPdState<J, D>& s) {
  s.scales = joint_nominal_gain_scales(p.gain_scale_ranges);
  s.delay_line.clear();
  const typename JointPdState<J, D>::Action zero = {};
  const std::size_t k = p.delay_steps < D ? p.delay_steps : D;
  for (std::size_t i = 0; i < k; ++i) s.delay_line.push_overwrite(zero);
  for (std::size_t i = 0; i < J; ++i) {
    s.last_qd_radps[i] = 0;
    s.last_safe_torque_Nm[i] = 0;
  }
  s.faults.clear();
  s.step_faults = 0;
}

/// As above, then draws the gain scales from `rng` if p.randomize_gain_scales.
template <std::size_t J, std::size_t D>
void joint_pd_reset(const JointPdParams<J, D>& p, JointPdState<J, D>& s, RngStream& rng) {
  joint_pd_reset(p, s);
  if (p.randomize_gain_scales) s.scales = randomize_joint_gain_scales(p.gain_scale_ranges, rng);
}

/// One update: reads num_joints positions (rad), velocities (rad/s) and actions, writes num_joints
/// torques (N m). Returns Status::ok, or Status::non_finite_input when the update was rejected.
template <std::size_t J, std::size_t D>
Status update_joint_pd(const JointPdParams<J, D>& p, JointPdState<J, D>& s, const real* q_rad, const real* qd_radps,
                       const real* action, real* torque_Nm) {
  KESTREL_ASSERT(q_rad != nullptr && qd_radps != nullptr && action != nullptr && torque_Nm != nullptr);
  KESTREL_ASSERT(p.num_joints <= J);
  using Action = typename JointPdState<J, D>::Action;
  const std::size_t n = p.num_joints;
  const int ni = static_cast<int>(n);
  std::uint32_t faults = 0;
  if (!all_finite(action, ni)) faults |= kFaultNonFiniteCommand;
  if (!all_finite(q_rad, ni) || !all_finite(qd_radps, ni)) faults |= kFaultNonFiniteState;

  real tau[J];
  Action in = {};
  if (faults == 0) {
    for (std::size_t i = 0; i < n; ++i) {
      real a = action[i];
      if (a > p.action_clip) {
        a = p.action_clip;
        faults |= kFaultCommandOutOfRange;
      } else if (a < -p.action_clip) {
        a = -p.action_clip;
        faults |= kFaultCommandOutOfRange;
      }
      in.v[i] = a;
    }
    // The action applied now: the newest one without delay, else the oldest in the line (zero
    // while a line that was never reset is still filling up).
    const std::size_t k = p.delay_steps < D ? p.delay_steps : D;
    static const Action kZero = {};
    const Action& applied = k == 0 ? in : (s.delay_line.size() >= k ? s.delay_line.at(0) : kZero);
    const real kp_scale = s.scales.kp_scale, kd_scale = s.scales.kd_scale;
    for (std::size_t i = 0; i < n; ++i) {
      const real a = applied.v[i] * p.action_scale;
      const real kp = p.kp[i] * kp_scale;
      const real kd = p.kd[i] * kd_scale;
      real t;
      switch (p.mode) {
        case JointControlMode::position:
          t = kp * (a + p.default_pos_rad[i] - q_rad[i]) - kd * qd_radps[i];
          break;
        case JointControlMode::velocity:
          t = kp * (a - qd_radps[i]) - kd * (qd_radps[i] - s.last_qd_radps[i]) / p.dt_s;
          break;
        case JointControlMode::torque:
        default:
          t = a;
          break;
      }
      const real lim = p.torque_limit_Nm[i];
      if (t > lim) {
        t = lim;
        faults |= kFaultSaturated;
      } else if (t < -lim) {
        t = -lim;
        faults |= kFaultSaturated;
      }
      tau[i] = t;
    }
    if (!all_finite(tau, ni)) {
      faults = (faults & ~static_cast<std::uint32_t>(kFaultSaturated)) | kFaultNonFiniteOutput;
    } else {
      if (k > 0) {
        if (s.delay_line.size() >= k) {
          Action oldest;
          (void)s.delay_line.pop(oldest);
        }
        s.delay_line.push_overwrite(in);
      }
      for (std::size_t i = 0; i < n; ++i) {
        s.last_qd_radps[i] = qd_radps[i];
        s.last_safe_torque_Nm[i] = tau[i];
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) torque_Nm[i] = s.last_safe_torque_Nm[i];
  s.step_faults = faults;
  s.faults.raise(faults);
  const std::uint32_t rejected = kFaultNonFiniteCommand | kFaultNonFiniteState | kFaultNonFiniteOutput;
  return (faults & rejected) != 0 ? Status::non_finite_input : Status::ok;
}

}  // namespace kestrel
