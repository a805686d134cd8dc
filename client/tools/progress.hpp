// Progress output on stderr: a one-line bar redrawn in place on a terminal,
// plain per-frame lines otherwise (logs, CI).
#pragma once

#include <chrono>
#include <cstdio>
#include <optional>
#include <string>

#include "dn/protocol/messages.hpp"

namespace dn::cli {

class Progress {
 public:
  // tty: redraw a bar (normally isatty(fileno(stderr))). quiet: print nothing per frame.
  Progress(size_t total, bool tty, bool quiet, std::FILE* out = stderr);
  ~Progress();

  // One frame finished: `line` is the full per-frame text (non-TTY),
  // `status` the short text shown next to the bar (TTY).
  void frame_done(const std::string& line, const std::string& status);
  // A line that must not be overwritten by the bar (warnings).
  void message(const std::string& line);
  // Clears the bar (call before the summary or an error message).
  void finish();

  static bool stderr_is_tty();

 private:
  void draw(const std::string& status);
  size_t total_, done_ = 0;
  bool tty_, quiet_, drawn_ = false;
  std::FILE* out_;
  std::chrono::steady_clock::time_point start_;
  std::string last_status_;
};

// A RESULT's sample counts for a per-frame line: "  samples min 3 median 8"
// (input frames the output rests on, protocol 1.9), or "" without them.
std::string samples_status(const std::optional<protocol::SampleCounts>& samples);

}  // namespace dn::cli
