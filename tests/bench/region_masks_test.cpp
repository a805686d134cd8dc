// The region masks of bench/region_metrics (bench/region_masks.cpp) on small
// hand-made frames.
#include "region_masks.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace {

using namespace dn::bench;

TEST(RegionMasks, GlossyAndRoughnessValues) {
  const std::vector<float> rough = {0.001f, 0.04f, 0.25f, 0.35f, 1.0f, std::nanf("")};
  EXPECT_EQ(glossy_mask(rough, 0.3f), (Mask{1, 1, 1, 0, 0, 0}));
  EXPECT_EQ(roughness_values_mask(rough, {0.04f, 0.35f}, 0.005f), (Mask{0, 1, 0, 1, 0, 0}));
}

TEST(RegionMasks, HighlightsAboveKTimesTheMedianDilated) {
  const int w = 7, h = 5;
  std::vector<float> rgb(size_t(w * h) * 3, 0.1f);
  auto set = [&](int x, int y, float v) { for (int c = 0; c < 3; ++c) rgb[size_t(y * w + x) * 3 + c] = v; };
  set(3, 2, 2.5f);  // 25 x the median luminance 0.1
  set(0, 0, 1.5f);  // 15 x: below k = 20
  const Mask m = highlight_mask(rgb.data(), w, h, 20.0f, 1);
  EXPECT_EQ(count(m), 9u);
  for (int y = 1; y <= 3; ++y)
    for (int x = 2; x <= 4; ++x) EXPECT_EQ(m[size_t(y * w + x)], 1) << x << "," << y;
  EXPECT_EQ(count(highlight_mask(rgb.data(), w, h, 20.0f, 0)), 1u);
  EXPECT_EQ(count(highlight_mask(rgb.data(), w, h, 10.0f, 0)), 2u);
}

TEST(RegionMasks, DilateClipsAtTheBorder) {
  Mask m(4 * 3, 0);
  m[0] = 1;
  EXPECT_EQ(dilate(m, 4, 3, 1), (Mask{1, 1, 0, 0, 1, 1, 0, 0, 0, 0, 0, 0}));
}

TEST(RegionMasks, DisocclusionOutsideTheImageAndDepthMismatch) {
  const int w = 8, h = 4;
  const size_t n = size_t(w * h);
  // The camera pans: every pixel comes from one pixel to the left (mv = -1, 0).
  std::vector<float> motion(2 * n, 0.0f);
  for (size_t i = 0; i < n; ++i) motion[2 * i] = -1.0f;
  std::vector<float> depth(n, 5.0f), prev(n, 5.0f);
  // An object at depth 2 covered pixel x = 4 in the previous frame; in the
  // current frame pixel 5 (p_prev = 4.5) sees the wall behind it at depth 5.
  for (int y = 0; y < h; ++y) prev[size_t(y * w + 4)] = 2.0f;
  // The background (infinite depth) agrees with itself.
  depth[size_t(3 * w + 2)] = prev[size_t(3 * w + 1)] = std::numeric_limits<float>::infinity();
  const Mask m = disocclusion_mask(motion, depth, prev, w, h, 0.1f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool expect = x == 0 || x == 5;  // left edge: p_prev.x = -0.5; x = 5: depth 5 against 2
      EXPECT_EQ(m[size_t(y * w + x)], expect ? 1 : 0) << x << "," << y;
    }
  // Within the relative tolerance: 5 against 5.4 (8 %) agrees.
  for (auto& d : prev) d = d == 2.0f ? 5.4f : d;
  EXPECT_EQ(count(disocclusion_mask(motion, depth, prev, w, h, 0.1f)), size_t(h));
  EXPECT_EQ(count(disocclusion_mask(motion, depth, prev, w, h, 0.05f)), size_t(2 * h));
}

}  // namespace
