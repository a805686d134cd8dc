// svgf per-pass device times at 640x360 and 1280x720, medians over 10 frames
// (skipped unless DN_PERF=1; prints a table). DN_TEST_VALIDATION=0 for timings
// without the validation layer.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <map>

#include "frames.hpp"
#include "gpu_test_env.hpp"

namespace dn {
namespace {

using test::ChannelId;
using test::Format;

TEST(Perf, SvgfPassTimes) {
  const char* env = std::getenv("DN_PERF");
  if (!env || std::string(env) != "1") GTEST_SKIP() << "set DN_PERF=1";
  std::printf("device: %s\n", test::context().name().c_str());
  const int frames = 10;
  for (auto [w, h] : {std::pair{640, 360}, std::pair{1280, 720}}) {
    for (Format in : {Format::F32, Format::F16}) {
      auto config = test::make_config("svgf", w, h,
                                      {{ChannelId::Radiance, in}, {ChannelId::Albedo, in}, {ChannelId::Normal, in},
                                       {ChannelId::Depth, in}, {ChannelId::Motion, in}},
                                      in);
      auto pipe = pipelines::create(test::context(), config);
      test::PanningScene scene(w, h, 1, 1.5f, 0.5f, 0.2f, 0.5f);
      std::vector<test::HostFrame> inputs;
      for (int t = 0; t < 2; ++t) {
        test::SceneFrame s = scene.frame(t);
        test::HostFrame f;
        f.add(ChannelId::Radiance, in, s.radiance);
        f.add(ChannelId::Albedo, in, std::vector<float>(s.radiance.size(), 0.5f));
        f.add(ChannelId::Normal, in, s.normal);
        f.add(ChannelId::Depth, in, s.depth);
        f.add(ChannelId::Motion, in, s.motion);
        inputs.push_back(std::move(f));
      }
      std::map<std::string, std::vector<double>> total;
      std::vector<std::string> order;
      std::vector<uint8_t> out;
      for (int t = 0; t < frames + 2; ++t) {
        std::vector<protocol::PassTiming> timings;
        pipe->process(inputs[t % 2].view(), true, out, timings);
        if (t < 2) continue;  // warm-up
        double sum = 0;
        for (const auto& tm : timings) {
          if (!total.count(tm.name)) order.push_back(tm.name);
          total[tm.name].push_back(tm.milliseconds);
          if (tm.name != "upload" && tm.name != "download") sum += tm.milliseconds;
        }
        if (!total.count("passes")) order.push_back("passes");
        total["passes"].push_back(sum);
      }
      std::printf("svgf %dx%d %s:", w, h, in == Format::F16 ? "fp16" : "fp32");
      for (const auto& n : order) {
        auto& v = total[n];
        std::sort(v.begin(), v.end());
        std::printf("  %s %.2f", n.c_str(), v[v.size() / 2]);
      }
      std::printf(" ms (median)  (%.1f MB device)\n", pipe->device_bytes() / 1e6);
    }
  }
}

// The final TAA blend (taa_alpha 0.1), 640x360 fp32: per-pass medians over 10 frames.
TEST(Perf, SvgfTaaPassTimes) {
  const char* env = std::getenv("DN_PERF");
  if (!env || std::string(env) != "1") GTEST_SKIP() << "set DN_PERF=1";
  const int frames = 10, w = 640, h = 360;
  const Format in = Format::F32;
  auto config = test::make_config("svgf", w, h,
                                  {{ChannelId::Radiance, in}, {ChannelId::Albedo, in}, {ChannelId::Normal, in},
                                   {ChannelId::Depth, in}, {ChannelId::Motion, in}},
                                  in, {{"taa_alpha", 0.1}});
  auto pipe = pipelines::create(test::context(), config);
  test::PanningScene scene(w, h, 1, 1.5f, 0.5f, 0.2f, 0.5f);
  std::vector<test::HostFrame> inputs;
  for (int t = 0; t < 2; ++t) {
    test::SceneFrame s = scene.frame(t);
    test::HostFrame f;
    f.add(ChannelId::Radiance, in, s.radiance);
    f.add(ChannelId::Albedo, in, std::vector<float>(s.radiance.size(), 0.5f));
    f.add(ChannelId::Normal, in, s.normal);
    f.add(ChannelId::Depth, in, s.depth);
    f.add(ChannelId::Motion, in, s.motion);
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
  std::printf("svgf taa %dx%d fp32:", w, h);
  for (const auto& n : order) {
    auto& v = total[n];
    std::sort(v.begin(), v.end());
    std::printf("  %s %.2f", n.c_str(), v[v.size() / 2]);
  }
  std::printf(" ms (median)  (%.1f MB device)\n", pipe->device_bytes() / 1e6);
}

// Split mode (diffuse + specular), 640x360 fp32: per-pass medians over 10 frames.
TEST(Perf, SvgfSplitPassTimes) {
  const char* env = std::getenv("DN_PERF");
  if (!env || std::string(env) != "1") GTEST_SKIP() << "set DN_PERF=1";
  const int frames = 10, w = 640, h = 360;
  const Format in = Format::F32;
  auto config = test::make_config("svgf", w, h,
                                  {{ChannelId::Diffuse, in}, {ChannelId::Specular, in}, {ChannelId::Albedo, in},
                                   {ChannelId::Normal, in}, {ChannelId::Depth, in}, {ChannelId::Motion, in}},
                                  in);
  auto pipe = pipelines::create(test::context(), config);
  test::PanningScene scene(w, h, 1, 1.5f, 0.5f, 0.2f, 0.5f);
  std::vector<test::HostFrame> inputs;
  for (int t = 0; t < 2; ++t) {
    test::SceneFrame s = scene.frame(t);
    std::vector<float> specular(s.radiance.size());
    for (size_t i = 0; i < specular.size(); ++i) specular[i] = 0.3f * s.radiance[(i * 7919) % specular.size()];
    test::HostFrame f;
    f.add(ChannelId::Diffuse, in, s.radiance);
    f.add(ChannelId::Specular, in, specular);
    f.add(ChannelId::Albedo, in, std::vector<float>(s.radiance.size(), 0.5f));
    f.add(ChannelId::Normal, in, s.normal);
    f.add(ChannelId::Depth, in, s.depth);
    f.add(ChannelId::Motion, in, s.motion);
    inputs.push_back(std::move(f));
  }
  std::map<std::string, std::vector<double>> total;
  std::vector<std::string> order;
  std::vector<uint8_t> out;
  for (int t = 0; t < frames + 2; ++t) {
    std::vector<protocol::PassTiming> timings;
    pipe->process(inputs[t % 2].view(), true, out, timings);
    if (t < 2) continue;  // warm-up
    double sum = 0;
    for (const auto& tm : timings) {
      if (!total.count(tm.name)) order.push_back(tm.name);
      total[tm.name].push_back(tm.milliseconds);
      if (tm.name != "upload" && tm.name != "download") sum += tm.milliseconds;
    }
    if (!total.count("passes")) order.push_back("passes");
    total["passes"].push_back(sum);
  }
  std::printf("svgf split %dx%d fp32:", w, h);
  for (const auto& n : order) {
    auto& v = total[n];
    std::sort(v.begin(), v.end());
    std::printf("  %s %.2f", n.c_str(), v[v.size() / 2]);
  }
  std::printf(" ms (median)  (%.1f MB device)\n", pipe->device_bytes() / 1e6);
}

}  // namespace
}  // namespace dn
