// One buffer for the large objects a core test needs only while it runs (a multibody model with
// its solver data, a sensor's ray tables, a network's weights, a parsed golden record). Too big
// for an MCU test's stack, they used to be statics, each with its own .bss for the whole run: the
// core test image is every core test linked together, and on netduinoplus2 (192 KiB of RAM under
// QEMU) those statics no longer fit. The tests run one after another (the ktest runner on the
// MCU, GoogleTest on the host), so one buffer serves them all.
//
//   auto& w = ktest::scratch<SomeStruct>();  // once per test, at its start
//
// gives a value-initialised SomeStruct in the buffer: zeroed, then its member initialisers run,
// exactly as a static of it started (for a struct without a user-provided constructor, which is
// what the tests pass). A test that needs several objects puts them in one struct. The next call,
// in this test or the next one, reuses the same bytes: a reference from an earlier call is dead.
// Nothing is allocated: placement new in a static array (the MCU images link without a heap).
//
// The size is checked at compile time, on the host too, so a test that outgrows the buffer fails
// the host build in CI instead of the netduinoplus2 link nobody runs there.
#pragma once

#include <cstddef>
#include <new>
#include <type_traits>

#include "kestrel/kernel/types.hpp"

namespace ktest {

/// The largest test's need with some room (see each user's struct; the biggest is
/// test_sensor_render's mesh test, 52 KiB in a float build), in bytes of a float build: the
/// objects are nearly all reals, so a double build (host-double) gets twice as many bytes.
inline constexpr std::size_t kScratchBytes = std::size_t{56} * 1024 * sizeof(kestrel::real) / sizeof(float);
/// Enough for any Eigen fixed-size type on the host's vector units (AVX-512: 64).
inline constexpr std::size_t kScratchAlign = 64;

alignas(kScratchAlign) inline unsigned char g_scratch_buffer[kScratchBytes];

template <class T>
T& scratch() {
  static_assert(sizeof(T) <= kScratchBytes, "the test's scratch struct is larger than ktest::kScratchBytes");
  static_assert(alignof(T) <= kScratchAlign, "the test's scratch struct needs more alignment than the buffer has");
  // Never destroyed (the next test overwrites it), as a static's destructor would only run at exit.
  static_assert(std::is_trivially_destructible<T>::value, "scratch objects are never destroyed");
  return *::new (static_cast<void*>(g_scratch_buffer)) T();
}

}  // namespace ktest
