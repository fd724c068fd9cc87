// Assertion hook. Asserts guard programming errors (violated preconditions inside the core), never
// bad user input — that is reported through Status and fault flags. The handler is set by the
// platform: the host prints and aborts, an MCU reports over its console and halts or resets.
#pragma once

namespace kestrel {

using AssertHandler = void (*)(const char* expr, const char* file, int line);

/// Install a handler; returns the previous one. nullptr restores the platform default.
AssertHandler set_assert_handler(AssertHandler handler);

/// Called by KESTREL_ASSERT on failure. Does not return unless the handler returns.
void assert_failed(const char* expr, const char* file, int line);

/// Weak default provided by the platform layer (kestrel_platform_assert_default).
}  // namespace kestrel

#if defined(KESTREL_DISABLE_ASSERTS)
#define KESTREL_ASSERT(cond) ((void)0)
#else
#define KESTREL_ASSERT(cond) ((cond) ? (void)0 : ::kestrel::assert_failed(#cond, __FILE__, __LINE__))
#endif
