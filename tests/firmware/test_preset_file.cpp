// Parameters as plain constexpr structs for the firmware, the same presets loadable on the desktop:
// the base quadrotor stack built from the constexpr presets and from base_quadrotor.yaml (the same
// values as text) must give bit-identical outputs over a closed-loop trajectory.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cstdlib>
#include <cstring>
#include <string>

#include "kestrel/allocation/allocation_model.hpp"
#include "kestrel/allocation/presets.hpp"
#include "kestrel/allocation/sequential_desaturation.hpp"
#include "kestrel/controllers/lee.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/kernel/rigid_body.hpp"

namespace al = kestrel::allocation;
using kestrel::real;
using kestrel::Status;
using kestrel::Vec3;

namespace {

// Numbers are parsed as text with strtod (exact decimal -> double) and then converted to `real`:
// the file holds the double build's values with 17 digits, which round-trip exactly (see the file).
real num(const YAML::Node& n) { return static_cast<real>(std::strtod(n.as<std::string>().c_str(), nullptr)); }
Vec3 vec3(const YAML::Node& n) { return Vec3(num(n[0]), num(n[1]), num(n[2])); }

struct Presets {
  kestrel::LeeParams lee;
  al::AirframeSpec airframe{};
  al::MotorModelConfig motors{};
};

Presets from_constexpr() {
  Presets p;
  p.lee = kestrel::lee_params_base_quadrotor();
  p.airframe = al::kBaseQuadrotor;
  p.motors = al::kBaseQuadrotorMotors;
  return p;
}

Presets from_file(const char* path) {
  const YAML::Node root = YAML::LoadFile(path);
  Presets p;
  const YAML::Node lee = root["lee"];
  p.lee.mass_kg = num(lee["mass_kg"]);
  p.lee.inertia_b = kestrel::Mat3::Zero();
  for (int i = 0; i < 3; ++i) p.lee.inertia_b(i, i) = num(lee["inertia_diag_kg_m2"][i]);
  p.lee.gravity_w = vec3(lee["gravity_w"]);
  p.lee.max_yaw_rate_radps = num(lee["max_yaw_rate_radps"]);
  for (int m = 0; m < 2; ++m) {
    const YAML::Node g = lee[m == 0 ? "gains_min" : "gains_max"];
    kestrel::LeeGains& dst = m == 0 ? p.lee.gain_ranges.min : p.lee.gain_ranges.max;
    dst.k_pos = vec3(g["k_pos"]);
    dst.k_vel = vec3(g["k_vel"]);
    dst.k_rot = vec3(g["k_rot"]);
    dst.k_angvel = vec3(g["k_angvel"]);
  }
  p.lee.randomize_gains = lee["randomize_gains"].as<bool>();
  p.lee.action_min = num(lee["action_min"]);
  p.lee.action_max = num(lee["action_max"]);

  const YAML::Node af = root["airframe"];
  static const std::string name = "base_quadrotor (file)";  // the spec keeps a pointer to it
  p.airframe.name = name.c_str();
  p.airframe.num_rotors = af["num_rotors"].as<int>();
  p.airframe.source = al::AirframeSource::rotor_geometry;
  p.airframe.thrust_min_N = num(af["thrust_min_N"]);
  p.airframe.thrust_max_N = num(af["thrust_max_N"]);
  p.airframe.thrust_to_torque_m = num(af["thrust_to_torque_m"]);
  p.airframe.mass_kg = num(af["mass_kg"]);
  for (int i = 0; i < p.airframe.num_rotors; ++i) {
    p.airframe.direction[i] = static_cast<std::int8_t>(af["direction"][i].as<int>());
    for (int k = 0; k < 3; ++k) {
      p.airframe.rotors[i].position_b_m[k] = num(af["rotor_positions_b_m"][i][k]);
      p.airframe.rotors[i].axis_b[k] = num(af["rotor_axis_b"][k]);
    }
  }

  const YAML::Node mo = root["motors"];
  // The motor model shares the airframe's count, limits, ratio and directions (presets::motors_from).
  p.motors.num_motors = p.airframe.num_rotors;
  p.motors.thrust_min_N = p.airframe.thrust_min_N;
  p.motors.thrust_max_N = p.airframe.thrust_max_N;
  p.motors.thrust_to_torque_m = p.airframe.thrust_to_torque_m;
  for (int i = 0; i < al::kMaxRotors; ++i) p.motors.direction[i] = p.airframe.direction[i];
  p.motors.integrator = mo["integrator"].as<std::string>() == "euler" ? al::MotorIntegrator::euler : al::MotorIntegrator::rk4;
  p.motors.use_rps = mo["use_rps"].as<bool>();
  p.motors.use_discrete_approximation = mo["use_discrete_approximation"].as<bool>();
  p.motors.time_constant_increasing_min_s = num(mo["time_constant_increasing_s"][0]);
  p.motors.time_constant_increasing_max_s = num(mo["time_constant_increasing_s"][1]);
  p.motors.time_constant_decreasing_min_s = num(mo["time_constant_decreasing_s"][0]);
  p.motors.time_constant_decreasing_max_s = num(mo["time_constant_decreasing_s"][1]);
  p.motors.thrust_constant_min = num(mo["thrust_constant"][0]);
  p.motors.thrust_constant_max = num(mo["thrust_constant"][1]);
  p.motors.max_rate = num(mo["max_rate"]);
  return p;
}

template <typename T>
bool same_bits(const T& a, const T& b) {
  return std::memcmp(&a, &b, sizeof(T)) == 0;
}

// Everything a trajectory produces, per step.
struct Trace {
  static constexpr int kSteps = 3000;  // 6 s at 500 Hz: take-off, a step and a yaw change
  real wrench[kSteps][6];
  real thrust[kSteps][4];
  real position[kSteps][3];
};

void fly(const Presets& p, Trace& out) {
  kestrel::LeeState lee_state;
  ASSERT_EQ(kestrel::validate_lee_params(p.lee), Status::ok);
  kestrel::lee_reset(p.lee, lee_state);
  al::Airframe airframe;
  ASSERT_EQ(al::make_airframe(p.airframe, airframe), Status::ok);
  al::AllocationModel model;
  const Status am = al::build_allocation_model(airframe, model);
  ASSERT_TRUE(am == Status::ok || am == Status::singular);  // the quad is rank 4
  al::AllocatorState alloc_state;
  al::reset_allocator(alloc_state);
  const al::SequentialDesaturationParams desat;
  al::MotorModelState motors;
  kestrel::RngStream rng(1, 0, kestrel::kPurposeMotors);
  const real idle[al::kMaxRotors] = {};
  ASSERT_EQ(al::motor_model_reset(p.motors, motors, rng, idle), Status::ok);
  kestrel::RigidBodyParams bp;
  bp.mass_kg = p.lee.mass_kg;
  bp.inertia_b = p.lee.inertia_b.map();
  bp.gravity_w = p.lee.gravity_w.map();
  bp.integrator = kestrel::Integrator::rk4;
  kestrel::RigidBodyModel body;
  ASSERT_EQ(kestrel::make_rigid_body_model(bp, body), Status::ok);
  kestrel::RigidBodyState state;
  const real dt = static_cast<real>(0.002);
  for (int k = 0; k < Trace::kSteps; ++k) {
    const bool second = k >= Trace::kSteps / 2;
    const real command[4] = {second ? static_cast<real>(1) : 0, second ? static_cast<real>(-0.5) : 0,
                             second ? static_cast<real>(1.5) : 1, second ? static_cast<real>(0.5) : 0};
    const kestrel::Wrench w = kestrel::update_lee_position(p.lee, lee_state, state, command);
    al::AllocationResult out_alloc;
    (void)al::allocate_sequential_desaturation(model, desat, alloc_state, w, out_alloc);
    (void)al::motor_model_step(p.motors, motors, out_alloc.thrust_N, dt);
    const kestrel::Vec6 wr = al::wrench_from_thrusts(airframe.effectiveness, airframe.num_rotors, motors.thrust_N);
    (void)kestrel::step_rigid_body(body, state, kestrel::Wrench::from_vec6(wr), dt);
    if (state.position_w[2] < 0) {  // floor, as the firmware example
      state.position_w[2] = 0;
      if (state.linvel_w[2] < 0) state.linvel_w = Vec3::Zero();
      state.angvel_b = Vec3::Zero();
    }
    for (int i = 0; i < 6; ++i) out.wrench[k][i] = w.as_vec6()[i];
    for (int i = 0; i < 4; ++i) out.thrust[k][i] = motors.thrust_N[i];
    for (int i = 0; i < 3; ++i) out.position[k][i] = state.position_w[i];
  }
}

}  // namespace

TEST(FirmwarePresetFile, LoadsTheConstexprPresetsBitForBit) {
  const Presets a = from_constexpr();
  const Presets b = from_file(KESTREL_PRESET_FILE);
  EXPECT_TRUE(same_bits(a.lee.mass_kg, b.lee.mass_kg));
  EXPECT_TRUE(same_bits(a.lee.inertia_b, b.lee.inertia_b));
  EXPECT_TRUE(same_bits(a.lee.gravity_w, b.lee.gravity_w));
  EXPECT_TRUE(same_bits(a.lee.max_yaw_rate_radps, b.lee.max_yaw_rate_radps));
  const kestrel::LeeGains ga = kestrel::lee_nominal_gains(a.lee.gain_ranges);
  const kestrel::LeeGains gb = kestrel::lee_nominal_gains(b.lee.gain_ranges);
  EXPECT_TRUE(same_bits(ga.k_pos, gb.k_pos) && same_bits(ga.k_vel, gb.k_vel));
  EXPECT_TRUE(same_bits(ga.k_rot, gb.k_rot) && same_bits(ga.k_angvel, gb.k_angvel));
  al::Airframe fa, fb;
  ASSERT_EQ(al::make_airframe(a.airframe, fa), Status::ok);
  ASSERT_EQ(al::make_airframe(b.airframe, fb), Status::ok);
  EXPECT_TRUE(same_bits(fa.effectiveness, fb.effectiveness));
  EXPECT_TRUE(same_bits(a.motors.thrust_constant_min, b.motors.thrust_constant_min));
  EXPECT_TRUE(same_bits(a.motors.thrust_constant_max, b.motors.thrust_constant_max));
  EXPECT_TRUE(same_bits(a.motors.time_constant_increasing_min_s, b.motors.time_constant_increasing_min_s));
  EXPECT_TRUE(same_bits(a.motors.time_constant_decreasing_max_s, b.motors.time_constant_decreasing_max_s));
  EXPECT_EQ(a.motors.use_rps, b.motors.use_rps);
  EXPECT_EQ(a.motors.integrator, b.motors.integrator);
}

TEST(FirmwarePresetFile, ClosedLoopTrajectoryIsBitIdentical) {
  static Trace ta, tb;  // static: 100 KB each
  fly(from_constexpr(), ta);
  fly(from_file(KESTREL_PRESET_FILE), tb);
  int first_diff = -1;
  for (int k = 0; k < Trace::kSteps && first_diff < 0; ++k)
    if (!same_bits(ta.wrench[k], tb.wrench[k]) || !same_bits(ta.thrust[k], tb.thrust[k]) ||
        !same_bits(ta.position[k], tb.position[k]))
      first_diff = k;
  EXPECT_EQ(first_diff, -1) << "first differing step";
  // The trajectory is not trivial: it took off and moved to the second setpoint.
  EXPECT_GT(ta.position[Trace::kSteps - 1][2], static_cast<real>(1.2));
  EXPECT_LT(ta.position[Trace::kSteps - 1][1], static_cast<real>(-0.3));
}
