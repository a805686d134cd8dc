// image on the device against the double-precision CPU reference in every
// guide form, with bad values; and against the truth of image_scene.hpp:
// below its input's error at 1, 4, 16 and 64 samples per pixel in every
// form, and below svgf's first frame with the same guides.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "frames.hpp"
#include "gpu_test_env.hpp"
#include "image_reference.hpp"
#include "image_scene.hpp"
#include "pipelines/pipeline.hpp"

namespace dn {
namespace {

using test::ChannelId;
using test::Format;

// Which guides a session declares.
struct Guides {
  const char* name;
  bool albedo, normal, depth;
};
const Guides kForms[] = {{"colour", false, false, false},
                         {"albedo", true, false, false},
                         {"albedo_normal", true, true, false},
                         {"all", true, true, true},
                         {"normal_depth", false, true, true}};

pipelines::SessionConfig config_of(const Guides& g, int w, int h, Format in,
                                   std::vector<pipelines::ParameterValue> params = {}) {
  std::vector<pipelines::InputChannel> channels = {{ChannelId::Radiance, in}};
  if (g.albedo) channels.push_back({ChannelId::Albedo, in});
  if (g.normal) channels.push_back({ChannelId::Normal, in});
  if (g.depth) channels.push_back({ChannelId::Depth, in});
  return test::make_config("image", w, h, channels, Format::F32, std::move(params));
}

test::HostFrame host_frame(const Guides& g, const test::ImageScene& s, const std::vector<float>& radiance, Format in) {
  test::HostFrame f;
  f.add(ChannelId::Radiance, in, radiance);
  if (g.albedo) f.add(ChannelId::Albedo, in, s.albedo);
  if (g.normal) f.add(ChannelId::Normal, in, s.normal);
  if (g.depth) f.add(ChannelId::Depth, in, s.depth);
  return f;
}

std::vector<float> run(pipelines::Pipeline& p, const test::HostFrame& f) {
  std::vector<uint8_t> out;
  std::vector<pipelines::PassTiming> timings;
  test::process(p, f.view(), true, out, timings);
  return test::decode_output(out, Format::F32);
}

class ImageTest : public test::GpuTest, public testing::WithParamInterface<Guides> {};
class ImageAgainstSvgfTest : public test::GpuTest {};

// The device against the CPU reference, with `params` (default: the pipeline's defaults).
void expect_reference(gpu::Context& context, const Guides& g, const std::vector<pipelines::ParameterValue>& params,
                      const test::ImageParams& reference_params);

TEST_P(ImageTest, MatchesTheCpuReferenceWithBadValues) { expect_reference(ctx(), GetParam(), {}, {}); }

// The decorrelated noise estimate, capped higher and unguarded (bench/image_quality.sh's
// image-all-decorrelated).
TEST_P(ImageTest, MatchesTheCpuReferenceWithTheDecorrelatedNoiseEstimate) {
  test::ImageParams reference;
  reference.decorrelated_noise = true;
  reference.noise_cap = 64.0;
  reference.harm_guard = 0.0;
  expect_reference(ctx(), GetParam(), {{"noise_estimate", 1}, {"noise_cap", 64}, {"harm_guard", 0}}, reference);
}

void expect_reference(gpu::Context& context, const Guides& g, const std::vector<pipelines::ParameterValue>& params,
                      const test::ImageParams& reference_params) {
  const test::ImageScene scene;
  std::vector<float> radiance = scene.noisy(1, 5);
  const float bad[] = {NAN, INFINITY, -INFINITY, -1.0f, 1e30f};
  for (int k = 0; k < 5; ++k) radiance[3 * (7 * scene.width + 5 + 9 * k)] = bad[k];
  test::ImageScene guides = scene;
  guides.normal[3 * (30 * scene.width + 20)] = NAN;  // a pixel without a usable normal
  guides.depth[30 * scene.width + 21] = INFINITY;    // and one that is background
  for (Format in : {Format::F32, Format::F16}) {
    SCOPED_TRACE(in == Format::F32 ? "fp32" : "fp16");
    auto pipe = pipelines::create(context, config_of(g, scene.width, scene.height, in, params));
    const test::HostFrame f = host_frame(g, guides, radiance, in);
    const std::vector<float> got = run(*pipe, f);
    test::ImageFrame r;
    r.radiance = test::decode_plane(f.plane(ChannelId::Radiance).bytes, in);
    if (g.albedo) r.albedo = test::decode_plane(f.plane(ChannelId::Albedo).bytes, in);
    if (g.normal) r.normal = test::decode_plane(f.plane(ChannelId::Normal).bytes, in);
    if (g.depth) r.depth = test::decode_plane(f.plane(ChannelId::Depth).bytes, in);
    const std::vector<double> want = test::image_reference(scene.width, scene.height, r, reference_params);
    ASSERT_EQ(got.size(), want.size());
    for (float v : got) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f) << v;
    EXPECT_LE(test::relative_rms(got, want), 1e-3);
    size_t gross = 0;
    for (size_t i = 0; i < want.size(); ++i)
      if (std::fabs(got[i] - want[i]) > 1e-2 * std::max(1.0, std::fabs(want[i]))) ++gross;
    EXPECT_EQ(gross, 0u);
  }
}

TEST_P(ImageTest, BelowItsInputsErrorAtEverySampleCount) {
  const Guides& g = GetParam();
  const test::ImageScene scene;
  auto pipe = pipelines::create(ctx(), config_of(g, scene.width, scene.height, Format::F32));
  for (int spp : {1, 4, 16, 64}) {
    const std::vector<float> noisy = scene.noisy(spp, 11 + spp);
    const std::vector<float> out = run(*pipe, host_frame(g, scene, noisy, Format::F32));
    const double in_error = scene.rmse(noisy), out_error = scene.rmse(out);
    std::printf("[ info     ] %s %d spp: RMSE input %.4f output %.4f (%.2fx)\n", g.name, spp, in_error, out_error,
                in_error / out_error);
    EXPECT_LT(out_error, in_error) << spp << " spp";
  }
}

// With the guides svgf has (and zero motion), image's frame is closer to the
// truth than svgf's first frame (its spatial estimate and a-trous) at every
// sample count.
TEST_F(ImageAgainstSvgfTest, BelowSvgfsFirstFrameAtEverySampleCount) {
  const test::ImageScene scene;
  const Guides all{"all", true, true, true};
  auto image = pipelines::create(ctx(), config_of(all, scene.width, scene.height, Format::F32));
  const std::vector<pipelines::InputChannel> svgf_channels = {
      {ChannelId::Radiance, Format::F32}, {ChannelId::Albedo, Format::F32}, {ChannelId::Normal, Format::F32},
      {ChannelId::Depth, Format::F32}, {ChannelId::Motion, Format::F32}};
  for (int spp : {1, 4, 16, 64}) {
    const std::vector<float> noisy = scene.noisy(spp, 11 + spp);
    test::HostFrame f = host_frame(all, scene, noisy, Format::F32);
    const std::vector<float> ours = run(*image, f);
    f.add(ChannelId::Motion, Format::F32, std::vector<float>(2 * scene.width * scene.height, 0.0f));
    auto svgf = pipelines::create(ctx(), test::make_config("svgf", scene.width, scene.height, svgf_channels));
    const std::vector<float> theirs = run(*svgf, f);
    std::printf("[ info     ] %d spp: RMSE image %.4f, svgf's first frame %.4f\n", spp, scene.rmse(ours),
                scene.rmse(theirs));
    EXPECT_LT(scene.rmse(ours), scene.rmse(theirs)) << spp << " spp";
  }
}

INSTANTIATE_TEST_SUITE_P(Forms, ImageTest, testing::ValuesIn(kForms),
                         [](const testing::TestParamInfo<Guides>& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace dn
