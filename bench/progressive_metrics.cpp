// progressive_metrics: per-frame error of a denoised sequence for
// bench/progressive_convergence.sh (paper 004): the RMSE and the
// noise-corrected MSE against one or two references, the temporal error
// against the previous output frame, and the holes a progressive output has
// below one sample per pixel.
//
//   progressive_metrics --output 'den/frame_%04d.exr' --reference 'ref_%04d.exr'
//                       [--reference2 'ref2_%04d.exr'] [--input 'in/frame_%04d.exr']
//                       --frames N [--first F]
//   progressive_metrics --average 'in/frame_%04d.exr' --frames N [--first F] --write FILE
//
// The second form writes the mean of the input frames' radiance.R/G/B (RGB
// float EXR): many 1-spp frames of a still camera average to the image the
// noisy frames converge to (dnrender's sample 0 goes through the pixel centre
// every frame), a reference without the aliasing a box-filtered one has.
//
// A pattern without a placeholder names one file for every frame (a still
// camera's one reference). Definitions (dn/image/metrics.hpp, as dn denoise):
//   rmse          sqrt(mean of (x - r1)^2) over pixels and components, linear.
//   nc_mse        mean of (x - r1)(x - r2): unbiased for the error against the
//                 truth (NaN without --reference2); ref_noise_mse = mean((r1 - r2)^2) / 2;
//                 nc_relmse the same relative, / (((r1 + r2) / 2)^2 + 0.01).
//   temporal      mean |Y_f - Y_{f-1}| of Rec. 709 linear luminance between
//                 this output frame and the previous one (NaN for the first).
//   holes         pixels whose output is exactly 0 in R, G and B where
//                 reference 1 has a channel > 0 and, with --input, the input's
//                 depth is a surface (finite, > 0): its centre sample did not
//                 leave the scene (scene 3's slit: a black background at the
//                 centre, light in the box-filtered reference).
//   zero_px       pixels whose output is exactly 0 in R, G and B (any reference).
//   nonfinite     pixels with a NaN or infinite output component.
//   uncovered     with --input: pixels whose sample_count.Y was 0 in every
//                 input frame from F to this one (no sample yet; "nan" without
//                 --input). Only meaningful for a still camera.
//   nc_mse_noemit with --input and --reference2: nc_mse over the pixels with no
//                 emission (input emission.R/G/B all 0) in their 3x3
//                 neighbourhood, i.e. without light sources (and background)
//                 and their edges; noemit_px counts those pixels.
//   flip_hdr      mean HDR-FLIP against r1 (dn/image/flip.hpp: default
//                 viewing, automatic exposures of r1).
// Prints a TSV: frame rmse nc_mse ref_noise_mse temporal holes zero_px nonfinite
// uncovered nc_relmse nc_mse_noemit noemit_px flip_hdr.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "dn/image/exr_io.hpp"
#include "dn/image/flip.hpp"
#include "dn/image/metrics.hpp"
#include "frame_path.hpp"

namespace {

using dn::bench::frame_path;

struct Options {
  std::string output, reference, reference2, input, average, write;
  int first = 0, frames = 0;
};

constexpr const char* kUsage =
    "usage: progressive_metrics --output PAT --reference PAT [--reference2 PAT] [--input PAT]\n"
    "         --frames N [--first F]\n"
    "       progressive_metrics --average PAT --frames N [--first F] --write FILE";

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
    else if (a == "--average") o.average = value();
    else if (a == "--write") o.write = value();
    else if (a == "--first") o.first = std::stoi(value());
    else if (a == "--frames") o.frames = std::stoi(value());
    else if (a == "-h" || a == "--help") {
      std::puts(kUsage);
      std::exit(0);
    } else throw std::invalid_argument("unknown option " + a);
  }
  if (o.frames < 1 || o.first < 0) throw std::invalid_argument("--frames >= 1 is required");
  if (!o.average.empty() ? o.write.empty() : o.output.empty() || o.reference.empty())
    throw std::invalid_argument(o.average.empty() ? "--output and --reference are required" : "--average needs --write");
  return o;
}

std::vector<float> read_rgb(const std::string& path, int& w, int& h, const char* what) {
  int rw = 0, rh = 0;
  std::vector<float> rgb = dn::image::read_exr_rgb(path, rw, rh);
  if (w == 0) w = rw, h = rh;
  if (rw != w || rh != h)
    throw std::invalid_argument(std::string(what) + " " + path + " is " + std::to_string(rw) + "x" +
                                std::to_string(rh) + ", the output is " + std::to_string(w) + "x" + std::to_string(h));
  return rgb;
}

// The mean radiance of the input frames, as an RGB float EXR.
int average(const Options& o) {
  std::vector<double> sum;
  int w = 0, h = 0;
  for (int f = o.first; f < o.first + o.frames; ++f) {
    const dn::image::ExrReader in(frame_path(o.average, f));
    if (sum.empty()) w = in.width(), h = in.height(), sum.assign(size_t(w) * size_t(h) * 3, 0.0);
    if (in.width() != w || in.height() != h) throw std::invalid_argument(in.path() + ": size differs from the first frame's");
    const std::vector<float> x = in.read({"radiance.R", "radiance.G", "radiance.B"});
    for (size_t i = 0; i < x.size(); ++i) sum[i] += x[i];
  }
  std::vector<float> mean(sum.size());
  for (size_t i = 0; i < sum.size(); ++i) mean[i] = float(sum[i] / o.frames);
  dn::image::write_exr_rgb(o.write, w, h, mean.data(), dn::image::ExrPixelType::Float);
  return 0;
}

// nc_mse over the pixels whose 3x3 neighbourhood has no emission; their count.
std::pair<double, size_t> nc_mse_without_emitters(const std::vector<float>& out, const std::vector<float>& ref,
                                                  const std::vector<float>& ref2, const std::vector<float>& emission,
                                                  int w, int h) {
  double sum = 0;
  size_t pixels = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      bool emits = false;
      for (int dy = -1; dy <= 1 && !emits; ++dy)
        for (int dx = -1; dx <= 1 && !emits; ++dx) {
          const int u = x + dx, v = y + dy;
          if (u < 0 || v < 0 || u >= w || v >= h) continue;
          const float* e = &emission[3 * (size_t(v) * size_t(w) + size_t(u))];
          emits = e[0] > 0.0f || e[1] > 0.0f || e[2] > 0.0f;
        }
      if (emits) continue;
      const size_t p = size_t(y) * size_t(w) + size_t(x);
      for (int k = 0; k < 3; ++k)
        sum += double(out[3 * p + k] - ref[3 * p + k]) * double(out[3 * p + k] - ref2[3 * p + k]);
      pixels++;
    }
  return {pixels ? sum / (3.0 * double(pixels)) : NAN, pixels};
}

int run(const Options& o) {
  if (!o.average.empty()) return average(o);
  std::printf("frame\trmse\tnc_mse\tref_noise_mse\ttemporal\tholes\tzero_px\tnonfinite\tuncovered\tnc_relmse\tnc_mse_noemit\tnoemit_px\tflip_hdr\n");
  std::vector<float> previous;
  std::vector<unsigned char> covered;
  for (int f = o.first; f < o.first + o.frames; ++f) {
    int w = 0, h = 0;
    const std::vector<float> out = read_rgb(frame_path(o.output, f), w, h, "output");
    const std::vector<float> ref = read_rgb(frame_path(o.reference, f), w, h, "reference");
    const size_t n = size_t(w) * size_t(h);
    double nc = NAN, ref_noise = NAN, nc_rel = NAN, nc_noemit = NAN;
    std::string noemit_px = "nan";
    std::vector<float> ref2;
    if (!o.reference2.empty()) {
      ref2 = read_rgb(frame_path(o.reference2, f), w, h, "reference2");
      nc = dn::image::noise_corrected_mse(out.data(), ref.data(), ref2.data(), 3 * n);
      ref_noise = dn::image::reference_noise_mse(ref.data(), ref2.data(), 3 * n);
      nc_rel = dn::image::noise_corrected_relative_mse(out.data(), ref.data(), ref2.data(), 3 * n);
    }
    const double rmse = dn::image::rmse(out.data(), ref.data(), 3 * n);
    const double temporal = previous.size() == out.size() ? dn::image::temporal_error(out.data(), previous.data(), n) : NAN;
    std::string uncovered = "nan";
    std::vector<float> depth;  // the input's (point-sampled) depth: holes only where it is a surface
    if (!o.input.empty()) {
      const dn::image::ExrReader input(frame_path(o.input, f));
      if (input.width() != w || input.height() != h)
        throw std::invalid_argument("input " + input.path() + " is " + std::to_string(input.width()) + "x" +
                                    std::to_string(input.height()) + ", the output is " + std::to_string(w) + "x" +
                                    std::to_string(h));
      depth = input.read_channel("depth.Z");
      const std::vector<float> count = input.read_channel("sample_count.Y");
      if (!ref2.empty()) {
        const auto [value, pixels] =
            nc_mse_without_emitters(out, ref, ref2, input.read({"emission.R", "emission.G", "emission.B"}), w, h);
        nc_noemit = value;
        noemit_px = std::to_string(pixels);
      }
      if (covered.size() != n) covered.assign(n, 0);
      size_t u = 0;
      for (size_t p = 0; p < n; ++p) {
        if (count[p] > 0.0f) covered[p] = 1;
        u += covered[p] ? 0 : 1;
      }
      uncovered = std::to_string(u);
    }
    size_t holes = 0, zero = 0, nonfinite = 0;
    for (size_t p = 0; p < n; ++p) {
      const float* x = &out[3 * p];
      const float* r = &ref[3 * p];
      if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2])) nonfinite++;
      if (x[0] == 0.0f && x[1] == 0.0f && x[2] == 0.0f) {
        zero++;
        const bool surface = depth.empty() || (std::isfinite(depth[p]) && depth[p] > 0.0f);
        if (surface && (r[0] > 0.0f || r[1] > 0.0f || r[2] > 0.0f)) holes++;
      }
    }
    const double flip = dn::image::flip_hdr(out.data(), ref.data(), w, h).mean;
    std::printf("%d\t%.6g\t%.6g\t%.6g\t%.6g\t%zu\t%zu\t%zu\t%s\t%.6g\t%.6g\t%s\t%.6g\n", f, rmse, nc, ref_noise,
                temporal, holes, zero, nonfinite, uncovered.c_str(), nc_rel, nc_noemit, noemit_px.c_str(), flip);
    previous = out;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(parse(argc, argv));
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "progressive_metrics: %s\n%s\n", e.what(), kUsage);
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "progressive_metrics: %s\n", e.what());
    return 1;
  }
}
