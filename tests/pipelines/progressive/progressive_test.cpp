// progressive (paper 004) on the device: the properties IMPLEMENTATION-NOTES
// B.4 names, each against an expectation computed here: the accumulation is a
// running mean, then an exponential average; the moments' steady-state
// variance carries the exponential average's bias; constant input comes back;
// a noise-free step edge stays sharp (and blurs without the luminance
// weight); below one sample per pixel, unsampled pixels keep their state bit
// for bit, pixels without data never reach a neighbour, and a stratified
// schedule leaves no hole after 1/f frames. The pass-by-pass comparison with
// the CPU reference is progressive_reference_test.cpp.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "gpu_test_env.hpp"
#include "pipelines/graph.hpp"
#include "svgf_inputs.hpp"

namespace dn {
namespace {

using namespace svgf_inputs;

class ProgressiveTest : public test::GpuTest {};

// A still, flat, fronto-parallel surface: albedo, normal, depth and motion
// constant, so every tap passes the geometry tests and only the signal varies.
struct FlatFrames {
  int w, h;
  float albedo = 0.5f;
  test::HostFrame frame(const std::vector<float>& radiance, const std::vector<float>* sample_count = nullptr) const {
    const size_t n = static_cast<size_t>(w) * h;
    test::HostFrame f;
    f.info.motion = MotionConvention::PixelsToPrevious;
    f.add(ChannelId::Radiance, Format::F32, radiance);
    f.add(ChannelId::Albedo, Format::F32, std::vector<float>(3 * n, albedo));
    std::vector<float> normal(3 * n, 0.0f);
    for (size_t i = 0; i < n; ++i) normal[3 * i + 2] = 1.0f;
    f.add(ChannelId::Normal, Format::F32, normal);
    f.add(ChannelId::Depth, Format::F32, std::vector<float>(n, 2.0f));
    f.add(ChannelId::Motion, Format::F32, std::vector<float>(2 * n, 0.0f));
    if (sample_count) f.add(ChannelId::SampleCount, Format::F32, *sample_count);
    return f;
  }
};

pipelines::SessionConfig progressive_config(int w, int h, std::vector<pipelines::ParameterValue> params = {},
                                            bool masked = false) {
  std::vector<pipelines::InputChannel> channels = {{ChannelId::Radiance, Format::F32},
                                                 {ChannelId::Albedo, Format::F32},
                                                 {ChannelId::Normal, Format::F32},
                                                 {ChannelId::Depth, Format::F32},
                                                 {ChannelId::Motion, Format::F32}};
  if (masked) channels.push_back({ChannelId::SampleCount, Format::F32});
  return test::make_config("progressive", w, h, channels, Format::F32, std::move(params));
}

// The sample_count of pixel i (image width w) at frame t of a 1/4-spp
// schedule that samples every pixel once in every 4 frames.
float quarter_spp_count(int i, int w, int t) { return ((i % w) + 2 * (i / w) + t) % 4 == 0 ? 1.0f : 0.0f; }

// Temporal accumulation alone: no a-trous iteration, no final blend.
const std::vector<pipelines::ParameterValue> kAccumulationOnly = {
    {"atrous_iterations", 0}, {"taa_alpha", 0}, {"taa_static_alpha", 0}};

// Grey radiance (luminance = the value: Rec. 709 weights sum to 1).
std::vector<float> grey(const std::vector<double>& v) {
  std::vector<float> out(3 * v.size());
  for (size_t i = 0; i < v.size(); ++i) out[3 * i] = out[3 * i + 1] = out[3 * i + 2] = static_cast<float>(v[i]);
  return out;
}

// A noise-free step in luminance, 0.2 left of the middle column and 1 right of it.
std::vector<double> luminance_step(int w, int h) {
  std::vector<double> step(static_cast<size_t>(w) * h);
  for (size_t i = 0; i < step.size(); ++i) step[i] = static_cast<int>(i % w) < w / 2 ? 0.2 : 1.0;
  return step;
}

// Paper 004 §4.2: r = max(a, 1/age), a = 0.1: for the first 1/a = 10 frames
// the output is the arithmetic mean of the frames so far, then each frame
// moves it by 0.1 toward the new one.
TEST_F(ProgressiveTest, AccumulationIsTheRunningMeanThenAnExponentialAverage) {
  const int w = 32, h = 16, n = w * h;
  FlatFrames scene{w, h};
  auto pipe = pipelines::create(ctx(), progressive_config(w, h, kAccumulationOnly));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> value(0.0, 2.0);
  std::vector<double> sum(n, 0.0), ema(n, 0.0);
  for (int t = 0; t < 16; ++t) {
    std::vector<double> x(n);
    for (double& v : x) v = value(rng);
    const auto out = run(*pipe, scene.frame(grey(x)));
    for (int i = 0; i < n; ++i) {
      sum[i] += x[i];
      ema[i] = t == 0 ? x[i] : ema[i] + std::max(0.1, 1.0 / (t + 1)) * (x[i] - ema[i]);
      // The exponential average and the mean agree for t < 10; after that only the former holds.
      const double want = t < 10 ? sum[i] / (t + 1) : ema[i];
      ASSERT_NEAR(out[3 * i], want, 2e-5 * std::max(want, 1.0)) << "frame " << t << " pixel " << i;
    }
    if (t >= 12) {  // and it is no longer the running mean: the test can tell them apart
      double apart = 0.0;
      for (int i = 0; i < n; ++i) apart = std::max(apart, std::fabs(ema[i] - sum[i] / (t + 1)));
      EXPECT_GT(apart, 0.01);
    }
  }
}

// With the exponential average of weight a, the moments' estimate m2 - m1^2
// of i.i.d. samples of variance s^2 settles at s^2 * 2 (1 - a) / (2 - a),
// 0.947 s^2 for a = 0.1 (IMPLEMENTATION-NOTES B.3): not s^2.
TEST_F(ProgressiveTest, SteadyStateMomentVarianceIsTheExponentialAveragesBiasedOne) {
  const int w = 96, h = 64, n = w * h;
  const double sigma = 0.25, a = 0.1;
  FlatFrames scene{w, h};
  auto pipe = pipelines::create(ctx(), progressive_config(w, h, kAccumulationOnly));
  auto* graph = dynamic_cast<pipelines::GraphPipeline*>(pipe.get());
  ASSERT_NE(graph, nullptr);
  graph->set_capture(true);
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(1.0, sigma);
  double sum = 0.0;
  int count = 0;
  for (int t = 0; t < 100; ++t) {
    std::vector<double> x(n);
    for (double& v : x) v = noise(rng);
    run(*pipe, scene.frame(grey(x)));
    if (t < 40) continue;  // the start-up (0.9^30 of it left) is gone
    const auto temporal = test::decode_output(graph->captured("svgf_reproject", "svgf_temporal"), Format::F32);
    for (int i = 0; i < n; ++i) {
      const double m1 = temporal[4 * i], m2 = temporal[4 * i + 1];
      sum += (m2 - m1 * m1) * scene.albedo * scene.albedo;  // moments of the demodulated luminance, x / albedo
      ++count;
    }
  }
  const double measured = sum / count, expected = sigma * sigma * 2.0 * (1.0 - a) / (2.0 - a);
  EXPECT_NEAR(measured / expected, 1.0, 0.02) << "measured " << measured << ", expected " << expected;
  EXPECT_LT(measured, 0.98 * sigma * sigma);  // the bias is there
}

TEST_F(ProgressiveTest, ConstantInputIsReturnedExactly) {
  const int w = 48, h = 32, n = w * h;
  FlatFrames scene{w, h};
  std::vector<float> radiance(3 * n);
  for (int i = 0; i < n; ++i) {
    radiance[3 * i] = 0.25f;
    radiance[3 * i + 1] = 1.5f;
    radiance[3 * i + 2] = 3000.0f;
  }
  auto pipe = pipelines::create(ctx(), progressive_config(w, h));
  for (int t = 0; t < 8; ++t) {
    const auto out = run(*pipe, scene.frame(radiance));
    for (int i = 0; i < 3 * n; ++i)
      ASSERT_NEAR(out[i], radiance[i], 1e-5 * radiance[i]) << "frame " << t << " element " << i;
  }
}

// Paper 004's regime (sample_count, here 1 everywhere). A noise-free step
// in luminance on one surface: once the pixels are old
// enough for the luminance weight (luminance_min_age), their variance is 0
// and the weight stops every tap across the step. The first frames, younger
// than that, are filtered without it, and the history takes that blur (it is
// the first iteration's output), which the exponential average then lets go
// at 0.9 per frame (0.09 of the step left after 8 frames, 2e-4 after 64).
// With the weight never on, the filter keeps blurring it. Without the final
// blend, which would keep the young frames' blur longer.
TEST_F(ProgressiveTest, StepEdgeWithoutVarianceIsKeptAndBlursWithoutTheLuminanceWeight) {
  const int w = 48, h = 16, n = w * h;
  FlatFrames scene{w, h};
  const std::vector<double> step = luminance_step(w, h);
  const std::vector<float> every_pixel(n, 1.0f);  // sample_count: paper 004's regime at 1 spp
  auto edge_error = [&](std::vector<pipelines::ParameterValue> params) {
    params.push_back({"taa_alpha", 0});
    params.push_back({"taa_static_alpha", 0});
    params.push_back({"harm_guard", 0});  // the filter's own behaviour: the guard would keep the noise-free step
    auto pipe = pipelines::create(ctx(), progressive_config(w, h, params, /*masked=*/true));
    std::vector<float> out;
    for (int t = 0; t < 64; ++t) out = run(*pipe, scene.frame(grey(step), &every_pixel));
    double worst = 0.0;
    for (int i = 0; i < n; ++i) worst = std::max(worst, std::fabs(out[3 * i] - step[i]));
    return worst;
  };
  EXPECT_LT(edge_error({}), 1e-3);
  EXPECT_GT(edge_error({{"luminance_min_age", 1024}}), 0.05);
}

// Paper 004 5's buffer one step behind (display_lag, with sample_count): on the same noise-free
// step, still, at 1 spp, the young frames (0-2) show the blur of the filter
// without a luminance weight, and at frame 3 every pixel comes of age and the
// filter returns the step. The final blend (fixed ratio 0.1) must then move
// the display toward it continuously: at frame 3 exactly 0.1 of the way, with
// no clamp, and no later frame more than 0.3 of the distance frame 2 left;
// the clamp comes back as the state decays, so by frame 64 the step is sharp.
// Clamped throughout (display_lag 0), the pixels beyond the step's 3x3 box
// snap to it at frame 3: the visible switch this buffer hides.
TEST_F(ProgressiveTest, TheDisplayFollowsTheHistorySwitchContinuously) {
  const int w = 48, h = 16, n = w * h;
  FlatFrames scene{w, h};
  const std::vector<double> step = luminance_step(w, h);
  const std::vector<float> every_pixel(n, 1.0f);  // sample_count: paper 004's regime at 1 spp
  auto frames = [&](std::vector<pipelines::ParameterValue> params) {
    params.push_back({"harm_guard", 0});  // the filter's own blur: the guard would keep the noise-free step
    auto pipe = pipelines::create(ctx(), progressive_config(w, h, std::move(params), /*masked=*/true));
    std::vector<std::vector<float>> out;
    for (int t = 0; t < 64; ++t) out.push_back(run(*pipe, scene.frame(grey(step), &every_pixel)));
    return out;
  };
  const auto lagged = frames({});
  double blur = 0.0;  // the young frames' largest distance from the step
  for (int i = 0; i < n; ++i) blur = std::max(blur, std::fabs(double(lagged[2][3 * i]) - step[i]));
  ASSERT_GT(blur, 0.05) << "the young frames must blur the step for the switch to show";
  for (int i = 0; i < n; ++i) {
    const double want = 0.9 * lagged[2][3 * i] + 0.1 * step[i];
    ASSERT_NEAR(lagged[3][3 * i], want, 1e-5) << "pixel " << i % w << "," << i / w;
  }
  double largest_change = 0.0;
  for (int t = 3; t < 64; ++t)
    for (int i = 0; i < n; ++i)
      largest_change = std::max(largest_change, double(std::fabs(lagged[t][3 * i] - lagged[t - 1][3 * i])));
  EXPECT_LE(largest_change, 0.3 * blur);
  double left = 0.0;
  for (int i = 0; i < n; ++i) left = std::max(left, std::fabs(double(lagged[63][3 * i]) - step[i]));
  EXPECT_LT(left, 1e-3);

  const auto clamped = frames({{"display_lag", 0}});
  double snap = 0.0;
  for (int i = 0; i < n; ++i) snap = std::max(snap, double(std::fabs(clamped[3][3 * i] - clamped[2][3 * i])));
  EXPECT_GT(snap, 0.6 * blur);
  std::printf("[ info     ] young blur %.4f; largest change per frame from frame 3: %.4f lagged, %.4f clamped\n", blur,
              largest_change, snap);
}

// Below one sample per pixel: sample_count 0 leaves a pixel's history (colour,
// length, moments, depth, normal) exactly as it was, while sampled pixels move.
TEST_F(ProgressiveTest, UnsampledPixelsKeepTheirStateBitForBit) {
  const int w = 40, h = 24, n = w * h;
  FlatFrames scene{w, h};
  auto pipe = pipelines::create(ctx(), progressive_config(w, h, {}, true));
  auto* graph = dynamic_cast<pipelines::GraphPipeline*>(pipe.get());
  ASSERT_NE(graph, nullptr);
  graph->set_capture(true);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> value(0.0, 2.0);
  std::vector<uint8_t> colour_before, aux_before;
  for (int t = 0; t < 10; ++t) {
    std::vector<float> count(n);
    std::vector<double> x(n, 0.0);
    for (int i = 0; i < n; ++i) {
      count[i] = quarter_spp_count(i, w, t);
      if (count[i] > 0.0f) x[i] = value(rng);
    }
    run(*pipe, scene.frame(grey(x), &count));
    // The history after the frame: colour (rewritten by the feedback
    // iteration), aux (moments, depth, normal: by the variance pass).
    const auto colour = graph->captured("svgf_atrous_0", "svgf_colour");
    const auto aux = graph->captured("svgf_variance", "svgf_aux");
    ASSERT_EQ(colour.size(), size_t(16) * n);
    if (t >= 4) {  // every pixel has data
      int sampled_changed = 0;
      for (int i = 0; i < n; ++i) {
        const bool same = std::memcmp(&colour[16 * i], &colour_before[16 * i], 16) == 0 &&
                          std::memcmp(&aux[16 * i], &aux_before[16 * i], 16) == 0;
        if (count[i] == 0.0f)
          ASSERT_TRUE(same) << "frame " << t << ": unsampled pixel " << i << "'s history changed";
        else
          sampled_changed += same ? 0 : 1;
      }
      EXPECT_EQ(sampled_changed, n / 4) << "frame " << t;
    }
    colour_before = colour;
    aux_before = aux;
  }
}

// Frame 0 at 1/4 spp: three pixels in four have no data (no sample, no
// history). Whatever their radiance plane holds, none of it reaches the
// output, and their empty value (0) does not darken a neighbour: a constant
// sampled signal comes back exactly everywhere. After 4 frames of the
// stratified schedule every pixel has data (history length >= 1).
TEST_F(ProgressiveTest, PixelsWithoutDataNeverReachANeighbourAndFourFramesLeaveNoHole) {
  const int w = 40, h = 24, n = w * h;
  FlatFrames scene{w, h};
  auto pipe = pipelines::create(ctx(), progressive_config(w, h, {}, true));
  auto* graph = dynamic_cast<pipelines::GraphPipeline*>(pipe.get());
  ASSERT_NE(graph, nullptr);
  graph->set_capture(true);
  const float garbage[] = {1e30f, -5.0f, NAN, INFINITY, 123.0f};
  for (int t = 0; t < 4; ++t) {
    std::vector<float> count(n), radiance(3 * n);
    int without_data = 0;
    for (int i = 0; i < n; ++i) {
      count[i] = quarter_spp_count(i, w, t);
      for (int c = 0; c < 3; ++c) radiance[3 * i + c] = count[i] > 0.0f ? 0.8f : garbage[(i + c) % 5];
    }
    const auto out = run(*pipe, scene.frame(radiance, &count));
    for (int i = 0; i < 3 * n; ++i) ASSERT_NEAR(out[i], 0.8f, 1e-5f) << "frame " << t << " element " << i;
    const auto temporal = test::decode_output(graph->captured("svgf_reproject", "svgf_temporal"), Format::F32);
    for (int i = 0; i < n; ++i) without_data += temporal[4 * i + 2] == 0.0f ? 1 : 0;
    EXPECT_EQ(without_data, t < 3 ? n - (t + 1) * n / 4 : 0) << "frame " << t;
  }
}

// Below one sample per pixel, what no history and no filter tap covers is
// filled for the display from the nearest ring of pixels with a value
// (ring_fill.glsl): unsampled background from sampled background, a surface
// pixel the a-trous taps did not reach (one iteration here, so only the 3x3
// around each 1/16 sample has data) from the nearest surface pixels with data.
TEST_F(ProgressiveTest, WhatNothingCoversIsFilledFromTheNearestPixelsWithAValue) {
  const int w = 40, h = 24, n = w * h;
  FlatFrames scene{w, h};
  auto pipe = pipelines::create(ctx(), progressive_config(w, h, {{"atrous_iterations", 1}}, true));
  std::vector<float> count(n), radiance(3 * n, 0.0f), depth(n, 2.0f);
  for (int i = 0; i < n; ++i) {
    const int x = i % w, y = i / w;
    count[i] = x % 4 == 1 && y % 4 == 2 ? 1.0f : 0.0f;  // 1/16
    if (x < 12) depth[i] = 0.0f;                        // background on the left
    if (count[i] > 0.0f)
      for (int c = 0; c < 3; ++c) radiance[3 * i + c] = x < 12 ? 0.3f : 0.8f;
  }
  test::HostFrame f = scene.frame(radiance, &count);
  for (auto& plane : f.planes)
    if (plane.id == ChannelId::Depth) plane.bytes = test::encode_plane(depth, Format::F32);
  const auto out = run(*pipe, f);
  int reached_by_the_fill = 0;
  for (int i = 0; i < n; ++i) {
    const int x = i % w, y = i / w;
    // Background passes through unfiltered (albedo 0.5 divides and multiplies back).
    const float want = x < 12 ? 0.3f : 0.8f;
    // A surface pixel right of the edge whose nearest ring holds only background would differ; none here.
    ASSERT_NEAR(out[3 * i], want, 1e-5f) << "pixel " << x << ", " << y;
    const bool next_to_sample = std::abs(x % 4 - 1) <= 1 && std::abs(y % 4 - 2) <= 1;
    reached_by_the_fill += x >= 12 && !next_to_sample ? 1 : 0;
  }
  EXPECT_GT(reached_by_the_fill, 100);
}

// The standard-deviation luminance weight (the default) is scale-equivariant:
// radiance times k gives output times k, on a noisy masked sequence too.
TEST_F(ProgressiveTest, OutputScalesWithInput) {
  const int w = 40, h = 24, n = w * h;
  FlatFrames scene{w, h};
  std::vector<std::vector<float>> frames, counts;
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> value(0.0, 2.0);
  for (int t = 0; t < 6; ++t) {
    std::vector<float> count(n), radiance(3 * n, 0.0f);
    for (int i = 0; i < n; ++i) {
      count[i] = ((i % w) + 2 * (i / w) + t) % 2 == 0 ? 1.0f : 0.0f;
      if (count[i] > 0.0f)
        for (int c = 0; c < 3; ++c) radiance[3 * i + c] = static_cast<float>(value(rng) * (1 + c));
    }
    frames.push_back(radiance);
    counts.push_back(count);
  }
  auto sequence = [&](float k) {
    auto pipe = pipelines::create(ctx(), progressive_config(w, h, {}, true));
    std::vector<float> out;
    for (int t = 0; t < 6; ++t) {
      std::vector<float> scaled = frames[t];
      for (float& v : scaled) v *= k;
      out = run(*pipe, scene.frame(scaled, &counts[t]));
    }
    return out;
  };
  const auto base = sequence(1.0f);
  for (float k : {1e-3f, 1e3f}) {
    const auto scaled = sequence(k);
    for (int i = 0; i < 3 * n; ++i) ASSERT_NEAR(scaled[i] / k, base[i], 1e-4 * std::max(base[i], 1e-3f)) << k;
  }
}

// Hard cases on every guide and the mask: NaN, infinite, huge, negative and
// zero values never make the output (or a later frame's) non-finite.
// With the G-buffer complete and sparse (then the bad guides of unsampled
// pixels go through the pyramid and the bad ones of sampled pixels seed it).
TEST_F(ProgressiveTest, BadInputsNeverReachTheOutput) {
  for (double sparse : {0.0, 1.0}) {
    SCOPED_TRACE(sparse ? "sparse G-buffer" : "complete G-buffer");
    const int w = 40, h = 24, n = w * h;
    auto pipe = pipelines::create(ctx(), progressive_config(w, h, {{"sparse_gbuffer", sparse}}, true));
    const float bad[] = {NAN, INFINITY, -INFINITY, 1e30f, -1.0f, 0.0f, 1e-40f};
    std::mt19937 rng(21);
    std::uniform_real_distribution<float> value(0.0f, 2.0f);
    for (int t = 0; t < 6; ++t) {
      std::vector<float> radiance(3 * n), albedo(3 * n), normal(3 * n, 0.0f), depth(n), motion(2 * n), count(n);
      for (int i = 0; i < n; ++i) {
        const bool hit = (i * 7 + t) % 5 == 0;
        const float b = bad[(i + t) % 7];
        for (int c = 0; c < 3; ++c) {
          radiance[3 * i + c] = hit && c == 0 ? b : value(rng);
          albedo[3 * i + c] = hit && c == 1 ? b : 0.5f;
        }
        normal[3 * i + 2] = hit && i % 3 == 0 ? b : 1.0f;
        depth[i] = hit && i % 3 == 1 ? b : 2.0f;
        motion[2 * i] = hit && i % 3 == 2 ? b : 0.0f;
        motion[2 * i + 1] = 0.0f;
        count[i] = hit && i % 2 == 0 ? b : float((i + t) % 2);
      }
      test::HostFrame f;
      f.info.motion = MotionConvention::PixelsToPrevious;
      f.add(ChannelId::Radiance, Format::F32, radiance);
      f.add(ChannelId::Albedo, Format::F32, albedo);
      f.add(ChannelId::Normal, Format::F32, normal);
      f.add(ChannelId::Depth, Format::F32, depth);
      f.add(ChannelId::Motion, Format::F32, motion);
      f.add(ChannelId::SampleCount, Format::F32, count);
      const auto out = run(*pipe, f);
      for (int i = 0; i < 3 * n; ++i) ASSERT_TRUE(std::isfinite(out[i])) << "frame " << t << " element " << i;
    }
  }
}

// The history source (paper 004 §5, P7): a pixel's history is its unfiltered
// accumulation until it is old enough for the luminance weight, then the
// first iteration's output at each of its samples, never at a frame without
// one. On a still, noise-free scene at 1/4 spp the output's image variance
// (IMPLEMENTATION-NOTES B.4 6) then stops falling at the scene's own: the
// young frames' blur (filtered without a luminance weight) is not kept, and
// what the feedback still blurs (taps of nearly equal luminance) settles
// where the exponential average's pull on each sample balances it. Without
// the final blend, which lets the displayed young frames' blur go at 0.9 per
// frame.
TEST_F(ProgressiveTest, StillSceneStopsBlurringBelowOneSamplePerPixel) {
  const int w = 48, h = 32, n = w * h;
  FlatFrames scene{w, h};
  std::vector<double> truth(n);
  for (int i = 0; i < n; ++i) {
    const int x = i % w, y = i / w;
    truth[i] = 0.5 + 0.4 * std::sin(x / 2.0) * std::cos(y / 3.0) + (x > w / 2 ? 0.5 : 0.0);
  }
  auto image_variance = [&](auto value) {
    double s = 0.0, s2 = 0.0;
    for (int i = 0; i < n; ++i) {
      s += value(i);
      s2 += value(i) * value(i);
    }
    return s2 / n - (s / n) * (s / n);
  };
  const double truth_variance = image_variance([&](int i) { return truth[i]; });
  auto pipe = pipelines::create(ctx(), progressive_config(w, h, {{"taa_alpha", 0}, {"taa_static_alpha", 0}}, true));
  std::vector<double> variance_at;  // after frames 60, 120, 180, 240
  double worst = 0.0;
  for (int t = 0; t < 240; ++t) {
    std::vector<float> count(n);
    std::vector<double> x(n, 0.0);
    for (int i = 0; i < n; ++i) {
      count[i] = quarter_spp_count(i, w, t);
      if (count[i] > 0.0f) x[i] = truth[i];
    }
    const auto out = run(*pipe, scene.frame(grey(x), &count));
    if (t % 60 == 59) variance_at.push_back(image_variance([&](int i) { return double(out[3 * i]); }));
    if (t == 239)
      for (int i = 0; i < n; ++i) worst = std::max(worst, std::fabs(out[3 * i] - truth[i]));
  }
  for (size_t k = 0; k < variance_at.size(); ++k)
    EXPECT_GT(variance_at[k], 0.995 * truth_variance) << "after frame " << 60 * (k + 1);
  EXPECT_GT(variance_at[3], 0.999 * variance_at[2]);  // no longer falling
  EXPECT_LT(worst, 0.01);  // "blurred to constant" would be off by up to 0.9
}

// CPU reference of gbuffer_fill's pull-push pyramid (docs/pipelines.md,
// progressive, "Sparse G-buffer"), in double precision: per pixel (nx, ny, nz, z).
std::vector<std::array<double, 4>> pull_push_reference(int w, int h, const std::vector<float>& depth,
                                                       const std::vector<float>& normal,
                                                       const std::vector<float>& count) {
  struct Level {
    int w, h;
    std::vector<std::array<double, 4>> v;
    std::vector<bool> valid;
  };
  std::vector<Level> levels(1);
  levels[0] = {w, h, std::vector<std::array<double, 4>>(size_t(w) * h), std::vector<bool>(size_t(w) * h)};
  for (int i = 0; i < w * h; ++i) {
    const bool fg = std::isfinite(depth[i]) && depth[i] > 0.0f;
    levels[0].v[i] = fg ? std::array<double, 4>{normal[3 * i], normal[3 * i + 1], normal[3 * i + 2], depth[i]}
                        : std::array<double, 4>{0, 0, 0, 0};
    levels[0].valid[i] = count[i] > 0.0f;
  }
  while (levels.back().w > 1 || levels.back().h > 1) {
    const Level& f = levels.back();
    Level c{(f.w + 2) / 3, (f.h + 2) / 3, {}, {}};
    c.v.assign(size_t(c.w) * c.h, {0, 0, 0, 0});
    c.valid.assign(size_t(c.w) * c.h, false);
    for (int y = 0; y < c.h; ++y)
      for (int x = 0; x < c.w; ++x) {
        std::array<double, 4> sum{0, 0, 0, 0};
        int fg = 0;
        bool any = false;
        for (int yy = 3 * y; yy < std::min(3 * y + 3, f.h); ++yy)
          for (int xx = 3 * x; xx < std::min(3 * x + 3, f.w); ++xx) {
            const int i = yy * f.w + xx;
            if (!f.valid[i]) continue;
            any = true;
            if (f.v[i][3] > 0.0) {
              for (int k = 0; k < 4; ++k) sum[k] += f.v[i][k];
              ++fg;
            }
          }
        auto& out = c.v[size_t(y) * c.w + x];
        if (fg > 0) {
          for (int k = 0; k < 4; ++k) out[k] = sum[k] / fg;
          const double len = std::sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2]);
          if (len > 0.0)
            for (int k = 0; k < 3; ++k) out[k] /= len;
        }
        c.valid[size_t(y) * c.w + x] = any;
      }
    levels.push_back(std::move(c));
  }
  for (size_t l = levels.size() - 1; l-- > 0;) {
    Level& f = levels[l];
    const Level& c = levels[l + 1];
    for (int y = 0; y < f.h; ++y)
      for (int x = 0; x < f.w; ++x) {
        const size_t i = size_t(y) * f.w + x, parent = size_t(y / 3) * c.w + x / 3;
        if (!f.valid[i] && c.valid[parent]) {
          f.v[i] = c.v[parent];
          f.valid[i] = true;
        }
      }
  }
  std::vector<std::array<double, 4>> out(size_t(w) * h);
  for (int i = 0; i < w * h; ++i) out[i] = levels[0].valid[i] ? levels[0].v[i] : std::array<double, 4>{0, 0, 0, 0};
  return out;
}

// sparse_gbuffer: where sample_count is 0 the depth and normal planes hold
// garbage; the chain reads them filled by the pull-push pyramid. A size no
// power of 3 divides, a background corner, a 10x10 block without any sample
// (filled from two levels up) and scattered samples elsewhere.
// Split signals below one sample per pixel go through the joint chain's
// masked paths (no-data pixels, the feedback mask, the last iteration's ring
// fill) per signal: diffuse with a zero specular gives the radiance session's
// output. One a-trous iteration of the 3x3 kernel at 1/16 spp leaves most
// pixels of the first frames without data, so the ring fill runs for both
// signals.
TEST_F(ProgressiveTest, SplitWithZeroSpecularEqualsRadianceBelowOneSpp) {
  const int w = 48, h = 32, n = w * h;
  const std::vector<pipelines::ParameterValue> params = {{"atrous_iterations", 1}};
  auto radiance_config = progressive_config(w, h, params, /*masked=*/true);
  auto split_config = radiance_config;
  split_config.channels[0] = {ChannelId::Diffuse, Format::F32};
  split_config.channels.insert(split_config.channels.begin() + 1, {ChannelId::Specular, Format::F32});
  ASSERT_FALSE(pipelines::validate(split_config).has_value());
  auto radiance_pipe = pipelines::create(ctx(), radiance_config);
  auto split_pipe = pipelines::create(ctx(), split_config);
  SvgfSceneGen scene(w, h, 13, 0.8f, 0.5f, 0.3f, 0.9f, 0.003);
  const std::vector<float> zero(3 * n, 0.0f);
  int filled = 0;  // first frame: output where neither p nor a 3x3 neighbour had a sample
  for (int t = 0; t < 5; ++t) {
    SCOPED_TRACE(testing::Message() << "frame " << t);
    const SvgfScene s = scene.frame(t);
    std::vector<float> count(n);
    for (int i = 0; i < n; ++i) count[i] = ((i % w) + 4 * (i / w) + t) % 16 == 0 ? 1.0f : 0.0f;
    test::HostFrame radiance = host_frame(s, w, h, Format::F32, MotionConvention::PixelsToPrevious, 0, false);
    test::HostFrame split = host_frame(s, w, h, Format::F32, MotionConvention::PixelsToPrevious, 0, false, &zero);
    radiance.add(ChannelId::SampleCount, Format::F32, count);
    split.add(ChannelId::SampleCount, Format::F32, count);
    const auto want = run(*radiance_pipe, radiance);
    const auto got = run(*split_pipe, split);
    ASSERT_EQ(got.size(), want.size());
    for (size_t i = 0; i < got.size(); ++i)
      ASSERT_NEAR(got[i], want[i], 1e-5 * std::max(1.0f, std::fabs(want[i]))) << i;
    if (t > 0) continue;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        bool sampled = false;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int qx = x + dx, qy = y + dy;
            if (qx >= 0 && qy >= 0 && qx < w && qy < h && count[qy * w + qx] > 0.0f) sampled = true;
          }
        const size_t i = size_t(y) * w + x;
        if (!sampled && s.depth[i] > 0.0f && want[3 * i] + want[3 * i + 1] + want[3 * i + 2] > 0.0f) ++filled;
      }
  }
  EXPECT_GT(filled, n / 10);
}

TEST_F(ProgressiveTest, SparseGbufferIsFilledByThePyramidAndSampledPixelsKeepTheirOwn) {
  const int w = 37, h = 23, n = w * h;
  std::vector<float> depth(n), normal(3 * n), count(n), radiance(3 * n, 0.5f), albedo(3 * n, 0.5f), motion(2 * n, 0.0f);
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float garbage[] = {NAN, 0.0f, INFINITY, -3.0f, 1e30f};
  for (int i = 0; i < n; ++i) {
    const int x = i % w, y = i / w;
    const bool block = x >= 20 && x < 30 && y >= 5 && y < 15;
    count[i] = !block && u(rng) < 0.3f ? 1.0f : 0.0f;
    const bool background = x < 6 && y < 5;
    const float nx = 0.3f * std::sin(x / 4.0f), ny = 0.2f * std::cos(y / 3.0f);
    const float len = std::sqrt(nx * nx + ny * ny + 1.0f);
    if (count[i] > 0.0f) {
      depth[i] = background ? INFINITY : 2.0f + 0.05f * x + 0.02f * y;
      normal[3 * i] = nx / len;
      normal[3 * i + 1] = ny / len;
      normal[3 * i + 2] = 1.0f / len;
    } else {
      depth[i] = garbage[i % 5];
      for (int k = 0; k < 3; ++k) normal[3 * i + k] = garbage[(i + k) % 5];
    }
  }
  auto pipe = pipelines::create(ctx(), progressive_config(w, h, {{"sparse_gbuffer", 1}}, true));
  auto* graph = dynamic_cast<pipelines::GraphPipeline*>(pipe.get());
  ASSERT_NE(graph, nullptr);
  graph->set_capture(true);
  test::HostFrame f;
  f.info.motion = MotionConvention::PixelsToPrevious;
  f.add(ChannelId::Radiance, Format::F32, radiance);
  f.add(ChannelId::Albedo, Format::F32, albedo);
  f.add(ChannelId::Normal, Format::F32, normal);
  f.add(ChannelId::Depth, Format::F32, depth);
  f.add(ChannelId::Motion, Format::F32, motion);
  f.add(ChannelId::SampleCount, Format::F32, count);
  const auto out = run(*pipe, f);
  for (float v : out) ASSERT_TRUE(std::isfinite(v));
  const auto filled_depth = test::decode_output(graph->captured("gbuffer_push_0", "gbuffer_depth"), Format::F32);
  const auto filled_normal = test::decode_output(graph->captured("gbuffer_push_0", "gbuffer_normal"), Format::F32);
  ASSERT_EQ(filled_depth.size(), size_t(n));
  const auto want = pull_push_reference(w, h, depth, normal, count);
  int filled_foreground = 0;
  for (int i = 0; i < n; ++i) {
    const bool fg = std::isfinite(depth[i]) && depth[i] > 0.0f;
    if (count[i] > 0.0f) {  // its own, bit for bit (background as 0)
      ASSERT_EQ(filled_depth[i], fg ? depth[i] : 0.0f) << i;
      for (int k = 0; k < 3; ++k) ASSERT_EQ(filled_normal[3 * i + k], fg ? normal[3 * i + k] : 0.0f) << i;
      continue;
    }
    ASSERT_NEAR(filled_depth[i], want[i][3], 1e-5 * std::max(1.0, want[i][3])) << "pixel " << i;
    for (int k = 0; k < 3; ++k) ASSERT_NEAR(filled_normal[3 * i + k], want[i][k], 1e-5) << "pixel " << i;
    filled_foreground += want[i][3] > 0.0 ? 1 : 0;
  }
  EXPECT_GT(filled_foreground, n / 2);  // the holes were filled, not left as background
  // The block's centre is 4 pixels from any sample: filled from two levels up.
  EXPECT_GT(filled_depth[10 * w + 25], 2.0f);
}

// On a flat scene the filled G-buffer is the true one, so a sparse session
// whose unsampled pixels hold garbage gives what a complete one gives.
TEST_F(ProgressiveTest, SparseGbufferOnAFlatSceneEqualsTheCompleteOne) {
  const int w = 40, h = 24, n = w * h;
  FlatFrames scene{w, h};
  auto complete = pipelines::create(ctx(), progressive_config(w, h, {}, true));
  auto sparse = pipelines::create(ctx(), progressive_config(w, h, {{"sparse_gbuffer", 1}}, true));
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> value(0.0, 2.0);
  for (int t = 0; t < 6; ++t) {
    std::vector<float> count(n);
    std::vector<double> x(n, 0.0);
    for (int i = 0; i < n; ++i) {
      count[i] = quarter_spp_count(i, w, t);
      if (count[i] > 0.0f) x[i] = value(rng);
    }
    test::HostFrame full = scene.frame(grey(x), &count);
    test::HostFrame holes = full;
    std::vector<float> depth(n, 2.0f), normal(3 * n, 0.0f);
    for (int i = 0; i < n; ++i) {
      normal[3 * i + 2] = 1.0f;
      if (count[i] == 0.0f) {
        depth[i] = NAN;
        normal[3 * i + 2] = 0.0f;
      }
    }
    for (auto& plane : holes.planes) {
      if (plane.id == ChannelId::Depth) plane.bytes = test::encode_plane(depth, Format::F32);
      if (plane.id == ChannelId::Normal) plane.bytes = test::encode_plane(normal, Format::F32);
    }
    const auto a = run(*complete, full), b = run(*sparse, holes);
    for (int i = 0; i < 3 * n; ++i) ASSERT_NEAR(b[i], a[i], 1e-6f * std::max(a[i], 1.0f)) << "frame " << t << " " << i;
  }
}

// A light panning across a far wall, at 1 spp (sample_count everywhere: paper
// 004's regime as dnrender sends it), with the final blend (taa_alpha 0.1):
// the bilinear history of a wall pixel beside the light holds part of the
// light's 1500, and a clamp box that took the light's pixels in (another
// surface, 3 depth units nearer) let it through, 0.9 of it a frame. The box
// takes p's surface only, so the wall stays at its 0.05.
TEST_F(ProgressiveTest, ALightBesideASurfaceDoesNotOpenTheFinalBlendsClamp) {
  const int w = 48, h = 16, n = w * h;
  const float wall = 0.05f, light = 1500.0f;
  const std::vector<float> every_pixel(n, 1.0f);
  auto config = test::make_config("progressive", w, h,
                                  {{ChannelId::Radiance, Format::F32},
                                   {ChannelId::Albedo, Format::F32},
                                   {ChannelId::Normal, Format::F32},
                                   {ChannelId::Depth, Format::F32},
                                   {ChannelId::Motion, Format::F32},
                                   {ChannelId::Emission, Format::F32},
                                   {ChannelId::SampleCount, Format::F32}},
                                  Format::F32, {});
  auto pipe = pipelines::create(ctx(), config);
  double worst = 0.0;
  for (int t = 0; t < 12; ++t) {
    // The view pans by half a pixel a frame: the light covers world [20, 23).
    auto lit = [&](int x) {
      const double u = x + 0.5 - 0.5 * t;
      return u >= 20.0 && u < 23.0;
    };
    std::vector<float> radiance(3 * n), emission(3 * n, 0.0f), albedo(3 * n), normal(3 * n, 0.0f), depth(n);
    for (int i = 0; i < n; ++i) {
      const bool l = lit(i % w);
      for (int c = 0; c < 3; ++c) {
        radiance[3 * i + c] = l ? light : wall;
        emission[3 * i + c] = l ? light : 0.0f;
        albedo[3 * i + c] = 0.5f;  // a lamp's diffuser: not kept as rendered, so in its neighbours' boxes but for depth
      }
      normal[3 * i + 2] = 1.0f;
      depth[i] = l ? 2.0f : 5.0f;
    }
    test::HostFrame f;
    f.info.motion = MotionConvention::PixelsToPrevious;
    std::vector<float> motion(2 * n, 0.0f);
    for (int i = 0; i < n; ++i) motion[2 * i] = -0.5f;
    f.add(ChannelId::Radiance, Format::F32, radiance);
    f.add(ChannelId::Albedo, Format::F32, albedo);
    f.add(ChannelId::Normal, Format::F32, normal);
    f.add(ChannelId::Depth, Format::F32, depth);
    f.add(ChannelId::Motion, Format::F32, t == 0 ? std::vector<float>(2 * n, 0.0f) : motion);
    f.add(ChannelId::Emission, Format::F32, emission);
    f.add(ChannelId::SampleCount, Format::F32, every_pixel);
    const std::vector<float> out = run(*pipe, f);
    for (int i = 0; i < n; ++i)
      if (!lit(i % w)) worst = std::max(worst, static_cast<double>(out[3 * i]));
  }
  EXPECT_LT(worst, 2.0 * wall) << "a wall pixel beside the light took the light's radiance";
}

// Below one sample per pixel (a 1/4-spp schedule), a metal's pixels (albedo
// 0: the guides do not explain what they show) are kept as rendered where
// sampled, as without sample_count: a noise-free 1-pixel highlight of 100 on
// a metal of 1 comes back exactly the frame it is sampled, young as it is
// (the young filter has no luminance weight and spread it before). Where
// unsampled, the pixel has no radiance of its own (the 0 sent there): it shows
// the filter's, not that 0. (No final blend and harm_guard 0: a still kept
// pixel is otherwise averaged with its own earlier outputs, and blended toward
// its temporal mean, both holding the filter's values of unsampled frames.)
TEST_F(ProgressiveTest, AMetalsSampledPixelsAreKeptAsRenderedBelowOneSpp) {
  const int w = 32, h = 16, n = w * h, hx = 13, hy = 7, hi = hy * w + hx;
  FlatFrames scene{w, h};
  scene.albedo = 0.0f;
  auto pipe = pipelines::create(ctx(), progressive_config(w, h, {{"harm_guard", 0}, {"taa_alpha", 0}, {"taa_static_alpha", 0}}, /*masked=*/true));
  for (int t = 0; t < 8; ++t) {
    std::vector<float> count(n), radiance(3 * n);
    for (int i = 0; i < n; ++i) {
      count[i] = quarter_spp_count(i, w, t);
      for (int c = 0; c < 3; ++c) radiance[3 * i + c] = count[i] > 0.0f ? (i == hi ? 100.0f : 1.0f) : 0.0f;
    }
    const std::vector<float> out = run(*pipe, scene.frame(radiance, &count));
    if (count[hi] > 0.0f)
      EXPECT_NEAR(out[3 * hi], 100.0f, 1e-3) << "frame " << t;
    else
      EXPECT_GT(out[3 * hi], 0.5f) << "frame " << t << ": the unsampled pixel showed the 0 it was sent";
  }
}

TEST(ProgressiveValidate, ChannelsAndParameters) {
  EXPECT_FALSE(pipelines::validate(progressive_config(16, 16)).has_value());
  EXPECT_FALSE(pipelines::validate(progressive_config(16, 16, {}, true)).has_value());
  EXPECT_FALSE(pipelines::validate(progressive_config(16, 16, {{"step_order", 1}, {"luminance_form", 1}})).has_value());
  // Clipping is svgf's, not paper 004's: refused, not ignored.
  const auto clip = pipelines::validate(progressive_config(16, 16, {{"alpha_colour", 0.2}, {"clip_roughness", 0.5}}));
  ASSERT_TRUE(clip.has_value());
  EXPECT_EQ(clip->problem, pipelines::ConfigProblem::InvalidParameter);
  EXPECT_EQ(clip->field, "parameters[1].value");
  EXPECT_NE(clip->message.find("clip_roughness"), std::string::npos) << clip->message;
  auto rough = progressive_config(16, 16);
  rough.channels.push_back({ChannelId::Roughness, Format::F32});
  const auto e = pipelines::validate(rough);
  ASSERT_TRUE(e.has_value());
  EXPECT_EQ(e->problem, pipelines::ConfigProblem::InvalidChannel);
  const auto sparse = pipelines::validate(progressive_config(16, 16, {{"sparse_gbuffer", 1}}));
  ASSERT_TRUE(sparse.has_value());
  EXPECT_EQ(sparse->problem, pipelines::ConfigProblem::InvalidParameter);
  EXPECT_NE(sparse->message.find("sample_count"), std::string::npos) << sparse->message;
  EXPECT_FALSE(pipelines::validate(progressive_config(16, 16, {{"sparse_gbuffer", 1}}, true)).has_value());
  const auto bad_order = pipelines::validate(progressive_config(16, 16, {{"step_order", 3}}));
  ASSERT_TRUE(bad_order.has_value());
  EXPECT_EQ(bad_order->problem, pipelines::ConfigProblem::InvalidParameter);
}

}  // namespace
}  // namespace dn

