#include "server/session/frame.hpp"

#include <algorithm>

#include "dn/protocol/codec.hpp"

namespace dn::server {
namespace {

std::shared_ptr<const std::vector<uint8_t>> encode_shared(const protocol::Message& m, uint64_t request_id) {
  auto bytes = std::make_shared<std::vector<uint8_t>>();
  protocol::encode(m, request_id, 0, *bytes);
  return bytes;
}

// RESULT.samples: counted false where the pipeline keeps no count.
protocol::SampleCounts result_samples(const std::optional<pipelines::SampleCounts>& samples) {
  if (!samples) return {};
  return protocol::SampleCounts{true, samples->min, samples->median};
}

}  // namespace

bool FrameJob::anyone_wants_output() const {
  return owner_wants_output || std::find(watcher_forms.begin(), watcher_forms.end(), true) != watcher_forms.end();
}

FrameDone encode_replies(uint64_t session_id, protocol::Format output_format, const FrameJob& job,
                         FrameOutcome&& outcome) {
  FrameDone done;
  done.session_id = session_id;
  done.request_id = job.request_id;
  done.frame_index = job.frame.info.frame_index;
  done.timings = std::move(outcome.timings);
  if (outcome.error) {
    done.failed = true;
    done.owner_message = encode_shared(
        protocol::Error{protocol::ErrorCode::DeviceError, "FRAME", "device failure: " + *outcome.error}, job.request_id);
    return done;
  }
  const protocol::PlaneView plane{protocol::ChannelId::Output, output_format,
                                  std::span<const uint8_t>(outcome.output.data(), outcome.output.size())};
  // One RESULT of the given form; the radiance plane is a view into the
  // FRAME's payload, alive until this returns.
  auto encode_form = [&](ResultForm form, bool with_output) {
    protocol::Result result;
    result.session_id = session_id;
    result.frame_index = job.frame.info.frame_index;
    for (const pipelines::PassTiming& t : done.timings) result.timings.push_back({t.name, t.milliseconds});
    if (with_output) result.planes = {plane};
    if (form.input)
      for (const protocol::PlaneView& p : job.frame.planes)
        if (p.id == protocol::ChannelId::Radiance) result.planes.push_back(p);
    if (form.samples) result.samples = result_samples(outcome.samples);
    return encode_shared(result, job.request_id);
  };
  for (size_t i = 0; i < job.watcher_forms.size(); ++i)
    if (job.watcher_forms[i]) done.watcher_messages[i] = encode_form(ResultForm{i >= 2, (i & 1) != 0}, true);
  const ResultForm owner{false, job.owner_gets_samples};
  if (job.owner_wants_output && done.watcher_messages[owner.index()])
    done.owner_message = done.watcher_messages[owner.index()];  // identical bytes: share them
  else
    done.owner_message = encode_form(owner, job.owner_wants_output);
  return done;
}

}  // namespace dn::server
