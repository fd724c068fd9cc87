// Board tests on the emulated MCU: SysTick against a known instruction count (the relation
// board.hpp documents: ticks * 1e9 / core clock = instructions under -icount shift=0, i.e. 40 per
// tick on the 25 MHz MPS2 boards and 125 per 21 ticks on the 168 MHz netduinoplus2; on RISC-V the
// board API's ticks are mcycle, one per instruction), systick_now() across wraps, semihosting
// file reads in chunks. Also built for the RISC-V port (platform/riscv/CMakeLists.txt).
#include <cstdint>
#include <cstring>

#include "kestrel/platform/board.hpp"
#include "kestrel/platform/console.hpp"
#include "ktest.hpp"
#include "test_io.hpp"

namespace board = kestrel::platform::board;
namespace con = kestrel::platform;

namespace {

// Exactly 2 instructions per iteration (subs; bne / addi; bnez), whatever the compiler does around it.
void spin(std::uint32_t iterations) {
#if defined(__riscv)
  asm volatile(
      "1: addi %0, %0, -1\n"
      "   bnez %0, 1b"
      : "+r"(iterations));
#else
  asm volatile(
      "1: subs %0, %0, #1\n"
      "   bne 1b"
      : "+r"(iterations)
      :
      : "cc");
#endif
}

// How far a region's count may be off: one tick where a tick is many instructions (a region's
// count depends on where in a tick it starts and ends). RISC-V counts single instructions, so the
// few instructions by which two regions' call overheads differ show: allow 16.
#if defined(KESTREL_PLATFORM_RISCV)
constexpr std::uint64_t kSlack = 16;
#else
constexpr std::uint64_t kSlack = 1;
#endif

std::uint64_t ticks_for(std::uint32_t iterations) {
  board::TickRegion region;
  spin(iterations);
  return region.elapsed();
}

volatile std::uint32_t g_callbacks = 0;
void count_callback() { g_callbacks = g_callbacks + 1; }

void print_measure(const char* what, std::uint64_t v) {
  con::print("  ");
  con::print(what);
  con::print(" ");
  con::print_uint(v);
  con::println();
}

}  // namespace

KTEST(SysTick, TicksCountCoreClockInstructionsUnderIcount) {
  board::systick_start();  // max reload (16.7M ticks): no wrap within one region below
  // 26M iterations = 52M instructions: 1.3M ticks at 25 MHz, 8.7M at 168 MHz (< 16.7M: no wrap).
  const std::uint32_t n1 = 1'000'000, n2 = 26'000'000;
  const std::uint64_t empty = board::measure_ticks([] {});
  const std::uint64_t t1 = ticks_for(n1);
  const std::uint64_t t2 = ticks_for(n2);
  board::systick_stop();
  // The difference cancels the measurement overhead: 2 * (n2 - n1) = 50M instructions. A region's
  // tick count depends on where in a tick it starts and ends, hence +-1 tick.
  const std::uint64_t instructions = 2ull * (n2 - n1);
  const std::uint64_t dt = t2 - t1;
  print_measure("core clock, Hz:", board::kCoreClockHz);
  print_measure("empty region, ticks:", empty);
  print_measure("1M iterations (2M instructions), ticks:", t1);
  print_measure("26M iterations (52M instructions), ticks:", t2);
  print_measure("difference (50M instructions), ticks:", dt);
  con::print("  instructions per tick: ");
  con::print_fixed(static_cast<double>(instructions) / static_cast<double>(dt), 5);
  con::println();
  // 50M instructions = 50 ms of virtual time = 1'250'000 ticks at 25 MHz, 8'400'000 at 168 MHz.
  const std::uint64_t expected = board::instructions_to_ticks(instructions);
  KEXPECT_EQ(expected * board::kIcountInstructionsPerSecond, instructions * board::kCoreClockHz);  // exact
  KEXPECT_GE(dt + kSlack, expected);
  KEXPECT_LE(dt, expected + kSlack);
  // t1 alone carries the region's overhead (one systick_now(), a few ticks at 168 MHz): subtract
  // the empty region's.
  KEXPECT_GE(t1 - empty + kSlack, board::instructions_to_ticks(2ull * n1));
  KEXPECT_LE(t1 - empty, board::instructions_to_ticks(2ull * n1) + kSlack);
  // And back: the conversion the benchmarks use gives the instruction count to within one tick.
  const std::uint64_t back = board::ticks_to_instructions(dt);
  const std::uint64_t one_tick = board::ticks_to_instructions(kSlack) + 1;
  KEXPECT_LE(back, instructions + one_tick);
  KEXPECT_GE(back + one_tick, instructions);
  KEXPECT_LE(board::ticks_to_instructions(empty), 40u);  // systick_now() costs < 40 instructions
}

KTEST(SysTick, NowIsMonotonicAcrossWraps) {
  g_callbacks = 0;
  board::systick_start(999, &count_callback);  // wraps every 1000 ticks (40000 instructions at 25 MHz)
  std::uint64_t prev = board::systick_now();
  bool monotonic = true;
  for (int i = 0; i < 20000; ++i) {
    const std::uint64_t now = board::systick_now();
    if (now < prev) monotonic = false;
    prev = now;
  }
  const std::uint64_t total = board::systick_now();
  const std::uint32_t wraps = board::systick_wraps();
  board::systick_stop();
  print_measure("ticks:", total);
  print_measure("wraps:", wraps);
  KEXPECT_TRUE(monotonic);
  KEXPECT_GE(wraps, 10u);
#if defined(KESTREL_PLATFORM_RISCV)
  // The callbacks come from the CLINT timer (100 instructions per mtime tick), started in its own
  // phase: within one of the counter's wraps.
  KEXPECT_LE(g_callbacks, wraps + 1u);
  KEXPECT_GE(g_callbacks + 1u, wraps);
#else
  KEXPECT_EQ(g_callbacks, wraps);
#endif
  KEXPECT_EQ(total / 1000u, wraps);
}

KTEST(Semihosting, ReadsAHostFileInChunksOfAnySize) {
  // This very source file, read three ways: whole-buffer, 4 KiB chunks, 7-byte chunks.
  static char whole[32768];
  const int h = ktest::file_open(KESTREL_BOARD_TEST_SOURCE);
  KASSERT_TRUE(h >= 0);
  const long n = ktest::file_read(h, whole, sizeof(whole) - 1);
  KEXPECT_EQ(ktest::file_read(h, whole, 16), 0);  // end of file
  ktest::file_close(h);
  KASSERT_TRUE(n > 1000 && n < static_cast<long>(sizeof(whole)) - 1);
  whole[n] = '\0';
  KEXPECT_TRUE(std::strstr(whole, "KTEST(Semihosting, ReadsAHostFileInChunksOfAnySize)") != nullptr);

  const std::size_t chunks[] = {4096, 7};
  for (std::size_t chunk : chunks) {
    static char part[4096];
    const int hc = ktest::file_open(KESTREL_BOARD_TEST_SOURCE);
    KASSERT_TRUE(hc >= 0);
    long total = 0;
    bool same = true;
    for (;;) {
      const long got = ktest::file_read(hc, part, chunk);
      if (got <= 0) break;
      if (total + got > n || std::memcmp(part, whole + total, static_cast<std::size_t>(got)) != 0) same = false;
      total += got;
    }
    ktest::file_close(hc);
    KEXPECT_EQ(total, n);
    KEXPECT_TRUE(same);
  }
  KEXPECT_EQ(ktest::file_open("/nonexistent/kestrel/file"), -1);
}

KTEST(Console, LongLinesAndNumbers) {
  // More than one console buffer (256 bytes) in a single write, then formatted numbers.
  static char line[600];
  for (std::size_t i = 0; i + 1 < sizeof(line); ++i) line[i] = static_cast<char>('a' + i % 26);
  line[sizeof(line) - 1] = '\0';
  con::println(line);
  con::print_sci(-1.2345678e-5, 5);
  con::print(" ");
  con::print_fixed(3.14159, 3);
  con::println();
  KEXPECT_TRUE(true);
}

KTEST(Board, DescribesItself) {
  con::print("  board ");
  con::print(board::kBoardName);
  con::print(", ");
  con::print(board::kCpuName);
  con::print(board::kHasDoubleFpu ? ", double-precision FPU" : board::kHasFpu ? ", single-precision FPU" : ", no FPU");
  con::println();
#if defined(KESTREL_PLATFORM_RISCV)
  KEXPECT_TRUE(std::strcmp(board::kBoardName, "virt") == 0);
  KEXPECT_TRUE(std::strncmp(board::kCpuName, "RV32IMA", 7) == 0);
#else
  KEXPECT_TRUE(std::strncmp(board::kBoardName, "mps2-an", 7) == 0 || std::strcmp(board::kBoardName, "netduinoplus2") == 0);
  KEXPECT_TRUE(std::strncmp(board::kCpuName, "Cortex-M", 8) == 0);
#endif
  KEXPECT_TRUE(board::kHasFpu || !board::kHasDoubleFpu);
}

KTEST(Stack, HighWaterMarkIsMeasured) {
  KEXPECT_GT(board::stack_used_bytes(), 0u);
  KEXPECT_LT(board::stack_used_bytes(), board::stack_size_bytes());
}
