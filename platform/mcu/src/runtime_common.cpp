// The part of the MCU runtime that does not depend on the core (Cortex-M and RISC-V ports): exit,
// fatal-error report, the platform's default assertion handler, libstdc++'s error paths
// (std::__throw_*) turned into a report and a non-zero exit instead of the exception machinery
// (which would pull in the heap), and the painted main stack's size and high-water mark.
// The start-up code of each port paints the stack from __stack_limit up with kStackPaint.
#include <cstdint>

#include "kestrel/platform/board.hpp"
#include "kestrel/platform/console.hpp"
#include "kestrel/platform/semihosting.hpp"
#include "runtime.h"

extern "C" {
extern std::uint32_t __stack_limit[];  // NOLINT: linker-script symbols
extern std::uint32_t __stack_top[];
}

using kestrel::platform::print;
using kestrel::platform::println;

namespace kestrel::platform::board {
namespace {
constexpr std::uint32_t kStackPaint = 0x5AC3C35Au;  // as written by the start-up code
}  // namespace

std::size_t stack_size_bytes() {
  return static_cast<std::size_t>(reinterpret_cast<std::uintptr_t>(__stack_top) -
                                  reinterpret_cast<std::uintptr_t>(__stack_limit));
}

std::size_t stack_used_bytes() {
  const std::uint32_t* p = __stack_limit;
  while (p < __stack_top && *p == kStackPaint) ++p;
  return static_cast<std::size_t>(reinterpret_cast<std::uintptr_t>(__stack_top) - reinterpret_cast<std::uintptr_t>(p));
}

void semihost_exit(int code) {
  // The Cortex-M MPU guard catches most overflows (RISC-V has no guard); a frame that skipped
  // over it shows here, as a paint word overwritten at the very bottom of the stack.
  if (*__stack_limit != kStackPaint) {
    print("\nkestrel: main stack reached its limit (overflow?)\n");
    if (code == 0) code = KESTREL_EXIT_FAULT;
  }
  semihost::exit(code);
}

}  // namespace kestrel::platform::board

extern "C" void kestrel_mcu_exit(int code) { kestrel::platform::board::semihost_exit(code); }

extern "C" void kestrel_mcu_fatal(const char* what, const char* detail) {
  println();
  print("kestrel: fatal: ");
  print(what);
  if (detail != nullptr && detail[0] != '\0') {
    print(": ");
    print(detail);
  }
  println();
  kestrel::platform::semihost::exit(KESTREL_EXIT_FATAL);
}


// Default for KESTREL_ASSERT (kernel/src/assert.cpp) when no handler is installed.
extern "C" void kestrel_platform_assert_default(const char* expr, const char* file, int line) {
  println();
  print("kestrel: assertion failed: ");
  print(expr);
  print(" (");
  print(file);
  print(":");
  kestrel::platform::print_int(line);
  println(")");
  kestrel::platform::semihost::exit(KESTREL_EXIT_FATAL);
}

// libstdc++'s error paths. libstdc++-nano's own versions call abort(); these say which one.
// All of functexcept.o's set is defined so that member is never pulled in beside them.
namespace std {
#define KESTREL_THROW_NOARG(fn) \
  void fn() { kestrel_mcu_fatal("std::" #fn, nullptr); }
#define KESTREL_THROW_MSG(fn) \
  void fn(const char* msg) { kestrel_mcu_fatal("std::" #fn, msg); }
KESTREL_THROW_NOARG(__throw_bad_exception)
KESTREL_THROW_NOARG(__throw_bad_alloc)
KESTREL_THROW_NOARG(__throw_bad_array_new_length)
KESTREL_THROW_NOARG(__throw_bad_cast)
KESTREL_THROW_NOARG(__throw_bad_typeid)
KESTREL_THROW_NOARG(__throw_bad_function_call)
KESTREL_THROW_MSG(__throw_logic_error)
KESTREL_THROW_MSG(__throw_domain_error)
KESTREL_THROW_MSG(__throw_invalid_argument)
KESTREL_THROW_MSG(__throw_length_error)
KESTREL_THROW_MSG(__throw_out_of_range)
KESTREL_THROW_MSG(__throw_runtime_error)
KESTREL_THROW_MSG(__throw_range_error)
KESTREL_THROW_MSG(__throw_overflow_error)
KESTREL_THROW_MSG(__throw_underflow_error)
// The format arguments are not expanded (that would need vsnprintf); the format names the check.
void __throw_out_of_range_fmt(const char* fmt, ...) { kestrel_mcu_fatal("std::__throw_out_of_range_fmt", fmt); }
#undef KESTREL_THROW_NOARG
#undef KESTREL_THROW_MSG
}  // namespace std
