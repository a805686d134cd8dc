// Hostile peers and faults against a real dnserver process: what a
// header alone may cost, messages that never finish, peers that never read,
// a second server on a live Unix socket, log lines a client could forge, and
// peers that vanish without closing.
#include <gtest/gtest.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>

#include "raw_client.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

using namespace std::chrono_literals;

// Resident memory of a process, bytes (/proc/PID/status VmRSS).
uint64_t resident_bytes(int pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stoull(line.substr(6)) * 1024;
  return 0;
}

// A FRAME header declaring `payload_length` bytes, nothing after it.
std::vector<uint8_t> frame_header(uint64_t request_id, uint32_t payload_length) {
  std::vector<uint8_t> bytes;
  protocol::encode(protocol::StatsRequest{}, request_id, 0, bytes);  // a valid header to patch
  bytes[6] = static_cast<uint8_t>(protocol::MessageType::Frame);
  bytes[7] = 0;
  std::memcpy(bytes.data() + 12, &payload_length, 4);  // little-endian, as the wire
  return bytes;
}

bool wait_for_log(ServerProcess& server, const std::string& needle, double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < end) {
    if (server.log().find(needle) != std::string::npos) return true;
    std::this_thread::sleep_for(100ms);
  }
  return false;
}

// Issue 15.1: four FRAME headers, each declaring twice a 2048x1024 session's
// frame (50 MB), used to take 4 x 50 MB of zero-filled memory at once; now
// memory follows the bytes that arrive (at most one 4 MiB step each).
TEST(HostilePeer, HeadersAloneDoNotBuyMemory) {
  ServerProcess server({"--no-warm-up"});
  constexpr uint32_t w = 2048, h = 1024;
  std::vector<RawClient> clients;
  std::vector<uint64_t> sessions;
  for (int i = 0; i < 4; ++i) {
    clients.emplace_back(server.tcp_url());
    clients.back().hello();
    sessions.push_back(clients.back().open(passthrough_session(w, h)));
  }
  std::this_thread::sleep_for(500ms);
  const uint64_t before = resident_bytes(server.pid());
  const uint32_t declared = 2u * w * h * 12u;  // within each connection's limit (twice its frame + 64 KiB)
  for (auto& c : clients) c.send_bytes(frame_header(7, declared));
  std::this_thread::sleep_for(1s);
  const uint64_t after = resident_bytes(server.pid());
  ASSERT_GT(before, 0u);
  std::printf("[ info     ] resident %.1f MB before, %.1f MB after 4 headers declaring %.1f MB\n", before / 1e6,
              after / 1e6, 4.0 * declared / 1e6);
  EXPECT_LT(after, before + (48u << 20)) << "RSS " << before / 1e6 << " MB -> " << after / 1e6
                                         << " MB after 4 headers declaring " << 4.0 * declared / 1e6 << " MB";
}

// Issue 15.1: the server-wide receive budget refuses a large message with a
// clear, non-fatal ERROR while other messages hold it, and the connection
// goes on (the same frame is served once the budget is free).
TEST(HostilePeer, ReceiveBudgetRefusesALargeMessageAndTheConnectionGoesOn) {
  ServerProcess server({"--no-warm-up", "--receive-budget", "60M"});
  constexpr uint32_t w = 2048, h = 1024;  // a radiance frame: 25 MB
  RawClient holder(server.tcp_url());
  holder.hello();
  holder.open(passthrough_session(w, h));
  holder.send_bytes(frame_header(7, 2u * w * h * 12u));  // holds 50 MB of the budget, sends nothing more
  RawClient renderer(server.tcp_url());
  renderer.hello();
  const auto request = passthrough_session(w, h);
  const uint64_t sid = renderer.open(request);
  auto f = make_frame(sid, 0, w, h, request.channels, 0.5f);
  renderer.send(f.frame, 11);
  auto r = renderer.receive(60.0);
  ASSERT_TRUE(r);
  auto* e = std::get_if<protocol::Error>(&r->message);
  ASSERT_NE(e, nullptr) << "expected an ERROR while the budget is held";
  EXPECT_EQ(e->code, protocol::ErrorCode::LimitExceeded);
  EXPECT_EQ(e->field, "header.payload_length");
  EXPECT_NE(e->message.find("--receive-budget"), std::string::npos) << e->message;
  EXPECT_EQ(r->header.request_id, 11u);

  holder.close();  // its partial message gives its share back
  std::this_thread::sleep_for(300ms);
  renderer.send(f.frame, 12);
  r = renderer.receive(60.0);
  ASSERT_TRUE(r);
  auto* result = std::get_if<protocol::Result>(&r->message);
  ASSERT_NE(result, nullptr) << "the same frame must be served once the budget is free";
  EXPECT_EQ(result->frame_index, 0u);
}

// Issue 15.2: one byte every 300 ms after HELLO used to hold a connection
// forever (each byte refreshed the idle clock); now a started message must
// finish within --message-timeout plus its size at --min-receive-rate.
TEST(HostilePeer, AMessageTricklingInTimesOut) {
  ServerProcess server({"--no-warm-up", "--message-timeout", "2"});
  RawClient slow(server.tcp_url());
  slow.hello();
  const std::vector<uint8_t> header = frame_header(3, 1000);
  std::atomic<bool> stop{false};
  std::thread trickle([&] {
    for (size_t i = 0; i < header.size() && !stop; ++i) {
      if (::send(slow.fd(), &header[i], 1, MSG_NOSIGNAL) != 1) return;
      std::this_thread::sleep_for(300ms);
    }
  });
  auto r = slow.receive(20.0);
  stop = true;
  trickle.join();
  ASSERT_TRUE(r) << "no ERROR within 20 s of a message trickling in at 3 bytes per second";
  auto* e = std::get_if<protocol::Error>(&r->message);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->code, protocol::ErrorCode::Timeout);
  EXPECT_NE(e->message.find("--message-timeout"), std::string::npos) << e->message;
  EXPECT_TRUE(slow.closed_by_server(10.0));
}

// Issue 15.3: a client that sends frames and never reads used to hold its
// results (and its session's device memory) forever; now the write deadline
// closes it and the session is freed.
TEST(HostilePeer, AClientThatNeverReadsIsClosedAndItsSessionFreed) {
  ServerProcess server({"--no-warm-up", "--write-timeout", "2", "--max-output-buffer", "1M", "--max-in-flight", "2"});
  RawClient stalled(server.tcp_url());
  int small = 64 * 1024;
  ::setsockopt(stalled.fd(), SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
  stalled.hello();
  constexpr uint32_t w = 256, h = 144;
  const auto request = passthrough_session(w, h);
  const uint64_t sid = stalled.open(request);
  std::thread sender([&] {
    for (int i = 0; i < 200; ++i) {
      auto f = make_frame(sid, static_cast<uint64_t>(i), w, h, request.channels, 1.0f);
      std::vector<uint8_t> bytes;
      protocol::encode(f.frame, static_cast<uint64_t>(i), 0, bytes);
      size_t off = 0;
      while (off < bytes.size()) {
        ssize_t n = ::send(stalled.fd(), bytes.data() + off, bytes.size() - off, MSG_NOSIGNAL);
        if (n <= 0) return;  // closed by the server
        off += static_cast<size_t>(n);
      }
    }
  });
  EXPECT_TRUE(wait_for_log(server, "event=connection.write_timeout", 30.0)) << server.log();
  ::shutdown(stalled.fd(), SHUT_RDWR);  // unblock the sender if it still waits
  sender.join();
  RawClient observer(server.tcp_url());
  observer.hello();
  auto figures = stats(observer);
  EXPECT_EQ(figures.at("sessions"), 0.0);
  EXPECT_EQ(figures.at("connections"), 1.0);
}

// Issue 15.7: a second server on a live Unix socket path must refuse to
// start (it used to unlink the first one's socket), and a server removes only
// the socket file it created.
TEST(HostilePeer, ASecondServerDoesNotStealALiveUnixSocket) {
  ServerProcess first({"--no-warm-up"});
  const std::string path = first.unix_url().substr(std::strlen("unix://"));
  std::string output;
  const int status = run_dnserver({"--no-warm-up", "--listen", first.unix_url()}, output, 60.0);
  EXPECT_NE(status, 0) << output;
  EXPECT_NE(output.find("another process is listening on " + path), std::string::npos) << output;
  RawClient still(first.unix_url());
  EXPECT_NO_THROW(still.hello());
  still.close();

  // The path taken over by another server after the first bound it: the
  // first, stopping, must leave the newcomer's socket in place.
  ASSERT_EQ(::unlink(path.c_str()), 0);
  ServerProcess second({"--no-warm-up", "--listen", first.unix_url()}, /*add_listeners=*/false);
  EXPECT_EQ(first.signal_and_wait(SIGTERM), 0);
  struct stat st{};
  EXPECT_EQ(::lstat(path.c_str(), &st), 0) << "the first server removed the second one's socket";
  RawClient after(first.unix_url());
  EXPECT_NO_THROW(after.hello());
}

// Issue 15.8: a client's strings reach the log escaped: no control character
// of theirs can end a line, start a forged one or drive a terminal.
TEST(HostilePeer, ClientStringsCannotForgeLogLines) {
  ServerProcess server({"--no-warm-up"});
  RawClient c(server.tcp_url());
  const std::string name = "x\rts=1 level=error event=forged\n\x1b[2J\t\x7f";
  c.send(protocol::Hello{0, name, ""}, 1);
  auto r = c.receive();
  ASSERT_TRUE(r);
  ASSERT_TRUE(wait_for_log(server, "event=connection.hello", 10.0));
  const std::string log = server.log();
  for (char ch : log) {
    const auto u = static_cast<unsigned char>(ch);
    ASSERT_TRUE(ch == '\n' || (u >= 0x20 && u != 0x7f)) << "raw control byte " << int(u) << " in the log:\n" << log;
  }
  std::istringstream lines(log);
  std::string line;
  while (std::getline(lines, line)) EXPECT_EQ(line.rfind("ts=", 0), 0u) << "a line not written by the server: " << line;
  EXPECT_NE(log.find("client=\"x\\rts=1 level=error event=forged\\n\\x1b[2J\\t\\x7f\""), std::string::npos) << log;
}

// Issue 15.9: a TCP peer that vanishes without closing is noticed by
// keepalive probes (and TCP_USER_TIMEOUT), not only by the 300 s idle
// timeout: the server's end of an idle connection runs the keepalive timer
// (/proc/net/tcp "tr" 2).
TEST(HostilePeer, TcpConnectionsRunKeepalive) {
  ServerProcess server({"--no-warm-up", "--dead-peer", "100"});
  RawClient c(server.tcp_url());
  c.hello();
  const uint16_t server_port = static_cast<uint16_t>(std::stoi(server.tcp_url().substr(server.tcp_url().rfind(':') + 1)));
  sockaddr_in local{};
  socklen_t len = sizeof local;
  ASSERT_EQ(::getsockname(c.fd(), reinterpret_cast<sockaddr*>(&local), &len), 0);
  const uint16_t client_port = ntohs(local.sin_port);
  std::ifstream in("/proc/net/tcp");
  std::string line;
  char want_local[32], want_remote[32];
  std::snprintf(want_local, sizeof want_local, "0100007F:%04X", server_port);
  std::snprintf(want_remote, sizeof want_remote, "0100007F:%04X", client_port);
  bool found = false;
  while (std::getline(in, line)) {
    std::istringstream f(line);
    std::string sl, local_addr, remote_addr, state, queues, timer;
    f >> sl >> local_addr >> remote_addr >> state >> queues >> timer;
    if (local_addr != want_local || remote_addr != want_remote) continue;
    found = true;
    EXPECT_EQ(timer.substr(0, 2), "02") << "the server's socket runs no keepalive timer: " << line;
  }
  EXPECT_TRUE(found) << "no /proc/net/tcp entry for the server's end " << want_local << " -> " << want_remote;
}

// Issue 15.4: 50 connections from another local user (uid 65534), half of
// them through HELLO, used to take every slot of a 40-connection server, and
// the next client could not connect at all. The per-peer limit (here 8 per
// uid) refuses the flood and leaves room for everyone else.
TEST(HostilePeer, AFloodFromOneUserNeverRefusesAnother) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to run the flood as another uid (setuid 65534)";
  ServerProcess server({"--no-warm-up", "--max-connections", "40", "--max-connections-per-peer", "8"});
  const std::string url = server.tcp_url();
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<uint16_t>(std::stoi(url.substr(url.rfind(':') + 1))));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  std::vector<uint8_t> hello;
  protocol::encode(protocol::Hello{0, "flood", ""}, 1, 0, hello);
  int ready[2], done[2];
  ASSERT_EQ(::pipe(ready), 0);
  ASSERT_EQ(::pipe(done), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {  // only system calls from here on
    ::close(ready[0]);
    ::close(done[1]);  // the parent's end: its exit (even a failed test's) ends the wait below
    ::alarm(120);
    int opened = 0;
    if (::setgid(65534) == 0 && ::setuid(65534) == 0) {
      for (int i = 0; i < 50; ++i) {
        int fd = ::socket(AF_INET, SOCK_STREAM, 0);
        if (fd < 0 || ::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) continue;
        ++opened;
        if (i % 2 == 0) (void)!::write(fd, hello.data(), hello.size());
      }
    } else {
      opened = -1;
    }
    (void)!::write(ready[1], &opened, sizeof opened);
    char c;
    (void)!::read(done[0], &c, 1);  // hold every connection until the parent is done
    ::_exit(0);
  }
  ::close(ready[1]);
  ::close(done[0]);
  int opened = 0;
  ASSERT_EQ(::read(ready[0], &opened, sizeof opened), static_cast<ssize_t>(sizeof opened));
  ASSERT_EQ(opened, 50) << "the flood could not run as uid 65534";
  std::this_thread::sleep_for(1s);

  RawClient good(url);
  EXPECT_NO_THROW(good.hello()) << server.log();
  const auto request = passthrough_session(16, 8);
  const uint64_t sid = good.open(request);
  auto f = make_frame(sid, 0, 16, 8, request.channels, 0.25f);
  good.send(f.frame, 2);
  auto r = good.receive();
  ASSERT_TRUE(r);
  EXPECT_NE(std::get_if<protocol::Result>(&r->message), nullptr);
  const std::string log = server.log();
  EXPECT_NE(log.find("identity=uid:65534"), std::string::npos) << log;
  EXPECT_NE(log.find("--max-connections-per-peer"), std::string::npos) << log;

  ::close(done[1]);  // the child's read returns: it exits, closing the flood
  int status = 0;
  ::waitpid(child, &status, 0);
  ::close(ready[0]);
}

}  // namespace
}  // namespace dn::test
