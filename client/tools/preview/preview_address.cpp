#include "preview_address.hpp"

#include <arpa/inet.h>

#include <cstring>

#include "args.hpp"

namespace dn::cli {

std::string PreviewAddress::civetweb_ports() const {
  return (ipv6 ? "[" + host + "]" : host) + ":" + std::to_string(port);
}

PreviewAddress parse_preview_address(const std::string& text) {
  PreviewAddress a;
  a.text = text;
  const auto bad = [&](const std::string& why) {
    return UsageError("--http: expected HOST:PORT with a numeric address (127.0.0.1:7879, [::1]:7879), got '" + text +
                      "': " + why);
  };
  const size_t colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0) throw bad("no port");
  std::string host = text.substr(0, colon);
  const long long port = parse_int(text.substr(colon + 1), "--http port");
  if (port < 0 || port > 65535) throw bad("port out of range 0..65535");
  a.port = int(port);
  if (host == "localhost") host = "127.0.0.1";
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') {
    a.ipv6 = true;
    host = host.substr(1, host.size() - 2);
  }
  if (a.ipv6) {
    in6_addr addr{};
    if (inet_pton(AF_INET6, host.c_str(), &addr) != 1) throw bad("'" + host + "' is not an IPv6 address");
    a.loopback = IN6_IS_ADDR_LOOPBACK(&addr);
  } else {
    in_addr addr{};
    if (inet_pton(AF_INET, host.c_str(), &addr) != 1) throw bad("'" + host + "' is not an IPv4 address");
    a.loopback = (ntohl(addr.s_addr) >> 24) == 127;
  }
  a.host = host;
  a.url_host = a.ipv6 ? "[" + host + "]" : host;
  return a;
}

}  // namespace dn::cli
