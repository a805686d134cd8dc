// dn denoise's frames: the range a pattern's existing files give when
// --start/--end are left out, and the check that every file a run needs is
// there before the first frame is sent.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace dn::cli {

// Frame numbers of the existing files that `pattern` names (its placeholder
// in the file name, not in a directory), ascending. Throws UsageError when
// the placeholder is in a directory name.
std::vector<long long> existing_frames(const std::string& pattern);

struct FrameRange {
  long long start = 0, end = 0;  // inclusive
  std::string detected;          // what was found, for the log; empty when both bounds were given
};

// Fills in the bounds not given from the existing files: start is the lowest
// frame found (at most `end`, when given), end the last frame of the run
// start, start + step, ... whose files all exist. Throws std::runtime_error
// when a bound is needed and no file matches.
FrameRange resolve_frame_range(const std::string& pattern, std::optional<long long> start,
                               std::optional<long long> end, long long step);

// Throws std::runtime_error naming the first missing file of `frames` in
// `pattern` (and how many others are missing), as "<what>: PATH (frame N)
// does not exist"; a pattern without a placeholder is one file for every
// frame: "<what>: PATH does not exist".
void require_frame_files(const std::vector<long long>& frames, const std::string& pattern, const std::string& what);

}  // namespace dn::cli
