// Host micro-benchmarks (Google Benchmark) of the functions the MCU bench counts instructions for
// (bench/control/mcu/control_bench.cpp): every controller kind through update_controller, joint PD,
// the pseudo-inverse and the allocators, the motor model, wrench_from_thrusts, the rigid-body step
// (both integrators), the whole cascade of the firmware example (platform/firmware: the same
// control_step, not a copy) and its C API form, and the 8x8 ToF scan (VL53L5CX preset) of a small
// fixed scene.
//
// Batched: every benchmark runs over N independent lanes (N = 1, 64, 4096; Google Benchmark's
// "batch" argument). A lane is what one vehicle owns (controller / allocator / motor state, its
// output); one benchmark iteration calls the function once per lane, so items/s is calls/s and cpu
// time / N is the cost of one call when N lanes' state must be streamed through the caches
// (lane_bytes and working_set_kib are reported with each row).
//
// Inputs: drawn from fixed Philox streams (RngStream(kSeed, input index, purpose)), realistic for a
// flying vehicle (near-hover states, setpoints within a metre, wrenches of the right class). They
// live in a ring of N + 63 entries walked call after call, so no two consecutive calls (and, for
// N > 1, no lane on two consecutive sweeps) see the same input: the branch predictor cannot replay
// a single input, and nothing can be constant-folded (the core is in separate static libraries;
// outputs are stored in the lanes, statuses go through DoNotOptimize, and each sweep ends with
// ClobberMemory). Input j is the same for every N, so the rings of N = 1 and N = 64 are prefixes of
// the N = 4096 one.
//
// Before any timing, main() runs every benchmark's self-check (64 lanes, 2 to 1200 sweeps): outputs
// finite, statuses as expected, the "saturated" wrench class really saturates and the "feasible"
// class does not, the ToF sees both hits and misses, the rigid body stays finite across its
// periodic reset. A failed check exits 1 (the ctest smoke run relies on it). Timings are never
// asserted.
//
// Usage: kestrel_bench_micro [--check-only] [Google Benchmark flags]; bench/micro/run.sh writes
// bench/results/host/micro.csv and re-renders bench/results/report.md.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "flight_loop.hpp"
#include "kestrel/allocation/allocation.hpp"
#include "kestrel/controllers/controller.hpp"
#include "kestrel/controllers/joint_pd.hpp"
#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/kernel/rigid_body.hpp"
#include "kestrel/kernel/rng.hpp"
#include "kestrel/kestrel.h"
#include "kestrel/sensors/ray_sensor.hpp"
#include "kestrel/sensors/scene.hpp"

using namespace kestrel;
namespace al = kestrel::allocation;
namespace se = kestrel::sensors;

namespace {

constexpr std::uint64_t kSeed = 6;      // issue 6
constexpr std::size_t kRingSlack = 63;  // input ring = batch + 63 (see the file comment)
constexpr real kDt = 0.002_r;           // 500 Hz, the firmware example's control rate

// Purposes of the input streams (one per kind of input; the index of the input is the stream id).
enum : std::uint32_t {
  kPurposeBody = kPurposeUser + 1,
  kPurposeAction,
  kPurposeWrench,
  kPurposeThrust,
  kPurposeAirframe,
  kPurposeJoints,
  kPurposeLaneGains,
};

RngStream input_stream(std::size_t index, std::uint32_t purpose) {
  return RngStream(kSeed, static_cast<std::uint32_t>(index), purpose);
}

real sym(RngStream& r, real half) { return r.uniform(-half, half); }

/// A state a flying multirotor sees: within a few metres of the origin, tilted up to 20 deg, any
/// heading, moving up to 1.5 m/s and turning up to 1 rad/s on each axis.
RigidBodyState draw_body(RngStream& r) {
  RigidBodyState b;
  b.position_w = Vec3(sym(r, 2), sym(r, 2), r.uniform(0.5_r, 2.5_r));
  const real roll = sym(r, 0.35_r), pitch = sym(r, 0.35_r), yaw = sym(r, kPi);
  b.orientation_wb = quat_from_euler_xyz(roll, pitch, yaw);
  b.linvel_w = Vec3(sym(r, 1.5_r), sym(r, 1.5_r), sym(r, 1.5_r));
  b.angvel_b = Vec3(sym(r, 1), sym(r, 1), sym(r, 1));
  return b;
}

bool finite_body(const RigidBodyState& b) {
  return b.position_w.allFinite() && b.orientation_wb.coeffs().allFinite() && b.linvel_w.allFinite() &&
         b.angvel_b.allFinite();
}

/// The airframe with each rotor hub moved by up to +-5 mm (build tolerance): distinct matrices, so
/// the pseudo-inverse never sees the same input twice in a row.
al::Airframe perturbed_airframe(const al::AirframeSpec& spec, std::size_t index) {
  RngStream r = input_stream(index, kPurposeAirframe);
  al::AirframeSpec s = spec;
  for (int i = 0; i < s.num_rotors; ++i)
    for (int a = 0; a < 2; ++a) s.rotors[i].position_b_m[a] += sym(r, 0.005_r);
  al::Airframe out;
  if (al::make_airframe(s, out) != Status::ok) std::fprintf(stderr, "bench_micro: make_airframe failed\n");
  return out;
}

std::string fail(const std::string& what, std::size_t lane) { return what + " (lane " + std::to_string(lane) + ")"; }

// ------------------------------------------------------------------------------------------------
// The batched runner. D provides: lanes (std::vector<Lane>), inputs (std::vector<Input>), void
// call(Lane&, const Input&), optionally reset_lanes() every D::kResetEvery sweeps (0: never), and
// std::string check() (empty = fine) that looks at the lanes after some sweeps.
template <class D>
struct Batched {
  std::size_t sweeps_done = 0;

  // One sweep: each lane once, inputs walked along the ring from position k.
  void sweep(std::size_t& k) {
    D& d = static_cast<D&>(*this);
    const std::size_t n = d.lanes.size(), m = d.inputs.size();
    for (std::size_t i = 0; i < n; ++i) {
      d.call(d.lanes[i], d.inputs[k]);
      if (++k == m) k = 0;
    }
    if (D::kResetEvery > 0 && ++sweeps_done == static_cast<std::size_t>(D::kResetEvery)) {
      d.reset_lanes();
      sweeps_done = 0;
    }
  }

  void run(benchmark::State& st) {
    D& d = static_cast<D&>(*this);
    std::size_t k = 0;
    for (auto _ : st) {
      sweep(k);
      benchmark::ClobberMemory();
    }
    const std::size_t n = d.lanes.size();
    st.SetItemsProcessed(static_cast<std::int64_t>(st.iterations()) * static_cast<std::int64_t>(n));
    const double lane_bytes = static_cast<double>(sizeof(typename decltype(d.lanes)::value_type) +
                                                  sizeof(typename decltype(d.inputs)::value_type));
    st.counters["lane_bytes"] = lane_bytes;
    st.counters["working_set_kib"] =
        (lane_bytes * static_cast<double>(n) +
         static_cast<double>(sizeof(typename decltype(d.inputs)::value_type) * kRingSlack)) /
        1024.0;
  }

  std::string self_check(int sweeps) {
    std::size_t k = 0;
    for (int s = 0; s < sweeps; ++s) sweep(k);
    return static_cast<D&>(*this).check();
  }

  // Default: nothing accumulates without bound.
  static constexpr int kResetEvery = 0;
  void reset_lanes() {}
};

std::size_t ring(std::size_t batch) { return batch + kRingSlack; }

// ------------------------------------------------------------------------------------------------
// Controllers through the registry dispatch (update_controller), as the MCU bench and the sim call
// them. Each lane: its own state (gains drawn per lane, as the sim's per-env reset does) and
// output.
struct ControllerBench : Batched<ControllerBench> {
  struct Lane {
    ControllerState state;
    ControllerOutput out;
    Status status = Status::ok;
  };
  struct Input {
    RigidBodyState body;
    real action[kMaxActionDim];
  };
  ControllerKind kind;
  ControllerParams params;
  std::vector<Lane> lanes;
  std::vector<Input> inputs;

  ControllerBench(std::size_t batch, ControllerKind k) : kind(k), lanes(batch), inputs(ring(batch)) {
    params.lee = kind == ControllerKind::rov_fully_actuated ? lee_params_rov() : lee_params_base_quadrotor();
    params.motors = direct_motor_params(4, 0, 2);
    for (std::size_t i = 0; i < lanes.size(); ++i) {
      RngStream g(kSeed, static_cast<std::uint32_t>(i), kPurposeLaneGains);
      controller_reset(kind, params, lanes[i].state, g);
    }
    for (std::size_t j = 0; j < inputs.size(); ++j) {
      RngStream r = input_stream(j, kPurposeBody);
      Input& in = inputs[j];
      in.body = draw_body(r);
      RngStream a = input_stream(j, kPurposeAction);
      const Vec3 p = in.body.position_w;
      for (real& v : in.action) v = 0;
      switch (kind) {
        case ControllerKind::lee_position:  // setpoint within a metre, any heading
          in.action[0] = p[0] + sym(a, 1);
          in.action[1] = p[1] + sym(a, 1);
          in.action[2] = p[2] + sym(a, 0.5_r);
          in.action[3] = sym(a, kPi);
          break;
        case ControllerKind::lee_velocity:
        case ControllerKind::lee_velocity_steering_angle:
          in.action[0] = sym(a, 2);
          in.action[1] = sym(a, 2);
          in.action[2] = sym(a, 1);
          in.action[3] = kind == ControllerKind::lee_velocity ? sym(a, 1) : sym(a, kPi);
          break;
        case ControllerKind::lee_acceleration:
          in.action[0] = sym(a, 3);
          in.action[1] = sym(a, 3);
          in.action[2] = sym(a, 2);
          in.action[3] = sym(a, 1);
          break;
        case ControllerKind::lee_attitude:  // [thrust, roll, pitch, yaw_rate]
          in.action[0] = sym(a, 0.3_r);
          in.action[1] = sym(a, 0.4_r);
          in.action[2] = sym(a, 0.4_r);
          in.action[3] = sym(a, 1);
          break;
        case ControllerKind::lee_rates:  // [thrust, p, q, r]
          in.action[0] = sym(a, 0.3_r);
          in.action[1] = sym(a, 2);
          in.action[2] = sym(a, 2);
          in.action[3] = sym(a, 1);
          break;
        case ControllerKind::rov_fully_actuated: {  // pose within a metre, attitude within 30 deg
          in.action[0] = p[0] + sym(a, 1);
          in.action[1] = p[1] + sym(a, 1);
          in.action[2] = p[2] + sym(a, 1);
          const Quat q = quat_from_euler_xyz(sym(a, 0.5_r), sym(a, 0.5_r), sym(a, 0.5_r));
          in.action[3] = q.x();
          in.action[4] = q.y();
          in.action[5] = q.z();
          in.action[6] = q.w();
          break;
        }
        case ControllerKind::direct_motor:  // a policy's thrusts, sometimes just outside [0, 2] N
          for (int m = 0; m < 4; ++m) in.action[m] = a.uniform(-0.1_r, 2.1_r);
          break;
        case ControllerKind::velocity_steering:  // not a multirotor kind: register_all skips them
        case ControllerKind::joint_pd:
          break;
      }
    }
  }
  void call(Lane& l, const Input& in) {
    l.status = update_controller(kind, params, l.state, in.body, in.action, kMaxActionDim, l.out);
    benchmark::DoNotOptimize(l.status);
  }
  std::string check() {
    for (std::size_t i = 0; i < lanes.size(); ++i) {
      const Lane& l = lanes[i];
      if (l.status != Status::ok) return fail("status not ok", i);
      if (l.out.is_wrench != controller_outputs_wrench(kind)) return fail("output kind", i);
      if (l.out.is_wrench ? !(l.out.wrench_b.as_vec6().allFinite() && l.out.wrench_b.force_b.norm() > 0)
                          : !all_finite(l.out.motor_thrust_N, 4))
        return fail("output not finite / zero", i);
    }
    return {};
  }
};

// update_lee_position called directly (the MCU bench's row of the same name: no dispatch).
struct LeePositionBench : Batched<LeePositionBench> {
  struct Lane {
    LeeState state;
    Wrench out;
  };
  struct Input {
    RigidBodyState body;
    real command[4];
  };
  LeeParams params = lee_params_base_quadrotor();
  std::vector<Lane> lanes;
  std::vector<Input> inputs;
  explicit LeePositionBench(std::size_t batch) : lanes(batch), inputs(ring(batch)) {
    for (Lane& l : lanes) lee_reset(params, l.state);
    for (std::size_t j = 0; j < inputs.size(); ++j) {
      RngStream r = input_stream(j, kPurposeBody);
      inputs[j].body = draw_body(r);
      RngStream a = input_stream(j, kPurposeAction);
      const Vec3 p = inputs[j].body.position_w;
      const real c[4] = {p[0] + sym(a, 1), p[1] + sym(a, 1), p[2] + sym(a, 0.5_r), sym(a, kPi)};
      std::memcpy(inputs[j].command, c, sizeof c);
    }
  }
  void call(Lane& l, const Input& in) { l.out = update_lee_position(params, l.state, in.body, in.command); }
  std::string check() {
    for (std::size_t i = 0; i < lanes.size(); ++i)
      if (!lanes[i].out.as_vec6().allFinite() || !(lanes[i].out.force_b[2] > 0)) return fail("wrench", i);
    return {};
  }
};

// Joint PD (legged_gym's _compute_torques), ANYmal C flat-terrain configuration of legged_gym
// (anymal_c_flat_config.py: kp 80, kd 2, action scale 0.5, 0.005 s sim step; default pose HFE
// +-0.4, KFE -+0.8), 12 joints, torque limit 80 N m, one step of action delay.
struct JointPdBench : Batched<JointPdBench> {
  using Params = JointPdParams<12, 4>;
  using State = JointPdState<12, 4>;
  struct Lane {
    State state;
    real torque_Nm[12];
    Status status = Status::ok;
  };
  struct Input {
    real q_rad[12], qd_radps[12], action[12];
  };
  Params params;
  std::vector<Lane> lanes;
  std::vector<Input> inputs;
  explicit JointPdBench(std::size_t batch) : lanes(batch), inputs(ring(batch)) {
    params.num_joints = 12;
    params.mode = JointControlMode::position;
    const real default_pos[12] = {0, 0.4_r, -0.8_r, 0, -0.4_r, 0.8_r, 0, 0.4_r, -0.8_r, 0, -0.4_r, 0.8_r};
    for (int i = 0; i < 12; ++i) {
      params.kp[i] = 80;
      params.kd[i] = 2;
      params.default_pos_rad[i] = default_pos[i];
      params.torque_limit_Nm[i] = 80;
    }
    params.action_scale = 0.5_r;
    params.dt_s = 0.005_r;
    params.delay_steps = 1;
    for (Lane& l : lanes) joint_pd_reset(params, l.state);
    for (std::size_t j = 0; j < inputs.size(); ++j) {
      RngStream r = input_stream(j, kPurposeJoints);
      for (int i = 0; i < 12; ++i) {
        inputs[j].q_rad[i] = default_pos[i] + sym(r, 0.3_r);
        inputs[j].qd_radps[i] = sym(r, 3);
        inputs[j].action[i] = sym(r, 2);
      }
    }
  }
  void call(Lane& l, const Input& in) {
    l.status = update_joint_pd(params, l.state, in.q_rad, in.qd_radps, in.action, l.torque_Nm);
    benchmark::DoNotOptimize(l.status);
  }
  std::string check() {
    for (std::size_t i = 0; i < lanes.size(); ++i) {
      if (lanes[i].status != Status::ok || !all_finite(lanes[i].torque_Nm, 12)) return fail("torques", i);
      real sum = 0;
      for (real t : lanes[i].torque_Nm) sum += std::fabs(t);
      if (!(sum > 0)) return fail("all torques zero", i);
    }
    return {};
  }
};

// ------------------------------------------------------------------------------------------------
// Allocation. Wrench classes (as the MCU bench's fixed commands, here drawn around them):
//  saturated: collective near the maximum with roll/pitch torque: every desaturation pass runs;
//  feasible:  near hover with small torques: the fast path (no motor at a limit).
enum class WrenchClass { saturated, feasible };

Vec6 draw_wrench(WrenchClass c, const al::AirframeSpec& spec, RngStream& r) {
  const real mg = spec.mass_kg * kStandardGravity;
  Vec6 w;
  const bool hexa = spec.num_rotors == 6;
  if (c == WrenchClass::saturated) {
    const real sx = r.uniform() < 0.5_r ? -1 : 1, sy = r.uniform() < 0.5_r ? -1 : 1;
    // Quad (0.13 m arm offsets): roll torque >= 0.09 N m asks >= 0.17 N more of two motors that
    // already average >= 1.84 N of their 2 N: at least one motor always hits its maximum.
    w << 0, 0, r.uniform(0.92_r, 0.98_r) * spec.thrust_max_N * static_cast<real>(spec.num_rotors),
        sx * r.uniform(0.09_r, 0.15_r) * (hexa ? 10 : 1), sy * r.uniform(0.04_r, 0.08_r) * (hexa ? 10 : 1),
        sym(r, 0.02_r) * (hexa ? 10 : 1);
  } else {
    const real t = hexa ? 0.3_r : 0.004_r;
    w << 0, 0, r.uniform(0.8_r, 1.2_r) * mg, sym(r, t), sym(r, t), sym(r, 0.25_r * t);
  }
  return w;
}

struct AllocSetup {
  const al::AirframeSpec* spec;
  al::Airframe airframe;
  al::AllocationModel model;
  explicit AllocSetup(const al::AirframeSpec& s) : spec(&s) {
    if (al::make_airframe(s, airframe) != Status::ok) std::fprintf(stderr, "bench_micro: make_airframe failed\n");
    const Status st = al::build_allocation_model(airframe, model);  // flat frames: singular (rank 4), expected
    if (st != Status::ok && st != Status::singular) std::fprintf(stderr, "bench_micro: allocation model failed\n");
  }
};

enum class Allocator { pinv, sequential_desaturation, cls };

struct AllocateBench : Batched<AllocateBench>, AllocSetup {
  struct Lane {
    al::AllocatorState state;
    al::AllocationResult out;
    Status status = Status::ok;
  };
  using Input = Vec6;
  Allocator allocator;
  WrenchClass wclass;
  al::SequentialDesaturationParams desat;
  al::ClsParams cls;
  std::vector<Lane> lanes;
  std::vector<Input> inputs;
  AllocateBench(std::size_t batch, const al::AirframeSpec& s, Allocator a, WrenchClass c)
      : AllocSetup(s), allocator(a), wclass(c), lanes(batch), inputs(ring(batch)) {
    for (Lane& l : lanes) al::reset_allocator(l.state);
    for (std::size_t j = 0; j < inputs.size(); ++j) {
      RngStream r = input_stream(j, kPurposeWrench);
      inputs[j] = draw_wrench(c, s, r);
    }
  }
  void call(Lane& l, const Input& w) {
    switch (allocator) {
      case Allocator::pinv:
        l.status = al::allocate_pinv(model, l.state, w, l.out);
        break;
      case Allocator::sequential_desaturation:
        l.status = al::allocate_sequential_desaturation(model, desat, l.state, w, l.out);
        break;
      case Allocator::cls:
        l.status = al::allocate_cls(model, cls, l.state, w, l.out);
        break;
    }
    benchmark::DoNotOptimize(l.status);
  }
  std::string check() {
    for (std::size_t i = 0; i < lanes.size(); ++i) {
      const Lane& l = lanes[i];
      if (l.status != Status::ok) return fail("status not ok", i);
      if (!all_finite(l.out.thrust_N, model.num_rotors) || !l.out.wrench_realized.allFinite())
        return fail("thrusts", i);
    }
    // The class is a property of the command: the unconstrained thrusts A+ w leave some motor's
    // range for every saturated command and none for a feasible one.
    for (std::size_t j = 0; j < inputs.size(); ++j) {
      real f[al::kMaxRotors];
      al::apply_pinv(model, inputs[j], f);
      bool outside = false;
      for (int m = 0; m < model.num_rotors; ++m)
        outside = outside || f[m] > model.thrust_max_N[m] || f[m] < model.thrust_min_N[m];
      if (outside != (wclass == WrenchClass::saturated))
        return "input " + std::to_string(j) + " not of its wrench class";
    }
    return {};
  }
};

// f = A+ w alone (the reference's unclamped thrust).
struct ApplyPinvBench : Batched<ApplyPinvBench>, AllocSetup {
  struct Lane {
    real thrust_N[al::kMaxRotors];
  };
  using Input = Vec6;
  std::vector<Lane> lanes;
  std::vector<Input> inputs;
  ApplyPinvBench(std::size_t batch, const al::AirframeSpec& s) : AllocSetup(s), lanes(batch), inputs(ring(batch)) {
    for (std::size_t j = 0; j < inputs.size(); ++j) {
      RngStream r = input_stream(j, kPurposeWrench);
      inputs[j] = draw_wrench(WrenchClass::feasible, s, r);
    }
  }
  void call(Lane& l, const Input& w) { al::apply_pinv(model, w, l.thrust_N); }
  std::string check() {
    for (std::size_t i = 0; i < lanes.size(); ++i) {
      real sum = 0;
      for (int m = 0; m < model.num_rotors; ++m) sum += lanes[i].thrust_N[m];
      if (!all_finite(lanes[i].thrust_N, model.num_rotors) || !(sum > 0)) return fail("thrusts", i);
    }
    return {};
  }
};

// The one-time pseudo-inverse (Jacobi SVD) of the effectiveness matrix, and the whole model build.
struct PinvBench : Batched<PinvBench> {
  struct Lane {
    al::PinvMatrix pinv;
    Status status = Status::ok;
  };
  using Input = al::EffectivenessMatrix;
  int num_rotors;
  std::vector<Lane> lanes;
  std::vector<Input> inputs;
  PinvBench(std::size_t batch, const al::AirframeSpec& s)
      : num_rotors(s.num_rotors), lanes(batch), inputs(ring(batch)) {
    for (std::size_t j = 0; j < inputs.size(); ++j) inputs[j] = perturbed_airframe(s, j).effectiveness;
  }
  void call(Lane& l, const Input& a) {
    l.status = al::pseudo_inverse(a, num_rotors, l.pinv);
    benchmark::DoNotOptimize(l.status);
  }
  std::string check() {
    // Every lane's last result finite, and the pseudo-inverse property A A+ A = A on one input.
    for (std::size_t i = 0; i < lanes.size(); ++i) {
      if (lanes[i].status != Status::ok && lanes[i].status != Status::singular) return fail("status", i);
      if (!lanes[i].pinv.allFinite()) return fail("pinv not finite", i);
    }
    al::PinvMatrix p;
    (void)al::pseudo_inverse(inputs[0], num_rotors, p);
    const al::EffectivenessMatrix r = inputs[0] * p * inputs[0];
    if (!((r - inputs[0]).cwiseAbs().maxCoeff() < 1e-4_r)) return "A A+ A != A";
    return {};
  }
};

struct BuildModelBench : Batched<BuildModelBench> {
  struct Lane {
    al::AllocationModel model;
    Status status = Status::ok;
  };
  using Input = al::Airframe;
  std::vector<Lane> lanes;
  std::vector<Input> inputs;
  BuildModelBench(std::size_t batch, const al::AirframeSpec& s) : lanes(batch), inputs(ring(batch)) {
    for (std::size_t j = 0; j < inputs.size(); ++j) inputs[j] = perturbed_airframe(s, j);
  }
  void call(Lane& l, const Input& a) {
    l.status = al::build_allocation_model(a, l.model);
    benchmark::DoNotOptimize(l.status);
  }
  std::string check() {
    for (std::size_t i = 0; i < lanes.size(); ++i)
      if ((lanes[i].status != Status::ok && lanes[i].status != Status::singular) || lanes[i].model.pinv_info.rank != 4)
        return fail("model", i);
    return {};
  }
};

// ------------------------------------------------------------------------------------------------
// Motor model: each lane's motors start at hover (constants drawn per lane from its own stream, as
// the sim's reset), references within +-50 % of hover: the motors move on every step.
struct MotorBench : Batched<MotorBench> {
  struct Lane {
    al::MotorModelState motors;
    Status status = Status::ok;
  };
  struct Input {
    real reference_N[al::kMaxRotors];
  };
  const al::MotorModelConfig* cfg;
  std::vector<Lane> lanes;
  std::vector<Input> inputs;
  MotorBench(std::size_t batch, const al::AirframeSpec& s, const al::MotorModelConfig& c)
      : cfg(&c), lanes(batch), inputs(ring(batch)) {
    const real hover = s.mass_kg * kStandardGravity / static_cast<real>(s.num_rotors);
    real init[al::kMaxRotors] = {};
    for (int m = 0; m < s.num_rotors; ++m) init[m] = hover;
    for (std::size_t i = 0; i < lanes.size(); ++i) {
      RngStream r(kSeed, static_cast<std::uint32_t>(i), kPurposeMotors);
      if (al::motor_model_reset(c, lanes[i].motors, r, init) != Status::ok)
        std::fprintf(stderr, "bench_micro: motor_model_reset failed\n");
    }
    for (std::size_t j = 0; j < inputs.size(); ++j) {
      RngStream r = input_stream(j, kPurposeThrust);
      for (int m = 0; m < al::kMaxRotors; ++m)
        inputs[j].reference_N[m] = m < s.num_rotors ? r.uniform(0.5_r, 1.5_r) * hover : 0;
    }
  }
  void call(Lane& l, const Input& in) {
    l.status = al::motor_model_step(*cfg, l.motors, in.reference_N, kDt);
    benchmark::DoNotOptimize(l.status);
  }
  std::string check() {
    for (std::size_t i = 0; i < lanes.size(); ++i)
      if (lanes[i].status != Status::ok || !all_finite(lanes[i].motors.thrust_N, cfg->num_motors) ||
          !(lanes[i].motors.thrust_N[0] > 0))
        return fail("motor thrusts", i);
    return {};
  }
};

// Body wrench from motor thrusts (A f), as the plant side of the firmware example and the sim use.
struct WrenchFromThrustsBench : Batched<WrenchFromThrustsBench>, AllocSetup {
  struct Lane {
    Vec6 wrench;
  };
  struct Input {
    real thrust_N[al::kMaxRotors];
  };
  std::vector<Lane> lanes;
  std::vector<Input> inputs;
  WrenchFromThrustsBench(std::size_t batch, const al::AirframeSpec& s)
      : AllocSetup(s), lanes(batch), inputs(ring(batch)) {
    const real hover = s.mass_kg * kStandardGravity / static_cast<real>(s.num_rotors);
    for (std::size_t j = 0; j < inputs.size(); ++j) {
      RngStream r = input_stream(j, kPurposeThrust);
      for (int m = 0; m < al::kMaxRotors; ++m)
        inputs[j].thrust_N[m] = m < s.num_rotors ? r.uniform(0.5_r, 1.5_r) * hover : 0;
    }
  }
  void call(Lane& l, const Input& in) {
    l.wrench = al::wrench_from_thrusts(airframe.effectiveness, airframe.num_rotors, in.thrust_N);
  }
  std::string check() {
    for (std::size_t i = 0; i < lanes.size(); ++i)
      if (!lanes[i].wrench.allFinite() || !(lanes[i].wrench[2] > 0)) return fail("wrench", i);
    return {};
  }
};

// Rigid-body step under a near-hover wrench. Each lane restarts from its initial state every 500
// sweeps (1 s of flight at 500 Hz), so the states stay those of a flying vehicle however long
// Google Benchmark runs; the restore costs one state copy per 500 calls.
struct RigidBodyBench : Batched<RigidBodyBench> {
  static constexpr int kResetEvery = 500;
  struct Lane {
    RigidBodyState state, initial;
    Status status = Status::ok;
  };
  using Input = Wrench;
  RigidBodyModel model;
  std::vector<Lane> lanes;
  std::vector<Input> inputs;
  RigidBodyBench(std::size_t batch, Integrator integrator) : lanes(batch), inputs(ring(batch)) {
    RigidBodyParams p;  // the base quadrotor (0.25 kg), Aerial Gym's inertia
    p.integrator = integrator;
    p.linear_drag_b = Vec3(0.1_r, 0.1_r, 0.1_r);  // some drag, so that branch of the model runs
    if (make_rigid_body_model(p, model) != Status::ok) std::fprintf(stderr, "bench_micro: rigid body model failed\n");
    for (std::size_t i = 0; i < lanes.size(); ++i) {
      RngStream r(kSeed, static_cast<std::uint32_t>(i), kPurposeReset);
      lanes[i].state = lanes[i].initial = draw_body(r);
    }
    const real mg = p.mass_kg * kStandardGravity;
    for (std::size_t j = 0; j < inputs.size(); ++j) {
      RngStream r = input_stream(j, kPurposeWrench);
      inputs[j].force_b = Vec3(0, 0, r.uniform(0.9_r, 1.1_r) * mg);
      inputs[j].torque_b = Vec3(sym(r, 2e-4_r), sym(r, 2e-4_r), sym(r, 1e-4_r));
    }
  }
  void call(Lane& l, const Input& w) {
    l.status = step_rigid_body(model, l.state, w, kDt);
    benchmark::DoNotOptimize(l.status);
  }
  void reset_lanes() {
    for (Lane& l : lanes) l.state = l.initial;
  }
  std::string check() {
    for (std::size_t i = 0; i < lanes.size(); ++i) {
      const Lane& l = lanes[i];
      if (l.status != Status::ok || !finite_body(l.state)) return fail("state", i);
      if (!(std::fabs(l.state.orientation_wb.norm() - 1) < 1e-4_r)) return fail("quaternion norm", i);
      if ((l.state.position_w - l.initial.position_w).norm() > 10) return fail("drifted away (reset not applied?)", i);
    }
    return {};
  }
};

// ------------------------------------------------------------------------------------------------
// The whole cascade: kestrel::firmware::control_step (Lee position -> sequential desaturation ->
// motor model), the code the firmware example runs at 500 Hz and the MCU bench's cascade row. Each
// lane is a whole FlightStack built by flight_init, motors spun up to hover.
struct CascadeBench : Batched<CascadeBench> {
  struct Lane {
    firmware::FlightStack stack;
  };
  struct Input {
    RigidBodyState estimate;
    real command[4];
  };
  std::vector<Lane> lanes;
  std::vector<Input> inputs;
  explicit CascadeBench(std::size_t batch) : lanes(batch), inputs(ring(batch)) {
    firmware::Plant plant;
    for (std::size_t i = 0; i < lanes.size(); ++i) {
      firmware::FlightStack& s = lanes[i].stack;
      if (firmware::flight_init(s, plant) != Status::ok) std::fprintf(stderr, "bench_micro: flight_init failed\n");
      real hover[al::kMaxRotors] = {};
      for (int m = 0; m < 4; ++m) hover[m] = s.model.ctrl.lee.mass_kg * kStandardGravity / 4;
      RngStream r(kSeed, static_cast<std::uint32_t>(i), kPurposeMotors);
      if (al::motor_model_reset(s.model.motors, s.state.motors, r, hover) != Status::ok)
        std::fprintf(stderr, "bench_micro: motor_model_reset failed\n");
    }
    for (std::size_t j = 0; j < inputs.size(); ++j) {
      RngStream r = input_stream(j, kPurposeBody);
      inputs[j].estimate = draw_body(r);
      RngStream a = input_stream(j, kPurposeAction);
      const Vec3 p = inputs[j].estimate.position_w;
      const real c[4] = {p[0] + sym(a, 1), p[1] + sym(a, 1), p[2] + sym(a, 0.5_r), sym(a, kPi)};
      std::memcpy(inputs[j].command, c, sizeof c);
    }
  }
  void call(Lane& l, const Input& in) { firmware::control_step(l.stack, in.estimate, in.command, kDt); }
  std::string check() {
    for (std::size_t i = 0; i < lanes.size(); ++i) {
      const firmware::FlightStack& s = lanes[i].stack;
      const real* f = s.state.motors.thrust_N;
      if (!all_finite(f, 4) || !all_finite(s.out.allocation.thrust_N, 4)) return fail("thrusts", i);
      if (!(f[0] + f[1] + f[2] + f[3] > 0))
        return fail("no thrust", i);
    }
    return {};
  }
};

// The same step through the C API (state / setpoint conversion and the fault summary included).
struct CapiBench : Batched<CapiBench> {
  struct Lane {
    kestrel_storage storage;
    kestrel_output out;
    kestrel_status status = KESTREL_OK;
  };
  struct Input {
    kestrel_state state;
    kestrel_setpoint setpoint;
  };
  std::vector<Lane> lanes;
  std::vector<Input> inputs;
  explicit CapiBench(std::size_t batch) : lanes(batch), inputs(ring(batch)) {
    for (Lane& l : lanes)
      if (kestrel_init(&l.storage, KESTREL_PRESET_BASE_QUADROTOR) != KESTREL_OK)
        std::fprintf(stderr, "bench_micro: kestrel_init failed\n");
    for (std::size_t j = 0; j < inputs.size(); ++j) {
      RngStream r = input_stream(j, kPurposeBody);
      const RigidBodyState b = draw_body(r);
      kestrel_state& s = inputs[j].state;
      for (int a = 0; a < 3; ++a) {
        s.position_w[a] = static_cast<float>(b.position_w[a]);
        s.linvel_w[a] = static_cast<float>(b.linvel_w[a]);
        s.angvel_b[a] = static_cast<float>(b.angvel_b[a]);
      }
      const Vec4 q = to_xyzw(b.orientation_wb);
      for (int a = 0; a < 4; ++a) s.orientation_xyzw[a] = static_cast<float>(q[a]);
      RngStream a = input_stream(j, kPurposeAction);
      inputs[j].setpoint.mode = KESTREL_MODE_POSITION;
      inputs[j].setpoint.value[0] = s.position_w[0] + static_cast<float>(sym(a, 1));
      inputs[j].setpoint.value[1] = s.position_w[1] + static_cast<float>(sym(a, 1));
      inputs[j].setpoint.value[2] = s.position_w[2] + static_cast<float>(sym(a, 0.5_r));
      inputs[j].setpoint.value[3] = static_cast<float>(sym(a, kPi));
    }
  }
  void call(Lane& l, const Input& in) {
    l.status = kestrel_step(&l.storage, &in.state, &in.setpoint, static_cast<float>(kDt), &l.out);
    benchmark::DoNotOptimize(l.status);
  }
  std::string check() {
    for (std::size_t i = 0; i < lanes.size(); ++i) {
      const Lane& l = lanes[i];
      if (l.status != KESTREL_OK || l.out.num_motors != 4) return fail("status", i);
      for (int m = 0; m < 4; ++m)
        if (!std::isfinite(l.out.motor_command[m]) || l.out.motor_command[m] < 0 || l.out.motor_command[m] > 1)
          return fail("motor command", i);
    }
    return {};
  }
};

// ------------------------------------------------------------------------------------------------
// 8x8 ToF frame (VL53L5CX preset: 64 zones, 0.2-4 m): render() of the 64 rays with range and
// segmentation outputs, as the MCU bench's tof_scan_vl53l5cx_8x8 row, against the same 4-object
// scene (tests/sensors/test_sensor_tof.cpp: floor plane, box wall 2 m ahead, capsule post, sphere).
// The MCU row renders from one pose; here each call has its own sensor pose near the origin (moved
// by up to 0.4 m, tilted up to 0.15 rad, turned up to 0.3 rad), so the zones see different objects
// and ranges from call to call. The _noise row adds the preset's range noise (per-lane stream).
struct TofBench : Batched<TofBench> {
  static constexpr std::uint32_t kZones = 64;
  struct Lane {
    real range[kZones];
    std::int32_t segmentation[kZones];
    RngStream noise_rng;
    Status status = Status::ok;
  };
  using Input = se::SensorPose;
  se::LidarParams tof = se::lidar_preset_vl53l5cx();
  real dirs[3 * kZones] = {};
  real scale[kZones] = {};
  se::SceneStorage<8> storage;
  se::Scene scene;
  bool noise;
  std::vector<Lane> lanes;
  std::vector<Input> inputs;
  TofBench(std::size_t batch, bool with_noise) : scene(storage), noise(with_noise), lanes(batch), inputs(ring(batch)) {
    se::RayTable t{dirs, scale, kZones, 0, 0};
    bool ok = se::lidar_rays(tof, t) == Status::ok;
    const Quat id = Quat::Identity();
    ok = ok && scene.add(se::Shape::plane(), Vec3(0, 0, -0.6_r), id, 1) == Status::ok;
    ok = ok && scene.add(se::Shape::box(0.1_r, 2, 2), Vec3(2.1_r, 0, 0), id, 2) == Status::ok;
    ok = ok && scene.add(se::Shape::capsule(0.1_r, 0.5_r), Vec3(1, 0.3_r, 0), id, 3) == Status::ok;
    ok = ok && scene.add(se::Shape::sphere(0.15_r), Vec3(1.5_r, -0.4_r, 0.3_r), id, 4) == Status::ok;
    ok = ok && scene.build() == Status::ok;
    if (!ok) std::fprintf(stderr, "bench_micro: ToF scene set-up failed\n");
    for (std::size_t i = 0; i < lanes.size(); ++i)
      lanes[i].noise_rng = RngStream(kSeed, static_cast<std::uint32_t>(i), kPurposeSensorNoise);
    for (std::size_t j = 0; j < inputs.size(); ++j) {
      RngStream r = input_stream(j, kPurposeBody);
      inputs[j].position_w = Vec3(sym(r, 0.4_r), sym(r, 0.4_r), sym(r, 0.3_r));
      inputs[j].orientation_ws = quat_from_euler_xyz(sym(r, 0.15_r), sym(r, 0.15_r), sym(r, 0.3_r));
    }
  }
  void call(Lane& l, const Input& pose) {
    const se::RayTable table{dirs, scale, kZones, tof.height, tof.width};
    se::SensorOutput out;
    out.range = l.range;
    out.segmentation = l.segmentation;
    l.status = se::render(scene, pose, table, tof.range, false, out, noise ? &tof.noise : nullptr,
                          noise ? &l.noise_rng : nullptr);
    benchmark::DoNotOptimize(l.status);
  }
  std::string check() {
    std::size_t hits = 0, total = 0;
    for (std::size_t i = 0; i < lanes.size(); ++i) {
      if (lanes[i].status != Status::ok || !all_finite(lanes[i].range, static_cast<int>(kZones)))
        return fail("render", i);
      for (std::uint32_t z = 0; z < kZones; ++z) {
        hits += lanes[i].segmentation[z] >= 0 ? 1 : 0;
        ++total;
        // A hit reads a range within the sensor's limits (noise may move it a little past them).
        const real v = lanes[i].range[z];
        if (lanes[i].segmentation[z] >= 0 && !noise && !(v >= tof.range.min_range && v <= tof.range.max_range))
          return fail("hit range " + std::to_string(v) + " outside the sensor's limits", i);
      }
    }
    if (4 * hits < total)
      return "fewer than a quarter of the zones hit: " + std::to_string(hits) + " of " + std::to_string(total);
    return {};
  }
};

// ------------------------------------------------------------------------------------------------
// Registration: "function/airframe/batch:N", function names as in the MCU bench's control.csv where
// the MCU bench has the same row.
std::vector<std::pair<std::string, std::function<std::string()>>> g_checks;

template <class B, class... Args>
void add(const std::string& function, const std::string& airframe, int check_sweeps, Args... args) {
  const std::string name = function + "/" + airframe;
  benchmark::RegisterBenchmark(name.c_str(),
                               [=](benchmark::State& st) {
                                 B b(static_cast<std::size_t>(st.range(0)), args...);
                                 b.run(st);
                               })
      ->ArgName("batch")
      ->Arg(1)
      ->Arg(64)
      ->Arg(4096);
  g_checks.emplace_back(name, [=]() {
    B b(64, args...);
    return b.self_check(check_sweeps);
  });
}

void register_all() {
  for (std::size_t k = 0; k < kNumMultirotorControllerKinds; ++k) {  // update_controller's kinds
    const auto kind = static_cast<ControllerKind>(k);
    add<ControllerBench>(controller_name(kind),
                         kind == ControllerKind::rov_fully_actuated ? "base_rov" : "base_quadrotor", 20, kind);
  }
  add<LeePositionBench>("update_lee_position", "base_quadrotor", 20);
  add<JointPdBench>("update_joint_pd", "anymal_c_12dof", 20);
  add<PinvBench>("pseudo_inverse", "base_quadrotor", 2, al::kBaseQuadrotor);
  add<PinvBench>("pseudo_inverse", "hexarotor", 2, al::kHexarotor);
  add<BuildModelBench>("build_allocation_model", "base_quadrotor", 2, al::kBaseQuadrotor);
  add<ApplyPinvBench>("apply_pinv", "base_quadrotor", 20, al::kBaseQuadrotor);
  add<AllocateBench>("allocate_pinv", "base_quadrotor", 20, al::kBaseQuadrotor, Allocator::pinv,
                     WrenchClass::saturated);
  add<AllocateBench>("allocate_sequential_desaturation_saturated", "base_quadrotor", 20, al::kBaseQuadrotor,
                     Allocator::sequential_desaturation, WrenchClass::saturated);
  add<AllocateBench>("allocate_sequential_desaturation_feasible", "base_quadrotor", 20, al::kBaseQuadrotor,
                     Allocator::sequential_desaturation, WrenchClass::feasible);
  add<AllocateBench>("allocate_sequential_desaturation_feasible", "hexarotor", 20, al::kHexarotor,
                     Allocator::sequential_desaturation, WrenchClass::feasible);
  add<AllocateBench>("allocate_cls_warm", "base_quadrotor", 20, al::kBaseQuadrotor, Allocator::cls,
                     WrenchClass::saturated);
  add<AllocateBench>("allocate_cls_warm", "hexarotor", 20, al::kHexarotor, Allocator::cls, WrenchClass::feasible);
  add<MotorBench>("motor_model_step_rk4_rps", "base_quadrotor", 20, al::kBaseQuadrotor, al::kBaseQuadrotorMotors);
  add<MotorBench>("motor_model_step_rk4_rps", "hexarotor", 20, al::kHexarotor, al::kHexarotorMotors);
  add<WrenchFromThrustsBench>("wrench_from_thrusts", "base_quadrotor", 20, al::kBaseQuadrotor);
  add<WrenchFromThrustsBench>("wrench_from_thrusts", "hexarotor", 20, al::kHexarotor);
  add<RigidBodyBench>("step_rigid_body_rk4", "base_quadrotor", 1200, Integrator::rk4);
  add<RigidBodyBench>("step_rigid_body_semi_implicit", "base_quadrotor", 1200, Integrator::semi_implicit_euler);
  add<CascadeBench>("cascade_lee_position_desat_motors", "base_quadrotor", 200);
  add<CapiBench>("kestrel_step_capi", "base_quadrotor", 200);
  add<TofBench>("tof_scan_vl53l5cx_8x8", "scene_4_objects", 4, false);
  add<TofBench>("tof_scan_vl53l5cx_8x8_noise", "scene_4_objects", 4, true);
}

}  // namespace

int main(int argc, char** argv) {
  bool check_only = false;
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--check-only") == 0) {
      check_only = true;
    } else {
      args.push_back(argv[i]);
    }
  }
  register_all();
  int failures = 0;
  for (const auto& [name, check] : g_checks) {
    const std::string why = check();
    if (!why.empty()) {
      std::fprintf(stderr, "bench_micro: self-check FAILED: %s: %s\n", name.c_str(), why.c_str());
      ++failures;
    }
  }
  std::fprintf(stderr, "bench_micro: self-check: %zu benchmarks, %d failed\n", g_checks.size(), failures);
  if (failures != 0) return 1;
  if (check_only) return 0;
  int n = static_cast<int>(args.size());
  benchmark::Initialize(&n, args.data());
  if (benchmark::ReportUnrecognizedArguments(n, args.data())) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
