// One frame's trip through the session service: the validated FRAME on its
// way to a worker, what the pipeline made of it, and the encoded replies the
// worker hands back to the event loop.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "dn/protocol/messages.hpp"
#include "session/frame_planes.hpp"

namespace dn::server {

// What one recipient's RESULT holds besides the output: the noisy radiance
// (a watcher of a SHARE_INPUT session, 1.7) and the sample counts (1.9),
// as far as its protocol knows them. index() numbers the four forms.
struct ResultForm {
  bool input = false;
  bool samples = false;
  size_t index() const { return (input ? 2 : 0) + (samples ? 1 : 0); }
};

// A validated frame; `frame` and `input` view into `payload`.
struct FrameJob {
  uint64_t request_id = 0;
  bool owner_wants_output = true;
  bool owner_gets_samples = false;          // the owner's protocol is >= 1.9
  std::array<bool, 4> watcher_forms = {};   // by ResultForm::index(): some watcher wants that form
  protocol::Frame frame;
  pipelines::FrameInput input;  // what the pipeline runs: the planes checked once
  std::vector<uint8_t> payload;

  bool anyone_wants_output() const;
};

// What the session's pipeline made of one frame.
struct FrameOutcome {
  std::vector<uint8_t> output;  // in the session's output format; empty when nobody wants it
  std::optional<pipelines::SampleCounts> samples;
  std::vector<pipelines::PassTiming> timings;
  std::optional<std::string> error;  // the device failed: why
};

// What a worker hands back to the event loop for one frame.
struct FrameDone {
  uint64_t session_id = 0;
  uint64_t request_id = 0;
  uint64_t frame_index = 0;
  std::shared_ptr<const std::vector<uint8_t>> owner_message;  // encoded RESULT or ERROR
  // Encoded RESULTs with the output, by ResultForm::index(), where wanted.
  std::array<std::shared_ptr<const std::vector<uint8_t>>, 4> watcher_messages;
  std::vector<pipelines::PassTiming> timings;
  bool failed = false;
};

// The replies to one frame: an ERROR to the owner when the device failed,
// else one RESULT per form its owner and watchers need (the owner's shares
// the bytes of a watcher's of the same form).
FrameDone encode_replies(uint64_t session_id, protocol::Format output_format, const FrameJob& job,
                         FrameOutcome&& outcome);

}  // namespace dn::server
