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

const std::vector<Args::Spec> kSpecs = watch_specs({
    {"http", "", true, false,
     "where the page is served, HOST:PORT (default " + std::string(kDefaultPreviewAddress) +
         "; port 0 picks a free one)",
     "HOST:PORT"},
    {"http-token", "", true, false,
     "secret the page's URL must carry as ?token= (default $DN_PREVIEW_TOKEN); required off loopback", "TOKEN"},
});

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
  const Display display = display_options(args);
  ctx.tonemap = display.tonemap;
  ctx.exposure = display.exposure;
  const bool quiet = args.has("quiet");
  Attached attached = attach(args, target, "dn-preview", watch_timeout_s(args));
  client::Watcher& watcher = attached.watcher;
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
      if (!ended_normally(watcher, quiet)) throw;  // SESSION_CLOSED is the normal end
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
