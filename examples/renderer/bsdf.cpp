#include "bsdf.hpp"

#include <algorithm>
#include <cmath>

#include "sampling.hpp"

namespace dn::render {

namespace ggx {

float D(float cos_h, float alpha) {
  const float a2 = alpha * alpha;
  const float d = cos_h * cos_h * (a2 - 1.0f) + 1.0f;
  return a2 / (kPi * d * d);
}

float lambda(const glm::vec3& w, float alpha) {
  const float z2 = w.z * w.z;
  if (z2 <= 0.0f) return INFINITY;
  const float tan2 = std::max(0.0f, 1.0f - z2) / z2;
  return 0.5f * (std::sqrt(1.0f + alpha * alpha * tan2) - 1.0f);
}

float G1(const glm::vec3& w, float alpha) { return 1.0f / (1.0f + lambda(w, alpha)); }

float G2(const glm::vec3& wo, const glm::vec3& wi, float alpha) {
  return 1.0f / (1.0f + lambda(wo, alpha) + lambda(wi, alpha));
}

glm::vec3 sample_vndf(const glm::vec3& wo, float alpha, glm::vec2 u) {
  const glm::vec3 vh = glm::normalize(glm::vec3(alpha * wo.x, alpha * wo.y, wo.z));
  const float lensq = vh.x * vh.x + vh.y * vh.y;
  const glm::vec3 t1 = lensq > 0.0f ? glm::vec3(-vh.y, vh.x, 0.0f) / std::sqrt(lensq) : glm::vec3(1, 0, 0);
  const glm::vec3 t2 = glm::cross(vh, t1);
  const float r = std::sqrt(u.x);
  const float phi = 2.0f * kPi * u.y;
  const float p1 = r * std::cos(phi);
  const float s = 0.5f * (1.0f + vh.z);
  const float p2 = (1.0f - s) * std::sqrt(std::max(0.0f, 1.0f - p1 * p1)) + s * r * std::sin(phi);
  const glm::vec3 nh = p1 * t1 + p2 * t2 + std::sqrt(std::max(0.0f, 1.0f - p1 * p1 - p2 * p2)) * vh;
  return glm::normalize(glm::vec3(alpha * nh.x, alpha * nh.y, std::max(1e-6f, nh.z)));
}

}  // namespace ggx

glm::vec3 fresnel_schlick(const glm::vec3& f0, float cos_theta) {
  const float m = std::clamp(1.0f - cos_theta, 0.0f, 1.0f);
  const float m2 = m * m;
  return f0 + (glm::vec3(1.0f) - f0) * (m2 * m2 * m);
}

Bsdf::Bsdf(const SurfaceParams& surface, const glm::vec3& wo) : surface_(surface), wo_(wo) {
  wo_.z = std::max(wo_.z, 1e-6f);
  if (surface_.has_specular && surface_.has_diffuse) {
    const glm::vec3 f = fresnel_schlick(surface_.f0, wo_.z);
    diffuse_scale_ = 1.0f - f.g;  // the coat's F0 is grey
    const float spec = luminance(f);
    const float diff = luminance(surface_.diffuse_albedo) * diffuse_scale_;
    p_specular_ = std::clamp(spec / std::max(spec + diff, 1e-6f), 0.05f, 0.95f);
  } else {
    p_specular_ = surface_.has_specular ? 1.0f : 0.0f;
  }
}

BsdfEval Bsdf::eval(const glm::vec3& wi) const {
  BsdfEval e;
  if (wi.z <= 0.0f) return e;
  if (surface_.has_diffuse) {
    e.f_diffuse = surface_.diffuse_albedo * (diffuse_scale_ / kPi);
    e.pdf_diffuse = (1.0f - p_specular_) * wi.z / kPi;
  }
  if (surface_.has_specular) {
    const glm::vec3 h = glm::normalize(wo_ + wi);
    const float d = ggx::D(h.z, surface_.alpha);
    const glm::vec3 f = fresnel_schlick(surface_.f0, glm::dot(wo_, h));
    e.f_specular = f * (d * ggx::G2(wo_, wi, surface_.alpha) / (4.0f * wo_.z * wi.z));
    e.pdf_specular = p_specular_ * ggx::G1(wo_, surface_.alpha) * d / (4.0f * wo_.z);
  }
  return e;
}

BsdfSample Bsdf::sample(float u_lobe, glm::vec2 u) const {
  BsdfSample s;
  if (!reflects()) return s;
  if (u_lobe < p_specular_) {
    const glm::vec3 h = ggx::sample_vndf(wo_, surface_.alpha, u);
    const float wo_h = glm::dot(wo_, h);
    s.wi = 2.0f * wo_h * h - wo_;
    if (s.wi.z <= 0.0f || wo_h <= 0.0f) return s;
    const float g1 = ggx::G1(wo_, surface_.alpha);
    s.weight = fresnel_schlick(surface_.f0, wo_h) * (ggx::G2(wo_, s.wi, surface_.alpha) / g1) / p_specular_;
    s.pdf = p_specular_ * g1 * ggx::D(h.z, surface_.alpha) / (4.0f * wo_.z);
    s.lobe = Lobe::Specular;
  } else {
    s.wi = sample_cosine_hemisphere(u);
    if (s.wi.z <= 0.0f) return s;
    const float p = 1.0f - p_specular_;
    s.weight = surface_.diffuse_albedo * (diffuse_scale_ / p);
    s.pdf = p * s.wi.z / kPi;
    s.lobe = Lobe::Diffuse;
  }
  s.valid = true;
  return s;
}

}  // namespace dn::render
