// The per-pixel online statistics (paper 003 Alg. 1) match a direct, two-pass
// computation over the very samples the renderer took.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "online_stats.hpp"
#include "scenes.hpp"
#include "test_support.hpp"

namespace dn::render {
namespace {

TEST(RendererStatistics, OnlineMomentsMatchDirectComputation) {
  const std::unique_ptr<Scene> scene = build_scene(4);  // fireflies: skewed samples
  RenderSettings st = test::small_settings(32, 18, 8.0);
  st.channels.statistics = true;
  st.channels.record_samples = true;
  const Camera cam = frame_camera(4, 0, st);
  const FrameBuffers fb = render_frame(*scene, cam, cam, 0, st);
  ASSERT_EQ(fb.samples_stride, 8);
  int skewed = 0;
  for (int i = 0; i < st.width * st.height; ++i) {
    ASSERT_EQ(fb.stat_count[i], 8.0f);
    for (int c = 0; c < 3; ++c) {
      std::vector<double> x, t;
      for (int s = 0; s < 8; ++s) {
        x.push_back(fb.samples[(size_t(i) * 8 + s) * 3 + c]);
        t.push_back(2.0 * std::sqrt(std::max(0.0, x.back())) - 2.0);
      }
      double mean = 0, raw = 0;
      for (int s = 0; s < 8; ++s) mean += t[s] / 8, raw += x[s] / 8;
      double m2 = 0, m3 = 0, abs3 = 0;
      for (double v : t) {
        m2 += (v - mean) * (v - mean);
        m3 += (v - mean) * (v - mean) * (v - mean);
        abs3 += std::fabs(v - mean) * (v - mean) * (v - mean);
      }
      const size_t k = 3 * size_t(i) + c;
      ASSERT_NEAR(fb.stat_mean[k], mean, 1e-4 * (1 + std::fabs(mean))) << "pixel " << i << " channel " << c;
      ASSERT_NEAR(fb.stat_raw_mean[k], raw, 1e-4 * (1 + raw)) << "pixel " << i;
      ASSERT_NEAR(fb.stat_m2[k], m2, 1e-4 * (1 + m2)) << "pixel " << i;
      ASSERT_NEAR(fb.stat_m3[k], m3, 1e-4 * (1 + std::fabs(abs3))) << "pixel " << i;
      // The raw mean is the radiance itself.
      ASSERT_NEAR(fb.radiance[k], raw, 1e-4 * (1 + raw));
      skewed += std::fabs(m3) > 0.1;
    }
  }
  EXPECT_GT(skewed, 10);  // the check saw non-trivial third moments
}

TEST(RendererStatistics, TwoSamplesHaveNoThirdMoment) {
  OnlineStats s;
  s.add(0.0f);
  s.add(4.0f);  // transformed: -2 and 2
  EXPECT_FLOAT_EQ(s.mean, 0.0f);
  EXPECT_FLOAT_EQ(s.m2, 8.0f);
  EXPECT_NEAR(s.m3, 0.0f, 1e-6f);
  EXPECT_FLOAT_EQ(s.raw_mean, 2.0f);
}

}  // namespace
}  // namespace dn::render
