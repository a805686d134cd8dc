// How many more sessions of one size and pipeline a server can take, from its
// STATS (docs/server.md "Capacity"): the one place a placer's arithmetic lives.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

#include "dn/protocol/messages.hpp"

namespace dn::client {

struct Capacity {
  uint64_t session_bytes = 0;       // device bytes one such session needs (the pipeline's model, rounded up)
  uint64_t by_memory = 0;           // device_memory_free_bytes / session_bytes (0 above max_session_bytes)
  uint64_t by_session_limit = 0;    // max_sessions - sessions - sessions_being_built
  std::optional<double> frame_ms;   // predicted device time per frame; none until the pipeline was measured
  std::optional<uint64_t> by_time;  // (1 - device_busy_fraction) / (fps * frame_ms / 1000); with fps > 0 and frame_ms
  uint64_t sessions = 0;            // the smallest of the bounds above: what fits
};

// Evaluates the STATS figures for `width` x `height` sessions of `pipeline` at
// `fps` frames per second (0: no frame-time bound). Throws Error (Usage) when
// the width, height or fps is invalid or STATS lacks a figure it needs (a
// server older than the capacity figures, or a pipeline it does not offer).
Capacity capacity(const protocol::Stats& stats, std::string_view pipeline, uint32_t width, uint32_t height,
                  double fps = 0);

}  // namespace dn::client
