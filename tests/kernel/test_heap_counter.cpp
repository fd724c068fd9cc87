// The allocation counter must be able to fail: it sees new, malloc and library allocations.
// (Host only: the MCU images have no heap at all, which their link proves.)
#include "ktest.hpp"

#if defined(KESTREL_TEST_GTEST)
#include <cstdlib>
#include <memory>
#include <vector>

#include "heap_counter.hpp"

namespace {
// Pointers escape through this so the compiler cannot elide the allocations (-fallocation-dce).
void* volatile g_sink = nullptr;
}  // namespace

KTEST(HeapCounter, CountsNewMallocAndContainers) {
  kestrel::test::HeapCounter c;
  KEXPECT_EQ(c.allocations(), 0u);
  auto p = std::make_unique<int>(3);
  g_sink = p.get();
  KEXPECT_EQ(c.allocations(), 1u);
  void* m = std::malloc(16);
  g_sink = m;
  KEXPECT_EQ(c.allocations(), 2u);
  std::free(m);
  std::vector<double> v(100);
  g_sink = v.data();
  KEXPECT_EQ(c.allocations(), 3u);
}

KTEST(HeapCounter, NestedScopesCountIndependently) {
  kestrel::test::HeapCounter outer;
  {
    auto a = std::make_unique<int>(1);
    g_sink = a.get();
  }
  kestrel::test::HeapCounter inner;
  KEXPECT_EQ(inner.allocations(), 0u);
  KEXPECT_EQ(outer.allocations(), 1u);
}
#endif
