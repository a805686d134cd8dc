#include "frame_range.hpp"

#include <algorithm>
#include <filesystem>
#include <set>
#include <stdexcept>

#include "args.hpp"
#include "frame_source.hpp"

namespace dn::cli {

namespace fs = std::filesystem;

std::vector<long long> existing_frames(const std::string& pattern) {
  const auto parts = split_frame_pattern(pattern);
  if (!parts) return {};
  if (parts->suffix.find('/') != std::string::npos)
    throw UsageError("cannot find the frames of '" + pattern +
                     "': its frame-number placeholder is in a directory name; give --start and --end");
  const fs::path prefix(parts->prefix);  // "in/frame_": look in "in" for names "frame_<digits><suffix>"
  const std::string head = prefix.filename().string();
  const fs::path dir = prefix.parent_path();
  std::vector<long long> frames;
  std::error_code ec;
  for (fs::directory_iterator it(dir.empty() ? fs::path(".") : dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= head.size() + parts->suffix.size() || name.compare(0, head.size(), head) != 0 ||
        name.compare(name.size() - parts->suffix.size(), parts->suffix.size(), parts->suffix) != 0)
      continue;
    const std::string digits = name.substr(head.size(), name.size() - head.size() - parts->suffix.size());
    if (digits.size() > 18 || !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
      continue;
    const long long n = std::stoll(digits);
    // Only the spelling the pattern writes: frame_01.exr is not frame 1 of frame_%d.exr.
    if (format_frame_number(parts->width, n) == digits) frames.push_back(n);
  }
  std::sort(frames.begin(), frames.end());
  return frames;
}

FrameRange resolve_frame_range(const std::string& pattern, std::optional<long long> start,
                               std::optional<long long> end, long long step) {
  if (start && end) return {*start, *end, {}};
  const std::vector<long long> found = existing_frames(pattern);
  const std::set<long long> present(found.begin(), found.end());
  FrameRange r;
  if (start) {
    r.start = *start;
  } else {
    auto lowest = std::find_if(found.begin(), found.end(), [&](long long n) { return !end || n <= *end; });
    if (lowest == found.end())
      throw std::runtime_error("no input file matches '" + pattern + "'" +
                               (end ? " at or below --end " + std::to_string(*end) : std::string()) +
                               "; give --start and --end, or check --input");
    r.start = *lowest;
  }
  if (end) {
    r.end = *end;
  } else {
    r.end = r.start;
    while (present.count(r.end + step)) r.end += step;
  }
  const size_t in_range = size_t((r.end - r.start) / step + 1);
  r.detected = "frames " + std::to_string(r.start) + ".." + std::to_string(r.end) + " (" + std::to_string(in_range) +
               " file" + (in_range == 1 ? "" : "s") + ") found from '" + pattern + "'";
  if (!end) {
    const auto later = std::count_if(found.begin(), found.end(), [&](long long n) { return n > r.end; });
    if (later > 0)
      r.detected += "; frame " + std::to_string(r.end + step) + " is missing, so the " + std::to_string(later) +
                    " later file" + (later == 1 ? " is" : "s are") + " left out (give --end to include them)";
  }
  return r;
}

void require_frame_files(const std::vector<long long>& frames, const std::string& pattern, const std::string& what) {
  // One file for every frame: named once, without a frame number.
  if (!has_frame_placeholder(pattern)) {
    const std::string path = format_frame_path(pattern, 0);
    if (!fs::exists(path)) throw std::runtime_error(what + ": " + path + " does not exist");
    return;
  }
  std::string first;
  size_t missing = 0;
  for (long long n : frames) {
    const std::string path = format_frame_path(pattern, n);
    if (fs::exists(path)) continue;
    if (missing++ == 0) first = path + " (frame " + std::to_string(n) + ")";
  }
  if (missing == 0) return;
  throw std::runtime_error(what + ": " + first + " does not exist" +
                           (missing > 1 ? " (and " + std::to_string(missing - 1) + " more of the " +
                                              std::to_string(frames.size()) + " frames are missing)"
                                        : std::string()));
}

}  // namespace dn::cli
