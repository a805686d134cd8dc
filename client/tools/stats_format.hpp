// dn stats: the server's STATS values as people read them. The unit comes
// from the name: _ms and _s durations, _bytes (or bytes_) sizes (B, kB, MB,
// GB: powers of 1000), _bytes_per_pixel; channel masks as channel names
// (_channels_lo: bit i = channel id i, _channels_hi: id 32 + i); anything else
// is a count (every digit exact, with thousands separators) or a plain
// number. Non-counts keep 3 significant digits.
#pragma once

#include <string>
#include <vector>

#include "dn/protocol/messages.hpp"

namespace dn::cli {

struct ReadableValue {
  std::string number;  // "1.23", "1,234,567", "radiance,albedo"
  std::string unit;    // "ms", "MB", ...; empty for counts and plain numbers
  bool words = false;  // a list of names: starts at the number column instead of widening it
};

ReadableValue readable_stat(const std::string& name, double value);

// One line per value: the name, the number right-aligned in a column as wide
// as the widest, then its unit; no trailing blanks ("warm_up_done   1").
std::string stats_report(const std::vector<protocol::StatValue>& values);

// The same lines with the exact values ("%.17g"), for scripts: dn stats --raw.
std::string stats_report_raw(const std::vector<protocol::StatValue>& values);

}  // namespace dn::cli
