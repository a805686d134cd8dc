// Authentication and listener rules of a real dnserver process.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
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

// Connects to the Unix socket as `uid` in a child process; returns the ERROR
// code received (0 for WELCOME, negative when something else happened) and
// fills `detail` with what the child saw, for the failure message.
int hello_as_uid(const std::string& url, uid_t uid, std::string& detail) {
  int pipe_fds[2];
  if (::pipe(pipe_fds) != 0) return -2;
  pid_t pid = ::fork();
  if (pid == 0) {
    ::close(pipe_fds[0]);
    int result = -1;
    std::string what = "setgid/setuid failed";
    if (::setgid(uid) == 0 && ::setuid(uid) == 0) {
      what = "no reply within 30 s";
      try {
        RawClient c(url);
        // A refused peer is answered at accept time and the server stops reading: our HELLO
        // may then fail with EPIPE, but the ERROR is already waiting to be read.
        try {
          c.send(protocol::Hello{0, "uid-test", ""}, 1);
        } catch (const std::exception&) {
        }
        auto r = c.receive(30.0);
        if (r && std::get_if<protocol::Welcome>(&r->message)) result = 0, what = "WELCOME";
        if (r && std::get_if<protocol::Error>(&r->message)) {
          result = static_cast<int>(std::get<protocol::Error>(r->message).code);
          what = "ERROR " + std::get<protocol::Error>(r->message).message;
        }
      } catch (const std::exception& e) {
        result = -4;
        what = e.what();
      }
    }
    what.resize(std::min<size_t>(what.size(), 200));
    [[maybe_unused]] auto w1 = ::write(pipe_fds[1], &result, sizeof result);
    [[maybe_unused]] auto w2 = ::write(pipe_fds[1], what.data(), what.size());
    ::_exit(0);
  }
  ::close(pipe_fds[1]);
  int result = -3;
  [[maybe_unused]] auto r = ::read(pipe_fds[0], &result, sizeof result);
  char buf[256];
  ssize_t n = ::read(pipe_fds[0], buf, sizeof buf);
  detail.assign(buf, n > 0 ? static_cast<size_t>(n) : 0);
  ::close(pipe_fds[0]);
  ::waitpid(pid, nullptr, 0);
  return result;
}

TEST(Auth, UnixPeerCredentialsChecked) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to connect as other uids";
  ServerProcess server({"--allow-uid", "12345"});
  std::string detail;
  EXPECT_EQ(hello_as_uid(server.unix_url(), 12345, detail), 0)
      << "an allowed uid was refused: " << detail << "\n" << server.log();
  EXPECT_EQ(hello_as_uid(server.unix_url(), 23456, detail), static_cast<int>(ErrorCode::Unauthenticated))
      << "a uid not allowed got in: " << detail << "\n" << server.log();
  // The TCP listener does not use peer credentials.
  RawClient tcp(server.tcp_url());
  EXPECT_NO_THROW(tcp.hello());
}

TEST(Auth, UnixSocketIsOwnerOnlyByDefault) {
  ServerProcess server;
  struct stat st{};
  ASSERT_EQ(::stat(server.unix_url().substr(7).c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
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
