#include "server/net/listener.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstring>
#include <stdexcept>

namespace dn::server::net {

std::optional<Endpoint> parse_endpoint(const std::string& url, std::string& error) {
  Endpoint e;
  e.url = url;
  if (url.rfind("unix://", 0) == 0) {
    e.kind = Endpoint::Kind::Unix;
    e.path = url.substr(7);
    if (e.path.empty() || e.path[0] != '/') {
      error = "'" + url + "': a Unix socket URL needs an absolute path (unix:///run/dn.sock)";
      return std::nullopt;
    }
    if (e.path.size() >= sizeof(sockaddr_un::sun_path)) {
      error = "'" + url + "': Unix socket path longer than " + std::to_string(sizeof(sockaddr_un::sun_path) - 1) + " bytes";
      return std::nullopt;
    }
    return e;
  }
  if (url.rfind("tcp://", 0) == 0) {
    std::string rest = url.substr(6);
    std::string port_text;
    if (!rest.empty() && rest[0] == '[') {  // [v6]:port
      auto close = rest.find(']');
      if (close == std::string::npos || close + 1 >= rest.size() || rest[close + 1] != ':') {
        error = "'" + url + "': expected tcp://[IPV6]:PORT";
        return std::nullopt;
      }
      e.host = rest.substr(1, close - 1);
      port_text = rest.substr(close + 2);
    } else {
      auto colon = rest.rfind(':');
      if (colon == std::string::npos) {
        error = "'" + url + "': expected tcp://HOST:PORT";
        return std::nullopt;
      }
      e.host = rest.substr(0, colon);
      port_text = rest.substr(colon + 1);
    }
    unsigned port = 0;
    auto [ptr, ec] = std::from_chars(port_text.data(), port_text.data() + port_text.size(), port);
    if (ec != std::errc() || ptr != port_text.data() + port_text.size() || port > 65535) {
      error = "'" + url + "': port '" + port_text + "' is not a number in 0..65535";
      return std::nullopt;
    }
    e.port = static_cast<uint16_t>(port);
    if (e.host == "localhost") e.host = "127.0.0.1";
    in_addr a4;
    in6_addr a6;
    if (inet_pton(AF_INET, e.host.c_str(), &a4) != 1 && inet_pton(AF_INET6, e.host.c_str(), &a6) != 1) {
      error = "'" + url + "': host '" + e.host + "' is not a numeric IPv4/IPv6 address or localhost";
      return std::nullopt;
    }
    return e;
  }
  error = "'" + url + "': expected tcp://HOST:PORT or unix:///PATH";
  return std::nullopt;
}

bool is_loopback(const Endpoint& e) {
  if (e.kind == Endpoint::Kind::Unix) return true;
  in_addr a4;
  if (inet_pton(AF_INET, e.host.c_str(), &a4) == 1) return (ntohl(a4.s_addr) >> 24) == 127;
  in6_addr a6;
  if (inet_pton(AF_INET6, e.host.c_str(), &a6) == 1) return IN6_IS_ADDR_LOOPBACK(&a6);
  return false;
}

namespace {
[[noreturn]] void fail(const Endpoint& e, const char* what) {
  throw std::runtime_error("listen " + e.url + ": " + what + ": " + std::strerror(errno));
}

// True when a connect to the socket path succeeds (or would: EAGAIN, a full backlog).
bool unix_socket_answers(const sockaddr_un& addr) {
  int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) return false;
  int rc = ::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr);
  bool answers = rc == 0 || errno == EAGAIN || errno == EINPROGRESS;
  ::close(fd);
  return answers;
}
}  // namespace

Listener open_listener(const Endpoint& e, bool other_users) {
  Listener l;
  l.endpoint = e;
  if (e.kind == Endpoint::Kind::Unix) {
    l.fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (l.fd < 0) fail(e, "socket");
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::memcpy(addr.sun_path, e.path.c_str(), e.path.size() + 1);
    // A stale socket file from a previous run would make bind fail; only remove
    // sockets, and only one nothing listens on: a live server keeps its path.
    struct stat st{};
    if (::lstat(e.path.c_str(), &st) == 0 && S_ISSOCK(st.st_mode)) {
      if (unix_socket_answers(addr)) {
        ::close(l.fd);
        throw std::runtime_error("listen " + e.url + ": another process is listening on " + e.path +
                                 " (a second server? stop it or choose another path)");
      }
      ::unlink(e.path.c_str());
    }
    mode_t old = ::umask(0077);  // owner-only socket file: peer credentials are checked too
    int rc = ::bind(l.fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
    ::umask(old);
    if (rc == 0) {
      ::chmod(e.path.c_str(), other_users ? 0666 : 0600);
      if (::lstat(e.path.c_str(), &st) == 0) {
        l.socket_dev = st.st_dev;
        l.socket_ino = st.st_ino;
      }
    }
    if (rc != 0) {
      int saved = errno;
      ::close(l.fd);
      errno = saved;
      fail(e, "bind");
    }
  } else {
    in6_addr a6;
    bool v6 = inet_pton(AF_INET6, e.host.c_str(), &a6) == 1;
    l.fd = ::socket(v6 ? AF_INET6 : AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (l.fd < 0) fail(e, "socket");
    int one = 1;
    ::setsockopt(l.fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    int rc;
    if (v6) {
      sockaddr_in6 addr{};
      addr.sin6_family = AF_INET6;
      addr.sin6_port = htons(e.port);
      addr.sin6_addr = a6;
      rc = ::bind(l.fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
    } else {
      sockaddr_in addr{};
      addr.sin_family = AF_INET;
      addr.sin_port = htons(e.port);
      inet_pton(AF_INET, e.host.c_str(), &addr.sin_addr);
      rc = ::bind(l.fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
    }
    if (rc != 0) {
      int saved = errno;
      ::close(l.fd);
      errno = saved;
      fail(e, "bind");
    }
    sockaddr_storage bound{};
    socklen_t len = sizeof bound;
    ::getsockname(l.fd, reinterpret_cast<sockaddr*>(&bound), &len);
    l.bound_port = ntohs(bound.ss_family == AF_INET6 ? reinterpret_cast<sockaddr_in6*>(&bound)->sin6_port
                                                     : reinterpret_cast<sockaddr_in*>(&bound)->sin_port);
  }
  if (::listen(l.fd, 128) != 0) {
    int saved = errno;
    ::close(l.fd);
    errno = saved;
    fail(e, "listen");
  }
  return l;
}

void close_listener(Listener& l) {
  if (l.fd >= 0) {
    ::close(l.fd);
    // Only the file this listener created: another server may have taken the path since.
    struct stat st{};
    if (l.endpoint.kind == Endpoint::Kind::Unix && ::lstat(l.endpoint.path.c_str(), &st) == 0 &&
        st.st_dev == l.socket_dev && st.st_ino == l.socket_ino)
      ::unlink(l.endpoint.path.c_str());
  }
  l.fd = -1;
}

}  // namespace dn::server::net
