// stat-temporal against its CPU reference (stat_temporal_reference.cpp) over
// moving sequences with a disocclusion and a shadow that moves over the
// surface, and the oracles of its statistics: a still camera accumulates
// every sample exactly (the P0b merge), a changed history is rejected by the
// Welch test and an unchanged one is kept, scaling the samples keeps every
// decision, and frames without statistics or with bad ones keep the history;
// a session without statistics planes takes each frame's radiance as one sample.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "gpu_test_env.hpp"
#include "online_stats.hpp"
#include "pipelines/graph.hpp"
#include "pipelines/pipeline.hpp"
#include "pipelines/stat/student_t.hpp"
#include "stat_samples.hpp"
#include "stat_temporal_reference.hpp"
#include "svgf_inputs.hpp"

namespace dn {
namespace {

using test::ChannelId;
using test::Format;

class StatTemporalTest : public test::GpuTest {};

// A sloped plane the camera pans over at `pan` px per frame (p_prev = p +
// (pan, 0)), albedo in blocks fixed to the plane, and in front of it a box
// (depth 3) fixed on screen whose edge uncovers the plane. A shadow no
// G-buffer shows lies on the plane right of world u = shadow_u + shadow_speed
// * frame: it moves over the surface, so a history the shadow crossed is stale.
// Each pixel's `spp` samples are exponential around light * albedo * scale.
struct SceneSpec {
  int w = 48, h = 32;
  float pan = 1.0f;
  float shadow_u = 30.0f, shadow_speed = 2.0f, shadow_light = 0.1f;
  bool box = true;
  int spp = 1;
  float scale = 1.0f;
  bool demodulated = false;  // statistics over sample / albedo (dnrender --stats-demodulated)
  bool metal = false;        // every fifth plane block sends albedo 0 (a metal's diffuse colour), lit as the others
};

bool metal_block(const SceneSpec& s, bool in_box, int block) { return s.metal && !in_box && block % 5 == 0; }

test::StatTemporalFrame scene_frame(const SceneSpec& s, int k, uint32_t seed) {
  test::StatTemporalFrame f;
  test::StatFrame& st = f.stats;
  st.width = s.w;
  st.height = s.h;
  const int n = s.w * s.h;
  for (auto* v : {&st.radiance, &st.albedo, &st.normal, &st.mean, &st.m2, &st.m3}) v->assign(3 * n, 0.0f);
  st.count.assign(n, static_cast<float>(s.spp));
  f.depth.assign(n, 0.0f);
  f.motion.assign(2 * n, 0.0f);
  std::mt19937 rng(seed * 7919u + static_cast<uint32_t>(k));
  for (int y = 0; y < s.h; ++y)
    for (int x = 0; x < s.w; ++x) {
      const int i = y * s.w + x;
      const bool in_box = s.box && x >= 8 && x < 18 && y >= 8 && y < 22;
      const float u = static_cast<float>(x) + s.pan * static_cast<float>(k);  // world position on the plane
      float light = 1.0f;
      if (in_box) {
        f.depth[i] = 3.0f;
        st.normal[3 * i] = 0.6f;
        st.normal[3 * i + 2] = 0.8f;
      } else {
        f.depth[i] = 6.0f + 0.01f * u;
        st.normal[3 * i + 2] = 1.0f;
        f.motion[2 * i] = s.pan;
        if (u > s.shadow_u + s.shadow_speed * static_cast<float>(k)) light = s.shadow_light;
      }
      const int block = in_box ? 5 : static_cast<int>(std::floor(u / 6.0f));
      for (int c = 0; c < 3; ++c) {
        const float albedo = 0.3f + 0.15f * static_cast<float>((block * 3 + c + 8) % 4);
        st.albedo[3 * i + c] = metal_block(s, in_box, block) ? 0.0f : albedo;
        test::put_exponential_samples(st, i, c, s.spp, s.scale * light * albedo, s.demodulated ? albedo : 1.0f, rng);
      }
    }
  return f;
}

// with_statistics false: the radiance is each frame's one sample per pixel.
std::vector<pipelines::InputChannel> channels(bool with_statistics = true) {
  std::vector<pipelines::InputChannel> c = {{ChannelId::Radiance, Format::F32},
                                          {ChannelId::Albedo, Format::F32},
                                          {ChannelId::Normal, Format::F32},
                                          {ChannelId::Depth, Format::F32},
                                          {ChannelId::Motion, Format::F32}};
  if (with_statistics)
    for (ChannelId id : {ChannelId::StatCount, ChannelId::StatMean, ChannelId::StatM2, ChannelId::StatM3})
      c.push_back({id, Format::F32});
  return c;
}

test::HostFrame host_frame(const test::StatTemporalFrame& f, bool with_statistics = true) {
  test::HostFrame h;
  h.info.flags = f.reset ? protocol::kFrameReset : 0u;
  h.add(ChannelId::Radiance, Format::F32, f.stats.radiance);
  h.add(ChannelId::Albedo, Format::F32, f.stats.albedo);
  h.add(ChannelId::Normal, Format::F32, f.stats.normal);
  h.add(ChannelId::Depth, Format::F32, f.depth);
  h.add(ChannelId::Motion, Format::F32, f.motion);
  if (!with_statistics) return h;
  h.add(ChannelId::StatCount, Format::F32, f.stats.count);
  h.add(ChannelId::StatMean, Format::F32, f.stats.mean);
  h.add(ChannelId::StatM2, Format::F32, f.stats.m2);
  h.add(ChannelId::StatM3, Format::F32, f.stats.m3);
  return h;
}

std::vector<float> t_squared(double alpha = 0.001) {  // history_alpha's default
  std::vector<float> t = pipelines::student_t_table(alpha, 1024);
  for (float& v : t) v = v * v;
  return t;
}
// The membership table of two still pixels with accumulated statistics.
std::vector<float> still_t_squared() { return t_squared(0.01); }  // still_alpha's default

struct Session {
  std::unique_ptr<pipelines::Pipeline> pipe;
  pipelines::GraphPipeline* graph = nullptr;
};

Session make(gpu::Context& ctx, int w, int h, std::vector<pipelines::ParameterValue> params = {{"radius", 4}},
             bool with_statistics = true) {
  auto config = test::make_config("stat-temporal", w, h, channels(with_statistics), Format::F32, std::move(params));
  EXPECT_FALSE(pipelines::validate(config).has_value());
  Session s;
  s.pipe = pipelines::create(ctx, config);
  s.graph = dynamic_cast<pipelines::GraphPipeline*>(s.pipe.get());
  EXPECT_NE(s.graph, nullptr);
  s.graph->set_capture(true);
  return s;
}

// The accumulators the frame left on the device (read where stat_prepare and
// stat_filter read them). With demodulated statistics the filter averages
// stat_prepare's demodulated means (`value`) instead of the raw means and
// multiplies by `modulation`, which stat_temporal writes.
struct DeviceState {
  std::vector<float> count, mean, m2, m3, raw;
  std::vector<float> value, modulation;  // demodulated only
};
DeviceState device_state(const Session& s, bool demodulated = false) {
  auto read = [&](const char* pass, const char* buffer) {
    return test::decode_output(s.graph->captured(pass, buffer), Format::F32);
  };
  DeviceState d{read("stat_prepare", "stat_acc_count"), read("stat_prepare", "stat_acc_mean"),
                read("stat_prepare", "stat_acc_m2"), read("stat_prepare", "stat_acc_m3"), {}, {}, {}};
  if (demodulated) {
    d.value = read("stat_filter", "stat_value");
    d.modulation = read("stat_filter", "stat_modulation");
  } else {
    d.raw = read("stat_filter", "stat_acc_raw");
  }
  return d;
}

// The frame's planes with the device's accumulators as its statistics and
// raw means: what stat_prepare and stat_filter read.
test::StatFrame accumulated(const test::StatTemporalFrame& f, const DeviceState& d) {
  test::StatFrame acc = f.stats;
  acc.count = d.count;
  acc.mean = d.mean;
  acc.m2 = d.m2;
  acc.m3 = d.m3;
  acc.radiance = d.raw;
  return acc;
}

// The filter parameters of the sessions make() opens from the radiance alone.
test::StatParams session_filter_params() {
  test::StatParams p;
  p.radius = 4;
  p.pool_single = true;
  p.spatial_shrink_from = 16.0;
  return p;
}

// What the filter passes read after frame f of a session make() opened from
// the radiance alone: the device's accumulators, the session's filter
// parameters and the CPU reference's test inputs over them.
struct FilterInputs {
  DeviceState device;
  test::StatFrame acc;
  test::StatParams params;
  test::StatPrepared prep;
};
FilterInputs filter_inputs(const Session& s, const test::StatTemporalFrame& f) {
  FilterInputs in{device_state(s), {}, session_filter_params(), {}};
  in.acc = accumulated(f, in.device);
  in.prep = test::stat_prepare(in.acc, in.params);
  return in;
}

// Pixels whose demodulated mean or modulation is off the reference's: the
// mean from the accumulated moments, and radiance over the frame's own
// demodulated mean (the guarded albedo where the frame brought no data, 1
// where nothing is accumulated).
size_t demodulation_mismatches(const DeviceState& d, const test::StatTemporalState& ref,
                               const test::StatTemporalFrame& f) {
  size_t off = 0;
  const test::StatFrame& st = f.stats;
  for (size_t i = 0; i < ref.acc.size(); ++i) {
    const test::StatAccumulator& a = ref.acc[i];
    const bool frame_data = st.count[i] > 0.0f;
    for (int c = 0; c < 3; ++c) {
      const size_t k = 3 * i + c;
      const double radiance = std::max(0.0f, st.radiance[k]);
      const double value = a.n > 0.0 ? test::raw_from_moments(a.n, a.mean[c], a.m2[c]) : radiance;
      const double m = !(a.n > 0.0) ? 1.0
                       : frame_data ? test::modulation(radiance, test::raw_from_moments(st.count[i], st.mean[k], st.m2[k]),
                                                       st.albedo[k])
                                    : test::guarded_albedo(st.albedo[k]);
      if (std::fabs(d.value[k] - value) > 1e-4 * (1e-3 + value) || std::fabs(d.modulation[k] - m) > 1e-4 * (1e-3 + m))
        ++off;
    }
  }
  return off;
}

// Pixels whose accumulator differs from the reference's: `decisions` where
// the count differs (another merge or rejection), `values` where the count
// agrees but a statistic is off by more than fp32 merging explains.
struct Mismatch {
  size_t decisions = 0, values = 0;
};
Mismatch compare(const DeviceState& d, const test::StatTemporalState& ref) {
  Mismatch m;
  for (size_t i = 0; i < ref.acc.size(); ++i) {
    const test::StatAccumulator& a = ref.acc[i];
    if (std::fabs(d.count[i] - a.n) > 1e-4 * (1.0 + a.n)) {
      ++m.decisions;
      continue;
    }
    bool ok = true;
    for (int c = 0; c < 3; ++c) {
      const double scale3 = std::pow(std::max(a.m2[c], 0.0) / std::max(a.n, 1.0), 1.5) * a.n;
      ok = ok && std::fabs(d.mean[3 * i + c] - a.mean[c]) <= 1e-4 * (1.0 + std::fabs(a.mean[c]));
      ok = ok && (d.raw.empty() || std::fabs(d.raw[3 * i + c] - a.raw[c]) <= 1e-4 * (1e-3 + std::fabs(a.raw[c])));
      ok = ok && std::fabs(d.m2[3 * i + c] - a.m2[c]) <= 1e-3 * (1e-3 + std::fabs(a.m2[c]));
      ok = ok && std::fabs(d.m3[3 * i + c] - a.m3[c]) <= 1e-3 * (1e-3 + std::fabs(a.m3[c]) + scale3);
    }
    if (!ok) ++m.values;
  }
  return m;
}

TEST_F(StatTemporalTest, MatchesCpuReference) {
  // from_radiance: the session declares no statistics planes; at 1 spp the
  // reference's statistics of the frame's one sample are what the server
  // must derive from the radiance (n = 1, y(x) or y(x / albedo), M2 = M3 = 0).
  struct Variant {
    const char* name;
    SceneSpec scene;
    double fading;
    bool from_radiance = false;
  };
  // At 1 spp a 3x3 window holds 9 samples: a dark shadow (2 %) moving fast
  // exercises the rejection.
  SceneSpec one_spp;
  one_spp.shadow_light = 0.02f;
  one_spp.shadow_speed = 4.0f;
  SceneSpec fractional = one_spp;
  fractional.pan = 0.6f;
  SceneSpec four_spp;
  four_spp.spp = 4;
  four_spp.pan = 1.3f;
  SceneSpec still = one_spp;
  still.pan = 0.0f;
  SceneSpec demodulated = four_spp;
  demodulated.demodulated = true;
  SceneSpec still_demodulated = still;
  still_demodulated.demodulated = true;
  SceneSpec metal = one_spp;
  metal.metal = true;
  const Variant variants[] = {{"pan1_1spp", one_spp, 0.9},
                              {"pan0.6_1spp", fractional, 0.9},
                              {"pan1.3_4spp_fading0.7", four_spp, 0.7},
                              {"still_shadow_moves", still, 0.9},
                              {"pan1.3_4spp_demodulated", demodulated, 0.9},
                              {"pan1_radiance_only", one_spp, 0.9, true},
                              {"still_radiance_only_demodulated", still_demodulated, 0.9, true},
                              {"pan1_metal_radiance_only", metal, 0.9, true}};
  const auto table = t_squared();
  for (const auto& v : variants) {
    SCOPED_TRACE(v.name);
    Session s = make(ctx(), v.scene.w, v.scene.h,
                     {{"radius", 4}, {"fading", v.fading}, {"demodulated", v.scene.demodulated ? 1.0 : 0.0}},
                     !v.from_radiance);
    test::StatTemporalState state;
    size_t rejected = 0, merged = 0;
    for (int k = 0; k < 8; ++k) {
      test::StatTemporalFrame f = scene_frame(v.scene, k, 3);
      f.reset = k == 5;  // a reset mid-sequence: every pixel starts afresh
      svgf_inputs::run(*s.pipe, host_frame(f, !v.from_radiance));
      const test::StatTemporalResult want = test::stat_temporal(f, state, v.fading, table);
      const DeviceState device = device_state(s, v.scene.demodulated);
      const Mismatch m = compare(device, want.state);
      if (v.scene.demodulated) {
        EXPECT_EQ(demodulation_mismatches(device, want.state, f), 0u) << "frame " << k << ": demodulated means or modulation";
      }
      EXPECT_EQ(m.decisions, 0u) << "frame " << k << ": pixels merged or rejected unlike the reference";
      EXPECT_EQ(m.values, 0u) << "frame " << k << ": accumulators off the reference";
      for (size_t i = 0; i < want.rejected.size(); ++i) {
        rejected += want.rejected[i];
        merged += want.state.acc[i].n > f.stats.count[i] + 1e-3;
      }
      if (k == 5) {  // the reset: every accumulator is the frame's own (the device's equals the reference's)
        for (size_t i = 0; i < want.state.acc.size(); ++i) ASSERT_EQ(want.state.acc[i].n, f.stats.count[i]);
      }
      state = want.state;
    }
    std::printf("[ info     ] %s: %zu merges, %zu rejections by the test over 8 frames\n", v.name, merged, rejected);
    EXPECT_GT(rejected, 0u) << "the sequence never exercises the test's rejection";
    EXPECT_GT(merged, 0u);
  }
}

// pool_single: from the radiance alone every pixel of a first frame holds
// one sample, so none has a variance for the Welch test; stat_prepare tests
// each as its own sample with a sample variance from its 3x3 window. The
// device's test inputs and output match the CPU reference over the device's
// accumulators, and the output is nearer the truth (the mean of 4096
// samples) than the frame; with pool_single 0 the frame comes back as sent.
TEST_F(StatTemporalTest, AFirstFrameFromTheRadianceIsFiltered) {
  SceneSpec still;
  still.pan = 0.0f;
  const test::StatTemporalFrame f = scene_frame(still, 0, 5);
  SceneSpec many = still;
  many.spp = 4096;
  const std::vector<float> truth = scene_frame(many, 0, 6).stats.radiance;
  auto rmse = [&](const std::vector<float>& v) {
    double e = 0.0;
    for (size_t k = 0; k < v.size(); ++k) e += (v[k] - truth[k]) * (v[k] - truth[k]);
    return std::sqrt(e / v.size());
  };

  Session s = make(ctx(), still.w, still.h, {{"radius", 4}}, false);
  const auto got = svgf_inputs::run(*s.pipe, host_frame(f, false));
  const FilterInputs in = filter_inputs(s, f);
  const test::StatFrame& acc = in.acc;
  const test::StatParams& p = in.params;
  const test::StatPrepared& prep = in.prep;
  const auto theta = test::decode_output(s.graph->captured("stat_prepare", "stat_theta"), Format::F32);
  const auto variance = test::decode_output(s.graph->captured("stat_prepare", "stat_variance"), Format::F32);
  size_t off = 0;
  for (int i = 0; i < still.w * still.h; ++i)
    for (int c = 0; c < 4; ++c) {
      if (std::fabs(theta[4 * i + c] - prep.theta[4 * i + c]) > 1e-6f * (1.0f + std::fabs(prep.theta[4 * i + c]))) ++off;
      if (c < 3 && std::fabs(variance[4 * i + c] - prep.variance[3 * i + c]) > 1e-5f * prep.variance[3 * i + c]) ++off;
    }
  EXPECT_EQ(off, 0u) << "stat_prepare values off the reference";
  const test::StatResult want = test::stat_filter(acc, prep, p, t_squared(p.alpha), still_t_squared());
  long members = 0;
  for (int m : want.members) members += m;
  const double rms = test::relative_rms(got, want.output);
  std::printf("[ info     ] first frame: relative RMS %.3g to the reference, %ld members; RMSE %.4f (frame %.4f)\n", rms,
              members, rmse(got), rmse(f.stats.radiance));
  EXPECT_LE(rms, 1e-5);
  EXPECT_GT(members, 0);
  EXPECT_LT(rmse(got), 0.8 * rmse(f.stats.radiance));

  Session off_session = make(ctx(), still.w, still.h, {{"radius", 4}, {"pool_single", 0}}, false);
  EXPECT_EQ(svgf_inputs::run(*off_session.pipe, host_frame(f, false)), f.stats.radiance);
}

// A one-sample pixel takes its variance from its 3x3 window by the
// second-smallest of the four 2x2 quadrants that hold it: the whole window's
// variance counts a small highlight next to the pixel as noise, and with it
// the pixel accepted the highlight. A first frame of 64 spp per pixel (one
// sample each, from the radiance) with a 2x2 highlight (x 20) on the plane:
// the error of the ring of 12 pixels around it is at most half the frame's
// there (0.73 with the whole window's variance), and the frame away from it
// is still filtered.
TEST_F(StatTemporalTest, AFirstFrameDoesNotSpreadAHighlight) {
  SceneSpec still;
  still.pan = 0.0f;
  still.spp = 64;
  test::StatTemporalFrame f = scene_frame(still, 0, 5);
  SceneSpec many = still;
  many.spp = 4096;
  const std::vector<float> truth = scene_frame(many, 0, 6).stats.radiance;
  const int fx = 36, fy = 16;
  for (int k = 0; k < 4; ++k)
    for (int c = 0; c < 3; ++c) f.stats.radiance[3 * ((fy + k / 2) * still.w + fx + k % 2) + c] *= 20.0f;
  auto rmse = [&](const std::vector<float>& v, bool around) {
    double e = 0.0;
    size_t n = 0;
    for (int y = 0; y < still.h; ++y)
      for (int x = 0; x < still.w; ++x) {
        const int d = std::max(std::max(fx - x, x - fx - 1), std::max(fy - y, y - fy - 1));
        if (d == 0 || (d == 1) != around) continue;
        for (int c = 0; c < 3; ++c) {
          const size_t k = 3 * size_t(y * still.w + x) + c;
          e += (v[k] - truth[k]) * (v[k] - truth[k]);
          ++n;
        }
      }
    return std::sqrt(e / double(n));
  };
  Session s = make(ctx(), still.w, still.h, {{"radius", 4}}, false);
  const auto got = svgf_inputs::run(*s.pipe, host_frame(f, false));
  std::printf("[ info     ] around the highlight RMSE %.4f (frame %.4f), elsewhere %.4f (frame %.4f)\n", rmse(got, true),
              rmse(f.stats.radiance, true), rmse(got, false), rmse(f.stats.radiance, false));
  EXPECT_LE(rmse(got, true), 0.5 * rmse(f.stats.radiance, true));
  EXPECT_LT(rmse(got, false), 0.8 * rmse(f.stats.radiance, false));
}

// A moving pixel's neighbours are tested by Eq. 14, a still one's by the
// symmetric test: after four frames of the 1 px pan (the plane moves, the
// box does not) stat_prepare marks exactly the plane's pixels, and the output
// matches the CPU reference over the device's accumulators with that
// per-pixel choice, which differs from the symmetric test everywhere.
TEST_F(StatTemporalTest, MovingPixelsTestTheirNeighboursAsymmetrically) {
  SceneSpec scene;
  Session s = make(ctx(), scene.w, scene.h, {{"radius", 4}}, false);
  test::StatTemporalFrame f;
  std::vector<float> got;
  for (int k = 0; k < 4; ++k) {
    f = scene_frame(scene, k, 11);
    got = svgf_inputs::run(*s.pipe, host_frame(f, false));
  }
  FilterInputs in = filter_inputs(s, f);
  const test::StatFrame& acc = in.acc;
  const test::StatParams& p = in.params;
  test::StatPrepared& prep = in.prep;
  const test::StatResult symmetric = test::stat_filter(acc, prep, p, t_squared(p.alpha), still_t_squared());
  const int n = scene.w * scene.h;
  prep.moving.assign(n, 0);
  for (int i = 0; i < n; ++i) prep.moving[i] = std::hypot(f.motion[2 * i], f.motion[2 * i + 1]) >= 0.005;
  const test::StatResult want = test::stat_filter(acc, prep, p, t_squared(p.alpha), still_t_squared());
  const auto variance = test::decode_output(s.graph->captured("stat_prepare", "stat_variance"), Format::F32);
  int marked = 0, wrong = 0;
  for (int i = 0; i < n; ++i) {
    marked += variance[4 * i + 3] == 1.0f;  // DN_STAT_MOVING
    wrong += (variance[4 * i + 3] == 1.0f) != (prep.moving[i] != 0);
  }
  const double rms = test::relative_rms(got, want.output), apart = test::relative_rms(got, symmetric.output);
  std::printf("[ info     ] %d of %d pixels moving; relative RMS %.3g to the reference, %.3g to the symmetric one\n",
              marked, n, rms, apart);
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(marked, n / 2);
  EXPECT_LT(marked, n);
  EXPECT_LE(rms, 1e-5);
  EXPECT_GT(apart, 1e-3);
}

// A still metal (albedo 0: its guides say nothing of what it shows) shows
// the plain mean of its own samples once it has two, gathering nothing: the
// Welch test of a few samples is too wide to keep a highlight's darker
// neighbours out. From the radiance alone over 6 still frames, stat_prepare
// marks exactly the metal pixels with 2 or more samples, each shows the mean
// of the radiance it was sent, and the whole output matches the CPU
// reference over the device's accumulators with those pixels kept.
TEST_F(StatTemporalTest, AStillMetalShowsTheMeanOfItsSamples) {
  SceneSpec scene;
  scene.pan = 0.0f;
  scene.metal = true;
  scene.shadow_light = 1.0f;  // no shadow: the pixels keep their samples
  const int frames = 6, n = scene.w * scene.h;
  Session s = make(ctx(), scene.w, scene.h, {{"radius", 4}}, false);
  std::vector<double> sum(3 * n, 0.0);
  test::StatTemporalFrame f;
  std::vector<float> got;
  for (int k = 0; k < frames; ++k) {
    f = scene_frame(scene, k, 5);
    for (int i = 0; i < 3 * n; ++i) sum[i] += f.stats.radiance[i];
    got = svgf_inputs::run(*s.pipe, host_frame(f, false));
  }
  FilterInputs in = filter_inputs(s, f);
  const DeviceState& d = in.device;
  const test::StatFrame& acc = in.acc;
  const test::StatParams& p = in.params;
  test::StatPrepared& prep = in.prep;
  const test::StatResult filtered = test::stat_filter(acc, prep, p, t_squared(p.alpha), still_t_squared());
  prep.kept.assign(n, 0);
  int metal_pixels = 0, complete = 0, off_mean = 0;
  for (int y = 0; y < scene.h; ++y)
    for (int x = 0; x < scene.w; ++x) {
      const int i = y * scene.w + x;
      const bool in_box = x >= 8 && x < 18 && y >= 8 && y < 22;
      if (!metal_block(scene, in_box, x / 6)) continue;
      ++metal_pixels;
      prep.kept[i] = d.count[i] >= 2.0f;
      if (d.count[i] != static_cast<float>(frames)) continue;
      ++complete;
      for (int c = 0; c < 3; ++c) {
        const double mean = sum[3 * i + c] / frames;
        off_mean += std::fabs(got[3 * i + c] - mean) > 1e-5 * (1e-3 + mean);
      }
    }
  const test::StatResult want = test::stat_filter(acc, prep, p, t_squared(p.alpha), still_t_squared());
  const auto variance = test::decode_output(s.graph->captured("stat_prepare", "stat_variance"), Format::F32);
  int marked = 0, wrong = 0;
  for (int i = 0; i < n; ++i) {
    const bool kept = variance[4 * i + 3] == 2.0f;  // DN_STAT_KEPT
    marked += kept;
    wrong += kept != (prep.kept[i] != 0);
  }
  const double rms = test::relative_rms(got, want.output), apart = test::relative_rms(got, filtered.output);
  std::printf("[ info     ] %d of %d metal pixels kept, %d with all %d samples; relative RMS %.3g to the reference, "
              "%.3g to the one that filters them\n",
              marked, metal_pixels, complete, frames, rms, apart);
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(complete, metal_pixels / 2);
  EXPECT_EQ(off_mean, 0) << "channels of metal pixels with every sample off the mean of their radiance";
  EXPECT_LE(rms, 1e-5);
  EXPECT_GT(apart, 1e-3);
}

// A still camera over an unchanging scene: still pixels do not fade, so a
// pixel whose history the test never rejected holds every sample, and its
// accumulators equal two-pass statistics of them all (the exact merge over
// 24 frames). The test may reject by chance (history_alpha per channel and
// frame): nearly every pixel must keep all its samples.
TEST_F(StatTemporalTest, StillCameraAccumulatesEverySampleExactly) {
  const int w = 40, h = 24, frames = 24, spp = 2;
  Session s = make(ctx(), w, h);
  std::vector<std::vector<double>> samples(3 * w * h);
  std::mt19937 rng(17);
  for (int k = 0; k < frames; ++k) {
    test::StatTemporalFrame f = scene_frame(SceneSpec{w, h, 0.0f, 0.0f, 0.0f, 1.0f, false, spp}, k, 1);
    for (int i = 0; i < w * h; ++i)
      for (int c = 0; c < 3; ++c) {
        render::OnlineStats acc;
        const double truth = 0.2 + 0.6 * ((i + c) % 5) / 4.0;
        for (int j = 0; j < spp; ++j) {
          const double r = (static_cast<double>(rng()) + 0.5) / 4294967296.0;
          const float x = static_cast<float>(-std::log(r) * truth);
          acc.add(x);
          samples[3 * i + c].push_back(x);
        }
        f.stats.radiance[3 * i + c] = acc.raw_mean;
        f.stats.mean[3 * i + c] = acc.mean;
        f.stats.m2[3 * i + c] = acc.m2;
        f.stats.m3[3 * i + c] = acc.m3;
      }
    svgf_inputs::run(*s.pipe, host_frame(f));
  }
  const DeviceState d = device_state(s);
  size_t complete = 0, off = 0;
  for (int i = 0; i < w * h; ++i) {
    if (d.count[i] != static_cast<float>(frames * spp)) continue;
    ++complete;
    for (int c = 0; c < 3; ++c) {
      const std::vector<double>& x = samples[3 * i + c];
      double mean = 0.0, raw = 0.0;
      for (double v : x) mean += 2.0 * std::sqrt(v) - 2.0, raw += v;
      mean /= x.size();
      raw /= x.size();
      double m2 = 0.0, m3 = 0.0;
      for (double v : x) {
        const double dy = 2.0 * std::sqrt(v) - 2.0 - mean;
        m2 += dy * dy;
        m3 += dy * dy * dy;
      }
      const bool ok = std::fabs(d.mean[3 * i + c] - mean) <= 1e-5 * (1.0 + std::fabs(mean)) &&
                      std::fabs(d.raw[3 * i + c] - raw) <= 1e-5 * raw &&
                      std::fabs(d.m2[3 * i + c] - m2) <= 1e-4 * m2 &&
                      std::fabs(d.m3[3 * i + c] - m3) <= 1e-4 * (std::fabs(m3) + std::pow(m2, 1.5) / std::sqrt(x.size()));
      off += !ok;
    }
  }
  std::printf("[ info     ] %zu of %d pixels kept all %d samples\n", complete, w * h, frames * spp);
  EXPECT_GE(complete, static_cast<size_t>(0.98 * w * h)) << "still pixels lost samples (rejections or fading)";
  EXPECT_EQ(off, 0u) << "accumulated statistics differ from two-pass ones";
}

// A moving metal (albedo 0: what it shows moves with the camera, not with its
// surface) keeps no history and shows its frame as sent: a fading memory
// trailed a reflected highlight, and the window's pooled variance counted a
// sharp reflection's edges as noise (moving Cycles room at 16 spp: above the
// input). The diffuse plane keeps about 1 / (1 - fading): after 10 frames of
// a 1 px pan 1 + 0.9 + ... + 0.9^9 = 6.5 (less what the test rejects).
TEST_F(StatTemporalTest, AMovingMetalShowsItsFrame) {
  SceneSpec scene;
  scene.metal = true;
  scene.box = false;
  scene.shadow_light = 1.0f;  // no shadow: nothing for the test to reject
  Session s = make(ctx(), scene.w, scene.h, {{"radius", 4}}, false);
  test::StatTemporalFrame f;
  std::vector<float> got;
  for (int k = 0; k < 10; ++k) {
    f = scene_frame(scene, k, 9);
    got = svgf_inputs::run(*s.pipe, host_frame(f, false));
  }
  const DeviceState d = device_state(s);
  double diffuse_n = 0.0;
  int metal = 0, diffuse = 0, metal_history = 0, metal_off_frame = 0;
  for (int y = 0; y < scene.h; ++y)
    for (int x = 1; x < scene.w - 10; ++x) {  // left of the columns the pan brought in during the last 10 frames
      const int i = y * scene.w + x;
      const int block = static_cast<int>(std::floor((static_cast<float>(x) + 9.0f) / 6.0f));
      if (metal_block(scene, false, block)) {
        ++metal;
        metal_history += d.count[i] != 1.0f;
        for (int c = 0; c < 3; ++c) {
          const float sent = f.stats.radiance[3 * i + c];
          metal_off_frame += std::fabs(got[3 * i + c] - sent) > 1e-5f * (1e-3f + sent);
        }
      } else {
        diffuse_n += d.count[i];
        ++diffuse;
      }
    }
  ASSERT_GT(metal, 0);
  ASSERT_GT(diffuse, 0);
  std::printf("[ info     ] %d metal pixels, %d with history, %d channels off their frame; diffuse mean samples %.3f\n",
              metal, metal_history, metal_off_frame, diffuse_n / diffuse);
  EXPECT_EQ(metal_history, 0);
  EXPECT_EQ(metal_off_frame, 0);
  EXPECT_GT(diffuse_n / diffuse, 5.0);
}

// Sparse light on a still camera, from the radiance alone: each sample is 20
// with probability 0.05, else 0 (a caustic, a small light's glints), so most
// frames' 3x3 windows hold nine zeros, a sample variance of 0. Under the
// history's hypothesis the frame's samples share its distribution: the test
// shrinks the frame's variance toward the history's, and nearly every pixel
// keeps all its samples. With the frame's own variance alone the window of
// zeros failed against the history's mean on most frames, two in a row
// rejected it, and the restarted pixels showed their zeros.
TEST_F(StatTemporalTest, SparseLightKeepsItsHistory) {
  const int w = 40, h = 24, frames = 48;
  Session s = make(ctx(), w, h, {{"radius", 4}}, false);
  std::mt19937 rng(23);
  std::bernoulli_distribution lit(0.05);
  for (int k = 0; k < frames; ++k) {
    test::StatTemporalFrame f = scene_frame(SceneSpec{w, h, 0.0f, 0.0f, 0.0f, 1.0f, false, 1}, k, 1);
    for (int i = 0; i < w * h; ++i) {
      const float x = lit(rng) ? 20.0f : 0.0f;
      for (int c = 0; c < 3; ++c) f.stats.radiance[3 * i + c] = x;
    }
    svgf_inputs::run(*s.pipe, host_frame(f, false));
  }
  const DeviceState d = device_state(s);
  size_t complete = 0;
  for (int i = 0; i < w * h; ++i) complete += d.count[i] == static_cast<float>(frames);
  std::printf("[ info     ] %zu of %d pixels kept all %d samples\n", complete, w * h, frames);
  EXPECT_GE(complete, static_cast<size_t>(0.98 * w * h)) << "sparse light restarted still histories";
}

// A still region beside one whose samples hold rare fireflies, from the
// radiance alone: each sample is uniform in [0.15, 0.25], plus 20 with
// probability 1/100 left of x = 24 (truth 0.4; right of it 0.2). Their
// Box-Cox means differ by less than the Welch test resolves, so a right
// pixel averages left neighbours' raw means, and those hold the fireflies.
// With spatial_shrink_from (stat-temporal's default 16) a still pixel's
// kernel narrows as sqrt(16 / n): after 128 frames the output matches the CPU
// reference over the device's accumulators, and the right pixels 4 to 11
// pixels from the edge (within the disc, radius 12) are lifted above their
// truth by less than half what they are with spatial_shrink_from 0.
TEST_F(StatTemporalTest, AStillPixelsKernelNarrowsAsItsSamplesAccumulate) {
  const int w = 48, h = 24, frames = 128, edge = 24, radius = 12;
  std::mt19937 rng(29);
  std::uniform_real_distribution<float> base(0.15f, 0.25f);
  std::bernoulli_distribution firefly(0.01);
  std::vector<test::StatTemporalFrame> sequence;
  for (int k = 0; k < frames; ++k) {
    test::StatTemporalFrame f = scene_frame(SceneSpec{w, h, 0.0f, 0.0f, 0.0f, 1.0f, false, 1}, k, 1);
    for (int i = 0; i < w * h; ++i) {
      const float x = base(rng) + (i % w < edge && firefly(rng) ? 20.0f : 0.0f);
      for (int c = 0; c < 3; ++c) f.stats.radiance[3 * i + c] = x, f.stats.albedo[3 * i + c] = 0.5f;
    }
    sequence.push_back(f);
  }
  // The output after the last frame and the mean lift of the right pixels 4 to 11 pixels from the edge.
  auto run = [&](double shrink_from, double* lift) {
    Session s = make(ctx(), w, h, {{"radius", radius}, {"spatial_shrink_from", shrink_from}}, false);
    std::vector<float> got;
    for (const auto& f : sequence) got = svgf_inputs::run(*s.pipe, host_frame(f, false));
    double sum = 0.0;
    int n = 0;
    for (int y = 0; y < h; ++y)
      for (int x = edge + 4; x < edge + radius; ++x)
        for (int c = 0; c < 3; ++c) sum += got[3 * size_t(y * w + x) + c] - 0.2, ++n;
    *lift = sum / n;
    return std::make_pair(std::move(s), got);
  };
  double lift = 0.0, lift_unshrunk = 0.0;
  auto [s, got] = run(16.0, &lift);
  run(0.0, &lift_unshrunk);
  FilterInputs in = filter_inputs(s, sequence.back());
  in.params.radius = radius;
  const test::StatResult want = test::stat_filter(in.acc, in.prep, in.params, t_squared(in.params.alpha), still_t_squared());
  const double rms = test::relative_rms(got, want.output);
  std::printf("[ info     ] beside the fireflies: lifted %.4f (%.4f with spatial_shrink_from 0); relative RMS %.3g "
              "to the reference\n",
              lift, lift_unshrunk, rms);
  EXPECT_LE(rms, 1e-5);
  EXPECT_GT(lift_unshrunk, 0.002) << "the scene does not lift the pixels beside the fireflies";
  EXPECT_LT(lift, 0.5 * lift_unshrunk);
}

// RESULT.samples from the radiance alone: a still pixel's accumulator holds
// one sample per frame, so the median pixel rests on every frame sent (a
// chance rejection may restart a few: the minimum is at least 1); a reset
// starts again from one. With the renderer's statistics (samples, not
// frames) nothing is counted.
TEST_F(StatTemporalTest, SampleCountsFromTheRadianceAreFrames) {
  SceneSpec spec;
  spec.pan = 0.0f;
  spec.box = false;
  spec.shadow_speed = 0.0f;
  spec.shadow_u = 1e9f;
  Session s = make(ctx(), spec.w, spec.h, {{"radius", 4}}, false);
  for (uint32_t t = 1; t <= 20; ++t) {
    svgf_inputs::run(*s.pipe, host_frame(scene_frame(spec, static_cast<int>(t), 2), false));
    const auto counts = s.pipe->samples();
    ASSERT_TRUE(counts) << t;
    EXPECT_EQ(counts->median, t) << t;
    EXPECT_GE(counts->min, 1u) << t;
  }
  test::StatTemporalFrame reset = scene_frame(spec, 21, 2);
  reset.reset = true;
  svgf_inputs::run(*s.pipe, host_frame(reset, false));
  EXPECT_EQ(s.pipe->samples()->median, 1u);
  EXPECT_EQ(s.pipe->samples()->min, 1u);

  Session with_statistics = make(ctx(), spec.w, spec.h);
  svgf_inputs::run(*with_statistics.pipe, host_frame(scene_frame(spec, 1, 2)));
  EXPECT_FALSE(with_statistics.pipe->samples());
}

// A still camera; on frame 12 the light on the left half drops to 5 % (a
// change no G-buffer shows). The Welch test rejects the stale history there
// (a still pixel on the second frame that fails: one frame may be a
// firefly) and keeps it elsewhere; the output follows the new light.
TEST_F(StatTemporalTest, RejectsAChangedHistoryAndKeepsAnUnchangedOne) {
  SceneSpec spec;
  spec.pan = 0.0f;
  spec.box = false;
  spec.shadow_speed = 0.0f;
  spec.shadow_u = 1e9f;  // no shadow
  const int frames = 14, change = 12;
  Session s = make(ctx(), spec.w, spec.h);
  std::vector<float> out;
  test::StatTemporalFrame f;
  for (int k = 0; k < frames; ++k) {
    f = scene_frame(spec, k, 9);
    if (k >= change)
      for (int y = 0; y < spec.h; ++y)
        for (int x = 0; x < spec.w / 2; ++x) {
          const int i = y * spec.w + x;
          for (int c = 0; c < 3; ++c) {
            f.stats.radiance[3 * i + c] *= 0.05f;  // samples x 0.05: Box-Cox y = 2 sqrt(x) - 2 moves accordingly
            const float y0 = f.stats.mean[3 * i + c];  // one sample: mean = 2 sqrt(x) - 2
            const float x0 = (y0 + 2.0f) * (y0 + 2.0f) / 4.0f;
            f.stats.mean[3 * i + c] = 2.0f * std::sqrt(0.05f * x0) - 2.0f;
          }
        }
    out = svgf_inputs::run(*s.pipe, host_frame(f));
  }
  const DeviceState d = device_state(s);
  size_t changed_kept = 0, changed = 0, unchanged_lost = 0, unchanged = 0;
  double out_changed = 0.0, truth_changed = 0.0;
  for (int y = 1; y < spec.h - 1; ++y)
    for (int x = 1; x < spec.w - 1; ++x) {
      const int i = y * spec.w + x;
      if (x < spec.w / 2 - 1) {  // windows wholly in the changed half
        ++changed;
        changed_kept += d.count[i] > static_cast<float>(frames - change) + 0.5f;
        for (int c = 0; c < 3; ++c) {
          out_changed += out[3 * i + c];
          truth_changed += 0.05 * f.stats.albedo[3 * i + c];
        }
      } else if (x > spec.w / 2) {
        ++unchanged;
        unchanged_lost += d.count[i] != static_cast<float>(frames);
      }
    }
  std::printf("[ info     ] changed: %zu of %zu kept a stale history; unchanged: %zu of %zu lost samples\n", changed_kept,
              changed, unchanged_lost, unchanged);
  EXPECT_LE(changed_kept, changed / 50) << "stale histories kept";
  EXPECT_LE(unchanged_lost, unchanged / 50) << "unchanged histories lost";
  EXPECT_NEAR(out_changed / truth_changed, 1.0, 0.25) << "the output did not follow the new light";
}

// Samples x 4: Box-Cox differences and deviations scale by 2, so every merge
// and rejection stays and the raw means scale by 4.
TEST_F(StatTemporalTest, ScalingTheSamplesKeepsEveryDecision) {
  SceneSpec spec;
  spec.shadow_light = 0.02f;
  spec.shadow_speed = 4.0f;
  SceneSpec scaled = spec;
  scaled.scale = 4.0f;
  Session a = make(ctx(), spec.w, spec.h), b = make(ctx(), spec.w, spec.h);
  for (int k = 0; k < 6; ++k) {
    svgf_inputs::run(*a.pipe, host_frame(scene_frame(spec, k, 2)));
    svgf_inputs::run(*b.pipe, host_frame(scene_frame(scaled, k, 2)));
    const DeviceState da = device_state(a), db = device_state(b);
    ASSERT_EQ(da.count, db.count) << "frame " << k << ": a merge or rejection changed with the scale";
    for (size_t i = 0; i < da.raw.size(); ++i)
      ASSERT_NEAR(db.raw[i], 4.0f * da.raw[i], 1e-5f * (1e-3f + 4.0f * da.raw[i])) << "frame " << k;
  }
}

// Frames that bring no data for a pixel (n = 0) or bad statistics (NaN,
// infinite) keep its history unchanged; the output stays finite.
TEST_F(StatTemporalTest, FramesWithoutDataKeepTheHistory) {
  SceneSpec spec;
  spec.pan = 0.0f;
  spec.shadow_speed = 0.0f;
  Session s = make(ctx(), spec.w, spec.h);
  for (int k = 0; k < 4; ++k) svgf_inputs::run(*s.pipe, host_frame(scene_frame(spec, k, 4)));
  const DeviceState before = device_state(s);
  test::StatTemporalFrame f = scene_frame(spec, 4, 4);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const int none = 3 * spec.w + 30, bad_m2 = 20 * spec.w + 25, bad_count = 25 * spec.w + 40;
  f.stats.count[none] = 0.0f;
  f.stats.m2[3 * bad_m2 + 1] = nan;
  f.stats.count[bad_count] = inf;
  const auto out = svgf_inputs::run(*s.pipe, host_frame(f));
  const DeviceState after = device_state(s);
  for (int i : {none, bad_m2, bad_count}) {
    EXPECT_EQ(after.count[i], before.count[i]) << "pixel " << i;
    for (int c = 0; c < 3; ++c) EXPECT_EQ(after.raw[3 * i + c], before.raw[3 * i + c]) << "pixel " << i;
  }
  for (float v : out) ASSERT_TRUE(std::isfinite(v));
}

TEST(StatTemporalValidate, NeedsDepthMotionAndFp32Statistics) {
  auto without = [](ChannelId id) {
    std::vector<pipelines::InputChannel> c;
    for (const auto& d : channels())
      if (d.id != id) c.push_back(d);
    return c;
  };
  for (ChannelId id : {ChannelId::Depth, ChannelId::Motion, ChannelId::StatM3}) {
    const auto err = pipelines::validate(test::make_config("stat-temporal", 16, 16, without(id)));
    ASSERT_TRUE(err.has_value());
    EXPECT_EQ(err->problem, pipelines::ConfigProblem::MissingChannel);
  }
  auto half = channels();
  for (auto& c : half)
    if (c.id == ChannelId::StatMean) c.format = Format::F16;
  const auto err = pipelines::validate(test::make_config("stat-temporal", 16, 16, half));
  ASSERT_TRUE(err.has_value());
  EXPECT_EQ(err->problem, pipelines::ConfigProblem::InvalidChannel);
  EXPECT_NE(err->message.find("stat-temporal takes stat_mean in fp32 only"), std::string::npos) << err->message;
}

}  // namespace
}  // namespace dn
