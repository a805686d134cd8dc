// Authentication and listener rules of a real dnserver process.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

#include "raw_client.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

using protocol::ErrorCode;

std::string write_token_file(const std::string& token) {
  std::string path = "/tmp/dn-token-" + std::to_string(::getpid());
  std::ofstream(path) << token << "\n";
  return path;
}

TEST(Auth, NonLoopbackListenerWithoutTokenRefusesToStart) {
  std::string out;
  int rc = run_dnserver({"--listen", "tcp://0.0.0.0:0"}, out);
  EXPECT_NE(rc, 0);
  EXPECT_NE(out.find("not a loopback address"), std::string::npos) << out;
  EXPECT_NE(out.find("token"), std::string::npos) << out;
}

TEST(Auth, TokenRequiredAndComparedExactly) {
  std::string file = write_token_file("s3cret-token");
  ServerProcess server({"--token-file", file});
  {
    RawClient c(server.tcp_url());
    c.send(protocol::Hello{0, "t", ""}, 1);
    auto r = c.receive();
    ASSERT_TRUE(r);
    auto* e = std::get_if<protocol::Error>(&r->message);
    ASSERT_NE(e, nullptr);
    EXPECT_EQ(e->code, ErrorCode::Unauthenticated);
    EXPECT_EQ(e->field, "HELLO.auth_token");
    EXPECT_TRUE(c.closed_by_server());
  }
  for (const char* wrong : {"s3cret-toke", "s3cret-token!", "S3cret-token"}) {
    RawClient c(server.tcp_url());
    c.send(protocol::Hello{0, "t", wrong}, 1);
    auto r = c.receive();
    ASSERT_TRUE(r);
    auto* e = std::get_if<protocol::Error>(&r->message);
    ASSERT_NE(e, nullptr) << wrong;
    EXPECT_EQ(e->code, ErrorCode::Unauthenticated);
    EXPECT_TRUE(c.closed_by_server());
  }
  RawClient ok(server.tcp_url());
  EXPECT_NO_THROW(ok.hello("s3cret-token"));
  RawClient ok_unix(server.unix_url());
  EXPECT_NO_THROW(ok_unix.hello("s3cret-token"));
  ::unlink(file.c_str());
}

TEST(Auth, NonLoopbackListenerWithTokenStarts) {
  std::string file = write_token_file("another-token");
  ServerProcess server({"--token-file", file, "--listen", "tcp://0.0.0.0:0"});
  EXPECT_TRUE(server.running());
  EXPECT_NE(server.log().find("url=tcp://0.0.0.0:"), std::string::npos);
  ::unlink(file.c_str());
}

TEST(Auth, BadFlagsNameTheFlag) {
  std::string out;
  EXPECT_EQ(run_dnserver({"--workers", "zero"}, out), 2);
  EXPECT_NE(out.find("--workers"), std::string::npos) << out;
  out.clear();
  EXPECT_EQ(run_dnserver({"--listen", "http://x"}, out), 1);
  EXPECT_NE(out.find("tcp://HOST:PORT"), std::string::npos) << out;
  out.clear();
  EXPECT_EQ(run_dnserver({"--bogus"}, out), 2);
  EXPECT_NE(out.find("--bogus"), std::string::npos) << out;
}

TEST(Auth, HelpDocumentsEveryFlag) {
  std::string out;
  EXPECT_EQ(run_dnserver({"--help"}, out), 0);
  for (const char* flag : {"--listen", "--token-file", "--allow-uid", "--device", "--list-devices", "--validation",
                           "--workers", "--max-sessions", "--max-connections", "--max-in-flight", "--max-message",
                           "--max-session-memory", "--max-output-buffer", "--max-resolution", "--handshake-timeout",
                           "--idle-timeout", "--heartbeat", "--shutdown-grace", "--log-level", "DN_TOKEN"})
    EXPECT_NE(out.find(flag), std::string::npos) << flag;
}

}  // namespace
}  // namespace dn::test
