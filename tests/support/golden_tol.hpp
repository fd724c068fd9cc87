// The tolerances a golden file declares (conventions.recommended_tolerance, rule
// |mine - golden| <= abs + rel |golden|), read with the pull reader so that a newer reference set
// brings its own. Header-only: used by the core tests (host and MCU) and the sim tests.
#pragma once

#include <cstring>

#include "json_pull.hpp"

namespace ktest {

struct GoldenTol {
  double abs = -1;
  double rel = -1;
};

/// Reads an {"abs": a, "rel": r} object; other members are skipped, a missing one keeps its value.
inline bool read_tolerance(JsonReader& r, GoldenTol& t) {
  if (!r.begin_object()) return false;
  char k[32];
  while (r.next_key(k, sizeof k)) {
    bool ok = true;
    if (std::strcmp(k, "abs") == 0) {
      ok = r.read_double(t.abs);
    } else if (std::strcmp(k, "rel") == 0) {
      ok = r.read_double(t.rel);
    } else {
      ok = r.skip_value();
    }
    if (!ok) return false;
  }
  return r.ok();
}

/// Reads an object of named tolerances ({"f_ref_N": {abs, rel}, ...}): the member names[i] goes to
/// *out[i]; members not named are skipped, named ones the file lacks keep their values.
inline bool read_named_tolerances(JsonReader& r, const char* const* names, GoldenTol* const* out, int n) {
  if (!r.begin_object()) return false;
  char k[64];
  while (r.next_key(k, sizeof k)) {
    int i = 0;
    while (i < n && std::strcmp(k, names[i]) != 0) ++i;
    if (!(i < n ? read_tolerance(r, *out[i]) : r.skip_value())) return false;
  }
  return r.ok();
}

/// With the reader at the value of the top-level "conventions" member: calls read_tol(r) at the
/// value of its recommended_tolerance and consumes the rest of the object.
template <typename ReadTol>
bool read_conventions_tolerance(JsonReader& r, ReadTol&& read_tol) {
  if (!r.begin_object()) return false;
  char k[64];
  while (r.next_key(k, sizeof k)) {
    if (!(std::strcmp(k, "recommended_tolerance") == 0 ? read_tol(r) : r.skip_value())) return false;
  }
  return r.ok();
}

}  // namespace ktest
