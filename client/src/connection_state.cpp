#include "connection_state.hpp"

#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace dn::client::detail {

namespace {

std::string errno_text(int err) { return std::strerror(err); }

int remaining_ms(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<Milliseconds>(deadline - Clock::now()).count();
  if (left <= 0) return 0;
  return left > 1'000'000'000 ? 1'000'000'000 : int(left);
}

void set_buffers(int fd, int bytes) {
  if (bytes <= 0) return;
  // Best effort: the kernel clamps to net.core.[rw]mem_max.
  setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &bytes, sizeof bytes);
  setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &bytes, sizeof bytes);
}

}  // namespace

ConnectionState::ConnectionState(Endpoint endpoint, const ConnectOptions& options)
    : endpoint_(std::move(endpoint)),
      endpoint_str_(endpoint_.to_string()),
      connect_timeout_(options.connect_timeout),
      io_timeout_(options.io_timeout),
      buffer_bytes_(options.socket_buffer_bytes),
      max_message_bytes_(options.max_message_bytes ? options.max_message_bytes : (uint64_t{1} << 32)),
      reader_(max_message_bytes_) {}

ConnectionState::~ConnectionState() { close(); }

void ConnectionState::close() {
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
  if (!broken_) {
    broken_ = true;
    failure_ = Error::transport(endpoint_str_, "connection closed by the client");
  }
}

void ConnectionState::check_usable() const {
  if (broken_) {
    if (failure_) throw *failure_;
    throw Error::transport(endpoint_str_, "connection is closed");
  }
}

Error ConnectionState::transport_error(const std::string& message, protocol::ErrorCode code) const {
  std::string m = message;
  if (last_unsolicited_error_) {
    m += " (last server error: " + std::string(code_name(last_unsolicited_error_->code));
    if (!last_unsolicited_error_->field.empty()) m += " at " + last_unsolicited_error_->field;
    m += ": " + last_unsolicited_error_->message + ")";
  }
  return Error::transport(endpoint_str_, m, code);
}

void ConnectionState::mark_failed(Error e) {
  // After a timeout the stream may be mid-message: the connection is unusable either way.
  if (!broken_) {
    broken_ = true;
    failure_ = std::move(e);
  }
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
}

void ConnectionState::fail_transport(const std::string& message, protocol::ErrorCode code) {
  mark_failed(transport_error(message, code));
  throw *failure_;
}

void ConnectionState::fail_protocol(const protocol::DecodeError& d) {
  mark_failed(Error::protocol_error(endpoint_str_, d.code, d.field, d.message));
  throw *failure_;
}

Clock::time_point ConnectionState::deadline_from(std::optional<Milliseconds> timeout, bool& has_deadline) const {
  const Milliseconds t = timeout ? *timeout : io_timeout_;
  has_deadline = timeout.has_value() || io_timeout_.count() > 0;
  return Clock::now() + t;
}

void ConnectionState::connect_socket(Clock::time_point deadline, int buffer_bytes) {
  if (endpoint_.kind == Endpoint::Kind::Unix) {
    int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0) fail_transport("socket(): " + errno_text(errno));
    set_buffers(fd, buffer_bytes);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::memcpy(addr.sun_path, endpoint_.path.data(), endpoint_.path.size());
    if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
      const int err = errno;
      if (err != EINPROGRESS) {
        ::close(fd);
        std::string hint = (err == ENOENT || err == ECONNREFUSED) ? " (is dnserver running and listening there?)"
                           : err == EAGAIN ? " (the server's listen backlog is full)"
                                           : "";
        fail_transport("cannot connect: " + errno_text(err) + hint);
      }
    }
    fd_ = fd;
    return;
  }

  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* list = nullptr;
  const std::string port = std::to_string(endpoint_.port);
  if (int rc = ::getaddrinfo(endpoint_.host.c_str(), port.c_str(), &hints, &list); rc != 0)
    fail_transport("cannot resolve host '" + endpoint_.host + "': " + gai_strerror(rc));
  std::string last_error = "no address";
  for (addrinfo* ai = list; ai; ai = ai->ai_next) {
    int fd = ::socket(ai->ai_family, ai->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, ai->ai_protocol);
    if (fd < 0) {
      last_error = "socket(): " + errno_text(errno);
      continue;
    }
    set_buffers(fd, buffer_bytes);  // before connect, so the window scale is negotiated for it
    int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    int rc = ::connect(fd, ai->ai_addr, ai->ai_addrlen);
    if (rc != 0 && errno == EINPROGRESS) {
      pollfd p{fd, POLLOUT, 0};
      int prc;
      do {
        prc = ::poll(&p, 1, remaining_ms(deadline));
      } while (prc < 0 && errno == EINTR);
      if (prc == 0) {
        ::close(fd);
        ::freeaddrinfo(list);
        fail_transport("connect timed out after " + std::to_string(connect_timeout_.count()) + " ms",
                       protocol::ErrorCode::Timeout);
      }
      int err = 0;
      socklen_t len = sizeof err;
      getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len);
      rc = err ? -1 : 0;
      errno = err;
    }
    if (rc == 0) {
      fd_ = fd;
      ::freeaddrinfo(list);
      return;
    }
    last_error = errno_text(errno);
    ::close(fd);
  }
  ::freeaddrinfo(list);
  fail_transport("cannot connect: " + last_error +
                 (last_error == errno_text(ECONNREFUSED) ? " (is dnserver running and listening there?)" : ""));
}

void ConnectionState::open(const std::string& client_name, const std::string& token) {
  const auto deadline = Clock::now() + connect_timeout_;
  connect_socket(deadline, buffer_bytes_);

  protocol::Hello hello;
  hello.client_name = client_name;
  hello.auth_token = token;
  const uint64_t id = next_request_id();
  send(hello, id, 0, true);
  Incoming in = wait_reply(id, std::chrono::duration_cast<Milliseconds>(deadline - Clock::now()) + Milliseconds(1));
  if (auto* w = std::get_if<protocol::Welcome>(&in.message)) {
    welcome_ = std::move(*w);
    return;
  }
  if (auto* e = std::get_if<protocol::Error>(&in.message)) {
    Error err = Error::server(*e, endpoint_str_);
    close();
    throw err;
  }
  fail_protocol({protocol::ErrorCode::Malformed, "header.type",
                 std::string("expected WELCOME or ERROR in reply to HELLO, got ") +
                     protocol::to_string(protocol::type_of(in.message))});
}

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
  if (expect_reply) pending_[request_id] = Pending{protocol::type_of(message), std::nullopt};
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
      mark_failed(transport_error(std::string("send failed: ") + errno_text(err) +
                                      (err == EPIPE || err == ECONNRESET ? " (connection closed by server)" : ""),
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
    auto it = pending_.find(request_id);
    if (it != pending_.end() && it->second.reply) {
      if (auto* e = std::get_if<protocol::Error>(&it->second.reply->message)) {
        Error err = Error::server(*e, endpoint_str_);
        pending_.erase(it);
        throw err;
      }
    }
  }
  throw *failure_;
}

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
      mark_failed(transport_error(mid ? "connection closed by server in the middle of a message"
                                      : "connection closed by server",
                                  protocol::ErrorCode::Internal));
      return;
    }
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN || errno == EWOULDBLOCK) return;
      mark_failed(transport_error(std::string("recv failed: ") + errno_text(errno), protocol::ErrorCode::Internal));
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

void ConnectionState::send_pong_if_due() {
  if (!pong_due_ || sending_ || broken_) return;
  const std::vector<uint8_t> bytes = protocol::encode(protocol::Pong{*pong_due_}, 0, 0);
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::send(fd_, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      done += size_t(n);
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else if (done == 0) {
      return;  // socket full or failing: answer later, or let the next call report the failure
    } else {
      pollfd p{fd_, POLLOUT, 0};  // 32 bytes partly out: finish them before anything else
      ::poll(&p, 1, 1000);
    }
  }
  pong_due_.reset();
}

void ConnectionState::dispatch(Incoming&& in) {
  const uint64_t id = in.header.request_id;
  if (auto* ping = std::get_if<protocol::Ping>(&in.message); ping && id == 0) {
    pong_due_ = ping->payload;  // the server's heartbeat
    send_pong_if_due();
    return;
  }
  if (auto it = pending_.find(id); it != pending_.end() && !it->second.reply) {
    it->second.reply = std::move(in);
    return;
  }
  if (auto it = watches_.find(id); it != watches_.end()) {
    it->second.items.push_back(std::move(in));
    return;
  }
  if (auto* r = std::get_if<protocol::Result>(&in.message)) {
    for (auto& [attach_id, q] : watches_)
      if (q.session_id == r->session_id) {
        q.items.push_back(std::move(in));
        return;
      }
  }
  if (auto* sc = std::get_if<protocol::SessionClosed>(&in.message)) {
    for (auto& [attach_id, q] : watches_)
      if (q.session_id == sc->session_id) {
        q.items.push_back(std::move(in));
        return;
      }
  }
  if (auto* e = std::get_if<protocol::Error>(&in.message)) {
    // Not the answer to anything we wait for (request_id 0, or a request we
    // forgot): remember it, so a following hang-up can say why.
    last_unsolicited_error_ = *e;
  }
  // Replies to forgotten requests (closed sessions) are dropped here.
}

bool ConnectionState::pump(std::optional<Milliseconds> timeout) {
  check_usable();
  read_available();
  check_usable();
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
  auto it = pending_.find(request_id);
  if (it == pending_.end())
    throw Error::usage("internal: waiting for request " + std::to_string(request_id) + " that was never sent");
  bool has_deadline = false;
  const auto deadline = deadline_from(timeout, has_deadline);
  for (;;) {
    it = pending_.find(request_id);
    if (it->second.reply) {
      Incoming in = std::move(*it->second.reply);
      pending_.erase(it);
      return in;
    }
    check_usable();
    wait_fd(POLLIN, deadline, has_deadline,
            ("after " + std::to_string((timeout ? *timeout : io_timeout_).count()) + " ms waiting for the reply to " +
             std::string(waiting_for(request_id)))
                .c_str());
  }
}

std::optional<Incoming> ConnectionState::take_reply_if_ready(uint64_t request_id) {
  auto it = pending_.find(request_id);
  if (it == pending_.end()) return std::nullopt;
  if (!it->second.reply && !broken_) {
    read_available();
    it = pending_.find(request_id);
  }
  if (!it->second.reply) return std::nullopt;
  Incoming in = std::move(*it->second.reply);
  pending_.erase(it);
  return in;
}

bool ConnectionState::reply_ready(uint64_t request_id) const {
  auto it = pending_.find(request_id);
  return it != pending_.end() && it->second.reply.has_value();
}

std::string ConnectionState::waiting_for(uint64_t request_id) const {
  auto it = pending_.find(request_id);
  if (it == pending_.end()) return "request " + std::to_string(request_id);
  return std::string(protocol::to_string(it->second.sent)) + " (request " + std::to_string(request_id) + ")";
}

void ConnectionState::forget(uint64_t request_id) { pending_.erase(request_id); }

void ConnectionState::add_watch(uint64_t attach_request_id, uint64_t session_id) {
  watches_[attach_request_id].session_id = session_id;
}
void ConnectionState::remove_watch(uint64_t attach_request_id) { watches_.erase(attach_request_id); }
WatchQueue* ConnectionState::watch(uint64_t attach_request_id) {
  auto it = watches_.find(attach_request_id);
  return it == watches_.end() ? nullptr : &it->second;
}

}  // namespace dn::client::detail
