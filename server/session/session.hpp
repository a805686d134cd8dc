// A session: one camera stream's configuration, its pipeline (and with it
// the device history), and the queue of frames waiting for the device.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "dn/protocol/messages.hpp"
#include "server/pipelines/pipeline.hpp"

namespace dn::server {

// A validated frame on its way to the device; `frame` views into `payload`.
// What one recipient's RESULT holds besides the output: the noisy radiance
// (a watcher of a SHARE_INPUT session, 1.7) and the sample counts (1.9),
// as far as its protocol knows them. index() numbers the four forms.
struct ResultForm {
  bool input = false;
  bool samples = false;
  size_t index() const { return (input ? 2 : 0) + (samples ? 1 : 0); }
};

struct FrameJob {
  uint64_t request_id = 0;
  bool owner_wants_output = true;
  bool owner_gets_samples = false;          // the owner's protocol is >= 1.9
  std::array<bool, 4> watcher_forms = {};   // by ResultForm::index(): some watcher wants that form
  protocol::Frame frame;
  std::vector<uint8_t> payload;
};

// What a worker hands back to the event loop for one frame.
struct FrameDone {
  uint64_t session_id = 0;
  uint64_t request_id = 0;
  uint64_t frame_index = 0;
  std::shared_ptr<const std::vector<uint8_t>> owner_message;  // encoded RESULT or ERROR
  // Encoded RESULTs with the output, by ResultForm::index(), where wanted.
  std::array<std::shared_ptr<const std::vector<uint8_t>>, 4> watcher_messages;
  std::vector<protocol::PassTiming> timings;
  bool failed = false;
};

// Bytes of one FRAME of a session: its planes plus generous room for the
// fixed fields (the session's message limit and the --max-message check).
uint64_t frame_message_bytes(const pipelines::SessionConfig& config);

class Session {
 public:
  Session(uint64_t id, uint64_t owner, pipelines::SessionConfig config, std::unique_ptr<pipelines::Pipeline> pipeline,
          std::string watch_key);
  ~Session();

  uint64_t id() const { return id_; }
  uint64_t owner() const { return owner_; }
  // What ATTACH must present (protocol 1.6); given to the owner in SESSION.
  const std::string& watch_key() const { return watch_key_; }
  const pipelines::SessionConfig& config() const { return config_; }
  // Device memory the session needs per frame; of which transient_bytes() is
  // scratch leased from the device's pool only while one of its frames runs.
  uint64_t device_bytes() const { return device_bytes_; }
  uint64_t transient_bytes() const { return transient_bytes_; }

  // Checks a decoded FRAME against this session: declared channels present
  // exactly once, in the declared format, with the right byte length, and a
  // frame index above the last one accepted.
  std::optional<protocol::Error> check_frame(const protocol::Frame& frame) const;

  // Runs the next pending frame on the device; called by one worker at a time.
  FrameDone run(FrameJob& job);

  // Event-loop state (touched only by the loop thread).
  std::optional<uint64_t> last_frame_index;
  uint32_t in_flight = 0;
  uint64_t frames_processed = 0;
  bool closing = false;
  uint64_t close_request_id = 0;
  std::vector<uint64_t> watchers;  // connection ids
  bool share_input = false;        // the owner's SHARE_INPUT: watchers at 1.7 also get the noisy radiance

  // Scheduler state (guarded by mutex).
  std::mutex mutex;
  std::deque<FrameJob> pending;
  bool scheduled = false;
  std::atomic<bool> cancelled{false};

 private:
  uint64_t id_;
  uint64_t owner_;
  std::string watch_key_;
  pipelines::SessionConfig config_;
  std::unique_ptr<pipelines::Pipeline> pipeline_;
  uint64_t device_bytes_;
  uint64_t transient_bytes_;
};

}  // namespace dn::server
