// Channel maps, the Cycles conversions and frame-path patterns.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>

#include "args.hpp"
#include "dn/image/exr_io.hpp"
#include "frame_source.hpp"
#include "presets.hpp"

namespace {

using namespace dn::cli;
using dn::image::ExrChannelOut;
using dn::image::ExrPixelType;
using dn::image::ExrReader;
using dn::protocol::ChannelId;

std::string tmp(const std::string& name) {
  return "/tmp/dn_client_test_" + std::to_string(::getpid()) + "_" + name;
}

// ---- a synthetic Blender/Cycles multilayer EXR --------------------------------
//
// A textured square moves by v = (+3, -2) pixels per frame in image
// coordinates (x right, y down: right and up on screen). Cycles computes its
// Vector pass in raster space, whose y axis points up (row 0 at the bottom),
// as Vector.xy = raster(previous position) - raster(current position), and
// Blender writes the rows to the EXR top row first. So a point at image
// position p was at p - v = (x - 3, y + 2) one frame earlier, whose raster y is
// (H - 1 - y) - 2: Vector.xy = (-3, -2) on the square, 0 elsewhere.
constexpr int W = 32, H = 24;
constexpr int kSquare = 8;
constexpr float kVx = 3.0f, kVy = -2.0f;

int square_x(int t) { return 6 + int(kVx) * t; }
int square_y(int t) { return 12 + int(kVy) * t; }
bool inside(int t, int x, int y) {
  return x >= square_x(t) && x < square_x(t) + kSquare && y >= square_y(t) && y < square_y(t) + kSquare;
}
// Texture in the square's own coordinates, so it moves with it.
float texel(int t, int x, int y) {
  return inside(t, x, y) ? 1.0f + 0.1f * float(x - square_x(t)) + 0.01f * float(y - square_y(t)) : 0.05f;
}

struct CyclesFrame {
  std::map<std::string, std::vector<float>> channels;  // name -> W*H, rows top-first
  void fill(const std::string& name, const std::function<float(int, int)>& f) {
    auto& v = channels[name];
    v.resize(size_t(W * H));
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) v[size_t(y * W + x)] = f(x, y);
  }
  void write(const std::string& path) const {
    std::vector<ExrChannelOut> out;
    for (const auto& [name, data] : channels) out.push_back({name, data.data(), 1, ExrPixelType::Float});
    dn::image::write_exr(path, W, H, out);
  }
};

CyclesFrame make_cycles_frame(int t, const std::string& layer = "ViewLayer", bool with_albedo = true) {
  CyclesFrame f;
  const std::string P = layer + ".";
  for (const char* c : {"R", "G", "B"}) {
    f.fill(P + "Combined." + c, [&](int x, int y) { return texel(t, x, y); });
    f.fill(P + "DiffDir." + c, [&](int x, int y) { return 0.25f * texel(t, x, y); });
    f.fill(P + "DiffInd." + c, [&](int x, int y) { return 0.5f * texel(t, x, y); });
    f.fill(P + "GlossDir." + c, [&](int, int) { return 0.125f; });
    f.fill(P + "GlossInd." + c, [&](int, int) { return 0.0625f; });
    if (with_albedo) f.fill(P + "DiffCol." + c, [&](int, int) { return 0.8f; });
    f.fill(P + "GlossCol." + c, [&](int, int) { return 0.04f; });
    f.fill(P + "Emit." + c, [&](int, int) { return 0.5f; });
    f.fill(P + "Env." + c, [&](int x, int y) { return inside(t, x, y) ? 0.0f : 2.0f; });
  }
  f.fill(P + "Normal.X", [](int, int) { return 0.0f; });
  f.fill(P + "Normal.Y", [](int, int) { return 0.0f; });
  f.fill(P + "Normal.Z", [](int, int) { return 1.0f; });
  f.fill(P + "Depth.Z", [&](int x, int y) { return inside(t, x, y) ? 5.0f : 1e10f; });
  f.fill(P + "Vector.X", [&](int x, int y) { return inside(t, x, y) ? -kVx : 0.0f; });
  f.fill(P + "Vector.Y", [&](int x, int y) { return inside(t, x, y) ? kVy : 0.0f; });  // raster y up
  f.fill(P + "Vector.Z", [&](int x, int y) { return inside(t, x, y) ? -kVx : 0.0f; });
  f.fill(P + "Vector.W", [&](int x, int y) { return inside(t, x, y) ? kVy : 0.0f; });
  return f;
}

dn::protocol::PipelineInfo pipeline(uint64_t required, uint64_t optional) {
  dn::protocol::PipelineInfo p;
  p.name = "svgf";
  p.required_channels = required;
  p.optional_channels = optional;
  return p;
}

uint64_t bits(std::initializer_list<ChannelId> ids) {
  uint64_t m = 0;
  for (auto id : ids) m |= dn::protocol::channel_bit(id);
  return m;
}

const LoadedPlane& plane(const LoadedFrame& f, ChannelId id) {
  for (const auto& p : f.planes)
    if (p.id == id) return p;
  throw std::runtime_error("no plane");
}

TEST(CyclesPreset, VectorAndDepthConversionOnSyntheticMotion) {
  const std::string prev_path = tmp("cycles_0001.exr"), cur_path = tmp("cycles_0002.exr");
  make_cycles_frame(1).write(prev_path);
  make_cycles_frame(2).write(cur_path);
  ExrReader cur(cur_path), prev(prev_path);

  Preset preset = make_preset("auto", cur.channels());
  EXPECT_EQ(preset.name, "cycles");
  EXPECT_EQ(preset.layer_prefix, "ViewLayer");
  const auto p = pipeline(bits({ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth,
                                ChannelId::Motion}),
                          bits({ChannelId::Diffuse, ChannelId::Specular, ChannelId::SpecularF0, ChannelId::Emission,
                                ChannelId::Roughness}));
  const auto plan = plan_channels(preset, {}, &p, std::nullopt, cur.channels(), cur_path);
  std::vector<ChannelId> ids;
  for (const auto& c : plan) ids.push_back(c.id);
  // Diffuse/specular split is left out because radiance is sent; no roughness
  // or SpecularF0 AOV in the file (GlossCol is not F0, docs/client.md).
  EXPECT_EQ(ids, (std::vector<ChannelId>{ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal,
                                         ChannelId::Depth, ChannelId::Motion, ChannelId::Emission}));

  const LoadedFrame fc = load_frame(cur, plan, 2);
  const LoadedFrame fp = load_frame(prev, plan, 1);
  const auto& mv = plane(fc, ChannelId::Motion).data;
  const auto& depth = plane(fc, ChannelId::Depth).data;
  const auto& rad_cur = plane(fc, ChannelId::Radiance).data;
  const auto& rad_prev = plane(fp, ChannelId::Radiance).data;
  int checked = 0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const size_t i = size_t(y * W + x);
      if (!inside(2, x, y)) {
        EXPECT_TRUE(std::isinf(depth[i]) && depth[i] > 0) << "background depth must be +inf";
        EXPECT_EQ(mv[2 * i], 0.0f);
        continue;
      }
      EXPECT_EQ(depth[i], 5.0f);
      // Canonical convention: p_prev = p + mv, pixels, y down.
      EXPECT_EQ(mv[2 * i + 0], -kVx);
      EXPECT_EQ(mv[2 * i + 1], -kVy);
      const int px = x + int(mv[2 * i + 0]), py = y + int(mv[2 * i + 1]);
      ASSERT_TRUE(px >= 0 && px < W && py >= 0 && py < H);
      // Reprojecting into the previous frame finds the same surface point.
      EXPECT_FLOAT_EQ(rad_prev[size_t(py * W + px) * 3], rad_cur[i * 3]) << x << "," << y;
      ++checked;
    }
  EXPECT_EQ(checked, kSquare * kSquare);

  // Sums of Cycles passes.
  const auto& emission = plane(fc, ChannelId::Emission).data;
  EXPECT_FLOAT_EQ(emission[0], 2.5f);  // Emit + Env in the background
  const auto split_plan =
      plan_channels(preset, {parse_channel_override("diffuse=DiffDir+DiffInd")}, &p, std::nullopt, cur.channels(),
                    cur_path);
  const LoadedFrame fs = load_frame(cur, split_plan, 2);
  const size_t c = size_t((square_y(2) + 1) * W + square_x(2) + 1);
  EXPECT_FLOAT_EQ(plane(fs, ChannelId::Diffuse).data[c * 3], 0.75f * rad_cur[c * 3]);
  std::remove(prev_path.c_str());
  std::remove(cur_path.c_str());
}

TEST(CyclesPreset, ConversionFunctions) {
  std::vector<float> d = {1.0f, 1e10f, std::numeric_limits<float>::quiet_NaN(), 0.0f, 3e9f, 123.0f, -2.0f};
  convert_cycles_depth(d);
  EXPECT_EQ(d[0], 1.0f);
  EXPECT_TRUE(std::isinf(d[1]));
  EXPECT_TRUE(std::isinf(d[2]));
  // Cycles' Denoising Depth is 0 on the sky: +inf, so that the conversion to
  // view depth (which adds the clip start) keeps it background.
  EXPECT_TRUE(std::isinf(d[3]) && d[3] > 0.0f);
  EXPECT_TRUE(std::isinf(d[4]));
  EXPECT_EQ(d[5], 123.0f);
  EXPECT_TRUE(std::isinf(d[6]) && d[6] > 0.0f);
  std::vector<float> v = {1.5f, 2.5f, -3.0f, -4.0f};
  convert_cycles_vector(v);
  EXPECT_EQ(v, (std::vector<float>{1.5f, -2.5f, -3.0f, 4.0f}));
}

TEST(CyclesPreset, CustomViewLayerIsDetected) {
  const std::string path = tmp("renderlayer.exr");
  make_cycles_frame(0, "RenderLayer").write(path);
  ExrReader r(path);
  Preset preset = make_preset("cycles", r.channels());
  EXPECT_EQ(preset.layer_prefix, "RenderLayer");
  const auto p = pipeline(bits({ChannelId::Radiance, ChannelId::Albedo}), 0);
  const auto plan = plan_channels(preset, {}, &p, std::nullopt, r.channels(), path);
  ASSERT_EQ(plan.size(), 2u);
  EXPECT_EQ(plan[1].describe(), "RenderLayer.DiffCol.{R,G,B}");
  std::remove(path.c_str());
}

TEST(ChannelMap, MissingRequiredChannelNamesChannelAndLayersTried) {
  const std::string path = tmp("noalbedo.exr");
  make_cycles_frame(0, "ViewLayer", /*with_albedo=*/false).write(path);
  ExrReader r(path);
  Preset preset = make_preset("auto", r.channels());
  const auto p = pipeline(bits({ChannelId::Radiance, ChannelId::Albedo}), 0);
  try {
    plan_channels(preset, {}, &p, std::nullopt, r.channels(), path);
    FAIL() << "albedo is missing";
  } catch (const ChannelMapError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("pipeline 'svgf' requires channel 'albedo'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("ViewLayer.DiffCol"), std::string::npos) << msg;
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("--channel albedo="), std::string::npos) << msg;
  }
  // An override that does not resolve names its own spec.
  try {
    plan_channels(preset, {parse_channel_override("albedo=BaseColor")}, &p, std::nullopt, r.channels(), path);
    FAIL();
  } catch (const ChannelMapError& e) {
    EXPECT_NE(std::string(e.what()).find("BaseColor|ViewLayer.BaseColor"), std::string::npos) << e.what();
  }
  // ... and one that does is used.
  const auto plan = plan_channels(preset, {parse_channel_override("albedo=GlossCol")}, &p, std::nullopt,
                                  r.channels(), path);
  EXPECT_EQ(plan[1].describe(), "ViewLayer.GlossCol.{R,G,B}");
  std::remove(path.c_str());
}

TEST(ChannelMap, DnrenderLayoutAndExplicitList) {
  const int w = 2, h = 2;
  std::vector<float> one(size_t(w * h), 1.0f);
  const std::string path = tmp("dnrender.exr");
  std::vector<ExrChannelOut> out;
  for (const char* n : {"radiance.R", "radiance.G", "radiance.B", "albedo.R", "albedo.G", "albedo.B", "normal.X",
                        "normal.Y", "normal.Z", "depth.Z", "motion.X", "motion.Y", "roughness.Y"})
    out.push_back({n, one.data(), 1, ExrPixelType::Half});
  dn::image::write_exr(path, w, h, out);
  ExrReader r(path);
  Preset preset = make_preset("auto", r.channels());
  EXPECT_EQ(preset.name, "dnrender");
  const auto plan = plan_channels(preset, {}, nullptr, parse_channel_list("radiance,roughness,motion"), r.channels(),
                                  path);
  ASSERT_EQ(plan.size(), 3u);
  EXPECT_EQ(plan[0].describe(), "radiance.{R,G,B}");
  EXPECT_EQ(plan[1].describe(), "roughness.Y");
  EXPECT_EQ(plan[2].describe(), "motion.{X,Y}");
  EXPECT_THROW(plan_channels(preset, {}, nullptr, parse_channel_list("radiance,specular"), r.channels(), path),
               ChannelMapError);
  std::remove(path.c_str());
}

// dnrender --stats layers -> the sample statistics (docs/protocol.md §7.7):
// sent for a pipeline that takes them, all four or none, and in F32 even with --fp16.
TEST(ChannelMap, DnrenderStatisticsAllFourInF32) {
  const int w = 3, h = 2, n = w * h;
  // Distinct values per layer and component, as dnrender writes them (float).
  std::map<std::string, std::vector<float>> layers;
  auto fill = [&](const std::string& layer, const std::string& comps, float base) {
    for (size_t c = 0; c < comps.size(); ++c) {
      auto& v = layers[layer + "." + comps[c]];
      for (int i = 0; i < n; ++i) v.push_back(base + 0.25f * float(c) + 0.0625f * float(i));
    }
  };
  fill("radiance", "RGB", 1.0f);
  fill("albedo", "RGB", 0.5f);
  fill("normal", "XYZ", 0.0f);
  fill("stat_count", "Y", 8.0f);
  fill("stat_mean", "RGB", -1.5f);
  fill("stat_m2", "RGB", 70000.0f);  // above binary16's 65504
  fill("stat_m3", "RGB", -3.0f);
  fill("stat_raw_mean", "RGB", 1.0f);
  auto write = [&](const std::string& path, const std::string& without) {
    std::vector<ExrChannelOut> out;
    for (const auto& [name, data] : layers)
      if (without.empty() || name.rfind(without + ".", 0) != 0) out.push_back({name, data.data(), 1, ExrPixelType::Float});
    dn::image::write_exr(path, w, h, out);
  };
  const std::string path = tmp("dnrender_stats.exr"), partial = tmp("dnrender_stats_partial.exr");
  write(path, "");
  write(partial, "stat_m3");
  ExrReader r(path), rp(partial);
  const Preset preset = make_preset("auto", r.channels());
  EXPECT_EQ(preset.name, "dnrender");
  const uint64_t statistics =
      bits({ChannelId::StatCount, ChannelId::StatMean, ChannelId::StatM2, ChannelId::StatM3});
  auto ids_of = [](const std::vector<ResolvedChannel>& plan) {
    std::vector<ChannelId> ids;
    for (const auto& c : plan) ids.push_back(c.id);
    return ids;
  };

  // stat's channel set: required, each from its own layer.
  const auto stat = pipeline(bits({ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal}) | statistics, 0);
  const auto plan = plan_channels(preset, {}, &stat, std::nullopt, r.channels(), path);
  ASSERT_EQ(ids_of(plan), (std::vector<ChannelId>{ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal,
                                                  ChannelId::StatCount, ChannelId::StatMean, ChannelId::StatM2,
                                                  ChannelId::StatM3}));
  EXPECT_EQ(plan[3].describe(), "stat_count.Y");
  EXPECT_EQ(plan[4].describe(), "stat_mean.{R,G,B}");
  EXPECT_EQ(plan[5].describe(), "stat_m2.{R,G,B}");
  EXPECT_EQ(plan[6].describe(), "stat_m3.{R,G,B}");
  const LoadedFrame f = load_frame(r, plan, 0);
  const std::pair<ChannelId, std::string> sources[] = {{ChannelId::StatCount, "stat_count"},
                                                        {ChannelId::StatMean, "stat_mean"},
                                                        {ChannelId::StatM2, "stat_m2"},
                                                        {ChannelId::StatM3, "stat_m3"}};
  for (const auto& [id, layer] : sources) {
    const auto& data = plane(f, id).data;
    const std::string comps = id == ChannelId::StatCount ? "Y" : "RGB";
    ASSERT_EQ(data.size(), size_t(n) * comps.size()) << layer;
    for (int i = 0; i < n; ++i)
      for (size_t c = 0; c < comps.size(); ++c)
        EXPECT_EQ(data[i * comps.size() + c], layers[layer + "." + comps[c]][i]) << layer << " pixel " << i;
  }
  // Declared F32 with --fp16 too; every other channel follows --fp16.
  for (ChannelId id : {ChannelId::StatCount, ChannelId::StatMean, ChannelId::StatM2, ChannelId::StatM3}) {
    EXPECT_EQ(wire_format(id, true), dn::protocol::Format::F32);
    EXPECT_EQ(wire_format(id, false), dn::protocol::Format::F32);
  }
  EXPECT_EQ(wire_format(ChannelId::Radiance, true), dn::protocol::Format::F16);
  EXPECT_EQ(wire_format(ChannelId::Radiance, false), dn::protocol::Format::F32);

  // A required statistic the file lacks stops the run, naming it.
  try {
    plan_channels(preset, {}, &stat, std::nullopt, rp.channels(), partial);
    FAIL() << "stat_m3 is missing";
  } catch (const ChannelMapError& e) {
    EXPECT_NE(std::string(e.what()).find("requires channel 'stat_m3'"), std::string::npos) << e.what();
  }
  // A pipeline that does not take them gets none.
  const auto svgf = pipeline(bits({ChannelId::Radiance, ChannelId::Albedo}), bits({ChannelId::Normal}));
  EXPECT_EQ(ids_of(plan_channels(preset, {}, &svgf, std::nullopt, r.channels(), path)),
            (std::vector<ChannelId>{ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal}));
  // Taken as optional: all four when the file has all four, none when it lacks one.
  const auto optional = pipeline(bits({ChannelId::Radiance}), statistics);
  EXPECT_EQ(ids_of(plan_channels(preset, {}, &optional, std::nullopt, r.channels(), path)),
            (std::vector<ChannelId>{ChannelId::Radiance, ChannelId::StatCount, ChannelId::StatMean,
                                    ChannelId::StatM2, ChannelId::StatM3}));
  EXPECT_EQ(ids_of(plan_channels(preset, {}, &optional, std::nullopt, rp.channels(), partial)),
            (std::vector<ChannelId>{ChannelId::Radiance}));
  // stat_raw_mean is no protocol channel: the raw mean is `radiance`.
  EXPECT_EQ(dn::protocol::find_channel("stat_raw_mean"), nullptr);
  std::remove(path.c_str());
  std::remove(partial.c_str());
}

TEST(ChannelMap, OverrideSyntax) {
  ChannelSpec s = parse_channel_override("normal=N.X,N.Y,N.Z");
  EXPECT_EQ(s.id, ChannelId::Normal);
  ASSERT_EQ(s.alternatives.size(), 1u);
  EXPECT_EQ(s.alternatives[0].terms[0].channels, (std::vector<std::string>{"N.X", "N.Y", "N.Z"}));
  s = parse_channel_override("motion=Vector@cycles");
  EXPECT_EQ(s.alternatives[0].convert, Convert::CyclesVector);
  s = parse_channel_override("emission = Emit + Env");
  EXPECT_EQ(s.alternatives[0].terms.size(), 2u);
  EXPECT_THROW(parse_channel_override("albedo"), ChannelMapError);
  EXPECT_THROW(parse_channel_override("colour=Foo"), ChannelMapError);
  EXPECT_THROW(parse_channel_override("normal=N.X,N.Y"), ChannelMapError);
  EXPECT_THROW(parse_channel_override("albedo=DiffCol@cycles"), ChannelMapError);
  EXPECT_THROW(parse_channel_override("albedo=A++B"), ChannelMapError);
  EXPECT_THROW(make_preset("arnold", {}), ChannelMapError);
  EXPECT_THROW(parse_channel_list("radiance,output"), ChannelMapError);
}

TEST(FramePaths, Patterns) {
  EXPECT_EQ(format_frame_path("in/frame_%04d.exr", 7), "in/frame_0007.exr");
  EXPECT_EQ(format_frame_path("in/frame_%d.exr", 123), "in/frame_123.exr");
  EXPECT_EQ(format_frame_path("in/####.exr", 42), "in/0042.exr");
  EXPECT_EQ(format_frame_path("100%%_%03d.png", 5), "100%_005.png");
  EXPECT_TRUE(has_frame_placeholder("a_%04d.exr"));
  EXPECT_FALSE(has_frame_placeholder("single.exr"));
  EXPECT_EQ(format_frame_path("single.exr", 3), "single.exr");
  EXPECT_THROW(format_frame_path("a_%s.exr", 1), UsageError);
  EXPECT_THROW(format_frame_path("a_%04d_%04d.exr", 1), UsageError);
}

}  // namespace
