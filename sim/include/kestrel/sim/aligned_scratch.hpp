// Caller scratch for the batched SIMD kernels (the legged and pick-and-place batched steps,
// sim/src/backends/articulated_batch.hpp): a size rounded up to 64-byte blocks, 64-byte aligned
// for their vector loads and stores, zeroed once. Allocated while setting up, never inside a step;
// one per thread.
#pragma once

#include <cstddef>
#include <vector>

namespace kestrel::sim {

class AlignedScratch {
 public:
  AlignedScratch() = default;
  explicit AlignedScratch(std::size_t bytes) { resize(bytes); }
  void resize(std::size_t bytes) { blocks_.assign((bytes + sizeof(Block) - 1) / sizeof(Block), Block{}); }
  void* data() { return blocks_.data(); }
  std::size_t bytes() const { return blocks_.size() * sizeof(Block); }

 private:
  struct alignas(64) Block {
    unsigned char b[64];
  };
  std::vector<Block> blocks_;
};

}  // namespace kestrel::sim
