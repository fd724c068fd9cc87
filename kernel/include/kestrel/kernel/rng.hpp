// Counter-based deterministic random streams.
//
// Philox4x32-10 (J. K. Salmon, M. A. Moraes, R. O. Dror, D. E. Shaw, "Parallel random numbers: as
// easy as 1, 2, 3", SC 2011). A stream is keyed by (seed, stream id, purpose): every environment,
// robot and purpose (gain randomisation, motor constants, sensor noise, ...) draws from its own
// independent sequence, so results do not depend on which thread runs which environment or on the
// order in which streams are used. The n-th draw of a stream is a pure function of
// (seed, stream, purpose, n): a stream can be skipped ahead or re-created at any point.
#pragma once

#include <cstdint>

#include "kestrel/kernel/types.hpp"

namespace kestrel {

/// Well-known purposes; users may add their own values above kPurposeUser.
enum RngPurpose : std::uint32_t {
  kPurposeGains = 1,
  kPurposeMotors = 2,
  kPurposeSensorNoise = 3,
  kPurposeReset = 4,
  kPurposeDisturbance = 5,
  kPurposePlacement = 6,
  kPurposeUser = 1000,
};

/// One Philox4x32-10 block: 4 output words from a 128-bit counter and 64-bit key.
void philox4x32_10(const std::uint32_t counter[4], const std::uint32_t key[2], std::uint32_t out[4]);

class RngStream {
 public:
  RngStream() = default;
  RngStream(std::uint64_t seed, std::uint32_t stream_id, std::uint32_t purpose);

  /// Next 32 random bits.
  std::uint32_t next_u32();
  /// Uniform in [0, 1) with 24 (float) or 53 (double) random bits; never returns 1.
  real uniform();
  /// Uniform in [lo, hi) (the rounding of lo + (hi - lo) u is kept below hi).
  real uniform(real lo, real hi);
  /// Standard normal N(0, 1) by the Box-Muller transform (Box & Muller 1958), one value per
  /// call (the sine branch is discarded, so a draw always consumes the same number of words).
  real normal();
  real normal(real mean, real stddev) { return mean + stddev * normal(); }

  /// Number of 32-bit words drawn so far.
  std::uint64_t position() const { return block_ * 4u + word_ % 4u; }
  /// Jump to word index n (O(1)).
  void seek(std::uint64_t n);

 private:
  void refill();
  std::uint32_t key_[2] = {0, 0};
  std::uint32_t stream_ = 0;
  std::uint32_t purpose_ = 0;
  std::uint64_t block_ = 0;  // counter of the block in buf_
  std::uint32_t word_ = 4;   // next word of buf_ to hand out (4 = empty)
  std::uint32_t buf_[4] = {0, 0, 0, 0};
};

}  // namespace kestrel
