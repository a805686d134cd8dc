// `dn denoise` inputs against the fake server: the positional IN, PFM and PNG
// colour, --albedo/--alb and --normal/--nrm side files, single files against
// sequences, and the errors for what it cannot read.
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

#include "args.hpp"
#include "commands.hpp"
#include "dn/image/exr_io.hpp"
#include "dn/image/pfm.hpp"
#include "dn/image/png.hpp"
#include "dn/protocol/codec.hpp"
#include "fake_server.hpp"
#include "frame_source.hpp"

namespace {

using namespace dn;
using namespace dn::protocol;
using dn::test::FakeServer;
using dn::test::Peer;
namespace fs = std::filesystem;

constexpr int W = 16, H = 12;
constexpr const char* kNoServer = "unix:///nonexistent/dn.sock";

struct Recorded {
  OpenSession open;
  std::vector<uint64_t> frames;
  std::map<uint64_t, std::map<ChannelId, std::vector<float>>> planes;  // per frame, as sent (F32)
};

// Offers svgf (test_welcome's: radiance and albedo required, normal and depth
// optional), passthrough (radiance; albedo, normal optional) and accumulate
// (radiance only), and answers each FRAME with its radiance.
void mirror_server(Peer& peer, Recorded& rec) {
  Welcome welcome = test::test_welcome();
  PipelineInfo passthrough{"passthrough", channel_bit(ChannelId::Radiance),
                           channel_bit(ChannelId::Albedo) | channel_bit(ChannelId::Normal), {}};
  PipelineInfo accumulate{"accumulate", channel_bit(ChannelId::Radiance), 0, {}};
  welcome.pipelines.push_back(passthrough);
  welcome.pipelines.push_back(accumulate);
  peer.handshake_with(welcome);
  for (;;) {
    auto m = peer.recv(10000);
    if (!m) return;
    const uint64_t id = m->header.request_id;
    if (auto* o = std::get_if<OpenSession>(&m->message)) {
      rec.open = *o;
      Session s;
      s.session_id = 5;
      s.width = o->width;
      s.height = o->height;
      s.pipeline = o->pipeline;
      s.output_format = o->output_format;
      s.channels = o->channels;
      s.watch_key = "00112233445566778899aabbccddeeff";
      s.watch_url = "";
      peer.send(s, id);
    } else if (auto* f = std::get_if<Frame>(&m->message)) {
      rec.frames.push_back(f->info.frame_index);
      std::vector<uint8_t> radiance;
      for (const auto& p : f->planes) {
        EXPECT_EQ(p.format, Format::F32);
        std::vector<float> v(p.bytes.size() / 4);
        std::memcpy(v.data(), p.bytes.data(), p.bytes.size());
        rec.planes[f->info.frame_index][p.id] = v;
        if (p.id == ChannelId::Radiance) radiance.assign(p.bytes.begin(), p.bytes.end());
      }
      Result r;
      r.session_id = f->info.session_id;
      r.frame_index = f->info.frame_index;
      if (!(m->header.flags & kFlagNoOutput)) r.planes.push_back({ChannelId::Output, Format::F32, radiance});
      peer.send(r, id);
    } else if (auto* c = std::get_if<CloseSession>(&m->message)) {
      peer.send(SessionClosed{c->session_id, rec.frames.size()}, id);
    }
  }
}

// The sRGB EOTF (IEC 61966-2-1) of an 8-bit value, in double precision.
float srgb8_to_linear(uint8_t v) {
  const double x = v / 255.0;
  return float(x <= 0.04045 ? x / 12.92 : std::pow((x + 0.055) / 1.055, 2.4));
}

std::vector<uint8_t> bytes_pattern(int seed, int w = W, int h = H) {
  std::vector<uint8_t> v(size_t(w * h * 3));
  for (size_t i = 0; i < v.size(); ++i) v[i] = uint8_t((i * 37 + size_t(seed) * 11) % 256);
  return v;
}

std::vector<float> floats_pattern(float scale, int w = W, int h = H) {
  std::vector<float> v(size_t(w * h * 3));
  for (size_t i = 0; i < v.size(); ++i) v[i] = scale * (0.5f + float(i % 29));
  return v;
}

std::string message_of(const std::vector<std::string>& args) {
  try {
    cli::run_denoise(args);
  } catch (const std::exception& e) {
    return e.what();
  }
  ADD_FAILURE() << "dn denoise succeeded";
  return {};
}

std::string usage_message_of(const std::vector<std::string>& args) {
  try {
    cli::run_denoise(args);
  } catch (const cli::UsageError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not a usage error: " << e.what();
    return e.what();
  }
  ADD_FAILURE() << "dn denoise succeeded";
  return {};
}

class DnCliInputs : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::path("/tmp") / ("dn_client_test_cli_inputs_" + std::to_string(::getpid()) + "_" +
                              ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir / "out");
  }
  void TearDown() override { fs::remove_all(dir); }
  std::string path(const std::string& name) const { return (dir / name).string(); }
  fs::path dir;
};

// IN positional, PNG colour made linear; -o a .pfm file: exactly that file, the radiance as sent.
TEST_F(DnCliInputs, PngPositionalToOneOutputFile) {
  const std::vector<uint8_t> srgb = bytes_pattern(1);
  image::write_png_rgb8(path("in.png"), W, H, srgb.data());
  Recorded rec;
  FakeServer server([&](Peer& peer) { mirror_server(peer, rec); });
  EXPECT_EQ(cli::run_denoise({path("in.png"), "-o", path("out/den.pfm"), "--pipeline", "passthrough", "--server",
                              server.url(), "--quiet"}),
            0);
  server.join();
  ASSERT_EQ(rec.open.channels.size(), 1u);
  EXPECT_EQ(rec.open.channels[0].id, ChannelId::Radiance);
  EXPECT_EQ(rec.open.width, uint32_t(W));
  EXPECT_EQ(rec.open.height, uint32_t(H));
  EXPECT_EQ(rec.frames, (std::vector<uint64_t>{0}));
  const std::vector<float>& radiance = rec.planes[0][ChannelId::Radiance];
  ASSERT_EQ(radiance.size(), srgb.size());
  for (size_t i = 0; i < srgb.size(); ++i) EXPECT_FLOAT_EQ(radiance[i], srgb8_to_linear(srgb[i])) << i;
  std::vector<std::string> written;
  for (const auto& e : fs::directory_iterator(dir / "out")) written.push_back(e.path().filename().string());
  EXPECT_EQ(written, (std::vector<std::string>{"den.pfm"}));
  int w = 0, h = 0;
  EXPECT_EQ(image::read_pfm_rgb(path("out/den.pfm"), w, h), radiance);
}

// oidnDenoise's spelling: PFM colour, --alb and --nrm; an albedo PNG is sRGB,
// a normal PNG's v is 2v - 1.
TEST_F(DnCliInputs, PfmWithAlbedoAndNormalAliases) {
  const std::vector<float> colour = floats_pattern(0.1f);
  const std::vector<uint8_t> albedo = bytes_pattern(2), normal = bytes_pattern(3);
  image::write_pfm_rgb(path("color.pfm"), W, H, colour.data());
  image::write_png_rgb8(path("albedo.png"), W, H, albedo.data());
  image::write_png_rgb8(path("normal.png"), W, H, normal.data());
  Recorded rec;
  FakeServer server([&](Peer& peer) { mirror_server(peer, rec); });
  EXPECT_EQ(cli::run_denoise({"--server", server.url(), "--pipeline", "passthrough", path("color.pfm"), "--alb",
                              path("albedo.png"), "--nrm", path("normal.png"), "-o", path("out.pfm"), "-q"}),
            0);
  server.join();
  std::vector<ChannelId> declared;
  for (const auto& c : rec.open.channels) declared.push_back(c.id);
  EXPECT_EQ(declared, (std::vector<ChannelId>{ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal}));
  auto& planes = rec.planes[0];
  EXPECT_EQ(planes[ChannelId::Radiance], colour);
  ASSERT_EQ(planes[ChannelId::Albedo].size(), albedo.size());
  ASSERT_EQ(planes[ChannelId::Normal].size(), normal.size());
  for (size_t i = 0; i < albedo.size(); ++i) {
    EXPECT_FLOAT_EQ(planes[ChannelId::Albedo][i], srgb8_to_linear(albedo[i])) << i;
    EXPECT_FLOAT_EQ(planes[ChannelId::Normal][i], float(2.0 * (normal[i] / 255.0) - 1.0)) << i;
  }
}

// A side-file pattern takes the input's frame numbers; a single side file serves every frame.
TEST_F(DnCliInputs, SideFilePatternsFollowTheInputFrames) {
  std::vector<float> nz(size_t(W * H * 3), 0.0f);  // +z everywhere
  for (size_t i = 2; i < nz.size(); i += 3) nz[i] = 1.0f;
  image::write_exr(path("normal.exr"), W, H,
                   {{"normal.X", nz.data() + 0, 3, image::ExrPixelType::Float},
                    {"normal.Y", nz.data() + 1, 3, image::ExrPixelType::Float},
                    {"normal.Z", nz.data() + 2, 3, image::ExrPixelType::Float}});
  for (int frame = 1; frame <= 3; ++frame) {
    const std::vector<float> colour = floats_pattern(float(frame)), albedo = floats_pattern(0.01f * float(frame));
    image::write_pfm_rgb(cli::format_frame_path(path("c_%04d.pfm"), frame), W, H, colour.data());
    image::write_pfm_rgb(cli::format_frame_path(path("a_####.pfm"), frame), W, H, albedo.data());
  }
  Recorded rec;
  FakeServer server([&](Peer& peer) { mirror_server(peer, rec); });
  EXPECT_EQ(cli::run_denoise({path("c_%04d.pfm"), "--albedo", path("a_####.pfm"), "--normal", path("normal.exr"),
                              "--pipeline", "passthrough", "--server", server.url(), "-o", path("out/d_%04d.pfm"),
                              "-q"}),
            0);
  server.join();
  EXPECT_EQ(rec.frames, (std::vector<uint64_t>{1, 2, 3}));
  for (int frame = 1; frame <= 3; ++frame) {
    EXPECT_EQ(rec.planes[uint64_t(frame)][ChannelId::Albedo], floats_pattern(0.01f * float(frame))) << frame;
    EXPECT_EQ(rec.planes[uint64_t(frame)][ChannelId::Normal], nz) << frame;
    EXPECT_TRUE(fs::exists(cli::format_frame_path(path("out/d_%04d.pfm"), frame))) << frame;
  }
}

// A frame missing from a side-file pattern is named before anything is sent.
TEST_F(DnCliInputs, SideFileMissingAFrameIsNamedBeforeConnecting) {
  for (int frame = 1; frame <= 3; ++frame) {
    const std::vector<float> v = floats_pattern(1.0f);
    image::write_pfm_rgb(cli::format_frame_path(path("c_%04d.pfm"), frame), W, H, v.data());
    if (frame != 2) image::write_pfm_rgb(cli::format_frame_path(path("a_%04d.pfm"), frame), W, H, v.data());
  }
  EXPECT_EQ(message_of({path("c_%04d.pfm"), "--alb", path("a_%04d.pfm"), "--pipeline", "passthrough", "--server",
                        kNoServer}),
            "--albedo: " + path("a_0002.pfm") + " (frame 2) does not exist");
  EXPECT_EQ(message_of({path("c_%04d.pfm"), "--nrm", path("n.pfm"), "--pipeline", "passthrough", "--server",
                        kNoServer}),
            "--normal: " + path("n.pfm") + " does not exist");
  EXPECT_EQ(message_of({path("c.png"), "--pipeline", "passthrough", "--server", kNoServer}),
            "input: " + path("c.png") + " does not exist");
}

// A side file of another size: both files and both sizes, and no session opened.
TEST_F(DnCliInputs, SizeMismatchNamesBothFilesAndSizes) {
  const std::vector<float> colour = floats_pattern(1.0f), small = floats_pattern(1.0f, 8, 8);
  image::write_pfm_rgb(path("color.pfm"), W, H, colour.data());
  image::write_pfm_rgb(path("albedo.pfm"), 8, 8, small.data());
  Recorded rec;
  FakeServer server([&](Peer& peer) { mirror_server(peer, rec); });
  EXPECT_EQ(message_of({path("color.pfm"), "--alb", path("albedo.pfm"), "--pipeline", "passthrough", "--server",
                        server.url(), "-q"}),
            "--albedo: " + path("albedo.pfm") + " is 8x8, but the input " + path("color.pfm") + " is 16x12");
  server.join();
  EXPECT_EQ(rec.open.width, 0u);  // never opened
}

// What cannot be read is named with the reason, before connecting.
TEST_F(DnCliInputs, UnreadableInputsAreNamedWithTheReason) {
  std::ofstream(path("text.pfm")) << "hello\n";
  EXPECT_NE(message_of({path("text.pfm"), "--pipeline", "passthrough", "--server", kNoServer})
                .find("PFM '" + path("text.pfm") + "': not a PFM: it starts with 'hello'"),
            std::string::npos);
  // An Adam7 PNG: the writer's file with its IHDR interlace byte set (and the CRC redone).
  std::vector<uint8_t> png = image::encode_png_rgb8(W, H, bytes_pattern(4).data());
  png[8 + 8 + 12] = 1;
  const uLong crc = crc32(crc32(0L, Z_NULL, 0), png.data() + 12, 17);
  for (int i = 0; i < 4; ++i) png[8 + 8 + 13 + size_t(i)] = uint8_t(crc >> (24 - 8 * i));
  std::ofstream(path("adam7.png"), std::ios::binary).write(reinterpret_cast<const char*>(png.data()), long(png.size()));
  EXPECT_EQ(message_of({path("adam7.png"), "--pipeline", "passthrough", "--server", kNoServer}),
            "PNG '" + path("adam7.png") + "': Adam7-interlaced PNGs are not supported; save it without interlacing");
  // A truncated side file.
  const std::vector<float> colour = floats_pattern(1.0f);
  image::write_pfm_rgb(path("color.pfm"), W, H, colour.data());
  const std::vector<uint8_t> whole = image::encode_png_rgb8(W, H, bytes_pattern(4).data());
  std::ofstream(path("cut.png"), std::ios::binary).write(reinterpret_cast<const char*>(whole.data()), 40);
  Recorded rec;
  FakeServer server([&](Peer& peer) { mirror_server(peer, rec); });
  EXPECT_NE(message_of({path("color.pfm"), "--nrm", path("cut.png"), "--pipeline", "passthrough", "--server",
                        server.url(), "-q"})
                .find("PNG '" + path("cut.png") + "': truncated"),
            std::string::npos);
  server.join();
}

// A PFM/PNG input gives radiance, and the side files albedo and normal: a
// pipeline that requires more is refused naming the channel, one that takes
// no albedo refuses --albedo.
TEST_F(DnCliInputs, PipelineChannelsAgainstWhatTheFilesGive) {
  const std::vector<uint8_t> srgb = bytes_pattern(5);
  image::write_png_rgb8(path("in.png"), W, H, srgb.data());
  image::write_png_rgb8(path("alb.png"), W, H, srgb.data());
  {
    Recorded rec;
    FakeServer server([&](Peer& peer) { mirror_server(peer, rec); });
    EXPECT_EQ(message_of({path("in.png"), "--pipeline", "svgf", "--server", server.url(), "-q"}),
              "pipeline 'svgf' requires channel 'albedo', but " + path("in.png") +
                  " gives only the colour (radiance); give it with --albedo FILE");
    server.join();
  }
  {
    Recorded rec;
    FakeServer server([&](Peer& peer) { mirror_server(peer, rec); });
    EXPECT_EQ(cli::run_denoise({path("in.png"), "--alb", path("alb.png"), "--pipeline", "svgf", "--server",
                                server.url(), "-q"}),
              0);
    server.join();
    ASSERT_EQ(rec.open.channels.size(), 2u);
    EXPECT_EQ(rec.open.channels[1].id, ChannelId::Albedo);
  }
  {
    Recorded rec;
    FakeServer server([&](Peer& peer) { mirror_server(peer, rec); });
    EXPECT_EQ(usage_message_of({path("in.png"), "--alb", path("alb.png"), "--pipeline", "accumulate", "--server",
                                server.url(), "-q"}),
              "--albedo: pipeline 'accumulate' does not take the albedo channel (see 'dn pipelines')");
    server.join();
  }
}

// With an EXR input a side file replaces the channel its layout gives.
TEST_F(DnCliInputs, ExrInputSideFileReplacesItsChannel) {
  const std::vector<float> rad = floats_pattern(1.0f), alb(size_t(W * H * 3), 0.5f), side = floats_pattern(0.02f);
  image::write_exr(path("f.exr"), W, H,
                   {{"radiance.R", rad.data() + 0, 3, image::ExrPixelType::Float},
                    {"radiance.G", rad.data() + 1, 3, image::ExrPixelType::Float},
                    {"radiance.B", rad.data() + 2, 3, image::ExrPixelType::Float},
                    {"albedo.R", alb.data() + 0, 3, image::ExrPixelType::Half},
                    {"albedo.G", alb.data() + 1, 3, image::ExrPixelType::Half},
                    {"albedo.B", alb.data() + 2, 3, image::ExrPixelType::Half}});
  image::write_pfm_rgb(path("side.pfm"), W, H, side.data());
  Recorded rec;
  FakeServer server([&](Peer& peer) { mirror_server(peer, rec); });
  EXPECT_EQ(cli::run_denoise({path("f.exr"), "--albedo", path("side.pfm"), "--pipeline", "svgf", "--server",
                              server.url(), "-q"}),
            0);
  server.join();
  std::vector<ChannelId> declared;
  for (const auto& c : rec.open.channels) declared.push_back(c.id);
  EXPECT_EQ(declared, (std::vector<ChannelId>{ChannelId::Radiance, ChannelId::Albedo}));
  EXPECT_EQ(rec.planes[0][ChannelId::Albedo], side);
  EXPECT_EQ(rec.planes[0][ChannelId::Radiance], rad);
}

TEST_F(DnCliInputs, BadCommandLinesAreUsageErrors) {
  const std::string in = path("in.png");
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{in, "--input", path("b.png")}, "the input is given twice, '" + in + "' and --input '" + path("b.png") + "'"},
      {{"-o", path("x.png")}, "missing the input: dn denoise IN -o OUT"},
      {{in, path("b.png")}, "unexpected argument '" + path("b.png") + "': dn denoise takes one IN"},
      {{in, "-o", path("o_%04d.png")}, "'" + path("o_%04d.png") + "' has a frame-number placeholder, but the input"},
      {{in, "--alb", path("a_####.png")}, "--albedo '" + path("a_####.png") + "' has a frame-number placeholder"},
      {{path("c_%04d.png"), "--start", "1", "--end", "2", "-o", path("o.png")}, "has no frame-number placeholder"},
      {{in, "--preset", "cycles"}, "--preset applies to EXR input only"},
      {{in, "--channel", "albedo=DiffCol"}, "--channel applies to EXR input only"},
      {{in, "--nrm", path("n.tif")}, "--normal '" + path("n.tif") + "': unknown extension '.tif'"},
      {{path("f.exr"), "--alb", path("a.pfm"), "--channel", "albedo=DiffCol"},
       "--albedo and --channel albedo=... both give the albedo channel"},
  };
  for (const auto& [extra, expected] : cases) {
    std::vector<std::string> args = {"--server", kNoServer, "--pipeline", "passthrough"};
    args.insert(args.end(), extra.begin(), extra.end());
    const std::string m = usage_message_of(args);
    EXPECT_NE(m.find(expected), std::string::npos) << m;
  }
}

TEST_F(DnCliInputs, HelpShowsThePositionalInputAndTheAliases) {
  testing::internal::CaptureStdout();
  EXPECT_EQ(cli::run_denoise({"--help"}), 0);
  const std::string help = testing::internal::GetCapturedStdout();
  for (const char* s : {"usage: dn denoise IN [-o OUT]", "--alb, --albedo FILE", "--nrm, --normal FILE", "--input IN"})
    EXPECT_NE(help.find(s), std::string::npos) << s << "\n" << help;
}

}  // namespace
