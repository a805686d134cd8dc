// svgf on the device against the double-precision CPU reference
// (svgf_reference.cpp), its properties and its hard cases.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <random>

#include "frames.hpp"
#include "gpu_test_env.hpp"
#include "pipelines/graph.hpp"
#include "pipelines/pipeline.hpp"
#include "pipelines/sample_summary.hpp"
#include "svgf_inputs.hpp"
#include "svgf_reference.hpp"

namespace dn {
namespace {

using protocol::MotionConvention;
using test::ChannelId;
using test::Format;

class SvgfTest : public test::GpuTest {};

using namespace svgf_inputs;

struct Variant {
  const char* name;
  int w, h;
  Format in, out;
  MotionConvention conv;
  bool emission;
  std::vector<pipelines::ParameterValue> params;
  float vx = 1.37f, vy = -0.61f, motion_noise = 0.45f;  // the scene's motion (px per frame)
  int frames = 7, reset_at = 5;                           // reset_at -1: none
};

void PrintTo(const Variant& v, std::ostream* os) { *os << v.name; }

class SvgfReferenceTest : public SvgfTest, public testing::WithParamInterface<Variant> {};

// Output after every frame against the reference, across formats, motion
// conventions and parameters (svgf_pass_test.cpp compares every pass's
// buffers as well).
TEST_P(SvgfReferenceTest, MatchesCpuReferenceOverFrames) {
  const Variant& v = GetParam();
  auto config = svgf_config(v.w, v.h, v.in, v.out, v.params, v.emission);
  ASSERT_FALSE(pipelines::validate(config).has_value());
  auto pipe = pipelines::create(ctx(), config);
  test::SvgfParams params;
  test::apply_parameters(params, v.params);
  test::SvgfReference ref(v.w, v.h, params);
  SvgfSceneGen scene(v.w, v.h, 4321, v.vx, v.vy, v.motion_noise, 0.8f, 0.003);
  const int frames = v.frames;
  double worst = 0.0;
  for (int t = 0; t < frames; ++t) {
    SCOPED_TRACE(testing::Message() << "frame " << t);
    const uint32_t flags = t == v.reset_at ? protocol::kFrameReset : 0u;
    const test::HostFrame f = host_frame(scene.frame(t), v.w, v.h, v.in, v.conv, flags, v.emission);
    const std::vector<float> got = run(*pipe, f, v.out);
    const std::vector<double> want = ref.step(reference_frame(f, v.w, v.h, v.emission));
    ASSERT_EQ(got.size(), want.size());
    for (float g : got) ASSERT_TRUE(std::isfinite(g) && g >= 0.0f) << g;
    const double rms = test::relative_rms(got, want);
    worst = std::max(worst, rms);
    EXPECT_LE(rms, 1e-3);
    size_t gross = 0;
    for (size_t i = 0; i < want.size(); ++i)
      if (std::fabs(got[i] - want[i]) > 2e-2 * std::max(1.0, std::fabs(want[i]))) ++gross;
    EXPECT_EQ(gross, 0u) << "pixels that disagree by more than 2% (a different discrete decision)";
  }
  std::printf("[ info     ] %s: worst relative RMS over %d frames %.3g\n", v.name, frames, worst);
}

INSTANTIATE_TEST_SUITE_P(
    Variants, SvgfReferenceTest,
    testing::Values(
        Variant{"temporal_only", 96, 64, Format::F32, Format::F32, MotionConvention::PixelsToPrevious, false,
                {{"atrous_iterations", 0}}},
        Variant{"one_iteration", 96, 64, Format::F32, Format::F32, MotionConvention::PixelsToPrevious, false,
                {{"atrous_iterations", 1}, {"feedback_tap", 0}}},
        Variant{"defaults", 128, 72, Format::F32, Format::F32, MotionConvention::PixelsToPrevious, true, {}},
        Variant{"paper_fp16", 97, 61, Format::F16, Format::F16, MotionConvention::PixelsToNext, true,
                {{"atrous_iterations", 5}, {"feedback_tap", 0}}},
        Variant{"uv_params", 80, 50, Format::F32, Format::F32, MotionConvention::UvToPrevious, false,
                {{"alpha_colour", 0.2}, {"alpha_moments", 0.3}, {"max_history", 8}, {"phi_colour", 4},
                 {"phi_normal", 32}, {"phi_depth", 2}, {"atrous_iterations", 3}, {"feedback_tap", 2}}},
        // phi_normal not a power of two: the a-trous normal weight by
        // exp2(phi log2 cos), not by squaring (svgf_atrous.pass, NORMAL_POWER).
        Variant{"phi_normal_100", 96, 64, Format::F32, Format::F32, MotionConvention::PixelsToPrevious, false,
                {{"phi_normal", 100}}},
        // The final TAA blend (taa_alpha > 0): moving camera, reset at frame 5.
        Variant{"taa", 128, 72, Format::F32, Format::F32, MotionConvention::PixelsToPrevious, true,
                {{"taa_alpha", 0.1}}},
        Variant{"taa_fp16_uv", 97, 61, Format::F16, Format::F16, MotionConvention::UvToPrevious, false,
                {{"taa_alpha", 0.25}, {"atrous_iterations", 2}}},
        // Nearly still (|mv| around the 0.05 px static limit): the static
        // blend's weight between 1 (or taa_alpha) and taa_static_alpha.
        Variant{"nearly_still", 96, 64, Format::F32, Format::F32, MotionConvention::PixelsToPrevious, true, {},
                0.01f, 0.02f, 0.02f},
        Variant{"nearly_still_taa", 96, 64, Format::F32, Format::F32, MotionConvention::PixelsToPrevious, false,
                {{"taa_alpha", 0.8}, {"taa_static_alpha", 0.3}}, 0.02f, -0.01f, 0.03f},
        // Still for 20 frames, no reset: the still running mean past its 8
        // samples is the guard's target (converge_still; 1: a narrow band,
        // so that many pixels are pulled).
        Variant{"still_converging", 64, 48, Format::F32, Format::F32, MotionConvention::PixelsToPrevious, true,
                {{"converge_still", 1}}, 0.0f, 0.0f, 0.0f, 20, -1},
        // The same at alpha_colour 0.2: the variance of the still mean handed
        // to the filter falls with all its samples, past the 9 of the blend.
        Variant{"still_converging_alpha", 64, 48, Format::F32, Format::F32, MotionConvention::PixelsToPrevious, true,
                {{"alpha_colour", 0.2}}, 0.0f, 0.0f, 0.0f, 20, -1},
        // History clipping off (clip_roughness 0) and the per-sample
        // variance (variance_of_mean 0): Falcor's svgf.
        Variant{"no_clip", 96, 64, Format::F32, Format::F32, MotionConvention::PixelsToPrevious, true,
                {{"clip_roughness", 0}, {"variance_of_mean", 0}}},
        // Paper 001 §6: the luminance bandwidth ramp of Eq. 8 and the
        // variance kept across the a-trous iterations (reset at frame 5:
        // short histories).
        Variant{"ramp_no_propagation", 96, 64, Format::F32, Format::F32, MotionConvention::PixelsToPrevious, true,
                {{"luminance_ramp", 1}, {"propagate_variance", 0}}}),
    [](const testing::TestParamInfo<Variant>& info) { return std::string(info.param.name); });

// A static geometry description: one plane, unit normals, zero motion.
struct Flat {
  int w, h;
  std::vector<float> albedo, normal, depth, motion;
  Flat(int w_, int h_, float z = 3.0f) : w(w_), h(h_) {
    const int n = w * h;
    albedo.assign(3 * n, 0.5f);
    normal.assign(3 * n, 0.0f);
    depth.assign(n, z);
    motion.assign(2 * n, 0.0f);
    for (int i = 0; i < n; ++i) normal[3 * i + 2] = 1.0f;
  }
  test::HostFrame frame(const std::vector<float>& radiance, uint32_t flags = 0) const {
    test::HostFrame f;
    f.info.flags = flags;
    f.add(ChannelId::Radiance, Format::F32, radiance);
    f.add(ChannelId::Albedo, Format::F32, albedo);
    f.add(ChannelId::Normal, Format::F32, normal);
    f.add(ChannelId::Depth, Format::F32, depth);
    f.add(ChannelId::Motion, Format::F32, motion);
    return f;
  }
};

TEST_F(SvgfTest, ConstantInputStaysConstant) {
  const int w = 64, h = 48, n = w * h;
  Flat scene(w, h);
  for (int i = 0; i < n; ++i) {
    scene.motion[2 * i] = 0.3f * ((i * 7) % 5) - 0.6f;
    scene.motion[2 * i + 1] = 0.25f;
  }
  std::vector<float> radiance(3 * n);
  for (int i = 0; i < n; ++i) {
    radiance[3 * i] = 0.25f;
    radiance[3 * i + 1] = 1.5f;
    radiance[3 * i + 2] = 3000.0f;
  }
  auto pipe = pipelines::create(ctx(), svgf_config(w, h));
  for (int t = 0; t < 8; ++t) {
    const auto out = run(*pipe, scene.frame(radiance));
    for (int i = 0; i < 3 * n; ++i)
      ASSERT_NEAR(out[i], radiance[i], 1e-5 * radiance[i]) << "frame " << t << " element " << i;
  }
}

// Two depth planes (z = 1 left, z = 10 right, same normal) with different
// noisy radiance: the filter averages within each plane and never across.
TEST_F(SvgfTest, HardGeometricEdgeIsNotBlurred) {
  const int w = 64, h = 32, n = w * h, edge = 32;
  Flat scene(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = edge; x < w; ++x) scene.depth[y * w + x] = 10.0f;
  auto pipe = pipelines::create(ctx(), svgf_config(w, h));
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> noise(0.5f, 1.5f);
  std::vector<float> radiance(3 * n), out;
  for (int t = 0; t < 6; ++t) {
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) radiance[3 * i + k] = (i % w < edge ? 1.0f : 20.0f) * noise(rng);
    out = run(*pipe, scene.frame(radiance));
  }
  for (int y = 0; y < h; ++y) {
    const float left = out[3 * (y * w + edge - 1)], right = out[3 * (y * w + edge)];
    EXPECT_LT(left, 1.6f) << "row " << y;   // mean 1, within the noise; 20 would leak in visibly
    EXPECT_GT(right, 12.0f) << "row " << y;  // mean 20
  }
}

// A still flat surface with uniform noise 0..2 around 1 (input RMS 1/sqrt(3)): the output's RMS after each of `frames` frames.
std::vector<double> flat_noisy_rms(gpu::Context& ctx, int frames) {
  const int w = 64, h = 48, n = w * h;
  Flat scene(w, h);
  auto pipe = pipelines::create(ctx, svgf_config(w, h));
  std::mt19937 rng(99);
  std::uniform_real_distribution<float> noise(0.0f, 2.0f);
  std::vector<float> radiance(3 * n);
  std::vector<double> rms;
  for (int t = 0; t < frames; ++t) {
    for (auto& r : radiance) r = noise(rng);
    const auto out = run(*pipe, scene.frame(radiance));
    double sum = 0;
    for (float v : out) sum += (v - 1.0) * (v - 1.0);
    rms.push_back(std::sqrt(sum / out.size()));
  }
  return rms;
}

TEST_F(SvgfTest, StaticNoisySceneErrorFalls) {
  const std::vector<double> rms = flat_noisy_rms(ctx(), 24);
  std::printf("[ info     ] rms after 1, 4, 8, 24 frames: %.4f %.4f %.4f %.4f (input %.4f)\n", rms[0], rms[3], rms[7],
              rms[23], 1.0 / std::sqrt(3.0));
  EXPECT_LT(rms[0], 0.5 / std::sqrt(3.0));
  EXPECT_LT(rms[3], rms[0]);
  EXPECT_LT(rms[7], rms[3]);
  EXPECT_LT(rms[23], rms[7]);
}

// The still running mean takes over the guard's target gradually: on a
// flat noisy still surface the filtered output is far better than a 4-sample
// mean, and switching to that mean at once raised the RMSE 2.5-fold at
// frame 4 (0.0138 -> 0.0339); over 4 samples, by at most 1.46.
TEST_F(SvgfTest, AStillViewDoesNotJumpWhenItsMeanTakesOver) {
  const std::vector<double> rms = flat_noisy_rms(ctx(), 8);
  std::printf("[ info     ] rms after 3 to 8 frames: %.5f %.5f %.5f %.5f %.5f %.5f\n", rms[2], rms[3], rms[4], rms[5],
              rms[6], rms[7]);
  for (int t = 4; t <= 8; ++t) EXPECT_LE(rms[t - 1], 1.6 * rms[2]) << t << " frames";
}

// A shadow falls on a still noisy floor (radiance 0..2 per channel, 0.2 of
// it on the left from frame 40) and leaves at frame 60: the still running
// mean must not hold the light that changed. Its change test restarts the
// mean and the history, so eight frames after each change the side is shown
// within 10 % (the running mean of all frames would show 0.87 in the
// shadow, the plain temporal blend 0.71; what is left decays as 1/n: the
// first a-trous output fed back mixed in neighbours restarted a frame
// later); the device matches the CPU reference on every frame, the restarts included.
TEST_F(SvgfTest, AShadowFallingOnAStillViewRestartsItsMean) {
  const int w = 64, h = 32, n = w * h, before = 40, after = 60;
  Flat scene(w, h);
  const std::vector<pipelines::ParameterValue> params = {{"taa_static_alpha", 0}};
  auto pipe = pipelines::create(ctx(), svgf_config(w, h, Format::F32, Format::F32, params));
  test::SvgfParams p;
  test::apply_parameters(p, params);
  test::SvgfReference ref(w, h, p);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> noise(0.0f, 2.0f);
  std::vector<float> radiance(3 * n);
  for (int t = 0; t < after + 8; ++t) {
    const bool shadow = t >= before && t < after;
    for (int i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c) radiance[3 * i + c] = noise(rng) * (shadow && i % w < w / 2 ? 0.2f : 1.0f);
    const test::HostFrame f = scene.frame(radiance);
    const std::vector<float> out = run(*pipe, f);
    const std::vector<double> want = ref.step(reference_frame(f, w, h, false));
    ASSERT_LE(test::relative_rms(out, want), 1e-3) << "frame " << t;
    if (t != before + 7 && t != after + 7) continue;
    double side = 0.0;
    int count = 0;
    for (int i = 0; i < n; ++i)
      if (i % w < w / 2 - 8)  // beyond the reach of the filter's bleed across the edge
        for (int c = 0; c < 3; ++c, ++count) side += out[3 * i + c];
    side /= count;
    const double truth = t < after ? 0.2 : 1.0;
    std::printf("[ info     ] shadowed side 8 frames after the change: %.4f (truth %.1f)\n", side, truth);
    EXPECT_NEAR(side, truth, 0.1 * truth);
  }
}

// A still pixel kept as rendered (albedo 0: a metal the renderer folds into
// its radiance) shows exactly the plain running mean of its samples from
// the first frame on, TAA on (the default), so it is never worse than that
// mean.
// The change test must not take noise for a change: on a still view of
// heavy-tailed light (exponential per channel) and of sparse light (90 %
// of samples 0, the rest up to 20), kept pixels (albedo 0) show their
// running mean exactly while it goes on, so a pixel off it was restarted.
// A test of each frame's box value twice in a row restarted 30 % of the
// sparse view within 64 frames.
TEST_F(SvgfTest, NoiseDoesNotRestartAStillMean) {
  const int w = 64, h = 48, n = w * h;
  Flat scene(w, h);
  std::fill(scene.albedo.begin(), scene.albedo.end(), 0.0f);
  auto pipe = pipelines::create(ctx(), svgf_config(w, h));
  std::mt19937 rng(5);
  std::exponential_distribution<float> exponential(1.0f);
  std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
  for (const bool sparse : {false, true}) {
    std::vector<float> radiance(3 * n);
    std::vector<double> sum(3 * n, 0.0);
    int restarted = 0;
    for (int t = 1; t <= 64; ++t) {
      for (int j = 0; j < 3 * n; ++j)
        sum[j] += radiance[j] = sparse ? (uniform(rng) < 0.1f ? 20.0f * uniform(rng) : 0.0f) : exponential(rng);
      const auto out = run(*pipe, scene.frame(radiance, t == 1 ? protocol::kFrameReset : 0u));
      restarted = 0;
      for (int i = 0; i < n; ++i)
        if (std::fabs(out[3 * i] - sum[3 * i] / t) > 1e-4 * (1.0 + sum[3 * i] / t)) ++restarted;
    }
    std::printf("[ info     ] %s light: %d of %d pixels restarted within 64 frames\n", sparse ? "sparse" : "exponential",
                restarted, n);
    EXPECT_LE(restarted, (sparse ? 0.04 : 0.005) * n);
  }
}

TEST_F(SvgfTest, AStillKeptPixelShowsThePlainMeanOfItsSamples) {
  const int w = 32, h = 16, n = w * h;
  Flat scene(w, h);
  for (int i = 0; i < n; ++i)
    if (i % w >= w / 2)
      for (int c = 0; c < 3; ++c) scene.albedo[3 * i + c] = 0.0f;
  auto pipe = pipelines::create(ctx(), svgf_config(w, h));
  std::mt19937 rng(5);
  std::exponential_distribution<float> noise(1.0f);  // heavy-tailed, like a metal's highlight at 1 spp
  std::vector<float> radiance(3 * n);
  std::vector<double> sum(3 * n, 0.0);
  for (int t = 1; t <= 12; ++t) {
    for (int j = 0; j < 3 * n; ++j) sum[j] += radiance[j] = noise(rng);
    const auto out = run(*pipe, scene.frame(radiance));
    for (int i = 0; i < n; ++i) {
      if (i % w < w / 2) continue;
      for (int c = 0; c < 3; ++c)
        ASSERT_NEAR(out[3 * i + c], sum[3 * i + c] / t, 1e-5 * (1.0 + sum[3 * i + c] / t)) << "frame " << t << " pixel " << i;
    }
  }
  // An albedo above 1.5 is that frame's own (Cycles' Denoising Albedo of a
  // light one reflected sample hit): the means of other frames' samples are
  // not remodulated by it; the pixel shows the frame's radiance.
  for (int i = 0; i < n; ++i)
    if (i % w >= w / 2)
      for (int c = 0; c < 3; ++c) scene.albedo[3 * i + c] = 14.0f;
  for (float& r : radiance) r = noise(rng);
  const auto out = run(*pipe, scene.frame(radiance));
  for (int i = 0; i < n; ++i) {
    if (i % w < w / 2) continue;
    for (int c = 0; c < 3; ++c) ASSERT_FLOAT_EQ(out[3 * i + c], radiance[3 * i + c]) << "pixel " << i;
  }
}

// Emission is added back unfiltered; on a still pixel its running mean is
// (converge_still). Radiance = emission, so the output is what is added:
// on the left, noisy light (uniform 0..2 times 0.8), the plain mean of the
// samples sent; on the right a steady emitter that steps from 3 to 5 at
// frame 20 (a change in place): the first changed sample is merged (one
// outlier), the second restarts the mean, so the output shows 5 from then.
// Moving pixels add the frame's own emission.
TEST_F(SvgfTest, StillEmissionIsItsRunningMeanAndFollowsAChange) {
  const int w = 32, h = 16, n = w * h, change = 20;
  Flat scene(w, h);
  // Without TAA, which would blend the output over frames.
  auto pipe = pipelines::create(
      ctx(), svgf_config(w, h, Format::F32, Format::F32, {{"taa_alpha", 0}, {"taa_static_alpha", 0}}, true));
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> noise(0.0f, 2.0f);
  std::vector<float> emission(3 * n);
  std::vector<double> sum(3 * n, 0.0);
  auto frame_of = [&](const std::vector<float>& e, uint32_t flags) {
    test::HostFrame f = scene.frame(e, flags);
    f.add(ChannelId::Emission, Format::F32, e);
    return f;
  };
  for (int t = 1; t <= change + 1; ++t) {
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k)
        emission[3 * i + k] = i % w < w / 2 ? 0.8f * noise(rng) : (t < change ? 3.0f : 5.0f);
    const auto out = run(*pipe, frame_of(emission, 0));
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) {
        const int j = 3 * i + k;
        sum[j] += emission[j];
        if (i % w < w / 2) {
          ASSERT_NEAR(out[j], sum[j] / t, 1e-5 * (1.0 + sum[j] / t)) << "frame " << t << " pixel " << i;
        } else if (t < change) {
          ASSERT_FLOAT_EQ(out[j], 3.0f) << "frame " << t;
        } else if (t == change) {
          ASSERT_NEAR(out[j], (3.0 * (change - 1) + 5.0) / change, 1e-5) << "the first changed sample is merged";
        } else {
          ASSERT_FLOAT_EQ(out[j], 5.0f) << "the second changed sample restarts the mean";
        }
      }
  }
  for (int i = 0; i < n; ++i) scene.motion[2 * i] = 0.5f;  // moving: the frame's own emission
  for (int i = 0; i < 3 * n; ++i) emission[i] = 0.8f * noise(rng);
  const auto out = run(*pipe, frame_of(emission, 0));
  for (int j = 0; j < 3 * n; ++j) ASSERT_FLOAT_EQ(out[j], emission[j]) << j;
}

// Renderers write no motion on background pixels (Cycles: 0), so a pixel
// that turns from a surface to the sky under a moving camera looks still.
// A background pixel keeps no emission mean: it shows its own emission
// (the sky's), and a surface that appears there again starts a new mean.
TEST_F(SvgfTest, ABackgroundPixelKeepsNoStillEmissionMean) {
  const int w = 32, h = 16, n = w * h;
  Flat scene(w, h);
  auto pipe = pipelines::create(
      ctx(), svgf_config(w, h, Format::F32, Format::F32, {{"taa_alpha", 0}, {"taa_static_alpha", 0}}, true));
  auto frame_of = [&](float e) {
    const std::vector<float> emission(3 * n, e);
    test::HostFrame f = scene.frame(emission);
    f.add(ChannelId::Emission, Format::F32, emission);
    return f;
  };
  for (int t = 0; t < 12; ++t) run(*pipe, frame_of(3.0f));  // a still emitter: its mean holds 12 samples
  std::fill(scene.depth.begin(), scene.depth.end(), std::numeric_limits<float>::infinity());
  std::vector<float> out = run(*pipe, frame_of(1.3f));
  for (int j = 0; j < 3 * n; ++j) ASSERT_FLOAT_EQ(out[j], 1.3f) << "the sky's own emission at " << j;
  std::fill(scene.depth.begin(), scene.depth.end(), 3.0f);
  out = run(*pipe, frame_of(0.4f));
  for (int j = 0; j < 3 * n; ++j) ASSERT_FLOAT_EQ(out[j], 0.4f) << "a new mean, without the sky's sample, at " << j;
}

// RESULT.samples: a still pixel rests on every frame sent (its running mean
// goes past the history cap); a reset starts again from one; without
// converge_still the count is the capped history length.
TEST_F(SvgfTest, SampleCountsFollowTheStillRunningMean) {
  const int w = 32, h = 16, n = w * h;
  Flat scene(w, h);
  std::vector<float> radiance(3 * n, 0.7f);
  auto pipe = pipelines::create(ctx(), svgf_config(w, h));
  for (uint32_t t = 1; t <= 45; ++t) {
    run(*pipe, scene.frame(radiance));
    const auto s = pipe->samples();
    ASSERT_TRUE(s) << t;
    EXPECT_EQ(s->min, t) << t;
    EXPECT_EQ(s->median, t) << t << " (every pixel rests on t frames: its bin's floor would be below the minimum)";
  }
  run(*pipe, scene.frame(radiance, protocol::kFrameReset));
  EXPECT_EQ(pipe->samples()->min, 1u);
  EXPECT_EQ(pipe->samples()->median, 1u);

  auto capped =
      pipelines::create(ctx(), svgf_config(w, h, Format::F32, Format::F32, {{"converge_still", 0}, {"max_history", 8}}));
  for (int t = 1; t <= 12; ++t) run(*capped, scene.frame(radiance));
  EXPECT_EQ(capped->samples()->min, 8u);
  EXPECT_EQ(capped->samples()->median, 8u);
}

// After a reset the output is exactly what a fresh session makes of the frame.
TEST_F(SvgfTest, ResetLeavesNoGhost) {
  const int w = 40, h = 30, n = w * h;
  Flat scene(w, h);
  std::vector<float> a(3 * n, 5.0f), b(3 * n);
  for (int i = 0; i < 3 * n; ++i) b[i] = 0.01f * (i % 17);
  auto pipe = pipelines::create(ctx(), svgf_config(w, h));
  for (int t = 0; t < 10; ++t) run(*pipe, scene.frame(a));
  auto fresh = pipelines::create(ctx(), svgf_config(w, h));
  const auto want = run(*fresh, scene.frame(b));
  EXPECT_EQ(run(*pipe, scene.frame(b, protocol::kFrameReset)), want);
  EXPECT_EQ(run(*pipe, scene.frame(b)), run(*fresh, scene.frame(b)));
}

TEST_F(SvgfTest, BadRadianceNeverReachesOutputOrHistoryAndPixelsRecover) {
  const int w = 32, h = 24, n = w * h;
  Flat scene(w, h);
  const float value = 2.0f;
  std::vector<float> good(3 * n, value);
  auto pipe = pipelines::create(ctx(), svgf_config(w, h));
  for (int t = 0; t < 6; ++t) run(*pipe, scene.frame(good));
  std::vector<float> bad = good;
  const float specials[] = {NAN, INFINITY, -INFINITY, -3.0f, 1e30f, 3e38f};
  for (int i = 0; i < 6; ++i) bad[3 * (40 + 37 * i) + (i % 3)] = specials[i];
  for (int k = 0; k < 3; ++k) bad[3 * 300 + k] = 1e30f;
  auto out = run(*pipe, scene.frame(bad));
  for (float v : out) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f && v <= value) << v;
  for (int t = 0; t < 60; ++t) {
    out = run(*pipe, scene.frame(good));
    for (float v : out) ASSERT_TRUE(std::isfinite(v)) << v;
  }
  for (int i = 0; i < 3 * n; ++i) EXPECT_NEAR(out[i], value, 0.01 * value) << i;
}

// A bright square in front of an all-black backdrop jumps away: the region it
// uncovers has only black history and black neighbours (zero moments, zero
// variance), so it must come out exactly black, not a ghost of the square and
// not 0/0.
TEST_F(SvgfTest, AllBlackDisoccludedRegionStaysBlack) {
  const int w = 64, h = 40, n = w * h;
  Flat scene(w, h, 8.0f);
  auto square = [&](int x0) {
    std::vector<float> radiance(3 * n, 0.0f);
    for (int i = 0; i < n; ++i) {
      const int x = i % w, y = i / w;
      const bool in = x >= x0 && x < x0 + 12 && y >= 14 && y < 26;
      scene.depth[i] = in ? 2.0f : 8.0f;
      for (int k = 0; k < 3; ++k) radiance[3 * i + k] = in ? 10.0f : 0.0f;
    }
    return radiance;
  };
  auto pipe = pipelines::create(ctx(), svgf_config(w, h));
  for (int t = 0; t < 6; ++t) run(*pipe, scene.frame(square(4)));
  for (int t = 0; t < 3; ++t) {
    const auto out = run(*pipe, scene.frame(square(48)));  // static camera: zero motion
    for (int i = 0; i < n; ++i) {
      const int x = i % w, y = i / w;
      for (int k = 0; k < 3; ++k) ASSERT_TRUE(std::isfinite(out[3 * i + k]));
      if (x >= 4 && x < 16 && y >= 14 && y < 26) {
        for (int k = 0; k < 3; ++k) ASSERT_EQ(out[3 * i + k], 0.0f) << "frame " << t << " pixel " << x << "," << y;
      }
    }
  }
}

// A dark surface that, as at well under one sample per pixel, gets a sample
// in one pixel of 16 (value 16 L, mean L) and exact zeros elsewhere, in front
// of a lit noisy wall: finite, non-negative (zero moments and zero variance
// are the common case there), and the region's mean output tends to L as the
// sparse samples accumulate (not to 0, not to the lit level). The depth edge
// keeps the wall out; on one surface SVGF's luminance edge-stopping (10 sigma
// by default) would let the lit side bleed in over the a-trous footprint.
TEST_F(SvgfTest, SparseDarkRegionConvergesToItsMean) {
  const int w = 64, h = 48, n = w * h;
  const float lit = 2.0f, dark = 0.05f;
  Flat scene(w, h);
  auto inside = [&](int i) { return i % w >= 16 && i % w < 48 && i / w >= 12 && i / w < 36; };
  for (int i = 0; i < n; ++i)
    if (inside(i)) scene.depth[i] = 1.5f;
  auto pipe = pipelines::create(ctx(), svgf_config(w, h));
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> noise(0.5f, 1.5f);
  std::uniform_int_distribution<int> pick(0, 15);
  std::vector<float> radiance(3 * n), out;
  double region_mean = 0.0;
  for (int t = 0; t < 40; ++t) {
    for (int i = 0; i < n; ++i) {
      const float v = inside(i) ? (pick(rng) == 0 ? 16.0f * dark : 0.0f) : lit * noise(rng);
      for (int k = 0; k < 3; ++k) radiance[3 * i + k] = v;
    }
    out = run(*pipe, scene.frame(radiance));
    for (float v : out) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f) << v;
  }
  // The mean over the region away from its border (the lit side bleeds in over a pixel or two).
  int count = 0;
  for (int i = 0; i < n; ++i)
    if (i % w >= 20 && i % w < 44 && i / w >= 16 && i / w < 32) {
      region_mean += out[3 * i];
      ++count;
    }
  region_mean /= count;
  std::printf("[ info     ] sparse dark region: mean output %.4f (mean input %.4f, lit %.1f)\n", region_mean, dark, lit);
  EXPECT_NEAR(region_mean, dark, 0.25 * dark);
}

// Radiance includes what the primary hit emits; with the emission channel
// declared, an emitter's pixels must come out at their radiance, not at
// radiance + emission (the emitted part is added back once, unfiltered).
TEST_F(SvgfTest, EmitterIsNotCountedTwice) {
  const int w = 48, h = 32, n = w * h;
  Flat scene(w, h);
  std::vector<float> radiance(3 * n), emission(3 * n, 0.0f);
  for (int i = 0; i < n; ++i) {
    const bool light = i % w >= 16 && i % w < 32 && i / w >= 8 && i / w < 24;
    for (int k = 0; k < 3; ++k) {
      emission[3 * i + k] = light ? 7.0f + k : 0.0f;
      radiance[3 * i + k] = light ? 7.0f + k : 0.5f;
      if (light) scene.albedo[3 * i + k] = 0.0f;
    }
    if (light) scene.depth[i] = 2.0f;  // a lamp in front of a wall
  }
  auto pipe = pipelines::create(ctx(), svgf_config(w, h, Format::F32, Format::F32, {}, true));
  for (int t = 0; t < 4; ++t) {
    test::HostFrame f = scene.frame(radiance);
    f.add(ChannelId::Emission, Format::F32, emission);
    const auto out = run(*pipe, f);
    for (int i = 0; i < 3 * n; ++i) ASSERT_NEAR(out[i], radiance[i], 1e-5 * radiance[i]) << "frame " << t << " " << i;
  }
}

// Zero, tiny, negative and non-finite albedo: not demodulated (factor 1), output finite.
TEST_F(SvgfTest, ZeroAlbedoGivesFiniteOutput) {
  const int w = 32, h = 24, n = w * h;
  Flat scene(w, h);
  const float specials[] = {0.0f, 1e-9f, -1.0f, NAN, INFINITY, 0.0f};
  for (int i = 0; i < 3 * n; ++i) scene.albedo[i] = specials[i % 6];
  std::vector<float> radiance(3 * n, 0.7f);
  auto pipe = pipelines::create(ctx(), svgf_config(w, h));
  for (int t = 0; t < 4; ++t) {
    const auto out = run(*pipe, scene.frame(radiance));
    for (int i = 0; i < 3 * n; ++i) ASSERT_NEAR(out[i], 0.7f, 1e-5) << i;
  }
}

// svgf(k x) = k svgf(x): documented epsilons (variance + 1e-20, luminance
// guard 1e-20, radiance cut 1e12) only act far outside this range.
TEST_F(SvgfTest, OutputScalesWithInput) {
  const int w = 64, h = 40;
  std::vector<std::vector<float>> base;
  for (double k : {1.0, 1e-3, 1e3, 1e-6, 1e4}) {
    SCOPED_TRACE(k);
    auto pipe = pipelines::create(ctx(), svgf_config(w, h, Format::F32, Format::F32, {}, true));
    SvgfSceneGen scene(w, h, 8, 0.6f, -0.4f, 0.3f, 0.9f);
    double worst = 0.0;
    for (int t = 0; t < 5; ++t) {
      SvgfScene s = scene.frame(t);
      for (auto& r : s.radiance) r = static_cast<float>(r * k);
      for (auto& e : s.emission) e = static_cast<float>(e * k);
      const auto out = run(*pipe, host_frame(s, w, h, Format::F32, MotionConvention::PixelsToPrevious, 0, true));
      if (k == 1.0) {
        base.push_back(out);
        continue;
      }
      std::vector<double> want(out.size());
      std::vector<float> got(out.size());
      for (size_t i = 0; i < out.size(); ++i) {
        want[i] = base[t][i];
        got[i] = static_cast<float>(out[i] / k);
      }
      const double rms = test::relative_rms(got, want);
      worst = std::max(worst, rms);
      EXPECT_LE(rms, 1e-3) << "frame " << t;
    }
    if (k != 1.0) std::printf("[ info     ] k = %g: worst relative RMS %.3g\n", k, worst);
  }
}

TEST_F(SvgfTest, TimingsNameEveryPass) {
  auto pipe = pipelines::create(ctx(), svgf_config(32, 32));
  SvgfSceneGen scene(32, 32, 3, 1, 1, 0, 0.1f);
  std::vector<pipelines::PassTiming> timings;
  run(*pipe, host_frame(scene.frame(0), 32, 32, Format::F32, MotionConvention::PixelsToPrevious, 0, false),
      Format::F32, &timings);
  std::vector<std::string> names;
  for (const auto& t : timings) names.push_back(t.name);
  EXPECT_EQ(names, (std::vector<std::string>{"upload", "svgf_reproject", "svgf_variance", "svgf_atrous_0",
                                             "svgf_atrous_1", "svgf_atrous_2", "svgf_atrous_3", "svgf_remodulate",
                                             "svgf_taa", "sample_summary", "download"}));
}

TEST_F(SvgfTest, DeviceBytesAreAsDocumented) {
  for (auto c : {svgf_config(64, 48), svgf_config(33, 17, Format::F16, Format::F16, {}, true),
                 svgf_config(20, 10, Format::F32, Format::F32, {{"atrous_iterations", 0}})}) {
    auto p = pipelines::create(ctx(), c);
    EXPECT_EQ(p->device_bytes(), pipelines::estimate_device_bytes(c));
  }
  // fp32: inputs 12+12+12+4+8, history 16+16 (one copy) + 16+4+16 (the still running mean, its M2 and its change
  // test: converge_still) + 16 (the TAA blend's, fp32 vec4(rgb, lag)), scratch 5*16 (3 illumination: the harm guard
  // keeps the first, guide, temporal), output 12 = 224 B/px, + the constants block (FrameConstants).
  EXPECT_EQ(pipelines::estimate_device_bytes(svgf_config(64, 48)), 64u * 48 * 224 + pipelines::GraphSpec::kConstantBytes +
            pipelines::kSampleSummaryBytes);
  // fp16 planes and output: the same 224 B/px (planes are fp32 on the device, widened at upload).
  EXPECT_EQ(pipelines::estimate_device_bytes(svgf_config(64, 48, Format::F16, Format::F16)), 64u * 48 * 224 + pipelines::GraphSpec::kConstantBytes +
            pipelines::kSampleSummaryBytes);
  // Without the TAA blend (taa_alpha and taa_static_alpha 0): 208 B/px; without converge_still 172; without
  // the harm guard (which alone reads the still mean) 156.
  EXPECT_EQ(pipelines::estimate_device_bytes(svgf_config(64, 48, Format::F32, Format::F32, {{"taa_static_alpha", 0}})),
            64u * 48 * 208 + pipelines::GraphSpec::kConstantBytes +
            pipelines::kSampleSummaryBytes);
  EXPECT_EQ(pipelines::estimate_device_bytes(
                svgf_config(64, 48, Format::F32, Format::F32, {{"taa_static_alpha", 0}, {"converge_still", 0}})),
            64u * 48 * 172 + pipelines::GraphSpec::kConstantBytes +
            pipelines::kSampleSummaryBytes);
  EXPECT_EQ(pipelines::estimate_device_bytes(
                svgf_config(64, 48, Format::F32, Format::F32, {{"taa_static_alpha", 0}, {"harm_guard", 0}})),
            64u * 48 * 156 + pipelines::GraphSpec::kConstantBytes +
            pipelines::kSampleSummaryBytes);
}

TEST(SvgfValidate, ChannelsAndParameters) {
  EXPECT_FALSE(pipelines::validate(svgf_config(16, 16, Format::F16, Format::F16, {}, true)).has_value());
  auto c = svgf_config(16, 16);
  c.channels.erase(c.channels.begin() + 1);
  const auto err = pipelines::validate(c);
  ASSERT_TRUE(err.has_value());
  EXPECT_EQ(err->problem, pipelines::ConfigProblem::MissingChannel);
  EXPECT_NE(err->message.find("albedo"), std::string::npos);
  EXPECT_TRUE(pipelines::validate(svgf_config(16, 16, Format::F32, Format::F32, {{"atrous_iterations", 9}})).has_value());
  EXPECT_TRUE(pipelines::validate(svgf_config(16, 16, Format::F32, Format::F32, {{"atrous_iterations", 2.5}})).has_value());
}

// A noisy specular signal loosely following the scene: 0.4 x radiance x U(0.3, 1.7) per component.
std::vector<float> specular_of(const SvgfScene& s, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.3f, 1.7f);
  std::vector<float> out(s.radiance.size());
  for (size_t i = 0; i < out.size(); ++i) out[i] = 0.4f * s.radiance[i] * u(rng);
  return out;
}

// Split mode: diffuse and specular each through their own chain, against the
// reference over frames (reset at frame 4).
TEST_F(SvgfTest, SplitMatchesCpuReferenceOverFrames) {
  struct SplitVariant {
    const char* name;
    int w, h;
    Format in, out;
    bool emission;
    std::vector<pipelines::ParameterValue> params;
    test::SvgfParams ref;
  };
  test::SvgfParams zero_iter;
  zero_iter.atrous_iterations = 0;
  test::SvgfParams paper;
  paper.atrous_iterations = 5;
  paper.feedback_tap = 0;
  test::SvgfParams taa;
  taa.taa_alpha = 0.1;
  const SplitVariant variants[] = {
      {"split_defaults", 128, 72, Format::F32, Format::F32, true, {}, test::SvgfParams{}},
      {"split_temporal_only", 96, 64, Format::F32, Format::F32, false, {{"atrous_iterations", 0}}, zero_iter},
      {"split_paper_fp16", 97, 61, Format::F16, Format::F16, true, {{"atrous_iterations", 5}, {"feedback_tap", 0}},
       paper},
      {"split_taa", 96, 64, Format::F32, Format::F32, true, {{"taa_alpha", 0.1}}, taa},
  };
  for (const auto& v : variants) {
    SCOPED_TRACE(v.name);
    auto config = svgf_split_config(v.w, v.h, v.in, v.out, v.params, v.emission);
    ASSERT_FALSE(pipelines::validate(config).has_value());
    auto pipe = pipelines::create(ctx(), config);
    test::SvgfReference ref(v.w, v.h, v.ref);
    SvgfSceneGen scene(v.w, v.h, 4321, 1.37f, -0.61f, 0.45f, 0.8f, 0.003);
    const int frames = 6;
    double worst = 0.0;
    for (int t = 0; t < frames; ++t) {
      SCOPED_TRACE(testing::Message() << "frame " << t);
      const uint32_t flags = t == 4 ? protocol::kFrameReset : 0u;
      const SvgfScene s = scene.frame(t);
      const std::vector<float> spec = specular_of(s, 77 + t);
      const test::HostFrame f =
          host_frame(s, v.w, v.h, v.in, MotionConvention::PixelsToPrevious, flags, v.emission, &spec);
      const std::vector<float> got = run(*pipe, f, v.out);
      const std::vector<double> want = ref.step(reference_frame(f, v.w, v.h, v.emission, true));
      ASSERT_EQ(got.size(), want.size());
      for (float g : got) ASSERT_TRUE(std::isfinite(g) && g >= 0.0f) << g;
      const double rms = test::relative_rms(got, want);
      worst = std::max(worst, rms);
      EXPECT_LE(rms, 1e-3);
    }
    std::printf("[ info     ] %s: worst relative RMS over %d frames %.3g\n", v.name, frames, worst);
  }
}

// Split mode with specular = 0 is radiance mode with radiance = diffuse + emission.
TEST_F(SvgfTest, SplitWithZeroSpecularEqualsRadianceMode) {
  const int w = 80, h = 56;
  auto radiance_pipe = pipelines::create(ctx(), svgf_config(w, h, Format::F32, Format::F32, {}, true));
  auto split_pipe = pipelines::create(ctx(), svgf_split_config(w, h, Format::F32, Format::F32, {}, true));
  SvgfSceneGen scene(w, h, 11, 0.8f, 0.5f, 0.3f, 0.9f, 0.003);
  const std::vector<float> zero(3 * w * h, 0.0f);
  for (int t = 0; t < 6; ++t) {
    SCOPED_TRACE(testing::Message() << "frame " << t);
    const SvgfScene s = scene.frame(t);
    SvgfScene with_emission = s;  // radiance = diffuse + specular (0) + emission
    for (size_t i = 0; i < s.radiance.size(); ++i) with_emission.radiance[i] = s.radiance[i] + s.emission[i];
    const auto want =
        run(*radiance_pipe, host_frame(with_emission, w, h, Format::F32, MotionConvention::PixelsToPrevious, 0, true));
    const auto got =
        run(*split_pipe, host_frame(s, w, h, Format::F32, MotionConvention::PixelsToPrevious, 0, true, &zero));
    ASSERT_EQ(got.size(), want.size());
    for (size_t i = 0; i < got.size(); ++i)
      ASSERT_NEAR(got[i], want[i], 1e-5 * std::max(1.0f, std::fabs(want[i]))) << i;
  }
}

// keep_unexplained in split mode: a moving pixel whose albedo is 0 in every
// component (a metal or mirror under a diffuse colour) shows its own diffuse
// + specular + emission as sent, a highlight among dark neighbours included;
// with keep_unexplained 0 the filter spreads the highlight.
TEST_F(SvgfTest, SplitKeepsPixelsWithoutAReflectanceAsRendered) {
  const int w = 64, h = 48;
  for (const double keep : {1.0, 0.0}) {
    SCOPED_TRACE(testing::Message() << "keep_unexplained " << keep);
    auto pipe = pipelines::create(
        ctx(), svgf_split_config(w, h, Format::F32, Format::F32, {{"keep_unexplained", keep}}, true));
    SvgfSceneGen scene(w, h, 5, 1.37f, -0.61f, 0.45f, 0.8f);
    size_t kept = 0, checked = 0;
    for (int t = 0; t < 5; ++t) {
      SvgfScene s = scene.frame(t);
      std::vector<float> spec = specular_of(s, 9 + t);
      // A metal block, dark but for a one-pixel highlight 100x its neighbours.
      for (int y = 16; y < 32; ++y)
        for (int x = 20; x < 44; ++x) {
          const int i = y * w + x;
          for (int k = 0; k < 3; ++k) {
            s.albedo[3 * i + k] = 0.0f;
            spec[3 * i + k] = (x == 31 && y == 23) ? 50.0f : 0.5f;
          }
        }
      const auto out = run(*pipe, host_frame(s, w, h, Format::F32, MotionConvention::PixelsToPrevious, 0, true, &spec));
      for (int y = 16; y < 32; ++y)
        for (int x = 20; x < 44; ++x) {
          const int i = y * w + x;
          if (!(std::hypot(s.motion[2 * i], s.motion[2 * i + 1]) >= 0.05f)) continue;  // moving: no blend toward history
          ++checked;
          bool same = true;
          for (int k = 0; k < 3; ++k) {
            const float sent = std::max(s.radiance[3 * i + k], 0.0f) + spec[3 * i + k] + s.emission[3 * i + k];
            same = same && std::fabs(out[3 * i + k] - sent) <= 1e-5f * std::max(1.0f, sent);
          }
          kept += same;
        }
    }
    ASSERT_GT(checked, 1000u);
    if (keep != 0.0) EXPECT_EQ(kept, checked);
    else EXPECT_LT(kept, checked / 2) << "without keep_unexplained the pixels are filtered";
  }
}

// keep_unexplained, split with a specular modulator: where the modulator
// (here specular_albedo) is 0 the pixel has no specular lobe, and its
// specular term is what it was sent (0), not the bright neighbours' light the
// filter brings in across the same surface (times the guarded 1). So those
// pixels come out exactly as in a session whose specular is 0 everywhere
// (the diffuse chain does not see the specular one), and without keep not.
TEST_F(SvgfTest, SplitPixelsWithoutASpecularLobeAddNoFilteredSpecular) {
  const int w = 64, h = 48, n = w * h;
  for (const double keep : {1.0, 0.0}) {
    SCOPED_TRACE(testing::Message() << "keep_unexplained " << keep);
    auto config = svgf_split_config(w, h, Format::F32, Format::F32, {{"keep_unexplained", keep}}, false);
    config.channels.push_back({ChannelId::SpecularAlbedo, Format::F32});
    auto lit = pipelines::create(ctx(), config);
    auto dark = pipelines::create(ctx(), config);
    SvgfSceneGen scene(w, h, 6, 1.37f, -0.61f, 0.45f, 0.8f);
    size_t same = 0, checked = 0;
    for (int t = 0; t < 4; ++t) {
      const SvgfScene s = scene.frame(t);
      std::vector<float> spec = specular_of(s, 31 + t), spec_albedo(3 * n, 0.5f);  // noisy: the filter mixes it
      const std::vector<float> no_spec(3 * n, 0.0f);
      for (int i = 0; i < n; ++i)
        if ((i % w) % 8 < 4)  // columns without a specular lobe: nothing sent there
          for (int k = 0; k < 3; ++k) spec[3 * i + k] = spec_albedo[3 * i + k] = 0.0f;
      auto frame = [&](const std::vector<float>& sp) {
        test::HostFrame f = host_frame(s, w, h, Format::F32, MotionConvention::PixelsToPrevious, 0, false, &sp);
        f.add(ChannelId::SpecularAlbedo, Format::F32, spec_albedo);
        return f;
      };
      const auto a = run(*lit, frame(spec));
      const auto b = run(*dark, frame(no_spec));
      for (int i = 0; i < n; ++i) {
        if ((i % w) % 8 >= 4) continue;
        ++checked;
        same += a[3 * i] == b[3 * i] && a[3 * i + 1] == b[3 * i + 1] && a[3 * i + 2] == b[3 * i + 2];
      }
    }
    ASSERT_GT(checked, 1000u);
    if (keep != 0.0) EXPECT_EQ(same, checked);
    else EXPECT_LT(same, checked / 2) << "without keep_unexplained the filter brings the lobe's light in";
  }
}

// The joint chain filters diffuse and specular in the same variance and
// a-trous passes with separate luminance weights and variances: a different
// specular input leaves every diffuse result (variance, each iteration, the
// histories the passes write) bit for bit as it was and changes the specular
// ones, over frames with history.
TEST_F(SvgfTest, JointChainKeepsTheSignalsApart) {
  const int w = 48, h = 32, iterations = 3;
  const std::vector<pipelines::ParameterValue> params = {{"atrous_iterations", iterations}};
  auto a = pipelines::create(ctx(), svgf_split_config(w, h, Format::F32, Format::F32, params));
  auto b = pipelines::create(ctx(), svgf_split_config(w, h, Format::F32, Format::F32, params));
  auto* ga = dynamic_cast<pipelines::GraphPipeline*>(a.get());
  auto* gb = dynamic_cast<pipelines::GraphPipeline*>(b.get());
  ASSERT_TRUE(ga && gb);
  ga->set_capture(true);
  gb->set_capture(true);
  SvgfSceneGen scene(w, h, 5, 0.8f, 0.5f, 0.3f, 0.9f, 0.003);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 4.0f);
  for (int t = 0; t < 4; ++t) {
    SCOPED_TRACE(testing::Message() << "frame " << t);
    const SvgfScene s = scene.frame(t);
    std::vector<float> specular_a(3 * w * h), specular_b(3 * w * h);
    for (size_t i = 0; i < specular_a.size(); ++i) {
      specular_a[i] = 0.5f * s.radiance[i];
      specular_b[i] = u(rng);
    }
    run(*a, host_frame(s, w, h, Format::F32, MotionConvention::PixelsToPrevious, 0, false, &specular_a));
    run(*b, host_frame(s, w, h, Format::F32, MotionConvention::PixelsToPrevious, 0, false, &specular_b));
    for (const char* buffer : {"svgf_illum_a", "svgf_colour", "svgf_aux"})
      EXPECT_EQ(ga->captured("svgf_variance", buffer), gb->captured("svgf_variance", buffer)) << buffer;
    for (const char* buffer : {"svgf_illum_c", "svgf_spec_colour", "svgf_spec_aux"})
      EXPECT_NE(ga->captured("svgf_variance", buffer), gb->captured("svgf_variance", buffer)) << buffer;
    for (int i = 0; i < iterations; ++i) {
      const std::string pass = "svgf_atrous_" + std::to_string(i);
      // After the first iteration b and e (d and f) alternate: a (c) keeps the harm guard's temporal mean.
      const std::string diffuse = i % 2 == 0 ? "svgf_illum_b" : "svgf_illum_e";
      const std::string specular = i % 2 == 0 ? "svgf_illum_d" : "svgf_illum_f";
      EXPECT_EQ(ga->captured(pass, diffuse), gb->captured(pass, diffuse)) << pass;
      EXPECT_NE(ga->captured(pass, specular), gb->captured(pass, specular)) << pass;
    }
  }
}

TEST_F(SvgfTest, SplitTimingsNameEveryPass) {
  auto pipe = pipelines::create(ctx(), svgf_split_config(32, 32, Format::F32, Format::F32, {{"atrous_iterations", 2}}));
  SvgfSceneGen scene(32, 32, 3, 1, 1, 0, 0.1f);
  const SvgfScene s = scene.frame(0);
  std::vector<pipelines::PassTiming> timings;
  run(*pipe, host_frame(s, 32, 32, Format::F32, MotionConvention::PixelsToPrevious, 0, false, &s.radiance), Format::F32,
      &timings);
  std::vector<std::string> names;
  for (const auto& t : timings) names.push_back(t.name);
  // One joint chain: both signals' variance and a-trous iterations are the same passes.
  EXPECT_EQ(names, (std::vector<std::string>{"upload", "svgf_reproject_diffuse", "svgf_reproject_specular",
                                             "svgf_variance", "svgf_atrous_0", "svgf_atrous_1", "svgf_remodulate",
                                             "svgf_taa", "sample_summary", "download"}));
}

TEST_F(SvgfTest, SplitDeviceBytesAreAsDocumented) {
  for (auto c : {svgf_split_config(64, 48), svgf_split_config(33, 17, Format::F16, Format::F16, {}, true),
                 svgf_split_config(20, 10, Format::F32, Format::F32, {{"atrous_iterations", 0}}),
                 svgf_split_config(21, 11, Format::F32, Format::F32, {{"atrous_iterations", 1}})}) {
    auto p = pipelines::create(ctx(), c);
    EXPECT_EQ(p->device_bytes(), pipelines::estimate_device_bytes(c));
  }
  // fp32: inputs 12+12 (diffuse, specular) +12+12+4+8, history 2 x (16+16+16+4+16: the still mean, its M2, its
  // change test) + 16 (TAA), scratch 9*16 (6 illumination: three per signal, the harm guard keeping the first, the
  // shared guide, 2 temporal: the joint a-trous passes read both signals'), output 12 = 368 B/px, + the constants block.
  EXPECT_EQ(pipelines::estimate_device_bytes(svgf_split_config(64, 48)), 64u * 48 * 368 + pipelines::GraphSpec::kConstantBytes +
            pipelines::kSampleSummaryBytes);
  // fp16 planes and output: the same 368 B/px (planes are fp32 on the device, widened at upload).
  EXPECT_EQ(pipelines::estimate_device_bytes(svgf_split_config(64, 48, Format::F16, Format::F16)),
            64u * 48 * 368 + pipelines::GraphSpec::kConstantBytes +
            pipelines::kSampleSummaryBytes);
}

TEST(SvgfValidate, RadianceOrDiffuseAndSpecular) {
  using pipelines::ConfigProblem;
  EXPECT_FALSE(pipelines::validate(svgf_split_config(16, 16)).has_value());
  EXPECT_FALSE(pipelines::validate(svgf_split_config(16, 16, Format::F16, Format::F16, {}, true)).has_value());
  auto expect = [](pipelines::SessionConfig c, ConfigProblem code, const std::string& field, const std::string& part) {
    const auto err = pipelines::validate(c);
    ASSERT_TRUE(err.has_value());
    EXPECT_EQ(err->problem, code);
    EXPECT_EQ(err->field, field);
    EXPECT_NE(err->message.find(part), std::string::npos) << err->message;
  };
  {  // radiance + diffuse + specular: the later of the clashing declarations is named
    auto c = svgf_split_config(16, 16);
    c.channels.push_back({ChannelId::Radiance, Format::F32});
    expect(c, ConfigProblem::InvalidChannel, "channels[6].id", "either radiance or diffuse + specular");
  }
  {  // radiance + specular
    auto c = svgf_config(16, 16);
    c.channels.push_back({ChannelId::Specular, Format::F32});
    expect(c, ConfigProblem::InvalidChannel, "channels[5].id", "specular");
  }
  {  // radiance + diffuse
    auto c = svgf_config(16, 16);
    c.channels.push_back({ChannelId::Diffuse, Format::F32});
    expect(c, ConfigProblem::InvalidChannel, "channels[5].id", "diffuse");
  }
  {  // diffuse alone
    auto c = svgf_split_config(16, 16);
    c.channels.erase(c.channels.begin() + 1);
    expect(c, ConfigProblem::MissingChannel, "channels", "specular");
  }
  {  // specular alone
    auto c = svgf_split_config(16, 16);
    c.channels.erase(c.channels.begin());
    expect(c, ConfigProblem::MissingChannel, "channels", "diffuse");
  }
  {  // no lighting channel at all
    auto c = svgf_config(16, 16);
    c.channels.erase(c.channels.begin());
    expect(c, ConfigProblem::MissingChannel, "channels", "radiance, or diffuse and specular");
  }
  // Lighting forms (docs/protocol.md §7.4): one form per signal, specular_lighting needs specular_albedo.
  auto lighting = [] {
    auto c = svgf_split_config(16, 16);
    c.channels[0].id = ChannelId::DiffuseLighting;
    c.channels[1].id = ChannelId::SpecularLighting;
    c.channels.push_back({ChannelId::SpecularAlbedo, Format::F32});
    return c;
  };
  EXPECT_FALSE(pipelines::validate(lighting()).has_value());
  {  // both forms of diffuse
    auto c = lighting();
    c.channels.push_back({ChannelId::Diffuse, Format::F32});
    expect(c, ConfigProblem::InvalidChannel, "channels[7].id", "diffuse or diffuse_lighting");
  }
  {  // specular_lighting without its modulator
    auto c = lighting();
    c.channels.pop_back();
    expect(c, ConfigProblem::MissingChannel, "channels", "specular_albedo");
  }
  {  // specular_albedo with radiance: nothing to modulate
    auto c = svgf_config(16, 16);
    c.channels.push_back({ChannelId::SpecularAlbedo, Format::F32});
    expect(c, ConfigProblem::InvalidChannel, "channels[5].id", "specular_albedo");
  }
  {  // svgf-fb computes its own specular modulator: specular_lighting is refused
    auto c = lighting();
    c.pipeline = "svgf-fb";
    c.channels.pop_back();
    c.channels.push_back({ChannelId::SpecularF0, Format::F32});
    c.channels.push_back({ChannelId::Roughness, Format::F32});
    const auto err = pipelines::validate(c);
    ASSERT_TRUE(err.has_value());
    EXPECT_EQ(err->problem, ConfigProblem::InvalidChannel);
    EXPECT_NE(err->message.find("does not use channel specular_lighting"), std::string::npos) << err->message;
  }
  // Other pipelines keep their rules: passthrough takes diffuse + specular alongside radiance, and still
  // requires radiance.
  EXPECT_FALSE(pipelines::validate(test::make_config("passthrough", 16, 16,
                                                     {{ChannelId::Radiance, Format::F32},
                                                      {ChannelId::Diffuse, Format::F32},
                                                      {ChannelId::Specular, Format::F32}}))
                   .has_value());
  expect(test::make_config("passthrough", 16, 16, {{ChannelId::Diffuse, Format::F32}, {ChannelId::Specular, Format::F32}}),
         ConfigProblem::MissingChannel, "channels", "radiance");
}


// ---- The final TAA blend (taa_alpha > 0, pass svgf_taa) ----

uint64_t round_up4_bytes(uint64_t b) { return (b + 3) / 4 * 4; }

std::vector<std::string> pass_names(pipelines::Pipeline& p, const test::HostFrame& f) {
  std::vector<pipelines::PassTiming> timings;
  std::vector<uint8_t> bytes;
  test::process(p, f.view(), true, bytes, timings);
  std::vector<std::string> names;
  for (const auto& t : timings) names.push_back(t.name);
  return names;
}

// taa_alpha = taa_static_alpha = 0 is the graph without TAA; either > 0
// (taa_static_alpha's default 0.5) adds svgf_taa after svgf_remodulate and
// 12 B/px of persistent history, nothing else. Where every pixel moves by
// more than 0.05 px the static blend alone changes no bit of the output.
TEST_F(SvgfTest, TaaOffIsTheGraphWithoutTaa) {
  const int w = 64, h = 40;
  SvgfSceneGen scene(w, h, 77, 1.3f, 0.4f, 0.3f, 0.5f);
  std::vector<test::HostFrame> frames;  // the scene's noise differs per call: make each frame once
  for (int t = 0; t < 5; ++t)
    frames.push_back(host_frame(scene.frame(t), w, h, Format::F32, MotionConvention::PixelsToPrevious, 0, true));
  auto frame = [&](int t) -> const test::HostFrame& { return frames[t]; };
  auto base = pipelines::create(ctx(), svgf_config(w, h, Format::F32, Format::F32, {}, true));
  auto off = pipelines::create(
      ctx(), svgf_config(w, h, Format::F32, Format::F32, {{"taa_alpha", 0}, {"taa_static_alpha", 0}}, true));
  auto on = pipelines::create(ctx(), svgf_config(w, h, Format::F32, Format::F32, {{"taa_alpha", 0.1}}, true));
  const std::vector<std::string> without = {"upload",        "svgf_reproject", "svgf_variance", "svgf_atrous_0",
                                            "svgf_atrous_1", "svgf_atrous_2",  "svgf_atrous_3", "svgf_remodulate",
                                            "sample_summary", "download"};
  EXPECT_EQ(pass_names(*off, frame(0)), without);
  std::vector<std::string> with = without;
  with.insert(with.end() - 2, "svgf_taa");
  EXPECT_EQ(pass_names(*on, frame(0)), with);
  EXPECT_EQ(pass_names(*base, frame(0)), with);
  EXPECT_EQ(on->device_bytes(), base->device_bytes());
  EXPECT_EQ(base->device_bytes(), off->device_bytes() + round_up4_bytes(uint64_t{w} * h * 16));
  for (int t = 1; t < 5; ++t) EXPECT_EQ(run(*off, frame(t)), run(*base, frame(t))) << "frame " << t;
}

TEST_F(SvgfTest, TaaDeviceBytesAreAsDocumented) {
  for (auto c : {svgf_config(64, 48, Format::F32, Format::F32, {{"taa_alpha", 0.1}}),
                 svgf_config(33, 17, Format::F16, Format::F16, {{"taa_alpha", 1}}, true),
                 svgf_split_config(20, 10, Format::F32, Format::F32, {{"taa_alpha", 0.5}, {"atrous_iterations", 0}})}) {
    auto p = pipelines::create(ctx(), c);
    EXPECT_EQ(p->device_bytes(), pipelines::estimate_device_bytes(c));
  }
  // 208 B/px without TAA + 16 B/px of TAA history.
  EXPECT_EQ(pipelines::estimate_device_bytes(svgf_config(64, 48, Format::F32, Format::F32, {{"taa_alpha", 0.1}})),
            64u * 48 * 224 + pipelines::GraphSpec::kConstantBytes +
            pipelines::kSampleSummaryBytes);
  EXPECT_EQ(pipelines::estimate_device_bytes(svgf_config(64, 48, Format::F16, Format::F16, {{"taa_alpha", 0.1}})),
            64u * 48 * 224 + pipelines::GraphSpec::kConstantBytes +
            pipelines::kSampleSummaryBytes);
}

// Static camera, a step edge whose sides swap at frame 4: at every pixel the
// blended output stays inside the 3x3 min/max of the current colour (the same
// session without TAA), so the old edge leaves no ghost beyond the clamp;
// away from the edge the output is the current colour right after the swap.
TEST_F(SvgfTest, TaaStaysInsideTheNeighbourhoodOfAStepEdge) {
  const int w = 48, h = 32, n = w * h;
  Flat scene(w, h);
  auto radiance = [&](int t) {
    std::vector<float> r(3 * n);
    for (int i = 0; i < n; ++i) {
      const bool left = (i % w) < w / 2;
      const float v = (left == (t < 4)) ? 8.0f : 0.2f;
      for (int k = 0; k < 3; ++k) r[3 * i + k] = v * (1.0f + 0.05f * k) * (1.0f + 0.02f * ((i * 7 + t * 3) % 5));
    }
    return r;
  };
  auto on = pipelines::create(ctx(), svgf_config(w, h, Format::F32, Format::F32, {{"taa_alpha", 0.1}}));
  auto off = pipelines::create(ctx(), svgf_config(w, h, Format::F32, Format::F32, {{"taa_static_alpha", 0}}));
  test::SvgfParams params;
  params.taa_alpha = 0.1;
  test::SvgfReference ref(w, h, params);
  for (int t = 0; t < 8; ++t) {
    SCOPED_TRACE(testing::Message() << "frame " << t);
    const test::HostFrame f = scene.frame(radiance(t));
    const auto got = run(*on, f);
    const auto cur = run(*off, f);
    const auto want = ref.step(reference_frame(f, w, h, false));
    EXPECT_LE(test::relative_rms(got, want), 1e-3);
    size_t outside = 0, ghost = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int k = 0; k < 3; ++k) {
          float lo = INFINITY, hi = -INFINITY;
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const int qx = x + dx, qy = y + dy;
              if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
              lo = std::min(lo, cur[3 * (qy * w + qx) + k]);
              hi = std::max(hi, cur[3 * (qy * w + qx) + k]);
            }
          const float g = got[3 * (y * w + x) + k], tol = 1e-6f * std::max(1.0f, hi);
          if (g < lo - tol || g > hi + tol) ++outside;
          if (t == 4 && std::abs(x - w / 2) > 6 && std::fabs(g - cur[3 * (y * w + x) + k]) > 0.02f * hi) ++ghost;
        }
    EXPECT_EQ(outside, 0u) << "values outside the 3x3 min/max of the current frame";
    EXPECT_EQ(ghost, 0u) << "the swapped edge left a ghost away from it";
  }
}

// After a reset the TAA output is exactly what a fresh session makes of the
// frame, which is the output without TAA.
TEST_F(SvgfTest, TaaResetLeavesNoGhost) {
  const int w = 40, h = 30, n = w * h;
  Flat scene(w, h);
  std::vector<float> a(3 * n, 5.0f), b(3 * n);
  for (int i = 0; i < 3 * n; ++i) b[i] = 0.01f * (i % 17);
  const std::vector<pipelines::ParameterValue> taa = {{"taa_alpha", 0.1}};
  auto pipe = pipelines::create(ctx(), svgf_config(w, h, Format::F32, Format::F32, taa));
  for (int t = 0; t < 10; ++t) run(*pipe, scene.frame(a));
  auto fresh = pipelines::create(ctx(), svgf_config(w, h, Format::F32, Format::F32, taa));
  auto plain = pipelines::create(ctx(), svgf_config(w, h));
  const auto want = run(*fresh, scene.frame(b));
  EXPECT_EQ(want, run(*plain, scene.frame(b)));
  EXPECT_EQ(run(*pipe, scene.frame(b, protocol::kFrameReset)), want);
  EXPECT_EQ(run(*pipe, scene.frame(b)), run(*fresh, scene.frame(b)));
}


}  // namespace
}  // namespace dn
