// Writes a rendered frame as one EXR in the dnrender layout (docs/client.md,
// "Preset dnrender") plus the extra layers documented in docs/renderer.md.
#pragma once

#include <array>
#include <map>
#include <string>

#include <glm/glm.hpp>

#include "camera.hpp"
#include "render.hpp"

namespace dn::render {

// GLM's column-major memory order, which is the M44f array the layout stores.
std::array<float, 16> to_array(const glm::mat4& m);

void write_frame_exr(const std::string& path, const FrameBuffers& fb, const Camera& camera, const Camera& previous,
                     const std::map<std::string, std::string>& attributes = {});

}  // namespace dn::render
