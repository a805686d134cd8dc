// dn watch: attach to a running session read-only and write its newest frames.
#include <cstdio>

#include "args.hpp"
#include "commands.hpp"
#include "dn/client/client.hpp"
#include "dn/image/metrics.hpp"
#include "frame_source.hpp"
#include "output_image.hpp"
#include "progress.hpp"
#include "watch_target.hpp"

namespace dn::cli {

namespace {

const std::vector<Args::Spec> kSpecs = {
    server_option(),
    session_option(),
    watch_key_option(),
    {"output", "-o", true, false,
     "output pattern; the format follows the extension: .exr (half), .png (tone-mapped) or .pfm", "PATTERN"},
    {"count", "", true, false, "stop after N frames (default: until the session ends)", "N"},
    {"token-file", "", true, false, "file holding the auth token", "FILE"},
    {"tonemap", "", true, false, "PNG tone map: aces | reinhard | clamp (default aces)", "OP"},
    {"exposure", "", true, false, "exposure multiplier before tone mapping (default 1)", "X"},
    {"timeout", "", true, false, "seconds to wait for the next frame (default 600); longer is an error", "SECONDS"},
    {"quiet", "-q", false, false, "no per-frame output", ""},
    {"help", "-h", false, false, "this help", ""},
};

}  // namespace

int run_watch(const std::vector<std::string>& argv) {
  Args args("watch", kSpecs);
  args.parse(argv);
  if (args.has("help")) {
    std::printf("usage: dn watch [--server URL] --session ID --key KEY --output 'w/frame_%%04d.png' [--count N]\n\n"
                "Exits 0 when it has written --count frames or when the session ends (its owner\n"
                "closed it or went away), 1 when the connection fails or the server refuses.\n\n"
                "options:\n%s",
                args.usage().c_str());
    return 0;
  }
  const std::string url = server_url(args.get_or("server", ""));
  const WatchTarget target = watch_target(args);
  const std::string output = args.require("output");
  const long long count = args.get_int("count", 0, 0, INT64_MAX);
  const bool quiet = args.has("quiet");
  const float exposure = float(args.get_double("exposure", 1.0));
  const double timeout_s = args.get_double("timeout", 600.0, kMinTimeoutSeconds, kMaxTimeoutSeconds);
  image::Tonemap tonemap = image::Tonemap::Aces;
  try {
    tonemap = image::parse_tonemap(args.get_or("tonemap", "aces"));
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--tonemap: ") + e.what());
  }
  const ImageFormat format = image_format_for(output, "--output");
  if (count != 1 && !has_frame_placeholder(output))
    throw UsageError("--output '" + output + "' has no frame-number placeholder (%04d or ####)");

  client::ConnectOptions copts;
  copts.client_name = "dn-watch";
  if (auto tf = args.get("token-file")) copts.token_file = *tf;
  copts.io_timeout = std::chrono::milliseconds(static_cast<long long>(timeout_s * 1000.0));
  client::Connection conn = client::Connection::connect(url, copts);
  client::Watcher watcher = conn.attach(target.session_id, target.key);
  const auto& info = watcher.info();
  if (!quiet)
    std::fprintf(stderr, "dn: watching session %llu on %s: %ux%u, pipeline %s\n", (unsigned long long)target.session_id,
                 conn.endpoint().c_str(), info.width, info.height, info.pipeline.c_str());

  Progress progress(size_t(count), Progress::stderr_is_tty() && count > 0, quiet);
  long long written = 0;
  for (;;) {
    if (count > 0 && written >= count) break;
    client::Result r;
    try {
      r = watcher.next();
    } catch (const client::Error&) {
      // SESSION_CLOSED is the normal end of a watch; an ERROR or a lost connection is not.
      const auto& closed = watcher.closed();
      if (!closed) throw;
      progress.finish();
      if (!quiet)
        std::fprintf(stderr, "dn: session %llu ended normally after %llu frames\n",
                     (unsigned long long)closed->session_id, (unsigned long long)closed->frames_processed);
      break;
    }
    if (!r.has_output()) continue;
    const std::vector<float> rgb = r.rgb();
    const std::string path = format_frame_path(output, (long long)r.frame_index);
    write_image(path, format, int(r.width), int(r.height), rgb.data(), {image::ExrPixelType::Half, tonemap, exposure});
    ++written;
    char line[256];
    std::snprintf(line, sizeof line, "frame %04llu -> %s (skipped %llu so far)", (unsigned long long)r.frame_index,
                  path.c_str(), (unsigned long long)watcher.dropped());
    progress.frame_done(line, "frame " + std::to_string(r.frame_index));
  }
  progress.finish();
  if (!quiet)
    std::fprintf(stderr, "dn: wrote %lld frame%s%s\n", written, written == 1 ? "" : "s",
                 count > 0 && written < count ? (" of the " + std::to_string(count) + " asked for").c_str() : "");
  return kExitOk;
}

}  // namespace dn::cli
