#include "result_from_message.hpp"

#include "dn/client/error.hpp"

namespace dn::client::detail {

Result result_from_message(Incoming&& in, const protocol::Session& info, const std::string& endpoint) {
  auto& r = std::get<protocol::Result>(in.message);
  Result out;
  out.session_id = r.session_id;
  out.frame_index = r.frame_index;
  out.width = info.width;
  out.height = info.height;
  out.format = info.output_format;
  out.timings = std::move(r.timings);
  if (r.samples && r.samples->counted) out.samples = r.samples;
  for (size_t i = 0; i < r.planes.size(); ++i) {
    const auto& p = r.planes[i];
    // Output, and the noisy radiance on a watcher's copy when the owner shares it (1.7).
    if (p.id != protocol::ChannelId::Output && p.id != protocol::ChannelId::Radiance) continue;
    const uint64_t expected = uint64_t(info.width) * info.height * 3 * protocol::bytes_per_component(p.format);
    if (p.bytes.size() != expected)
      throw Error::protocol_error(endpoint, protocol::ErrorCode::InvalidChannel,
                                  "RESULT.planes[" + std::to_string(i) + "].byte_length",
                                  std::string(p.id == protocol::ChannelId::Output ? "output" : "radiance") +
                                      " plane has " + std::to_string(p.bytes.size()) + " bytes, expected " +
                                      std::to_string(expected));
    if (p.id == protocol::ChannelId::Output) {
      out.format = p.format;
      out.output = p.bytes;
    } else {
      out.input_format = p.format;
      out.input = p.bytes;
    }
  }
  out.storage = std::move(in.payload);
  return out;
}

}  // namespace dn::client::detail
