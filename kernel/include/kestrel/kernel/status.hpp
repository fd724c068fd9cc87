// Status codes and fault flags.
//
// The core never throws and never crashes on bad input: functions that can fail return a Status
// (marked [[nodiscard]] at the call sites that can run out or fail), and components latch fault
// bits a supervisor can read, clear and report.
#pragma once

#include <cstdint>

namespace kestrel {

enum class Status : std::uint8_t {
  ok = 0,
  invalid_argument,   // a parameter is outside its documented range
  non_finite_input,   // NaN or infinity in an input; the output was held
  capacity_exceeded,  // a fixed-capacity container or workspace is full
  singular,           // a matrix or geometry cannot be inverted / has lost rank
  not_converged,      // an iterative solver hit its iteration bound (result is still usable)
  non_finite_output,  // finite inputs overflowed to NaN/inf inside a stage; the last safe output was held
};

const char* to_string(Status s);

/// Fault bits, latched until cleared by the owner.
enum Fault : std::uint32_t {
  kFaultNone = 0,
  kFaultNonFiniteCommand = 1u << 0,  // command had NaN/inf: output held at last safe value
  kFaultNonFiniteState = 1u << 1,    // state estimate had NaN/inf: output held
  kFaultCommandOutOfRange = 1u << 2, // command clipped to its allowed range
  kFaultSaturated = 1u << 3,         // an actuator or limit saturated
  kFaultSingular = 1u << 4,          // geometry lost rank / desired attitude undefined
  kFaultUnallocated = 1u << 5,       // part of the commanded wrench could not be produced
  kFaultMotorFailure = 1u << 6,      // a motor is marked dead or weak
  kFaultNotConverged = 1u << 7,      // iteration bound reached
  kFaultNonFiniteOutput = 1u << 8,   // an internal result was non-finite and was replaced
};

/// A set of latched fault bits.
struct FaultFlags {
  std::uint32_t bits = 0;
  constexpr void raise(std::uint32_t f) { bits |= f; }
  constexpr bool has(std::uint32_t f) const { return (bits & f) != 0; }
  constexpr bool any() const { return bits != 0; }
  constexpr void clear(std::uint32_t f = 0xffffffffu) { bits &= ~f; }
};

}  // namespace kestrel
