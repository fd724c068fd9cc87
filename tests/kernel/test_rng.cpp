#include "kestrel/kernel/rng.hpp"

#include <cmath>

#include "ktest.hpp"

using namespace kestrel;

KTEST(Rng, PhiloxKnownAnswer) {
  // Known-answer vectors from Random123's kat_vectors (philox4x32 10 rounds).
  {
    const std::uint32_t ctr[4] = {0, 0, 0, 0}, key[2] = {0, 0};
    std::uint32_t out[4];
    philox4x32_10(ctr, key, out);
    KEXPECT_EQ(out[0], 0x6627e8d5u);
    KEXPECT_EQ(out[1], 0xe169c58du);
    KEXPECT_EQ(out[2], 0xbc57ac4cu);
    KEXPECT_EQ(out[3], 0x9b00dbd8u);
  }
  {
    const std::uint32_t ctr[4] = {0xffffffffu, 0xffffffffu, 0xffffffffu, 0xffffffffu};
    const std::uint32_t key[2] = {0xffffffffu, 0xffffffffu};
    std::uint32_t out[4];
    philox4x32_10(ctr, key, out);
    KEXPECT_EQ(out[0], 0x408f276du);
    KEXPECT_EQ(out[1], 0x41c83b0eu);
    KEXPECT_EQ(out[2], 0xa20bc7c6u);
    KEXPECT_EQ(out[3], 0x6d5451fdu);
  }
  {
    const std::uint32_t ctr[4] = {0x243f6a88u, 0x85a308d3u, 0x13198a2eu, 0x03707344u};
    const std::uint32_t key[2] = {0xa4093822u, 0x299f31d0u};
    std::uint32_t out[4];
    philox4x32_10(ctr, key, out);
    KEXPECT_EQ(out[0], 0xd16cfe09u);
    KEXPECT_EQ(out[1], 0x94fdccebu);
    KEXPECT_EQ(out[2], 0x5001e420u);
    KEXPECT_EQ(out[3], 0x24126ea1u);
  }
}

KTEST(Rng, SameKeySameSequenceDifferentStreamsDiffer) {
  RngStream a(42, 7, kPurposeGains), b(42, 7, kPurposeGains), c(42, 8, kPurposeGains), d(42, 7, kPurposeMotors);
  int same_c = 0, same_d = 0;
  for (int i = 0; i < 100; ++i) {
    const std::uint32_t va = a.next_u32();
    KEXPECT_EQ(va, b.next_u32());
    same_c += va == c.next_u32();
    same_d += va == d.next_u32();
  }
  KEXPECT_EQ(same_c, 0);
  KEXPECT_EQ(same_d, 0);
}

KTEST(Rng, SeekIsRandomAccess) {
  RngStream a(1, 2, 3);
  KEXPECT_EQ(a.position(), 0u);
  std::uint32_t seq[11];
  for (auto& v : seq) v = a.next_u32();
  for (int start = 0; start < 10; ++start) {
    RngStream b(1, 2, 3);
    b.seek(static_cast<std::uint64_t>(start));
    KEXPECT_EQ(b.next_u32(), seq[start]);
    KEXPECT_EQ(b.next_u32(), seq[start + 1]);
  }
  KEXPECT_EQ(a.position(), 11u);
  a.next_u32();
  KEXPECT_EQ(a.position(), 12u);  // block boundary
}

KTEST(Rng, UniformAndNormalStatistics) {
  RngStream s(20250101, 0, kPurposeSensorNoise);
  const int n = 20000;
  double sum = 0, sum2 = 0, nsum = 0, nsum2 = 0, nsum4 = 0;
  real umin = 1, umax = 0;
  for (int i = 0; i < n; ++i) {
    const real u = s.uniform();
    umin = u < umin ? u : umin;
    umax = u > umax ? u : umax;
    sum += static_cast<double>(u);
    sum2 += static_cast<double>(u) * static_cast<double>(u);
    const double z = static_cast<double>(s.normal());
    nsum += z;
    nsum2 += z * z;
    nsum4 += z * z * z * z;
  }
  KEXPECT_GE(umin, 0);
  KEXPECT_LT(umax, 1);
  const double mean = sum / n, var = sum2 / n - mean * mean;
  KEXPECT_NEAR(mean, 0.5, 0.01);          // sigma of the mean = 0.29/sqrt(n) = 0.002
  KEXPECT_NEAR(var, 1.0 / 12.0, 0.003);
  const double nmean = nsum / n, nvar = nsum2 / n - nmean * nmean;
  KEXPECT_NEAR(nmean, 0, 0.03);           // 4 sigma
  KEXPECT_NEAR(nvar, 1, 0.04);
  KEXPECT_NEAR(nsum4 / n, 3, 0.25);       // Gaussian kurtosis
}

KTEST(Rng, UniformRange) {
  RngStream s(5, 5, 5);
  for (int i = 0; i < 1000; ++i) {
    const real v = s.uniform(-2, 3);
    KEXPECT_GE(v, -2);
    KEXPECT_LT(v, 3);
  }
}
