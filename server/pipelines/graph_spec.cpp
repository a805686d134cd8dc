// GraphSpec: the pure-data half of graph.hpp (buffers, passes, their sizes
// and the build-time check), and the channel helpers definitions use.
#include "pipelines/graph.hpp"

#include <algorithm>
#include <stdexcept>

namespace dn::pipelines {

uint64_t round_up4(uint64_t bytes) { return (bytes + 3) & ~uint64_t{3}; }

protocol::Format channel_format(const SessionConfig& config, protocol::ChannelId channel) {
  for (const auto& c : config.channels)
    if (c.id == channel) return c.format;
  return protocol::Format::F32;
}

bool has_channel(const SessionConfig& config, protocol::ChannelId channel) {
  for (const auto& c : config.channels)
    if (c.id == channel) return true;
  return false;
}

uint64_t channel_mask(const SessionConfig& config) {
  uint64_t mask = 0;
  for (const auto& c : config.channels) mask |= protocol::channel_bit(c.id);
  return mask;
}

uint64_t GraphSpec::device_bytes() const {
  uint64_t total = kConstantBytes;
  for (const auto& b : buffers) total += b.role == BufferRole::History ? 2 * b.bytes : b.bytes;
  return total;
}

uint64_t GraphSpec::transient_bytes() const {
  uint64_t total = 0;
  for (const auto& b : buffers)
    if (b.role == BufferRole::Scratch) total += b.bytes;
  return total;
}

const BufferSpec* GraphSpec::largest_binding() const {
  const BufferSpec* best = nullptr;
  for (const auto& b : buffers)
    if (!best || b.bytes > best->bytes) best = &b;
  return best;
}

const BufferSpec* GraphSpec::find(const std::string& name) const {
  for (const auto& a : aliases)
    if (a.name == name) return find(a.of);
  for (const auto& b : buffers)
    if (b.name == name) return &b;
  return nullptr;
}

void GraphSpec::add_alias(std::string name, std::string of) { aliases.push_back({std::move(name), std::move(of)}); }

void GraphSpec::add_input(const SessionConfig& config, protocol::ChannelId channel, std::string name) {
  const auto* info = protocol::find_channel(channel);
  const auto format = channel_format(config, channel);
  BufferSpec b;
  b.name = std::move(name);
  b.role = BufferRole::Input;
  b.channel = channel;
  b.format = format;
  for (size_t i = 0; i < config.channels.size(); ++i)
    if (config.channels[i].id == channel) b.plane = i;
  b.plane_bytes = protocol::plane_bytes(*info, format, config.width, config.height);
  b.bytes = protocol::plane_bytes(*info, protocol::Format::F32, config.width, config.height);
  buffers.push_back(std::move(b));
}

void GraphSpec::add_output(const SessionConfig& config) {
  const auto* info = protocol::find_channel(protocol::ChannelId::Output);
  BufferSpec b;
  b.name = kOutput;
  b.role = BufferRole::Output;
  b.channel = protocol::ChannelId::Output;
  b.format = config.output_format;
  b.plane_bytes = protocol::plane_bytes(*info, config.output_format, config.width, config.height);
  b.bytes = protocol::plane_bytes(*info, protocol::Format::F32, config.width, config.height);
  buffers.push_back(std::move(b));
}

void GraphSpec::add_sized(std::string name, BufferRole role, uint64_t bytes) {
  BufferSpec b;
  b.name = std::move(name);
  b.role = role;
  b.bytes = round_up4(bytes);
  buffers.push_back(std::move(b));
}

void GraphSpec::add_history(std::string name) {
  add_sized(std::move(name), BufferRole::History, 0);
  buffers.back().sized_by_bindings = true;
}

void GraphSpec::add_persistent(std::string name) {
  add_sized(std::move(name), BufferRole::Persistent, 0);
  buffers.back().sized_by_bindings = true;
}

void GraphSpec::add_scratch(std::string name) {
  add_sized(std::move(name), BufferRole::Scratch, 0);
  buffers.back().sized_by_bindings = true;
}

void GraphSpec::size_from_bindings() {
  const uint64_t pixels = uint64_t{width} * height;
  for (BufferSpec& b : buffers) {
    if (!b.sized_by_bindings) continue;
    std::string first;  // "pass.binding" that gave the size
    uint64_t bytes = 0;
    for (const PassSpec& pass : passes)
      for (size_t i = 0; i < pass.bindings().size(); ++i) {
        const BindingRef& ref = pass.bindings()[i];
        const BufferSpec* bound = ref.bound() ? find(ref.buffer) : nullptr;
        if (bound != &b) continue;
        const shaders::BindingDecl& decl = pass.declaration().bindings[i];
        const uint32_t per_pixel = pass.declaration().per_pixel(decl.name);
        if (per_pixel == 0) continue;
        const uint64_t rule = pixels * per_pixel * shaders::element_bytes(decl.element);
        const std::string here = pass.name() + "." + std::string(decl.name);
        if (first.empty()) {
          first = here;
          bytes = rule;
        } else if (rule != bytes) {
          throw std::logic_error("buffer " + b.name + ": " + here + " declares " + std::to_string(rule) +
                                 " bytes, " + first + " " + std::to_string(bytes));
        }
      }
    if (first.empty())
      throw std::logic_error("buffer " + b.name + " has no size: no binding of it declares DN_PER_PIXEL");
    b.bytes = round_up4(bytes);
  }
}

void GraphSpec::add_scratch(std::string name, uint64_t bytes_per_pixel) {
  add_sized(std::move(name), BufferRole::Scratch, uint64_t{width} * height * bytes_per_pixel);
}

void GraphSpec::add_scratch_elements(std::string name, uint64_t elements, uint64_t bytes_per_element) {
  add_sized(std::move(name), BufferRole::Scratch, elements * bytes_per_element);
}

gpu::Extent GraphSpec::level(uint32_t factor, uint32_t level) const {
  return gpu::level_size(width, height, factor, level);
}

void GraphSpec::add_shared(std::string name, SharedResource resource) {
  BufferSpec b;
  b.name = std::move(name);
  b.role = BufferRole::Shared;  // bytes 0: the context holds it for every session
  b.shared = resource;
  buffers.push_back(std::move(b));
}

void GraphSpec::add_constant(std::string name, std::vector<uint8_t> data) {
  BufferSpec b;
  b.name = std::move(name);
  b.role = BufferRole::Constant;
  b.bytes = round_up4(data.size());
  b.data = std::move(data);
  buffers.push_back(std::move(b));
}

void GraphSpec::add_readback(std::string name, uint64_t bytes) { add_sized(std::move(name), BufferRole::Readback, bytes); }

PassSpec& GraphSpec::add_pass(std::string name, std::string_view shader) {
  return passes.emplace_back(std::move(name), shader);
}

void GraphSpec::check() const {
  for (size_t i = 0; i < buffers.size(); ++i) {
    for (size_t j = 0; j < i; ++j)
      if (buffers[j].name == buffers[i].name)
        throw std::logic_error("pipeline graph: buffer " + buffers[i].name + " defined twice");
    if (buffers[i].role == BufferRole::Shared && !buffers[i].shared)
      throw std::logic_error("pipeline graph: shared buffer " + buffers[i].name + " has no resource");
    if (buffers[i].sized_by_bindings && buffers[i].bytes == 0)
      throw std::logic_error("pipeline graph: buffer " + buffers[i].name +
                             " is sized by its bindings, and size_from_bindings() has not run");
  }
  for (const BufferAlias& a : aliases) {
    if (!find(a.of) || std::any_of(aliases.begin(), aliases.end(), [&](const BufferAlias& o) { return o.name == a.of; }))
      throw std::logic_error("pipeline graph: alias " + a.name + " of " + a.of + ", which is no buffer");
    for (const auto& b : buffers)
      if (b.name == a.name) throw std::logic_error("pipeline graph: alias " + a.name + " is a buffer's name too");
    // From the first pass that binds the alias on, the buffer's earlier contents are dead.
    bool aliased = false;
    for (const PassSpec& pass : passes) {
      const auto& refs = pass.bindings();
      aliased = aliased || std::any_of(refs.begin(), refs.end(), [&](const BindingRef& r) { return r.buffer == a.name; });
      if (aliased && std::any_of(refs.begin(), refs.end(), [&](const BindingRef& r) { return r.buffer == a.of; }))
        throw std::logic_error("pipeline graph: pass " + pass.name() + " binds " + a.of + " while it holds " + a.name);
    }
  }
  for (const PassSpec& pass : passes) {
    if (!pass.declaration().modes.empty() && !pass.selected_mode())
      throw std::logic_error("pipeline graph: pass " + pass.name() + " selects no mode of shader " +
                             std::string(pass.shader()));
    for (std::string_view missing : pass.unbound_required())
      throw std::logic_error("pipeline graph: pass " + pass.name() + " leaves required binding " +
                             std::string(missing) + " unbound");
    for (size_t i = 0; i < pass.bindings().size(); ++i) {
      const BindingRef& ref = pass.bindings()[i];
      if (!ref.bound()) continue;
      const std::string binding(pass.declaration().bindings[i].name);
      const BufferSpec* b = find(ref.buffer);
      if (!b)
        throw std::logic_error("pipeline graph: pass " + pass.name() + " binds " + binding +
                               " to undefined buffer " + ref.buffer);
      if (ref.slot == Slot::Previous && b->role != BufferRole::History)
        throw std::logic_error("pipeline graph: pass " + pass.name() + " binds " + binding +
                               " to the previous copy of " + ref.buffer + ", which is not History");
      const shaders::Access access = pass.declaration().bindings[i].access;
      const bool writes = access == shaders::Access::write || access == shaders::Access::read_write;
      if (writes && (b->role == BufferRole::Input || b->role == BufferRole::Shared || b->role == BufferRole::Constant))
        throw std::logic_error("pipeline graph: pass " + pass.name() + " binds " + binding +
                               " (written) to read-only buffer " + ref.buffer);
    }
  }
}

}  // namespace dn::pipelines
