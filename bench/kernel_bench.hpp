// What the kernel benchmarks (bilinear_bench, stat_gather_bench) share: their
// common options (--device, --size WxH repeatable, --reps) and the median
// device time of repeated dispatches from Vulkan timestamps, after one
// untimed run (first dispatch, caches).
#pragma once

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "gpu/buffer.hpp"
#include "gpu/commands.hpp"
#include "gpu/context.hpp"
#include "gpu/timestamps.hpp"

namespace dn::bench {

struct KernelBenchOptions {
  std::string device;
  std::vector<std::pair<uint32_t, uint32_t>> sizes;
  int reps = 0;  // the benchmark's default until set
};

// Consumes argv[i] (and its value, advancing i) when it is a common option;
// false when it is not one. Throws std::runtime_error on a missing or bad value.
inline bool parse_kernel_bench_option(int argc, char** argv, int& i, KernelBenchOptions& o) {
  const std::string a = argv[i];
  if (a != "--device" && a != "--size" && a != "--reps") return false;
  if (i + 1 >= argc) throw std::runtime_error(a + " needs a value");
  const std::string v = argv[++i];
  if (a == "--device") {
    o.device = v;
  } else if (a == "--size") {
    unsigned w = 0, h = 0;
    if (std::sscanf(v.c_str(), "%ux%u", &w, &h) != 2 || !w || !h) throw std::runtime_error("bad --size " + v);
    o.sizes.emplace_back(w, h);
  } else {
    o.reps = std::max(1, std::atoi(v.c_str()));
  }
  return true;
}

// Parses a benchmark's command line when it takes only the common options;
// false (after printing the usage or the error) on anything else.
inline bool parse_kernel_bench_args(int argc, char** argv, const char* name, KernelBenchOptions& o) {
  try {
    for (int i = 1; i < argc; ++i) {
      if (parse_kernel_bench_option(argc, argv, i, o)) continue;
      std::fprintf(stderr, "usage: %s [--device SEL] [--size WxH]... [--reps N]\n", argv[0]);
      return false;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", name, e.what());
    return false;
  }
  return true;
}

// Creates the context on options.device, runs `body` (which prints the
// table) and returns the process's exit code: 1 on an exception or any
// validation message, 0 otherwise. `name` prefixes the error.
inline int run_on_device(const char* name, const KernelBenchOptions& options,
                         const std::function<void(dn::gpu::Context&)>& body) {
  try {
    dn::gpu::ContextOptions co;
    co.device = options.device;
    dn::gpu::Context ctx(co);
    body(ctx);
    if (ctx.validation_enabled() && ctx.validation_message_count() > 0) {
      std::fprintf(stderr, "%llu validation messages\n",
                   static_cast<unsigned long long>(ctx.validation_message_count()));
      return 1;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", name, e.what());
    return 1;
  }
  return 0;
}

// A buffer's contents as floats (after its readback).
inline std::vector<float> read_floats(const dn::gpu::Buffer& b) {
  std::vector<float> out(b.size() / 4);
  b.read({reinterpret_cast<uint8_t*>(out.data()), b.size()});
  return out;
}

// A w x h RGBA fp32 grid of values uniform in [0, 4), the same for a size.
inline std::vector<float> random_rgba(uint32_t w, uint32_t h) {
  std::mt19937 rng(w * 31 + h);
  std::uniform_real_distribution<float> dist(0.0f, 4.0f);
  std::vector<float> rgba(size_t{w} * h * 4);
  for (auto& v : rgba) v = dist(rng);
  return rgba;
}

inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

// Records `reps` timed repetitions of `dispatch` (each between two
// timestamps, a barrier after each) after one untimed warm-up submission,
// then the readback of `result`; returns the median device ms.
template <class Dispatch>
double time_dispatches(dn::gpu::Context& ctx, const dn::gpu::Buffer& result, int reps, Dispatch dispatch,
                       const std::function<void(VkCommandBuffer)>& before = {}) {
  dn::gpu::CommandStream stream(ctx);
  dn::gpu::TimestampPool timestamps(ctx, 2 * reps);
  VkCommandBuffer cmd = stream.begin();
  if (before) before(cmd);
  dispatch(cmd);
  stream.submit_and_wait();
  cmd = stream.begin();
  timestamps.reset(cmd);
  for (int i = 0; i < reps; ++i) {
    timestamps.write(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, 2 * i);
    dispatch(cmd);
    timestamps.write(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, 2 * i + 1);
    dn::gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                            VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT);
  }
  result.record_readback(cmd, result.size(), VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT);
  stream.submit_and_wait();
  const auto intervals = timestamps.read_intervals_ms(2 * reps);
  std::vector<double> ms;
  for (int i = 0; i < reps; ++i) ms.push_back(intervals[2 * i]);
  return median(ms);
}

// The sampled image and everything around it (own descriptor layout: the
// Kernel class binds storage buffers only).
}  // namespace dn::bench
