// GLSL expansion of a pass declaration (shaders/passes/<pass>.pass): include
// this, then the declaration, where the shader declares its resources.
//   DN_BINDING(n, name, element, access, need)
//     -> layout(std430, set = 0, binding = n) <access> buffer name_block { element data[]; } name;
//   DN_SPEC(id, name, type, default)
//     -> layout(constant_id = id) const type name = default;
// The host reads the same file as a table (server/pipelines/pass.hpp binds by
// name); tests/pipelines/spirv_reflection_test.cpp checks the compiled SPIR-V
// against that table.
#ifndef DN_PASS_GLSL
#define DN_PASS_GLSL

#define DN_ACCESS_read readonly
#define DN_ACCESS_write writeonly
#define DN_ACCESS_read_write

#define DN_BINDING(n, name, element, access, need) \
  layout(std430, set = 0, binding = n) DN_ACCESS_##access buffer name##_block { element data[]; } name;
#define DN_SPEC(id, name, type, value) layout(constant_id = id) const type name = value;

#endif
