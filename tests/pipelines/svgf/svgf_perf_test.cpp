// svgf per-pass device times, medians over 10 frames (skipped unless DN_PERF=1;
// prints a table). DN_TEST_VALIDATION=0 for timings without the validation layer.
#include <gtest/gtest.h>

#include "gpu_test_env.hpp"
#include "perf_support.hpp"

namespace dn {
namespace {

using test::ChannelId;
using test::Format;

constexpr int kFrames = 10;

// Two alternating frames of the panning scene (a still camera when !moving);
// split mode sends diffuse + a decorrelated specular instead of radiance.
std::vector<test::HostFrame> svgf_inputs(int w, int h, Format in, bool split, bool moving = true) {
  test::PanningScene scene(w, h, 1, moving ? 1.5f : 0.0f, moving ? 0.5f : 0.0f, moving ? 0.2f : 0.0f, 0.5f);
  std::vector<test::HostFrame> inputs;
  for (int t = 0; t < 2; ++t) {
    test::SceneFrame s = scene.frame(t);
    test::HostFrame f;
    if (split) {
      std::vector<float> specular(s.radiance.size());
      for (size_t i = 0; i < specular.size(); ++i) specular[i] = 0.3f * s.radiance[(i * 7919) % specular.size()];
      f.add(ChannelId::Diffuse, in, s.radiance);
      f.add(ChannelId::Specular, in, specular);
    } else {
      f.add(ChannelId::Radiance, in, s.radiance);
    }
    f.add(ChannelId::Albedo, in, std::vector<float>(s.radiance.size(), 0.5f));
    f.add(ChannelId::Normal, in, s.normal);
    f.add(ChannelId::Depth, in, s.depth);
    f.add(ChannelId::Motion, in, s.motion);
    inputs.push_back(std::move(f));
  }
  return inputs;
}

std::vector<pipelines::InputChannel> svgf_channels(Format in, bool split) {
  std::vector<pipelines::InputChannel> c;
  if (split) {
    c = {{ChannelId::Diffuse, in}, {ChannelId::Specular, in}};
  } else {
    c = {{ChannelId::Radiance, in}};
  }
  for (ChannelId id : {ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth, ChannelId::Motion}) c.push_back({id, in});
  return c;
}

void run(const std::string& label, int w, int h, Format in, bool split,
         std::vector<pipelines::ParameterValue> parameters = {}, bool moving = true) {
  auto config = test::make_config("svgf", w, h, svgf_channels(in, split), in, std::move(parameters));
  auto pipe = pipelines::create(test::context(), config);
  const auto times = test::time_passes(*pipe, svgf_inputs(w, h, in, split, moving), kFrames);
  char full[96];
  std::snprintf(full, sizeof full, "%s %dx%d %s", label.c_str(), w, h, in == Format::F16 ? "fp16" : "fp32");
  test::print_pass_times(full, times, pipe->device_bytes());
}

TEST(Perf, SvgfPassTimes) {
  if (!test::perf_requested()) GTEST_SKIP() << "set DN_PERF=1";
  std::printf("device: %s\n", test::context().name().c_str());
  for (auto [w, h] : {std::pair{640, 360}, std::pair{1280, 720}})
    for (Format in : {Format::F32, Format::F16}) run("svgf", w, h, in, false);
}

// The final TAA blend, 640x360 fp32: everywhere (taa_alpha 0.1), the
// default static blend alone on a moving and on a still camera, and none.
TEST(Perf, SvgfTaaPassTimes) {
  if (!test::perf_requested()) GTEST_SKIP() << "set DN_PERF=1";
  run("svgf taa", 640, 360, Format::F32, false, {{"taa_alpha", 0.1}});
  run("svgf static blend, moving", 640, 360, Format::F32, false);
  run("svgf static blend, still", 640, 360, Format::F32, false, {}, false);
  run("svgf no taa", 640, 360, Format::F32, false, {{"taa_static_alpha", 0}});
  run("svgf no taa, still", 640, 360, Format::F32, false, {{"taa_static_alpha", 0}}, false);
}

// Split mode (diffuse + specular), 640x360 fp32.
TEST(Perf, SvgfSplitPassTimes) {
  if (!test::perf_requested()) GTEST_SKIP() << "set DN_PERF=1";
  run("svgf split", 640, 360, Format::F32, true);
}

}  // namespace
}  // namespace dn
