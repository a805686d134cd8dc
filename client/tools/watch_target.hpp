// The session a watching command attaches to: --session ID and --key KEY
// (default $DN_WATCH_KEY), shared by dn watch and dn preview.
#pragma once

#include <cstdint>
#include <string>

#include "args.hpp"

namespace dn::cli {

struct WatchTarget {
  uint64_t session_id = 0;
  std::string key;  // the session's watch key (protocol 1.6)
};

// The two option specs, in the order they appear in --help.
Args::Spec session_option();
Args::Spec watch_key_option();

// Parses and checks both; UsageError naming the option otherwise.
WatchTarget watch_target(const Args& args);

}  // namespace dn::cli
