// `dn denoise` end to end against the fake server: EXR sequence in, EXR/PNG
// out, metrics against references, errors naming the frame.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "args.hpp"
#include "dn/client/endpoint.hpp"
#include "commands.hpp"
#include "dn/image/exr_io.hpp"
#include "dn/image/flip.hpp"
#include "dn/image/metrics.hpp"
#include "dn/image/pfm.hpp"
#include "dn/protocol/codec.hpp"
#include "fake_server.hpp"
#include "frame_source.hpp"
#include "reference_metrics.hpp"

namespace {

using namespace dn;
using namespace dn::protocol;
using dn::test::FakeServer;
using dn::test::Peer;
namespace fs = std::filesystem;

constexpr int W = 16, H = 12;

struct EchoLog {
  OpenSession open;
  std::vector<uint64_t> frames;
  std::vector<uint32_t> flags;
  std::vector<FrameInfo> infos;
  bool closed = false;
};

// A server that answers every FRAME with 2 * radiance (in the session's
// output format), or ERROR for frame `fail_on`.
void echo_server(Peer& peer, EchoLog& log, std::optional<uint64_t> fail_on = std::nullopt) {
  peer.handshake();
  Session session;
  for (;;) {
    auto m = peer.recv(10000);
    if (!m) return;
    const uint64_t id = m->header.request_id;
    if (auto* o = std::get_if<OpenSession>(&m->message)) {
      log.open = *o;
      session.session_id = 3;
      session.width = o->width;
      session.height = o->height;
      session.pipeline = o->pipeline;
      session.output_format = o->output_format;
      session.channels = o->channels;
      session.watch_key = "00112233445566778899aabbccddeeff";
      session.watch_url = "";  // a 1.8 server's SESSION ends with the watch URL
      peer.send(session, id);
    } else if (auto* f = std::get_if<Frame>(&m->message)) {
      log.frames.push_back(f->info.frame_index);
      log.flags.push_back(m->header.flags);
      log.infos.push_back(f->info);
      if (fail_on && f->info.frame_index == *fail_on) {
        peer.send(Error{ErrorCode::InvalidChannel, "FRAME.planes[0]", "radiance has NaNs"}, id);
        continue;
      }
      Result r;
      r.session_id = f->info.session_id;
      r.frame_index = f->info.frame_index;
      r.timings = {{"filter", 1.0}};
      std::vector<float> rgb(size_t(W * H * 3), 0.0f);
      for (const auto& p : f->planes)
        if (p.id == ChannelId::Radiance) {
          for (size_t i = 0; i < rgb.size(); ++i) {
            if (p.format == Format::F32) {
              std::memcpy(&rgb[i], p.bytes.data() + 4 * i, 4);
            } else {
              uint16_t h;
              std::memcpy(&h, p.bytes.data() + 2 * i, 2);
              rgb[i] = half_to_float(h);
            }
            rgb[i] *= 2.0f;
          }
        }
      std::vector<uint8_t> bytes;
      if (session.output_format == Format::F32) {
        bytes.resize(rgb.size() * 4);
        std::memcpy(bytes.data(), rgb.data(), bytes.size());
      } else {
        bytes.resize(rgb.size() * 2);
        for (size_t i = 0; i < rgb.size(); ++i) {
          const uint16_t h = float_to_half(rgb[i]);
          std::memcpy(bytes.data() + 2 * i, &h, 2);
        }
      }
      if (!(m->header.flags & kFlagNoOutput)) r.planes.push_back({ChannelId::Output, session.output_format, bytes});
      peer.send(r, id);
    } else if (auto* c = std::get_if<CloseSession>(&m->message)) {
      log.closed = true;
      peer.send(SessionClosed{c->session_id, log.frames.size()}, id);
    }
  }
}

// Connects to a FakeServer and hangs up, so that a server whose client never
// came (dn failed before connecting) stops waiting for one.
void poke(const std::string& url) {
  const client::Endpoint e = client::parse_endpoint(url);
  const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, e.path.c_str(), sizeof addr.sun_path - 1);
  (void)::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr);
  ::close(fd);
}

std::string file_head(const fs::path& p, size_t n) {
  std::ifstream in(p, std::ios::binary);
  std::string s(n, '\0');
  in.read(s.data(), std::streamsize(n));
  s.resize(size_t(in.gcount()));
  return s;
}

// run_denoise with stdout (or stderr) captured; an exception is a test failure
// reported after the capture ends, so that its message is seen.
int denoise_capturing(const std::vector<std::string>& args, bool capture_stderr, std::string& captured) {
  int rc = -1;
  std::string error;
  if (capture_stderr) testing::internal::CaptureStderr();
  else testing::internal::CaptureStdout();
  try {
    rc = cli::run_denoise(args);
  } catch (const std::exception& e) {
    error = e.what();
  }
  captured = capture_stderr ? testing::internal::GetCapturedStderr() : testing::internal::GetCapturedStdout();
  if (!error.empty()) ADD_FAILURE() << "dn denoise threw: " << error;
  return rc;
}

float radiance_value(int frame, size_t i) { return 0.25f * float(frame) + 0.001f * float(i % 97); }

class DnCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::path("/tmp") / ("dn_client_test_cli_" + std::to_string(::getpid()) + "_" +
                              ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir / "in");
    fs::create_directories(dir / "ref");
    // dnrender layout: radiance, albedo, normal, depth, motion + camera attributes.
    for (int frame = 1; frame <= 4; ++frame) {
      std::vector<float> rad(size_t(W * H * 3)), alb(size_t(W * H * 3), 0.5f), nrm(size_t(W * H * 3), 0.0f),
          depth(size_t(W * H), 2.0f), motion(size_t(W * H * 2), 0.0f);
      for (size_t i = 0; i < rad.size(); ++i) rad[i] = radiance_value(frame, i);
      image::ExrWriteOptions o;
      std::array<float, 16> view{};
      view[0] = view[5] = view[10] = view[15] = 1.0f;
      view[12] = float(frame);  // translation x
      o.camera.view = view;
      o.camera.projection = view;
      o.camera.jitter = std::array<float, 2>{0.5f, -0.5f};
      std::vector<image::ExrChannelOut> ch = {
          {"radiance.R", rad.data() + 0, 3, image::ExrPixelType::Float},
          {"radiance.G", rad.data() + 1, 3, image::ExrPixelType::Float},
          {"radiance.B", rad.data() + 2, 3, image::ExrPixelType::Float},
          {"albedo.R", alb.data() + 0, 3, image::ExrPixelType::Half},
          {"albedo.G", alb.data() + 1, 3, image::ExrPixelType::Half},
          {"albedo.B", alb.data() + 2, 3, image::ExrPixelType::Half},
          {"normal.X", nrm.data() + 0, 3, image::ExrPixelType::Half},
          {"normal.Y", nrm.data() + 1, 3, image::ExrPixelType::Half},
          {"normal.Z", nrm.data() + 2, 3, image::ExrPixelType::Half},
          {"depth.Z", depth.data(), 1, image::ExrPixelType::Float},
          {"motion.X", motion.data() + 0, 2, image::ExrPixelType::Float},
          {"motion.Y", motion.data() + 1, 2, image::ExrPixelType::Float},
      };
      image::write_exr(cli::format_frame_path((dir / "in/frame_%04d.exr").string(), frame), W, H, ch, o);
      std::vector<float> ref(rad);
      for (auto& v : ref) v *= 2.0f;
      image::write_exr_rgb(cli::format_frame_path((dir / "ref/ref_%04d.exr").string(), frame), W, H, ref.data(),
                           image::ExrPixelType::Float);
    }
  }
  void TearDown() override { fs::remove_all(dir); }

  std::vector<std::string> base_args(const std::string& url) {
    return {"--server", url, "--pipeline", "svgf", "--input", (dir / "in/frame_%04d.exr").string(),
            "--start", "1", "--end", "4", "--quiet"};
  }
  fs::path dir;
};

TEST_F(DnCli, DenoisesSequenceWritesOutputsAndMetrics) {
  EchoLog log;
  FakeServer server([&](Peer& peer) { echo_server(peer, log); });
  auto args = base_args(server.url());
  for (const std::string& a : {std::string("--output"), (dir / "out/den_%04d.exr").string(), std::string("--png"),
                               (dir / "png/den_####.png").string(), std::string("-r"),
                               (dir / "ref/ref_%04d.exr").string(), std::string("--in-flight"), std::string("2"),
                               std::string("--exr-float")})
    args.push_back(a);
  testing::internal::CaptureStdout();
  EXPECT_EQ(cli::run_denoise(args), 0);
  const std::string out = testing::internal::GetCapturedStdout();
  server.join();

  // Required (radiance, albedo) plus the optional channels the file has (normal, depth).
  std::vector<ChannelId> declared;
  for (const auto& c : log.open.channels) declared.push_back(c.id);
  EXPECT_EQ(declared, (std::vector<ChannelId>{ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal,
                                              ChannelId::Depth}));
  EXPECT_EQ(log.open.width, uint32_t(W));
  EXPECT_EQ(log.frames, (std::vector<uint64_t>{1, 2, 3, 4}));
  EXPECT_TRUE(log.closed);
  // Camera from the dn.* attributes; previous camera from the previous frame; reset on the first.
  ASSERT_EQ(log.infos.size(), 4u);
  EXPECT_EQ(log.infos[0].flags, kFrameReset);
  EXPECT_EQ(log.infos[1].flags, 0u);
  EXPECT_EQ(log.infos[1].view[12], 2.0f);
  EXPECT_EQ(log.infos[1].prev_view[12], 1.0f);
  EXPECT_EQ(log.infos[1].jitter[0], 0.5f);
  EXPECT_EQ(log.infos[1].motion, MotionConvention::PixelsToPrevious);
  for (int frame = 1; frame <= 4; ++frame) {
    int w = 0, h = 0;
    const auto rgb =
        image::read_exr_rgb(cli::format_frame_path((dir / "out/den_%04d.exr").string(), frame), w, h);
    ASSERT_EQ(w, W);
    EXPECT_FLOAT_EQ(rgb[7], 2.0f * radiance_value(frame, 7));
    EXPECT_TRUE(fs::exists(cli::format_frame_path((dir / "png/den_####.png").string(), frame)));
  }
  // Output == reference: RMSE 0, SSIM 1.
  EXPECT_NE(out.find("mean rmse 0.000000"), std::string::npos) << out;
  EXPECT_NE(out.find("ssim 1.00000"), std::string::npos) << out;
}

TEST_F(DnCli, NoOutputsMeansNoOutputFramesAndFp16) {
  EchoLog log;
  FakeServer server([&](Peer& peer) { echo_server(peer, log); });
  auto args = base_args(server.url());
  args.push_back("--fp16");
  args.push_back("--channels");
  args.push_back("radiance,albedo");
  EXPECT_EQ(cli::run_denoise(args), 0);
  server.join();
  ASSERT_EQ(log.open.channels.size(), 2u);
  EXPECT_EQ(log.open.channels[0].format, Format::F16);
  EXPECT_EQ(log.open.output_format, Format::F16);
  ASSERT_EQ(log.flags.size(), 4u);
  for (uint32_t f : log.flags) EXPECT_EQ(f, kFlagNoOutput);
}

TEST_F(DnCli, ServerErrorNamesTheFrame) {
  EchoLog log;
  FakeServer server([&](Peer& peer) { echo_server(peer, log, 3); });
  auto args = base_args(server.url());
  args.push_back("--output");
  args.push_back((dir / "out/den_%04d.exr").string());
  try {
    cli::run_denoise(args);
    FAIL() << "frame 3 fails";
  } catch (const std::exception& e) {
    EXPECT_STREQ(e.what(), "frame 3: server error InvalidChannel at FRAME.planes[0]: radiance has NaNs");
  }
  server.join();
}

TEST_F(DnCli, MissingRequiredChannelFailsBeforeOpeningASession) {
  EchoLog log;
  FakeServer server([&](Peer& peer) { echo_server(peer, log); });
  auto args = base_args(server.url());
  args.push_back("--channel");
  args.push_back("albedo=base_color");
  try {
    cli::run_denoise(args);
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("channel 'albedo'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("base_color"), std::string::npos) << e.what();
  }
  server.join();
  EXPECT_EQ(log.open.width, 0u);  // never opened
}

TEST_F(DnCli, UsageErrors) {
  EXPECT_THROW(cli::run_denoise({"--pipeline", "svgf"}), cli::UsageError);
  EXPECT_THROW(cli::run_denoise({"--server", "unix:///x", "--pipeline", "svgf", "--input", "a_%04d.exr", "--start",
                                 "5", "--end", "1"}),
               cli::UsageError);
  EXPECT_THROW(cli::run_denoise({"--bogus"}), cli::UsageError);
  EXPECT_THROW(cli::run_denoise({"--server", "unix:///x", "--pipeline", "svgf", "--input", "a_%04d.exr", "--start",
                                 "1", "--end", "2", "--output", "single.exr"}),
               cli::UsageError);
  EXPECT_THROW(cli::run_denoise({"--server", "unix:///x", "--pipeline", "svgf", "--input", "a.exr", "--param",
                                 "alpha"}),
               cli::UsageError);
}

// Without --start/--end: the run of existing files from the lowest number (1..4 here).
TEST_F(DnCli, DetectsTheFrameRangeWhenStartAndEndAreOmitted) {
  EchoLog log;
  FakeServer server([&](Peer& peer) { echo_server(peer, log); });
  std::vector<std::string> args = {"--server", server.url(), "--pipeline", "svgf", "--input",
                                   (dir / "in/frame_%04d.exr").string()};
  std::string err;
  EXPECT_EQ(denoise_capturing(args, true, err), 0);
  server.join();
  EXPECT_EQ(log.frames, (std::vector<uint64_t>{1, 2, 3, 4}));
  EXPECT_NE(err.find("dn: frames 1..4 (4 files) found from"), std::string::npos) << err;
}

// A missing input in the middle of the range: named, and nothing reaches the server.
TEST_F(DnCli, MissingInputFileIsNamedBeforeAnythingIsSent) {
  fs::remove(dir / "in/frame_0003.exr");
  std::atomic<bool> received{false};
  FakeServer server([&](Peer& peer) { received = peer.recv(10000).has_value(); });
  try {
    cli::run_denoise(base_args(server.url()));
    FAIL() << "frame 3 is missing";
  } catch (const std::exception& e) {
    EXPECT_EQ(std::string(e.what()), "--input: " + (dir / "in/frame_0003.exr").string() + " (frame 3) does not exist");
  }
  poke(server.url());
  server.join();
  EXPECT_FALSE(received) << "dn connected although an input was missing";
}

// -o: .pfm and .png (any case) by extension; an unknown extension is refused before connecting.
TEST_F(DnCli, OutputFormatFollowsTheExtension) {
  EchoLog log;
  FakeServer server([&](Peer& peer) { echo_server(peer, log); });
  auto args = base_args(server.url());
  args.insert(args.end(), {"-o", (dir / "out/den_%04d.PFM").string()});
  EXPECT_EQ(cli::run_denoise(args), 0);
  server.join();
  for (int frame = 1; frame <= 4; ++frame) {
    int w = 0, h = 0;
    const auto rgb = image::read_pfm_rgb(cli::format_frame_path((dir / "out/den_%04d.PFM").string(), frame), w, h);
    ASSERT_EQ(w, W);
    EXPECT_FLOAT_EQ(rgb[7], 2.0f * radiance_value(frame, 7));
  }
  EchoLog log_png;
  FakeServer png_server([&](Peer& peer) { echo_server(peer, log_png); });
  args = base_args(png_server.url());
  args.insert(args.end(), {"--output", (dir / "png/den_####.png").string()});
  EXPECT_EQ(cli::run_denoise(args), 0);
  png_server.join();
  EXPECT_EQ(file_head(dir / "png/den_0004.png", 4), "\x89PNG");

  args = base_args("unix:///nonexistent/dn.sock");
  args.insert(args.end(), {"--output", (dir / "out/den_%04d.jpg").string()});
  try {
    cli::run_denoise(args);
    FAIL() << ".jpg is not an output format";
  } catch (const cli::UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown extension '.jpg'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(".exr, .png or .pfm"), std::string::npos) << e.what();
  }
}

// --fail: 0 within the threshold, kExitThresholdExceeded (3) above it, with the verdict on stdout.
TEST_F(DnCli, FailThresholdDecidesTheExitStatus) {
  EchoLog log;
  FakeServer server([&](Peer& peer) { echo_server(peer, log); });
  auto args = base_args(server.url());
  args.insert(args.end(), {"-r", (dir / "ref/ref_%04d.exr").string(), "--fail", "0.001"});
  std::string out;
  EXPECT_EQ(denoise_capturing(args, false, out), cli::kExitOk);
  server.join();
  EXPECT_NE(out.find("PASS: 0 of 4 frames"), std::string::npos) << out;

  // A reference 1.5 times the output: relMSE about 0.2 in every frame.
  fs::create_directories(dir / "far");
  for (int frame = 1; frame <= 4; ++frame) {
    int w = 0, h = 0;
    auto ref = image::read_exr_rgb(cli::format_frame_path((dir / "ref/ref_%04d.exr").string(), frame), w, h);
    for (auto& v : ref) v *= 1.5f;
    image::write_exr_rgb(cli::format_frame_path((dir / "far/ref_%04d.exr").string(), frame), w, h, ref.data(),
                         image::ExrPixelType::Float);
  }
  EchoLog log_far;
  FakeServer far_server([&](Peer& peer) { echo_server(peer, log_far); });
  args = base_args(far_server.url());
  args.insert(args.end(), {"-r", (dir / "far/ref_%04d.exr").string(), "--fail", "0.05"});
  EXPECT_EQ(denoise_capturing(args, false, out), cli::kExitThresholdExceeded);
  far_server.join();
  EXPECT_NE(out.find("FAILURE: 4 of 4 frames (100 %) have relmse above 0.05"), std::string::npos) << out;
  EXPECT_TRUE(log_far.closed) << "the whole run is denoised before the verdict";
}

// Column NAME of a two-line --summary TSV.
double summary_column(const fs::path& file, const std::string& name) {
  std::ifstream in(file);
  std::string header, values;
  std::getline(in, header);
  std::getline(in, values);
  std::istringstream h(header), v(values);
  std::string key, value;
  while (std::getline(h, key, '\t') && std::getline(v, value, '\t'))
    if (key == name) return std::stod(value);
  ADD_FAILURE() << "no column " << name << " in " << header;
  return NAN;
}

TEST_F(DnCli, ReferenceReportsFlipAndTheInputsOwnError) {
  // The echo server's output is 2 x radiance. Against references of 1.2 x radiance
  // (frames 1, 2) the input is closer than the output; against 2.5 x (frames 3, 4)
  // the output is.
  fs::create_directories(dir / "ref_far");
  std::vector<std::vector<float>> inputs, outputs, refs;
  for (int frame = 1; frame <= 4; ++frame) {
    std::vector<float> rad(size_t(W * H * 3));
    for (size_t i = 0; i < rad.size(); ++i) rad[i] = radiance_value(frame, i);
    std::vector<float> ref(rad), out(rad);
    for (auto& v : ref) v *= frame <= 2 ? 1.2f : 2.5f;
    for (auto& v : out) v *= 2.0f;
    image::write_exr_rgb(cli::format_frame_path((dir / "ref_far/ref_%04d.exr").string(), frame), W, H, ref.data(),
                         image::ExrPixelType::Float);
    inputs.push_back(rad), outputs.push_back(out), refs.push_back(ref);
  }
  EchoLog log;
  FakeServer server([&](Peer& peer) { echo_server(peer, log); });
  auto args = base_args(server.url());
  args.erase(std::find(args.begin(), args.end(), "--quiet"));
  for (const std::string& a : {std::string("-r"), (dir / "ref_far/ref_%04d.exr").string(), std::string("--tonemap"),
                               std::string("reinhard"), std::string("--summary"), (dir / "summary.tsv").string()})
    args.push_back(a);
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  EXPECT_EQ(cli::run_denoise(args), 0);
  const std::string out = testing::internal::GetCapturedStdout(), err = testing::internal::GetCapturedStderr();
  server.join();

  double ldr = 0, hdr = 0, in_rmse = 0, in_relmse = 0;
  for (size_t k = 0; k < 4; ++k) {
    const double l = image::flip_ldr_tonemapped(outputs[k].data(), refs[k].data(), W, H, image::Tonemap::Reinhard).mean;
    const double h = image::flip_hdr(outputs[k].data(), refs[k].data(), W, H).mean;
    const double r = image::rmse(inputs[k].data(), refs[k].data(), refs[k].size());
    ASSERT_GT(l, 0.0);
    ASSERT_GT(h, 0.0);
    ldr += l / 4, hdr += h / 4, in_rmse += r / 4;
    in_relmse += image::relative_mse(inputs[k].data(), refs[k].data(), refs[k].size()) / 4;
    // Per frame: the input's error on the frame's line, ꟻLIP on a line of its own after the last frame.
    char want[160];
    std::snprintf(want, sizeof want, "input_rmse %.5f", r);
    EXPECT_NE(err.find(want), std::string::npos) << want << "\n" << err;
    std::snprintf(want, sizeof want, "frame %04zu  flip_ldr %.5f  flip_hdr %.5f", k + 1, l, h);
    EXPECT_NE(err.find(want), std::string::npos) << want << "\n" << err;
  }
  const fs::path summary = dir / "summary.tsv";
  EXPECT_NEAR(summary_column(summary, "flip_ldr"), ldr, 1e-5 * ldr);
  EXPECT_NEAR(summary_column(summary, "flip_hdr"), hdr, 1e-5 * hdr);
  EXPECT_NEAR(summary_column(summary, "input_rmse"), in_rmse, 1e-5 * in_rmse);
  EXPECT_NEAR(summary_column(summary, "input_relmse"), in_relmse, 1e-5 * in_relmse);
  EXPECT_EQ(summary_column(summary, "worse_rmse"), 2.0);
  EXPECT_EQ(summary_column(summary, "worse_relmse"), 2.0);
  // The existing columns keep their places; the new ones come after them.
  std::ifstream in(summary);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header.rfind("rmse\trelmse\tssim\te2e_ms\tserver_ms\tframes\tfps\tdevice_ms\ttemporal\t"
                         "device_bytes_per_pixel\tnc_mse\tnc_relmse\tref_noise_mse\tflip_ldr\tflip_hdr\tinput_rmse\t"
                         "input_relmse\tworse_rmse\tworse_relmse",
                         0),
            0u)
      << header;
  EXPECT_NE(out.find("output worse than input: 2 (rmse), 2 (relmse) of 4 frames"), std::string::npos) << out;
  EXPECT_NE(out.find("mean  flip_ldr "), std::string::npos) << out;
}

TEST(ReferenceMetrics, InputRadianceIsRadianceElseTheSplitSum) {
  using cli::LoadedPlane;
  const std::vector<float> r{1, 2, 3}, d{0.5f, 0.25f, 1}, s{0.25f, 0.5f, 2}, e{1, 0, 0};
  EXPECT_EQ(cli::input_radiance({{ChannelId::Diffuse, d}, {ChannelId::Radiance, r}}), r);
  EXPECT_EQ(cli::input_radiance({{ChannelId::Diffuse, d}, {ChannelId::Specular, s}}),
            (std::vector<float>{0.75f, 0.75f, 3}));
  EXPECT_EQ(cli::input_radiance({{ChannelId::Diffuse, d}, {ChannelId::Specular, s}, {ChannelId::Emission, e}}),
            (std::vector<float>{1.75f, 0.75f, 3}));
  // Lighting forms count times their albedo (Cycles: DiffDir x DiffCol); without it, not measured.
  const std::vector<float> a{2, 4, 0.5f};
  EXPECT_EQ(cli::input_radiance({{ChannelId::DiffuseLighting, d}, {ChannelId::Albedo, a}, {ChannelId::Specular, s}}),
            (std::vector<float>{1.25f, 1.5f, 2.5f}));
  EXPECT_EQ(cli::input_radiance({{ChannelId::Diffuse, d},
                                 {ChannelId::SpecularLighting, s},
                                 {ChannelId::SpecularAlbedo, a}}),
            (std::vector<float>{1, 2.25f, 2}));
  EXPECT_TRUE(cli::input_radiance({{ChannelId::DiffuseLighting, d}, {ChannelId::Specular, s}}).empty());
  EXPECT_TRUE(cli::input_radiance({{ChannelId::Diffuse, d}, {ChannelId::SpecularLighting, s}}).empty());
  // Not measured: no input error, and such frames count in neither worse_* column.
  cli::ReferenceExtrasTotals t;
  t.add_input(cli::input_error({}, r), 5.0, 5.0);
  t.add_input(cli::input_error(r, r), 1.0, NAN);  // input exact: any output error, and NaN, is worse
  EXPECT_EQ(t.input_frames, 1u);
  EXPECT_EQ(t.worse_rmse, 1u);
  EXPECT_EQ(t.worse_relmse, 1u);
}

// Each of these is a bad command line (exit status 2), found before any file is read or server reached.
TEST_F(DnCli, BadCommandLinesAreUsageErrors) {
  const std::vector<std::string> base = {"--server", "unix:///nonexistent/dn.sock", "--pipeline", "svgf", "--input",
                                         (dir / "in/frame_%04d.exr").string(), "--start", "1", "--end", "4"};
  const std::vector<std::vector<std::string>> extras = {
      {"--timeout", "-1"},          {"--timeout", "soon"},        {"--exposure", "nan"},
      {"--fail", "0.1"},            {"--fail-metric", "rmse"},     {"-r", "r_%04d.exr", "--fail", "x"},
      {"-r", "r_%04d.exr", "--fail", "1", "--fail-metric", "ssim"},
      {"-r", "r_%04d.exr", "--fail", "1", "--fail-percent", "101"},
      {"--output", "o_%04d.png", "--exr-float"},
      {"--png", "o_%04d.exr"},      {"--preset", "blender"},      {"--step", "0"},
      {"--in-flight"},              {"--quiet=yes"},              {"--output", "o_%04d"},
  };
  for (const auto& extra : extras) {
    auto args = base;
    args.insert(args.end(), extra.begin(), extra.end());
    std::string joined;
    for (const auto& a : extra) joined += a + " ";
    EXPECT_THROW(cli::run_denoise(args), cli::UsageError) << joined;
  }
  EXPECT_THROW(cli::run_denoise({"--server", "http://host:80", "--pipeline", "svgf", "--input", "a.exr"}),
               cli::UsageError);
}

// Neither --server nor $DN_SERVER: dnserver's default address.
TEST(DnCliServer, DefaultsToTheServersDefaultAddress) {
  const char* saved = std::getenv("DN_SERVER");
  const std::string saved_value = saved ? saved : "";
  ::unsetenv("DN_SERVER");
  EXPECT_EQ(cli::server_url(""), "tcp://127.0.0.1:7878");
  EXPECT_EQ(cli::server_url(""), client::kDefaultServerUrl);
  ::setenv("DN_SERVER", "unix:///tmp/x.sock", 1);
  EXPECT_EQ(cli::server_url(""), "unix:///tmp/x.sock");
  EXPECT_EQ(cli::server_url("tcp://[::1]:9"), "tcp://[::1]:9");
  EXPECT_THROW(cli::server_url("tcp://::1:9"), cli::UsageError);
  if (saved) ::setenv("DN_SERVER", saved_value.c_str(), 1);
  else ::unsetenv("DN_SERVER");
}

}  // namespace
