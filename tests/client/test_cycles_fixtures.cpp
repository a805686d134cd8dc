// The cycles preset on real Blender Cycles EXRs (tests/fixtures/cycles, made
// by examples/blender/cycles_room.py with Debian's Blender 3.4.1): the
// channels it sends rebuild Combined, in split mode (lighting forms with
// their colour passes as modulators, docs/protocol.md §7.4) and in radiance
// mode (Denoising Albedo as the guide albedo).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "dn/image/exr_io.hpp"
#include "frame_source.hpp"
#include "presets.hpp"

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
    if (c.id == ChannelId::Albedo) EXPECT_EQ(c.describe(), "ViewLayer.Denoising Albedo.{R,G,B} (clamped to 1)");
    if (c.id == ChannelId::Emission) EXPECT_EQ(c.describe(), "ViewLayer.Emit.{R,G,B} + ViewLayer.Env.{R,G,B}");
    EXPECT_NE(c.id, ChannelId::DiffuseLighting);
    EXPECT_NE(c.id, ChannelId::SpecularLighting);
    EXPECT_NE(c.id, ChannelId::SpecularAlbedo);
    radiance = radiance || c.id == ChannelId::Radiance;
  }
  EXPECT_TRUE(radiance);
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

}  // namespace
