// Cortex-M build of the firmware example: SysTick interrupts at the control rate, the loop sleeps
// (WFI) until each tick, and the control and plant steps are timed with SysTick. Under QEMU with
// -icount shift=0 one tick is exactly 40 instructions, so the costs are instruction counts.
#include <cstddef>
#include <cstdint>

#include "flight_loop.hpp"
#include "kestrel/platform/board.hpp"
#include "loop_clock.hpp"
#include "kestrel/platform/console.hpp"

namespace board = kestrel::platform::board;

namespace {
using kestrel::firmware::loop_clock::now_ticks;
using kestrel::firmware::loop_clock::wait_for_tick;

// Static: the whole control stack lives in .bss, sized at link time.
kestrel::firmware::FlightStack g_stack;
kestrel::firmware::Plant g_plant;
}  // namespace

int main() {
  using namespace kestrel::firmware;
  const FlightConfig config;
  kestrel::firmware::loop_clock::start_ticks(config.control_rate_hz);
  FlightReport report;
  if (fly(config, g_stack, g_plant, &now_ticks, &wait_for_tick, report) != kestrel::Status::ok) {
    kestrel::platform::println("firmware example: initialisation failed");
    return 1;
  }
  board::systick_stop();
  char target[96];
  kestrel::firmware::loop_clock::describe_target(target);
  print_report(config, report, target, "instructions",
               static_cast<double>(board::kIcountInstructionsPerTick));
  // Steady-state cost without the loop: 1000 back-to-back steps.
  board::systick_start();
  const std::uint64_t ticks = time_control_steps(g_stack, 1000, &now_ticks);
  board::systick_stop();
  kestrel::platform::print("  back-to-back control step: ");
  kestrel::platform::print_fixed(static_cast<double>(board::ticks_to_instructions(ticks)) / 1000.0, 1);
  kestrel::platform::println(" instructions (1000 steps)");
  kestrel::firmware::loop_clock::print_stack_use();
  const bool ok = flight_pass(report);
  kestrel::platform::println(ok ? "firmware example: PASS" : "firmware example: FAIL");
  return ok ? 0 : 1;
}
