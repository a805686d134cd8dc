// Highlights survive temporal filtering (docs/pipelines.md, "svgf
// in detail", HDR step rule and history clipping): a mirror reflecting a
// small light, 100 on a noisy 0.4 background (roughness 0), through svgf in radiance and in
// split mode, still and under a camera pan that moves the surface 2 px per
// frame and its reflection 1 px (the surface's motion vectors are wrong for
// the reflection, as they are for every reflection). Every frame, the output
// keeps >= 95 % of the highlight's energy inside its footprint dilated by
// 1 px and no pixel outside that exceeds twice its true value; over the
// sequence the mean luminance stays within 2 % of the input's.
// FireflyTest: the isolated-bright-pixel exception of the HDR step rule.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "gpu_test_env.hpp"
#include "pipelines/pipeline.hpp"
#include "svgf_inputs.hpp"

namespace dn {
namespace {

using protocol::ChannelId;
using protocol::Format;
using svgf_inputs::run;

constexpr int kW = 96, kH = 64, kFrames = 12, kSize = 3;
constexpr float kBackground = 0.4f, kLight = 100.0f;

struct Motion {
  const char* name;
  int surface;    // px per frame the surface moves right (its motion vectors say so)
  int highlight;  // px per frame the reflection moves right
};

float noise(uint32_t i, uint32_t t) {
  uint32_t h = i * 747796405u + t * 2891336453u + 12345u;
  h = ((h >> ((h >> 28u) + 4u)) ^ h) * 277803737u;
  return static_cast<float>((h >> 22u) ^ h) / 4294967296.0f;
}

bool in_footprint(int x, int y, int t, const Motion& m, int dilate) {
  const int x0 = 30 + m.highlight * t, y0 = 30;
  return x >= x0 - dilate && x < x0 + kSize + dilate && y >= y0 - dilate && y < y0 + kSize + dilate;
}

class HighlightTest : public test::GpuTest, public testing::WithParamInterface<std::tuple<Motion, bool>> {};
class FireflyTest : public test::GpuTest {};

TEST_P(HighlightTest, StaysInItsFootprint) {
  const auto& [motion, split] = GetParam();
  std::vector<pipelines::InputChannel> decls;
  if (split) decls = {{ChannelId::Diffuse, Format::F32}, {ChannelId::Specular, Format::F32}};
  else decls = {{ChannelId::Radiance, Format::F32}};
  for (ChannelId id : {ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth, ChannelId::Motion, ChannelId::Roughness})
    decls.push_back({id, Format::F32});
  auto pipe = pipelines::create(ctx(), test::make_config("svgf", kW, kH, decls));
  const int n = kW * kH;
  double in_sum = 0.0, out_sum = 0.0, worst_outside = 0.0, worst_energy = 1e30;
  for (int t = 0; t < kFrames; ++t) {
    std::vector<float> diffuse(3 * n), specular(3 * n, 0.0f), albedo(3 * n, 1.0f), normal(3 * n), depth(n, 5.0f),
        mv(2 * n);
    for (int i = 0; i < n; ++i) {
      const int x = i % kW, y = i / kW;
      const float bg = kBackground * (0.5f + noise(static_cast<uint32_t>(i), static_cast<uint32_t>(t)));
      const bool light = in_footprint(x, y, t, motion, 0);
      for (int k = 0; k < 3; ++k) {
        diffuse[3 * i + k] = light ? 0.0f : bg;
        specular[3 * i + k] = light ? kLight : 0.0f;
      }
      normal[3 * i + 2] = 1.0f;
      mv[2 * i] = -static_cast<float>(motion.surface);  // p_prev = p + mv
    }
    test::HostFrame f;
    f.info.flags = t == 0 ? protocol::kFrameReset : 0u;
    if (split) {
      f.add(ChannelId::Diffuse, Format::F32, diffuse);
      f.add(ChannelId::Specular, Format::F32, specular);
    } else {
      std::vector<float> radiance(3 * n);
      for (int i = 0; i < 3 * n; ++i) radiance[i] = diffuse[i] + specular[i];
      f.add(ChannelId::Radiance, Format::F32, radiance);
    }
    f.add(ChannelId::Albedo, Format::F32, albedo);
    f.add(ChannelId::Normal, Format::F32, normal);
    f.add(ChannelId::Depth, Format::F32, depth);
    f.add(ChannelId::Motion, Format::F32, mv);
    f.add(ChannelId::Roughness, Format::F32, std::vector<float>(n, 0.0f));  // a mirror
    const auto out = run(*pipe, f);
    double energy = 0.0, outside = 0.0;
    for (int i = 0; i < n; ++i) {
      const int x = i % kW, y = i / kW;
      for (int k = 0; k < 3; ++k) {
        in_sum += diffuse[3 * i + k] + specular[3 * i + k];
        out_sum += out[3 * i + k];
      }
      if (in_footprint(x, y, t, motion, 1)) energy += out[3 * i] - kBackground;
      else outside = std::max(outside, static_cast<double>(out[3 * i]));
    }
    const double want = kSize * kSize * (kLight - kBackground);
    EXPECT_GE(energy, 0.95 * want) << "frame " << t << ": highlight energy inside its dilated footprint";
    EXPECT_LE(outside, 2.0 * kBackground) << "frame " << t << ": brightest pixel outside the dilated footprint";
    worst_outside = std::max(worst_outside, outside);
    worst_energy = std::min(worst_energy, energy / want);
  }
  const double drift = std::fabs(out_sum - in_sum) / in_sum;
  EXPECT_LE(drift, 0.02) << "mean luminance of the output against the input's, over the sequence";
  std::printf("[ info     ] %s %s: energy kept >= %.4f, brightest outside %.3f (true %.1f), mean drift %.4f\n",
              motion.name, split ? "split" : "radiance", worst_energy, worst_outside, kBackground, drift);
}

// The other side of the HDR step rule: a lone bright pixel (a firefly: all
// 8 neighbours darker than half of it) on the first frame, when the variance
// is the 7x7 spatial estimate, is taken apart by the a-trous instead of
// passing through as its own zero-variance sample; the 3x3 highlight of the
// tests above is kept. Radiance mode, roughness 1 (no history clipping).
TEST_F(FireflyTest, IsFilteredWhereAHighlightIsKept) {
  std::vector<pipelines::InputChannel> decls = {{ChannelId::Radiance, Format::F32}};
  for (ChannelId id : {ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth, ChannelId::Motion})
    decls.push_back({id, Format::F32});
  auto pipe = pipelines::create(ctx(), test::make_config("svgf", kW, kH, decls));
  const int n = kW * kH, firefly = 20 * kW + 60;
  std::vector<float> radiance(3 * n), albedo(3 * n, 1.0f), normal(3 * n), depth(n, 5.0f), mv(2 * n, 0.0f);
  for (int i = 0; i < n; ++i) {
    const float bg = kBackground * (0.5f + noise(static_cast<uint32_t>(i), 0u));
    const bool light = in_footprint(i % kW, i / kW, 0, Motion{"still", 0, 0}, 0) || i == firefly;
    for (int k = 0; k < 3; ++k) radiance[3 * i + k] = light ? kLight : bg;
    normal[3 * i + 2] = 1.0f;
  }
  test::HostFrame f;
  f.info.flags = protocol::kFrameReset;
  f.add(ChannelId::Radiance, Format::F32, radiance);
  f.add(ChannelId::Albedo, Format::F32, albedo);
  f.add(ChannelId::Normal, Format::F32, normal);
  f.add(ChannelId::Depth, Format::F32, depth);
  f.add(ChannelId::Motion, Format::F32, mv);
  const auto out = run(*pipe, f);
  double highlight = 0.0;
  for (int i = 0; i < n; ++i)
    if (in_footprint(i % kW, i / kW, 0, Motion{"still", 0, 0}, 1)) highlight += out[3 * i] - kBackground;
  std::printf("[ info     ] firefly %.2f -> %.2f; highlight energy kept %.4f\n", kLight, out[3 * firefly],
              highlight / (kSize * kSize * (kLight - kBackground)));
  EXPECT_LT(out[3 * firefly], 0.25f * kLight) << "a lone firefly passes through the spatial filter";
  EXPECT_GE(highlight, 0.95 * kSize * kSize * (kLight - kBackground)) << "the 3x3 highlight lost energy";
}

// Two-valued light (a penumbra: 1 with probability 0.7, else 0, per pixel
// and frame) seen by a still camera on a flat surface of the given
// roughness, 24 frames through svgf with these parameters: the mean
// frame-to-frame change of the output over the last 8 frames, and the mean
// output over them.
struct StillFlicker {
  double change = 0.0, mean = 0.0;
};
StillFlicker still_camera_flicker(gpu::Context& ctx, const std::vector<pipelines::ParameterValue>& params, float roughness) {
  std::vector<pipelines::InputChannel> decls = {{ChannelId::Radiance, Format::F32}};
  for (ChannelId id : {ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth, ChannelId::Motion, ChannelId::Roughness})
    decls.push_back({id, Format::F32});
  auto pipe = pipelines::create(ctx, test::make_config("svgf", kW, kH, decls, Format::F32, params));
  const int n = kW * kH, frames = 24, measured = 8;
  std::vector<float> albedo(3 * n, 1.0f), normal(3 * n), depth(n, 5.0f), mv(2 * n, 0.0f), previous;
  for (int i = 0; i < n; ++i) normal[3 * i + 2] = 1.0f;
  StillFlicker r;
  for (int t = 0; t < frames; ++t) {
    std::vector<float> radiance(3 * n);
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k)
        radiance[3 * i + k] = noise(static_cast<uint32_t>(i), static_cast<uint32_t>(t)) < 0.7f ? 1.0f : 0.0f;
    test::HostFrame f;
    f.info.flags = t == 0 ? protocol::kFrameReset : 0u;
    f.add(ChannelId::Radiance, Format::F32, radiance);
    f.add(ChannelId::Albedo, Format::F32, albedo);
    f.add(ChannelId::Normal, Format::F32, normal);
    f.add(ChannelId::Depth, Format::F32, depth);
    f.add(ChannelId::Motion, Format::F32, mv);
    f.add(ChannelId::Roughness, Format::F32, std::vector<float>(n, roughness));
    const auto out = run(*pipe, f);
    if (t >= frames - measured)
      for (int i = 0; i < 3 * n; ++i) {
        r.change += std::fabs(out[i] - previous[i]);
        r.mean += out[i];
      }
    previous = out;
  }
  r.change /= 3.0 * n * measured;
  r.mean /= 3.0 * n * measured;
  return r;
}

// The other side of history clipping: on a still camera nothing moved, so a
// converged history must not be clipped toward a 1-spp box that misses the
// mean. The two-valued light on a mirror (clipped everywhere): the
// frame-to-frame change of the output stays within 25 % of the same
// pipeline's without clipping (clip_roughness 0). Clipping toward the raw
// 1-spp box made it 13x (1.10x measured with the static rule,
// docs/pipelines.md). Without the static TAA blend, which would hide it.
TEST_F(FireflyTest, StillCameraClippingAddsNoFlicker) {
  const double clipped = still_camera_flicker(ctx(), {{"taa_static_alpha", 0}}, 0.0f).change;
  const double unclipped = still_camera_flicker(ctx(), {{"taa_static_alpha", 0}, {"clip_roughness", 0}}, 0.0f).change;
  std::printf("[ info     ] still-camera frame-to-frame change: clipped %.5f, unclipped %.5f (ratio %.3f)\n", clipped,
              unclipped, clipped / unclipped);
  EXPECT_GT(unclipped, 0.0);
  EXPECT_LE(clipped, 1.25 * unclipped);
}

// The static TAA blend (taa_static_alpha, default 0.5): on a still camera
// the output is also averaged over frames, so what the a-trous leaves
// flickers less, without moving the mean; on a mirror (clipped history) and
// a diffuse surface. Unclamped, an average with weight 0.5 would leave
// sqrt(0.5 / 1.5) = 0.58 of the change; the 3x3 clamp to the current
// colour holds it back (measured 0.83 on the mirror, 0.76 diffuse).
TEST_F(FireflyTest, StaticBlendStabilisesAStillCamera) {
  for (float roughness : {0.0f, 1.0f}) {
    SCOPED_TRACE(testing::Message() << "roughness " << roughness);
    const StillFlicker blended = still_camera_flicker(ctx(), {}, roughness);
    const StillFlicker plain = still_camera_flicker(ctx(), {{"taa_static_alpha", 0}}, roughness);
    std::printf("[ info     ] roughness %.0f: frame-to-frame change %.5f with the static blend, %.5f without (%.3f); "
                "mean %.4f, %.4f\n",
                roughness, blended.change, plain.change, blended.change / plain.change, blended.mean, plain.mean);
    EXPECT_GT(plain.change, 0.0);
    EXPECT_LE(blended.change, 0.9 * plain.change);
    EXPECT_NEAR(blended.mean, plain.mean, 0.01 * plain.mean);
  }
}

INSTANTIATE_TEST_SUITE_P(Svgf, HighlightTest,
                         testing::Combine(testing::Values(Motion{"still", 0, 0}, Motion{"pan", 2, 1}),
                                          testing::Bool()),
                         [](const auto& info) {
                           return std::string(std::get<0>(info.param).name) +
                                  (std::get<1>(info.param) ? "_split" : "_radiance");
                         });

}  // namespace
}  // namespace dn
