#include "material.hpp"

#include <algorithm>
#include <cmath>

namespace dn::render {
namespace {

// Surfaces lie on cell boundaries (the room floor at y = 0): a hit's coordinate
// there is +-1e-7, and floor() of it would flip the checker pixel by pixel.
// Cells start this far below each integer, so such a surface reads one cell.
constexpr float kCellEpsilon = 1e-3f;

// 0 or 1: which of the two pattern values applies at p.
float pattern_select(Pattern pattern, const glm::vec3& p, float scale) {
  const glm::vec3 q = p * scale;
  switch (pattern) {
    case Pattern::None:
      return 0.0f;
    case Pattern::Checker:
      return static_cast<float>((static_cast<int>(std::floor(q.x + kCellEpsilon)) +
                                 static_cast<int>(std::floor(q.y + kCellEpsilon)) +
                                 static_cast<int>(std::floor(q.z + kCellEpsilon))) & 1);
    case Pattern::Stripes:
      return std::fmod(std::fabs(q.x + 0.5f * q.z), 1.0f) < 0.5f ? 1.0f : 0.0f;
    case Pattern::Tiles: {
      // Grout lines between square tiles: a thin grid.
      const float fx = q.x - std::floor(q.x), fz = q.z - std::floor(q.z);
      return (fx < 0.06f || fz < 0.06f) ? 1.0f : 0.0f;
    }
  }
  return 0.0f;
}

// The convex region of constant pattern value that holds p: checker, the
// cube cell; stripes, the half-unit slab; tiles, the tile or one of the three
// grout rectangles of its cell.
glm::ivec4 pattern_cell(Pattern pattern, const glm::vec3& p, float scale) {
  const glm::vec3 q = p * scale;
  auto fl = [](float v) { return static_cast<int>(std::floor(v)); };
  switch (pattern) {
    case Pattern::None:
      return glm::ivec4(0);
    case Pattern::Checker:
      return {fl(q.x + kCellEpsilon), fl(q.y + kCellEpsilon), fl(q.z + kCellEpsilon), 0};
    case Pattern::Stripes:
      return {fl(2.0f * (q.x + 0.5f * q.z)), 0, 0, 1};
    case Pattern::Tiles: {
      const float fx = q.x - std::floor(q.x), fz = q.z - std::floor(q.z);
      return {fl(q.x), fl(q.z), fx < 0.06f ? 1 : 0, fz < 0.06f ? 1 : 0};
    }
  }
  return glm::ivec4(0);
}

}  // namespace

MaterialRegion material_region(const Material& m, const glm::vec3& p) {
  return {pattern_cell(m.albedo_map, p, m.map_scale), pattern_cell(m.roughness_map, p, m.map_scale)};
}

bool same_material_region(const Material& m, const glm::vec3& a, const glm::vec3& b) {
  return material_region(m, a) == material_region(m, b);
}

SurfaceParams evaluate_material(const Material& m, const glm::vec3& p) {
  SurfaceParams s;
  if (m.kind == MaterialKind::Emitter) {
    s.emission = m.emission;
    return s;
  }
  const glm::vec3 colour = glm::mix(m.albedo, m.albedo2, pattern_select(m.albedo_map, p, m.map_scale));
  const float alpha = std::max(kMinAlpha, glm::mix(m.alpha, m.alpha2, pattern_select(m.roughness_map, p, m.map_scale)));
  switch (m.kind) {
    case MaterialKind::Diffuse:
      s.diffuse_albedo = colour;
      s.has_diffuse = true;
      break;
    case MaterialKind::Metal:
      s.f0 = colour;
      s.alpha = alpha;
      s.has_specular = true;
      break;
    case MaterialKind::Coated:
      s.diffuse_albedo = colour;
      s.f0 = glm::vec3(kDielectricF0);
      s.alpha = alpha;
      s.has_diffuse = s.has_specular = true;
      break;
    case MaterialKind::Emitter:
      break;
  }
  return s;
}

}  // namespace dn::render
