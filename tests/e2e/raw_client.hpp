// A deliberately simple blocking client for end-to-end tests: it can send
// arbitrary bytes (to misbehave on purpose) and read replies with timeouts.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "dn/protocol/codec.hpp"

namespace dn::test {

struct Received {
  protocol::Header header;
  std::vector<uint8_t> payload;  // keeps decoded plane views alive
  protocol::Message message;
};

class RawClient {
 public:
  explicit RawClient(const std::string& url);
  ~RawClient();
  RawClient(RawClient&& other) noexcept;
  RawClient(const RawClient&) = delete;

  void send_bytes(const std::vector<uint8_t>& bytes);
  void send(const protocol::Message& m, uint64_t request_id, uint32_t flags = 0);
  // Next message, or nullopt on timeout or when the server closed the connection.
  std::optional<Received> receive(double timeout_s = 20.0);
  // Decode what arrives as a client of protocol 1.`minor` reads it (default:
  // this version), so a field the server must not send it fails as trailing bytes.
  void read_as_minor(uint8_t minor) { read_minor_ = minor; }
  // True when the server closed the connection (EOF) within the timeout.
  bool closed_by_server(double timeout_s = 10.0);

  // HELLO → WELCOME; throws on anything else.
  protocol::Welcome hello(const std::string& token = "");
  // OPEN_SESSION → SESSION id; throws on ERROR.
  uint64_t open(const protocol::OpenSession& request, uint64_t request_id = 1);
  // OPEN_SESSION → the whole SESSION reply (with its watch key); throws on ERROR.
  protocol::Session open_session(const protocol::OpenSession& request, uint64_t request_id = 1);

  int fd() const { return fd_; }
  void close();

 private:
  int fd_ = -1;
  uint8_t read_minor_ = protocol::kVersionMinor;
  std::vector<uint8_t> buffer_;
};

// A frame with deterministic contents for each declared channel.
struct SyntheticFrame {
  protocol::Frame frame;
  std::vector<std::vector<uint8_t>> storage;
};
SyntheticFrame make_frame(uint64_t session_id, uint64_t frame_index, uint32_t width, uint32_t height,
                          const std::vector<protocol::ChannelDecl>& channels, float radiance_value);

// STATS_REQUEST -> the STATS values (messages before the STATS are skipped;
// throws when none comes), and the same by name.
std::vector<protocol::StatValue> stats_values(RawClient& c);
std::map<std::string, double> stats(RawClient& c);

// The first float of a RESULT's first plane (fp32 output).
float first_output_value(const protocol::Result& result);

// The expected passthrough output of a radiance plane value: identical RGB everywhere.
protocol::OpenSession passthrough_session(uint32_t width, uint32_t height);

}  // namespace dn::test
