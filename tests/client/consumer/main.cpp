// Compiles against the installed headers, links dn::client (and through it
// dn::protocol) and exercises a few calls that need no server.
#include <dn/client/client.hpp>
#include <dn/protocol/codec.hpp>

#include <cstdio>
#include <vector>

int main() {
  using namespace dn;
  const client::Endpoint ep = client::parse_endpoint("tcp://localhost:7000");
  if (ep.port != 7000) return 1;
  try {
    client::parse_endpoint("http://localhost");
    return 1;
  } catch (const client::Error& e) {
    if (e.kind() != client::ErrorKind::Usage) return 1;
  }
  client::ConnectOptions opts;
  opts.connect_timeout = std::chrono::milliseconds(500);
  try {
    client::Connection::connect("unix:///nonexistent/dnclient-consumer.sock", opts);
    return 1;
  } catch (const client::Error& e) {
    if (e.kind() != client::ErrorKind::Transport) return 1;
  }
  // The protocol library is linked too.
  const std::vector<uint8_t> bytes = protocol::encode(protocol::Ping{42}, 7);
  if (bytes.size() < protocol::kHeaderSize) return 1;
  std::vector<float> radiance(4 * 4 * 3, 1.0f);
  client::FrameInput in;
  in.add(protocol::ChannelId::Radiance, radiance);
  std::printf("dnclient consumer ok (%zu-byte PING, %zu plane)\n", bytes.size(), in.planes.size());
  return 0;
}
