// bench/side_by_side puts each panel's method name in the image: the real
// binary is run on two small EXRs (one bright, one dark) labelled "svgf" and
// "reflect", its PNG is decoded here (zlib), and the label strips are checked
// pixel by pixel against glyph shapes written out again below, independently
// of bench/bitmap_font.hpp: white ink exactly where the letter has it, the
// strip's dark background everywhere else.
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "dn/image/exr_io.hpp"

namespace {

namespace fs = std::filesystem;

// The expected letters, 5 columns by 9 rows ('#' ink), as side_by_side must draw them.
const std::map<char, std::vector<std::string>> kLetters = {
    {'s', {".....", ".....", ".###.", "#....", ".###.", "....#", "####.", ".....", "....."}},
    {'v', {".....", ".....", "#...#", "#...#", "#...#", ".#.#.", "..#..", ".....", "....."}},
    {'g', {".....", ".....", ".####", "#...#", "#...#", "#...#", ".####", "....#", ".###."}},
    {'f', {"..##.", ".#..#", ".#...", "###..", ".#...", ".#...", ".#...", ".....", "....."}},
    {'r', {".....", ".....", "#.##.", "##..#", "#....", "#....", "#....", ".....", "....."}},
    {'e', {".....", ".....", ".###.", "#...#", "#####", "#....", ".###.", ".....", "....."}},
    {'l', {".##..", "..#..", "..#..", "..#..", "..#..", "..#..", ".###.", ".....", "....."}},
    {'c', {".....", ".....", ".###.", "#....", "#....", "#...#", ".###.", ".....", "....."}},
    {'t', {".#...", ".#...", "###..", ".#...", ".#...", ".#..#", "..##.", ".....", "....."}},
};

struct Rgb8 {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;
  const uint8_t* at(int x, int y) const { return &rgb[3 * (size_t(y) * size_t(width) + size_t(x))]; }
};

uint32_t be32(const uint8_t* p) { return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3]; }

// An 8-bit RGB PNG with filter type 0 on every row (what dn_imageio writes).
Rgb8 read_png(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<uint8_t> png((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Rgb8 im;
  std::vector<uint8_t> idat;
  for (size_t at = 8; at + 12 <= png.size();) {
    const uint32_t len = be32(&png[at]);
    const std::string type(reinterpret_cast<const char*>(&png[at + 4]), 4);
    const uint8_t* data = &png[at + 8];
    if (type == "IHDR") {
      im.width = int(be32(data));
      im.height = int(be32(data + 4));
      EXPECT_EQ(data[8], 8);
      EXPECT_EQ(data[9], 2);
    }
    if (type == "IDAT") idat.insert(idat.end(), data, data + len);
    at += 12 + len;
  }
  const size_t stride = 1 + 3 * size_t(im.width);
  std::vector<uint8_t> raw(stride * size_t(im.height));
  uLongf raw_len = uLongf(raw.size());
  EXPECT_EQ(uncompress(raw.data(), &raw_len, idat.data(), uLong(idat.size())), Z_OK);
  EXPECT_EQ(raw_len, raw.size());
  for (int y = 0; y < im.height; ++y) {
    EXPECT_EQ(raw[size_t(y) * stride], 0) << "filter of row " << y;
    im.rgb.insert(im.rgb.end(), raw.begin() + long(size_t(y) * stride + 1), raw.begin() + long(size_t(y + 1) * stride));
  }
  return im;
}

constexpr int kPanelW = 96, kPanelH = 40;
constexpr int kGutter = 4, kStrip = 26, kInset = 4, kScale = 2, kAdvance = 6;

// Every pixel of the strip above the column at x0: white where `text`'s
// letters (at scale 2 from (x0 + 4, 4)) have ink, (24, 24, 24) elsewhere.
// Returns the number of ink pixels, -1 on the first mismatch (reported).
int check_strip(const Rgb8& im, int x0, const std::string& text) {
  int ink = 0;
  for (int y = 0; y < kStrip; ++y)
    for (int x = 0; x < kPanelW; ++x) {
      bool expect_ink = false;
      const int tx = x - kInset, ty = y - kInset;
      if (tx >= 0 && ty >= 0) {
        const size_t letter = size_t(tx / (kAdvance * kScale));
        const int col = (tx % (kAdvance * kScale)) / kScale, row = ty / kScale;
        if (letter < text.size() && col < 5 && row < 9) expect_ink = kLetters.at(text[letter])[size_t(row)][size_t(col)] == '#';
      }
      const uint8_t* p = im.at(x0 + x, y);
      const uint8_t want = expect_ink ? 255 : 24;
      if (p[0] != want || p[1] != want || p[2] != want) {
        ADD_FAILURE() << "'" << text << "' strip at (" << x << ", " << y << "): " << int(p[0]) << "," << int(p[1])
                      << "," << int(p[2]) << ", expected " << int(want);
        return -1;
      }
      ink += expect_ink;
    }
  return ink;
}

TEST(SideBySideLabels, EachPanelCarriesItsMethodName) {
  const fs::path dir = fs::temp_directory_path() / ("dn_side_by_side_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::vector<float> bright(size_t(kPanelW) * kPanelH * 3, 50.0f), dark(bright.size(), 0.0f);
  dn::image::write_exr_rgb((dir / "a.exr").string(), kPanelW, kPanelH, bright.data(), dn::image::ExrPixelType::Float);
  dn::image::write_exr_rgb((dir / "b.exr").string(), kPanelW, kPanelH, dark.data(), dn::image::ExrPixelType::Float);
  const std::string out = (dir / "sheet.png").string();
  const std::string cmd = std::string(DN_SIDE_BY_SIDE_PATH) + " --out " + out + " --label svgf --label reflect " +
                          (dir / "a.exr").string() + " " + (dir / "b.exr").string();
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const Rgb8 im = read_png(out);
  ASSERT_EQ(im.width, 2 * kPanelW + kGutter);
  ASSERT_EQ(im.height, kStrip + kPanelH) << "the label strip sits above the panels";

  const int svgf_ink = check_strip(im, 0, "svgf");
  const int reflect_ink = check_strip(im, kPanelW + kGutter, "reflect");
  EXPECT_GT(svgf_ink, 0);
  EXPECT_GT(reflect_ink, svgf_ink);
  // The two strips differ (the names are in the image, not in a caption).
  size_t differing = 0;
  for (int y = 0; y < kStrip; ++y)
    for (int x = 0; x < kPanelW; ++x) differing += im.at(x, y)[0] != im.at(kPanelW + kGutter + x, y)[0];
  EXPECT_GT(differing, 100u);
  // Below the strips the panels: bright and dark as rendered, untouched by the labels.
  EXPECT_GT(im.at(kPanelW / 2, kStrip + kPanelH / 2)[0], 200);
  EXPECT_EQ(im.at(kPanelW + kGutter + kPanelW / 2, kStrip + kPanelH / 2)[0], 0);

  // One --label per input, or none.
  const std::string bad = std::string(DN_SIDE_BY_SIDE_PATH) + " --out " + out + " --label svgf " +
                          (dir / "a.exr").string() + " " + (dir / "b.exr").string() + " 2>/dev/null";
  EXPECT_NE(std::system(bad.c_str()), 0);
  fs::remove_all(dir);
}

}  // namespace
