// Watch files: a session's watch key (and id) handed to watchers through a
// file only its user can read, never through a command line, which every
// local user can read in /proc/PID/cmdline (ps). An owner given a watch file
// rewrites it for each session it opens; `dn watch` / `dn preview --key-file`
// read it, and `dn preview` started first waits for the next session named there.
#pragma once

#include <cstdint>
#include <string>

namespace dn::client {

class Session;

// The file's text: the key on the first line, then "session ID" when an
// owner wrote it (a file the user writes by hand may hold the key alone).
struct WatchFile {
  std::string key;          // 32 lowercase hex digits
  uint64_t session_id = 0;  // 0: the file names no session
};

// Throws Error (Usage) naming `path` when it cannot be read, is readable or
// writable by group or others (the key is a secret), or holds no well-formed key.
WatchFile read_watch_file(const std::string& path);

// Writes `file` to `path` with mode 0600, atomically (a temporary file in the
// same directory, then rename), so a reader never sees half a file. Throws
// Error (Usage) naming `path` on failure.
void write_watch_file(const std::string& path, const WatchFile& file);

// Ready-to-paste commands for the session's watchers that keep the key off
// the command line: with a watch file "dn watch --server URL --key-file FILE",
// else "DN_WATCH_KEY=KEY dn watch --server URL --session ID" (the shell puts
// the key in dn's environment, which only its user can read).
std::string watch_hint(const Session& session, const std::string& watch_file);
std::string preview_hint(const Session& session, const std::string& watch_file);

// The two lines an owner prints as its session opens, each starting "PROGRAM: ":
// "session ID (watch it with: <watch_hint> --output 'watch/%04d.png')" and
// "preview it with: <preview_hint> (then open http://127.0.0.1:7879/)".
std::string owner_hints(const std::string& program, const Session& session, const std::string& watch_file);

// Where `dn preview` serves its page unless told otherwise (--http).
inline constexpr const char* kDefaultPreviewUrl = "http://127.0.0.1:7879/";

}  // namespace dn::client
