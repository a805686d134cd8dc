// Frames: the images packed into a client::FrameInput with the filter's
// camera and flags, sent on its session; results written to the output image.
#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "handles.hpp"

namespace dn::capi {
namespace {

// The filter's session, opened by its last successful dnCommitFilter.
client::Session& open_session(DNFilterImpl& f) {
  if (!f.session)
    throw CError{DN_ERROR_INVALID_OPERATION,
                 "the filter has no session: set its images, then call dnCommitFilter (and check its error)"};
  return *f.session;
}

// The same, provided nothing that needs a new one changed since
// dnCommitFilter (pointers and strides may change freely).
client::Session& committed_session(DNFilterImpl& f) {
  open_session(f);
  if (f.session_generation != f.device->generation)
    throw CError{DN_ERROR_INVALID_OPERATION,
                 "the device reconnected since dnCommitFilter and the session was lost with the old connection: "
                 "call dnCommitFilter again (the history starts anew)"};
  client::SessionDesc now;
  try {
    now = describe(f);
  } catch (const CError& e) {
    throw CError{DN_ERROR_INVALID_OPERATION, "the filter changed since dnCommitFilter: " + e.message};
  }
  if (!same_session(now, f.committed))
    throw CError{DN_ERROR_INVALID_OPERATION,
                 "the images (which, their formats or size) or parameters changed since dnCommitFilter: call "
                 "dnCommitFilter again"};
  return *f.session;
}

client::FrameInput frame_input(DNFilterImpl& f) {
  client::FrameInput in;
  in.info.view = f.view;
  in.info.projection = f.projection;
  in.info.jitter = f.jitter;
  in.info.motion = f.motion;
  in.reset(f.reset_next);
  f.scratch.resize(f.inputs.size());
  size_t i = 0;
  for (const auto& [id, image] : f.inputs) {
    const std::span<const uint8_t> bytes = packed_plane(image, f.scratch[i++]);
    in.add(id, wire_format(image.format), bytes.data(), bytes.size());
  }
  return in;
}

// Sends one frame; the reset flag is spent once it is sent.
void submit(DNFilterImpl& f, client::Session& session) {
  session.submit(frame_input(f));
  f.reset_next = false;
}

std::string matrix_problem(const float* m, const char* what) {
  if (!m) return std::string(what) + " is NULL";
  for (int i = 0; i < 16; ++i)
    if (!std::isfinite(m[i])) return std::string(what) + "[" + std::to_string(i) + "] is not finite";
  return {};
}

}  // namespace

void sync_filter(DNFilterImpl& f, const char* where) {
  if (!f.session) {
    f.pending.clear();
    return;
  }
  while (!f.pending.empty()) {
    const Image out = f.pending.front();
    std::optional<client::Result> result;
    try {
      result = f.session->wait();
    } catch (const client::Error& e) {
      if (e.kind() != client::ErrorKind::Server) {
        f.pending.clear();  // the connection is gone: nothing more will arrive
        throw;
      }
      f.pending.pop_front();  // the server refused this frame; the session goes on
      record_error(f.device, where, error_code(e), e.what());
      continue;
    }
    f.pending.pop_front();
    f.samples = result->samples;
    try {
      write_output(*result, out);
    } catch (...) {
      auto [code, message] = describe_current_exception();
      record_error(f.device, where, code, message);
    }
  }
}

}  // namespace dn::capi

using namespace dn;
using namespace dn::capi;

extern "C" {

DN_API void dnExecuteFilter(DNFilter filter) {
  guarded_filter_void(filter, "dnExecuteFilter", [&](DNFilterImpl& f) {
    sync_filter(f, "dnExecuteFilter");
    client::Session& session = committed_session(f);
    submit(f, session);
    const client::Result result = session.wait();
    f.samples = result.samples;
    write_output(result, *f.output);
  });
}

DN_API bool dnGetFilterSamples(DNFilter filter, uint32_t* outMin, uint32_t* outMedian) {
  return guarded_filter(filter, "dnGetFilterSamples", false, [&](DNFilterImpl& f) {
    if (outMin) *outMin = f.samples ? f.samples->min : 0;
    if (outMedian) *outMedian = f.samples ? f.samples->median : 0;
    return f.samples.has_value();
  });
}

DN_API void dnExecuteFilterAsync(DNFilter filter) {
  guarded_filter_void(filter, "dnExecuteFilterAsync", [&](DNFilterImpl& f) {
    client::Session& session = committed_session(f);
    submit(f, session);
    f.pending.push_back(*f.output);
  });
}

DN_API void dnSyncFilter(DNFilter filter) {
  guarded_filter_void(filter, "dnSyncFilter", [&](DNFilterImpl& f) { sync_filter(f, "dnSyncFilter"); });
}

DN_API void dnSetFilterCamera(DNFilter filter, const float view[16], const float projection[16],
                              const float jitter[2]) {
  guarded_filter_void(filter, "dnSetFilterCamera", [&](DNFilterImpl& f) {
    for (const std::string& problem : {matrix_problem(view, "view"), matrix_problem(projection, "projection")})
      if (!problem.empty()) throw CError{DN_ERROR_INVALID_ARGUMENT, problem};
    if (jitter && !(std::isfinite(jitter[0]) && std::isfinite(jitter[1])))
      throw CError{DN_ERROR_INVALID_ARGUMENT, "jitter is not finite"};
    std::copy(view, view + 16, f.view.begin());
    std::copy(projection, projection + 16, f.projection.begin());
    f.jitter = jitter ? std::array<float, 2>{jitter[0], jitter[1]} : std::array<float, 2>{0, 0};
  });
}

DN_API void dnResetFilterHistory(DNFilter filter) {
  guarded_filter_void(filter, "dnResetFilterHistory", [&](DNFilterImpl& f) { f.reset_next = true; });
}

DN_API uint64_t dnGetFilterSessionId(DNFilter filter) {
  return guarded_filter(filter, "dnGetFilterSessionId", uint64_t{0},
                        [&](DNFilterImpl& f) { return open_session(f).id(); });
}

DN_API const char* dnGetFilterWatchKey(DNFilter filter) {
  return guarded_filter(filter, "dnGetFilterWatchKey", static_cast<const char*>(nullptr),
                        [&](DNFilterImpl& f) -> const char* {
                          open_session(f);
                          return f.watch_key.c_str();
                        });
}

DN_API const char* dnGetFilterWatchCommand(DNFilter filter) {
  return guarded_filter(filter, "dnGetFilterWatchCommand", static_cast<const char*>(nullptr),
                        [&](DNFilterImpl& f) -> const char* {
                          open_session(f);
                          return f.watch_command.c_str();
                        });
}

DN_API const char* dnGetFilterPipeline(DNFilter filter) {
  return guarded_filter(filter, "dnGetFilterPipeline", static_cast<const char*>(nullptr),
                        [&](DNFilterImpl& f) -> const char* {
                          open_session(f);
                          return f.session ? f.session->info().pipeline.c_str() : "";
                        });
}

DN_API const char* dnGetFilterPipelineReason(DNFilter filter) {
  return guarded_filter(filter, "dnGetFilterPipelineReason", static_cast<const char*>(nullptr),
                        [&](DNFilterImpl& f) -> const char* {
                          open_session(f);
                          if (!f.session || !f.session->info().pipeline_reason) return "";
                          return f.session->info().pipeline_reason->c_str();
                        });
}

}  // extern "C"
