#include "watch_target.hpp"

#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "commands.hpp"
#include "dn/protocol/messages.hpp"

namespace dn::cli {

std::vector<Args::Spec> watch_specs(std::vector<Args::Spec> own) {
  std::vector<Args::Spec> specs = {
      server_option(),
      {"session", "", true, false,
       "id of the session to watch (printed by dn denoise and dnrender --server; default: the one the key file names)",
       "ID"},
      {"key-file", "", true, false,
       "file holding the watch key (and the session id), mode 0600: the owner's --watch-key-file", "FILE"},
      {"key", "", true, false,
       "the session's watch key; visible to every local user in the process list: prefer $DN_WATCH_KEY or --key-file",
       "KEY"},
  };
  specs.insert(specs.end(), own.begin(), own.end());
  specs.insert(specs.end(), {
      {"token-file", "", true, false, "file holding the server's auth token", "FILE"},
      {"tonemap", "", true, false, "tone map for PNGs and the preview page: aces | reinhard | clamp (default aces)",
       "OP"},
      {"exposure", "", true, false, "exposure multiplier before tone mapping (default 1)", "X"},
      {"timeout", "", true, false, "seconds to wait for the next frame (default 600); longer is an error", "SECONDS"},
      {"quiet", "-q", false, false, "no per-frame output", ""},
      {"help", "-h", false, false, "this help", ""},
  });
  return specs;
}

client::WatchFile read_key_file(const std::string& path) {
  try {
    return client::read_watch_file(path);
  } catch (const client::Error& e) {
    throw UsageError("--key-file: " + e.server_message());
  }
}

WatchTarget watch_target(const Args& args, const char* command, bool session_optional) {
  WatchTarget t;
  if (args.has("key") && args.has("key-file"))
    throw UsageError("give the watch key once: --key-file FILE or --key KEY, not both");
  // The key is the capability to watch (protocol 1.6): from a file or the
  // environment, so that it need not appear in the process list.
  if (auto file = args.get("key-file")) {
    t.key_file = *file;
    // A caller that waits for a session (dn preview started first) waits for its file too.
    std::error_code ec;
    if (session_optional && !args.has("session") && !std::filesystem::exists(*file, ec)) return t;
    const client::WatchFile f = read_key_file(*file);
    t.key = f.key;
    t.session_id = f.session_id;
  } else if (auto key = args.get("key")) {
    t.key = *key;
    std::fprintf(stderr,
                 "dn %s: warning: --key puts the watch key in the process list, where every local user can read it "
                 "(ps, /proc/PID/cmdline); pass it in DN_WATCH_KEY or a --key-file instead\n",
                 command);
  } else if (const char* env = std::getenv("DN_WATCH_KEY"); env) {
    t.key = env;
  }
  if (t.key.empty())
    throw UsageError(
        "missing the watch key: set DN_WATCH_KEY or give --key-file FILE (both printed with the session's id)");
  if (!protocol::is_well_formed_watch_key(t.key))
    throw UsageError(std::string(args.has("key") ? "--key" : "DN_WATCH_KEY") +
                     ": expected the session's watch key, " + std::to_string(protocol::kWatchKeyLength) +
                     " lowercase hex digits, got '" + t.key + "' (" + std::to_string(t.key.size()) + " characters)");
  // Session ids are random 64-bit numbers: parse the full unsigned range.
  if (const auto session_text = args.get("session")) {
    const char* b = session_text->data();
    const char* e = b + session_text->size();
    auto [ptr, ec] = std::from_chars(b, e, t.session_id);
    if (ec != std::errc() || ptr != e || t.session_id == 0)
      throw UsageError("--session: expected a session id (1 to 18446744073709551615), got '" + *session_text + "'");
  }
  if (t.session_id == 0 && !session_optional)
    throw UsageError(t.key_file.empty() ? "missing required option --session"
                                        : "missing --session: the key file " + t.key_file + " names no session");
  return t;
}

Display display_options(const Args& args) {
  Display d;
  try {
    d.tonemap = image::parse_tonemap(args.get_or("tonemap", "aces"));
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--tonemap: ") + e.what());
  }
  d.exposure = float(args.get_double("exposure", 1.0));
  return d;
}

double watch_timeout_s(const Args& args) {
  return args.get_double("timeout", 600.0, kMinTimeoutSeconds, kMaxTimeoutSeconds);
}

Attached attach(const Args& args, const WatchTarget& target, const char* client_name, double timeout_s) {
  client::ConnectOptions copts;
  copts.client_name = client_name;
  if (auto tf = args.get("token-file")) copts.token_file = *tf;
  copts.io_timeout = std::chrono::milliseconds(static_cast<long long>(timeout_s * 1000.0));
  client::Connection conn = client::Connection::connect(server_url(args.get_or("server", "")), copts);
  client::Watcher watcher = conn.attach(target.session_id, target.key);
  return {std::move(conn), std::move(watcher)};
}

bool ended_normally(const client::Watcher& watcher, bool quiet) {
  const auto& closed = watcher.closed();
  if (!closed) return false;
  if (!quiet)
    std::fprintf(stderr, "dn: session %llu ended normally after %llu frames\n", (unsigned long long)closed->session_id,
                 (unsigned long long)closed->frames_processed);
  return true;
}

}  // namespace dn::cli
