// dnrender's argument parsing: every option, and clear errors for bad ones.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>

#include "cli.hpp"
#include "dn/protocol/channels.hpp"
#include "stream.hpp"

namespace dn::render {
namespace {

TEST(RendererCli, ParsesEveryOption) {
  const CliOptions o = parse_cli({"--scene", "3", "--frames", "10", "--first", "5", "--hold-camera", "7", "--width", "320", "--height",
                                  "180", "--spp", "0.25", "--seed", "9", "--out", "o", "--reference", "512", "--cache",
                                  "c", "--server", "tcp://h:1", "--pipeline", "svgf", "--in-flight", "3", "--stats",
                                  "--reflection", "--jitter", "--max-depth", "5", "--threads", "2", "--send-split",
                                  "--png", "--quiet", "--gbuffer-grid", "2", "--reference2"});
  EXPECT_EQ(o.scene, 3);
  EXPECT_EQ(o.frames, 10);
  EXPECT_EQ(o.first, 5);
  EXPECT_EQ(o.hold_camera, 7);
  EXPECT_EQ(o.render.width, 320);
  EXPECT_EQ(o.render.height, 180);
  EXPECT_DOUBLE_EQ(o.render.spp, 0.25);
  EXPECT_EQ(o.render.seed, 9u);
  EXPECT_EQ(o.out, "o");
  EXPECT_EQ(o.reference_spp, 512);
  EXPECT_EQ(o.cache, "c");
  EXPECT_TRUE(o.reference2);
  EXPECT_EQ(o.server, "tcp://h:1");
  EXPECT_EQ(o.pipeline, "svgf");
  EXPECT_EQ(o.in_flight, 3);
  EXPECT_TRUE(o.render.channels.statistics && o.render.channels.reflection && o.render.jitter);
  EXPECT_EQ(o.render.max_depth, 5);
  EXPECT_EQ(o.render.threads, 2);
  EXPECT_EQ(o.render.gbuffer_grid, 2);
  EXPECT_TRUE(o.send_split && o.png && o.quiet);
  EXPECT_FALSE(o.help);
}

// --reference2 writes the second reference next to the first in --out.
TEST(RendererCli, SecondReferenceIsCopiedToOut) {
  const auto dir = std::filesystem::temp_directory_path() / ("dn_renderer_cli_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const std::string out = (dir / "seq").string(), cache = (dir / "cache").string();
  ASSERT_EQ(run_cli(parse_cli({"--scene", "2", "--width", "32", "--height", "18", "--frames", "2", "--reference", "2",
                               "--reference2", "--cache", cache, "--out", out, "--quiet"})),
            0);
  for (const char* name : {"ref_0000.exr", "ref2_0000.exr", "ref_0001.exr", "ref2_0001.exr", "frame_0001.exr"})
    EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(out) / name)) << name;
  std::filesystem::remove_all(dir);
}

TEST(RendererCli, RejectsBadArguments) {
  for (const std::vector<std::string>& bad :
       std::vector<std::vector<std::string>>{{"--scene", "7"},
                                             {"--scene", "x"},
                                             {"--spp", "0"},
                                             {"--spp", "-1"},
                                             {"--width", "0"},
                                             {"--frames"},
                                             {"--bogus"},
                                             {"--server", "tcp://h:1"},
                                             {"--png"},
                                             {"--height", "12abc"},
                                             {"--gbuffer-grid", "-1"},
                                             {"--reference2"}})
    EXPECT_THROW(parse_cli(bad), UsageError) << bad[0];
  try {
    parse_cli({"--scene", "8"});
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("--scene"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace dn::render

namespace dn::render {
namespace {

uint64_t mask(std::initializer_list<protocol::ChannelId> ids) {
  uint64_t m = 0;
  for (auto id : ids) m |= protocol::channel_bit(id);
  return m;
}

// Streaming renders only what the pipeline takes.
TEST(RendererStream, ChannelsForAPipeline) {
  using protocol::ChannelId;
  const ChannelSet radiance_only = channels_for(mask({ChannelId::Radiance}), false);
  EXPECT_FALSE(radiance_only.split || radiance_only.gbuffer || radiance_only.motion || radiance_only.sample_count);
  const ChannelSet accumulate =
      channels_for(mask({ChannelId::Radiance, ChannelId::Normal, ChannelId::Depth, ChannelId::Motion}), false);
  EXPECT_TRUE(accumulate.gbuffer && accumulate.motion);
  EXPECT_FALSE(accumulate.split || accumulate.sample_count);
  const ChannelSet fb = channels_for(mask({ChannelId::Diffuse, ChannelId::Specular, ChannelId::Albedo,
                                           ChannelId::SpecularF0, ChannelId::Roughness, ChannelId::Normal,
                                           ChannelId::Depth, ChannelId::Motion, ChannelId::Emission}),
                                     false);
  EXPECT_TRUE(fb.split && fb.gbuffer && fb.motion);
  EXPECT_FALSE(fb.statistics || fb.reflection || fb.sample_count);
  // Radiance or split: split only when asked to send it (or for emission).
  const ChannelSet either = channels_for(mask({ChannelId::Radiance, ChannelId::Diffuse, ChannelId::Specular}), false);
  EXPECT_FALSE(either.split);
  EXPECT_TRUE(channels_for(mask({ChannelId::Radiance, ChannelId::Diffuse, ChannelId::Specular}), true).split);
  // The reflection features (ids 15-21) only for a pipeline that takes one of them.
  EXPECT_FALSE(channels_for(mask({ChannelId::Radiance, ChannelId::Roughness, ChannelId::Depth}), false).reflection);
  for (int id = 15; id <= 21; ++id) {
    const ChannelSet reflect = channels_for(mask({ChannelId::Radiance, static_cast<ChannelId>(id)}), false);
    EXPECT_TRUE(reflect.reflection) << id;
    EXPECT_FALSE(reflect.statistics) << id;
  }
}

}  // namespace
}  // namespace dn::render
