// dnrender's argument parsing: every option, and clear errors for bad ones.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>

#include "cli.hpp"
#include "reference_cache.hpp"
#include "dn/protocol/channels.hpp"
#include "scenes.hpp"
#include "stream.hpp"
#include "test_support.hpp"

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

TEST(RendererCli, ShareInputGoesToTheSession) {
  EXPECT_FALSE(parse_cli({"--server", "tcp://h:1", "--pipeline", "svgf"}).share_input);
  EXPECT_TRUE(parse_cli({"--server", "tcp://h:1", "--pipeline", "svgf", "--share-input"}).share_input);
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

TEST(RendererCli, DefaultReferenceCacheFollowsXdg) {
  EXPECT_EQ(default_cache_dir("/x/cache", "/home/u"), "/x/cache/dnrender");
  EXPECT_EQ(default_cache_dir(nullptr, "/home/u"), "/home/u/.cache/dnrender");
  EXPECT_EQ(default_cache_dir("", "/home/u"), "/home/u/.cache/dnrender");  // empty counts as unset (XDG spec)
  try {
    default_cache_dir(nullptr, "");
    ADD_FAILURE() << "no cache directory without $XDG_CACHE_HOME and $HOME";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("--cache"), std::string::npos) << e.what();
  }
}

// Without --cache, references go to $XDG_CACHE_HOME/dnrender: nothing is
// written into the current directory, only the copies into --out.
TEST(RendererCli, ReferencesWithoutCacheLeaveTheCurrentDirectoryAlone) {
  const auto dir = std::filesystem::temp_directory_path() / ("dn_renderer_xdg_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const auto cwd = dir / "cwd", xdg = dir / "xdg", out = dir / "seq";
  std::filesystem::create_directories(cwd);
  const auto previous_cwd = std::filesystem::current_path();
  const char* previous_xdg = std::getenv("XDG_CACHE_HOME");
  const std::string saved_xdg = previous_xdg ? previous_xdg : "";
  std::filesystem::current_path(cwd);
  ::setenv("XDG_CACHE_HOME", xdg.c_str(), 1);
  const int status = run_cli(parse_cli({"--scene", "2", "--width", "16", "--height", "9", "--frames", "1", "--reference",
                                        "2", "--out", out.string(), "--quiet"}));
  std::filesystem::current_path(previous_cwd);
  if (previous_xdg) ::setenv("XDG_CACHE_HOME", saved_xdg.c_str(), 1);
  else ::unsetenv("XDG_CACHE_HOME");
  ASSERT_EQ(status, 0);
  EXPECT_TRUE(std::filesystem::is_empty(cwd)) << "dnrender wrote into the current directory";
  EXPECT_TRUE(std::filesystem::exists(reference_path((xdg / "dnrender").string(), 2, 16, 9, 0, 2)));
  EXPECT_TRUE(std::filesystem::exists(out / "ref_0000.exr"));
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
                                             {"--reference2"},
                                             {"--share-input"},
                                             {"--server", "tcp://h:1", "--pipeline", "svgf", "--share-input",
                                              "--send-split"}})
    EXPECT_THROW(parse_cli(bad), UsageError) << bad[0];
  try {
    parse_cli({"--scene", "8"});
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("--scene"), std::string::npos) << e.what();
  }
}

TEST(RendererCli, ParsesSppSchedule) {
  EXPECT_EQ(parse_cli({}).render.spp_schedule, SppSchedule::Stratified);
  EXPECT_EQ(parse_cli({"--spp-schedule", "random"}).render.spp_schedule, SppSchedule::Random);
  EXPECT_EQ(parse_cli({"--spp", "0.25", "--spp-schedule", "stratified"}).render.spp_schedule,
            SppSchedule::Stratified);
  EXPECT_THROW(parse_cli({"--spp-schedule"}), UsageError);
  try {
    parse_cli({"--spp-schedule", "bayer"});
    ADD_FAILURE() << "an unknown schedule was accepted";
  } catch (const UsageError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("--spp-schedule"), std::string::npos) << message;
    EXPECT_NE(message.find("bayer"), std::string::npos) << message;
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
  // The sample statistics (ids 51-54, docs/protocol.md §7.7) only for a pipeline that takes them.
  EXPECT_FALSE(channels_for(mask({ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal, ChannelId::SampleCount}),
                            false)
                   .statistics);
  for (int id = 51; id <= 54; ++id) {
    const ChannelSet stat = channels_for(mask({ChannelId::Radiance, static_cast<ChannelId>(id)}), false);
    EXPECT_TRUE(stat.statistics) << id;
    EXPECT_FALSE(stat.reflection || stat.split) << id;
  }
}

// What a session declares for stat's channel set, and that the statistics it
// streams are the frame's own planes: fp32, interleaved as the protocol lays
// them out, the same values FrameBuffers holds, over the samples whose mean
// is the streamed radiance.
TEST(RendererStream, StatisticsAreStreamedFromTheFrameBuffers) {
  using protocol::ChannelId;
  const uint64_t stat = mask({ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal, ChannelId::StatCount,
                              ChannelId::StatMean, ChannelId::StatM2, ChannelId::StatM3});
  const std::unique_ptr<Scene> scene = build_scene(4);  // fireflies: skewed samples
  RenderSettings st = test::small_settings(24, 16, 4.0);
  st.channels = channels_for(stat, false);
  ASSERT_TRUE(st.channels.statistics && st.channels.gbuffer);
  st.channels.sample_count = true;
  const Camera cam = frame_camera(4, 0, st);
  const FrameBuffers fb = render_frame(*scene, cam, cam, 0, st);
  EXPECT_EQ(stream_channels(stat, fb, false),
            (std::vector<ChannelId>{ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal, ChannelId::StatCount,
                                    ChannelId::StatMean, ChannelId::StatM2, ChannelId::StatM3}));
  const size_t pixels = size_t(st.width) * st.height;
  const std::pair<ChannelId, const std::vector<float>*> planes[] = {{ChannelId::StatCount, &fb.stat_count},
                                                                    {ChannelId::StatMean, &fb.stat_mean},
                                                                    {ChannelId::StatM2, &fb.stat_m2},
                                                                    {ChannelId::StatM3, &fb.stat_m3}};
  size_t spread = 0;
  for (const auto& [id, expected] : planes) {
    const std::vector<float>* streamed = stream_plane(fb, id);
    ASSERT_EQ(streamed, expected) << protocol::find_channel(id)->name;
    ASSERT_EQ(streamed->size(), pixels * protocol::find_channel(id)->components);
    // The bytes of the FRAME plane: byte_length of an F32 plane of this size.
    EXPECT_EQ(streamed->size() * sizeof(float),
              protocol::plane_bytes(*protocol::find_channel(id), protocol::Format::F32, st.width, st.height));
    for (float v : *streamed) ASSERT_TRUE(std::isfinite(v));
  }
  for (size_t i = 0; i < pixels; ++i) {
    EXPECT_EQ(fb.stat_count[i], 4.0f) << i;
    EXPECT_EQ(fb.stat_count[i], fb.sample_count[i]) << i;
    for (size_t c = 0; c < 3; ++c) {
      const size_t k = 3 * i + c;
      // radiance is the raw mean of the samples the statistics describe
      EXPECT_NEAR(fb.radiance[k], fb.stat_raw_mean[k], 1e-5f * (1.0f + fb.radiance[k])) << i;
      EXPECT_GE(fb.stat_mean[k], -2.0f) << i;  // y = 2 sqrt(x) - 2 >= -2
      EXPECT_GE(fb.stat_m2[k], 0.0f) << i;
      spread += fb.stat_m2[k] > 0.0f;
    }
  }
  EXPECT_GT(spread, pixels / 4);  // the planes carry real spreads, not zeros
  // Radiance or split still decided as before; the statistics stay.
  const uint64_t stat_split = stat | mask({ChannelId::Diffuse, ChannelId::Specular});
  const std::vector<ChannelId> no_split = stream_channels(stat_split, fb, true);  // fb has no split planes
  EXPECT_EQ(no_split.front(), ChannelId::Radiance);
  EXPECT_EQ(no_split.size(), 7u);
  // A pipeline that does not take them gets none, whatever the frame has.
  const uint64_t svgf = mask({ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth,
                              ChannelId::Motion, ChannelId::Emission});
  for (ChannelId id : stream_channels(svgf, fb, false)) EXPECT_FALSE(protocol::is_sample_statistic(id));
  // A frame rendered without --stats has none to send (open() then names the missing required one).
  RenderSettings plain = st;
  plain.channels.statistics = false;
  const FrameBuffers fb_plain = render_frame(*scene, cam, cam, 0, plain);
  EXPECT_TRUE(stream_plane(fb_plain, ChannelId::StatMean)->empty());
  EXPECT_EQ(stream_channels(stat, fb_plain, false),
            (std::vector<ChannelId>{ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal}));
}

}  // namespace
}  // namespace dn::render
