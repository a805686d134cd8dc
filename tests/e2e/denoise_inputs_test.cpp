// `dn denoise` asks only for what the chosen pipeline uses, against a real
// dnserver: passthrough and accumulate on a bare RGBA EXR and on the
// committed Cycles fixtures without their Denoising Data and Position passes
// (written here at run time), and a file that cannot give what the pipeline
// needs is refused before any session is opened.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <random>

#include "command.hpp"
#include "dn/image/exr_io.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 3;  // the fixtures' frame_0000 .. frame_0002

std::string frame_name(const std::string& stem, int n) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%s_%04d.exr", stem.c_str(), n);
  return buf;
}

// Copies an EXR keeping the channels `keep` accepts, each as 32-bit float.
void copy_channels(const std::string& from, const std::string& to, const std::function<bool(const std::string&)>& keep) {
  const image::ExrReader in(from);
  std::vector<std::string> names;
  for (const auto& c : in.channels())
    if (keep(c)) names.push_back(c);
  const std::vector<float> data = in.read(names);
  std::vector<image::ExrChannelOut> out;
  for (size_t i = 0; i < names.size(); ++i)
    out.push_back({names[i], data.data() + i, names.size(), image::ExrPixelType::Float});
  image::write_exr(to, in.width(), in.height(), out);
}

bool is_denoising_data(const std::string& c) { return c.find(".Denoising ") != std::string::npos; }
bool is_position(const std::string& c) { return c.find(".Position.") != std::string::npos; }

class DenoiseInputs : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("dn-inputs-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // The fixtures with the channels `keep` accepts, as in/frame_%04d.exr.
  void write_cycles_variant(const std::function<bool(const std::string&)>& keep) {
    fs::create_directories(dir_ / "in");
    for (int n = 0; n < kFrames; ++n)
      copy_channels(std::string(DN_CYCLES_FIXTURES) + "/" + frame_name("frame", n), (dir_ / "in" / frame_name("frame", n)).string(),
                    keep);
  }

  // dn denoise of in/frame_%04d.exr into out_<pipeline>/f_%04d.exr (32-bit float).
  int denoise(const ServerProcess& server, const std::string& pipeline, const std::string& preset, std::string& log) {
    return run_command(std::string(DN_DN_PATH) + " denoise -q --server " + server.tcp_url() + " --pipeline " +
                           pipeline + " --preset " + preset + " --input '" + (dir_ / "in").string() +
                           "/frame_%04d.exr' --exr-float -o '" + (dir_ / ("out_" + pipeline)).string() +
                           "/f_%04d.exr'",
                       log);
  }

  // Output frame n of `pipeline` as interleaved RGB.
  std::vector<float> output(const std::string& pipeline, int n) {
    int w = 0, h = 0;
    return image::read_exr_rgb((dir_ / ("out_" + pipeline) / frame_name("f", n)).string(), w, h);
  }

  fs::path dir_;
};

bool session_opened(ServerProcess& server) { return server.log().find("event=session.open") != std::string::npos; }

// An image's RGB as the server receives it through passthrough: the input, exactly.
std::vector<float> rgb_of(const std::string& path, const std::string& r, const std::string& g, const std::string& b) {
  return image::ExrReader(path).read({r, g, b});
}

TEST_F(DenoiseInputs, BareRgbaExrThroughPassthroughAndAccumulate) {
  fs::create_directories(dir_ / "in");
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 4.0f);
  const int w = 64, h = 36;
  for (int n = 0; n < kFrames; ++n) {
    std::vector<float> rgba(size_t(w) * h * 4);
    for (float& v : rgba) v = u(rng);
    std::vector<image::ExrChannelOut> ch;
    for (int k = 0; k < 4; ++k) ch.push_back({std::string(1, "RGBA"[k]), rgba.data() + k, 4, image::ExrPixelType::Float});
    image::write_exr((dir_ / "in" / frame_name("frame", n)).string(), w, h, ch);
  }
  ServerProcess server;
  std::string log;
  ASSERT_EQ(denoise(server, "passthrough", "auto", log), 0) << log;
  for (int n = 0; n < kFrames; ++n)
    EXPECT_EQ(output("passthrough", n), rgb_of((dir_ / "in" / frame_name("frame", n)).string(), "R", "G", "B"))
        << "frame " << n;

  // accumulate requires normal, depth and motion: refused, naming the channel, before a session is opened.
  ServerProcess fresh;
  EXPECT_EQ(denoise(fresh, "accumulate", "auto", log), 1) << log;
  EXPECT_NE(log.find("requires channel 'normal'"), std::string::npos) << log;
  EXPECT_NE(log.find("--channel normal=LAYER"), std::string::npos) << log;
  EXPECT_FALSE(session_opened(fresh)) << fresh.log();
}

TEST_F(DenoiseInputs, CyclesWithoutDenoisingDataOrPositionThroughPassthroughAndAccumulate) {
  write_cycles_variant([](const std::string& c) { return !is_denoising_data(c) && !is_position(c); });
  ServerProcess server;
  for (const char* pipeline : {"passthrough", "accumulate"}) {
    SCOPED_TRACE(pipeline);
    std::string log;
    ASSERT_EQ(denoise(server, pipeline, "cycles", log), 0) << log;
    for (int n = 0; n < kFrames; ++n) {
      const std::vector<float> out = output(pipeline, n);
      const std::vector<float> in = rgb_of((dir_ / "in" / frame_name("frame", n)).string(), "ViewLayer.Combined.R",
                                           "ViewLayer.Combined.G", "ViewLayer.Combined.B");
      ASSERT_EQ(out.size(), in.size());
      if (std::string(pipeline) == "passthrough") EXPECT_EQ(out, in) << "frame " << n;
      for (float v : out) ASSERT_TRUE(std::isfinite(v)) << "frame " << n;
    }
  }
}

TEST_F(DenoiseInputs, CyclesWithoutDenoisingDataThroughPassthrough) {
  // Position kept: the reflection features could be made from it, but
  // passthrough does not use them.
  write_cycles_variant([](const std::string& c) { return !is_denoising_data(c); });
  ServerProcess server;
  std::string log;
  ASSERT_EQ(denoise(server, "passthrough", "cycles", log), 0) << log;
  EXPECT_EQ(output("passthrough", 1), rgb_of((dir_ / "in" / frame_name("frame", 1)).string(), "ViewLayer.Combined.R",
                                              "ViewLayer.Combined.G", "ViewLayer.Combined.B"));
  // reflect requires them, and they are made from the Denoising
  // Data: refused before a session is opened, naming the channel and the passes.
  ServerProcess fresh;
  EXPECT_EQ(denoise(fresh, "reflect", "cycles", log), 1) << log;
  EXPECT_NE(log.find("requires channel 'reflection_"), std::string::npos) << log;
  EXPECT_NE(log.find("Denoising Data"), std::string::npos) << log;
  EXPECT_FALSE(session_opened(fresh)) << fresh.log();
}

TEST_F(DenoiseInputs, AMissingCameraIsReportedBeforeTheSessionOpens) {
  // svgf's depth is the Denoising Depth made a view depth with the camera,
  // which the file cannot give without its Position pass.
  write_cycles_variant([](const std::string& c) { return !is_position(c); });
  ServerProcess server;
  std::string log;
  EXPECT_EQ(denoise(server, "svgf", "cycles", log), 1) << log;
  EXPECT_NE(log.find("camera"), std::string::npos) << log;
  EXPECT_NE(log.find("--camera FILE"), std::string::npos) << log;
  EXPECT_FALSE(session_opened(server)) << server.log();
}

}  // namespace
}  // namespace dn::test
