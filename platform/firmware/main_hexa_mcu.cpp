// Cortex-M build of the hexarotor firmware example: SysTick interrupts at the 1 kHz scheduler
// tick, the loop sleeps (WFI) until each tick. Under QEMU -icount shift=0 one SysTick tick is
// exactly 40 instructions, so the per-tick costs printed are instruction counts.
#include <cstddef>
#include <cstdint>

#include "hexa_loop.hpp"
#include "kestrel/platform/board.hpp"
#include "loop_clock.hpp"
#include "kestrel/platform/console.hpp"

namespace board = kestrel::platform::board;

namespace {
using kestrel::firmware::loop_clock::now_ticks;
using kestrel::firmware::loop_clock::wait_for_tick;

// Static: the whole stack, the plant and the scene live in .bss, sized at link time.
kestrel::firmware::HexaStack g_stack;
kestrel::firmware::HexaPlant g_plant;
}  // namespace

int main() {
  using namespace kestrel::firmware;
  const HexaConfig& config = kHexaConfig;
  kestrel::firmware::loop_clock::start_ticks(config.tick_hz);
  HexaReport report;
  if (hexa_fly(config, g_stack, g_plant, &now_ticks, &wait_for_tick, report) != kestrel::Status::ok) {
    kestrel::platform::println("hexarotor firmware example: initialisation failed");
    return 1;
  }
  board::systick_stop();
  char target[96];
  kestrel::firmware::loop_clock::describe_target(target);
  hexa_print_report(config, report, target, "instructions", static_cast<double>(board::kIcountInstructionsPerTick));
  kestrel::firmware::loop_clock::print_stack_use();
  const bool ok = hexa_pass(config, report);
  kestrel::platform::println(ok ? "hexarotor firmware example: PASS" : "hexarotor firmware example: FAIL");
  return ok ? 0 : 1;
}
