// Helpers shared by the allocation tests (header-only, no heap, no iostream).
#pragma once

#include <cmath>
#include <type_traits>

#include "kestrel/allocation/allocation_model.hpp"
#include "kestrel/allocation/presets.hpp"
#include "kestrel/kernel/math.hpp"
#include "ktest.hpp"

namespace alloc_test {

using namespace kestrel;
using namespace kestrel::allocation;

/// Runs f() inside KEXPECT_NO_HEAP and returns its result: every call into the allocation layer
/// in these tests goes through this (or through KEXPECT_NO_HEAP directly).
template <typename F>
auto no_heap(F&& f) {
  using R = decltype(f());
  if constexpr (std::is_void_v<R>) {
    KEXPECT_NO_HEAP(f());
  } else {
    R r{};
    KEXPECT_NO_HEAP(r = f());
    return r;
  }
}

/// Builds the airframe and the allocation model of a preset (status of the model build returned).
inline Status build_preset(const AirframeSpec& spec, Airframe& airframe, AllocationModel& model,
                           const MotorHealth& health = MotorHealth()) {
  const Status st = no_heap([&] { return make_airframe(spec, airframe); });
  if (st != Status::ok) return st;
  return no_heap([&] { return build_allocation_model(airframe, health, model); });
}

inline Vec6 wrench(real fx, real fy, real fz, real tx, real ty, real tz) {
  Vec6 w;
  w << fx, fy, fz, tx, ty, tz;
  return w;
}

inline Vec6 hover_wrench(const AirframeSpec& spec) { return wrench(0, 0, spec.mass_kg * kStandardGravity, 0, 0, 0); }

/// Counts golden/tolerance comparisons and reports only the first few failures in full, so a
/// badly broken run does not print thousands of lines; finish() fails if anything failed.
struct CloseCounter {
  int checked = 0;
  int failed = 0;
  int first_bad_id = -1;
  void check(double actual, double expected, double abs_tol, double rel_tol, const char* what, int id) {
    ++checked;
    const double err = std::fabs(actual - expected);
    if (err <= abs_tol + rel_tol * std::fabs(expected)) return;  // NaN fails here too
    ++failed;
    if (first_bad_id < 0) first_bad_id = id;
    if (failed <= 8) {
      KEXPECT_CLOSE(actual, expected, abs_tol, rel_tol, what);
    }
  }
};

}  // namespace alloc_test
