#include "pipelines/pass.hpp"

#include <algorithm>
#include <bit>
#include <stdexcept>

#include "dn/shaders/shaders.hpp"

namespace dn::pipelines {

PassSpec::PassSpec(std::string name, std::string_view shader)
    : name_(std::move(name)), decl_(shaders::declaration(shader)) {
  if (!decl_) throw std::logic_error("pass " + name_ + ": shader " + std::string(shader) + " has no declaration");
  bindings_.resize(decl_->bindings.size());
  values_.resize(decl_->constants.size());
}

PassSpec& PassSpec::bind(std::string_view binding, std::string buffer, Slot slot) {
  const shaders::BindingDecl* b = decl_->binding(binding);
  if (!b)
    throw std::logic_error("pass " + name_ + ": shader " + std::string(decl_->shader) + " declares no binding " +
                           std::string(binding));
  BindingRef& ref = bindings_[b->binding - 1];
  if (ref.bound()) throw std::logic_error("pass " + name_ + ": binding " + std::string(binding) + " bound twice");
  if (buffer.empty()) throw std::logic_error("pass " + name_ + ": binding " + std::string(binding) + " to no buffer");
  ref = {std::move(buffer), slot};
  return *this;
}

PassSpec& PassSpec::set(std::string_view constant, uint32_t value) {
  if (!decl_->modes.empty() && constant == "MODE")
    throw std::logic_error("pass " + name_ + ": shader " + std::string(decl_->shader) +
                           " names its modes: select one with mode(), not MODE");
  return set_constant(constant, value);
}

PassSpec& PassSpec::mode(std::string_view name) {
  const shaders::ModeDecl* m = decl_->mode(name);
  if (!m)
    throw std::logic_error("pass " + name_ + ": shader " + std::string(decl_->shader) + " has no mode " +
                           std::string(name));
  mode_ = m;
  return set_constant("MODE", m->value);
}

PassSpec& PassSpec::set_constant(std::string_view constant, uint32_t value) {
  const shaders::SpecDecl* c = decl_->constant(constant);
  if (!c)
    throw std::logic_error("pass " + name_ + ": shader " + std::string(decl_->shader) +
                           " declares no specialization constant " + std::string(constant));
  std::optional<uint32_t>& slot = values_[c->id - 1];
  if (slot) throw std::logic_error("pass " + name_ + ": constant " + std::string(constant) + " set twice");
  if (c->type == shaders::SpecType::t_bool && value > 1)
    throw std::logic_error("pass " + name_ + ": bool constant " + std::string(constant) + " set to " +
                           std::to_string(value));
  slot = value;
  return *this;
}

std::vector<std::string_view> PassSpec::unbound_required() const {
  std::vector<std::string_view> out;
  for (size_t i = 0; i < bindings_.size(); ++i) {
    const std::string_view binding = decl_->bindings[i].name;
    const bool needed_by_mode =
        mode_ && std::any_of(decl_->mode_needs.begin(), decl_->mode_needs.end(), [&](const shaders::ModeNeed& n) {
          return n.mode == mode_->name && n.binding == binding;
        });
    if (!bindings_[i].bound() && (decl_->bindings[i].need == shaders::Need::required || needed_by_mode))
      out.push_back(binding);
  }
  return out;
}

std::vector<gpu::SpecConstant> PassSpec::specialization(uint32_t workgroup_size) const {
  std::vector<gpu::SpecConstant> out;
  out.reserve(values_.size() + 1);
  out.push_back({0, workgroup_size});
  for (size_t i = 0; i < values_.size(); ++i)
    out.push_back({decl_->constants[i].id, values_[i].value_or(decl_->constants[i].default_bits)});
  return out;
}

namespace {

struct TexelElement {
  std::string_view element;
  VkFormat format;
  uint32_t bytes;
};
// One row per DN_TEXEL_SAMPLER_<element> of shaders/include/pass.glsl.
constexpr TexelElement kTexelElements[] = {
    {"vec4", VK_FORMAT_R32G32B32A32_SFLOAT, 16}, {"vec2", VK_FORMAT_R32G32_SFLOAT, 8},
    {"float", VK_FORMAT_R32_SFLOAT, 4},          {"uvec4", VK_FORMAT_R32G32B32A32_UINT, 16},
    {"uvec2", VK_FORMAT_R32G32_UINT, 8},         {"uint", VK_FORMAT_R32_UINT, 4},
};

const TexelElement& texel_element(std::string_view element) {
  for (const auto& t : kTexelElements)
    if (t.element == element) return t;
  throw std::logic_error("texel binding of element type " + std::string(element) + ": no texel form");
}

}  // namespace

VkFormat texel_format(std::string_view element) { return texel_element(element).format; }
uint32_t texel_bytes(std::string_view element) { return texel_element(element).bytes; }

gpu::KernelDesc kernel_desc(const shaders::Declaration& decl, std::vector<gpu::SpecConstant> constants) {
  gpu::KernelDesc desc;
  desc.name = std::string(decl.shader);
  desc.spirv = shaders::get(decl.shader);
  desc.storage_buffers = static_cast<uint32_t>(decl.bindings.size());
  for (const auto& b : decl.bindings)
    if (b.access == shaders::Access::texel) {
      desc.texel_formats.assign(decl.bindings.size(), VK_FORMAT_UNDEFINED);
      break;
    }
  if (!desc.texel_formats.empty())
    for (size_t i = 0; i < decl.bindings.size(); ++i)
      if (decl.bindings[i].access == shaders::Access::texel) desc.texel_formats[i] = texel_format(decl.bindings[i].element);
  desc.spec_constants = std::move(constants);
  return desc;
}

PassSpec& PassSpec::over_grid(gpu::Extent size, gpu::Extent source, uint32_t block) {
  Grid g;
  g.block = block;
  g.push.size[0] = size.width;
  g.push.size[1] = size.height;
  g.push.source[0] = source.width;
  g.push.source[1] = source.height;
  grid = g;
  return *this;
}

PassSpec& PassSpec::arg(std::string_view name, uint32_t value) { return set_arg(name, shaders::SpecType::t_uint, value); }

PassSpec& PassSpec::arg(std::string_view name, float value) {
  return set_arg(name, shaders::SpecType::t_float, std::bit_cast<uint32_t>(value));
}

PassSpec& PassSpec::set_arg(std::string_view name, shaders::SpecType type, uint32_t bits) {
  const shaders::GridArgDecl* a = decl_->grid_arg(name);
  if (!a)
    throw std::logic_error("pass " + name_ + ": shader " + std::string(decl_->shader) + " declares no grid argument " +
                           std::string(name));
  if (a->type != type)
    throw std::logic_error("pass " + name_ + ": grid argument " + std::string(name) + " is a " +
                           (a->type == shaders::SpecType::t_float ? "float" : "uint"));
  if (!grid) throw std::logic_error("pass " + name_ + ": grid argument " + std::string(name) + " before over_grid");
  grid->push.args[a->slot] = bits;
  return *this;
}

gpu::KernelDesc kernel_desc(const PassSpec& pass, uint32_t linear_workgroup_size) {
  if (!pass.grid) return kernel_desc(pass.declaration(), pass.specialization(linear_workgroup_size));
  gpu::KernelDesc desc = kernel_desc(pass.declaration(), pass.specialization(pass.grid->block));
  desc.spec_constants.erase(desc.spec_constants.begin());  // constant 0 is the local size: set below
  desc.local_size_x = desc.local_size_y = pass.grid->block;
  desc.push_constant_bytes = sizeof(gpu::GridPush);
  return desc;
}

}  // namespace dn::pipelines
