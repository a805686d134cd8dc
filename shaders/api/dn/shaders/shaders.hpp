// Embedded SPIR-V of every compute shader in shaders/, generated at build time.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace dn::shaders {

// The SPIR-V words of the shader compiled from <name>.comp, or an empty span
// when there is no such shader.
std::span<const uint32_t> get(std::string_view name);

// Names of all embedded shaders, in build order.
std::vector<std::string_view> names();

}  // namespace dn::shaders
