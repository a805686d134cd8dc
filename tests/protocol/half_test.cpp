// binary16 conversions: exhaustive round trip and known values.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <limits>

#include "support.hpp"

namespace dn::protocol::test {
namespace {

// Independent reference: the exact value of a half, from its fields.
double half_value(uint16_t h) {
  const int sign = (h & 0x8000) ? -1 : 1;
  const int exp = (h >> 10) & 0x1F;
  const int mant = h & 0x3FF;
  if (exp == 0) return sign * std::ldexp(mant, -24);
  if (exp == 31) return mant ? std::numeric_limits<double>::quiet_NaN() : sign * INFINITY;
  return sign * std::ldexp(1024 + mant, exp - 25);
}

TEST(Half, ExhaustiveRoundTrip) {
  for (uint32_t i = 0; i < 65536; ++i) {
    const uint16_t h = static_cast<uint16_t>(i);
    const float f = half_to_float(h);
    const double expected = half_value(h);
    if (std::isnan(expected)) {
      ASSERT_TRUE(std::isnan(f)) << std::hex << i;
      // NaN keeps its sign and payload (quiet stays quiet, signalling stays signalling).
      const uint32_t fb = std::bit_cast<uint32_t>(f);
      EXPECT_EQ(fb >> 31, i >> 15u);
      EXPECT_EQ((fb >> 13) & 0x3FFu, i & 0x3FFu);
    } else {
      ASSERT_EQ(static_cast<double>(f), expected) << std::hex << i;
      ASSERT_EQ(std::signbit(f), (i & 0x8000) != 0) << std::hex << i;
    }
    ASSERT_EQ(float_to_half(f), h) << std::hex << i;
  }
}

TEST(Half, KnownValues) {
  EXPECT_EQ(float_to_half(0.0f), 0x0000);
  EXPECT_EQ(float_to_half(-0.0f), 0x8000);
  EXPECT_EQ(float_to_half(1.0f), 0x3C00);
  EXPECT_EQ(float_to_half(-2.0f), 0xC000);
  EXPECT_EQ(float_to_half(65504.0f), 0x7BFF);            // largest finite
  EXPECT_EQ(float_to_half(6.1035156e-5f), 0x0400);       // smallest normal 2^-14
  EXPECT_EQ(float_to_half(std::ldexp(1.0f, -24)), 0x0001);  // smallest subnormal
  EXPECT_EQ(float_to_half(std::ldexp(1023.0f, -24)), 0x03FF);  // largest subnormal
  EXPECT_EQ(float_to_half(65520.0f), 0x7C00);            // halfway past 65504: ties to even -> inf
  EXPECT_EQ(float_to_half(65519.996f), 0x7BFF);          // just below halfway
  EXPECT_EQ(float_to_half(1e10f), 0x7C00);
  EXPECT_EQ(float_to_half(-1e10f), 0xFC00);
  EXPECT_EQ(float_to_half(INFINITY), 0x7C00);
  EXPECT_EQ(float_to_half(-INFINITY), 0xFC00);
  EXPECT_EQ(half_to_float(0x7BFF), 65504.0f);
  EXPECT_EQ(half_to_float(0x0001), std::ldexp(1.0f, -24));
  EXPECT_EQ(half_to_float(0x3555), 0.333251953125f);
}

TEST(Half, RoundToNearestEven) {
  // 1 + 2^-11 is halfway between 1 and 1 + 2^-10: ties to even (1).
  EXPECT_EQ(float_to_half(1.0f + std::ldexp(1.0f, -11)), 0x3C00);
  // 1 + 3 * 2^-11 is halfway between 1 + 2^-10 (odd) and 1 + 2^-9: up.
  EXPECT_EQ(float_to_half(1.0f + 3 * std::ldexp(1.0f, -11)), 0x3C02);
  // Just above halfway rounds up.
  EXPECT_EQ(float_to_half(std::nextafter(1.0f + std::ldexp(1.0f, -11), 2.0f)), 0x3C01);
  // Subnormal ties: 2^-25 (half of the smallest subnormal) -> 0; 3 * 2^-25 -> 2 * 2^-24.
  EXPECT_EQ(float_to_half(std::ldexp(1.0f, -25)), 0x0000);
  EXPECT_EQ(float_to_half(std::nextafter(std::ldexp(1.0f, -25), 1.0f)), 0x0001);
  EXPECT_EQ(float_to_half(3 * std::ldexp(1.0f, -25)), 0x0002);
  EXPECT_EQ(float_to_half(-3 * std::ldexp(1.0f, -25)), 0x8002);
  // Rounding up out of the subnormal range gives the smallest normal.
  EXPECT_EQ(float_to_half(std::nextafter(std::ldexp(1.0f, -14), 0.0f)), 0x0400);
  // Float subnormals are far below the half range.
  EXPECT_EQ(float_to_half(std::numeric_limits<float>::denorm_min()), 0x0000);
}

TEST(Half, AgreesWithDoubleRoundingOnRandomFloats) {
  // Reference: pick the nearest half by exact comparison in double.
  std::mt19937 rng(3);
  for (int i = 0; i < 200000; ++i) {
    const float f = std::bit_cast<float>(static_cast<uint32_t>(rng()));
    if (!std::isfinite(f) || std::fabs(f) >= 65520.0f) continue;
    const uint16_t h = float_to_half(f);
    const double got = half_value(h);
    // Neighbours of the result must not be closer.
    const double err = std::fabs(got - f);
    for (int d : {-1, 1}) {
      const uint16_t nb = static_cast<uint16_t>((h & 0x7FFF) + d) | (h & 0x8000);
      if ((h & 0x7FFF) == 0 && d < 0) continue;
      const double v = half_value(nb);
      if (std::isnan(v) || std::isinf(v)) continue;
      const double nerr = std::fabs(v - f);
      ASSERT_LE(err, nerr) << f;
      if (err == nerr) {
        ASSERT_EQ(h & 1, 0) << "tie not to even for " << f;
      }
    }
  }
}

TEST(Half, NaNStaysNaN) {
  EXPECT_EQ(float_to_half(std::numeric_limits<float>::quiet_NaN()) & 0x7C00, 0x7C00);
  EXPECT_NE(float_to_half(std::numeric_limits<float>::quiet_NaN()) & 0x03FF, 0);
  // A float NaN whose payload sits only in bits the half cannot hold is still a NaN.
  const float low_payload_nan = std::bit_cast<float>(0x7F800001u);
  const uint16_t h = float_to_half(low_payload_nan);
  EXPECT_EQ(h & 0x7C00, 0x7C00);
  EXPECT_NE(h & 0x03FF, 0);
  EXPECT_EQ(float_to_half(std::bit_cast<float>(0xFFC00000u)) & 0x8000, 0x8000);
}

}  // namespace
}  // namespace dn::protocol::test
