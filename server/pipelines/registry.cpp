// The pipeline contract: the list of pipelines, configuration validation,
// device-byte estimates and creation.
#include <atomic>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <set>

#include "gpu/context.hpp"
#include "pipelines/auto_choice.hpp"
#include "pipelines/definitions.hpp"
#include "pipelines/registry.hpp"

namespace dn::pipelines {

std::string channel_list(uint64_t mask) {
  std::string out;
  for (const auto& c : protocol::kChannels) {
    if (!(mask & protocol::channel_bit(c.id))) continue;
    if (!out.empty()) out += ", ";
    out += c.name;
  }
  return out.empty() ? "none" : out;
}

namespace {

std::string format_number(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

ConfigError error(ConfigProblem problem, std::string field, std::string message) {
  return ConfigError{problem, std::move(field), std::move(message)};
}

}  // namespace

const std::vector<PipelineDefinition>& definitions() {
  static const std::vector<PipelineDefinition> all = {
#define DN_PIPELINE(family, id) id##_definition(),
#include "pipelines/pipelines.def"
#undef DN_PIPELINE
  };
  return all;
}

const PipelineDefinition* find_definition(std::string_view name) {
  for (const auto& d : definitions())
    if (d.description.name == name) return &d;
  return nullptr;
}

GraphSpec begin_graph(const SessionConfig& config) {
  GraphSpec g;
  g.width = config.width;
  g.height = config.height;
  const PipelineDefinition* def = find_definition(config.pipeline);
  g.parameters = parameter_block(def->parameter_groups, config.parameters, def->parameter_defaults);
  return g;
}

const std::vector<PipelineDescription>& available_pipelines() {
  static const std::vector<PipelineDescription> all = [] {
    std::vector<PipelineDescription> out;
    for (const auto& d : definitions()) out.push_back(d.description);
    return out;
  }();
  return all;
}

namespace {

std::atomic<uint64_t> graphs_built{0};

// The one place a graph is built: the definition's builder, the buffers'
// sizes from their bindings' rules, then the build-time check of every
// binding and buffer name.
std::shared_ptr<const GraphSpec> build_graph(const PipelineDefinition& def, const SessionConfig& config) {
  graphs_built.fetch_add(1, std::memory_order_relaxed);
  auto g = std::make_shared<GraphSpec>(def.build(config));
  g->size_from_bindings();
  g->check();
  return g;
}

std::optional<ConfigError> limit_error(const SessionConfig& config, const GraphSpec& graph,
                                       const gpu::DeviceLimits& limits) {
  const BufferSpec* big = graph.largest_binding();
  if (big && big->bytes > limits.max_storage_buffer_range)
    return error(ConfigProblem::LimitExceeded, "width",
                 "resolution " + std::to_string(config.width) + "x" + std::to_string(config.height) + " needs " +
                     std::to_string(big->bytes) + " bytes in one device buffer (" + big->name +
                     "); the device allows " + std::to_string(limits.max_storage_buffer_range));
  return std::nullopt;
}

}  // namespace

uint64_t graphs_built_count() { return graphs_built.load(std::memory_order_relaxed); }

namespace {
struct SharedResourceTimings {
  std::vector<SharedResourceTiming> list;
};
}  // namespace

const std::vector<SharedResourceTiming>& prepare_shared_resources(gpu::Context& context) {
  return context
      .shared<SharedResourceTimings>([&] {
        auto timings = std::make_unique<SharedResourceTimings>();
        for (const auto& def : definitions())
          for (const auto& shared : def.shared_resources) {
            if (std::any_of(timings->list.begin(), timings->list.end(),
                            [&](const auto& t) { return t.name == shared.name; }))
              continue;  // declared by several pipelines: made once
            const auto start = std::chrono::steady_clock::now();
            shared.resource(context);
            timings->list.push_back(
                {shared.name,
                 std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count()});
          }
        return timings;
      })
      .list;
}

BindingSize largest_binding(const SessionConfig& config) {
  const PipelineDefinition* def = find_definition(config.pipeline);
  if (!def) return {};
  const auto graph = build_graph(*def, config);  // b points into it: keep it alive (ASan found the dangling read)
  const BufferSpec* b = graph->largest_binding();
  return b ? BindingSize{b->name, b->bytes} : BindingSize{};
}

std::optional<ConfigError> check_device_limits(const SessionConfig& config, const gpu::DeviceLimits& limits) {
  const PipelineDefinition* def = find_definition(config.pipeline);
  if (!def) return std::nullopt;
  return limit_error(config, *build_graph(*def, config), limits);
}

// Resolution, output format and each channel against what `desc` takes.
std::optional<ConfigError> check_declaration(const SessionConfig& config, const PipelineDescription& desc) {
  if (config.width == 0)
    return error(ConfigProblem::InvalidParameter, "width", "width must be at least 1");
  if (config.height == 0)
    return error(ConfigProblem::InvalidParameter, "height", "height must be at least 1");
  if (config.width > kMaxDimension)
    return error(ConfigProblem::LimitExceeded, "width",
                 "width " + std::to_string(config.width) + " exceeds " + std::to_string(kMaxDimension));
  if (config.height > kMaxDimension)
    return error(ConfigProblem::LimitExceeded, "height",
                 "height " + std::to_string(config.height) + " exceeds " + std::to_string(kMaxDimension));
  if (config.output_format != protocol::Format::F16 && config.output_format != protocol::Format::F32)
    return error(ConfigProblem::InvalidParameter, "output_format",
                 "output format " + std::to_string(static_cast<int>(config.output_format)) +
                     " is neither f16 (1) nor f32 (2)");

  uint64_t declared = 0;
  for (size_t i = 0; i < config.channels.size(); ++i) {
    const auto& ch = config.channels[i];
    const std::string field = "channels[" + std::to_string(i) + "]";
    const auto* info = protocol::find_channel(ch.id);
    if (!info || ch.id == protocol::ChannelId::Output)
      return error(ConfigProblem::InvalidChannel, field + ".id",
                   "channel id " + std::to_string(static_cast<int>(ch.id)) + " is not an input channel");
    if (ch.format != protocol::Format::F16 && ch.format != protocol::Format::F32)
      return error(ConfigProblem::InvalidChannel, field + ".format",
                   "channel " + std::string(info->name) + " has format " +
                       std::to_string(static_cast<int>(ch.format)) + ", expected f16 (1) or f32 (2)");
    const uint64_t bit = protocol::channel_bit(ch.id);
    if (declared & bit)
      return error(ConfigProblem::InvalidChannel, field + ".id",
                   "channel " + std::string(info->name) + " is declared twice");
    if (!((desc.required_channels | desc.optional_channels) & bit))
      return error(ConfigProblem::InvalidChannel, field + ".id",
                   "pipeline " + desc.name + " does not use channel " + std::string(info->name) +
                       "; it takes: " + channel_list(desc.required_channels | desc.optional_channels));
    declared |= bit;
  }
  if (const uint64_t missing = desc.required_channels & ~declared)
    return error(ConfigProblem::MissingChannel, "channels",
                 "pipeline " + desc.name + " requires channel(s) " + channel_list(missing));
  return std::nullopt;
}

namespace {

// Everything validate() checks except the device limits.
std::optional<ConfigError> validate_config(const SessionConfig& config) {
  const PipelineDefinition* def = find_definition(config.pipeline);
  if (!def) {
    std::string names;
    for (const auto& d : definitions()) names += (names.empty() ? "" : ", ") + d.description.name;
    return error(ConfigProblem::UnknownPipeline, "pipeline",
                 "unknown pipeline \"" + config.pipeline + "\"; available: " + names + ", " +
                     std::string(kAutoPipeline));
  }
  const PipelineDescription& desc = def->description;
  if (auto err = check_declaration(config, desc)) return err;
  if (def->check_channels)
    if (auto err = def->check_channels(config)) return err;

  std::set<std::string> seen;
  for (size_t i = 0; i < config.parameters.size(); ++i) {
    const auto& p = config.parameters[i];
    const std::string field = "parameters[" + std::to_string(i) + "]";
    const ParameterInfo* info = nullptr;
    for (const auto& candidate : desc.parameters)
      if (candidate.name == p.name) info = &candidate;
    if (!info) {
      std::string names;
      for (const auto& candidate : desc.parameters) names += (names.empty() ? "" : ", ") + candidate.name;
      return error(ConfigProblem::InvalidParameter, field + ".name",
                   "pipeline " + desc.name + " has no parameter \"" + p.name +
                       "\"; it has: " + (names.empty() ? "none" : names));
    }
    if (!seen.insert(p.name).second)
      return error(ConfigProblem::InvalidParameter, field + ".name", "parameter " + p.name + " is given twice");
    if (!std::isfinite(p.value) || p.value < info->min_value || p.value > info->max_value)
      return error(ConfigProblem::InvalidParameter, field + ".value",
                   p.name + " = " + format_number(p.value) + " is outside [" + format_number(info->min_value) + ", " +
                       format_number(info->max_value) + "]");
    if (info->integer && p.value != std::floor(p.value))
      return error(ConfigProblem::InvalidParameter, field + ".value",
                   p.name + " = " + format_number(p.value) + " must be an integer");
  }

  return std::nullopt;
}

}  // namespace

std::variant<PreparedPipeline, ConfigError> prepare(const SessionConfig& config) {
  if (config.pipeline == kAutoPipeline) return prepare_auto(config);
  if (auto err = validate_config(config)) return *err;
  auto graph = build_graph(*find_definition(config.pipeline), config);
  if (auto err = limit_error(config, *graph, gpu::current_device_limits())) return *err;
  const uint64_t bytes = graph->device_bytes();
  return PreparedPipeline(config, std::move(graph), bytes);
}

std::unique_ptr<Pipeline> create(gpu::Context& context, const PreparedPipeline& prepared) {
  if (auto err = limit_error(prepared.config(), prepared.graph(), context.limits())) throw DeviceFailure(err->message);
  return std::make_unique<GraphPipeline>(context, prepared.config(), prepared.shared_graph());
}

std::optional<ConfigError> validate(const SessionConfig& config) {
  auto prepared = prepare(config);
  if (auto* err = std::get_if<ConfigError>(&prepared)) return std::move(*err);
  return std::nullopt;
}

uint64_t estimate_device_bytes(const SessionConfig& config) {
  const PipelineDefinition* def = find_definition(config.pipeline);
  return def ? build_graph(*def, config)->device_bytes() : 0;
}

std::unique_ptr<Pipeline> create(gpu::Context& context, const SessionConfig& config) {
  if (auto err = validate_config(config)) throw std::invalid_argument(err->field + ": " + err->message);
  auto graph = build_graph(*find_definition(config.pipeline), config);
  if (auto err = limit_error(config, *graph, context.limits())) throw DeviceFailure(err->message);
  return std::make_unique<GraphPipeline>(context, config, std::move(graph));
}

}  // namespace dn::pipelines
