// Guide-ray supersampling (paper 001 §5; docs/pipelines.md "Extra samples"):
// the device's assignment, mixing and resolve against a host
// implementation of the documented rules; extra samples that repeat the guide
// change nothing; at a sub-pixel edge between two surfaces the resolved
// pixel shows both in proportion to its samples; the session rules.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

#include "gpu_test_env.hpp"
#include "pipelines/graph.hpp"
#include "pipelines/pipeline.hpp"
#include "svgf_inputs.hpp"

namespace dn {
namespace {

using protocol::ChannelId;
using protocol::Format;
using protocol::SampleField;
using protocol::sample_channel;
using svgf_inputs::run;

class SupersampleTest : public test::GpuTest {};

// One frame: the guides (sample 0) and n extra samples, radiance mode.
struct SsFrame {
  int w = 0, h = 0, n = 0;
  Format format = Format::F32;  // of every plane
  std::vector<float> radiance, albedo, normal, depth, motion;
  struct Sample {
    std::vector<float> radiance, normal, depth, offset;
  };
  std::vector<Sample> samples;

  SsFrame(int w_, int h_, int n_) : w(w_), h(h_), n(n_) {
    const int px = w * h;
    radiance.assign(3 * px, 0.0f);
    albedo.assign(3 * px, 1.0f);
    normal.assign(3 * px, 0.0f);
    depth.assign(px, 5.0f);
    motion.assign(2 * px, 0.0f);
    samples.resize(n);
    for (auto& s : samples) {
      s.radiance.assign(3 * px, 0.0f);
      s.normal.assign(3 * px, 0.0f);
      s.depth.assign(px, 5.0f);
      s.offset.assign(2 * px, 0.0f);
    }
  }
  std::vector<pipelines::InputChannel> channels(bool with_samples) const {
    std::vector<pipelines::InputChannel> c = {{ChannelId::Radiance, format}, {ChannelId::Albedo, format},
                                            {ChannelId::Normal, format},   {ChannelId::Depth, format},
                                            {ChannelId::Motion, format}};
    for (int j = 1; with_samples && j <= n; ++j)
      for (SampleField f : {SampleField::Radiance, SampleField::Normal, SampleField::Depth, SampleField::Offset})
        c.push_back({sample_channel(j, f), format});
    return c;
  }
  test::HostFrame host(bool with_samples, uint32_t flags) const {
    test::HostFrame f;
    f.info.flags = flags;
    f.add(ChannelId::Radiance, format, radiance);
    f.add(ChannelId::Albedo, format, albedo);
    f.add(ChannelId::Normal, format, normal);
    f.add(ChannelId::Depth, format, depth);
    f.add(ChannelId::Motion, format, motion);
    for (int j = 1; with_samples && j <= n; ++j) {
      const Sample& s = samples[j - 1];
      f.add(sample_channel(j, SampleField::Radiance), format, s.radiance);
      f.add(sample_channel(j, SampleField::Normal), format, s.normal);
      f.add(sample_channel(j, SampleField::Depth), format, s.depth);
      f.add(sample_channel(j, SampleField::Offset), format, s.offset);
    }
    return f;
  }
};

// The documented assignment (server/pipelines/stages/supersample_assign.comp) in double precision:
// the guide offset code of sample s of pixel p, and the margin between the
// best and the second-best score (decisions closer than that may round
// either way on the device).
int host_assign(const SsFrame& f, int p, const SsFrame::Sample& s, double& margin) {
  const int x = p % f.w, y = p / f.w;
  const double ox = std::clamp<double>(s.offset[2 * p], -0.5, 0.5), oy = std::clamp<double>(s.offset[2 * p + 1], -0.5, 0.5);
  const double sx = x + 0.5 + ox, sy = y + 0.5 + oy;
  const int bx = static_cast<int>(std::floor(sx - 0.5)), by = static_cast<int>(std::floor(sy - 0.5));
  const double z = s.depth[p];
  const bool fg = std::isfinite(z) && z > 0.0;
  double best = 0.0, second = 0.0;
  int pick_x = x, pick_y = y;
  for (int k = 0; k < 4; ++k) {
    const int gx = bx + (k & 1), gy = by + (k >> 1);
    if (gx < 0 || gy < 0 || gx >= f.w || gy >= f.h) continue;
    const int g = gy * f.w + gx;
    const double zg = f.depth[g];
    const bool gfg = std::isfinite(zg) && zg > 0.0;
    double w;
    if (!fg || !gfg) {
      w = fg == gfg ? 1.0 : 0.0;
    } else {
      double c = 0.0;
      for (int i = 0; i < 3; ++i) c += double(s.normal[3 * p + i]) * f.normal[3 * g + i];
      w = std::exp(-std::fabs(z - zg) / (0.01 * std::max(z, zg))) * std::pow(std::max(c, 0.0), 128.0);
    }
    w *= (1.0 - std::fabs(sx - (gx + 0.5))) * (1.0 - std::fabs(sy - (gy + 0.5)));
    if (w > best) {
      second = best;
      best = w;
      pick_x = gx;
      pick_y = gy;
    } else {
      second = std::max(second, w);
    }
  }
  margin = best - second;
  return (pick_x - x + 1) + 3 * (pick_y - y + 1);
}

// A frame of two surfaces (a near plane left of a slanted edge, a far one
// right of it), noisy radiance, samples at random offsets.
SsFrame random_frame(int w, int h, int n, uint32_t seed) {
  SsFrame f(w, h, n);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  auto surface = [&](double x, double y, float& z, float* nrm) {
    const bool near = x < 0.45 * w + 0.2 * y;
    z = near ? 4.0f + 0.01f * static_cast<float>(y) : 9.0f;
    nrm[0] = near ? 0.0f : 0.6f;
    nrm[1] = 0.0f;
    nrm[2] = near ? 1.0f : 0.8f;
  };
  for (int p = 0; p < w * h; ++p) {
    const int x = p % w, y = p / w;
    surface(x + 0.5, y + 0.5, f.depth[p], &f.normal[3 * p]);
    for (int k = 0; k < 3; ++k) f.radiance[3 * p + k] = u(rng) * 2.0f;
    for (auto& s : f.samples) {
      s.offset[2 * p] = u(rng) - 0.5f;
      s.offset[2 * p + 1] = u(rng) - 0.5f;
      surface(x + 0.5 + s.offset[2 * p], y + 0.5 + s.offset[2 * p + 1], s.depth[p], &s.normal[3 * p]);
      for (int k = 0; k < 3; ++k) s.radiance[3 * p + k] = u(rng) * 2.0f;
    }
  }
  // Hard cases: a NaN offset (the sample takes no part), a NaN radiance
  // (mixed as 0), a background sample, a sample off the image's edge.
  f.samples[0].offset[2 * 5] = std::nanf("");
  f.samples[0].radiance[3 * 7] = std::nanf("");
  f.samples[n - 1].depth[w + 3] = 0.0f;
  f.samples[0].offset[0] = -0.5f;
  f.samples[0].offset[1] = -0.5f;
  return f;
}

TEST_F(SupersampleTest, AssignMixAndResolveFollowTheDocumentedRules) {
  const int w = 64, h = 40, n = 3;
  const SsFrame f = random_frame(w, h, n, 7);
  auto pipe = pipelines::create(ctx(), test::make_config("svgf", w, h, f.channels(true)));
  auto* graph = dynamic_cast<pipelines::GraphPipeline*>(pipe.get());
  ASSERT_NE(graph, nullptr);
  graph->set_capture(true);
  const auto out = run(*pipe, f.host(true, protocol::kFrameReset));
  auto words = [](const std::vector<uint8_t>& b) {
    std::vector<uint32_t> v(b.size() / 4);
    std::memcpy(v.data(), b.data(), v.size() * 4);
    return v;
  };
  auto floats = [](const std::vector<uint8_t>& b) {
    std::vector<float> v(b.size() / 4);
    std::memcpy(v.data(), b.data(), v.size() * 4);
    return v;
  };
  const auto assignment = words(graph->captured("supersample_assign", "supersample_assignment"));
  ASSERT_GE(assignment.size(), static_cast<size_t>(w * h));

  // Assignment: equal wherever the host's best score leads by more than 1e-4
  // or ties exactly (equal inputs give equal scores: the first candidate).
  int decided = 0, mismatched = 0, unused = 0;
  for (int p = 0; p < w * h; ++p)
    for (int j = 1; j <= n; ++j) {
      const uint32_t code = (assignment[p] >> (4 * (j - 1))) & 15u;
      const auto& s = f.samples[j - 1];
      if (!std::isfinite(s.offset[2 * p]) || !std::isfinite(s.offset[2 * p + 1])) {
        EXPECT_EQ(code, 15u) << "pixel " << p << " sample " << j << ": a NaN offset takes no part";
        ++unused;
        continue;
      }
      double margin = 0.0;
      const int want = host_assign(f, p, s, margin);
      if (margin > 1e-4 || margin == 0.0) {
        ++decided;
        if (static_cast<int>(code) != want) ++mismatched;
      }
    }
  EXPECT_EQ(mismatched, 0) << "of " << decided << " clear decisions";
  EXPECT_GT(decided, w * h * n * 9 / 10);
  EXPECT_EQ(unused, 1);

  // Mix (Eq. 7) with the device's assignment: mean of the guide's sample and
  // those assigned to it, NaN as 0.
  const auto mixed = floats(graph->captured("supersample_mix", "supersample_mixed_radiance"));
  std::vector<double> sum(3 * w * h), count(w * h, 1.0);
  auto clean = [](float v) { return std::isfinite(v) ? std::max(0.0, double(v)) : 0.0; };
  for (int p = 0; p < w * h; ++p)
    for (int k = 0; k < 3; ++k) sum[3 * p + k] += clean(f.radiance[3 * p + k]);
  for (int p = 0; p < w * h; ++p)
    for (int j = 1; j <= n; ++j) {
      const uint32_t code = (assignment[p] >> (4 * (j - 1))) & 15u;
      if (code == 15u) continue;
      const int gx = p % w + static_cast<int>(code % 3) - 1, gy = p / w + static_cast<int>(code / 3) - 1;
      ASSERT_TRUE(gx >= 0 && gy >= 0 && gx < w && gy < h) << "pixel " << p << " assigned outside the image";
      const int g = gy * w + gx;
      for (int k = 0; k < 3; ++k) sum[3 * g + k] += clean(f.samples[j - 1].radiance[3 * p + k]);
      count[g] += 1.0;
    }
  double worst = 0.0;
  for (int i = 0; i < 3 * w * h; ++i) worst = std::max(worst, std::fabs(mixed[i] - sum[i] / count[i / 3]));
  EXPECT_LE(worst, 1e-5) << "mixed signal against the host's Eq. 7";

  // Resolve: the mean of the pixel's displayed colour and its samples' guides'.
  // The displayed frame as the final TAA blend (taa_static_alpha) writes it.
  const auto display = floats(graph->captured("svgf_taa", "supersample_display"));
  double worst_resolve = 0.0;
  for (int p = 0; p < w * h; ++p) {
    double r[3] = {display[3 * p], display[3 * p + 1], display[3 * p + 2]}, c = 1.0;
    for (int j = 1; j <= n; ++j) {
      const uint32_t code = (assignment[p] >> (4 * (j - 1))) & 15u;
      if (code == 15u) continue;
      const int g = (p / w + static_cast<int>(code / 3) - 1) * w + p % w + static_cast<int>(code % 3) - 1;
      for (int k = 0; k < 3; ++k) r[k] += display[3 * g + k];
      c += 1.0;
    }
    for (int k = 0; k < 3; ++k)
      worst_resolve = std::max(worst_resolve, std::fabs(out[3 * p + k] - r[k] / c) / std::max(1.0, r[k] / c));
  }
  EXPECT_LE(worst_resolve, 1e-5) << "output against the host's resolve of the displayed frame";
  std::printf("[ info     ] %d clear assignments, all equal; mix within %.2g, resolve within %.2g\n", decided, worst,
              worst_resolve);
}

// Extra samples that repeat the guide (offset 0, same hit, same radiance)
// leave every output as the session without them gives it, with fp32 and
// with fp16 planes.
TEST_F(SupersampleTest, SamplesThatRepeatTheGuideChangeNothing) {
  const int w = 48, h = 32, n = 3;
  for (Format format : {Format::F32, Format::F16}) {
    SsFrame shape(w, h, n);
    shape.format = format;
    auto with = pipelines::create(ctx(), test::make_config("svgf", w, h, shape.channels(true)));
    auto without = pipelines::create(ctx(), test::make_config("svgf", w, h, shape.channels(false)));
    double worst = 0.0;
    for (int t = 0; t < 4; ++t) {
      SsFrame f = random_frame(w, h, n, 100 + t);
      f.format = format;
      for (int p = 0; p < w * h; ++p) f.motion[2 * p] = -1.0f;  // a pan: history is reprojected
      for (auto& s : f.samples) {
        s.radiance = f.radiance;
        s.normal = f.normal;
        s.depth = f.depth;
        std::fill(s.offset.begin(), s.offset.end(), 0.0f);
      }
      const uint32_t flags = t == 0 ? protocol::kFrameReset : 0u;
      const auto a = run(*with, f.host(true, flags)), b = run(*without, f.host(false, flags));
      worst = std::max(worst, test::relative_rms(a, std::vector<double>(b.begin(), b.end())));
    }
    std::printf("[ info     ] guide-repeating samples, %s planes: worst relative RMS %.2g over 4 frames\n",
                format == Format::F16 ? "fp16" : "fp32", worst);
    EXPECT_LE(worst, 1e-5);
  }
}

// A sub-pixel edge between a near bright surface and a far dark one: the
// guide through the pixel centre sees one side, its samples see both, and the
// resolved pixel shows each side in proportion to its samples (0.5 here:
// two samples on each side), where one sample per pixel gives a hard step.
TEST_F(SupersampleTest, SubPixelEdgeIsResolvedInProportion) {
  const int w = 32, h = 16, n = 3, edge_pixel = 15;
  const double edge_x = edge_pixel + 0.6;  // the guide of pixel 15 (x 15.5) is left of it
  const float bright = 1.0f, dark = 0.1f;
  SsFrame f(w, h, n);
  const float offsets[4][2] = {{0.0f, 0.0f}, {0.3f, -0.25f}, {-0.3f, 0.25f}, {0.3f, 0.25f}};
  auto put = [&](double x, std::vector<float>& rad, std::vector<float>& nrm, std::vector<float>& z, int p) {
    const bool near = x < edge_x;
    for (int k = 0; k < 3; ++k) rad[3 * p + k] = near ? bright : dark;
    nrm[3 * p + 2] = 1.0f;
    z[p] = near ? 3.0f : 8.0f;
  };
  for (int p = 0; p < w * h; ++p) {
    const int x = p % w;
    put(x + 0.5, f.radiance, f.normal, f.depth, p);
    for (int j = 1; j <= n; ++j) {
      auto& s = f.samples[j - 1];
      s.offset[2 * p] = offsets[j][0];
      s.offset[2 * p + 1] = offsets[j][1];
      put(x + 0.5 + offsets[j][0], s.radiance, s.normal, s.depth, p);
    }
  }
  // Still frames: the history converges to the noiseless values.
  auto with = pipelines::create(ctx(), test::make_config("svgf", w, h, f.channels(true)));
  auto without = pipelines::create(ctx(), test::make_config("svgf", w, h, f.channels(false)));
  std::vector<float> a, b;
  for (int t = 0; t < 3; ++t) {
    a = run(*with, f.host(true, t == 0 ? protocol::kFrameReset : 0u));
    b = run(*without, f.host(false, t == 0 ? protocol::kFrameReset : 0u));
  }
  const int p = (h / 2) * w + edge_pixel;
  // Samples 0 and 2 (x 15.5, 15.2) on the bright side, 1 and 3 (15.8) on the dark one.
  const double want = 0.5 * (bright + dark);
  std::printf("[ info     ] edge pixel: 1 spp %.3f, 4 spp %.3f (coverage %.3f)\n", b[3 * p], a[3 * p], want);
  EXPECT_NEAR(a[3 * p], want, 0.02 * want);
  EXPECT_NEAR(b[3 * p], bright, 0.02 * bright);
  // Away from the edge nothing changes.
  for (int x : {4, 27}) EXPECT_NEAR(a[3 * ((h / 2) * w + x)], b[3 * ((h / 2) * w + x)], 1e-5);
}

TEST(SupersampleValidate, SessionRules) {
  const SsFrame f(16, 16, 2);
  auto expect = [](pipelines::SessionConfig c, pipelines::ConfigProblem code, const std::string& text) {
    const auto err = pipelines::validate(c);
    ASSERT_TRUE(err.has_value()) << text;
    EXPECT_EQ(err->problem, code) << err->message;
    EXPECT_NE(err->message.find(text), std::string::npos) << err->message;
  };
  EXPECT_FALSE(pipelines::validate(test::make_config("svgf", 16, 16, f.channels(true))).has_value());
  {  // a sample without its offset
    auto c = test::make_config("svgf", 16, 16, f.channels(true));
    c.channels.pop_back();
    expect(c, pipelines::ConfigProblem::MissingChannel, "sample2_offset");
  }
  {  // sample 2 without sample 1
    auto c = test::make_config("svgf", 16, 16, f.channels(false));
    for (SampleField k : {SampleField::Radiance, SampleField::Normal, SampleField::Depth, SampleField::Offset})
      c.channels.push_back({sample_channel(2, k), Format::F32});
    expect(c, pipelines::ConfigProblem::MissingChannel, "without extra sample 1");
  }
  {  // split colours in a radiance session
    auto c = test::make_config("svgf", 16, 16, f.channels(true));
    c.channels.push_back({sample_channel(1, SampleField::Diffuse), Format::F32});
    expect(c, pipelines::ConfigProblem::InvalidChannel, "sample1_diffuse");
  }
  {  // one format per kind
    auto c = test::make_config("svgf", 16, 16, f.channels(true));
    for (auto& d : c.channels)
      if (d.id == sample_channel(2, SampleField::Depth)) d.format = Format::F16;
    expect(c, pipelines::ConfigProblem::InvalidChannel, "sample2_depth");
  }
  {  // lighting forms
    auto c = test::make_config("svgf", 16, 16,
                               {{ChannelId::DiffuseLighting, Format::F32}, {ChannelId::Specular, Format::F32},
                                {ChannelId::Albedo, Format::F32}, {ChannelId::Normal, Format::F32},
                                {ChannelId::Depth, Format::F32}, {ChannelId::Motion, Format::F32}});
    for (SampleField k : {SampleField::Diffuse, SampleField::Specular, SampleField::Normal, SampleField::Depth,
                          SampleField::Offset})
      c.channels.push_back({sample_channel(1, k), Format::F32});
    expect(c, pipelines::ConfigProblem::InvalidChannel, "lighting forms");
  }
  {  // accumulate takes none
    auto c = test::make_config("accumulate", 16, 16, f.channels(true));
    c.channels.erase(c.channels.begin() + 1);  // albedo, which accumulate does not take either
    const auto err = pipelines::validate(c);
    ASSERT_TRUE(err.has_value());
    EXPECT_NE(err->message.find("sample1_radiance"), std::string::npos) << err->message;
  }
}

}  // namespace
}  // namespace dn
