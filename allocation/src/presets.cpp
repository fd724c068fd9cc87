// The presets are constexpr data in presets.hpp; this file compiles them (and, through the
// umbrella header, every allocation header) under the core's flags
// (-Wdouble-promotion in the float build) and checks their invariants at compile time.
#include "kestrel/allocation/allocation.hpp"

namespace kestrel::allocation {

namespace {

constexpr bool directions_ok(const AirframeSpec& s) {
  for (int i = 0; i < s.num_rotors; ++i) {
    if (s.direction[i] != 1 && s.direction[i] != -1) return false;
  }
  return s.num_rotors >= 1 && s.num_rotors <= kMaxRotors && s.thrust_min_N <= s.thrust_max_N;
}

static_assert(directions_ok(kBaseQuadrotor) && kBaseQuadrotor.num_rotors == 4, "base_quadrotor preset");
// With a reduced KESTREL_MAX_ROTORS (airframe.hpp) the larger presets are empty.
static_assert(kMaxRotors < 8 || (directions_ok(kBaseRandom) && kBaseRandom.num_rotors == 8), "base_random preset");
static_assert(kMaxRotors < 8 || (directions_ok(kBaseOctarotor) && kBaseOctarotor.num_rotors == 8), "base_octarotor preset");
static_assert(kMaxRotors < 8 || (directions_ok(kBaseRov) && kBaseRov.num_rotors == 8), "base_rov preset");
static_assert(kMaxRotors < 6 || (directions_ok(kHexarotor) && kHexarotor.num_rotors == 6), "hexarotor preset");
static_assert(kMaxRotors >= 6 || (kHexarotor.num_rotors == 0 && kBaseRov.num_rotors == 0), "presets beyond the capacity are empty");
static_assert(directions_ok(kX500) && kX500.num_rotors == 4, "x500 preset");
static_assert(airframe_spec(AirframePreset::x500).num_rotors == 4, "preset lookup");
static_assert(motor_model_preset(AirframePreset::base_quadrotor).use_rps, "quad motors use the rotor-speed state");
// Quirk 9: no rotor-speed preset may allow negative thrust (validate() would reject it).
constexpr bool rps_ok(const MotorModelConfig& m) {
  return !m.use_rps || (m.thrust_min_N >= 0 && m.thrust_constant_min > 0);
}
static_assert(rps_ok(kBaseQuadrotorMotors) && rps_ok(kBaseRandomMotors) && rps_ok(kBaseOctarotorMotors) &&
                  rps_ok(kHexarotorMotors) && rps_ok(kX500Motors),
              "rotor-speed motor presets");

}  // namespace

}  // namespace kestrel::allocation
