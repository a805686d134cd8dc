// Per-pass device times at 1280x720, medians over 20 frames (skipped unless DN_PERF=1; prints a table).
// Run with DN_TEST_VALIDATION=0 for timings without the validation layer.
#include <gtest/gtest.h>

#include <cstdio>
#include <algorithm>
#include <map>

#include "frames.hpp"
#include "gpu_test_env.hpp"

namespace dn {
namespace {

using test::ChannelId;
using test::Format;

TEST(Perf, PassTimesAt720p) {
  const char* env = std::getenv("DN_PERF");
  if (!env || std::string(env) != "1") GTEST_SKIP() << "set DN_PERF=1";
  const int w = 1280, h = 720, frames = 20;
  std::printf("device: %s\n", test::context().name().c_str());
  for (Format in : {Format::F32, Format::F16}) {
    for (const char* name : {"passthrough", "accumulate"}) {
      auto config = std::string(name) == "passthrough"
                        ? test::make_config(name, w, h, {{ChannelId::Radiance, in}}, in)
                        : test::accumulate_config(w, h, in, in);
      auto pipe = pipelines::create(test::context(), config);
      test::PanningScene scene(w, h, 1, 1.5f, 0.5f, 0.2f, 0.5f);
      std::vector<test::HostFrame> inputs;
      for (int t = 0; t < 2; ++t) {
        test::SceneFrame s = scene.frame(t);
        test::HostFrame f;
        f.add(ChannelId::Radiance, in, s.radiance);
        if (std::string(name) == "accumulate") {
          f.add(ChannelId::Normal, in, s.normal);
          f.add(ChannelId::Depth, in, s.depth);
          f.add(ChannelId::Motion, in, s.motion);
        }
        inputs.push_back(std::move(f));
      }
      std::map<std::string, std::vector<double>> total;
      std::vector<std::string> order;
      std::vector<uint8_t> out;
      for (int t = 0; t < frames + 2; ++t) {
        std::vector<protocol::PassTiming> timings;
        pipe->process(inputs[t % 2].view(), true, out, timings);
        if (t < 2) continue;  // warm-up
        for (const auto& tm : timings) {
          if (!total.count(tm.name)) order.push_back(tm.name);
          total[tm.name].push_back(tm.milliseconds);
        }
      }
      std::printf("%-12s %s:", name, in == Format::F16 ? "fp16" : "fp32");
      for (const auto& n : order) {
        auto& v = total[n];
        std::sort(v.begin(), v.end());
        std::printf("  %s %.2f ms (min %.2f)", n.c_str(), v[v.size() / 2], v.front());  // median, min
      }
      std::printf("   (%.1f MB device)\n", pipe->device_bytes() / 1e6);
    }
  }
}

}  // namespace
}  // namespace dn
