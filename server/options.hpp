// dnserver's command line: every flag, its default and its help text live here.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace dn::server {

struct ServerOptions {
  std::vector<std::string> listen;       // tcp://HOST:PORT or unix:///PATH; default protocol::kDefaultServerUrl
  std::vector<std::string> listen_proxied;  // same URLs, behind a balancer: PROXY v2 header first (docs/server.md)
  std::string token_file;                // shared secret; also DN_TOKEN in the environment
  std::string token;                     // resolved token (from file or environment)
  std::vector<uint32_t> allowed_uids;    // Unix-socket peers besides our own uid and root
  std::string device;                    // Vulkan device selector: index or name substring
  bool list_devices = false;
  bool validation = false;               // Khronos validation layer
  uint32_t workers = 2;                  // device worker threads
  uint32_t max_sessions = 16;
  uint32_t max_connections = 256;
  uint32_t max_connections_per_peer = 0;  // per uid (Unix socket, loopback TCP) or remote IP; 0: half of max_connections
  uint32_t max_unauthenticated = 0;      // before HELLO, all peers together; 0: half of max_connections
  uint32_t max_frames_in_flight = 4;     // per session, before reading from its connection pauses
  uint64_t max_message_bytes = 1ull << 30;
  uint64_t max_session_bytes = 2ull << 30;   // device bytes per session
  uint64_t max_device_bytes = 0;             // device bytes of all sessions; 0: the device's local heaps
  uint64_t max_output_buffer_bytes = 256ull << 20;  // per connection, before reading pauses
  uint64_t max_queued_output_bytes = 1ull << 30;    // per connection: above it the connection is closed
  uint64_t receive_budget_bytes = 4ull << 30;       // all connections: declared sizes of messages being received
  uint32_t max_width = 8192;
  uint32_t max_height = 8192;
  double handshake_timeout_s = 5.0;
  double idle_timeout_s = 300.0;         // nothing received for this long: close (0 = never)
  double heartbeat_s = 30.0;             // nothing received for this long: send PING
  double message_timeout_s = 30.0;       // a started message gets this long plus its size at min_receive_rate
  uint64_t min_receive_rate = 1ull << 20;  // bytes per second a started message must average (with the above)
  double write_timeout_s = 60.0;         // queued output and nothing written for this long: close (0 = never)
  double dead_peer_s = 120.0;            // TCP keepalive and TCP_USER_TIMEOUT: a vanished peer is noticed in this time
  double shutdown_grace_s = 30.0;        // SIGTERM: time allowed to finish frames in flight
  double idle_trim_s = 5.0;              // quiet this long: give back memory no session holds (0 = never)
  std::string log_level = "info";
  std::string advertise_url;             // SESSION.watch_url (1.8): where watchers reach this backend; empty: none
  std::string cache_dir;                 // on-disk pipeline cache; default: the user's cache dir (server/cache_dir.hpp)
  bool cache_dir_given = false;          // --cache-dir was explicit: an unusable directory is an error, not a warning
  bool disk_cache = true;                // --no-disk-cache: compiled pipelines are kept in memory only
  bool warm_up = true;                   // --no-warm-up: compile the default pipelines on first use instead of at start
};

struct ParseOutcome {
  bool ok = true;
  bool exit_now = false;  // --help or --version printed
  std::string error;      // names the flag and what was wrong
};

ParseOutcome parse_options(int argc, char** argv, ServerOptions& out);
std::string help_text();

}  // namespace dn::server
