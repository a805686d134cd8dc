// GLSL expansion of a pass declaration (shaders/passes/<pass>.pass, whose rows
// the build numbers into generated/passes/<pass>.pass: n and id below): include
// this, then generated/passes/<pass>.pass, where the shader declares its resources.
//   DN_BINDING(n, name, element, read | write | read_write, need)
//     -> layout(std430, set = 0, binding = n) <access> buffer name_block { element data[]; } name;
//        and, for read: element name_at(uint i) = name.data[i]
//   DN_BINDING(n, name, element, texel, need)
//     -> layout(set = 0, binding = n) uniform [u]samplerBuffer name_texels;
//        element name_at(uint i): element i, by texelFetch
// A shader that reads through name_at() runs with either access, so a
// binding switches between read and texel in its .pass alone.
//   DN_SPEC(id, name, type, default)
//     -> layout(constant_id = id) const type name = default;
//   DN_GRID_ARG(slot, name, uint | float)
//     -> type dn_arg_name(): word `slot` of the grid's args (the host's PassSpec::arg)
//   DN_MODE(value, name) -> const uint DN_MODE_name = value (PassSpec::mode)
//   DN_MODE_NEEDS(mode, binding) -> nothing (GraphSpec::check)
// A texel binding reads the same buffer through a uniform texel buffer view
// (the host makes one of the element's format): lavapipe gathers a texel in
// one fetch, where it loads a storage buffer word by word, lane by lane
// (bench/gather_bench: 5x5 vec4 neighbourhoods 0.28-0.30x the time).
// The host reads the same file as a table (server/pipelines/pass.hpp binds by
// name); tests/pipelines/spirv_reflection_test.cpp checks the compiled SPIR-V
// against that table.
#ifndef DN_PASS_GLSL
#define DN_PASS_GLSL

#define DN_ACCESS_read readonly
#define DN_ACCESS_write writeonly
#define DN_ACCESS_read_write

#define DN_STORAGE_BINDING(n, name, element, access) \
  layout(std430, set = 0, binding = n) DN_ACCESS_##access buffer name##_block { element data[]; } name;
#define DN_BINDING_read(n, name, element) \
  DN_STORAGE_BINDING(n, name, element, read) \
  element name##_at(uint i) { return name.data[i]; }
#define DN_BINDING_write(n, name, element) DN_STORAGE_BINDING(n, name, element, write)
#define DN_BINDING_read_write(n, name, element) DN_STORAGE_BINDING(n, name, element, read_write)

// Texel bindings: the sampler type and the components of the fetched texel
// that make the element (the host's format: server/pipelines/pass.cpp).
#define DN_TEXEL_SAMPLER_vec4 samplerBuffer
#define DN_TEXEL_SAMPLER_vec2 samplerBuffer
#define DN_TEXEL_SAMPLER_float samplerBuffer
#define DN_TEXEL_SAMPLER_uvec4 usamplerBuffer
#define DN_TEXEL_SAMPLER_uvec2 usamplerBuffer
#define DN_TEXEL_SAMPLER_uint usamplerBuffer
#define DN_TEXEL_PICK_vec4(t) (t)
#define DN_TEXEL_PICK_vec2(t) (t).xy
#define DN_TEXEL_PICK_float(t) (t).x
#define DN_TEXEL_PICK_uvec4(t) (t)
#define DN_TEXEL_PICK_uvec2(t) (t).xy
#define DN_TEXEL_PICK_uint(t) (t).x
#define DN_BINDING_texel(n, name, element)                                  \
  layout(set = 0, binding = n) uniform DN_TEXEL_SAMPLER_##element name##_texels; \
  element name##_at(uint i) { return DN_TEXEL_PICK_##element(texelFetch(name##_texels, int(i))); }

#define DN_BINDING(n, name, element, access, need) DN_BINDING_##access(n, name, element)
#define DN_SPEC(id, name, type, value) layout(constant_id = id) const type name = value;
// A named grid argument: word `slot` of the grid's push constants (grid2d.glsl,
// included before), read as dn_arg_<name>() of its type (uint or float).
#define DN_GRID_ARG_uint(slot) dn_grid.args[slot]
#define DN_GRID_ARG_float(slot) uintBitsToFloat(dn_grid.args[slot])
#define DN_GRID_ARG(slot, name, type) type dn_arg_##name() { return DN_GRID_ARG_##type(slot); }
// A named value of the uint constant MODE, compared as MODE == DN_MODE_<name>;
// the bindings a mode needs are the host's check alone.
#define DN_MODE(value, name) const uint DN_MODE_##name = value;
#define DN_MODE_NEEDS(mode, binding)
// How many elements per pixel of the session the binding's buffer holds: the
// host sizes the buffer from it (GraphSpec::size_from_bindings).
#define DN_PER_PIXEL(binding, count)

#endif
