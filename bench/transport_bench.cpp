// The transport alone: pipelined FRAME -> RESULT round trips against a real
// dnserver process over loopback TCP (or a Unix socket), through the
// `passthrough` pipeline, which does no filtering. Prints frames per second,
// GB/s (request + reply bytes over wall time) and the per-stage times:
// encode, send, decode (client side) and upload, copy, download (server side).
// Frames are sent the way the client library sends them: encode_segments()
// plus sendmsg(), so plane bytes are never copied in user space.
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <arpa/inet.h>
#include <sys/uio.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

#include "frame_set.hpp"
#include "server_process.hpp"

namespace {

using Clock = std::chrono::steady_clock;
using dn::protocol::Format;

double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

int connect_to(const std::string& url) {
  int fd;
  if (url.rfind("unix://", 0) == 0) {
    fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::strncpy(a.sun_path, url.c_str() + 7, sizeof a.sun_path - 1);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) throw std::runtime_error("connect " + url);
  } else {
    std::string rest = url.substr(6);
    auto colon = rest.rfind(':');
    fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(std::stoi(rest.substr(colon + 1))));
    inet_pton(AF_INET, rest.substr(0, colon).c_str(), &a.sin_addr);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) throw std::runtime_error("connect " + url);
    int one = 1;
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  }
  int size = 8 << 20;
  ::setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &size, sizeof size);
  ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &size, sizeof size);
  return fd;
}

// Sends gathered segments with sendmsg: plane bytes go from the renderer's memory to the socket.
void send_segments(int fd, const std::vector<std::span<const uint8_t>>& segments) {
  dn::protocol::SegmentCursor cursor;
  while (!cursor.done(segments)) {
    iovec iov[64];
    size_t count = 0;
    for (size_t i = cursor.segment; i < segments.size() && count < 64; ++i, ++count) {
      const auto piece = cursor.remaining(segments, i);
      iov[count] = {const_cast<uint8_t*>(piece.data()), piece.size()};
    }
    msghdr msg{};
    msg.msg_iov = iov;
    msg.msg_iovlen = count;
    ssize_t n = ::sendmsg(fd, &msg, MSG_NOSIGNAL);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error("send failed");
    }
    cursor.advance(segments, static_cast<size_t>(n));
  }
}

void send_all(int fd, const std::vector<uint8_t>& bytes) {
  size_t sent = 0;
  while (sent < bytes.size()) {
    ssize_t n = ::send(fd, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error("send failed");
    }
    sent += static_cast<size_t>(n);
  }
}

struct Message {
  dn::protocol::Header header;
  std::vector<uint8_t> payload;
};

Message receive(int fd, dn::protocol::MessageReader& reader) {
  for (;;) {
    auto target = reader.writable();
    ssize_t n = ::recv(fd, target.data(), target.size(), 0);
    if (n <= 0) throw std::runtime_error("server closed the connection");
    auto status = reader.commit(static_cast<size_t>(n));
    if (status == dn::protocol::MessageReader::Status::Failed) throw std::runtime_error(reader.error().message);
    if (status == dn::protocol::MessageReader::Status::Ready) {
      Message m{reader.header(), {}};
      m.payload = reader.take_payload();
      return m;
    }
  }
}

dn::protocol::Message decode(const Message& m) {
  dn::protocol::Message out;
  if (auto err = dn::protocol::decode_payload(m.header, m.payload, out)) throw std::runtime_error(err->message);
  if (auto* e = std::get_if<dn::protocol::Error>(&out))
    throw std::runtime_error("server error at " + e->field + ": " + e->message);
  return out;
}

struct Report {
  double fps = 0, gbps = 0, mb_per_frame = 0;
  std::map<std::string, double> stage_ms;  // medians
};

Report run(const std::string& url, uint32_t width, uint32_t height, Format format, int frames, int in_flight) {
  const auto channels = dn::bench::svgf_channels(format);
  auto data = dn::bench::make_frame(width, height, channels);
  int fd = connect_to(url);
  dn::protocol::MessageReader reader(1ull << 31);
  send_all(fd, dn::protocol::encode(dn::protocol::Hello{0, "transport_bench", ""}, 1));
  decode(receive(fd, reader));
  dn::protocol::OpenSession open;
  open.width = width;
  open.height = height;
  open.pipeline = "passthrough";
  open.output_format = format;
  open.channels = channels;
  send_all(fd, dn::protocol::encode(open, 2));
  auto session = std::get<dn::protocol::Session>(decode(receive(fd, reader)));
  data.frame.info.session_id = session.session_id;

  const int warmup = 3;
  std::mutex m;
  std::condition_variable cv;
  int outstanding = 0;
  std::vector<double> encode_ms, send_ms;
  uint64_t request_bytes = 0;
  std::thread sender([&] {
    std::vector<uint8_t> scratch;
    std::vector<std::span<const uint8_t>> segments;
    for (int i = 0; i < warmup + frames; ++i) {
      {
        std::unique_lock lock(m);
        cv.wait(lock, [&] { return outstanding < in_flight; });
        ++outstanding;
      }
      data.frame.info.frame_index = static_cast<uint64_t>(i);
      auto t0 = Clock::now();
      dn::protocol::encode_segments(data.frame, 100 + static_cast<uint64_t>(i), 0, scratch, segments);
      double e = ms_since(t0);
      auto t1 = Clock::now();
      send_segments(fd, segments);
      double s = ms_since(t1);
      if (i >= warmup) {
        encode_ms.push_back(e);
        send_ms.push_back(s);
        for (auto seg : segments) request_bytes += seg.size();
      }
    }
  });

  std::map<std::string, std::vector<double>> server_ms;
  std::vector<double> decode_ms;
  uint64_t reply_bytes = 0;
  Clock::time_point start;
  for (int i = 0; i < warmup + frames; ++i) {
    if (i == warmup) start = Clock::now();
    Message reply = receive(fd, reader);
    auto t0 = Clock::now();
    auto result = std::get<dn::protocol::Result>(decode(reply));
    double d = ms_since(t0);
    {
      std::lock_guard lock(m);
      --outstanding;
    }
    cv.notify_one();
    if (i < warmup) continue;
    decode_ms.push_back(d);
    reply_bytes += dn::protocol::kHeaderSize + reply.payload.size();
    for (const auto& t : result.timings) server_ms[t.name].push_back(t.milliseconds);
  }
  const double wall_s = ms_since(start) / 1000.0;
  sender.join();
  ::close(fd);

  Report r;
  r.fps = frames / wall_s;
  r.gbps = static_cast<double>(request_bytes + reply_bytes) / wall_s / 1e9;
  r.mb_per_frame = static_cast<double>(request_bytes + reply_bytes) / frames / 1e6;
  r.stage_ms["encode"] = median(encode_ms);
  r.stage_ms["send"] = median(send_ms);
  r.stage_ms["decode"] = median(decode_ms);
  for (auto& [name, v] : server_ms) r.stage_ms[name] = median(v);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  uint32_t width = 1280, height = 720;
  int frames = 40, in_flight = 4;
  bool use_unix = false;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--frames" && i + 1 < argc) frames = std::atoi(argv[++i]);
    else if (a == "--in-flight" && i + 1 < argc) in_flight = std::atoi(argv[++i]);
    else if (a == "--width" && i + 1 < argc) width = static_cast<uint32_t>(std::atoi(argv[++i]));
    else if (a == "--height" && i + 1 < argc) height = static_cast<uint32_t>(std::atoi(argv[++i]));
    else if (a == "--unix") use_unix = true;
    else {
      std::fprintf(stderr, "usage: transport_bench [--frames N] [--in-flight K] [--width W] [--height H] [--unix]\n");
      return 2;
    }
  }
  try {
    dn::test::ServerProcess server({"--max-in-flight", std::to_string(in_flight)});
    const std::string url = use_unix ? server.unix_url() : server.tcp_url();
    std::printf("transport: %ux%u, passthrough, %d frames after 3 warm-up, %d in flight, %s\n", width, height, frames,
                in_flight, url.c_str());
    std::printf("| format | MB/frame (req+reply) | frames/s | GB/s | encode ms | send ms | decode ms | upload ms | copy ms | download ms |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
    for (Format f : {Format::F32, Format::F16}) {
      Report r = run(url, width, height, f, frames, in_flight);
      double copy = 0;
      for (auto& [name, ms] : r.stage_ms)
        if (name != "encode" && name != "send" && name != "decode" && name != "upload" && name != "download") copy += ms;
      std::printf("| %s | %.1f | %.1f | %.2f | %.2f | %.2f | %.3f | %.2f | %.2f | %.2f |\n", f == Format::F32 ? "fp32" : "fp16",
                  r.mb_per_frame, r.fps, r.gbps, r.stage_ms["encode"], r.stage_ms["send"], r.stage_ms["decode"],
                  r.stage_ms["upload"], copy, r.stage_ms["download"]);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "transport_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
