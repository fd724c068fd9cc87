// Host build of the hexarotor firmware example: the same loop as the MCU image, timed with the
// steady clock (reported, never asserted: the host is shared and noisy).
#include <cstdio>

#include "hexa_loop.hpp"
#include "kestrel/platform/console.hpp"
#include "loop_clock.hpp"

namespace {
using kestrel::firmware::loop_clock::now_ns;
}  // namespace

int main() {
  using namespace kestrel::firmware;
  static HexaStack stack;  // static, as on the MCU: nothing of the stack on the heap
  static HexaPlant plant;
  HexaReport report;
  if (hexa_fly(kHexaConfig, stack, plant, &now_ns, nullptr, report) != kestrel::Status::ok) {
    std::fprintf(stderr, "hexarotor firmware example: initialisation failed\n");
    return 1;
  }
  hexa_print_report(kHexaConfig, report, "host", "ns", 1.0);
  const bool ok = hexa_pass(kHexaConfig, report);
  kestrel::platform::println(ok ? "hexarotor firmware example: PASS" : "hexarotor firmware example: FAIL");
  return ok ? 0 : 1;
}
