// The session service: OPEN_SESSION (validated here, built off the loop by the
// PipelineBuilder) within the device-memory budget, FRAME (to the Scheduler's
// workers), ATTACH, CLOSE_SESSION, STATS, and the fan-out of each finished
// frame to its owner and watchers. Runs on the event loop; replies go out
// through the connection layer.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "server/net/connection_layer.hpp"
#include "server/idle_trim.hpp"
#include "server/pipelines/registry.hpp"
#include "server/session/pipeline_builder.hpp"
#include "server/session/registry.hpp"
#include "server/session/scheduler.hpp"

namespace dn::gpu {
class Context;
}

namespace dn::server {

class SessionService final : public RequestHandler {
 public:
  // Prepares the pipelines' shared resources on `device`, starts the workers,
  // the builder and (with --warm-up) the warm-up.
  SessionService(const ServerOptions& options, gpu::Context& device, std::string device_name,
                 ConnectionLayer& connections, net::EventLoop& loop, ServerCounters& counters,
                 PipelineFactory factory);
  ~SessionService() override;

  void on_request(net::Connection& c, const protocol::Header& h, protocol::Message&& m,
                  std::vector<uint8_t>&& payload) override;
  bool has_work(const net::Connection& c) const override;
  bool window_full(const net::Connection& c) const override;
  void on_closed(net::Connection& c) override;

  // Finished builds and frames handed over by other threads (the loop's wake handler).
  void drain_completions();
  // Scratch and, with --idle-trim, memory no session holds go back to the device.
  void check_timers(std::chrono::steady_clock::time_point now);
  void begin_shutdown() { shutting_down_ = true; }
  // Stops the builder and the workers (a frame on the device finishes).
  void stop();
  // Nothing is being built or run on the device.
  bool idle() const { return sessions_being_built_ == 0 && sessions_.frames_in_flight() == 0; }
  uint64_t frames_in_flight() const { return sessions_.frames_in_flight(); }
  size_t session_count() const { return sessions_.size(); }

 private:
  void on_open_session(net::Connection& c, const protocol::Header& h, const protocol::OpenSession& m);
  void on_frame(net::Connection& c, const protocol::Header& h, protocol::Frame&& m, std::vector<uint8_t>&& payload);
  void on_attach(net::Connection& c, const protocol::Header& h, const protocol::Attach& m);
  void on_close_session(net::Connection& c, const protocol::Header& h, const protocol::CloseSession& m);
  void on_stats(net::Connection& c, const protocol::Header& h);
  void on_pipeline_built(BuiltPipeline&& built);
  void on_frame_done(FrameDone&& done);
  void finish_session(const std::shared_ptr<Session>& s, bool notify);
  // The connection's message limit follows the largest frame of the sessions it owns.
  void refresh_message_limit(net::Connection& c);
  void error(net::Connection& c, uint64_t request_id, protocol::ErrorCode code, std::string field,
             std::string message) {
    connections_.send_error(c, request_id, code, std::move(field), std::move(message), false);
  }
  uint64_t committed_device_bytes() const;
  void trim_when_idle(std::chrono::steady_clock::time_point now);

  const ServerOptions& options_;
  gpu::Context& device_;
  std::string device_name_;
  ConnectionLayer& connections_;
  ServerCounters& counters_;
  SessionRegistry sessions_;
  std::unique_ptr<Scheduler> scheduler_;
  std::unique_ptr<PipelineBuilder> builder_;
  uint32_t sessions_being_built_ = 0;
  bool shutting_down_ = false;
  // Capacity: the device memory all sessions may need (--max-device-memory, at
  // most the device's local heaps), and what open sessions and builds claim of it.
  uint64_t device_budget_bytes_ = 0;
  uint64_t bytes_being_built_ = 0;
  std::mutex completions_mutex_;  // guards completions_, built_ and warm_up_ (written by other threads)
  std::vector<FrameDone> completions_;
  std::vector<BuiltPipeline> built_;
  std::optional<WarmUpReport> warm_up_;
  std::vector<pipelines::SharedResourceTiming> shared_resources_;
  IdleTrimSchedule idle_trim_;
  bool warm_up_kernels_kept_ = false;  // KernelCache::keep_current() ran after the warm-up
};

}  // namespace dn::server
