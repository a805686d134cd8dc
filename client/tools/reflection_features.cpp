#include "reflection_features.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <glm/glm.hpp>
#include <glm/gtc/type_ptr.hpp>

namespace dn::cli {
namespace {

using protocol::ChannelId;

std::vector<float>* plane_with(LoadedFrame& frame, const std::vector<ResolvedChannel>& plan, Convert c) {
  for (const auto& ch : plan)
    if (ch.convert == c)
      for (auto& p : frame.planes)
        if (p.id == ch.id) return &p.data;
  return nullptr;
}

// The raw Denoising Depth's EXR channel: the term of the length and depth
// conversions, a source of the hit's (presets.cpp); empty when none is planned.
std::string denoising_depth_channel(const std::vector<ResolvedChannel>& plan) {
  for (const auto& ch : plan) {
    if ((ch.convert == Convert::CyclesChainLength || ch.convert == Convert::CyclesChainDepth) && !ch.terms.empty())
      return ch.terms.front().front();
    if (ch.convert == Convert::CyclesChainHit && !ch.sources.empty()) return ch.sources.front().front();
  }
  return {};
}

// A path that goes on less than this fraction of the primary distance past
// the primary hit stopped there (float rounding).
constexpr double kNoChain = 1e-3;
// Below this specular albedo the length past the mirror is not recoverable.
constexpr double kMinMirrorAlbedo = 0.05;

// Schlick's Fresnel: the reflectance of a smooth surface of F0 `f0` at cos theta `c`.
double schlick(double f0, double c) { return f0 + (1.0 - f0) * std::pow(1.0 - std::clamp(c, 0.0, 1.0), 5.0); }

}  // namespace

void derive_reflection_features(LoadedFrame& frame, const std::vector<ResolvedChannel>& plan,
                                const dn::image::ExrReader& exr, const ChannelSyntax& syntax) {
  std::vector<float>* dir = plane_with(frame, plan, Convert::CyclesMirrorDirection);
  std::vector<float>* length = plane_with(frame, plan, Convert::CyclesChainLength);
  std::vector<float>* vdepth = plane_with(frame, plan, Convert::CyclesChainDepth);
  std::vector<float>* hit = plane_with(frame, plan, Convert::CyclesChainHit);
  std::vector<float>* cam_normal = plane_with(frame, plan, Convert::CyclesCameraNormal);
  if (!dir && !length && !vdepth && !hit && !cam_normal) return;
  if (!frame.camera.view || !frame.camera.projection)
    throw std::runtime_error(frame.path + ": the reflection features need the frame's camera: give the Position "
                             "pass (View Layer Properties > Passes > Data > Position) or " + syntax.camera);
  const glm::dmat4 view = glm::dmat4(glm::make_mat4(frame.camera.view->data()));
  const glm::dmat4 to_world = glm::inverse(view);
  const glm::dvec3 eye = glm::dvec3(to_world[3]);
  std::vector<float> position;
  for (const auto& p : frame.planes)
    if (p.id == ChannelId::Position) position = p.data;
  if (position.empty()) throw std::logic_error("derive_reflection_features: the plan lacks position");
  const size_t n = size_t(frame.width) * size_t(frame.height);

  // The Denoising Depth (raw) from the file; the mirror's F0 from the plan.
  std::vector<float> dd, f0;
  if (length || vdepth || hit) {
    const std::string dd_channel = denoising_depth_channel(plan);
    if (dd_channel.empty()) throw std::logic_error("derive_reflection_features: no Denoising Depth in the plan");
    dd = exr.read_channel(dd_channel);
  }
  for (const auto& p : frame.planes)
    if (p.id == ChannelId::SpecularF0) f0 = p.data;
  // Per pixel: primary distance t1 and view depth z1 (cos = z1 / t1).
  std::vector<double> t1(n), z1(n);
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec3 p(position[3 * i], position[3 * i + 1], position[3 * i + 2]);
    t1[i] = glm::length(p - eye);
    z1[i] = -(view * glm::dvec4(p, 1.0)).z;
  }
  // The clip start: (t1 - DD) cos where the path stops at the primary hit.
  double clip = 0.0;
  if (!dd.empty()) {
    std::vector<double> offsets;
    for (size_t i = 0; i < n; ++i) {
      const double gap = t1[i] - double(dd[i]);
      if (std::isfinite(gap) && z1[i] > 0.0 && gap >= 0.0 && gap <= 0.05 * t1[i]) offsets.push_back(gap * z1[i] / t1[i]);
    }
    if (!offsets.empty()) {
      std::nth_element(offsets.begin(), offsets.begin() + offsets.size() / 2, offsets.end());
      clip = offsets[offsets.size() / 2];
    }
  }

  for (size_t i = 0; i < n; ++i) {
    const glm::dvec3 p(position[3 * i], position[3 * i + 1], position[3 * i + 2]);
    const bool fg = std::isfinite(t1[i]) && z1[i] > 0.0;
    // Mirror direction about the Normal pass (loaded into `dir`), and cos theta_o.
    glm::dvec3 r(0.0);
    double cos_o = 1.0;
    if (dir) {
      const glm::dvec3 nn((*dir)[3 * i], (*dir)[3 * i + 1], (*dir)[3 * i + 2]);
      const double len = glm::length(nn);
      if (fg && len > 0.0 && std::isfinite(len)) {
        const glm::dvec3 d = (p - eye) / t1[i], u = nn / len;
        r = d - 2.0 * glm::dot(d, u) * u;
        cos_o = std::fabs(glm::dot(d, u));
      }
      for (int k = 0; k < 3; ++k) (*dir)[3 * i + k] = float(r[k]);
    }
    // The mirror's specular albedo, averaged over RGB (1 without an F0).
    double a_mean = 1.0;
    if (!f0.empty()) {
      a_mean = 0.0;
      for (int k = 0; k < 3; ++k) a_mean += schlick(std::isfinite(f0[3 * i + k]) ? f0[3 * i + k] : 1.0, cos_o) / 3.0;
    }
    // The length past the primary hit.
    double t2 = 0.0;
    if (!dd.empty() && fg) {
      const double past = double(dd[i]) + clip * t1[i] / z1[i] - t1[i];
      if (a_mean >= kMinMirrorAlbedo && std::isfinite(past) && past > kNoChain * t1[i]) t2 = past / a_mean;
    }
    if (length) (*length)[i] = float(t2);
    if (vdepth) (*vdepth)[i] = fg ? float(z1[i] * (t1[i] + t2) / t1[i]) : std::numeric_limits<float>::infinity();
    if (hit)
      for (int k = 0; k < 3; ++k) (*hit)[3 * i + k] = float(p[k] + r[k] * t2);
    if (cam_normal) {
      const glm::dvec3 c((*cam_normal)[3 * i], (*cam_normal)[3 * i + 1], (*cam_normal)[3 * i + 2]);
      // Cycles' camera space looks down +z; the view matrix's down -z.
      const glm::dvec3 w = glm::dvec3(to_world * glm::dvec4(c.x, c.y, -c.z, 0.0));
      for (int k = 0; k < 3; ++k) (*cam_normal)[3 * i + k] = float(w[k]);
    }
  }
}

}  // namespace dn::cli
