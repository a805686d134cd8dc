// dn denoise: stream a frame sequence or one file (EXR with its channel
// layout, or PFM / PNG colour with side files) through a server session, pipelined.
#include <cctype>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <functional>
#include <future>
#include <map>
#include <optional>

#include "args.hpp"
#include "camera_recovery.hpp"
#include "colour_frames.hpp"
#include "commands.hpp"
#include "dn/client/client.hpp"
#include "dn/client/watch_file.hpp"
#include "dn/image/exr_io.hpp"
#include "dn/image/metrics.hpp"
#include "frame_range.hpp"
#include "frame_source.hpp"
#include "input_image.hpp"
#include "output_image.hpp"
#include "presets.hpp"
#include "progress.hpp"
#include "reference_metrics.hpp"
#include "reference_threshold.hpp"
#include "reflection_features.hpp"
#include "sequence_metrics.hpp"
#include "side_files.hpp"
#include "statistics_kind.hpp"
#include "unexplained_note.hpp"

namespace dn::cli {

using protocol::ChannelId;
using protocol::Format;

namespace {

const std::vector<Args::Spec> kSpecs = {
    server_option(),
    {"pipeline", "", true, false, "denoising pipeline (default auto: the server chooses; see 'dn pipelines')", "NAME"},
    {"input", "", true, false, "the input IN as an option (the positional IN is the same)", "IN"},
    {"albedo", "--alb", true, false,
     "albedo image, sent as the albedo channel: one file, or a pattern with the input's frame numbers "
     "(.exr, .pfm, .png: sRGB)",
     "FILE"},
    {"normal", "--nrm", true, false, "normal image, sent as the normal channel, as --albedo (.png: v in [0,1] is 2v-1)",
     "FILE"},
    {"start", "", true, false, "first frame number (default: the lowest number of an existing input file)", "N"},
    {"end", "", true, false,
     "last frame number, inclusive (default: the end of the run of existing files from --start)", "M"},
    {"step", "", true, false, "frame number step (default 1)", "S"},
    {"output", "-o", true, false,
     "output file (a single-file IN) or pattern; the format follows the extension: .exr (half unless --exr-float), "
     ".png (tone-mapped) or .pfm (float)",
     "OUT"},
    {"png", "", true, false, "also write tone-mapped 8-bit PNGs to this pattern (.png)", "PATTERN"},
    {"preset", "", true, false, "channel layout of an EXR input: dnrender | cycles | auto (default auto)", "NAME"},
    {"layer", "", true, false, "Cycles view layer name (default: detected from '<layer>.Combined.R')", "NAME"},
    {"channel", "", true, true, "map a protocol channel: NAME=LAYER | NAME=A+B | NAME=C1,C2,C3 [@cycles]", "MAP"},
    {"channels", "", true, false, "send exactly these protocol channels (comma-separated)", "LIST"},
    {"fp16", "", false, false, "send input planes and receive the output as fp16", ""},
    {"output-format", "", true, false, "f32 | f16 output on the wire (default f16 with --fp16, else f32)", "FMT"},
    {"param", "", true, true, "pipeline parameter NAME=VALUE", "NAME=VALUE"},
    {"reference", "-r", true, false,
     "reference pattern (EXR, or .pfm / .png by extension): print RMSE, relMSE, SSIM, FLIP and the input's error per frame",
     "PATTERN"},
    {"fail", "", true, false,
     "with -r: a frame fails when its --fail-metric is above X; too many failing frames make dn exit 3", "X"},
    {"fail-metric", "", true, false, "relmse | rmse: the metric --fail bounds (default relmse)", "NAME"},
    {"fail-percent", "", true, false, "percentage of frames allowed to fail --fail (default 0)", "P"},
    {"reference2", "", true, false,
     "second reference independent of -r: noise-corrected MSE and the references' noise floor", "PATTERN"},
    {"in-flight", "", true, false, "frames kept in flight (default 3)", "K"},
    {"token-file", "", true, false, "file holding the auth token (default $DN_TOKEN / $DN_TOKEN_FILE)", "FILE"},
    {"tonemap", "", true, false, "PNG, SSIM and LDR-FLIP tone map: aces | reinhard | clamp (default aces)", "OP"},
    {"exposure", "", true, false, "exposure multiplier before tone mapping (default 1)", "X"},
    {"exr-float", "", false, false, "write 32-bit float output EXRs", ""},
    {"motion-convention", "", true, false,
     "motion vectors in the input: to-previous | to-next | uv (default: preset's)", "NAME"},
    {"timeout", "", true, false, "seconds to wait for any one reply (default 120)", "SECONDS"},
    {"camera", "", true, false,
     "per-frame cameras: lines 'frame N view <16> projection <16>' (default: EXR header, else from the Position pass)",
     "FILE"},
    {"summary", "", true, false, "write the mean metrics and timings as a two-line TSV to FILE", "FILE"},
    {"warmup", "", true, false,
     "denoise the first N frames but leave them out of the means (metrics, timings, temporal error)", "N"},
    {"watch-key-file", "", true, false,
     "write the session's watch key and id to FILE (mode 0600) for dn watch / dn preview --key-file FILE", "FILE"},
    {"quiet", "-q", false, false, "no per-frame output", ""},
    {"help", "-h", false, false, "this help", ""},
};

constexpr const char* kUsage =
    "usage: dn denoise IN [-o OUT] [--pipeline NAME] [--server URL] [--albedo FILE] [--normal FILE]\n"
    "                  [--start N] [--end M] [--png PATTERN] [--preset dnrender|cycles|auto]\n"
    "                  [--channel NAME=LAYER ...] [--fp16] [--param NAME=VALUE ...] [-r PATTERN [--fail X]]\n"
    "                  [--in-flight K] [--token-file FILE] [--camera FILE]\n"
    "\n"
    "IN is one file or a frame pattern ('in/frame_%04d.exr', 'in/####.png'); a single file is one\n"
    "frame and its OUT names one file. The format follows the extension: .exr (channels by --preset),\n"
    ".pfm or .png (colour only; --albedo/--alb and --normal/--nrm add those channels).\n"
    "Without --start/--end the frames are the run of consecutive existing input files from the\n"
    "lowest number found. Every input and reference file is checked before anything is sent.\n"
    "Exit status: 0 success; 1 error (server, connection, files); 2 bad command line; 3 the\n"
    "output is farther from the -r reference than --fail allows.\n";

protocol::Mat4 identity() {
  protocol::Mat4 m{};
  m[0] = m[5] = m[10] = m[15] = 1.0f;
  return m;
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

// Called in open_session's handler: --param names and values are checked
// against the server's table only after connecting, but a refused one is
// still a bad command line (nothing was sent for the session).
[[noreturn]] void rethrow_parameter_error_as_usage(const client::Error& e) {
  if (e.kind() == client::ErrorKind::Usage && e.code() == protocol::ErrorCode::InvalidParameter)
    throw UsageError(e.what());
  throw;
}

void ensure_parent_dir(const std::string& path) {
  const auto parent = std::filesystem::path(path).parent_path();
  if (!parent.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(parent, ec);
  }
}

struct Metrics {
  double rmse = 0, relmse = 0, ssim = 0;
};

struct Totals {
  size_t frames = 0, with_ref = 0, temporal_pairs = 0;
  double latency_ms = 0, server_ms = 0, device_ms = 0;
  double rmse = 0, relmse = 0, ssim = 0, temporal = 0;
};

// IN: positional, or --input as scripts written before it give it; exactly one.
std::string input_argument(const Args& args) {
  const auto& positional = args.positionals();
  const auto option = args.get("input");
  if (!positional.empty() && option)
    throw UsageError("the input is given twice, '" + positional.front() + "' and --input '" + *option +
                     "': give one");
  if (positional.empty() && !option)
    throw UsageError("missing the input: dn denoise IN -o OUT (IN a file or a frame pattern)");
  return option ? *option : positional.front();
}

// Device time of a frame: its passes, without the host-side upload and download stages.
double device_pass_ms(const client::Result& r) {
  double ms = 0;
  for (const auto& t : r.timings)
    if (t.name != "upload" && t.name != "download") ms += t.milliseconds;
  return ms;
}

}  // namespace

int run_denoise(const std::vector<std::string>& argv) {
  Args args("denoise", kSpecs, "IN", 1);
  args.parse(argv);
  if (args.has("help")) {
    std::printf("%s\noptions:\n%s", kUsage, args.usage().c_str());
    return 0;
  }

  // ---- options ---------------------------------------------------------------
  const std::string url = server_url(args.get_or("server", ""));
  const std::string preset_name = args.get_or("preset", "auto");
  try {
    make_preset(preset_name, {}, args.get_or("layer", ""));  // the name alone, before any file is read
  } catch (const ChannelMapError& e) {
    throw UsageError(std::string("--preset: ") + e.what());
  }
  const std::string pipeline_name = args.get_or("pipeline", protocol::kAutoPipeline);
  const std::string input = input_argument(args);
  const ImageFormat input_format = input_format_for(input);
  if (input_format != ImageFormat::Exr)
    for (const char* exr_only : {"preset", "layer", "channel", "channels", "camera"})
      if (args.has(exr_only))
        throw UsageError(std::string("--") + exr_only + " applies to EXR input only; '" + input +
                         "' gives the colour alone (add --albedo / --normal for those channels)");
  const auto output = args.get("output");
  const auto png = args.get("png");
  const auto reference = args.get("reference");
  const auto reference2 = args.get("reference2");
  if (reference2 && !reference) throw UsageError("--reference2 needs -r/--reference");
  const std::optional<ImageFormat> output_image =
      output ? std::optional(image_format_for(*output, "--output")) : std::nullopt;
  if (png && image_format_for(*png, "--png") != ImageFormat::Png)
    throw UsageError("--png '" + *png + "' must end in .png (--output chooses other formats by extension)");
  if (args.has("exr-float") && output_image != ImageFormat::Exr)
    throw UsageError("--exr-float needs an --output ending in .exr");
  std::optional<ThresholdCheck> threshold;
  if (args.has("fail")) {
    if (!reference) throw UsageError("--fail needs -r/--reference");
    threshold.emplace(FailThreshold{parse_fail_metric(args.get_or("fail-metric", "relmse")),
                                    args.get_double("fail", 0.0, 0.0, HUGE_VAL),
                                    args.get_double("fail-percent", 0.0, 0.0, 100.0)});
  } else if (args.has("fail-metric") || args.has("fail-percent")) {
    throw UsageError(std::string(args.has("fail-metric") ? "--fail-metric" : "--fail-percent") + " needs --fail");
  }
  const bool fp16 = args.has("fp16");
  const bool quiet = args.has("quiet");
  const bool exr_float = args.has("exr-float");
  const std::optional<long long> start_given =
      args.has("start") ? std::optional(args.get_int("start", 0, 0, INT64_MAX / 2)) : std::nullopt;
  const std::optional<long long> end_given =
      args.has("end") ? std::optional(args.get_int("end", 0, 0, INT64_MAX / 2)) : std::nullopt;
  const long long step = args.get_int("step", 1, 1, 1 << 30);
  const long long in_flight = args.get_int("in-flight", 3, 1, 1024);
  const double timeout_s = args.get_double("timeout", 120.0, kMinTimeoutSeconds, kMaxTimeoutSeconds);
  const long long warmup = args.get_int("warmup", 0, 0, INT64_MAX / 2);
  const float exposure = float(args.get_double("exposure", 1.0));
  image::Tonemap tonemap = image::Tonemap::Aces;
  try {
    tonemap = image::parse_tonemap(args.get_or("tonemap", "aces"));
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--tonemap: ") + e.what());
  }
  Format output_format = fp16 ? Format::F16 : Format::F32;
  if (auto f = args.get("output-format")) {
    if (*f == "f16") output_format = Format::F16;
    else if (*f == "f32") output_format = Format::F32;
    else throw UsageError("--output-format: expected f16 or f32, got '" + *f + "'");
  }
  std::optional<protocol::MotionConvention> motion_override;
  if (auto m = args.get("motion-convention")) {
    if (*m == "to-previous") motion_override = protocol::MotionConvention::PixelsToPrevious;
    else if (*m == "to-next") motion_override = protocol::MotionConvention::PixelsToNext;
    else if (*m == "uv") motion_override = protocol::MotionConvention::UvToPrevious;
    else throw UsageError("--motion-convention: expected to-previous, to-next or uv, got '" + *m + "'");
  }
  if (start_given && end_given && *end_given < *start_given)
    throw UsageError("--end " + std::to_string(*end_given) + " is before --start " + std::to_string(*start_given));
  std::vector<protocol::Parameter> params;
  for (const auto& p : args.all("param")) {
    auto [name, value] = split_assignment(p, "--param");
    params.push_back({name, parse_double(value, "--param " + name)});
  }
  std::vector<ChannelSpec> overrides;
  for (const auto& c : args.all("channel")) {
    try {
      overrides.push_back(parse_channel_override(c));
    } catch (const ChannelMapError& e) {
      throw UsageError(e.what());
    }
  }
  std::optional<std::vector<ChannelId>> only;
  if (auto list = args.get("channels")) {
    try {
      only = parse_channel_list(*list);
    } catch (const ChannelMapError& e) {
      throw UsageError(e.what());
    }
  }

  std::vector<long long> frames;
  const bool sequence = has_frame_placeholder(input);
  if (sequence) {
    const FrameRange range = resolve_frame_range(input, start_given, end_given, step);
    if (!range.detected.empty() && !quiet) std::fprintf(stderr, "dn: %s\n", range.detected.c_str());
    for (long long n = range.start; n <= range.end; n += step) frames.push_back(n);
  } else {
    if (end_given && *end_given != start_given.value_or(0))
      throw UsageError("the input '" + input + "' has no frame-number placeholder (%04d or ####)");
    frames.push_back(start_given.value_or(0));
    // One file in, one file out: a pattern here would be filled with a frame number nobody gave.
    for (const auto* opt : {&output, &png, &reference, &reference2})
      if (*opt && has_frame_placeholder(**opt))
        throw UsageError("'" + **opt + "' has a frame-number placeholder, but the input '" + input +
                         "' is a single file: give one file");
  }
  for (const auto* opt : {&output, &png, &reference, &reference2})
    if (*opt && frames.size() > 1 && !has_frame_placeholder(**opt))
      throw UsageError("output/reference pattern '" + **opt + "' has no frame-number placeholder (%04d or ####)");
  const std::vector<SideFile> sides = side_files_from(args, sequence);
  for (const auto& s : sides)
    for (const auto& o : overrides)
      if (o.id == s.id)
        throw UsageError(s.option + " and --channel " + std::string(protocol::find_channel(s.id)->name) +
                         "=... both give the " + std::string(protocol::find_channel(s.id)->name) + " channel");

  // Every file the run reads, before anything is sent.
  require_frame_files(frames, input, args.has("input") ? "--input" : "input");
  for (const auto& s : sides) require_frame_files(frames, s.pattern, s.option);
  if (reference) require_frame_files(frames, *reference, "-r/--reference");
  if (reference2) require_frame_files(frames, *reference2, "--reference2");

  // ---- first frame: size and channel layout ---------------------------------
  const std::string first_path = format_frame_path(input, frames.front());
  std::optional<image::ExrReader> first;   // an EXR input's first frame, open
  std::optional<LoadedFrame> first_colour;  // a PFM / PNG input's first frame, read
  Preset preset;
  if (input_format == ImageFormat::Exr) {
    first.emplace(first_path);
    preset = make_preset(preset_name, first->channels(), args.get_or("layer", ""));
  } else {
    first_colour = load_colour_frame(input, input_format, frames.front());
  }
  const int width = first ? first->width() : first_colour->width;
  const int height = first ? first->height() : first_colour->height;
  // ---- connect and open the session -----------------------------------------
  client::ConnectOptions copts;
  copts.client_name = "dn-cli";
  if (auto tf = args.get("token-file")) copts.token_file = *tf;
  copts.io_timeout = std::chrono::milliseconds(static_cast<long long>(timeout_s * 1000.0));
  client::Connection conn = client::Connection::connect(url, copts);
  const protocol::PipelineInfo* pipeline = conn.find_pipeline(pipeline_name);
  if (!pipeline && !conn.welcome().pipelines.empty()) {
    std::string names;
    for (const auto& p : conn.welcome().pipelines) names += (names.empty() ? "" : ", ") + p.name;
    throw UsageError("--pipeline: server " + conn.endpoint() + " has no pipeline '" + pipeline_name +
                     "' (it offers: " + names + ")" +
                     (pipeline_name == protocol::kAutoPipeline ? "; it cannot choose one (protocol before 1.10): name one with --pipeline" : ""));
  }
  check_side_channels(pipeline, sides, pipeline_name);

  // What each channel is made from, for the log: "radiance <- in.png".
  std::vector<std::pair<ChannelId, std::string>> sources;
  std::vector<ResolvedChannel> plan;  // an EXR input's channels, from its layout
  std::optional<RoughGuidePlan> rough_guides;
  std::optional<FrameCameras> cameras;
  std::function<LoadedFrame(size_t)> load;
  if (first) {
    // The side files' channels are theirs: the EXR layout plans the others.
    std::optional<protocol::PipelineInfo> layout_pipeline;
    if (pipeline) layout_pipeline = without_side_channels(*pipeline, sides);
    // One file is one frame: with nothing before it, its motion moves no history, and auto
    // would choose a temporal pipeline for a frame that has none.
    if (layout_pipeline && !sequence && pipeline_name == protocol::kAutoPipeline)
      layout_pipeline->optional_channels &= ~protocol::channel_bit(ChannelId::Motion);
    std::optional<std::vector<ChannelId>> layout_only = only;
    if (layout_only) std::erase_if(*layout_only, [&](ChannelId id) { return is_side_channel(sides, id); });
    plan = plan_channels(preset, overrides, layout_pipeline ? &*layout_pipeline : nullptr, layout_only,
                         first->channels(), first_path);
    // A server that lists no pipelines gets the layout's usual channels, albedo and normal among them.
    std::erase_if(plan, [&](const ResolvedChannel& ch) { return is_side_channel(sides, ch.id); });
    rough_guides = plan_rough_guides(preset, plan, first->channels());
    apply_statistics_kind(first->string_attribute("dn.stat_samples"), first_path, plan, pipeline, params);
    if (const std::string note = unexplained_pixels_note(preset, plan, rough_guides ? &*rough_guides : nullptr, pipeline, params); !note.empty())
      std::fprintf(stderr, "dn: %s\n", note.c_str());
    // Cameras: --camera FILE > the header's dn.* > recovered from the Position pass > identity (camera_recovery.hpp),
    // looked for only when the pipeline or a planned channel's conversion uses them.
    cameras.emplace(args.get_or("camera", ""), preset, first->channels(), plan_needs_camera(pipeline, plan));
    for (const auto& ch : plan) {
      std::string where;
      if (rough_guides)
        for (const auto& r : rough_guides->channels)
          if (r.id == ch.id)
            where = " where " + rough_guides->describe_rule() + ", else " + r.describe();
      sources.emplace_back(ch.id, ch.describe() + where);
    }
    load = [&](size_t i) {
      const std::string path = format_frame_path(input, frames[i]);
      image::ExrReader exr = (i == 0) ? std::move(*first) : image::ExrReader(path);
      LoadedFrame lf = load_frame(exr, plan, frames[i], rough_guides ? &*rough_guides : nullptr);
      cameras->apply(exr, frames[i], lf.camera);
      apply_camera_conversions(lf, plan, exr);
      if (rough_guides) apply_rough_guides(lf, *rough_guides);
      derive_reflection_features(lf, plan, exr);
      add_side_planes(lf, sides);
      return lf;
    };
  } else {
    plan_colour_channels(pipeline, pipeline_name, sides, first_path);
    sources.emplace_back(ChannelId::Radiance, input);
    load = [&](size_t i) {
      LoadedFrame lf = (i == 0) ? std::move(*first_colour) : load_colour_frame(input, input_format, frames[i]);
      add_side_planes(lf, sides);
      return lf;
    };
  }
  for (const auto& s : sides) sources.emplace_back(s.id, s.pattern + " (" + s.option + ")");
  // The first frame is made in full (channels, camera, conversions) before the session opens: a file that
  // cannot give what the pipeline needs is refused with nothing opened on the server.
  LoadedFrame first_frame = load(0);

  client::SessionDesc desc;
  desc.width = uint32_t(width);
  desc.height = uint32_t(height);
  desc.pipeline = pipeline_name;
  desc.output_format = output_format;
  desc.parameters = params;
  desc.max_in_flight = uint32_t(in_flight);
  for (const auto& source : sources) desc.channel(source.first, wire_format(source.first, fp16));

  if (!quiet) {
    const std::string layout = first ? "preset " + preset.name : std::string(input_format == ImageFormat::Png ? "PNG" : "PFM") + " colour";
    std::fprintf(stderr, "dn: %s (%s), %dx%d, pipeline %s, %s, %zu frame%s\n", conn.endpoint().c_str(),
                 conn.welcome().device_name.c_str(), width, height, pipeline_name.c_str(), layout.c_str(),
                 frames.size(), frames.size() == 1 ? "" : "s");
    for (const auto& [id, from] : sources)
      std::fprintf(stderr, "dn:   %-12s <- %s\n", protocol::find_channel(id)->name.data(), from.c_str());
  }
  client::Session session = [&] {
    try {
      return conn.open_session(desc);
    } catch (const client::Error& e) {
      rethrow_parameter_error_as_usage(e);
    }
  }();
  // The watch key reaches watchers through a file or the environment, never a command line.
  const std::string watch_key_file = args.get_or("watch-key-file", "");
  if (!watch_key_file.empty()) client::write_watch_file(watch_key_file, {session.watch_key(), session.id()});
  if (!quiet && session.info().pipeline_reason && !session.info().pipeline_reason->empty())
    std::fprintf(stderr, "dn: %s chose pipeline %s: %s\n", pipeline_name.c_str(), session.info().pipeline.c_str(),
                 session.info().pipeline_reason->c_str());
  if (!quiet) std::fputs(client::owner_hints("dn", session, watch_key_file).c_str(), stderr);

  // The summary's temporal error needs the frames too.
  const bool want_output = output || png || reference || args.has("summary");
  const auto motion = motion_override.value_or(protocol::MotionConvention::PixelsToPrevious);

  // ---- the pipelined loop ------------------------------------------------------
  Progress progress(frames.size(), Progress::stderr_is_tty(), quiet);
  Totals totals;
  NoiseCorrectedTotals nc_totals;
  ReferenceExtrasTotals extras;
  // The noisy radiance of each frame in flight (with -r), for its own error.
  std::map<long long, std::vector<float>> inputs;
  // ꟻLIP runs after the last frame so that its cost stays out of the timings: the
  // outputs wait here, up to a memory budget past which they are measured at once.
  struct PendingFlip {
    long long number;
    std::vector<float> rgb;
  };
  std::vector<PendingFlip> pending_flip;
  size_t pending_flip_bytes = 0;
  constexpr size_t kPendingFlipBudget = size_t(512) << 20;
  std::vector<std::string> flip_lines;
  const auto t_begin = std::chrono::steady_clock::now();
  std::deque<long long> submitted;  // frame numbers in flight, in order
  std::vector<float> previous_rgb;  // the last output, for the temporal error
  long long handled = 0;            // results received so far

  auto handle = [&](const client::Result& r) {
    const long long number = (long long)r.frame_index;
    submitted.pop_front();
    std::vector<float> rgb;
    if (r.has_output()) rgb = r.rgb();
    const long long position = handled++;
    const bool measured = position >= warmup;
    const ImageWriteOptions write_options{exr_float ? image::ExrPixelType::Float : image::ExrPixelType::Half, tonemap,
                                          exposure};
    if (output)
      write_image(format_frame_path(*output, number), *output_image, int(r.width), int(r.height), rgb.data(),
                  write_options);
    if (png)
      write_image(format_frame_path(*png, number), ImageFormat::Png, int(r.width), int(r.height), rgb.data(),
                  write_options);
    std::optional<Metrics> m;
    std::optional<NoiseCorrected> nc;
    std::optional<InputError> in_err;
    std::optional<FlipMetrics> flip_now;
    if (reference) {
      int rw = 0, rh = 0;
      const std::string path = format_frame_path(*reference, number);
      const std::vector<float> ref = read_reference_rgb(path, rw, rh);
      if (rw != int(r.width) || rh != int(r.height))
        throw std::runtime_error("reference " + path + " is " + std::to_string(rw) + "x" + std::to_string(rh) +
                                 ", the output is " + std::to_string(r.width) + "x" + std::to_string(r.height));
      m = Metrics{image::rmse(rgb.data(), ref.data(), rgb.size()),
                  image::relative_mse(rgb.data(), ref.data(), rgb.size()),
                  image::ssim_tonemapped(rgb.data(), ref.data(), rw, rh, tonemap, exposure)};
      if (reference2) {
        nc = noise_corrected_metrics(rgb, ref, rw, rh, format_frame_path(*reference2, number));
        if (measured) nc_totals.add(*nc);
      }
      if (measured && threshold) threshold->add(number, m->rmse, m->relmse);
      if (auto it = inputs.find(number); it != inputs.end()) {
        in_err = input_error(it->second, ref);
        inputs.erase(it);
        if (measured) extras.add_input(*in_err, m->rmse, m->relmse);
      }
      if (measured) {
        const size_t bytes = rgb.size() * sizeof(float);
        if (pending_flip_bytes + bytes <= kPendingFlipBudget) {
          pending_flip.push_back({number, rgb});
          pending_flip_bytes += bytes;
        } else {
          flip_now = flip_metrics(rgb, ref, rw, rh, tonemap, exposure);
          extras.add_flip(*flip_now);
        }
      }
      if (measured) {
        totals.with_ref++;
        totals.rmse += m->rmse;
        totals.relmse += m->relmse;
        totals.ssim += m->ssim;
      }
    }
    if (measured) {
      totals.frames++;
      totals.latency_ms += r.latency.count();
      totals.server_ms += r.total_timing_ms();
      totals.device_ms += device_pass_ms(r);
    }
    if (position > warmup && !rgb.empty() && previous_rgb.size() == rgb.size()) {
      totals.temporal += image::temporal_error(rgb.data(), previous_rgb.data(), size_t(r.width) * r.height);
      totals.temporal_pairs++;
    }
    previous_rgb = std::move(rgb);

    char head[96];
    std::snprintf(head, sizeof head, "frame %04lld  e2e %.1f ms  server %.1f ms", number, r.latency.count(),
                  r.total_timing_ms());
    std::string line = head + samples_status(r.samples);
    if (!r.timings.empty()) {
      line += " [";
      for (size_t i = 0; i < r.timings.size(); ++i)
        line += (i ? ", " : "") + r.timings[i].name + " " + fmt("%.2f", r.timings[i].milliseconds);
      line += "]";
    }
    if (auto cam = cameras ? cameras->record(number) : std::nullopt; cam && cam->source == FrameCameras::Source::Recovered)
      line += fmt("  camera residual %.3f px", cam->rms_px);
    std::string status = fmt("e2e %.1f ms", r.latency.count()) + fmt("  server %.1f ms", r.total_timing_ms());
    if (m) {
      const std::string q = fmt("  rmse %.5f", m->rmse) + fmt("  relmse %.5f", m->relmse) + fmt("  ssim %.4f", m->ssim);
      line += q;
      if (nc) line += noise_corrected_status(*nc);
      if (in_err) line += input_error_status(*in_err);
      if (flip_now) line += flip_status(*flip_now);
      status += fmt("  rmse %.5f", m->rmse) + fmt("  ssim %.4f", m->ssim);
    }
    progress.frame_done(line, status);
  };
  // Attach the frame number to errors thrown for a frame.
  auto collect = [&](bool newest, auto&& fn) {
    try {
      return fn();
    } catch (const client::Error& e) {
      const long long n = submitted.empty() ? -1 : newest ? submitted.back() : submitted.front();
      throw std::runtime_error("frame " + std::to_string(n) + ": " + e.what());
    }
  };

  std::future<LoadedFrame> next;
  for (size_t i = 0; i < frames.size(); ++i) {
    LoadedFrame f = i == 0 ? std::move(first_frame) : next.get();
    if (i + 1 < frames.size()) next = std::async(std::launch::async, load, i + 1);
    if (f.width != width || f.height != height)
      throw std::runtime_error(f.path + " is " + std::to_string(f.width) + "x" + std::to_string(f.height) +
                               ", the sequence started at " + std::to_string(width) + "x" + std::to_string(height));
    client::FrameInput in;
    in.frame_index = uint64_t(f.number);
    in.no_output = !want_output;
    in.info.motion = motion;
    in.info.view = f.camera.view.value_or(identity());
    in.info.projection = f.camera.projection.value_or(identity());
    if (f.camera.jitter) in.info.jitter = *f.camera.jitter;
    if (f.camera.prev_view && f.camera.prev_projection) {
      in.fill_previous_camera = false;
      in.info.prev_view = *f.camera.prev_view;
      in.info.prev_projection = *f.camera.prev_projection;
      in.info.prev_jitter = f.camera.prev_jitter.value_or(std::array<float, 2>{});
    }
    if (i == 0) in.reset();
    if (reference) inputs[f.number] = input_radiance(f.planes);
    for (const auto& p : f.planes) in.add(p.id, std::span<const float>(p.data));
    submitted.push_back(f.number);
    collect(true, [&] { return session.submit(in); });
    while (auto r = collect(false, [&] { return session.poll(); })) handle(*r);
  }
  while (session.in_flight() > 0) handle(collect(false, [&] { return session.wait(); }));
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_begin).count();
  progress.finish();
  session.close();
  for (const auto& p : pending_flip) {
    int rw = 0, rh = 0;
    const std::vector<float> ref = read_reference_rgb(format_frame_path(*reference, p.number), rw, rh);
    const FlipMetrics f = flip_metrics(p.rgb, ref, rw, rh, tonemap, exposure);
    extras.add_flip(f);
    char head[32];
    std::snprintf(head, sizeof head, "frame %04lld", p.number);
    flip_lines.push_back(head + flip_status(f));
  }
  if (!quiet)
    for (const auto& l : flip_lines) std::fprintf(stderr, "%s\n", l.c_str());

  if (!quiet) {
    const double n = double(std::max<size_t>(totals.frames, 1));
    std::fprintf(stderr, "dn: %zu frames in %.2f s (%.2f fps), mean e2e %.1f ms, mean server %.1f ms\n", totals.frames,
                 wall, wall > 0 ? double(handled) / wall : 0.0, totals.latency_ms / n, totals.server_ms / n);
    if (cameras) std::fprintf(stderr, "dn: %s\n", cameras->summary().c_str());
  }
  if (reference && totals.with_ref) {
    const double n = double(totals.with_ref);
    std::printf("mean rmse %.6f  relmse %.6f  ssim %.5f  (%zu frames, ssim on %s-tone-mapped luma)\n",
                totals.rmse / n, totals.relmse / n, totals.ssim / n, totals.with_ref, image::to_string(tonemap));
    if (nc_totals.frames) std::printf("mean%s\n", noise_corrected_status(nc_totals.mean()).c_str());
    if (extras.flip_frames)
      std::printf("mean%s  (%zu frames, ldr on %s-tone-mapped images)\n", flip_status(extras.flip_mean()).c_str(),
                  extras.flip_frames, image::to_string(tonemap));
    if (extras.input_frames)
      std::printf("mean%s  output worse than input: %zu (rmse), %zu (relmse) of %zu frames\n",
                  input_error_status(extras.input_mean()).c_str(), extras.worse_rmse, extras.worse_relmse,
                  extras.input_frames);
  }
  if (threshold) std::printf("%s\n", threshold->verdict().c_str());
  if (auto summary = args.get("summary")) {
    ensure_parent_dir(*summary);
    std::FILE* f = std::fopen(summary->c_str(), "w");
    if (!f) throw std::runtime_error("cannot write --summary file " + *summary);
    const double n = double(std::max<size_t>(totals.frames, 1));
    const double r = double(std::max<size_t>(totals.with_ref, 1));
    const bool have_ref = totals.with_ref > 0;
    const double pixels = double(session.info().width) * session.info().height;
    std::fprintf(f, "rmse\trelmse\tssim\te2e_ms\tserver_ms\tframes\tfps\tdevice_ms\ttemporal\tdevice_bytes_per_pixel%s%s\n",
                 noise_corrected_summary_header(), reference_extras_summary_header());
    std::fprintf(f, "%.6g\t%.6g\t%.6g\t%.3f\t%.3f\t%zu\t%.3f\t%.3f\t%.6g\t%.1f%s%s\n", have_ref ? totals.rmse / r : NAN,
                 have_ref ? totals.relmse / r : NAN, have_ref ? totals.ssim / r : NAN, totals.latency_ms / n,
                 totals.server_ms / n, totals.frames, wall > 0 ? double(handled) / wall : 0.0,
                 totals.device_ms / n, totals.temporal_pairs ? totals.temporal / double(totals.temporal_pairs) : NAN,
                 pixels > 0 ? double(session.info().device_bytes) / pixels : 0.0,
                 noise_corrected_summary_values(nc_totals.mean()).c_str(),
                 reference_extras_summary_values(extras).c_str());
    std::fclose(f);
  }
  return threshold && threshold->failed() ? kExitThresholdExceeded : kExitOk;
}

}  // namespace dn::cli
