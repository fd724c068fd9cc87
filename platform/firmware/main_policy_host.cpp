// Host build of the policy firmware example: the same loop, timed with the steady clock.
#include <cstdio>

#include "kestrel/platform/console.hpp"
#include "loop_clock.hpp"
#include "policy_loop.hpp"

int main() {
  using namespace kestrel::firmware;
  static FlightStack stack;
  static Plant plant;
  const FlightConfig config;
  PolicyFlightReport report;
  if (fly_policy(config, stack, plant, &loop_clock::now_ns, nullptr, report) != kestrel::Status::ok) {
    std::fprintf(stderr, "firmware policy example: initialisation failed\n");
    return 1;
  }
  print_policy_report(report, "host", "ns", 1.0);
  const bool ok = policy_flight_pass(report);
  kestrel::platform::println(ok ? "firmware policy example: PASS" : "firmware policy example: FAIL");
  return ok ? 0 : 1;
}
