// The per-pixel online statistics (paper 003 Alg. 1) match a direct, two-pass
// computation over the very samples the renderer took, and over 1 … 10^4
// synthetic skewed samples (notes A.4 oracle 1), where merging partial
// accumulators (notes A.2 P0b) must give what sequential accumulation gives.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
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

// --stats-demodulated: the statistics are over each sample divided by the
// guarded diffuse albedo of its own primary hit (docs/protocol.md §7.7),
// computed here in two passes from the recorded samples and albedos; the
// radiance stays the undivided mean. Scene 1: a checkered floor, a mirror
// sphere (diffuse albedo 0: divided by 1) and the background.
TEST(RendererStatistics, DemodulatedStatisticsAreOverEachSampleOverItsAlbedo) {
  const std::unique_ptr<Scene> scene = build_scene(1);
  RenderSettings st = test::small_settings(48, 27, 8.0);
  st.gbuffer_grid = 0;  // the albedo channel is sample 0's own point albedo
  st.channels.statistics = true;
  st.channels.statistics_demodulated = true;
  st.channels.record_samples = true;
  const Camera cam = frame_camera(1, 0, st);
  const FrameBuffers fb = render_frame(*scene, cam, cam, 0, st);
  ASSERT_TRUE(fb.statistics_demodulated);
  ASSERT_EQ(fb.samples_stride, 8);
  const auto guard = [](double a) { return std::isfinite(a) && a >= double(1e-3f) ? a : 1.0; };
  int divided = 0, undivided = 0;
  for (int i = 0; i < st.width * st.height; ++i)
    for (int c = 0; c < 3; ++c) {
      const size_t k = 3 * size_t(i) + c;
      ASSERT_EQ(fb.sample_albedo[size_t(i) * 8 * 3 + c], fb.albedo[k]) << "sample 0's albedo, pixel " << i;
      std::vector<double> t;
      double raw = 0, radiance = 0;
      for (int s = 0; s < 8; ++s) {
        const size_t j = (size_t(i) * 8 + s) * 3 + c;
        const double a = fb.sample_albedo[j];
        const double x = std::max(0.0, double(fb.samples[j])) / guard(a);
        (guard(a) == 1.0 ? undivided : divided) += 1;
        t.push_back(2.0 * std::sqrt(x) - 2.0);
        raw += x / 8;
        radiance += fb.samples[j] / 8.0;
      }
      double mean = 0;
      for (double v : t) mean += v / 8;
      double m2 = 0, m3 = 0, abs3 = 0;
      for (double v : t) {
        m2 += (v - mean) * (v - mean);
        m3 += (v - mean) * (v - mean) * (v - mean);
        abs3 += std::fabs(v - mean) * (v - mean) * (v - mean);
      }
      ASSERT_NEAR(fb.stat_mean[k], mean, 1e-4 * (1 + std::fabs(mean))) << "pixel " << i << " channel " << c;
      ASSERT_NEAR(fb.stat_raw_mean[k], raw, 1e-4 * (1 + raw)) << "pixel " << i;
      ASSERT_NEAR(fb.stat_m2[k], m2, 1e-4 * (1 + m2)) << "pixel " << i;
      ASSERT_NEAR(fb.stat_m3[k], m3, 1e-4 * (1 + abs3)) << "pixel " << i;
      ASSERT_NEAR(fb.radiance[k], radiance, 1e-4 * (1 + radiance)) << "radiance is not demodulated, pixel " << i;
    }
  // Both kinds of sample occur: diffuse hits, and the mirror and the background.
  EXPECT_GT(divided, 1000);
  EXPECT_GT(undivided, 100);
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


// Samples from a fixed-seed mt19937 through transforms written here, so the
// values do not depend on the standard library's distribution implementations.
double uniform_open01(std::mt19937& rng) { return (double(rng()) + 0.5) / 4294967296.0; }

std::vector<float> exponential_samples(int count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<float> x;
  for (int i = 0; i < count; ++i) x.push_back(float(-std::log(uniform_open01(rng))));
  return x;
}

// exp(sigma z), z standard normal by Box-Muller: right-skewed, heavy tailed.
std::vector<float> lognormal_samples(int count, uint32_t seed, double sigma) {
  std::mt19937 rng(seed);
  std::vector<float> x;
  for (int i = 0; i < count; ++i) {
    const double r = std::sqrt(-2.0 * std::log(uniform_open01(rng)));
    x.push_back(float(std::exp(sigma * r * std::cos(2.0 * std::numbers::pi * uniform_open01(rng)))));
  }
  return x;
}

// Two-pass statistics of the first `count` samples in double, with the scales
// the relative errors are taken against: M3 is a signed sum that can nearly
// cancel, so its errors are relative to sum |d|^3, as in the test above.
struct TwoPass {
  double mean = 0, m2 = 0, m3 = 0, abs_mean = 0, abs3 = 0, raw_mean = 0;
};

TwoPass two_pass(const std::vector<float>& x, size_t count) {
  TwoPass r;
  for (size_t i = 0; i < count; ++i) {
    const double y = 2.0 * std::sqrt(std::max(0.0, double(x[i]))) - 2.0;
    r.mean += y / double(count);
    r.abs_mean += std::fabs(y) / double(count);
    r.raw_mean += x[i] / double(count);
  }
  for (size_t i = 0; i < count; ++i) {
    const double d = 2.0 * std::sqrt(std::max(0.0, double(x[i]))) - 2.0 - r.mean;
    r.m2 += d * d;
    r.m3 += d * d * d;
    r.abs3 += std::fabs(d) * d * d;
  }
  return r;
}

struct Errors {
  double mean, m2, m3, raw_mean;
  double worst() const { return std::max({mean, m2, m3, raw_mean}); }
};

// Relative errors of `s` against a two-pass reference of the same samples.
Errors relative_errors(const OnlineStats& s, const TwoPass& r) {
  const auto rel = [](double got, double want, double scale) {
    return scale > 0 ? std::fabs(got - want) / scale : std::fabs(got - want);
  };
  return {rel(s.mean, r.mean, r.abs_mean), rel(s.m2, r.m2, r.m2), rel(s.m3, r.m3, r.abs3),
          rel(s.raw_mean, r.raw_mean, r.raw_mean)};
}

// The bug the regression guard is for: M2 updated first, then the classical
// M3 formula, which expects the M2 of the previous n.
void add_with_swapped_m2_m3(OnlineStats& s, float x) {
  s.n += 1.0f;
  s.raw_mean += (x - s.raw_mean) / s.n;
  const float delta = box_cox_half(x) - s.mean;
  const float delta_n = delta / s.n;
  s.mean += delta_n;
  const float term = delta * delta_n * (s.n - 1.0f);
  s.m2 += term;
  s.m3 += term * delta_n * (s.n - 2.0f) - 3.0f * delta_n * s.m2;
}

constexpr double kOnlineTolerance = 1e-5;  // notes A.4 oracle 1 (fp32)
const size_t kCheckpoints[] = {1, 2, 3, 5, 10, 30, 100, 300, 1000, 3000, 10000};

struct SampleSet {
  const char* name;
  std::vector<float> x;
};
std::vector<SampleSet> sample_sets() {
  return {{"exponential", exponential_samples(10000, 1234u)}, {"lognormal", lognormal_samples(10000, 5678u, 1.0)}};
}

TEST(RendererStatistics, OnlineMatchesTwoPassUpTo10000Samples) {
  for (const SampleSet& set : sample_sets()) {
    OnlineStats s;
    size_t added = 0;
    for (size_t count : kCheckpoints) {
      while (added < count) s.add(set.x[added++]);
      ASSERT_EQ(s.n, float(count));
      const Errors e = relative_errors(s, two_pass(set.x, count));
      EXPECT_LE(e.worst(), kOnlineTolerance) << set.name << " n " << count << ": mean " << e.mean << " m2 " << e.m2
                                             << " m3 " << e.m3 << " raw " << e.raw_mean;
    }
  }
}

TEST(RendererStatistics, SwappedM2M3OrderFailsTwoPass) {
  // Regression guard: the check above catches the swapped update order.
  for (const SampleSet& set : sample_sets()) {
    OnlineStats s;
    size_t added = 0;
    for (size_t count : kCheckpoints) {
      while (added < count) add_with_swapped_m2_m3(s, set.x[added++]);
      if (count < 2) continue;  // one sample: both orders give M3 = 0
      const Errors e = relative_errors(s, two_pass(set.x, count));
      EXPECT_GT(e.m3, 10 * kOnlineTolerance) << set.name << " n " << count;
    }
  }
}

// Merges the accumulators of consecutive chunks of x, chunk by chunk.
OnlineStats merged_chunks(const std::vector<float>& x, const std::vector<size_t>& chunk_sizes) {
  OnlineStats total;
  size_t next = 0;
  for (size_t size : chunk_sizes) {
    OnlineStats part;
    for (size_t i = 0; i < size; ++i) part.add(x[next++]);
    total.merge(part);
  }
  return total;
}

TEST(RendererStatistics, MergeOfHalvesEqualsSequentialAdd) {
  for (const SampleSet& set : sample_sets()) {
    OnlineStats sequential;
    for (float v : set.x) sequential.add(v);
    const TwoPass reference = two_pass(set.x, set.x.size());
    // Halves, then uneven splits: one sample on either side, 3 : 9997, 7000 : 3000.
    for (size_t first : {size_t(5000), size_t(1), size_t(9999), size_t(3), size_t(7000)}) {
      const OnlineStats merged = merged_chunks(set.x, {first, set.x.size() - first});
      EXPECT_EQ(merged.n, sequential.n);
      const auto rel = [](double a, double b, double scale) { return std::fabs(a - b) / scale; };
      EXPECT_LE(rel(merged.mean, sequential.mean, reference.abs_mean), kOnlineTolerance) << set.name << " " << first;
      EXPECT_LE(rel(merged.m2, sequential.m2, reference.m2), kOnlineTolerance) << set.name << " " << first;
      EXPECT_LE(rel(merged.m3, sequential.m3, reference.abs3), kOnlineTolerance) << set.name << " " << first;
      EXPECT_LE(rel(merged.raw_mean, sequential.raw_mean, reference.raw_mean), kOnlineTolerance) << set.name;
      EXPECT_LE(relative_errors(merged, reference).worst(), kOnlineTolerance) << set.name << " " << first;
    }
  }
}

TEST(RendererStatistics, MergeOfPerFramePartialsMatchesTwoPass) {
  // Temporal accumulation: 625 frames of 16 samples, each frame's partial
  // merged into the history (notes A.5, temporal extension).
  for (const SampleSet& set : sample_sets()) {
    const OnlineStats merged = merged_chunks(set.x, std::vector<size_t>(625, 16));
    EXPECT_EQ(merged.n, 10000.0f);
    const Errors e = relative_errors(merged, two_pass(set.x, set.x.size()));
    EXPECT_LE(e.worst(), kOnlineTolerance) << set.name << ": mean " << e.mean << " m2 " << e.m2 << " m3 " << e.m3;
  }
}

TEST(RendererStatistics, MergeWithEmptyIsIdentity) {
  OnlineStats a;
  for (float v : lognormal_samples(37, 99u, 1.0)) a.add(v);
  const auto expect_same = [](const OnlineStats& got, const OnlineStats& want) {
    EXPECT_EQ(got.n, want.n);
    EXPECT_EQ(got.mean, want.mean);
    EXPECT_EQ(got.m2, want.m2);
    EXPECT_EQ(got.m3, want.m3);
    EXPECT_EQ(got.raw_mean, want.raw_mean);
  };
  OnlineStats left = a;
  left.merge(OnlineStats{});
  expect_same(left, a);
  OnlineStats right;
  right.merge(a);
  expect_same(right, a);
  OnlineStats none;
  none.merge(OnlineStats{});
  expect_same(none, OnlineStats{});  // no 0/0
}

}  // namespace
}  // namespace dn::render
