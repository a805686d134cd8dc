// Compiles against the installed headers, links dn::client (and through it
// dn::protocol) and dn::imageio (and through it OpenEXR and zlib), and
// exercises a few calls that need no server.
#include <dn/client/client.hpp>
#include <dn/image/exr_io.hpp>
#include <dn/image/metrics.hpp>
#include <dn/image/png.hpp>
#include <dn/protocol/codec.hpp>

#include <cstdio>
#include <filesystem>
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

  // dn::imageio: an EXR round trip (OpenEXR), a PNG (zlib), a metric.
  const std::string exr = "dnclient_consumer.exr";  // in the working directory the test gives
  image::write_exr_rgb(exr, 4, 4, radiance.data(), image::ExrPixelType::Float);
  int w = 0, h = 0;
  const std::vector<float> back = image::read_exr_rgb(exr, w, h);
  std::filesystem::remove(exr);
  if (w != 4 || h != 4 || image::rmse(back.data(), radiance.data(), back.size()) != 0.0) return 1;
  const std::vector<uint8_t> srgb = image::to_srgb8(radiance.data(), 16);
  const std::vector<uint8_t> png = image::encode_png_rgb8(4, 4, srgb.data());
  if (png.size() < 8 || png[1] != 'P') return 1;
  std::printf("dnclient consumer ok (%zu-byte PING, %zu plane, %zu-byte PNG)\n", bytes.size(), in.planes.size(),
              png.size());
  return 0;
}
