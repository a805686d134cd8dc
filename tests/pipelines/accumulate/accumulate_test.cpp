// accumulate on the device against the double-precision CPU reference, and
// its properties (constant input, convergence, reset, bad values, motion
// conventions, skipped downloads, concurrency).
#include <gtest/gtest.h>

#include <thread>

#include "accumulate_reference.hpp"
#include "frames.hpp"
#include "gpu_test_env.hpp"
#include "pipelines/pipeline.hpp"

namespace dn {
namespace {

using protocol::MotionConvention;
using test::ChannelId;
using test::Format;

class AccumulateTest : public test::GpuTest {};

// Encodes a scene frame for the device in the given formats and motion convention.
test::HostFrame host_frame(const test::SceneFrame& s, int w, int h, Format in, MotionConvention conv, uint32_t flags,
                           uint64_t index) {
  test::HostFrame f;
  f.info.frame_index = index;
  f.info.flags = flags;
  f.info.motion = conv;
  std::vector<float> mv = s.motion;
  for (size_t i = 0; i < mv.size(); ++i) {
    if (conv == MotionConvention::PixelsToNext) mv[i] = -mv[i];
    if (conv == MotionConvention::UvToPrevious) mv[i] /= static_cast<float>(i % 2 == 0 ? w : h);
  }
  f.add(ChannelId::Radiance, in, s.radiance);
  f.add(ChannelId::Normal, in, s.normal);
  f.add(ChannelId::Depth, in, s.depth);
  f.add(ChannelId::Motion, in, mv);
  return f;
}

// What the reference sees: exactly the decoded planes, motion converted in double precision.
test::ReferenceFrame reference_frame(const test::HostFrame& f, int w, int h) {
  test::ReferenceFrame r;
  r.radiance = test::decode_plane(f.plane(ChannelId::Radiance).bytes, f.plane(ChannelId::Radiance).format);
  r.normal = test::decode_plane(f.plane(ChannelId::Normal).bytes, f.plane(ChannelId::Normal).format);
  r.depth = test::decode_plane(f.plane(ChannelId::Depth).bytes, f.plane(ChannelId::Depth).format);
  r.motion = test::decode_plane(f.plane(ChannelId::Motion).bytes, f.plane(ChannelId::Motion).format);
  for (size_t i = 0; i < r.motion.size(); ++i) {
    if (f.info.motion == MotionConvention::PixelsToNext) r.motion[i] = -r.motion[i];
    if (f.info.motion == MotionConvention::UvToPrevious) r.motion[i] *= (i % 2 == 0 ? w : h);
  }
  r.reset = (f.info.flags & protocol::kFrameReset) != 0;
  return r;
}

std::vector<float> run(pipelines::Pipeline& p, const test::HostFrame& f, std::vector<pipelines::PassTiming>* timings = nullptr) {
  std::vector<uint8_t> out;
  std::vector<pipelines::PassTiming> t;
  test::process(p, f.view(), true, out, timings ? *timings : t);
  return out.empty() ? std::vector<float>{} : test::decode_output(out, Format::F32);
}

struct Variant {
  const char* name;
  int w, h;
  Format in, out;
  MotionConvention conv;
  std::vector<pipelines::ParameterValue> params;
};

void PrintTo(const Variant& v, std::ostream* os) { *os << v.name; }

class AccumulateReferenceTest : public AccumulateTest, public testing::WithParamInterface<Variant> {};

TEST_P(AccumulateReferenceTest, MatchesCpuReferenceOverFrames) {
  const Variant& v = GetParam();
  auto config = test::accumulate_config(v.w, v.h, v.in, v.out, v.params);
  ASSERT_FALSE(pipelines::validate(config).has_value());
  auto pipe = pipelines::create(ctx(), config);
  test::AccumulateParams params;
  for (const auto& p : v.params) {
    if (p.name == "alpha_min") params.alpha_min = p.value;
    if (p.name == "max_history") params.max_history = p.value;
    if (p.name == "depth_tolerance") params.depth_tolerance = p.value;
    if (p.name == "normal_threshold") params.normal_threshold = p.value;
  }
  test::AccumulateReference ref(v.w, v.h, params);
  test::PanningScene scene(v.w, v.h, 1234, 1.37f, -0.61f, 0.45f, 0.8f, 0.003);

  const int frames = 9;
  double worst = 0.0;
  for (int t = 0; t < frames; ++t) {
    SCOPED_TRACE(testing::Message() << "frame " << t);
    const uint32_t flags = t == 6 ? protocol::kFrameReset : 0u;
    const test::HostFrame f = host_frame(scene.frame(t), v.w, v.h, v.in, v.conv, flags, t);
    std::vector<uint8_t> bytes;
    std::vector<pipelines::PassTiming> timings;
    test::process(*pipe, f.view(), true, bytes, timings);
    ASSERT_EQ(bytes.size(), size_t(v.w) * v.h * 3 * protocol::bytes_per_component(v.out));
    const std::vector<float> got = test::decode_output(bytes, v.out);
    const std::vector<double> want = ref.step(reference_frame(f, v.w, v.h));
    for (float g : got) ASSERT_TRUE(std::isfinite(g) && g >= 0.0f) << g;
    const double rms = test::relative_rms(got, want);
    worst = std::max(worst, rms);
    EXPECT_LE(rms, 1e-3);
    // No pixel may disagree grossly (a different accept/reject decision).
    size_t gross = 0;
    for (size_t i = 0; i < want.size(); ++i)
      if (std::fabs(got[i] - want[i]) > 1e-2 * std::max(1.0, std::fabs(want[i]))) ++gross;
    EXPECT_EQ(gross, 0u);
  }
  RecordProperty("worst_relative_rms", std::to_string(worst));
  std::printf("[ info     ] %s: worst relative RMS over %d frames %.3g\n", v.name, frames, worst);
}

INSTANTIATE_TEST_SUITE_P(
    Variants, AccumulateReferenceTest,
    testing::Values(Variant{"fp32", 96, 64, Format::F32, Format::F32, MotionConvention::PixelsToPrevious, {}},
                    Variant{"fp16_in_out", 256, 144, Format::F16, Format::F16, MotionConvention::PixelsToPrevious, {}},
                    Variant{"fp16_in_next", 97, 61, Format::F16, Format::F32, MotionConvention::PixelsToNext, {}},
                    Variant{"uv_params", 80, 50, Format::F32, Format::F32, MotionConvention::UvToPrevious,
                            {{"alpha_min", 0.2}, {"max_history", 8}, {"depth_tolerance", 0.05},
                             {"normal_threshold", 0.5}}}),
    [](const testing::TestParamInfo<Variant>& info) { return std::string(info.param.name); });

// A static scene of constant radiance: every frame's output is that radiance.
TEST_F(AccumulateTest, ConstantInputStaysConstant) {
  const int w = 64, h = 48, n = w * h;
  auto pipe = pipelines::create(ctx(), test::accumulate_config(w, h));
  std::vector<float> radiance(3 * n), normal(3 * n), depth(n, 3.0f), motion(2 * n);
  for (int i = 0; i < n; ++i) {
    radiance[3 * i] = 0.25f;
    radiance[3 * i + 1] = 1.5f;
    radiance[3 * i + 2] = 3000.0f;
    normal[3 * i + 2] = 1.0f;
    motion[2 * i] = 0.3f * ((i * 7) % 5) - 0.6f;  // sub-pixel motion, constant colour: still constant
    motion[2 * i + 1] = 0.25f;
  }
  test::HostFrame f;
  f.add(ChannelId::Radiance, Format::F32, radiance);
  f.add(ChannelId::Normal, Format::F32, normal);
  f.add(ChannelId::Depth, Format::F32, depth);
  f.add(ChannelId::Motion, Format::F32, motion);
  for (int t = 0; t < 12; ++t) {
    const auto out = run(*pipe, f);
    for (int i = 0; i < 3 * n; ++i) ASSERT_NEAR(out[i], radiance[i], 1e-6 * radiance[i]) << "frame " << t << " element " << i;
  }
}

// Static scene, radiance = mean + uniform noise: the error of the output
// falls as 1/sqrt(n) while 1/n > alpha_min, then settles at the exponential
// average's sigma * sqrt(alpha / (2 - alpha)).
TEST_F(AccumulateTest, StaticNoisySceneConvergesToItsMean) {
  const int w = 64, h = 64, n = w * h;
  const float mean = 1.0f, half_width = 0.5f;
  const double sigma = half_width / std::sqrt(3.0);
  auto pipe = pipelines::create(ctx(), test::accumulate_config(w, h));
  std::mt19937 rng(99);
  std::uniform_real_distribution<float> noise(-half_width, half_width);
  std::vector<float> normal(3 * n), depth(n, 2.0f), motion(2 * n, 0.0f), radiance(3 * n);
  for (int i = 0; i < n; ++i) normal[3 * i + 2] = 1.0f;

  std::vector<double> rms;
  for (int t = 1; t <= 80; ++t) {
    for (auto& r : radiance) r = mean + noise(rng);
    test::HostFrame f;
    f.add(ChannelId::Radiance, Format::F32, radiance);
    f.add(ChannelId::Normal, Format::F32, normal);
    f.add(ChannelId::Depth, Format::F32, depth);
    f.add(ChannelId::Motion, Format::F32, motion);
    const auto out = run(*pipe, f);
    double sum = 0;
    for (float v : out) sum += (v - mean) * (v - mean);
    rms.push_back(std::sqrt(sum / out.size()));
  }
  for (int frames : {1, 2, 4, 8, 16}) {
    const double expected = sigma / std::sqrt(frames);
    EXPECT_NEAR(rms[frames - 1] / expected, 1.0, 0.05) << "after " << frames << " frames";
  }
  EXPECT_LT(rms[15], rms[3] * 0.55);
  const double alpha = 0.05;
  const double plateau = sigma * std::sqrt(alpha / (2 - alpha));
  EXPECT_NEAR(rms[79] / plateau, 1.0, 0.1);
}

// A still camera over a flat surface (normal +z, depth 2, no motion) showing `radiance`.
test::HostFrame still_frame(const std::vector<float>& radiance, uint32_t flags) {
  const size_t n = radiance.size() / 3;
  std::vector<float> normal(3 * n, 0.0f), depth(n, 2.0f), motion(2 * n, 0.0f);
  for (size_t i = 0; i < n; ++i) normal[3 * i + 2] = 1.0f;
  test::HostFrame f;
  f.info.flags = flags;
  f.add(ChannelId::Radiance, Format::F32, radiance);
  f.add(ChannelId::Normal, Format::F32, normal);
  f.add(ChannelId::Depth, Format::F32, depth);
  f.add(ChannelId::Motion, Format::F32, motion);
  return f;
}

TEST_F(AccumulateTest, ResetLeavesNoGhost) {
  const int w = 40, h = 30, n = w * h;
  auto pipe = pipelines::create(ctx(), test::accumulate_config(w, h));
  std::vector<float> a(3 * n, 5.0f), b(3 * n);
  for (int i = 0; i < 3 * n; ++i) b[i] = 0.01f * (i % 17);
  for (int t = 0; t < 10; ++t) run(*pipe, still_frame(a, 0));
  // Without reset the old colour would dominate; with it the output is exactly the new frame.
  auto out = run(*pipe, still_frame(b, protocol::kFrameReset));
  for (int i = 0; i < 3 * n; ++i) ASSERT_EQ(out[i], b[i]) << i;
  out = run(*pipe, still_frame(b, 0));
  for (int i = 0; i < 3 * n; ++i) ASSERT_NEAR(out[i], b[i], 1e-6) << i;
}

// RESULT.samples: every pixel of a still view rests on as many frames as were
// sent (up to max_history); a reset starts again from one.
TEST_F(AccumulateTest, SampleCountsAreTheHistoryLength) {
  const int w = 24, h = 12, n = w * h;
  auto pipe = pipelines::create(ctx(), test::accumulate_config(w, h, Format::F32, Format::F32, {{"max_history", 6}}));
  const std::vector<float> radiance(3 * n, 1.5f);
  auto frame = [&](uint32_t flags) { return still_frame(radiance, flags); };
  EXPECT_FALSE(pipe->samples()) << "a count before the first frame";
  for (uint32_t t = 1; t <= 9; ++t) {
    run(*pipe, frame(0));
    const auto s = pipe->samples();
    ASSERT_TRUE(s) << t;
    EXPECT_EQ(s->min, std::min(t, 6u)) << t;
    EXPECT_EQ(s->median, std::min(t, 6u)) << t;
  }
  run(*pipe, frame(protocol::kFrameReset));
  EXPECT_EQ(pipe->samples()->median, 1u);
}

TEST_F(AccumulateTest, BadValuesNeverReachOutputOrHistoryAndPixelsRecover) {
  const int w = 32, h = 16, n = w * h;
  auto pipe = pipelines::create(ctx(), test::accumulate_config(w, h));
  const float value = 2.0f;
  std::vector<float> normal(3 * n), depth(n, 2.0f), motion(2 * n, 0.0f), good(3 * n, value);
  for (int i = 0; i < n; ++i) normal[3 * i + 2] = 1.0f;
  auto frame = [&](const std::vector<float>& radiance, const std::vector<float>& nrm, const std::vector<float>& z,
                   const std::vector<float>& mv) {
    test::HostFrame f;
    f.add(ChannelId::Radiance, Format::F32, radiance);
    f.add(ChannelId::Normal, Format::F32, nrm);
    f.add(ChannelId::Depth, Format::F32, z);
    f.add(ChannelId::Motion, Format::F32, mv);
    return f;
  };
  for (int t = 0; t < 8; ++t) run(*pipe, frame(good, normal, depth, motion));

  std::vector<float> bad = good, bad_normal = normal, bad_depth = depth, bad_motion = motion;
  const float specials[] = {NAN, INFINITY, -INFINITY, -3.0f, -0.0f};
  for (int i = 0; i < 5; ++i) bad[3 * i + 1] = specials[i];   // pixels 0..4, green
  for (int k = 0; k < 3; ++k) bad[3 * 5 + k] = NAN;           // pixel 5, all components
  bad_normal[3 * 6] = NAN;                                     // pixel 6: bad normal
  bad_depth[7] = NAN;                                          // pixel 7: bad depth -> background
  bad_motion[2 * 8] = INFINITY;                                // pixel 8: bad motion
  auto out = run(*pipe, frame(bad, bad_normal, bad_depth, bad_motion));
  for (float v : out) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f) << v;
  EXPECT_EQ(out[3 * 7 + 1], value);  // background: passes the current radiance through
  EXPECT_EQ(out[3 * 6 + 1], value);  // history dropped for the bad normal: current value
  EXPECT_EQ(out[3 * 8 + 1], value);  // and for the bad motion
  // NaN, +Inf, -Inf, negative and -0 all count as a zero sample: darker, finite, all alike.
  EXPECT_LT(out[3 * 0 + 1], value);
  for (int i = 1; i < 5; ++i) EXPECT_EQ(out[3 * i + 1], out[3 * 0 + 1]) << "pixel " << i;
  for (int k = 0; k < 3; ++k) EXPECT_EQ(out[3 * 5 + k], out[3 * 0 + 1]) << "pixel 5 component " << k;
  EXPECT_EQ(out[3 * 9 + 1], value);  // a clean pixel is untouched

  // Recovery: good frames again; every pixel converges back to the value, monotonically.
  std::vector<float> previous = out;
  for (int t = 0; t < 40; ++t) {
    out = run(*pipe, frame(good, normal, depth, motion));
    for (int i = 0; i < 3 * n; ++i) {
      ASSERT_TRUE(std::isfinite(out[i])) << i;
      ASSERT_GE(out[i] + 1e-6f, previous[i]) << "pixel value " << i << " moved away from the input";
    }
    previous = out;
  }
  for (int i = 0; i < 3 * n; ++i) EXPECT_NEAR(out[i], value, 0.03 * value) << i;
}

TEST_F(AccumulateTest, BackgroundPixelsPassRadianceThrough) {
  const int w = 16, h = 8, n = w * h;
  auto pipe = pipelines::create(ctx(), test::accumulate_config(w, h));
  std::vector<float> normal(3 * n), depth(n), motion(2 * n, 0.0f), radiance(3 * n);
  for (int i = 0; i < n; ++i) {
    normal[3 * i + 2] = 1.0f;
    depth[i] = (i % 2) ? 0.0f : INFINITY;
  }
  for (int t = 0; t < 4; ++t) {
    for (int i = 0; i < 3 * n; ++i) radiance[i] = static_cast<float>(t + 1) * (1 + i % 3);
    test::HostFrame f;
    f.add(ChannelId::Radiance, Format::F32, radiance);
    f.add(ChannelId::Normal, Format::F32, normal);
    f.add(ChannelId::Depth, Format::F32, depth);
    f.add(ChannelId::Motion, Format::F32, motion);
    EXPECT_EQ(run(*pipe, f), radiance);
  }
}

TEST_F(AccumulateTest, MotionConventionsAgree) {
  const int w = 48, h = 32;
  std::vector<std::vector<float>> results;
  for (auto conv : {MotionConvention::PixelsToPrevious, MotionConvention::PixelsToNext, MotionConvention::UvToPrevious}) {
    auto pipe = pipelines::create(ctx(), test::accumulate_config(w, h));
    test::PanningScene scene(w, h, 5, 0.75f, 1.25f, 0.0f, 0.5f);
    std::vector<float> last;
    for (int t = 0; t < 5; ++t) last = run(*pipe, host_frame(scene.frame(t), w, h, Format::F32, conv, 0, t));
    results.push_back(last);
  }
  for (size_t r = 1; r < results.size(); ++r)
    for (size_t i = 0; i < results[0].size(); ++i) ASSERT_NEAR(results[r][i], results[0][i], 1e-4) << r << " " << i;
}

// accumulate is linear in radiance: scaling the input by k scales the output
// by k, from 1e-6 to 1e4 (DESIGN.md, scale equivariance), with no epsilon.
TEST_F(AccumulateTest, OutputScalesWithInput) {
  const int w = 48, h = 32;
  std::vector<std::vector<float>> base;
  for (double k : {1.0, 1e-6, 1e4}) {
    SCOPED_TRACE(k);
    auto pipe = pipelines::create(ctx(), test::accumulate_config(w, h));
    test::PanningScene scene(w, h, 8, 0.6f, -0.4f, 0.3f, 0.9f);
    for (int t = 0; t < 6; ++t) {
      test::SceneFrame s = scene.frame(t);
      for (auto& r : s.radiance) r = static_cast<float>(r * k);
      const auto out = run(*pipe, host_frame(s, w, h, Format::F32, MotionConvention::PixelsToPrevious, 0, t));
      if (k == 1.0) {
        base.push_back(out);
        continue;
      }
      for (size_t i = 0; i < out.size(); ++i)
        ASSERT_NEAR(out[i] / k, base[t][i], 1e-5 * std::max(1.0f, base[t][i])) << "frame " << t << " element " << i;
    }
  }
}

// want_output=false skips only the download: history advances the same.
TEST_F(AccumulateTest, SkippingOutputKeepsHistory) {
  const int w = 40, h = 24;
  auto a = pipelines::create(ctx(), test::accumulate_config(w, h));
  auto b = pipelines::create(ctx(), test::accumulate_config(w, h));
  test::PanningScene scene(w, h, 11, 0.5f, 0.0f, 0.2f, 0.7f);
  std::vector<float> last_a, last_b;
  for (int t = 0; t < 5; ++t) {
    const auto f = host_frame(scene.frame(t), w, h, Format::F32, MotionConvention::PixelsToPrevious, 0, t);
    last_a = run(*a, f);
    std::vector<uint8_t> out;
    std::vector<pipelines::PassTiming> timings;
    const bool want = t == 4;
    test::process(*b, f.view(), want, out, timings);
    EXPECT_EQ(out.empty(), !want);
    ASSERT_EQ(timings.size(), 4u);  // upload, accumulate, sample_summary, download
    if (!want) {
      EXPECT_EQ(timings[3].milliseconds, 0.0);
    }
    if (want) last_b = test::decode_output(out, Format::F32);
  }
  EXPECT_EQ(last_a, last_b);
}

TEST_F(AccumulateTest, TimingsNameUploadPassesAndDownload) {
  auto pipe = pipelines::create(ctx(), test::accumulate_config(32, 32));
  test::PanningScene scene(32, 32, 3, 1, 1, 0, 0.1f);
  std::vector<pipelines::PassTiming> timings;
  run(*pipe, host_frame(scene.frame(0), 32, 32, Format::F32, MotionConvention::PixelsToPrevious, 0, 0), &timings);
  ASSERT_EQ(timings.size(), 4u);
  EXPECT_EQ(timings[0].name, "upload");
  EXPECT_EQ(timings[1].name, "accumulate");
  EXPECT_EQ(timings[2].name, "sample_summary");
  EXPECT_EQ(timings[3].name, "download");
  for (const auto& t : timings) EXPECT_GE(t.milliseconds, 0.0) << t.name;
}

// Two sessions on two threads: same results as running them one after the other.
TEST_F(AccumulateTest, ConcurrentSessionsAreIndependent) {
  const int w = 64, h = 40;
  test::PanningScene scene_a(w, h, 21, 1.1f, 0.3f, 0.3f, 0.6f), scene_b(w, h, 22, -0.4f, 0.9f, 0.3f, 0.6f);
  std::vector<test::HostFrame> frames_a, frames_b;
  for (int t = 0; t < 6; ++t) {
    frames_a.push_back(host_frame(scene_a.frame(t), w, h, Format::F32, MotionConvention::PixelsToPrevious, 0, t));
    frames_b.push_back(host_frame(scene_b.frame(t), w, h, Format::F16, MotionConvention::PixelsToPrevious, 0, t));
  }
  auto sequential = [&](const std::vector<test::HostFrame>& frames, Format in) {
    auto p = pipelines::create(ctx(), test::accumulate_config(w, h, in));
    std::vector<float> last;
    for (const auto& f : frames) last = run(*p, f);
    return last;
  };
  const auto want_a = sequential(frames_a, Format::F32);
  const auto want_b = sequential(frames_b, Format::F16);
  std::vector<float> got_a, got_b;
  std::thread ta([&] { got_a = sequential(frames_a, Format::F32); });
  std::thread tb([&] { got_b = sequential(frames_b, Format::F16); });
  ta.join();
  tb.join();
  EXPECT_EQ(got_a, want_a);
  EXPECT_EQ(got_b, want_b);
}

}  // namespace
}  // namespace dn
