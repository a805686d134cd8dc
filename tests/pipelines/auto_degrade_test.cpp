// "auto" with whatever guides a renderer has (docs/pipelines.md "auto"): for
// radiance with every subset of albedo, normal, depth and motion, the
// pipeline the table chooses runs a still view of image_scene.hpp at 4
// samples per pixel, new noise each frame, and every frame comes out closer
// to the truth than its input: a missing guide costs quality, never harm.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "frames.hpp"
#include "gpu_test_env.hpp"
#include "image_scene.hpp"
#include "pipelines/auto_choice.hpp"
#include "pipelines/pipeline.hpp"

namespace dn {
namespace {

using test::ChannelId;
using test::Format;

class AutoDegradeTest : public test::GpuTest {};

TEST_F(AutoDegradeTest, EverySubsetOfTheGuidesDenoisesEveryFrameOfAStillView) {
  const test::ImageScene scene;
  const size_t pixels = size_t(scene.width) * scene.height;
  const ChannelId guides[] = {ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth, ChannelId::Motion};
  for (unsigned subset = 0; subset < 16; ++subset) {
    std::vector<pipelines::InputChannel> declared = {{ChannelId::Radiance, Format::F32}};
    std::string name = "radiance";
    for (unsigned g = 0; g < 4; ++g)
      if (subset & (1u << g)) {
        declared.push_back({guides[g], Format::F32});
        name += "+" + std::string(protocol::find_channel(guides[g])->name);
      }
    SCOPED_TRACE(name);
    auto prepared = pipelines::prepare(test::make_config(std::string(pipelines::kAutoPipeline), scene.width,
                                                         scene.height, declared));
    const auto* err = std::get_if<pipelines::ConfigError>(&prepared);
    ASSERT_FALSE(err) << err->message;
    const pipelines::PreparedPipeline& chosen = std::get<pipelines::PreparedPipeline>(prepared);
    auto pipe = pipelines::create(ctx(), chosen);
    for (uint32_t frame = 0; frame < 3; ++frame) {
      const std::vector<float> noisy = scene.noisy(4, 101 + frame);
      test::HostFrame f;
      f.info.frame_index = frame;
      for (const auto& ch : chosen.config().channels) {
        if (ch.id == ChannelId::Radiance) f.add(ch.id, Format::F32, noisy);
        if (ch.id == ChannelId::Albedo) f.add(ch.id, Format::F32, scene.albedo);
        if (ch.id == ChannelId::Normal) f.add(ch.id, Format::F32, scene.normal);
        if (ch.id == ChannelId::Depth) f.add(ch.id, Format::F32, scene.depth);
        if (ch.id == ChannelId::Motion) f.add(ch.id, Format::F32, std::vector<float>(2 * pixels, 0.0f));
      }
      std::vector<uint8_t> out;
      std::vector<pipelines::PassTiming> timings;
      test::process(*pipe, f.view(), true, out, timings);
      const double in_error = scene.rmse(noisy), out_error = scene.rmse(test::decode_output(out, Format::F32));
      std::printf("[ info     ] %s -> %s, frame %u: RMSE input %.4f output %.4f\n", name.c_str(),
                  chosen.config().pipeline.c_str(), frame, in_error, out_error);
      EXPECT_LT(out_error, in_error) << chosen.config().pipeline << ", frame " << frame;
    }
  }
}

}  // namespace
}  // namespace dn
