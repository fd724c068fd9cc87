#include "kestrel/kernel/rng.hpp"

#include <cmath>

namespace kestrel {

// Philox4x32-10 constants from Salmon et al. (2011), table 2 / Random123.
namespace {
constexpr std::uint32_t kPhiloxM0 = 0xD2511F53u;
constexpr std::uint32_t kPhiloxM1 = 0xCD9E8D57u;
constexpr std::uint32_t kPhiloxW0 = 0x9E3779B9u;  // golden ratio
constexpr std::uint32_t kPhiloxW1 = 0xBB67AE85u;  // sqrt(3) - 1

inline void mulhilo(std::uint32_t a, std::uint32_t b, std::uint32_t& hi, std::uint32_t& lo) {
  const std::uint64_t p = static_cast<std::uint64_t>(a) * b;
  hi = static_cast<std::uint32_t>(p >> 32);
  lo = static_cast<std::uint32_t>(p);
}
}  // namespace

void philox4x32_10(const std::uint32_t counter[4], const std::uint32_t key[2], std::uint32_t out[4]) {
  std::uint32_t c0 = counter[0], c1 = counter[1], c2 = counter[2], c3 = counter[3];
  std::uint32_t k0 = key[0], k1 = key[1];
  for (int round = 0; round < 10; ++round) {
    std::uint32_t hi0, lo0, hi1, lo1;
    mulhilo(kPhiloxM0, c0, hi0, lo0);
    mulhilo(kPhiloxM1, c2, hi1, lo1);
    const std::uint32_t n0 = hi1 ^ c1 ^ k0;
    const std::uint32_t n1 = lo1;
    const std::uint32_t n2 = hi0 ^ c3 ^ k1;
    const std::uint32_t n3 = lo0;
    c0 = n0;
    c1 = n1;
    c2 = n2;
    c3 = n3;
    k0 += kPhiloxW0;
    k1 += kPhiloxW1;
  }
  out[0] = c0;
  out[1] = c1;
  out[2] = c2;
  out[3] = c3;
}

RngStream::RngStream(std::uint64_t seed, std::uint32_t stream_id, std::uint32_t purpose)
    : key_{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32)},
      stream_(stream_id),
      purpose_(purpose) {}

void RngStream::refill() {
  // Counter = (block index low, block index high, stream id, purpose): distinct streams and
  // purposes never share a counter value under the same key.
  const std::uint32_t ctr[4] = {static_cast<std::uint32_t>(block_), static_cast<std::uint32_t>(block_ >> 32), stream_,
                                purpose_};
  philox4x32_10(ctr, key_, buf_);
  word_ = 0;
}

std::uint32_t RngStream::next_u32() {
  if (word_ >= 4) refill();
  const std::uint32_t v = buf_[word_++];
  if (word_ == 4) ++block_;
  return v;
}

void RngStream::seek(std::uint64_t n) {
  block_ = n / 4u;
  const std::uint32_t w = static_cast<std::uint32_t>(n % 4u);
  if (w == 0) {
    word_ = 4;  // refill lazily
  } else {
    refill();
    word_ = w;
  }
}

real RngStream::uniform() {
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
  const std::uint64_t hi = next_u32() >> 5;  // 27 bits
  const std::uint64_t lo = next_u32() >> 6;  // 26 bits
  return static_cast<double>((hi << 26) | lo) * (1.0 / 9007199254740992.0);
#else
  return static_cast<float>(next_u32() >> 8) * (1.0f / 16777216.0f);
#endif
}

real RngStream::uniform(real lo, real hi) {
  const real r = lo + (hi - lo) * uniform();
  // In float, lo + (hi - lo) * u can round up to hi for u just below 1.
  return (r < hi || !(hi > lo)) ? r : std::nextafter(hi, lo);
}

real RngStream::normal() {
  // u1 in (0, 1] so log() is finite.
  const real u1 = real(1) - uniform();
  const real u2 = uniform();
  return std::sqrt(real(-2) * std::log(u1)) * std::cos(kTwoPi * u2);
}

}  // namespace kestrel
