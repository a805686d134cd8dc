// Materials of the example scenes. Roughness is always GGX alpha (the
// protocol's Roughness channel), never perceptual roughness.
#pragma once

#include <glm/glm.hpp>

namespace dn::render {

enum class MaterialKind {
  Diffuse,  // Lambert only
  Metal,    // GGX only, coloured F0
  Coated,   // Lambert base under a GGX layer with F0 = 0.04
  Emitter,  // emits, reflects nothing
};

// Procedural maps, evaluated from the world position (no UVs needed).
enum class Pattern { None, Checker, Stripes, Tiles };

struct Material {
  MaterialKind kind = MaterialKind::Diffuse;
  glm::vec3 albedo{0.8f};     // diffuse albedo (Diffuse, Coated); F0 for Metal
  float alpha = 1.0f;         // GGX alpha (Metal, Coated)
  glm::vec3 emission{0.0f};   // Emitter: emitted radiance
  Pattern albedo_map = Pattern::None;
  glm::vec3 albedo2{0.2f};    // the second colour of the albedo pattern
  float map_scale = 1.0f;     // pattern cells per world unit
  Pattern roughness_map = Pattern::None;
  float alpha2 = 0.3f;        // the second alpha of the roughness pattern
};

// Coated surfaces: dielectric specular layer with n ~ 1.5.
inline constexpr float kDielectricF0 = 0.04f;
// The floor of every alpha, so GGX stays finite for mirrors.
inline constexpr float kMinAlpha = 1e-3f;

// Reflection classes (docs/protocol.md §7.5) by the GGX alpha of a pixel's
// specular lobe, the roughness channel (a coated surface by its coat's): below
// kMirrorRoughness its specular signal is a mirror image, below
// kGlossyRoughness a blurred one. They equal the server's defaults of
// reflect.mirror_roughness and reflect.glossy_roughness, so the renderer
// computes the reflection features exactly where the server reads them.
inline constexpr float kMirrorRoughness = 0.1f;
inline constexpr float kGlossyRoughness = 0.4f;

enum class ReflectionClass { None, Glossy, Mirror };
inline ReflectionClass reflection_class(float roughness) {
  if (roughness < kMirrorRoughness) return ReflectionClass::Mirror;
  return roughness < kGlossyRoughness ? ReflectionClass::Glossy : ReflectionClass::None;
}

// A material evaluated at one point: what the BSDF and the G-buffers need.
struct SurfaceParams {
  glm::vec3 diffuse_albedo{0.0f};  // 0 for metals and emitters
  glm::vec3 f0{0.0f};              // 0 for pure Lambert and emitters
  float alpha = 1.0f;              // 1 for pure Lambert (no specular lobe)
  glm::vec3 emission{0.0f};
  bool has_diffuse = false, has_specular = false;
};

SurfaceParams evaluate_material(const Material& m, const glm::vec3& world_position);

// The convex region of m's maps that holds a point: the cell of each map.
// Points with equal regions lie in one convex set over which the maps are
// constant (so is every point of a convex set with its corners in it).
struct MaterialRegion {
  glm::ivec4 albedo{0}, roughness{0};
  bool operator==(const MaterialRegion&) const = default;
};
MaterialRegion material_region(const Material& m, const glm::vec3& p);

// Whether a and b lie in one convex region over which m's maps are constant.
bool same_material_region(const Material& m, const glm::vec3& a, const glm::vec3& b);

}  // namespace dn::render
