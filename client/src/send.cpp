// Sending: one gathered message at a time, reading what arrives while the
// socket is full, and the server's ERROR winning over a broken pipe.
#include <poll.h>
#include <sys/socket.h>
#include <sys/uio.h>

#include <cerrno>

#include "connection_state.hpp"
#include "io_wait.hpp"

namespace dn::client::detail {

void ConnectionState::wait_fd(short events, Clock::time_point deadline, bool has_deadline, const char* what) {
  for (;;) {
    if (broken_ || fd_ < 0) return;
    pollfd p{fd_, events, 0};
    const int t = has_deadline ? remaining_ms(deadline) : -1;
    const int rc = ::poll(&p, 1, t);
    if (rc < 0) {
      if (errno == EINTR) continue;
      fail_transport(std::string("poll(): ") + errno_text(errno));
    }
    if (rc == 0) fail_transport(std::string("timed out ") + what, protocol::ErrorCode::Timeout);
    if (p.revents & (POLLIN | POLLHUP | POLLERR)) read_available();
    if (broken_) return;  // the caller reports it (after looking at what arrived first)
    if ((events & POLLOUT) && (p.revents & (POLLOUT | POLLERR | POLLHUP))) return;
    if (!(events & POLLOUT)) return;
  }
}

void ConnectionState::send(const protocol::Message& message, uint64_t request_id, uint32_t flags, bool expect_reply,
                           uint64_t max_bytes) {
  check_usable();
  // Gather the message: header and fields in send_buffer_, plane bytes sent
  // straight from the caller's memory (no copy of a 100 MB frame).
  protocol::encode_segments(message, request_id, flags, send_buffer_, send_segments_);
  uint64_t total = 0;
  for (auto seg : send_segments_) total += seg.size();
  if (max_bytes && total > max_bytes)
    throw Error::usage(protocol::ErrorCode::LimitExceeded, protocol::to_string(protocol::type_of(message)),
                       "message of " + std::to_string(total) + " bytes exceeds the server's max_message_bytes " +
                           std::to_string(max_bytes));
  if (expect_reply) demux_.expect(request_id, protocol::type_of(message));
  sending_ = true;
  struct ClearSending {
    ConnectionState* self;
    ~ClearSending() { self->sending_ = false; }
  } clear_sending{this};
  protocol::SegmentCursor cursor;
  bool has_deadline = false;
  auto deadline = deadline_from(std::nullopt, has_deadline);
  while (!cursor.done(send_segments_)) {
    iovec iov[64];
    size_t count = 0;
    for (size_t i = cursor.segment; i < send_segments_.size() && count < 64; ++i, ++count) {
      const auto piece = cursor.remaining(send_segments_, i);
      iov[count] = {const_cast<uint8_t*>(piece.data()), piece.size()};
    }
    msghdr msg{};
    msg.msg_iov = iov;
    msg.msg_iovlen = count;
    const ssize_t n = ::sendmsg(fd_, &msg, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      cursor.advance(send_segments_, size_t(n));
      deadline = deadline_from(std::nullopt, has_deadline);  // io_timeout bounds a stall, not the whole send
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      wait_fd(POLLOUT | POLLIN, deadline, has_deadline,
              ("sending: no progress for " + std::to_string(io_timeout_.count()) + " ms").c_str());
      if (broken_) throw_send_failure(request_id, expect_reply);  // reading found the connection closed
      continue;
    }
    const int err = errno;
    // The server may have said why before hanging up: read it.
    read_available();
    if (!broken_)
      mark_failed(transport_error(err == EPIPE || err == ECONNRESET
                                      ? "connection lost while sending: the server closed the connection (send: " +
                                            errno_text(err) + ")"
                                      : "send failed: " + errno_text(err),
                                  protocol::ErrorCode::Internal));
    throw_send_failure(request_id, expect_reply);
  }
  send_segments_.clear();
  sending_ = false;
  send_pong_if_due();
}

void ConnectionState::throw_send_failure(uint64_t request_id, bool expect_reply) {
  // A server that rejects a message mid-stream (e.g. MessageTooLarge) answers
  // ERROR and hangs up while we are still sending: its answer beats EPIPE.
  if (expect_reply) {
    if (const Incoming* reply = demux_.peek(request_id)) {
      if (auto* e = std::get_if<protocol::Error>(&reply->message)) {
        Error err = Error::server(*e, endpoint_str_);
        demux_.forget(request_id);
        throw err;
      }
    }
  }
  throw *failure_;
}

}  // namespace dn::client::detail
