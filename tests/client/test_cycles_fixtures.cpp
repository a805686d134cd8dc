// The cycles preset on real Blender Cycles EXRs (tests/fixtures/cycles, made
// by examples/blender/cycles_room.py with Debian's Blender 3.4.1): the
// channels it sends rebuild Combined, in split mode (lighting forms with
// their colour passes as modulators, docs/protocol.md §7.4) and in radiance
// mode (Denoising Albedo as the guide albedo); mirrors take the albedo and
// depth of what they reflect, and that depth is measured like Depth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "camera_recovery.hpp"
#include "dn/image/exr_io.hpp"
#include "frame_source.hpp"
#include "presets.hpp"
#include "reflection_features.hpp"
#include "unexplained_note.hpp"

namespace {

using namespace dn::cli;
using dn::protocol::ChannelId;

std::string fixture(const std::string& name) { return std::string(DN_CYCLES_FIXTURES) + "/" + name; }

dn::protocol::PipelineInfo svgf_like() {
  using dn::protocol::channel_bit;
  dn::protocol::PipelineInfo p;
  p.name = "svgf";
  p.required_channels = channel_bit(ChannelId::Albedo) | channel_bit(ChannelId::Normal) |
                        channel_bit(ChannelId::Depth) | channel_bit(ChannelId::Motion);
  p.optional_channels = channel_bit(ChannelId::Radiance) | channel_bit(ChannelId::Diffuse) |
                        channel_bit(ChannelId::Specular) | channel_bit(ChannelId::DiffuseLighting) |
                        channel_bit(ChannelId::SpecularLighting) | channel_bit(ChannelId::SpecularAlbedo) |
                        channel_bit(ChannelId::Emission) | channel_bit(ChannelId::Roughness);
  return p;
}

const std::vector<float>& plane(const LoadedFrame& f, ChannelId id) {
  for (const auto& p : f.planes)
    if (p.id == id) return p.data;
  throw std::runtime_error("plane missing: " + std::string(dn::protocol::find_channel(id)->name));
}

// The channels the plan sends, remodulated as the server does (modulators
// used as they are: the guard only matters where a modulator is < 1e-3,
// where the lighting passes are 0 in Cycles' output too).
TEST(CyclesFixtures, SplitChannelsRebuildCombined) {
  for (const char* name : {"frame_0000.exr", "frame_0002.exr", "ref_0001.exr"}) {
    SCOPED_TRACE(name);
    const dn::image::ExrReader exr(fixture(name));
    const Preset preset = make_preset("auto", exr.channels());
    ASSERT_EQ(preset.name, "cycles");
    auto p = svgf_like();
    p.optional_channels &= ~dn::protocol::channel_bit(ChannelId::Radiance);  // a pipeline without radiance: split
    const auto plan = plan_channels(preset, {}, &p, std::nullopt, exr.channels(), fixture(name));
    std::vector<ChannelId> ids;
    for (const auto& c : plan) ids.push_back(c.id);
    for (ChannelId want : {ChannelId::DiffuseLighting, ChannelId::SpecularLighting, ChannelId::SpecularAlbedo,
                           ChannelId::Emission, ChannelId::Roughness})
      EXPECT_NE(std::find(ids.begin(), ids.end(), want), ids.end()) << dn::protocol::find_channel(want)->name;
    EXPECT_EQ(std::find(ids.begin(), ids.end(), ChannelId::Diffuse), ids.end()) << "one form per signal";
    const LoadedFrame f = load_frame(exr, plan, 0);
    const auto combined = exr.read({"ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B"});
    const auto& dl = plane(f, ChannelId::DiffuseLighting);
    const auto& sl = plane(f, ChannelId::SpecularLighting);
    const auto& a = plane(f, ChannelId::Albedo);
    const auto& sa = plane(f, ChannelId::SpecularAlbedo);
    const auto& e = plane(f, ChannelId::Emission);
    double worst = 0.0, peak = 0.0;
    for (size_t i = 0; i < combined.size(); ++i) {
      const double rebuilt = double(dl[i]) * a[i] + double(sl[i]) * sa[i] + e[i];
      worst = std::max(worst, std::fabs(rebuilt - combined[i]) / std::max(1.0, double(std::fabs(combined[i]))));
      peak = std::max(peak, double(combined[i]));
    }
    EXPECT_LE(worst, 1e-5) << "worst |rebuilt - Combined| / max(1, Combined)";
    EXPECT_GT(peak, 10.0) << "the fixture should show the light in the mirror";
  }
}

// Radiance mode: Combined as it is, Denoising Albedo as the albedo (it
// follows the mirror to what it reflects), the split channels left out.
TEST(CyclesFixtures, RadianceModeTakesTheDenoisingAlbedo) {
  const dn::image::ExrReader exr(fixture("frame_0001.exr"));
  const Preset preset = make_preset("cycles", exr.channels());
  const auto p = svgf_like();
  const auto plan = plan_channels(preset, {}, &p, std::nullopt, exr.channels(), fixture("frame_0001.exr"));
  bool radiance = false;
  for (const auto& c : plan) {
    if (c.id == ChannelId::Albedo) EXPECT_EQ(c.describe(), "ViewLayer.Denoising Albedo.{R,G,B}");
    if (c.id == ChannelId::Emission) EXPECT_EQ(c.describe(), "ViewLayer.Emit.{R,G,B} + ViewLayer.Env.{R,G,B}");
    EXPECT_NE(c.id, ChannelId::DiffuseLighting);
    EXPECT_NE(c.id, ChannelId::SpecularLighting);
    EXPECT_NE(c.id, ChannelId::SpecularAlbedo);
    radiance = radiance || c.id == ChannelId::Radiance;
  }
  EXPECT_TRUE(radiance);
}

// Radiance mode's frame as dn denoise loads it: the plan, the camera
// recovered from the Position pass, the camera conversions and, with
// `rough_guides`, the per-pixel guides from the Roughness AOV.
struct RadianceFrame {
  LoadedFrame frame;
  std::optional<RoughGuidePlan> guides;
};
// `without`: EXR channels containing it are hidden from the plan (as if the
// file lacked them).
RadianceFrame load_radiance_frame(const std::string& name, bool rough_guides, const std::string& without = "") {
  const dn::image::ExrReader exr(fixture(name));
  std::vector<std::string> channels;
  for (const auto& c : exr.channels())
    if (without.empty() || c.find(without) == std::string::npos) channels.push_back(c);
  const Preset preset = make_preset("cycles", channels);
  const auto p = svgf_like();
  const auto plan = plan_channels(preset, {}, &p, std::nullopt, channels, fixture(name));
  RadianceFrame r;
  if (rough_guides) r.guides = plan_rough_guides(preset, plan, channels);
  r.frame = load_frame(exr, plan, 0, r.guides ? &*r.guides : nullptr);
  const auto positions = exr.read({"ViewLayer.Position.X", "ViewLayer.Position.Y", "ViewLayer.Position.Z"});
  const RecoveredCamera cam = recover_camera(positions, exr.width(), exr.height());
  r.frame.camera.view = cam.view;
  r.frame.camera.projection = cam.projection;
  apply_camera_conversions(r.frame, plan, exr);
  if (r.guides) apply_rough_guides(r.frame, *r.guides);
  return r;
}

// Denoising Depth is the length of the path to the first non-specular hit,
// from the near plane; converted, it is that point's depth along the view
// axis. On surfaces where Cycles stops at the primary hit (roughness^4 above
// 0.075^2, i.e. roughness > 0.27) it must equal the Depth pass (Cycles'
// camera-space z). At 1 spp both come from the one sample, taken at a random
// point of the pixel while the conversion uses the pixel centre's ray, which
// bounds the agreement at about (1/2 px / focal length) x tan(angle off the
// axis) ~ 0.5 % here; the raw path length is off by the clip start and by
// 1/cos(angle) - 1, several % (the test checks that it would see that).
TEST(CyclesFixtures, VirtualDepthIsTheViewDepthWhereCyclesStopsAtThePrimaryHit) {
  const RadianceFrame r = load_radiance_frame("frame_0000.exr", false);
  const dn::image::ExrReader exr(fixture("frame_0000.exr"));
  const auto z = exr.read_channel("ViewLayer.Depth.Z");
  const auto path = exr.read_channel("ViewLayer.Denoising Depth.Z");
  const auto rough = exr.read_channel("ViewLayer.Roughness.X");
  const auto& depth = plane(r.frame, ChannelId::Depth);
  double worst = 0.0, worst_unconverted = 0.0;
  size_t n = 0;
  for (size_t i = 0; i < z.size(); ++i) {
    if (!(rough[i] > 0.3f) || !(z[i] < 1e9f)) continue;
    worst = std::max(worst, std::fabs(double(depth[i]) - z[i]) / z[i]);
    worst_unconverted = std::max(worst_unconverted, std::fabs(double(path[i]) - z[i]) / z[i]);
    ++n;
  }
  EXPECT_GT(n, z.size() / 4) << "rough foreground pixels";
  EXPECT_LE(worst, 0.01) << "worst |virtual depth - Depth.Z| / Depth.Z";
  EXPECT_GE(worst_unconverted, 0.05) << "the raw path length differs (the test would see a missing conversion)";
}

// Cycles writes Depth 1e10 and Denoising Depth 0 where a ray leaves the
// scene; the Roughness AOV is 0 there, so the rough guides take the Denoising
// Depth. Either way the pixel must reach the server as background (+inf),
// not as a surface at the clip start, and no foreground pixel may.
TEST(CyclesFixtures, BackgroundPixelsStayBackgroundWithEveryGuide) {
  for (const char* name : {"frame_0000.exr", "window_0000.exr"})
    for (bool rough : {false, true}) {
      const RadianceFrame r = load_radiance_frame(name, rough);
      const dn::image::ExrReader exr(fixture(name));
      const auto z = exr.read_channel("ViewLayer.Depth.Z");
      const auto& depth = plane(r.frame, ChannelId::Depth);
      size_t background = 0;
      for (size_t i = 0; i < z.size(); ++i) {
        if (z[i] >= 1e9f) {
          ++background;
          ASSERT_TRUE(std::isinf(depth[i]) && depth[i] > 0.0f) << name << " rough " << rough << " pixel " << i << ": " << depth[i];
        } else {
          ASSERT_TRUE(std::isfinite(depth[i]) && depth[i] > 0.0f) << name << " rough " << rough << " pixel " << i;
        }
      }
      if (std::string(name) == "window_0000.exr") EXPECT_GT(background, 100u) << "the window shows the sky";
    }
}

// The passes the guide tests compare against, straight from the file.
struct GuidePasses {
  std::vector<float> z, rough, diffcol, dalb, dnrm;
  explicit GuidePasses(const std::string& name) {
    const dn::image::ExrReader exr(fixture(name));
    z = exr.read_channel("ViewLayer.Depth.Z");
    rough = exr.read_channel("ViewLayer.Roughness.X");
    diffcol = exr.read({"ViewLayer.DiffCol.R", "ViewLayer.DiffCol.G", "ViewLayer.DiffCol.B"});
    dalb = exr.read({"ViewLayer.Denoising Albedo.R", "ViewLayer.Denoising Albedo.G", "ViewLayer.Denoising Albedo.B"});
    dnrm = exr.read({"ViewLayer.Denoising Normal.X", "ViewLayer.Denoising Normal.Y", "ViewLayer.Denoising Normal.Z"});
  }
  // Where a mirror shows the world: Denoising Normal 0.
  bool shows_world(size_t i) const { return dnrm[3 * i] == 0.0f && dnrm[3 * i + 1] == 0.0f && dnrm[3 * i + 2] == 0.0f; }
};

// Mirrors (Roughness AOV < kCyclesMirrorRoughness) take the albedo and depth
// of what they reflect, so their depth lies beyond the mirror's own surface
// (the path goes on from it);
// every other pixel takes its primary hit's DiffCol and Depth.
TEST(CyclesFixtures, MirrorsTakeTheAlbedoAndDepthOfWhatTheyReflect) {
  const RadianceFrame r = load_radiance_frame("frame_0001.exr", true);
  ASSERT_TRUE(r.guides.has_value()) << "the fixture has the Roughness AOV";
  const GuidePasses f("frame_0001.exr");
  const auto &z = f.z, &rough = f.rough, &diffcol = f.diffcol, &dalb = f.dalb;
  const auto& depth = plane(r.frame, ChannelId::Depth);
  const auto& albedo = plane(r.frame, ChannelId::Albedo);
  size_t mirrors = 0, beyond = 0, others = 0;
  for (size_t i = 0; i < z.size(); ++i) {
    if (!(z[i] < 1e9f)) continue;
    if (rough[i] < kCyclesMirrorRoughness) {
      // Where the mirror shows the world (Denoising Normal 0), Cycles 3.4
      // leaves the depth at the mirror (later versions write FLT_MAX).
      const bool world = f.shows_world(i);
      ++mirrors;
      beyond += world ? depth[i] >= z[i] * 0.9999f : depth[i] > z[i] * 1.0001f;
      for (int k = 0; k < 3; ++k) ASSERT_EQ(albedo[3 * i + k], dalb[3 * i + k]) << "pixel " << i;
    } else {
      ++others;
      ASSERT_EQ(depth[i], z[i]) << "pixel " << i;
      for (int k = 0; k < 3; ++k) ASSERT_EQ(albedo[3 * i + k], diffcol[3 * i + k]) << "pixel " << i;
    }
  }
  EXPECT_GT(mirrors, 20u) << "the mirror sphere";
  EXPECT_GT(others, mirrors);
  EXPECT_EQ(beyond, mirrors) << "mirror pixels whose depth lies beyond the mirror";
}

// Without a Roughness AOV, a mirror is told by its path going on past the
// primary hit (the Denoising Depth beyond Depth), but only on a surface with
// a diffuse colour: a metal (DiffCol 0) may be glossy as well as a mirror
// (the gold sphere, roughness 0.2, whose one sampled reflection the
// Denoising passes follow too), and nothing in the file tells which, so it
// keeps DiffCol (0: the server shows it as rendered) and Depth. The file's
// AOV is the oracle for the rough pixels: DiffCol and Depth.
TEST(CyclesFixtures, WithoutTheRoughnessAovMetalsKeepTheDiffuseColour) {
  const RadianceFrame r = load_radiance_frame("frame_0001.exr", true, ".Roughness.");
  ASSERT_TRUE(r.guides.has_value());
  EXPECT_FALSE(r.guides->key.has_value());
  EXPECT_EQ(r.guides->describe_rule(), "the Denoising Depth lies beyond Depth");
  const GuidePasses f("frame_0001.exr");
  const auto &z = f.z, &rough = f.rough, &diffcol = f.diffcol, &dalb = f.dalb;
  const auto& depth = plane(r.frame, ChannelId::Depth);
  const auto& albedo = plane(r.frame, ChannelId::Albedo);
  size_t metals = 0, past_primary = 0, rough_pixels = 0;
  for (size_t i = 0; i < z.size(); ++i) {
    if (!(z[i] < 1e9f)) continue;
    const float* d = &diffcol[3 * i];
    if (std::max({d[0], d[1], d[2]}) < kReflectanceMin) {
      ++metals;
      bool differs = false;  // the Denoising Albedo would have differed
      for (int k = 0; k < 3; ++k) differs = differs || dalb[3 * i + k] != d[k];
      past_primary += differs;
      ASSERT_EQ(depth[i], z[i]) << "pixel " << i;
      for (int k = 0; k < 3; ++k) ASSERT_EQ(albedo[3 * i + k], d[k]) << "pixel " << i;
    } else if (rough[i] > 0.3f) {
      ++rough_pixels;
      ASSERT_EQ(depth[i], z[i]) << "pixel " << i;
      for (int k = 0; k < 3; ++k) ASSERT_EQ(albedo[3 * i + k], d[k]) << "pixel " << i;
    }
  }
  // The spheres are in view, and their Denoising Albedo (what the test would see taken) is not DiffCol.
  EXPECT_GT(metals, 40u);
  EXPECT_GT(past_primary, metals / 2);
  EXPECT_GT(rough_pixels, metals);
}

// dn denoise's note on pixels kept as rendered: without Denoising Data every
// mirror and metal; with it but without the Roughness AOV the metals; with
// both none, and none when the pipeline does not keep them or the user
// turned keep_unexplained off.
TEST(CyclesFixtures, NoteNamesThePassesThatWouldDenoiseKeptPixels) {
  auto note = [](const std::string& name, const std::string& without, bool takes_keep,
                 std::vector<dn::protocol::Parameter> params = {}) {
    const dn::image::ExrReader exr(fixture(name));
    std::vector<std::string> channels;
    for (const auto& c : exr.channels())
      if (without.empty() || c.find(without) == std::string::npos) channels.push_back(c);
    const Preset preset = make_preset("cycles", channels);
    auto p = svgf_like();
    if (takes_keep) p.parameters.push_back({"keep_unexplained"});
    const auto plan = plan_channels(preset, {}, &p, std::nullopt, channels, fixture(name));
    const auto guides = plan_rough_guides(preset, plan, channels);
    return unexplained_pixels_note(preset, plan, guides ? &*guides : nullptr, &p, params);
  };
  EXPECT_NE(note("nodd_0000.exr", "", true).find("enable View Layer > Passes > Data > Denoising Data"),
            std::string::npos);
  EXPECT_NE(note("frame_0000.exr", ".Roughness.", true).find("add a Value AOV named Roughness"), std::string::npos);
  EXPECT_EQ(note("frame_0000.exr", "", true), "");
  EXPECT_EQ(note("nodd_0000.exr", "", false), "");
  EXPECT_EQ(note("nodd_0000.exr", "", true, {{"keep_unexplained", 0.0}}), "");
}

// A missing pass names the Blender setting that makes it.
TEST(CyclesFixtures, MissingPassNamesTheBlenderSetting) {
  const dn::image::ExrReader exr(fixture("frame_0000.exr"));
  std::vector<std::string> channels;
  for (const auto& c : exr.channels())
    if (c.find(".DiffCol.") == std::string::npos && c.find(".Denoising Albedo.") == std::string::npos)
      channels.push_back(c);
  const Preset preset = make_preset("cycles", channels);
  const auto p = svgf_like();
  try {
    plan_channels(preset, {}, &p, std::nullopt, channels, "frame.exr");
    FAIL() << "albedo is missing";
  } catch (const ChannelMapError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("Passes > Data > Denoising Data"), std::string::npos) << msg;
    EXPECT_NE(msg.find("Passes > Light > Diffuse: Color"), std::string::npos) << msg;
  }
}

// A pipeline that accepts every channel but uses only radiance (passthrough)
// gets the file's plain layers: no camera, no mirror guides, no reflection
// features, with or without the Denoising Data and Position passes.
TEST(CyclesFixtures, AcceptedChannelsAreSentAsTheFileHasThem) {
  dn::protocol::PipelineInfo passthrough;
  passthrough.name = "passthrough";
  passthrough.required_channels = dn::protocol::channel_bit(ChannelId::Radiance);
  for (const auto& c : dn::protocol::kChannels)
    if (c.id != ChannelId::Radiance && c.id != ChannelId::Output)
      passthrough.optional_channels |= dn::protocol::channel_bit(c.id);
  const dn::image::ExrReader exr(fixture("frame_0000.exr"));
  auto without = [&](std::initializer_list<const char*> passes) {
    std::vector<std::string> out;
    for (const auto& c : exr.channels())
      if (std::none_of(passes.begin(), passes.end(), [&](const char* p) { return c.find(p) != std::string::npos; }))
        out.push_back(c);
    return out;
  };
  for (const auto& channels : {exr.channels(), without({".Denoising "}), without({".Denoising ", ".Position."})}) {
    const Preset preset = make_preset("cycles", channels);
    const auto plan = plan_channels(preset, {}, &passthrough, std::nullopt, channels, "frame.exr");
    EXPECT_FALSE(plan_needs_camera(&passthrough, plan));
    for (const auto& c : plan) {
      EXPECT_FALSE(is_derived(c.convert, c.past_specular)) << dn::protocol::find_channel(c.id)->name;
      if (c.id == ChannelId::Depth) EXPECT_EQ(c.describe(), "ViewLayer.Depth.Z (Cycles depth)");
    }
    EXPECT_FALSE(plan_rough_guides(preset, plan, channels));
  }
}

// A derived reflection feature is made only when the passes its conversion
// reads exist: without the Denoising Data the hit (Position + direction x the
// length the Denoising Depth gives) cannot be made, so a pipeline that
// requires it is refused at planning, naming the pass.
TEST(CyclesFixtures, ReflectionHitNeedsTheDenoisingDepth) {
  dn::protocol::PipelineInfo p;
  p.name = "needs-hit";
  p.required_channels = dn::protocol::channel_bit(ChannelId::Radiance) |
                        dn::protocol::channel_bit(ChannelId::ReflectionPosition);
  const dn::image::ExrReader exr(fixture("frame_0000.exr"));
  std::vector<std::string> channels;
  for (const auto& c : exr.channels())
    if (c.find(".Denoising Depth.") == std::string::npos) channels.push_back(c);
  const Preset preset = make_preset("cycles", channels);
  try {
    plan_channels(preset, {}, &p, std::nullopt, channels, "frame.exr");
    FAIL() << "the reflection position cannot be made";
  } catch (const ChannelMapError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("requires channel 'reflection_position'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("with ViewLayer.Denoising Depth"), std::string::npos) << msg;
    EXPECT_NE(msg.find("Passes > Data > Denoising Data"), std::string::npos) << msg;
  }
  // With the pass, the hit's source is the Denoising Depth.
  const Preset full = make_preset("cycles", exr.channels());
  const auto plan = plan_channels(full, {}, &p, std::nullopt, exr.channels(), "frame.exr");
  ASSERT_EQ(plan.back().id, ChannelId::ReflectionPosition);
  ASSERT_EQ(plan.back().sources.size(), 1u);
  EXPECT_EQ(plan.back().sources[0], std::vector<std::string>{"ViewLayer.Denoising Depth.Z"});
  EXPECT_TRUE(plan_needs_camera(&p, plan));
}

// The layers of a file: its channel names less the component, sorted, once each.
std::vector<std::string> layers_of(const std::vector<std::string>& channels) {
  std::vector<std::string> out;
  for (const auto& c : channels) out.push_back(c.substr(0, c.rfind('.')));
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// What cycles_room.py --passes preset writes: the passes the cycles preset
// reads without Denoising Data, no Mist, no shader AOVs (README of the fixtures).
const std::vector<std::string> kPresetLayers = {
    "ViewLayer.Combined", "ViewLayer.Depth",     "ViewLayer.DiffCol",  "ViewLayer.DiffDir",  "ViewLayer.DiffInd",
    "ViewLayer.Emit",     "ViewLayer.Env",       "ViewLayer.GlossCol", "ViewLayer.GlossDir", "ViewLayer.GlossInd",
    "ViewLayer.Normal",   "ViewLayer.Position",  "ViewLayer.TransCol", "ViewLayer.TransDir", "ViewLayer.TransInd",
    "ViewLayer.Vector",   "ViewLayer.VolumeDir", "ViewLayer.VolumeInd"};

TEST(CyclesFixtures, NoDenoisingDataFilesHoldOnlyThePresetPasses) {
  for (const char* name : {"nodd_0000.exr", "nodd_0001.exr", "nodd_0002.exr"}) {
    SCOPED_TRACE(name);
    const dn::image::ExrReader exr(fixture(name));
    EXPECT_EQ(layers_of(exr.channels()), kPresetLayers);
    EXPECT_EQ(exr.channels().size(), 54u);  // Combined RGBA, Vector XYZW, 1 each for Depth, 3 for the rest
    EXPECT_EQ(exr.width(), 64);
    EXPECT_EQ(exr.height(), 36);
  }
}

TEST(CyclesFixtures, FourSppFilesHoldEveryPass) {
  std::vector<std::string> want = kPresetLayers;
  for (const char* l : {"Denoising Albedo", "Denoising Depth", "Denoising Normal", "Mist", "Roughness", "SpecularF0"})
    want.push_back(std::string("ViewLayer.") + l);
  std::sort(want.begin(), want.end());
  const dn::image::ExrReader frame(fixture("frame_0000.exr"));
  for (const char* name : {"spp4_0000.exr", "spp4_0001.exr", "spp4_0002.exr"}) {
    SCOPED_TRACE(name);
    const dn::image::ExrReader exr(fixture(name));
    EXPECT_EQ(layers_of(exr.channels()), want);
    EXPECT_EQ(exr.channels(), frame.channels()) << "the 1-spp fixtures' channels, all 67";
    EXPECT_EQ(exr.channels().size(), 67u);
  }
}

// The passes a file holds do not change the render: the Combined pass of the
// no-Denoising-Data files is the 1-spp input's (same seed, same samples) up to
// Cycles' run-to-run float noise, which two renders with the same settings show
// as well (a fraction of a percent of the values, at most ~5e-4 relative).
// A render with other samples (the 4-spp files, same seed) is far from it.
TEST(CyclesFixtures, DenoisingDataDoesNotChangeTheRender) {
  const std::vector<std::string> rgba = {"ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B",
                                         "ViewLayer.Combined.A"};
  for (const char* n : {"0000", "0001", "0002"}) {
    SCOPED_TRACE(n);
    const auto a = dn::image::ExrReader(fixture(std::string("nodd_") + n + ".exr")).read(rgba);
    const auto b = dn::image::ExrReader(fixture(std::string("frame_") + n + ".exr")).read(rgba);
    const auto c = dn::image::ExrReader(fixture(std::string("spp4_") + n + ".exr")).read(rgba);
    ASSERT_EQ(a.size(), b.size());
    ASSERT_EQ(c.size(), b.size());
    double diff = 0.0, other = 0.0, total = 0.0;
    size_t far = 0;
    for (size_t i = 0; i < b.size(); ++i) {
      const double d = std::fabs(double(a[i]) - b[i]);
      far += d > 2e-3 * std::max(0.01, double(std::fabs(b[i])));
      diff += d;
      other += std::fabs(double(c[i]) - b[i]);
      total += std::fabs(b[i]);
    }
    EXPECT_EQ(far, 0u) << "values differing by more than 2e-3 relative";
    EXPECT_LE(diff, 1e-5 * total) << "sum |nodd - frame| over sum |frame|";
    EXPECT_GE(other, 0.05 * total) << "sum |spp4 - frame| over sum |frame|: other samples";
  }
}

// Without Denoising Data and AOVs (Blender's defaults plus the light passes)
// svgf runs on the primary hit's guides: DiffCol as albedo, the Depth pass,
// no mirror guides.
TEST(CyclesFixtures, WithoutDenoisingDataSvgfTakesThePrimaryHitsGuides) {
  const dn::image::ExrReader exr(fixture("nodd_0001.exr"));
  const Preset preset = make_preset("auto", exr.channels());
  ASSERT_EQ(preset.name, "cycles");
  const auto p = svgf_like();
  const auto plan = plan_channels(preset, {}, &p, std::nullopt, exr.channels(), fixture("nodd_0001.exr"));
  std::string albedo, depth;
  for (const auto& c : plan) {
    if (c.id == ChannelId::Albedo) albedo = c.describe();
    if (c.id == ChannelId::Depth) depth = c.describe();
  }
  EXPECT_EQ(albedo, "ViewLayer.DiffCol.{R,G,B}");
  EXPECT_EQ(depth, "ViewLayer.Depth.Z (Cycles depth)");
  EXPECT_FALSE(plan_rough_guides(preset, plan, exr.channels()));
}

}  // namespace

namespace reflect_features {

// What the cycles preset sends to `reflect` (docs/client.md, "Reflection
// features from Cycles passes"): on the mirror sphere (Roughness AOV <
// kCyclesMirrorRoughness) the derived hit, Position + mirror direction x
// (path length past the primary hit), is a point of the scene; where that
// point is in view, the Position pass of the pixel it projects to holds it
// within that pixel's footprint (points hidden from the camera do not match).
// The direction obeys the law of reflection about the Normal pass, and where
// Cycles stops at the primary hit (roughness > 0.27) there is no chain, and
// the Denoising Normal (camera space) converted is the Normal pass. The
// length past the mirror against the scene's own geometry.
TEST(CyclesFixtures, ReflectionFeaturesPutTheMirrorsHitOnTheScene) {
  using dn::protocol::channel_bit;
  dn::protocol::PipelineInfo reflect;
  reflect.name = "reflect";
  for (ChannelId id : {ChannelId::Specular, ChannelId::Albedo, ChannelId::SpecularF0, ChannelId::Roughness,
                       ChannelId::Normal, ChannelId::Depth, ChannelId::Motion, ChannelId::Position,
                       ChannelId::ReflectionPosition, ChannelId::ReflectionAlbedo, ChannelId::ReflectionNormal,
                       ChannelId::ReflectionDepth, ChannelId::ReflectionDirection, ChannelId::ReflectionDistance})
    reflect.required_channels |= channel_bit(id);
  reflect.optional_channels = channel_bit(ChannelId::Diffuse) | channel_bit(ChannelId::Emission);
  const std::string name = fixture("frame_0001.exr");
  const dn::image::ExrReader exr(name);
  const Preset preset = make_preset("cycles", exr.channels());
  const auto plan = plan_channels(preset, {}, &reflect, std::nullopt, exr.channels(), name);
  LoadedFrame frame = load_frame(exr, plan, 1);
  const auto positions = exr.read({"ViewLayer.Position.X", "ViewLayer.Position.Y", "ViewLayer.Position.Z"});
  const RecoveredCamera cam = recover_camera(positions, exr.width(), exr.height());
  frame.camera.view = cam.view;
  frame.camera.projection = cam.projection;
  apply_camera_conversions(frame, plan, exr);
  derive_reflection_features(frame, plan, exr);

  const int w = exr.width(), h = exr.height();
  const auto rough = exr.read_channel("ViewLayer.Roughness.X");
  const auto normal = exr.read({"ViewLayer.Normal.X", "ViewLayer.Normal.Y", "ViewLayer.Normal.Z"});
  const auto& hit = plane(frame, ChannelId::ReflectionPosition);
  const auto& dir = plane(frame, ChannelId::ReflectionDirection);
  const auto& dist = plane(frame, ChannelId::ReflectionDistance);
  const auto& pos = plane(frame, ChannelId::Position);
  const auto& rnormal = plane(frame, ChannelId::ReflectionNormal);
  size_t normals_agree = 0;
  double eye[3];
  {
    // The camera position: -R^T t of the (rigid) view matrix.
    const auto& v = cam.view;
    for (int k = 0; k < 3; ++k) eye[k] = -(v[4 * k] * v[12] + v[4 * k + 1] * v[13] + v[4 * k + 2] * v[14]);
  }
  // Projection with the recovered camera (column-major view and projection).
  auto project = [&](const float* p, int& px, int& py) {
    const auto& v = cam.view;
    const auto& m = cam.projection;
    double e[4], c[4];
    for (int r = 0; r < 4; ++r) e[r] = v[r] * p[0] + v[4 + r] * p[1] + v[8 + r] * p[2] + v[12 + r];
    for (int r = 0; r < 4; ++r) c[r] = m[r] * e[0] + m[4 + r] * e[1] + m[8 + r] * e[2] + m[12 + r] * e[3];
    if (!(c[3] > 0.0)) return false;
    px = int(std::floor((c[0] / c[3] + 1.0) * 0.5 * w));
    py = int(std::floor((1.0 - c[1] / c[3]) * 0.5 * h));
    return px >= 0 && py >= 0 && px < w && py < h;
  };
  size_t exact_length = 0;
  size_t mirrors = 0, in_view = 0, on_surface = 0, rough_without_chain = 0, rough_pixels = 0;
  for (size_t i = 0; i < rough.size(); ++i) {
    const double n[3] = {normal[3 * i], normal[3 * i + 1], normal[3 * i + 2]};
    const double nn = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(nn > 0.5)) continue;  // background
    const double r[3] = {dir[3 * i], dir[3 * i + 1], dir[3 * i + 2]};
    EXPECT_NEAR(std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]), 1.0, 1e-5) << "pixel " << i;
    EXPECT_GT(r[0] * n[0] + r[1] * n[1] + r[2] * n[2], -1e-4) << "the mirror direction leaves the surface";
    if (rough[i] > 0.3f) {
      ++rough_pixels;
      // Where the path stops at the primary hit the Denoising Normal (camera
      // space, converted) is the Normal pass's (world space).
      const double dot = (rnormal[3 * i] * n[0] + rnormal[3 * i + 1] * n[1] + rnormal[3 * i + 2] * n[2]) / nn;
      normals_agree += dot > 0.999;
      rough_without_chain += dist[i] == 0.0f;
      continue;
    }
    if (!(rough[i] < kCyclesMirrorRoughness) || !(dist[i] > 0.0f)) continue;
    ++mirrors;
    // The scene as examples/blender/cycles_room.py builds it: the mirror
    // sphere (centre (-0.8, 1.2, 0.6), radius 0.6) in the room [-2.5, 2.5] x
    // [-3, 3] x [0, 2.8]. The exact length past the mirror, with the analytic
    // normal, to the room's walls (other objects in the way: no match).
    {
      const double c[3] = {-0.8, 1.2, 0.6};
      double dv[3], u[3], rr[3], dl = 0.0, ul = 0.0;
      for (int k = 0; k < 3; ++k) dv[k] = pos[3 * i + k] - eye[k], u[k] = pos[3 * i + k] - c[k];
      for (int k = 0; k < 3; ++k) dl += dv[k] * dv[k], ul += u[k] * u[k];
      dl = std::sqrt(dl), ul = std::sqrt(ul);
      double du = 0.0;
      for (int k = 0; k < 3; ++k) dv[k] /= dl, u[k] /= ul, du += dv[k] * u[k];
      for (int k = 0; k < 3; ++k) rr[k] = dv[k] - 2.0 * du * u[k];
      const double lo[3] = {-2.5, -3.0, 0.0}, hi[3] = {2.5, 3.0, 2.8};
      double t = 1e30;
      for (int k = 0; k < 3; ++k) {
        if (rr[k] > 0) t = std::min(t, (hi[k] - pos[3 * i + k]) / rr[k]);
        if (rr[k] < 0) t = std::min(t, (lo[k] - pos[3 * i + k]) / rr[k]);
      }
      exact_length += std::fabs(dist[i] - t) <= 0.01 * t;
    }
    int px, py;
    if (!project(&hit[3 * i], px, py)) continue;
    const size_t j = size_t(py) * w + px;
    const double d[3] = {pos[3 * j] - hit[3 * i], pos[3 * j + 1] - hit[3 * i + 1], pos[3 * j + 2] - hit[3 * i + 2]};
    const double gap = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    ++in_view;
    // The Position there is a random point of that pixel (1 spp): allow
    // 1.5 pixel footprints at the hit's distance from the camera.
    const double eye_dist = std::sqrt((hit[3 * i] - eye[0]) * (hit[3 * i] - eye[0]) +
                                      (hit[3 * i + 1] - eye[1]) * (hit[3 * i + 1] - eye[1]) +
                                      (hit[3 * i + 2] - eye[2]) * (hit[3 * i + 2] - eye[2]));
    on_surface += gap <= 1.5 * eye_dist * 2.0 / (cam.projection[5] * h);
  }
  std::printf("mirror pixels %zu, hit in view %zu, on the surface there %zu; rough pixels %zu without a chain %zu, "
              "normals agreeing %zu; length past the mirror within 1 %% of the analytic room's %zu\n", mirrors, in_view,
              on_surface, rough_pixels, rough_without_chain, normals_agree, exact_length);
  EXPECT_GT(mirrors, 20u) << "the mirror sphere";
  EXPECT_GT(in_view, mirrors / 4);
  EXPECT_GE(on_surface, in_view * 4 / 5) << "derived hits where the scene is";
  // Cycles' Denoising Depth weighs the length past the mirror by its albedo
  // (0.95 here): without undoing that the lengths are 5 % short.
  EXPECT_GE(exact_length, mirrors * 9 / 10) << "lengths past the mirror within 1 % of the scene's";
  EXPECT_EQ(rough_without_chain, rough_pixels);
  EXPECT_GE(normals_agree, rough_pixels * 99 / 100) << "Denoising Normal to world";
}

}  // namespace reflect_features
