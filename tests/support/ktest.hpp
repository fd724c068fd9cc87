// ktest: the core tests are written once against these macros and run twice — under GoogleTest
// on the host and under Kestrel's own tiny runner on the emulated MCU (no heap, no exceptions, no
// iostreams, output through the platform console). Keep to the macros below so a test builds on
// both.
#pragma once

#include <cmath>
#include <cstddef>

#if defined(KESTREL_TEST_GTEST)
#include <gtest/gtest.h>

#define KTEST(suite, name) TEST(suite, name)
#define KEXPECT_TRUE(c) EXPECT_TRUE(c)
#define KEXPECT_FALSE(c) EXPECT_FALSE(c)
#define KEXPECT_EQ(a, b) EXPECT_EQ(a, b)
#define KEXPECT_NE(a, b) EXPECT_NE(a, b)
#define KEXPECT_LT(a, b) EXPECT_LT(a, b)
#define KEXPECT_LE(a, b) EXPECT_LE(a, b)
#define KEXPECT_GT(a, b) EXPECT_GT(a, b)
#define KEXPECT_GE(a, b) EXPECT_GE(a, b)
#define KEXPECT_NEAR(a, b, tol) EXPECT_NEAR(a, b, tol)
#define KASSERT_TRUE(c) ASSERT_TRUE(c)
#define KASSERT_EQ(a, b) ASSERT_EQ(a, b)
/// |actual - expected| <= abs + rel * |expected| (the golden tolerance rule). `what` names the value.
#define KEXPECT_CLOSE(actual, expected, abs_tol, rel_tol, what)                                                   \
  EXPECT_LE(std::fabs(static_cast<double>(actual) - static_cast<double>(expected)),                            \
            static_cast<double>(abs_tol) + static_cast<double>(rel_tol) * std::fabs(static_cast<double>(expected))) \
      << (what) << ": actual " << static_cast<double>(actual) << " expected " << static_cast<double>(expected)
#define KTEST_SKIP(msg) GTEST_SKIP() << (msg)
#define KTEST_NOTE(msg) ::testing::Test::RecordProperty("note", msg)
#include "heap_counter.hpp"
/// Runs `stmt` and expects it made no heap allocation (host: counted; MCU: the link has no heap).
#define KEXPECT_NO_HEAP(stmt)                                                   \
  do {                                                                          \
    ::kestrel::test::HeapCounter ktest_heap_;                                   \
    stmt;                                                                       \
    EXPECT_EQ(ktest_heap_.allocations(), 0u) << "heap allocation in: " #stmt;   \
  } while (0)

#else  // Kestrel's own runner (MCU)

namespace ktest {
using TestFn = void (*)();
struct Registrar {
  Registrar(const char* suite, const char* name, TestFn fn);
};
void fail(const char* file, int line, const char* expr);
void fail_values(const char* file, int line, const char* expr, double a, double b);
void fail_close(const char* file, int line, const char* what, double actual, double expected, double tol);
void skip(const char* msg);
void note(const char* msg);
bool current_failed();
}  // namespace ktest

#define KTEST_CAT2(a, b) a##b
#define KTEST_CAT(a, b) KTEST_CAT2(a, b)
#define KTEST(suite, name)                                                              \
  static void ktest_##suite##_##name();                                                 \
  static ::ktest::Registrar KTEST_CAT(ktest_reg_##suite##_##name, __LINE__)(#suite, #name, \
                                                                           &ktest_##suite##_##name); \
  static void ktest_##suite##_##name()

#define KEXPECT_TRUE(c) ((c) ? (void)0 : ::ktest::fail(__FILE__, __LINE__, #c))
#define KEXPECT_FALSE(c) (!(c) ? (void)0 : ::ktest::fail(__FILE__, __LINE__, "!(" #c ")"))
#define KTEST_CMP(a, b, op)                                                                       \
  do {                                                                                            \
    const auto ktest_a_ = (a);                                                                    \
    const auto ktest_b_ = (b);                                                                    \
    if (!(ktest_a_ op ktest_b_))                                                                  \
      ::ktest::fail_values(__FILE__, __LINE__, #a " " #op " " #b, static_cast<double>(ktest_a_), \
                           static_cast<double>(ktest_b_));                                        \
  } while (0)
#define KEXPECT_EQ(a, b) KTEST_CMP(a, b, ==)
#define KEXPECT_NE(a, b) KTEST_CMP(a, b, !=)
#define KEXPECT_LT(a, b) KTEST_CMP(a, b, <)
#define KEXPECT_LE(a, b) KTEST_CMP(a, b, <=)
#define KEXPECT_GT(a, b) KTEST_CMP(a, b, >)
#define KEXPECT_GE(a, b) KTEST_CMP(a, b, >=)
#define KEXPECT_NEAR(a, b, tol)                                                                       \
  do {                                                                                                \
    const double ktest_a_ = static_cast<double>(a), ktest_b_ = static_cast<double>(b);                \
    if (!(std::fabs(ktest_a_ - ktest_b_) <= static_cast<double>(tol)))                                \
      ::ktest::fail_close(__FILE__, __LINE__, #a " ~ " #b, ktest_a_, ktest_b_, static_cast<double>(tol)); \
  } while (0)
#define KASSERT_TRUE(c)                                   \
  do {                                                    \
    if (!(c)) {                                           \
      ::ktest::fail(__FILE__, __LINE__, #c);              \
      return;                                             \
    }                                                     \
  } while (0)
#define KASSERT_EQ(a, b)                   \
  do {                                     \
    KTEST_CMP(a, b, ==);                   \
    if (::ktest::current_failed()) return; \
  } while (0)
#define KEXPECT_CLOSE(actual, expected, abs_tol, rel_tol, what)                                           \
  do {                                                                                                    \
    const double ktest_a_ = static_cast<double>(actual), ktest_e_ = static_cast<double>(expected);        \
    const double ktest_t_ = static_cast<double>(abs_tol) + static_cast<double>(rel_tol) * std::fabs(ktest_e_); \
    if (!(std::fabs(ktest_a_ - ktest_e_) <= ktest_t_)) ::ktest::fail_close(__FILE__, __LINE__, what, ktest_a_, ktest_e_, ktest_t_); \
  } while (0)
#define KTEST_SKIP(msg)    \
  do {                     \
    ::ktest::skip(msg);    \
    return;                \
  } while (0)
#define KTEST_NOTE(msg) ::ktest::note(msg)
/// On the MCU there is no heap to count: the image links without one (see platform/).
#define KEXPECT_NO_HEAP(stmt) \
  do {                        \
    stmt;                     \
  } while (0)

#endif
