// What every watching command (dn watch, dn preview) shares: the session to
// attach to (--session ID; the key from $DN_WATCH_KEY, --key-file FILE or
// --key KEY), the connection options, the display options, and the normal end
// of a watch.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "args.hpp"
#include "dn/client/client.hpp"
#include "dn/client/watch_file.hpp"
#include "dn/image/metrics.hpp"

namespace dn::cli {

struct WatchTarget {
  uint64_t session_id = 0;  // 0: none yet (only where the caller allows it)
  std::string key;          // the session's watch key (protocol 1.6)
  std::string key_file;     // --key-file, as given: an owner rewrites it for each session
};

// --server, --session, --key-file, --key, then `own`, then --token-file,
// --tonemap, --exposure, --timeout, --quiet, --help.
std::vector<Args::Spec> watch_specs(std::vector<Args::Spec> own);

// --session (else the session the key file names) and the key, checked;
// UsageError naming the option otherwise. A key given with --key is visible
// to every local user (ps): `command` ("watch") warns about it on stderr.
// With `session_optional` and no --session, a key file that names no
// session, or is not there yet, is accepted (session_id 0).
WatchTarget watch_target(const Args& args, const char* command, bool session_optional = false);

// The key file read again (an owner rewrites it as it opens each session);
// UsageError naming it when it is unreadable, open to others or malformed.
client::WatchFile read_key_file(const std::string& path);

struct Display {
  image::Tonemap tonemap = image::Tonemap::Aces;
  float exposure = 1.0f;
};
Display display_options(const Args& args);  // --tonemap, --exposure

double watch_timeout_s(const Args& args);  // --timeout: the longest wait for a frame

// Connects (as `client_name`, --token-file, the timeout as io_timeout) and attaches.
struct Attached {
  client::Connection connection;
  client::Watcher watcher;
};
Attached attach(const Args& args, const WatchTarget& target, const char* client_name, double timeout_s);

// For the client::Error that next() threw: true when it was the session's
// normal end (SESSION_CLOSED), which is then reported unless `quiet`; false
// for anything else, which the caller rethrows.
bool ended_normally(const client::Watcher& watcher, bool quiet);

}  // namespace dn::cli
