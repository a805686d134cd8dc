#include "cli.hpp"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>

#include "dn/image/metrics.hpp"
#include "dn/image/png.hpp"
#include "frame_exr.hpp"
#include "reference_cache.hpp"
#include "scenes.hpp"
#include "stream.hpp"

namespace dn::render {

const char* const kUsage =
    "usage: dnrender [options]\n"
    "Path-traces a built-in scene (CPU, Embree) with the channels the denoising service takes.\n"
    "\n"
    "  --scene N          1 room, 2 pillars (disocclusion), 3 gap (indirect), 4 fireflies,\n"
    "                     5 roughness (fine roughness maps), 6 mirror-floor (planar mirror, glossy floor)\n"
    "                     (default 1)\n"
    "  --frames N         number of frames (default 1)\n"
    "  --first F          first frame index (default 0)\n"
    "  --hold-camera F    keep the camera of path frame F for every frame (still scene, new noise\n"
    "                     each frame: for temporal stability)\n"
    "  --width W          image width (default 640)\n"
    "  --height H         image height (default 360)\n"
    "  --spp X            samples per pixel; fractions allowed: 0.25 gives a quarter of the pixels a sample\n"
    "                     each frame, 2.25 gives every pixel 2 and a quarter of them a third (default 1)\n"
    "  --spp-schedule S   which pixels take the extra sample of a fractional spp:\n"
    "                     stratified (default): for a fraction 1/k, k = 2..1024 (0.5, 0.25, 2.125), each\n"
    "                     pixel exactly once in every k frames, in a seed-dependent ordered-dither pattern;\n"
    "                     any other fraction (0.3, 2.7) falls back to random\n"
    "                     random: each pixel independently, with the fraction as probability, every frame\n"
    "  --seed S           random seed (default 1)\n"
    "  --max-depth D      bounces after the primary hit (default 8)\n"
    "  --threads T        render threads (default: all cores)\n"
    "  --jitter           per-frame Halton sub-pixel camera jitter (written as dn.jitter)\n"
    "  --gbuffer-grid K   albedo/specular_f0/roughness/normal: pixel-footprint averages of K x K\n"
    "                     stratified G-buffer rays (default 4); 0: point-sampled at the radiance ray\n"
    "  --extra-samples N  guide-ray supersampling (paper 001 §5; needs --spp 1): N = 1..3 more primary\n"
    "                     samples per pixel, each with its own path, normal, depth and offset\n"
    "                     (sample<j>_* layers, protocol channels 33-50)\n"
    "  --stats            also per-pixel online statistics (stat_* layers, paper 003 Alg. 1); with\n"
    "                     --server streamed as protocol channels 51-54 when the pipeline takes them\n"
    "  --stats-demodulated  --stats over demodulated samples: each sample's radiance divided by the\n"
    "                     guarded diffuse albedo of its primary hit (docs/protocol.md §7.7); streamed\n"
    "                     with the pipeline's parameter demodulated = 1, written with dn.stat_samples\n"
    "  --reflection       also the reflection features of mirror and glossy pixels (reflection_* layers,\n"
    "                     protocol channels 15-21)\n"
    "  --out DIR          write DIR/frame_%04d.exr (dnrender layout, docs/client.md)\n"
    "  --png              with --out, also DIR/frame_%04d.png (ACES tone-mapped radiance preview)\n"
    "  --reference SPP    render SPP-sample references into the cache (reused when present);\n"
    "                     with --out also copied to DIR/ref_%04d.exr\n"
    "  --reference2       with --reference, also a second reference with an independent seed\n"
    "                     (cache ref2_%04d.exr; with --out copied to DIR/ref2_%04d.exr)\n"
    "  --cache DIR        reference cache (default $XDG_CACHE_HOME/dnrender, else\n"
    "                     ~/.cache/dnrender; never the current directory)\n"
    "  --server URL       stream frames to dnserver (tcp://HOST:PORT or unix:///path), write\n"
    "                     DIR/denoised_%04d.exr when --out is given\n"
    "  --pipeline P       server pipeline for --server (svgf, svgf-fb, ...)\n"
    "  --in-flight K      frames in flight to the server (default 2)\n"
    "  --reconnect-for S  if the server connection is lost: report the frames in flight as lost,\n"
    "                     keep reconnecting for up to S seconds, and go on in a new session\n"
    "                     (history reset; default 30)\n"
    "  --send-split       send diffuse + specular instead of radiance when the pipeline takes both\n"
    "  --share-input      let the session's watchers (dn preview) see the noisy radiance too\n"
    "  --watch-key-file F write each session's watch key and id to F (mode 0600) for\n"
    "                     `dn watch --key-file F` and `dn preview --key-file F`\n"
    "  --quiet            no per-frame lines\n"
    "  --help             this help\n"
    "Without --out, --server or --reference, frames are rendered and only timed (ms, Mrays/s).\n";

namespace {

double parse_number(const std::string& flag, const std::string& text, double lo, double hi) {
  double v = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size())
    throw UsageError(flag + ": expected a number, got '" + text + "'");
  if (!(v >= lo && v <= hi))
    throw UsageError(flag + ": " + text + " is out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return v;
}

int parse_int(const std::string& flag, const std::string& text, long long lo, long long hi) {
  long long v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size())
    throw UsageError(flag + ": expected an integer, got '" + text + "'");
  if (v < lo || v > hi)
    throw UsageError(flag + ": " + text + " is out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return static_cast<int>(v);
}

SppSchedule parse_spp_schedule(const std::string& flag, const std::string& text) {
  if (text == "stratified") return SppSchedule::Stratified;
  if (text == "random") return SppSchedule::Random;
  throw UsageError(flag + ": expected stratified or random, got '" + text + "'");
}

}  // namespace

CliOptions parse_cli(const std::vector<std::string>& args) {
  CliOptions o;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&]() -> const std::string& {
      if (i + 1 >= args.size()) throw UsageError(a + " needs a value");
      return args[++i];
    };
    if (a == "--help" || a == "-h") o.help = true;
    else if (a == "--scene") o.scene = parse_int(a, value(), 1, kSceneCount);
    else if (a == "--frames") o.frames = parse_int(a, value(), 1, 1000000);
    else if (a == "--first") o.first = parse_int(a, value(), 0, 1000000);
    else if (a == "--hold-camera") o.hold_camera = parse_int(a, value(), 0, 1000000);
    else if (a == "--width") o.render.width = parse_int(a, value(), 1, 8192);
    else if (a == "--height") o.render.height = parse_int(a, value(), 1, 8192);
    else if (a == "--spp") {
      o.render.spp = parse_number(a, value(), 0.0, 1 << 20);
      if (o.render.spp <= 0.0) throw UsageError("--spp must be > 0");
    } else if (a == "--spp-schedule") o.render.spp_schedule = parse_spp_schedule(a, value());
    else if (a == "--seed") o.render.seed = static_cast<uint32_t>(parse_int(a, value(), 0, 0x7FFFFFFF));
    else if (a == "--max-depth") o.render.max_depth = parse_int(a, value(), 1, 64);
    else if (a == "--threads") o.render.threads = parse_int(a, value(), 1, 1024);
    else if (a == "--jitter") o.render.jitter = true;
    else if (a == "--gbuffer-grid") o.render.gbuffer_grid = parse_int(a, value(), 0, 16);
    else if (a == "--extra-samples") o.render.extra_samples = parse_int(a, value(), 0, 3);
    else if (a == "--stats") o.render.channels.statistics = true;
    else if (a == "--stats-demodulated") o.render.channels.statistics = o.render.channels.statistics_demodulated = true;
    else if (a == "--reflection") o.render.channels.reflection = true;
    else if (a == "--out") o.out = value();
    else if (a == "--reference") o.reference_spp = parse_int(a, value(), 1, 1 << 20);
    else if (a == "--reference2") o.reference2 = true;
    else if (a == "--cache") o.cache = value();
    else if (a == "--server") o.server = value();
    else if (a == "--pipeline") o.pipeline = value();
    else if (a == "--in-flight") o.in_flight = parse_int(a, value(), 1, 64);
    else if (a == "--reconnect-for") o.reconnect_for_s = parse_int(a, value(), 1, 86400);
    else if (a == "--send-split") o.send_split = true;
    else if (a == "--share-input") o.share_input = true;
    else if (a == "--watch-key-file") o.watch_key_file = value();
    else if (a == "--png") o.png = true;
    else if (a == "--quiet" || a == "-q") o.quiet = true;
    else throw UsageError("unknown argument '" + a + "'");
  }
  if (!o.server.empty() && o.pipeline.empty()) throw UsageError("--server needs --pipeline");
  if (o.png && o.out.empty()) throw UsageError("--png needs --out");
  if (o.render.extra_samples > 0 && o.render.spp != 1.0)
    throw UsageError("--extra-samples needs --spp 1 (sample 0 is the guide ray through the pixel centre)");
  if (o.reference2 && !o.reference_spp) throw UsageError("--reference2 needs --reference");
  if (o.server.empty() && !o.pipeline.empty()) throw UsageError("--pipeline needs --server");
  if (o.share_input && o.server.empty()) throw UsageError("--share-input needs --server");
  if (!o.watch_key_file.empty() && o.server.empty()) throw UsageError("--watch-key-file needs --server");
  if (o.share_input && o.send_split) throw UsageError("--share-input shares the radiance plane, which --send-split does not send");
  return o;
}

namespace {

std::string frame_file(const std::string& dir, const char* pattern, int frame) {
  char name[64];
  std::snprintf(name, sizeof name, pattern, frame);
  return (std::filesystem::path(dir) / name).string();
}

void make_references(const Scene& scene, const CliOptions& o) {
  const std::string cache =
      o.cache.empty() ? default_cache_dir(std::getenv("XDG_CACHE_HOME"), std::getenv("HOME")) : o.cache;
  for (int f = o.first; f < o.first + o.frames; ++f)
    for (int index = 1; index <= (o.reference2 ? 2 : 1); ++index) {
      ReferenceRequest rq;
      rq.scene_id = o.scene;
      rq.width = o.render.width;
      rq.height = o.render.height;
      rq.frame = o.hold_camera.value_or(f);
      rq.spp = *o.reference_spp;
      rq.seed = o.render.seed;
      rq.index = index;
      rq.threads = o.render.threads;
      rq.cache_dir = cache;
      const auto t0 = std::chrono::steady_clock::now();
      bool rendered = false;
      const std::string path = ensure_reference(scene, rq, rendered);
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      // "reference2" for the second, so that scripts reading "reference rendered|reused PATH" see only the first.
      const char* what = index == 1 ? "reference" : "reference2";
      if (rendered) std::fprintf(stderr, "dnrender: %s rendered %s (%.1f s)\n", what, path.c_str(), s);
      else std::fprintf(stderr, "dnrender: %s reused %s\n", what, path.c_str());
      if (!o.out.empty()) {
        std::filesystem::create_directories(o.out);
        std::filesystem::copy_file(path, frame_file(o.out, index == 1 ? "ref_%04d.exr" : "ref2_%04d.exr", f),
                                   std::filesystem::copy_options::overwrite_existing);
      }
    }
}

}  // namespace

int run_cli(const CliOptions& o) {
  if (o.help) {
    std::fputs(kUsage, stdout);
    return 0;
  }
  const std::unique_ptr<Scene> scene = build_scene(o.scene);
  if (o.reference_spp) make_references(*scene, o);
  const bool timing_only = o.out.empty() && o.server.empty();
  if (o.reference_spp && timing_only) return 0;

  if (!o.out.empty()) std::filesystem::create_directories(o.out);
  std::unique_ptr<FrameStreamer> streamer;
  RenderSettings settings = o.render;
  if (!o.server.empty()) {
    StreamOptions so;  // by name: positional initialisation once swapped quiet and statistics_demodulated
    so.url = o.server;
    so.pipeline = o.pipeline;
    so.in_flight = o.in_flight;
    so.send_split = o.send_split;
    so.share_input = o.share_input;
    so.watch_key_file = o.watch_key_file;
    so.out_dir = o.out;
    so.statistics_demodulated = o.render.channels.statistics_demodulated;
    so.quiet = o.quiet;
    so.reconnect_for_s = o.reconnect_for_s;
    streamer = std::make_unique<FrameStreamer>(so);
    // Without --out nothing but the session sees the frame: render only what the pipeline takes.
    // With it, the files get the asked-for channels, plus the reflection features and the sample
    // statistics if the pipeline takes them.
    const ChannelSet needed = streamer->channels_needed();
    if (o.out.empty()) settings.channels = needed;
    else {
      settings.channels.reflection |= needed.reflection;
      settings.channels.statistics |= needed.statistics;
    }
    settings.channels.statistics_demodulated = o.render.channels.statistics_demodulated;
    // The server refuses a channel its pipeline does not take (INVALID_CHANNEL), so --stats
    // streams the statistics (ids 51-54) only to a pipeline whose masks list them.
    if (o.render.channels.statistics && !needed.statistics)
      std::fprintf(stderr,
                   "dnrender: --stats is ignored for streaming: pipeline %s takes no sample statistics "
                   "(stat_count, stat_mean, stat_m2, stat_m3)%s\n",
                   o.pipeline.c_str(), o.out.empty() ? "; they are not rendered" : "; they are still written to --out");
  }
  std::vector<double> ms, mrays, rays_per_pixel;
  FrameBuffers fb;
  for (int f = o.first; f < o.first + o.frames; ++f) {
    const int path_frame = o.hold_camera.value_or(f);
    const Camera camera = frame_camera(o.scene, path_frame, settings);
    const Camera previous = o.hold_camera ? camera : frame_camera(o.scene, f - 1, settings);
    render_frame_into(*scene, camera, previous, f, settings, fb);
    ms.push_back(fb.seconds * 1e3);
    mrays.push_back(static_cast<double>(fb.rays) / fb.seconds * 1e-6);
    rays_per_pixel.push_back(static_cast<double>(fb.rays) / (double(fb.width) * fb.height));
    if (!o.quiet)
      std::fprintf(stderr, "dnrender: frame %04d  %.1f ms  %.2f Mrays  %.1f Mrays/s\n", f, ms.back(),
                   static_cast<double>(fb.rays) * 1e-6, mrays.back());
    if (!o.out.empty()) {
      std::map<std::string, std::string> attributes = {{"dn.scene", scene_name(o.scene)},
                                                       {"dn.frame", std::to_string(f)},
                                                       {"dn.spp", std::to_string(o.render.spp)},
                                                       {"dn.seed", std::to_string(o.render.seed)}};
      write_frame_exr(frame_file(o.out, "frame_%04d.exr", f), fb, camera, previous, attributes);
      if (o.png) {
        const auto bytes = image::to_srgb8(fb.radiance.data(), fb.radiance.size() / 3);
        image::write_png_rgb8(frame_file(o.out, "frame_%04d.png", f), fb.width, fb.height, bytes.data());
      }
    }
    if (streamer) {
      streamer->submit(f, fb, camera, previous, f == o.first);
      if (!o.quiet && f == o.first) {
        std::string names;
        for (const auto& n : streamer->channel_names()) names += " " + n;
        std::fprintf(stderr, "dnrender: streaming to %s, pipeline %s, channels:%s\n", o.server.c_str(),
                     o.pipeline.c_str(), names.c_str());
      }
    }
  }
  if (streamer) streamer->finish();
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  };
  std::fprintf(stderr, "dnrender: %d frame%s of %dx%d at %g spp: median %.1f ms/frame, %.1f Mrays/s, %.2f rays/pixel\n",
               o.frames, o.frames == 1 ? "" : "s", o.render.width, o.render.height, o.render.spp, median(ms),
               median(mrays), median(rays_per_pixel));
  return 0;
}

}  // namespace dn::render
