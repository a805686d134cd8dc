// Builds sessions' pipelines off the event loop. Compiling kernels (seconds on
// a cold lavapipe cache) and allocating device memory happen on this thread,
// one request at a time in arrival order, so a client opening a session never
// delays another connection's frames. Results go back through a callback that
// must only hand them to the event loop.
//
// At start it can warm up, on a thread of its own so requests never queue
// behind it: build every offered pipeline in every input form (fp32 and fp16
// planes, default parameters) and run it once, so the first real session
// finds its kernels compiled, then save the on-disk pipeline cache. A request
// needing a kernel the warm-up is compiling waits for that kernel only
// (gpu::KernelCache).
//
// A build whose kernels have never run on the device (a form or parameter the
// warm-up did not cover) runs one frame of zeros through a copy of the
// pipeline on a private device before the session opens: on lavapipe that
// compiles the machine code beside the shared queue instead of inside it, in
// every other session's way (run_off_queue).
#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "server/pipelines/pipeline.hpp"

namespace dn::gpu {
class Context;
class Kernel;
}

namespace dn::server {

struct BuildRequest {
  uint64_t connection_id = 0;
  uint64_t request_id = 0;
  pipelines::PreparedPipeline prepared;  // validated, its graph built (pipelines::prepare)
  bool share_input = false;              // OPEN_SESSION's SHARE_INPUT flag (protocol 1.7)
};

struct BuiltPipeline {
  BuildRequest request;
  std::unique_ptr<pipelines::Pipeline> pipeline;  // null when building failed
  std::string error;                              // why, when it failed
  double build_ms = 0.0;                          // compile + allocate, wall clock
  double compile_ms = 0.0;                        // of which compiling kernels
  double first_run_ms = 0.0;                      // of which the frame on a private device (0: none needed)
  std::string first_run_error;                    // why that frame failed (the session still opens)
};

struct WarmUpReport {
  uint32_t offered = 0;         // configurations warm_up_configs() lists
  uint32_t configs = 0;         // of which built, run and dropped
  uint64_t kernels = 0;         // kernels compiled
  double ms = 0.0;              // wall clock of the whole warm-up
  uint64_t cache_bytes = 0;     // pipeline cache written to disk (0: none)
  std::string error;            // the first failure, if any
};

// Makes a session's pipeline from its validated configuration; throws with a
// reason when it cannot. The default (empty) builds it on the device with
// pipelines::create; the server's state-machine fuzz target gives a host-only one.
using PipelineFactory = std::function<std::unique_ptr<pipelines::Pipeline>(const pipelines::PreparedPipeline&)>;

class PipelineBuilder {
 public:
  PipelineBuilder(gpu::Context& context, std::function<void(BuiltPipeline&&)> on_built, PipelineFactory factory = {});
  ~PipelineBuilder();

  // Starts the warm-up (once); on_done runs on the warm-up thread when it finishes.
  void warm_up(std::function<void(const WarmUpReport&)> on_done);
  void submit(BuildRequest&& request);
  // Finishes the build in progress, drops the rest, joins the thread.
  void stop();

  // The sessions the warm-up builds: for every offered pipeline at its
  // default parameters, the input forms whose graphs hold every kernel any of
  // its forms compiles (pipelines/input_forms.hpp), fp32 (no kernel depends on
  // a wire format). A configuration a pipeline refuses is reported in
  // WarmUpReport::error.
  static std::vector<pipelines::SessionConfig> warm_up_configs();
  // Lavapipe compiles a kernel anew for some frame sizes: measured with one
  // svgf kernel set, 256x144, 640x360 and 1280x720 share machine code, while
  // 64x64 and frames below about 64x64 (48x36, 40x30) each need their own.
  // The warm-up takes a size of the first kind, the common one.
  static constexpr uint32_t kWarmUpWidth = 256, kWarmUpHeight = 144;

  // Whether any of these kernels has not been prepared at this frame size.
  static bool needs_first_run(const std::vector<std::shared_ptr<const gpu::Kernel>>& kernels, uint32_t width,
                              uint32_t height);

 private:
  void loop();
  void hold_for_test();
  double run_off_queue(const pipelines::PreparedPipeline& prepared,
                       const std::vector<std::shared_ptr<const gpu::Kernel>>& kernels);

  gpu::Context& context_;
  std::function<void(BuiltPipeline&&)> on_built_;
  PipelineFactory factory_;
  const bool off_queue_;  // whether run_off_queue helps on this device
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::function<void()>> jobs_;
  bool stopping_ = false;
  std::thread thread_;
  std::thread warm_thread_;
};

}  // namespace dn::server
