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
  char target[96] = "QEMU ";
  {
    // "<cpu>, QEMU <board>, -icount shift=0" without snprintf (newlib's pulls in malloc).
    const char* parts[] = {board::kCpuName, ", QEMU ", board::kBoardName, ", -icount shift=0"};
    std::size_t n = 0;
    for (const char* p : parts)
      for (; *p != '\0' && n + 1 < sizeof(target); ++p) target[n++] = *p;
    target[n] = '\0';
  }
  hexa_print_report(config, report, target, "instructions", static_cast<double>(board::kIcountInstructionsPerTick));
  kestrel::platform::print("  stack used: ");
  kestrel::platform::print_uint(board::stack_used_bytes());
  kestrel::platform::print(" of ");
  kestrel::platform::print_uint(board::stack_size_bytes());
  kestrel::platform::println(" bytes");
  const bool ok = hexa_pass(config, report);
  kestrel::platform::println(ok ? "hexarotor firmware example: PASS" : "hexarotor firmware example: FAIL");
  return ok ? 0 : 1;
}
