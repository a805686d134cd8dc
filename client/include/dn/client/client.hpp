// dn::client — the C++ client of dnserver. See docs/client.md.
//
//   auto conn = dn::client::Connection::connect("unix:///run/dn.sock");
//   auto session = conn.open_session(dn::client::SessionDesc{1920, 1080, "svgf"}
//                                        .channel(ChannelId::Radiance) ...);
//   dn::client::FrameInput in;
//   in.add(ChannelId::Radiance, radiance_span) ...;
//   dn::client::Result out = session.denoise(in);
#pragma once

#include "dn/client/capacity.hpp"
#include "dn/client/connection.hpp"
#include "dn/client/endpoint.hpp"
#include "dn/client/error.hpp"
#include "dn/client/options.hpp"
#include "dn/client/parameters.hpp"
#include "dn/client/reconnecting_session.hpp"
#include "dn/client/session.hpp"
#include "dn/client/session_desc.hpp"
#include "dn/client/watcher.hpp"
#include "dn/protocol/channels.hpp"
#include "dn/protocol/messages.hpp"

namespace dn::client {

inline constexpr const char* kClientVersion = "0.1.0";

}  // namespace dn::client
