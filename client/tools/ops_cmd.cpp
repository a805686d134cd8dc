// dn ping / dn stats / dn pipelines: small operational checks.
#include <cstdio>
#include <cstdlib>
#include <optional>

#include "args.hpp"
#include "commands.hpp"
#include "dn/client/client.hpp"
#include "server_info.hpp"
#include "stats_format.hpp"

namespace dn::cli {

std::string server_url(const std::string& option_value) {
  std::string url = option_value;
  if (url.empty())
    if (const char* env = std::getenv("DN_SERVER"); env && *env) url = env;
  if (url.empty()) url = client::kDefaultServerUrl;
  // A malformed address is a bad command line (exit 2), found before any work.
  try {
    client::parse_endpoint(url);
  } catch (const client::Error& e) {
    throw UsageError(std::string(option_value.empty() ? "$DN_SERVER: " : "--server: ") + e.what());
  }
  return url;
}

Args::Spec server_option() {
  return {"server", "", true, false,
          std::string("server address: tcp://HOST:PORT or unix:///path (default $DN_SERVER, else ") +
              client::kDefaultServerUrl + ")",
          "URL"};
}

int run_ping(const std::vector<std::string>& argv) {
  Args args("ping", {server_option(),
                     {"count", "-c", true, false, "number of pings (default 3)", "N"},
                     {"token-file", "", true, false, "file holding the auth token", "FILE"},
                     {"timeout", "", true, false, "seconds (default 10)", "SECONDS"},
                     {"help", "-h", false, false, "this help", ""}});
  args.parse(argv);
  if (args.has("help")) {
    std::printf("usage: dn ping [--server URL] [--count N]\n\noptions:\n%s", args.usage().c_str());
    return 0;
  }
  const long long count = args.get_int("count", 3, 1, 1000000);
  client::Connection conn = connect_for(args, "dn-ping");
  const auto& w = conn.welcome();
  std::printf("%s: %s on %s\n", conn.endpoint().c_str(), w.server_version.c_str(), w.device_name.c_str());
  std::printf("limits: max message %llu bytes, %llu bytes per session, %u sessions, %ux%u, %u frames in flight\n",
              (unsigned long long)w.limits.max_message_bytes, (unsigned long long)w.limits.max_session_bytes,
              w.limits.max_sessions, w.limits.max_width, w.limits.max_height, w.limits.max_frames_in_flight);
  for (const auto& p : w.pipelines) {
    std::printf("pipeline %-12s requires %s; optional %s\n", p.name.c_str(), channel_set(p.required_channels).c_str(),
                channel_set(p.optional_channels).c_str());
    std::printf("  parameters: %s\n", parameter_names(w, p).c_str());
  }
  double best = 1e300, sum = 0;
  for (long long i = 0; i < count; ++i) {
    const double ms = conn.ping().count();
    best = std::min(best, ms);
    sum += ms;
    std::printf("pong %lld: %.3f ms\n", i + 1, ms);
  }
  std::printf("rtt min %.3f ms, mean %.3f ms\n", best, sum / double(count));
  return 0;
}

int run_stats(const std::vector<std::string>& argv) {
  Args args("stats", {server_option(),
                      {"raw", "", false, false, "exact values (%.17g), no units: for scripts", ""},
                      {"token-file", "", true, false, "file holding the auth token", "FILE"},
                      {"timeout", "", true, false, "seconds (default 10)", "SECONDS"},
                      {"help", "-h", false, false, "this help", ""}});
  args.parse(argv);
  if (args.has("help")) {
    std::printf("usage: dn stats [--server URL] [--raw]\n\n"
                "Prints the server's statistics, one per line: 3 significant digits with units\n"
                "(ms, s, min, h; B, kB, MB, GB; B/px), channel masks as channel names, counts\n"
                "exact with thousands separators.\n\n"
                "options:\n%s",
                args.usage().c_str());
    return 0;
  }
  client::Connection conn = connect_for(args, "dn-stats");
  const protocol::Stats s = conn.stats();
  std::fputs((args.has("raw") ? stats_report_raw(s.values) : stats_report(s.values)).c_str(), stdout);
  return 0;
}

int run_pipelines(const std::vector<std::string>& argv) {
  Args args("pipelines", {server_option(),
                          {"pipeline", "-p", true, false, "show only this pipeline", "NAME"},
                          {"token-file", "", true, false, "file holding the auth token", "FILE"},
                          {"timeout", "", true, false, "seconds (default 10)", "SECONDS"},
                          {"help", "-h", false, false, "this help", ""}});
  args.parse(argv);
  if (args.has("help")) {
    std::printf("usage: dn pipelines [--server URL] [--pipeline NAME]\n\n"
                "Lists the server's pipelines: required and optional channels, how many kernels its\n"
                "input forms compile, and each parameter's name, default, range, whether it is an\n"
                "integer, and what it does.\n\noptions:\n%s",
                args.usage().c_str());
    return 0;
  }
  client::Connection conn = connect_for(args, "dn-pipelines");
  const auto& w = conn.welcome();
  // Each pipeline's kernel variants come from STATS: a server that does not
  // answer it still gets its pipelines listed, without them.
  std::optional<protocol::Stats> stats;
  try {
    stats = conn.stats();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dn pipelines: no kernel variants (STATS failed: %s)\n", e.what());
  }
  std::printf("%s: %s on %s\n\n%s", conn.endpoint().c_str(), w.server_version.c_str(), w.device_name.c_str(),
              pipelines_report(w, args.get_or("pipeline", ""), stats ? &*stats : nullptr).c_str());
  return 0;
}

}  // namespace dn::cli
