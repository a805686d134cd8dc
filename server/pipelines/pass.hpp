// One pass of a graph: a shader whose buffers are bound and whose
// specialization constants are set by the names its declaration gives them
// (its <shader>.pass, dn::shaders::declaration). Pure data: no
// device objects, so building and checking a graph needs no device.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "dn/shaders/declaration.hpp"
#include "gpu/compute.hpp"
#include "gpu/levels.hpp"

namespace dn::pipelines {

// Which copy of a History buffer a binding takes (other roles: Current).
enum class Slot { Current, Previous };

struct BindingRef {
  std::string buffer;  // a GraphSpec buffer; empty: not bound
  Slot slot = Slot::Current;
  bool bound() const { return !buffer.empty(); }
};

class PassSpec {
 public:
  // name: the pass (and timing) name; shader: dn::shaders name. Throws
  // std::logic_error when the shader has no declaration.
  PassSpec(std::string name, std::string_view shader);

  const std::string& name() const { return name_; }
  std::string_view shader() const { return decl_->shader; }
  const shaders::Declaration& declaration() const { return *decl_; }

  // Binds the declared binding `binding` to graph buffer `buffer`. Throws
  // std::logic_error when the shader declares no such binding or it is bound
  // already.
  PassSpec& bind(std::string_view binding, std::string buffer, Slot slot = Slot::Current);
  // Sets the declared specialization constant `constant` (bool: 0 or 1).
  // Throws std::logic_error for an unknown name, a second set or a bool
  // outside 0/1.
  PassSpec& set(std::string_view constant, uint32_t value);
  // Selects the declared mode `name` (DN_MODE: a value of the uint constant
  // MODE, which set() then refuses); its needs (DN_MODE_NEEDS) become
  // required bindings. Throws std::logic_error for an unknown mode.
  PassSpec& mode(std::string_view name);
  // The selected mode, or nullptr (a shader with modes must have one: GraphSpec::check).
  const shaders::ModeDecl* selected_mode() const { return mode_; }

  // One entry per declared binding, in binding order (bindings()[i] is
  // binding i + 1); unbound ones have an empty buffer.
  const std::vector<BindingRef>& bindings() const { return bindings_; }
  // Names of required bindings (and the selected mode's needs) nothing is bound to.
  std::vector<std::string_view> unbound_required() const;
  // Constant 0 (the workgroup size) followed by every declared constant, set
  // or default, by id: equal specializations give equal kernel-cache keys.
  std::vector<gpu::SpecConstant> specialization(uint32_t workgroup_size) const;

  // Dispatch: one invocation per `pixels_per_invocation` pixels, or exactly
  // `invocations` invocations when that is nonzero (1-D, frame.glsl) ...
  uint32_t pixels_per_invocation = 2;
  uint64_t invocations = 0;
  // ... or, when set, one invocation per pixel of grid.size in square
  // block x block workgroups with grid as push constants (grid2d.glsl): for
  // passes with shared-memory tiles or at a reduced resolution.
  struct Grid {
    uint32_t block = 8;
    gpu::GridPush push;
  };
  std::optional<Grid> grid;
  PassSpec& over_grid(gpu::Extent size, gpu::Extent source, uint32_t block = 8);
  // Sets the declared grid argument `name` (DN_GRID_ARG, read by the shader
  // as dn_arg_<name>()) of a pass over a grid; unset ones are 0. Throws
  // std::logic_error for an unknown name, the other type or no grid.
  PassSpec& arg(std::string_view name, uint32_t value);
  PassSpec& arg(std::string_view name, float value);

 private:
  std::string name_;
  const shaders::Declaration* decl_ = nullptr;
  std::vector<BindingRef> bindings_;
  std::vector<std::optional<uint32_t>> values_;  // per declared constant
  PassSpec& set_arg(std::string_view name, shaders::SpecType type, uint32_t bits);
  PassSpec& set_constant(std::string_view constant, uint32_t value);
  const shaders::ModeDecl* mode_ = nullptr;
};

// The kernel description of a declared shader with these constants.
gpu::KernelDesc kernel_desc(const shaders::Declaration& decl, std::vector<gpu::SpecConstant> constants);
// The view format of a texel binding of this element type (shaders/include/
// pass.glsl lists the types it expands) and its bytes per element; throws
// std::logic_error for a type with no texel form.
VkFormat texel_format(std::string_view element);
uint32_t texel_bytes(std::string_view element);
// The kernel description of a pass: 1-D with the graph's workgroup size, or its grid's square workgroups.
gpu::KernelDesc kernel_desc(const PassSpec& pass, uint32_t linear_workgroup_size);

}  // namespace dn::pipelines
