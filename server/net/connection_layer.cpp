#include "server/net/connection_layer.hpp"

#include <fcntl.h>
#include <sys/epoll.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "server/handshake.hpp"
#include "server/log.hpp"
#include "server/net/auth.hpp"
#include "server/net/peer_identity.hpp"
#include "server/net/proxy_header.hpp"
#include "server/net/socket_options.hpp"

namespace dn::server {
namespace {

using protocol::ErrorCode;
using Clock = std::chrono::steady_clock;

constexpr size_t kReadBudgetPerEvent = 8u << 20;  // bytes read per wake-up before other sockets get a turn
constexpr uint64_t kControlMessageBytes = 64u << 10;  // the largest control message (OPEN_SESSION, ...)

// ERROR strings have wire limits (docs/protocol.md); cut at a UTF-8 character boundary.
std::string fit(std::string text, size_t limit) {
  if (text.size() <= limit) return text;
  size_t cut = limit;
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
  text.resize(cut);
  return text;
}

}  // namespace

ConnectionLayer::ConnectionLayer(const ServerOptions& options, net::EventLoop& loop, ServerCounters& counters,
                                 std::string device_name)
    : options_(options), loop_(loop), counters_(counters), device_name_(std::move(device_name)) {
  receive_budget_.limit = options_.receive_budget_bytes;
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
}

ConnectionLayer::~ConnectionLayer() {
  for (auto& l : listeners_) net::close_listener(l);
}

std::vector<std::string> ConnectionLayer::listening_urls() const {
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

void ConnectionLayer::begin_shutdown() {
  shutting_down_ = true;
  for (auto& l : listeners_) {
    loop_.remove(l.fd);
    net::close_listener(l);
  }
}

void ConnectionLayer::close_all(const char* reason) {
  for (auto it = connections_.begin(); it != connections_.end();) close((it++)->first, reason);
}

bool ConnectionLayer::output_pending() const {
  return std::any_of(connections_.begin(), connections_.end(),
                     [](const auto& entry) { return entry.second->has_pending_output(); });
}

net::Connection* ConnectionLayer::find(uint64_t id) {
  auto it = connections_.find(id);
  return it == connections_.end() ? nullptr : it->second.get();
}

void ConnectionLayer::add_live_state(LiveState& live) const {
  live.connections = connections_.size();
  for (auto& [id, conn] : connections_) {
    live.bytes_in_open += conn->bytes_in;
    live.bytes_out_open += conn->bytes_out;
  }
}

void ConnectionLayer::accept_from(net::Listener& listener) {
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

uint64_t ConnectionLayer::adopt(int fd) {
  // The loop never blocks on a socket: as accept4 gives them, non-blocking.
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
  sockaddr_storage addr{};
  addr.ss_family = AF_UNIX;
  const uint64_t id = next_id_;
  admit(fd, addr, /*is_unix=*/true);
  return id;
}

void ConnectionLayer::admit(int fd, const sockaddr_storage& addr, bool is_unix, bool proxied) {
  uint64_t id = next_id_++;
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
  else count_peer(c, +1);
  ++unauthenticated_;
  loop_.add(fd, EPOLLIN, [this, id](uint32_t events) { on_event(id, events); });
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

std::string ConnectionLayer::per_peer_refusal(const net::Connection& c) const {
  // Defaults to half of --max-connections, as --max-unauthenticated does (admit).
  const uint32_t per_peer =
      options_.max_connections_per_peer ? options_.max_connections_per_peer : std::max(1u, options_.max_connections / 2);
  auto it = peer_connections_.find(c.peer_identity);
  if (it == peer_connections_.end() || it->second <= per_peer) return {};
  return "peer " + c.peer_identity + " already has " + std::to_string(per_peer) +
         " connections (--max-connections-per-peer)";
}

void ConnectionLayer::refuse(net::Connection& c, const std::string& refusal) {
  log::warn("connection.refused", {{"conn", c.id()}, {"peer", c.peer()}, {"identity", c.peer_identity}, {"reason", refusal}});
  send_error(c, 0, ErrorCode::LimitExceeded, "connections", refusal, true);
}

void ConnectionLayer::on_proxy_header(net::Connection& c) {
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
  count_peer(c, +1);
  if (std::string refusal = per_peer_refusal(c); !refusal.empty()) refuse(c, refusal);
}

void ConnectionLayer::refuse_proxy_header(net::Connection& c, ErrorCode code, const std::string& reason) {
  log::warn("proxy.refused", {{"conn", c.id()}, {"peer", c.peer()}, {"reason", reason}});
  send_error(c, 0, code, "proxy_header", reason, true);
}

void ConnectionLayer::on_event(uint64_t id, uint32_t events) {
  net::Connection* c = find(id);
  if (!c) return;
  if (events & EPOLLERR) return close(id, "socket error");
  if (events & EPOLLOUT) {
    if (!c->flush()) return close(id, "write failed");
  }
  if ((events & (EPOLLIN | EPOLLHUP)) && c->awaiting_proxy_header() && !c->close_after_flush) {
    auto status = c->read_proxy_header();
    if (status == net::Connection::ReadStatus::Closed) return close(id, "peer closed before a PROXY header");
    if (status == net::Connection::ReadStatus::Failed) refuse_proxy_header(*c, ErrorCode::BadMagic, c->proxy_error());
    else if (!c->awaiting_proxy_header()) on_proxy_header(*c);
  }
  if ((events & (EPOLLIN | EPOLLHUP)) && !c->awaiting_proxy_header()) {
    auto status = c->read_available(
        [&](const protocol::Header& h, std::vector<uint8_t>&& payload, bool refused) {
          if (!refused) return on_message(*c, h, std::move(payload));
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
      if ((events & EPOLLHUP) || !has_work(*c)) return close(id, "peer closed");
      c->close_after_flush = true;
    } else if (status == net::Connection::ReadStatus::Failed) {
      const auto& e = c->read_error();
      log::warn("protocol.framing_error", {{"conn", id}, {"field", e.field}, {"reason", e.message}});
      send_error(*c, 0, e.code, e.field, e.message, true);
    } else if ((events & EPOLLHUP) && c->reading_paused()) {
      return close(id, "peer hung up");
    }
  }
  c = find(id);
  if (!c) return;
  if (c->close_after_flush && !has_work(*c)) return close(id, "closed after error");
  update_interest(*c);
}

void ConnectionLayer::update_interest(net::Connection& c) {
  // Pause reading while the peer does not take its output; resume below half the limit.
  if (!c.reading_paused() && c.queued_bytes() > options_.max_output_buffer_bytes) c.set_reading_paused(true);
  if (c.reading_paused()) {
    if (!handler_->window_full(c) && c.queued_bytes() <= options_.max_output_buffer_bytes / 2) c.set_reading_paused(false);
  }
  uint32_t events = 0;
  if (!c.reading_paused() && !c.close_after_flush) events |= EPOLLIN;
  if (c.has_pending_output()) events |= EPOLLOUT;
  loop_.modify(c.fd(), events);
}

void ConnectionLayer::send(net::Connection& c, const protocol::Message& m, uint64_t request_id) {
  auto bytes = std::make_shared<std::vector<uint8_t>>();
  protocol::encode(m, request_id, 0, *bytes);
  send_encoded(c, std::move(bytes));
}

void ConnectionLayer::send_encoded(net::Connection& c, Bytes bytes) {
  c.queue(std::move(bytes));
  if (!c.flush()) c.close_after_flush = true;  // nothing more can be written; close on the next turn
}

void ConnectionLayer::send_error(net::Connection& c, uint64_t request_id, ErrorCode code, std::string field,
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

void ConnectionLayer::on_message(net::Connection& c, const protocol::Header& header, std::vector<uint8_t>&& payload) {
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
  if (std::holds_alternative<protocol::Hello>(message))
    return send_error(c, header.request_id, ErrorCode::NotReady, "header.type", "HELLO sent twice", false);
  if (const auto* ping = std::get_if<protocol::Ping>(&message)) return send(c, protocol::Pong{ping->payload}, header.request_id);
  if (std::holds_alternative<protocol::Pong>(message)) return;  // heartbeat answered: receiving it refreshed last_received
  handler_->on_request(c, header, std::move(message), std::move(payload));
}

void ConnectionLayer::on_hello(net::Connection& c, const protocol::Header& h, const protocol::Hello& m) {
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

void ConnectionLayer::close(uint64_t id, const char* reason) {
  auto it = connections_.find(id);
  if (it == connections_.end()) return;
  std::unique_ptr<net::Connection> c = std::move(it->second);
  connections_.erase(it);
  if (!c->awaiting_proxy_header()) count_peer(*c, -1);  // counted once its peer was known
  if (!c->authenticated) --unauthenticated_;
  loop_.remove(c->fd());
  counters_.bytes_in_closed += c->bytes_in;
  counters_.bytes_out_closed += c->bytes_out;
  handler_->on_closed(*c);
  log::debug("connection.close", {{"conn", id}, {"peer", c->peer()}, {"reason", reason}});
}

void ConnectionLayer::count_peer(const net::Connection& c, int delta) {
  uint32_t& n = peer_connections_[c.peer_identity];
  n += delta;
  if (n == 0) peer_connections_.erase(c.peer_identity);
}

void ConnectionLayer::send_watched(net::Connection& c, Bytes bytes, uint64_t session_id) {
  c.queue(std::move(bytes), session_id);
  if (!c.flush()) c.close_after_flush = true;
  update_interest(c);
}

void ConnectionLayer::set_largest_frame(net::Connection& c, uint64_t frame_bytes) {
  // Up to twice the largest frame (so a frame with a wrong plane size still gets a
  // recoverable ERROR); nothing bigger is allocated.
  c.set_max_message_bytes(std::min(2 * frame_bytes + kControlMessageBytes, options_.max_message_bytes));
}

bool ConnectionLayer::has_work(const net::Connection& c) const {
  return c.has_pending_output() || handler_->has_work(c);
}

}  // namespace dn::server
