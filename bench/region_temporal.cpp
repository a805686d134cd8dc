// region_temporal: the still-camera temporal error of a denoised sequence over
// regions of the frame (bench/speed_error.sh), beside dn denoise's whole-frame
// figure: where a pipeline flickers. Masks from region_masks.cpp.
//
//   region_temporal --output 'out/still_%04d.exr' --input 'in/still/frame_%04d.exr'
//                   --first F --frames N [--method NAME] [--region all|glossy ...]
//                   [--glossy-below R] [--roughness-layer L]
//
// For every frame f of [F, F + N), metrics.hpp temporal_error (mean |Y_f -
// Y_{f-1}| of linear luminance) over the region's pixels, the glossy mask
// taken from frame f's input roughness; the mean over the N frames, as dn
// denoise --warmup F reports it for the whole frame (region all).
// Prints a TSV header and one line per region: region method temporal pixels
// (masked pixels per frame, the mean over the frames).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "dn/image/exr_io.hpp"
#include "dn/image/metrics.hpp"
#include "frame_path.hpp"
#include "region_masks.hpp"

namespace {

using dn::bench::frame_path;

struct Options {
  std::string output, input, method = "-", roughness_layer = "roughness.Y";
  int first = -1, frames = 0;
  std::vector<std::string> regions;
  float glossy_below = 0.3f;
};

constexpr const char* kUsage =
    "usage: region_temporal --output PAT --input PAT --first F --frames N [--method NAME]\n"
    "         [--region all|glossy ...] [--glossy-below R] [--roughness-layer L]";

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    if (a == "--output") o.output = value();
    else if (a == "--input") o.input = value();
    else if (a == "--method") o.method = value();
    else if (a == "--first") o.first = std::stoi(value());
    else if (a == "--frames") o.frames = std::stoi(value());
    else if (a == "--glossy-below") o.glossy_below = std::stof(value());
    else if (a == "--roughness-layer") o.roughness_layer = value();
    else if (a == "--region") {
      std::stringstream ss(value());
      for (std::string r; std::getline(ss, r, ',');)
        if (!r.empty()) o.regions.push_back(r);
    } else if (a == "-h" || a == "--help") {
      std::puts(kUsage);
      std::exit(0);
    } else throw std::invalid_argument("unknown option " + a);
  }
  if (o.output.empty() || o.input.empty() || o.first < 1 || o.frames <= 0)
    throw std::invalid_argument(std::string("--first must be >= 1 (frame F is compared with F - 1)\n") + kUsage);
  if (o.regions.empty()) o.regions = {"all", "glossy"};
  for (const auto& r : o.regions)
    if (r != "all" && r != "glossy") throw std::invalid_argument("unknown region '" + r + "' (all, glossy)");
  return o;
}

int run(const Options& o) {
  std::vector<double> sum(o.regions.size(), 0.0), pixels(o.regions.size(), 0.0);
  std::vector<int> frames(o.regions.size(), 0);
  int w = 0, h = 0;
  std::vector<float> previous = dn::image::read_exr_rgb(frame_path(o.output, o.first - 1), w, h);
  for (int f = o.first; f < o.first + o.frames; ++f) {
    int fw = 0, fh = 0;
    const std::vector<float> current = dn::image::read_exr_rgb(frame_path(o.output, f), fw, fh);
    if (fw != w || fh != h) throw std::invalid_argument("output " + frame_path(o.output, f) + " changes size");
    const size_t n = size_t(w) * size_t(h);
    const dn::image::ExrReader input(frame_path(o.input, f));
    if (input.width() != w || input.height() != h)
      throw std::invalid_argument("input " + input.path() + " is not the output's size");
    for (size_t r = 0; r < o.regions.size(); ++r) {
      const dn::bench::Mask mask = o.regions[r] == "all"
                                       ? dn::bench::Mask(n, 1)
                                       : dn::bench::glossy_mask(input.read_channel(o.roughness_layer), o.glossy_below);
      const double e = dn::image::temporal_error(current.data(), previous.data(), mask.data(), n);
      if (std::isnan(e)) continue;  // no pixel of the region in this frame
      sum[r] += e;
      pixels[r] += double(dn::bench::count(mask));
      frames[r]++;
    }
    previous = current;
  }
  std::printf("region\tmethod\ttemporal\tpixels\n");
  for (size_t r = 0; r < o.regions.size(); ++r)
    std::printf("%s\t%s\t%.6g\t%.1f\n", o.regions[r].c_str(), o.method.c_str(),
                frames[r] ? sum[r] / frames[r] : std::nan(""), frames[r] ? pixels[r] / frames[r] : 0.0);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(parse(argc, argv));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "region_temporal: %s\n", e.what());
    return 2;
  }
}
