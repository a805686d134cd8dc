#include "channel_check.hpp"

#include <string>

#include "dn/client/error.hpp"

namespace dn::client::detail {

void check_channels(const protocol::Welcome& welcome, const SessionDesc& desc) {
  const protocol::PipelineInfo* info = nullptr;
  for (const auto& p : welcome.pipelines)
    if (p.name == desc.pipeline) info = &p;
  if (!info) return;
  const uint64_t takes = info->required_channels | info->optional_channels;
  for (size_t i = 0; i < desc.channels.size(); ++i) {
    const auto id = desc.channels[i].id;
    if (takes & protocol::channel_bit(id)) continue;
    std::string list;
    for (const auto& c : protocol::kChannels)
      if (takes & protocol::channel_bit(c.id)) list += (list.empty() ? "" : ", ") + std::string(c.name);
    const auto* c = protocol::find_channel(id);
    throw Error::usage(protocol::ErrorCode::InvalidChannel,
                       "OPEN_SESSION.channels[" + std::to_string(i) + "].id",
                       "pipeline '" + desc.pipeline + "' on this server does not take channel " +
                           (c ? std::string(c->name) : std::to_string(static_cast<int>(id))) + "; it takes: " + list);
  }
}

}  // namespace dn::client::detail
