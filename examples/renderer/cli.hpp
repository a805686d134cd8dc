// dnrender's command line: parsing (testable, no side effects) and the run.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "render.hpp"

namespace dn::render {

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct CliOptions {
  int scene = 1;
  int frames = 1;
  int first = 0;
  std::optional<int> hold_camera;   // every frame seen from this path frame's camera (fresh noise per frame)
  RenderSettings render;
  std::string out;                  // frames to DIR/frame_%04d.exr
  std::optional<int> reference_spp;
  bool reference2 = false;          // also the second, independent reference (ref2_%04d.exr)
  std::string cache;                // --cache; empty: default_cache_dir() ($XDG_CACHE_HOME/dnrender)
  std::string server, pipeline;
  int in_flight = 2;
  double reconnect_for_s = 30.0;    // after a lost server connection, how long to keep reconnecting
  bool send_split = false;
  bool share_input = false;         // let watchers (dn preview) see the noisy radiance (protocol 1.7)
  std::string watch_key_file;       // --watch-key-file: each session's watch key and id, mode 0600
  bool png = false;                 // also DIR/frame_%04d.png, tone-mapped radiance
  bool quiet = false;
  bool help = false;
};

extern const char* const kUsage;

// Throws UsageError with a message naming the offending argument.
CliOptions parse_cli(const std::vector<std::string>& args);

// Runs what the options ask for; returns the process exit status.
int run_cli(const CliOptions& options);

}  // namespace dn::render
