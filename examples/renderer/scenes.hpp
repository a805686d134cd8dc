// The built-in scenes and their camera paths. Scenes are static; only
// the camera moves, as a deterministic function of the frame index.
#pragma once

#include <memory>
#include <string>

#include "camera.hpp"
#include "scene.hpp"

namespace dn::render {

inline constexpr int kSceneCount = 6;

// 1 room: roughness-mapped glossy floor, mirror and glossy metal spheres, diffuse objects, soft shadows
// 2 pillars: a sideways flythrough past pillars that keep occluding a dim, indirectly lit wall
// 3 gap: a dark room lit mostly indirectly through a slit in one wall
// 4 fireflies: a small, very bright sphere light over glossy surfaces
// 5 roughness: fine roughness checks and stripes on a glossy floor and a metal panel (BRDF-map detail)
// 6 mirror-floor: a planar wall mirror and a glossy floor, camera translating sideways (reflection motion)
std::unique_ptr<Scene> build_scene(int scene_id);
std::string scene_name(int scene_id);
// Unjittered camera of frame `frame` (frame - 1 gives the previous camera, also for frame 0).
Camera scene_camera(int scene_id, int frame, int width, int height);

}  // namespace dn::render
