// Host-side proof that the core does not allocate: counts calls to the global allocation
// functions (operator new/delete and malloc/calloc/realloc/free via glibc's hooks-free wrappers)
// made while a HeapCounter is alive on the current thread.
//
//   kestrel::test::HeapCounter c;
//   step(...);
//   EXPECT_EQ(c.allocations(), 0u);
#pragma once

#include <cstddef>

namespace kestrel::test {

class HeapCounter {
 public:
  HeapCounter();
  ~HeapCounter();
  HeapCounter(const HeapCounter&) = delete;
  HeapCounter& operator=(const HeapCounter&) = delete;
  /// Allocations (new, new[], malloc, calloc, realloc, aligned variants) since construction.
  std::size_t allocations() const;
  /// Bytes of the largest single request since construction (set-up size checks: a loader must
  /// refuse a bad header before it sizes a buffer from it).
  std::size_t largest_allocation() const;

 private:
  std::size_t start_;
  std::size_t outer_largest_;
};

/// Total allocations seen on this thread since program start (for diagnostics).
std::size_t allocation_count();

}  // namespace kestrel::test
