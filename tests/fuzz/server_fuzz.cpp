// libFuzzer target for the server's connection and session state machine.
//
// One Server lives for the whole run, with no listener: each input opens two
// client connections on socketpairs (Server::adopt), plays a sequence of
// operations on them and closes them. The server's real code runs from the
// socket read to the reply (framing, handshake, OPEN_SESSION validation, the
// builder and worker threads, FRAME checks, ATTACH keys, CLOSE_SESSION,
// STATS, backpressure, fatal errors); only the device is replaced by a
// host-only pipeline (the factory below), so an input takes microseconds.
//
// Input: a sequence of operations, each a byte choosing the connection (bit 0)
// and the kind (the rest), followed by the bytes that kind reads (Input):
// HELLO, OPEN_SESSION (a pipeline, tiny sizes, channel sets with mutations,
// one parameter at an edge), FRAME bursts (valid planes or mutated ones, NaN
// and Inf values, frame indices in order, repeated or arbitrary), ATTACH with
// the right, no or a wrong key (to either connection's sessions), CLOSE_SESSION,
// STATS, PING, PONG, a message type only servers send, raw bytes, a header
// that declares more than follows, and shutting the client's write side.
// After each operation the server runs until it settles.
//
// Properties checked (a violation aborts):
//   - nothing crashes, leaks, races into ASan or trips UBSan;
//   - everything the server writes frames and decodes, and is a message a
//     server sends; every ERROR says why;
//   - while a connection's stream is well formed and open, every request that
//     has a reply gets exactly one, and a FRAME's RESULT names its session and
//     frame index and carries an Output plane of the session's size unless
//     the frame asked for none; a watcher's copy carries that Output plane
//     first and, only on a 1.7 connection, at most the session's radiance
//     plane after it (SHARE_INPUT);
//   - RESULTs of a session reach each connection in increasing frame order;
//   - the server settles (nothing built, run or written) after every step;
//   - once both clients have closed, no connection and no session remains.
//
// Built as `server_fuzz` (clang, -fsanitize=fuzzer) when DN_BUILD_FUZZ=ON, and
// always as `server_fuzz_replay` (with replay_main.cpp), which runs files or
// directories of inputs (tests/fuzz/server_corpus in ctest).
#include <fcntl.h>
#include <linux/sockios.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "dn/protocol/codec.hpp"
#include "server/gpu/context.hpp"
#include "server/log.hpp"
#include "server/session/frame_planes.hpp"
#include "server/pipelines/pipeline.hpp"
#include "server/server.hpp"

using namespace dn;
using namespace dn::protocol;

namespace {

[[noreturn]] void violated(const std::string& what) {
  std::fprintf(stderr, "server_fuzz: property violated: %s\n", what.c_str());
  std::abort();
}

// Reads the input front to back; past its end every read is zero.
class Input {
 public:
  Input(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  bool empty() const { return pos_ >= size_; }
  uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  uint32_t below(uint32_t n) { return n ? byte() % n : 0; }
  bool flag() { return byte() & 1; }
  uint64_t u64() {
    uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v = v << 8 | byte();
    return v;
  }
  std::vector<uint8_t> bytes(size_t n) {
    std::vector<uint8_t> out;
    while (n-- && !empty()) out.push_back(byte());
    return out;
  }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

// The device stand-in: sizes like the real pipeline, an Output plane of the
// session's size, and device failures on demand (width 7 cannot be built;
// a session's 6th, 17th, 28th, ... frame fails on the "device").
class HostPipeline : public pipelines::Pipeline {
 public:
  explicit HostPipeline(const pipelines::PreparedPipeline& p) : config_(p.config()), bytes_(p.device_bytes()) {}
  uint64_t device_bytes() const override { return bytes_; }
  const pipelines::SessionConfig& config() const override { return config_; }
  void process(const pipelines::FrameInput&, bool want_output, std::vector<uint8_t>& output,
               std::vector<pipelines::PassTiming>& timings) override {
    if (frames_++ % 11 == 5) throw pipelines::DeviceFailure("fuzz: simulated device loss");
    if (want_output)
      output.assign(uint64_t{config_.width} * config_.height * 3 * bytes_per_component(config_.output_format), 0x3c);
    timings.push_back({"host", 0.0});
  }

 private:
  pipelines::SessionConfig config_;
  uint64_t bytes_;
  uint64_t frames_ = 0;
};

std::unique_ptr<pipelines::Pipeline> make_host_pipeline(const pipelines::PreparedPipeline& p) {
  if (p.config().width == 7) throw pipelines::DeviceFailure("fuzz: simulated allocation failure");
  return std::make_unique<HostPipeline>(p);
}

struct Harness {
  std::unique_ptr<gpu::Context> device;
  std::unique_ptr<server::Server> server;
};

Harness& harness() {
  static Harness* h = [] {
    ::signal(SIGPIPE, SIG_IGN);
    // DN_FUZZ_LOG=info shows what the server does with an input (default: errors only).
    log::Level level = log::Level::Error;
    if (const char* text = std::getenv("DN_FUZZ_LOG")) log::parse_level(text, level);
    log::set_level(level);
    auto* made = new Harness;  // lives for the whole run
    made->device = std::make_unique<gpu::Context>();
    server::ServerOptions options;
    options.listen.clear();
    options.workers = 2;
    options.warm_up = false;
    options.max_width = 16;
    options.max_height = 16;
    options.max_sessions = 6;
    options.max_frames_in_flight = 2;
    made->server = std::make_unique<server::Server>(options, *made->device, "fuzz", make_host_pipeline);
    return made;
  }();
  return *h;
}

struct KnownSession {
  uint64_t id = 0;
  std::string key;
  uint32_t width = 0, height = 0;
  Format output_format = Format::F32;
  std::vector<ChannelDecl> channels;
  uint64_t next_index = 0;
};

// What a request's reply must look like.
struct Pending {
  MessageType request;
  uint64_t session_id = 0;   // FRAME
  uint64_t frame_index = 0;  // FRAME
  bool wants_output = true;  // FRAME
  uint32_t width = 0, height = 0;
  Format output_format = Format::F32;
};

// One client connection, seen from the client's end of its socketpair.
struct Peer {
  int fd = -1;
  MessageReader reader{uint64_t{1} << 26};
  bool eof = false;      // the server closed it
  bool in_step = true;   // every message written whole and well formed: replies can be counted
  bool write_shut = false;
  // The minor of this client's first HELLO: replies hold what min(it, the
  // server's) defines, and are read as that version (docs/protocol.md §10).
  std::optional<uint8_t> minor;
  std::map<uint64_t, Pending> pending;  // request id -> expected reply
  uint64_t next_request = 1;
  std::vector<KnownSession> sessions;    // opened by this peer
  std::set<uint64_t> watched;
  // Session id -> frame index of the last RESULT seen, as a reply to FRAME
  // and as a watcher's copy (a connection may watch its own session).
  std::map<uint64_t, uint64_t> last_reply, last_watched;

  bool live() const { return fd >= 0 && !eof; }
};

bool sent_by_servers(MessageType t) {
  switch (t) {
    case MessageType::Welcome: case MessageType::Error: case MessageType::Session: case MessageType::Result:
    case MessageType::Ping: case MessageType::Pong: case MessageType::SessionClosed: case MessageType::Stats:
      return true;
    default:
      return false;
  }
}

void check_reply(Peer& p, const Header& h, const Message& m) {
  if (!sent_by_servers(h.type)) violated(std::string("server sent ") + to_string(h.type));
  if (const auto* e = std::get_if<Error>(&m); e && e->message.empty()) violated("ERROR without a message");
  auto it = p.pending.find(h.request_id);
  const Pending* expected = it == p.pending.end() ? nullptr : &it->second;

  if (const auto* r = std::get_if<Result>(&m)) {
    const bool is_reply = expected && expected->request == MessageType::Frame &&
                          expected->session_id == r->session_id && expected->frame_index == r->frame_index;
    auto [last, first] = (is_reply ? p.last_reply : p.last_watched).try_emplace(r->session_id, r->frame_index);
    if (!first) {
      if (r->frame_index <= last->second) violated("RESULTs of a session out of order");
      last->second = r->frame_index;
    }
    if (!is_reply) {
      if (!p.watched.count(r->session_id)) violated("RESULT for a session neither owned by the frame's request nor watched");
      if (r->planes.empty() || r->planes[0].id != ChannelId::Output) violated("watcher's RESULT without an Output plane first");
      if (r->planes.size() > 2 || (r->planes.size() == 2 && (r->planes[1].id != ChannelId::Radiance ||
                                                            p.minor.value_or(0) < kShareInputMinor)))
        violated("watcher's RESULT with planes other than Output and, from 1.7, the shared radiance");
      return;
    }
    if (expected->wants_output) {
      const uint64_t bytes = uint64_t{expected->width} * expected->height * 3 * bytes_per_component(expected->output_format);
      if (r->planes.size() != 1 || r->planes[0].id != ChannelId::Output || r->planes[0].bytes.size() != bytes)
        violated("RESULT without the session's Output plane");
    }
  } else if (const auto* s = std::get_if<SessionClosed>(&m); s && !(expected && expected->request == MessageType::CloseSession)) {
    if (!p.watched.count(s->session_id)) violated("SESSION_CLOSED for a session not watched");
    return;
  } else if (h.type == MessageType::Ping) {
    return;
  } else if (h.type == MessageType::Error && !expected) {
    return;  // a connection-level error (request id 0 or unknown)
  }
  if (!expected) {
    if (p.in_step) violated(std::string(to_string(h.type)) + " answers no request");
    return;
  }
  if (const auto* s = std::get_if<Session>(&m)) {
    if (expected->request == MessageType::OpenSession)
      p.sessions.push_back({s->session_id, s->watch_key.value_or(""), s->width, s->height, s->output_format,
                            s->channels, 0});
    else if (expected->request == MessageType::Attach)
      p.watched.insert(s->session_id);
    else
      violated("SESSION answers neither OPEN_SESSION nor ATTACH");
  }
  p.pending.erase(it);
}

void drain(Peer& p) {
  while (p.live()) {
    std::span<uint8_t> w = p.reader.writable();
    const ssize_t n = ::read(p.fd, w.data(), w.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN) return;
      p.eof = true;  // ECONNRESET: the server closed with our bytes unread
      return;
    }
    if (n == 0) {
      p.eof = true;
      return;
    }
    auto status = p.reader.commit(static_cast<size_t>(n));
    while (status == MessageReader::Status::Ready) {
      Header h = p.reader.header();
      h.version_minor = std::min(h.version_minor, p.minor.value_or(kVersionMinor));
      std::vector<uint8_t> payload = p.reader.take_payload();
      Message m;
      // WELCOME is the same for every client of a minor and the largest
      // message to decode: checked once per distinct payload.
      static std::set<std::vector<uint8_t>> welcomes_checked;
      if (h.type == MessageType::Welcome && welcomes_checked.count(payload)) {
        m = Welcome{};
      } else {
        if (auto err = decode_payload(h, payload, m))
          violated("server sent an undecodable " + std::string(to_string(h.type)) + ": " + err->message);
        if (h.type == MessageType::Welcome) welcomes_checked.insert(payload);
      }
      check_reply(p, h, m);
      status = p.reader.commit(0);
    }
    if (status == MessageReader::Status::Failed) violated("server broke framing: " + p.reader.error().message);
  }
}

// One turn of the server's loop; it waits only while work is on the builder
// or a worker thread, whose completion wakes it at once.
void turn(server::Server& server) { server.run_once(server.quiescent() ? 0 : 50); }

// Bytes written by `fd` that its peer has not read yet.
int unread_by_server(int fd) {
  int n = 0;
  return ::ioctl(fd, SIOCOUTQ, &n) == 0 ? n : 0;
}

// Runs the server until it settles: nothing built, run or written, and every
// byte the clients wrote read (or their connection closed).
void settle(Peer (&peers)[2]) {
  server::Server& server = *harness().server;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  for (int calm = 0; calm < 2;) {
    turn(server);
    bool busy = !server.quiescent();
    for (Peer& p : peers) {
      drain(p);
      if (p.live() && unread_by_server(p.fd) > 0) busy = true;
    }
    calm = busy ? 0 : calm + 1;
    if (std::chrono::steady_clock::now() > deadline) violated("server did not settle within 60 s");
  }
  for (Peer& p : peers)
    if (p.live() && p.in_step && !p.pending.empty())
      violated(std::string(to_string(p.pending.begin()->second.request)) + " was never answered");
}

void write_all(Peer (&peers)[2], Peer& p, const std::vector<uint8_t>& bytes) {
  size_t off = 0;
  while (off < bytes.size() && p.live() && !p.write_shut) {
    const ssize_t n = ::write(p.fd, bytes.data() + off, bytes.size() - off);
    if (n > 0) {
      off += static_cast<size_t>(n);
    } else if (n < 0 && errno == EAGAIN) {
      turn(*harness().server);  // the server reads; keep taking its replies
      for (Peer& q : peers) drain(q);
    } else if (n < 0 && errno != EINTR) {
      p.eof = true;  // EPIPE: the server has closed
    }
  }
  if (off < bytes.size()) p.in_step = false;
}

// Encodes and writes a message expecting `reply` (nullopt: none).
void send(Peer (&peers)[2], Peer& p, const Message& m, std::optional<Pending> reply, uint32_t flags = 0) {
  const uint64_t request = p.next_request++;
  std::vector<uint8_t> bytes;
  try {
    bytes = encode(m, request, flags);
  } catch (const std::exception&) {
    return;  // not encodable (a string over its limit): nothing to send
  }
  if (reply && p.live() && !p.write_shut) p.pending.emplace(request, *reply);
  write_all(peers, p, bytes);
}

double edge_value(Input& in, const pipelines::ParameterInfo& info) {
  switch (in.below(8)) {
    case 0: return info.default_value;
    case 1: return info.min_value;
    case 2: return info.max_value;
    case 3: return info.min_value - 1;
    case 4: return info.max_value + 0.5;
    case 5: return std::numeric_limits<double>::quiet_NaN();
    case 6: return std::numeric_limits<double>::infinity();
    default: {
      const uint64_t bits = in.u64();
      double v;
      std::memcpy(&v, &bits, sizeof v);
      return v;
    }
  }
}

void open_session(Peer (&peers)[2], Peer& p, Input& in) {
  const auto& all = pipelines::available_pipelines();
  OpenSession m;
  const uint32_t which = in.below(static_cast<uint32_t>(all.size()) + 1);
  const pipelines::PipelineDescription* d = which < all.size() ? &all[which] : nullptr;
  m.pipeline = d ? d->name : "no-such-pipeline";
  m.width = in.byte() == 255 ? 100000 : 1 + in.below(9);
  m.height = 1 + in.below(5);
  m.output_format = in.flag() ? Format::F16 : Format::F32;
  const uint64_t optional_mask = d ? d->optional_channels & in.u64() : 0;
  uint64_t mask = (d ? d->required_channels : 1) | optional_mask;
  if (in.flag()) mask |= channel_bit(ChannelId::Radiance);  // what "radiance, or the split form" pipelines need
  const uint8_t formats = in.byte();
  for (uint32_t id = 0; id < 64; ++id)
    if (mask >> id & 1)
      m.channels.push_back({static_cast<ChannelId>(id), (formats >> (id % 8)) & 1 ? Format::F16 : Format::F32});
  switch (in.below(6)) {  // a mutation of the channel list
    case 0: if (!m.channels.empty()) m.channels.erase(m.channels.begin() + in.below(m.channels.size())); break;
    case 1: if (!m.channels.empty()) m.channels.push_back(m.channels[in.below(m.channels.size())]); break;
    case 2: m.channels.push_back({static_cast<ChannelId>(in.byte()), Format::F32}); break;
    default: break;
  }
  if (d && !d->parameters.empty() && in.flag()) {
    const auto& info = d->parameters[in.below(d->parameters.size())];
    m.parameters.push_back({info.name, edge_value(in, info)});
  }
  send(peers, p, m, Pending{MessageType::OpenSession}, in.flag() ? kFlagShareInput : 0);
}

// Fills a plane: zeros, ones, NaN, Inf, huge values or input bytes.
void fill_plane(std::vector<uint8_t>& bytes, Format f, uint8_t pattern, Input& in) {
  const float values[] = {0.0f, 1.0f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                          -3.4e38f, 1e-42f};
  if (pattern % 7 == 6) {
    for (auto& b : bytes) b = in.byte();
    return;
  }
  const float v = values[pattern % 7];
  if (f == Format::F32) {
    for (size_t i = 0; i + 4 <= bytes.size(); i += 4) std::memcpy(&bytes[i], &v, 4);
  } else {
    const uint16_t hv = float_to_half(v);
    for (size_t i = 0; i + 2 <= bytes.size(); i += 2) std::memcpy(&bytes[i], &hv, 2);
  }
}

void send_frames(Peer (&peers)[2], Peer& p, Input& in) {
  const uint32_t pick = in.below(static_cast<uint32_t>(p.sessions.size()) + 1);
  KnownSession fallback{in.u64() % 64, "", 2, 2, Format::F32, {{ChannelId::Radiance, Format::F32}}, 0};
  KnownSession& s = pick < p.sessions.size() ? p.sessions[pick] : fallback;
  const uint32_t burst = 1 + in.below(5);
  for (uint32_t f = 0; f < burst; ++f) {
    const uint8_t how = in.byte();
    std::vector<std::vector<uint8_t>> storage;
    storage.reserve(s.channels.size() + 1);
    Frame frame;
    frame.info.session_id = s.id;
    frame.info.frame_index = how % 8 == 0 ? in.u64() : how % 8 == 1 && s.next_index ? s.next_index - 1 : s.next_index;
    frame.info.flags = how & 0x10 ? kFrameReset : 0;
    frame.info.motion = static_cast<MotionConvention>(in.below(3));
    for (const ChannelDecl& c : s.channels) {
      const ChannelInfo* info = find_channel(c.id);
      storage.emplace_back(info ? plane_bytes(*info, c.format, s.width, s.height) : 4, uint8_t{0});
      fill_plane(storage.back(), c.format, in.byte(), in);
      frame.planes.push_back({c.id, c.format, storage.back()});
    }
    switch (how >> 5) {  // a mutation of the planes
      case 1: if (!frame.planes.empty()) frame.planes.pop_back(); break;
      case 2: if (!storage.empty()) { storage.back().resize(storage.back().size() / 2); frame.planes.back().bytes = storage.back(); } break;
      case 3: if (!frame.planes.empty()) frame.planes.back().format = frame.planes.back().format == Format::F16 ? Format::F32 : Format::F16; break;
      case 4: if (!frame.planes.empty()) frame.planes.push_back(frame.planes.front()); break;
      default: break;
    }
    const bool no_output = how & 0x08;
    s.next_index = std::max(s.next_index, frame.info.frame_index + 1);
    send(peers, p, frame, Pending{MessageType::Frame, s.id, frame.info.frame_index, !no_output, s.width, s.height, s.output_format},
         no_output ? kFlagNoOutput : 0);
  }
}

void attach(Peer (&peers)[2], Peer& p, Input& in) {
  Peer& owner = peers[in.flag()];
  Attach m;
  const uint32_t pick = in.below(static_cast<uint32_t>(owner.sessions.size()) + 1);
  m.session_id = pick < owner.sessions.size() ? owner.sessions[pick].id : in.u64() % 64;
  switch (in.below(3)) {
    case 0: if (pick < owner.sessions.size()) m.watch_key = owner.sessions[pick].key; break;
    case 1: m.watch_key = std::string(kWatchKeyLength, 'a'); break;
    default: break;
  }
  send(peers, p, m, Pending{MessageType::Attach});
}

void step(Peer (&peers)[2], Input& in) {
  const uint8_t op = in.byte();
  Peer& p = peers[op & 1];
  if (!p.live()) return;
  switch ((op >> 1) % 12) {
    case 0: {
      Hello m{0, "fuzz", in.flag() ? "not-the-token" : ""};
      std::vector<uint8_t> bytes = encode(m, p.next_request, 0);
      bytes[5] = static_cast<uint8_t>(in.below(9));  // the client's minor version
      if (!p.minor) p.minor = bytes[5];
      p.pending.emplace(p.next_request++, Pending{MessageType::Hello});
      write_all(peers, p, bytes);
      break;
    }
    case 1: open_session(peers, p, in); break;
    case 2: send_frames(peers, p, in); break;
    case 3: attach(peers, p, in); break;
    case 4: {
      const uint32_t pick = in.below(static_cast<uint32_t>(p.sessions.size()) + 1);
      send(peers, p, CloseSession{pick < p.sessions.size() ? p.sessions[pick].id : in.u64() % 64},
           Pending{MessageType::CloseSession});
      break;
    }
    case 5: send(peers, p, StatsRequest{}, Pending{MessageType::StatsRequest}); break;
    case 6: send(peers, p, Ping{in.u64()}, Pending{MessageType::Ping}); break;
    case 7: send(peers, p, Pong{in.u64()}, std::nullopt); break;
    case 8: send(peers, p, SessionClosed{in.u64(), 0}, Pending{MessageType::SessionClosed}); break;
    case 9: p.in_step = false; write_all(peers, p, in.bytes(in.below(48))); break;
    case 10: {  // a header declaring more payload than follows
      std::vector<uint8_t> bytes = encode(Ping{1}, p.next_request++, 0);
      const uint32_t declared = 8 + in.below(4096);
      std::memcpy(&bytes[12], &declared, 4);
      p.in_step = false;
      write_all(peers, p, bytes);
      break;
    }
    default:
      ::shutdown(p.fd, SHUT_WR);
      p.write_shut = true;
      p.in_step = false;  // the server answers what it has, then may close
      break;
  }
  settle(peers);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Harness& h = harness();
  Peer peers[2];
  for (Peer& p : peers) {
    int fds[2];
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, fds) != 0) violated("socketpair failed");
    p.fd = fds[1];
    h.server->adopt(fds[0]);
  }
  Input in(data, size);
  for (int steps = 0; !in.empty() && steps < 64; ++steps) step(peers, in);
  for (Peer& p : peers) ::close(p.fd);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (h.server->connection_count() > 0 || h.server->session_count() > 0 || !h.server->quiescent()) {
    turn(*h.server);
    if (std::chrono::steady_clock::now() > deadline)
      violated(std::to_string(h.server->connection_count()) + " connections and " +
               std::to_string(h.server->session_count()) + " sessions outlived their clients");
  }
  return 0;
}
