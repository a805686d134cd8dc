// side_by_side: one PNG comparing frames of the same shot, for docs/results.md.
// Top row: each input EXR tone-mapped, left to right in argument order.
// Below: for each crop rectangle, a row of the same crop from every input,
// enlarged (nearest neighbour) to the panel width, so detail and noise show.
//
//   side_by_side --out cmp.png [--crop X,Y,W,H ...] [--exposure E] [--label NAME ...] a.exr b.exr ...
//
// Crop rectangles are fractions of the image (0..1). Panels are separated by
// 4-pixel white gutters. --label (once per input, in the same order) puts the
// panel's name in the image: a dark strip of kLabelStrip pixels above each
// column, the name in white in the bitmap font of bitmap_font.hpp at scale 2
// with its top-left corner kLabelInset pixels right of the column's left edge
// and kLabelInset below the top (scale 1, vertically centred, where the name
// is too wide for the panel at 2; cut where it is too wide at 1), so it reads
// on bright and dark renders alike.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "dn/image/exr_io.hpp"
#include "dn/image/metrics.hpp"
#include "dn/image/png.hpp"
#include "bitmap_font.hpp"

namespace {

struct Crop {
  double x, y, w, h;
};

struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  // display sRGB8
};

constexpr int kGutter = 4;
constexpr int kLabelInset = 4;
constexpr int kLabelStrip = 2 * dn::font::kGlyphHeight + 2 * kLabelInset;  // 26
constexpr uint8_t kLabelBackground[3] = {24, 24, 24};
constexpr uint8_t kLabelText[3] = {255, 255, 255};

// The name in the strip above the column at x0, pw pixels wide.
void draw_label(Image& sheet, int x0, int pw, std::string name) {
  for (int y = 0; y < kLabelStrip; ++y)
    for (int x = x0; x < x0 + pw; ++x)
      for (int k = 0; k < 3; ++k) sheet.rgb[3 * (size_t(y) * sheet.width + x) + k] = kLabelBackground[k];
  const int room = pw - 2 * kLabelInset;
  int scale = dn::font::text_width(name, 2) <= room ? 2 : 1;
  while (!name.empty() && dn::font::text_width(name, scale) > room) name.pop_back();
  const int y = scale == 2 ? kLabelInset : (kLabelStrip - dn::font::kGlyphHeight) / 2;
  // Cut to fit: the name stays inside its column.
  dn::font::draw_text(sheet.rgb.data(), sheet.width, sheet.height, x0 + kLabelInset, y, name, scale, kLabelText);
}

Crop parse_crop(const std::string& s) {
  Crop c{};
  if (std::sscanf(s.c_str(), "%lf,%lf,%lf,%lf", &c.x, &c.y, &c.w, &c.h) != 4 || c.w <= 0 || c.h <= 0 || c.x < 0 ||
      c.y < 0 || c.x + c.w > 1.0 + 1e-9 || c.y + c.h > 1.0 + 1e-9)
    throw std::invalid_argument("--crop wants X,Y,W,H as fractions of the image inside [0,1], got '" + s + "'");
  return c;
}

// Copies `src` region (sx, sy, sw, sh) scaled to dw x dh into `dst` at (dx, dy).
void blit(const Image& src, int sx, int sy, int sw, int sh, Image& dst, int dx, int dy, int dw, int dh) {
  for (int y = 0; y < dh; ++y) {
    const int ys = sy + std::min(sh - 1, y * sh / dh);
    for (int x = 0; x < dw; ++x) {
      const int xs = sx + std::min(sw - 1, x * sw / dw);
      for (int k = 0; k < 3; ++k)
        dst.rgb[3 * (size_t(dy + y) * dst.width + dx + x) + k] = src.rgb[3 * (size_t(ys) * src.width + xs) + k];
    }
  }
}

int run(int argc, char** argv) {
  std::string out;
  std::vector<Crop> crops;
  std::vector<std::string> inputs, labels;
  float exposure = 1.0f;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    if (a == "--out") out = value();
    else if (a == "--crop") crops.push_back(parse_crop(value()));
    else if (a == "--exposure") exposure = std::stof(value());
    else if (a == "--label") labels.push_back(value());
    else if (!a.empty() && a[0] == '-') throw std::invalid_argument("unknown option " + a);
    else inputs.push_back(a);
  }
  if (out.empty() || inputs.empty())
    throw std::invalid_argument("usage: side_by_side --out OUT.png [--crop X,Y,W,H] [--label NAME ...] a.exr ...");
  if (!labels.empty() && labels.size() != inputs.size())
    throw std::invalid_argument(std::to_string(labels.size()) + " --label for " + std::to_string(inputs.size()) +
                                " inputs: give one per input, in the same order");

  std::vector<Image> panels;
  for (const auto& path : inputs) {
    Image im;
    const std::vector<float> rgb = dn::image::read_exr_rgb(path, im.width, im.height);
    im.rgb = dn::image::to_srgb8(rgb.data(), rgb.size() / 3, dn::image::Tonemap::Aces, exposure);
    if (!panels.empty() && (im.width != panels[0].width || im.height != panels[0].height))
      throw std::invalid_argument(path + " is not the size of " + inputs[0]);
    panels.push_back(std::move(im));
  }
  const int pw = panels[0].width, ph = panels[0].height, n = int(panels.size());
  // Each crop row is as tall as the crop enlarged to the panel width.
  std::vector<int> crop_h;
  for (const Crop& c : crops) crop_h.push_back(std::max(1, int(pw * (c.h * ph) / (c.w * pw))));
  Image sheet;
  sheet.width = n * pw + (n - 1) * kGutter;
  const int top = labels.empty() ? 0 : kLabelStrip;
  sheet.height = top + ph;
  for (int h : crop_h) sheet.height += kGutter + h;
  sheet.rgb.assign(size_t(sheet.width) * sheet.height * 3, 255);
  for (int p = 0; p < n; ++p) {
    const int x0 = p * (pw + kGutter);
    if (!labels.empty()) draw_label(sheet, x0, pw, labels[p]);
    blit(panels[p], 0, 0, pw, ph, sheet, x0, top, pw, ph);
    int y0 = top + ph;
    for (size_t c = 0; c < crops.size(); ++c) {
      y0 += kGutter;
      const int sx = int(crops[c].x * pw), sy = int(crops[c].y * ph);
      const int sw = std::max(1, std::min(pw - sx, int(crops[c].w * pw)));
      const int sh = std::max(1, std::min(ph - sy, int(crops[c].h * ph)));
      blit(panels[p], sx, sy, sw, sh, sheet, x0, y0, pw, crop_h[c]);
      y0 += crop_h[c];
    }
  }
  dn::image::write_png_rgb8(out, sheet.width, sheet.height, sheet.rgb.data());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "side_by_side: %s\n", e.what());
    return 2;
  }
}
