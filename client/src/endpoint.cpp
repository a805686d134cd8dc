#include "dn/client/endpoint.hpp"

#include <sys/un.h>

#include <charconv>

#include "dn/client/error.hpp"

namespace dn::client {

namespace {

[[noreturn]] void bad(std::string_view url, const std::string& why) {
  throw Error::usage("invalid server address '" + std::string(url) + "': " + why +
                     " (expected tcp://HOST:PORT or unix:///path/to/socket)");
}

}  // namespace

std::string Endpoint::to_string() const {
  if (kind == Kind::Unix) return "unix://" + path;
  const bool v6 = host.find(':') != std::string::npos;
  return "tcp://" + (v6 ? "[" + host + "]" : host) + ":" + std::to_string(port);
}

Endpoint parse_endpoint(std::string_view url) {
  Endpoint ep;
  const size_t sep = url.find("://");
  if (url.empty()) bad(url, "empty");
  if (sep == std::string_view::npos) bad(url, "missing scheme");
  const std::string_view scheme = url.substr(0, sep);
  const std::string_view rest = url.substr(sep + 3);
  if (scheme == "unix") {
    ep.kind = Endpoint::Kind::Unix;
    if (rest.empty()) bad(url, "empty socket path");
    if (rest.find('\0') != std::string_view::npos) bad(url, "NUL in socket path");
    if (rest.size() >= sizeof(sockaddr_un{}.sun_path))
      bad(url, "socket path longer than " + std::to_string(sizeof(sockaddr_un{}.sun_path) - 1) + " bytes");
    ep.path = std::string(rest);
    return ep;
  }
  if (scheme != "tcp") bad(url, "unknown scheme '" + std::string(scheme) + "'");
  ep.kind = Endpoint::Kind::Tcp;
  if (rest.empty()) bad(url, "missing host and port");
  if (rest.find('/') != std::string_view::npos) bad(url, "a tcp address has no path");
  std::string_view host, port;
  if (rest.front() == '[') {
    const size_t close = rest.find(']');
    if (close == std::string_view::npos) bad(url, "unterminated '[' in IPv6 address");
    host = rest.substr(1, close - 1);
    const std::string_view after = rest.substr(close + 1);
    if (after.empty() || after.front() != ':') bad(url, "missing ':PORT' after IPv6 address");
    port = after.substr(1);
  } else {
    const size_t colon = rest.rfind(':');
    if (colon == std::string_view::npos) bad(url, "missing ':PORT'");
    host = rest.substr(0, colon);
    port = rest.substr(colon + 1);
    if (host.find(':') != std::string_view::npos) bad(url, "IPv6 addresses must be in brackets, e.g. tcp://[::1]:7000");
  }
  if (host.empty()) bad(url, "missing host");
  if (port.empty()) bad(url, "missing port");
  unsigned value = 0;
  auto [ptr, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
  if (ec != std::errc() || ptr != port.data() + port.size()) bad(url, "port '" + std::string(port) + "' is not a number");
  if (value == 0 || value > 65535) bad(url, "port " + std::string(port) + " out of range 1..65535");
  ep.host = std::string(host);
  ep.port = uint16_t(value);
  return ep;
}

}  // namespace dn::client
