#include "policy_loop.hpp"

#include <cmath>
#include <cstring>

#include "kestrel/kernel/math.hpp"
#include "kestrel/platform/console.hpp"
#include "kestrel/policy/mlp.hpp"
#include "kestrel/policy/observations.hpp"
#include "position_policy.hpp"

namespace kestrel::firmware {

namespace {

using policy::generated::kPositionPolicy;
static_assert(policy::generated::kPositionPolicyType::obs_dim == policy::kPositionSetpointObsDim,
              "the exported policy must read the position-setpoint observation");
static_assert(policy::generated::kPositionPolicyType::action_dim == 4, "Lee velocity takes 4 values");

constexpr real kTaskActionClip = 10;  // position_setpoint_task clips actions to +-10 (sim/src/tasks/task.cpp)
// (The exported network already maps its tanh output to +-2 m/s and +-1 rad/s, the env's action_scale.)
constexpr real kSuccessRadius_m = 0.3_r;  // the task's success radius

// Starts the plant hovering at the first waypoint: the policy was trained on starts in the air.
void hover_at(const FlightConfig& c, FlightStack& s, Plant& p) {
  p.state = RigidBodyState();
  p.state.position_w = Vec3(c.waypoints[0].position_w[0], c.waypoints[0].position_w[1], c.waypoints[0].position_w[2]);
  real hover[allocation::kMaxRotors] = {};
  const int n = s.model.airframe.num_rotors;
  for (int i = 0; i < n; ++i) hover[i] = s.model.ctrl.lee.mass_kg * kStandardGravity / static_cast<real>(n);
  RngStream rng(1, 0, kPurposeMotors);
  (void)robots::multirotor_reset(s.model, s.state, nullptr, rng, hover);
}

constexpr std::uint64_t kFnvOffset = 1469598103934665603ull;
constexpr std::uint64_t kFnvPrime = 1099511628211ull;

// FNV-1a over the object representation of each state component (memcpy: no type punning), in a
// fixed order, so equal hashes mean every bit of every step's state was equal.
std::uint64_t hash_state(std::uint64_t h, const RigidBodyState& st) {
  real v[13];
  for (int i = 0; i < 3; ++i) {
    v[i] = st.position_w[i];
    v[7 + i] = st.linvel_w[i];
    v[10 + i] = st.angvel_b[i];
  }
  for (int i = 0; i < 4; ++i) v[3 + i] = st.orientation_wb.coeffs()[i];  // Eigen stores xyzw
  unsigned char b[sizeof v];
  std::memcpy(b, v, sizeof v);
  for (const unsigned char c : b) {
    h ^= c;
    h *= kFnvPrime;
  }
  return h;
}

}  // namespace

Status fly_policy(const FlightConfig& c, FlightStack& s, Plant& p, ClockFn clock, WaitFn wait, PolicyFlightReport& r) {
  if (const Status st = flight_init(s, p); st != Status::ok) return st;
  // kPositionPolicy is checked when it is compiled (position_policy.hpp's static_assert on the
  // constexpr validate_mlp): nothing to check, and no checking code in flash, at start-up.
  r = PolicyFlightReport();
  const real dt = 1 / c.control_rate_hz;
  const int steps = static_cast<int>(c.duration_s * c.control_rate_hz + 0.5_r);
  const Waypoint& goal = c.waypoints[c.num_waypoints > 1 ? 1 : 0];
  const Vec3 target_w(goal.position_w[0], goal.position_w[1], goal.position_w[2]);
  const real hold_start = c.duration_s - c.hold_window_s;

  // Two flights over the same course: 0 = the policy, 1 = the Lee position controller.
  for (int pass = 0; pass < 2; ++pass) {
    hover_at(c, s, p);
    real action[4] = {0, 0, 0, 0};
    real sum_sq = 0;
    int count = 0;
    real e = 0;
    std::uint64_t hash = kFnvOffset;
    for (int k = 0; k < steps; ++k) {
      if (wait != nullptr) wait();
      const real t = static_cast<real>(k) * dt;
      if (pass == 0) {
        const std::uint64_t t0 = clock();
        float obs_f[policy::kPositionSetpointObsDim];
        policy::position_setpoint_observation_vehicle_frame(p.state, target_w, obs_f);
        real obs_buf[policy::kPositionSetpointObsDim];
        const real* obs = policy::observation_as_real(obs_f, obs_buf, policy::kPositionSetpointObsDim);
        real a[4];
        if (policy::mlp_forward(kPositionPolicy, obs, a) == Status::ok) {
          // The task's clip, as the simulator applies it; left out where the network cannot
          // exceed it (checked at compile time: its squash and scale bound every action).
          if constexpr (policy::actions_within(kPositionPolicy, kTaskActionClip)) {
            for (int i = 0; i < 4; ++i) action[i] = a[i];
          } else {
            for (int i = 0; i < 4; ++i) action[i] = clamp(a[i], -kTaskActionClip, kTaskActionClip);
          }
        } else {
          ++r.rejected_inferences;  // hold the last action
        }
        const std::uint64_t t1 = clock();
        (void)robots::multirotor_control(s.model, ControllerKind::lee_velocity, s.state, p.state, action, 4,
                                         s.out.command);
        (void)robots::multirotor_actuate(s.model, s.state, dt, s.out);
        const std::uint64_t t2 = clock();
        r.policy_cost_total += t1 - t0;
        r.control_cost_total += t2 - t1;
      } else {
        const real command[4] = {goal.position_w[0], goal.position_w[1], goal.position_w[2], 0};
        control_step(s, p.state, command, dt);
      }
      plant_step(s, p, dt);
      hash = hash_state(hash, p.state);
      e = (target_w - p.state.position_w).norm();
      if (!is_finite(e)) r.finite = false;
      if (t + dt > hold_start) {
        sum_sq += e * e;
        ++count;
      }
    }
    const real rms = count > 0 ? std::sqrt(sum_sq / static_cast<real>(count)) : 0;
    if (pass == 0) {
      r.steps = steps;
      r.hold_rms_error_m = rms;
      r.final_error_m = e;
      r.faults = robots::multirotor_faults(s.state);
      r.policy_trajectory_hash = hash;
    } else {
      r.lee_hold_rms_error_m = rms;
      r.lee_final_error_m = e;
      r.lee_trajectory_hash = hash;
    }
  }
  return Status::ok;
}

bool policy_flight_pass(const PolicyFlightReport& r) {
  return r.finite && r.rejected_inferences == 0 && r.final_error_m < kSuccessRadius_m;
}

void print_policy_report(const PolicyFlightReport& r, const char* target, const char* cost_unit, double cost_scale) {
  using namespace kestrel::platform;
  print("kestrel firmware policy example [");
  print(target);
  println("]: trained position policy (MLP) -> Lee velocity -> sequential desaturation -> motor model -> rigid body");
  print("  ");
  print_int(r.steps);
  println(" steps at 500 Hz from a hover at the first waypoint to the second");
  print("  policy:  hold error RMS ");
  print_fixed(static_cast<double>(r.hold_rms_error_m) * 1000, 2);
  print(" mm, final error ");
  print_fixed(static_cast<double>(r.final_error_m) * 1000, 2);
  print(" mm, rejected inferences ");
  print_int(r.rejected_inferences);
  println("");
  print("  Lee position controller over the same course: hold error RMS ");
  print_fixed(static_cast<double>(r.lee_hold_rms_error_m) * 1000, 2);
  print(" mm, final error ");
  print_fixed(static_cast<double>(r.lee_final_error_m) * 1000, 2);
  println(" mm");
  print("  cost per step: observation + policy network ");
  print_fixed(static_cast<double>(r.policy_cost_total) * cost_scale / r.steps, 1);
  print(" ");
  print(cost_unit);
  print(", chain after it ");
  print_fixed(static_cast<double>(r.control_cost_total) * cost_scale / r.steps, 1);
  print(" ");
  println(cost_unit);
  // One line, same format on every target: the parity ctest compares it between host and MCU.
  print("  trajectory hash (FNV-1a over the plant state bits of every step): policy ");
  print_uint(r.policy_trajectory_hash);
  print(", Lee ");
  print_uint(r.lee_trajectory_hash);
  println("");
}

}  // namespace kestrel::firmware
