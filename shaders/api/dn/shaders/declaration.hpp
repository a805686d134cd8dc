// The resource declaration of every shader (its <name>.pass): the buffers
// it binds, the specialization constants, grid arguments and modes it reads. The
// same X-macro file becomes the shader's GLSL declarations (include/pass.glsl)
// and, here, a table, so the host binds buffers and sets constants by name
// and never by position. The table is generated at build time (one per
// shader in DN_SHADER_SOURCES) from the numbered declarations
// (shaders/tools/number_pass.cpp); numbering is checked when it compiles.
#pragma once

#include <bit>
#include <cstdint>
#include <span>
#include <string_view>

namespace dn::shaders {

// texel: read through a uniform texel buffer view of the element's format
// (shaders/include/pass.glsl), not as a storage buffer.
enum class Access : uint8_t { read, write, read_write, texel };
// An unbound optional binding is bound to a context-wide placeholder buffer;
// the shader must not touch it then (a specialization constant decides).
enum class Need : uint8_t { required, optional };
enum class SpecType : uint8_t { t_bool, t_int, t_uint, t_float };

struct BindingDecl {
  uint32_t binding = 0;      // set 0, binding 1.. in declaration order (0 is the FrameConstants block)
  std::string_view name;     // the GLSL instance name (block name: <name>_block) and the host's name
  std::string_view element;  // GLSL type of the block's only member, data[]
  Access access = Access::read;
  Need need = Need::required;
  constexpr uint32_t number() const { return binding; }
};

struct SpecDecl {
  uint32_t id = 0;  // constant_id 1.. in declaration order (0 is the workgroup size)
  std::string_view name;
  SpecType type = SpecType::t_bool;
  uint32_t default_bits = 0;  // the 32-bit value VkSpecializationInfo would carry
  constexpr uint32_t number() const { return id; }
};

// A named word of the grid's push constants (dn::gpu::GridPush::args): the
// shader reads it as dn_arg_<name>(), the host sets it with PassSpec::arg.
struct GridArgDecl {
  uint32_t slot = 0;  // 0..3 in declaration order
  std::string_view name;
  SpecType type = SpecType::t_uint;  // t_uint or t_float
  constexpr uint32_t number() const { return slot; }
};

// A named value of the pass's uint constant MODE (0, 1, ... in declaration
// order): the shader compares MODE with DN_MODE_<name>, the host selects it
// with PassSpec::mode(name).
struct ModeDecl {
  uint32_t value = 0;
  std::string_view name;
  constexpr uint32_t number() const { return value; }
};

// A binding a mode cannot run without (GraphSpec::check refuses it unbound).
struct ModeNeed {
  std::string_view mode;
  std::string_view binding;
};

// The size rule of a binding: its buffer holds `per_pixel` elements per
// pixel of the session (DN_PER_PIXEL), so the host sizes it from here.
struct SizeDecl {
  std::string_view binding;
  uint32_t per_pixel = 0;
};

// Bytes of one element of a binding's data[] (std430), 0 for a type a size
// rule cannot use.
constexpr uint32_t element_bytes(std::string_view element) {
  if (element == "float" || element == "uint" || element == "int") return 4;
  if (element == "vec2" || element == "uvec2" || element == "ivec2") return 8;
  if (element == "vec4" || element == "uvec4" || element == "ivec4") return 16;
  return 0;
}

struct Declaration {
  std::string_view shader;
  std::span<const BindingDecl> bindings;  // bindings[i].binding == i + 1
  std::span<const SpecDecl> constants;    // constants[i].id == i + 1
  std::span<const GridArgDecl> grid_args;  // grid_args[i].slot == i
  std::span<const ModeDecl> modes;          // modes[i].value == i
  std::span<const ModeNeed> mode_needs;
  std::span<const SizeDecl> sizes;

  constexpr const BindingDecl* binding(std::string_view name) const {
    for (const auto& b : bindings)
      if (b.name == name) return &b;
    return nullptr;
  }
  constexpr const SpecDecl* constant(std::string_view name) const {
    for (const auto& c : constants)
      if (c.name == name) return &c;
    return nullptr;
  }
  constexpr const ModeDecl* mode(std::string_view name) const {
    for (const auto& m : modes)
      if (m.name == name) return &m;
    return nullptr;
  }
  // The binding's DN_PER_PIXEL count; 0 when it declares no size rule.
  constexpr uint32_t per_pixel(std::string_view binding) const {
    for (const auto& s : sizes)
      if (s.binding == binding) return s.per_pixel;
    return 0;
  }
  constexpr const GridArgDecl* grid_arg(std::string_view name) const {
    for (const auto& a : grid_args)
      if (a.name == name) return &a;
    return nullptr;
  }
};

// The declaration of the shader compiled from <name>.comp; nullptr if none.
const Declaration* declaration(std::string_view shader);
// Every declaration, in DN_SHADER_SOURCES order.
std::span<const Declaration> declarations();

// A default literal as the 32 bits a specialization constant carries.
constexpr uint32_t spec_bits(bool v) { return v ? 1u : 0u; }
constexpr uint32_t spec_bits(int v) { return static_cast<uint32_t>(v); }
constexpr uint32_t spec_bits(unsigned v) { return v; }
constexpr uint32_t spec_bits(float v) { return std::bit_cast<uint32_t>(v); }
constexpr uint32_t spec_bits(double v) { return std::bit_cast<uint32_t>(static_cast<float>(v)); }

}  // namespace dn::shaders
