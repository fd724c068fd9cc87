// Host build of the firmware example: the same loop, timed with the steady clock.
#include <cstdio>

#include "flight_loop.hpp"
#include "kestrel/platform/console.hpp"
#include "loop_clock.hpp"

namespace {
using kestrel::firmware::loop_clock::now_ns;
}  // namespace

int main() {
  using namespace kestrel::firmware;
  static FlightStack stack;
  static Plant plant;
  const FlightConfig config;
  FlightReport report;
  if (fly(config, stack, plant, &now_ns, nullptr, report) != kestrel::Status::ok) {
    std::fprintf(stderr, "firmware example: initialisation failed\n");
    return 1;
  }
  print_report(config, report, "host", "ns", 1.0);
  // Steady-state cost: many back-to-back steps, best of 5 runs (the host is shared and noisy).
  const int n = 100000;
  std::uint64_t best = ~0ull;
  for (int rep = 0; rep < 5; ++rep) {
    const std::uint64_t t = time_control_steps(stack, n, &now_ns);
    best = t < best ? t : best;
  }
  kestrel::platform::print("  back-to-back control step: ");
  kestrel::platform::print_fixed(static_cast<double>(best) / n, 1);
  kestrel::platform::println(" ns (best of 5 x 100000)");
  const bool ok = flight_pass(report);
  kestrel::platform::println(ok ? "firmware example: PASS" : "firmware example: FAIL");
  return ok ? 0 : 1;
}
