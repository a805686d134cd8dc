// region_metrics: error of a denoised sequence over the pixels of chosen
// roughness values only (the roughness-mapped surfaces of a dnrender scene),
// for the svgf-fb evidence in bench/speed_error.sh.
//
//   region_metrics --output 'out/frame_%04d.exr' --reference 'in/ref_%04d.exr'
//                  --input 'in/frame_%04d.exr' --frames N --roughness 0.04,0.35 [--tolerance 0.005]
//
// The mask of each frame: pixels of the input's roughness.Y layer within
// `tolerance` of one of the values. Prints a TSV header and one line of means
// over the frames: RMSE and relMSE over the masked pixels (linear RGB),
// SSIM = mean local SSIM (metrics.hpp, ACES-tone-mapped luma) of the windows
// centred on masked pixels, and the mean masked pixel count.
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "dn/image/exr_io.hpp"
#include "dn/image/metrics.hpp"

namespace {

std::string frame_path(const std::string& pattern, int frame) {
  char buf[1024];
  std::snprintf(buf, sizeof buf, pattern.c_str(), frame);
  return buf;
}

struct Options {
  std::string output, reference, input;
  int frames = 0;
  std::vector<float> roughness;
  float tolerance = 0.005f;
};

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
    else if (a == "--input") o.input = value();
    else if (a == "--frames") o.frames = std::stoi(value());
    else if (a == "--tolerance") o.tolerance = std::stof(value());
    else if (a == "--roughness") {
      std::stringstream ss(value());
      std::string item;
      while (std::getline(ss, item, ',')) o.roughness.push_back(std::stof(item));
    } else throw std::invalid_argument("unknown option " + a);
  }
  if (o.output.empty() || o.reference.empty() || o.input.empty() || o.frames <= 0 || o.roughness.empty())
    throw std::invalid_argument(
        "usage: region_metrics --output PAT --reference PAT --input PAT --frames N --roughness A,B [--tolerance T]");
  return o;
}

int run(const Options& o) {
  double rmse = 0, relmse = 0, ssim = 0, pixels = 0;
  for (int f = 0; f < o.frames; ++f) {
    int w = 0, h = 0, rw = 0, rh = 0;
    const std::vector<float> out = dn::image::read_exr_rgb(frame_path(o.output, f), w, h);
    const std::vector<float> ref = dn::image::read_exr_rgb(frame_path(o.reference, f), rw, rh);
    const dn::image::ExrReader input(frame_path(o.input, f));
    if (rw != w || rh != h || input.width() != w || input.height() != h)
      throw std::invalid_argument("frame " + std::to_string(f) + ": output, reference and input sizes differ");
    const std::vector<float> rough = input.read_channel("roughness.Y");
    std::vector<uint8_t> mask(size_t(w) * h, 0);
    size_t count = 0;
    for (size_t i = 0; i < mask.size(); ++i)
      for (float v : o.roughness)
        if (std::fabs(rough[i] - v) <= o.tolerance) mask[i] = 1;
    double se = 0, rel = 0;
    for (size_t i = 0; i < mask.size(); ++i) {
      if (!mask[i]) continue;
      ++count;
      for (int k = 0; k < 3; ++k) {
        const double d = double(out[3 * i + k]) - ref[3 * i + k];
        se += d * d;
        rel += d * d / (double(ref[3 * i + k]) * ref[3 * i + k] + 0.01);
      }
    }
    if (count == 0) throw std::invalid_argument("frame " + std::to_string(f) + ": no pixel has those roughness values");
    const auto a = dn::image::display_luma(out.data(), mask.size());
    const auto b = dn::image::display_luma(ref.data(), mask.size());
    const auto map = dn::image::ssim_map(a.data(), b.data(), w, h);
    double s = 0;
    size_t windows = 0;
    for (int y = 0; y + 10 < h; ++y)
      for (int x = 0; x + 10 < w; ++x)
        if (mask[size_t(y + 5) * w + x + 5]) {
          s += map[size_t(y) * (w - 10) + x];
          ++windows;
        }
    rmse += std::sqrt(se / (3.0 * count));
    relmse += rel / (3.0 * count);
    ssim += windows ? s / double(windows) : NAN;
    pixels += double(count);
  }
  const double n = o.frames;
  std::printf("rmse\trelmse\tssim\tpixels\n%.6g\t%.6g\t%.6g\t%.0f\n", rmse / n, relmse / n, ssim / n, pixels / n);
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
