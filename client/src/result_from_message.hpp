// Internal: turns a received RESULT into the library's Result, checking the
// output plane's size against the session. Shared by Session and Watcher.
#pragma once

#include <string>

#include "connection_state.hpp"
#include "dn/client/session.hpp"

namespace dn::client::detail {

// `in` must hold a protocol::Result; its payload moves into the Result's storage.
Result result_from_message(Incoming&& in, const protocol::Session& info, const std::string& endpoint);

}  // namespace dn::client::detail
