// The server's counters and the STATS reply built from them
// (docs/server.md lists every value).
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "dn/protocol/messages.hpp"
#include "server/capacity/frame_times.hpp"
#include "server/pipelines/registry.hpp"
#include "server/session/pipeline_builder.hpp"

namespace dn::gpu {
class Context;
}

namespace dn::server {

struct ServerCounters {
  std::chrono::steady_clock::time_point started = std::chrono::steady_clock::now();
  uint64_t frames_processed = 0;
  uint64_t frames_failed = 0;
  uint64_t sessions_opened = 0;
  uint64_t connections_accepted = 0;
  uint64_t bytes_in_closed = 0;  // from connections already closed
  uint64_t bytes_out_closed = 0;

  struct TimingSum {
    double total_ms = 0;
    uint64_t count = 0;
  };
  std::map<std::string, TimingSum> pass_timings;
  FrameTimes frame_times;  // per pipeline, for the capacity figures

  // OPEN_SESSION builds (successful or not), off the event loop.
  struct Builds {
    uint64_t count = 0;
    double total_ms = 0, max_ms = 0, last_ms = 0;
    double compile_ms = 0;  // of total_ms, compiling kernels
    double first_run_ms = 0;  // of total_ms, frames on a private device (PipelineBuilder::run_off_queue)
  } builds;

  void add_frame_timings(const std::vector<pipelines::PassTiming>& timings);
  void add_build(const BuiltPipeline& built);
};

// What STATS reports besides the counters: the live state, gathered by the server.
struct LiveState {
  uint64_t connections = 0;
  uint64_t bytes_in_open = 0, bytes_out_open = 0;  // of open connections
  uint64_t sessions = 0;
  uint64_t sessions_being_built = 0;
  uint64_t frames_in_flight = 0;
  uint64_t device_bytes = 0;      // every open session's device_bytes()
  uint64_t transient_bytes = 0;   // of which scratch leased per frame
  struct SessionFigures {
    uint64_t id = 0, frames = 0;
    double persistent_per_pixel = 0, transient_per_pixel = 0;
  };
  std::vector<SessionFigures> sessions_figures;
  // Capacity (docs/server.md "Capacity").
  uint64_t device_budget_bytes = 0;       // what all sessions together may need
  uint64_t being_built_bytes = 0;         // estimates of the sessions being built
  uint64_t max_sessions = 0, max_session_bytes = 0;
  std::optional<WarmUpReport> warm_up;                         // once it finished
  std::vector<pipelines::SharedResourceTiming> shared_resources;  // made at start-up
};

protocol::Stats make_stats(const ServerCounters& counters, const LiveState& live, gpu::Context& device);

}  // namespace dn::server
