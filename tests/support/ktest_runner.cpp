// Kestrel's own test runner for the ktest macros (ktest.hpp, non-GoogleTest branch): the core
// tests on the emulated MCU. No heap, no exceptions, no stdio: tests register themselves into a
// fixed-capacity table from static constructors, main() runs them in registration order and
// reports through the platform console (kestrel/platform/console.hpp).
//
// Output: one line per test ("[ RUN ]" / "[  OK  ]" / "[ FAIL ]" / "[ SKIP ]"), each failure as
// "file:line: Failure" plus the expression and values, and last a line exactly
// "<passed> passed, <failed> failed" with ", <skipped> skipped" appended if any were skipped.
// main() returns 1 if any test failed (the MCU image exits with that status), else 0.
#include <cstdint>

#include "kestrel/platform/console.hpp"
#include "ktest.hpp"
#if defined(KESTREL_PLATFORM_CORTEX_M) || defined(KESTREL_PLATFORM_RISCV)
#include "kestrel/platform/board.hpp"
#endif

#ifndef KTEST_MAX_TESTS
#define KTEST_MAX_TESTS 320  // 12 bytes each (the core suite has ~160; the netduinoplus2 image is short of RAM); raise with -DKTEST_MAX_TESTS=<n>
#endif

namespace ktest {
namespace {

namespace con = kestrel::platform;

struct Entry {
  const char* suite;
  const char* name;
  TestFn fn;
};

Entry g_tests[KTEST_MAX_TESTS];
int g_count = 0;
int g_dropped = 0;  // registrations beyond KTEST_MAX_TESTS

bool g_failed = false;   // current test
bool g_skipped = false;  // current test

void print_location(const char* file, int line) {
  con::print(file);
  con::print(":");
  con::print_int(line);
  con::println(": Failure");
}

// Integers print as integers; a value that is exactly a float32 prints with 9 significant digits
// (enough to tell any two floats apart), anything else with 17 (any two doubles).
void print_value(double v) {
  if (v == v && v >= -9.0e15 && v <= 9.0e15 && v == static_cast<double>(static_cast<std::int64_t>(v))) {
    con::print_int(static_cast<std::int64_t>(v));
    return;
  }
  const bool is_float = static_cast<double>(static_cast<float>(v)) == v;
  con::print_sci(v, is_float ? 9 : 17);
}

}  // namespace

Registrar::Registrar(const char* suite, const char* name, TestFn fn) {
  if (g_count < KTEST_MAX_TESTS) {
    g_tests[g_count++] = Entry{suite, name, fn};
  } else {
    ++g_dropped;
  }
}

void fail(const char* file, int line, const char* expr) {
  g_failed = true;
  print_location(file, line);
  con::print("  expected: ");
  con::println(expr);
}

void fail_values(const char* file, int line, const char* expr, double a, double b) {
  g_failed = true;
  print_location(file, line);
  con::print("  expected: ");
  con::println(expr);
  con::print("  values:   ");
  print_value(a);
  con::print(" vs ");
  print_value(b);
  con::println();
}

void fail_close(const char* file, int line, const char* what, double actual, double expected, double tol) {
  g_failed = true;
  print_location(file, line);
  con::print("  ");
  con::print(what);
  con::print(": actual ");
  print_value(actual);
  con::print(" expected ");
  print_value(expected);
  con::print(" (|diff| ");
  print_value(actual > expected ? actual - expected : expected - actual);
  con::print(" > tol ");
  print_value(tol);
  con::println(")");
}

void skip(const char* msg) {
  g_skipped = true;
  con::print("  skipped: ");
  con::println(msg);
}

void note(const char* msg) {
  con::print("  note: ");
  con::println(msg);
}

bool current_failed() { return g_failed; }

}  // namespace ktest

int main() {
  namespace con = kestrel::platform;
  using ktest::g_tests;
  int passed = 0, failed = 0, skipped = 0;
  con::print("ktest: ");
  con::print_int(ktest::g_count);
  con::println(" tests");
  if (ktest::g_dropped > 0) {
    con::print("ktest: registry full, ");
    con::print_int(ktest::g_dropped);
    con::println(" tests not registered: raise KTEST_MAX_TESTS");
    failed += ktest::g_dropped;
  }
  for (int i = 0; i < ktest::g_count; ++i) {
    const ktest::Entry& t = g_tests[i];
    con::print("[ RUN  ] ");
    con::print(t.suite);
    con::print(".");
    con::println(t.name);
    ktest::g_failed = false;
    ktest::g_skipped = false;
    t.fn();
    if (ktest::g_failed) {
      ++failed;
      con::print("[ FAIL ] ");
    } else if (ktest::g_skipped) {
      ++skipped;
      con::print("[ SKIP ] ");
    } else {
      ++passed;
      con::print("[  OK  ] ");
    }
    con::print(t.suite);
    con::print(".");
    con::println(t.name);
  }
#if defined(KESTREL_PLATFORM_CORTEX_M) || defined(KESTREL_PLATFORM_RISCV)
  con::print("ktest: main stack used ");
  con::print_uint(kestrel::platform::board::stack_used_bytes());
  con::print(" of ");
  con::print_uint(kestrel::platform::board::stack_size_bytes());
  con::println(" bytes");
#endif
  con::print_int(passed);
  con::print(" passed, ");
  con::print_int(failed);
  con::print(" failed");
  if (skipped > 0) {
    con::print(", ");
    con::print_int(skipped);
    con::print(" skipped");
  }
  con::println();
  return failed > 0 ? 1 : 0;
}
