// What every watching command (dn watch, dn preview) shares: the session to
// attach to (--session ID, --key KEY or $DN_WATCH_KEY), the connection
// options, the display options, and the normal end of a watch.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "args.hpp"
#include "dn/client/client.hpp"
#include "dn/image/metrics.hpp"

namespace dn::cli {

struct WatchTarget {
  uint64_t session_id = 0;
  std::string key;  // the session's watch key (protocol 1.6)
};

// --server, --session, --key, then `own`, then --token-file, --tonemap,
// --exposure, --timeout, --quiet, --help.
std::vector<Args::Spec> watch_specs(std::vector<Args::Spec> own);

// --session and --key, checked; UsageError naming the option otherwise.
WatchTarget watch_target(const Args& args);

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
