// Accuracy and determinism of the kernel's float sine/cosine (math.hpp, detail::sincos_f32),
// measured against double-precision std::sin / std::cos. Runs on the host and under QEMU on the
// MCUs (the reference is double on both; on a single-precision FPU that is software double,
// acceptable in a test). detail::sincos_f32 is tested directly so a -DKESTREL_DOUBLE=ON build
// checks it too.
#include "kestrel/kernel/math.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>

#include "ktest.hpp"

using namespace kestrel;

namespace {

// Error in units of 2^-24 (half an ulp of 1): absolute error scaled so that values near 1 read as
// ulps; used on wide ranges where sin/cos cross zero and relative error is not meaningful.
double abs_err_units(float got, double want) { return std::fabs(static_cast<double>(got) - want) * 16777216.0; }

// Error in ulps of the float nearest to want.
double ulp_err(float got, double want) {
  const float w = static_cast<float>(want);
  const float next = std::nextafter(std::fabs(w), 1e30f);
  const double ulp = static_cast<double>(next) - static_cast<double>(std::fabs(w));
  return std::fabs(static_cast<double>(got) - want) / ulp;
}

std::uint32_t bits(float v) {
  std::uint32_t u;
  std::memcpy(&u, &v, sizeof u);
  return u;
}

}  // namespace

KTEST(Math, SinCosUlpOnPrimaryRange) {
  // |x| <= pi/4: no reduction error, relative accuracy in ulps.
  double worst_s = 0, worst_c = 0;
  for (int i = -4000; i <= 4000; ++i) {
    const float x = static_cast<float>(i) * (0.78539816f / 4000.0f);
    float s, c;
    detail::sincos_f32(x, s, c);
    const double xd = static_cast<double>(x);
    if (x != 0) worst_s = std::fmax(worst_s, ulp_err(s, std::sin(xd)));
    worst_c = std::fmax(worst_c, ulp_err(c, std::cos(xd)));
  }
  KEXPECT_LE(worst_s, 2.0);
  KEXPECT_LE(worst_c, 2.0);
}

KTEST(Math, SinCosAbsoluteErrorOverControllerRange) {
  // The commanded angles the controllers see (clipped to the action range, default +-10 rad) and
  // beyond, up to 100 rad: absolute error within 3 half-ulps of 1 (about 1.8e-7).
  double worst = 0;
  for (int i = -20000; i <= 20000; ++i) {
    const float x = static_cast<float>(i) * 0.005f;
    float s, c;
    detail::sincos_f32(x, s, c);
    const double xd = static_cast<double>(x);
    worst = std::fmax(worst, abs_err_units(s, std::sin(xd)));
    worst = std::fmax(worst, abs_err_units(c, std::cos(xd)));
  }
  KEXPECT_LE(worst, 3.0);
  // Up to Cephes' lossth (8192 rad): still within a few units.
  double worst_far = 0;
  for (int i = 0; i < 4096; ++i) {  // x < 8192: beyond it the reduction is the lossy one
    const float x = static_cast<float>(i) * 2.0f + 0.318f;
    float s, c;
    detail::sincos_f32(x, s, c);
    worst_far = std::fmax(worst_far, abs_err_units(s, std::sin(static_cast<double>(x))));
    worst_far = std::fmax(worst_far, abs_err_units(c, std::cos(static_cast<double>(x))));
  }
  KEXPECT_LE(worst_far, 4.0);
}

KTEST(Math, SinCosSymmetryAndSpecialValues) {
  for (int i = 1; i <= 500; ++i) {
    const float x = static_cast<float>(i) * 0.0137f;
    float s1, c1, s2, c2;
    detail::sincos_f32(x, s1, c1);
    detail::sincos_f32(-x, s2, c2);
    KEXPECT_EQ(bits(s1), bits(-s2));  // exactly odd
    KEXPECT_EQ(bits(c1), bits(c2));   // exactly even
  }
  float s, c;
  detail::sincos_f32(0.0f, s, c);
  KEXPECT_EQ(s, 0.0f);
  KEXPECT_EQ(c, 1.0f);
  detail::sincos_f32(INFINITY, s, c);
  KEXPECT_TRUE(std::isnan(s) && std::isnan(c));
  detail::sincos_f32(NAN, s, c);
  KEXPECT_TRUE(std::isnan(s) && std::isnan(c));
  detail::sincos_f32(1e30f, s, c);  // beyond 2^24: Cephes' (0, 1)
  KEXPECT_EQ(s, 0.0f);
  KEXPECT_EQ(c, 1.0f);
}

KTEST(Math, SinCosKnownBits) {
  // Bit patterns fixed here so the host (glibc) and MCU (newlib) builds are checked to give the
  // same bits: the function uses only float +, -, * and conversions, no libm.
  float s, c;
  detail::sincos_f32(0.3f, s, c);
  KEXPECT_NEAR(static_cast<double>(s), std::sin(0.3), 2e-7);
  KEXPECT_NEAR(static_cast<double>(c), std::cos(0.3), 2e-7);
  KEXPECT_EQ(bits(s), 0x3e974e6du);
  KEXPECT_EQ(bits(c), 0x3f7490efu);
  detail::sincos_f32(-2.5f, s, c);
  KEXPECT_EQ(bits(s), 0xbf193579u);
  KEXPECT_EQ(bits(c), 0xbf4d17bfu);
}
