// The stat pipeline (paper 003) against its CPU reference (stat_reference.cpp)
// and the properties the paper and IMPLEMENTATION-NOTES A.4 name: identity
// and symmetry of membership, the t -> infinity limit, constant input,
// scale invariance of the membership, the n < 2 and non-finite guards.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>

#include "gpu_test_env.hpp"
#include "online_stats.hpp"
#include "pipelines/graph.hpp"
#include "pipelines/pipeline.hpp"
#include "pipelines/stat/student_t.hpp"
#include "stat_reference.hpp"
#include "stat_samples.hpp"
#include "svgf_inputs.hpp"

namespace dn {
namespace {

using test::ChannelId;
using test::Format;

class StatTest : public test::GpuTest {};

// A plane under a hard shadow edge that no G-buffer shows (lit 1.0 on the
// left, 0.2 on the right), albedo in blocks of 8 px, one normal; each pixel's
// `spp` samples are exponential around its true value (skewed, like path
// tracing), scaled by `scale`. Statistics as dnrender computes them; with
// `demodulated`, over each sample divided by its guarded albedo (dnrender
// --stats-demodulated), and some albedo components below the guard's 1e-3.
test::StatFrame shadow_frame(int w, int h, int spp, uint32_t seed, float scale = 1.0f, bool demodulated = false) {
  test::StatFrame f;
  f.width = w;
  f.height = h;
  const int n = w * h;
  f.radiance.resize(3 * n);
  f.albedo.resize(3 * n);
  f.normal.assign(3 * n, 0.0f);
  f.count.assign(n, static_cast<float>(spp));
  f.mean.resize(3 * n);
  f.m2.resize(3 * n);
  f.m3.resize(3 * n);
  std::mt19937 rng(seed);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int i = y * w + x;
      f.normal[3 * i + 2] = 1.0f;
      const float lit = x < w / 2 ? 1.0f : 0.2f;
      for (int c = 0; c < 3; ++c) {
        const int block = ((x / 8) * 3 + (y / 8) + c) % 4;
        float& albedo = f.albedo[3 * i + c];
        albedo = 0.3f + 0.1f * static_cast<float>(block);
        if (demodulated && (x / 8 + c) % 3 == 0) albedo = block % 2 ? 5e-4f : 2e-3f;  // either side of the guard
        const float divisor = demodulated ? static_cast<float>(test::guarded_albedo(albedo)) : 1.0f;
        test::put_exponential_samples(f, i, c, spp, scale * lit * albedo, divisor, rng);
      }
    }
  return f;
}

std::vector<pipelines::InputChannel> stat_channels(Format guides = Format::F32) {
  return {{ChannelId::Radiance, guides}, {ChannelId::Albedo, guides},   {ChannelId::Normal, guides},
          {ChannelId::StatCount, Format::F32}, {ChannelId::StatMean, Format::F32}, {ChannelId::StatM2, Format::F32},
          {ChannelId::StatM3, Format::F32}};
}

test::HostFrame host_frame(const test::StatFrame& f, Format guides = Format::F32) {
  test::HostFrame h;
  h.add(ChannelId::Radiance, guides, f.radiance);
  h.add(ChannelId::Albedo, guides, f.albedo);
  h.add(ChannelId::Normal, guides, f.normal);
  h.add(ChannelId::StatCount, Format::F32, f.count);
  h.add(ChannelId::StatMean, Format::F32, f.mean);
  h.add(ChannelId::StatM2, Format::F32, f.m2);
  h.add(ChannelId::StatM3, Format::F32, f.m3);
  return h;
}

// What the device saw when the guides went as fp16: the rounded values.
test::StatFrame rounded(test::StatFrame f, Format guides) {
  if (guides == Format::F16) {
    for (auto* v : {&f.radiance, &f.albedo, &f.normal}) *v = test::decode_output(test::encode_plane(*v, Format::F16), Format::F16);
  }
  return f;
}

std::vector<float> t_squared(double alpha) {
  std::vector<float> t = pipelines::student_t_table(alpha, 1024);
  for (float& v : t) v = v * v;
  return t;
}

std::unique_ptr<pipelines::Pipeline> make(gpu::Context& ctx, int w, int h, std::vector<pipelines::ParameterValue> params,
                                          Format guides = Format::F32, Format out = Format::F32) {
  auto config = test::make_config("stat", w, h, stat_channels(guides), out, std::move(params));
  EXPECT_FALSE(pipelines::validate(config).has_value());
  return pipelines::create(ctx, config);
}

// Paper 003's setting, which a session gets only by asking for it.
const std::vector<pipelines::ParameterValue> kPaper = {{"alpha", 0.005}, {"membership_falloff", 0}};

std::vector<pipelines::ParameterValue> with_paper(std::vector<pipelines::ParameterValue> params) {
  params.insert(params.end(), kPaper.begin(), kPaper.end());
  return params;
}

struct Variant {
  const char* name;
  int w, h;
  Format guides;
  std::vector<pipelines::ParameterValue> params;
  test::StatParams ref;
};

TEST_F(StatTest, MatchesCpuReference) {
  // A session without parameters: membership falloff 4 at alpha 0.05.
  test::StatParams defaults;
  defaults.alpha = 0.05;
  defaults.falloff = 4.0;
  test::StatParams r6;
  r6.radius = 6;
  r6.sigma_spatial = 3.0;
  test::StatParams asym = r6;
  asym.asymmetric = true;
  test::StatParams floor = r6;
  floor.variance_floor = 0.01;
  floor.alpha = 0.05;
  test::StatParams demodulated;
  demodulated.demodulated = true;
  test::StatParams demodulated_r6 = r6;
  demodulated_r6.demodulated = true;
  test::StatParams falloff;
  falloff.falloff = 2.0;
  test::StatParams falloff_asym = asym;
  falloff_asym.falloff = 0.5;
  const test::StatParams paper = test::StatParams::paper();
  test::StatParams paper_asym = paper;
  paper_asym.radius = 6;
  paper_asym.sigma_spatial = 3.0;
  paper_asym.asymmetric = true;
  const std::vector<pipelines::ParameterValue> p6 = {{"radius", 6}, {"sigma_spatial", 3}};
  const Variant variants[] = {
      {"defaults", 48, 32, Format::F32, {}, defaults},
      {"paper", 48, 32, Format::F32, kPaper, paper},
      {"paper_asymmetric_tiled", 64, 40, Format::F32,
       with_paper({{"radius", 6}, {"sigma_spatial", 3}, {"asymmetric", 1}}), paper_asym},
      {"radius6", 64, 40, Format::F32, p6, r6},
      {"asymmetric", 64, 40, Format::F32, {{"radius", 6}, {"sigma_spatial", 3}, {"asymmetric", 1}}, asym},
      {"floor_alpha_fp16", 61, 37, Format::F16,
       {{"radius", 6}, {"sigma_spatial", 3}, {"variance_floor", 0.01}, {"alpha", 0.05}}, floor},
      {"floor_alpha_fp16_even", 62, 38, Format::F16,
       {{"radius", 6}, {"sigma_spatial", 3}, {"variance_floor", 0.01}, {"alpha", 0.05}}, floor},
      {"demodulated", 48, 32, Format::F32, {{"demodulated", 1}}, demodulated},
      {"demodulated_tiled", 64, 40, Format::F32, {{"radius", 6}, {"sigma_spatial", 3}, {"demodulated", 1}},
       demodulated_r6},
      {"falloff", 47, 32, Format::F32, {{"membership_falloff", 2}}, falloff},
      {"falloff_asymmetric_tiled", 64, 40, Format::F32,
       {{"radius", 6}, {"sigma_spatial", 3}, {"asymmetric", 1}, {"membership_falloff", 0.5}}, falloff_asym},
  };
  for (const auto& v : variants) {
    SCOPED_TRACE(v.name);
    auto pipe = make(ctx(), v.w, v.h, v.params, v.guides, v.guides);
    auto* graph = dynamic_cast<pipelines::GraphPipeline*>(pipe.get());
    ASSERT_NE(graph, nullptr);
    graph->set_capture(true);
    // Radius <= 6 at an even width: the shared-memory tile (stat_filter_tiled).
    const bool tiled = v.ref.radius <= 6 && v.w % 2 == 0;
    for (const auto& pass : graph->spec().passes) {
      if (pass.name() == "stat_filter") {
        EXPECT_EQ(pass.shader(), tiled ? "stat_filter_tiled" : "stat_filter");
      }
    }
    const test::StatFrame f = shadow_frame(v.w, v.h, 8, 11, 1.0f, v.ref.demodulated);
    const auto got = svgf_inputs::run(*pipe, host_frame(f, v.guides), v.guides);
    const test::StatFrame seen = rounded(f, v.guides);
    const test::StatPrepared prep = test::stat_prepare(seen, v.ref);
    const auto theta = test::decode_output(graph->captured("stat_prepare", "stat_theta"), Format::F32);
    const auto variance = test::decode_output(graph->captured("stat_prepare", "stat_variance"), Format::F32);
    size_t theta_off = 0;
    for (int i = 0; i < v.w * v.h; ++i)
      for (int c = 0; c < 4; ++c) {
        const float want = prep.theta[4 * i + c];
        if (std::fabs(theta[4 * i + c] - want) > 1e-6f * (1.0f + std::fabs(want))) ++theta_off;
        if (c < 3 && std::fabs(variance[4 * i + c] - prep.variance[3 * i + c]) > 1e-6f * (1e-6f + prep.variance[3 * i + c]))
          ++theta_off;
      }
    EXPECT_EQ(theta_off, 0u) << "stat_prepare values off the reference";
    const test::StatResult want = test::stat_filter(seen, prep, v.ref, t_squared(v.ref.alpha));
    const double rms = test::relative_rms(got, want.output);
    size_t gross = 0;
    for (size_t k = 0; k < got.size(); ++k)
      if (std::fabs(got[k] - want.output[k]) > (v.guides == Format::F16 ? 2e-3 : 1e-4) * (1e-3 + std::fabs(want.output[k])))
        ++gross;
    long members = 0, rejected = 0;
    for (size_t i = 0; i < want.members.size(); ++i) members += want.members[i], rejected += want.rejected[i];
    std::printf("[ info     ] %s: relative RMS %.3g, %zu gross; reference members %ld, rejected %ld\n", v.name, rms,
                gross, members, rejected);
    EXPECT_LE(rms, v.guides == Format::F16 ? 1e-3 : 1e-5);
    EXPECT_EQ(gross, 0u) << "pixels that disagree (a different membership decision)";
    EXPECT_GT(rejected, 0) << "the test never rejected a tap: the frame does not exercise membership";
    EXPECT_GT(members, 0);
  }
}

// A fine texture (albedo uniform in [0.45, 0.55] per pixel and channel)
// under even light, 1024 exponential samples per pixel: statistics over
// radiance tell neighbours' albedos apart and the test rejects them, while
// demodulated statistics see one lighting, so every neighbour is a member
// and the result, remodulated by each pixel's albedo, keeps the texture
// (measured: RMSE 0.0017 against the input's 0.0157 and 0.0186 over radiance). The
// base weight ignores albedo here (sigma_albedo 10), so only the test differs;
// at the paper's setting, where every accepted neighbour counts fully (the
// defaults' falloff and alpha 0.05 give 0.0089 against 0.0149).
TEST_F(StatTest, DemodulatedStatisticsAverageAcrossTexture) {
  const int w = 40, h = 24, spp = 1024;
  auto frame = [&](bool demodulated) {
    test::StatFrame f;
    f.width = w;
    f.height = h;
    f.albedo.resize(3 * w * h);
    f.normal.assign(3 * w * h, 0.0f);
    f.count.assign(w * h, static_cast<float>(spp));
    for (auto* v : {&f.radiance, &f.mean, &f.m2, &f.m3}) v->resize(3 * w * h);
    std::mt19937 rng(17);  // the same samples for both
    for (int i = 0; i < w * h; ++i) {
      f.normal[3 * i + 2] = 1.0f;
      for (int c = 0; c < 3; ++c) {
        const float albedo = 0.45f + 0.1f * static_cast<float>((rng() + 0.5) / 4294967296.0);
        f.albedo[3 * i + c] = albedo;
        test::put_exponential_samples(f, i, c, spp, albedo, demodulated ? albedo : 1.0f, rng);
      }
    }
    return f;
  };
  const std::vector<pipelines::ParameterValue> base = with_paper({{"radius", 6}, {"sigma_spatial", 3}, {"sigma_albedo", 10}});
  std::vector<pipelines::ParameterValue> with = base;
  with.push_back({"demodulated", 1});
  const test::StatFrame plain_frame = frame(false), demodulated_frame = frame(true);
  const auto plain = svgf_inputs::run(*make(ctx(), w, h, base), host_frame(plain_frame));
  const auto demodulated = svgf_inputs::run(*make(ctx(), w, h, with), host_frame(demodulated_frame));
  // Error against the truth, albedo x 1, away from the border.
  auto rmse = [&](const std::vector<float>& v) {
    double sum = 0.0;
    int count = 0;
    for (int y = 6; y < h - 6; ++y)
      for (int x = 6; x < w - 6; ++x)
        for (int c = 0; c < 3; ++c) {
          const int k = 3 * (y * w + x) + c;
          sum += (v[k] - plain_frame.albedo[k]) * (v[k] - plain_frame.albedo[k]);
          ++count;
        }
    return std::sqrt(sum / count);
  };
  const double input = rmse(plain_frame.radiance), over_radiance = rmse(plain), over_demodulated = rmse(demodulated);
  std::printf("[ info     ] RMSE: input %.5f, statistics over radiance %.5f, demodulated %.5f\n", input, over_radiance,
              over_demodulated);
  // Over radiance the accepted neighbours' other albedos bias the result
  // (measured above the input's error); demodulated, only noise is left.
  EXPECT_LT(over_demodulated, 0.5 * input);
  EXPECT_LT(over_demodulated, 0.5 * over_radiance);
}

TEST_F(StatTest, ConstantInputIsReturnedExactly) {
  const int w = 40, h = 24;
  test::StatFrame f = shadow_frame(w, h, 4, 5);
  for (int i = 0; i < w * h; ++i)
    for (int c = 0; c < 3; ++c) {
      f.radiance[3 * i + c] = f.radiance[c];
      f.albedo[3 * i + c] = f.albedo[c];
      f.mean[3 * i + c] = f.mean[c];
      f.m2[3 * i + c] = f.m2[c];
      f.m3[3 * i + c] = f.m3[c];
    }
  auto pipe = make(ctx(), w, h, {});
  const auto got = svgf_inputs::run(*pipe, host_frame(f));
  for (size_t k = 0; k < got.size(); ++k) ASSERT_EQ(got[k], f.radiance[k]) << "component " << k;
}

// Paper 003's t -> infinity limit: with all-or-nothing membership, where
// the test accepts every tap (n = 2 per pixel: nu = 2, and alpha 1e-6 makes
// t about 707), the output is the base filter's: the reference with
// membership switched off.
TEST_F(StatTest, AcceptingEveryTapIsTheBaseFilter) {
  const int w = 48, h = 32;
  const test::StatFrame f = shadow_frame(w, h, 2, 9);
  test::StatParams p = test::StatParams::paper();
  p.alpha = 1e-6;
  p.radius = 6;
  p.sigma_spatial = 3.0;
  const test::StatPrepared prep = test::stat_prepare(f, p);
  const auto table = t_squared(p.alpha);
  const test::StatResult tested = test::stat_filter(f, prep, p, table);
  long rejected = 0;
  for (int r : tested.rejected) rejected += r;
  ASSERT_EQ(rejected, 0) << "the frame must be one where the test accepts every tap";
  p.base_only = true;
  const test::StatResult base = test::stat_filter(f, prep, p, table);
  auto pipe = make(ctx(), w, h, {{"alpha", 1e-6}, {"membership_falloff", 0}, {"radius", 6}, {"sigma_spatial", 3}});
  const auto got = svgf_inputs::run(*pipe, host_frame(f));
  EXPECT_LE(test::relative_rms(got, base.output), 1e-5);
  // membership 0 is that base filter on any frame (here one with rejections).
  const test::StatFrame edge = shadow_frame(w, h, 16, 4);
  p.alpha = 0.005;
  const test::StatResult edge_base = test::stat_filter(edge, test::stat_prepare(edge, p), p, t_squared(p.alpha));
  auto base_pipe = make(ctx(), w, h, {{"membership", 0}, {"radius", 6}, {"sigma_spatial", 3}});
  EXPECT_LE(test::relative_rms(svgf_inputs::run(*base_pipe, host_frame(edge)), edge_base.output), 1e-5);
}

// Samples times 4 (sqrt(4 x) = 2 sqrt(x) exactly): the Box-Cox differences
// and deviations scale by 2, so every membership decision stays and the
// output is 4x; also 1/16.
TEST_F(StatTest, ScalingTheSamplesKeepsMembership) {
  const int w = 48, h = 32;
  test::StatParams p;
  p.radius = 6;
  p.sigma_spatial = 3.0;
  const auto table = t_squared(p.alpha);
  const test::StatFrame base = shadow_frame(w, h, 8, 21);
  const test::StatResult want = test::stat_filter(base, test::stat_prepare(base, p), p, table);
  auto pipe = make(ctx(), w, h, {{"radius", 6}, {"sigma_spatial", 3}});
  const auto got = svgf_inputs::run(*pipe, host_frame(base));
  for (float scale : {4.0f, 1.0f / 16.0f}) {
    SCOPED_TRACE(testing::Message() << "scale " << scale);
    const test::StatFrame scaled = shadow_frame(w, h, 8, 21, scale);
    const test::StatResult s = test::stat_filter(scaled, test::stat_prepare(scaled, p), p, table);
    EXPECT_EQ(s.members, want.members) << "membership changed with the scale of the samples";
    auto pipe_s = make(ctx(), w, h, {{"radius", 6}, {"sigma_spatial", 3}});
    const auto got_s = svgf_inputs::run(*pipe_s, host_frame(scaled));
    std::vector<double> expected(got.begin(), got.end());
    for (double& e : expected) e *= scale;
    EXPECT_LE(test::relative_rms(got_s, expected), 1e-5);
  }
}

// Feature preservation (IMPLEMENTATION-NOTES A.4 9): a hard shadow edge on a
// plane of one albedo and one normal, which no guide shows, at 64 spp. The
// 10-90 % width of the column-averaged profile stays within a few pixels for
// stat and blurs to about the spatial sigma (10 px) for the base filter.
// Width: the pixels of the profile strictly between its 90 % and 10 %
// levels (a step: 0).
double edge_width(const std::vector<float>& out, int w, int h) {
  std::vector<double> profile(w, 0.0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) profile[x] += out[3 * (y * w + x) + 1] / h;
  const double hi = profile[2], lo = profile[w - 3], d = hi - lo;
  int between = 0;
  for (int x = 2; x < w - 2; ++x) between += profile[x] < hi - 0.1 * d && profile[x] > lo + 0.1 * d;
  return between;
}

TEST_F(StatTest, KeepsAShadowEdgeNoGuideShowsSharp) {
  const int w = 96, h = 24;
  test::StatFrame f = shadow_frame(w, h, 64, 31);
  // One albedo everywhere: only the samples tell the two sides apart.
  for (int i = 0; i < w * h; ++i) {
    const float lit = i % w < w / 2 ? 1.0f : 0.2f;
    std::mt19937 rng(static_cast<uint32_t>(i));
    for (int c = 0; c < 3; ++c) {
      f.albedo[3 * i + c] = 0.5f;
      render::OnlineStats s;
      for (int k = 0; k < 64; ++k) {
        const double u = (static_cast<double>(rng()) + 0.5) / 4294967296.0;
        s.add(static_cast<float>(-std::log(u)) * lit * 0.5f);
      }
      f.radiance[3 * i + c] = s.raw_mean;
      f.mean[3 * i + c] = s.mean;
      f.m2[3 * i + c] = s.m2;
      f.m3[3 * i + c] = s.m3;
    }
  }
  auto stat_pipe = make(ctx(), w, h, {});
  auto base_pipe = make(ctx(), w, h, {{"membership", 0}});
  const double stat = edge_width(svgf_inputs::run(*stat_pipe, host_frame(f)), w, h);
  const double base = edge_width(svgf_inputs::run(*base_pipe, host_frame(f)), w, h);
  const double input = edge_width(f.radiance, w, h);
  std::printf("[ info     ] edge width (pixels between the 10 %% and 90 %% levels): input %.0f px, stat %.0f px, base filter %.0f px\n", input, stat, base);
  EXPECT_LE(stat, 3.0);
  EXPECT_GE(base, 10.0);
}

// With equal n the symmetric test is symmetric bit for bit (property (c));
// p is always its own member.
TEST(StatReference, MembershipIsSymmetric) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> theta(-2.0f, 6.0f), var(0.0f, 0.05f);
  const float t2 = 2.8131f * 2.8131f;
  int accepted = 0;
  for (int k = 0; k < 200000; ++k) {
    const float a = theta(rng), b = k % 3 == 0 ? a + 0.01f * theta(rng) : theta(rng), va = var(rng), vb = var(rng);
    const bool ab = test::stat_member(a, b, t2, va, vb, false);
    ASSERT_EQ(ab, test::stat_member(b, a, t2, vb, va, false)) << a << " " << b << " " << va << " " << vb;
    accepted += ab;
    ASSERT_TRUE(test::stat_member(a, a, t2, va, va, false));
    ASSERT_TRUE(test::stat_member(a, a, t2, va, va, true));
  }
  EXPECT_GT(accepted, 1000);
  EXPECT_LT(accepted, 199000);
  // Zero variance: only exactly equal means pass, in both forms.
  EXPECT_TRUE(test::stat_member(1.5f, 1.5f, t2, 0.0f, 0.0f, true));
  EXPECT_FALSE(test::stat_member(1.5f, std::nextafter(1.5f, 2.0f), t2, 0.0f, 0.0f, false));
}

// n = 0 and non-finite statistics: the pixel keeps its own (sanitized) raw
// mean. n = 1: it gathers with the single-sample test (as the reference
// does). Neither is anybody's member, so changing its radiance changes no
// other pixel's output.
TEST_F(StatTest, PixelsWithoutStatisticsKeepTheirOwnValue) {
  const int w = 40, h = 24;
  test::StatFrame f = shadow_frame(w, h, 8, 13);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const int one = 5 * w + 7, none = 10 * w + 30, bad = 15 * w + 12, inf_radiance = 3 * w + 33;
  f.count[one] = 1.0f;
  f.count[none] = 0.0f;
  f.m2[3 * bad + 1] = nan;
  f.radiance[3 * inf_radiance] = std::numeric_limits<float>::infinity();
  auto pipe = make(ctx(), w, h, {{"radius", 6}, {"sigma_spatial", 3}});
  const auto got = svgf_inputs::run(*pipe, host_frame(f));
  for (int i : {none, bad})
    for (int c = 0; c < 3; ++c) EXPECT_EQ(got[3 * i + c], f.radiance[3 * i + c]) << "pixel " << i;
  test::StatParams p;
  p.radius = 6;
  p.sigma_spatial = 3.0;
  const test::StatResult want = test::stat_filter(f, test::stat_prepare(f, p), p, t_squared(p.alpha));
  EXPECT_GT(want.members[one], 0) << "the single-sample test must accept some neighbours here";
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(got[3 * one + c], want.output[3 * one + c], 1e-5 * std::fabs(want.output[3 * one + c]));
  for (float v : got) ASSERT_TRUE(std::isfinite(v));
  test::StatFrame changed = f;
  for (int i : {one, none, bad})
    for (int c = 0; c < 3; ++c) changed.radiance[3 * i + c] = 1e6f;
  auto pipe2 = make(ctx(), w, h, {{"radius", 6}, {"sigma_spatial", 3}});
  const auto got2 = svgf_inputs::run(*pipe2, host_frame(changed));
  for (int i = 0; i < w * h; ++i) {
    if (i == one || i == none || i == bad) continue;
    for (int c = 0; c < 3; ++c) ASSERT_EQ(got2[3 * i + c], got[3 * i + c]) << "pixel " << i;
  }
}

// Non-finite guides (a renderer's NaN albedo on the background, an
// infinite one, a NaN normal) never reach the output, with statistics over
// radiance or demodulated.
TEST_F(StatTest, NonFiniteGuidesNeverReachTheOutput) {
  const int w = 40, h = 24;
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (bool demodulated : {false, true}) {
    SCOPED_TRACE(demodulated ? "demodulated" : "over radiance");
    test::StatFrame f = shadow_frame(w, h, 8, 19, 1.0f, demodulated);
    f.albedo[3 * (4 * w + 9)] = nan;
    f.albedo[3 * (12 * w + 20) + 1] = inf;
    f.albedo[3 * (20 * w + 30) + 2] = -inf;
    f.normal[3 * (8 * w + 14) + 2] = nan;
    for (const auto& params : {std::vector<pipelines::ParameterValue>{{"demodulated", demodulated ? 1.0 : 0.0}},
                               std::vector<pipelines::ParameterValue>{{"radius", 6}, {"sigma_spatial", 3},
                                                                {"demodulated", demodulated ? 1.0 : 0.0}}}) {
      const auto got = svgf_inputs::run(*make(ctx(), w, h, params), host_frame(f));
      size_t bad = 0;
      for (float v : got) bad += !std::isfinite(v);
      EXPECT_EQ(bad, 0u) << "non-finite output components";
    }
  }
}

// What a session without parameters runs with, for stat and stat-temporal
// (the WELCOME listing and the values resolved for the constants block):
// membership falloff 4 at alpha 0.05; the paper's values are one request away.
TEST(StatParameters, SessionsWithoutParametersGetFalloff4AtAlpha005) {
  for (const char* name : {"stat", "stat-temporal"}) {
    SCOPED_TRACE(name);
    const pipelines::PipelineDescription* description = nullptr;
    for (const auto& d : pipelines::available_pipelines())
      if (d.name == name) description = &d;
    ASSERT_NE(description, nullptr);
    auto value_of = [&](const std::vector<float>& values, const std::string& parameter) {
      for (size_t i = 0; i < description->parameters.size(); ++i)
        if (description->parameters[i].name == parameter) return values.at(i);
      ADD_FAILURE() << "no parameter " << parameter;
      return -1.0f;
    };
    std::vector<float> listed;
    for (const auto& p : description->parameters) listed.push_back(static_cast<float>(p.default_value));
    EXPECT_EQ(value_of(listed, "alpha"), 0.05f);
    EXPECT_EQ(value_of(listed, "membership_falloff"), 4.0f);
    const auto resolved = pipelines::resolve_parameters(name, {});
    EXPECT_EQ(value_of(resolved, "alpha"), 0.05f);
    EXPECT_EQ(value_of(resolved, "membership_falloff"), 4.0f);
    const auto paper = pipelines::resolve_parameters(name, kPaper);
    EXPECT_EQ(value_of(paper, "alpha"), 0.005f);
    EXPECT_EQ(value_of(paper, "membership_falloff"), 0.0f);
  }
  auto config = test::make_config("stat", 16, 16, stat_channels(), Format::F32, kPaper);
  EXPECT_FALSE(pipelines::validate(config).has_value()) << "the paper's values must be accepted";
}

TEST(StatValidate, StatisticsOnlyInFp32) {
  for (ChannelId id : {ChannelId::StatCount, ChannelId::StatMean, ChannelId::StatM2, ChannelId::StatM3}) {
    auto channels = stat_channels();
    for (auto& c : channels)
      if (c.id == id) c.format = Format::F16;
    const auto err = pipelines::validate(test::make_config("stat", 16, 16, channels));
    ASSERT_TRUE(err.has_value());
    EXPECT_EQ(err->problem, pipelines::ConfigProblem::InvalidChannel);
    EXPECT_NE(err->message.find(protocol::find_channel(id)->name), std::string::npos) << err->message;
  }
  auto missing = stat_channels();
  missing.pop_back();
  const auto err = pipelines::validate(test::make_config("stat", 16, 16, missing));
  ASSERT_TRUE(err.has_value());
  EXPECT_EQ(err->problem, pipelines::ConfigProblem::MissingChannel);
}

}  // namespace
}  // namespace dn
