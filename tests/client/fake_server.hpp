// A scripted stand-in for dnserver: listens on a Unix-domain socket (or TCP
// loopback), accepts one connection on a thread and runs a handler that talks
// the protocol through dn_protocol. Blocking I/O; gtest assertions in the
// handler are fine (gtest is thread-safe on POSIX).
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "dn/protocol/codec.hpp"

namespace dn::test {

struct Received {
  protocol::Header header{};
  std::shared_ptr<std::vector<uint8_t>> payload;
  protocol::Message message;
};

class Peer {
 public:
  explicit Peer(int fd) : fd_(fd) {}
  int fd() const { return fd_; }
  // Next message; nullopt on EOF or when nothing arrives within timeout_ms.
  std::optional<Received> recv(int timeout_ms = 5000);
  void send(const protocol::Message& m, uint64_t request_id, uint32_t flags = 0);
  void send_raw(const std::vector<uint8_t>& bytes);
  // Reads and discards exactly n bytes (for "close in the middle of a message").
  bool read_raw(size_t n, int timeout_ms = 5000);
  // Waits for HELLO, checks the token when `token` is set, answers WELCOME
  // (test_welcome: a protocol 1.0 server, no parameter tables). Returns the HELLO.
  protocol::Hello handshake(const std::optional<std::string>& token = std::nullopt, uint32_t max_in_flight = 4,
                            uint64_t max_message_bytes = 64ull << 20);
  // Waits for HELLO and answers `welcome`. Returns the HELLO.
  protocol::Hello handshake_with(const protocol::Welcome& welcome);
  // A WELCOME with parameter tables is sent as a 1.1 server sends it; one
  // without, as a 1.0 server (header minor 0), since a 1.1 client requires
  // the tables under a 1.1 header.
  void send_welcome(const protocol::Welcome& welcome, uint64_t request_id);
  void close();
  bool eof() const { return eof_; }

 private:
  int fd_;
  bool eof_ = false;
  // The minor version the WELCOME announced: later messages are decoded as
  // that version reads them, so a field the client must not send to it
  // (docs/protocol.md §10) fails the test as trailing bytes.
  uint8_t announced_minor_ = protocol::kVersionMinor;
  protocol::MessageReader reader_{uint64_t{1} << 32};
};

protocol::Welcome test_welcome(uint32_t max_in_flight = 4, uint64_t max_message_bytes = 64ull << 20);
// test_welcome() from a 1.1 server: svgf takes alpha_colour (0.05 in [0, 1])
// and atrous_iterations (integer, 4 in [0, 8]); passthrough takes nothing.
protocol::Welcome test_welcome_with_parameters();
// A 1.8 server's reply to ATTACH: a read-only passthrough session of w x h.
protocol::Session attach_reply(uint64_t session_id, uint32_t width, uint32_t height);

class FakeServer {
 public:
  using Handler = std::function<void(Peer&)>;
  explicit FakeServer(Handler handler, bool tcp = false);
  ~FakeServer();  // waits for the handler to finish
  const std::string& url() const { return url_; }
  void join();

 private:
  int listen_fd_ = -1;
  std::string url_, path_;
  std::thread thread_;
};

}  // namespace dn::test
