// dn capacity: how many more sessions of one size and pipeline the server can
// take, from its STATS (dn::client::capacity; docs/server.md "Capacity").
#include <cstdio>

#include "commands.hpp"
#include "dn/client/capacity.hpp"
#include "dn/client/client.hpp"
#include "server_info.hpp"

namespace dn::cli {

namespace {

// "1920x1080" -> {1920, 1080}; UsageError naming --size otherwise.
std::pair<uint32_t, uint32_t> parse_size(const std::string& text) {
  const size_t x = text.find('x');
  if (x == std::string::npos) throw UsageError("--size: '" + text + "' is not WIDTHxHEIGHT (e.g. 1920x1080)");
  const long long w = parse_int(text.substr(0, x), "--size width"), h = parse_int(text.substr(x + 1), "--size height");
  if (w < 1 || h < 1 || w > 65535 || h > 65535)
    throw UsageError("--size: " + text + " is outside 1x1 .. 65535x65535");
  return {static_cast<uint32_t>(w), static_cast<uint32_t>(h)};
}

}  // namespace

int run_capacity(const std::vector<std::string>& argv) {
  Args args("capacity", {server_option(),
                         {"pipeline", "-p", true, false, "the sessions' pipeline", "NAME"},
                         {"size", "", true, false, "the sessions' width x height", "WxH"},
                         {"fps", "", true, false, "frames per second each session sends (default 0: no time bound)", "N"},
                         {"explain", "", false, false, "also print each bound, one per line", ""},
                         {"token-file", "", true, false, "file holding the auth token", "FILE"},
                         {"timeout", "", true, false, "seconds (default 10)", "SECONDS"},
                         {"help", "-h", false, false, "this help", ""}});
  args.parse(argv);
  if (args.has("help")) {
    std::printf("usage: dn capacity --pipeline NAME --size WxH [--fps N] [--server URL] [--explain]\n\n"
                "Prints how many more sessions of that size and pipeline the server can take now:\n"
                "the least of what fits its free device memory, its session limit and, with --fps,\n"
                "the device time left (docs/server.md \"Capacity\").\n\n"
                "options:\n%s",
                args.usage().c_str());
    return 0;
  }
  const std::string pipeline = args.require("pipeline");
  const auto [width, height] = parse_size(args.require("size"));
  const double fps = args.get_double("fps", 0, 0, 1e6);
  client::Connection conn = connect_for(args, "dn-capacity");
  const client::Capacity c = client::capacity(conn.stats(), pipeline, width, height, fps);
  std::printf("%llu\n", (unsigned long long)c.sessions);
  if (args.has("explain")) {
    std::printf("session_bytes %llu\nby_memory %llu\nby_session_limit %llu\n", (unsigned long long)c.session_bytes,
                (unsigned long long)c.by_memory, (unsigned long long)c.by_session_limit);
    if (c.frame_ms) std::printf("frame_ms %.6g\n", *c.frame_ms);
    else std::printf("frame_ms unmeasured\n");
    if (c.by_time) std::printf("by_time %llu\n", (unsigned long long)*c.by_time);
  }
  return 0;
}

}  // namespace dn::cli
