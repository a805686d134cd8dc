// dn preview: watch a session and serve it to browsers as a live page. With
// --key-file and no --session it serves the page at once and shows whichever
// session the file names, then the next one the owner writes there.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <thread>

#include "args.hpp"
#include "commands.hpp"
#include "dn/client/client.hpp"
#include "preview_address.hpp"
#include "preview_frame.hpp"
#include "preview_http.hpp"
#include "watch_target.hpp"

namespace dn::cli {

namespace {

// How often a waiting preview looks at the key file for the next session.
constexpr auto kKeyFilePoll = std::chrono::milliseconds(200);

const std::vector<Args::Spec> kSpecs = watch_specs({
    {"http", "", true, false,
     "where the page is served, HOST:PORT (default " + std::string(kDefaultPreviewAddress) +
         "; port 0 picks a free one)",
     "HOST:PORT"},
    {"http-token", "", true, false,
     "secret the page's URL must carry as ?token= (default $DN_PREVIEW_TOKEN); required off loopback", "TOKEN"},
    {"verbose", "-v", false, false, "a line per frame shown", ""},
});

void publish_status(PreviewHttpServer& server, const std::string& status, uint64_t session, const std::string& detail) {
  server.publish_status(std::make_shared<const std::vector<uint8_t>>(encode_preview_status(status, session, detail)));
}

// Blocks until the key file names a session other than `previous`; a file
// not there yet is waited for, one open to others is a UsageError.
WatchTarget next_session_in(const std::string& key_file, uint64_t previous) {
  for (;;) {
    std::error_code ec;
    if (std::filesystem::exists(key_file, ec)) {
      const client::WatchFile f = read_key_file(key_file);
      if (f.session_id != 0 && f.session_id != previous) return {f.session_id, f.key, key_file};
    }
    std::this_thread::sleep_for(kKeyFilePoll);
  }
}

// Shows the attached session's frames until it ends normally (returns the
// frames it processed); any other end is thrown.
uint64_t show_session(Attached& attached, const WatchTarget& target, PreviewHttpServer& server, PreviewContext ctx,
                      bool verbose, bool quiet) {
  client::Watcher& watcher = attached.watcher;
  ctx.session_id = target.session_id;
  ctx.pipeline = watcher.info().pipeline;
  const std::string what = "session " + std::to_string(target.session_id) + ": " +
                           std::to_string(watcher.info().width) + "x" + std::to_string(watcher.info().height) + ", " +
                           ctx.pipeline;
  if (!quiet) std::fprintf(stderr, "dn: showing %s\n", what.c_str());
  publish_status(server, "live", target.session_id, what);
  for (;;) {
    client::Result r;
    try {
      r = watcher.next();
    } catch (const client::Error&) {
      if (!ended_normally(watcher, quiet)) throw;  // SESSION_CLOSED is the normal end
      return watcher.closed()->frames_processed;
    }
    if (!r.has_output()) continue;
    ctx.dropped = watcher.dropped();
    server.publish(std::make_shared<const std::vector<uint8_t>>(encode_preview_frame(r, ctx)));
    if (verbose)
      std::fprintf(stderr, "dn: frame %llu to %zu page%s\n", (unsigned long long)r.frame_index, server.pages(),
                   server.pages() == 1 ? "" : "s");
  }
}

}  // namespace

int run_preview(const std::vector<std::string>& argv) {
  Args args("preview", kSpecs);
  args.parse(argv);
  if (args.has("help")) {
    std::printf("usage: dn preview [--server URL] --key-file FILE [--http HOST:PORT]\n"
                "       DN_WATCH_KEY=KEY dn preview [--server URL] --session ID [--http HOST:PORT]\n\n"
                "Serves a page that shows the session's newest denoised frame live, with its frame\n"
                "index, pipeline and per-pass timings, and the noisy input beside it when the\n"
                "session's owner shares it. With --key-file and no --session it may start before\n"
                "the owner (dnrender --server or dn denoise given --watch-key-file FILE): it shows\n"
                "the session the file names, then each next one. When a session ends the page keeps\n"
                "its last frame, marked ended; dn preview runs until interrupted. Exits 1 when the\n"
                "connection fails or the server refuses a session given with --session.\n\n"
                "options:\n%s",
                args.usage().c_str());
    return 0;
  }
  WatchTarget target = watch_target(args, "preview", /*session_optional=*/true);
  // Without --session the key file says which session: wait for it, and after it each next one.
  const bool follow = !args.has("session");
  if (follow && target.key_file.empty()) throw UsageError("missing required option --session (or --key-file FILE)");
  const PreviewAddress http = parse_preview_address(args.get_or("http", kDefaultPreviewAddress));
  std::string token = args.get_or("http-token", "");
  if (token.empty())
    if (const char* env = std::getenv("DN_PREVIEW_TOKEN"); env) token = env;
  if (!http.loopback && token.empty())
    throw UsageError("--http " + http.text +
                     " is not a loopback address: give --http-token TOKEN (or DN_PREVIEW_TOKEN) so that only "
                     "those with the token see the session");
  PreviewContext ctx;
  const Display display = display_options(args);
  ctx.tonemap = display.tonemap;
  ctx.exposure = display.exposure;
  const bool quiet = args.has("quiet");
  const bool verbose = args.has("verbose");
  const double timeout_s = watch_timeout_s(args);
  // A session given by --session that cannot be watched is an error before anything is served.
  std::optional<Attached> attached;
  if (!follow) attached.emplace(attach(args, target, "dn-preview", timeout_s));

  PreviewHttpServer server(http.civetweb_ports(), token);
  // One line on stdout, flushed: scripts (and the browser tests) read the URL from it.
  const std::string which = follow ? "the sessions named in " + target.key_file
                                   : "session " + std::to_string(target.session_id);
  std::printf("dn: preview of %s at http://%s:%d/%s\n", which.c_str(), http.url_host.c_str(), server.port(),
              token.empty() ? "" : "?token=TOKEN");
  std::fflush(stdout);

  uint64_t previous = 0;  // the session last shown, or found not open
  if (follow) publish_status(server, "waiting", 0, "waiting for a session named in " + target.key_file);
  for (;;) {
    if (!attached) {
      // Until the next session opens the page keeps what it shows: "waiting", or the last frame and "ended".
      target = next_session_in(target.key_file, previous);
      previous = target.session_id;
      try {
        attached.emplace(attach(args, target, "dn-preview", timeout_s));
      } catch (const client::Error& e) {
        // A key file left by an owner that has gone: wait for the next one it writes.
        if (!quiet)
          std::fprintf(stderr, "dn: session %llu named in %s cannot be watched (%s); waiting for the next one\n",
                       (unsigned long long)target.session_id, target.key_file.c_str(), e.what());
        continue;
      }
    }
    const uint64_t frames = show_session(*attached, target, server, ctx, verbose, quiet);
    attached.reset();
    std::string ended = "session " + std::to_string(target.session_id) + " ended after " + std::to_string(frames) +
                        " frame" + (frames == 1 ? "" : "s");
    if (follow) ended += "; waiting for the next session named in " + target.key_file;
    publish_status(server, "ended", target.session_id, ended);
    if (!follow) break;
  }
  if (!quiet) std::fprintf(stderr, "dn: the page keeps the last frame until dn preview is interrupted\n");
  for (;;) std::this_thread::sleep_for(std::chrono::hours(1));
}

}  // namespace dn::cli
