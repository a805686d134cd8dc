// dn denoise -r: ꟻLIP of the output (dn/image/flip.hpp) and the noisy input's own
// error against the reference, per frame and for the --summary columns flip_ldr,
// flip_hdr, input_rmse, input_relmse, worse_rmse, worse_relmse. Header-only: the
// per-frame calls and the summary columns are all denoise_cmd.cpp needs.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "dn/image/flip.hpp"
#include "dn/image/metrics.hpp"
#include "frame_source.hpp"

namespace dn::cli {

// The noisy radiance a frame sent: its radiance plane, else diffuse + specular
// (+ emission), the protocol's radiance of split inputs, each signal in either
// form (lighting x its albedo); empty when the frame sent neither, and then
// the input is not measured.
inline std::vector<float> input_radiance(const std::vector<LoadedPlane>& planes) {
  using protocol::ChannelId;
  auto find = [&](ChannelId id) -> const LoadedPlane* {
    for (const auto& p : planes)
      if (p.id == id) return &p;
    return nullptr;
  };
  if (const auto* r = find(ChannelId::Radiance)) return r->data;
  // A signal's radiance: the radiance form, else lighting x albedo; empty if neither.
  auto signal = [&](ChannelId radiance, ChannelId lighting, ChannelId albedo) -> std::vector<float> {
    if (const auto* r = find(radiance)) return r->data;
    const auto *l = find(lighting), *a = find(albedo);
    if (!l || !a || l->data.size() != a->data.size()) return {};
    std::vector<float> out = l->data;
    for (size_t i = 0; i < out.size(); ++i) out[i] *= a->data[i];
    return out;
  };
  std::vector<float> sum = signal(ChannelId::Diffuse, ChannelId::DiffuseLighting, ChannelId::Albedo);
  const std::vector<float> s = signal(ChannelId::Specular, ChannelId::SpecularLighting, ChannelId::SpecularAlbedo);
  if (sum.empty() || sum.size() != s.size()) return {};
  for (size_t i = 0; i < sum.size(); ++i) sum[i] += s[i];
  if (const auto* e = find(ChannelId::Emission); e && e->data.size() == sum.size())
    for (size_t i = 0; i < sum.size(); ++i) sum[i] += e->data[i];
  return sum;
}

struct InputError {
  double rmse = NAN, relmse = NAN;  // NaN: not measured
};

inline InputError input_error(const std::vector<float>& input, const std::vector<float>& ref) {
  if (input.empty() || input.size() != ref.size()) return {};
  return {image::rmse(input.data(), ref.data(), ref.size()), image::relative_mse(input.data(), ref.data(), ref.size())};
}

struct FlipMetrics {
  double ldr = NAN, hdr = NAN;
};

// LDR-ꟻLIP on the tone-mapped images (the --tonemap/--exposure of SSIM and PNG),
// HDR-ꟻLIP on the linear radiance.
inline FlipMetrics flip_metrics(const std::vector<float>& rgb, const std::vector<float>& ref, int width, int height,
                                image::Tonemap tonemap, float exposure) {
  return {image::flip_ldr_tonemapped(rgb.data(), ref.data(), width, height, tonemap, exposure).mean,
          image::flip_hdr(rgb.data(), ref.data(), width, height).mean};
}

// Means over the measured frames, and how many of them the output made worse
// than its input (output error above the input's, NaN output counting as above,
// as --fail counts it; frames whose input was not measured are not counted).
struct ReferenceExtrasTotals {
  size_t flip_frames = 0, input_frames = 0, worse_rmse = 0, worse_relmse = 0;
  double flip_ldr = 0, flip_hdr = 0, input_rmse = 0, input_relmse = 0;

  void add_input(const InputError& in, double out_rmse, double out_relmse) {
    if (std::isnan(in.rmse)) return;
    input_frames++;
    input_rmse += in.rmse;
    input_relmse += in.relmse;
    if (!(out_rmse <= in.rmse)) worse_rmse++;
    if (!(out_relmse <= in.relmse)) worse_relmse++;
  }
  void add_flip(const FlipMetrics& f) {
    flip_frames++;
    flip_ldr += f.ldr;
    flip_hdr += f.hdr;
  }
  FlipMetrics flip_mean() const {
    return flip_frames ? FlipMetrics{flip_ldr / double(flip_frames), flip_hdr / double(flip_frames)} : FlipMetrics{};
  }
  InputError input_mean() const {
    return input_frames ? InputError{input_rmse / double(input_frames), input_relmse / double(input_frames)}
                        : InputError{};
  }
};

// The --summary columns, appended after the existing ones (scripts find columns by name).
inline const char* reference_extras_summary_header() {
  return "\tflip_ldr\tflip_hdr\tinput_rmse\tinput_relmse\tworse_rmse\tworse_relmse";
}
inline std::string reference_extras_summary_values(const ReferenceExtrasTotals& t) {
  const FlipMetrics f = t.flip_mean();
  const InputError in = t.input_mean();
  const double worse_rmse = t.input_frames ? double(t.worse_rmse) : NAN;
  const double worse_relmse = t.input_frames ? double(t.worse_relmse) : NAN;
  char buf[192];
  std::snprintf(buf, sizeof buf, "\t%.6g\t%.6g\t%.6g\t%.6g\t%.6g\t%.6g", f.ldr, f.hdr, in.rmse, in.relmse, worse_rmse,
                worse_relmse);
  return buf;
}
// Per-frame texts: "  input_rmse X  input_relmse Y" and "  flip_ldr X  flip_hdr Y".
inline std::string input_error_status(const InputError& in) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "  input_rmse %.5f  input_relmse %.5f", in.rmse, in.relmse);
  return buf;
}
inline std::string flip_status(const FlipMetrics& f) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "  flip_ldr %.5f  flip_hdr %.5f", f.ldr, f.hdr);
  return buf;
}

}  // namespace dn::cli
