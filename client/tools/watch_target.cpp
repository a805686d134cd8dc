#include "watch_target.hpp"

#include <charconv>
#include <cstdlib>

#include "dn/protocol/messages.hpp"

namespace dn::cli {

Args::Spec session_option() {
  return {"session", "", true, false, "id of the session to watch (printed by dn denoise and dnrender --server)", "ID"};
}

Args::Spec watch_key_option() {
  return {"key", "", true, false, "the session's watch key (default $DN_WATCH_KEY; printed with the id)", "KEY"};
}

WatchTarget watch_target(const Args& args) {
  WatchTarget t;
  // Session ids are random 64-bit numbers: parse the full unsigned range.
  const auto session_text = args.get("session");
  if (!session_text) throw UsageError("missing required option --session");
  const char* b = session_text->data();
  const char* e = b + session_text->size();
  auto [ptr, ec] = std::from_chars(b, e, t.session_id);
  if (ec != std::errc() || ptr != e || t.session_id == 0)
    throw UsageError("--session: expected a session id (1 to 18446744073709551615), got '" + *session_text + "'");
  // The key is the capability to watch (protocol 1.6); from the environment so
  // that it need not appear in a process listing.
  t.key = args.get_or("key", "");
  if (t.key.empty())
    if (const char* env = std::getenv("DN_WATCH_KEY"); env) t.key = env;
  if (t.key.empty())
    throw UsageError("missing --key KEY (or set DN_WATCH_KEY): the session's watch key, printed with its id");
  if (!protocol::is_well_formed_watch_key(t.key))
    throw UsageError("--key: expected the session's watch key, " + std::to_string(protocol::kWatchKeyLength) +
                     " lowercase hex digits, got '" + t.key + "' (" + std::to_string(t.key.size()) + " characters)");
  return t;
}

}  // namespace dn::cli
