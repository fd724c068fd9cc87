// Counts heap allocations by replacing the global operator new family and wrapping malloc,
// calloc, realloc, aligned_alloc and posix_memalign with the linker's --wrap (see
// tests/CMakeLists.txt), so allocations from C code and from libraries are seen too.
#include "heap_counter.hpp"

#include <cstdlib>
#include <new>

namespace {
thread_local std::size_t t_count = 0;
thread_local std::size_t t_largest = 0;  // largest single request since the innermost HeapCounter began
inline void note(std::size_t n) {
  ++t_count;
  if (n > t_largest) t_largest = n;
}
}

extern "C" {
void* __real_malloc(std::size_t);
void* __real_calloc(std::size_t, std::size_t);
void* __real_realloc(void*, std::size_t);
void* __real_aligned_alloc(std::size_t, std::size_t);
int __real_posix_memalign(void**, std::size_t, std::size_t);

void* __wrap_malloc(std::size_t n) {
  note(n);
  return __real_malloc(n);
}
void* __wrap_calloc(std::size_t a, std::size_t b) {
  note(b != 0 && a > static_cast<std::size_t>(-1) / b ? static_cast<std::size_t>(-1) : a * b);
  return __real_calloc(a, b);
}
void* __wrap_realloc(void* p, std::size_t n) {
  note(n);
  return __real_realloc(p, n);
}
void* __wrap_aligned_alloc(std::size_t a, std::size_t n) {
  note(n);
  return __real_aligned_alloc(a, n);
}
int __wrap_posix_memalign(void** p, std::size_t a, std::size_t n) {
  note(n);
  return __real_posix_memalign(p, a, n);
}
}

namespace {
void* counted_new(std::size_t n) {
  note(n);
  void* p = __real_malloc(n == 0 ? 1 : n);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void* counted_new_aligned(std::size_t n, std::size_t align) {
  note(n);
  void* p = nullptr;
  if (__real_posix_memalign(&p, align < sizeof(void*) ? sizeof(void*) : align, n == 0 ? 1 : n) != 0) {
    throw std::bad_alloc();
  }
  return p;
}
}  // namespace

void* operator new(std::size_t n) { return counted_new(n); }
void* operator new[](std::size_t n) { return counted_new(n); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  note(n);
  return __real_malloc(n == 0 ? 1 : n);
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  note(n);
  return __real_malloc(n == 0 ? 1 : n);
}
void* operator new(std::size_t n, std::align_val_t a) { return counted_new_aligned(n, static_cast<std::size_t>(a)); }
void* operator new[](std::size_t n, std::align_val_t a) { return counted_new_aligned(n, static_cast<std::size_t>(a)); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

namespace kestrel::test {
HeapCounter::HeapCounter() : start_(t_count), outer_largest_(t_largest) { t_largest = 0; }
HeapCounter::~HeapCounter() {
  if (outer_largest_ > t_largest) t_largest = outer_largest_;
}
std::size_t HeapCounter::allocations() const { return t_count - start_; }
std::size_t HeapCounter::largest_allocation() const { return t_largest; }
std::size_t allocation_count() { return t_count; }
}  // namespace kestrel::test
