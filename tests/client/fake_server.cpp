#include "fake_server.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstring>

namespace dn::test {

using namespace dn::protocol;

Welcome test_welcome(uint32_t max_in_flight, uint64_t max_message_bytes) {
  Welcome w;
  w.server_version = "fake-dnserver 0.0";
  w.device_name = "Fake Device";
  w.limits.max_message_bytes = max_message_bytes;
  w.limits.max_session_bytes = 1ull << 30;
  w.limits.max_sessions = 8;
  w.limits.max_width = 8192;
  w.limits.max_height = 8192;
  w.limits.max_frames_in_flight = max_in_flight;
  PipelineInfo svgf;
  svgf.name = "svgf";
  svgf.required_channels = channel_bit(ChannelId::Radiance) | channel_bit(ChannelId::Albedo);
  svgf.optional_channels = channel_bit(ChannelId::Normal) | channel_bit(ChannelId::Depth);
  w.pipelines.push_back(svgf);
  return w;
}

protocol::Session attach_reply(uint64_t session_id, uint32_t width, uint32_t height) {
  protocol::Session s;
  s.session_id = session_id;
  s.width = width;
  s.height = height;
  s.pipeline = "passthrough";
  s.read_only = true;
  s.watch_key = "";  // the reply to ATTACH does not repeat the key
  s.watch_url = "";  // ... and this server advertises none
  return s;
}

Welcome test_welcome_with_parameters() {
  Welcome w = test_welcome();
  w.has_parameters = true;
  w.pipelines[0].parameters = {
      {"alpha_colour", 0.05, 0.0, 1.0, false, "Floor of the temporal blend weight of the colour."},
      {"atrous_iterations", 4.0, 0.0, 8.0, true, "Number of a-trous iterations."}};
  PipelineInfo passthrough;
  passthrough.name = "passthrough";
  passthrough.required_channels = channel_bit(ChannelId::Radiance);
  w.pipelines.push_back(passthrough);
  return w;
}

std::optional<Received> Peer::recv(int timeout_ms) {
  for (;;) {
    std::span<uint8_t> buf = reader_.writable();
    pollfd p{fd_, POLLIN, 0};
    const int rc = ::poll(&p, 1, timeout_ms);
    if (rc <= 0) return std::nullopt;
    const ssize_t n = ::recv(fd_, buf.data(), buf.size(), 0);
    if (n <= 0) {
      eof_ = true;
      return std::nullopt;
    }
    const auto st = reader_.commit(size_t(n));
    if (st == MessageReader::Status::Failed) {
      ADD_FAILURE() << "fake server: framing error " << reader_.error().message;
      return std::nullopt;
    }
    if (st == MessageReader::Status::Ready) {
      Received r;
      r.header = reader_.header();
      r.payload = std::make_shared<std::vector<uint8_t>>(reader_.take_payload());
      Header as_read = r.header;
      as_read.version_minor = std::min(as_read.version_minor, announced_minor_);
      if (auto e = decode_payload(as_read, *r.payload, r.message)) {
        ADD_FAILURE() << "fake server: decode error at " << e->field << ": " << e->message;
        return std::nullopt;
      }
      return r;
    }
  }
}

void Peer::send_raw(const std::vector<uint8_t>& bytes) {
  size_t off = 0;
  while (off < bytes.size()) {
    const ssize_t n = ::send(fd_, bytes.data() + off, bytes.size() - off, MSG_NOSIGNAL);
    if (n <= 0) return;  // client went away; the test decides whether that matters
    off += size_t(n);
  }
}

void Peer::send(const Message& m, uint64_t request_id, uint32_t flags) {
  // Under this version's header a RESULT carries RESULT.samples (the client
  // reads appended fields by the header's minor): not counted unless set.
  if (const auto* r = std::get_if<Result>(&m); r && !r->samples) {
    Result with = *r;
    with.samples = protocol::SampleCounts{};
    return send_raw(encode(with, request_id, flags));
  }
  // Likewise a SESSION carries SESSION.pipeline_reason after its watch URL: empty unless set.
  if (const auto* s = std::get_if<Session>(&m); s && s->watch_url && !s->pipeline_reason) {
    Session with = *s;
    with.pipeline_reason = "";
    return send_raw(encode(with, request_id, flags));
  }
  send_raw(encode(m, request_id, flags));
}

bool Peer::read_raw(size_t n, int timeout_ms) {
  std::vector<uint8_t> buf(n);
  size_t got = 0;
  while (got < n) {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) <= 0) return false;
    const ssize_t r = ::recv(fd_, buf.data() + got, n - got, 0);
    if (r <= 0) return false;
    got += size_t(r);
  }
  return true;
}

Hello Peer::handshake(const std::optional<std::string>& token, uint32_t max_in_flight, uint64_t max_message_bytes) {
  auto m = recv();
  if (!m) {
    ADD_FAILURE() << "fake server: no HELLO";
    return {};
  }
  auto* hello = std::get_if<Hello>(&m->message);
  if (!hello) {
    ADD_FAILURE() << "fake server: expected HELLO, got " << to_string(type_of(m->message));
    return {};
  }
  if (token && hello->auth_token != *token) {
    send(Error{ErrorCode::Unauthenticated, "HELLO.auth_token", "bad token"}, m->header.request_id);
    return *hello;
  }
  send_welcome(test_welcome(max_in_flight, max_message_bytes), m->header.request_id);
  return *hello;
}

Hello Peer::handshake_with(const Welcome& welcome) {
  auto m = recv();
  if (!m || !std::holds_alternative<Hello>(m->message)) {
    ADD_FAILURE() << "fake server: no HELLO";
    return {};
  }
  send_welcome(welcome, m->header.request_id);
  return std::get<Hello>(m->message);
}

void Peer::send_welcome(const Welcome& welcome, uint64_t request_id) {
  std::vector<uint8_t> bytes = encode(welcome, request_id);
  if (!welcome.has_parameters) bytes[5] = 0;  // header version_minor: a 1.0 server
  announced_minor_ = bytes[5];
  send_raw(bytes);
}

void Peer::close() {
  if (fd_ >= 0) {
    ::shutdown(fd_, SHUT_RDWR);
    ::close(fd_);
    fd_ = -1;
  }
}

FakeServer::FakeServer(Handler handler, bool tcp) {
  static std::atomic<int> counter{0};
  if (tcp) {
    listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = 0;
    if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) ADD_FAILURE() << "bind: " << strerror(errno);
    socklen_t len = sizeof a;
    ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&a), &len);
    url_ = "tcp://127.0.0.1:" + std::to_string(ntohs(a.sin_port));
  } else {
    path_ = "/tmp/dn_client_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + ".sock";
    ::unlink(path_.c_str());
    listen_fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::strncpy(a.sun_path, path_.c_str(), sizeof a.sun_path - 1);
    if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) ADD_FAILURE() << "bind: " << strerror(errno);
    url_ = "unix://" + path_;
  }
  if (::listen(listen_fd_, 4) != 0) ADD_FAILURE() << "listen: " << strerror(errno);
  thread_ = std::thread([this, handler = std::move(handler)] {
    pollfd p{listen_fd_, POLLIN, 0};
    if (::poll(&p, 1, 10000) <= 0) {
      ADD_FAILURE() << "fake server: no client connected";
      return;
    }
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
    if (fd < 0) {
      ADD_FAILURE() << "accept: " << strerror(errno);
      return;
    }
    Peer peer(fd);
    handler(peer);
    peer.close();
  });
}

void FakeServer::join() {
  if (thread_.joinable()) thread_.join();
}

FakeServer::~FakeServer() {
  join();
  if (listen_fd_ >= 0) ::close(listen_fd_);
  if (!path_.empty()) ::unlink(path_.c_str());
}

}  // namespace dn::test
