#include "raw_client.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <netinet/in.h>
#include <arpa/inet.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <stdexcept>

namespace dn::test {
namespace {

int connect_url(const std::string& url) {
  if (url.rfind("unix://", 0) == 0) {
    std::string path = url.substr(7);
    int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
      ::close(fd);
      throw std::runtime_error("connect " + url + ": " + std::strerror(errno));
    }
    return fd;
  }
  std::string rest = url.substr(6);
  auto colon = rest.rfind(':');
  std::string host = rest.substr(0, colon);
  int port = std::stoi(rest.substr(colon + 1));
  int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<uint16_t>(port));
  inet_pton(AF_INET, host.c_str(), &addr.sin_addr);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    ::close(fd);
    throw std::runtime_error("connect " + url + ": " + std::strerror(errno));
  }
  return fd;
}

}  // namespace

RawClient::RawClient(const std::string& url) : fd_(connect_url(url)) {}
RawClient::~RawClient() { close(); }
RawClient::RawClient(RawClient&& o) noexcept : fd_(o.fd_), buffer_(std::move(o.buffer_)) { o.fd_ = -1; }

void RawClient::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

void RawClient::send_bytes(const std::vector<uint8_t>& bytes) {
  size_t sent = 0;
  while (sent < bytes.size()) {
    ssize_t n = ::send(fd_, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(std::string("send: ") + std::strerror(errno));
    }
    sent += static_cast<size_t>(n);
  }
}

void RawClient::send(const protocol::Message& m, uint64_t request_id, uint32_t flags) {
  send_bytes(protocol::encode(m, request_id, flags));
}

std::optional<Received> RawClient::receive(double timeout_s) {
  auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    if (buffer_.size() >= protocol::kHeaderSize) {
      protocol::Header h;
      if (auto err = protocol::decode_header(std::span(buffer_.data(), protocol::kHeaderSize), 1ull << 32, h))
        throw std::runtime_error("server sent a bad header: " + err->message);
      if (buffer_.size() >= protocol::kHeaderSize + h.payload_length) {
        Received r;
        r.header = h;
        r.payload.assign(buffer_.begin() + protocol::kHeaderSize, buffer_.begin() + protocol::kHeaderSize + h.payload_length);
        buffer_.erase(buffer_.begin(), buffer_.begin() + protocol::kHeaderSize + h.payload_length);
        protocol::Header as_read = h;
        as_read.version_minor = std::min(h.version_minor, read_minor_);
        if (auto err = protocol::decode_payload(as_read, r.payload, r.message))
          throw std::runtime_error("server sent a bad payload: " + err->field + ": " + err->message);
        return r;
      }
    }
    auto left = std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0 || fd_ < 0) return std::nullopt;
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(left * 1000) + 1) <= 0) return std::nullopt;
    uint8_t chunk[1 << 16];
    ssize_t n = ::recv(fd_, chunk, sizeof chunk, 0);
    if (n <= 0) return std::nullopt;
    buffer_.insert(buffer_.end(), chunk, chunk + n);
  }
}

bool RawClient::closed_by_server(double timeout_s) {
  auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    auto left = std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0) return false;
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(left * 1000) + 1) <= 0) return false;
    uint8_t chunk[4096];
    ssize_t n = ::recv(fd_, chunk, sizeof chunk, 0);
    if (n == 0) return true;
    if (n < 0) return errno == ECONNRESET;
  }
}

protocol::Welcome RawClient::hello(const std::string& token) {
  send(protocol::Hello{0, "e2e-test", token}, 1);
  auto r = receive();
  if (!r) throw std::runtime_error("no reply to HELLO");
  if (auto* w = std::get_if<protocol::Welcome>(&r->message)) return *w;
  if (auto* e = std::get_if<protocol::Error>(&r->message)) throw std::runtime_error("HELLO refused: " + e->message);
  throw std::runtime_error("unexpected reply to HELLO");
}

uint64_t RawClient::open(const protocol::OpenSession& request, uint64_t request_id) {
  return open_session(request, request_id).session_id;
}

protocol::Session RawClient::open_session(const protocol::OpenSession& request, uint64_t request_id) {
  send(request, request_id);
  // Opening may compile the session's kernels: on a cold Mesa cache and a loaded machine, past 20 s.
  auto r = receive(90.0);
  if (!r) throw std::runtime_error("no reply to OPEN_SESSION");
  if (auto* s = std::get_if<protocol::Session>(&r->message)) return *s;
  if (auto* e = std::get_if<protocol::Error>(&r->message))
    throw std::runtime_error("OPEN_SESSION refused: " + e->field + ": " + e->message);
  throw std::runtime_error("unexpected reply to OPEN_SESSION");
}

SyntheticFrame make_frame(uint64_t session_id, uint64_t frame_index, uint32_t width, uint32_t height,
                          const std::vector<protocol::ChannelDecl>& channels, float radiance_value) {
  SyntheticFrame f;
  f.frame.info.session_id = session_id;
  f.frame.info.frame_index = frame_index;
  for (int i = 0; i < 4; ++i) {
    f.frame.info.view[i * 5] = f.frame.info.projection[i * 5] = 1.0f;
    f.frame.info.prev_view[i * 5] = f.frame.info.prev_projection[i * 5] = 1.0f;
  }
  f.storage.reserve(channels.size());
  for (const auto& decl : channels) {
    const protocol::ChannelInfo& info = *protocol::find_channel(decl.id);
    const size_t count = size_t{width} * height * info.components;
    std::vector<float> values(count);
    for (size_t i = 0; i < count; ++i) {
      switch (decl.id) {
        case protocol::ChannelId::Normal: values[i] = (i % 3 == 2) ? 1.0f : 0.0f; break;
        case protocol::ChannelId::Depth: values[i] = 5.0f; break;
        case protocol::ChannelId::Motion: values[i] = 0.0f; break;
        default: values[i] = radiance_value; break;
      }
    }
    std::vector<uint8_t> bytes(count * protocol::bytes_per_component(decl.format));
    if (decl.format == protocol::Format::F32) {
      std::memcpy(bytes.data(), values.data(), bytes.size());
    } else {
      for (size_t i = 0; i < count; ++i) {
        uint16_t h = protocol::float_to_half(values[i]);
        std::memcpy(bytes.data() + 2 * i, &h, 2);
      }
    }
    f.storage.push_back(std::move(bytes));
    f.frame.planes.push_back({decl.id, decl.format, std::span<const uint8_t>(f.storage.back())});
  }
  return f;
}

std::vector<protocol::StatValue> stats_values(RawClient& c) {
  c.send(protocol::StatsRequest{}, 900);
  for (;;) {  // RESULTs of frames in flight may come first
    auto r = c.receive();
    if (!r) throw std::runtime_error("no STATS reply");
    if (auto* st = std::get_if<protocol::Stats>(&r->message)) return st->values;
  }
}

std::map<std::string, double> stats(RawClient& c) {
  std::map<std::string, double> out;
  for (const auto& v : stats_values(c)) out[v.name] = v.value;
  return out;
}

float first_output_value(const protocol::Result& result) {
  float v;
  std::memcpy(&v, result.planes.at(0).bytes.data(), 4);
  return v;
}

protocol::OpenSession passthrough_session(uint32_t width, uint32_t height) {
  protocol::OpenSession o;
  o.width = width;
  o.height = height;
  o.pipeline = "passthrough";
  o.output_format = protocol::Format::F32;
  o.channels = {{protocol::ChannelId::Radiance, protocol::Format::F32}};
  return o;
}

}  // namespace dn::test
