#include "server/session/pipeline_builder.hpp"

#include <strings.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <variant>

#include "gpu/compute.hpp"
#include "gpu/context.hpp"
#include "gpu/pipeline_cache.hpp"
#include "pipelines/frame_input.hpp"
#include "pipelines/input_forms.hpp"

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
  std::vector<std::vector<uint8_t>> planes;  // the input's views point into these
  planes.reserve(config.channels.size());
  pipelines::FrameInput input;
  for (const auto& c : config.channels) {
    const auto* info = protocol::find_channel(c.id);
    planes.emplace_back(protocol::plane_bytes(*info, c.format, config.width, config.height), uint8_t{0});
    input.planes.push_back(planes.back());
  }
  std::vector<uint8_t> output;
  std::vector<pipelines::PassTiming> timings;
  pipeline.process(input, false, output, timings);
}

// Whether a frame on a private device keeps kernel compiles out of the shared
// queue: lavapipe JIT-compiles at a kernel's first dispatch, on the device
// that dispatches it, and only Mesa's shader cache carries the machine code
// to another device. A GPU driver compiles when the pipeline is created.
bool can_prepare_off_queue(const gpu::Context& context) {
  if (context.info().type != "cpu") return false;
  for (const char* name : {"MESA_SHADER_CACHE_DISABLE", "MESA_GLSL_CACHE_DISABLE"}) {
    const char* v = std::getenv(name);  // Mesa's env_var_as_boolean
    if (v && (!std::strcmp(v, "1") || !strcasecmp(v, "true") || !strcasecmp(v, "yes") || !strcasecmp(v, "y")))
      return false;
  }
  return true;
}

}  // namespace

bool PipelineBuilder::needs_first_run(const std::vector<std::shared_ptr<const gpu::Kernel>>& kernels,
                                      uint32_t width, uint32_t height) {
  for (const auto& k : kernels)
    if (!k->prepared_at(width, height)) return true;
  return false;
}

// One frame of zeros through a copy of the session's pipeline (same size,
// so lavapipe picks the same variants) on a device of its own, whose queue
// runs beside the shared one. Destroying that device waits for Mesa's shader
// cache writes, so the session's first real frame loads the machine code.
double PipelineBuilder::run_off_queue(const pipelines::PreparedPipeline& prepared,
                                      const std::vector<std::shared_ptr<const gpu::Kernel>>& kernels) {
  const auto start = Clock::now();
  {
    gpu::ContextOptions options = context_.options();
    options.pipeline_cache_dir.clear();
    gpu::Context private_device(options);
    const gpu::KernelCache::Recording its_own;  // keeps its kernels out of the caller's recording; gone before the device
    run_one_frame(*pipelines::create(private_device, prepared), prepared.config());
  }
  for (const auto& k : kernels) k->mark_prepared(prepared.config().width, prepared.config().height);
  return ms_since(start);
}

PipelineBuilder::PipelineBuilder(gpu::Context& context, std::function<void(BuiltPipeline&&)> on_built,
                                 PipelineFactory factory)
    : context_(context),
      on_built_(std::move(on_built)),
      factory_(std::move(factory)),
      off_queue_(!factory_ && can_prepare_off_queue(context)),
      thread_([this] { loop(); }) {}

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
    gpu::KernelCache::Recording used;
    try {
      out.pipeline = factory_ ? factory_(out.request.prepared) : pipelines::create(context_, out.request.prepared);
    } catch (const std::exception& e) {
      out.error = e.what();
    }
    out.compile_ms = gpu::KernelCache::compile_ms_of_this_thread() - compiled_before;
    if (out.pipeline && off_queue_ && needs_first_run(used.kernels(), out.request.prepared.config().width,
                                                         out.request.prepared.config().height)) {
      try {
        out.first_run_ms = run_off_queue(out.request.prepared, used.kernels());
      } catch (const std::exception& e) {  // the session still works: its first frame compiles in the shared queue
        out.first_run_error = e.what();
      }
    }
    out.build_ms = ms_since(start);
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
    const auto configs = warm_up_configs();
    report.offered = static_cast<uint32_t>(configs.size());
    for (const auto& config : configs) {
      {
        std::lock_guard lock(mutex_);
        if (stopping_) return;
      }
      try {
        const auto prepared = pipelines::prepare(config);
        if (auto* err = std::get_if<pipelines::ConfigError>(&prepared)) throw std::invalid_argument(err->message);
        // Built, run once and dropped: its kernels stay in the cache, compiled and dispatched.
        gpu::KernelCache::Recording used;
        auto pipeline = pipelines::create(context_, std::get<pipelines::PreparedPipeline>(prepared));
        for (const auto& k : used.kernels()) k->mark_prepared(config.width, config.height);
        run_one_frame(*pipeline, config);
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
  // Formats decide no kernel: the forms that hold every kernel, in fp32.
  std::vector<pipelines::SessionConfig> out;
  for (const auto& p : pipelines::available_pipelines())
    for (const uint64_t form : pipelines::kernel_variants(p).covering_forms)
      out.push_back(pipelines::form_config(p, form, kWarmUpWidth, kWarmUpHeight));
  return out;
}

}  // namespace dn::server
