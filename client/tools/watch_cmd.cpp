// dn watch: attach to a running session read-only and write its newest frames,
// to files (--output), into the tev viewer (--tev HOST:PORT), or both.
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <optional>

#include "args.hpp"
#include "commands.hpp"
#include "dn/client/client.hpp"
#include "dn/image/metrics.hpp"
#include "frame_source.hpp"
#include "output_image.hpp"
#include "progress.hpp"
#include "tev_stream.hpp"

namespace dn::cli {

namespace {

const std::vector<Args::Spec> kSpecs = {
    server_option(),
    {"session", "", true, false, "id of the session to watch (printed by dn denoise and dnrender --server)", "ID"},
    {"key", "", true, false, "the session's watch key (default $DN_WATCH_KEY; printed with the id)", "KEY"},
    {"output", "-o", true, false,
     "output pattern; the format follows the extension: .exr (half), .png (tone-mapped) or .pfm", "PATTERN"},
    {"tev", "", true, false,
     "also (or instead) stream the frames into the tev HDR viewer listening at HOST:PORT (tev's default 127.0.0.1:14158)",
     "HOST:PORT"},
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
    std::printf("usage: dn watch [--server URL] --session ID --key KEY --output 'w/frame_%%04d.png' [--count N]\n"
                "       dn watch [--server URL] --session ID --key KEY --tev 127.0.0.1:14158 [--output ...]\n\n"
                "--tev shows each frame in tev as image 'dn session ID' (float R, G, B: the HDR values).\n"
                "Exits 0 when it has written --count frames or when the session ends (its owner\n"
                "closed it or went away), 1 when the connection fails or the server refuses, or\n"
                "when tev cannot be reached or goes away.\n\n"
                "options:\n%s",
                args.usage().c_str());
    return 0;
  }
  const std::string url = server_url(args.get_or("server", ""));
  // Session ids are random 64-bit numbers: parse the full unsigned range.
  const auto session_text = args.get("session");
  if (!session_text) throw UsageError("missing required option --session");
  uint64_t session_id = 0;
  {
    const char* b = session_text->data();
    const char* e = b + session_text->size();
    auto [ptr, ec] = std::from_chars(b, e, session_id);
    if (ec != std::errc() || ptr != e || session_id == 0)
      throw UsageError("--session: expected a session id (1 to 18446744073709551615), got '" + *session_text + "'");
  }
  // The key is the capability to watch (protocol 1.6); from the environment so
  // that it need not appear in a process listing.
  std::string key = args.get_or("key", "");
  if (key.empty())
    if (const char* env = std::getenv("DN_WATCH_KEY"); env) key = env;
  if (key.empty()) throw UsageError("missing --key KEY (or set DN_WATCH_KEY): the session's watch key, printed with its id");
  if (!protocol::is_well_formed_watch_key(key))
    throw UsageError("--key: expected the session's watch key, " + std::to_string(protocol::kWatchKeyLength) +
                     " lowercase hex digits, got '" + key + "' (" + std::to_string(key.size()) + " characters)");
  const std::string output = args.get_or("output", "");
  std::optional<tev::Address> tev_address;
  if (auto t = args.get("tev")) tev_address = tev::parse_address(*t);
  if (output.empty() && !tev_address)
    throw UsageError("missing --output PATTERN or --tev HOST:PORT (where the frames go; both may be given)");
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
  const ImageFormat format = output.empty() ? ImageFormat::Pfm : image_format_for(output, "--output");
  if (!output.empty() && count != 1 && !has_frame_placeholder(output))
    throw UsageError("--output '" + output + "' has no frame-number placeholder (%04d or ####)");

  // tev first: an address where nothing listens is found before the server is bothered.
  std::optional<tev::Stream> tev_stream;
  if (tev_address) tev_stream.emplace(*tev_address, timeout_s);
  const std::string tev_image = "dn session " + std::to_string(session_id);

  client::ConnectOptions copts;
  copts.client_name = "dn-watch";
  if (auto tf = args.get("token-file")) copts.token_file = *tf;
  copts.io_timeout = std::chrono::milliseconds(static_cast<long long>(timeout_s * 1000.0));
  client::Connection conn = client::Connection::connect(url, copts);
  client::Watcher watcher = conn.attach(uint64_t(session_id), key);
  const auto& info = watcher.info();
  if (!quiet)
    std::fprintf(stderr, "dn: watching session %llu on %s: %ux%u, pipeline %s%s\n", (unsigned long long)session_id,
                 conn.endpoint().c_str(), info.width, info.height, info.pipeline.c_str(),
                 tev_stream ? (", into tev at " + tev_stream->address() + " as '" + tev_image + "'").c_str() : "");

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
    std::string where;
    if (!output.empty()) {
      where = format_frame_path(output, (long long)r.frame_index);
      write_image(where, format, int(r.width), int(r.height), rgb.data(), {image::ExrPixelType::Half, tonemap, exposure});
    }
    if (tev_stream) {
      try {
        tev_stream->show(tev_image, int(r.width), int(r.height), rgb.data());
      } catch (const std::exception&) {
        progress.finish();
        throw;
      }
      where += (where.empty() ? "tev " : " and tev ") + tev_stream->address();
    }
    ++written;
    char line[512];
    std::snprintf(line, sizeof line, "frame %04llu -> %s (skipped %llu so far)", (unsigned long long)r.frame_index,
                  where.c_str(), (unsigned long long)watcher.dropped());
    progress.frame_done(line, "frame " + std::to_string(r.frame_index));
  }
  progress.finish();
  if (!quiet)
    std::fprintf(stderr, "dn: %s %lld frame%s%s\n", output.empty() ? "showed" : "wrote", written, written == 1 ? "" : "s",
                 count > 0 && written < count ? (" of the " + std::to_string(count) + " asked for").c_str() : "");
  return kExitOk;
}

}  // namespace dn::cli
