// Checks a session's declared channels against the server's WELCOME before
// OPEN_SESSION: a channel the pipeline does not list in its masks (for
// example a lighting-form channel sent to a server older than protocol 1.2,
// whose masks never list ids 12-14) fails here with the channels it takes.
#pragma once

#include "dn/client/session_desc.hpp"
#include "dn/protocol/messages.hpp"

namespace dn::client::detail {

// Throws Error::usage (INVALID_CHANNEL) naming the channel and what the
// pipeline takes; does nothing when WELCOME does not list the pipeline (the
// server answers UNKNOWN_PIPELINE then).
void check_channels(const protocol::Welcome& welcome, const SessionDesc& desc);

}  // namespace dn::client::detail
