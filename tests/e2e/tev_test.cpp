// dn watch --tev against a fake tev: a loopback listener that decodes what it
// receives with a decoder of its own, written from tev's documented packet
// format (README "Over the Network" and IpcPacket::interpretAs* in src/Ipc.cpp
// of github.com/Tom94/tev v2.13.1), not from dn's encoder:
//
//   [uint32 LE total length, these 4 bytes included][uint8 type][payload]
//   CreateImage = 4:   bool grabFocus, cstring name, int32 width, height, nChannels, nChannels cstrings
//   UpdateImageV3 = 6: bool grabFocus, cstring name, int32 nChannels, nChannels cstrings,
//                      int32 x, y, width, height, nChannels int64 offsets, nChannels int64 strides,
//                      float32 data[offset[c] + pixel * stride[c]]
//
// A real dnserver and a real session: the frames tev is shown must equal, bit
// for bit, the ones a plain `dn watch --output *.pfm` of the same session wrote.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <thread>

#include "child_process.hpp"
#include "dn/image/pfm.hpp"
#include "raw_client.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct TevImage {
  std::string name;
  int32_t width = 0, height = 0;
  std::vector<std::string> channels;
};

// What the fake tev saw, packet by packet and as whole frames.
struct TevLog {
  std::vector<TevImage> creates;
  std::vector<bool> create_focus;
  size_t updates = 0;
  size_t largest_packet = 0;
  std::vector<std::string> errors;             // decoding failures: each fails the test
  std::vector<std::vector<float>> frames;      // completed frames, interleaved in channel order
  std::vector<std::string> frame_names;
  bool connection_closed = false;
};

// Reads a packet's fields in order; each read checks the bounds.
class Reader {
 public:
  explicit Reader(const std::vector<uint8_t>& p) : p_(p) {}
  uint32_t u32() { return uint32_t(take(4)); }
  int32_t i32() { return int32_t(uint32_t(take(4))); }
  int64_t i64() { return int64_t(take(8)); }
  uint8_t u8() { return uint8_t(take(1)); }
  std::string cstring() {
    const auto end = std::find(p_.begin() + long(at_), p_.end(), uint8_t(0));
    if (end == p_.end()) throw std::runtime_error("unterminated string");
    std::string s(p_.begin() + long(at_), end);
    at_ = size_t(end - p_.begin()) + 1;
    return s;
  }
  float f32_at(size_t float_index) const {  // from the current position
    const size_t b = at_ + 4 * float_index;
    if (b + 4 > p_.size()) throw std::runtime_error("float data past the packet's end");
    const uint32_t bits = uint32_t(p_[b]) | uint32_t(p_[b + 1]) << 8 | uint32_t(p_[b + 2]) << 16 | uint32_t(p_[b + 3]) << 24;
    float f;
    std::memcpy(&f, &bits, 4);
    return f;
  }
  size_t remaining() const { return p_.size() - at_; }

 private:
  uint64_t take(int n) {
    if (at_ + size_t(n) > p_.size()) throw std::runtime_error("field past the packet's end");
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v |= uint64_t(p_[at_ + size_t(i)]) << (8 * i);
    at_ += size_t(n);
    return v;
  }
  const std::vector<uint8_t>& p_;
  size_t at_ = 0;
};

class FakeTev {
 public:
  // close_after_frames > 0: hang up once that many whole frames arrived (tev quit).
  explicit FakeTev(size_t close_after_frames = 0) : close_after_(close_after_frames) {
    listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(listen_fd_, 4) != 0)
      throw std::runtime_error("fake tev: bind/listen failed");
    socklen_t len = sizeof a;
    ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
    thread_ = std::thread([this] { serve(); });
  }
  ~FakeTev() {
    ::shutdown(listen_fd_, SHUT_RDWR);
    ::close(listen_fd_);
    thread_.join();
  }
  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  bool wait_frames(size_t n, double timeout_s) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                             [&] { return log_.frames.size() >= n || log_.connection_closed; }) &&
           log_.frames.size() >= n;
  }
  TevLog log() {
    std::lock_guard lock(mutex_);
    return log_;
  }

 private:
  void serve() {
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
    if (fd < 0) return;
    std::vector<uint8_t> buffer;
    uint8_t chunk[65536];
    for (bool open = true; open;) {
      const ssize_t n = ::recv(fd, chunk, sizeof chunk, 0);
      if (n <= 0) break;
      buffer.insert(buffer.end(), chunk, chunk + n);
      // Whole packets: the length field counts itself.
      while (buffer.size() >= 4) {
        const uint32_t length = uint32_t(buffer[0]) | uint32_t(buffer[1]) << 8 | uint32_t(buffer[2]) << 16 |
                                uint32_t(buffer[3]) << 24;
        if (length < 5) {
          note_error("packet length " + std::to_string(length) + " < 5");
          open = false;
          break;
        }
        if (buffer.size() < length) break;
        std::vector<uint8_t> packet(buffer.begin(), buffer.begin() + length);
        buffer.erase(buffer.begin(), buffer.begin() + length);
        handle(packet);
        std::lock_guard lock(mutex_);
        if (close_after_ > 0 && log_.frames.size() >= close_after_) open = false;
      }
    }
    ::close(fd);
    std::lock_guard lock(mutex_);
    log_.connection_closed = true;
    changed_.notify_all();
  }

  void note_error(const std::string& e) {
    std::lock_guard lock(mutex_);
    log_.errors.push_back(e);
    changed_.notify_all();
  }

  void handle(const std::vector<uint8_t>& packet) {
    try {
      Reader r(packet);
      if (r.u32() != packet.size()) throw std::runtime_error("length field");
      const uint8_t type = r.u8();
      std::lock_guard lock(mutex_);
      log_.largest_packet = std::max(log_.largest_packet, packet.size());
      if (type == 4) {  // CreateImage
        const bool focus = r.u8() == 1;
        TevImage im;
        im.name = r.cstring();
        im.width = r.i32();
        im.height = r.i32();
        const int32_t n = r.i32();
        for (int32_t c = 0; c < n; ++c) im.channels.push_back(r.cstring());
        if (r.remaining() != 0) throw std::runtime_error("CreateImage: trailing bytes");
        log_.creates.push_back(im);
        log_.create_focus.push_back(focus);
        image_ = im;
        pixels_.assign(size_t(im.width) * im.height * im.channels.size(), 0.0f);
        covered_ = 0;
        return;
      }
      if (type != 6) throw std::runtime_error("unexpected packet type " + std::to_string(type));
      r.u8();  // grabFocus
      const std::string name = r.cstring();
      const int32_t n = r.i32();
      std::vector<std::string> channels;
      for (int32_t c = 0; c < n; ++c) channels.push_back(r.cstring());
      const int32_t x = r.i32(), y = r.i32(), w = r.i32(), h = r.i32();
      std::vector<int64_t> offsets(static_cast<size_t>(n)), strides(static_cast<size_t>(n));
      for (auto& o : offsets) o = r.i64();
      for (auto& s : strides) s = r.i64();
      if (name != image_.name) throw std::runtime_error("UpdateImage of '" + name + "', not the created image");
      if (channels != image_.channels) throw std::runtime_error("UpdateImage channels differ from CreateImage's");
      if (x < 0 || y < 0 || w <= 0 || h <= 0 || x + w > image_.width || y + h > image_.height)
        throw std::runtime_error("tile outside the image");
      size_t floats = 0;
      for (int32_t c = 0; c < n; ++c)
        floats = std::max(floats, size_t(offsets[size_t(c)] + (int64_t(w) * h - 1) * strides[size_t(c)] + 1));
      if (r.remaining() != 4 * floats) throw std::runtime_error("UpdateImage: data size does not match the tile");
      for (int32_t py = 0; py < h; ++py)
        for (int32_t px = 0; px < w; ++px) {
          const size_t tile_pixel = size_t(py) * w + px;
          const size_t image_pixel = size_t(y + py) * image_.width + (x + px);
          for (int32_t c = 0; c < n; ++c)
            pixels_[image_pixel * size_t(n) + size_t(c)] =
                r.f32_at(size_t(offsets[size_t(c)]) + tile_pixel * size_t(strides[size_t(c)]));
        }
      ++log_.updates;
      covered_ += size_t(w) * h;
      if (covered_ > size_t(image_.width) * image_.height) throw std::runtime_error("tiles overlap within a frame");
      if (covered_ == size_t(image_.width) * image_.height) {
        log_.frames.push_back(pixels_);
        log_.frame_names.push_back(name);
        covered_ = 0;
        changed_.notify_all();
      }
    } catch (const std::exception& e) {
      note_error(e.what());  // the lock taken above was released on the way out
    }
  }

  int listen_fd_ = -1;
  uint16_t port_ = 0;
  size_t close_after_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable changed_;
  TevLog log_;
  TevImage image_;
  std::vector<float> pixels_;
  size_t covered_ = 0;
};

// HDR values, different in every pixel, channel and frame (and far above 1).
float pattern(uint64_t frame, uint32_t x, uint32_t y, int c) {
  return 0.001f + float(frame) * 3.25f + float(x) * 0.0625f + float(y) * 1.5f + float(c) * 200.0f;
}

SyntheticFrame patterned_frame(uint64_t sid, uint64_t index, uint32_t w, uint32_t h,
                               const std::vector<protocol::ChannelDecl>& channels) {
  SyntheticFrame f = make_frame(sid, index, w, h, channels, 0.0f);
  std::vector<float> rgb(size_t(w) * h * 3);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) rgb[3 * (size_t(y) * w + x) + size_t(c)] = pattern(index, x, y, c);
  std::memcpy(f.storage[0].data(), rgb.data(), f.storage[0].size());  // radiance, F32
  return f;
}

// A real server with a passthrough session open (fp32 radiance in and out) and its watch key.
struct OwnedSession {
  OwnedSession(uint32_t width, uint32_t height)
      : owner(server.tcp_url()), request(passthrough_session(width, height)) {
    owner.hello();
    opened = owner.open_session(request);
  }
  uint64_t id() const { return opened.session_id; }
  std::string key() const { return opened.watch_key.value_or(""); }
  // Sends frame `index` (patterned) and waits for its RESULT.
  bool stream(uint64_t index) {
    auto f = patterned_frame(id(), index, request.width, request.height, request.channels);
    owner.send(f.frame, index + 1);
    return owner.receive().has_value();
  }
  ServerProcess server;
  RawClient owner;
  protocol::OpenSession request;
  protocol::Session opened;
};

class DnWatchTev : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("dn_tev_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

// 200x144 goes as 2x2 tiles of at most 128x128 (the right and bottom ones
// partial); five frames, each shown in tev exactly as a plain watcher of the
// same session wrote it.
TEST_F(DnWatchTev, TevIsShownTheFramesAPlainWatcherReceives) {
  constexpr uint32_t W = 200, H = 144;
  constexpr int kFrames = 5;
  OwnedSession session(W, H);
  const uint64_t sid = session.id();
  const std::string key = session.key();

  FakeTev tev;
  const std::vector<std::string> common = {"watch",   "--server", session.server.tcp_url(), "--session", std::to_string(sid),
                                           "--key",   key,        "--count",        std::to_string(kFrames),
                                           "--timeout", "60"};
  std::vector<std::string> tev_args = common, plain_args = common;
  tev_args.insert(tev_args.end(), {"--tev", tev.address()});
  plain_args.insert(plain_args.end(), {"--output", (dir_ / "w_%04d.pfm").string()});
  ChildProcess tev_watch(DN_DN_PATH, tev_args);
  ChildProcess plain_watch(DN_DN_PATH, plain_args);
  ASSERT_TRUE(tev_watch.read_until("dn: watching session", 60)) << tev_watch.output();
  EXPECT_NE(tev_watch.output().find("into tev at " + tev.address() + " as 'dn session " + std::to_string(sid) + "'"),
            std::string::npos)
      << tev_watch.output();
  ASSERT_TRUE(plain_watch.read_until("dn: watching session", 60)) << plain_watch.output();

  // One frame at a time, the next once both watchers have this one: neither drops any.
  for (uint64_t i = 0; i < uint64_t(kFrames); ++i) {
    ASSERT_TRUE(session.stream(i));
    ASSERT_TRUE(tev.wait_frames(i + 1, 60)) << "tev has " << tev.log().frames.size() << " frames\n"
                                             << tev_watch.output();
    char name[32];
    std::snprintf(name, sizeof name, "w_%04d.pfm", int(i));
    const auto deadline = Clock::now() + std::chrono::seconds(60);
    while (!fs::exists(dir_ / name) && Clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    ASSERT_TRUE(fs::exists(dir_ / name)) << plain_watch.output();
  }
  ASSERT_EQ(tev_watch.wait(60), 0) << tev_watch.output();
  ASSERT_EQ(plain_watch.wait(60), 0) << plain_watch.output();

  const TevLog log = tev.log();
  EXPECT_TRUE(log.errors.empty()) << log.errors.front();
  ASSERT_EQ(log.creates.size(), 1u) << "the first frame creates the image; later ones update it";
  EXPECT_EQ(log.creates[0].name, "dn session " + std::to_string(sid));
  EXPECT_EQ(log.creates[0].width, int32_t(W));
  EXPECT_EQ(log.creates[0].height, int32_t(H));
  EXPECT_EQ(log.creates[0].channels, (std::vector<std::string>{"R", "G", "B"}));
  EXPECT_TRUE(log.create_focus[0]);
  EXPECT_EQ(log.updates, size_t(kFrames) * 2 * 2) << "2 x 2 tiles per frame";
  EXPECT_LE(log.largest_packet, size_t(256 * 1024));
  ASSERT_EQ(log.frames.size(), size_t(kFrames));
  for (int i = 0; i < kFrames; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "w_%04d.pfm", i);
    int w = 0, h = 0;
    const std::vector<float> written = image::read_pfm_rgb((dir_ / name).string(), w, h);
    ASSERT_EQ(w, int(W));
    ASSERT_EQ(h, int(H));
    ASSERT_EQ(log.frames[size_t(i)].size(), written.size());
    size_t differing = 0;
    for (size_t k = 0; k < written.size(); ++k) differing += log.frames[size_t(i)][k] != written[k];
    EXPECT_EQ(differing, 0u) << "frame " << i << ": tev's pixels differ from the plain watcher's";
    // And they are the HDR values sent (passthrough at fp32).
    EXPECT_EQ(log.frames[size_t(i)][3 * (size_t(H - 1) * W + (W - 1)) + 2], pattern(uint64_t(i), W - 1, H - 1, 2));
  }
  EXPECT_NE(tev_watch.output().find("dn: showed 5 frames"), std::string::npos) << tev_watch.output();
}

// Nothing listening at --tev: exit 1 naming tev, before the server is contacted
// (the server address here is unreachable too, and is not what is reported).
TEST_F(DnWatchTev, UnreachableTevIsExitOne) {
  int port = 0;
  {  // a port that was free a moment ago
    FakeTev probe;
    port = std::stoi(probe.address().substr(probe.address().rfind(':') + 1));
  }
  ChildProcess watch(DN_DN_PATH, {"watch", "--server", "tcp://127.0.0.1:1", "--session", "5", "--key",
                                  "00112233445566778899aabbccddeeff", "--tev", "127.0.0.1:" + std::to_string(port)});
  EXPECT_EQ(watch.wait(30), 1) << watch.output();
  EXPECT_NE(watch.output().find("dn watch: error: cannot connect to tev at 127.0.0.1:" + std::to_string(port) +
                                ": Connection refused (is tev running"),
            std::string::npos)
      << watch.output();
}

// Bad --tev values and neither --output nor --tev: exit 2.
TEST_F(DnWatchTev, BadTevAddressIsExitTwo) {
  const std::vector<std::string> base = {"watch", "--server", "tcp://127.0.0.1:1", "--session", "5",
                                         "--key", "00112233445566778899aabbccddeeff"};
  for (const std::vector<std::string>& extra : std::vector<std::vector<std::string>>{
           {"--tev", "localhost"}, {"--tev", "localhost:0"}, {"--tev", ":14158"}, {"--tev", "::1:14158"}, {}}) {
    std::vector<std::string> args = base;
    args.insert(args.end(), extra.begin(), extra.end());
    ChildProcess watch(DN_DN_PATH, args);
    EXPECT_EQ(watch.wait(30), 2) << watch.output();
    EXPECT_NE(watch.output().find(extra.empty() ? "missing --output PATTERN or --tev HOST:PORT" : "--tev: expected HOST:PORT"),
              std::string::npos)
        << watch.output();
  }
}

// tev quits mid-stream: dn watch says so and exits 1 (no SIGPIPE: that would be 141).
TEST_F(DnWatchTev, TevGoingAwayIsAClearErrorNotASignal) {
  constexpr uint32_t W = 64, H = 32;
  OwnedSession session(W, H);
  FakeTev tev(/*close_after_frames=*/1);
  ChildProcess watch(DN_DN_PATH, {"watch", "--server", session.server.tcp_url(), "--session",
                                  std::to_string(session.id()), "--key", session.key(), "--count", "100", "--timeout",
                                  "60", "--tev", tev.address()});
  ASSERT_TRUE(watch.read_until("dn: watching session", 60)) << watch.output();
  for (uint64_t i = 0; i < 200 && watch.running(); ++i) {
    ASSERT_TRUE(session.stream(i));
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_EQ(watch.wait(30), 1) << watch.output();
  EXPECT_NE(watch.output().find("dn watch: error: tev at " + tev.address() + " went away after 1 frame ("),
            std::string::npos)
      << watch.output();
  EXPECT_TRUE(tev.log().errors.empty());
}

}  // namespace
}  // namespace dn::test
