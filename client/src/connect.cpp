// Connecting: the socket (Unix or TCP, non-blocking, within
// connect_timeout) and the HELLO -> WELCOME handshake.
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "connection_state.hpp"
#include "io_wait.hpp"

namespace dn::client::detail {

namespace {

void set_buffers(int fd, int bytes) {
  if (bytes <= 0) return;
  // Best effort: the kernel clamps to net.core.[rw]mem_max.
  setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &bytes, sizeof bytes);
  setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &bytes, sizeof bytes);
}

}  // namespace

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
    negotiated_minor_ = std::min(in.header.version_minor, protocol::kVersionMinor);
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

}  // namespace dn::client::detail
