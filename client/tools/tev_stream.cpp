// tev's TCP protocol, the sending side (format: tev_stream.hpp).
#include "tev_stream.hpp"

#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "args.hpp"

namespace dn::cli::tev {

namespace {

// Little-endian writer of one packet; the length is patched in by finish().
class Packet {
 public:
  explicit Packet(uint8_t type) {
    bytes_.resize(4);
    bytes_.push_back(type);
  }
  void u8(uint8_t v) { bytes_.push_back(v); }
  void boolean(bool v) { u8(v ? 1 : 0); }
  void i32(int32_t v) { le(uint32_t(v), 4); }
  void i64(int64_t v) { le(uint64_t(v), 8); }
  void f32(float v) {
    uint32_t bits;
    std::memcpy(&bits, &v, 4);
    le(bits, 4);
  }
  // n floats; a straight copy on a little-endian host.
  void f32s(const float* v, size_t n) {
    if constexpr (std::endian::native == std::endian::little) {
      const size_t at = bytes_.size();
      bytes_.resize(at + 4 * n);
      std::memcpy(bytes_.data() + at, v, 4 * n);
    } else {
      for (size_t i = 0; i < n; ++i) f32(v[i]);
    }
  }
  void str(std::string_view s) {
    if (s.find('\0') != std::string_view::npos) throw std::invalid_argument("tev: a name with a NUL byte");
    bytes_.insert(bytes_.end(), s.begin(), s.end());
    bytes_.push_back(0);
  }
  void reserve(size_t n) { bytes_.reserve(bytes_.size() + n); }
  std::vector<uint8_t> finish() {
    const uint64_t size = bytes_.size();
    if (size > UINT32_MAX) throw std::length_error("tev: packet over 4 GiB");
    for (int i = 0; i < 4; ++i) bytes_[i] = uint8_t(size >> (8 * i));
    return std::move(bytes_);
  }

 private:
  void le(uint64_t v, int n) {
    for (int i = 0; i < n; ++i) bytes_.push_back(uint8_t(v >> (8 * i)));
  }
  std::vector<uint8_t> bytes_;
};

const std::vector<std::string> kRgb = {"R", "G", "B"};

[[noreturn]] void bad_address(const std::string& text, const std::string& why) {
  throw UsageError("--tev: expected HOST:PORT (tev's default is " + std::string(kDefaultAddress) + "), got '" + text +
                   "': " + why);
}

}  // namespace

Address parse_address(const std::string& text) {
  Address a;
  a.text = text;
  std::string port;
  if (!text.empty() && text.front() == '[') {
    const size_t close = text.find(']');
    if (close == std::string::npos) bad_address(text, "unterminated '['");
    if (close + 1 >= text.size() || text[close + 1] != ':') bad_address(text, "missing ':PORT'");
    a.host = text.substr(1, close - 1);
    port = text.substr(close + 2);
  } else {
    const size_t colon = text.rfind(':');
    if (colon == std::string::npos) bad_address(text, "missing ':PORT'");
    a.host = text.substr(0, colon);
    port = text.substr(colon + 1);
    if (a.host.find(':') != std::string::npos) bad_address(text, "an IPv6 address goes in brackets, [::1]:14158");
  }
  if (a.host.empty()) bad_address(text, "missing host");
  unsigned value = 0;
  auto [ptr, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
  if (port.empty() || ec != std::errc() || ptr != port.data() + port.size() || value == 0 || value > 65535)
    bad_address(text, "the port must be a number 1..65535");
  a.port = uint16_t(value);
  return a;
}

std::vector<uint8_t> create_image_packet(std::string_view name, bool grab_focus, int32_t width, int32_t height,
                                         const std::vector<std::string>& channels) {
  Packet p(kCreateImage);
  p.boolean(grab_focus);
  p.str(name);
  p.i32(width);
  p.i32(height);
  p.i32(int32_t(channels.size()));
  for (const auto& c : channels) p.str(c);
  return p.finish();
}

std::vector<uint8_t> update_image_packet(std::string_view name, bool grab_focus, const float* rgb, int image_width,
                                         int32_t x, int32_t y, int32_t w, int32_t h) {
  Packet p(kUpdateImageV3);
  p.boolean(grab_focus);
  p.str(name);
  p.i32(3);
  for (const auto& c : kRgb) p.str(c);
  p.i32(x);
  p.i32(y);
  p.i32(w);
  p.i32(h);
  for (int64_t c = 0; c < 3; ++c) p.i64(c);  // offsets: interleaved
  for (int c = 0; c < 3; ++c) p.i64(3);      // strides
  p.reserve(size_t(w) * h * 12);
  for (int32_t row = 0; row < h; ++row) {
    const float* src = rgb + 3 * (size_t(y + row) * image_width + x);
    p.f32s(src, size_t(3) * w);
  }
  return p.finish();
}

Stream::Stream(const Address& address, double io_timeout_s) : address_(address) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* list = nullptr;
  const std::string port = std::to_string(address.port);
  if (int rc = ::getaddrinfo(address.host.c_str(), port.c_str(), &hints, &list); rc != 0)
    throw std::runtime_error("cannot reach tev at " + address.text + ": " + ::gai_strerror(rc));
  // SO_SNDTIMEO bounds connect() as well as each send (a host that does not
  // answer, a tev that stopped reading).
  timeval tv{};
  const double t = std::max(0.001, io_timeout_s);
  tv.tv_sec = time_t(t);
  tv.tv_usec = suseconds_t((t - std::floor(t)) * 1e6);
  std::string why = "no address";
  for (addrinfo* ai = list; ai; ai = ai->ai_next) {
    const int fd = ::socket(ai->ai_family, ai->ai_socktype | SOCK_CLOEXEC, ai->ai_protocol);
    if (fd < 0) {
      why = std::strerror(errno);
      continue;
    }
    ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    if (::connect(fd, ai->ai_addr, ai->ai_addrlen) == 0) {
      fd_ = fd;
      break;
    }
    if (errno == EINPROGRESS || errno == EAGAIN) {
      char text[64];
      std::snprintf(text, sizeof text, "no answer within %g s (--timeout)", t);
      why = text;
    } else {
      why = std::strerror(errno);
    }
    ::close(fd);
  }
  ::freeaddrinfo(list);
  if (fd_ < 0)
    throw std::runtime_error("cannot connect to tev at " + address.text + ": " + why +
                             " (is tev running and listening there? `tev --host " + address.text +
                             "` listens on that address; tev's default is " + kDefaultAddress + ")");
  const int one = 1;
  ::setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
}

Stream::~Stream() {
  if (fd_ >= 0) ::close(fd_);
}

void Stream::gone(const std::string& why) {
  throw std::runtime_error("tev at " + address_.text + " went away after " + std::to_string(frames_) + " frame" +
                           (frames_ == 1 ? "" : "s") + " (" + why + "); stopping the watch");
}

// tev never writes to its clients: a readable socket means it closed the
// connection (or reset it). Found before a frame, so a tev that went away
// between frames is reported at once rather than after a send into the void.
void Stream::check_alive() {
  pollfd p{fd_, POLLIN | POLLRDHUP, 0};
  if (::poll(&p, 1, 0) <= 0) return;
  if (p.revents & (POLLERR | POLLHUP | POLLRDHUP)) gone("it closed the connection");
  if (p.revents & POLLIN) {
    char buf[256];
    const ssize_t n = ::recv(fd_, buf, sizeof buf, MSG_DONTWAIT);
    if (n == 0) gone("it closed the connection");
    if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK) gone(std::string("recv: ") + std::strerror(errno));
  }
}

void Stream::send_all(const std::vector<uint8_t>& packet) {
  size_t done = 0;
  while (done < packet.size()) {
    const ssize_t n = ::send(fd_, packet.data() + done, packet.size() - done, MSG_NOSIGNAL);
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN || errno == EWOULDBLOCK) gone("it stopped reading: a send timed out");
      if (errno == EPIPE || errno == ECONNRESET) gone("it closed the connection");
      gone(std::string("send: ") + std::strerror(errno));
    }
    done += size_t(n);
  }
}

void Stream::show(const std::string& name, int width, int height, const float* rgb) {
  check_alive();
  if (name != image_ || width != width_ || height != height_) {
    send_all(create_image_packet(name, true, width, height, kRgb));
    image_ = name;
    width_ = width;
    height_ = height;
  }
  for (int y = 0; y < height; y += kTileSize)
    for (int x = 0; x < width; x += kTileSize)
      send_all(update_image_packet(name, false, rgb, width, x, y, std::min(kTileSize, width - x),
                                   std::min(kTileSize, height - y)));
  ++frames_;
}

}  // namespace dn::cli::tev
