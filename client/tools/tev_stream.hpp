// dn watch --tev HOST:PORT: frames streamed into the tev HDR viewer over its
// TCP protocol, so the HDR values can be inspected live (exposure, pixel
// values) rather than as tone-mapped PNGs.
//
// The packet format follows tev's own encoder, IpcPacket::set* in src/Ipc.cpp
// and include/tev/Ipc.h of https://github.com/Tom94/tev at v2.13.1 (commit
// cfec189593eb4b177b32bdeae4b278bd7d9f2eca; unchanged up to 18dabdd of
// 2026-08): every packet is
//
//   uint32 total length in bytes (these 4 included) | uint8 type | payload
//
// little-endian, strings NUL-terminated, bools one byte (0 or 1):
//
//   CreateImage   (type 4): bool grabFocus, string name, int32 width, int32 height,
//                           int32 nChannels, nChannels x string channel name
//   UpdateImageV3 (type 6): bool grabFocus, string name, int32 nChannels,
//                           nChannels x string channel name, int32 x, y, width, height,
//                           nChannels x int64 offset, nChannels x int64 stride,
//                           float32 data: channel c of tile pixel p (row-major in
//                           the tile) at data[offset[c] + p * stride[c]]
//
// tev answers nothing; it overwrites an image of the same name on CreateImage.
// UpdateImageV3 is the newest UpdateImage tev has (V2 added channels, V3
// offsets and strides); here the data is interleaved RGB: offsets 0, 1, 2,
// strides 3.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace dn::cli::tev {

inline constexpr uint8_t kCreateImage = 4;
inline constexpr uint8_t kUpdateImageV3 = 6;
// tev's default address (`tev` without --host listens there).
inline constexpr const char* kDefaultAddress = "127.0.0.1:14158";
// Frames go as tiles of at most kTileSize x kTileSize pixels: one UpdateImage
// packet stays under 200 KiB (tev's receive buffer starts at 1 MiB), and tev
// shows a large frame as it arrives.
inline constexpr int kTileSize = 128;

struct Address {
  std::string host;  // without brackets
  uint16_t port = 0;
  std::string text;  // as given, for messages
};

// "HOST:PORT" ("[::1]:14158" for IPv6); UsageError naming --tev otherwise.
Address parse_address(const std::string& text);

// The packets (exposed for the tests' round trip).
std::vector<uint8_t> create_image_packet(std::string_view name, bool grab_focus, int32_t width, int32_t height,
                                         const std::vector<std::string>& channels);
// The tile (x, y, w, h) of an interleaved RGB image `image_width` pixels wide.
std::vector<uint8_t> update_image_packet(std::string_view name, bool grab_focus, const float* rgb, int image_width,
                                         int32_t x, int32_t y, int32_t w, int32_t h);

// A blocking TCP connection to tev.
class Stream {
 public:
  // Connects; throws std::runtime_error naming the address when tev is not
  // there. `io_timeout_s` bounds one send (a tev that stopped reading).
  Stream(const Address& address, double io_timeout_s);
  ~Stream();
  Stream(const Stream&) = delete;
  Stream& operator=(const Stream&) = delete;

  // Shows one frame (width x height interleaved RGB floats, rows top-first)
  // as image `name`: CreateImage (channels R, G, B; focus) on the first frame
  // or when the size changes, then the frame as UpdateImage tiles. Throws
  // std::runtime_error when tev has gone away (never raises SIGPIPE).
  void show(const std::string& name, int width, int height, const float* rgb);

  const std::string& address() const { return address_.text; }
  uint64_t frames_sent() const { return frames_; }

 private:
  void check_alive();
  void send_all(const std::vector<uint8_t>& packet);
  [[noreturn]] void gone(const std::string& why);

  Address address_;
  int fd_ = -1;
  std::string image_;  // the image created, with its size
  int width_ = 0, height_ = 0;
  uint64_t frames_ = 0;
};

}  // namespace dn::cli::tev
