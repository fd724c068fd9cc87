// Heap canary: an image that allocates. It must NOT link (see cmake/KestrelMcu.cmake); the ctests
// mcu.heap_canary_*_link_fails build it and pass only on "undefined reference to `__wrap_...'".
#include <cstdlib>
#include <new>

// Volatile so the compiler cannot elide the allocation (it may drop a malloc/free pair).
void* volatile g_sink;

int main() {
#if defined(KESTREL_CANARY_MALLOC)
  g_sink = std::malloc(64);
#elif defined(KESTREL_CANARY_NEW)
  g_sink = new int(16);
#else
#error "define KESTREL_CANARY_MALLOC or KESTREL_CANARY_NEW"
#endif
  return g_sink != nullptr ? 0 : 1;
}
