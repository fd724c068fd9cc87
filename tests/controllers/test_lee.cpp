// Behaviour of the Lee controllers beyond the golden cases: hover, input rejection and clipping,
// degenerate attitudes, the lee_rates thrust convention, gain randomisation, closed loop.
#include <cmath>
#include <cstring>
#include <limits>

#include "kestrel/controllers/lee.hpp"
#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/kernel/rigid_body.hpp"
#include "kestrel/kernel/rng.hpp"
#include "ktest.hpp"

using namespace kestrel;

namespace {

using UpdateFn = Wrench (*)(const LeeParams&, LeeState&, const RigidBodyState&, const real*);

struct Kind {
  const char* name;
  UpdateFn fn;
  std::size_t dim;
};

const Kind kKinds[] = {
    {"position", &update_lee_position, kLeeActionDim},
    {"velocity", &update_lee_velocity, kLeeActionDim},
    {"acceleration", &update_lee_acceleration, kLeeActionDim},
    {"attitude", &update_lee_attitude, kLeeActionDim},
    {"rates", &update_lee_rates, kLeeActionDim},
    {"velocity_steering_angle", &update_lee_velocity_steering_angle, kLeeActionDim},
    {"rov_fully_actuated", &update_rov_fully_actuated, kPoseActionDim},
};

bool wrench_finite(const Wrench& w) { return all_finite(w.force_b) && all_finite(w.torque_b); }
bool state_finite(const LeeState& s) {
  return wrench_finite(s.last_safe_wrench_b) && all_finite(s.accel_command_w) && all_finite(s.desired_quat_xyzw) &&
         all_finite(s.desired_angvel_b) && all_finite(s.gains.k_pos) && all_finite(s.gains.k_angvel);
}
bool same_wrench(const Wrench& a, const Wrench& b) { return a.force_b == b.force_b && a.torque_b == b.torque_b; }

// The zero-error action of each kind at a hovering state at `p` with identity attitude.
void hover_action(std::size_t kind, const Vec3& p, real* a) {
  for (int i = 0; i < 7; ++i) a[i] = 0;
  if (kind == 0 || kind == 6) {
    a[0] = p[0];
    a[1] = p[1];
    a[2] = p[2];
  }
  if (kind == 6) a[6] = 1;  // identity quaternion, xyzw
}

LeeParams params_for(std::size_t kind) { return kind == 6 ? lee_params_rov() : lee_params_base_quadrotor(); }

}  // namespace

KTEST(LeeController, PresetsValidate) {
  KEXPECT_TRUE(validate_lee_params(lee_params_base_quadrotor()) == Status::ok);
  KEXPECT_TRUE(validate_lee_params(lee_params_rov()) == Status::ok);
  LeeParams p = lee_params_base_quadrotor();
  p.mass_kg = 0;
  KEXPECT_TRUE(validate_lee_params(p) == Status::invalid_argument);
  p = lee_params_base_quadrotor();
  p.gain_ranges.min.k_rot[1] = 2;  // min > max
  KEXPECT_TRUE(validate_lee_params(p) == Status::invalid_argument);
  p = lee_params_base_quadrotor();
  p.inertia_b(0, 0) = std::numeric_limits<real>::quiet_NaN();
  KEXPECT_TRUE(validate_lee_params(p) == Status::invalid_argument);
  p = lee_params_base_quadrotor();
  p.action_min = p.action_max;
  KEXPECT_TRUE(validate_lee_params(p) == Status::invalid_argument);
}

// Fuzz finding F1: finite but absurd gains (k_angvel.z = 1e37: 1e38 N m at 10 rad/s) overflowed the
// allocation on every step. Parameters with which overflow is unavoidable are refused up front.
KTEST(LeeController, GainsMassInertiaGravityBounded) {
  LeeParams p = lee_params_base_quadrotor();
  p.gain_ranges.max.k_angvel[2] = 1e37_r;
  KEXPECT_TRUE(validate_lee_params(p) == Status::invalid_argument);
  p = lee_params_base_quadrotor();
  p.gain_ranges.min.k_pos[0] = -2 * kLeeMaxGain;
  KEXPECT_TRUE(validate_lee_params(p) == Status::invalid_argument);
  p = lee_params_base_quadrotor();
  p.gain_ranges.min.k_rot[0] = kLeeMaxGain;  // at the bound: accepted
  p.gain_ranges.max.k_rot[0] = kLeeMaxGain;
  KEXPECT_TRUE(validate_lee_params(p) == Status::ok);
  p = lee_params_base_quadrotor();
  p.mass_kg = 2 * kLeeMaxMassKg;
  KEXPECT_TRUE(validate_lee_params(p) == Status::invalid_argument);
  p = lee_params_base_quadrotor();
  p.inertia_b(1, 1) = 2 * kLeeMaxInertiaKgm2;
  KEXPECT_TRUE(validate_lee_params(p) == Status::invalid_argument);
  p = lee_params_base_quadrotor();
  p.gravity_w[2] = -2 * kLeeMaxGravityMps2;
  KEXPECT_TRUE(validate_lee_params(p) == Status::invalid_argument);
}

KTEST(LeeController, HoverGivesWeightAndZeroTorque) {
  for (std::size_t k = 0; k < sizeof(kKinds) / sizeof(kKinds[0]); ++k) {
    const LeeParams p = params_for(k);
    LeeState s;
    lee_reset(p, s);
    RigidBodyState body;
    body.position_w = Vec3(1, -2, 3);
    real a[7];
    hover_action(k, body.position_w, a);
    Wrench w;
    KEXPECT_NO_HEAP(w = kKinds[k].fn(p, s, body, a));
    const double mg = static_cast<double>(p.mass_kg) * static_cast<double>(kStandardGravity);
    KEXPECT_NEAR(w.force_b[0], 0, 1e-6);
    KEXPECT_NEAR(w.force_b[1], 0, 1e-6);
    KEXPECT_NEAR(w.force_b[2], mg, 1e-6 * mg);
    KEXPECT_NEAR(w.torque_b.norm(), 0, 1e-7);
    KEXPECT_EQ(s.step_faults, 0u);
    KEXPECT_FALSE(s.faults.any());
    KEXPECT_TRUE(same_wrench(w, s.last_safe_wrench_b));
  }
}

KTEST(LeeController, NonFiniteCommandHoldsLastSafeWrench) {
  const real nan = std::numeric_limits<real>::quiet_NaN();
  const real inf = std::numeric_limits<real>::infinity();
  for (std::size_t k = 0; k < sizeof(kKinds) / sizeof(kKinds[0]); ++k) {
    const LeeParams p = params_for(k);
    LeeState s;
    lee_reset(p, s);
    RigidBodyState body;
    body.angvel_b = Vec3(0.3_r, -0.2_r, 0.1_r);
    real a[7];
    hover_action(k, body.position_w, a);
    a[0] += 0.5_r;
    a[3] += 0.2_r;

    // Before any accepted update the held output is zero.
    real bad[7];
    std::memcpy(bad, a, sizeof a);
    bad[1] = nan;
    Wrench w;
    KEXPECT_NO_HEAP(w = kKinds[k].fn(p, s, body, bad));
    KEXPECT_TRUE(same_wrench(w, Wrench()));
    KEXPECT_EQ(s.step_faults, static_cast<std::uint32_t>(kFaultNonFiniteCommand));

    const Wrench good = kKinds[k].fn(p, s, body, a);
    KEXPECT_TRUE(wrench_finite(good));
    KEXPECT_GT(good.torque_b.norm(), 0);
    KEXPECT_EQ(s.step_faults, 0u);
    KEXPECT_TRUE(s.faults.has(kFaultNonFiniteCommand));  // latched from before
    const LeeState before = s;

    for (real v : {nan, inf, -inf}) {
      for (std::size_t i = 0; i < kKinds[k].dim; ++i) {
        std::memcpy(bad, a, sizeof a);
        bad[i] = v;
        KEXPECT_NO_HEAP(w = kKinds[k].fn(p, s, body, bad));
        KEXPECT_TRUE(same_wrench(w, good));
        KEXPECT_EQ(s.step_faults, static_cast<std::uint32_t>(kFaultNonFiniteCommand));
        KEXPECT_TRUE(state_finite(s));
        KEXPECT_TRUE(s.accel_command_w == before.accel_command_w);
        KEXPECT_TRUE(s.desired_quat_xyzw == before.desired_quat_xyzw);
        KEXPECT_TRUE(s.desired_angvel_b == before.desired_angvel_b);
      }
    }
    lee_reset(p, s);
    KEXPECT_FALSE(s.faults.any());
  }
}

KTEST(LeeController, NonFiniteStateHoldsLastSafeWrench) {
  const real nan = std::numeric_limits<real>::quiet_NaN();
  for (std::size_t k = 0; k < sizeof(kKinds) / sizeof(kKinds[0]); ++k) {
    const LeeParams p = params_for(k);
    LeeState s;
    lee_reset(p, s);
    RigidBodyState body;
    real a[7];
    hover_action(k, body.position_w, a);
    a[1] += 0.3_r;
    const Wrench good = kKinds[k].fn(p, s, body, a);
    for (int field = 0; field < 4; ++field) {
      RigidBodyState bad = body;
      if (field == 0) bad.position_w[2] = nan;
      if (field == 1) bad.orientation_wb = quat_from_xyzw(0, nan, 0, 1);
      if (field == 2) bad.linvel_w[0] = std::numeric_limits<real>::infinity();
      if (field == 3) bad.angvel_b[1] = nan;
      Wrench w;
      KEXPECT_NO_HEAP(w = kKinds[k].fn(p, s, bad, a));
      KEXPECT_TRUE(same_wrench(w, good));
      KEXPECT_EQ(s.step_faults, static_cast<std::uint32_t>(kFaultNonFiniteState));
      KEXPECT_TRUE(s.faults.has(kFaultNonFiniteState));
      KEXPECT_TRUE(state_finite(s));
    }
    // Both at once: both bits.
    RigidBodyState bad = body;
    bad.angvel_b[0] = nan;
    real bad_a[7];
    std::memcpy(bad_a, a, sizeof a);
    bad_a[0] = nan;
    KEXPECT_TRUE(same_wrench(kKinds[k].fn(p, s, bad, bad_a), good));
    KEXPECT_EQ(s.step_faults, static_cast<std::uint32_t>(kFaultNonFiniteState | kFaultNonFiniteCommand));
  }
}

KTEST(LeeController, OutOfRangeCommandIsClippedAndFlagged) {
  for (std::size_t k = 0; k < sizeof(kKinds) / sizeof(kKinds[0]); ++k) {
    const LeeParams p = params_for(k);
    LeeState s_clip, s_edge;
    lee_reset(p, s_clip);
    lee_reset(p, s_edge);
    RigidBodyState body;
    body.orientation_wb = quat_from_euler_xyz(0.1_r, -0.2_r, 0.3_r);
    body.angvel_b = Vec3(0.1_r, 0.2_r, -0.3_r);
    real a[7];
    hover_action(k, body.position_w, a);
    real edge[7];
    a[0] = 25;
    a[2] = -1e6_r;
    std::memcpy(edge, a, sizeof a);
    edge[0] = 10;
    edge[2] = -10;
    real a_copy[7];
    std::memcpy(a_copy, a, sizeof a);
    Wrench w_clip, w_edge;
    KEXPECT_NO_HEAP(w_clip = kKinds[k].fn(p, s_clip, body, a));
    w_edge = kKinds[k].fn(p, s_edge, body, edge);
    KEXPECT_TRUE(same_wrench(w_clip, w_edge));  // identical to the command at the clip bounds
    KEXPECT_EQ(s_clip.step_faults & kFaultCommandOutOfRange, static_cast<std::uint32_t>(kFaultCommandOutOfRange));
    KEXPECT_EQ(s_edge.step_faults & kFaultCommandOutOfRange, 0u);
    KEXPECT_EQ(std::memcmp(a, a_copy, sizeof a), 0);  // the caller's array is not clipped in place
    KEXPECT_TRUE(wrench_finite(w_clip));
    // Latched until reset, per-step bits cleared by the next clean update.
    (void)kKinds[k].fn(p, s_clip, body, edge);
    KEXPECT_EQ(s_clip.step_faults & kFaultCommandOutOfRange, 0u);
    KEXPECT_TRUE(s_clip.faults.has(kFaultCommandOutOfRange));
  }
}

KTEST(LeeController, DegenerateDesiredAttitudeFallsBackWithoutNaN) {
  LeeParams p = lee_params_base_quadrotor();
  p.gain_ranges = LeeGainRanges();
  p.gain_ranges.min.k_pos = p.gain_ranges.max.k_pos = Vec3(1, 1, 1);
  p.gain_ranges.min.k_vel = p.gain_ranges.max.k_vel = Vec3(1, 1, 1);
  p.gain_ranges.min.k_rot = p.gain_ranges.max.k_rot = Vec3(1, 1, 0.5_r);
  p.gain_ranges.min.k_angvel = p.gain_ranges.max.k_angvel = Vec3(0.15_r, 0.15_r, 0.15_r);
  LeeState s;
  lee_reset(p, s);
  RigidBodyState body;
  body.position_w = Vec3(0, 0, kStandardGravity);
  // Zero collective force: a = K_pos (0 - p) = -g exactly, so F = m (a - g) = 0.
  {
    const real a[4] = {0, 0, 0, 0.4_r};
    Wrench w;
    KEXPECT_NO_HEAP(w = update_lee_position(p, s, body, a));
    KEXPECT_TRUE(wrench_finite(w));
    KEXPECT_TRUE(state_finite(s));
    KEXPECT_TRUE(s.step_faults & kFaultSingular);
    KEXPECT_EQ(w.force_b[2], 0);
    // Fallback keeps the current thrust axis (body z) and the commanded heading.
    const Mat3 r_d = quat_from_xyzw(s.desired_quat_xyzw).toRotationMatrix();
    KEXPECT_NEAR(r_d(2, 2), 1, 1e-6);
  }
  // Force along the commanded heading (world +x, yaw 0): b3 x heading = 0. Body x is along b3
  // too (identity attitude), so the second fallback (-body z) is used.
  {
    const real a[4] = {1, 0, 0, 0};
    Wrench w;
    KEXPECT_NO_HEAP(w = update_lee_position(p, s, body, a));
    KEXPECT_TRUE(wrench_finite(w));
    KEXPECT_TRUE(state_finite(s));
    KEXPECT_TRUE(s.step_faults & kFaultSingular);
    const Mat3 r_d = quat_from_xyzw(s.desired_quat_xyzw).toRotationMatrix();
    KEXPECT_NEAR(r_d(0, 2), 1, 1e-6);   // b3 along +x
    KEXPECT_NEAR(r_d(2, 0), -1, 1e-6);  // b1 = -z: the minimal rotation (about body y)
    KEXPECT_NEAR(std::fabs(r_d.determinant()), 1, 1e-5);
  }
  // Near (not exactly) degenerate stays on the normal path.
  {
    const real a[4] = {1, 0, 0.01_r, 0};
    (void)update_lee_position(p, s, body, a);
    KEXPECT_EQ(s.step_faults & kFaultSingular, 0u);
  }
  // Velocity and steering controllers with zero force.
  {
    RigidBodyState b2;
    b2.linvel_w = Vec3(0, 0, kStandardGravity);  // a = K_vel (0 - v) = -g
    const real a[4] = {0, 0, 0, 0};
    KEXPECT_TRUE(wrench_finite(update_lee_velocity(p, s, b2, a)));
    KEXPECT_TRUE(s.step_faults & kFaultSingular);
    KEXPECT_TRUE(wrench_finite(update_lee_velocity_steering_angle(p, s, b2, a)));
    KEXPECT_TRUE(s.step_faults & kFaultSingular);
    KEXPECT_TRUE(state_finite(s));
  }
  // Acceleration controller: a = g gives F = 0; the reference's atan2(0, 0) = 0 gives a level
  // attitude at the current yaw.
  {
    RigidBodyState b3;
    b3.orientation_wb = quat_from_euler_xyz(0.2_r, 0.1_r, 1.0_r);
    const real a[4] = {0, 0, -kStandardGravity, 0};
    Wrench w;
    KEXPECT_NO_HEAP(w = update_lee_acceleration(p, s, b3, a));
    KEXPECT_TRUE(wrench_finite(w));
    KEXPECT_TRUE(s.step_faults & kFaultSingular);
    const Vec3 e = euler_xyz(quat_from_xyzw(s.desired_quat_xyzw));
    KEXPECT_NEAR(e[0], 0, 1e-6);
    KEXPECT_NEAR(e[1], 0, 1e-6);
    KEXPECT_NEAR(e[2], 1.0, 1e-5);
  }
  // ROV: a zero command quaternion -> identity, as the reference's eps-clamped normalisation.
  {
    LeeParams rp = lee_params_rov();
    LeeState rs;
    lee_reset(rp, rs);
    RigidBodyState b4;
    b4.orientation_wb = quat_from_euler_xyz(0.3_r, 0, 0);
    const real a[7] = {0, 0, 0, 0, 0, 0, 0};
    Wrench w;
    KEXPECT_NO_HEAP(w = update_rov_fully_actuated(rp, rs, b4, a));
    KEXPECT_TRUE(wrench_finite(w));
    KEXPECT_TRUE(rs.step_faults & kFaultSingular);
    KEXPECT_TRUE(rs.desired_quat_xyzw == Vec4(0, 0, 0, 1));
    KEXPECT_LT(w.torque_b[0], 0);  // rolls back toward level
  }
}

KTEST(LeeRates, ThrustConventionDiffersFromCrashingReference) {
  // The reference's lee_rates_control raises on every call (golden status "crashes", quirk 1).
  // For a single environment its thrust line would have computed m (command + 9.81): the command
  // as a vertical acceleration offset. Kestrel uses the attitude controller's convention instead,
  // fz = (command + 1) m |g|, so "0 = hover" holds for both thrust-commanding controllers.
  const LeeParams p = lee_params_base_quadrotor();
  LeeState s;
  lee_reset(p, s);
  RigidBodyState body;
  body.orientation_wb = quat_from_euler_xyz(0.3_r, 0.2_r, 0);  // tilt: not compensated
  real a[4] = {0.5_r, 0.1_r, -0.2_r, 2.0_r};  // r = 2 rad/s > max_yaw_rate = pi/3
  Wrench w;
  KEXPECT_NO_HEAP(w = update_lee_rates(p, s, body, a));
  const double m = static_cast<double>(p.mass_kg), g = static_cast<double>(kStandardGravity);
  KEXPECT_NEAR(w.force_b[2], 1.5 * m * g, 1e-5);
  KEXPECT_GT(std::fabs(static_cast<double>(w.force_b[2]) - m * (0.5 + g)), 1.0);  // not the reference's would-be value
  KEXPECT_EQ(w.force_b[0], 0);
  KEXPECT_EQ(w.force_b[1], 0);
  // Same thrust as lee_attitude for the same thrust command.
  LeeState s_att;
  lee_reset(p, s_att);
  const real att[4] = {0.5_r, 0, 0, 0};
  KEXPECT_EQ(update_lee_attitude(p, s_att, body, att).force_b[2], w.force_b[2]);
  // The body-z rate is clamped on a copy (quirk 2 not reproduced): the caller's action keeps 2.0.
  KEXPECT_EQ(a[3], 2.0_r);
  KEXPECT_EQ(s.desired_angvel_b[2], p.max_yaw_rate_radps);
  KEXPECT_EQ(s.desired_angvel_b[0], 0.1_r);
  // At rest, the torque is the pure rate term: -k_w (0 - w_d).
  const real kw = s.gains.k_angvel[2];
  KEXPECT_NEAR(w.torque_b[2], static_cast<double>(kw * p.max_yaw_rate_radps), 1e-7);
  KEXPECT_NEAR(w.torque_b[0], static_cast<double>(kw * 0.1_r), 1e-7);
  // Hover thrust at command 0.
  const real hover[4] = {0, 0, 0, 0};
  KEXPECT_NEAR(update_lee_rates(p, s, body, hover).force_b[2], m * g, 1e-5);
}

KTEST(LeeController, AccelerationControllerReproducesFrameQuirk) {
  // Quirk 4, recorded in the golden data and kept: at yaw 90 deg a world +x acceleration command
  // tilts the desired thrust axis toward world +y.
  const LeeParams p = lee_params_base_quadrotor();
  LeeState s;
  lee_reset(p, s);
  RigidBodyState body;
  body.orientation_wb = quat_from_euler_xyz(0, 0, kPi / 2);
  const real a[4] = {2, 0, 0, 0};
  KEXPECT_NO_HEAP((void)update_lee_acceleration(p, s, body, a));
  const Mat3 r_d = quat_from_xyzw(s.desired_quat_xyzw).toRotationMatrix();
  KEXPECT_NEAR(r_d(0, 2), 0, 1e-6);
  KEXPECT_GT(r_d(1, 2), 0.15);
  KEXPECT_TRUE(s.accel_command_w == Vec3(2, 0, 0));
}

KTEST(LeeController, GainRandomisationIsReproducibleAndInRange) {
  const LeeGainRanges r = lee_gain_ranges_default();
  RngStream a(1234, 7, kPurposeGains), b(1234, 7, kPurposeGains), c(1234, 8, kPurposeGains);
  LeeGains ga, gb, gc;
  KEXPECT_NO_HEAP(ga = randomize_lee_gains(r, a));
  gb = randomize_lee_gains(r, b);
  gc = randomize_lee_gains(r, c);
  KEXPECT_TRUE(ga.k_pos == gb.k_pos && ga.k_vel == gb.k_vel && ga.k_rot == gb.k_rot && ga.k_angvel == gb.k_angvel);
  KEXPECT_TRUE(ga.k_pos != gc.k_pos);
  KEXPECT_TRUE(ga.k_angvel != gc.k_angvel);
  // Many instances: every component inside [min, max], and the draws fill the range.
  real lo_seen = 10, hi_seen = 0;
  for (std::uint32_t inst = 0; inst < 200; ++inst) {
    RngStream rng(99, inst, kPurposeGains);
    const LeeGains g = randomize_lee_gains(r, rng);
    const PlainVec3* v[4] = {&g.k_pos, &g.k_vel, &g.k_rot, &g.k_angvel};
    const PlainVec3* mn[4] = {&r.min.k_pos, &r.min.k_vel, &r.min.k_rot, &r.min.k_angvel};
    const PlainVec3* mx[4] = {&r.max.k_pos, &r.max.k_vel, &r.max.k_rot, &r.max.k_angvel};
    for (int i = 0; i < 4; ++i) {
      for (int k = 0; k < 3; ++k) {
        KEXPECT_GE((*v[i])[k], (*mn[i])[k]);
        KEXPECT_LE((*v[i])[k], (*mx[i])[k]);
      }
    }
    lo_seen = g.k_pos[0] < lo_seen ? g.k_pos[0] : lo_seen;
    hi_seen = g.k_pos[0] > hi_seen ? g.k_pos[0] : hi_seen;
  }
  KEXPECT_LT(lo_seen, 2.05_r);
  KEXPECT_GT(hi_seen, 2.95_r);
  // Midpoints are the golden (unrandomised) gains, bit for bit in float.
  const LeeGains n = lee_nominal_gains(r);
  KEXPECT_TRUE(n.k_pos == Vec3(2.5_r, 2.5_r, 1.5_r));
  KEXPECT_TRUE(n.k_vel == Vec3(2.5_r, 2.5_r, 2.5_r));
  KEXPECT_TRUE(n.k_rot == Vec3(1.0_r, 1.0_r, 0.5_r));
  KEXPECT_NEAR(n.k_angvel[0], 0.15, 1e-7);
}

KTEST(LeeController, ResetDrawsGainsOnlyWhenConfigured) {
  LeeParams p = lee_params_base_quadrotor();  // randomize_gains = false, as Aerial Gym's config
  LeeState s;
  RngStream rng(5, 0, kPurposeGains);
  const std::uint64_t start = rng.position();
  KEXPECT_NO_HEAP(lee_reset(p, s, rng));
  KEXPECT_TRUE(s.gains.k_pos == lee_nominal_gains(p.gain_ranges).k_pos);
  KEXPECT_EQ(rng.position(), start);  // nothing drawn
  p.randomize_gains = true;
  lee_reset(p, s, rng);
  KEXPECT_TRUE(s.gains.k_pos != lee_nominal_gains(p.gain_ranges).k_pos);
  KEXPECT_GT(rng.position(), start);
  // The ROV preset randomises, but its only non-degenerate range is k_angvel.
  const LeeParams rov = lee_params_rov();
  KEXPECT_TRUE(rov.randomize_gains);
  RngStream r2(5, 1, kPurposeGains);
  lee_reset(rov, s, r2);
  KEXPECT_TRUE(s.gains.k_vel == Vec3(8, 8, 8));
  KEXPECT_GE(s.gains.k_angvel[0], 2.1_r);
  KEXPECT_LE(s.gains.k_angvel[0], 2.2_r);
}

KTEST(LeeController, ClosedLoopPositionConvergesToSetpoint) {
  const LeeParams p = lee_params_base_quadrotor();
  LeeState s;
  lee_reset(p, s);
  RigidBodyParams bp;
  bp.mass_kg = p.mass_kg;
  bp.inertia_b = p.inertia_b.map();
  bp.gravity_w = p.gravity_w.map();
  bp.integrator = Integrator::rk4;
  RigidBodyModel model;
  KASSERT_TRUE(make_rigid_body_model(bp, model) == Status::ok);
  RigidBodyState body;
  const Vec3 target(0.6_r, -0.48_r, 0.64_r);  // 1 m away
  const real yaw_sp = 0.5_r;
  const real a[4] = {target[0], target[1], target[2], yaw_sp};
  const real dt = 0.002_r;
  double max_tilt_cos_min = 1;
  bool all_ok = true;
  for (int i = 0; i < 2500; ++i) {  // 5 s
    Wrench w;
    KEXPECT_NO_HEAP(w = update_lee_position(p, s, body, a));
    const Status st = step_rigid_body(model, body, w, dt);
    all_ok = all_ok && s.step_faults == 0 && wrench_finite(w) && st == Status::ok;
    const double cz = static_cast<double>(body.orientation_wb.toRotationMatrix()(2, 2));
    max_tilt_cos_min = cz < max_tilt_cos_min ? cz : max_tilt_cos_min;
  }
  KEXPECT_TRUE(all_ok);
  KEXPECT_LT((body.position_w - target).norm(), 0.03);
  KEXPECT_LT(body.linvel_w.norm(), 0.05);
  KEXPECT_LT(body.angvel_b.norm(), 0.05);
  KEXPECT_NEAR(euler_xyz(body.orientation_wb)[2], yaw_sp, 0.01);
  KEXPECT_GT(max_tilt_cos_min, 0.5);  // never tilted past 60 deg on the way
}

KTEST(LeeController, ClosedLoopVelocityAndAttitudeStayBounded) {
  // Velocity control in the vehicle frame converges to the commanded world velocity.
  const LeeParams p = lee_params_base_quadrotor();
  LeeState s;
  lee_reset(p, s);
  RigidBodyParams bp;
  RigidBodyModel model;
  KASSERT_TRUE(make_rigid_body_model(bp, model) == Status::ok);
  RigidBodyState body;
  body.orientation_wb = quat_from_euler_xyz(0, 0, kPi / 2);  // vehicle x = world y
  const real a[4] = {1, 0, 0.2_r, 0};
  for (int i = 0; i < 2000; ++i) {
    Wrench w;
    KEXPECT_NO_HEAP(w = update_lee_velocity(p, s, body, a));
    (void)step_rigid_body(model, body, w, 0.002_r);
  }
  KEXPECT_NEAR(body.linvel_w[0], 0, 0.02);
  KEXPECT_NEAR(body.linvel_w[1], 1, 0.02);
  KEXPECT_NEAR(body.linvel_w[2], 0.2, 0.02);
}

KTEST(LeeController, PositionFlagsEveryNonFiniteStateComponent) {
  // update_lee_position checks the state through its output probe only (lee.cpp): every one of
  // the 13 state values, as NaN, +inf or -inf, must still be named kFaultNonFiniteState and leave
  // the state untouched, also with zero gains (0 * inf must not hide one).
  const real bad_values[3] = {std::numeric_limits<real>::quiet_NaN(), std::numeric_limits<real>::infinity(),
                              -std::numeric_limits<real>::infinity()};
  for (int zero_gains = 0; zero_gains < 2; ++zero_gains) {
    const LeeParams p = lee_params_base_quadrotor();
    LeeState s;
    lee_reset(p, s);
    if (zero_gains != 0) s.gains = LeeGains();
    RigidBodyState body;
    body.orientation_wb = quat_from_euler_xyz(0.1_r, -0.2_r, 0.3_r);
    const real a[4] = {0.5_r, -0.3_r, 1, 0.4_r};
    const Wrench good = update_lee_position(p, s, body, a);
    KEXPECT_EQ(s.step_faults, 0u);
    const LeeState before = s;
    for (int field = 0; field < 13; ++field) {
      for (real v : bad_values) {
        RigidBodyState bad = body;
        if (field < 3) bad.position_w[field] = v;
        else if (field < 6) bad.linvel_w[field - 3] = v;
        else if (field < 9) bad.angvel_b[field - 6] = v;
        else bad.orientation_wb.coeffs()[field - 9] = v;
        const Wrench w = update_lee_position(p, s, bad, a);
        KEXPECT_TRUE(same_wrench(w, good));
        KEXPECT_EQ(s.step_faults, static_cast<std::uint32_t>(kFaultNonFiniteState));
        KEXPECT_TRUE(state_finite(s));
        KEXPECT_TRUE(s.accel_command_w == before.accel_command_w);
        KEXPECT_TRUE(s.desired_quat_xyzw == before.desired_quat_xyzw);
      }
    }
  }
}

KTEST(LeeController, DiagonalInertiaFastPathGivesTheSameBits) {
  // lee_reset flags a diagonal inertia; the 3-product gyroscopic term must equal the full one.
  const LeeParams p = lee_params_base_quadrotor();
  LeeState fast, full;
  lee_reset(p, fast);
  lee_reset(p, full);
  KEXPECT_TRUE(fast.inertia_diagonal);
  full.inertia_diagonal = false;
  RigidBodyState body;
  body.orientation_wb = quat_from_euler_xyz(0.2_r, 0.1_r, -0.4_r);
  body.angvel_b = Vec3(1.5_r, -2.0_r, 0.7_r);
  const real a[4] = {0.2_r, 0.1_r, 1.5_r, 0.3_r};
  const Wrench wf = update_lee_position(p, fast, body, a);
  const Wrench wg = update_lee_position(p, full, body, a);
  KEXPECT_TRUE(same_wrench(wf, wg));
  LeeParams q = p;
  q.inertia_b(0, 1) = q.inertia_b(1, 0) = 1e-5_r;
  LeeState t;
  lee_reset(q, t);
  KEXPECT_FALSE(t.inertia_diagonal);
}
