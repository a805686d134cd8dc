// A session: one camera stream's configuration, its pipeline (and with it
// the device history), and its event-loop state.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "dn/protocol/messages.hpp"
#include "server/session/frame.hpp"
#include "server/pipelines/pipeline.hpp"

namespace dn::server {

// Bytes of one FRAME of a session: its planes plus generous room for the
// fixed fields (the session's message limit and the --max-message check).
uint64_t frame_message_bytes(const pipelines::SessionConfig& config);

class Session {
 public:
  Session(uint64_t id, uint64_t owner, const pipelines::PreparedPipeline& prepared,
          std::unique_ptr<pipelines::Pipeline> pipeline, std::string watch_key);
  ~Session();

  uint64_t id() const { return id_; }
  uint64_t owner() const { return owner_; }
  // What ATTACH must present (protocol 1.6); given to the owner in SESSION.
  const std::string& watch_key() const { return watch_key_; }
  // The pipeline's configuration (for "auto", the chosen pipeline and the channels it reads).
  const pipelines::SessionConfig& config() const { return config_; }
  // config() with the channels each FRAME carries: all the client declared.
  const pipelines::SessionConfig& frame_config() const { return frame_config_; }
  // For a session opened as "auto": why config().pipeline; empty otherwise.
  const std::string& choice_reason() const { return choice_reason_; }
  // Device memory the session needs per frame; of which transient_bytes() is
  // scratch leased from the device's pool only while one of its frames runs.
  uint64_t device_bytes() const { return device_bytes_; }
  uint64_t transient_bytes() const { return transient_bytes_; }

  // Checks a decoded FRAME against this session: declared channels present
  // exactly once, in the declared format, with the right byte length, and a
  // frame index above the last one accepted.
  std::variant<pipelines::FrameInput, protocol::Error> check_frame(const protocol::Frame& frame) const;

  // Runs a frame on the device; called by one worker at a time.
  FrameOutcome run(const FrameJob& job);

  // Event-loop state (touched only by the loop thread).
  std::optional<uint64_t> last_frame_index;
  uint32_t in_flight = 0;
  uint64_t frames_processed = 0;
  bool closing = false;
  uint64_t close_request_id = 0;
  std::vector<uint64_t> watchers;  // connection ids
  bool share_input = false;        // the owner's SHARE_INPUT: watchers at 1.7 also get the noisy radiance

 private:
  uint64_t id_;
  uint64_t owner_;
  std::string watch_key_;
  pipelines::SessionConfig config_;
  pipelines::SessionConfig frame_config_;
  std::string choice_reason_;
  std::unique_ptr<pipelines::Pipeline> pipeline_;
  uint64_t device_bytes_;
  uint64_t transient_bytes_;
};

}  // namespace dn::server
