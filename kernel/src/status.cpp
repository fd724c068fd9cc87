#include "kestrel/kernel/status.hpp"

namespace kestrel {

const char* to_string(Status s) {
  switch (s) {
    case Status::ok: return "ok";
    case Status::invalid_argument: return "invalid_argument";
    case Status::non_finite_input: return "non_finite_input";
    case Status::capacity_exceeded: return "capacity_exceeded";
    case Status::singular: return "singular";
    case Status::not_converged: return "not_converged";
    case Status::non_finite_output: return "non_finite_output";
  }
  return "unknown";
}

}  // namespace kestrel
