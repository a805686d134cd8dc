// Per-pass device times at 1280x720, medians over 20 frames (skipped unless DN_PERF=1; prints a table).
// Run with DN_TEST_VALIDATION=0 for timings without the validation layer.
#include <gtest/gtest.h>

#include "gpu_test_env.hpp"
#include "perf_support.hpp"

namespace dn {
namespace {

using test::ChannelId;
using test::Format;

TEST(Perf, PassTimesAt720p) {
  if (!test::perf_requested()) GTEST_SKIP() << "set DN_PERF=1";
  const int w = 1280, h = 720, frames = 20;
  std::printf("device: %s\n", test::context().name().c_str());
  for (Format in : {Format::F32, Format::F16}) {
    for (const std::string name : {"passthrough", "accumulate"}) {
      const bool accumulate = name == "accumulate";
      auto config = accumulate ? test::accumulate_config(w, h, in, in)
                               : test::make_config(name, w, h, {{ChannelId::Radiance, in}}, in);
      auto pipe = pipelines::create(test::context(), config);
      test::PanningScene scene(w, h, 1, 1.5f, 0.5f, 0.2f, 0.5f);
      std::vector<test::HostFrame> inputs;
      for (int t = 0; t < 2; ++t) {
        test::SceneFrame s = scene.frame(t);
        test::HostFrame f;
        f.add(ChannelId::Radiance, in, s.radiance);
        if (accumulate) {
          f.add(ChannelId::Normal, in, s.normal);
          f.add(ChannelId::Depth, in, s.depth);
          f.add(ChannelId::Motion, in, s.motion);
        }
        inputs.push_back(std::move(f));
      }
      const auto times = test::time_passes(*pipe, inputs, frames);
      char label[64];
      std::snprintf(label, sizeof label, "%-12s %s", name.c_str(), in == Format::F16 ? "fp16" : "fp32");
      test::print_pass_times(label, times, pipe->device_bytes());
    }
  }
}

}  // namespace
}  // namespace dn
