// One path: next-event estimation with MIS (power heuristic) for area
// lights, BSDF sampling, Russian roulette.
//
// The diffuse/specular split: light reflected at the primary hit by NEE goes
// to the lobe that reflected it (each lobe's BRDF is evaluated separately);
// everything a path gathers after its first bounce goes to the lobe that
// first bounce sampled. Emission seen directly by the camera goes to neither.
// So radiance = diffuse + specular + emission, sample by sample.
#pragma once

#include <glm/glm.hpp>

#include "sampling.hpp"
#include "scene.hpp"

namespace dn::render {

struct PathResult {
  glm::vec3 diffuse{0.0f}, specular{0.0f}, emission{0.0f};
  glm::vec3 total() const { return diffuse + specular + emission; }
};

struct PathSettings {
  int max_depth = 8;        // path vertices after the primary hit
  bool next_event = true;   // false: BSDF sampling alone (an independent estimator, for tests)
};

// `primary` is what the camera ray along `dir` hit (found == false: background).
PathResult trace_path(const Scene& scene, const glm::vec3& dir, const Hit& primary, Rng& rng,
                      const PathSettings& settings, TraceContext& ctx);

// The shading normal: the geometric normal turned towards the side `towards` points to.
inline glm::vec3 facing_normal(const glm::vec3& normal, const glm::vec3& towards) {
  return glm::dot(normal, towards) < 0.0f ? -normal : normal;
}

}  // namespace dn::render
