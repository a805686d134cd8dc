// The wire-format boundary (wire_format.hpp): an fp16 plane widens to fp32
// exactly (every half, the odd last element of an odd-length plane,
// subnormals, infinities, signed zeros; NaN stays NaN), and fp32 narrows to
// fp16 as IEEE round-to-nearest-even does except that finite values beyond
// 65504 saturate, checked against the independent conversion of half.hpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "half.hpp"
#include "pipelines/wire_format.hpp"

namespace dn {
namespace {

std::vector<float> widen(const std::vector<uint16_t>& halves) {
  std::vector<uint8_t> bytes(halves.size() * 2);
  for (size_t i = 0; i < halves.size(); ++i) {
    bytes[2 * i] = static_cast<uint8_t>(halves[i]);
    bytes[2 * i + 1] = static_cast<uint8_t>(halves[i] >> 8);
  }
  std::vector<float> out(halves.size());
  pipelines::widen_halves(bytes.data(), halves.size(), out.data());
  return out;
}

std::vector<uint16_t> narrow(const std::vector<float>& values) {
  std::vector<uint8_t> bytes(values.size() * 2);
  pipelines::narrow_to_halves(values.data(), values.size(), bytes.data());
  std::vector<uint16_t> out(values.size());
  for (size_t i = 0; i < out.size(); ++i) out[i] = static_cast<uint16_t>(bytes[2 * i] | (bytes[2 * i + 1] << 8));
  return out;
}

uint32_t bits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}

TEST(WireFormat, EveryHalfWidensExactly) {
  // All 65536 patterns, at every offset modulo the 8-wide fast path, plus
  // odd lengths that end in a scalar tail.
  std::vector<uint16_t> all(65536 + 7);
  for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<uint16_t>(i < 7 ? 0x3c00 + i : i - 7);
  for (size_t length : {all.size(), size_t{1}, size_t{7}, size_t{65}, size_t{1001}}) {
    const std::vector<uint16_t> halves(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(length));
    const auto got = widen(halves);
    for (size_t i = 0; i < halves.size(); ++i) {
      const float want = test::from_half(halves[i]);
      if (std::isnan(want))
        EXPECT_TRUE(std::isnan(got[i])) << std::hex << halves[i];
      else
        ASSERT_EQ(bits(got[i]), bits(want)) << "half 0x" << std::hex << halves[i];
    }
  }
}

TEST(WireFormat, NarrowingRoundsToNearestEvenAndSaturates) {
  std::mt19937 rng(11);
  std::vector<float> values = {0.0f, -0.0f, 1.0f, -1.0f, 65504.0f, -65504.0f, 65519.99f, 65520.0f, -65520.0f,
                               1e9f, -1e9f, std::numeric_limits<float>::max(), 5.96e-8f, 2.98e-8f, 2.99e-8f,
                               1e-40f, 6.1035e-5f, 0.33333334f, 1.0009766f, 1.00048828125f, 1.00146484375f};
  std::uniform_int_distribution<uint32_t> pattern;
  while (values.size() < 20001) {
    float f;
    const uint32_t u = pattern(rng);
    std::memcpy(&f, &u, 4);
    if (std::isfinite(f)) values.push_back(f);
  }
  const auto got = narrow(values);
  for (size_t i = 0; i < values.size(); ++i) {
    const float v = values[i];
    const uint16_t want = std::fabs(v) > 65504.0f ? static_cast<uint16_t>(v < 0 ? 0xfbff : 0x7bff) : test::to_half(v);
    ASSERT_EQ(got[i], want) << "value " << v << " (element " << i << ")";
  }
}

TEST(WireFormat, NarrowingKeepsInfinityAndNaN) {
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<float> values = {inf, -inf, std::nanf(""), -std::nanf(""), inf, -inf, std::nanf(""), 1.0f, inf};
  const auto got = narrow(values);
  EXPECT_EQ(got[0], 0x7c00);
  EXPECT_EQ(got[1], 0xfc00);
  EXPECT_EQ(got[4], 0x7c00);
  EXPECT_EQ(got[8], 0x7c00);  // the scalar tail too
  for (size_t i : {2u, 3u, 6u}) EXPECT_TRUE((got[i] & 0x7c00) == 0x7c00 && (got[i] & 0x3ff) != 0) << i;
}

TEST(WireFormat, Fp16NaNStaysNaN) {
  for (float v : widen({0x7e00, 0x7c01, 0xfe00})) EXPECT_TRUE(std::isnan(v));
}

}  // namespace
}  // namespace dn
