// Fixed-capacity containers (ETL-style: capacity in the type, overflow is an answer, not a crash).
#pragma once

#include <cstddef>

#include "kestrel/kernel/assert.hpp"
#include "kestrel/kernel/status.hpp"

namespace kestrel {

/// A vector with compile-time capacity N and no heap. push_back on a full vector returns
/// Status::capacity_exceeded and leaves the contents unchanged.
template <typename T, std::size_t N>
class FixedVector {
 public:
  static constexpr std::size_t kCapacity = N;

  [[nodiscard]] Status push_back(const T& v) {
    if (size_ >= N) return Status::capacity_exceeded;
    data_[size_++] = v;
    return Status::ok;
  }
  void pop_back() {
    KESTREL_ASSERT(size_ > 0);
    --size_;
  }
  void clear() { size_ = 0; }
  [[nodiscard]] Status resize(std::size_t n, const T& fill = T()) {
    if (n > N) return Status::capacity_exceeded;
    for (std::size_t i = size_; i < n; ++i) data_[i] = fill;
    size_ = n;
    return Status::ok;
  }

  std::size_t size() const { return size_; }
  static constexpr std::size_t capacity() { return N; }
  bool empty() const { return size_ == 0; }
  bool full() const { return size_ == N; }

  T& operator[](std::size_t i) {
    KESTREL_ASSERT(i < size_);
    return data_[i];
  }
  const T& operator[](std::size_t i) const {
    KESTREL_ASSERT(i < size_);
    return data_[i];
  }
  T* begin() { return data_; }
  T* end() { return data_ + size_; }
  const T* begin() const { return data_; }
  const T* end() const { return data_ + size_; }
  T* data() { return data_; }
  const T* data() const { return data_; }

 private:
  T data_[N] = {};
  std::size_t size_ = 0;
};

/// A FIFO ring buffer with compile-time capacity N (used for action-delay queues).
/// push() on a full buffer returns Status::capacity_exceeded unless overwrite is requested.
template <typename T, std::size_t N>
class RingBuffer {
 public:
  static_assert(N > 0, "RingBuffer needs a capacity");
  static constexpr std::size_t kCapacity = N;

  [[nodiscard]] Status push(const T& v) {
    if (size_ == N) return Status::capacity_exceeded;
    data_[(head_ + size_) % N] = v;
    ++size_;
    return Status::ok;
  }
  /// Push, dropping the oldest element when full.
  void push_overwrite(const T& v) {
    if (size_ == N) {
      head_ = (head_ + 1) % N;
      --size_;
    }
    data_[(head_ + size_) % N] = v;
    ++size_;
  }
  [[nodiscard]] Status pop(T& out) {
    if (size_ == 0) return Status::capacity_exceeded;
    out = data_[head_];
    head_ = (head_ + 1) % N;
    --size_;
    return Status::ok;
  }
  /// i-th oldest element (0 = front).
  const T& at(std::size_t i) const {
    KESTREL_ASSERT(i < size_);
    return data_[(head_ + i) % N];
  }
  T& at(std::size_t i) {
    KESTREL_ASSERT(i < size_);
    return data_[(head_ + i) % N];
  }
  void clear() {
    head_ = 0;
    size_ = 0;
  }
  std::size_t size() const { return size_; }
  static constexpr std::size_t capacity() { return N; }
  bool empty() const { return size_ == 0; }
  bool full() const { return size_ == N; }

 private:
  T data_[N] = {};
  std::size_t head_ = 0;
  std::size_t size_ = 0;
};

}  // namespace kestrel
