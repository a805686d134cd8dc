// -o/--output: the image format follows the extension (client/tools/output_image.hpp),
// and the PFM writer/reader (dn/image/pfm.hpp).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "args.hpp"
#include "dn/image/pfm.hpp"
#include "output_image.hpp"

namespace {

namespace fs = std::filesystem;
using namespace dn::cli;

std::string head_of(const fs::path& p, size_t n) {
  std::ifstream in(p, std::ios::binary);
  std::string s(n, '\0');
  in.read(s.data(), std::streamsize(n));
  s.resize(size_t(in.gcount()));
  return s;
}

TEST(OutputImage, FormatFollowsTheExtensionInAnyCase) {
  EXPECT_EQ(image_format_for("out/f_%04d.exr", "--output"), ImageFormat::Exr);
  EXPECT_EQ(image_format_for("out/f_####.EXR", "--output"), ImageFormat::Exr);
  EXPECT_EQ(image_format_for("f.Png", "--output"), ImageFormat::Png);
  EXPECT_EQ(image_format_for("f_%d.pfm", "--output"), ImageFormat::Pfm);
}

TEST(OutputImage, UnknownOrMissingExtensionIsAUsageErrorNamingTheAcceptedOnes) {
  for (const char* bad : {"f_%04d.jpg", "f_%04d", "dir.exr/f_%04d", "f.tiff"}) {
    try {
      image_format_for(bad, "--output");
      FAIL() << bad;
    } catch (const UsageError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("--output '" + std::string(bad) + "'"), std::string::npos) << m;
      EXPECT_NE(m.find(".exr, .png or .pfm"), std::string::npos) << m;
    }
  }
}

TEST(OutputImage, WritesEachFormat) {
  const fs::path dir = fs::temp_directory_path() / ("dn_output_image_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const int w = 3, h = 2;
  std::vector<float> rgb(size_t(w * h * 3));
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = 0.1f * float(i);
  write_image((dir / "a/x.exr").string(), ImageFormat::Exr, w, h, rgb.data(), {});
  write_image((dir / "a/x.png").string(), ImageFormat::Png, w, h, rgb.data(), {});
  write_image((dir / "a/x.pfm").string(), ImageFormat::Pfm, w, h, rgb.data(), {});
  EXPECT_EQ(head_of(dir / "a/x.exr", 4), std::string("\x76\x2f\x31\x01", 4));
  EXPECT_EQ(head_of(dir / "a/x.png", 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(head_of(dir / "a/x.pfm", 12), "PF\n3 2\n-1.0\n");
  // Little-endian floats, rows bottom-first: the file's first pixel is the last row's first.
  const std::string bytes = head_of(dir / "a/x.pfm", 12 + size_t(w * h * 3) * 4);
  ASSERT_EQ(bytes.size(), 12 + size_t(w * h * 3) * 4);
  float first = 0;
  std::memcpy(&first, bytes.data() + 12, 4);
  EXPECT_FLOAT_EQ(first, rgb[size_t(w * 3)]);
  int rw = 0, rh = 0;
  EXPECT_EQ(dn::image::read_pfm_rgb((dir / "a/x.pfm").string(), rw, rh), rgb);
  EXPECT_EQ(rw, w);
  EXPECT_EQ(rh, h);
  fs::remove_all(dir);
}

}  // namespace
