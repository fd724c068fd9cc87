// Build-time generator of the baked quadrotor control stack (see
// bench/control/mcu/baked_cascade.hpp): runs the core's own set-up on the host — the Lee preset
// (lee_params_base_quadrotor), make_airframe(kBaseQuadrotor) and build_allocation_model (Jacobi
// pseudo-inverse) at KESTREL_MAX_ROTORS=4, then lee_reset and motor_model_reset for the initial
// state — and writes every resulting number as a C++ constant,
// floats as hex-float literals (%a), so the header holds exactly the bits the host computed.
// Nothing is recomputed differently: these are the functions the start-up-built images call.
// That the host and the MCU compute the same bits (IEEE single precision, -ffp-contract=off,
// correctly rounded sqrt and division on both) is not assumed: cascade_parity.cpp, built with
// KESTREL_CASCADE_BAKED, builds the model on the MCU at start-up and compares it with this header
// bit for bit (ctest kestrel_cascade_capacity_parity).
//
//   kestrel_bake_cascade <output header>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "../mcu/baked_cascade.hpp"
#include "kestrel/allocation/airframe.hpp"
#include "kestrel/allocation/motor_model.hpp"
#include "kestrel/allocation/presets.hpp"
#include "kestrel/allocation/sequential_desaturation.hpp"

// The kernel's assertion hook (the platform layer provides it in Kestrel's own images).
extern "C" void kestrel_platform_assert_default(const char* expr, const char* file, int line) {
  std::fprintf(stderr, "kestrel_bake_cascade: assertion failed: %s (%s:%d)\n", expr, file, line);
  std::abort();
}

namespace {

namespace al = kestrel::allocation;
using kestrel::real;

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "kestrel_bake_cascade: %s\n", what.c_str());
  std::exit(1);
}

std::string hexf(real v, const char* field) {
  if (!std::isfinite(v)) fail(std::string("non-finite value in ") + field);
  char buf[48];
  std::snprintf(buf, sizeof buf, "%af", static_cast<double>(v));
  return buf;
}

template <typename T>
std::string list(const T* v, int n, const char* field) {
  std::string s = "{";
  for (int i = 0; i < n; ++i) {
    if (i) s += ", ";
    if constexpr (std::is_same_v<T, real>) {
      s += hexf(v[i], field);
    } else {
      s += std::to_string(static_cast<long long>(v[i]));
    }
  }
  return s + "}";
}

std::string gains_initialiser(const kestrel::LeeGains& g, const char* field) {
  return "{" + list(g.k_pos.data(), 3, field) + ", " + list(g.k_vel.data(), 3, field) + ", " +
         list(g.k_rot.data(), 3, field) + ", " + list(g.k_angvel.data(), 3, field) + "}";
}

// LeeParams' aggregate initialiser, its members in declaration order (a member added to
// LeeParams and missed here fails kestrel_cascade_capacity_parity's field-by-field comparison).
std::string lee_initialiser(const kestrel::LeeParams& p) {
  std::string s = "{\n";
  s += "    /*mass_kg*/ " + hexf(p.mass_kg, "mass_kg") + ",\n";
  s += "    /*inertia_b (column-major)*/ " + list(p.inertia_b.data(), 9, "inertia_b") + ",\n";
  s += "    /*gravity_w*/ " + list(p.gravity_w.data(), 3, "gravity_w") + ",\n";
  s += "    /*max_yaw_rate_radps*/ " + hexf(p.max_yaw_rate_radps, "max_yaw_rate_radps") + ",\n";
  s += "    /*gain_ranges {min, max} of {k_pos, k_vel, k_rot, k_angvel}*/ {\n        " +
       gains_initialiser(p.gain_ranges.min, "gain_ranges.min") + ",\n        " +
       gains_initialiser(p.gain_ranges.max, "gain_ranges.max") + "},\n";
  s += std::string("    /*randomize_gains*/ ") + (p.randomize_gains ? "true" : "false") + ",\n";
  s += "    /*action_min*/ " + hexf(p.action_min, "action_min") + ",\n";
  s += "    /*action_max*/ " + hexf(p.action_max, "action_max") + ",\n}";
  return s;
}

std::string model_initialiser(const al::AllocationModel& m) {
  constexpr int n = al::kMaxRotors;
  std::string s = "{\n";
  s += "    /*num_rotors*/ " + std::to_string(m.num_rotors) + ",\n";
  s += "    /*effectiveness (column-major 6 x " + std::to_string(n) + ")*/ " +
       list(m.effectiveness.data(), 6 * n, "effectiveness") + ",\n";
  s += "    /*pinv (column-major " + std::to_string(n) + " x 6)*/ " + list(m.pinv.data(), 6 * n, "pinv") + ",\n";
  s += "    /*pinv_col_abs_max*/ " + list(m.pinv_col_abs_max, 6, "pinv_col_abs_max") + ",\n";
  s += "    /*pinv_col_movable_mask*/ " + list(m.pinv_col_movable_mask, 6, "pinv_col_movable_mask") + ",\n";
  s += "    /*thrust_min_N*/ " + list(m.thrust_min_N, n, "thrust_min_N") + ",\n";
  s += "    /*thrust_max_N*/ " + list(m.thrust_max_N, n, "thrust_max_N") + ",\n";
  s += "    /*dead_mask*/ " + std::to_string(m.dead_mask) + ",\n";
  s += "    /*weak_mask*/ " + std::to_string(m.weak_mask) + ",\n";
  s += "    /*wrench_row_mask*/ " + std::to_string(m.wrench_row_mask) + ",\n";
  const al::PinvInfo& i = m.pinv_info;
  s += "    /*pinv_info {rank, sweeps, rotations, converged, sigma_max, sigma_min_kept}*/ {" +
       std::to_string(i.rank) + ", " + std::to_string(i.sweeps) + ", " + std::to_string(i.rotations) + ", " +
       (i.converged ? "true" : "false") + ", " + hexf(i.sigma_max, "pinv_info.sigma_max") + ", " +
       hexf(i.sigma_min_kept, "pinv_info.sigma_min_kept") + "},\n";
  s += "    /*faults*/ {" + std::to_string(m.faults.bits) + "u},\n}";
  return s;
}

std::string lee_state_initialiser(const kestrel::LeeState& st) {
  return "{\n    /*gains*/ " + gains_initialiser(st.gains, "gains") + ",\n    /*inertia_diagonal*/ " +
         (st.inertia_diagonal ? "true" : "false") + ",\n}";
}

std::string motors_initialiser(const al::MotorModelState& m) {
  constexpr int n = al::kMaxRotors;
  std::string s = "{\n";
  s += "    /*num_motors*/ " + std::to_string(m.num_motors) + ",\n";
  s += "    /*thrust_N*/ " + list(m.thrust_N, n, "thrust_N") + ",\n";
  s += "    /*axial_torque_Nm*/ " + list(m.axial_torque_Nm, n, "axial_torque_Nm") + ",\n";
  s += "    /*time_constant_increasing_s*/ " + list(m.time_constant_increasing_s, n, "time_constant_increasing_s") + ",\n";
  s += "    /*time_constant_decreasing_s*/ " + list(m.time_constant_decreasing_s, n, "time_constant_decreasing_s") + ",\n";
  s += "    /*thrust_constant*/ " + list(m.thrust_constant, n, "thrust_constant") + ",\n";
  s += "    /*health_scale*/ " + list(m.health_scale, n, "health_scale") + ",\n";
  s += "    /*pending_scale*/ " + list(m.pending_scale, n, "pending_scale") + ",\n";
  s += "    /*failure_time_s*/ " + list(m.failure_time_s, n, "failure_time_s") + ",\n";
  s += "    /*last_reference_N*/ " + list(m.last_reference_N, n, "last_reference_N") + ",\n";
  s += "    /*pending_mask*/ " + std::to_string(m.pending_mask) + ",\n";
  s += "    /*elapsed_s*/ " + hexf(m.elapsed_s, "elapsed_s") + ",\n";
  s += "    /*faults*/ {" + std::to_string(m.faults.bits) + "u},\n}";
  return s;
}

std::string read_all(const std::string& path) {
  std::string s;
  std::FILE* f = std::fopen(path.c_str(), "r");
  if (!f) return s;
  char buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) s.append(buf, n);
  std::fclose(f);
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) fail("usage: kestrel_bake_cascade <output header>");
  static_assert(al::kMaxRotors == 4, "the baked quad stack is generated for KESTREL_MAX_ROTORS=4");

  // The set-up of bench/control/mcu/stack_image.cpp (KESTREL_STACK_CASCADE) and cascade_parity.cpp.
  const kestrel::LeeParams lee = kestrel::lee_params_base_quadrotor();
  if (kestrel::validate_lee_params(lee) != kestrel::Status::ok) fail("lee_params_base_quadrotor() does not validate");
  al::Airframe airframe;
  if (al::make_airframe(al::kBaseQuadrotor, airframe) != kestrel::Status::ok) fail("make_airframe(kBaseQuadrotor) failed");
  al::AllocationModel model;
  if (al::build_allocation_model(airframe, model) == kestrel::Status::invalid_argument)
    fail("build_allocation_model(kBaseQuadrotor) failed");
  const al::SequentialDesaturationParams desat;
  kestrel::LeeState lee_state;
  kestrel::lee_reset(lee, lee_state);
  al::MotorModelState motors;
  kestrel::RngStream motor_rng(1, 0, kestrel::kPurposeMotors);
  const real idle[al::kMaxRotors] = {};
  if (al::motor_model_reset(al::kBaseQuadrotorMotors, motors, motor_rng, idle) != kestrel::Status::ok)
    fail("motor_model_reset(kBaseQuadrotorMotors) failed");

  const std::string path = argv[1];
  const std::string tmp = path + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "w");
  if (!f) fail("cannot write " + tmp);
  std::fprintf(f,
               "// Generated at build time by bench/control/bake/bake_cascade.cpp (host build of the core's set-up\n"
               "// code, KESTREL_MAX_ROTORS=4) from lee_params_base_quadrotor(), kBaseQuadrotor and\n"
               "// build_allocation_model(). Do not edit. Floats are hex-float literals: the exact bits.\n"
               "#pragma once\n\n"
               "#include \"baked_cascade.hpp\"\n"
               "#include \"kestrel/allocation/sequential_desaturation.hpp\"\n\n"
               "static_assert(kestrel::allocation::kMaxRotors == 4, \"generated for KESTREL_MAX_ROTORS=4\");\n\n"
               "namespace kestrel::baked {\n\n"
               "inline constexpr LeeParams kLeeBaseQuadrotor = %s;\n\n"
               "inline constexpr allocation::AllocationModel kModelBaseQuadrotor = %s;\n\n"
               "inline constexpr allocation::SequentialDesaturationParams kDesat = {\n"
               "    /*airmode*/ static_cast<allocation::Airmode>(%d), /*yaw_headroom*/ %s};\n\n"
               "// Initial state: lee_reset(kLeeBaseQuadrotor) and motor_model_reset(kBaseQuadrotorMotors,\n"
               "// RngStream(1, 0, kPurposeMotors), idle thrust).\n"
               "inline constexpr LeeStateData kLeeStateInitial = %s;\n\n"
               "inline constexpr allocation::MotorModelState kMotorsInitial = %s;\n\n"
               "}  // namespace kestrel::baked\n",
               lee_initialiser(lee).c_str(), model_initialiser(model).c_str(), static_cast<int>(desat.airmode),
               hexf(desat.yaw_headroom, "yaw_headroom").c_str(), lee_state_initialiser(lee_state).c_str(),
               motors_initialiser(motors).c_str());
  if (std::fclose(f) != 0) fail("cannot write " + tmp);
  // An unchanged header keeps its time stamp, so the images that include it are not rebuilt.
  if (read_all(tmp) == read_all(path)) {
    std::remove(tmp.c_str());
    return 0;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) fail("cannot rename " + tmp + " to " + path);
  return 0;
}
