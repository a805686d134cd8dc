// A still view converges, for every denoising pipeline that takes a plain
// G-buffer (docs/pipelines.md, "A still view converges"): a still camera on
// one flat surface of albedo 0.5 lit 1 on the left and 0.25 on the right (a
// shadow edge the guides cannot see, so every spatial filter blurs it),
// each frame one noisy sample per pixel (uniform in [0, 2] times the truth,
// seed 17). The truth is exact. After 1, 2, 4, 8, 16 and 32 frames the
// output's RMSE against it is at or below the plain running mean's, and it
// falls from 8 to 32 frames. svgf-fb streams the same light as its diffuse
// signal (no specular light, F0 0.04, roughness 1); stat-temporal works from
// the radiance alone. reflect has its own still-view test on path-traced
// frames (reflect_test.cpp), as it needs the reflection features. svgf also
// over 64 frames, with converge_still and without, with a firefly in its
// still mean, and with progressive on sparse light.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "frames.hpp"
#include "gpu_test_env.hpp"
#include "pipelines/pipeline.hpp"
#include "svgf_inputs.hpp"

namespace dn {
namespace {

using test::ChannelId;
using test::Format;

class StillConvergenceTest : public test::GpuTest, public testing::WithParamInterface<std::string> {};
class SvgfStillConvergenceTest : public test::GpuTest {};

constexpr int kWidth = 48, kHeight = 16, kEdge = 24, kFrames = 32;

double truth(int pixel) { return 0.5 * (pixel % kWidth < kEdge ? 1.0 : 0.25); }

// The session's channels: what the pipeline takes, all fp32.
std::vector<pipelines::InputChannel> channels_of(const std::string& pipeline) {
  std::vector<ChannelId> ids = {ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth,
                                ChannelId::Motion};
  if (pipeline == "svgf-fb")
    ids = {ChannelId::Diffuse,   ChannelId::Specular, ChannelId::Albedo, ChannelId::SpecularF0,
           ChannelId::Roughness, ChannelId::Normal,   ChannelId::Depth,  ChannelId::Motion};
  std::vector<pipelines::InputChannel> out;
  for (ChannelId id : ids) out.push_back({id, Format::F32});
  return out;
}

// The 4 columns from `blank` (if >= 0) have no normal (0, 0, 0).
test::HostFrame still_frame(const std::string& pipeline, const std::vector<float>& light, int blank = -1) {
  const int n = kWidth * kHeight;
  std::vector<float> albedo(3 * n, 0.5f), normal(3 * n, 0.0f), depth(n, 3.0f), motion(2 * n, 0.0f);
  for (int i = 0; i < n; ++i) normal[3 * i + 2] = blank >= 0 && i % kWidth >= blank && i % kWidth < blank + 4 ? 0.0f : 1.0f;
  test::HostFrame f;
  if (pipeline == "svgf-fb") {
    f.add(ChannelId::Diffuse, Format::F32, light);
    f.add(ChannelId::Specular, Format::F32, std::vector<float>(3 * n, 0.0f));
    f.add(ChannelId::SpecularF0, Format::F32, std::vector<float>(3 * n, 0.04f));
    f.add(ChannelId::Roughness, Format::F32, std::vector<float>(n, 1.0f));
  } else {
    f.add(ChannelId::Radiance, Format::F32, light);
  }
  f.add(ChannelId::Albedo, Format::F32, albedo);
  f.add(ChannelId::Normal, Format::F32, normal);
  f.add(ChannelId::Depth, Format::F32, depth);
  f.add(ChannelId::Motion, Format::F32, motion);
  return f;
}

// Where the error is measured, what the frames lack and how their light is sampled.
struct StillRegion {
  int columns = -1;     // >= 0: only the 4 columns from this one
  int blank_every = 0;  // > 0: those columns have no normal on every frame t with t % blank_every == 0
  int sparse = 0;       // > 0: a sample is `sparse` times the truth with probability 1 / sparse, else 0
  int firefly_frame = 0;  // > 0: on this frame pixel kFirefly's sample is kFireflyGain times the truth
  bool firefly_only = false;  // measure pixel kFirefly alone
};
constexpr int kFirefly = 8 * kWidth + 10;  // on the lit side, away from the edge
constexpr float kFireflyGain = 50.0f;

// The output's RMSE against the truth after each of `frames` still frames;
// mean_rmse: the plain running mean's.
std::vector<double> still_rmse(gpu::Context& ctx, const std::string& pipeline, std::vector<pipelines::ParameterValue> params,
                               int frames, std::vector<double>& mean_rmse, StillRegion region = {}) {
  const int n = kWidth * kHeight;
  auto pipe = pipelines::create(ctx, test::make_config(pipeline, kWidth, kHeight, channels_of(pipeline), Format::F32,
                                                       std::move(params)));
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> noise(0.0f, 2.0f);
  std::bernoulli_distribution hit(region.sparse > 0 ? 1.0 / region.sparse : 1.0);
  std::vector<float> light(3 * n);
  std::vector<double> sum(3 * n, 0.0), out_rmse;
  mean_rmse.clear();
  for (int t = 1; t <= frames; ++t) {
    for (int i = 0; i < n; ++i) {
      const float path = region.sparse > 0 && hit(rng) ? static_cast<float>(region.sparse) : 0.0f;  // one per pixel
      for (int k = 0; k < 3; ++k) light[3 * i + k] = static_cast<float>(truth(i)) * (region.sparse > 0 ? path : noise(rng));
    }
    if (t == region.firefly_frame)
      for (int k = 0; k < 3; ++k) light[3 * kFirefly + k] = static_cast<float>(truth(kFirefly)) * kFireflyGain;
    const bool blank = region.blank_every > 0 && t % region.blank_every == 0;
    const std::vector<float> out = svgf_inputs::run(*pipe, still_frame(pipeline, light, blank ? region.columns : -1));
    double e = 0.0, em = 0.0;
    int counted = 0;
    for (int j = 0; j < 3 * n; ++j) {
      sum[j] += light[j];
      if (region.columns >= 0 && (j / 3 % kWidth < region.columns || j / 3 % kWidth >= region.columns + 4)) continue;
      if (region.firefly_only && j / 3 != kFirefly) continue;
      e += (out[j] - truth(j / 3)) * (out[j] - truth(j / 3));
      em += (sum[j] / t - truth(j / 3)) * (sum[j] / t - truth(j / 3));
      ++counted;
    }
    out_rmse.push_back(std::sqrt(e / counted));
    mean_rmse.push_back(std::sqrt(em / counted));
  }
  return out_rmse;
}

TEST_P(StillConvergenceTest, AtOrBelowTheRunningMeanAndFalling) {
  const std::string pipeline = GetParam();
  std::vector<double> mean;
  const std::vector<double> out = still_rmse(ctx(), pipeline, {}, kFrames, mean);
  std::printf("[ info     ] %s RMSE after 1, 4, 8, 32 frames: %.4f %.4f %.4f %.4f; running mean %.4f %.4f %.4f %.4f\n",
              pipeline.c_str(), out[0], out[3], out[7], out[31], mean[0], mean[3], mean[7], mean[31]);
  for (int t : {1, 2, 4, 8, 16, 32}) EXPECT_LE(out[t - 1], mean[t - 1]) << t << " frames";
  EXPECT_LT(out[31], out[7]);
}

// svgf over 64 frames, against itself without converge_still: at or below
// the running mean at every count and still falling from 16 to 64 frames;
// without it the filtered history holds the blur, above the mean at 64.
TEST_F(SvgfStillConvergenceTest, ConvergeStillIsWhatLetsGoOfTheBlur) {
  std::vector<double> mean, unused;
  const std::vector<double> out = still_rmse(ctx(), "svgf", {}, 64, mean);
  const std::vector<double> off = still_rmse(ctx(), "svgf", {{"converge_still", 0}}, 64, unused);
  std::printf("[ info     ] RMSE after 16, 64 frames: %.4f %.4f; running mean %.4f %.4f; without converge_still %.4f %.4f\n",
              out[15], out[63], mean[15], mean[63], off[15], off[63]);
  for (int t : {1, 2, 4, 8, 16, 32, 64}) EXPECT_LE(out[t - 1], mean[t - 1]) << t << " frames";
  EXPECT_LT(out[63], out[15]);
  EXPECT_GT(off[63], mean[63]) << "the scene does not show what converge_still is for";
}

// The blur at the edge goes as the samples come: once a still pixel holds
// n > 8 samples, the filter starts from their plain mean with a variance
// that falls as 1 / (n sqrt(n / 8)), faster than the mean's, so after 16, 32
// and 64 frames the 4 columns at the edge are at or below the running mean's
// error there too, and after 64 at most half of it (from the capped, filtered
// history the filter kept its blur: after 16 / 32 / 64 frames 0.0956 /
// 0.0709 / 0.0382 against the mean's 0.0513 / 0.0344 / 0.0230; with the
// variance over n alone 0.0378 / 0.0232 / 0.0169).
TEST_F(SvgfStillConvergenceTest, TheEdgeLetsGoOfItsBlur) {
  std::vector<double> mean;
  const std::vector<double> out = still_rmse(ctx(), "svgf", {}, 64, mean, {.columns = kEdge - 2});
  std::printf("[ info     ] edge RMSE after 16, 32, 64 frames: %.4f %.4f %.4f; running mean %.4f %.4f %.4f\n", out[15],
              out[31], out[63], mean[15], mean[31], mean[63]);
  for (int t : {16, 32, 64}) EXPECT_LE(out[t - 1], mean[t - 1]) << t << " frames";
  EXPECT_LE(out[63], 0.5 * mean[63]) << "the edge's blur does not fall faster than the mean's noise";
}

// A renderer may leave a sample's normal empty on a surface it did hit
// (Cycles' Denoising Normal is (0, 0, 0) on some paths): such a sample is
// one more of the same pixel, whose depth has not moved. 4 columns of the
// lit side have no normal on every 8th frame; after 16, 32 and 64 frames
// (each such a frame) their output is at or below the running mean's error
// there: the still mean went on across the gaps and the pixel shows it
// (restarted, it showed that frame's one sample).
TEST_F(SvgfStillConvergenceTest, AMissingNormalDoesNotRestartTheStillMean) {
  std::vector<double> mean;
  const std::vector<double> out = still_rmse(ctx(), "svgf", {}, 64, mean, {.columns = 8, .blank_every = 8});
  std::printf("[ info     ] RMSE without normals after 16, 32, 64 frames: %.4f %.4f %.4f; running mean %.4f %.4f %.4f\n",
              out[15], out[31], out[63], mean[15], mean[31], mean[63]);
  for (int t : {16, 32, 64}) EXPECT_LE(out[t - 1], mean[t - 1]) << t << " frames";
}

// Sparse light (each sample 8 times the truth with probability 1/8, else
// 0): the guard switches on once a pixel's history holds 4 samples, and a
// variance from so few of them is mostly 0, so it pulled the filtered value
// onto the pixel's noisy mean and the view got worse from 3 to 4 frames
// (svgf RMSE 0.0615 to 0.0789; 0.0608 with a still pixel's guard widened
// and its variance pooled over its 3x3 still neighbours). The output stays
// at or below the running mean throughout.
TEST_F(SvgfStillConvergenceTest, SparseLightDoesNotGetWorseAsTheGuardSwitchesOn) {
  for (const std::string pipeline : {"svgf", "progressive"}) {
    std::vector<double> mean;
    const std::vector<double> out = still_rmse(ctx(), pipeline, {}, 8, mean, {.sparse = 8});
    std::printf("[ info     ] %s sparse light RMSE after 2, 3, 4, 8 frames: %.4f %.4f %.4f %.4f; running mean %.4f %.4f %.4f %.4f\n",
                pipeline.c_str(), out[1], out[2], out[3], out[7], mean[1], mean[2], mean[3], mean[7]);
    EXPECT_LE(out[3], out[2]) << pipeline;
    for (int t = 1; t <= 8; ++t) EXPECT_LE(out[t - 1], mean[t - 1]) << pipeline << ", " << t << " frames";
  }
}

// Sparse light again, through stat-temporal: a few samples' Box-Cox means of
// such light lie far apart, and stat's 5 % test split them, so every still
// pixel gathered few members; accumulated means are tested at still_alpha
// (1 %): from 2 frames on the error is below the 5 % test's at every count
// (after 2 / 4 / 16 frames 0.2384 / 0.2492 / 0.1502 at 5 %), and at or below
// the running mean's.
TEST_F(SvgfStillConvergenceTest, StatTemporalTestsAccumulatedMeansAtStillAlpha) {
  constexpr int kSparseFrames = 16;
  std::vector<double> mean, unused;
  const std::vector<double> out = still_rmse(ctx(), "stat-temporal", {}, kSparseFrames, mean, {.sparse = 8});
  const std::vector<double> at_alpha =
      still_rmse(ctx(), "stat-temporal", {{"still_alpha", 0.05}}, kSparseFrames, unused, {.sparse = 8});
  std::printf("[ info     ] sparse light RMSE after 2, 4, 16 frames: %.4f %.4f %.4f; still_alpha 0.05 %.4f %.4f %.4f; running mean %.4f %.4f %.4f\n",
              out[1], out[3], out[15], at_alpha[1], at_alpha[3], at_alpha[15], mean[1], mean[3], mean[15]);
  for (int t = 1; t <= kSparseFrames; ++t) {
    EXPECT_LE(out[t - 1], mean[t - 1]) << t << " frames";
    if (t >= 2) EXPECT_LT(out[t - 1], at_alpha[t - 1]) << t << " frames";
  }
}

// One sample 50 times the truth on the 12th frame: the pixel's still mean
// holds it for good, and from 8 samples the filter starts from that mean.
// The variance steering its edge-stopping is that of the samples the mean
// holds, so the firefly stays filtered: after 32, 48 and 64 frames the
// pixel's error is at most 1/20 of the running mean's there. With the
// exponential moments' variance, which forgets the firefly within a few
// dozen frames, the filter let go of it: 0.0008, 0.0481, 0.0891 against
// the mean's 0.7408, 0.5059, 0.3680.
TEST_F(SvgfStillConvergenceTest, AFireflyInAStillMeanStaysFiltered) {
  std::vector<double> mean;
  const std::vector<double> out = still_rmse(ctx(), "svgf", {}, 64, mean, {.firefly_frame = 12, .firefly_only = true});
  std::printf("[ info     ] firefly pixel error after 12, 32, 48, 64 frames: %.4f %.4f %.4f %.4f; running mean %.4f %.4f %.4f %.4f\n",
              out[11], out[31], out[47], out[63], mean[11], mean[31], mean[47], mean[63]);
  for (int t : {32, 48, 64}) EXPECT_LE(out[t - 1], mean[t - 1] / 20.0) << t << " frames";
}

INSTANTIATE_TEST_SUITE_P(Pipelines, StillConvergenceTest,
                         testing::Values("svgf", "svgf-fb", "progressive", "stat-temporal"),
                         [](const testing::TestParamInfo<std::string>& info) {
                           std::string name = info.param;
                           for (char& c : name)
                             if (c == '-') c = '_';
                           return name;
                         });

}  // namespace
}  // namespace dn
