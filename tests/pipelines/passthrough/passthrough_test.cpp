// passthrough: fp32 copies of finite values are bit-exact; fp16 <-> fp32
// conversion follows IEEE round-to-nearest-even (checked against the tests'
// own to_half), an fp16 output saturating at 65504; NaN and +-Inf become 0.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>

#include "frames.hpp"
#ifdef DN_HAVE_PROTOCOL_LIB
#include "dn/protocol/codec.hpp"
#endif
#include "gpu_test_env.hpp"
#include "pipelines/pipeline.hpp"

namespace dn {
namespace {

using test::ChannelId;
using test::Format;

class PassthroughTest : public test::GpuTest {
 protected:
  std::vector<uint8_t> run(uint32_t w, uint32_t h, Format in, Format out, const std::vector<float>& radiance,
                           std::vector<pipelines::PassTiming>* timings = nullptr) {
    auto config = test::make_config("passthrough", w, h, {{ChannelId::Radiance, in}}, out);
    EXPECT_FALSE(pipelines::validate(config).has_value());
    auto pipe = pipelines::create(ctx(), config);
    test::HostFrame f;
    f.add(ChannelId::Radiance, in, radiance);
    std::vector<uint8_t> bytes;
    std::vector<pipelines::PassTiming> t;
    test::process(*pipe, f.view(), true, bytes, timings ? *timings : t);
    return bytes;
  }
};

std::vector<float> random_values(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> mantissa(1.0f, 2.0f);
  std::uniform_int_distribution<int> exponent(-30, 20);
  std::vector<float> out(n);
  for (auto& v : out) v = std::ldexp(mantissa(rng), exponent(rng)) * ((rng() & 1) ? 1.0f : -1.0f);
  return out;
}

TEST_F(PassthroughTest, Fp32CopyIsBitExact) {
  const uint32_t w = 33, h = 17;  // odd pixel count
  auto values = random_values(w * h * 3, 1);
  values[0] = -0.0f;
  values[1] = 1e-41f;  // subnormal
  values[2] = INFINITY;
  values[3] = -INFINITY;
  values[4] = 3.4e38f;
  auto expected = values;
  expected[2] = expected[3] = 0.0f;  // non-finite: 0
  const auto bytes = run(w, h, Format::F32, Format::F32, values);
  EXPECT_EQ(bytes, test::encode_plane(expected, Format::F32));
}

TEST_F(PassthroughTest, Fp32NonFiniteBecomesZero) {
  std::vector<float> values(3 * 4, 1.0f);
  values[5] = NAN;
  values[6] = INFINITY;
  values[7] = -INFINITY;
  for (Format out_format : {Format::F32, Format::F16}) {
    const auto out = test::decode_output(run(2, 2, Format::F32, out_format, values), out_format);
    EXPECT_EQ(out[5], 0.0f);
    EXPECT_EQ(out[6], 0.0f);
    EXPECT_EQ(out[7], 0.0f);
    EXPECT_EQ(out[4], 1.0f);
  }
}

// Round to nearest even; a finite value beyond the largest finite half
// saturates to +-65504 (docs/pipelines.md, "Output format conversion"),
// NaN and Inf become 0.
TEST_F(PassthroughTest, Fp32ToFp16RoundsToNearestEvenAndSaturates) {
  const uint32_t w = 41, h = 13;  // odd pixel count: the last half-word is padding
  auto values = random_values(w * h * 3, 2);
  // Ties and near-ties at several magnitudes, beyond the half range, subnormal halves, zeros, non-finite.
  const float special[] = {1.0f + 0x1p-11f, 1.0f + 3 * 0x1p-11f, 1.0f + 0x1p-11f + 0x1p-20f, 65504.0f, 65519.0f,
                           65520.0f, 1e6f, -1e6f, 0x1p-24f, 0x1p-25f, 0x1.8p-25f, 3 * 0x1p-26f, 0x1p-15f + 0x1p-25f,
                           6.1e-5f, -0.0f, 0.0f, 1e-30f, 2049.0f, 2051.0f, -2051.0f, 3.4e38f,
                           std::numeric_limits<float>::max(), -1e38f, 1e11f, INFINITY, -INFINITY};
  for (size_t i = 0; i < std::size(special); ++i) values[i] = special[i];
  const auto bytes = run(w, h, Format::F32, Format::F16, values);
  ASSERT_EQ(bytes.size(), size_t(w) * h * 3 * 2);
  for (size_t i = 0; i < values.size(); ++i) {
    uint16_t got;
    std::memcpy(&got, bytes.data() + 2 * i, 2);
    const float v = values[i];
    const float saturated = std::isfinite(v) ? std::clamp(v, -65504.0f, 65504.0f) : 0.0f;
    ASSERT_EQ(got, test::to_half(saturated)) << "element " << i << " value " << v;
#ifdef DN_HAVE_PROTOCOL_LIB
    ASSERT_EQ(got, protocol::float_to_half(saturated)) << "element " << i << " value " << v;
#endif
  }
}

TEST_F(PassthroughTest, Fp16ToFp32IsExact) {
  const uint32_t w = 19, h = 9;
  std::vector<float> values = random_values(w * h * 3, 3);
  for (auto& v : values) v = test::from_half(test::to_half(v));  // representable in fp16 (incl. subnormals, inf)
  auto expected = values;
  for (auto& v : expected) v = std::isfinite(v) ? v : 0.0f;
  ASSERT_NE(expected, values);  // the random values reach Inf in fp16
  const auto out = test::decode_output(run(w, h, Format::F16, Format::F32, values), Format::F32);
  EXPECT_EQ(out, expected);
}

TEST_F(PassthroughTest, Fp16ToFp16IsExact) {
  const uint32_t w = 21, h = 11;
  std::vector<float> values = random_values(w * h * 3, 4);
  auto expected = values;
  for (auto& v : expected) v = std::isfinite(test::from_half(test::to_half(v))) ? v : 0.0f;
  ASSERT_NE(expected, values);  // the random values reach Inf in fp16
  EXPECT_EQ(run(w, h, Format::F16, Format::F16, values), test::encode_plane(expected, Format::F16));
}

TEST_F(PassthroughTest, ReportsTimingsAndSkipsDownloadWhenAsked) {
  auto config = test::make_config("passthrough", 16, 16, {{ChannelId::Radiance, Format::F32}});
  auto pipe = pipelines::create(ctx(), config);
  test::HostFrame f;
  f.add(ChannelId::Radiance, Format::F32, std::vector<float>(16 * 16 * 3, 0.5f));
  std::vector<uint8_t> out;
  std::vector<pipelines::PassTiming> timings;
  test::process(*pipe, f.view(), false, out, timings);
  EXPECT_TRUE(out.empty());
  ASSERT_EQ(timings.size(), 3u);
  EXPECT_EQ(timings[0].name, "upload");
  EXPECT_EQ(timings[1].name, "passthrough");
  EXPECT_EQ(timings[2].name, "download");
  for (const auto& t : timings) EXPECT_GE(t.milliseconds, 0.0);
}

TEST_F(PassthroughTest, BadFrameThrowsAndThePipelineKeepsWorking) {
  auto config = test::make_config("passthrough", 8, 8, {{ChannelId::Radiance, Format::F32}});
  auto pipe = pipelines::create(ctx(), config);
  std::vector<uint8_t> out;
  std::vector<pipelines::PassTiming> timings;
  test::HostFrame wrong_size;
  wrong_size.add(ChannelId::Radiance, Format::F32, std::vector<float>(8 * 8 * 3 - 1, 1.0f));
  EXPECT_THROW(test::process(*pipe, wrong_size.view(), true, out, timings), std::invalid_argument);
  test::HostFrame wrong_format;
  wrong_format.add(ChannelId::Radiance, Format::F16, std::vector<float>(8 * 8 * 3, 1.0f));
  EXPECT_THROW(test::process(*pipe, wrong_format.view(), true, out, timings), std::invalid_argument);
  test::HostFrame missing;
  EXPECT_THROW(test::process(*pipe, missing.view(), true, out, timings), std::invalid_argument);

  test::HostFrame good;
  const std::vector<float> values(8 * 8 * 3, 0.75f);
  good.add(ChannelId::Radiance, Format::F32, values);
  timings.clear();
  test::process(*pipe, good.view(), true, out, timings);
  EXPECT_EQ(test::decode_output(out, Format::F32), values);
}

}  // namespace
}  // namespace dn
