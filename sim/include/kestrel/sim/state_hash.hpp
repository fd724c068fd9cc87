// The state hashes of the backends and worlds (Simulator::state_hash, World::state_hash,
// PickPlaceWorld::state_hash): FNV-1a 64 (G. Fowler, L. C. Noll, K.-P. Vo) over the bytes of the
// state in a fixed order, so equal states give equal hashes on every run and thread count.
#pragma once

#include <cstddef>
#include <cstdint>

namespace kestrel::sim {

struct Fnv1a {
  std::uint64_t h = 1469598103934665603ull;  // the 64-bit offset basis
  void bytes(const void* p, std::size_t n) {
    const unsigned char* c = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) {
      h ^= c[i];
      h *= 1099511628211ull;
    }
  }
  template <class T>
  void pod(const T& v) { bytes(&v, sizeof(T)); }
  /// x's eight bytes, least significant first (the same on every host).
  void u64_le(std::uint64_t x) {
    for (int b = 0; b < 8; ++b) {
      h ^= (x >> (8 * b)) & 0xffu;
      h *= 1099511628211ull;
    }
  }
};

}  // namespace kestrel::sim
