#include "pipelines/stages/split_signals.hpp"

#include "pipelines/stages/supersample.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;


// Index of the channel in the declaration, or -1.
int index_of(const SessionConfig& config, ChannelId id) {
  for (size_t i = 0; i < config.channels.size(); ++i)
    if (config.channels[i].id == id) return static_cast<int>(i);
  return -1;
}

std::string name(ChannelId id) { return std::string(protocol::find_channel(id)->name); }

// "channels[i].id" of the later of two declared channels (the one that conflicts).
std::string later_field(int a, int b) {
  return "channels[" + std::to_string(std::max(a, b)) + "].id";
}

}  // namespace

uint64_t split_channel_bits() {
  return protocol::channel_bit(ChannelId::Diffuse) | protocol::channel_bit(ChannelId::DiffuseLighting) |
         protocol::channel_bit(ChannelId::Specular) | protocol::channel_bit(ChannelId::SpecularLighting) |
         protocol::channel_bit(ChannelId::SpecularAlbedo);
}

bool has_split_signals(const SessionConfig& config) {
  for (ChannelId id : {ChannelId::Diffuse, ChannelId::DiffuseLighting, ChannelId::Specular,
                       ChannelId::SpecularLighting})
    if (index_of(config, id) >= 0) return true;
  return false;
}

std::vector<SvgfSignal> split_signals(const SessionConfig& config, const Modulator& specular_default) {
  const Modulator albedo{"albedo", ChannelId::Albedo};
  const Modulator specular_albedo{"specular_albedo", ChannelId::SpecularAlbedo};
  std::vector<SvgfSignal> out;
  if (has_channel(config, ChannelId::DiffuseLighting)) {
    Modulator m = albedo;
    m.client_divided = true;
    out.push_back({ChannelId::DiffuseLighting, "diffuse_lighting", "_diffuse", "svgf", m});
  } else {
    out.push_back({ChannelId::Diffuse, "diffuse", "_diffuse", "svgf", albedo});
  }
  if (has_channel(config, ChannelId::SpecularLighting)) {
    Modulator m = specular_albedo;
    m.client_divided = true;
    out.push_back({ChannelId::SpecularLighting, "specular_lighting", "_specular", "svgf_spec", m});
    out.back().clip = true;
  } else {
    const bool declared = has_channel(config, ChannelId::SpecularAlbedo);
    out.push_back({ChannelId::Specular, "specular", "_specular", "svgf_spec", declared ? specular_albedo : specular_default});
    out.back().clip = true;
  }
  return out;
}

std::optional<ConfigError> check_split_channels(const SessionConfig& config, const std::string& pipeline,
                                                bool radiance_allowed) {
  const int radiance = index_of(config, ChannelId::Radiance);
  const int diffuse = index_of(config, ChannelId::Diffuse), diffuse_l = index_of(config, ChannelId::DiffuseLighting);
  const int specular = index_of(config, ChannelId::Specular),
            specular_l = index_of(config, ChannelId::SpecularLighting);
  const int specular_albedo = index_of(config, ChannelId::SpecularAlbedo);
  const std::string who = "pipeline " + pipeline;
  if (diffuse >= 0 && diffuse_l >= 0)
    return ConfigError{ConfigProblem::InvalidChannel, later_field(diffuse, diffuse_l),
                       who + " takes diffuse or diffuse_lighting (one form per signal), not both"};
  if (specular >= 0 && specular_l >= 0)
    return ConfigError{ConfigProblem::InvalidChannel, later_field(specular, specular_l),
                       who + " takes specular or specular_lighting (one form per signal), not both"};
  const int d = std::max(diffuse, diffuse_l), s = std::max(specular, specular_l);
  if (radiance >= 0 && (d >= 0 || s >= 0)) {
    const int other = d >= 0 ? d : s;
    return ConfigError{ConfigProblem::InvalidChannel, later_field(radiance, other),
                       who + " takes either radiance or diffuse + specular (each in radiance or lighting form), "
                             "not both (radiance and " + name(config.channels[other].id) + " declared)"};
  }
  if (d >= 0 && s < 0)
    return ConfigError{ConfigProblem::MissingChannel, "channels",
                       who + " requires channel specular or specular_lighting together with " +
                           name(config.channels[d].id)};
  if (s >= 0 && d < 0)
    return ConfigError{ConfigProblem::MissingChannel, "channels",
                       who + " requires channel diffuse or diffuse_lighting together with " +
                           name(config.channels[s].id)};
  if (specular_l >= 0 && specular_albedo < 0)
    return ConfigError{ConfigProblem::MissingChannel, "channels",
                       who + " requires channel specular_albedo with specular_lighting (its modulator)"};
  if (specular_albedo >= 0 && s < 0)
    return ConfigError{ConfigProblem::InvalidChannel, "channels[" + std::to_string(specular_albedo) + "].id",
                       who + " uses specular_albedo only as the modulator of specular or specular_lighting, and "
                             "neither is declared"};
  if (d < 0 && (!radiance_allowed || radiance < 0))
    return ConfigError{ConfigProblem::MissingChannel, "channels",
                       who + (radiance_allowed ? " requires channel radiance, or diffuse and specular (either form)"
                                               : " requires diffuse and specular (either form)")};
  return check_extra_samples(config);
}

std::vector<SvgfSignal> radiance_or_split_signals(const SessionConfig& config, bool emission) {
  if (has_split_signals(config)) return split_signals(config, Modulator{});
  // Radiance includes what the primary hit emits (docs/protocol.md); the
  // emitted part is added back unfiltered, so it is not filtered as well.
  SvgfSignal radiance{ChannelId::Radiance, "radiance", "", "svgf", Modulator{"albedo", ChannelId::Albedo}};
  radiance.subtract_emission = emission;
  radiance.clip = true;  // it carries the highlights and reflections
  return {radiance};
}

std::optional<ConfigError> check_split_only(const SessionConfig& config) {
  return check_split_channels(config, config.pipeline, /*radiance_allowed=*/false);
}

}  // namespace dn::pipelines
