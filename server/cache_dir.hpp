// Where dnserver keeps its on-disk caches (compiled pipelines): the user's
// cache directory by default, created and checked so that no other local user
// can plant or read a file there.
#pragma once

#include <string>

#include "server/options.hpp"

namespace dn::server {

// $XDG_CACHE_HOME/dnserver if that is an absolute path, else $HOME/.cache/dnserver;
// "" when neither is set.
std::string default_cache_dir();

// Creates `dir` (and missing parents) with mode 0700 and checks the result: a
// real directory (not a symlink), owned by this user, not writable by group
// or others. Returns "" when usable, else the reason.
std::string prepare_cache_dir(const std::string& dir);

// The directory the pipeline cache uses under these options ("" = memory
// only): --no-disk-cache gives "", an unusable --cache-dir throws
// std::runtime_error with the reason, an unusable default is logged and
// skipped (the server still runs).
std::string resolve_cache_dir(const ServerOptions& options);

}  // namespace dn::server
