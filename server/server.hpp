// The server: accepts connections, speaks protocol v1 on one epoll event loop,
// owns the sessions and hands frames to the device workers.
#pragma once

#include <sys/socket.h>

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "server/idle_trim.hpp"
#include "server/net/connection.hpp"
#include "server/net/event_loop.hpp"
#include "server/net/listener.hpp"
#include "server/options.hpp"
#include "server/session/pipeline_builder.hpp"
#include "server/session/registry.hpp"
#include "server/session/scheduler.hpp"
#include "server/session/session.hpp"
#include "server/pipelines/registry.hpp"
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
  std::vector<std::string> listening_urls() const;

  // For in-process drivers (the state-machine fuzz target, tests/fuzz/server_fuzz.cpp),
  // which run the loop themselves instead of run():
  // serves an already connected stream socket as if a Unix listener had accepted it
  // (same limits and checks); returns its connection id.
  uint64_t adopt(int fd);
  // One turn of the event loop and the timers, as run() takes them.
  void run_once(int timeout_ms);
  // Nothing is being built, run on the device or waiting to be written.
  bool quiescent() const;
  size_t connection_count() const { return connections_.size(); }
  size_t session_count() const { return sessions_.size(); }

 private:
  using Bytes = net::Bytes;

  void accept_from(net::Listener& listener);
  void admit(int fd, const sockaddr_storage& addr, bool is_unix, bool proxied = false);
  // --max-connections-per-peer, once the connection's peer is known and counted: a reason, or empty.
  std::string per_peer_refusal(const net::Connection& c) const;
  void refuse(net::Connection& c, const std::string& refusal);
  // Proxied listeners: the PROXY header names the peer (server/net/proxy_header.hpp).
  void on_proxy_header(net::Connection& c);
  void refuse_proxy_header(net::Connection& c, protocol::ErrorCode code, const std::string& reason);
  void on_connection_event(uint64_t connection_id, uint32_t events);
  void handle_message(net::Connection& c, const protocol::Header& header, std::vector<uint8_t>&& payload);

  void on_hello(net::Connection& c, const protocol::Header& h, const protocol::Hello& m);
  void on_open_session(net::Connection& c, const protocol::Header& h, const protocol::OpenSession& m);
  void on_frame(net::Connection& c, const protocol::Header& h, protocol::Frame&& m, std::vector<uint8_t>&& payload);
  void on_attach(net::Connection& c, const protocol::Header& h, const protocol::Attach& m);
  void on_close_session(net::Connection& c, const protocol::Header& h, const protocol::CloseSession& m);
  void on_stats(net::Connection& c, const protocol::Header& h);

  void send(net::Connection& c, const protocol::Message& m, uint64_t request_id);
  void send_encoded(net::Connection& c, Bytes bytes);
  void send_error(net::Connection& c, uint64_t request_id, protocol::ErrorCode code, std::string field,
                  std::string message, bool fatal);
  void update_interest(net::Connection& c);
  void refresh_message_limit(net::Connection& c);
  void close_connection(uint64_t connection_id, const char* reason);
  void finish_session(const std::shared_ptr<Session>& s, bool notify);
  void drain_completions();
  void on_frame_done(FrameDone&& done);
  void on_pipeline_built(BuiltPipeline&& built);
  void save_pipeline_cache();
  void check_timers();
  // --idle-trim: memory no session holds goes back once the server is quiet.
  void trim_when_idle(std::chrono::steady_clock::time_point now);
  void begin_shutdown();
  bool shutdown_complete() const;
  net::Connection* find_connection(uint64_t id);
  bool has_work(const net::Connection& c) const;

  ServerOptions options_;
  gpu::Context& device_;
  std::string device_name_;
  net::EventLoop loop_;
  std::vector<net::Listener> listeners_;
  net::ReceiveBudget receive_budget_;  // --receive-budget, shared by every connection
  std::map<uint64_t, std::unique_ptr<net::Connection>> connections_;
  // Per-peer limits: open connections per peer identity, and those not
  // through HELLO yet in all.
  std::map<std::string, uint32_t> peer_connections_;
  uint32_t unauthenticated_ = 0;
  void count_connection(const net::Connection& c, int delta);
  SessionRegistry sessions_;
  uint64_t next_connection_id_ = 1;

  std::unique_ptr<Scheduler> scheduler_;
  std::unique_ptr<PipelineBuilder> builder_;
  uint32_t sessions_being_built_ = 0;
  // Capacity: the device memory all sessions may need (--max-device-memory, at
  // most the device's local heaps), and what open sessions and builds claim of it.
  uint64_t device_budget_bytes_ = 0;
  uint64_t bytes_being_built_ = 0;
  uint64_t committed_device_bytes() const;
  std::mutex completions_mutex_;  // guards completions_, built_ and warm_up_ (written by other threads)
  std::vector<FrameDone> completions_;
  std::vector<BuiltPipeline> built_;
  std::optional<WarmUpReport> warm_up_;

  std::atomic<bool> stop_requested_{false};
  bool shutting_down_ = false;
  std::chrono::steady_clock::time_point shutdown_deadline_{};
  int signal_fd_ = -1;

  std::map<uint8_t, Bytes> welcome_by_minor_;  // encoded WELCOME (request id 0) per negotiated minor
  ServerCounters counters_;
  std::vector<pipelines::SharedResourceTiming> shared_resources_;
  IdleTrimSchedule idle_trim_;
  bool warm_up_kernels_kept_ = false;  // KernelCache::keep_current() ran after the warm-up
};

}  // namespace dn::server
