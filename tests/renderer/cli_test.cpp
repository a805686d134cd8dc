// dnrender's argument parsing: every option, and clear errors for bad ones.
#include <gtest/gtest.h>

#include "cli.hpp"

namespace dn::render {
namespace {

TEST(RendererCli, ParsesEveryOption) {
  const CliOptions o = parse_cli({"--scene", "3", "--frames", "10", "--first", "5", "--hold-camera", "7", "--width", "320", "--height",
                                  "180", "--spp", "0.25", "--seed", "9", "--out", "o", "--reference", "512", "--cache",
                                  "c", "--server", "tcp://h:1", "--pipeline", "svgf", "--in-flight", "3", "--stats",
                                  "--spec-hit", "--jitter", "--max-depth", "5", "--threads", "2", "--send-split",
                                  "--png", "--quiet"});
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
  EXPECT_EQ(o.server, "tcp://h:1");
  EXPECT_EQ(o.pipeline, "svgf");
  EXPECT_EQ(o.in_flight, 3);
  EXPECT_TRUE(o.render.channels.statistics && o.render.channels.specular_hit && o.render.jitter);
  EXPECT_EQ(o.render.max_depth, 5);
  EXPECT_EQ(o.render.threads, 2);
  EXPECT_TRUE(o.send_split && o.png && o.quiet);
  EXPECT_FALSE(o.help);
}

TEST(RendererCli, RejectsBadArguments) {
  for (const std::vector<std::string>& bad :
       std::vector<std::vector<std::string>>{{"--scene", "6"},
                                             {"--scene", "x"},
                                             {"--spp", "0"},
                                             {"--spp", "-1"},
                                             {"--width", "0"},
                                             {"--frames"},
                                             {"--bogus"},
                                             {"--server", "tcp://h:1"},
                                             {"--png"},
                                             {"--height", "12abc"}})
    EXPECT_THROW(parse_cli(bad), UsageError) << bad[0];
  try {
    parse_cli({"--scene", "7"});
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("--scene"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace dn::render
