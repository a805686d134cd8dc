// The server: one epoll event loop, the connection layer that speaks protocol
// v1 on it, and the session service above that owns the sessions and hands
// frames to the device workers; plus the run loop, signals and the graceful
// shutdown.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "server/net/connection_layer.hpp"
#include "server/net/event_loop.hpp"
#include "server/options.hpp"
#include "server/session/service.hpp"
#include "server/stats.hpp"

namespace dn::gpu {
class Context;
}

namespace dn::server {

class Server {
 public:
  // Opens the listeners; throws std::runtime_error with a reason on bad options.
  // `factory` makes sessions' pipelines (default: on `device`).
  Server(ServerOptions options, gpu::Context& device, std::string device_name, PipelineFactory factory = {});
  ~Server();

  // Runs the event loop until request_stop() (or SIGTERM when handle_signals) and
  // the graceful shutdown has finished.
  void run(bool handle_signals);
  // Thread-safe: begins the graceful shutdown.
  void request_stop();

  // Actual listening addresses (a port of 0 resolved), for tests and logs.
  std::vector<std::string> listening_urls() const { return connections_.listening_urls(); }

  // For in-process drivers (the state-machine fuzz target, tests/fuzz/server_fuzz.cpp),
  // which run the loop themselves instead of run():
  // serves an already connected stream socket as if a Unix listener had accepted it
  // (same limits and checks); returns its connection id.
  uint64_t adopt(int fd) { return connections_.adopt(fd); }
  // One turn of the event loop and the timers, as run() takes them.
  void run_once(int timeout_ms);
  // Nothing is being built, run on the device or waiting to be written.
  bool quiescent() const { return service_.idle() && !connections_.output_pending(); }
  size_t connection_count() const { return connections_.size(); }
  size_t session_count() const { return service_.session_count(); }

 private:
  void begin_shutdown();
  bool shutdown_complete() const;
  void save_pipeline_cache();

  ServerOptions options_;
  gpu::Context& device_;
  std::string device_name_;
  ServerCounters counters_;
  net::EventLoop loop_;
  ConnectionLayer connections_;
  SessionService service_;

  std::atomic<bool> stop_requested_{false};
  bool shutting_down_ = false;
  std::chrono::steady_clock::time_point shutdown_deadline_{};
  int signal_fd_ = -1;
};

}  // namespace dn::server
