// Watch keys (protocol 1.6): the capability to ATTACH to a session. Whoever
// holds a session's key may watch it; the id alone is not a secret.
#pragma once

#include <string>
#include <string_view>

namespace dn::server {

// 128 bits from getrandom(2) as protocol::kWatchKeyLength lowercase hex
// digits. Throws std::runtime_error when the kernel gives no randomness: a
// guessable key would be worse than no session.
std::string new_watch_key();

// Constant-time comparison against the session's key; an empty `presented`
// never matches.
bool watch_key_matches(const std::string& expected, std::string_view presented);

}  // namespace dn::server
