// Fractional samples per pixel: a deterministic per-pixel mask, stratified over frames or random.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <set>
#include <vector>

#include "scenes.hpp"
#include "test_support.hpp"

namespace dn::render {
namespace {

TEST(RendererSampling, QuarterSppSamplesAQuarterOfThePixels) {
  const std::unique_ptr<Scene> scene = build_scene(1);
  const RenderSettings st = test::small_settings(128, 72, 0.25);
  const Camera cam = frame_camera(1, 3, st);
  const FrameBuffers fb = render_frame(*scene, cam, frame_camera(1, 2, st), 3, st);
  const int n = st.width * st.height;
  int sampled = 0;
  for (int i = 0; i < n; ++i) {
    const float count = fb.sample_count[i];
    ASSERT_TRUE(count == 0.0f || count == 1.0f);
    if (count == 1.0f) {
      ++sampled;
      continue;
    }
    for (int c = 0; c < 3; ++c) {
      ASSERT_EQ(fb.radiance[3 * i + c], 0.0f);
      ASSERT_EQ(fb.diffuse[3 * i + c], 0.0f);
      ASSERT_EQ(fb.specular[3 * i + c], 0.0f);
    }
    ASSERT_GT(fb.depth[i], 0.0f);  // G-buffers are complete even where no path was traced
  }
  const double fraction = double(sampled) / n;
  EXPECT_NEAR(fraction, 0.25, 0.02);

  // The mask is a function of (seed, frame, pixel): the same again, different next frame.
  const FrameBuffers again = render_frame(*scene, cam, cam, 3, st);
  EXPECT_EQ(again.sample_count, fb.sample_count);
  const FrameBuffers next = render_frame(*scene, cam, cam, 4, st);
  EXPECT_NE(next.sample_count, fb.sample_count);
}

TEST(RendererSampling, FractionalSppAddsASampleWithTheFraction) {
  for (const SppSchedule schedule : {SppSchedule::Stratified, SppSchedule::Random}) {
    int total = 0;
    for (uint32_t p = 0; p < 10000; ++p) total += samples_for_pixel(2.5, 7, 1, p, 100, schedule);
    EXPECT_NEAR(total / 10000.0, 2.5, 0.03);
    EXPECT_EQ(samples_for_pixel(3.0, 7, 1, 5, 100, schedule), 3);
  }
}

// Each pixel's extra samples (count - floor(spp)) over frames first .. first + frames - 1, per frame.
std::vector<std::vector<int>> extra_samples(double spp, uint32_t seed, int first, int frames, int width, int height,
                                            SppSchedule schedule = SppSchedule::Stratified) {
  std::vector<std::vector<int>> masks(frames, std::vector<int>(size_t(width) * height));
  const int whole = static_cast<int>(std::floor(spp));
  for (int t = 0; t < frames; ++t)
    for (uint32_t p = 0; p < masks[t].size(); ++p)
      masks[t][p] = samples_for_pixel(spp, seed, first + t, p, width, schedule) - whole;
  return masks;
}

// Pairs of horizontally or vertically adjacent pixels both set in `mask`.
int adjacent_pairs(const std::vector<int>& mask, int width, int height) {
  int pairs = 0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      if (!mask[size_t(y) * width + x]) continue;
      if (x + 1 < width && mask[size_t(y) * width + x + 1]) ++pairs;
      if (y + 1 < height && mask[size_t(y + 1) * width + x]) ++pairs;
    }
  return pairs;
}

constexpr int kW = 128, kH = 72;

TEST(RendererSampling, StratifiedPeriods) {
  EXPECT_EQ(stratified_period(0.5), 2);
  EXPECT_EQ(stratified_period(0.25), 4);
  EXPECT_EQ(stratified_period(2.25), 4);
  EXPECT_EQ(stratified_period(1.0 / 64), 64);
  EXPECT_EQ(stratified_period(0.2), 5);
  EXPECT_EQ(stratified_period(5.1), 10);  // 5.1 - 5 is not exactly 0.1 in binary
  EXPECT_EQ(stratified_period(0.3333333), 3);
  EXPECT_EQ(stratified_period(1.0 / 1024), 1024);
  EXPECT_EQ(stratified_period(0.333), 0);
  EXPECT_EQ(stratified_period(0.3), 0);
  EXPECT_EQ(stratified_period(2.7), 0);
  EXPECT_EQ(stratified_period(1.0 / 1025), 0);
  EXPECT_EQ(stratified_period(1.0), 0);
  EXPECT_EQ(stratified_period(3.0), 0);
}

// The schedule a progressive denoiser needs: over any k consecutive frames every pixel is
// sampled exactly once, and every frame samples the same number of pixels.
TEST(RendererSampling, StratifiedSamplesEveryPixelOncePerPeriod) {
  for (const int k : {2, 4, 8, 16, 32, 64})
    for (const int first : {0, 37}) {
      const auto masks = extra_samples(1.0 / k, 1, first, k, kW, kH);
      std::vector<int> times(size_t(kW) * kH, 0);
      for (const auto& mask : masks) {
        int sampled = 0;
        for (size_t p = 0; p < mask.size(); ++p) {
          ASSERT_TRUE(mask[p] == 0 || mask[p] == 1);
          sampled += mask[p];
          times[p] += mask[p];
        }
        EXPECT_EQ(sampled, kW * kH / k) << "k " << k;  // 128x72 is a whole number of tiles
      }
      for (size_t p = 0; p < times.size(); ++p)
        ASSERT_EQ(times[p], 1) << "k " << k << " from " << first << " pixel " << p;
    }
  // An image of cut tiles: still once per period; a frame's count off by at most one per cut tile.
  const int w = 125, h = 70;
  for (const int k : {4, 8, 64}) {
    const int tile = 1 << (std::countr_zero(unsigned(k)) + 1) / 2;
    const int cut_tiles = (w % tile ? (h + tile - 1) / tile : 0) + (h % tile ? (w + tile - 1) / tile : 0);
    std::vector<int> times(size_t(w) * h, 0);
    for (const auto& mask : extra_samples(1.0 / k, 1, 3, k, w, h)) {
      int sampled = 0;
      for (size_t p = 0; p < mask.size(); ++p) {
        sampled += mask[p];
        times[p] += mask[p];
      }
      EXPECT_NEAR(sampled, double(w) * h / k, cut_tiles) << "k " << k;
    }
    EXPECT_EQ(std::count(times.begin(), times.end(), 1), w * h) << "k " << k;
  }
}

// Bayer: each frame's pixels form a lattice with no two neighbours (k = 2: a checkerboard),
// and so does the union of each aligned half period (for a progressive denoiser the first
// frames of a period already cover the image evenly).
TEST(RendererSampling, StratifiedFramesHaveNoAdjacentSamples) {
  for (const int k : {2, 4, 8, 16, 32, 64}) {
    const auto masks = extra_samples(1.0 / k, 3, 0, 2 * k, kW, kH);
    for (int t = 0; t < 2 * k; ++t) EXPECT_EQ(adjacent_pairs(masks[t], kW, kH), 0) << "k " << k << " frame " << t;
    for (int half = 0; half < 4 && k >= 4; ++half) {
      std::vector<int> uni(size_t(kW) * kH, 0);
      for (int t = half * k / 2; t < (half + 1) * k / 2; ++t)
        for (size_t p = 0; p < uni.size(); ++p) uni[p] |= masks[t][p];
      EXPECT_EQ(adjacent_pairs(uni, kW, kH), 0) << "k " << k << " half period " << half;
    }
  }
  // The random rule puts neighbours in the same frame.
  EXPECT_GT(adjacent_pairs(extra_samples(0.25, 3, 0, 1, kW, kH, SppSchedule::Random)[0], kW, kH), 500);
}

TEST(RendererSampling, StratifiedPatternDependsOnTheSeed) {
  for (const int k : {2, 4, 8, 16, 32, 64}) {
    std::set<std::vector<int>> frames;
    std::set<std::vector<std::vector<int>>> periods;
    for (uint32_t seed = 1; seed <= 16; ++seed) {
      const auto masks = extra_samples(1.0 / k, seed, 5, k, kW, kH);
      frames.insert(masks[0]);
      periods.insert(masks);
    }
    // A frame's mask is one of only k (a position in the tile), and k = 2 has just the two
    // checkerboards; seeds spread over them, and over many more whole-period patterns.
    EXPECT_GE(frames.size(), std::min<size_t>(k, 16) / 2) << "k " << k;
    EXPECT_GE(periods.size(), std::min<size_t>(k, 12)) << "k " << k;
  }
}

// Periods that are not powers of two: a rank-1 lattice instead of the Bayer tile, with the
// same once-per-period guarantee and no neighbours in one frame; each row samples every
// k-th pixel, so a frame's count is within one per row of W H / k.
TEST(RendererSampling, StratifiedOtherPeriodsCoverEveryPixelOnce) {
  for (const int k : {3, 5, 6, 7, 12, 100})
    for (const int first : {0, 11}) {
      const auto masks = extra_samples(1.0 / k, 2, first, k, kW, kH);
      std::vector<int> times(size_t(kW) * kH, 0);
      for (const auto& mask : masks) {
        int sampled = 0;
        for (size_t p = 0; p < mask.size(); ++p) {
          sampled += mask[p];
          times[p] += mask[p];
        }
        EXPECT_NEAR(sampled, double(kW) * kH / k, kH) << "k " << k;
        EXPECT_EQ(adjacent_pairs(mask, kW, kH), 0) << "k " << k;
      }
      for (size_t p = 0; p < times.size(); ++p)
        ASSERT_EQ(times[p], 1) << "k " << k << " from " << first << " pixel " << p;
    }
  std::set<std::vector<int>> seeds;
  for (uint32_t seed = 1; seed <= 4; ++seed) seeds.insert(extra_samples(0.2, seed, 0, 1, kW, kH)[0]);
  EXPECT_GE(seeds.size(), 2u);
}

// Independent expectation: with a uniform random mask a pixel stays unsampled in 4 frames
// at 0.25 spp with probability 0.75^4 = 31.6 %.
TEST(RendererSampling, RandomScheduleLeavesPixelsUncovered) {
  const auto masks = extra_samples(0.25, 1, 0, 4, kW, kH, SppSchedule::Random);
  int uncovered = 0;
  for (size_t p = 0; p < masks[0].size(); ++p)
    uncovered += (masks[0][p] | masks[1][p] | masks[2][p] | masks[3][p]) == 0;
  EXPECT_NEAR(double(uncovered) / (kW * kH), std::pow(0.75, 4), 0.02);
}

// A fraction that is not 1/k takes the random rule under either schedule, bit for bit.
TEST(RendererSampling, OtherFractionsFallBackToRandom) {
  for (const double spp : {0.3, 2.7, 0.333})
    for (int frame = 0; frame < 3; ++frame)
      EXPECT_EQ(extra_samples(spp, 4, frame, 1, kW, kH)[0],
                extra_samples(spp, 4, frame, 1, kW, kH, SppSchedule::Random)[0])
          << spp;
}

TEST(RendererSampling, WholePlusQuarterGivesOneThirdSamplePerFourFrames) {
  for (const int first : {0, 9}) {
    std::vector<int> threes(size_t(kW) * kH, 0);
    for (int t = first; t < first + 4; ++t)
      for (uint32_t p = 0; p < threes.size(); ++p) {
        const int count = samples_for_pixel(2.25, 1, t, p, kW);
        ASSERT_TRUE(count == 2 || count == 3) << count;
        threes[p] += count == 3;
      }
    for (size_t p = 0; p < threes.size(); ++p) ASSERT_EQ(threes[p], 1) << p;
  }
}

// render_frame takes each pixel's count from samples_for_pixel with the settings' schedule.
TEST(RendererSampling, RenderFollowsTheSchedule) {
  const std::unique_ptr<Scene> scene = build_scene(1);
  RenderSettings st = test::small_settings(32, 18, 0.5);
  st.max_depth = 1;
  const Camera cam = frame_camera(1, 2, st);
  for (const SppSchedule schedule : {SppSchedule::Stratified, SppSchedule::Random}) {
    st.spp_schedule = schedule;
    const FrameBuffers fb = render_frame(*scene, cam, cam, 2, st);
    for (uint32_t p = 0; p < fb.sample_count.size(); ++p)
      ASSERT_EQ(fb.sample_count[p], samples_for_pixel(0.5, st.seed, 2, p, st.width, schedule)) << p;
  }
}

TEST(RendererSampling, FramesAreDeterministicAcrossThreadCounts) {
  const std::unique_ptr<Scene> scene = build_scene(3);
  RenderSettings st = test::small_settings(48, 27, 1.0);
  const Camera cam = frame_camera(3, 1, st);
  st.threads = 1;
  const FrameBuffers one = render_frame(*scene, cam, cam, 1, st);
  st.threads = 2;
  st.tile = 7;
  const FrameBuffers two = render_frame(*scene, cam, cam, 1, st);
  EXPECT_EQ(one.radiance, two.radiance);
  EXPECT_GT(one.rays, uint64_t(48 * 27));
}

// Guide rays (--extra-samples): the ordinary planes are sample 0's, bit for
// bit those of a render without extra samples; each extra sample's depth is
// the primary hit at its own offset (primary_position, an independent ray
// cast), its normal a unit vector on a hit, its offset inside the pixel.
TEST(RendererSampling, ExtraSamplesAreGuideRaysPlusTheirOwnHits) {
  const std::unique_ptr<Scene> scene = build_scene(1);
  RenderSettings st = test::small_settings(64, 36, 1.0);
  const Camera cam = frame_camera(1, 3, st), prev = frame_camera(1, 2, st);
  const FrameBuffers plain = render_frame(*scene, cam, prev, 3, st);
  st.extra_samples = 2;
  const FrameBuffers fb = render_frame(*scene, cam, prev, 3, st);
  EXPECT_EQ(fb.radiance, plain.radiance);
  EXPECT_EQ(fb.diffuse, plain.diffuse);
  EXPECT_EQ(fb.depth, plain.depth);
  EXPECT_EQ(fb.normal, plain.normal);
  ASSERT_EQ(fb.extra.size(), 2u);
  const int n = st.width * st.height;
  int hits = 0, checked = 0;
  for (const auto& e : fb.extra) {
    ASSERT_EQ(e.offset.size(), size_t(2 * n));
    for (int i = 0; i < n; ++i) {
      const float ox = e.offset[2 * i], oy = e.offset[2 * i + 1];
      ASSERT_TRUE(ox >= -0.5f && ox < 0.5f && oy >= -0.5f && oy < 0.5f) << ox << ", " << oy;
      glm::vec3 position;
      const bool hit = primary_position(*scene, cam, st.width, st.height, i % st.width + 0.5f + ox,
                                        i / st.width + 0.5f + oy, position);
      ++checked;
      if (!hit) {
        EXPECT_TRUE(std::isinf(e.depth[i])) << i;
        continue;
      }
      ++hits;
      const float depth = -(cam.view * glm::vec4(position, 1.0f)).z;
      EXPECT_NEAR(e.depth[i], depth, 1e-4f * depth) << i;
      EXPECT_NEAR(glm::length(test::at3(e.normal, i)), 1.0f, 1e-4f) << i;
    }
    // Different positions from sample 0: the samples are not the guide again.
    EXPECT_NE(e.radiance, fb.radiance);
  }
  EXPECT_GT(hits, checked / 2);
}

}  // namespace
}  // namespace dn::render
