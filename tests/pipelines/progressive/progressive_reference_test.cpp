// progressive (progressive SVGF, paper 004) on the device against the
// double-precision CPU reference (svgf_reference.cpp with paper 004's
// switches), over frames of a moving scene, with and without fewer than one
// sample per pixel (sample_count).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "frames.hpp"
#include "gpu_test_env.hpp"
#include "pipelines/pipeline.hpp"
#include "svgf_inputs.hpp"
#include "svgf_reference.hpp"

namespace dn {
namespace {

using protocol::MotionConvention;
using test::ChannelId;
using test::Format;
using namespace svgf_inputs;

// svgf's channels (split: diffuse + specular) for the progressive pipeline,
// plus a fp32 sample_count plane when masked.
pipelines::SessionConfig progressive_config(int w, int h, std::vector<pipelines::ParameterValue> params, bool emission,
                                            bool split, bool mask) {
  const Format in = Format::F32;
  std::vector<pipelines::InputChannel> channels;
  if (split) {
    channels = {{ChannelId::Diffuse, in}, {ChannelId::Specular, in}};
  } else {
    channels = {{ChannelId::Radiance, in}};
  }
  for (ChannelId id : {ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth, ChannelId::Motion})
    channels.push_back({id, in});
  if (emission) channels.push_back({ChannelId::Emission, in});
  if (mask) channels.push_back({ChannelId::SampleCount, Format::F32});
  return test::make_config("progressive", w, h, channels, Format::F32, std::move(params));
}

// The reference with the progressive pipeline's own defaults
// (server/pipelines/progressive/progressive.cpp), then the session's parameters; with
// `sparse` (a sample_count plane) paper 004's regime, without it SVGF's
// young-pixel estimate and step order (the age gate and the display lag do
// not apply).
test::SvgfParams progressive_params(const std::vector<pipelines::ParameterValue>& ps, bool sparse) {
  test::SvgfParams p;
  p.alpha_colour = 0.1;
  p.alpha_moments = 0.1;
  p.atrous_iterations = 5;
  p.phi_normal = 64;
  p.taa_alpha = 0.1;
  p.taa_static_alpha = 0.1;
  p.clip_roughness = 0;
  p.kernel_radius = 1;
  p.spatial_estimate = false;
  p.luminance_form = 0;
  p.sigma_luminance = 4;
  p.epsilon_luminance = 0.05;
  p.luminance_min_age = 4;
  p.display_lag = true;
  test::apply_parameters(p, ps);
  if (!sparse) {
    p.spatial_estimate = true;
    p.luminance_min_age = 0;
    p.display_lag = false;
  }
  return p;
}

// A noisy specular signal loosely following the scene (as svgf_test.cpp's).
std::vector<float> specular_of(const SvgfScene& s, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.3f, 1.7f);
  std::vector<float> out(s.radiance.size());
  for (size_t i = 0; i < out.size(); ++i) out[i] = 0.4f * s.radiance[i] * u(rng);
  return out;
}

// 1/4 spp: pixel (x, y) is sampled at frame t iff (x + 2y + t) % 4 == 0 (every
// pixel once in 4 frames, neighbouring rows interleaved). Unsampled pixels
// count 0, or NaN (also "not sampled") at every third.
std::vector<float> quarter_spp(int w, int h, int t) {
  std::vector<float> count(w * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      count[y * w + x] = (x + 2 * y + t) % 4 == 0 ? 1.0f : ((x + y) % 3 == 0 ? NAN : 0.0f);
  return count;
}

// Which pixels a frame samples: every one without a sample_count plane
// (None), every one with the plane saying so (Full: paper 004's regime at
// 1 spp), or quarter_spp's (Quarter).
enum class Mask { None, Full, Quarter };

struct Variant {
  const char* name;
  bool split, emission;
  Mask mask;
  std::vector<pipelines::ParameterValue> params;
  float vx = 1.37f, vy = -0.61f, motion_noise = 0.45f;  // the scene's motion (px per frame)
  int w = 64, h = 40;
  int frames = 8, reset_at = 5;  // reset_at -1: none
};

void PrintTo(const Variant& v, std::ostream* os) { *os << v.name; }

class ProgressiveReferenceTest : public test::GpuTest, public testing::WithParamInterface<Variant> {};

// Output after every frame against the reference, with SvgfReferenceTest's tolerances.
TEST_P(ProgressiveReferenceTest, MatchesCpuReferenceOverFrames) {
  const Variant& v = GetParam();
  const int w = v.w, h = v.h;
  const bool masked = v.mask != Mask::None;
  auto config = progressive_config(w, h, v.params, v.emission, v.split, masked);
  ASSERT_FALSE(pipelines::validate(config).has_value());
  auto pipe = pipelines::create(ctx(), config);
  test::SvgfReference ref(w, h, progressive_params(v.params, masked));
  SvgfSceneGen scene(w, h, 4321, v.vx, v.vy, v.motion_noise, 0.8f, 0.003);
  const int frames = v.frames;
  double worst = 0.0;
  size_t no_data_first = 0;
  for (int t = 0; t < frames; ++t) {
    SCOPED_TRACE(testing::Message() << "frame " << t);
    const uint32_t flags = t == v.reset_at ? protocol::kFrameReset : 0u;
    SvgfScene s = scene.frame(t);
    std::vector<float> spec = v.split ? specular_of(s, 77 + t) : std::vector<float>{};
    const std::vector<float> count = v.mask == Mask::Quarter ? quarter_spp(w, h, t)
                                     : v.mask == Mask::Full  ? std::vector<float>(w * h, 1.0f)
                                                             : std::vector<float>{};
    if (masked)  // nothing rendered where nothing was sampled
      for (int i = 0; i < w * h; ++i)
        if (!(count[i] > 0.0f))
          for (int k = 0; k < 3; ++k) {
            s.radiance[3 * i + k] = 0.0f;
            if (v.split) spec[3 * i + k] = 0.0f;
          }
    test::HostFrame f = host_frame(s, w, h, Format::F32, MotionConvention::PixelsToPrevious, flags, v.emission,
                                   v.split ? &spec : nullptr);
    test::SvgfFrame r = reference_frame(f, w, h, v.emission, v.split);
    if (masked) {
      f.add(ChannelId::SampleCount, Format::F32, count);
      const auto& plane = f.plane(ChannelId::SampleCount);
      r.sample_count = test::decode_plane(plane.bytes, plane.format);
    }
    const std::vector<float> got = run(*pipe, f);
    const std::vector<double> want = ref.step(r);
    if (t == 0)
      no_data_first = std::count(ref.variance().begin(), ref.variance().end(), test::kSvgfNoData);
    ASSERT_EQ(got.size(), want.size());
    for (float g : got) ASSERT_TRUE(std::isfinite(g) && g >= 0.0f) << g;
    const double rms = test::relative_rms(got, want);
    worst = std::max(worst, rms);
    EXPECT_LE(rms, 1e-3);
    size_t gross = 0;
    for (size_t i = 0; i < want.size(); ++i)
      if (std::fabs(got[i] - want[i]) > 2e-2 * std::max(1.0, std::fabs(want[i]))) {
        if (gross < 5)
          ADD_FAILURE() << "pixel " << (i / 3) % w << "," << (i / 3) / w << " channel " << i % 3 << ": got "
                        << got[i] << ", reference " << want[i];
        ++gross;
      }
    EXPECT_EQ(gross, 0u) << "pixels that disagree by more than 2% (a different discrete decision)";
  }
  // The quarter-spp variants must exercise pixels without data (3/4 of the first frame's foreground).
  if (v.mask == Mask::Quarter) {
    EXPECT_GT(no_data_first, size_t(w * h / 8));
  }
  std::printf("[ info     ] %s: worst relative RMS over %d frames %.3g\n", v.name, frames, worst);
}

INSTANTIATE_TEST_SUITE_P(
    Progressive, ProgressiveReferenceTest,
    testing::Values(
        // A sample at every pixel, no sample_count plane: SVGF's young-pixel estimate and step order.
        Variant{"defaults", false, true, Mask::None, {}},
        Variant{"step_order_finest_first", false, true, Mask::None, {{"step_order", 0}}},
        Variant{"variance_form", false, true, Mask::None, {{"luminance_form", 1}}},
        Variant{"six_iterations", false, false, Mask::None, {{"atrous_iterations", 6}}},
        Variant{"split", true, true, Mask::None, {}},
        // Paper 004's regime at 1 spp (sample_count 1 everywhere), moving.
        Variant{"full_mask_moving", false, true, Mask::Full, {}},
        Variant{"full_mask_finest_first", false, true, Mask::Full, {{"step_order", 0}}},
        // 1/4 spp: a static camera (unsampled pixels keep their history
        // exactly) and a moving one (they keep the reprojected history).
        Variant{"quarter_spp_static", false, true, Mask::Quarter, {}, 0.0f, 0.0f, 0.0f},
        Variant{"quarter_spp_moving", false, true, Mask::Quarter, {}},
        Variant{"quarter_spp_moving_finest_first", false, true, Mask::Quarter, {{"step_order", 0}}},
        // A still camera at 1 spp: pixels come of age at frame 3, and the
        // display lags across the switch (display_lag) until the reset at 5;
        // and the same clamped throughout.
        Variant{"still_display_lag", false, true, Mask::Full, {}, 0.0f, 0.0f, 0.0f},
        Variant{"still_no_display_lag", false, true, Mask::Full, {{"display_lag", 0}}, 0.0f, 0.0f, 0.0f},
        // Sub-pixel motion: the lag shrinks with the stillness.
        Variant{"creeping_display_lag", false, true, Mask::Full, {}, 0.02f, 0.01f, 0.0f},
        // The weight coming in over 3 samples past an age gate of 1 (so that
        // 8 frames at 1/4 spp reach it).
        Variant{"quarter_spp_static_ramp_in", false, false, Mask::Quarter,
                {{"luminance_min_age", 1}, {"luminance_ramp_in", 3}}, 0.0f, 0.0f, 0.0f},
        // The luminance weight at every age (at 1/4 spp a history reaches
        // length 4 only after 13 frames): p without data has none, and the
        // variance Gaussian skips taps without data. Whole-pixel motion only:
        // a bilinear blend of one valid tap leaves a single sample's moments
        // with a rounding residual for a variance (exactly 0 or not, fp32 vs
        // double), which decides the HDR step rule and, in the std-dev form,
        // the luminance weight; the age gate is there for that.
        Variant{"quarter_spp_static_luminance", false, false, Mask::Quarter, {{"luminance_min_age", 0}}, 0.0f, 0.0f,
                0.0f},
        Variant{"quarter_spp_moving_variance_form", false, true, Mask::Quarter,
                {{"luminance_min_age", 0}, {"luminance_form", 1}}, 1.0f, -1.0f, 0.0f},
        // Still at 1/4 spp for 48 frames: from 9 samples every pixel, sampled
        // or not, filters its still running mean, whose variance falls with
        // all its samples (past alpha_colour 0.2's 9 of the exponential blend).
        Variant{"quarter_spp_still_converging", false, true, Mask::Quarter, {{"alpha_colour", 0.2}}, 0.0f, 0.0f,
                0.0f, 64, 40, 48, -1}),
    [](const testing::TestParamInfo<Variant>& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace dn
