// One frame as the preview page receives it over its WebSocket: a binary
// message holding a JSON header, then the tone-mapped denoised image, then
// (when the owner shares it) the tone-mapped noisy input, each RGBA8, rows
// top-first. Layout (little-endian):
//   u32 json_bytes | json | RGBA8 output (w*h*4) | RGBA8 input (w*h*4, if "has_input")
// A status message (what the preview is doing between frames) is the JSON
// alone, with a "status" field: u32 json_bytes | json.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "dn/client/session.hpp"
#include "dn/image/metrics.hpp"

namespace dn::cli {

struct PreviewContext {
  uint64_t session_id = 0;
  std::string pipeline;
  image::Tonemap tonemap = image::Tonemap::Aces;
  float exposure = 1.0f;
  uint64_t dropped = 0;  // frames the watcher skipped so far (latest-frame delivery)
};

// The JSON header alone (tests and the page read the same fields).
std::string preview_header_json(const client::Result& r, const PreviewContext& ctx);

// The whole binary message for one RESULT that carries an output plane.
std::vector<uint8_t> encode_preview_frame(const client::Result& r, const PreviewContext& ctx);

// "waiting" (for a session to open), "live" (frames of session_id follow) or
// "ended" (session_id closed after `frames` frames; the page keeps its last one).
// `detail` is a sentence the page shows as is.
std::vector<uint8_t> encode_preview_status(const std::string& status, uint64_t session_id, const std::string& detail);

}  // namespace dn::cli
