// The BSDF: a Lambert lobe and a GGX microfacet lobe (Schlick Fresnel,
// height-correlated Smith G2, visible-normal sampling after Heitz 2018).
// Directions are local: +z is the shading normal; wo points away from the
// surface towards the viewer.
//
// Each lobe is its own estimator: a sample picks one lobe with probability
// p_lobe and returns weight f_lobe cos / (p_lobe pdf_lobe). That keeps the
// diffuse and specular radiance separately unbiased, which the split output
// needs, and MIS then weighs each lobe against light sampling on its own.
#pragma once

#include <glm/glm.hpp>

#include "material.hpp"

namespace dn::render {

enum class Lobe : int { Diffuse = 0, Specular = 1 };

namespace ggx {
float D(float cos_h, float alpha);
float lambda(const glm::vec3& w, float alpha);
float G1(const glm::vec3& w, float alpha);
float G2(const glm::vec3& wo, const glm::vec3& wi, float alpha);  // height-correlated
glm::vec3 sample_vndf(const glm::vec3& wo, float alpha, glm::vec2 u);  // returns the half vector
}  // namespace ggx

glm::vec3 fresnel_schlick(const glm::vec3& f0, float cos_theta);

struct BsdfEval {
  glm::vec3 f_diffuse{0.0f}, f_specular{0.0f};  // BRDF values (no cosine)
  float pdf_diffuse = 0.0f, pdf_specular = 0.0f;  // solid-angle pdfs, lobe choice included
};

struct BsdfSample {
  glm::vec3 wi{0.0f};
  glm::vec3 weight{0.0f};  // f cos / pdf
  float pdf = 0.0f;        // lobe choice included
  Lobe lobe = Lobe::Diffuse;
  bool valid = false;
};

class Bsdf {
 public:
  Bsdf(const SurfaceParams& surface, const glm::vec3& wo);
  bool reflects() const { return surface_.has_diffuse || surface_.has_specular; }
  float specular_probability() const { return p_specular_; }
  BsdfEval eval(const glm::vec3& wi) const;
  BsdfSample sample(float u_lobe, glm::vec2 u) const;

 private:
  SurfaceParams surface_;
  glm::vec3 wo_;
  float diffuse_scale_ = 1.0f;  // energy the coat lets through to the base: 1 - F(cos_o)
  float p_specular_ = 0.0f;
};

}  // namespace dn::render
