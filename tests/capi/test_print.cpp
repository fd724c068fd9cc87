// Console for the C test program: C has no access to the C++ console (kestrel/platform/console.hpp),
// and printf is not an option on the MCU (newlib's float formatting pulls in malloc).
#include "kestrel/platform/console.hpp"

extern "C" void capi_test_print(const char* s) { kestrel::platform::print(s); }
extern "C" void capi_test_print_fixed(double v, int decimals) { kestrel::platform::print_fixed(v, decimals); }
extern "C" void capi_test_print_int(long v) { kestrel::platform::print_int(v); }
