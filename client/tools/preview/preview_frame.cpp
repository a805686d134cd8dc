#include "preview_frame.hpp"

#include <cstdio>
#include <cstring>

namespace dn::cli {

namespace {

// JSON string literal; names come from the server, so escape everything JSON requires.
std::string json_string(std::string_view s) {
  std::string out = "\"";
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (u < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", u);
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string json_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4f", v);
  return buf;
}

void append_rgba8(std::vector<uint8_t>& out, const std::vector<float>& rgb, size_t pixels, const PreviewContext& ctx) {
  const std::vector<uint8_t> srgb = image::to_srgb8(rgb.data(), pixels, ctx.tonemap, ctx.exposure);
  const size_t at = out.size();
  out.resize(at + pixels * 4);
  for (size_t i = 0; i < pixels; ++i) {
    std::memcpy(&out[at + i * 4], &srgb[i * 3], 3);
    out[at + i * 4 + 3] = 255;
  }
}

}  // namespace

std::string preview_header_json(const client::Result& r, const PreviewContext& ctx) {
  std::string j = "{\"session\":\"" + std::to_string(ctx.session_id) + "\"";  // a string: ids exceed 2^53
  j += ",\"frame_index\":" + std::to_string(r.frame_index);
  j += ",\"width\":" + std::to_string(r.width) + ",\"height\":" + std::to_string(r.height);
  j += ",\"pipeline\":" + json_string(ctx.pipeline);
  j += ",\"tonemap\":" + json_string(image::to_string(ctx.tonemap));
  j += ",\"exposure\":" + json_number(ctx.exposure);
  j += ",\"dropped\":" + std::to_string(ctx.dropped);
  j += ",\"total_ms\":" + json_number(r.total_timing_ms());
  j += ",\"timings\":[";
  for (size_t i = 0; i < r.timings.size(); ++i) {
    if (i) j += ",";
    j += "{\"name\":" + json_string(r.timings[i].name) + ",\"ms\":" + json_number(r.timings[i].milliseconds) + "}";
  }
  j += "],\"has_input\":";
  j += r.has_input() ? "true" : "false";
  // Input frames the output rests on (protocol 1.9); null from an older server or a pipeline without a count.
  j += ",\"samples\":";
  j += r.samples ? "{\"min\":" + std::to_string(r.samples->min) + ",\"median\":" + std::to_string(r.samples->median) + "}"
                 : std::string("null");
  return j + "}";
}

namespace {

std::vector<uint8_t> with_length(const std::string& json) {
  std::vector<uint8_t> out(4 + json.size());
  const auto n = static_cast<uint32_t>(json.size());
  for (int b = 0; b < 4; ++b) out[b] = uint8_t(n >> (8 * b));
  std::memcpy(out.data() + 4, json.data(), json.size());
  return out;
}

}  // namespace

std::vector<uint8_t> encode_preview_status(const std::string& status, uint64_t session_id, const std::string& detail) {
  return with_length("{\"status\":" + json_string(status) + ",\"session\":\"" + std::to_string(session_id) +
                     "\",\"detail\":" + json_string(detail) + "}");
}

std::vector<uint8_t> encode_preview_frame(const client::Result& r, const PreviewContext& ctx) {
  const std::string json = preview_header_json(r, ctx);
  const size_t pixels = size_t(r.width) * r.height;
  std::vector<uint8_t> out = with_length(json);
  out.reserve(out.size() + pixels * 4 * (r.has_input() ? 2 : 1));
  append_rgba8(out, r.rgb(), pixels, ctx);
  if (r.has_input()) append_rgba8(out, r.input_rgb(), pixels, ctx);
  return out;
}

}  // namespace dn::cli
