// Every embedded shader against its declaration (its <name>.pass,
// dn::shaders::declaration), from the compiled SPIR-V itself: spirv-cross
// --reflect output written at build time (shaders/CMakeLists.txt). Storage
// buffers: binding numbers, names, element type, readonly/writeonly;
// specialization constants: ids, names, types, defaults; the constants block
// at binding 0: FrameConstants with the C++ struct's member offsets, down to
// every parameters.def row in its parameter struct, and no uniform block.
#include <gtest/gtest.h>

#include <cstddef>
#include <set>
#include <string>

#include "dn/shaders/declaration.hpp"
#include "dn/shaders/shaders.hpp"
#include "json_lite.hpp"
#include "pipelines/frame_constants.hpp"
#include "pipelines/parameters.hpp"
#include "text_file.hpp"

namespace dn {
namespace {

using test::json::Value;

Value reflection(std::string_view shader) {
  return test::json::parse(test::read_text(std::string(DN_SPIRV_DIR) + "/" + std::string(shader) + ".spv.json"));
}

const char* type_name(shaders::SpecType t) {
  switch (t) {
    case shaders::SpecType::t_bool: return "bool";
    case shaders::SpecType::t_int: return "int";
    case shaders::SpecType::t_uint: return "uint";
    case shaders::SpecType::t_float: return "float";
  }
  return "?";
}

// spirv-cross writes bool defaults as true/false and numbers as numbers
// (a float default as its value).
uint32_t default_bits(const Value& v, shaders::SpecType type) {
  if (v.kind == Value::Kind::Bool) return v.boolean ? 1u : 0u;
  if (type == shaders::SpecType::t_float) return shaders::spec_bits(static_cast<float>(v.number));
  if (type == shaders::SpecType::t_int) return static_cast<uint32_t>(static_cast<int32_t>(v.number));
  return static_cast<uint32_t>(v.number);
}

// Offsets of FrameConstants' members as C++ lays them out.
struct Member {
  std::string name;
  size_t offset;
};
std::vector<Member> frame_constants_members() {
  using pipelines::FrameConstants;
  return {{"size", offsetof(FrameConstants, size)},
          {"motion", offsetof(FrameConstants, motion)},
          {"inverse_view_projection", offsetof(FrameConstants, inverse_view_projection)},
          {"previous_view_projection", offsetof(FrameConstants, previous_view_projection)},
          {"params", offsetof(FrameConstants, params)}};
}

// Offsets of the parameter struct's members (one per parameters.def row, <group>_<name>).
std::vector<Member> parameter_members() {
  std::vector<Member> out;
  const pipelines::Parameters p;
  for (const auto& row : pipelines::parameter_table())
    out.push_back({std::string(row.group) + "_" + row.info.name,
                   static_cast<size_t>(reinterpret_cast<const char*>(&(p.*row.member)) -
                                       reinterpret_cast<const char*>(&p))});
  return out;
}

std::vector<std::string> shader_names() {
  std::vector<std::string> out;
  for (auto n : shaders::names()) out.emplace_back(n);
  return out;
}

TEST(Reflection, EveryEmbeddedShaderHasADeclarationAndViceVersa) {
  std::set<std::string> embedded, declared;
  for (auto n : shaders::names()) embedded.emplace(n);
  for (const auto& d : shaders::declarations()) declared.emplace(d.shader);
  EXPECT_EQ(embedded, declared);
}

class ShaderReflection : public testing::TestWithParam<std::string> {};

TEST_P(ShaderReflection, BuffersMatchTheDeclaration) {
  const shaders::Declaration* decl = shaders::declaration(GetParam());
  ASSERT_NE(decl, nullptr);
  const Value r = reflection(GetParam());
  std::set<uint32_t> seen;
  const Value empty;
  const Value& ssbos = r.has("ssbos") ? r["ssbos"] : empty;
  for (const Value& b : ssbos.array) {
    const uint32_t binding = static_cast<uint32_t>(b["binding"].number);
    SCOPED_TRACE("binding " + std::to_string(binding) + " (" + b["name"].string + ")");
    EXPECT_EQ(b["set"].number, 0.0);
    if (binding == 0) continue;  // the constants block (below)
    ASSERT_LE(binding, decl->bindings.size()) << "not declared";
    EXPECT_TRUE(seen.insert(binding).second) << "bound twice";
    const shaders::BindingDecl& d = decl->bindings[binding - 1];
    EXPECT_EQ(b["name"].string, std::string(d.name) + "_block");
    const bool readonly = b.has("readonly") && b["readonly"].boolean;
    const bool writeonly = b.has("writeonly") && b["writeonly"].boolean;
    EXPECT_EQ(readonly, d.access == shaders::Access::read) << d.name;
    EXPECT_EQ(writeonly, d.access == shaders::Access::write) << d.name;
    // The block's one member: `element data[]`, a runtime array.
    const Value& type = r["types"][b["type"].string];
    ASSERT_EQ(type["members"].array.size(), 1u);
    const Value& member = type["members"][0];
    EXPECT_EQ(member["name"].string, "data");
    EXPECT_EQ(member["type"].string, std::string(d.element)) << d.name;
    ASSERT_TRUE(member.has("array"));
    EXPECT_EQ(member["array"].array.size(), 1u);
    EXPECT_EQ(member["array"][0].number, 0.0) << "runtime-sized";
  }
  // Texel bindings (pass.glsl): a [u]samplerBuffer named <name>_texels of
  // the element's scalar kind. (A bench kernel's own sampled image is not
  // part of its declaration: bench_bilinear_image.)
  const Value& textures = r.has("textures") ? r["textures"] : empty;
  for (const Value& t : textures.array) {
    if (t["type"].string.find("samplerBuffer") == std::string::npos) continue;
    const uint32_t binding = static_cast<uint32_t>(t["binding"].number);
    SCOPED_TRACE("binding " + std::to_string(binding) + " (" + t["name"].string + ")");
    EXPECT_EQ(t["set"].number, 0.0);
    ASSERT_GE(binding, 1u);
    ASSERT_LE(binding, decl->bindings.size()) << "not declared";
    EXPECT_TRUE(seen.insert(binding).second) << "bound twice";
    const shaders::BindingDecl& d = decl->bindings[binding - 1];
    EXPECT_EQ(d.access, shaders::Access::texel) << d.name << " is read as a texel buffer but declared otherwise";
    EXPECT_EQ(t["name"].string, std::string(d.name) + "_texels");
    const bool unsigned_element = d.element.front() == 'u';
    EXPECT_EQ(t["type"].string, unsigned_element ? "usamplerBuffer" : "samplerBuffer") << d.name;
  }
  EXPECT_EQ(seen.size(), decl->bindings.size()) << "declared bindings missing from the SPIR-V";
}

TEST_P(ShaderReflection, SpecializationConstantsMatchTheDeclaration) {
  const shaders::Declaration* decl = shaders::declaration(GetParam());
  ASSERT_NE(decl, nullptr);
  const Value r = reflection(GetParam());
  // Constant 0 is the workgroup size (local_size_x_id = 0) in every shader.
  const Value& entry = r["entryPoints"][0];
  EXPECT_TRUE(entry["workgroup_size_is_spec_constant_id"][0].boolean);
  EXPECT_EQ(entry["workgroup_size"][0].number, 0.0);
  std::set<uint32_t> seen;
  const Value empty;
  const Value& constants = r.has("specialization_constants") ? r["specialization_constants"] : empty;
  for (const Value& c : constants.array) {
    const uint32_t id = static_cast<uint32_t>(c["id"].number);
    if (id == 0) continue;
    SCOPED_TRACE("constant_id " + std::to_string(id) + " (" + c["name"].string + ")");
    ASSERT_LE(id, decl->constants.size()) << "not declared";
    EXPECT_TRUE(seen.insert(id).second);
    const shaders::SpecDecl& d = decl->constants[id - 1];
    EXPECT_EQ(c["name"].string, std::string(d.name));
    EXPECT_EQ(c["type"].string, type_name(d.type));
    EXPECT_EQ(default_bits(c["default_value"], d.type), d.default_bits) << d.name;
  }
  EXPECT_EQ(seen.size(), decl->constants.size()) << "declared constants missing from the SPIR-V";
}

// Lavapipe inlines the values of small uniform blocks into the shader and
// keeps a compiled variant per set of values: constants that change every
// frame recompiled every pass each frame and grew the server without bound.
TEST_P(ShaderReflection, NoKernelDeclaresAUniformBlock) {
  const Value r = reflection(GetParam());
  EXPECT_FALSE(r.has("ubos")) << "declare constants as a readonly buffer (shaders/include/frame.glsl says why)";
}

// Binding 0: FrameConstants with the C++ layout, or (kernels outside the
// pipelines: fb_lut_probe, bench_copy) a block of their own; none at all for
// the table generator fb_lut. Read-only, like every kernel's constants.
TEST_P(ShaderReflection, ConstantsBlockIsFrameConstantsWithTheCppLayout) {
  const Value r = reflection(GetParam());
  if (!r.has("ssbos")) return;
  const Value* found = nullptr;
  for (const Value& b : r["ssbos"].array)
    if (b["binding"].number == 0.0) found = &b;
  if (!found) return;  // fb_lut: binding 0 unused
  const Value& block = *found;
  EXPECT_EQ(block["set"].number, 0.0);
  EXPECT_TRUE(block.has("readonly") && block["readonly"].boolean);
  if (block["name"].string != "FrameConstants") return;  // fb_lut_probe, bench_copy: their own block
  EXPECT_LE(block["block_size"].number, static_cast<double>(sizeof(pipelines::FrameConstants)));
  const Value& members = r["types"][block["type"].string]["members"];
  const auto want = frame_constants_members();
  ASSERT_EQ(members.array.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(members[i]["name"].string, want[i].name);
    EXPECT_EQ(members[i]["offset"].number, static_cast<double>(want[i].offset)) << want[i].name;
  }
  // The parameter struct: every row of parameters.def, a float at C++'s offset.
  const Value& params = r["types"][members[want.size() - 1]["type"].string]["members"];
  const auto rows = parameter_members();
  ASSERT_EQ(params.array.size(), rows.size());
  for (size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(params[i]["name"].string, rows[i].name);
    EXPECT_EQ(params[i]["type"].string, "float") << rows[i].name;
    EXPECT_EQ(params[i]["offset"].number, static_cast<double>(rows[i].offset)) << rows[i].name;
  }
}

INSTANTIATE_TEST_SUITE_P(Shaders, ShaderReflection, testing::ValuesIn(shader_names()),
                         [](const testing::TestParamInfo<std::string>& info) { return info.param; });

}  // namespace
}  // namespace dn
