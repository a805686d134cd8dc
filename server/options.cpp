#include "server/options.hpp"

#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <sstream>
#include <string_view>

#include "dn/protocol/messages.hpp"

namespace dn::server {
namespace {

template <typename T>
bool parse_number(std::string_view text, T& out) {
  auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  return ec == std::errc() && ptr == text.data() + text.size();
}

bool parse_seconds(std::string_view text, double& out) {
  std::string s(text);
  char* end = nullptr;
  double v = std::strtod(s.c_str(), &end);
  if (end == s.c_str() || *end != '\0' || !(v >= 0.0) || v > 1e7) return false;
  out = v;
  return true;
}

// Accepts plain bytes or a K/M/G (binary) suffix: 512M, 2G.
bool parse_bytes(std::string_view text, uint64_t& out) {
  uint64_t scale = 1;
  if (!text.empty()) {
    switch (text.back()) {
      case 'K': case 'k': scale = 1ull << 10; break;
      case 'M': case 'm': scale = 1ull << 20; break;
      case 'G': case 'g': scale = 1ull << 30; break;
      default: break;
    }
    if (scale != 1) text.remove_suffix(1);
  }
  uint64_t v = 0;
  if (!parse_number(text, v) || v == 0 || v > (1ull << 40) / scale) return false;
  out = v * scale;
  return true;
}

// An address clients connect to (so, unlike --listen, a host name is fine):
// tcp://HOST:PORT with a port in 1..65535, or unix:///PATH; printable ASCII
// within SESSION.watch_url's limit.
bool is_advertisable_url(std::string_view url) {
  if (url.empty() || url.size() > protocol::kMaxWatchUrlBytes) return false;
  for (const char c : url)
    if (c < 0x21 || c > 0x7e) return false;
  if (url.rfind("unix:///", 0) == 0) return url.size() > 8;
  if (url.rfind("tcp://", 0) != 0) return false;
  const std::string_view rest = url.substr(6);
  const size_t colon = rest.rfind(':');
  if (colon == std::string_view::npos || colon == 0) return false;
  int port = 0;
  return parse_number(rest.substr(colon + 1), port) && port >= 1 && port <= 65535;
}

struct Flag {
  const char* name;
  const char* arg;  // nullptr for a switch
  const char* help;
  std::function<bool(ServerOptions&, std::string_view)> apply;
};

const std::vector<Flag>& flags() {
  static const std::string listen_help = std::string("listen on tcp://HOST:PORT or unix:///PATH; repeatable (default ") +
                                         protocol::kDefaultServerUrl + "). A non-loopback TCP address requires a token.";
  static const std::vector<Flag> table = {
      {"--listen", "URL", listen_help.c_str(),
       [](ServerOptions& o, std::string_view v) { o.listen.emplace_back(v); return true; }},
      {"--listen-proxied", "URL",
       "listen on URL (as --listen) behind a balancer: every connection must start with a PROXY protocol v2 "
       "header (HAProxy send-proxy-v2), whose source address becomes the peer; requires a token; repeatable",
       [](ServerOptions& o, std::string_view v) { o.listen_proxied.emplace_back(v); return true; }},
      {"--token-file", "PATH", "read the shared authentication token from PATH (else $DN_TOKEN)",
       [](ServerOptions& o, std::string_view v) { o.token_file = v; return true; }},
      {"--allow-uid", "UID", "also accept Unix-socket peers with this uid (own uid and root always); repeatable",
       [](ServerOptions& o, std::string_view v) {
         uint32_t uid;
         if (!parse_number(v, uid)) return false;
         o.allowed_uids.push_back(uid);
         return true;
       }},
      {"--device", "NAME|INDEX", "Vulkan device by index or name substring (default: first discrete GPU, else lavapipe)",
       [](ServerOptions& o, std::string_view v) { o.device = v; return true; }},
      {"--list-devices", nullptr, "print the Vulkan devices and exit",
       [](ServerOptions& o, std::string_view) { o.list_devices = true; return true; }},
      {"--validation", nullptr, "enable the Khronos validation layer (also DN_VALIDATION=1)",
       [](ServerOptions& o, std::string_view) { o.validation = true; return true; }},
      {"--workers", "N", "device worker threads (default 2)",
       [](ServerOptions& o, std::string_view v) { return parse_number(v, o.workers) && o.workers >= 1 && o.workers <= 64; }},
      {"--max-sessions", "N", "sessions per server (default 16)",
       [](ServerOptions& o, std::string_view v) { return parse_number(v, o.max_sessions) && o.max_sessions >= 1; }},
      {"--max-connections", "N", "open connections (default 256)",
       [](ServerOptions& o, std::string_view v) { return parse_number(v, o.max_connections) && o.max_connections >= 1; }},
      {"--max-connections-per-peer", "N",
       "open connections per peer: per uid for Unix-socket and loopback TCP peers, else per IP address "
       "(default half of --max-connections)",
       [](ServerOptions& o, std::string_view v) {
         return parse_number(v, o.max_connections_per_peer) && o.max_connections_per_peer >= 1;
       }},
      {"--max-unauthenticated", "N",
       "connections that have not completed HELLO, all peers together (default half of --max-connections)",
       [](ServerOptions& o, std::string_view v) { return parse_number(v, o.max_unauthenticated) && o.max_unauthenticated >= 1; }},
      {"--max-in-flight", "N", "frames in flight per session before reading pauses (default 4)",
       [](ServerOptions& o, std::string_view v) {
         return parse_number(v, o.max_frames_in_flight) && o.max_frames_in_flight >= 1 && o.max_frames_in_flight <= 64;
       }},
      {"--max-message", "BYTES", "largest message accepted, K/M/G suffixes (default 1G)",
       [](ServerOptions& o, std::string_view v) { return parse_bytes(v, o.max_message_bytes) && o.max_message_bytes >= 4096; }},
      {"--max-session-memory", "BYTES", "device memory per session (default 2G)",
       [](ServerOptions& o, std::string_view v) { return parse_bytes(v, o.max_session_bytes); }},
      {"--max-device-memory", "BYTES", "device memory of all sessions together (default and at most: the device's local heaps)",
       [](ServerOptions& o, std::string_view v) { return parse_bytes(v, o.max_device_bytes) && o.max_device_bytes > 0; }},
      {"--max-output-buffer", "BYTES", "queued output per connection before its reading pauses (default 256M)",
       [](ServerOptions& o, std::string_view v) { return parse_bytes(v, o.max_output_buffer_bytes); }},
      {"--max-queued-output", "BYTES",
       "queued output per connection above which it is closed (a peer that does not read; default 1G)",
       [](ServerOptions& o, std::string_view v) { return parse_bytes(v, o.max_queued_output_bytes); }},
      {"--receive-budget", "BYTES",
       "declared sizes of all messages being received at once; a message beyond it gets an ERROR (default 4G)",
       [](ServerOptions& o, std::string_view v) { return parse_bytes(v, o.receive_budget_bytes); }},
      {"--max-resolution", "WxH", "largest session resolution (default 8192x8192)",
       [](ServerOptions& o, std::string_view v) {
         auto x = v.find('x');
         return x != std::string_view::npos && parse_number(v.substr(0, x), o.max_width) &&
                parse_number(v.substr(x + 1), o.max_height) && o.max_width >= 1 && o.max_height >= 1;
       }},
      {"--handshake-timeout", "SECONDS", "time a new connection has to send HELLO (default 5)",
       [](ServerOptions& o, std::string_view v) { return parse_seconds(v, o.handshake_timeout_s) && o.handshake_timeout_s > 0; }},
      {"--idle-timeout", "SECONDS", "close a connection that sent nothing for this long, 0 = never (default 300)",
       [](ServerOptions& o, std::string_view v) { return parse_seconds(v, o.idle_timeout_s); }},
      {"--idle-trim", "SECONDS",
       "after this long with no frame, session or connection change, give back memory no session holds: free "
       "transient scratch, kernels outside the warm-up set no session uses, malloc's free pages; 0 = never (default 5)",
       [](ServerOptions& o, std::string_view v) { return parse_seconds(v, o.idle_trim_s); }},
      {"--heartbeat", "SECONDS", "PING a connection that sent nothing for this long, 0 = never (default 30)",
       [](ServerOptions& o, std::string_view v) { return parse_seconds(v, o.heartbeat_s); }},
      {"--message-timeout", "SECONDS",
       "a started message must complete within this plus its size at --min-receive-rate, else ERROR and close "
       "(default 30)",
       [](ServerOptions& o, std::string_view v) { return parse_seconds(v, o.message_timeout_s) && o.message_timeout_s > 0; }},
      {"--min-receive-rate", "BYTES", "bytes per second a started message must average, K/M/G suffixes (default 1M)",
       [](ServerOptions& o, std::string_view v) { return parse_bytes(v, o.min_receive_rate); }},
      {"--write-timeout", "SECONDS",
       "close a connection whose queued output made no progress for this long, 0 = never (default 60)",
       [](ServerOptions& o, std::string_view v) { return parse_seconds(v, o.write_timeout_s); }},
      {"--dead-peer", "SECONDS",
       "TCP keepalive and TCP_USER_TIMEOUT: a peer that vanished without closing is dropped after about this "
       "long, 0 = the kernel's defaults (default 120)",
       [](ServerOptions& o, std::string_view v) { return parse_seconds(v, o.dead_peer_s) && (o.dead_peer_s == 0 || o.dead_peer_s >= 2); }},
      {"--shutdown-grace", "SECONDS", "on SIGTERM, time allowed to finish frames in flight (default 30)",
       [](ServerOptions& o, std::string_view v) { return parse_seconds(v, o.shutdown_grace_s); }},
      {"--advertise-url", "URL",
       "tell each session's owner where watchers reach this server (SESSION.watch_url, protocol 1.8), e.g. a "
       "balancer's port that routes to this backend alone: tcp://HOST:PORT or unix:///PATH",
       [](ServerOptions& o, std::string_view v) {
         o.advertise_url = v;
         return is_advertisable_url(v);
       }},
      {"--cache-dir", "DIR",
       "keep compiled pipelines in DIR across runs (default $XDG_CACHE_HOME/dnserver or ~/.cache/dnserver; "
       "created 0700, must belong to this user and not be writable by others)",
       [](ServerOptions& o, std::string_view v) {
         o.cache_dir = v;
         o.cache_dir_given = true;
         return !v.empty() && v[0] == '/';
       }},
      {"--no-disk-cache", nullptr, "keep compiled pipelines in memory only",
       [](ServerOptions& o, std::string_view) { o.disk_cache = false; return true; }},
      {"--no-warm-up", nullptr, "do not compile the default pipelines at start (each compiles on first use)",
       [](ServerOptions& o, std::string_view) { o.warm_up = false; return true; }},
      {"--warm-up", nullptr, "compile the default pipelines at start, on a thread of their own (the default)",
       [](ServerOptions& o, std::string_view) { o.warm_up = true; return true; }},
      {"--log-level", "LEVEL", "debug, info, warn or error (default info)",
       [](ServerOptions& o, std::string_view v) {
         o.log_level = v;
         return v == "debug" || v == "info" || v == "warn" || v == "error";
       }},
  };
  return table;
}

std::string trim_token(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' ' || s.back() == '\t')) s.pop_back();
  return s;
}

}  // namespace

std::string help_text() {
  std::ostringstream out;
  out << "usage: dnserver [flags]\n\n"
         "Denoising server: owns a Vulkan device, serves protocol v1 (docs/protocol.md).\n\n"
         "flags:\n";
  for (const Flag& f : flags()) {
    std::string left = std::string("  ") + f.name + (f.arg ? std::string(" ") + f.arg : "");
    out << left;
    out << std::string(left.size() < 34 ? 34 - left.size() : 1, ' ') << f.help << "\n";
  }
  out << "  --help                          print this text and exit\n"
         "  --version                       print the version and exit\n\n"
         "environment:\n"
         "  DN_TOKEN                        authentication token when --token-file is not given\n"
         "  DN_VALIDATION=1                 same as --validation\n";
  return out.str();
}

ParseOutcome parse_options(int argc, char** argv, ServerOptions& out) {
  ParseOutcome result;
  for (int i = 1; i < argc; ++i) {
    std::string_view arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::fputs(help_text().c_str(), stdout);
      result.exit_now = true;
      return result;
    }
    if (arg == "--version") {
      std::puts("dnserver 0.1.0 (protocol 1.0)");
      result.exit_now = true;
      return result;
    }
    std::string_view value;
    bool inline_value = false;
    if (auto eq = arg.find('='); eq != std::string_view::npos && arg.starts_with("--")) {
      value = arg.substr(eq + 1);
      arg = arg.substr(0, eq);
      inline_value = true;
    }
    const Flag* flag = nullptr;
    for (const Flag& f : flags())
      if (arg == f.name) flag = &f;
    if (!flag) {
      result = {false, false, "unknown flag '" + std::string(arg) + "' (see --help)"};
      return result;
    }
    if (flag->arg && !inline_value) {
      if (i + 1 >= argc) {
        result = {false, false, std::string(flag->name) + " needs a value: " + flag->arg};
        return result;
      }
      value = argv[++i];
    }
    if (!flag->apply(out, value)) {
      result = {false, false, "invalid value '" + std::string(value) + "' for " + flag->name + " (expected " + flag->arg + ")"};
      return result;
    }
  }
  // The default listener only when none is given: several servers behind one
  // balancer on one machine must not all try to take the default port.
  if (out.listen.empty() && out.listen_proxied.empty()) out.listen.push_back(protocol::kDefaultServerUrl);

  if (!out.token_file.empty()) {
    std::ifstream in(out.token_file);
    if (!in) return {false, false, "--token-file: cannot read '" + out.token_file + "'"};
    std::stringstream ss;
    ss << in.rdbuf();
    out.token = trim_token(ss.str());
    if (out.token.empty()) return {false, false, "--token-file: '" + out.token_file + "' is empty"};
  } else if (const char* env = std::getenv("DN_TOKEN"); env && *env) {
    out.token = trim_token(env);
  }
  if (out.token.size() > 256) return {false, false, "authentication token is longer than 256 bytes"};
  if (const char* v = std::getenv("DN_VALIDATION"); v && std::string_view(v) == "1") out.validation = true;
  return result;
}

}  // namespace dn::server
