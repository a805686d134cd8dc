// One camera stream on the server: per-frame inputs in, denoised frames out.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "dn/client/error.hpp"
#include "dn/protocol/messages.hpp"

namespace dn::client {

namespace detail {
class ConnectionState;
struct Incoming;
}  // namespace detail

// One input plane: bytes owned by the caller, valid until submit()/denoise() returns.
struct Plane {
  protocol::ChannelId id = protocol::ChannelId::Radiance;
  protocol::Format format = protocol::Format::F32;
  std::span<const uint8_t> bytes;
};

struct FrameInput {
  // Camera matrices (unjittered, column-major like GLM), jitter in pixels,
  // flags (protocol::kFrameReset) and the motion-vector convention.
  // info.session_id is always set by the Session; info.frame_index is replaced
  // by `frame_index` below.
  protocol::FrameInfo info{};
  // Frame index sent to the server; must increase within a session. Default:
  // one more than the previous frame's (0 for the first).
  std::optional<uint64_t> frame_index;
  // true: info.prev_view/prev_projection/prev_jitter are taken from the
  // previous frame submitted on this session (for the first frame and after a
  // reset, from this frame). false: sent as given.
  bool fill_previous_camera = true;
  // FRAME flag kFlagNoOutput: the server processes the frame (history moves
  // on) but RESULT carries no output plane.
  bool no_output = false;
  std::vector<Plane> planes;

  FrameInput& add(protocol::ChannelId id, protocol::Format format, const void* data, size_t bytes) {
    planes.push_back({id, format, {static_cast<const uint8_t*>(data), bytes}});
    return *this;
  }
  FrameInput& add(protocol::ChannelId id, std::span<const float> f32) {
    return add(id, protocol::Format::F32, f32.data(), f32.size_bytes());
  }
  FrameInput& add_f16(protocol::ChannelId id, std::span<const uint16_t> half_bits) {
    return add(id, protocol::Format::F16, half_bits.data(), half_bits.size_bytes());
  }
  FrameInput& reset(bool on = true) {
    info.flags = on ? (info.flags | protocol::kFrameReset) : (info.flags & ~protocol::kFrameReset);
    return *this;
  }
};

struct Result {
  uint64_t session_id = 0;
  uint64_t frame_index = 0;
  uint32_t width = 0, height = 0;
  protocol::Format format = protocol::Format::F32;  // of `output`
  std::vector<protocol::PassTiming> timings;       // device passes and server stages, as the server names them
  std::span<const uint8_t> output;                 // RGB interleaved, rows top-first; empty for no_output frames
  // Client-side time from when submit() started sending the frame (after any
  // wait for window space) to the arrival of this RESULT; zero for Watcher results.
  std::chrono::duration<double, std::milli> latency{0};

  // A watcher's copy from a session whose owner shares its input (SessionDesc::
  // share_input, protocol 1.7): the frame's noisy radiance as the owner sent it,
  // RGB interleaved, rows top-first, in `input_format`. Empty otherwise.
  protocol::Format input_format = protocol::Format::F32;
  std::span<const uint8_t> input;
  // How many input frames the output rests on per pixel, over the frame: the
  // fewest and the median (protocol 1.9, RESULT.samples). Empty from an older
  // server and from pipelines that keep no history length.
  std::optional<protocol::SampleCounts> samples;
  bool has_output() const { return !output.empty(); }
  bool has_input() const { return !input.empty(); }
  std::vector<float> input_rgb() const;                       // input as float RGB (converted from fp16)
  double total_timing_ms() const;                             // sum of all timings
  std::optional<double> timing_ms(std::string_view name) const;  // one named timing
  std::vector<float> rgb() const;                             // output as float RGB (converted from fp16)
  void copy_rgb(std::span<float> dst) const;                  // dst.size() must be width*height*3

  std::shared_ptr<const std::vector<uint8_t>> storage;  // keeps `output` alive
};

class Session {
 public:
  Session(Session&&) noexcept;
  Session& operator=(Session&&) noexcept;
  // Closes the session on the server if still open (without waiting for the reply).
  ~Session();

  uint64_t id() const { return info_.session_id; }
  uint32_t width() const { return info_.width; }
  uint32_t height() const { return info_.height; }
  const protocol::Session& info() const { return info_; }  // the server's SESSION reply
  // The capability to watch this session (protocol 1.6): give it to whoever
  // should ATTACH (Connection::attach, `dn watch --key`). Empty from an older server.
  const std::string& watch_key() const;
  // Where watchers of this session connect (protocol 1.8, dnserver
  // --advertise-url: e.g. a balancer's port that reaches this backend);
  // empty when the server names none: then this connection's address.
  const std::string& watch_url() const;
  // The server address watchers use: watch_url(), else this connection's.
  std::string watch_server() const;
  // The `dn watch` command that watches this session, ready to paste into a
  // shell: "DN_WATCH_KEY=KEY dn watch --server URL --session ID" (the key in
  // dn's environment, not on its command line; none from an older server),
  // URL being watch_url() when the server gives one.
  std::string watch_command() const;
  uint32_t max_in_flight() const { return max_in_flight_; }
  // Submitted and not yet returned by wait()/poll() (answered or not).
  size_t in_flight() const { return outstanding_.size() + ready_.size(); }
  bool is_open() const { return open_; }

  // Synchronous: submit + wait. Throws Usage if pipelined frames are outstanding.
  Result denoise(const FrameInput& frame);

  // Pipelined: checks the planes against the session (declared channel,
  // format, byte size; the message size against the server's limit), then
  // sends the frame and returns its frame index. Blocks while max_in_flight()
  // frames are outstanding, collecting arrived results into an internal queue
  // (no extra threads). A plane whose format differs from the declared one is
  // converted (f32 <-> f16) on the way.
  uint64_t submit(const FrameInput& frame);
  // Next result in submission order; blocks until it arrives. A frame the
  // server rejected throws its Error here (the session stays usable).
  Result wait();
  // Next result in order if it has already arrived; never blocks.
  std::optional<Result> poll();

  // CLOSE_SESSION -> SESSION_CLOSED. Results not yet collected are discarded.
  protocol::SessionClosed close();

 private:
  friend class Connection;
  Session(std::shared_ptr<detail::ConnectionState> state, protocol::Session info, uint32_t max_in_flight);

  struct Outstanding {
    uint64_t request_id;
    uint64_t frame_index;
    bool no_output;
    std::chrono::steady_clock::time_point submitted;
  };
  struct Ready {
    std::optional<Result> result;
    std::optional<Error> error;
  };
  Result finish(const Outstanding& o, detail::Incoming&& in);
  Ready collect(const Outstanding& o, detail::Incoming&& in);
  Result take(Ready&& r);
  void check_usable() const;

  std::shared_ptr<detail::ConnectionState> state_;
  protocol::Session info_;
  uint32_t max_in_flight_ = 1;
  bool open_ = true;
  std::optional<uint64_t> last_frame_index_;
  protocol::Mat4 last_view_{}, last_projection_{};
  std::array<float, 2> last_jitter_{};
  std::deque<Outstanding> outstanding_;
  std::deque<Ready> ready_;
  std::vector<std::vector<uint8_t>> scratch_;  // format conversions
};

}  // namespace dn::client
