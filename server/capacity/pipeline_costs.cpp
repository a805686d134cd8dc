#include "server/capacity/pipeline_costs.hpp"

#include <optional>
#include <variant>

namespace dn::server {

namespace {

// Two sizes far apart, of different aspect, that every pipeline accepts.
constexpr uint32_t kSmallW = 64, kSmallH = 32, kLargeW = 1024, kLargeH = 512;

// The channel index a refusal's field names ("channels[3].id"), if any.
std::optional<size_t> named_channel(const std::string& field) {
  const std::string key = "channels[";
  const size_t at = field.find(key);
  if (at == std::string::npos) return std::nullopt;
  return std::stoul(field.substr(at + key.size()));
}

}  // namespace

pipelines::SessionConfig reference_session(const pipelines::PipelineDescription& pipeline, uint32_t width,
                                           uint32_t height) {
  pipelines::SessionConfig config;
  config.width = width;
  config.height = height;
  config.pipeline = pipeline.name;
  config.output_format = protocol::Format::F32;
  for (const protocol::ChannelInfo& c : protocol::kChannels)
    if ((pipeline.required_channels | pipeline.optional_channels) & protocol::channel_bit(c.id))
      config.channels.push_back({c.id, protocol::Format::F32});
  // Channels that exclude each other (svgf: radiance or diffuse + specular):
  // drop the one each refusal names, else the last optional one, until accepted.
  while (true) {
    auto prepared = pipelines::prepare(config);
    const auto* refused = std::get_if<pipelines::ConfigError>(&prepared);
    if (!refused) return config;
    std::optional<size_t> drop = named_channel(refused->field);
    if (!drop || *drop >= config.channels.size() ||
        pipeline.required_channels & protocol::channel_bit(config.channels[*drop].id)) {
      drop.reset();
      for (size_t i = config.channels.size(); i-- > 0;)
        if (!(pipeline.required_channels & protocol::channel_bit(config.channels[i].id))) {
          drop = i;
          break;
        }
    }
    if (!drop) return config;  // nothing optional left: fit_pipeline_cost reports the refusal
    config.channels.erase(config.channels.begin() + static_cast<std::ptrdiff_t>(*drop));
  }
}

PipelineCost fit_pipeline_cost(const pipelines::PipelineDescription& pipeline) {
  auto bytes_at = [&](uint32_t w, uint32_t h) -> double {
    auto prepared = pipelines::prepare(reference_session(pipeline, w, h));
    if (!std::holds_alternative<pipelines::PreparedPipeline>(prepared)) return -1;
    return static_cast<double>(std::get<pipelines::PreparedPipeline>(prepared).device_bytes());
  };
  const double small = bytes_at(kSmallW, kSmallH), large = bytes_at(kLargeW, kLargeH);
  if (small < 0 || large < 0) return {};
  const double small_pixels = double(kSmallW) * kSmallH, large_pixels = double(kLargeW) * kLargeH;
  PipelineCost cost{pipeline.name, 0, (large - small) / (large_pixels - small_pixels), 0};
  for (const auto& c : reference_session(pipeline, kSmallW, kSmallH).channels)
    cost.reference_channels |= protocol::channel_bit(c.id);
  cost.fixed_bytes = small - cost.bytes_per_pixel * small_pixels;
  return cost;
}

const std::vector<PipelineCost>& pipeline_costs() {
  static const std::vector<PipelineCost> costs = [] {
    std::vector<PipelineCost> all;
    for (const auto& p : pipelines::available_pipelines())
      if (PipelineCost c = fit_pipeline_cost(p); !c.pipeline.empty()) all.push_back(std::move(c));
    return all;
  }();
  return costs;
}

}  // namespace dn::server
