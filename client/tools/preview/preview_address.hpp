// dn preview's --http HOST:PORT: parsed, checked, and whether it is loopback
// (anything else needs a token).
#pragma once

#include <string>

namespace dn::cli {

inline constexpr const char* kDefaultPreviewAddress = "127.0.0.1:7879";

struct PreviewAddress {
  std::string text;      // as given
  std::string host;      // an IPv4 address, or an IPv6 one without brackets
  int port = 0;          // 0: a free one
  bool ipv6 = false;
  bool loopback = false;  // 127.0.0.0/8 or ::1 ("localhost" is read as 127.0.0.1)
  std::string url_host;   // host as written in a URL ([::1] for IPv6)
  std::string civetweb_ports() const;  // civetweb's "listening_ports" value
};

// UsageError naming --http for anything but HOST:PORT with a numeric address.
PreviewAddress parse_preview_address(const std::string& text);

}  // namespace dn::cli
