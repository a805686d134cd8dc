#include "server/server.hpp"

#include <algorithm>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <signal.h>
#include <sys/epoll.h>
#include <sys/signalfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "dn/protocol/codec.hpp"
#include "gpu/compute.hpp"
#include "gpu/context.hpp"
#include "gpu/devices.hpp"
#include "gpu/pipeline_cache.hpp"
#include "gpu/transient_pool.hpp"
#include "server/handshake.hpp"
#include "server/log.hpp"
#include "server/net/peer_identity.hpp"
#include "server/net/proxy_header.hpp"
#include "server/net/socket_options.hpp"
#include "server/stats.hpp"
#include "server/net/auth.hpp"
#include "server/pipelines/registry.hpp"

namespace dn::server {
namespace {

using protocol::ErrorCode;
using Clock = std::chrono::steady_clock;

constexpr size_t kReadBudgetPerEvent = 8u << 20;  // bytes read per wake-up before other sockets get a turn
constexpr int kTimerTickMs = 200;
constexpr uint64_t kControlMessageBytes = 64u << 10;  // the largest control message (OPEN_SESSION, ...)

// ERROR strings have wire limits (docs/protocol.md); cut at a UTF-8 character boundary.
std::string fit(std::string text, size_t limit) {
  if (text.size() <= limit) return text;
  size_t cut = limit;
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
  text.resize(cut);
  return text;
}

double seconds_since(Clock::time_point t, Clock::time_point now) {
  return std::chrono::duration<double>(now - t).count();
}

}  // namespace

Server::Server(ServerOptions options, gpu::Context& device, std::string device_name, PipelineFactory factory)
    : options_(std::move(options)),
      device_(device),
      device_name_(std::move(device_name)),
      idle_trim_(options_.idle_trim_s) {
  receive_budget_.limit = options_.receive_budget_bytes;
  const uint64_t heaps = gpu::describe_device(device_.physical_device(), 0).device_local_bytes;
  device_budget_bytes_ = options_.max_device_bytes && (options_.max_device_bytes < heaps || heaps == 0)
                             ? options_.max_device_bytes
                             : heaps;
  log::info("device_memory_budget", {{"bytes", device_budget_bytes_}, {"device_local_heaps", heaps}});

  // Context-wide resources the pipelines declare (svgf-fb's F_beta table):
  // made once per device before any session can bind them, then shared
  // read-only (a second Server on the same context reuses them).
  shared_resources_ = pipelines::prepare_shared_resources(device_);
  for (const auto& r : shared_resources_)
    log::info("shared_resource", {{"name", r.name}, {"ms", r.ms}, {"device", device_name_}});

  std::vector<std::pair<net::Endpoint, bool>> endpoints;  // and whether proxied
  for (const bool proxied : {false, true}) {
    const char* flag = proxied ? "--listen-proxied " : "--listen ";
    for (const std::string& url : proxied ? options_.listen_proxied : options_.listen) {
      std::string error;
      auto e = net::parse_endpoint(url, error);
      if (!e) throw std::runtime_error(flag + error);
      if (e->kind == net::Endpoint::Kind::Tcp && !net::is_loopback(*e) && options_.token.empty())
        throw std::runtime_error(flag + url +
                                 " is not a loopback address: set an authentication token with --token-file or DN_TOKEN");
      // A balancer serves whoever reaches it, wherever its own listener is.
      if (proxied && options_.token.empty())
        throw std::runtime_error(flag + url +
                                 " is reached through a balancer: set an authentication token with --token-file or DN_TOKEN");
      endpoints.emplace_back(*e, proxied);
    }
  }
  for (const auto& [e, proxied] : endpoints) {
    listeners_.push_back(net::open_listener(e, !options_.allowed_uids.empty()));
    net::Listener& l = listeners_.back();
    l.proxied = proxied;
    log::info("listen", {{"url", listening_urls().back()},
                         {"auth", options_.token.empty() ? "none" : "token"},
                         {"proxy_protocol", proxied ? "v2" : "none"}});
    size_t index = listeners_.size() - 1;
    loop_.add(l.fd, EPOLLIN, [this, index](uint32_t) { accept_from(listeners_[index]); });
  }

  scheduler_ = std::make_unique<Scheduler>(options_.workers, [this](FrameDone&& done) {
    {
      std::lock_guard lock(completions_mutex_);
      completions_.push_back(std::move(done));
    }
    loop_.wake();
  });
  builder_ = std::make_unique<PipelineBuilder>(device_, [this](BuiltPipeline&& built) {
    {
      std::lock_guard lock(completions_mutex_);
      built_.push_back(std::move(built));
    }
    loop_.wake();
  }, std::move(factory));
  if (options_.warm_up) {
    builder_->warm_up([this](const WarmUpReport& report) {
      {
        std::lock_guard lock(completions_mutex_);
        warm_up_ = report;
      }
      // A failure leaves some configuration a client can open cold: a warning.
      log::write(report.error.empty() ? log::Level::Info : log::Level::Warn, "warm_up",
                 {{"sessions", report.configs},
                  {"offered", report.offered},
                  {"kernels", report.kernels},
                  {"ms", report.ms},
                  {"cache_bytes", report.cache_bytes},
                  {"error", report.error}});
    });
  }
  loop_.set_wake_handler([this] { drain_completions(); });
}

Server::~Server() {
  if (builder_) builder_->stop();
  if (scheduler_) scheduler_->stop();
  for (auto& l : listeners_) net::close_listener(l);
  if (signal_fd_ >= 0) ::close(signal_fd_);
}

std::vector<std::string> Server::listening_urls() const {
  std::vector<std::string> urls;
  for (const auto& l : listeners_) {
    if (l.endpoint.kind == net::Endpoint::Kind::Unix) {
      urls.push_back("unix://" + l.endpoint.path);
    } else {
      bool v6 = l.endpoint.host.find(':') != std::string::npos;
      urls.push_back("tcp://" + (v6 ? "[" + l.endpoint.host + "]" : l.endpoint.host) + ":" +
                     std::to_string(l.bound_port));
    }
  }
  return urls;
}

void Server::request_stop() {
  stop_requested_ = true;
  loop_.wake();
}

void Server::run(bool handle_signals) {
  if (handle_signals) {
    sigset_t mask;
    sigemptyset(&mask);
    sigaddset(&mask, SIGTERM);
    sigaddset(&mask, SIGINT);
    pthread_sigmask(SIG_BLOCK, &mask, nullptr);
    signal_fd_ = ::signalfd(-1, &mask, SFD_NONBLOCK | SFD_CLOEXEC);
    if (signal_fd_ < 0) throw std::runtime_error(std::string("signalfd: ") + std::strerror(errno));
    loop_.add(signal_fd_, EPOLLIN, [this](uint32_t) {
      signalfd_siginfo info;
      while (::read(signal_fd_, &info, sizeof info) == sizeof info) {
        log::info("signal", {{"signal", info.ssi_signo == SIGTERM ? "SIGTERM" : "SIGINT"}});
        stop_requested_ = true;
      }
    });
  }
  log::info("ready", {{"device", device_name_}, {"workers", options_.workers}});
  for (;;) {
    run_once(kTimerTickMs);
    if (shutting_down_ && shutdown_complete()) break;
  }
  for (auto it = connections_.begin(); it != connections_.end();) close_connection((it++)->first, "shutdown");
  builder_->stop();
  scheduler_->stop();
  save_pipeline_cache();
  log::info("stopped", {{"frames", counters_.frames_processed}});
}

void Server::run_once(int timeout_ms) {
  loop_.run_once(timeout_ms);
  if (stop_requested_ && !shutting_down_) begin_shutdown();
  check_timers();
}

bool Server::quiescent() const {
  if (sessions_being_built_ > 0 || sessions_.frames_in_flight() > 0) return false;
  for (const auto& [id, c] : connections_)
    if (c->has_pending_output()) return false;
  return true;
}

void Server::begin_shutdown() {
  shutting_down_ = true;
  shutdown_deadline_ = Clock::now() + std::chrono::milliseconds(static_cast<int64_t>(options_.shutdown_grace_s * 1000));
  for (auto& l : listeners_) {
    loop_.remove(l.fd);
    net::close_listener(l);
  }
  log::info("shutdown.begin", {{"frames_in_flight", sessions_.frames_in_flight()}, {"connections", connections_.size()}});
}

bool Server::shutdown_complete() const {
  if (Clock::now() >= shutdown_deadline_) {
    log::warn("shutdown.deadline", {{"grace_s", options_.shutdown_grace_s}});
    return true;
  }
  return quiescent();
}

void Server::accept_from(net::Listener& listener) {
  const bool is_unix = listener.endpoint.kind == net::Endpoint::Kind::Unix;
  for (;;) {
    sockaddr_storage addr{};
    socklen_t len = sizeof addr;
    int fd = ::accept4(listener.fd, reinterpret_cast<sockaddr*>(&addr), &len, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EINTR) continue;
      if (errno != EAGAIN && errno != EWOULDBLOCK) log::warn("accept.failed", {{"error", std::strerror(errno)}});
      return;
    }
    admit(fd, addr, is_unix, listener.proxied);
  }
}

uint64_t Server::adopt(int fd) {
  sockaddr_storage addr{};
  addr.ss_family = AF_UNIX;
  const uint64_t id = next_connection_id_;
  admit(fd, addr, /*is_unix=*/true);
  return id;
}

void Server::admit(int fd, const sockaddr_storage& addr, bool is_unix, bool proxied) {
  uint64_t id = next_connection_id_++;
  ++counters_.connections_accepted;
  // Until HELLO, only control messages are expected: no peer makes us allocate a frame's worth unasked.
  auto conn = std::make_unique<net::Connection>(fd, id, is_unix, net::peer_name(addr, is_unix), kControlMessageBytes,
                                                &receive_budget_);
  net::tune_socket(fd, is_unix, options_.dead_peer_s);
  net::Connection& c = *conn;
  c.peer_identity = net::peer_identity(fd, addr, is_unix);
  connections_[id] = std::move(conn);
  // Behind a balancer the peer is the one its PROXY header names: counted
  // per peer once that is read (on_proxy_header), not as the balancer.
  if (proxied) c.expect_proxy_header();
  else count_connection(c, +1);
  ++unauthenticated_;
  loop_.add(fd, EPOLLIN, [this, id](uint32_t events) { on_connection_event(id, events); });
  log::debug("connection.open", {{"conn", id}, {"peer", c.peer()}, {"identity", c.peer_identity}});

  // Limits, global then per peer: a flood from one peer is refused before
  // it can take the slots every other peer needs.
  std::string refusal;
  // Both default to half of --max-connections: a flood from one peer, or of
  // connections that never say HELLO, leaves the other half to everyone else.
  const uint32_t half = std::max(1u, options_.max_connections / 2);
  const uint32_t unauthenticated = options_.max_unauthenticated ? options_.max_unauthenticated : half;
  if (connections_.size() > options_.max_connections)
    refusal = "server already has " + std::to_string(options_.max_connections) + " connections (--max-connections)";
  else if (!proxied)
    refusal = per_peer_refusal(c);
  if (refusal.empty() && unauthenticated_ > unauthenticated)
    refusal = "server already has " + std::to_string(unauthenticated) +
              " connections without HELLO (--max-unauthenticated)";
  if (!refusal.empty()) return refuse(c, refusal);
  if (is_unix) {
    uint32_t uid = 0;
    if (!net::unix_peer_allowed(fd, options_.allowed_uids, uid)) {
      log::warn("auth.refused", {{"conn", id}, {"peer_uid", uid}});
      send_error(c, 0, ErrorCode::Unauthenticated, "peer_credentials",
                 "Unix-socket peer uid " + std::to_string(uid) + " is not allowed (--allow-uid)", true);
    }
  }
}

std::string Server::per_peer_refusal(const net::Connection& c) const {
  // Defaults to half of --max-connections, as --max-unauthenticated does (admit).
  const uint32_t per_peer =
      options_.max_connections_per_peer ? options_.max_connections_per_peer : std::max(1u, options_.max_connections / 2);
  auto it = peer_connections_.find(c.peer_identity);
  if (it == peer_connections_.end() || it->second <= per_peer) return {};
  return "peer " + c.peer_identity + " already has " + std::to_string(per_peer) +
         " connections (--max-connections-per-peer)";
}

void Server::refuse(net::Connection& c, const std::string& refusal) {
  log::warn("connection.refused", {{"conn", c.id()}, {"peer", c.peer()}, {"identity", c.peer_identity}, {"reason", refusal}});
  send_error(c, 0, ErrorCode::LimitExceeded, "connections", refusal, true);
}

void Server::on_proxy_header(net::Connection& c) {
  const net::ProxyHeader& h = c.proxy_header();
  const std::string via = c.peer();
  // LOCAL (the balancer's health check), UNSPEC, UNIX or UDP: the socket's own peer stays.
  const bool forwarded = h.source.ss_family != AF_UNSPEC;
  if (forwarded) {
    c.set_peer(net::peer_name(h.source, false));
    c.peer_identity = net::address_identity(h.source);
  }
  log::write(forwarded ? log::Level::Info : log::Level::Debug, "connection.proxied",
             {{"conn", c.id()},
              {"peer", c.peer()},
              {"via", via},
              {"command", h.command == net::ProxyHeader::Command::Local ? "LOCAL" : "PROXY"},
              {"identity", c.peer_identity}});
  count_connection(c, +1);
  if (std::string refusal = per_peer_refusal(c); !refusal.empty()) refuse(c, refusal);
}

void Server::refuse_proxy_header(net::Connection& c, ErrorCode code, const std::string& reason) {
  log::warn("proxy.refused", {{"conn", c.id()}, {"peer", c.peer()}, {"reason", reason}});
  send_error(c, 0, code, "proxy_header", reason, true);
}

net::Connection* Server::find_connection(uint64_t id) {
  auto it = connections_.find(id);
  return it == connections_.end() ? nullptr : it->second.get();
}

void Server::on_connection_event(uint64_t id, uint32_t events) {
  net::Connection* c = find_connection(id);
  if (!c) return;
  if (events & EPOLLERR) return close_connection(id, "socket error");
  if (events & EPOLLOUT) {
    if (!c->flush()) return close_connection(id, "write failed");
  }
  if ((events & (EPOLLIN | EPOLLHUP)) && c->awaiting_proxy_header() && !c->close_after_flush) {
    auto status = c->read_proxy_header();
    if (status == net::Connection::ReadStatus::Closed) return close_connection(id, "peer closed before a PROXY header");
    if (status == net::Connection::ReadStatus::Failed) refuse_proxy_header(*c, ErrorCode::BadMagic, c->proxy_error());
    else if (!c->awaiting_proxy_header()) on_proxy_header(*c);
  }
  if ((events & (EPOLLIN | EPOLLHUP)) && !c->awaiting_proxy_header()) {
    auto status = c->read_available(
        [&](const protocol::Header& h, std::vector<uint8_t>&& payload, bool refused) {
          if (!refused) return handle_message(*c, h, std::move(payload));
          log::warn("receive.budget_refused", {{"conn", c->id()}, {"peer", c->peer()}, {"bytes", h.payload_length}});
          send_error(*c, h.request_id, ErrorCode::LimitExceeded, "header.payload_length",
                     "the server's receive budget (--receive-budget " + std::to_string(options_.receive_budget_bytes) +
                         " bytes) is taken by other messages being received; this " +
                         std::to_string(h.payload_length) + "-byte payload was dropped: send it again later",
                     !c->authenticated);
        },
        kReadBudgetPerEvent);
    if (status == net::Connection::ReadStatus::Closed) {
      // A peer that only shut down its sending side still gets the results of its frames.
      if ((events & EPOLLHUP) || !has_work(*c)) return close_connection(id, "peer closed");
      c->close_after_flush = true;
    } else if (status == net::Connection::ReadStatus::Failed) {
      const auto& e = c->read_error();
      log::warn("protocol.framing_error", {{"conn", id}, {"field", e.field}, {"reason", e.message}});
      send_error(*c, 0, e.code, e.field, e.message, true);
    } else if ((events & EPOLLHUP) && c->reading_paused()) {
      return close_connection(id, "peer hung up");
    }
  }
  c = find_connection(id);
  if (!c) return;
  if (c->close_after_flush && !has_work(*c)) return close_connection(id, "closed after error");
  update_interest(*c);
}

bool Server::has_work(const net::Connection& c) const {
  if (c.has_pending_output() || c.sessions_being_built > 0) return true;
  for (uint64_t sid : c.owned_sessions)
    if (const Session* s = sessions_.find(sid); s && s->in_flight > 0) return true;
  return false;
}

void Server::refresh_message_limit(net::Connection& c) {
  // A peer may send messages up to twice the frame size of the largest session it owns (so a
  // frame with a wrong plane size still gets a recoverable ERROR); nothing bigger is allocated.
  uint64_t limit = kControlMessageBytes;
  for (uint64_t sid : c.owned_sessions)
    if (const Session* s = sessions_.find(sid))
      limit = std::max(limit, 2 * frame_message_bytes(s->config()) + kControlMessageBytes);
  c.set_max_message_bytes(std::min(limit, options_.max_message_bytes));
}

void Server::update_interest(net::Connection& c) {
  // Pause reading while the peer does not take its output; resume below half the limit.
  if (!c.reading_paused() && c.queued_bytes() > options_.max_output_buffer_bytes) c.set_reading_paused(true);
  if (c.reading_paused()) {
    bool window_full = false;
    for (uint64_t sid : c.owned_sessions)
      if (const Session* s = sessions_.find(sid); s && s->in_flight >= options_.max_frames_in_flight) window_full = true;
    if (!window_full && c.queued_bytes() <= options_.max_output_buffer_bytes / 2) c.set_reading_paused(false);
  }
  uint32_t events = 0;
  if (!c.reading_paused() && !c.close_after_flush) events |= EPOLLIN;
  if (c.has_pending_output()) events |= EPOLLOUT;
  loop_.modify(c.fd(), events);
}

void Server::send(net::Connection& c, const protocol::Message& m, uint64_t request_id) {
  auto bytes = std::make_shared<std::vector<uint8_t>>();
  protocol::encode(m, request_id, 0, *bytes);
  send_encoded(c, std::move(bytes));
}

void Server::send_encoded(net::Connection& c, Bytes bytes) {
  c.queue(std::move(bytes));
  if (!c.flush()) c.close_after_flush = true;  // nothing more can be written; close on the next turn
}

void Server::send_error(net::Connection& c, uint64_t request_id, ErrorCode code, std::string field,
                        std::string message, bool fatal) {
  log::info("request.error", {{"conn", c.id()},
                              {"code", protocol::to_string(code)},
                              {"field", field},
                              {"reason", message},
                              {"fatal", fatal}});
  send(c, protocol::Error{code, fit(std::move(field), 256), fit(std::move(message), 1024)}, request_id);
  if (fatal) {
    c.close_after_flush = true;
    // Never read from a connection that broke framing again.
    ::shutdown(c.fd(), SHUT_RD);
  }
}

void Server::handle_message(net::Connection& c, const protocol::Header& header, std::vector<uint8_t>&& payload) {
  protocol::Message message;
  if (auto err = protocol::decode_payload(header, payload, message)) {
    // Framing is intact, so the connection can go on after a bad payload.
    send_error(c, header.request_id, err->code, err->field, err->message, !c.authenticated);
    return;
  }
  if (!c.authenticated) {
    if (auto* hello = std::get_if<protocol::Hello>(&message)) return on_hello(c, header, *hello);
    return send_error(c, header.request_id, ErrorCode::NotReady, "header.type",
                      std::string(protocol::to_string(header.type)) + " before HELLO: the first message must be HELLO",
                      true);
  }
  std::visit(
      [&](auto&& m) {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, protocol::Hello>) {
          send_error(c, header.request_id, ErrorCode::NotReady, "header.type", "HELLO sent twice", false);
        } else if constexpr (std::is_same_v<T, protocol::OpenSession>) {
          on_open_session(c, header, m);
        } else if constexpr (std::is_same_v<T, protocol::Frame>) {
          on_frame(c, header, std::move(m), std::move(payload));
        } else if constexpr (std::is_same_v<T, protocol::Attach>) {
          on_attach(c, header, m);
        } else if constexpr (std::is_same_v<T, protocol::Ping>) {
          send(c, protocol::Pong{m.payload}, header.request_id);
        } else if constexpr (std::is_same_v<T, protocol::Pong>) {
          // Heartbeat answered; receiving it already refreshed last_received.
        } else if constexpr (std::is_same_v<T, protocol::CloseSession>) {
          on_close_session(c, header, m);
        } else if constexpr (std::is_same_v<T, protocol::StatsRequest>) {
          on_stats(c, header);
        } else {
          send_error(c, header.request_id, ErrorCode::UnknownMessageType, "header.type",
                     std::string(protocol::to_string(header.type)) + " is sent by servers, not clients", false);
        }
      },
      message);
}

void Server::on_hello(net::Connection& c, const protocol::Header& h, const protocol::Hello& m) {
  if (!options_.token.empty() && !net::tokens_equal(options_.token, m.auth_token)) {
    log::warn("auth.refused", {{"conn", c.id()}, {"peer", c.peer()}, {"client", m.client_name}});
    return send_error(c, h.request_id, ErrorCode::Unauthenticated, "HELLO.auth_token",
                      m.auth_token.empty() ? "this server requires an authentication token"
                                           : "authentication token does not match",
                      true);
  }
  if (shutting_down_) return send_error(c, h.request_id, ErrorCode::ShuttingDown, "", "server is shutting down", true);
  c.authenticated = true;
  --unauthenticated_;
  c.administrator = !options_.token.empty();  // the token was checked above
  c.negotiated_minor = std::min(h.version_minor, protocol::kVersionMinor);
  log::info("connection.hello", {{"conn", c.id()}, {"peer", c.peer()}, {"client", m.client_name}});
  // WELCOME depends only on the client's minor: encoded once per minor (it
  // carries every pipeline's parameter table), not for every HELLO.
  Bytes& welcome = welcome_by_minor_[c.negotiated_minor];
  if (!welcome) welcome = std::make_shared<const std::vector<uint8_t>>(
                    protocol::encode(make_welcome(options_, device_name_, c.negotiated_minor)));
  auto reply = std::make_shared<std::vector<uint8_t>>(*welcome);
  protocol::set_request_id(*reply, h.request_id);
  send_encoded(c, std::move(reply));
}

void Server::close_connection(uint64_t id, const char* reason) {
  auto it = connections_.find(id);
  if (it == connections_.end()) return;
  std::unique_ptr<net::Connection> c = std::move(it->second);
  connections_.erase(it);
  if (!c->awaiting_proxy_header()) count_connection(*c, -1);  // counted once its peer was known
  if (!c->authenticated) --unauthenticated_;
  loop_.remove(c->fd());
  counters_.bytes_in_closed += c->bytes_in;
  counters_.bytes_out_closed += c->bytes_out;
  for (uint64_t sid : std::vector<uint64_t>(c->owned_sessions))
    if (auto s = sessions_.get(sid)) finish_session(s, false);
  for (uint64_t sid : c->watched_sessions)
    if (Session* s = sessions_.find(sid)) std::erase(s->watchers, id);
  log::debug("connection.close", {{"conn", id}, {"peer", c->peer()}, {"reason", reason}});
}

void Server::count_connection(const net::Connection& c, int delta) {
  uint32_t& n = peer_connections_[c.peer_identity];
  n += delta;
  if (n == 0) peer_connections_.erase(c.peer_identity);
}

void Server::drain_completions() {
  std::vector<FrameDone> batch;
  std::vector<BuiltPipeline> built;
  {
    std::lock_guard lock(completions_mutex_);
    batch.swap(completions_);
    built.swap(built_);
  }
  for (BuiltPipeline& b : built) on_pipeline_built(std::move(b));
  for (FrameDone& d : batch) on_frame_done(std::move(d));
}

void Server::check_timers() {
  const auto now = Clock::now();
  // Scratch no frame has leased for a while goes back to the device.
  gpu::TransientPool::of(device_).trim(std::chrono::seconds(30));
  std::vector<std::pair<uint64_t, const char*>> to_close;
  for (auto& [id, c] : connections_) {
    // A peer that does not take its output: bounded in bytes and in time.
    if (c->queued_bytes() > options_.max_queued_output_bytes) {
      log::warn("connection.output_overflow", {{"conn", id}, {"peer", c->peer()}, {"queued_bytes", c->queued_bytes()}});
      to_close.emplace_back(id, "queued output above --max-queued-output");
      continue;
    }
    if (c->has_pending_output() && options_.write_timeout_s > 0 &&
        seconds_since(c->last_write_progress(), now) > options_.write_timeout_s) {
      log::warn("connection.write_timeout",
                {{"conn", id}, {"peer", c->peer()}, {"queued_bytes", c->queued_bytes()}, {"timeout_s", options_.write_timeout_s}});
      to_close.emplace_back(id, "write timeout");
      continue;
    }
    if (c->close_after_flush) {
      if (!has_work(*c)) to_close.emplace_back(id, "closed after error");
      continue;
    }
    // A started message must finish in message_timeout_s plus its size at
    // min_receive_rate, however its bytes trickle in (each one refreshes the idle clock).
    if (c->receiving() && !c->reading_paused()) {
      const double allowed = options_.message_timeout_s + static_cast<double>(c->message_bytes_declared()) /
                                                              static_cast<double>(options_.min_receive_rate);
      if (seconds_since(c->message_started(), now) > allowed) {
        log::warn("connection.message_timeout", {{"conn", id},
                                                 {"peer", c->peer()},
                                                 {"received", c->message_bytes_received()},
                                                 {"declared", c->message_bytes_declared()}});
        send_error(*c, 0, ErrorCode::Timeout, "",
                   "a message was started " + std::to_string(static_cast<int64_t>(allowed)) + " s ago and has " +
                       std::to_string(c->message_bytes_received()) + " of its " +
                       (c->message_bytes_declared() ? std::to_string(c->message_bytes_declared()) : std::string("24+")) +
                       " bytes (--message-timeout, --min-receive-rate)",
                   true);
        update_interest(*c);
        continue;
      }
    }
    if (!c->authenticated) {
      if (seconds_since(c->created, now) > options_.handshake_timeout_s && c->awaiting_proxy_header()) {
        refuse_proxy_header(*c, ErrorCode::Timeout,
                            "no complete PROXY header within " + std::to_string(options_.handshake_timeout_s) +
                                " s of connecting (--handshake-timeout)");
        update_interest(*c);
      } else if (seconds_since(c->created, now) > options_.handshake_timeout_s) {
        send_error(*c, 0, ErrorCode::Timeout, "HELLO",
                   "no HELLO within " + std::to_string(options_.handshake_timeout_s) + " s of connecting", true);
        update_interest(*c);
      }
      continue;
    }
    const double idle = seconds_since(c->last_received, now);
    if (has_work(*c)) continue;  // waiting for its own frames or draining output is not idle
    if (options_.idle_timeout_s > 0 && idle > options_.idle_timeout_s) {
      send_error(*c, 0, ErrorCode::Timeout, "", "nothing received for " + std::to_string(options_.idle_timeout_s) + " s",
                 true);
      update_interest(*c);
    } else if (options_.heartbeat_s > 0 && idle > options_.heartbeat_s &&
               seconds_since(c->last_ping_sent, now) > options_.heartbeat_s) {
      c->last_ping_sent = now;
      send(*c, protocol::Ping{static_cast<uint64_t>(now.time_since_epoch().count())}, 0);
      update_interest(*c);
    }
  }
  for (auto& [id, reason] : to_close) close_connection(id, reason);
  trim_when_idle(now);
}

void Server::trim_when_idle(Clock::time_point now) {
  bool warm_up_done = false;
  {
    std::lock_guard lock(completions_mutex_);
    warm_up_done = warm_up_.has_value();
  }
  // The warm-up's kernels stay compiled for the server's lifetime; later ones only while used.
  if (warm_up_done && !warm_up_kernels_kept_) {
    device_.kernels().keep_current();
    warm_up_kernels_kept_ = true;
  }
  const bool busy = sessions_being_built_ > 0 || sessions_.frames_in_flight() > 0 || (options_.warm_up && !warm_up_done);
  const std::vector<uint64_t> activity{counters_.frames_processed, counters_.frames_failed, counters_.sessions_opened,
                                       counters_.connections_accepted, sessions_.size(), connections_.size()};
  if (!idle_trim_.due(activity, busy, now)) return;
  const IdleTrimReport r = trim_idle_memory(device_);
  log::info("idle_trim", {{"resident_before", r.resident_before},
                          {"resident_after", r.resident_after},
                          {"transient_bytes", r.transient_bytes},
                          {"kernels", r.kernels},
                          {"sessions", sessions_.size()},
                          {"ms", r.ms}});
}

void Server::on_stats(net::Connection& c, const protocol::Header& h) {
  LiveState live;
  live.connections = connections_.size();
  for (auto& [id, conn] : connections_) {
    live.bytes_in_open += conn->bytes_in;
    live.bytes_out_open += conn->bytes_out;
  }
  live.sessions = sessions_.size();
  live.sessions_being_built = sessions_being_built_;
  live.device_budget_bytes = device_budget_bytes_;
  live.being_built_bytes = bytes_being_built_;
  live.max_sessions = options_.max_sessions;
  live.max_session_bytes = options_.max_session_bytes;
  for (auto& [id, s] : sessions_) {
    live.frames_in_flight += s->in_flight;
    live.device_bytes += s->device_bytes();  // a closed one's is freed once its last frame leaves the device
    live.transient_bytes += s->transient_bytes();
    // A session's id and figures only to its owner or an administrator: another
    // local user must not learn what to ATTACH to (docs/server.md, "Security").
    if (s->owner() != c.id() && !c.administrator) continue;
    const double pixels = static_cast<double>(uint64_t{s->config().width} * s->config().height);
    live.sessions_figures.push_back({id, s->frames_processed,
                                     static_cast<double>(s->device_bytes() - s->transient_bytes()) / pixels,
                                     static_cast<double>(s->transient_bytes()) / pixels});
  }
  {
    std::lock_guard lock(completions_mutex_);
    live.warm_up = warm_up_;
  }
  live.shared_resources = shared_resources_;
  send(c, make_stats(counters_, live, device_), h.request_id);
}

uint64_t Server::committed_device_bytes() const {
  uint64_t bytes = bytes_being_built_;
  for (const auto& [id, s] : sessions_) bytes += s->device_bytes();
  return bytes;
}

void Server::save_pipeline_cache() {
  try {
    const uint64_t bytes = device_.pipeline_cache().save();
    if (bytes) log::info("pipeline_cache.saved", {{"path", device_.pipeline_cache().path()}, {"bytes", bytes}});
  } catch (const std::exception& e) {
    log::warn("pipeline_cache.save_failed", {{"reason", e.what()}});
  }
}

}  // namespace dn::server
