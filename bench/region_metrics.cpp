// region_metrics: error of a denoised sequence over regions of the frame only,
// to show where each pipeline fails (bench/speed_error.sh). The masks are
// built by region_masks.cpp.
//
//   region_metrics --output 'out/frame_%04d.exr' --reference 'in/ref_%04d.exr'
//                  --input 'in/frame_%04d.exr' --frames N [--first F] [--method NAME]
//                  [--reference2 'in/ref2_%04d.exr'] [--region NAME ...]
//
// Regions (--region, repeatable or comma-separated; default: glossy,
// highlights, disocclusion, and roughness-mapped when --roughness is given):
//   roughness-mapped  input roughness within --tolerance (0.005) of one of --roughness A,B,...
//   glossy            mirror and glossy surfaces: input roughness < --glossy-below (0.3)
//   highlights        reference luminance > --highlight-k (20) x the frame's median
//                     luminance, dilated by --highlight-dilate (1) pixels
//   disocclusion      motion points outside the image, or no previous-frame depth
//                     within --depth-tolerance (0.1, relative) around where it points;
//                     from the second frame on (the first has no previous frame)
// Layers read from the input EXR: --roughness-layer (roughness.Y; Cycles: an
// AOV such as ViewLayer.Roughness.V), --depth-layer (depth.Z), --motion-layers
// (motion.X,motion.Y: pixels to the previous frame, p_prev = p + mv).
//
// Prints a TSV header and one line per region:
//   region method rmse relmse ssim nc_mse nc_relmse ref_noise_mse pixels
// pooled over every masked pixel of every frame (RMSE and relMSE over linear
// RGB components, against --reference; SSIM = mean local SSIM, metrics.hpp on
// ACES-tone-mapped luma, of the windows centred on masked pixels); nc_mse,
// nc_relmse and ref_noise_mse (metrics.hpp) need --reference2, NaN without;
// pixels = masked pixels per frame, the mean over the frames the region is
// defined on. A region with no pixel prints NaN (pixels 0), except
// roughness-mapped, where that is an error (wrong scene or values).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "dn/image/exr_io.hpp"
#include "dn/image/metrics.hpp"
#include "frame_path.hpp"
#include "region_masks.hpp"

namespace {

using dn::bench::Mask;

using dn::bench::frame_path;

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

struct Options {
  std::string output, reference, reference2, input, method = "-";
  int frames = 0, first = 0;
  std::vector<std::string> regions;
  std::vector<float> roughness;
  float tolerance = 0.005f;
  std::string roughness_layer = "roughness.Y", depth_layer = "depth.Z";
  std::vector<std::string> motion_layers = {"motion.X", "motion.Y"};
  float glossy_below = 0.3f, highlight_k = 20.0f, depth_tolerance = 0.1f;
  int highlight_dilate = 1;
};

constexpr const char* kUsage =
    "usage: region_metrics --output PAT --reference PAT --input PAT --frames N [--first F] [--method NAME]\n"
    "         [--reference2 PAT] [--region roughness-mapped|glossy|highlights|disocclusion ...]\n"
    "         [--roughness A,B] [--tolerance T] [--roughness-layer L] [--glossy-below R]\n"
    "         [--highlight-k K] [--highlight-dilate PX] [--depth-layer L] [--motion-layers X,Y]\n"
    "         [--depth-tolerance REL]";

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    if (a == "--output") o.output = value();
    else if (a == "--reference") o.reference = value();
    else if (a == "--reference2") o.reference2 = value();
    else if (a == "--input") o.input = value();
    else if (a == "--method") o.method = value();
    else if (a == "--frames") o.frames = std::stoi(value());
    else if (a == "--first") o.first = std::stoi(value());
    else if (a == "--tolerance") o.tolerance = std::stof(value());
    else if (a == "--roughness")
      for (const auto& v : split(value())) o.roughness.push_back(std::stof(v));
    else if (a == "--region")
      for (const auto& v : split(value())) o.regions.push_back(v);
    else if (a == "--roughness-layer") o.roughness_layer = value();
    else if (a == "--glossy-below") o.glossy_below = std::stof(value());
    else if (a == "--highlight-k") o.highlight_k = std::stof(value());
    else if (a == "--highlight-dilate") o.highlight_dilate = std::stoi(value());
    else if (a == "--depth-layer") o.depth_layer = value();
    else if (a == "--depth-tolerance") o.depth_tolerance = std::stof(value());
    else if (a == "--motion-layers") {
      o.motion_layers = split(value());
      if (o.motion_layers.size() != 2) throw std::invalid_argument("--motion-layers wants X,Y");
    } else if (a == "-h" || a == "--help") {
      std::puts(kUsage);
      std::exit(0);
    } else throw std::invalid_argument("unknown option " + a);
  }
  if (o.output.empty() || o.reference.empty() || o.input.empty() || o.frames <= 0)
    throw std::invalid_argument(kUsage);
  if (o.regions.empty()) {
    if (!o.roughness.empty()) o.regions.push_back("roughness-mapped");
    for (const char* r : {"glossy", "highlights", "disocclusion"}) o.regions.push_back(r);
  }
  for (const auto& r : o.regions) {
    if (r != "roughness-mapped" && r != "glossy" && r != "highlights" && r != "disocclusion")
      throw std::invalid_argument("unknown region '" + r + "' (roughness-mapped, glossy, highlights, disocclusion)");
    if (r == "roughness-mapped" && o.roughness.empty())
      throw std::invalid_argument("region roughness-mapped needs --roughness A,B,...");
  }
  return o;
}

// Sums over the masked pixels of every frame of one region.
struct Sums {
  double se = 0, rel = 0, nc = 0, nc_rel = 0, ref_noise = 0, ssim = 0;
  size_t components = 0, windows = 0, pixels = 0, frames = 0;
};

struct Frame {
  int width = 0, height = 0;
  std::vector<float> out, ref, ref2;  // interleaved RGB
  std::vector<double> ssim_map;       // metrics.hpp ssim_map of display luma
};

void accumulate(Sums& s, const Frame& f, const Mask& mask) {
  s.frames++;
  const bool two = !f.ref2.empty();
  for (size_t i = 0; i < mask.size(); ++i) {
    if (!mask[i]) continue;
    s.pixels++;
    for (size_t k = 3 * i; k < 3 * i + 3; ++k) {
      const double x = f.out[k], r = f.ref[k];
      s.se += (x - r) * (x - r);
      s.rel += (x - r) * (x - r) / (r * r + 0.01);
      if (two) {
        const double r2 = f.ref2[k], m = 0.5 * (r + r2);
        s.nc += (x - r) * (x - r2);
        s.nc_rel += (x - r) * (x - r2) / (m * m + 0.01);
        s.ref_noise += 0.5 * (r - r2) * (r - r2);
      }
      s.components++;
    }
  }
  const int w = f.width, h = f.height;
  if (f.ssim_map.empty()) return;
  for (int y = 0; y + 10 < h; ++y)
    for (int x = 0; x + 10 < w; ++x)
      if (mask[size_t(y + 5) * size_t(w) + size_t(x + 5)]) {
        s.ssim += f.ssim_map[size_t(y) * size_t(w - 10) + size_t(x)];
        s.windows++;
      }
}

std::vector<float> read_rgb(const std::string& path, int width, int height, const char* what) {
  int w = 0, h = 0;
  std::vector<float> rgb = dn::image::read_exr_rgb(path, w, h);
  if (w != width || h != height)
    throw std::invalid_argument(std::string(what) + " " + path + " is " + std::to_string(w) + "x" +
                                std::to_string(h) + ", the output is " + std::to_string(width) + "x" +
                                std::to_string(height));
  return rgb;
}

int run(const Options& o) {
  std::vector<Sums> sums(o.regions.size());
  std::vector<float> previous_depth;
  for (int f = o.first; f < o.first + o.frames; ++f) {
    Frame fr;
    fr.out = dn::image::read_exr_rgb(frame_path(o.output, f), fr.width, fr.height);
    const int w = fr.width, h = fr.height;
    const size_t n = size_t(w) * size_t(h);
    fr.ref = read_rgb(frame_path(o.reference, f), w, h, "reference");
    if (!o.reference2.empty()) fr.ref2 = read_rgb(frame_path(o.reference2, f), w, h, "reference2");
    const dn::image::ExrReader input(frame_path(o.input, f));
    if (input.width() != w || input.height() != h)
      throw std::invalid_argument("input " + input.path() + " is " + std::to_string(input.width()) + "x" +
                                  std::to_string(input.height()) + ", the output is " + std::to_string(w) + "x" +
                                  std::to_string(h));
    const auto a = dn::image::display_luma(fr.out.data(), n);
    const auto b = dn::image::display_luma(fr.ref.data(), n);
    fr.ssim_map = dn::image::ssim_map(a.data(), b.data(), w, h);

    std::optional<std::vector<float>> roughness, depth;
    for (size_t r = 0; r < o.regions.size(); ++r) {
      const std::string& region = o.regions[r];
      if ((region == "roughness-mapped" || region == "glossy") && !roughness)
        roughness = input.read_channel(o.roughness_layer);
      if (region == "disocclusion" && !depth) depth = input.read_channel(o.depth_layer);
      Mask mask;
      if (region == "roughness-mapped") mask = dn::bench::roughness_values_mask(*roughness, o.roughness, o.tolerance);
      else if (region == "glossy") mask = dn::bench::glossy_mask(*roughness, o.glossy_below);
      else if (region == "highlights") mask = dn::bench::highlight_mask(fr.ref.data(), w, h, o.highlight_k, o.highlight_dilate);
      else {  // disocclusion: not defined on the first frame
        if (previous_depth.size() != n) continue;
        const std::vector<float> motion = input.read(o.motion_layers);
        mask = dn::bench::disocclusion_mask(motion, *depth, previous_depth, w, h, o.depth_tolerance);
      }
      accumulate(sums[r], fr, mask);
    }
    if (depth) previous_depth = std::move(*depth);
  }

  std::printf("region\tmethod\trmse\trelmse\tssim\tnc_mse\tnc_relmse\tref_noise_mse\tpixels\n");
  const bool two = !o.reference2.empty();
  for (size_t r = 0; r < o.regions.size(); ++r) {
    const Sums& s = sums[r];
    if (s.pixels == 0 && o.regions[r] == "roughness-mapped")
      throw std::invalid_argument("no pixel has those roughness values in any frame");
    const double c = double(s.components);
    const double nan = std::nan("");
    std::printf("%s\t%s\t%.6g\t%.6g\t%.6g\t%.6g\t%.6g\t%.6g\t%.1f\n", o.regions[r].c_str(), o.method.c_str(),
                s.components ? std::sqrt(s.se / c) : nan, s.components ? s.rel / c : nan,
                s.windows ? s.ssim / double(s.windows) : nan, two && s.components ? s.nc / c : nan,
                two && s.components ? s.nc_rel / c : nan, two && s.components ? s.ref_noise / c : nan,
                s.frames ? double(s.pixels) / double(s.frames) : 0.0);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(parse(argc, argv));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "region_metrics: %s\n", e.what());
    return 2;
  }
}
