#include "server/session/pipeline_builder.hpp"

#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <stdexcept>
#include <variant>

#include "gpu/compute.hpp"
#include "gpu/context.hpp"
#include "gpu/pipeline_cache.hpp"

namespace dn::server {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// One frame of zeros through a freshly built pipeline. Lavapipe compiles a
// kernel's machine code at its first dispatch, not when the VkPipeline is
// created (seconds per a-trous kernel with a cold Mesa cache), and the
// kernel cache shares VkPipelines across sessions: dispatching once here
// keeps that cost out of every session's first frame.
void run_one_frame(pipelines::Pipeline& pipeline, const pipelines::SessionConfig& config) {
  std::vector<std::vector<uint8_t>> planes;  // the frame's views point into these
  planes.reserve(config.channels.size());
  protocol::Frame frame;
  for (const auto& c : config.channels) {
    const auto* info = protocol::find_channel(c.id);
    planes.emplace_back(protocol::plane_bytes(*info, c.format, config.width, config.height), uint8_t{0});
    frame.planes.push_back({c.id, c.format, planes.back()});
  }
  std::vector<uint8_t> output;
  std::vector<protocol::PassTiming> timings;
  pipeline.process(frame, false, output, timings);
}

}  // namespace

PipelineBuilder::PipelineBuilder(gpu::Context& context, std::function<void(BuiltPipeline&&)> on_built,
                                 PipelineFactory factory)
    : context_(context), on_built_(std::move(on_built)), factory_(std::move(factory)), thread_([this] { loop(); }) {}

PipelineBuilder::~PipelineBuilder() { stop(); }

void PipelineBuilder::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    jobs_.clear();
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  if (warm_thread_.joinable()) warm_thread_.join();
}

void PipelineBuilder::loop() {
  for (;;) {
    std::function<void()> job;
    {
      std::unique_lock lock(mutex_);
      cv_.wait(lock, [this] { return stopping_ || !jobs_.empty(); });
      if (stopping_) return;
      job = std::move(jobs_.front());
      jobs_.pop_front();
    }
    job();
  }
}

// Test hook: with DN_TEST_HOLD_BUILDS=PATH every build waits until PATH
// exists, so an end-to-end test can show that other connections are served
// while a session is being built without relying on how long a build takes.
void PipelineBuilder::hold_for_test() {
  const char* path = std::getenv("DN_TEST_HOLD_BUILDS");
  if (!path || !*path) return;
  for (;;) {
    if (::access(path, F_OK) == 0) return;
    std::unique_lock lock(mutex_);
    if (cv_.wait_for(lock, std::chrono::milliseconds(20), [this] { return stopping_; })) return;
  }
}

void PipelineBuilder::submit(BuildRequest&& request) {
  auto job = [this, request = std::move(request)]() mutable {
    hold_for_test();
    BuiltPipeline out{std::move(request)};
    const auto start = Clock::now();
    const double compiled_before = gpu::KernelCache::compile_ms_of_this_thread();
    try {
      out.pipeline = factory_ ? factory_(out.request.prepared) : pipelines::create(context_, out.request.prepared);
    } catch (const std::exception& e) {
      out.error = e.what();
    }
    out.build_ms = ms_since(start);
    out.compile_ms = gpu::KernelCache::compile_ms_of_this_thread() - compiled_before;
    on_built_(std::move(out));
  };
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    jobs_.push_back(std::move(job));
  }
  cv_.notify_one();
}

void PipelineBuilder::warm_up(std::function<void(const WarmUpReport&)> on_done) {
  if (warm_thread_.joinable()) return;
  warm_thread_ = std::thread([this, on_done = std::move(on_done)] {
    WarmUpReport report;
    const auto start = Clock::now();
    const uint64_t kernels_before = context_.kernels().stats().kernels;
    for (const auto& config : warm_up_configs()) {
      {
        std::lock_guard lock(mutex_);
        if (stopping_) return;
      }
      try {
        const auto prepared = pipelines::prepare(config);
        if (auto* err = std::get_if<pipelines::ConfigError>(&prepared)) throw std::invalid_argument(err->message);
        // Built, run once and dropped: its kernels stay in the cache, compiled and dispatched.
        run_one_frame(*pipelines::create(context_, std::get<pipelines::PreparedPipeline>(prepared)), config);
        ++report.configs;
      } catch (const std::exception& e) {
        if (report.error.empty()) report.error = config.pipeline + ": " + e.what();
      }
    }
    report.kernels = context_.kernels().stats().kernels - kernels_before;
    try {
      if (report.kernels > 0) report.cache_bytes = context_.pipeline_cache().save();
    } catch (const std::exception& e) {
      if (report.error.empty()) report.error = e.what();
    }
    report.ms = ms_since(start);
    on_done(report);
  });
}

std::vector<pipelines::SessionConfig> PipelineBuilder::warm_up_configs() {
  using protocol::ChannelId;
  std::vector<pipelines::SessionConfig> out;
  for (const protocol::Format format : {protocol::Format::F32, protocol::Format::F16}) {
    for (const auto& p : pipelines::available_pipelines()) {
      pipelines::SessionConfig config;
      config.width = 64;  // kernels do not depend on the resolution
      config.height = 64;
      config.pipeline = p.name;
      config.output_format = format;
      uint64_t mask = p.required_channels;
      // Pipelines that take radiance or a split form: the radiance form, unless the split one is required.
      const uint64_t radiance = protocol::channel_bit(ChannelId::Radiance);
      const uint64_t split = protocol::channel_bit(ChannelId::Diffuse) | protocol::channel_bit(ChannelId::Specular);
      if ((p.optional_channels & radiance) && !(mask & split)) mask |= radiance;
      for (const auto& c : protocol::kChannels)
        if (mask & protocol::channel_bit(c.id)) config.channels.push_back({c.id, format});
      out.push_back(std::move(config));
    }
  }
  return out;
}

}  // namespace dn::server
