// dn watch: attach to a running session read-only and write its newest frames,
// to files (--output), into the tev viewer (--tev HOST:PORT), or both.
#include <cstdio>
#include <optional>

#include "args.hpp"
#include "commands.hpp"
#include "dn/client/client.hpp"
#include "dn/image/metrics.hpp"
#include "frame_source.hpp"
#include "output_image.hpp"
#include "progress.hpp"
#include "tev_stream.hpp"
#include "watch_target.hpp"

namespace dn::cli {

namespace {

const std::vector<Args::Spec> kSpecs = watch_specs({
    {"output", "-o", true, false,
     "output pattern; the format follows the extension: .exr (half), .png (tone-mapped) or .pfm", "PATTERN"},
    {"tev", "", true, false,
     "also (or instead) stream the frames into the tev HDR viewer listening at HOST:PORT (tev's default 127.0.0.1:14158)",
     "HOST:PORT"},
    {"count", "", true, false, "stop after N frames (default: until the session ends)", "N"},
});

}  // namespace

int run_watch(const std::vector<std::string>& argv) {
  Args args("watch", kSpecs);
  args.parse(argv);
  if (args.has("help")) {
    std::printf("usage: DN_WATCH_KEY=KEY dn watch [--server URL] --session ID --output 'w/frame_%%04d.png' [--count N]\n"
                "       dn watch [--server URL] --key-file FILE --tev 127.0.0.1:14158 [--output ...]\n\n"
                "The watch key comes from $DN_WATCH_KEY or --key-file (mode 0600; the session id too when\n"
                "the owner wrote it): a --key on the command line is readable by every local user.\n"
                "--tev shows each frame in tev as image 'dn session ID' (float R, G, B: the HDR values).\n"
                "Exits 0 when it has written --count frames or when the session ends (its owner\n"
                "closed it or went away), 1 when the connection fails or the server refuses, or\n"
                "when tev cannot be reached or goes away.\n\n"
                "options:\n%s",
                args.usage().c_str());
    return 0;
  }
  const WatchTarget target = watch_target(args, "watch");
  const std::string output = args.get_or("output", "");
  std::optional<tev::Address> tev_address;
  if (auto t = args.get("tev")) tev_address = tev::parse_address(*t);
  if (output.empty() && !tev_address)
    throw UsageError("missing --output PATTERN or --tev HOST:PORT (where the frames go; both may be given)");
  const long long count = args.get_int("count", 0, 0, INT64_MAX);
  const bool quiet = args.has("quiet");
  const Display display = display_options(args);
  const double timeout_s = watch_timeout_s(args);
  const ImageFormat format = output.empty() ? ImageFormat::Pfm : image_format_for(output, "--output");
  if (!output.empty() && count != 1 && !has_frame_placeholder(output))
    throw UsageError("--output '" + output + "' has no frame-number placeholder (%04d or ####)");

  // tev first: an address where nothing listens is found before the server is bothered.
  std::optional<tev::Stream> tev_stream;
  if (tev_address) tev_stream.emplace(*tev_address, timeout_s);
  const std::string tev_image = "dn session " + std::to_string(target.session_id);

  Attached attached = attach(args, target, "dn-watch", timeout_s);
  client::Connection& conn = attached.connection;
  client::Watcher& watcher = attached.watcher;
  const auto& info = watcher.info();
  if (!quiet)
    std::fprintf(stderr, "dn: watching session %llu on %s: %ux%u, pipeline %s%s\n", (unsigned long long)target.session_id,
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
      progress.finish();
      if (!ended_normally(watcher, quiet)) throw;  // SESSION_CLOSED is the normal end; an ERROR or a lost connection is not
      break;
    }
    if (!r.has_output()) continue;
    const std::vector<float> rgb = r.rgb();
    std::string where;
    if (!output.empty()) {
      where = format_frame_path(output, (long long)r.frame_index);
      write_image(where, format, int(r.width), int(r.height), rgb.data(), {image::ExrPixelType::Half, display.tonemap, display.exposure});
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
    progress.frame_done(line + samples_status(r.samples), "frame " + std::to_string(r.frame_index) + samples_status(r.samples));
  }
  progress.finish();
  if (!quiet)
    std::fprintf(stderr, "dn: %s %lld frame%s%s\n", output.empty() ? "showed" : "wrote", written, written == 1 ? "" : "s",
                 count > 0 && written < count ? (" of the " + std::to_string(count) + " asked for").c_str() : "");
  return kExitOk;
}

}  // namespace dn::cli
