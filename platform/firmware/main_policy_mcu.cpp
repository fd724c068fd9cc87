// Cortex-M build of the policy firmware example: SysTick at the control rate, WFI between ticks;
// under QEMU -icount shift=0 the costs are instruction counts.
#include "kestrel/platform/board.hpp"
#include "kestrel/platform/console.hpp"
#include "loop_clock.hpp"
#include "policy_loop.hpp"

namespace board = kestrel::platform::board;

namespace {
kestrel::firmware::FlightStack g_stack;
kestrel::firmware::Plant g_plant;
}  // namespace

int main() {
  using namespace kestrel::firmware;
  const FlightConfig config;
  loop_clock::start_ticks(config.control_rate_hz);
  PolicyFlightReport report;
  if (fly_policy(config, g_stack, g_plant, &loop_clock::now_ticks, &loop_clock::wait_for_tick, report) !=
      kestrel::Status::ok) {
    kestrel::platform::println("firmware policy example: initialisation failed");
    return 1;
  }
  board::systick_stop();
  char target[96];
  loop_clock::describe_target(target);
  print_policy_report(report, target, "instructions", static_cast<double>(board::kIcountInstructionsPerTick));
  loop_clock::print_stack_use();
  const bool ok = policy_flight_pass(report);
  kestrel::platform::println(ok ? "firmware policy example: PASS" : "firmware policy example: FAIL");
  return ok ? 0 : 1;
}
