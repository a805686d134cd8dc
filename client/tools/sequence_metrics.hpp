// dn denoise --reference2: error against the truth from two independent
// references (dn/image/metrics.hpp: noise_corrected_mse,
// noise_corrected_relative_mse, reference_noise_mse), per frame and as means
// for the --summary columns nc_mse, nc_relmse, ref_noise_mse. Header-only: the
// per-frame call and the summary columns are all denoise_cmd.cpp needs.
#pragma once

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "dn/image/metrics.hpp"
#include "input_image.hpp"

namespace dn::cli {

struct NoiseCorrected {
  double nc_mse = NAN, nc_relmse = NAN, ref_noise_mse = NAN;
};

// Reads the second reference of a frame and compares `rgb` (the output,
// interleaved RGB) with both references. Throws naming the file when its size
// differs from the output's.
inline NoiseCorrected noise_corrected_metrics(const std::vector<float>& rgb, const std::vector<float>& ref,
                                              int width, int height, const std::string& ref2_path) {
  int w = 0, h = 0;
  const std::vector<float> ref2 = read_reference_rgb(ref2_path, w, h);
  if (w != width || h != height)
    throw std::runtime_error("second reference " + ref2_path + " is " + std::to_string(w) + "x" +
                             std::to_string(h) + ", the output and first reference are " + std::to_string(width) +
                             "x" + std::to_string(height));
  const size_t n = rgb.size();
  if (ref.size() != n || ref2.size() != n) throw std::runtime_error("second reference " + ref2_path + ": size mismatch");
  return {image::noise_corrected_mse(rgb.data(), ref.data(), ref2.data(), n),
          image::noise_corrected_relative_mse(rgb.data(), ref.data(), ref2.data(), n),
          image::reference_noise_mse(ref.data(), ref2.data(), n)};
}

// Means over the measured frames; NaN when no frame had a second reference.
struct NoiseCorrectedTotals {
  size_t frames = 0;
  double nc_mse = 0, nc_relmse = 0, ref_noise_mse = 0;

  void add(const NoiseCorrected& m) {
    frames++;
    nc_mse += m.nc_mse;
    nc_relmse += m.nc_relmse;
    ref_noise_mse += m.ref_noise_mse;
  }
  NoiseCorrected mean() const {
    if (frames == 0) return {};
    const double n = double(frames);
    return {nc_mse / n, nc_relmse / n, ref_noise_mse / n};
  }
};

// The --summary columns, appended after the existing ones (scripts find columns by name).
inline const char* noise_corrected_summary_header() { return "\tnc_mse\tnc_relmse\tref_noise_mse"; }
inline std::string noise_corrected_summary_values(const NoiseCorrected& m) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "\t%.6g\t%.6g\t%.6g", m.nc_mse, m.nc_relmse, m.ref_noise_mse);
  return buf;
}
// The per-frame text: "  nc_mse X  nc_relmse Y  ref_noise_mse Z".
inline std::string noise_corrected_status(const NoiseCorrected& m) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "  nc_mse %.6g  nc_relmse %.6g  ref_noise_mse %.6g", m.nc_mse, m.nc_relmse,
                m.ref_noise_mse);
  return buf;
}

}  // namespace dn::cli
