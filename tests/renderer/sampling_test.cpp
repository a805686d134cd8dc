// Fewer than one sample per pixel: a deterministic per-pixel mask.
#include <gtest/gtest.h>

#include <cmath>

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
  int total = 0;
  for (uint32_t p = 0; p < 10000; ++p) total += samples_for_pixel(2.5, 7, 1, p);
  EXPECT_NEAR(total / 10000.0, 2.5, 0.03);
  EXPECT_EQ(samples_for_pixel(3.0, 7, 1, 5), 3);
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
