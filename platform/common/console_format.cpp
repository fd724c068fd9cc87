// Number formatting on top of console_write(), identical on every target.
#include <cmath>
#include <cstring>

#include "kestrel/platform/console.hpp"

namespace kestrel::platform {

void print(const char* s) { console_write(s, std::strlen(s)); }

void println(const char* s) {
  print(s);
  console_write("\n", 1);
}

void print_hex32(std::uint32_t v) {
  const char* hex = "0123456789abcdef";
  char buf[10] = {'0', 'x'};
  for (int i = 0; i < 8; ++i) buf[2 + i] = hex[(v >> (28 - 4 * i)) & 0xfu];
  console_write(buf, sizeof(buf));
}

void print_uint(std::uint64_t v) {
  char buf[24];
  int n = 0;
  do {
    buf[n++] = static_cast<char>('0' + v % 10u);
    v /= 10u;
  } while (v != 0 && n < 24);
  char out[24];
  for (int i = 0; i < n; ++i) out[i] = buf[n - 1 - i];
  console_write(out, static_cast<std::size_t>(n));
}

void print_int(std::int64_t v) {
  if (v < 0) {
    console_write("-", 1);
    print_uint(static_cast<std::uint64_t>(-(v + 1)) + 1u);
  } else {
    print_uint(static_cast<std::uint64_t>(v));
  }
}

void print_fixed(double v, int decimals) {
  if (std::isnan(v)) return print("nan");
  if (std::isinf(v)) return print(v < 0 ? "-inf" : "inf");
  if (decimals < 0) decimals = 0;
  if (decimals > 9) decimals = 9;
  if (v < 0) {
    console_write("-", 1);
    v = -v;
  }
  double scale = 1;
  for (int i = 0; i < decimals; ++i) scale *= 10;
  if (v * scale >= 1.8e19) return print_sci(v, decimals + 1);
  const std::uint64_t total = static_cast<std::uint64_t>(v * scale + 0.5);
  const std::uint64_t s = static_cast<std::uint64_t>(scale);
  print_uint(total / s);
  if (decimals > 0) {
    console_write(".", 1);
    std::uint64_t frac = total % s;
    char buf[10];
    for (int i = decimals - 1; i >= 0; --i) {
      buf[i] = static_cast<char>('0' + frac % 10u);
      frac /= 10u;
    }
    console_write(buf, static_cast<std::size_t>(decimals));
  }
}

void print_sci(double v, int digits) {
  if (std::isnan(v)) return print("nan");
  if (std::isinf(v)) return print(v < 0 ? "-inf" : "inf");
  if (digits < 1) digits = 1;
  if (v < 0) {
    console_write("-", 1);
    v = -v;
  }
  int e = 0;
  if (v != 0) {
    while (v >= 10) {
      v /= 10;
      ++e;
    }
    while (v < 1) {
      v *= 10;
      --e;
    }
  }
  double scale = 1;
  for (int i = 1; i < digits; ++i) scale *= 10;
  std::uint64_t m = static_cast<std::uint64_t>(v * scale + 0.5);
  if (m >= static_cast<std::uint64_t>(scale * 10)) {  // rounding carried into a new digit
    m /= 10u;
    ++e;
  }
  const std::uint64_t s = static_cast<std::uint64_t>(scale);
  print_uint(m / s);
  if (digits > 1) {
    console_write(".", 1);
    std::uint64_t frac = m % s;
    char buf[20];
    for (int i = digits - 2; i >= 0; --i) {
      buf[i] = static_cast<char>('0' + frac % 10u);
      frac /= 10u;
    }
    console_write(buf, static_cast<std::size_t>(digits - 1));
  }
  console_write(e < 0 ? "e-" : "e+", 2);
  const int ae = e < 0 ? -e : e;
  if (ae < 10) console_write("0", 1);
  print_int(ae);
}

}  // namespace kestrel::platform
