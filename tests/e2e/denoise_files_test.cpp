// `dn denoise` on the files people already have (oidnDenoise's PFM and PNG,
// with albedo and normal side files, a Blender EXR with its default passes)
// against a real dnserver: passthrough returns the colour, so the output file
// must equal the input file; image denoises it; without --pipeline the
// server chooses.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "command.hpp"
#include "dn/image/pfm.hpp"
#include "dn/image/png.hpp"
#include "dn/image/png_read.hpp"
#include "server_process.hpp"
#include "summary_file.hpp"

namespace dn::test {
namespace {

namespace fs = std::filesystem;

constexpr int W = 16, H = 8;

double squared_error(const std::vector<float>& a, const std::vector<float>& b) {
  double sum = 0.0;
  for (size_t i = 0; i < a.size(); ++i) sum += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
  return sum;
}

class DenoiseFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("dn-denoise-files-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  // dn denoise with `args` against `server`; its exit status, `output` its stdout and stderr.
  int dn_denoise(const ServerProcess& server, const std::string& args, std::string& output) const {
    return run_command(std::string(DN_DN_PATH) + " denoise --server " + server.unix_url() + " " + args, output);
  }
  // Writes color.pfm, albedo.pfm and normal.pfm (each w x h rgb) and runs
  // `dn denoise color.pfm --alb albedo.pfm --nrm normal.pfm -o out.pfm` with `args`.
  int denoise_trio(const ServerProcess& server, int w, int h, const std::vector<float>& colour,
                   const std::vector<float>& albedo, const std::vector<float>& normal, const std::string& args,
                   std::string& output) const {
    image::write_pfm_rgb(path("color.pfm"), w, h, colour.data());
    image::write_pfm_rgb(path("albedo.pfm"), w, h, albedo.data());
    image::write_pfm_rgb(path("normal.pfm"), w, h, normal.data());
    return dn_denoise(server,
                      "'" + path("color.pfm") + "' --alb '" + path("albedo.pfm") + "' --nrm '" + path("normal.pfm") +
                          "' -o '" + path("out.pfm") + "' " + args,
                      output);
  }
  fs::path dir_;
};

// 8-bit sRGB in, passthrough, 8-bit sRGB out: --tonemap clamp makes the
// output's encoding the inverse of the input's decoding.
TEST_F(DenoiseFiles, PngThroughPassthroughIsTheSamePng) {
  std::vector<uint8_t> srgb(size_t(W * H * 3));
  for (size_t i = 0; i < srgb.size(); ++i) srgb[i] = uint8_t((i * 97 + 13) % 256);
  srgb[0] = 0;
  srgb[1] = 255;
  image::write_png_rgb8(path("in.png"), W, H, srgb.data());
  ServerProcess server;
  std::string log;
  ASSERT_EQ(dn_denoise(server, "'" + path("in.png") + "' -o '" + path("out.png") + "' --pipeline passthrough --tonemap clamp",
                       log),
            0)
      << log;
  int w = 0, h = 0;
  const std::vector<float> in = image::read_png_rgb(path("in.png"), w, h, image::PngTransfer::Linear);
  const std::vector<float> out = image::read_png_rgb(path("out.png"), w, h, image::PngTransfer::Linear);
  ASSERT_EQ(w, W);
  ASSERT_EQ(h, H);
  ASSERT_EQ(out.size(), in.size());
  for (size_t i = 0; i < in.size(); ++i) EXPECT_NEAR(out[i], in[i], 0.5 / 255.0) << i;
}

// oidnDenoise's command line, PFM in and out (fp32): the colour exactly.
TEST_F(DenoiseFiles, PfmWithAlbedoAndNormalThroughPassthroughIsTheColour) {
  std::vector<float> colour(size_t(W * H * 3)), albedo(colour.size()), normal(colour.size(), 0.0f);
  for (size_t i = 0; i < colour.size(); ++i) {
    colour[i] = 0.013f * float(i % 61) + (i % 7 == 0 ? 20.0f : 0.0f);  // HDR values too
    albedo[i] = 0.1f + 0.8f * float(i % 11) / 10.0f;
  }
  for (size_t i = 2; i < normal.size(); i += 3) normal[i] = 1.0f;
  ServerProcess server;
  std::string log;
  ASSERT_EQ(denoise_trio(server, W, H, colour, albedo, normal, "--pipeline passthrough", log), 0) << log;
  EXPECT_NE(log.find("albedo       <- " + path("albedo.pfm") + " (--albedo)"), std::string::npos) << log;
  EXPECT_NE(log.find("normal       <- " + path("normal.pfm") + " (--normal)"), std::string::npos) << log;
  int w = 0, h = 0;
  EXPECT_EQ(image::read_pfm_rgb(path("out.pfm"), w, h), colour);
  EXPECT_EQ(w, W);
  EXPECT_EQ(h, H);
}

// oidnDenoise's job done: a noisy colour (a smooth gradient times samples
// uniform in [0, 2], seeded) with its albedo and normal, through image: the
// output is closer to the noise-free colour than the input, in RMSE.
TEST_F(DenoiseFiles, NoisyPfmTrioThroughImageComesOutCloserToTheTruth) {
  constexpr int w = 48, h = 32;
  std::vector<float> truth(size_t(w * h * 3)), noisy(truth.size()), albedo(truth.size(), 0.5f), normal(truth.size(), 0.0f);
  uint32_t state = 12345;
  auto uniform02 = [&] { state = state * 1664525u + 1013904223u; return 2.0f * float(state >> 8) / float(1u << 24); };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int k = 0; k < 3; ++k) {
        const size_t i = size_t((y * w + x) * 3 + k);
        truth[i] = 0.5f * (0.2f + 0.8f * float(x) / w);
        noisy[i] = truth[i] * uniform02();
      }
  for (size_t i = 2; i < normal.size(); i += 3) normal[i] = 1.0f;
  ServerProcess server;
  std::string log;
  ASSERT_EQ(denoise_trio(server, w, h, noisy, albedo, normal, "--pipeline image -q", log), 0) << log;
  int ow = 0, oh = 0;
  const std::vector<float> out = image::read_pfm_rgb(path("out.pfm"), ow, oh);
  ASSERT_EQ(out.size(), truth.size());
  EXPECT_LT(squared_error(out, truth), 0.25 * squared_error(noisy, truth));  // RMSE at most half the input's
}

// -r takes a PFM or a PNG reference by its extension, as the input: the
// summary's RMSE of the output and of the input are those against the
// reference as this test reads it (a PNG as sRGB-decoded 8-bit values).
TEST_F(DenoiseFiles, APfmOrPngReferenceIsMeasuredByItsExtension) {
  constexpr int w = 24, h = 16;
  const size_t values = size_t(w * h * 3);
  std::vector<float> noisy(values), albedo(values, 0.5f), normal(values);
  std::vector<uint8_t> truth8(values);
  for (size_t i = 0; i < values; ++i) {
    truth8[i] = uint8_t(40 + (i * 7) % 160);
    noisy[i] = (i % 3 == 2 ? 0.0f : 1.0f) * float(i % 5) * 0.1f;
    normal[i] = i % 3 == 2 ? 1.0f : 0.0f;
  }
  image::write_png_rgb8(path("truth.png"), w, h, truth8.data());
  int pw = 0, ph = 0;
  const std::vector<float> truth = image::read_png_rgb(path("truth.png"), pw, ph, image::PngTransfer::Srgb);
  ASSERT_EQ(truth.size(), values);
  image::write_pfm_rgb(path("truth.pfm"), w, h, truth.data());
  ServerProcess server;
  for (const char* reference : {"truth.pfm", "truth.png"}) {
    SCOPED_TRACE(reference);
    std::string log;
    const std::string args = "--pipeline image -q -r '" + path(reference) + "' --summary '" + path("s.tsv") + "'";
    ASSERT_EQ(denoise_trio(server, w, h, noisy, albedo, normal, args, log), 0) << log;
    int ow = 0, oh = 0;
    const std::vector<float> out = image::read_pfm_rgb(path("out.pfm"), ow, oh);
    const auto summary = test::summary_columns(path("s.tsv"));
    const double n = double(truth.size());
    EXPECT_NEAR(summary.at("rmse"), std::sqrt(squared_error(out, truth) / n), 1e-4);
    EXPECT_NEAR(summary.at("input_rmse"), std::sqrt(squared_error(noisy, truth) / n), 1e-4);
  }
}

// The three files of the common job, each with one command and no --pipeline:
// the server chooses (image for each), dn says so, and the output is closer
// to the truth than the input (a reference for the Blender file).
TEST_F(DenoiseFiles, WithoutAPipelineTheServerChoosesForEachKindOfFile) {
  ServerProcess server;
  const std::string chose_image = "dn: auto chose pipeline image: ";

  // Blender EXRs at 1 spp against their 64-spp reference: with Blender's default passes only
  // (Combined, Depth), and with every pass, the Vector pass among them: one file is one frame,
  // its motion not sent.
  const std::string fixtures = DN_CYCLES_FIXTURES;
  std::string log;
  for (const char* exr : {"plain_0000.exr", "frame_0000.exr"}) {
    ASSERT_EQ(dn_denoise(server, "'" + fixtures + "/" + exr + "' -o '" + path(exr) + "' -r '" + fixtures +
                                     "/ref_0000.exr'",
                         log),
              0)
        << log;
    EXPECT_NE(log.find(chose_image), std::string::npos) << exr << "\n" << log;
    EXPECT_EQ(log.find("motion       <-"), std::string::npos) << exr << "\n" << log;
    EXPECT_NE(log.find("output worse than input: 0 (rmse), 0 (relmse) of 1 frames"), std::string::npos)
        << exr << "\n" << log;
  }

  // A noisy 8-bit PNG (sRGB): a mid grey with per-pixel noise.
  std::vector<uint8_t> srgb(size_t(W * H * 3));
  uint32_t state = 7;
  for (auto& v : srgb) {
    state = state * 1664525u + 1013904223u;
    v = uint8_t(96 + (state >> 26));  // 96 .. 159
  }
  image::write_png_rgb8(path("in.png"), W, H, srgb.data());
  ASSERT_EQ(dn_denoise(server, "'" + path("in.png") + "' -o '" + path("out.png") + "'", log), 0) << log;
  EXPECT_NE(log.find(chose_image), std::string::npos) << log;
  EXPECT_TRUE(fs::exists(path("out.png")));

  // oidnDenoise's trio: colour, albedo and normal PFMs.
  constexpr int w = 48, h = 32;
  std::vector<float> truth(size_t(w * h * 3)), noisy(truth.size()), albedo(truth.size(), 0.5f), normal(truth.size(), 0.0f);
  for (size_t i = 0; i < truth.size(); ++i) {
    state = state * 1664525u + 1013904223u;
    truth[i] = 0.25f;
    noisy[i] = truth[i] * 2.0f * float(state >> 8) / float(1u << 24);
  }
  for (size_t i = 2; i < normal.size(); i += 3) normal[i] = 1.0f;
  ASSERT_EQ(denoise_trio(server, w, h, noisy, albedo, normal, "", log), 0) << log;
  EXPECT_NE(log.find(chose_image), std::string::npos) << log;
  int ow = 0, oh = 0;
  const std::vector<float> out = image::read_pfm_rgb(path("out.pfm"), ow, oh);
  ASSERT_EQ(out.size(), truth.size());
  EXPECT_LT(squared_error(out, truth), squared_error(noisy, truth));
}

// A side file of another size: exit status 1, one line naming both files and sizes.
TEST_F(DenoiseFiles, SideFileOfAnotherSizeFails) {
  const std::vector<float> colour(size_t(W * H * 3), 0.5f), small(size_t(8 * 8 * 3), 0.5f);
  image::write_pfm_rgb(path("color.pfm"), W, H, colour.data());
  image::write_pfm_rgb(path("albedo.pfm"), 8, 8, small.data());
  ServerProcess server;
  std::string log;
  EXPECT_EQ(dn_denoise(server,
                       "'" + path("color.pfm") + "' --albedo '" + path("albedo.pfm") + "' -o '" + path("out.pfm") +
                           "' --pipeline passthrough -q",
                       log),
            1);
  EXPECT_NE(log.find("dn denoise: error: --albedo: " + path("albedo.pfm") + " is 8x8, but the input " +
                     path("color.pfm") + " is 16x8"),
            std::string::npos)
      << log;
  EXPECT_FALSE(fs::exists(path("out.pfm")));
}

}  // namespace
}  // namespace dn::test
