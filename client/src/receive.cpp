// Receiving: non-blocking reads into the framing reader, every complete
// message decoded and routed, and the waits for replies built on it.
#include <poll.h>
#include <sys/socket.h>

#include <cerrno>

#include "connection_state.hpp"
#include "io_wait.hpp"

namespace dn::client::detail {

void ConnectionState::read_available() {
  if (fd_ < 0) return;
  for (;;) {
    std::span<uint8_t> buf = reader_.writable();
    if (buf.empty()) {
      // Should not happen: the reader always wants bytes unless Ready/Failed.
      return;
    }
    const ssize_t n = ::recv(fd_, buf.data(), buf.size(), MSG_DONTWAIT);
    if (n == 0) {
      const bool mid = reader_.bytes_buffered() > 0;
      mark_failed(transport_error(mid ? "connection lost: the server closed the connection in the middle of a message"
                                      : "connection lost: the server closed the connection",
                                  protocol::ErrorCode::Internal));
      return;
    }
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN || errno == EWOULDBLOCK) return;
      // A server that dies with our frames unread resets the connection instead of closing it.
      const int err = errno;
      mark_failed(transport_error(err == ECONNRESET ? "connection lost: the server reset the connection (recv: " +
                                                          errno_text(err) + ")"
                                                    : "connection lost: recv failed: " + errno_text(err),
                                  protocol::ErrorCode::Internal));
      return;
    }
    const auto status = reader_.commit(size_t(n));
    if (status == protocol::MessageReader::Status::Failed) {
      const auto& d = reader_.error();
      mark_failed(Error::protocol_error(endpoint_str_, d.code, d.field, d.message));
      return;
    }
    if (status == protocol::MessageReader::Status::Ready) {
      Incoming in;
      in.header = reader_.header();
      in.payload = std::make_shared<std::vector<uint8_t>>(reader_.take_payload());
      in.received = Clock::now();
      if (auto err = protocol::decode_payload(in.header, *in.payload, in.message)) {
        mark_failed(Error::protocol_error(endpoint_str_, err->code, err->field, err->message));
        return;
      }
      dispatch(std::move(in));
    }
  }
}

void ConnectionState::dispatch(Incoming&& in) {
  ++messages_dispatched_;
  if (take_heartbeat(in)) return;
  demux_.route(std::move(in));
}

bool ConnectionState::pump(std::optional<Milliseconds> timeout) {
  check_usable();
  const uint64_t before = messages_dispatched_;
  read_available();
  check_usable();
  // Something was already waiting in the socket: the caller looks at it before anything waits.
  if (messages_dispatched_ != before) return true;
  if (timeout && timeout->count() == 0) return true;
  bool has_deadline = false;
  const auto deadline = deadline_from(timeout, has_deadline);
  pollfd p{fd_, POLLIN, 0};
  for (;;) {
    const int rc = ::poll(&p, 1, has_deadline ? remaining_ms(deadline) : -1);
    if (rc < 0 && errno == EINTR) continue;
    if (rc < 0) fail_transport(std::string("poll(): ") + errno_text(errno));
    if (rc == 0) return false;
    read_available();
    check_usable();
    return true;
  }
}

void ConnectionState::pump_nonblocking() {
  check_usable();
  read_available();
}

Incoming ConnectionState::wait_reply(uint64_t request_id, std::optional<Milliseconds> timeout) {
  if (!demux_.awaiting(request_id))
    throw Error::usage("internal: waiting for request " + std::to_string(request_id) + " that was never sent");
  bool has_deadline = false;
  const auto deadline = deadline_from(timeout, has_deadline);
  for (;;) {
    if (auto in = demux_.take(request_id)) return std::move(*in);
    check_usable();
    wait_fd(POLLIN, deadline, has_deadline,
            ("after " + std::to_string((timeout ? *timeout : io_timeout_).count()) + " ms waiting for the reply to " +
             demux_.waiting_for(request_id))
                .c_str());
  }
}

std::optional<Incoming> ConnectionState::take_reply_if_ready(uint64_t request_id) {
  if (!demux_.awaiting(request_id)) return std::nullopt;
  if (!demux_.reply_ready(request_id) && !broken_) read_available();
  return demux_.take(request_id);
}

}  // namespace dn::client::detail
