// The connection layer's deadlines: output a peer does not take, messages
// that trickle in, HELLO and PROXY headers that never come, idle peers and
// the heartbeat that keeps a quiet one alive.
#include "server/net/connection_layer.hpp"
#include "server/log.hpp"

namespace dn::server {
namespace {

using protocol::ErrorCode;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t, Clock::time_point now) {
  return std::chrono::duration<double>(now - t).count();
}

}  // namespace

void ConnectionLayer::check_timers(Clock::time_point now) {
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
  for (auto& [id, reason] : to_close) close(id, reason);
}

}  // namespace dn::server
