// Console output for the host and the boards: plain text without printf (newlib's printf pulls
// in malloc for floating-point formatting, and the MCU images link without a heap).
#pragma once

#include <cstddef>
#include <cstdint>

namespace kestrel::platform {

/// Writes n bytes to the console (host: stdout; MCU: semihosting).
void console_write(const char* s, std::size_t n);

void print(const char* s);
void print_int(std::int64_t v);
void print_uint(std::uint64_t v);
/// Fixed-point with `decimals` digits after the point; handles nan/inf. Uses double arithmetic
/// only on the host-facing reporting path, never in the control core.
void print_fixed(double v, int decimals);
/// Scientific notation with `digits` significant digits (e.g. 1.234e-05).
void print_sci(double v, int digits);
void println(const char* s = "");
/// "0x" and eight lower-case hex digits (fault-flag words).
void print_hex32(std::uint32_t v);

}  // namespace kestrel::platform
