// dn preview: watch a session and serve it to browsers as a live page.
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "args.hpp"
#include "commands.hpp"
#include "dn/client/client.hpp"
#include "preview_address.hpp"
#include "preview_frame.hpp"
#include "preview_http.hpp"
#include "watch_target.hpp"

namespace dn::cli {

namespace {

const std::vector<Args::Spec> kSpecs = {
    server_option(),
    session_option(),
    watch_key_option(),
    {"http", "", true, false,
     "where the page is served, HOST:PORT (default " + std::string(kDefaultPreviewAddress) +
         "; port 0 picks a free one)",
     "HOST:PORT"},
    {"http-token", "", true, false,
     "secret the page's URL must carry as ?token= (default $DN_PREVIEW_TOKEN); required off loopback", "TOKEN"},
    {"token-file", "", true, false, "file holding the server's auth token", "FILE"},
    {"tonemap", "", true, false, "tone map for the page: aces | reinhard | clamp (default aces)", "OP"},
    {"exposure", "", true, false, "exposure multiplier before tone mapping (default 1)", "X"},
    {"timeout", "", true, false, "seconds to wait for the next frame (default 600); longer is an error", "SECONDS"},
    {"quiet", "-q", false, false, "no per-frame output", ""},
    {"help", "-h", false, false, "this help", ""},
};

}  // namespace

int run_preview(const std::vector<std::string>& argv) {
  Args args("preview", kSpecs);
  args.parse(argv);
  if (args.has("help")) {
    std::printf("usage: dn preview [--server URL] --session ID --key KEY [--http HOST:PORT]\n\n"
                "Serves a page that shows the session's newest denoised frame live, with its frame\n"
                "index, pipeline and per-pass timings, and the noisy input beside it when the\n"
                "session's owner shares it. Exits 0 when the session ends, 1 when the connection\n"
                "fails or the server refuses.\n\n"
                "options:\n%s",
                args.usage().c_str());
    return 0;
  }
  const std::string url = server_url(args.get_or("server", ""));
  const WatchTarget target = watch_target(args);
  const PreviewAddress http = parse_preview_address(args.get_or("http", kDefaultPreviewAddress));
  std::string token = args.get_or("http-token", "");
  if (token.empty())
    if (const char* env = std::getenv("DN_PREVIEW_TOKEN"); env) token = env;
  if (!http.loopback && token.empty())
    throw UsageError("--http " + http.text +
                     " is not a loopback address: give --http-token TOKEN (or DN_PREVIEW_TOKEN) so that only "
                     "those with the token see the session");
  PreviewContext ctx;
  try {
    ctx.tonemap = image::parse_tonemap(args.get_or("tonemap", "aces"));
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--tonemap: ") + e.what());
  }
  ctx.exposure = float(args.get_double("exposure", 1.0));
  const double timeout_s = args.get_double("timeout", 600.0, kMinTimeoutSeconds, kMaxTimeoutSeconds);
  const bool quiet = args.has("quiet");

  client::ConnectOptions copts;
  copts.client_name = "dn-preview";
  if (auto tf = args.get("token-file")) copts.token_file = *tf;
  copts.io_timeout = std::chrono::milliseconds(static_cast<long long>(timeout_s * 1000.0));
  client::Connection conn = client::Connection::connect(url, copts);
  client::Watcher watcher = conn.attach(target.session_id, target.key);
  ctx.session_id = target.session_id;
  ctx.pipeline = watcher.info().pipeline;

  PreviewHttpServer server(http.civetweb_ports(), token);
  // One line on stdout, flushed: scripts (and the browser test) read the URL from it.
  std::printf("dn: preview of session %llu (%ux%u, %s) at http://%s:%d/%s\n", (unsigned long long)target.session_id,
              watcher.info().width, watcher.info().height, ctx.pipeline.c_str(), http.url_host.c_str(), server.port(),
              token.empty() ? "" : "?token=TOKEN");
  std::fflush(stdout);

  for (;;) {
    client::Result r;
    try {
      r = watcher.next();
    } catch (const client::Error&) {
      const auto& closed = watcher.closed();  // SESSION_CLOSED is the normal end
      if (!closed) throw;
      if (!quiet)
        std::fprintf(stderr, "dn: session %llu ended normally after %llu frames\n",
                     (unsigned long long)closed->session_id, (unsigned long long)closed->frames_processed);
      return kExitOk;
    }
    if (!r.has_output()) continue;
    ctx.dropped = watcher.dropped();
    server.publish(std::make_shared<const std::vector<uint8_t>>(encode_preview_frame(r, ctx)));
    if (!quiet)
      std::fprintf(stderr, "dn: frame %llu to %zu page%s\n", (unsigned long long)r.frame_index, server.pages(),
                   server.pages() == 1 ? "" : "s");
  }
}

}  // namespace dn::cli
