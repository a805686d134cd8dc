// dnsynth's buffers follow the protocol's conventions (docs/protocol.md §7):
// unit world-space normals, positive linear view depth with +inf for the
// background, and motion in pixels with p_prev = p + mv — checked against the
// previous frame's own position buffer, not against the formula that made it.
#include <gtest/gtest.h>

#include <cmath>

#include "scene.hpp"

namespace dn::synth {
namespace {

constexpr int kW = 320, kH = 180;
// Bilinear interpolation of positions is not exact under perspective: allow 0.5 % of the depth.
constexpr float kTolerance = 0.005f;

glm::vec3 bilinear_position(const FrameBuffers& fb, float px, float py) {
  // Pixel centres are at +0.5.
  const float x = px - 0.5f, y = py - 0.5f;
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const float fx = x - x0, fy = y - y0;
  auto at = [&](int xi, int yi) {
    const size_t i = size_t(yi) * kW + xi;
    return glm::vec3(fb.position[3 * i], fb.position[3 * i + 1], fb.position[3 * i + 2]);
  };
  return glm::mix(glm::mix(at(x0, y0), at(x0 + 1, y0), fx), glm::mix(at(x0, y0 + 1), at(x0 + 1, y0 + 1), fx), fy);
}

TEST(Conventions, NormalsAreUnitAndDepthPositiveOrInfinite) {
  const FrameBuffers fb = render(3, kW, kH, 1);
  int hits = 0, background = 0;
  for (int i = 0; i < kW * kH; ++i) {
    const float d = fb.depth[i];
    if (std::isinf(d)) {
      ++background;
      continue;
    }
    ++hits;
    ASSERT_GT(d, 0.0f);
    const glm::vec3 n(fb.normal[3 * i], fb.normal[3 * i + 1], fb.normal[3 * i + 2]);
    ASSERT_NEAR(glm::length(n), 1.0f, 1e-5f);
    // Depth is the distance along the view axis, not along the ray: never more than the ray length.
    const Camera cam = camera_at(3, kW, kH);
    const glm::vec3 p(fb.position[3 * i], fb.position[3 * i + 1], fb.position[3 * i + 2]);
    ASSERT_NEAR(d, -(cam.view * glm::vec4(p, 1.0f)).z, 1e-3f * d);
  }
  EXPECT_GT(hits, kW * kH / 2);
  EXPECT_GT(background, 0);
}

// Whether the previous frame saw a single surface around (px, py): all four
// bilinear taps hit geometry at nearly the same depth (no silhouette).
bool smooth_around(const FrameBuffers& fb, float px, float py) {
  const int x0 = static_cast<int>(std::floor(px - 0.5f)), y0 = static_cast<int>(std::floor(py - 0.5f));
  float lo = INFINITY, hi = 0.0f;
  for (int dy = 0; dy < 2; ++dy)
    for (int dx = 0; dx < 2; ++dx) {
      const float d = fb.depth[size_t(y0 + dy) * kW + x0 + dx];
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
  return std::isfinite(hi) && hi < lo * 1.02f;
}

TEST(Conventions, MotionPointsToThePreviousPosition) {
  const FrameBuffers prev = render(4, kW, kH, 1);
  const FrameBuffers cur = render(5, kW, kH, 1);
  const Camera prev_cam = camera_at(4, kW, kH);
  int checked = 0, matched = 0;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const size_t i = size_t(y) * kW + x;
      if (std::isinf(cur.depth[i])) continue;
      const float px = x + 0.5f + cur.motion[2 * i], py = y + 0.5f + cur.motion[2 * i + 1];
      if (px < 1.0f || py < 1.0f || px > kW - 1.0f || py > kH - 1.0f) continue;
      if (!smooth_around(prev, px, py)) continue;  // silhouettes: bilinear mixes two surfaces
      const glm::vec3 p(cur.position[3 * i], cur.position[3 * i + 1], cur.position[3 * i + 2]);
      // Disoccluded: something nearer hid the point in the previous frame.
      const float prev_depth_of_p = -(prev_cam.view * glm::vec4(p, 1.0f)).z;
      const size_t j = size_t(py) * kW + size_t(px);
      if (prev.depth[j] < prev_depth_of_p * 0.98f) continue;
      ++checked;
      // The scene is static: the same world point must be where the motion vector says it was.
      if (glm::distance(bilinear_position(prev, px, py), p) < kTolerance * cur.depth[i]) ++matched;
    }
  }
  EXPECT_GT(checked, kW * kH / 2);
  EXPECT_GT(matched, checked * 99 / 100) << matched << " of " << checked;
  RecordProperty("matched_percent", 100 * matched / checked);
}

TEST(Conventions, NegatedMotionFails) {
  // Guards the test above: the opposite convention must not pass it.
  const FrameBuffers prev = render(4, kW, kH, 1);
  const FrameBuffers cur = render(5, kW, kH, 1);
  int checked = 0, matched = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const size_t i = size_t(y) * kW + x;
      if (std::isinf(cur.depth[i])) continue;
      const float px = x + 0.5f - cur.motion[2 * i], py = y + 0.5f - cur.motion[2 * i + 1];
      if (px < 1.0f || py < 1.0f || px > kW - 1.0f || py > kH - 1.0f) continue;
      const glm::vec3 p(cur.position[3 * i], cur.position[3 * i + 1], cur.position[3 * i + 2]);
      ++checked;
      if (glm::distance(bilinear_position(prev, px, py), p) < kTolerance * cur.depth[i]) ++matched;
    }
  EXPECT_LT(matched, checked / 2);
  RecordProperty("matched_percent", 100 * matched / checked);
}

}  // namespace
}  // namespace dn::synth
