// A frame's file name from a printf pattern ('out/frame_%04d.exr'), for the
// bench tools that read sequences (region_metrics, region_temporal).
#pragma once

#include <cstdio>
#include <string>

namespace dn::bench {

inline std::string frame_path(const std::string& pattern, int frame) {
  char buf[1024];
  std::snprintf(buf, sizeof buf, pattern.c_str(), frame);
  return buf;
}

}  // namespace dn::bench
