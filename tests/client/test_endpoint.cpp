#include <gtest/gtest.h>

#include "dn/client/endpoint.hpp"
#include "dn/client/error.hpp"

namespace {

using dn::client::Endpoint;
using dn::client::parse_endpoint;

std::string error_of(const std::string& url) {
  try {
    parse_endpoint(url);
  } catch (const dn::client::Error& e) {
    EXPECT_EQ(e.kind(), dn::client::ErrorKind::Usage);
    return e.what();
  }
  ADD_FAILURE() << "'" << url << "' was accepted";
  return {};
}

TEST(Endpoint, Tcp) {
  Endpoint e = parse_endpoint("tcp://render-farm.local:7311");
  EXPECT_EQ(e.kind, Endpoint::Kind::Tcp);
  EXPECT_EQ(e.host, "render-farm.local");
  EXPECT_EQ(e.port, 7311);
  EXPECT_EQ(e.to_string(), "tcp://render-farm.local:7311");
  e = parse_endpoint("tcp://127.0.0.1:1");
  EXPECT_EQ(e.host, "127.0.0.1");
  EXPECT_EQ(e.port, 1);
  e = parse_endpoint("tcp://[::1]:65535");
  EXPECT_EQ(e.host, "::1");
  EXPECT_EQ(e.port, 65535);
  EXPECT_EQ(e.to_string(), "tcp://[::1]:65535");
}

TEST(Endpoint, Unix) {
  Endpoint e = parse_endpoint("unix:///run/dn/server.sock");
  EXPECT_EQ(e.kind, Endpoint::Kind::Unix);
  EXPECT_EQ(e.path, "/run/dn/server.sock");
  EXPECT_EQ(e.to_string(), "unix:///run/dn/server.sock");
  EXPECT_EQ(parse_endpoint("unix://relative.sock").path, "relative.sock");
}

TEST(Endpoint, ClearErrors) {
  EXPECT_NE(error_of("").find("empty"), std::string::npos);
  EXPECT_NE(error_of("localhost:7000").find("missing scheme"), std::string::npos);
  EXPECT_NE(error_of("http://localhost:80").find("unknown scheme 'http'"), std::string::npos);
  EXPECT_NE(error_of("tcp://localhost").find("missing ':PORT'"), std::string::npos);
  EXPECT_NE(error_of("tcp://:7000").find("missing host"), std::string::npos);
  EXPECT_NE(error_of("tcp://host:").find("missing port"), std::string::npos);
  EXPECT_NE(error_of("tcp://host:http").find("not a number"), std::string::npos);
  EXPECT_NE(error_of("tcp://host:0").find("out of range"), std::string::npos);
  EXPECT_NE(error_of("tcp://host:70000").find("out of range"), std::string::npos);
  EXPECT_NE(error_of("tcp://::1:80").find("brackets"), std::string::npos);
  EXPECT_NE(error_of("tcp://[::1]80").find("missing ':PORT'"), std::string::npos);
  EXPECT_NE(error_of("tcp://host:80/path").find("no path"), std::string::npos);
  EXPECT_NE(error_of("unix://").find("empty socket path"), std::string::npos);
  EXPECT_NE(error_of("unix:///" + std::string(200, 'x')).find("longer than"), std::string::npos);
  // Every message says what is accepted.
  EXPECT_NE(error_of("udp://h:1").find("tcp://HOST:PORT or unix:///path"), std::string::npos);
}

}  // namespace
